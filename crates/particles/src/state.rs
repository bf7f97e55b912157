//! Particle state (structure of arrays) and the orthorhombic periodic box.

/// An orthorhombic periodic box centred on the origin: coordinates lie in `[-L/2, L/2)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimBox {
    /// Edge lengths.
    pub l: [f64; 3],
}

impl SimBox {
    /// A box with edges `l` (all must be finite and > 0).
    pub fn new(l: [f64; 3]) -> Self {
        assert!(
            l.iter().all(|x| x.is_finite() && *x > 0.0),
            "box edges must be > 0"
        );
        Self { l }
    }

    /// A cube of side `l`.
    pub fn cube(l: f64) -> Self {
        Self::new([l; 3])
    }

    /// Volume.
    #[inline]
    pub fn volume(&self) -> f64 {
        self.l[0] * self.l[1] * self.l[2]
    }

    /// Minimum-image convention applied to a separation vector.
    #[inline(always)]
    pub fn min_image(&self, mut d: [f64; 3]) -> [f64; 3] {
        for k in 0..3 {
            let l = self.l[k];
            if d[k] >= 0.5 * l {
                d[k] -= l;
                if d[k] >= 0.5 * l {
                    d[k] -= l * (d[k] / l + 0.5).floor();
                }
            } else if d[k] < -0.5 * l {
                d[k] += l;
                if d[k] < -0.5 * l {
                    d[k] -= l * (d[k] / l + 0.5).floor();
                }
            }
        }
        d
    }

    /// Wrap `p` into the box, counting crossings in `image`.
    #[inline(always)]
    pub fn wrap(&self, p: &mut [f64; 3], image: &mut [i32; 3]) {
        for k in 0..3 {
            let l = self.l[k];
            if p[k] >= 0.5 * l || p[k] < -0.5 * l {
                let n = (p[k] / l + 0.5).floor();
                p[k] -= n * l;
                // Saturating: a blown-up position (stopped by the run's checks) must not panic.
                image[k] = image[k].saturating_add(n as i32);
                // Rounding can leave p exactly at +L/2.
                if p[k] >= 0.5 * l {
                    p[k] -= l;
                    image[k] = image[k].saturating_add(1);
                }
            }
        }
    }

    /// Lees–Edwards minimum image (Lees & Edwards 1972; Allen & Tildesley, sec. 11.3.1) of a
    /// separation `d = x_i - x_j` when the periodic image of the box above (`y + L_y`) is
    /// displaced by `offset` along x: the y image index `n = floor(d_y / L_y + 1/2)` is taken
    /// first, `d_y -= n L_y`, `d_x -= n offset` (eq. LE-1), then x and z as [`Self::min_image`].
    /// Returns the separation and `n`: the image of `j` used moves with `v_j + n gamma_dot L_y`
    /// along x (eq. LE-2). With `offset = 0` the separation is that of [`Self::min_image`].
    #[inline(always)]
    pub fn min_image_sheared(&self, mut d: [f64; 3], offset: f64) -> ([f64; 3], f64) {
        let ly = self.l[1];
        let n = if d[1] >= 0.5 * ly || d[1] < -0.5 * ly {
            (d[1] / ly + 0.5).floor()
        } else {
            0.0
        };
        d[1] -= n * ly;
        d[0] -= n * offset;
        (self.min_image(d), n)
    }

    /// Wrap `p` into a Lees–Edwards box (box above displaced by `offset` along x and moving
    /// with `shear_velocity = gamma_dot L_y` along x): a particle leaving through the top
    /// (`y >= L_y/2`) re-enters at the bottom with `x -= offset` and `v_x -= gamma_dot L_y`, and
    /// the reverse through the bottom (eq. LE-3); then x and z as [`Self::wrap`]. `image[1]`
    /// counts the y crossings; `image[0]` counts the x wraps only, so under shear
    /// [`Self::unwrap`] does not include the shifts of the y crossings.
    #[inline(always)]
    pub fn wrap_sheared(
        &self,
        p: &mut [f64; 3],
        v: &mut [f64; 3],
        image: &mut [i32; 3],
        offset: f64,
        shear_velocity: f64,
    ) {
        let ly = self.l[1];
        if p[1] >= 0.5 * ly || p[1] < -0.5 * ly {
            let mut n = (p[1] / ly + 0.5).floor();
            p[1] -= n * ly;
            if p[1] >= 0.5 * ly {
                p[1] -= ly;
                n += 1.0;
            }
            p[0] -= n * offset;
            v[0] -= n * shear_velocity;
            image[1] = image[1].saturating_add(n as i32);
        }
        self.wrap(p, image);
    }

    /// Unwrapped position `p + image * L`.
    #[inline]
    pub fn unwrap(&self, p: [f64; 3], image: [i32; 3]) -> [f64; 3] {
        [
            p[0] + image[0] as f64 * self.l[0],
            p[1] + image[1] as f64 * self.l[1],
            p[2] + image[2] as f64 * self.l[2],
        ]
    }
}

/// Particle data as one contiguous array per quantity.
///
/// Positions are wrapped into the box; `image` counts box crossings so that
/// `position + image * L` is the unwrapped trajectory. Velocities and masses are carried for
/// the inertial methods (DPD, MPCD); Brownian dynamics ignores them.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Particles {
    /// Wrapped positions.
    pub pos: Vec<[f64; 3]>,
    /// Periodic image counts.
    pub image: Vec<[i32; 3]>,
    /// Type index of each particle (into `type_names`).
    pub typeid: Vec<u32>,
    /// Diameters.
    pub diameter: Vec<f64>,
    /// Velocities.
    pub vel: Vec<[f64; 3]>,
    /// Masses.
    pub mass: Vec<f64>,
    /// Names of the types.
    pub type_names: Vec<String>,
}

impl Particles {
    /// `pos.len()` particles of one type `"A"` with diameter `diameter`, unit mass, at rest.
    pub fn monodisperse(pos: Vec<[f64; 3]>, diameter: f64) -> Self {
        let n = pos.len();
        Self {
            pos,
            image: vec![[0; 3]; n],
            typeid: vec![0; n],
            diameter: vec![diameter; n],
            vel: vec![[0.0; 3]; n],
            mass: vec![1.0; n],
            type_names: vec!["A".into()],
        }
    }

    /// Number of particles.
    #[inline]
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// No particles?
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Number of types.
    #[inline]
    pub fn n_types(&self) -> usize {
        self.type_names.len().max(1)
    }

    /// Check that all arrays have the same length and type ids are in range.
    pub fn check(&self) -> Result<(), String> {
        let n = self.pos.len();
        for (name, len) in [
            ("image", self.image.len()),
            ("typeid", self.typeid.len()),
            ("diameter", self.diameter.len()),
            ("vel", self.vel.len()),
            ("mass", self.mass.len()),
        ] {
            if len != n {
                return Err(format!(
                    "particle array {name} has {len} entries, expected {n}"
                ));
            }
        }
        if let Some(t) = self.typeid.iter().find(|&&t| t as usize >= self.n_types()) {
            return Err(format!(
                "type id {t} out of range ({} types)",
                self.n_types()
            ));
        }
        if let Some(i) = self
            .pos
            .iter()
            .position(|p| p.iter().any(|x| !x.is_finite()))
        {
            return Err(format!("particle {i} has a non-finite position"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_and_unwrap_round_trip() {
        let b = SimBox::new([4.0, 5.0, 6.0]);
        let mut p = [2.5, -7.6, 13.0];
        let orig = p;
        let mut img = [0; 3];
        b.wrap(&mut p, &mut img);
        for k in 0..3 {
            assert!(p[k] >= -0.5 * b.l[k] && p[k] < 0.5 * b.l[k]);
        }
        let u = b.unwrap(p, img);
        for k in 0..3 {
            assert!((u[k] - orig[k]).abs() < 1e-12);
        }
        let d = b.min_image([3.9, -4.9, 0.1]);
        assert!((d[0] + 0.1).abs() < 1e-12 && (d[1] - 0.1).abs() < 1e-12);
    }

    #[test]
    fn lees_edwards_image_and_wrap() {
        let b = SimBox::new([6.0, 5.0, 4.0]);
        let off = 1.25;
        // j near the top, i near the bottom: i sees j's image below (n = -1), at x_j - offset.
        let (xi, xj) = ([0.3, -2.4, 0.0], [-0.1, 2.3, 0.1]);
        let (d, n) = b.min_image_sheared([xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]], off);
        assert_eq!(n, -1.0);
        assert!((d[1] - 0.3).abs() < 1e-12);
        assert!((d[0] - (0.4 + off)).abs() < 1e-12, "{d:?}");
        // No crossing: the plain minimum image.
        let (d0, n0) = b.min_image_sheared([2.9, 1.0, -3.9], off);
        assert_eq!((d0, n0), (b.min_image([2.9, 1.0, -3.9]), 0.0));
        // Leaving through the top: x shifted by -offset, v_x by -gamma L_y.
        let (mut p, mut v, mut img) = ([2.8, 2.6, 0.0], [0.5, 1.0, 0.0], [0, 0, 0]);
        b.wrap_sheared(&mut p, &mut v, &mut img, off, 0.7);
        assert!((p[1] + 2.4).abs() < 1e-12 && (p[0] - (2.8 - off)).abs() < 1e-12);
        assert!((v[0] + 0.2).abs() < 1e-12 && img == [0, 1, 0]);
        // And back through the bottom.
        p[1] -= 0.2;
        b.wrap_sheared(&mut p, &mut v, &mut img, off, 0.7);
        assert!((p[1] - 2.4).abs() < 1e-12 && (p[0] - 2.8).abs() < 1e-12);
        assert!((v[0] - 0.5).abs() < 1e-12 && img == [0, 0, 0]);
    }
}
