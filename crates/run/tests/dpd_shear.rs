//! Lees–Edwards shear flow in the DPD engine (issue 19): zero shear is the engine of before
//! bitwise; the pair forces under shear equal a brute-force sum with the shifted images; x
//! momentum changes only by the boundary flux and the flow profile is linear with the imposed
//! slope; the shear viscosity of DPD water agrees with the Green–Kubo value; results do not
//! depend on the threads; restarts continue bitwise; bad input is refused with the key.

use colloidsim_md::dpd::setup::DpdSetup;
use colloidsim_md::dpd::{Dpd, NeighborMode};
use colloidsim_particles::Particles;
use colloidsim_run::methods::dpd::params;

use crate::common;
use common::{brute_force, on_ranks};

/// FNV-1a over the bits of `x`.
fn fnv(h: &mut u64, x: f64) {
    for b in x.to_bits().to_le_bytes() {
        *h ^= b as u64;
        *h = h.wrapping_mul(0x100_0000_01b3);
    }
}

/// Fingerprints (positions, velocities, images, forces, list builds) and the thermo of the last
/// step (pressure and kinetic tensors, temperature) of 150 steps of the colloid suspension with
/// lists and with cells, and of DPD water at dt = 0.04 (cells), all without shear.
fn fingerprints() -> Vec<(u64, Vec<f64>)> {
    let sus = |mode: NeighborMode| {
        let mut s = params::setup(
            "method = \"dpd\"\nseed = 9\n[system]\nbox_length = 8.0\nphi = 0.15\nradius_distribution = \"uniform\"\nradius_spread = 0.2\n[colloids]\nmorse_depth = 12.0\n",
        )
        .unwrap();
        s.params.neighbors = mode;
        s
    };
    let water = params::setup(
        "method = \"dpd\"\nseed = 4\n[system]\nbox_length = 8.0\nkT = 1.0\n[run]\ndt = 0.04\n",
    )
    .unwrap();
    [sus(NeighborMode::Verlet), sus(NeighborMode::Cells), water]
        .iter()
        .map(|setup| {
            let mut sim = setup.build().unwrap();
            sim.run(150).unwrap();
            let th = sim.advance_with_thermo().unwrap();
            let p = sim.snapshot();
            let mut h = 0xcbf2_9ce4_8422_2325u64;
            for i in 0..p.len() {
                for k in 0..3 {
                    fnv(&mut h, p.pos[i][k]);
                    fnv(&mut h, p.vel[i][k]);
                    fnv(&mut h, p.image[i][k] as f64);
                }
            }
            for f in sim.forces() {
                for x in f {
                    fnv(&mut h, x);
                }
            }
            fnv(&mut h, sim.neighbor_builds() as f64);
            let mut thermo: Vec<f64> = th.pressure.iter().chain(&th.kinetic).copied().collect();
            thermo.push(th.temperature);
            (h, thermo)
        })
        .collect()
}

/// The trajectory fingerprints of [`fingerprints`] and the thermo of the engine before
/// Lees–Edwards was added (commit fc1f1d7), computed with this test code at commit 2993974,
/// whose trajectories were still bitwise those of fc1f1d7 (x86_64).
const BEFORE: [(u64, [f64; 13]); 3] = [
    (
        17739977233140845882,
        [
            3.1489247753231857,
            2.476865655491114,
            3.155381857832733,
            -0.24232517440508064,
            0.18289207374396063,
            0.07552839520914066,
            0.24493301534606032,
            0.2615978913649084,
            0.23171712107758055,
            -0.004965838520817311,
            0.003437261244577489,
            -0.006257735749513321,
            0.09523380958118856,
        ],
    ),
    (
        10630691389392135251,
        [
            3.148924775323183,
            2.4768656554911135,
            3.1553818578327344,
            -0.24232517440508053,
            0.18289207374396055,
            0.07552839520914104,
            0.2449330153460603,
            0.26159789136490846,
            0.23171712107758055,
            -0.004965838520817299,
            0.003437261244577477,
            -0.006257735749513331,
            0.09523380958118853,
        ],
    ),
    (
        17026446278268495649,
        [
            24.22081567192621,
            24.200189125002257,
            24.171498628100213,
            0.32402151190224326,
            -0.13484633271795948,
            0.211854859224822,
            3.01596285819573,
            3.135206929870558,
            3.120731470790518,
            0.13294892450692464,
            0.017773447437109624,
            -0.017324010364202218,
            1.0308823983788677,
        ],
    ),
];

/// Trajectories bitwise; the thermo to round-off only: since 2026-12-04 its sums run row of
/// cells by row (so that a grid of ranks cut along y adds them in the same order), before
/// layer by layer.
#[test]
fn zero_shear_is_the_engine_of_before_bitwise() {
    for ((h, thermo), (h0, thermo0)) in fingerprints().into_iter().zip(BEFORE) {
        assert_eq!(h, h0, "trajectory");
        let scale = thermo0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (a, b) in thermo.iter().zip(thermo0) {
            assert!((a - b).abs() <= 1e-13 * scale, "thermo {a} against {b}");
        }
    }
}

fn scenario(text: &str) -> DpdSetup {
    params::setup(text).unwrap()
}

/// The colloid suspension of the thread tests (Morse attraction, polydisperse) under shear.
fn suspension(mode: NeighborMode, shear: f64) -> DpdSetup {
    let mut s = scenario(&format!(
        "method = \"dpd\"\nseed = 9\n[system]\nbox_length = 8.0\nphi = 0.15\nradius_distribution = \"uniform\"\nradius_spread = 0.2\n[colloids]\nmorse_depth = 12.0\n[run]\nshear_rate = {shear}\n"
    ));
    s.params.neighbors = mode;
    s
}

/// DPD water (density 3, a = 25, gamma = 4.5, kT = 1) in a cube of side `l` under shear.
fn water(l: f64, dt: f64, shear: f64, seed: u64) -> DpdSetup {
    scenario(&format!(
        "method = \"dpd\"\nseed = {seed}\n[system]\nbox_length = {l}\nkT = 1.0\n[run]\ndt = {dt}\nshear_rate = {shear}\n"
    ))
}

#[test]
fn sheared_forces_equal_a_brute_force_sum_over_the_shifted_images() {
    // 250 steps at gamma_dot = 2 move the offset by 2 * 8 * 0.25 = 4 (continuously from a start
    // without overlaps); a fresh engine on that state at that step sums its forces.
    for mode in [NeighborMode::Verlet, NeighborMode::Cells] {
        let setup = suspension(mode, 2.0);
        let mut run = setup.build().unwrap();
        run.run(250).unwrap();
        let p = run.snapshot();
        let sim = Dpd::new(
            p.clone(),
            setup.sbox,
            setup.params,
            DpdSetup::colloid_types(),
            250,
        )
        .unwrap();
        assert_eq!(sim.snapshot(), p);
        let offset = sim.shear_offset();
        assert!((3.9..4.1).contains(&offset), "offset {offset}");
        let got = sim.forces();
        let want = brute_force(&p, &setup.sbox, &setup.params, 250, offset);
        let scale = want
            .iter()
            .map(|f| f.iter().map(|x| x.abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            for k in 0..3 {
                assert!(
                    (g[k] - w[k]).abs() <= 1e-9 * scale,
                    "{mode:?}: particle {i} (type {}): engine {g:?}, brute force {w:?}",
                    p.typeid[i]
                );
            }
        }
        // Without the image velocity in the dissipative force the sum differs (resolved).
        let mut wrong = setup.params;
        wrong.shear_rate = 0.0;
        let bad = brute_force(&p, &setup.sbox, &wrong, 250, offset);
        let dmax = got
            .iter()
            .zip(&bad)
            .map(|(g, b)| (0..3).map(|k| (g[k] - b[k]).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        assert!(dmax > 1e-3 * scale, "{mode:?}: {dmax} vs scale {scale}");
    }
}

/// Build `setup` and run 800 steps plus one thermo step on a pool of `threads` threads.
fn run_on_threads(setup: &DpdSetup, threads: usize) -> (Particles, String, Vec<[f64; 3]>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut sim = setup.build().unwrap();
        sim.run(800).unwrap();
        let th = sim.advance_with_thermo().unwrap();
        (sim.snapshot(), format!("{th:?}"), sim.forces())
    })
}

#[test]
fn sheared_results_do_not_depend_on_the_number_of_threads() {
    for mode in [NeighborMode::Verlet, NeighborMode::Cells] {
        // gamma_dot L_y t = 1.5 * 8 * 0.8: the offset moves 9.6 (more than L_x), many list
        // rebuilds.
        let setup = suspension(mode, 1.5);
        let (a, ta, fa) = run_on_threads(&setup, 1);
        let (b, tb, fb) = run_on_threads(&setup, 2);
        assert!(a == b, "{mode:?}: 2 threads differ from 1");
        assert_eq!(ta, tb);
        assert!(fa == fb);
        // Particles did cross the y boundary.
        assert!(a.image.iter().any(|i| i[1] != 0));
    }
}

#[test]
fn a_sheared_restart_continues_bitwise() {
    for mode in [NeighborMode::Verlet, NeighborMode::Cells] {
        let setup = suspension(mode, 1.5);
        let mut a = setup.build().unwrap();
        a.set_sync_every(50);
        a.run(100).unwrap();
        let (snap, forces) = (a.snapshot(), a.forces());
        a.run(150).unwrap();
        let mut b = Dpd::restart(
            snap,
            &forces,
            setup.sbox,
            setup.params,
            DpdSetup::colloid_types(),
            100,
            50,
        )
        .unwrap();
        assert_eq!(b.shear_offset().to_bits(), {
            let mut c = setup.build().unwrap();
            c.run(100).unwrap();
            c.shear_offset().to_bits()
        });
        b.run(150).unwrap();
        assert!(a.snapshot() == b.snapshot(), "{mode:?}: restart differs");
    }
}

/// Slope and its standard error of a least-squares line through `(x, y)`.
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// Mean and standard error of `x` from `blocks` block means.
fn mean_and_error(x: &[f64], blocks: usize) -> (f64, f64) {
    let m = x.len() / blocks;
    let means: Vec<f64> = (0..blocks)
        .map(|b| x[b * m..(b + 1) * m].iter().sum::<f64>() / m as f64)
        .collect();
    let mean = means.iter().sum::<f64>() / blocks as f64;
    let var = means.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (blocks - 1) as f64;
    (mean, (var / blocks as f64).sqrt())
}

/// What a shear run of DPD water measures.
#[derive(Debug)]
struct ShearRun {
    /// `<-P_xy> / gamma_dot` over the second half, and its block standard error.
    eta: (f64, f64),
    /// Slope of the mean `v_x(y)` profile (8 bins) over the second half, and its block error.
    slope: (f64, f64),
    /// Kinetic temperature (peculiar velocities) over the second half.
    temperature: f64,
    /// Largest change of `P_x + gamma_dot L_y sum m image_y` (x momentum corrected by the
    /// boundary flux of the crossings), relative to `sum m |v_x|`.
    momentum_drift: f64,
}

/// DPD water (L = 8, 1536 beads, kT = 1, dt = 0.01) at shear rate `rate` for `steps` steps
/// from the linear profile; the stress every step, the profile every 10 steps.
fn shear_run(rate: f64, steps: u64, seed: u64) -> ShearRun {
    let setup = water(8.0, 0.01, rate, seed);
    let mut sim = setup.build().unwrap();
    let ly = setup.sbox.l[1];
    let corrected = |sim: &Dpd| {
        let p = sim.snapshot();
        let mut px = 0.0;
        let mut scale = 0.0;
        for i in 0..p.len() {
            px += p.mass[i] * (p.vel[i][0] + rate * ly * p.image[i][1] as f64);
            scale += p.mass[i] * p.vel[i][0].abs();
        }
        (px, scale)
    };
    let (px0, scale) = corrected(&sim);
    let mut drift: f64 = 0.0;
    let bins = 8;
    let y: Vec<f64> = (0..bins)
        .map(|b| -0.5 * ly + (b as f64 + 0.5) * ly / bins as f64)
        .collect();
    let (mut stress, mut slopes, mut temps) = (Vec::new(), Vec::new(), Vec::new());
    let (mut sum, mut count) = (vec![0.0; bins], vec![0.0; bins]);
    for s in 0..steps {
        let p = sim.advance_with_pressure().unwrap();
        if s >= steps / 2 {
            stress.push(-p[3]);
            if s % 10 == 0 {
                sum.iter_mut().for_each(|x| *x = 0.0);
                count.iter_mut().for_each(|x| *x = 0.0);
                sim.add_velocity_profile(&mut sum, &mut count);
                let v: Vec<f64> = sum.iter().zip(&count).map(|(a, c)| a / c).collect();
                slopes.push(slope(&y, &v));
                temps.push(sim.thermo().temperature);
            }
        }
        if s % 500 == 0 {
            drift = drift.max((corrected(&sim).0 - px0).abs() / scale);
        }
    }
    let (m, e) = mean_and_error(&stress, 10);
    ShearRun {
        eta: (m / rate, e / rate),
        slope: mean_and_error(&slopes, 10),
        temperature: temps.iter().sum::<f64>() / temps.len() as f64,
        momentum_drift: drift,
    }
}

/// Shear rate of the CI test: DPD water heats under shear (the thermostat removes the viscous
/// heat `eta gamma_dot^2` only at a finite rate): measured T = 1.03 kT at 0.5, 1.12 kT at 1.
const RATE: f64 = 0.5;

#[test]
fn dpd_water_under_shear_has_the_linear_profile_and_the_green_kubo_viscosity() {
    let r = shear_run(RATE, 12_000, 7);
    println!("{r:?}");
    // x momentum changes only by the boundary flux: pair forces conserve it exactly.
    assert!(r.momentum_drift < 1e-12, "{r:?}");
    // The measured profile v_x(y) is linear with the imposed slope (4 block errors).
    assert!(r.slope.1 < 0.02 * RATE, "{r:?}");
    assert!((r.slope.0 - RATE).abs() < 4.0 * r.slope.1, "{r:?}");
    // The temperature of the peculiar velocities: kT plus the viscous heating (3 %).
    assert!((r.temperature - 1.0).abs() < 0.06, "{r:?}");
    // The viscosity agrees with Green-Kubo (0.832 +- 0.012 at t_max = 2,
    // docs/reports/dpd-validation.md) within 4 combined standard errors.
    let (gk, gk_err) = (0.832, 0.012);
    let tol = 4.0 * (r.eta.1.powi(2) + gk_err * gk_err).sqrt();
    assert!(r.eta.1 < 0.03, "{r:?}");
    assert!((r.eta.0 - gk).abs() < tol, "{r:?}: tolerance {tol}");
}

/// The notes' colloid model (R_c = 1, kT = 0.1, gamma = 4.5, eta0 = 0.3, contact and squeeze
/// lubrication, dt = 0.001) at volume fraction `phi` in a box of 12 rc sheared at `rate`
/// (`scripts/suspension_viscosity.py` runs the same model in a box of 15 for 10^5 steps).
fn notes_suspension(phi: f64, rate: f64) -> DpdSetup {
    scenario(&format!(
        "method = \"dpd\"\nseed = 3\n[system]\nbox_length = 12.0\nphi = {phi}\nkT = 0.1\n\
         [colloids]\neta0 = 0.3\n[run]\ndt = 0.001\nskin = 0.4\nshear_rate = {rate}\n"
    ))
}

/// `<-P_xy> / rate` over the second half of `steps` steps and its standard error (10 blocks).
fn shear_viscosity(setup: &DpdSetup, rate: f64, steps: u64) -> (f64, f64) {
    let mut sim = setup.build().unwrap();
    let mut stress = Vec::new();
    for s in 0..steps {
        let p = sim.advance_with_pressure().unwrap();
        if s >= steps / 2 {
            stress.push(-p[3]);
        }
    }
    let (m, e) = mean_and_error(&stress, 10);
    (m / rate, e / rate)
}

/// The suspension at phi = 0.1 is more viscous than its solvent by the dilute theory:
/// `eta_r = 1 + 2.5 phi + 5.2 phi^2 = 1.302` (Einstein with Batchelor's 1977 hydrodynamic pair
/// term; 6.2 with the Brownian stress gives 1.312) within 4 standard errors of
/// the ratio (the long runs of docs/reports/dpd-validation.md give 1.271 +- 0.015), and
/// certainly above 1: a suspension whose colloids did not take part in the flow would fail.
#[test]
fn the_colloid_suspension_has_the_dilute_relative_viscosity() {
    let (rate, steps) = (0.2, 16_000);
    let (e0, s0) = shear_viscosity(&notes_suspension(0.0, rate), rate, steps);
    let (e1, s1) = shear_viscosity(&notes_suspension(0.1, rate), rate, steps);
    let r = e1 / e0;
    let err = r * ((s0 / e0).powi(2) + (s1 / e1).powi(2)).sqrt();
    println!("solvent {e0} +- {s0}, suspension {e1} +- {s1}, eta_r = {r} +- {err}");
    assert!(err < 0.06, "{err}");
    assert!(r - 1.0 > 4.0 * err, "eta_r = {r} +- {err}");
    assert!((r - 1.302).abs() < 4.0 * err, "eta_r = {r} +- {err}");
}

/// The table of docs/reports/dpd-validation.md: longer runs at three rates (`-- --ignored --nocapture`).
#[test]
#[ignore]
fn shear_viscosity_table() {
    for rate in [0.25, 0.5, 1.0] {
        let r = shear_run(rate, 40_000, 11);
        println!("rate {rate}: {r:?}");
    }
}

#[test]
fn bad_shear_rates_are_refused_with_the_key() {
    let base = "method = \"dpd\"\n[system]\nbox_length = 8.0\n[run]\n";
    for bad in ["-0.1", "nan", "inf", "11.0"] {
        let e = params::setup(&format!("{base}shear_rate = {bad}\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("run.shear_rate"), "{bad}: {e}");
    }
    // A sheared run is cut into slabs only (the y boundary moves the images along x), and a
    // grid needs at least one rank along each axis.
    for (bad, says) in [
        (
            "shear_rate = 0.5\nrank_grid = [2, 1]",
            "sheared run is cut along z only",
        ),
        ("rank_grid = [0, 2]", "in [1, 1000000], got [0, 2]"),
    ] {
        let e = params::setup(&format!("{base}{bad}\n"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("run.rank_grid") && e.contains(says),
            "{bad}: {e}"
        );
    }
    // The engine refuses a non-finite rate too.
    let mut setup = water(8.0, 0.04, 0.0, 1);
    setup.params.shear_rate = f64::NAN;
    let e = setup.build().err().expect("refused").to_string();
    assert!(e.contains("shear rate"), "{e}");
}

/// The forces a running engine used at its last step against those of a fresh engine (new
/// lists or cells) on the same positions and the same half-step velocities
/// (`v(n) - F dt / 2m`): a pair missing from an aged Verlet list shows as a difference.
fn check_against_fresh(sim: &Dpd, setup: &DpdSetup) {
    let mut p = sim.snapshot();
    let f = sim.forces();
    let dt = setup.params.dt;
    for i in 0..p.len() {
        for k in 0..3 {
            p.vel[i][k] -= 0.5 * dt * f[i][k] / p.mass[i];
        }
    }
    let mut prm = setup.params;
    prm.neighbors = NeighborMode::Cells;
    let fresh = Dpd::new(p, setup.sbox, prm, DpdSetup::colloid_types(), sim.step).unwrap();
    let g = fresh.forces();
    let scale = g
        .iter()
        .map(|f| f.iter().map(|x| x.abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    for i in 0..g.len() {
        for k in 0..3 {
            assert!(
                (f[i][k] - g[i][k]).abs() < 1e-8 * scale,
                "step {}: particle {i}: running {:?}, fresh {:?}",
                sim.step,
                f[i],
                g[i]
            );
        }
    }
}

#[test]
fn aged_verlet_lists_under_shear_miss_no_pair() {
    // DPD water at rate 3 started at rest (no streaming profile: the fastest particles move
    // about 0.05 a step while the offset moves 0.24, so only the offset's drift calls for the
    // first rebuilds), and the colloid suspension at rate 1.5 from its profile, both with Verlet
    // lists.
    for (mut setup, at_rest, steps, every) in [
        (water(8.0, 0.01, 3.0, 3), true, 40, 1),
        (suspension(NeighborMode::Verlet, 1.5), false, 600, 37),
    ] {
        setup.params.neighbors = NeighborMode::Verlet;
        let mut p = setup.initial_particles().unwrap();
        if at_rest {
            for (v, x) in p.vel.iter_mut().zip(&p.pos) {
                v[0] -= setup.params.shear_rate * x[1];
            }
        }
        let mut sim = setup.build_from(p, 0).unwrap();
        assert!(!sim.uses_cells());
        let b0 = sim.neighbor_builds();
        for s in 1..=steps {
            sim.advance().unwrap();
            if s % every == 0 {
                check_against_fresh(&sim, &setup);
            }
        }
        assert!(sim.neighbor_builds() > b0 + 5);
    }
}

/// Particles, forces, the thermo of the last step and the velocity profile after `steps`
/// steps plus one thermo step.
fn end_of(sim: &mut Dpd, steps: u64) -> (Particles, Vec<[f64; 3]>, String, Vec<f64>) {
    sim.run(steps).unwrap();
    let th = sim.advance_with_thermo().unwrap();
    let (mut sum, mut count) = (vec![0.0; 8], vec![0.0; 8]);
    sim.add_velocity_profile(&mut sum, &mut count);
    sum.extend(count);
    (sim.snapshot(), sim.forces(), format!("{th:?}"), sum)
}

#[test]
fn a_decomposed_shear_run_is_bitwise_the_single_rank_run() {
    // The suspension (lists and cells) at rate 1.5 and water at dt 0.04 (cells) at rate 0.5:
    // particles cross the y boundary inside every slab and migrate between ranks along z.
    let mut cases: Vec<(DpdSetup, u64)> = [NeighborMode::Verlet, NeighborMode::Cells]
        .into_iter()
        .map(|m| (suspension(m, 1.5), 800))
        .collect();
    cases.push((water(7.0, 0.04, 0.5, 4), 150));
    for (setup, steps) in &cases {
        let one = end_of(&mut setup.build().unwrap(), *steps);
        assert!(one.0.image.iter().any(|i| i[1] != 0));
        for ranks in [2, 3] {
            let ends = on_ranks(ranks, |c| {
                end_of(&mut setup.build_decomposed(c).unwrap(), *steps)
            });
            for (r, e) in ends.iter().enumerate() {
                let what = format!("{:?}, rank {r} of {ranks}", setup.params.neighbors);
                assert!(one.0 == e.0, "{what}: particles differ");
                assert!(one.1 == e.1, "{what}: forces differ");
                assert_eq!(one.2, e.2, "{what}: thermo differs");
                assert!(one.3 == e.3, "{what}: profile differs");
            }
        }
    }
}

#[test]
fn the_pressure_parts_sum_to_the_pressure_tensor() {
    // The sheared suspension with Morse attraction: every part but none of the classes lost.
    let setup = suspension(NeighborMode::Verlet, 1.5);
    let vol = setup.sbox.volume();
    let mut sim = setup.build().unwrap();
    sim.run(300).unwrap();
    let th = sim.advance_with_thermo().unwrap();
    let parts = sim.pressure_parts();
    let total = sim.pressure_tensor();
    let scale = total.iter().map(|x| x.abs()).fold(0.0, f64::max);
    for k in 0..6 {
        let sum: f64 = parts.iter().map(|p| p[k]).sum();
        assert!(
            (sum - total[k]).abs() < 1e-12 * scale,
            "component {k}: {sum} against {}",
            total[k]
        );
        // The kinetic parts are thermo's kinetic tensor, split by type.
        let kin = parts[0][k] + parts[1][k];
        assert!((kin - th.kinetic[k]).abs() < 1e-12 * scale, "kinetic {k}");
    }
    let names = colloidsim_md::dpd::PRESSURE_PARTS;
    let part = |n: &str| parts[names.iter().position(|m| *m == n).unwrap()];
    // The colloid classes are there (colloids, their solvent shells, contacts and Morse bonds
    // in a dense attractive suspension) and the pairs with a colloid are part of their class.
    for n in [
        "kinetic_colloid",
        "conservative_colloid",
        "dissipative_colloid",
        "morse",
    ] {
        assert!(part(n)[0] != 0.0, "{n} is zero");
    }
    let v = &th.virial;
    for k in 0..6 {
        let cons = part("conservative_solvent")[k] + part("conservative_colloid")[k];
        assert!(
            (cons - v.conservative[k] / vol).abs() < 1e-12 * scale,
            "conservative {k}"
        );
    }
}
