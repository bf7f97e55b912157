//! The drying droplet: conservation and confinement, bad input.

use colloidsim_md::BdError;
use colloidsim_particles::External;

fn scenario(extra_run: &str) -> String {
    format!(
        r#"
method = "droplet-bd"
seed = 5
[system]
particles = 400
phi0 = 0.1
[drying]
peclet = 10
final_volume_fraction = 0.45
[run]
{extra_run}
"#
    )
}

/// N is constant and no particle gets beyond the interface's soft range: beyond
/// `s = range` the potential is linear with slope `k range`, so an excursion of 10 kT / (k range)
/// further has Boltzmann weight e^-10 per sample. The bound holds while the suspension is
/// dilute (here dried to phi = 0.3 with k = 100 kT / d^2); at high compression the osmotic
/// pressure of the packing pushes the outer layer further into the soft interface (see
/// docs/droplet.md), which this bound does not cover.
#[test]
fn drying_keeps_every_particle_inside_the_interface_range() {
    let text = scenario("")
        .replace(
            "final_volume_fraction = 0.45",
            "final_volume_fraction = 0.3",
        )
        .replace("[run]", "[interface]\nstiffness = 100.0\n[run]");
    let p = droplet_params(&text);
    let mut sim = p.build_replica(0).unwrap();
    let slack = 10.0 * p.kt / (p.stiffness * p.range);
    let mut worst: f64 = f64::NEG_INFINITY;
    let mut in_wall = 0usize;
    let mut done = 0;
    while done < p.steps {
        let k = 50.min(p.steps - done);
        sim.run(k).unwrap();
        done += k;
        let t = sim.time();
        let wall = p.radius_at(t) + p.offset;
        let snap = sim.snapshot();
        assert_eq!(snap.len(), p.particles);
        for x in &snap.pos {
            let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
            worst = worst.max(r - wall);
            if r > wall {
                in_wall += 1;
            }
        }
    }
    assert!(
        worst < p.range + slack,
        "a particle reached s = {worst} beyond the wall (range {}, slack {slack})",
        p.range
    );
    // The check is not vacuous: the drying front does push particles into the interface.
    assert!(
        in_wall > 0 && worst > 0.0,
        "nobody ever touched the interface"
    );
    // The end state is at the requested mean volume fraction.
    let r_end = p.radius_at(sim.time());
    assert!(r_end <= p.r_end + 1e-9);
    // The interface energy is finite everywhere and zero inside.
    assert_eq!(p.interface().energy([0.0; 3], sim.time()), 0.0);
}

#[test]
fn too_large_a_time_step_is_reported_with_step_and_particle() {
    // A slow drying (enough steps of dt = 0.05 to be accepted) of a dense droplet, whose WCA
    // cores a step of 0.05 d^2/D0 cannot resolve.
    let text = scenario("dt = 0.05")
        .replace("phi0 = 0.1", "phi0 = 0.3")
        .replace("peclet = 10", "peclet = 0.1");
    let p = droplet_params(&text);
    let mut sim = p.build_replica(0).unwrap();
    match sim.run(p.steps) {
        // The engine names its parameter (`dt`); the run layer names the key.
        Err(e @ BdError::BlowUp { .. }) => assert!(e.to_string().contains("`dt`")),
        other => panic!("expected a blow-up, got {other:?}"),
    }
    // A drying too fast for the step is refused before it starts, naming the key.
    let e = droplet_error(&scenario("dt = 0.5"));
    assert_eq!(e.key, "drying.peclet", "{e}");
}

#[test]
fn replicas_differ_and_initial_configuration_is_inside() {
    let p = droplet_params(&scenario(""));
    let a = p.build_replica(0).unwrap().snapshot();
    let b = p.build_replica(1).unwrap().snapshot();
    assert!(a.pos != b.pos);
    let wall = p.r0 + p.offset;
    assert!(
        a.pos
            .iter()
            .all(|x| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() <= wall + 1e-12)
    );
    // An unreadable initial file is a clear error naming the engine's input (the run layer
    // names the key, system.initial).
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("x.gsd");
    std::fs::write(&bad, "not gsd").unwrap();
    let text = scenario("").replace(
        "phi0 = 0.1",
        &format!("phi0 = 0.1\ninitial = \"{}\"", bad.display()),
    );
    let p = droplet_params(&text);
    let e = p
        .build_replica(0)
        .err()
        .expect("unreadable GSD accepted")
        .to_string();
    assert!(e.starts_with("initial: ") && e.contains("x.gsd"), "{e}");
}

#[test]
fn an_interface_too_soft_to_hold_the_colloids_is_refused() {
    // 20 kT are reached 20.25 d beyond the wall at k = 2 kT/d^2 (range d/2), more than R0.
    let soft = scenario("").replace("[run]", "[interface]\nstiffness = 2.0\n[run]");
    let e = droplet_error(&soft);
    assert_eq!(e.key, "interface.stiffness", "{e}");
    assert!(e.to_string().contains("does not hold"), "{e}");
    // So stiff that one step overshoots its well (D0 k dt / kT >= 1): refused too.
    let stiff = scenario("dt = 1e-3").replace("[run]", "[interface]\nstiffness = 1e4\n[run]");
    let e = droplet_error(&stiff);
    assert_eq!(e.key, "interface.stiffness", "{e}");
    assert!(e.to_string().contains("overshoots"), "{e}");
    // The default (50 kT/d^2) holds them within about a diameter.
    droplet_params(&scenario(""));
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

/// The error naming a key that a `droplet-bd` scenario is refused with.
fn droplet_error(text: &str) -> colloidsim_core::ParamError {
    colloidsim_run::methods::droplet_bd::params::read(
        &toml::from_str(text).unwrap(),
        std::path::Path::new("."),
        None,
    )
    .unwrap_err()
    .downcast()
    .unwrap()
}

/// The warnings of `text` run through the run path (droplets dried to phi = 0.5).
fn run_warnings(text: &str) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    let sc = colloidsim_run::Scenario::from_toml(text, dir.path()).unwrap();
    let opts = colloidsim_run::RunOptions {
        out: Some(dir.path().join("run")),
        ..Default::default()
    };
    let r = colloidsim_run::run(&sc, &opts, &colloidsim_run::Control::default()).unwrap();
    r.summary["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap().to_string())
        .collect()
}

#[test]
fn a_droplet_whose_interface_left_colloids_behind_says_so() {
    // 100 spheres dried to phi = 0.5 at Pe = 300 in a 20 kT/d^2 interface: the interface
    // outruns them and most end beyond R.
    let fast = |pe: f64, k: f64| {
        format!(
            "method = \"droplet-bd\"\nseed = 5\n[system]\nparticles = 100\nphi0 = 0.1\n\
             [drying]\npeclet = {pe}\nfinal_volume_fraction = 0.5\n\
             [interface]\nstiffness = {k}\n"
        )
    };
    let w = run_warnings(&fast(300.0, 20.0));
    assert!(
        w.iter()
            .any(|w| w.contains("beyond R at the end") && w.contains("interface.stiffness")),
        "{w:?}"
    );
    // Dried slowly in a stiff interface the droplet compacts: no such warning.
    let w = run_warnings(&fast(3.0, 100.0));
    assert!(!w.iter().any(|w| w.contains("beyond R")), "{w:?}");
}

/// `interface.hard`: no centre ever ends a step beyond its species' wall
/// `R(t) + offset - (d - d_min) / 2`, free draining and with RPY, while the drying front keeps
/// pressing the outer spheres against it (not vacuous: some centres end within 0.05 d of their
/// wall).
#[test]
fn a_hard_interface_keeps_every_centre_inside_its_wall() {
    for (particles, counts, hydro) in [
        (400, "[360, 40]", ""),
        (
            90,
            "[80, 10]",
            "[hydrodynamics]\nmodel = \"rpy\"\nmethod = \"direct\"\n",
        ),
    ] {
        let text = format!(
            "method = \"droplet-bd\"\nseed = 3\n[system]\nparticles = {particles}\nphi0 = 0.1\n\
             [system.species]\ndiameters = [1.0, 2.0]\ncounts = {counts}\n\
             [drying]\npeclet = 30\nfinal_volume_fraction = 0.35\n[interface]\nhard = true\n{hydro}"
        );
        let p = droplet_params(&text);
        assert!(p.hard_interface && p.stiffness == 0.0);
        let check = |t: f64, pos: &[[f64; 3]], d: &[f64], closest: &mut f64| {
            for (x, &di) in pos.iter().zip(d) {
                let wall = p.radius_at(t) + p.offset - 0.5 * (di - p.diameter);
                let s = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() - wall;
                assert!(
                    s <= 1e-12,
                    "a centre of diameter {di} ended {s} beyond its wall at t = {t}"
                );
                *closest = closest.max(s);
            }
        };
        let mut closest = f64::NEG_INFINITY;
        let (mut done, every) = (0, 20);
        if hydro.is_empty() {
            let mut sim = p.build_replica(0).unwrap();
            while done < p.steps {
                let k = every.min(p.steps - done);
                sim.run(k).unwrap();
                done += k;
                let s = sim.snapshot();
                check(sim.time(), &s.pos, &s.diameter, &mut closest);
            }
        } else {
            let h = p.hydrodynamics.clone().unwrap();
            let mut sim = p.build_hydro_replica(0, &h).unwrap();
            let steps = p.steps.min(3000);
            while done < steps {
                let k = every.min(steps - done);
                sim.run(k).unwrap();
                done += k;
                let s = sim.particles();
                check(sim.time(), &s.pos, &s.diameter, &mut closest);
            }
        }
        assert!(
            closest > -0.05,
            "{hydro}: no centre came near its wall ({closest})"
        );
    }
}

/// A hard wall samples the uniform density of an ideal particle in the ball of radius
/// `w = R0 + offset`: one sphere (no pair forces) in a static droplet, `<r^2> = 3 w^2 / 5`,
/// within four standard errors of the mean over independent replicas. Without the reflection
/// the sphere leaves (no interface force acts on it) and `<r^2>` grows without bound.
#[test]
fn a_hard_wall_samples_the_uniform_density_of_an_ideal_sphere() {
    let p = droplet_params(
        "method = \"droplet-bd\"\nseed = 9\n[system]\nparticles = 1\nradius = 2.5\n\
         [drying]\npeclet = 0\nduration = 1.0\n[interface]\nhard = true\n",
    );
    let w = p.r0 + p.offset;
    // 8 replicas of 60 relaxation times w^2 / (pi^2 D0) each, sampled every 50 steps.
    let (replicas, steps, every) = (8, 200_000u64, 50u64);
    let means: Vec<f64> = (0..replicas)
        .map(|r| {
            let mut sim = p.build_replica(r).unwrap();
            let mut sum = 0.0;
            for _ in 0..steps / every {
                sim.run(every).unwrap();
                let x = sim.snapshot().pos[0];
                let r2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
                assert!(
                    r2 <= w * w * (1.0 + 1e-12),
                    "the sphere left the droplet: r^2 = {r2}"
                );
                sum += r2 / (w * w);
            }
            sum / (steps / every) as f64
        })
        .collect();
    let n = replicas as f64;
    let mean = means.iter().sum::<f64>() / n;
    let se = (means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
    assert!(se < 0.02, "too few samples to test: standard error {se}");
    assert!(
        (mean - 0.6).abs() < 4.0 * se,
        "<r^2> / w^2 = {mean} +- {se}, uniform density gives 3/5"
    );
}

/// A hard interface has no spring: its stiffness or range is refused naming the key.
#[test]
fn a_hard_interface_with_a_spring_is_refused() {
    for key in ["stiffness = 100.0", "range = 0.5"] {
        let e = droplet_error(
            &scenario("").replace("[run]", &format!("[interface]\nhard = true\n{key}\n[run]")),
        );
        assert_eq!(
            e.key,
            format!("interface.{}", key.split(' ').next().unwrap()),
            "{e}"
        );
        assert!(e.to_string().contains("no spring"), "{e}");
    }
}
