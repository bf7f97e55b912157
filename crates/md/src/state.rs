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
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// No particles?
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Number of types.
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
}
