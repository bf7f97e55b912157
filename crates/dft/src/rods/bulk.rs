//! Exact homogeneous results for hard and sticky rods (checks of the inhomogeneous solver).
//!
//! Source: the isobaric solution of 1D nearest-neighbour fluids (Takahashi 1942; e.g. A. Santos,
//! *A Concise Course on the Theory of Classical Liquids*, Springer 2016, ch. 5). With the Laplace
//! transform of the Boltzmann factor `Omega(s) = int_0^inf e^{-s r} e^{-beta V(r)} dr`, which for
//! `exp(-beta V) = Theta(r - sigma) + gamma delta(r - sigma)` (Eq. 30) is
//! `Omega(s) = e^{-s sigma} (1/s + gamma)`, the pressure `p` follows from
//! `1/rho = -d ln Omega / ds` at `s = beta p`, i.e. `beta p (1 + gamma beta p) = rho / (1 - rho sigma)`,
//! the chemical potential from `beta mu = -ln Omega(beta p)` (thermal wavelength 1), and the
//! nearest-neighbour distance density `rho e^{-beta p r} e^{-beta V(r)} / Omega(beta p)`.
//! At `gamma = 0` these are the Tonks-gas results of the hard-rods paper, docs/references.md.

/// `beta p` of the homogeneous fluid at density `rho` (Tonks gas at `gamma = 0`).
pub fn beta_pressure(sigma: f64, gamma: f64, rho: f64) -> f64 {
    let x = rho / (1.0 - rho * sigma);
    // positive root of gamma P^2 + P - x = 0, cancellation-free
    2.0 * x / (1.0 + (1.0 + 4.0 * gamma * x).sqrt())
}

/// `beta mu = beta p sigma + ln(beta p / (1 + gamma beta p))`; at `gamma = 0`
/// `ln(rho/(1 - rho sigma)) + rho sigma/(1 - rho sigma)`.
pub fn beta_mu(sigma: f64, gamma: f64, rho: f64) -> f64 {
    let p = beta_pressure(sigma, gamma, rho);
    p * sigma + (p / (1.0 + gamma * p)).ln()
}

/// Regular part of the pair density at contact, `rho2(x, x + sigma^+) = rho beta p / (1 + gamma beta p)`;
/// `rho^2 / (1 - rho sigma)` at `gamma = 0`.
pub fn contact_density(sigma: f64, gamma: f64, rho: f64) -> f64 {
    let p = beta_pressure(sigma, gamma, rho);
    rho * p / (1.0 + gamma * p)
}

/// Density of bonded (touching) pairs per unit length, the weight of `delta(r - sigma)` in the pair
/// density: `gamma` times [`contact_density`].
pub fn bonded_pair_density(sigma: f64, gamma: f64, rho: f64) -> f64 {
    gamma * contact_density(sigma, gamma, rho)
}

/// `S(0)` of the homogeneous fluid: for a 1D nearest-neighbour fluid the structure factor at
/// `q = 0` is the variance of the nearest-neighbour distance over its squared mean,
/// `S(0) = rho^2 d^2 ln Omega / ds^2` at `s = beta p` (the same isobaric solution as above). For
/// Baxter's sticky rods this is `(1 + 2 gamma beta p) (1 - rho sigma)^2`, the Tonks gas's
/// `(1 - rho sigma)^2` at `gamma = 0`; equal to `1 / (d beta p / d rho)` (compressibility rule).
pub fn structure_factor_zero(sigma: f64, gamma: f64, rho: f64) -> f64 {
    let p = beta_pressure(sigma, gamma, rho);
    (1.0 + 2.0 * gamma * p) * (1.0 - rho * sigma).powi(2)
}

/// `S(0)` of rods with the finite-range sticky contact that BCD simulates (hard-rods paper
/// Eq. 33: `exp(-beta V(r)) = 1 + gamma (eps + sigma - r)^p / A` on `[sigma, sigma + eps]`,
/// `A = eps^(p+1) / (p + 1)`, so that the Boltzmann factor carries the weight `eps + gamma` there).
/// The Laplace transform `Omega(s)` of the Boltzmann factor is integrated by 64-point
/// Gauss–Legendre quadrature on the contact range plus the exact tail, `beta p` is found by
/// bisection from `1 / rho = -d ln Omega / ds`, and `S(0)` is the gap variance over the squared
/// mean gap. It tends to [`structure_factor_zero`] as `eps -> 0`.
pub fn structure_factor_zero_finite_range(
    sigma: f64,
    gamma: f64,
    eps: f64,
    order: f64,
    rho: f64,
) -> f64 {
    let (nodes, weights) = colloidsim_core::quadrature::gauss_legendre(64);
    let a = eps.powf(order + 1.0) / (order + 1.0);
    // The first three moments of r under e^{-s r} e^{-beta V(r)}, divided by e^{-s sigma}.
    let moments = |s: f64| {
        let mut m = [0.0; 3];
        for (&x, &w) in nodes.iter().zip(&weights) {
            let u = 0.5 * eps * (x + 1.0);
            let r = sigma + u;
            let f = 0.5 * eps * w * (1.0 + gamma * (eps - u).powf(order) / a) * (-s * u).exp();
            m[0] += f;
            m[1] += f * r;
            m[2] += f * r * r;
        }
        // Tail r > sigma + eps: e^{-s r} integrated exactly.
        let (e, c) = ((-s * eps).exp(), sigma + eps);
        m[0] += e / s;
        m[1] += e * (c / s + 1.0 / (s * s));
        m[2] += e * (c * c / s + 2.0 * c / (s * s) + 2.0 / (s * s * s));
        m
    };
    let mean_gap = |s: f64| {
        let m = moments(s);
        m[1] / m[0]
    };
    // The mean distance falls monotonically with s: bracket 1/rho and bisect.
    let target = 1.0 / rho;
    let (mut lo, mut hi) = (1e-12, 1.0);
    while mean_gap(hi) > target {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mean_gap(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let m = moments(0.5 * (lo + hi));
    let mean = m[1] / m[0];
    (m[2] / m[0] - mean * mean) / (mean * mean)
}

/// Long-time mean-square displacement of a tagged particle in a single file of Brownian
/// particles without hydrodynamics: `(2 S(0) / rho) sqrt(D_c t / pi)` with the collective
/// diffusion coefficient `D_c = D / S(0)` (Kollmann, Phys. Rev. Lett. 90, 180602 (2003)), i.e.
/// `(2 / rho) sqrt(S(0) D t / pi)`; for hard rods `(1 - rho sigma) / rho sqrt(4 D t / pi)`.
pub fn single_file_msd(s0: f64, rho: f64, diffusion: f64, t: f64) -> f64 {
    2.0 / rho * (s0 * diffusion * t / std::f64::consts::PI).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn structure_factor_obeys_the_compressibility_rule() {
        for &(sigma, gamma, rho) in &[(0.5, 0.0, 0.5), (0.5, 1.0, 0.5), (0.1, 10.0, 0.5)] {
            let h = 1e-5;
            let dp = (beta_pressure(sigma, gamma, rho + h) - beta_pressure(sigma, gamma, rho - h))
                / (2.0 * h);
            let s0 = structure_factor_zero(sigma, gamma, rho);
            assert!(
                (s0 * dp - 1.0).abs() < 1e-8,
                "{sigma} {gamma} {rho}: {}",
                s0 * dp
            );
        }
        assert!((structure_factor_zero(0.5, 0.0, 0.5) - 0.5625).abs() < 1e-15);
    }

    #[test]
    fn finite_range_structure_factor_tends_to_baxter() {
        let (sigma, rho) = (0.5, 0.5);
        // gamma = 0: the contact range carries weight eps and the model is the Tonks gas.
        let hard = structure_factor_zero_finite_range(sigma, 0.0, 0.05, 3.0, rho);
        assert!((hard - 0.5625).abs() < 1e-10, "{hard}");
        let baxter = structure_factor_zero(sigma, 1.0, rho);
        let mut last = f64::INFINITY;
        for eps in [0.05, 0.01, 0.002] {
            let d = (structure_factor_zero_finite_range(sigma, 1.0, eps, 3.0, rho) - baxter).abs();
            assert!(d < last, "eps {eps}: {d} not below {last}");
            last = d;
        }
        assert!(last < 2e-3 * baxter, "{last}");
    }

    #[test]
    fn single_file_law_of_hard_rods() {
        let (sigma, rho, t) = (0.5, 0.5, 50.0);
        let s0 = structure_factor_zero(sigma, 0.0, rho);
        let tonks = (1.0 - rho * sigma) / rho * (4.0 * t / std::f64::consts::PI).sqrt();
        assert!((single_file_msd(s0, rho, 1.0, t) - tonks).abs() < 1e-12);
    }
}
