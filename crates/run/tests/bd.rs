//! The bulk method (`method = "bd"`) validated through the run path, from its outputs
//! (`summary.json`, `msd.csv`), with fixed seeds and tolerances from each run's own block
//! errors:
//!
//! - Hasimoto: one sphere with RPY (PSE) in periodic cubes of L/a = 10 (and 16, `#[ignore]`d):
//!   D/D0 from the MSD against `mu(L)/mu0`. The same sphere free draining (D/D0 = 1) fails the
//!   comparison. Broken on purpose: kT 10 % high in the engine only (the analysis keeping kT)
//!   fails it, see the test.
//! - Dilute sedimentation: K = U / (mu0 F) of a periodic WCA suspension (phi = 0.03) under a
//!   body force against `mu(L)/mu0 - 5 phi' - 8 phi' (mu(L)/mu0 - 1)`; the same suspension free
//!   draining (K = 1) fails it.
//! - Free draining: D/D0 = 1 for dilute spheres with Euler and with Leimkuhler–Matthews.
//!
//! The default tests are sized to a few seconds each; longer, tighter versions are `#[ignore]`d
//! (their numbers are in docs/validation.md and docs/bd.md).

use colloidsim_run::{Control, RunOptions, Scenario};
use serde_json::Value;

/// Run `text` through the run path into a temporary folder; its summary.
fn run(text: &str) -> Value {
    let dir = tempfile::tempdir().unwrap();
    let sc = Scenario::from_toml(text, dir.path()).unwrap();
    let opts = RunOptions {
        out: Some(dir.path().join("run")),
        ..Default::default()
    };
    let r = colloidsim_run::run(&sc, &opts, &Control::default())
        .unwrap_or_else(|e| panic!("{e:#}\n{text}"));
    eprintln!("{}", r.message);
    let msd = std::fs::read_to_string(dir.path().join("run/msd.csv")).unwrap_or_default();
    assert!(msd.is_empty() || msd.starts_with("t,msd"), "{msd}");
    r.summary
}

fn figure(v: &Value, what: &str, value: &str) -> (f64, f64) {
    let f = &v[what];
    match (f[value].as_f64(), f["error"].as_f64()) {
        (Some(x), Some(e)) => (x, e),
        _ => panic!("{what}: no figure: {}", f["why_null"]),
    }
}

/// One sphere in a periodic cube of edge `l` (diameter 1), RPY by PSE at tolerance 1e-3 with
/// splitting `xi`, `time` sampled in 8 blocks of replicas; D from the MSD between lags 2 and 8
/// steps (one sphere has no structure: every lag is a long one).
fn one_sphere(l: f64, xi: f64, time: f64, replicas: usize, model: &str) -> String {
    format!(
        r#"method = "bd"
seed = 11
replicas = {replicas}
[system]
particles = 1
box_length = {l}
[run]
dt = 0.05
time = {time}
[observe.msd]
max_lag = 0.4
points = 8
[hydrodynamics]
model = "{model}"
{}
"#,
        if model == "rpy" {
            format!("splitting = {xi}")
        } else {
            String::new()
        }
    )
}

/// D/D0 of one sphere against Hasimoto within 4 standard errors; the same sphere free draining
/// fails the comparison. Checked to fail: kT 10 % high in the engine alone (`kt: 1.1 * self.kt`
/// in `BulkParams::hydro_bd_params`) gave D/D0 = 0.79 +- 0.01 against 0.7204 (7 sigma).
fn hasimoto_from_the_msd(l: f64, xi: f64, time: f64, replicas: usize) {
    let s = run(&one_sphere(l, xi, time, replicas, "rpy"));
    let (d, e) = figure(&s, "self_diffusion", "D_over_D0");
    let want = s["references"]["hasimoto_mu_over_mu0"].as_f64().unwrap();
    eprintln!(
        "L/a = {}: D/D0 = {d:.5} +- {e:.5}, Hasimoto {want:.5}",
        2.0 * l
    );
    // The run resolves a 10 % error of kT or of the mobility.
    assert!(4.0 * e < 0.1 * want, "too short to test: error {e}");
    // PSE at tolerance 1e-3 adds at most 1e-3 mu0 (docs/hydrodynamics.md).
    assert!(
        (d - want).abs() < 4.0 * e + 1e-3,
        "D/D0 = {d} +- {e} vs {want}"
    );
    let fd = run(&one_sphere(l, xi, time, replicas, "free-draining"));
    let (d, e) = figure(&fd, "self_diffusion", "D_over_D0");
    assert!(
        (d - 1.0).abs() < 4.0 * e,
        "free draining: D/D0 = {d} +- {e}"
    );
    assert!(
        (d - want).abs() > 4.0 * e + 1e-3,
        "free draining passes the Hasimoto check: {d} +- {e}"
    );
}

#[test]
fn one_sphere_diffuses_with_hasimoto_mobility_at_l_10a() {
    hasimoto_from_the_msd(5.0, 2.0, 1000.0, 1);
}

#[test]
#[ignore = "long: about a minute"]
fn one_sphere_diffuses_with_hasimoto_mobility_at_l_10a_and_16a_long() {
    hasimoto_from_the_msd(5.0, 2.0, 4000.0, 1);
    hasimoto_from_the_msd(8.0, 1.0, 4000.0, 1);
}

/// A dilute WCA suspension (`n` spheres at phi = 0.03, body force 5 kT/d along -z) sampled for
/// `time` per replica in 8 blocks, after `equilibrate`.
fn suspension(n: usize, time: f64, replicas: usize, model: &str) -> String {
    let l = (n as f64 * std::f64::consts::PI / 6.0 / 0.03).cbrt();
    // Free draining needs a smaller step for the WCA core (0.005 blew up once in 4 x 80,000
    // steps of 100 spheres; RPY damps the relative motion at contact).
    let dt = if model == "rpy" { 0.005 } else { 0.0025 };
    format!(
        r#"method = "bd"
seed = 5
replicas = {replicas}
[system]
particles = {n}
box_length = {l}
body_force = [0.0, 0.0, -5.0]
[run]
dt = {dt}
time = {time}
equilibrate = 2.0
[hydrodynamics]
model = "{model}"
"#
    )
}

/// K against the dilute formula within 4 standard errors plus an allowance for the O(phi^2)
/// terms the formula leaves out; the same suspension free draining (K = 1) fails it.
fn sedimentation(n: usize, time: f64, replicas: usize) {
    let s = run(&suspension(n, time, replicas, "rpy"));
    let (k, e) = figure(&s, "sedimentation_coefficient", "K");
    let want = s["sedimentation_coefficient"]["dilute_reference"]
        .as_f64()
        .unwrap();
    let mu_l = s["references"]["hasimoto_mu_over_mu0"].as_f64().unwrap();
    eprintln!("N = {n}: K = {k:.4} +- {e:.4}, dilute RPY {want:.4}, mu(L)/mu0 {mu_l:.4}");
    // O(phi^2) at phi = 0.03: 0.01 for a coefficient of 11.
    let allowance = 0.01;
    assert!(
        (k - want).abs() < 4.0 * e + allowance,
        "K = {k} +- {e} vs {want}"
    );
    // The pair term -5 phi is resolved: the self term alone (mu(L)/mu0) is excluded.
    assert!(
        (k - mu_l).abs() > 4.0 * e + allowance,
        "K = {k} +- {e}: no -5 phi"
    );
    let fd = run(&suspension(n, time, replicas, "free-draining"));
    let (k, e) = figure(&fd, "sedimentation_coefficient", "K");
    assert!((k - 1.0).abs() < 4.0 * e, "free draining: K = {k} +- {e}");
    assert!(
        (k - want).abs() > 4.0 * e + allowance,
        "free draining passes the sedimentation check: {k} +- {e}"
    );
}

#[test]
fn dilute_sedimentation_follows_the_pairwise_rpy_law() {
    sedimentation(40, 160.0, 1);
}

#[test]
#[ignore = "long: several minutes"]
fn dilute_sedimentation_follows_the_pairwise_rpy_law_long() {
    sedimentation(100, 400.0, 4);
}

/// 200 free-draining WCA spheres at phi = 0.001 (collisions are rare: D_L = D0 (1 - 2 phi)),
/// 8 blocks of 40 time units (4.2 d^2 / D0), D between lags of 2.5 and 10. (At dt = 0.005 a
/// collision with kT 10 % high blew up: the WCA core needs the smaller step.)
fn dilute_free(integrator: &str) -> String {
    format!(
        r#"method = "bd"
seed = 8
[system]
particles = 200
box_length = 47.1
[run]
dt = 0.0025
time = 320.0
integrator = "{integrator}"
"#
    )
}

#[test]
fn free_draining_spheres_diffuse_with_d0_with_euler_and_lm() {
    for integrator in ["euler", "lm"] {
        let s = run(&dilute_free(integrator));
        let (d, e) = figure(&s, "self_diffusion", "D_over_D0");
        eprintln!("{integrator}: D/D0 = {d:.5} +- {e:.5}");
        assert!(4.0 * e < 0.06, "{integrator}: too short to test: {e}");
        assert!((d - 1.0).abs() < 4.0 * e, "{integrator}: D/D0 = {d} +- {e}");
        // No force: the mean velocity is zero within its error.
        let v = &s["mean_velocity"];
        for k in 0..3 {
            let (u, e) = (
                v["value"][k].as_f64().unwrap(),
                v["error"][k].as_f64().unwrap(),
            );
            assert!(u.abs() < 4.0 * e, "{integrator}: U = {u} +- {e}");
        }
        assert!(s["sedimentation_coefficient"]["K"].is_null());
    }
}

/// A run too short for a figure says so instead of giving one.
#[test]
fn figures_of_runs_too_short_are_null_with_the_reason() {
    let s = run(&suspension(40, 4.0, 1, "rpy"));
    for what in ["sedimentation_coefficient", "self_diffusion"] {
        let f = &s[what];
        assert!(f["error"].is_null(), "{what}: {f}");
        let why = f["why_null"].as_str().unwrap();
        assert!(!why.is_empty());
    }
    assert!(
        s["mean_velocity"]["why_null"]
            .as_str()
            .unwrap()
            .contains("relaxation time")
    );
    assert!(
        s["self_diffusion"]["why_null"]
            .as_str()
            .unwrap()
            .contains("a^2 / D0")
    );
    // One sphere under a body force: its motion about the centre of mass is nil, so no MSD (and
    // no D) but its sedimentation coefficient, 1 free draining.
    let dir = tempfile::tempdir().unwrap();
    let text = "method = \"bd\"\n[system]\nparticles = 1\nbox_length = 6.0\n\
                body_force = [0.0, 3.0, 0.0]\n[run]\ndt = 0.02\ntime = 200.0\n";
    let sc = Scenario::from_toml(text, dir.path()).unwrap();
    let out = dir.path().join("one");
    let opts = RunOptions {
        out: Some(out.clone()),
        ..Default::default()
    };
    let r = colloidsim_run::run(&sc, &opts, &Control::default()).unwrap();
    assert!(!out.join("msd.csv").exists() && !r.files.contains(&"msd.csv".to_string()));
    let why = r.summary["self_diffusion"]["why_null"].as_str().unwrap();
    assert!(why.contains("one sphere under a body force"), "{why}");
    let (k, e) = figure(&r.summary, "sedimentation_coefficient", "K");
    assert!((k - 1.0).abs() < 4.0 * e, "K = {k} +- {e}");
}

/// `system.initial`: a run starts from the last frame of another's trajectory (relative to the
/// scenario's folder); a file of another box or another number of spheres is refused naming the
/// key and the file, before anything is written.
#[test]
fn a_run_starts_from_a_gsd_frame_of_the_same_box() {
    let dir = tempfile::tempdir().unwrap();
    let base = "method = \"bd\"\n[system]\nparticles = 30\nbox_length = 7.0\n[run]\ndt = 0.005\ntime = 0.4\n";
    let first = Scenario::from_toml(
        &format!("{base}[observe.trajectory]\nevery = 10\n"),
        dir.path(),
    )
    .unwrap();
    let opts = |name: &str| RunOptions {
        out: Some(dir.path().join(name)),
        ..Default::default()
    };
    colloidsim_run::run(&first, &opts("first"), &Control::default()).unwrap();
    let start = |text: &str| {
        Scenario::from_toml(
            &text.replace("[run]", "initial = \"first/trajectory.gsd\"\n[run]"),
            dir.path(),
        )
        .unwrap()
    };
    let r = colloidsim_run::run(&start(base), &opts("second"), &Control::default()).unwrap();
    assert_eq!(r.summary["completed"], true);
    for (text, words) in [
        (
            base.replace("box_length = 7.0", "box_length = 7.5"),
            "is not the cube",
        ),
        (
            base.replace("particles = 30", "particles = 31"),
            "holds 30 particles",
        ),
    ] {
        let e =
            colloidsim_run::run(&start(&text), &opts("never"), &Control::default()).unwrap_err();
        let e = format!("{e:#}");
        assert!(
            e.contains("system.initial") && e.contains("trajectory.gsd") && e.contains(words),
            "{e}"
        );
        assert!(!dir.path().join("never").exists());
    }
}

/// Run `text` in `dir/name`; the summary and the trajectory's bytes (empty without one).
fn run_in(dir: &std::path::Path, name: &str, text: &str) -> (Value, Vec<u8>) {
    let sc = Scenario::from_toml(text, dir).unwrap();
    let opts = RunOptions {
        out: Some(dir.join(name)),
        ..Default::default()
    };
    let r = colloidsim_run::run(&sc, &opts, &Control::default())
        .unwrap_or_else(|e| panic!("{e:#}\n{text}"));
    eprintln!("{}", r.message);
    let traj = std::fs::read(dir.join(name).join("trajectory.gsd")).unwrap_or_default();
    (r.summary, traj)
}

/// One species declared in `[system.species]` is the plain run: the same trajectory bytes and
/// the same figures (free draining under a body force, and with RPY).
#[test]
fn one_declared_species_is_the_plain_bulk_run_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    for (i, hydro) in ["", "[hydrodynamics]\nmodel = \"rpy\"\n"]
        .iter()
        .enumerate()
    {
        let plain = format!(
            "method = \"bd\"\nseed = 4\n[system]\nparticles = 30\nbox_length = 7.0\n\
             body_force = [0.0, 0.0, -2.0]\n[run]\ndt = 0.005\ntime = 0.4\n\
             [observe.trajectory]\nevery = 10\n{hydro}"
        );
        let one = plain.replace(
            "[run]",
            "[system.species]\ndiameters = [1.0]\ncounts = [30]\n[run]",
        );
        let (a, ta) = run_in(dir.path(), &format!("plain{i}"), &plain);
        let (b, tb) = run_in(dir.path(), &format!("one{i}"), &one);
        assert!(!ta.is_empty());
        assert_eq!(ta, tb, "{hydro}");
        for k in ["mean_velocity", "self_diffusion", "pressure", "parameters"] {
            assert_eq!(a[k], b[k], "{k}");
        }
        assert!(b.get("species").is_none());
    }
}

/// A dilute free-draining mixture (phi = 0.003, diameters 1 and 1.25) under a body force:
/// each species diffuses with its Stokes D0_s = kT / (3 pi eta d_s) about its own centre of
/// mass and sediments at Stokes' mu_s F_s with F_s = F (d_s / d)^3 (exact in expectation for
/// free spheres; collisions change it by O(phi)), within 4 block errors of 32 blocks; the
/// common D is null with the reason, the trajectory holds the species' types. (With 16 blocks
/// the block error itself scatters by 20 %. Seed 21 is a realization whose z deviates sum about
/// 3 errors low: K_A = 0.978 +- 0.0065 here, 0.978 +- 0.0055 at d_B = 1.5 (the same noise
/// streams); seeds 22 and 23 gave 1.013 +- 0.008 and 1.000 +- 0.007.)
#[test]
fn a_dilute_mixture_diffuses_and_sediments_at_each_species_stokes_values() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"method = "bd"
seed = 22
replicas = 2
[system]
particles = 140
box_length = 30.0
body_force = [0.0, 0.0, -2.0]
[system.species]
diameters = [1.0, 1.25]
counts = [100, 40]
[run]
dt = 0.0025
time = 320.0
[observe]
blocks = 16
[observe.msd]
max_lag = 20.0
[observe.trajectory]
every = 20000
"#;
    let (s, traj) = run_in(dir.path(), "mix", text);
    let species = s["species"].as_array().unwrap();
    assert_eq!(species.len(), 2);
    for (k, sp) in species.iter().enumerate() {
        let d = [1.0, 1.25][k];
        let f = &sp["self_diffusion"];
        let (x, e) = (
            f["D_over_D0"].as_f64().unwrap_or_else(|| panic!("{f}")),
            f["error"].as_f64().unwrap(),
        );
        let d0 = f["D0"].as_f64().unwrap();
        assert!((d0 - 1.0 / (3.0 * std::f64::consts::PI * d)).abs() < 1e-15);
        eprintln!("species {k}: D/D0 = {x:.4} +- {e:.4}");
        assert!(4.0 * e < 0.25, "too short to test: {e}");
        assert!((x - 1.0).abs() < 4.0 * e, "species {k}: D/D0 = {x} +- {e}");
        let v = &sp["velocity"];
        let (k_s, k_e) = (v["K"].as_f64().unwrap(), v["K_error"].as_f64().unwrap());
        let stokes = v["stokes"].as_f64().unwrap();
        assert!((stokes - 2.0 * d * d / (3.0 * std::f64::consts::PI)).abs() < 1e-14);
        eprintln!("species {k}: U / (mu F) = {k_s:.4} +- {k_e:.4}");
        assert!(4.0 * k_e < 0.1, "too short to test: {k_e}");
        assert!(
            (k_s - 1.0).abs() < 4.0 * k_e,
            "species {k}: K = {k_s} +- {k_e}"
        );
    }
    assert!(
        s["self_diffusion"]["why_null"]
            .as_str()
            .unwrap()
            .contains("drift apart")
    );
    let msd = std::fs::read_to_string(dir.path().join("mix/msd.csv")).unwrap();
    assert!(
        msd.starts_with("t,msd,err,msd_A,err_A,msd_B,err_B"),
        "{msd}"
    );
    // The trajectory's frames hold the species: their names, typeids and diameters.
    assert!(!traj.is_empty());
    let f = colloidsim_md::gsd::read_frame(&dir.path().join("mix/trajectory.gsd"), None).unwrap();
    assert_eq!(
        f.particles.type_names,
        vec!["A".to_string(), "B".to_string()]
    );
    assert_eq!(f.particles.typeid.iter().filter(|&&t| t == 1).count(), 40);
    assert_eq!(f.particles.diameter[139], 1.25);
}

fn read_bd(text: &str) -> anyhow::Result<colloidsim_md::brownian::bulk::BulkParams> {
    colloidsim_run::methods::bd::params::read(
        &toml::from_str(text).unwrap(),
        std::path::Path::new("."),
        None,
    )
}

/// Bad species input is refused naming its key: counts that do not sum to the particles,
/// a diameter of zero or below, a size ratio PSE cannot resolve (20 > 16), a box too small
/// for the mixture, a body force that moves the large spheres too far per step.
#[test]
fn bad_species_input_names_the_key() {
    let base = "method = \"bd\"\n[system]\nparticles = 40\nbox_length = 12.0\n\
                [system.species]\ndiameters = [1.0, 2.0]\ncounts = [30, 10]\n\
                [run]\ndt = 0.005\ntime = 4.0\n";
    let p = read_bd(base).unwrap();
    assert_eq!(p.species.counts, vec![30, 10]);
    assert_eq!(p.diameter, 1.0);
    let phi = (30.0 + 80.0) * std::f64::consts::PI / 6.0 / 1728.0;
    assert!((p.phi - phi).abs() < 1e-15);
    let rpy = "[hydrodynamics]\nmodel = \"rpy\"\n";
    for (from, to, extra, key) in [
        ("[30, 10]", "[30, 11]", "", "system.species.counts"),
        ("[1.0, 2.0]", "[1.0, 0.0]", "", "system.species.diameters"),
        ("[1.0, 2.0]", "[1.0, -2.0]", "", "system.species.diameters"),
        ("[1.0, 2.0]", "[0.1, 2.0]", rpy, "system.species.diameters"),
        (
            "box_length = 12.0",
            "box_length = 5.0",
            "",
            "system.box_length",
        ),
    ] {
        let text = base.replace(from, to) + extra;
        let e = read_bd(&text).unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.starts_with(key), "{to}: {msg}");
    }
    // A large-sphere drift too large for the step names the body force.
    let e = read_bd(&base.replace(
        "box_length = 12.0",
        "box_length = 12.0\nbody_force = [0.0, 0.0, -120.0]",
    ))
    .unwrap_err();
    let msg = format!("{e:#}");
    assert!(
        msg.starts_with("system.body_force") && msg.contains("largest"),
        "{msg}"
    );
}

/// Lennard-Jones spheres (cut and shifted at 2.5 sigma) at the supercritical state point
/// T* = 2, rho* = `rho`: `n` spheres, `time` sampled in 10 blocks, Leimkuhler–Matthews at
/// `dt`; `epsilon` is the well depth of the run.
fn lj_fluid(n: usize, rho: f64, epsilon: f64, dt: f64, time: f64) -> String {
    format!(
        r#"method = "bd"
seed = 17
[system]
particles = {n}
box_length = {l}
kT = 2.0
[pair]
kind = "lj"
epsilon = [{epsilon:?}]
cutoff = 2.5
[run]
dt = {dt}
time = {time}
equilibrate = 5.0
integrator = "lm"
[observe]
blocks = 10
"#,
        l = (n as f64 / rho).cbrt()
    )
}

/// The virial pressure of the LJ fluid against the equation of state of Johnson, Zollweg and
/// Gubbins (1993) at T* = 2, rho* = 0.4: the run's pressure plus the mean-field tail of the
/// cut-off within 3 block errors of the EOS (which fits the simulations it was made from to
/// about 1 %). Broken on purpose (the reference taken at epsilon 1.1), it fails.
#[test]
fn the_lj_virial_pressure_follows_the_jzg_equation_of_state() {
    let s = run(&lj_fluid(125, 0.4, 1.0, 0.002, 100.0));
    let p = &s["pressure"];
    let lj = &p["lennard_jones"];
    let (v, e) = (p["value"].as_f64().unwrap(), p["error"].as_f64().unwrap());
    let with_tail = lj["pressure_with_tail"].as_f64().unwrap();
    let jzg = lj["jzg_pressure"].as_f64().unwrap();
    eprintln!(
        "P = {v:.4} +- {e:.4}, with tail {with_tail:.4}, JZG {jzg:.4}, ideal {}",
        p["ideal"]
    );
    assert!(3.0 * e < 0.05 * jzg, "too short to test: {e}");
    assert!(
        (with_tail - jzg).abs() < 3.0 * e,
        "P + tail = {with_tail} +- {e}, JZG {jzg}"
    );
    assert_eq!(
        (
            lj["T_star"].as_f64(),
            lj["rho_star"].as_f64().map(|r| (r * 1e12).round() / 1e12)
        ),
        (Some(2.0), Some(0.4))
    );
    assert!(p["why_null"].is_null() && p["ideal"].as_f64().unwrap() > 0.0);
}

/// `run.tune_skin` refuses what it cannot tune, naming the key.
#[test]
fn skin_tuning_with_hydrodynamics_is_refused_naming_the_key() {
    let text = "method = \"bd\"\n[system]\nparticles = 20\nbox_length = 8.0\n\
                [run]\ndt = 0.001\ntime = 0.1\ntune_skin = true\n[hydrodynamics]\nmodel = \"rpy\"\n";
    let e = format!("{:#}", read_bd(text).unwrap_err());
    assert!(
        e.contains("run.tune_skin") && e.contains("free-draining"),
        "{e}"
    );
}

/// A dilute gas of spheres (d = 1, kT = 1) with the pair interaction `pair` (the lines of a
/// `[pair]` table) at number density `rho`: 300 spheres, Leimkuhler–Matthews at `dt` for `time`
/// in 8 blocks. (The box's slowest density mode relaxes in `L^2 / (4 pi^2 D0)`, 70–150 time
/// units here; with 20 blocks of 20 the block error of the soft spheres' Z came out about
/// half their scatter over seeds, with 8 as large as it.)
fn dilute_gas(pair: &str, rho: f64, dt: f64, time: f64) -> String {
    format!(
        "method = \"bd\"\nseed = 17\n[system]\nparticles = 300\nbox_length = {l}\nkT = 1.0\n\
         [pair]\n{pair}\n[run]\ndt = {dt}\ntime = {time}\nequilibrate = 5.0\n\
         integrator = \"lm\"\n[observe]\nblocks = 8\n",
        l = (300.0 / rho).cbrt()
    )
}

/// The dilute pair fluids of the virial-series checks (BD here, Monte Carlo in
/// tests/hs_mc_pair.rs), spheres of d = 1 at kT = 1: the `[pair]` lines and the number density.
/// Harmonic soft spheres `U = 5 kT (1.2 - r)^2` below r = 1.2 are tabulated into `table` from
/// r = 0.002 (below it the engine continues the first force, which is this force).
pub(crate) fn dilute_pair_fluids(table: &std::path::Path) -> [(String, f64); 4] {
    crate::species::harmonic_table(table, 5.0, 1.2, 0.002, 0.002, 600);
    [
        (
            format!("kind = \"table\"\ntable = \"{}\"", table.display()),
            0.05,
        ),
        (
            "kind = \"yukawa\"\ncharges = [10.0]\nbjerrum_length = 0.1\ndebye_length = 0.5\nrange = 2.0"
                .into(),
            0.02,
        ),
        (
            "kind = \"ao\"\ndepletant_diameter = 0.2\ndepletant_fraction = 0.2".into(),
            0.1,
        ),
        (
            "kind = \"morse\"\ndepth = 0.5\nkappa = 10.0\nh0 = 0.0\nrange = 0.5".into(),
            0.1,
        ),
    ]
}

/// The exact `B2` and `B3` of a one-species interaction (d = 1, kT = 1): Mayer-function
/// quadratures of its energy (`second_virial`, `third_virial`).
pub(crate) fn exact_virials(spec: &colloidsim_particles::PairSpec) -> (f64, f64) {
    use colloidsim_particles::Pair;
    use colloidsim_particles::interaction::{second_virial, third_virial};
    let p = spec.build(&[1.0], 1.0).unwrap();
    let rc = p.r_cut_max();
    let mayer = |r: f64| (-p.energy(r * r, 0, 0, 1.0, 1.0)).exp() - 1.0;
    (
        second_virial(&p, 0, 0, 1.0, 1.0, 1.0, 20_000),
        third_virial(|r| if r == 0.0 { -1.0 } else { mayer(r) }, rc, 3000),
    )
}

/// The virial pressure of dilute gases of a tabulated (harmonic soft spheres), the
/// screened-Coulomb (Yukawa), the Asakura–Oosawa and the Morse interaction
/// ([`dilute_pair_fluids`]) against the virial series `Z = 1 + B2 rho + B3 rho^2`, with the
/// exact `B2` and `B3` of the same interaction ([`exact_virials`]): within 3 block errors. The
/// next term, `B4 rho^3`, is about one error for the Yukawa gas if `B4 / B2^3` is the hard
/// spheres' 0.29, and far below it for the others. Each fails when its interaction is replaced
/// by the bare WCA core (which the measured `Z` is more than 10 errors from), and the Yukawa
/// gas resolves `B3` (its `Z` is more than 4 errors from `1 + B2 rho`). Morse's narrow well
/// (1 / kappa = 0.1 d) needs the smaller step: at dt = 0.002 it read 3 errors high.
#[test]
fn dilute_pair_fluids_follow_the_exact_virial_series() {
    let dir = tempfile::tempdir().unwrap();
    // The interaction whose virials are computed is the one the run reads from the scenario;
    // (dt, time) per fluid.
    let steps = [
        (0.002, 400.0),
        (0.002, 400.0),
        (0.002, 400.0),
        (0.0005, 200.0),
    ];
    let cases = dilute_pair_fluids(&dir.path().join("soft.csv"))
        .into_iter()
        .zip(steps)
        .map(|((pair, rho), (dt, time))| (pair, rho, dt, time));
    for (pair, rho, dt, time) in cases {
        let text = dilute_gas(&pair, rho, dt, time);
        let spec = read_bd(&text).unwrap().pair.expect("a [pair] table");
        let s = run(&text);
        let p = &s["pressure"];
        let ideal = p["ideal"].as_f64().unwrap();
        let (z, err) = (
            p["value"].as_f64().unwrap() / ideal,
            p["error"].as_f64().unwrap() / ideal,
        );
        follows_the_virial_series(&spec, rho, (z, err));
    }
}

/// Assert that `Z = z +- err` measured at number density `rho` with the pair interaction
/// `spec` (one species, d = 1, kT = 1) is within 3 errors of its exact `1 + B2 rho + B3 rho^2`
/// and more than 10 errors from the bare WCA core's; a Yukawa gas more than 4 errors from
/// `1 + B2 rho` (it resolves `B3`).
pub(crate) fn follows_the_virial_series(
    spec: &colloidsim_particles::PairSpec,
    rho: f64,
    (z, err): (f64, f64),
) {
    let (b2, b3) = exact_virials(spec);
    let (b2_wca, b3_wca) = exact_virials(&colloidsim_particles::PairSpec::wca(1.0, 1));
    let series = 1.0 + b2 * rho + b3 * rho * rho;
    let wca = 1.0 + b2_wca * rho + b3_wca * rho * rho;
    eprintln!(
        "{}: rho {rho}: Z = {z:.4} +- {err:.4}; B2 = {b2:.4}, B3 = {b3:.4}: series {series:.4} \
         ({:+.1} err), 1 + B2 rho {:.4}, bare WCA {wca:.4}",
        spec.kind(),
        (z - series) / err,
        1.0 + b2 * rho
    );
    assert!(
        (z - series).abs() < 3.0 * err,
        "{}: Z = {z} +- {err} vs the series {series}",
        spec.kind()
    );
    assert!(
        (z - wca).abs() > 10.0 * err,
        "{}: too short to tell from WCA",
        spec.kind()
    );
    if spec.kind() == "yukawa" {
        assert!((z - 1.0 - b2 * rho).abs() > 4.0 * err, "B3 not resolved");
    }
}
