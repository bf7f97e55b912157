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
