//! Pair forces of the DPD colloid model (the DPD notes, docs/references.md).
//!
//! All forces act along `e_ij = (x_i - x_j) / r` on the surface gap `h = r - (a_i + a_j)`; a
//! positive magnitude pushes `i` away from `j`. Solvent beads are point particles (`a = 0`).

/// The parameters of the colloid–colloid interactions that DPD lacks: contact, Morse and
/// squeeze-mode lubrication. All lengths are surface gaps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColloidForces {
    /// Contact modulus `f_c` (force; the notes quote `10000 kT / rc`).
    pub contact: f64,
    /// Contact range `Delta` (surface roughness).
    pub contact_range: f64,
    /// Morse depth `D0` (energy; 0 switches Morse off).
    pub morse_depth: f64,
    /// Morse inverse range `kappa`.
    pub morse_kappa: f64,
    /// Morse minimum `r0` (surface gap).
    pub morse_r0: f64,
    /// Background viscosity `eta0` of the squeeze lubrication (0 switches it off).
    pub eta0: f64,
    /// Gap `delta` below which the lubrication coefficient stops growing.
    pub lubrication_gap: f64,
}

impl ColloidForces {
    /// Contact force magnitude (two-piece, continuous at `h = 0`):
    /// `f_c abar^3 (1 - h)` for `h < 0`, `f_c abar^3 (1 - h / Delta)^3` for `0 <= h <= Delta`,
    /// 0 beyond.
    #[inline(always)]
    pub fn contact_force(&self, h: f64, abar: f64) -> f64 {
        let f0 = self.contact * abar * abar * abar;
        if h < 0.0 {
            f0 * (1.0 - h)
        } else if h < self.contact_range {
            let u = 1.0 - h / self.contact_range;
            f0 * u * u * u
        } else {
            0.0
        }
    }

    /// Potential of [`Self::contact_force`] (zero beyond `Delta`):
    /// `f_c abar^3 Delta (1 - h / Delta)^4 / 4` on `[0, Delta]`, continued for `h < 0` by
    /// `f_c abar^3 (Delta / 4 - h + h^2 / 2)`.
    pub fn contact_energy(&self, h: f64, abar: f64) -> f64 {
        let f0 = self.contact * abar * abar * abar;
        let d = self.contact_range;
        if h < 0.0 {
            f0 * (0.25 * d - h + 0.5 * h * h)
        } else if h < d {
            let u = 1.0 - h / d;
            0.25 * f0 * d * u * u * u * u
        } else {
            0.0
        }
    }

    /// Morse force `-dU/dh = 2 kappa D0 [exp(-2 kappa (h - r0)) - exp(-kappa (h - r0))]`.
    #[inline(always)]
    pub fn morse_force(&self, h: f64) -> f64 {
        let e1 = (-self.morse_kappa * (h - self.morse_r0)).exp();
        2.0 * self.morse_kappa * self.morse_depth * (e1 * e1 - e1)
    }

    /// Morse potential `U = D0 [exp(-2 kappa (h - r0)) - 2 exp(-kappa (h - r0))]`.
    pub fn morse_energy(&self, h: f64) -> f64 {
        let e1 = (-self.morse_kappa * (h - self.morse_r0)).exp();
        self.morse_depth * (e1 * e1 - 2.0 * e1)
    }

    /// Squeeze-mode lubrication coefficient `a_sq = (3 pi eta0 / 2) abar^2 / max(h, delta)`
    /// (Ball & Melrose 1997, appendix A).
    #[inline(always)]
    pub fn squeeze_coefficient(&self, h: f64, abar: f64) -> f64 {
        1.5 * std::f64::consts::PI * self.eta0 * abar * abar / h.max(self.lubrication_gap)
    }
}

/// How the random force of a colloid–colloid pair with lubrication is weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LubricationNoise {
    /// `sqrt(2 kT (gamma w^2 + a_sq) / dt) theta`: the variance matches the friction
    /// `gamma w^2 + a_sq` at every gap, so fluctuation–dissipation holds exactly.
    #[default]
    Exact,
    /// The authors' code: `sqrt(2 kT (gamma + a_sq) / dt) w theta`, which holds only as w -> 1
    /// (kept to reproduce published runs and to show the difference).
    Authors,
}

/// A key for the pair random numbers of one step: different steps and seeds give unrelated keys.
#[inline]
pub fn step_key(seed: u32, step: u64) -> u64 {
    fmix64(fmix64(step ^ 0x9E37_79B9_7F4A_7C15) ^ ((seed as u64) << 32 | 0x5851_F42D))
}

/// The symmetric pair random number `theta_ij = theta_ji` of a step: uniform on
/// `[-sqrt 3, sqrt 3)` (zero mean, unit variance), a pure function of (step key, the unordered
/// pair of tags) — counter-based, so independent of threads and storage order.
#[inline(always)]
pub fn pair_noise(key: u64, tag_i: u32, tag_j: u32) -> f64 {
    let (lo, hi) = if tag_i < tag_j {
        (tag_i, tag_j)
    } else {
        (tag_j, tag_i)
    };
    let x = fmix64(fmix64(((hi as u64) << 32 | lo as u64) ^ key) ^ key.rotate_left(29));
    // 53 random bits -> [0, 1) -> [-sqrt 3, sqrt 3).
    let u = (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    (2.0 * u - 1.0) * SQRT3
}

const SQRT3: f64 = 1.732_050_807_568_877_2;

/// MurmurHash3's 64-bit finaliser (a bijection with full avalanche).
#[inline(always)]
fn fmix64(mut x: u64) -> u64 {
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51_afd7_ed55_8ccd);
    x ^= x >> 33;
    x = x.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    x ^ (x >> 33)
}

/// Colloid–solvent surface cut-off `rc' = (rc^3 + R^3)^(1/3) - R`, which gives a colloid the
/// same interaction volume as a solvent bead (notes, "colloid–solvent").
pub fn colloid_solvent_cutoff(rc: f64, radius: f64) -> f64 {
    (rc.powi(3) + radius.powi(3)).cbrt() - radius
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> ColloidForces {
        ColloidForces {
            contact: 1000.0,
            contact_range: 1e-3,
            morse_depth: 1.2,
            morse_kappa: 30.0,
            morse_r0: 0.0,
            eta0: 0.3,
            lubrication_gap: 1e-3,
        }
    }

    /// Central difference of `u` at `h` with step `eps`.
    fn derivative(u: impl Fn(f64) -> f64, h: f64, eps: f64) -> f64 {
        (u(h + eps) - u(h - eps)) / (2.0 * eps)
    }

    #[test]
    fn contact_force_is_minus_the_derivative_of_its_potential() {
        let m = model();
        for abar in [0.7, 1.0, 1.3] {
            for h in [-0.02, -1e-4, 1e-4, 3e-4, 7e-4, 9.9e-4, 2e-3] {
                let fd = -derivative(|x| m.contact_energy(x, abar), h, 1e-8);
                let f = m.contact_force(h, abar);
                assert!(
                    (fd - f).abs() <= 1e-6 * f.abs().max(1.0),
                    "h {h}: force {f}, -dU/dh {fd}"
                );
            }
        }
        // Continuous at h = 0 and at Delta.
        assert!((m.contact_force(-1e-12, 1.0) - m.contact_force(0.0, 1.0)).abs() < 1e-6);
        assert!(m.contact_force(1e-3 - 1e-12, 1.0).abs() < 1e-20);
        // A wrong exponent would be caught: (1 - h/Delta)^2 differs from -dU/dh by far more.
        let h = 5e-4;
        let wrong = 1000.0 * (1.0 - h / 1e-3_f64).powi(2);
        let fd = -derivative(|x| m.contact_energy(x, 1.0), h, 1e-8);
        assert!((wrong - fd).abs() > 0.1 * fd);
    }

    #[test]
    fn morse_force_is_minus_the_derivative_of_its_potential() {
        let m = model();
        for h in [-0.01, 0.0, 0.01, 0.023, 0.05, 0.1, 0.3] {
            let fd = -derivative(|x| m.morse_energy(x), h, 1e-7);
            let f = m.morse_force(h);
            assert!(
                (fd - f).abs() <= 1e-6 * f.abs().max(0.1), // FD rounding ~ 1e-16 U / eps ~ 1e-9
                "h {h}: force {f}, -dU/dh {fd}"
            );
        }
        // Minimum of depth D0 at r0.
        assert!((m.morse_energy(0.0) + 1.2).abs() < 1e-12);
        assert!(m.morse_force(0.0).abs() < 1e-12);
    }

    #[test]
    fn squeeze_coefficient_saturates_below_delta() {
        let m = model();
        let a1 = m.squeeze_coefficient(1e-4, 1.0);
        let a2 = m.squeeze_coefficient(-0.01, 1.0);
        assert_eq!(a1, a2);
        let exact = 1.5 * std::f64::consts::PI * 0.3 / 0.1;
        assert!((m.squeeze_coefficient(0.1, 1.0) - exact).abs() < 1e-12);
    }

    #[test]
    fn pair_noise_is_symmetric_with_unit_variance_and_uncorrelated() {
        let key = step_key(7, 11);
        assert_eq!(pair_noise(key, 3, 9), pair_noise(key, 9, 3));
        assert_ne!(pair_noise(key, 3, 9), pair_noise(step_key(7, 12), 3, 9));
        assert_ne!(pair_noise(key, 3, 9), pair_noise(step_key(8, 11), 3, 9));
        let n = 400_000u32;
        let (mut s1, mut s2, mut s12) = (0.0, 0.0, 0.0);
        let mut prev = 0.0;
        for k in 0..n {
            // Neighbouring tags and steps: the keys most likely to correlate.
            let x = pair_noise(step_key(1, (k % 64) as u64), k / 64, k / 64 + 1);
            s1 += x;
            s2 += x * x;
            s12 += x * prev;
            prev = x;
            assert!(x.abs() <= SQRT3);
        }
        let nf = n as f64;
        // Standard errors: mean 1/sqrt(n), variance sqrt(0.8/n) (uniform), covariance 1/sqrt(n).
        assert!((s1 / nf).abs() < 5.0 / nf.sqrt());
        assert!((s2 / nf - 1.0).abs() < 5.0 * (0.8 / nf).sqrt());
        assert!((s12 / nf).abs() < 5.0 / nf.sqrt());
    }

    #[test]
    fn colloid_solvent_cutoff_matches_the_notes() {
        // R = 1, rc = 1: centre cut-off 2^(1/3) = 1.26, surface 0.26.
        let c = colloid_solvent_cutoff(1.0, 1.0);
        assert!((c - (2f64.cbrt() - 1.0)).abs() < 1e-15);
        // Interaction volume equals the solvent's for any radius.
        for r in [0.5, 1.0, 2.0, 3.7] {
            let c = colloid_solvent_cutoff(1.0, r);
            assert!(((r + c).powi(3) - r.powi(3) - 1.0).abs() < 1e-12);
        }
    }
}
