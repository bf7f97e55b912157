//! Bulk limit of the radial Rosenfeld functional and its convergence in the grid spacing.
//!
//! For a uniform density the cell-integrated radial kernels are exact, so the weighted densities,
//! `beta mu_ex` and `beta P = rho + rho beta mu_ex - beta f_ex` equal the Percus–Yevick
//! compressibility values (`beta P / rho = (1 + eta + eta^2) / (1 - eta)^3`,
//! `beta mu_ex = -ln(1 - eta) + (14 eta - 13 eta^2 + 5 eta^3) / (2 (1 - eta)^3)`) to rounding at
//! every cell, including the centre `r < a` (direct quadrature). For a non-uniform density the
//! scheme is second order in `dr`, checked on nested grids.

use std::f64::consts::PI;

use colloidsim_dft::radial::{RadialGrid, Rosenfeld, bulk, fmt::rosenfeld_phi};

#[test]
fn radial_uniform_fluid_gives_percus_yevick_everywhere() {
    let d = 1.0;
    for dr in [0.1, 0.05, 0.02] {
        let grid = RadialGrid::covering(dr, 6.0).unwrap();
        let mut fmt = Rosenfeld::new(&grid, d).unwrap();
        for eta in [0.1, 0.3, 0.45] {
            let rho0 = bulk::density(eta, d);
            let rho = vec![rho0; grid.len()];
            let fex = fmt.evaluate(&rho, grid.len()).unwrap();
            assert!(fex.is_finite());
            let mu_py = bulk::excess_chemical_potential(rho0, d);
            let p_py = bulk::pressure(rho0, d);
            let f_py = bulk::excess_free_energy_density(rho0, d);
            // Away from the grid's outer edge (where the fluid ends) the fluid is bulk.
            for (i, r) in grid.centres().iter().enumerate() {
                if *r > grid.r_max() - 1.5 * d {
                    break;
                }
                assert!(
                    (fmt.n3()[i] - eta).abs() < 1e-12,
                    "dr {dr} eta {eta} r {r}: n3"
                );
                assert!((fmt.n2()[i] - PI * d * d * rho0).abs() < 1e-11 * rho0);
                assert!(fmt.nv2()[i].abs() < 1e-11, "nv2 {} at r {r}", fmt.nv2()[i]);
                let mu = fmt.mu_ex()[i];
                assert!(
                    (mu - mu_py).abs() < 1e-11 * mu_py,
                    "dr {dr} eta {eta} r {r}: {mu} vs {mu_py}"
                );
                let p = rho0 + rho0 * mu - f_py;
                assert!((p - p_py).abs() < 1e-11 * p_py);
            }
        }
    }
}

#[test]
fn radial_rosenfeld_phi_of_bulk_weighted_densities_is_the_percus_yevick_free_energy() {
    // Phi(n3 = eta, n2 = pi d^2 rho, nv2 = 0) = beta f_ex (PY compressibility), and its
    // derivatives give mu_ex = sum_alpha dPhi/dn_alpha * (weight integral: V_sphere, S_sphere).
    let d = 1.0;
    let a = 0.5 * d;
    for eta in [0.05, 0.2, 0.35, 0.5] {
        let rho = bulk::density(eta, d);
        let (phi, p3, p2, pv) = rosenfeld_phi(eta, PI * d * d * rho, 0.0, a);
        let f = bulk::excess_free_energy_density(rho, d);
        assert!(
            (phi - f).abs() < 1e-13 * f.abs().max(1.0),
            "eta {eta}: {phi} vs {f}"
        );
        let mu = p3 * 4.0 / 3.0 * PI * a.powi(3) + p2 * 4.0 * PI * a * a;
        let mu_py = bulk::excess_chemical_potential(rho, d);
        assert!(
            (mu - mu_py).abs() < 1e-12 * mu_py,
            "eta {eta}: {mu} vs {mu_py}"
        );
        assert_eq!(pv, 0.0);
    }
}

/// `mu_ex` of a smooth profile on a grid of spacing `h`, at cell centres.
fn mu_profile(h: f64) -> (Vec<f64>, Vec<f64>) {
    let grid = RadialGrid::covering(h, 5.0).unwrap();
    let mut fmt = Rosenfeld::new(&grid, 1.0).unwrap();
    let rho: Vec<f64> = grid
        .centres()
        .iter()
        .map(|r| bulk::density(0.3, 1.0) * (1.0 + 0.3 * (1.3 * r).cos()))
        .collect();
    fmt.evaluate(&rho, grid.len()).unwrap();
    (grid.centres().to_vec(), fmt.mu_ex().to_vec())
}

#[test]
fn radial_non_uniform_profile_converges_at_second_order_including_the_centre() {
    // Refinement by 3 keeps the coarse centres on the fine grids.
    let h = 0.1;
    let (r1, m1) = mu_profile(h);
    let (_, m2) = mu_profile(h / 3.0);
    let (_, m3) = mu_profile(h / 9.0);
    let (mut e1, mut e2) = (0.0f64, 0.0f64);
    for (i, r) in r1.iter().enumerate() {
        if *r > 3.5 {
            break;
        }
        e1 = e1.max((m1[i] - m3[9 * i + 4]).abs());
        e2 = e2.max((m2[3 * i + 1] - m3[9 * i + 4]).abs());
    }
    // Second order: e1 / e2 = 9 (80/81) / (8/9) = 10; first order would give 4.
    let ratio = e1 / e2;
    assert!(ratio > 7.0, "convergence ratio {ratio} (e1 {e1}, e2 {e2})");
    assert!(e2 < 1e-2, "error at dr = d/30: {e2}");
}
