//! Brownian dynamics with hydrodynamics: free-draining diffusion through the generic engine,
//! Hasimoto's periodic self-diffusion from a measured MSD, bitwise restarts and thread-count
//! independence, and errors that name the step or the key.

use colloidsim_md::hydro::ewald::hasimoto_rpy;
use colloidsim_md::hydro::{
    AnyMobility, FreeDraining, HydroError, HydroMethod, HydroModel, HydroParams, LanczosError,
    Mobility, Pse, PseParams,
};
use colloidsim_md::{HydroBdError, HydroBdParams, HydroBrownian};
use colloidsim_particles::{NoExternal, NoPair, Particles, SimBox};
use std::f64::consts::PI;

fn lattice(n_side: usize, l: f64) -> Vec<[f64; 3]> {
    let s = l / n_side as f64;
    let mut v = Vec::new();
    for i in 0..n_side {
        for j in 0..n_side {
            for k in 0..n_side {
                v.push([i, j, k].map(|c| (c as f64 + 0.5) * s - 0.5 * l));
            }
        }
    }
    v
}

/// Mean squared displacement per particle after `steps` steps, from unwrapped positions.
fn msd<M: Mobility>(sim: &HydroBrownian<NoPair, NoExternal, M>, start: &[[f64; 3]]) -> f64 {
    let p = sim.particles();
    let mut s = 0.0;
    for ((x, img), x0) in p.pos.iter().zip(&p.image).zip(start) {
        let u = sim.sbox.unwrap(*x, *img);
        s += (0..3).map(|k| (u[k] - x0[k]).powi(2)).sum::<f64>();
    }
    s / p.len() as f64
}

#[test]
fn free_draining_through_the_generic_engine_diffuses_with_stokes_einstein() {
    let (l, eta, kt, dt) = (12.0, 0.8, 1.3, 0.01);
    let pos = lattice(8, l);
    let n = pos.len();
    let mob = FreeDraining::new(&vec![0.5; n], eta).unwrap();
    let mut params = HydroBdParams::new(dt, 3);
    params.kt = kt;
    let mut sim = HydroBrownian::new(
        Particles::monodisperse(pos.clone(), 1.0),
        SimBox::cube(l),
        NoPair,
        NoExternal,
        mob,
        params,
        0,
    )
    .unwrap();
    let steps = 100;
    // Displacements of different steps and particles are independent: sum them all.
    let mut sum = 0.0;
    let mut prev = pos.clone();
    for _ in 0..steps {
        sim.advance().unwrap();
        let p = sim.particles();
        for ((x, img), q) in p.pos.iter().zip(&p.image).zip(prev.iter_mut()) {
            let u = sim.sbox.unwrap(*x, *img);
            sum += (0..3).map(|k| (u[k] - q[k]).powi(2)).sum::<f64>();
            *q = u;
        }
    }
    let d0 = kt / (6.0 * PI * eta * 0.5);
    let got = sum / (6.0 * dt * (steps as usize * n) as f64);
    // 3 * 512 * 100 Gaussian components: relative standard error sqrt(2 / 153600) = 0.36%.
    assert!(
        (got / d0 - 1.0).abs() < 0.02,
        "D = {got} vs Stokes-Einstein {d0}"
    );
    assert!(msd(&sim, &pos) > 0.0);
}

#[test]
fn one_sphere_in_a_periodic_box_diffuses_with_hasimoto_mobility() {
    // L / a = 10: the periodic images slow the sphere by 28%.
    let (a, eta, kt, dt) = (0.5, 1.0, 1.0, 0.05);
    let l = 10.0 * a;
    let mut p = PseParams::paper(a, eta, l);
    p.splitting = 1.0 / a;
    let mob = Pse::new(1, p).unwrap();
    let start = [[0.3, -0.1, 0.2]];
    let mut sim = HydroBrownian::new(
        Particles::monodisperse(start.to_vec(), 2.0 * a),
        SimBox::cube(l),
        NoPair,
        NoExternal,
        mob,
        HydroBdParams::new(dt, 11),
        0,
    )
    .unwrap();
    let steps = 6000;
    let mut sum = 0.0;
    let mut prev = start[0];
    for _ in 0..steps {
        sim.advance().unwrap();
        let q = sim
            .sbox
            .unwrap(sim.particles().pos[0], sim.particles().image[0]);
        sum += (0..3).map(|k| (q[k] - prev[k]).powi(2)).sum::<f64>();
        prev = q;
    }
    // Each step's displacement is Gaussian with variance 2 kT mu(L) dt per axis, independent
    // across steps: relative standard error sqrt(2 / (3 * 6000)) = 1.05%.
    let mu = sum / (6.0 * kt * dt * steps as f64);
    let mu0 = 1.0 / (6.0 * PI * eta * a);
    let want = hasimoto_rpy(a, l);
    assert!(
        (mu / mu0 / want - 1.0).abs() < 0.045,
        "mu/mu0 = {} vs Hasimoto {want}",
        mu / mu0
    );
}

fn droplet(n: usize, hydro: &str) -> (colloidsim_md::DropletParams, HydroParams) {
    let text = format!(
        "method = \"droplet-bd\"\nseed = 4\n[system]\nparticles = {n}\nphi0 = 0.1\n[drying]\npeclet = 5\n"
    );
    let p = droplet_params(&text);
    // The same droplet with `[hydrodynamics]`: its resolved hydrodynamics.
    let with = droplet_params(&format!("{text}[hydrodynamics]\n{hydro}\n"));
    (p, with.hydrodynamics.unwrap())
}

#[test]
fn droplet_with_rpy_restarts_bitwise_and_does_not_depend_on_threads() {
    for hydro in [
        "model = \"rpy\"\nmethod = \"direct\"",
        "model = \"rpy\"\nmethod = \"pse\"\nbox_factor = 2.0",
    ] {
        let (p, h) = droplet(120, hydro);
        let run = |threads: usize, split: bool| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let mut sim = p.build_hydro_replica(1, &h).unwrap();
                    if split {
                        sim.run(12).unwrap();
                        // A checkpoint: the particles (positions and images) and the step.
                        let saved = sim.particles().clone();
                        let step = sim.step;
                        let mut again = p.build_hydro_replica(1, &h).unwrap();
                        again = HydroBrownian::new(
                            saved,
                            again.sbox,
                            again.pair.clone(),
                            again.external,
                            p.build_hydro_replica(1, &h).unwrap().into_mobility(),
                            *again.params(),
                            step,
                        )
                        .unwrap();
                        again.run(13).unwrap();
                        again.particles().clone()
                    } else {
                        sim.run(25).unwrap();
                        sim.particles().clone()
                    }
                })
        };
        let whole = run(1, false);
        assert_eq!(whole, run(2, false), "{hydro}: thread count");
        assert_eq!(whole, run(2, true), "{hydro}: restart");
        assert_ne!(
            whole.pos,
            droplet(120, hydro)
                .0
                .build_hydro_replica(1, &h)
                .unwrap()
                .particles()
                .pos
        );
    }
}

#[test]
fn a_lanczos_failure_stops_the_run_naming_the_step() {
    let (p, mut h) = droplet(
        100,
        "model = \"rpy\"\nmethod = \"direct\"\ntolerance = 1e-9",
    );
    h.max_iterations = 2;
    let mut sim = p.build_hydro_replica(0, &h).unwrap();
    sim.step = 7;
    let e = sim.run(1).unwrap_err();
    match &e {
        HydroBdError::Hydro(HydroError::Lanczos {
            step: 7,
            source: LanczosError::NotConverged { iterations: 2, .. },
        }) => {}
        other => panic!("{other}"),
    }
    let s = e.to_string();
    assert!(s.contains("step 7") && s.contains("2 iterations"), "{s}");
}

#[test]
fn a_box_too_small_for_the_droplet_is_refused_naming_the_key() {
    // The run layer refuses it naming the key, with the least value.
    let text = "method = \"droplet-bd\"\nseed = 4\n[system]\nparticles = 100\nphi0 = 0.1\n\
                [drying]\npeclet = 5\n[hydrodynamics]\nmodel = \"rpy\"\nmethod = \"pse\"\nbox_factor = 1.2\n";
    let e = colloidsim_run::methods::droplet_bd::params::read(
        &toml::from_str(text).unwrap(),
        std::path::Path::new("."),
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("hydrodynamics.box_factor") && e.contains("at least"),
        "{e}"
    );
    // The engine refuses it too, naming its own parameter.
    let (p, mut h) = droplet(100, "model = \"rpy\"\nmethod = \"pse\"\nbox_factor = 2.0");
    h.box_factor = 1.2;
    let e = match p.build_hydro_replica(0, &h) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a box of 1.2 droplet diameters was accepted"),
    };
    assert!(e.starts_with("box_factor") && e.contains("at least"), "{e}");
    h.model = HydroModel::FreeDraining;
    h.method = None;
    let sim = p.build_hydro_replica(0, &h).unwrap();
    assert!(matches!(sim.mobility(), AnyMobility::FreeDraining(_)));
    h.model = HydroModel::Rpy;
    h.method = Some(HydroMethod::Direct);
    assert!(matches!(
        p.build_hydro_replica(0, &h).unwrap().mobility(),
        AnyMobility::Direct(_)
    ));
}

#[test]
fn dilute_sedimentation_follows_k_1_minus_5_phi() {
    // The mean velocity of a periodic suspension under a uniform body force F, relative to
    // mu0 F: with pairwise RPY and hard-sphere exclusion, K = mu(L)/mu0 - 5 phi (N - 1)/N
    // + O(phi a / L, phi^2): the self term with its periodic images (Hasimoto) and the excluded overlap
    // region int_{r<2a} n (A + B/3) d^3r = 5 phi (the rest of the pair sum cancels against
    // the zero-mean-flow backflow). The paper's value K = 1 - 5 phi is the N -> infinity limit.
    use colloidsim_particles::init::random_in_box;
    let (a, eta, phi, n) = (0.5, 1.0, 0.02, 2000);
    let l = (n as f64 * PI / 6.0 / phi).cbrt();
    let mu0 = 1.0 / (6.0 * PI * eta * a);
    // Inside the excluded sphere the periodic tensor is the free one plus the images'
    // (mu(L) - mu0) I to leading order, so the excluded region also removes
    // n (4 pi / 3) (2a)^3 (mu(L) - mu0) = 8 phi (mu(L) - mu0).
    let phi_n = phi * (n - 1) as f64 / n as f64;
    let images = hasimoto_rpy(a, l) - 1.0;
    let want = hasimoto_rpy(a, l) - 5.0 * phi_n - 8.0 * phi_n * images;
    let mut ks = Vec::new();
    for seed in 1..=40 {
        let pos = random_in_box(n, 2.0 * a, &SimBox::cube(l), seed, 0).unwrap();
        let mut m = Pse::new(n, PseParams::paper(a, eta, l)).unwrap();
        m.set_positions(&pos).unwrap();
        let f = vec![[0.0, 0.0, 1.0]; n];
        let mut u = vec![[0.0; 3]; n];
        m.apply(&f, &mut u);
        ks.push(u.iter().map(|v| v[2]).sum::<f64>() / (n as f64 * mu0));
    }
    let mean = ks.iter().sum::<f64>() / ks.len() as f64;
    let m = ks.len() as f64;
    let sd = (ks.iter().map(|k| (k - mean).powi(2)).sum::<f64>() / (m - 1.0)).sqrt();
    let se = sd / m.sqrt();
    eprintln!("K = {mean:.5} +- {se:.5} over {m} configurations; mu(L)/mu0 - 5 phi = {want:.5}");
    // The mean velocity of one random configuration scatters by about 0.02 (long-wavelength
    // density fluctuations): 40 configurations give a standard error of about 0.003. Allow 3.5
    // standard errors plus 0.004 for the O(phi^2) terms; Batchelor's -6.55 phi would be lower by
    // 0.031, free draining (no -5 phi) higher by 0.1.
    assert!(
        (mean - want).abs() < 3.5 * se + 0.004,
        "K = {mean} +- {se} vs {want}"
    );
}

/// A `droplet-bd` scenario read by the run layer (its keys through their declarations).
fn droplet_params(text: &str) -> colloidsim_md::DropletParams {
    colloidsim_run::methods::droplet_bd::params::read(
        &toml::from_str(text).unwrap(),
        std::path::Path::new("."),
        None,
    )
    .unwrap()
}
