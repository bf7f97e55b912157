//! The Rotne–Prager–Yamakawa pair tensor in an unbounded fluid.
//!
//! Every tensor here has the form `M_ij = A(r) I + B(r) r̂r̂` (r = x_i − x_j); [`PairTensor`]
//! stores `(A, B)`. Monodisperse spheres of radius a in a fluid of viscosity eta
//! (the drying-droplet paper, docs/references.md; Rotne & Prager 1969, Yamakawa 1970), with `mu0 = 1 / (6 pi eta a)`:
//!
//! - self: `M_ii = mu0 I`;
//! - `r >= 2a`: `M_ij = 1/(8 pi eta r) [(1 + 2a^2/(3 r^2)) I + (1 − 2a^2/r^2) r̂r̂]`;
//! - `r < 2a` (overlapping): `M_ij = mu0 [(1 − 9 r/(32 a)) I + (3 r/(32 a)) r̂r̂]`.
//!
//! Unequal radii a_i, a_j (Zuk, Wajnryb, Mizerski & Szymczak, J. Fluid Mech. 741, R5 (2014),
//! Eqs. 2.4–2.6):
//!
//! - `r > a_i + a_j`: `1/(8 pi eta r) [(1 + (a_i^2 + a_j^2)/(3 r^2)) I + (1 − (a_i^2 + a_j^2)/r^2) r̂r̂]`;
//! - `|a_i − a_j| < r <= a_i + a_j`: `1/(6 pi eta a_i a_j) {[16 r^3 (a_i + a_j) − ((a_i − a_j)^2 + 3 r^2)^2] / (32 r^3) I
//!   + 3 ((a_i − a_j)^2 − r^2)^2 / (32 r^3) r̂r̂}`;
//! - `r <= |a_i − a_j|` (one sphere inside the other): `1/(6 pi eta max(a_i, a_j)) I`.
//!
//! The tensor is continuous across both branch points and positive definite for any
//! configuration; its divergence with respect to the positions vanishes
//! (`sum_j d/dx_j . M_ij = 0`), so Brownian dynamics with it needs no drift term.

use std::f64::consts::PI;

/// `M = a I + b r̂r̂`: the scalar functions of an isotropic pair tensor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairTensor {
    /// Coefficient of the identity.
    pub a: f64,
    /// Coefficient of `r̂r̂`.
    pub b: f64,
}

impl PairTensor {
    /// The 3x3 matrix `a I + b r̂r̂` for the separation `d` (`r̂ = d / |d|`; `d = 0`: `a I`).
    pub fn matrix(&self, d: [f64; 3]) -> [[f64; 3]; 3] {
        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let mut m = [[0.0; 3]; 3];
        for p in 0..3 {
            for q in 0..3 {
                let rr = if r2 > 0.0 { d[p] * d[q] / r2 } else { 0.0 };
                m[p][q] = if p == q { self.a } else { 0.0 } + self.b * rr;
            }
        }
        m
    }
}

/// Monodisperse RPY pair tensor of two spheres of radius `a` at distance `r` in a fluid of
/// viscosity `eta` (both branches; `r = 0` gives the self term `mu0 I`).
pub fn rpy(r: f64, a: f64, eta: f64) -> PairTensor {
    let mu0 = 1.0 / (6.0 * PI * eta * a);
    if r >= 2.0 * a {
        let c = 1.0 / (8.0 * PI * eta * r);
        let s2 = a * a / (r * r);
        PairTensor {
            a: c * (1.0 + 2.0 / 3.0 * s2),
            b: c * (1.0 - 2.0 * s2),
        }
    } else {
        PairTensor {
            a: mu0 * (1.0 - 9.0 * r / (32.0 * a)),
            b: mu0 * 3.0 * r / (32.0 * a),
        }
    }
}

/// The far branch of the monodisperse RPY tensor (the `r >= 2a` formula at any `r > 0`):
/// the tensor whose periodic sum Beenakker's Ewald formulas give.
pub fn rpy_far(r: f64, a: f64, eta: f64) -> PairTensor {
    let c = 1.0 / (8.0 * PI * eta * r);
    let s2 = a * a / (r * r);
    PairTensor {
        a: c * (1.0 + 2.0 / 3.0 * s2),
        b: c * (1.0 - 2.0 * s2),
    }
}

/// RPY pair tensor of spheres of radii `ai`, `aj` at distance `r` (Zuk et al. 2014; all three
/// branches). Equal radii give [`rpy`].
pub fn rpy_unequal(r: f64, ai: f64, aj: f64, eta: f64) -> PairTensor {
    let sum = ai + aj;
    let diff = (ai - aj).abs();
    if r > sum {
        let c = 1.0 / (8.0 * PI * eta * r);
        let s2 = (ai * ai + aj * aj) / (r * r);
        PairTensor {
            a: c * (1.0 + s2 / 3.0),
            b: c * (1.0 - s2),
        }
    } else if r > diff {
        let c = 1.0 / (6.0 * PI * eta * ai * aj * 32.0 * r * r * r);
        let q = diff * diff + 3.0 * r * r;
        let p = diff * diff - r * r;
        PairTensor {
            a: c * (16.0 * r * r * r * sum - q * q),
            b: c * 3.0 * p * p,
        }
    } else {
        PairTensor {
            a: 1.0 / (6.0 * PI * eta * ai.max(aj)),
            b: 0.0,
        }
    }
}

/// The pair block of [`crate::Mobility::pair_block`] for the separation `d = x_i - x_j` of
/// spheres of radii `ai`, `aj`: the unit vector `r̂` (any unit vector at `d = 0`) and
/// [`rpy_unequal`].
pub fn pair_block(d: [f64; 3], ai: f64, aj: f64, eta: f64) -> ([f64; 3], PairTensor) {
    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let e = if r > 0.0 {
        d.map(|c| c / r)
    } else {
        [0.0, 0.0, 1.0]
    };
    (e, rpy_unequal(r, ai, aj, eta))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn branches_meet_at_contact_and_self_term_is_stokes() {
        let (a, eta) = (0.7, 1.3);
        let mu0 = 1.0 / (6.0 * PI * eta * a);
        let t0 = rpy(0.0, a, eta);
        assert_eq!(t0, PairTensor { a: mu0, b: 0.0 });
        let inside = rpy(2.0 * a * (1.0 - 1e-12), a, eta);
        let outside = rpy(2.0 * a, a, eta);
        assert!((inside.a - outside.a).abs() < 1e-10 * mu0);
        assert!((inside.b - outside.b).abs() < 1e-10 * mu0);
        // At contact: A = mu0 (1 - 9/16) = 7/16 mu0, B = 3/16 mu0.
        assert!((outside.a - 7.0 / 16.0 * mu0).abs() < 1e-14);
        assert!((outside.b - 3.0 / 16.0 * mu0).abs() < 1e-14);
    }

    #[test]
    fn unequal_radii_reduce_to_monodisperse_and_are_continuous() {
        let eta = 0.9;
        for &r in &[0.0, 0.3, 0.9, 1.4, 1.99, 2.0, 2.5, 7.0] {
            let (m, u) = (rpy(r, 1.0, eta), rpy_unequal(r, 1.0, 1.0, eta));
            assert!(
                (m.a - u.a).abs() < 1e-14 && (m.b - u.b).abs() < 1e-14,
                "r = {r}"
            );
        }
        let (ai, aj) = (1.0, 0.4);
        for &rb in &[ai + aj, ai - aj] {
            let lo = rpy_unequal(rb * (1.0 - 1e-10), ai, aj, eta);
            let hi = rpy_unequal(rb * (1.0 + 1e-10), ai, aj, eta);
            assert!((lo.a - hi.a).abs() < 1e-8, "{rb}: {lo:?} {hi:?}");
            assert!((lo.b - hi.b).abs() < 1e-8, "{rb}: {lo:?} {hi:?}");
        }
        // Symmetric in the radii.
        let (x, y) = (rpy_unequal(1.1, ai, aj, eta), rpy_unequal(1.1, aj, ai, eta));
        assert_eq!(x, y);
    }

    /// `(A, B)` of the RPY tensor from its definition, the Stokeslet averaged over the two
    /// sphere surfaces: in Fourier space `sinc(k a_i) sinc(k a_j) (I − k̂k̂) / (eta k^2)`, so
    /// `A = 1/(2 pi^2 eta) int_0^inf sinc(k a_i) sinc(k a_j) [j0(kr) − j1(kr)/(kr)] dk` and
    /// `B = 1/(2 pi^2 eta) int_0^inf sinc(k a_i) sinc(k a_j) j2(kr) dk` (Simpson's rule to
    /// k = 600; the integrands fall as k^-3).
    fn fourier_rpy(r: f64, ai: f64, aj: f64, eta: f64) -> (f64, f64) {
        let sinc = |x: f64| {
            if x < 1e-3 {
                1.0 - x * x / 6.0
            } else {
                x.sin() / x
            }
        };
        let f = |k: f64| {
            let x = k * r;
            let (p, q) = if x < 1e-2 {
                (2.0 / 3.0 - x * x / 10.0, x * x / 15.0)
            } else {
                let (s, c) = x.sin_cos();
                let j0 = s / x;
                let j1 = s / (x * x) - c / x;
                let j2 = (3.0 / (x * x) - 1.0) * s / x - 3.0 * c / (x * x);
                (j0 - j1 / x, j2)
            };
            let w = sinc(k * ai) * sinc(k * aj);
            (w * p, w * q)
        };
        let (k_max, m) = (600.0, 600_000);
        let h = k_max / m as f64;
        let (mut sa, mut sb) = (0.0, 0.0);
        for i in 0..=m {
            let c = if i == 0 || i == m {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let (p, q) = f(i as f64 * h);
            sa += c * p;
            sb += c * q;
        }
        let pre = h / 3.0 / (2.0 * PI * PI * eta);
        (pre * sa, pre * sb)
    }

    #[test]
    fn unequal_radii_match_the_fourier_definition_in_all_three_branches() {
        // Zuk et al. (2014) Eqs. for r > a_i + a_j (apart), |a_i − a_j| < r <= a_i + a_j
        // (overlapping) and r <= |a_i − a_j| (the small sphere inside the large one).
        let (ai, aj, eta) = (1.0, 0.4, 1.3);
        let mu = 1.0 / (6.0 * PI * eta * ai);
        for r in [0.2, 0.5, 0.9, 1.2, 1.6, 3.0] {
            let t = rpy_unequal(r, ai, aj, eta);
            let (a, b) = fourier_rpy(r, ai, aj, eta);
            assert!(
                (t.a - a).abs() < 2e-5 * mu && (t.b - b).abs() < 2e-5 * mu,
                "r {r}: closed form {t:?}, Fourier ({a}, {b})"
            );
        }
        // The inner branch is exactly the larger sphere's Stokes mobility.
        assert_eq!(rpy_unequal(0.3, ai, aj, eta), PairTensor { a: mu, b: 0.0 });
    }
}
