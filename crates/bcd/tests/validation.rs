//! Validation against exact results, with tolerances from the runs' statistical errors
//! (fixed seeds). Each test also checks that a deliberately wrong reference would be rejected.

use crate::common;

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
/// on one core (`cargo test --release -p colloidsim-bcd --test integration validation::sticky -- --ignored`).
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

/// The exact contact theory checked without BCD: Metropolis Monte Carlo of 200 hard rods
/// (sigma = 0.5) on a ring of 400 in the hard-rods paper's Fig. 4 wells, `U = 3 cos(2 pi x)`
/// (U0 = 6 kT). The window estimator (Eq. 27, window 0.02, 25 bins over a period) matches the
/// grand-canonical expectation of `Equilibrium::window_contact_average` times the canonical
/// `(N - 1) / N`, bin by bin (chi^2 over 25 bins, errors from 20 blocks) and pooled; Eq. 24's
/// contact value itself (the window -> 0 limit) and a rod length 2% off are rejected.
#[test]
fn exact_contact_density_matches_monte_carlo_in_deep_wells() {
    use colloidsim_dft::rods::{self, BetaPotential, Domain, RodsProblem};
    use rand::{RngExt, SeedableRng, rngs::StdRng};
    let (n, length, sigma, u0, w) = (200usize, 400.0, 0.5, 6.0, 0.02);
    let (bins, blocks, sweeps_per_block) = (25usize, 20usize, 25_000usize);
    let u = move |x: f64| 0.5 * u0 * (std::f64::consts::TAU * x).cos();
    let mut rng = StdRng::seed_from_u64(11);
    // Start with one rod in every other well, near its bottom (x = 1/2 mod 1).
    let mut x: Vec<f64> = (0..n).map(|i| 2.0 * i as f64 + 0.5).collect();
    let sweep = |x: &mut [f64], rng: &mut StdRng| {
        for _ in 0..n {
            let i = rng.random_range(0..n);
            let new = x[i] + 0.3 * (2.0 * rng.random::<f64>() - 1.0);
            let left = if i > 0 { x[i - 1] } else { x[n - 1] - length };
            let right = if i + 1 < n { x[i + 1] } else { x[0] + length };
            if new - left < sigma || right - new < sigma {
                continue;
            }
            let du = u(new) - u(x[i]);
            if du <= 0.0 || rng.random::<f64>() < (-du).exp() {
                x[i] = new;
            }
        }
    };
    for _ in 0..100_000 {
        sweep(&mut x, &mut rng);
    }
    let mut per_block = vec![vec![0.0; bins]; blocks];
    for counts in per_block.iter_mut() {
        for _ in 0..sweeps_per_block {
            sweep(&mut x, &mut rng);
            for i in 0..n {
                let right = if i + 1 < n { x[i + 1] } else { x[0] + length };
                if right - x[i] < sigma + w {
                    let b = (x[i].rem_euclid(1.0) * bins as f64) as usize;
                    counts[b.min(bins - 1)] += 1.0;
                }
            }
        }
        // Eq. 27: count / (samples dx w (L / lambda)).
        let norm = sweeps_per_block as f64 * (1.0 / bins as f64) * w * length;
        counts.iter_mut().for_each(|c| *c /= norm);
    }
    let theory = |sigma: f64| {
        let p = RodsProblem::new(sigma, n as f64 / length, Domain::Periodic { period: 1.0 })
            .with_dx(sigma / 500.0)
            .with_potential(BetaPotential::from_fn(1.0, u));
        let eq = rods::equilibrium(&p).unwrap();
        let canonical = (n - 1) as f64 / n as f64;
        let window = eq.window_contact_average(bins, 1.0, w).unwrap().unwrap();
        let contact = eq.bin_average(bins, 1.0).unwrap().contact_density;
        let scale = |v: Vec<f64>| v.into_iter().map(|c| c * canonical).collect::<Vec<_>>();
        (scale(window), scale(contact))
    };
    let (mc, err): (Vec<f64>, Vec<f64>) = (0..bins)
        .map(|b| mean_and_error(&per_block.iter().map(|c| c[b]).collect::<Vec<_>>()))
        .unzip();
    let chi2 = |t: &[f64]| -> f64 { (0..bins).map(|b| ((mc[b] - t[b]) / err[b]).powi(2)).sum() };
    let pooled = |t: &[f64]| t.iter().sum::<f64>();
    let (mc_pooled, pooled_err) = mean_and_error(
        &per_block
            .iter()
            .map(|c| c.iter().sum::<f64>())
            .collect::<Vec<_>>(),
    );
    let (window, contact) = theory(sigma);
    let (window_off, _) = theory(1.02 * sigma);
    eprintln!(
        "MC pooled {mc_pooled:.4} +- {pooled_err:.4}; window theory {:.4} (chi2 {:.1} over {bins} \
         bins), Eq. 24 {:.4} (chi2 {:.1}), sigma 2% off {:.4} (chi2 {:.1})",
        pooled(&window),
        chi2(&window),
        pooled(&contact),
        chi2(&contact),
        pooled(&window_off),
        chi2(&window_off)
    );
    // chi^2 of 25 bins: mean 25, sd 7; 50 is beyond the 99.8th percentile.
    assert!(chi2(&window) < 50.0, "chi2 {}", chi2(&window));
    assert!((mc_pooled - pooled(&window)).abs() < 4.0 * pooled_err);
    assert!(
        chi2(&contact) > 100.0,
        "Eq. 24 without the window: chi2 {}",
        chi2(&contact)
    );
    assert!(
        chi2(&window_off) > 100.0,
        "sigma 2% off: chi2 {}",
        chi2(&window_off)
    );
}

/// BCD's contact density in a potential, with errors between independent replicas (blocks of
/// one run are not independent here: the contact indicator's correlations decay like a random
/// walk's returns, docs/bcd.md). 50 hard rods (sigma = 0.5) on a ring of 100 in
/// `U = (1/2) cos(2 pi x)` (U0 = 1 kT), window 0.05, dt = 2e-5, 8 replicas of 100 time units.
/// Expected, per bin: `(N - 1)/N [rho2_window + (delta / w) rho2_contact]`, the exact window
/// average (grand canonical, `Equilibrium::window_contact_average`), the canonical factor and
/// the time-step boundary layer `delta = 0.5826 sqrt(4 D dt)` at contact (docs/bcd.md). Without
/// the boundary layer (10 % here) the pooled value is rejected.
#[test]
fn contact_density_in_a_cosine_potential_matches_the_window_theory() {
    use colloidsim_bcd::forces::Field;
    use colloidsim_core::field1d::{ExternalField, FieldTerm};
    use colloidsim_dft::rods::{self, BetaPotential, Domain, RodsProblem};
    use rayon::prelude::*;
    let (n, length, sigma, w, dt, u0) = (50usize, 100.0, 0.5, 0.05, 2e-5, 1.0);
    let (bins, replicas, time, every) = (10usize, 8u32, 100.0, 5u64);
    let field = ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: u0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    };
    let profiles: Vec<Vec<f64>> = (1..=replicas)
        .into_par_iter()
        .map(|seed| {
            let c = cfg(length, sigma, dt, seed);
            let x0 = init::random(&c, n, seed).unwrap();
            let mut b = Bcd::new(c, x0, Field::new(&field), NoPair).unwrap();
            b.run((2.0 / dt) as u64).unwrap();
            let mut cd = ContactDensity::new(bins, w, 1.0, sigma, length, Boundary::Periodic);
            for _ in 0..(time / dt) as u64 / every {
                b.run(every).unwrap();
                cd.sample(b.positions());
            }
            cd.profile().1
        })
        .collect();
    let p = RodsProblem::new(sigma, n as f64 / length, Domain::Periodic { period: 1.0 })
        .with_dx(sigma / 400.0)
        .with_potential(BetaPotential::from_field(&field, 1.0));
    let eq = rods::equilibrium(&p).unwrap();
    let window = eq.window_contact_average(bins, 1.0, w).unwrap().unwrap();
    let contact = eq.bin_average(bins, 1.0).unwrap().contact_density;
    let canonical = (n - 1) as f64 / n as f64;
    let delta = 0.582_597_157_939_010_7 * (4.0 * dt).sqrt();
    let expected = |layer: f64| -> Vec<f64> {
        (0..bins)
            .map(|k| canonical * (window[k] + layer / w * contact[k]))
            .collect()
    };
    let (with_layer, without) = (expected(delta), expected(0.0));
    let per_bin: Vec<(f64, f64)> = (0..bins)
        .map(|k| mean_and_error(&profiles.iter().map(|p| p[k]).collect::<Vec<_>>()))
        .collect();
    let chi2: f64 = per_bin
        .iter()
        .zip(&with_layer)
        .map(|((m, e), t)| ((m - t) / e).powi(2))
        .sum();
    let (pooled, pooled_err) = mean_and_error(
        &profiles
            .iter()
            .map(|p| p.iter().sum::<f64>())
            .collect::<Vec<_>>(),
    );
    let z = |t: &[f64]| (pooled - t.iter().sum::<f64>()) / pooled_err;
    eprintln!(
        "pooled {pooled:.4} +- {pooled_err:.4}; expected {:.4} (z {:.2}, chi2 {chi2:.1} over \
         {bins} bins), without the boundary layer {:.4} (z {:.2})",
        with_layer.iter().sum::<f64>(),
        z(&with_layer),
        without.iter().sum::<f64>(),
        z(&without)
    );
    // chi^2 of 10 bins: 29.6 is the 99.9th percentile.
    assert!(chi2 < 29.6, "chi2 {chi2}");
    assert!(z(&with_layer).abs() < 4.0);
    assert!(z(&without).abs() > 4.0);
}

/// The exact sticky-rod theory is the eps -> 0 limit of the finite well BCD simulates, and the
/// dense Fig. 6 column at eps = 0.05 lies measurably above it (docs/figures.md, "All of
/// Fig. 6"): Monte Carlo (`colloidsim_bcd::mc`, no time step) of 80 rods, sigma = 0.8, on a
/// ring of 100 in U0 = 6 kT. For hard rods (gamma = 0) the peak (three bins around the
/// theory's maximum) matches the Percus theory within 0.4 % (which checks the sampler); with
/// gamma = 1 it is about 1.5 % above the Baxter theory at eps = 0.05 and at most 0.45 of that
/// at eps = 0.0125 (0.23 % at 4e6 sweeps: the shift vanishes with eps). Errors from 8 blocks of 1.5e5 sweeps after 3e5.
#[test]
fn sticky_theory_is_the_small_well_limit_of_monte_carlo() {
    use colloidsim_bcd::mc::StickyRing;
    use rayon::prelude::*;
    let (n, length, sigma, bins, blocks, per_block) = (80usize, 100.0, 0.8, 50usize, 8, 150_000);
    let cases = [(0.0, 0.05, 1u64), (1.0, 0.05, 2), (1.0, 0.0125, 3)];
    let profiles: Vec<Vec<Vec<f64>>> = cases
        .par_iter()
        .map(|&(gamma, eps, seed)| {
            let mut ring = StickyRing::new(n, length, 6.0, sigma, gamma, eps, seed);
            for _ in 0..300_000 {
                ring.sweep();
            }
            (0..blocks)
                .map(|_| {
                    let mut h = vec![0.0; bins];
                    for _ in 0..per_block {
                        ring.sweep();
                        ring.histogram(&mut h);
                    }
                    let norm = per_block as f64 * length / bins as f64;
                    h.into_iter().map(|c| c / norm).collect()
                })
                .collect()
        })
        .collect();
    let theory = |gamma: f64| fig6_theory(sigma, n as f64 / length, gamma, bins);
    let (hard, sticky) = (theory(0.0), theory(1.0));
    let per_bin = |p: &[Vec<f64>]| -> Vec<(f64, f64)> {
        (0..bins)
            .map(|b| mean_and_error(&p.iter().map(|h| h[b]).collect::<Vec<_>>()))
            .collect()
    };
    let chi2 = |p: &[Vec<f64>], t: &[f64]| -> f64 {
        per_bin(p)
            .iter()
            .zip(t)
            .map(|((m, e), t)| ((m - t) / e).powi(2))
            .sum::<f64>()
            / bins as f64
    };
    // The peak (three bins around the theory's maximum) over the theory `t`, per block.
    let peak = |p: &[Vec<f64>], t: &[f64]| {
        mean_and_error(&p.iter().map(|h| peak_deviation(h, t)).collect::<Vec<_>>())
    };
    let (hard_peak, hard_err) = peak(&profiles[0], &hard);
    let wrong = chi2(&profiles[0], &sticky);
    let (wide, wide_err) = peak(&profiles[1], &sticky);
    let (narrow, narrow_err) = peak(&profiles[2], &sticky);
    eprintln!(
        "hard rods: peak {:.2} % +- {:.2} % from the Percus theory (chi2 per bin {:.1}; against \
         the sticky theory {wrong:.0}); gamma = 1 peak above the Baxter theory: {:.2} % +- {:.2} % \
         at eps = 0.05, {:.2} % +- {:.2} % at 0.0125",
        100.0 * hard_peak,
        100.0 * hard_err,
        chi2(&profiles[0], &hard),
        100.0 * wide,
        100.0 * wide_err,
        100.0 * narrow,
        100.0 * narrow_err
    );
    // The sampler's own error on a peak (hard rods: 0.09 % +- 0.04 % at 4e6 sweeps) is well
    // below the finite-well shift it measures; block errors of the dense ring's profile are too
    // small for a chi^2 test (its occupation of the wells relaxes slowly).
    assert!(
        hard_peak.abs() < 0.004,
        "hard rods: peak {hard_peak} +- {hard_err}"
    );
    assert!(
        wrong > 10.0,
        "the sampler cannot tell hard from sticky: {wrong}"
    );
    assert!(wide > 0.01 && wide > 6.0 * wide_err, "{wide} +- {wide_err}");
    assert!(
        narrow < 0.45 * wide && narrow.abs() < 0.008,
        "eps = 0.0125: {narrow} +- {narrow_err} against {wide} at 0.05"
    );
}

/// The exact eps -> 0 profile of hard (`gamma = 0`) or sticky rods of length `sigma` at mean
/// density `rho` in the hard-rods paper's Fig. 6 potential `U = 3 kT cos(2 pi x)`, averaged
/// over `bins` bins of one period.
fn fig6_theory(sigma: f64, rho: f64, gamma: f64, bins: usize) -> Vec<f64> {
    use colloidsim_dft::rods::{self, BetaPotential, Domain, RodInteraction, RodsProblem};
    let interaction = if gamma > 0.0 {
        RodInteraction::Sticky { gamma }
    } else {
        RodInteraction::Hard
    };
    let p = RodsProblem::new(sigma, rho, Domain::Periodic { period: 1.0 })
        .with_dx(sigma / 400.0)
        .with_potential(BetaPotential::from_fn(1.0, |x| {
            3.0 * (std::f64::consts::TAU * x).cos()
        }))
        .with_interaction(interaction);
    rods::equilibrium(&p)
        .unwrap()
        .bin_average(bins, 1.0)
        .unwrap()
        .rho
}

/// The peak of a binned profile `h` over the theory's `t`, minus 1: three bins around the
/// theory's maximum (as docs/figures.md quotes every Fig. 6 panel).
fn peak_deviation(h: &[f64], t: &[f64]) -> f64 {
    let bins = t.len();
    let top = (0..bins).max_by(|&a, &b| t[a].total_cmp(&t[b])).unwrap();
    let window = [(top + bins - 1) % bins, top, (top + 1) % bins];
    window.iter().map(|&b| h[b]).sum::<f64>() / window.iter().map(|&b| t[b]).sum::<f64>() - 1.0
}

/// BCD's time-step error in the dense sticky column of Fig. 6 (80 rods, sigma = rho = 0.8,
/// gamma = 1, eps = 0.05, p = 3, U0 = 6 kT), and its limit: each seed is a Monte Carlo run of
/// the finite well (`colloidsim_bcd::mc`, the exact equilibrium BCD must reach as dt -> 0) and
/// BCD runs from its last configuration at three steps; the peak (three bins around the
/// theory's maximum) is fitted seed by seed by a straight line in sqrt(dt) (the projection of
/// hard contacts leaves a boundary layer of width ~ sqrt(D dt) at contact, which the well
/// fills) and extrapolated to dt = 0. The extrapolation must meet the Monte Carlo peak within
/// 3 combined errors and reject the eps -> 0 theory; the largest step (the paper's Eq. 34
/// would allow larger) must lie measurably below (docs/figures.md, "All of Fig. 6"). 17 min of
/// CPU, 13.5 min on 2 shared cores (`cargo test --release -p colloidsim-bcd --test integration
/// validation::sticky_dense_time_step -- --ignored`); with 5 instead of 10 time units per run it failed (the theory not
/// rejected: +0.68 % +- 0.39 %).
#[test]
#[ignore]
fn sticky_dense_time_step_error_extrapolates_to_the_finite_well() {
    use colloidsim_bcd::forces::CosineForce;
    use colloidsim_bcd::mc::StickyRing;
    use colloidsim_core::field1d::{ExternalField, FieldTerm};
    use rayon::prelude::*;
    let (n, length, sigma, gamma, eps, bins) = (80usize, 100.0, 0.8, 1.0, 0.05, 50usize);
    let dts = [2.5e-6, 1.25e-6, 6.25e-7];
    let (equilibrate, sample, every) = (1.0, 10.0, 5u64);
    let field = ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    };
    let histogram = |x: &[f64], h: &mut [f64]| {
        for &xi in x {
            let b = (xi.rem_euclid(1.0) * bins as f64) as usize;
            h[b.min(bins - 1)] += 1.0;
        }
    };
    let normalise = |h: &mut Vec<f64>, samples: u64| {
        let norm = samples as f64 * length / bins as f64;
        h.iter_mut().for_each(|v| *v /= norm);
    };
    // Per seed: the Monte Carlo profile, and BCD's at each step.
    let seeds: Vec<(Vec<f64>, Vec<Vec<f64>>)> = (0..16u64)
        .into_par_iter()
        .map(|seed| {
            let mut ring = StickyRing::new(n, length, 6.0, sigma, gamma, eps, 700 + seed);
            for _ in 0..100_000 {
                ring.sweep();
            }
            let mut mc = vec![0.0; bins];
            let sweeps = 400_000;
            for _ in 0..sweeps {
                ring.sweep();
                ring.histogram(&mut mc);
            }
            normalise(&mut mc, sweeps);
            let start = init::from_positions(
                &cfg(length, sigma, dts[0], 0),
                ring.x.iter().map(|x| x.rem_euclid(length)).collect(),
            )
            .unwrap();
            let bcd = dts
                .iter()
                .map(|&dt| {
                    let c = cfg(length, sigma, dt, 700 + seed as u32);
                    let sticky = Sticky::new(gamma, eps, 3.0, sigma, 1.0).unwrap();
                    let cosine = CosineForce::from_field(&field).unwrap();
                    let mut b = Bcd::new(c, start.clone(), cosine, sticky).unwrap();
                    b.run((equilibrate / dt).round() as u64).unwrap();
                    let (mut h, mut samples) = (vec![0.0; bins], 0);
                    for _ in 0..((sample / dt).round() as u64 / every) {
                        b.run(every).unwrap();
                        histogram(b.positions(), &mut h);
                        samples += 1;
                    }
                    normalise(&mut h, samples);
                    h
                })
                .collect();
            (mc, bcd)
        })
        .collect();
    let theory = fig6_theory(sigma, n as f64 / length, gamma, bins);
    let (mc, mc_err) = mean_and_error(
        &seeds
            .iter()
            .map(|(m, _)| peak_deviation(m, &theory))
            .collect::<Vec<_>>(),
    );
    let per_step: Vec<(f64, f64)> = (0..dts.len())
        .map(|k| {
            mean_and_error(
                &seeds
                    .iter()
                    .map(|(_, b)| peak_deviation(&b[k], &theory))
                    .collect::<Vec<_>>(),
            )
        })
        .collect();
    // Seed by seed: the least-squares line in sqrt(dt), at dt = 0.
    let xs: Vec<f64> = dts.iter().map(|dt| dt.sqrt()).collect();
    let mx = xs.iter().sum::<f64>() / xs.len() as f64;
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    let intercepts: Vec<f64> = seeds
        .iter()
        .map(|(_, b)| {
            let ys: Vec<f64> = b.iter().map(|h| peak_deviation(h, &theory)).collect();
            let my = ys.iter().sum::<f64>() / ys.len() as f64;
            let slope = xs
                .iter()
                .zip(&ys)
                .map(|(x, y)| (x - mx) * (y - my))
                .sum::<f64>()
                / sxx;
            my - slope * mx
        })
        .collect();
    let (limit, limit_err) = mean_and_error(&intercepts);
    for (dt, (p, e)) in dts.iter().zip(&per_step) {
        eprintln!(
            "dt = {dt:e}: peak {:+.2} % +- {:.2} %",
            100.0 * p,
            100.0 * e
        );
    }
    eprintln!(
        "extrapolated (sqrt dt): {:+.2} % +- {:.2} %; Monte Carlo of the finite well {:+.2} % +- \
         {:.2} %",
        100.0 * limit,
        100.0 * limit_err,
        100.0 * mc,
        100.0 * mc_err
    );
    let combined = limit_err.hypot(mc_err);
    assert!(
        (limit - mc).abs() < 3.0 * combined,
        "dt -> 0: {limit} +- {limit_err} against the finite well's {mc} +- {mc_err}"
    );
    // The eps -> 0 theory (0), which the finite well lies above, is rejected.
    assert!(limit > 3.0 * limit_err, "{limit} +- {limit_err}");
    // The time-step error is real at the largest step.
    let (p0, e0) = per_step[0];
    assert!(
        mc - p0 > 3.0 * e0.hypot(mc_err),
        "dt = {}: {p0} +- {e0} against {mc}",
        dts[0]
    );
}
