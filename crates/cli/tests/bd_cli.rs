//! End-to-end tests of `colloidsim run` with the bulk method (`method = "bd"`): runs with RPY
//! (PSE) and free draining (Leimkuhler–Matthews) restart bitwise after an interrupt or a kill
//! and give the same files on 1 and 2 threads; a Lanczos square root that does not converge
//! and a time step too large for the WCA core stop the run naming the step; bad input is refused
//! before anything is written, naming the key.

use std::path::Path;

use crate::common;
use common::{assert_same_outputs, colloidsim as run, complete, files, p, restarts_bitwise, text};

/// summary.json fields that depend on the session (timing, threads) or on when the neighbour
/// list was rebuilt (a restart rebuilds it).
const VOLATILE: &[&str] = &[
    "wall_seconds",
    "particle_steps_per_second",
    "neighbor_list_builds",
    "threads",
];

/// 20 spheres with RPY under a body force, 2 replicas of 210 steps (10 equilibration, 8 blocks
/// of 25; checkpoints every 21 steps), MSD and a trajectory frame of replica 0 every 25 steps.
const RPY: &str = r#"
method = "bd"
seed = 3
replicas = 2
[system]
particles = 20
box_length = 8.0
body_force = [1.0, 0.0, -2.0]
[run]
dt = 0.01
time = 2.0
equilibrate = 0.1
[observe.trajectory]
every = 25
[hydrodynamics]
model = "rpy"
"#;

/// 60 free-draining spheres with Leimkuhler–Matthews, 400 steps.
const LM: &str = r#"
method = "bd"
seed = 4
[system]
particles = 60
box_length = 7.0
[run]
dt = 0.005
time = 2.0
integrator = "lm"
[observe.trajectory]
every = 40
"#;

/// Interrupted or killed at each of `stops`, the run continues with `--restart` to the same
/// files as the uninterrupted run in `a`; and the run on one thread gives them too.
fn restarts_and_threads(tmp: &Path, sc: &Path, a: &Path, stops: &[(&str, &str)]) {
    restarts_bitwise(tmp, sc, a, stops, VOLATILE);
    let one = tmp.join("one-thread");
    let o = run(
        &[p("run"), sc, p("--out"), &one, p("--threads"), p("1")],
        &[],
    );
    assert!(o.status.success());
    assert_same_outputs(a, &one, VOLATILE);
}

#[test]
fn bulk_rpy_restarts_bitwise_and_does_not_depend_on_threads() {
    let (tmp, sc, a) = complete("rpy", RPY);
    let names: Vec<String> = files(&a).into_keys().collect();
    for f in ["msd.csv", "msd.png", "trajectory.gsd", "summary.json"] {
        assert!(names.iter().any(|n| n == f), "missing {f} in {names:?}");
    }
    assert!(
        !names.iter().any(|n| n.starts_with("checkpoint")),
        "{names:?}"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["parameters"]["hydrodynamics"]["method"], "pse");
    assert_eq!(summary["blocks"], 16);
    let msd = std::fs::read_to_string(a.join("msd.csv")).unwrap();
    assert!(msd.starts_with("t,msd,err\n"), "{msd}");
    // In replica 0 (mid-block, trajectory open), between the replicas, killed in replica 1.
    restarts_and_threads(
        tmp.path(),
        &sc,
        &a,
        &[
            ("COLLOIDSIM_INTERRUPT_AT_STEP", "77"),
            ("COLLOIDSIM_INTERRUPT_AT_STEP", "210"),
            ("COLLOIDSIM_KILL_AT_STEP", "333"),
        ],
    );
    // Another seed gives another run.
    let c = tmp.path().join("c");
    let o = run(&[p("run"), &sc, p("--out"), &c, p("--seed"), p("4")], &[]);
    assert!(o.status.success());
    assert!(files(&c)["msd.csv"] != files(&a)["msd.csv"]);
}

#[test]
fn bulk_free_draining_lm_restarts_bitwise_and_does_not_depend_on_threads() {
    let (tmp, sc, a) = complete("lm", LM);
    restarts_and_threads(
        tmp.path(),
        &sc,
        &a,
        &[
            ("COLLOIDSIM_INTERRUPT_AT_STEP", "123"),
            ("COLLOIDSIM_KILL_AT_STEP", "301"),
        ],
    );
}

/// A run that cannot go on stops through the failure path: `summary.json` says so and names
/// the replica and step, no checkpoint is left.
fn fails_naming_the_step(scenario: &str, words: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("fail.toml");
    std::fs::write(&sc, scenario).unwrap();
    let a = tmp.path().join("a");
    let o = run(&[p("run"), &sc, p("--out"), &a], &[]);
    assert!(!o.status.success());
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["completed"], false);
    let e = summary["error"].as_str().unwrap();
    for w in words {
        assert!(e.contains(w), "{w}: {e}");
    }
    assert!(!a.join("checkpoint.bin").exists());
}

#[test]
fn lanczos_failures_and_blow_ups_stop_the_run_naming_the_step() {
    fails_naming_the_step(
        &RPY.replace("model = \"rpy\"", "model = \"rpy\"\nmax_iterations = 1"),
        &["replica 0", "step 0", "did not converge", "max_iterations"],
    );
    // Spheres at phi = 0.25 with a time step far too large for the WCA core.
    fails_naming_the_step(
        "method = \"bd\"\n[system]\nparticles = 500\nbox_length = 10.2\n[run]\ndt = 0.2\ntime = 8.0\n",
        &["replica 0", "blow-up at step", "reduce run.dt"],
    );
}

#[test]
fn bad_input_is_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    for (from, to, words) in [
        (
            "box_length = 8.0",
            "box_length = 2.5",
            "system.box_length: 20 spheres of diameter 1 in a cube of edge 2.5 give phi = 0.6702",
        ),
        (
            "particles = 20\nbox_length = 8.0",
            "particles = 1\nbox_length = 3.0",
            "system.box_length: an edge of 3 is too small for the neighbour range",
        ),
        (
            "[1.0, 0.0, -2.0]",
            "[1.0, 0.0, -2000.0]",
            "system.body_force: a force of magnitude",
        ),
        (
            "[1.0, 0.0, -2.0]",
            "[1.0, nan, -2.0]",
            "system.body_force: must be 3 numbers",
        ),
        (
            "[1.0, 0.0, -2.0]",
            "[1.0, -2.0]",
            "system.body_force: must be 3 numbers",
        ),
        (
            "model = \"rpy\"",
            "model = \"rpy\"\nmethod = \"direct\"",
            "hydrodynamics.method: \"direct\" is RPY in an unbounded fluid",
        ),
        (
            "model = \"rpy\"",
            "model = \"rpy\"\nbox_factor = 2.0",
            "hydrodynamics.box_factor: applies to droplet-bd only",
        ),
        (
            "model = \"rpy\"",
            "model = \"rpy\"\nsplitting = 0.3",
            "hydrodynamics.splitting",
        ),
        (
            "model = \"rpy\"",
            "model = \"rpy\"\ntolerance = 0.2",
            "hydrodynamics.tolerance: must be a number in (0, 0.01]",
        ),
        (
            "equilibrate = 0.1",
            "equilibrate = 0.1\nintegrator = \"lm\"",
            "run.integrator",
        ),
        ("time = 2.0", "time = 0.05", "run.time"),
        ("particles = 20", "particles = 0", "system.particles"),
        ("seed = 3", "seed = 3\nspeed = 1", "speed: unknown key"),
    ] {
        assert!(RPY.contains(from), "{from}");
        let sc = tmp.path().join("bad.toml");
        std::fs::write(&sc, RPY.replace(from, to)).unwrap();
        let out = tmp.path().join("never");
        let o = run(&[p("run"), &sc, p("--out"), &out], &[]);
        assert!(!o.status.success());
        assert!(text(&o).contains(words), "{to}: {}", text(&o));
        assert!(!out.exists(), "{to}: the output folder was created");
    }
}

/// A mixture (diameters 1 and 1.5) under a body force, with RPY (PSE for unequal radii) and
/// free draining: interrupted and killed, it restarts to the same files (each sphere keeps its
/// species' diameter), and on one thread too.
#[test]
fn bulk_mixtures_restart_bitwise_with_their_diameters() {
    let species = "[system.species]\ndiameters = [1.0, 1.5]\ncounts = [14, 6]\n[run]";
    let rpy = RPY.replace("[run]", species);
    let (tmp, sc, a) = complete("mix-rpy", &rpy);
    restarts_and_threads(
        tmp.path(),
        &sc,
        &a,
        &[("COLLOIDSIM_INTERRUPT_AT_STEP", "77")],
    );
    let free = RPY
        .replace("[run]", species)
        .replace("[hydrodynamics]\nmodel = \"rpy\"\n", "");
    let (tmp, sc, a) = complete("mix-free", &free);
    restarts_and_threads(
        tmp.path(),
        &sc,
        &a,
        &[
            ("COLLOIDSIM_INTERRUPT_AT_STEP", "123"),
            ("COLLOIDSIM_KILL_AT_STEP", "301"),
        ],
    );
}
