//! End-to-end tests of `colloidsim run` with hydrodynamics: droplets with RPY (direct and PSE)
//! restart bitwise after an interrupt or a kill (checked to fail when the checkpoint rounds the
//! positions to single precision), a Lanczos square root that does not converge stops the run
//! through the failure path, naming the step, and bad `[hydrodynamics]` input is refused before
//! anything is written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use common::{assert_same_outputs, files, text};

/// summary.json fields that depend on the session (timing) or on when the neighbour list was
/// rebuilt (a restart rebuilds it).
const VOLATILE: &[&str] = &[
    "wall_seconds",
    "particle_steps_per_second",
    "neighbor_list_builds",
];

/// 150 colloids with RPY in free space, 2 replicas of 200 steps (checkpoints every 20 steps),
/// a trajectory frame of replica 0 every 25 steps and its cross-section.
const DIRECT: &str = r#"
method = "droplet-bd"
seed = 3
replicas = 2
[system]
particles = 150
phi0 = 0.05
[drying]
peclet = 10
duration = 0.8
[run]
dt = 0.004
[observe]
profile = { bins = 10, fractions = [0, 0.5, 1.0] }
trajectory = { every = 25 }
cross_section = { width = 1.0 }
[hydrodynamics]
model = "rpy"
method = "direct"
"#;

/// 100 colloids with RPY by PSE in a box of two droplet diameters, 50 steps.
const PSE: &str = r#"
method = "droplet-bd"
seed = 5
[system]
particles = 100
phi0 = 0.05
[drying]
peclet = 10
duration = 0.2
[run]
dt = 0.004
[observe]
profile = { bins = 8, fractions = [0, 1.0] }
[hydrodynamics]
model = "rpy"
method = "pse"
box_factor = 2.0
"#;

fn run(args: &[&Path], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_colloidsim"));
    c.args(args).arg("--quiet");
    for (k, v) in env {
        c.env(k, v);
    }
    let o = c.output().unwrap();
    eprintln!("{}", text(&o));
    o
}

fn p(s: &str) -> &Path {
    Path::new(s)
}

/// Write `scenario` as NAME.toml in a temporary folder and run it to completion into `NAME`.
fn complete(name: &str, scenario: &str) -> (tempfile::TempDir, PathBuf, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join(format!("{name}.toml"));
    std::fs::write(&sc, scenario).unwrap();
    let a = tmp.path().join(name);
    let o = run(&[p("run"), &sc, p("--out"), &a], &[]);
    assert!(o.status.success());
    (tmp, sc, a)
}

/// Interrupted (as by Ctrl-C) or killed without a checkpoint at each position of `stops`,
/// the run continues with `--restart` to the same files as the uninterrupted run in `a`.
fn restarts_bitwise(tmp: &Path, sc: &Path, a: &Path, stops: &[(&str, &str)]) {
    for (hook, at) in stops {
        let b = tmp.join(format!("b-{hook}-{at}"));
        let o = run(&[p("run"), sc, p("--out"), &b], &[(hook, at)]);
        assert!(!o.status.success());
        assert!(b.join("checkpoint.bin").exists(), "{hook} {at}");
        assert!(!b.join("summary.json").exists());
        let o = run(&[p("run"), sc, p("--restart"), &b], &[]);
        assert!(o.status.success());
        assert_same_outputs(a, &b, VOLATILE);
    }
}

#[test]
fn droplet_with_rpy_restarts_bitwise() {
    let (tmp, sc, a) = complete("direct", DIRECT);
    let names: Vec<String> = files(&a).into_keys().collect();
    for f in [
        "profile_0.00.csv",
        "profile_1.00.csv",
        "profiles.png",
        "trajectory.gsd",
        "cross_section.csv",
        "cross_section.png",
        "summary.json",
    ] {
        assert!(names.iter().any(|n| n == f), "missing {f} in {names:?}");
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["parameters"]["hydrodynamics"]["method"], "direct");
    // In replica 0 (trajectory open), at the start of replica 1, killed within replica 1.
    restarts_bitwise(
        tmp.path(),
        &sc,
        &a,
        &[
            ("COLLOIDSIM_INTERRUPT_AT_STEP", "77"),
            ("COLLOIDSIM_INTERRUPT_AT_STEP", "200"),
            ("COLLOIDSIM_KILL_AT_STEP", "333"),
        ],
    );
    // Another seed gives another run.
    let c = tmp.path().join("c");
    let o = run(&[p("run"), &sc, p("--out"), &c, p("--seed"), p("4")], &[]);
    assert!(o.status.success());
    assert!(files(&c)["profile_1.00.csv"] != files(&a)["profile_1.00.csv"]);
}

#[test]
fn droplet_with_pse_restarts_bitwise() {
    let (tmp, sc, a) = complete("pse", PSE);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["parameters"]["hydrodynamics"]["method"], "pse");
    assert!(summary["parameters"]["pse"]["grid"].as_u64().unwrap() >= 8);
    restarts_bitwise(
        tmp.path(),
        &sc,
        &a,
        &[("COLLOIDSIM_INTERRUPT_AT_STEP", "23")],
    );
}

#[test]
fn a_lanczos_square_root_that_does_not_converge_stops_the_run_naming_the_step() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("lanczos.toml");
    let text_ = DIRECT.replace(
        "method = \"direct\"",
        "method = \"direct\"\ntolerance = 1e-9\nmax_iterations = 3",
    );
    std::fs::write(&sc, text_).unwrap();
    let a = tmp.path().join("a");
    let o = run(&[p("run"), &sc, p("--out"), &a], &[]);
    assert!(!o.status.success());
    let all = text(&o);
    assert!(
        all.contains("step 0") && all.contains("did not converge") && all.contains("3 iterations"),
        "{all}"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["completed"], false);
    let e = summary["error"].as_str().unwrap();
    assert!(
        e.contains("replica 0") && e.contains("step 0") && e.contains("max_iterations"),
        "{e}"
    );
    assert!(!a.join("checkpoint.bin").exists());
}

#[test]
fn bad_hydrodynamics_are_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    for (change, words) in [
        (
            "tolerance = 0.2",
            "hydrodynamics.tolerance: must be a number in (0, 0.1]",
        ),
        (
            "tolerance = 0",
            "hydrodynamics.tolerance: must be a number in (0, 0.1]",
        ),
        (
            "splitting = -1",
            "hydrodynamics.splitting: must be a finite number > 0",
        ),
        ("box_factor = 1.2", "hydrodynamics.box_factor"),
        ("max_iterations = 0", "hydrodynamics.max_iterations"),
    ] {
        let text_ = PSE.replace("box_factor = 2.0", change);
        let sc = tmp.path().join("bad.toml");
        std::fs::write(&sc, text_).unwrap();
        let out = tmp.path().join("never");
        let o = run(&[p("run"), &sc, p("--out"), &out], &[]);
        assert!(!o.status.success());
        assert!(text(&o).contains(words), "{change}: {}", text(&o));
        assert!(!out.exists(), "{change}: the output folder was created");
    }
}
