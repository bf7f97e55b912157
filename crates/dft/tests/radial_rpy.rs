//! Pairwise RPY flux with the dilute pair correlation: bulk sedimentation coefficient.
//!
//! For a uniform density and a uniform radial force F (so `g = rho d(beta mu) = -rho beta F`),
//! the flux is `J = rho beta D0 F K` with `K = 1 - 5 phi` far from the centre (paper Eq. 28 with
//! its curvature term < 1 % for r >> d; METHODS.md: "K = 1 - 5 phi, not Batchelor's 6.55").

use std::f64::consts::PI;

use colloidsim_dft::radial::{RadialGrid, rpy::RpyKernel};

#[test]
fn radial_hydrodynamic_flux_hinders_like_one_minus_five_phi() {
    let dr = 0.02;
    let grid = RadialGrid::covering(dr, 40.0).unwrap();
    let kernel = RpyKernel::new(&grid, 1.0);
    let rho = 0.3;
    let phi = PI * rho / 6.0;
    let force = 1.0; // outward, in kT / d
    let g = vec![-rho * force; grid.len()];
    let mut u = vec![0.0; grid.len() + 1];
    kernel.velocities(&g, grid.len(), &mut u);
    // Face at r = 30 d: J_self = rho D0 F, J_HI = rho u.
    let f = (30.0 / dr).round() as usize;
    let k = 1.0 + u[f] / force;
    let expected = 1.0 - 5.0 * phi;
    assert!(
        (k - expected).abs() < 0.01 * 5.0 * phi,
        "K = {k}, expected {expected}"
    );
    // The sign matters: HI opposes the force (K < 1), it does not assist it.
    assert!(k < 1.0);
    // No hydrodynamic drift at the centre (symmetry), and it decays toward it.
    assert_eq!(u[0], 0.0);
    assert!(u[1].abs() < u[f].abs());
}
