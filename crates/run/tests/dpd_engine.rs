//! Validation of the DPD colloid engine (issue 5): thermostat temperature, momentum
//! conservation, fluctuation–dissipation with lubrication, thread independence, bad input.

use colloidsim_md::dpd::setup::DpdSetup;
use colloidsim_md::dpd::{Dpd, DpdError, DpdParams, LubricationNoise, NeighborMode};
use colloidsim_particles::{Particles, SimBox};
use colloidsim_run::methods::dpd::monitor::TemperatureMonitor;
use colloidsim_run::methods::dpd::params;

use crate::common;

/// Mean and standard error from `blocks` block averages of `x`.
fn mean_and_error(x: &[f64], blocks: usize) -> (f64, f64) {
    let m = x.len() / blocks;
    let means: Vec<f64> = (0..blocks)
        .map(|b| x[b * m..(b + 1) * m].iter().sum::<f64>() / m as f64)
        .collect();
    let mean = means.iter().sum::<f64>() / blocks as f64;
    let var = means.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (blocks - 1) as f64;
    (mean, (var / blocks as f64).sqrt())
}

fn scenario(text: &str) -> DpdSetup {
    params::setup(text).unwrap()
}

/// Pure DPD water (a = 25, gamma = 4.5, density 3, kT = 1) in a cube of side `l`.
fn water(l: f64, dt: f64, seed: u64) -> Dpd {
    scenario(&format!(
        "method = \"dpd\"\nseed = {seed}\n[system]\nbox_length = {l}\nkT = 1.0\n[run]\ndt = {dt}\n"
    ))
    .build()
    .unwrap()
}

/// Kinetic temperatures sampled every `every` steps after `skip` steps.
fn sample_temperature(sim: &mut Dpd, skip: u64, steps: u64, every: u64) -> Vec<f64> {
    sim.run(skip).unwrap();
    let mut t = Vec::new();
    for s in 0..steps {
        sim.advance().unwrap();
        if s.is_multiple_of(every) {
            t.push(sim.thermo().temperature);
        }
    }
    t
}

#[test]
fn water_holds_kt_within_one_percent_at_dt_0_01_and_conserves_momentum() {
    let mut sim = water(8.0, 0.01, 3);
    let p0 = sim.momentum();
    let t = sample_temperature(&mut sim, 500, 6000, 10);
    let (m, se) = mean_and_error(&t, 20);
    eprintln!("dt = 0.01: T = {m:.5} +- {se:.5}");
    // The estimate resolves 1 %, and the temperature is within 1 % of kT.
    assert!(se < 0.003, "standard error {se} too large to test 1 %");
    assert!((m - 1.0).abs() < 0.01, "T = {m} +- {se}");
    // Pair forces are exactly antisymmetric: momentum is conserved to rounding
    // (thermal momentum per bead ~ 1, 1536 beads).
    let p1 = sim.momentum();
    for k in 0..3 {
        assert!((p1[k] - p0[k]).abs() < 1e-9, "momentum {p0:?} -> {p1:?}");
    }
}

#[test]
fn water_pressure_matches_the_published_equation_of_state() {
    // a = 25, density 3, kT = 1: P = 23.637(2) (Lowe thermostat) and 23.635(2) (Shardlow), and
    // 23.587 from the Liyana-Arachchi et al. (2015) equation of state (Allen & Tildesley's DPD
    // example, 100-particle tables). The pressure tensor here is kinetic + full pair virial / V.
    let mut sim = water(8.0, 0.01, 6);
    sim.run(500).unwrap();
    let mut p = Vec::new();
    for s in 0..6000u64 {
        if s.is_multiple_of(10) {
            let th = sim.advance_with_thermo().unwrap();
            p.push((th.pressure[0] + th.pressure[1] + th.pressure[2]) / 3.0);
        } else {
            sim.advance().unwrap();
        }
    }
    let (m, se) = mean_and_error(&p, 20);
    eprintln!("water at density 3: p = {m:.4} +- {se:.4}");
    assert!(se < 0.03, "error {se} too large");
    // Measured 23.71 +- 0.02 here at dt = 0.01 and at dt = 0.005 alike; the published runs used
    // 100 particles (a box of side 3.2) and the EOS fit and the runs differ by 0.05 themselves,
    // so 0.1 (0.4 %) is allowed beyond the statistics. A 1 % error in the repulsion moves p by
    // 0.17 (to 23.88) and fails.
    assert!((m - 23.637).abs() < 4.0 * se + 0.1, "p = {m} +- {se}");
}

#[test]
fn water_at_dt_0_04_runs_warm_by_the_documented_amount() {
    // docs/dpd.md: at dt = 0.04 the kinetic temperature of DPD water runs 2-4 % above kT
    // (velocity Verlet with half-step velocities in the dissipative force).
    let mut sim = water(8.0, 0.04, 4);
    let t = sample_temperature(&mut sim, 200, 4000, 5);
    let (m, se) = mean_and_error(&t, 20);
    eprintln!("dt = 0.04: T = {m:.5} +- {se:.5}");
    assert!(se < 0.004);
    assert!(m > 1.0 + 3.0 * se, "no measurable drift: T = {m} +- {se}");
    assert!(m < 1.06, "drift larger than documented: T = {m} +- {se}");
}

/// Dense colloids without solvent on a simple cubic lattice with gaps 0.1: every colloid has
/// six neighbours in the lubrication range, and the only thermostat is the colloid pair
/// friction and noise, so the kinetic temperature measures how well the noise matches the
/// friction.
fn lubricated_colloids(noise: LubricationNoise) -> Vec<f64> {
    let n_side = 6;
    let spacing = 2.1;
    let l = n_side as f64 * spacing;
    let mut pos = Vec::new();
    for i in 0..n_side {
        for j in 0..n_side {
            for k in 0..n_side {
                pos.push([
                    (i as f64 + 0.5) * spacing - 0.5 * l,
                    (j as f64 + 0.5) * spacing - 0.5 * l,
                    (k as f64 + 0.5) * spacing - 0.5 * l,
                ]);
            }
        }
    }
    let n = pos.len();
    let mass = 4.0 / 3.0 * std::f64::consts::PI * 3.0;
    let kt = 0.1;
    // Start cold: the thermostat must heat the colloids to kT.
    let mut p = Particles::monodisperse(pos, 2.0);
    p.mass = vec![mass; n];
    p.type_names = vec!["C".into()];
    let setup = scenario(
        "method = \"dpd\"\n[system]\nbox_length = 20.0\nphi = 0.1\n[colloids]\neta0 = 0.3\n",
    );
    let mut params: DpdParams = setup.params;
    params.kt = kt;
    params.lubrication_noise = noise;
    let mut sim = Dpd::new(p, SimBox::cube(l), params, vec![true], 0).unwrap();
    sample_temperature(&mut sim, 3000, 24000, 20)
}

#[test]
fn colloid_temperature_with_lubrication_is_kt_only_with_the_exact_noise() {
    let kt = 0.1;
    let t = lubricated_colloids(LubricationNoise::Exact);
    let (m, se) = mean_and_error(&t, 12);
    eprintln!("exact noise: T/kT = {:.4} +- {:.4}", m / kt, se / kt);
    assert!(se / kt < 0.015, "error {se} too large");
    assert!(
        (m / kt - 1.0).abs() < 4.0 * se / kt + 0.01,
        "T/kT = {} +- {}",
        m / kt,
        se / kt
    );
    // The authors' noise (weighted by w) is too weak for the lubrication friction away from
    // contact: the colloids run measurably cold.
    let t = lubricated_colloids(LubricationNoise::Authors);
    let (ma, sea) = mean_and_error(&t, 12);
    eprintln!("authors' noise: T/kT = {:.4} +- {:.4}", ma / kt, sea / kt);
    assert!(
        ma < m - 4.0 * (se * se + sea * sea).sqrt(),
        "exact {m} vs authors {ma}"
    );
}

/// A small colloid suspension used for the bitwise checks.
fn suspension() -> DpdSetup {
    scenario(
        "method = \"dpd\"\nseed = 9\n[system]\nbox_length = 8.0\nphi = 0.15\nradius_distribution = \"uniform\"\nradius_spread = 0.2\n[colloids]\nmorse_depth = 12.0\n",
    )
}

/// Build `setup` and run 300 steps plus one thermo step on a pool of `threads` threads.
fn run_on_threads(setup: &DpdSetup, threads: usize) -> (Particles, colloidsim_md::dpd::Thermo) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut sim = setup.build().unwrap();
        sim.run(300).unwrap();
        let th = sim.advance_with_thermo().unwrap();
        (sim.snapshot(), th)
    })
}

#[test]
fn results_do_not_depend_on_the_number_of_threads() {
    let mut setup = suspension();
    for mode in [NeighborMode::Verlet, NeighborMode::Cells] {
        setup.params.neighbors = mode;
        let (a, ta) = run_on_threads(&setup, 1);
        for threads in [2, 3] {
            let (b, tb) = run_on_threads(&setup, threads);
            assert!(a == b, "{mode:?}: {threads} threads differ from 1");
            assert_eq!(ta, tb);
        }
        assert!(a.typeid.iter().filter(|&&t| t == 1).count() > 5);
    }
}

#[test]
fn bad_input_is_refused_with_the_key() {
    let base = "method = \"dpd\"\n[system]\nbox_length = 10.0\nphi = 0.1\n";
    let err = |extra: &str| {
        params::setup(&format!("{base}{extra}"))
            .unwrap_err()
            .to_string()
    };
    assert!(err("[dpd]\ngamma = 0.0\n").contains("dpd.gamma"));
    assert!(err("[dpd]\ngamma = 250.0\n").contains("(0, 200]"));
    assert!(err("[colloids]\ncutoff = 0.0005\n").contains("colloids.cutoff"));
    assert!(err("[run]\ndt = -1.0\n").contains("run.dt"));
    let e = params::setup(&format!("{base}[system2]\n"));
    assert!(e.is_err());
    let text = format!("{base}[dpd]\ngamma = 2.0\n");
    let (_, ok) = params::read(&toml::from_str(&text).unwrap(), None).unwrap();
    assert!(ok.warnings.iter().any(|w| w.contains("gamma")));
    // Overlapping colloids at the start.
    let setup = scenario(base);
    let mut p = setup.initial_particles().unwrap();
    let (a, b) = (0, 1);
    assert_eq!((p.typeid[a], p.typeid[b]), (1, 1));
    p.pos[b] = [p.pos[a][0] + 1.9, p.pos[a][1], p.pos[a][2]];
    let e = setup
        .build_from(p, 0)
        .err()
        .expect("overlap refused")
        .to_string();
    assert!(e.contains("overlap"), "{e}");
}

#[test]
fn a_heating_time_step_is_detected() {
    // dt = 0.1 heats DPD water far beyond 10 %.
    let mut sim = water(8.0, 0.1, 5);
    let mut mon = TemperatureMonitor::new(1.0, 0.1, 200);
    let mut stopped = None;
    for _ in 0..2000 {
        match sim.advance() {
            Ok(()) => {}
            Err(e @ DpdError::Unstable { .. }) | Err(e @ DpdError::NonFinite { .. }) => {
                stopped = Some(e.to_string());
                break;
            }
            Err(e) => panic!("{e}"),
        }
        if sim.step.is_multiple_of(10)
            && let Err(e) = mon.push(sim.step, sim.thermo().temperature)
        {
            stopped = Some(e);
            break;
        }
    }
    let msg = stopped.expect("no drift detected");
    // The engine names its parameter (`dt`; the run layer names the key), the monitor the key.
    assert!(msg.contains("`dt`") || msg.contains("run.dt"), "{msg}");
    // At dt = 0.01 the same monitor stays quiet.
    let mut sim = water(8.0, 0.01, 5);
    let mut mon = TemperatureMonitor::new(1.0, 0.1, 200);
    for _ in 0..1000 {
        sim.advance().unwrap();
        if sim.step.is_multiple_of(10) {
            mon.push(sim.step, sim.thermo().temperature).unwrap();
        }
    }
}

/// The standard system (phi = 0.2, kT = 0.1, gamma = 4.5, eta0 = 0.3, dt = 0.001) in a box of
/// side 12: mean colloid kinetic temperature over `steps` after `skip`, with its block error.
fn colloid_temperature_in_solvent(noise: &str, skip: u64, steps: u64) -> (f64, f64) {
    let mut sim = scenario(&format!(
        "method = \"dpd\"\nseed = 21\n[system]\nbox_length = 12.0\nphi = 0.2\n[colloids]\nlubrication_noise = \"{noise}\"\n"
    ))
    .build()
    .unwrap();
    sim.run(skip).unwrap();
    let mut t = Vec::new();
    for s in 0..steps {
        sim.advance().unwrap();
        if s.is_multiple_of(50) {
            t.push(sim.thermo().temperature_by_type[1]);
        }
    }
    mean_and_error(&t, 20)
}

#[test]
#[ignore = "long validation (~2 min on 2 cores); results in docs/validation.md"]
fn colloid_temperature_in_solvent_at_phi_0_2_with_lubrication() {
    let kt = 0.1;
    let (m, se) = colloid_temperature_in_solvent("exact", 5000, 40000);
    eprintln!(
        "exact noise, in solvent: T_c/kT = {:.4} +- {:.4}",
        m / kt,
        se / kt
    );
    let (ma, sea) = colloid_temperature_in_solvent("authors", 5000, 40000);
    eprintln!(
        "authors' noise, in solvent: T_c/kT = {:.4} +- {:.4}",
        ma / kt,
        sea / kt
    );
    assert!(
        (m / kt - 1.0).abs() < 4.0 * se / kt + 0.005,
        "T_c/kT = {}",
        m / kt
    );
}

#[test]
#[ignore = "long validation (~2.5 min on 2 cores); results in docs/validation.md"]
fn colloid_diffusion_at_phi_0_05_against_stokes_einstein() {
    let setup = scenario(
        "method = \"dpd\"\nseed = 5\n[system]\nbox_length = 12.0\nphi = 0.05\n[colloids]\neta0 = 0.3\n",
    );
    let mut sim = setup.build().unwrap();
    sim.run(5000).unwrap();
    let tags: Vec<u32> = (0..setup.colloids as u32).collect();
    let every = 200u64;
    let frames_n = 400usize; // 80,000 steps = 80 DPD times = 1.4 tau_D
    let mut frames = Vec::new();
    for f in 0..=frames_n {
        if f > 0 {
            sim.run(every).unwrap();
        }
        let mut x = Vec::new();
        sim.unwrapped(&tags, &mut x);
        frames.push(x);
    }
    let msd = |lag: usize| {
        let mut s = 0.0;
        let mut c = 0;
        for t0 in 0..=frames_n - lag {
            for (a, b) in frames[t0].iter().zip(&frames[t0 + lag]) {
                s += (0..3).map(|k| (b[k] - a[k]).powi(2)).sum::<f64>();
                c += 1;
            }
        }
        s / c as f64
    };
    let dt_frame = every as f64 * setup.params.dt;
    // Long-time slopes between 10 and 25 and between 25 and 50 DPD times (m / zeta ~ 1).
    let slope = |a: usize, b: usize| (msd(b) - msd(a)) / ((b - a) as f64 * dt_frame) / 6.0;
    let d1 = slope(50, 125);
    let d2 = slope(125, 250);
    let d = 0.5 * (d1 + d2);
    eprintln!(
        "phi = 0.05, {} colloids: D = {d:.5} (slopes {d1:.5}, {d2:.5}), D0 = {:.5}, D / D0 = {:.3}",
        setup.colloids,
        setup.d0,
        d / setup.d0
    );
    assert!(d > 0.0 && d.is_finite());
    // Diffusive at long times: the two slopes agree within the scatter of 21 colloids.
    assert!((d1 - d2).abs() < 0.5 * d, "slopes {d1} and {d2}");
}

#[test]
fn engine_forces_equal_a_brute_force_sum_over_all_pairs() {
    for mode in [NeighborMode::Verlet, NeighborMode::Cells] {
        let mut setup = suspension();
        setup.params.neighbors = mode;
        check_forces_against_brute_force(&setup);
    }
}

fn check_forces_against_brute_force(setup: &DpdSetup) {
    let p = setup.initial_particles().unwrap();
    let sim = setup.build().unwrap();
    let got = sim.forces();
    let want = common::brute_force(&p, &setup.sbox, &setup.params, 0, 0.0);
    let scale = want
        .iter()
        .map(|f| f.iter().map(|x| x.abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    for (i, (g, w)) in got.iter().zip(&want).enumerate() {
        for k in 0..3 {
            assert!(
                (g[k] - w[k]).abs() <= 1e-9 * scale,
                "particle {i} (type {}): engine {g:?}, brute force {w:?}",
                p.typeid[i]
            );
        }
    }
    // A 1 % error in the colloid-solvent repulsion is resolved by the comparison.
    let mut wrong = setup.params;
    wrong.repulsion_cs *= 1.01;
    let bad = common::brute_force(&p, &setup.sbox, &wrong, 0, 0.0);
    assert!(
        got.iter()
            .zip(&bad)
            .any(|(g, b)| (0..3).any(|k| (g[k] - b[k]).abs() > 1e-6 * scale))
    );
}

#[test]
fn a_restart_at_a_synchronised_step_continues_bitwise() {
    for mode in [NeighborMode::Verlet, NeighborMode::Cells] {
        let mut setup = suspension();
        setup.params.neighbors = mode;
        let mut a = setup.build().unwrap();
        a.set_sync_every(50);
        a.run(100).unwrap();
        let (snap, forces) = (a.snapshot(), a.forces());
        a.run(150).unwrap();
        let mut b = Dpd::restart(
            snap.clone(),
            &forces,
            setup.sbox,
            setup.params,
            DpdSetup::colloid_types(),
            100,
            50,
        )
        .unwrap();
        b.run(150).unwrap();
        assert!(a.snapshot() == b.snapshot(), "{mode:?}: restart differs");
    }
}
