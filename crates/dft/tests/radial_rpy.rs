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
    kernel.velocities(&g, &vec![rho; grid.len()], grid.len(), &mut u);
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

/// `K = 1 - 5 phi + 12 phi int_1^range x h(x) dx` from the total correlation alone.
fn bulk_k(phi: f64, range: f64) -> f64 {
    colloidsim_dft::radial::pair::bulk_sedimentation(phi, range).unwrap()
}

/// Trokhymchuk's `g`: far from the centre the kernel gives the bulk `K` of its `h`, at a node of
/// the packing-fraction table and between two; with the Richardson extrapolation in `1/x^2` of
/// the curvature term (paper Eq. 28).
#[test]
fn radial_trokhymchuk_flux_gives_the_bulk_sedimentation_coefficient_of_its_pair_correlation() {
    use colloidsim_dft::radial::{PairCorrelation, PairTable, rpy::PAIR_RANGE};
    let dr = 0.05;
    let grid = RadialGrid::covering(dr, 100.0).unwrap();
    let t0 = std::time::Instant::now();
    let kernel = RpyKernel::with_pair(
        &grid,
        1.0,
        PairCorrelation::Trokhymchuk,
        PairTable::default(),
    )
    .unwrap();
    eprintln!("kernel setup {:.2} s", t0.elapsed().as_secs_f64());
    let node = PairTable::default().eta_max / 10.0;
    for (phi, interpolated) in [(5.0 * node, false), (0.31, true)] {
        let rho = 6.0 * phi / PI;
        let g = vec![-rho; grid.len()];
        let mut u = vec![0.0; grid.len() + 1];
        kernel.velocities(&g, &vec![rho; grid.len()], grid.len(), &mut u);
        let k_at = |x: f64| 1.0 + u[(x / dr).round() as usize];
        let (k40, k80) = (k_at(40.0), k_at(80.0));
        let k_inf = (4.0 * k80 - k40) / 3.0;
        let expected = if interpolated {
            let (lo, hi) = ((phi / node).floor() * node, (phi / node).ceil() * node);
            let w = (phi - lo) / node;
            // The kernel interpolates h linearly between nodes; K - 1 + 5 phi is rho times it.
            let tail = |e: f64| (bulk_k(e, PAIR_RANGE) - 1.0 + 5.0 * e) / e;
            1.0 - 5.0 * phi + phi * ((1.0 - w) * tail(lo) + w * tail(hi))
        } else {
            bulk_k(phi, PAIR_RANGE)
        };
        eprintln!(
            "phi {phi:.4}: K(40) {k40:.5} K(80) {k80:.5} extrapolated {k_inf:.5} expected {expected:.5} (exact at phi: {:.5}, dilute {:.4})",
            bulk_k(phi, PAIR_RANGE),
            1.0 - 5.0 * phi
        );
        assert!(
            (k_inf - expected).abs() < 2e-4,
            "phi {phi}: K {k_inf} vs {expected}"
        );
        // Positive, unlike the dilute 1 - 5 phi < 0.
        assert!(k_inf > 0.1);
    }
}
