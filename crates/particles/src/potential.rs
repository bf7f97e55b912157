//! Pair and external potentials.
//!
//! Potentials are generic parameters of the engines (no trait objects in the force loop).
//! A [`Pair`] returns `F/r` (the force on particle i is `(F/r) * (r_i - r_j)`); an
//! [`External`] returns the force on one particle at time t.

use std::f64::consts::PI;

/// A pair potential with per-type parameters.
pub trait Pair: Sync + Send {
    /// Largest cut-off over all type pairs and diameters present (sets the neighbour list range).
    fn r_cut_max(&self) -> f64;
    /// `F/r` at squared distance `r2` between particles of types `ti`, `tj` and diameters
    /// `di`, `dj`; zero beyond the cut-off.
    fn force_over_r(&self, r2: f64, ti: u32, tj: u32, di: f64, dj: f64) -> f64;
    /// Energy at squared distance `r2` (zero beyond the cut-off).
    fn energy(&self, r2: f64, ti: u32, tj: u32, di: f64, dj: f64) -> f64;
}

/// No pair interaction (ideal particles).
#[derive(Debug, Clone, Copy, Default)]
pub struct NoPair;

impl Pair for NoPair {
    #[inline]
    fn r_cut_max(&self) -> f64 {
        0.0
    }
    #[inline(always)]
    fn force_over_r(&self, _: f64, _: u32, _: u32, _: f64, _: f64) -> f64 {
        0.0
    }
    #[inline]
    fn energy(&self, _: f64, _: u32, _: u32, _: f64, _: f64) -> f64 {
        0.0
    }
}

/// Lennard-Jones parameters of one type pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LjParams {
    /// Well depth epsilon.
    pub epsilon: f64,
    /// Length sigma.
    pub sigma: f64,
    /// Cut-off radius (WCA: `2^(1/6) sigma`).
    pub r_cut: f64,
}

/// Lennard-Jones `4 eps [(s/r)^12 - (s/r)^6]`, cut at `r_cut` and shifted to zero there, with a
/// symmetric table of per-type parameters. WCA is the special case `r_cut = 2^(1/6) sigma`.
#[derive(Debug, Clone)]
pub struct LennardJones {
    n_types: usize,
    // Per type pair: sigma^2, 24 eps, 4 eps, r_cut^2, energy shift.
    table: Vec<[f64; 5]>,
    r_cut_max: f64,
}

impl LennardJones {
    /// One type: WCA with `epsilon`, `sigma`.
    pub fn wca(epsilon: f64, sigma: f64) -> Self {
        Self::new(
            1,
            &[LjParams {
                epsilon,
                sigma,
                r_cut: 2f64.powf(1.0 / 6.0) * sigma,
            }],
        )
    }

    /// `n_types` types with parameters for each unordered pair in the order
    /// (0,0), (0,1), ..., (0,n-1), (1,1), (1,2), ...
    pub fn new(n_types: usize, pairs: &[LjParams]) -> Self {
        assert_eq!(
            pairs.len(),
            n_types * (n_types + 1) / 2,
            "one parameter set per unordered type pair"
        );
        let mut table = vec![[0.0; 5]; n_types * n_types];
        let mut k = 0;
        let mut r_cut_max: f64 = 0.0;
        for a in 0..n_types {
            for b in a..n_types {
                let p = pairs[k];
                k += 1;
                let s2 = p.sigma * p.sigma;
                let sr6 = (s2 / (p.r_cut * p.r_cut)).powi(3);
                let shift = 4.0 * p.epsilon * (sr6 * sr6 - sr6);
                let row = [
                    s2,
                    24.0 * p.epsilon,
                    4.0 * p.epsilon,
                    p.r_cut * p.r_cut,
                    shift,
                ];
                table[a * n_types + b] = row;
                table[b * n_types + a] = row;
                r_cut_max = r_cut_max.max(p.r_cut);
            }
        }
        Self {
            n_types,
            table,
            r_cut_max,
        }
    }
}

impl Pair for LennardJones {
    #[inline]
    fn r_cut_max(&self) -> f64 {
        self.r_cut_max
    }

    #[inline(always)]
    fn force_over_r(&self, r2: f64, ti: u32, tj: u32, _: f64, _: f64) -> f64 {
        let [s2, e24, _, rc2, _] = self.table[ti as usize * self.n_types + tj as usize];
        // Evaluated unconditionally and selected (no branch to mispredict: about half of a
        // Verlet list's entries lie in the skin, beyond the cut-off).
        let ir2 = 1.0 / r2;
        let sr6 = (s2 * ir2) * (s2 * ir2) * (s2 * ir2);
        let f = e24 * sr6 * (2.0 * sr6 - 1.0) * ir2;
        if r2 < rc2 { f } else { 0.0 }
    }

    #[inline]
    fn energy(&self, r2: f64, ti: u32, tj: u32, _: f64, _: f64) -> f64 {
        let [s2, _, e4, rc2, shift] = self.table[ti as usize * self.n_types + tj as usize];
        if r2 >= rc2 {
            return 0.0;
        }
        let sr6 = (s2 / r2).powi(3);
        e4 * (sr6 * sr6 - sr6) - shift
    }
}

/// Morse attraction on the surface distance `h = r - (d_i + d_j)/2`:
/// `U = D [exp(-2 kappa (h - h0)) - 2 exp(-kappa (h - h0))]` for `h < h_cut`, shifted to zero at
/// `h_cut`. One parameter set for all type pairs (diameters come from the particles).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Morse {
    /// Well depth D.
    pub depth: f64,
    /// Inverse range kappa.
    pub kappa: f64,
    /// Surface distance of the minimum h0.
    pub h0: f64,
    /// Surface-distance cut-off.
    pub h_cut: f64,
    /// Largest diameter present (sets the neighbour range).
    pub d_max: f64,
}

impl Morse {
    #[inline(always)]
    fn u_and_du(&self, h: f64) -> (f64, f64) {
        let e = (-self.kappa * (h - self.h0)).exp();
        (
            self.depth * (e * e - 2.0 * e),
            self.depth * self.kappa * (-2.0 * e * e + 2.0 * e),
        )
    }
}

impl Pair for Morse {
    #[inline]
    fn r_cut_max(&self) -> f64 {
        self.d_max + self.h_cut
    }

    #[inline(always)]
    fn force_over_r(&self, r2: f64, _: u32, _: u32, di: f64, dj: f64) -> f64 {
        let r = r2.sqrt();
        let h = r - 0.5 * (di + dj);
        if h >= self.h_cut {
            return 0.0;
        }
        -self.u_and_du(h).1 / r
    }

    #[inline]
    fn energy(&self, r2: f64, _: u32, _: u32, di: f64, dj: f64) -> f64 {
        let h = r2.sqrt() - 0.5 * (di + dj);
        if h >= self.h_cut {
            return 0.0;
        }
        self.u_and_du(h).0 - self.u_and_du(self.h_cut).0
    }
}

/// The sum of two pair potentials (e.g. WCA core plus Morse attraction).
#[derive(Debug, Clone)]
pub struct PairSum<A, B>(pub A, pub B);

impl<A: Pair, B: Pair> Pair for PairSum<A, B> {
    #[inline]
    fn r_cut_max(&self) -> f64 {
        self.0.r_cut_max().max(self.1.r_cut_max())
    }
    #[inline(always)]
    fn force_over_r(&self, r2: f64, ti: u32, tj: u32, di: f64, dj: f64) -> f64 {
        self.0.force_over_r(r2, ti, tj, di, dj) + self.1.force_over_r(r2, ti, tj, di, dj)
    }
    #[inline]
    fn energy(&self, r2: f64, ti: u32, tj: u32, di: f64, dj: f64) -> f64 {
        self.0.energy(r2, ti, tj, di, dj) + self.1.energy(r2, ti, tj, di, dj)
    }
}

/// A one-body force field that may depend on time.
pub trait External: Sync + Send {
    /// Force on a particle at (wrapped) position `p` at time `t`.
    fn force(&self, p: [f64; 3], t: f64) -> [f64; 3];
    /// Energy of a particle at `p` at time `t`.
    fn energy(&self, p: [f64; 3], t: f64) -> f64;
    /// Force on a particle of diameter `d` at `p` at time `t` (the engines call this; a field
    /// that acts alike on every size keeps the default, [`External::force`]).
    #[inline(always)]
    fn force_on(&self, p: [f64; 3], t: f64, _d: f64) -> [f64; 3] {
        self.force(p, t)
    }
    /// Energy of a particle of diameter `d` at `p` at time `t`.
    #[inline]
    fn energy_of(&self, p: [f64; 3], t: f64, _d: f64) -> f64 {
        self.energy(p, t)
    }
    /// A hard wall of the field: how far `s > 0` a particle of diameter `d` that a step ending
    /// at time `t` left at `p` lies beyond it, and the wall's outward unit normal `n` there
    /// (the engines reflect it to `p - 2 s n`, moving the others with it where the mobility
    /// couples them); `None` inside, and for a field without one (the default).
    #[inline(always)]
    fn overshoot(&self, _p: [f64; 3], _t: f64, _d: f64) -> Option<(f64, [f64; 3])> {
        None
    }
    /// The outward normal velocity at time `t` of the hard wall of [`External::overshoot`]
    /// (negative for a wall moving in): engines with inertia reflect a velocity in the wall's
    /// frame. 0 (the default): a wall at rest.
    #[inline]
    fn wall_speed(&self, _t: f64) -> f64 {
        0.0
    }
}

/// No external field.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoExternal;

impl External for NoExternal {
    #[inline(always)]
    fn force(&self, _: [f64; 3], _: f64) -> [f64; 3] {
        [0.0; 3]
    }
    #[inline]
    fn energy(&self, _: [f64; 3], _: f64) -> f64 {
        0.0
    }
}

/// A constant body force on every particle (e.g. gravity less buoyancy, for sedimentation).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ConstantForce(pub [f64; 3]);

impl External for ConstantForce {
    #[inline(always)]
    fn force(&self, _: [f64; 3], _: f64) -> [f64; 3] {
        self.0
    }
    #[inline]
    fn energy(&self, p: [f64; 3], _: f64) -> f64 {
        -(self.0[0] * p[0] + self.0[1] * p[1] + self.0[2] * p[2])
    }
}

/// Sphere whose surface area falls linearly: `R(t) = sqrt(R0^2 - alpha t / (4 pi))`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereAreaLaw {
    /// Initial radius.
    pub r0: f64,
    /// Rate of loss of surface area (0: static sphere).
    pub alpha: f64,
}

impl SphereAreaLaw {
    /// Radius at time `t` (clamped at 0).
    #[inline(always)]
    pub fn radius(&self, t: f64) -> f64 {
        (self.r0 * self.r0 - self.alpha * t / (4.0 * PI))
            .max(0.0)
            .sqrt()
    }

    /// `dR/dt = -alpha / (8 pi R)` (0 once the sphere has vanished).
    #[inline]
    pub fn speed(&self, t: f64) -> f64 {
        let r = self.radius(t);
        if r > 0.0 {
            -self.alpha / (8.0 * PI * r)
        } else {
            0.0
        }
    }
}

/// The droplet interface of the drying-droplet paper: with `s = |p - centre| - (R(t) + offset)`, `V = 0` for
/// `s < 0`, `V = k s^2 / 2` for `0 <= s < range`, `V = k range^2 / 2 + k range (s - range)` beyond.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicInterface {
    /// Centre of the droplet.
    pub centre: [f64; 3],
    /// Radius law.
    pub radius: SphereAreaLaw,
    /// Spring constant k.
    pub stiffness: f64,
    /// Range of the harmonic part.
    pub range: f64,
    /// Offset of the wall from R(t).
    pub offset: f64,
}

impl External for HarmonicInterface {
    #[inline(always)]
    fn force(&self, p: [f64; 3], t: f64) -> [f64; 3] {
        let d = [
            p[0] - self.centre[0],
            p[1] - self.centre[1],
            p[2] - self.centre[2],
        ];
        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let wall = self.radius.radius(t) + self.offset;
        if r2 <= wall * wall {
            return [0.0; 3];
        }
        let r = r2.sqrt();
        let s = r - wall;
        let f = -self.stiffness * s.min(self.range) / r;
        [f * d[0], f * d[1], f * d[2]]
    }

    #[inline]
    fn energy(&self, p: [f64; 3], t: f64) -> f64 {
        let d = [
            p[0] - self.centre[0],
            p[1] - self.centre[1],
            p[2] - self.centre[2],
        ];
        let s = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
            - (self.radius.radius(t) + self.offset);
        if s <= 0.0 {
            0.0
        } else if s < self.range {
            0.5 * self.stiffness * s * s
        } else {
            self.stiffness * self.range * (s - 0.5 * self.range)
        }
    }
}

/// The droplet interface acting on spheres of several sizes: its `offset` places the wall for
/// spheres of `reference_diameter`, and a sphere of diameter `d` meets it `(d - reference) / 2`
/// further in, so every sphere's surface (not its centre) stops at the same place:
/// `wall(d) = R(t) + offset - (d - reference) / 2`. With one size it is [`HarmonicInterface`].
///
/// `hard`: the limit of an infinitely stiff interface instead, a hard wall at `wall(d)` (the
/// spring's stiffness and range unused): no force, and a step that ends a distance `s` beyond
/// the wall ends `s` inside it ([`External::overshoot`]: reflection, exact for a free Brownian
/// step at a flat wall; here the wall is a sphere that moves in).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeciesInterface {
    /// The interface for spheres of the reference diameter.
    pub interface: HarmonicInterface,
    /// The reference diameter (the smallest species').
    pub reference_diameter: f64,
    /// A hard wall instead of the spring.
    pub hard: bool,
}

impl SpeciesInterface {
    #[inline(always)]
    fn for_size(&self, d: f64) -> HarmonicInterface {
        let mut w = self.interface;
        w.offset -= 0.5 * (d - self.reference_diameter);
        w
    }
}

impl External for SpeciesInterface {
    #[inline(always)]
    fn force(&self, p: [f64; 3], t: f64) -> [f64; 3] {
        self.force_on(p, t, self.reference_diameter)
    }
    #[inline]
    fn energy(&self, p: [f64; 3], t: f64) -> f64 {
        self.energy_of(p, t, self.reference_diameter)
    }
    #[inline(always)]
    fn force_on(&self, p: [f64; 3], t: f64, d: f64) -> [f64; 3] {
        if self.hard {
            return [0.0; 3];
        }
        self.for_size(d).force(p, t)
    }
    /// The hard wall's energy is 0 inside and infinite beyond.
    #[inline]
    fn energy_of(&self, p: [f64; 3], t: f64, d: f64) -> f64 {
        match (self.hard, self.overshoot(p, t, d)) {
            (false, _) => self.for_size(d).energy(p, t),
            (true, None) => 0.0,
            (true, Some(_)) => f64::INFINITY,
        }
    }
    /// The hard wall: a centre at distance `r > wall(d)` from the centre of the droplet is
    /// `s = r - wall(d)` beyond it, the normal radial.
    #[inline(always)]
    fn overshoot(&self, p: [f64; 3], t: f64, d: f64) -> Option<(f64, [f64; 3])> {
        if !self.hard {
            return None;
        }
        let w = self.for_size(d);
        let c = [p[0] - w.centre[0], p[1] - w.centre[1], p[2] - w.centre[2]];
        let r2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
        let wall = w.radius.radius(t) + w.offset;
        if r2 <= wall * wall {
            return None;
        }
        let r = r2.sqrt();
        Some((r - wall, [c[0] / r, c[1] / r, c[2] / r]))
    }
    /// The hard wall moves with the radius, `dR/dt`.
    #[inline]
    fn wall_speed(&self, t: f64) -> f64 {
        if self.hard {
            self.interface.radius.speed(t)
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_force_is_minus_gradient<P: Pair>(p: &P, d: f64, r_lo: f64, r_hi: f64) {
        for k in 0..50 {
            let r = r_lo + (r_hi - r_lo) * (k as f64 + 0.5) / 50.0;
            let h = 1e-6;
            let du = (p.energy((r + h) * (r + h), 0, 0, d, d)
                - p.energy((r - h) * (r - h), 0, 0, d, d))
                / (2.0 * h);
            let f = p.force_over_r(r * r, 0, 0, d, d) * r;
            assert!(
                (f + du).abs() < 1e-5 * (1.0 + du.abs()),
                "r {r}: F {f} vs -dU/dr {}",
                -du
            );
        }
    }

    #[test]
    fn forces_are_minus_gradients_and_vanish_at_the_cut() {
        let wca = LennardJones::wca(1.0, 1.0);
        check_force_is_minus_gradient(&wca, 1.0, 0.9, 1.2);
        let rc = 2f64.powf(1.0 / 6.0);
        assert!(wca.energy(rc * rc * 0.999_999, 0, 0, 1.0, 1.0).abs() < 1e-5);
        assert_eq!(wca.force_over_r(rc * rc, 0, 0, 1.0, 1.0), 0.0);
        // u(1) = 4 (1 - 1) + 1 = 1 for the shifted WCA.
        assert!((wca.energy(1.0, 0, 0, 1.0, 1.0) - 1.0).abs() < 1e-12);
        let morse = Morse {
            depth: 2.0,
            kappa: 10.0,
            h0: 0.02,
            h_cut: 0.3,
            d_max: 1.0,
        };
        check_force_is_minus_gradient(&morse, 1.0, 0.98, 1.35);
        check_force_is_minus_gradient(&PairSum(wca, morse), 1.0, 0.95, 1.35);
    }

    #[test]
    fn interface_force_is_minus_gradient_and_zero_inside() {
        let w = HarmonicInterface {
            centre: [0.5, 0.0, 0.0],
            radius: SphereAreaLaw {
                r0: 5.0,
                alpha: 0.0,
            },
            stiffness: 50.0,
            range: 0.5,
            offset: -0.5,
        };
        assert_eq!(w.force([1.0, 1.0, 1.0], 0.0), [0.0; 3]);
        for r in [4.6, 4.8, 4.99, 5.2, 6.0] {
            let p = [0.5 + r * 0.6, r * 0.8, 0.0];
            let f = w.force(p, 0.0);
            let h = 1e-6;
            for k in 0..3 {
                let (mut a, mut b) = (p, p);
                a[k] += h;
                b[k] -= h;
                let g = (w.energy(a, 0.0) - w.energy(b, 0.0)) / (2.0 * h);
                assert!((f[k] + g).abs() < 1e-5, "r {r} k {k}: {} vs {}", f[k], -g);
            }
        }
        // Sized: a sphere of diameter 2 meets the wall half a diameter of 1 further in; one of
        // the reference size feels the plain interface, bit for bit.
        let s = SpeciesInterface {
            interface: w,
            reference_diameter: 1.0,
            hard: false,
        };
        let p = [0.5 + 4.4, 0.0, 0.0];
        assert_eq!(s.force_on(p, 0.0, 1.0), w.force(p, 0.0));
        assert!((s.force_on(p, 0.0, 2.0)[0] + 50.0 * 0.4).abs() < 1e-12);
        assert!((s.energy_of(p, 0.0, 2.0) - 0.5 * 50.0 * 0.4f64.powi(2)).abs() < 1e-12);
        let law = SphereAreaLaw {
            r0: 25.0,
            alpha: 4.0 * PI,
        };
        assert!((law.radius(625.0 - 9.0) - 3.0).abs() < 1e-12);
    }
}
