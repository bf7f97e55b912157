//! Bulk hard-sphere equation of state that Rosenfeld FMT reproduces: Percus–Yevick compressibility.
//!
//! With packing fraction `eta = pi rho d^3 / 6`:
//! - `beta P / rho = (1 + eta + eta^2) / (1 - eta)^3`,
//! - `beta mu_ex = -ln(1 - eta) + (14 eta - 13 eta^2 + 5 eta^3) / (2 (1 - eta)^3)`,
//! - `beta f_ex / rho = -ln(1 - eta) + 3 eta (2 - eta) / (2 (1 - eta)^2)`.

use std::f64::consts::PI;

/// Packing fraction `eta = pi rho d^3 / 6`.
pub fn packing_fraction(rho: f64, diameter: f64) -> f64 {
    PI * rho * diameter.powi(3) / 6.0
}

/// Number density of packing fraction `eta`.
pub fn density(eta: f64, diameter: f64) -> f64 {
    6.0 * eta / (PI * diameter.powi(3))
}

/// `beta P` (PY compressibility).
pub fn pressure(rho: f64, diameter: f64) -> f64 {
    let e = packing_fraction(rho, diameter);
    rho * (1.0 + e + e * e) / (1.0 - e).powi(3)
}

/// `beta mu_ex` (PY compressibility).
pub fn excess_chemical_potential(rho: f64, diameter: f64) -> f64 {
    let e = packing_fraction(rho, diameter);
    -(1.0 - e).ln() + (14.0 * e - 13.0 * e * e + 5.0 * e.powi(3)) / (2.0 * (1.0 - e).powi(3))
}

/// Excess free-energy density `beta f_ex` (per volume).
pub fn excess_free_energy_density(rho: f64, diameter: f64) -> f64 {
    let e = packing_fraction(rho, diameter);
    rho * (-(1.0 - e).ln() + 3.0 * e * (2.0 - e) / (2.0 * (1.0 - e).powi(2)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thermodynamic_consistency() {
        // mu_ex = d f_ex / d rho and P = rho mu - f with mu = ln rho + mu_ex.
        let d = 1.3;
        for eta in [0.05, 0.2, 0.4, 0.5] {
            let rho = density(eta, d);
            let h = 1e-6 * rho;
            let dfd = (excess_free_energy_density(rho + h, d)
                - excess_free_energy_density(rho - h, d))
                / (2.0 * h);
            assert!((dfd - excess_chemical_potential(rho, d)).abs() < 1e-7);
            let p =
                rho + rho * excess_chemical_potential(rho, d) - excess_free_energy_density(rho, d);
            assert!((p - pressure(rho, d)).abs() < 1e-10 * p);
        }
    }
}
