//! Bulk equations of state of hard-sphere mixtures that the functionals of [`super::fmt`] imply,
//! written in the moments `xi_m = (pi / 6) sum_i rho_i d_i^m` (independently of the weighted
//! densities; tests compare the functional's bulk limit with them).
//!
//! - Percus–Yevick compressibility / scaled-particle theory (Lebowitz, Phys. Rev. 133, A895
//!   (1964); the bulk limit of Rosenfeld's functional):
//!   `beta P = (6 / pi) [xi0 / (1 - xi3) + 3 xi1 xi2 / (1 - xi3)^2 + 3 xi2^3 / (1 - xi3)^3]`,
//!   `beta f_ex = (6 / pi) [-xi0 ln(1 - xi3) + 3 xi1 xi2 / (1 - xi3) + 3 xi2^3 / (2 (1 - xi3)^2)]`.
//! - Boublík–Mansoori–Carnahan–Starling–Leland (Boublík, J. Chem. Phys. 53, 471 (1970); Mansoori,
//!   Carnahan, Starling and Leland, J. Chem. Phys. 54, 1523 (1971); the bulk limit of White Bear):
//!   `beta P = (6 / pi) [xi0 / (1 - xi3) + 3 xi1 xi2 / (1 - xi3)^2 + (3 - xi3) xi2^3 / (1 - xi3)^3]`,
//!   `beta f_ex = (6 / pi) [(xi2^3 / xi3^2 - xi0) ln(1 - xi3) + 3 xi1 xi2 / (1 - xi3)
//!   + xi2^3 / (xi3 (1 - xi3)^2)]`.
//!
//! The excess chemical potentials are `beta mu_ex,i = sum_m d_i^m A_m` with
//! `A_m = (pi / 6) d(beta f_ex) / d xi_m`:
//! PY: `A0 = -ln(1 - xi3)`, `A1 = 3 xi2 / (1 - xi3)`, `A2 = 3 xi1 / (1 - xi3) + 9 xi2^2 / (2 (1 - xi3)^2)`,
//! `A3 = xi0 / (1 - xi3) + 3 xi1 xi2 / (1 - xi3)^2 + 3 xi2^3 / (1 - xi3)^3`;
//! BMCSL: `A0`, `A1` the same, `A2 = 3 xi1 / (1 - xi3) + 3 xi2^2 / (xi3 (1 - xi3)^2)
//! + 3 xi2^2 ln(1 - xi3) / xi3^2`, `A3 = xi0 / (1 - xi3) + 3 xi1 xi2 / (1 - xi3)^2
//! - xi2^3 [2 ln(1 - xi3) / xi3^3 + (2 - 5 xi3 + xi3^2) / (xi3^2 (1 - xi3)^3)]`.

use std::f64::consts::PI;

use super::fmt::Functional;

/// `xi_m = (pi / 6) sum_i rho_i d_i^m`, `m = 0..=3`.
pub fn moments(rho: &[f64], diameters: &[f64]) -> [f64; 4] {
    std::array::from_fn(|m| {
        PI / 6.0
            * rho
                .iter()
                .zip(diameters)
                .map(|(r, d)| r * d.powi(m as i32))
                .sum::<f64>()
    })
}

/// `beta P` of the PY compressibility / scaled-particle equation of state.
pub fn py_pressure(rho: &[f64], diameters: &[f64]) -> f64 {
    let [x0, x1, x2, x3] = moments(rho, diameters);
    let q = 1.0 / (1.0 - x3);
    6.0 / PI * (x0 * q + 3.0 * x1 * x2 * q * q + 3.0 * x2.powi(3) * q.powi(3))
}

/// `beta P` of BMCSL.
pub fn bmcsl_pressure(rho: &[f64], diameters: &[f64]) -> f64 {
    let [x0, x1, x2, x3] = moments(rho, diameters);
    let q = 1.0 / (1.0 - x3);
    6.0 / PI * (x0 * q + 3.0 * x1 * x2 * q * q + (3.0 - x3) * x2.powi(3) * q.powi(3))
}

/// `beta f_ex` (per volume) of the equation of state `functional` implies.
pub fn excess_free_energy_density(functional: Functional, rho: &[f64], diameters: &[f64]) -> f64 {
    let [x0, x1, x2, x3] = moments(rho, diameters);
    let l = (1.0 - x3).ln();
    let q = 1.0 / (1.0 - x3);
    6.0 / PI
        * match functional {
            Functional::Rosenfeld => -x0 * l + 3.0 * x1 * x2 * q + 1.5 * x2.powi(3) * q * q,
            Functional::WhiteBear => {
                (x2.powi(3) / (x3 * x3) - x0) * l + 3.0 * x1 * x2 * q + x2.powi(3) / x3 * q * q
            }
        }
}

/// `beta P` of the equation of state `functional` implies.
pub fn pressure(functional: Functional, rho: &[f64], diameters: &[f64]) -> f64 {
    match functional {
        Functional::Rosenfeld => py_pressure(rho, diameters),
        Functional::WhiteBear => bmcsl_pressure(rho, diameters),
    }
}

/// `beta mu_ex,i` of every species for the equation of state `functional` implies.
pub fn excess_chemical_potentials(
    functional: Functional,
    rho: &[f64],
    diameters: &[f64],
) -> Vec<f64> {
    let [x0, x1, x2, x3] = moments(rho, diameters);
    let l = (1.0 - x3).ln();
    let q = 1.0 / (1.0 - x3);
    let a0 = -l;
    let a1 = 3.0 * x2 * q;
    let (a2, a3) = match functional {
        Functional::Rosenfeld => (
            3.0 * x1 * q + 4.5 * x2 * x2 * q * q,
            x0 * q + 3.0 * x1 * x2 * q * q + 3.0 * x2.powi(3) * q.powi(3),
        ),
        Functional::WhiteBear => (
            3.0 * x1 * q + 3.0 * x2 * x2 / x3 * q * q + 3.0 * x2 * x2 * l / (x3 * x3),
            x0 * q + 3.0 * x1 * x2 * q * q
                - x2.powi(3)
                    * (2.0 * l / x3.powi(3) + (2.0 - 5.0 * x3 + x3 * x3) / (x3 * x3) * q.powi(3)),
        ),
    };
    diameters
        .iter()
        .map(|d| a0 + a1 * d + a2 * d * d + a3 * d.powi(3))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gibbs–Duhem: `P = sum rho_i (1 + mu_ex,i) - f_ex`, and `mu_ex,i = d f_ex / d rho_i`.
    #[test]
    fn closed_forms_are_thermodynamically_consistent() {
        let d = [1.0, 2.0];
        for f in [Functional::Rosenfeld, Functional::WhiteBear] {
            for rho in [[0.3, 0.05], [0.05, 0.08]] {
                let mu = excess_chemical_potentials(f, &rho, &d);
                let p: f64 = rho.iter().zip(&mu).map(|(r, m)| r * (1.0 + m)).sum::<f64>()
                    - excess_free_energy_density(f, &rho, &d);
                assert!((p / pressure(f, &rho, &d) - 1.0).abs() < 1e-13, "{f:?}");
                for i in 0..2 {
                    let h = 1e-6 * rho[i];
                    let (mut up, mut dn) = (rho, rho);
                    up[i] += h;
                    dn[i] -= h;
                    let fd = (excess_free_energy_density(f, &up, &d)
                        - excess_free_energy_density(f, &dn, &d))
                        / (2.0 * h);
                    assert!((fd - mu[i]).abs() < 1e-7 * mu[i].abs(), "{f:?} {i}");
                }
            }
        }
        // One species: BMCSL is Carnahan–Starling.
        let eta: f64 = 0.3;
        let rho = [6.0 * eta / PI];
        let cs = rho[0] * (1.0 + eta + eta * eta - eta.powi(3)) / (1.0 - eta).powi(3);
        assert!((bmcsl_pressure(&rho, &[1.0]) / cs - 1.0).abs() < 1e-14);
    }
}
