//! Validation against exact results, with tolerances from the runs' statistical errors
//! (fixed seeds). Each test also checks that a deliberately wrong reference would be rejected.

use colloidsim_bcd::forces::{ForceTable, NoField, NoPair};
use colloidsim_bcd::observe::{ContactDensity, DensityProfile};
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};
use colloidsim_dft::rods::{self, BetaPotential, Domain, RodsProblem};

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

fn mean_and_error(samples: &[f64]) -> (f64, f64) {
    let k = samples.len() as f64;
    let m = samples.iter().sum::<f64>() / k;
    let var = samples.iter().map(|s| (s - m).powi(2)).sum::<f64>() / (k - 1.0);
    (m, (var / k).sqrt())
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
    let msd: f64 = b
        .positions()
        .iter()
        .zip(&x0)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        / n as f64;
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
            let m = b
                .positions()
                .iter()
                .zip(&x0)
                .map(|(x, y)| (x - y).powi(2))
                .sum::<f64>()
                / n as f64;
            per_time[k].push(m);
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
    let (n, length, sigma, bins) = (50, 100.0, 0.5, 20);
    let field = ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    };
    let theory = |s: f64| {
        let p = RodsProblem::new(s, n as f64 / length, Domain::Periodic { period: 1.0 })
            .with_dx(1e-3)
            .with_potential(BetaPotential::from_field(&field, 1.0));
        rods::equilibrium(&p)
            .unwrap()
            .bin_average(bins, 1.0)
            .unwrap()
            .rho
    };
    let c = cfg(length, sigma, 1e-4, 21);
    let x0 = init::random(&c, n, 21).unwrap();
    let table = ForceTable::from_field(&field).unwrap();
    let mut b = Bcd::new(c, x0, table, NoPair).unwrap();
    b.run(20_000).unwrap();
    let mut blocks: Vec<Vec<f64>> = Vec::new();
    for _ in 0..10 {
        let mut d = DensityProfile::new(bins, 1.0, length);
        for _ in 0..20_000 {
            b.step().unwrap();
            d.sample(b.positions());
        }
        blocks.push(d.profile().1);
    }
    let exact = theory(sigma);
    let wrong = theory(1.1 * sigma);
    let (mut worst, mut chi2_wrong) = (0.0f64, 0.0);
    for k in 0..bins {
        let col: Vec<f64> = blocks.iter().map(|b| b[k]).collect();
        let (m, err) = mean_and_error(&col);
        let err = err.max(1e-3 * m.abs()).max(1e-12);
        worst = worst.max((m - exact[k]).abs() / err);
        chi2_wrong += ((m - wrong[k]) / err).powi(2);
    }
    eprintln!("largest deviation {worst:.2} sigma; chi2 against sigma * 1.1: {chi2_wrong:.0}");
    assert!(worst < 4.5, "deviation {worst} standard errors");
    assert!(
        chi2_wrong > 4.0 * bins as f64,
        "wrong sigma not caught: chi2 {chi2_wrong}"
    );
}
