//! The Leimkuhler–Matthews integrator (`Integrator::Lm`): its noise is the Euler noise of steps
//! n and n + 1 averaged, it restarts bitwise and does not depend on the thread count, its
//! premerged step still equals the chronological one, and it removes most of Euler's bias of
//! the density in the hard-rods paper's cosine potential at equal cost per step.

#[allow(dead_code)] // shares the validation tests' helpers; uses only some
use crate::common;

use colloidsim_bcd::forces::{NoField, NoPair};
use colloidsim_bcd::observe::DensityProfile;
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Integrator, Update, init};
use colloidsim_core::rng::fill_normal_wide;
use colloidsim_dft::rods::{self, BetaPotential, Domain, RodsProblem};
use common::{cosine, cosine_field, mean_and_error};
use rayon::prelude::*;

fn config(length: f64, sigma: f64, dt: f64, boundary: Boundary, update: Update) -> BcdConfig {
    BcdConfig {
        length,
        sigma,
        mobility: 1.0,
        kt: 1.0,
        dt,
        boundary,
        seed: 17,
        update,
    }
}

/// The noise is keyed by (seed, step, rod) as Euler's: one LM step of free rods moves rod i by
/// `sqrt(2 D dt) (xi_{i,n} + xi_{i,n+1}) / 2`, with `xi_{.,n}` the deviates Euler uses at step n.
#[test]
fn lm_noise_is_the_mean_of_eulers_deviates_of_steps_n_and_n_plus_1() {
    let n = 600; // three noise segments of 256 rods
    for (boundary, update) in [
        (Boundary::Periodic, Update::Premerge),
        (Boundary::Walls, Update::Premerge),
        (Boundary::Periodic, Update::Chronological),
    ] {
        // Rods 16 apart never meet in four steps.
        let mut cfg = config(1e4, 1e-6, 1e-3, boundary, update);
        cfg.mobility = 0.7;
        let x0 = init::lattice(&cfg, n).unwrap();
        let mut b = Bcd::new(cfg.clone(), x0.clone(), NoField, NoPair)
            .unwrap()
            .with_integrator(Integrator::Lm);
        b.run(3).unwrap();
        let x1 = b.positions().to_vec();
        b.step().unwrap();
        let (mut xi3, mut xi4) = (vec![0.0; n], vec![0.0; n]);
        for seg in 0..n.div_ceil(256) {
            let r = seg * 256..(seg * 256 + 256).min(n);
            fill_normal_wide(cfg.seed, 3, seg as u64, &mut xi3[r.clone()]);
            fill_normal_wide(cfg.seed, 4, seg as u64, &mut xi4[r]);
        }
        let amp = (2.0 * cfg.diffusion() * cfg.dt).sqrt();
        for i in 0..n {
            let want = 0.5 * amp * (xi3[i] + xi4[i]);
            let got = b.positions()[i] - x1[i];
            assert!(
                (got - want).abs() < 1e-9 * amp,
                "{boundary:?} {update:?} rod {i}: moved {got}, expected {want}"
            );
        }
    }
}

/// Free rods: LM displacements over k steps have variance 2 D dt (k - 1/2) (the deviates of
/// neighbouring steps are shared), Euler's 2 D dt k. At k = 2 the two differ by 25%.
#[test]
fn lm_msd_of_free_rods_is_two_d_dt_times_k_minus_one_half() {
    let n = 20_000;
    let cfg = config(1e9, 1e-6, 1e-3, Boundary::Periodic, Update::Premerge);
    let x0 = init::lattice(&cfg, n).unwrap();
    let msd = |integrator| {
        let mut b = Bcd::new(cfg.clone(), x0.clone(), NoField, NoPair)
            .unwrap()
            .with_integrator(integrator);
        b.run(5).unwrap();
        let start = b.positions().to_vec();
        b.run(2).unwrap();
        b.positions()
            .iter()
            .zip(&start)
            .map(|(a, s)| (a - s).powi(2))
            .sum::<f64>()
            / n as f64
    };
    let unit = 2.0 * cfg.diffusion() * cfg.dt;
    let err = (2.0 / n as f64).sqrt(); // relative error of a Gaussian variance from n samples
    let (lm, euler) = (msd(Integrator::Lm) / unit, msd(Integrator::Euler) / unit);
    assert!(
        (lm - 1.5).abs() < 4.0 * err * 1.5,
        "LM: {lm} x 2 D dt, expected 1.5"
    );
    assert!(
        (euler - 2.0).abs() < 4.0 * err * 2.0,
        "Euler: {euler} x 2 D dt, expected 2"
    );
}

/// A run restarted from a state saved mid-run continues bitwise: the kept deviates are drawn
/// again from the step counter. On the ring (several chunks), between walls and in the
/// chronological update.
#[test]
fn lm_restart_from_state_is_bitwise_identical() {
    for (n, length, boundary, update) in [
        (9000, 10_000.0, Boundary::Periodic, Update::Premerge),
        (100, 120.0, Boundary::Walls, Update::Premerge),
        (40, 50.0, Boundary::Periodic, Update::Chronological),
    ] {
        let cfg = config(length, 0.9, 1e-3, boundary, update);
        let x = init::random(&cfg, n, 2).unwrap();
        let mut a = Bcd::new(cfg.clone(), x, cosine(), NoPair)
            .unwrap()
            .with_integrator(Integrator::Lm);
        a.run(150).unwrap();
        let saved = a.state().clone();
        a.run(150).unwrap();
        let mut b = Bcd::from_state(cfg, saved, cosine(), NoPair)
            .unwrap()
            .with_integrator(Integrator::Lm);
        b.run(150).unwrap();
        assert!(
            a.state() == b.state(),
            "{boundary:?} {update:?}: states differ"
        );
    }
}

#[test]
fn lm_thread_count_does_not_change_the_result() {
    for boundary in [Boundary::Periodic, Boundary::Walls] {
        let cfg = config(10_000.0, 0.95, 1e-3, boundary, Update::Premerge);
        let x = init::random(&cfg, 10_000, 4).unwrap();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut b = Bcd::new(cfg.clone(), x.clone(), |x: f64| 3.0 * x.sin(), NoPair)
                    .unwrap()
                    .with_integrator(Integrator::Lm);
                b.run(200).unwrap();
                b.state().clone()
            })
        };
        assert!(run(1) == run(3), "{boundary:?}: 1 and 3 threads differ");
    }
}

/// Fragmentation and premerging act on whatever free velocities the integrator gives: with LM
/// the premerged step still equals the chronological event-driven one (fast-bcd Sec. IV).
#[test]
fn lm_premerge_equals_chronological() {
    let rugged = |x: f64| 3.0 * (2.3 * x).sin() + 1.5 * (7.1 * x + 0.3).cos();
    for (k, boundary) in [Boundary::Periodic, Boundary::Walls]
        .into_iter()
        .cycle()
        .take(40)
        .enumerate()
    {
        let n = 5 + k;
        let length = n as f64 / (0.6 + 0.009 * k as f64);
        let mut a_cfg = config(
            length,
            1.0,
            [1e-3, 1e-2, 5e-2][k % 3],
            boundary,
            Update::Premerge,
        );
        a_cfg.seed = k as u32;
        let mut b_cfg = a_cfg.clone();
        b_cfg.update = Update::Chronological;
        let x0 = init::random(&a_cfg, n, k as u32).unwrap();
        let mut a = Bcd::new(a_cfg, x0, rugged, NoPair)
            .unwrap()
            .with_integrator(Integrator::Lm);
        for _ in 0..3 {
            let mut b = Bcd::from_state(b_cfg.clone(), a.state().clone(), rugged, NoPair)
                .unwrap()
                .with_integrator(Integrator::Lm);
            a.step().unwrap();
            b.step().unwrap();
            for i in 0..n {
                let (p, q) = (a.positions()[i], b.positions()[i]);
                assert!(
                    (p - q).abs() < 1e-9 * length,
                    "case {k} rod {i}: {p} vs {q}"
                );
            }
            assert_eq!(a.state().bond, b.state().bond, "case {k}");
            assert!(a.min_clearance() > -1e-9);
        }
    }
}

/// The hard-rods paper's Fig. 3 case sigma = rho = 0.5 (50 rods on L = 100, U0 = 6 kT) at
/// dt = 1e-3: Euler's L1 error of the density against the exact theory is about 3.4% (its
/// O(dt U'') bias, U'' = 118 kT in the wells), LM's about 0.3%. Both run the same steps (one
/// deviate per rod and step); eight seeds are pooled, so that the statistical floor of the L1
/// error (about 0.1%) is far below Euler's bias.
#[test]
fn lm_density_error_is_five_times_smaller_than_eulers_at_dt_1e_3() {
    let (n, length, dt, bins) = (50, 100.0, 1e-3, 50);
    let exact = {
        let p = RodsProblem::new(0.5, n as f64 / length, Domain::Periodic { period: 1.0 })
            .with_dx(1e-3)
            .with_potential(BetaPotential::from_field(&cosine_field(), 1.0));
        rods::equilibrium(&p)
            .unwrap()
            .bin_average(bins, 1.0)
            .unwrap()
            .rho
    };
    let profiles = |integrator: Integrator| -> Vec<Vec<f64>> {
        (0..8u32)
            .into_par_iter()
            .map(|seed| {
                let cfg = BcdConfig {
                    seed: 300 + seed,
                    ..config(length, 0.5, dt, Boundary::Periodic, Update::Premerge)
                };
                let x0 = init::random(&cfg, n, cfg.seed).unwrap();
                let mut b = Bcd::new(cfg, x0, cosine(), NoPair)
                    .unwrap()
                    .with_integrator(integrator);
                // Relax into the wells (hops between wells take ~10 time units).
                b.run(20_000).unwrap();
                let mut d = DensityProfile::new(bins, 1.0, length);
                for _ in 0..60_000 {
                    b.step().unwrap();
                    d.sample(b.positions());
                }
                d.profile().1
            })
            .collect()
    };
    // Relative L1 error of the pooled profile, and its noise floor sqrt(2/pi) sum se / sum rho.
    let l1 = |p: &[Vec<f64>]| {
        let norm: f64 = exact.iter().sum();
        let (mut err, mut floor) = (0.0, 0.0);
        for (b, &e) in exact.iter().enumerate() {
            let col: Vec<f64> = p.iter().map(|v| v[b]).collect();
            let (m, se) = mean_and_error(&col);
            err += (m - e).abs();
            floor += se;
        }
        (
            err / norm,
            (2.0 / std::f64::consts::PI).sqrt() * floor / norm,
        )
    };
    let (euler, euler_floor) = l1(&profiles(Integrator::Euler));
    let (lm, lm_floor) = l1(&profiles(Integrator::Lm));
    eprintln!(
        "density L1 error at dt = 1e-3: Euler {euler:.2e} (noise floor {euler_floor:.1e}), LM {lm:.2e} (floor {lm_floor:.1e})"
    );
    // The comparison is about bias: the statistical floor must be far below Euler's error.
    assert!(euler_floor < 0.1 * euler && lm_floor < 0.1 * euler);
    assert!(euler > 0.02, "Euler's known O(dt) bias is missing: {euler}");
    assert!(5.0 * lm < euler, "LM {lm} vs Euler {euler}");
}
