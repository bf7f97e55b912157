//! Validation of the Brownian engine against exact results. Tolerances are derived from the
//! statistical error of each run (fixed seeds); each test also checks that a deliberately wrong
//! input would have been caught.

use colloidsim_md::gsd::{GsdWriter, read_frame};
use colloidsim_md::init::{random_in_box, random_in_sphere};
use colloidsim_md::{
    BdError, BdParams, Brownian, External, HarmonicInterface, Integrator, LennardJones, NoExternal,
    NoPair, Pair, Particles, SimBox, SphereAreaLaw,
};
use rayon::prelude::*;
use std::f64::consts::PI;

fn unwrapped(sim_box: &SimBox, p: &Particles) -> Vec<[f64; 3]> {
    p.pos
        .iter()
        .zip(&p.image)
        .map(|(x, i)| sim_box.unwrap(*x, *i))
        .collect()
}

/// Free particles: MSD(t) = 6 D t with D = kT / (3 pi eta d).
#[test]
fn free_particle_msd_is_6_d_t() {
    let n = 4000;
    let sbox = SimBox::cube(10.0); // small box: many crossings exercise the image counts
    let pos = random_in_box(n, 0.0, &sbox, 3, 0).unwrap();
    let mut params = BdParams::new(0.01, 11);
    params.viscosity = 0.7;
    params.kt = 1.3;
    let d = 1.2;
    let mut sim = Brownian::new(
        Particles::monodisperse(pos, d),
        sbox,
        NoPair,
        NoExternal,
        params,
        0,
    )
    .unwrap();
    let d0 = params.kt / (3.0 * PI * params.viscosity * d);
    let x0 = unwrapped(&sbox, &sim.snapshot());
    for block in 1..=4 {
        sim.run(100).unwrap();
        let x = unwrapped(&sbox, &sim.snapshot());
        let msd = x
            .iter()
            .zip(&x0)
            .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>())
            .sum::<f64>()
            / n as f64;
        let t = sim.time();
        let want = 6.0 * d0 * t;
        // |dr|^2 = 2 D t chi^2_3: relative standard error of the mean sqrt(2/3) / sqrt(N).
        let tol = 5.0 * (2.0 / 3.0f64).sqrt() / (n as f64).sqrt();
        assert!(
            (msd / want - 1.0).abs() < tol,
            "block {block}: MSD {msd} vs 6 D t = {want} (tolerance {tol})"
        );
        // A 10 % error in the friction (e.g. radius instead of diameter somewhere) is caught.
        assert!((msd / (want * 1.1) - 1.0).abs() > tol);
    }
}

/// Ideal particles in a static harmonic shell: rho(r) proportional to exp(-V(r) / kT).
#[test]
fn ideal_particles_in_static_shell_follow_boltzmann() {
    let n = 3000;
    let r0 = 4.0;
    let wall = |k: f64| HarmonicInterface {
        centre: [0.0; 3],
        radius: SphereAreaLaw { r0, alpha: 0.0 },
        stiffness: k,
        range: 0.5,
        offset: 0.0,
    };
    let k = 4.0;
    let sbox = SimBox::cube(30.0);
    let pos = random_in_sphere(n, 0.0, [0.0; 3], r0, 5, 0).unwrap();
    let mut params = BdParams::new(0.002, 21);
    params.viscosity = 1.0 / (3.0 * PI); // friction 1, D = 1
    let mut sim = Brownian::new(
        Particles::monodisperse(pos, 1.0),
        sbox,
        NoPair,
        wall(k),
        params,
        0,
    )
    .unwrap();
    sim.run(2500).unwrap();
    let (bins, r_max) = (40usize, r0 + 2.0);
    let dr = r_max / bins as f64;
    let mut hist = vec![0.0; bins];
    let frames = 40;
    for _ in 0..frames {
        sim.run(250).unwrap();
        for p in &sim.particles().pos {
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            if r < r_max {
                hist[(r / dr) as usize] += 1.0;
            }
        }
    }
    let samples = (n * frames) as f64;
    // Expected counts: samples * int_bin 4 pi r^2 exp(-V) dr / Z, by fine quadrature.
    let expected = |k: f64| -> Vec<f64> {
        let w = wall(k);
        let m = 400;
        let shell = |a: f64, b: f64| -> f64 {
            let h = (b - a) / m as f64;
            (0..m)
                .map(|j| {
                    let r = a + (j as f64 + 0.5) * h;
                    4.0 * PI * r * r * (-w.energy([r, 0.0, 0.0], 0.0)).exp() * h
                })
                .sum()
        };
        let z = shell(0.0, r_max + 10.0);
        (0..bins)
            .map(|b| samples * shell(b as f64 * dr, (b + 1) as f64 * dr) / z)
            .collect()
    };
    // Frames 0.5 time units apart are nearly independent (rms displacement 1 per axis);
    // allow a factor 2 for the remaining correlation.
    let chi2 = |e: &[f64]| -> f64 {
        hist.iter()
            .zip(e)
            .filter(|(_, e)| **e > 20.0)
            .map(|(o, e)| (o - e).powi(2) / (2.0 * e))
            .sum()
    };
    let dof = bins as f64;
    let good = chi2(&expected(k));
    assert!(
        good < dof + 5.0 * (2.0 * dof).sqrt(),
        "chi2 {good} for {dof} bins"
    );
    // The wall region alone (r > R): the fraction of samples there matches.
    let e = expected(k);
    let b_wall = (r0 / dr) as usize;
    let (o_out, e_out): (f64, f64) = (hist[b_wall..].iter().sum(), e[b_wall..].iter().sum());
    assert!(
        (o_out - e_out).abs() < 5.0 * (2.0 * e_out).sqrt(),
        "{o_out} vs {e_out} beyond R"
    );
    // A stiffness off by 10 % is caught.
    let bad = chi2(&expected(1.1 * k));
    assert!(
        bad > dof + 5.0 * (2.0 * dof).sqrt(),
        "wrong k not caught: {bad}"
    );
}

/// Two WCA particles: the distribution of their separation is 4 pi r^2 exp(-u(r)/kT) / Z.
#[test]
fn two_wca_particles_sample_exp_minus_u() {
    let l = 3.0;
    let sbox = SimBox::cube(l);
    let wca = LennardJones::wca(1.0, 1.0);
    let (r_lo, r_hi, bins) = (0.85, 1.45, 12usize);
    let dr = (r_hi - r_lo) / bins as f64;
    let engines = 32;
    let hist: Vec<f64> = (0..engines)
        .into_par_iter()
        .map(|e| {
            let pos = random_in_box(2, 1.0, &sbox, 100 + e as u32, 0).unwrap();
            let mut params = BdParams::new(2e-4, 1000 + e as u32);
            params.viscosity = 1.0 / (3.0 * PI);
            let mut sim = Brownian::new(
                Particles::monodisperse(pos, 1.0),
                sbox,
                wca.clone(),
                NoExternal,
                params,
                0,
            )
            .unwrap();
            let mut h = vec![0.0; bins];
            for _ in 0..2500 {
                sim.run(100).unwrap();
                let p = &sim.particles().pos;
                let d = sbox.min_image([p[0][0] - p[1][0], p[0][1] - p[1][1], p[0][2] - p[1][2]]);
                let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if (r_lo..r_hi).contains(&r) {
                    h[((r - r_lo) / dr) as usize] += 1.0;
                }
            }
            h
        })
        .reduce(
            || vec![0.0; bins],
            |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect(),
        );
    let samples = (engines * 2500) as f64;
    // For r < L/2 the minimum-image separation has density 4 pi r^2 exp(-u) / Z with
    // Z = V - int 4 pi r^2 (1 - exp(-u)) dr.
    let expected = |sigma: f64| -> Vec<f64> {
        let u = LennardJones::wca(1.0, sigma);
        let m = 2000;
        let integral = |a: f64, b: f64, f: &dyn Fn(f64) -> f64| -> f64 {
            let h = (b - a) / m as f64;
            (0..m).map(|j| f(a + (j as f64 + 0.5) * h) * h).sum()
        };
        let boltz = |r: f64| (-u.energy(r * r, 0, 0, 1.0, 1.0)).exp();
        let z = l.powi(3) - integral(1e-3, 1.2 * sigma, &|r| 4.0 * PI * r * r * (1.0 - boltz(r)));
        (0..bins)
            .map(|b| {
                let a = r_lo + b as f64 * dr;
                samples * integral(a, a + dr, &|r| 4.0 * PI * r * r * boltz(r)) / z
            })
            .collect()
    };
    // Samples 100 steps apart (rms relative displacement 0.28 per axis) are close to
    // independent; a factor 2 covers the remaining correlation.
    let chi2 = |e: &[f64]| -> f64 {
        hist.iter()
            .zip(e)
            .map(|(o, e)| (o - e).powi(2) / (2.0 * e))
            .sum()
    };
    let dof = bins as f64;
    let limit = dof + 5.0 * (2.0 * dof).sqrt();
    let good = chi2(&expected(1.0));
    assert!(good < limit, "chi2 {good}; observed {hist:?}");
    // sigma off by 5 % is caught.
    let bad = chi2(&expected(1.05));
    assert!(bad > limit, "wrong sigma not caught: chi2 {bad}");
}

fn wca_system(n: usize, phi: f64, dt: f64, seed: u32) -> Brownian<LennardJones, NoExternal> {
    colloidsim_md::bench::wca_periodic(n, phi, dt, seed).unwrap()
}

/// Runs are bitwise identical for 1 and 2 threads, and a restart from a GSD checkpoint
/// continues bitwise identically, with either integrator (Leimkuhler–Matthews draws its kept
/// deviate again at the restart).
#[test]
fn thread_count_and_restart_do_not_change_the_trajectory() {
    let mut last = Vec::new();
    for integrator in [Integrator::Euler, Integrator::Lm] {
        let system = |seed: u32| wca_system(3000, 0.2, 1e-4, seed).with_integrator(integrator);
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut sim = system(7);
                sim.run(700).unwrap(); // includes a re-sort at step 500
                sim.snapshot()
            })
        };
        let one = run(1);
        assert!(one == run(2), "{integrator:?}: 1 and 2 threads differ");
        assert!(one == run(3), "{integrator:?}: 1 and 3 threads differ");

        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("checkpoint.gsd");
        let mut sim = system(7);
        sim.run(120).unwrap();
        let mut w = GsdWriter::create_new(&path).unwrap();
        w.write_checkpoint(sim.step, &sim.sbox, &sim.snapshot(), &sim.list_state(), &[])
            .unwrap();
        drop(w);
        let f = read_frame(&path, None).unwrap();
        assert_eq!(f.step, 120);
        let mut again = Brownian::restart(
            f.particles,
            f.sbox,
            LennardJones::wca(1.0, 1.0),
            NoExternal,
            *sim.params(),
            f.step,
            f.list.as_ref(),
        )
        .unwrap();
        assert_eq!(again.params().integrator, integrator);
        again.run(580).unwrap();
        assert!(again.snapshot() == one, "{integrator:?}: restart differs");
        // A different seed does change it (the comparison can fail).
        let mut other = system(8);
        other.run(700).unwrap();
        assert!(other.snapshot().pos != one.pos);
        last.push(one.pos);
    }
    // The integrators differ (Leimkuhler–Matthews is not Euler under another name).
    assert!(last[0] != last[1]);
}

/// A time step far too large for the WCA core is detected, naming the step and the particle.
#[test]
fn blow_up_names_step_and_particle() {
    let mut sim = wca_system(2000, 0.3, 0.05, 1);
    let err = sim.run(1000).unwrap_err();
    match &err {
        BdError::BlowUp { step, particle, .. } => {
            assert!(*step < 1000 && *particle < 2000);
            let msg = err.to_string();
            assert!(
                msg.contains(&format!("step {step}"))
                    && msg.contains(&format!("particle {particle}"))
            );
            assert!(msg.contains("reduce `dt`"), "{msg}");
        }
        e => panic!("expected a blow-up, got {e}"),
    }
    // The same system at a sensible step runs.
    wca_system(2000, 0.3, 1e-4, 1).run(200).unwrap();
}

/// Pair forces of `pair` on every particle by a brute-force sum over all pairs (minimum image).
fn brute_force_pairs(p: &Particles, sbox: &SimBox, pair: &impl Pair) -> Vec<[f64; 3]> {
    let n = p.len();
    let mut f = vec![[0.0; 3]; n];
    for i in 0..n {
        for j in 0..n {
            if i == j {
                continue;
            }
            let (a, b) = (p.pos[i], p.pos[j]);
            let d = sbox.min_image([a[0] - b[0], a[1] - b[1], a[2] - b[2]]);
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let fr = pair.force_over_r(r2, p.typeid[i], p.typeid[j], p.diameter[i], p.diameter[j]);
            for k in 0..3 {
                f[i][k] += fr * d[k];
            }
        }
    }
    f
}

/// The half neighbour lists with slab buffers give the brute-force forces, for boxes with one,
/// two, three and many cells along an axis and two particle types, after the particles have
/// moved within the skin (lists not fresh) and after rebuilds.
#[test]
fn engine_forces_equal_a_brute_force_sum_over_all_pairs() {
    // Types 0 and 1 with sigma 1 and 1.3; the cross pair has sigma 1.15 and a full LJ cut-off.
    let lj = |sigma: f64, cut: f64| colloidsim_md::LjParams {
        epsilon: 1.0,
        sigma,
        r_cut: cut * sigma,
    };
    let wca = 2f64.powf(1.0 / 6.0);
    let pair = LennardJones::new(2, &[lj(1.0, wca), lj(1.15, 2.5), lj(1.3, wca)]);
    // range = 2.875 + skin 0.3 = 3.175: edges 6.4 (2 cells), 9.6 (3 cells), 30 (9 cells).
    for (l, n) in [
        ([6.4, 9.6, 30.0], 60),
        ([9.6, 6.4, 6.4], 30),
        ([12.0, 12.0, 12.0], 150),
    ] {
        let sbox = SimBox::new(l);
        let pos = random_in_box(n, 1.3, &sbox, 3, 0).unwrap();
        let mut p = Particles::monodisperse(pos, 1.0);
        p.type_names = vec!["A".into(), "B".into()];
        for i in 0..n {
            if i % 3 == 0 {
                p.typeid[i] = 1;
                p.diameter[i] = 1.3;
            }
        }
        let mut params = BdParams::new(1e-4, 5);
        params.viscosity = 1.0 / (3.0 * PI);
        let mut sim = Brownian::new(p, sbox, pair.clone(), NoExternal, params, 0).unwrap();
        for steps in [0, 7, 200] {
            sim.run(steps).unwrap();
            let snap = sim.snapshot();
            let want = brute_force_pairs(&snap, &sbox, &pair);
            let got = sim.forces();
            let scale = want.iter().flatten().fold(1.0f64, |m, x| m.max(x.abs()));
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                for k in 0..3 {
                    assert!(
                        (g[k] - w[k]).abs() <= 1e-12 * scale,
                        "box {l:?}, step {}: particle {i}: engine {g:?}, brute force {w:?}",
                        sim.step
                    );
                }
            }
        }
        assert!(sim.neighbor_builds() >= 2, "the lists were rebuilt");
        // The comparison can fail: a force table missing the cross pair differs.
        let wrong = LennardJones::new(2, &[lj(1.0, wca), lj(1.15, wca), lj(1.3, wca)]);
        let snap = sim.snapshot();
        let bad = brute_force_pairs(&snap, &sbox, &wrong);
        assert!(
            bad.iter()
                .zip(sim.forces())
                .any(|(b, g)| (0..3).any(|k| (b[k] - g[k]).abs() > 1e-6))
        );
    }
}
