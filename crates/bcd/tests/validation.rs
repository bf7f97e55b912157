//! Validation against exact results, with tolerances from the runs' statistical errors
//! (fixed seeds). Each test also checks that a deliberately wrong reference would be rejected.

mod common;

use colloidsim_bcd::forces::{NoField, NoPair, Sticky};
use colloidsim_bcd::observe::ContactDensity;
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Update, init};
use common::mean_and_error;

/// Mean-square displacement of the rods from `x0`.
fn msd(x: &[f64], x0: &[f64]) -> f64 {
    x.iter().zip(x0).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / x.len() as f64
}

fn cfg(length: f64, sigma: f64, dt: f64, seed: u32) -> BcdConfig {
    BcdConfig {
        length,
        sigma,
        mobility: 1.0,
        kt: 1.0,
        dt,
        boundary: Boundary::Periodic,
        seed,
        update: Update::Premerge,
    }
}

/// Dilute rods never meet within the run: MSD = 2 D t, error sqrt(2/N) 2 D t.
#[test]
fn free_rods_diffuse_with_msd_2dt() {
    let n = 20_000;
    let mut c = cfg(2.0e7, 1e-6, 1e-3, 3);
    c.mobility = 0.7; // D = 0.7
    let x0 = init::lattice(&c, n).unwrap();
    let mut b = Bcd::new(c.clone(), x0.clone(), NoField, NoPair).unwrap();
    b.run(1000).unwrap();
    let t = b.time();
    let msd = msd(b.positions(), &x0);
    let exact = 2.0 * c.diffusion() * t;
    let err = (2.0 / n as f64).sqrt() * exact;
    assert!(
        (msd - exact).abs() < 4.0 * err,
        "msd {msd} vs {exact} +- {err}"
    );
    // A 10% error in D would be caught.
    assert!((msd - 1.1 * exact).abs() > 4.0 * err);
}

/// Single-file diffusion: MSD -> (1 - rho sigma)/rho sqrt(4 D t / pi) once t >> the collision
/// time (1/rho - sigma)^2 / D = 1 and t << L^2 / D. Replicas give the statistical error.
#[test]
fn single_file_diffusion_follows_the_exact_law() {
    let (n, length, sigma) = (200, 400.0, 0.5);
    let rho = n as f64 / length;
    let times = [50.0];
    let dt = 2e-3;
    let mut per_time: Vec<Vec<f64>> = vec![Vec::new(); times.len()];
    for seed in 0..16 {
        let c = cfg(length, sigma, dt, 100 + seed);
        let x0 = init::random(&c, n, 100 + seed).unwrap();
        let mut b = Bcd::new(c, x0.clone(), NoField, NoPair).unwrap();
        let mut done = 0.0;
        for (k, &t) in times.iter().enumerate() {
            b.run(((t - done) / dt).round() as u64).unwrap();
            done = t;
            per_time[k].push(msd(b.positions(), &x0));
        }
    }
    for (k, &t) in times.iter().enumerate() {
        let (m, err) = mean_and_error(&per_time[k]);
        let exact = (1.0 - rho * sigma) / rho * (4.0 * t / std::f64::consts::PI).sqrt();
        eprintln!("t = {t}: MSD {m:.3} +- {err:.3}, exact {exact:.3}");
        assert!(
            (m - exact).abs() < 4.0 * err,
            "t={t}: {m} +- {err} vs {exact}"
        );
        // The free-diffusion law 2Dt, or the point-particle law without the (1 - rho sigma)
        // factor, would be rejected.
        assert!((m - exact / (1.0 - rho * sigma)).abs() > 4.0 * err);
    }
}

/// Sticky rods (hard-rods paper Fig. 7, gamma = 1: L = 400, sigma = rho = 0.5, U0 = 0, the
/// contact of Eq. 33 with eps = 0.05, p = 3): the long-time single-file law
/// `(2 / rho) sqrt(S(0) D t / pi)` (Kollmann 2003, with `D_c = D / S(0)` for Brownian particles
/// without hydrodynamics), where `S(0)` is that of the simulated finite-range model from the
/// exact isobaric solution. The hard-rod law (`S(0) = (1 - rho sigma)^2`), 26 % lower, must be
/// rejected. 16 replicas, equilibrated for 5 time units from random placement. About 5 minutes
/// on one core (`cargo test --release -p colloidsim-bcd --test validation -- --ignored sticky`).
#[test]
#[ignore]
fn sticky_single_file_diffusion_follows_the_exact_law() {
    let (n, length, sigma, gamma, eps, order) = (200, 400.0, 0.5, 1.0, 0.05, 3.0);
    let rho = n as f64 / length;
    let (dt, equilibrate) = (2e-5, 5.0);
    let times = [10.0, 25.0, 50.0];
    let mut per_time: Vec<Vec<f64>> = vec![Vec::new(); times.len()];
    for seed in 0..16 {
        let c = cfg(length, sigma, dt, 300 + seed);
        let x = init::random(&c, n, 300 + seed).unwrap();
        let sticky = Sticky::new(gamma, eps, order, sigma, 1.0).unwrap();
        let mut b = Bcd::new(c, x, NoField, sticky).unwrap();
        b.run((equilibrate / dt).round() as u64).unwrap();
        let x0 = b.positions().to_vec();
        let mut done = 0.0;
        for (k, &t) in times.iter().enumerate() {
            b.run(((t - done) / dt).round() as u64).unwrap();
            done = t;
            per_time[k].push(msd(b.positions(), &x0));
        }
    }
    use colloidsim_dft::rods::bulk;
    let s0 = bulk::structure_factor_zero_finite_range(sigma, gamma, eps, order, rho);
    let s0_hard = bulk::structure_factor_zero(sigma, 0.0, rho);
    eprintln!(
        "S(0): finite-range model {s0:.5}, Baxter {:.5}, hard rods {s0_hard:.5}",
        bulk::structure_factor_zero(sigma, gamma, rho)
    );
    for (k, &t) in times.iter().enumerate() {
        let (m, err) = mean_and_error(&per_time[k]);
        let exact = bulk::single_file_msd(s0, rho, 1.0, t);
        let hard = bulk::single_file_msd(s0_hard, rho, 1.0, t);
        eprintln!(
            "t = {t}: MSD {m:.3} +- {err:.3}, sticky law {exact:.3} ({:+.2} SE), hard-rod law {hard:.3}",
            (m - exact) / err
        );
        if t == 50.0 {
            assert!(
                (m - exact).abs() < 4.0 * err,
                "t={t}: {m} +- {err} vs {exact}"
            );
            assert!(
                (m - hard).abs() > 4.0 * err,
                "the hard-rod law is not rejected"
            );
        }
    }
}

/// Tonks gas: the nearest-neighbour gap is exponential with rate a = rho / (1 - rho sigma).
/// In a fixed-step BCD the gap of a pair is a random walk stopped at contact; to leading order
/// its stationary law is the continuous one with the wall moved out by
/// delta = -zeta(1/2)/sqrt(2 pi) sqrt(2 D_rel dt) = 0.5826 sqrt(4 D dt) (Siegmund's corrected
/// diffusion approximation), so the window estimator of Eq. (27) gives
/// rho2 = rho [1 - exp(-a w) + a delta] / w.
#[test]
fn homogeneous_contact_density_matches_the_tonks_gas() {
    let (n, length, sigma, w, dt): (usize, f64, f64, f64, f64) = (100, 200.0, 1.0, 0.1, 5e-5);
    let rho2 = |rho: f64, sigma: f64| {
        let a = rho / (1.0 - rho * sigma);
        let delta = 0.582_597_157_939_010_7 * (4.0 * dt).sqrt();
        rho * (1.0 - (-a * w).exp() + a * delta) / w
    };
    let rho = n as f64 / length;
    let mut blocks = Vec::new();
    let c = cfg(length, sigma, dt, 7);
    let x0 = init::random(&c, n, 7).unwrap();
    let mut b = Bcd::new(c.clone(), x0, NoField, NoPair).unwrap();
    // Blocks of 4 time units, the gap relaxation time (1/a)^2 / D.
    for _ in 0..16 {
        let mut cd = ContactDensity::new(1, w, length, sigma, length, Boundary::Periodic);
        for _ in 0..80_000 {
            b.step().unwrap();
            cd.sample(b.positions());
        }
        blocks.push(cd.profile().1[0]);
    }
    let (m, err) = mean_and_error(&blocks);
    let exact = rho2(rho, sigma);
    eprintln!("rho2 {m:.5} +- {err:.5}, exact with time-step correction {exact:.5}");
    assert!((m - exact).abs() < 4.0 * err, "{m} +- {err} vs {exact}");
    // A rod length 20% off would be caught.
    assert!((m - rho2(rho, 1.2 * sigma)).abs() > 4.0 * err);
}

/// Hard rods in the cosine potential (hard-rods paper Fig. 3, sigma = 0.5, rho = 0.5): the
/// histogram agrees with the exact Percus profile bin by bin within 4.5 standard errors
/// (batch means), and the profile for a rod length 10% off is rejected.
#[test]
fn density_in_cosine_potential_matches_exact_theory() {
    let o = common::compare(&common::Case {
        sigma: 0.5,
        rho: 0.5,
        gamma: None,
        length: 400.0,
        dt: 1e-4,
        bins: 20,
        equilibrate_steps: 20_000,
        blocks: 10,
        block_steps: 20_000,
        seed: 21,
    });
    eprintln!(
        "largest deviation {:.2} sigma; chi2 against sigma * 1.1: {:.0}",
        o.worst, o.chi2_wrong_sigma
    );
    assert!(o.worst < 4.5, "deviation {} standard errors", o.worst);
    assert!(o.chi2_wrong_sigma > 4.0 * o.bins as f64);
}
