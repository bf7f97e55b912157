//! End-to-end tests of `colloidsim run` on droplet-bd scenarios: checkpoints and `--restart`.

use std::path::PathBuf;

use crate::common;
use common::{assert_same_outputs, colloidsim as run, files, p, text};

/// summary.json fields that depend on the session (timing) or on when the neighbour list was
/// rebuilt (a restart rebuilds it).
const VOLATILE: &[&str] = &[
    "wall_seconds",
    "particle_steps_per_second",
    "neighbor_list_builds",
];

/// 200 colloids, 3 replicas of 300 steps (checkpoints every 30 steps), a trajectory frame of
/// replica 0 every 20 steps: a second or two.
const TINY: &str = r#"
method = "droplet-bd"
seed = 3
replicas = 3
[system]
particles = 200
phi0 = 0.05
[drying]
peclet = 10
duration = 1.2
[run]
dt = 0.004
[observe]
profile = { bins = 10, fractions = [0, 0.25, 0.5, 0.75, 1.0] }
trajectory = { every = 20 }
"#;

fn setup() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("tiny.toml");
    std::fs::write(&sc, TINY).unwrap();
    let a = tmp.path().join("a");
    let o = run(&[p("run"), &sc, p("--out"), &a], &[]);
    assert!(o.status.success());
    (tmp, sc, a)
}

#[test]
fn interrupted_run_restarts_bitwise() {
    let (tmp, sc, a) = setup();
    let names: Vec<String> = files(&a).into_keys().collect();
    for f in [
        "scenario.toml",
        "profile_0.00.csv",
        "profile_1.00.csv",
        "profiles.png",
        "trajectory.gsd",
        "summary.json",
    ] {
        assert!(names.iter().any(|n| n == f), "missing {f} in {names:?}");
    }
    // A completed run keeps no checkpoint.
    assert!(
        !names.iter().any(|n| n.starts_with("checkpoint")),
        "{names:?}"
    );

    // Interrupted (as by Ctrl-C) in replica 0 (trajectory open), at the start of replica 1,
    // and in the middle of replica 1 (profiles of replica 0 and of part of replica 1 to restore).
    for at in ["123", "300", "450"] {
        let b = tmp.path().join(format!("b{at}"));
        let o = run(
            &[p("run"), &sc, p("--out"), &b],
            &[("COLLOIDSIM_INTERRUPT_AT_STEP", at)],
        );
        assert!(!o.status.success());
        assert!(
            text(&o).contains(&format!("interrupted at step {at}")),
            "{}",
            text(&o)
        );
        assert!(b.join("checkpoint.bin").exists());
        assert!(!b.join("summary.json").exists());
        let o = run(&[p("run"), &sc, p("--restart"), &b], &[]);
        assert!(o.status.success());
        assert_same_outputs(&a, &b, VOLATILE);
    }
}

#[test]
fn killed_run_restarts_from_the_last_periodic_checkpoint() {
    let (tmp, sc, a) = setup();
    // Killed without a checkpoint at step 170 of replica 0: the last checkpoint is at step 150,
    // and trajectory.gsd already holds the frame of step 160, which the restart drops and
    // writes again. Then killed in replica 1.
    for at in ["170", "475"] {
        let c = tmp.path().join(format!("c{at}"));
        let o = run(
            &[p("run"), &sc, p("--out"), &c],
            &[("COLLOIDSIM_KILL_AT_STEP", at)],
        );
        assert!(!o.status.success());
        assert!(c.join("checkpoint.bin").exists());
        let o = run(&[p("run"), &sc, p("--restart"), &c], &[]);
        assert!(o.status.success());
        assert_same_outputs(&a, &c, VOLATILE);
    }
}

#[test]
fn restart_refuses_without_checkpoint_changed_scenario_or_completed_run() {
    let (tmp, sc, a) = setup();
    // A completed run is not overwritten.
    let before = files(&a);
    let o = run(&[p("run"), &sc, p("--restart"), &a], &[]);
    assert!(!o.status.success());
    assert!(text(&o).contains("complete"), "{}", text(&o));
    assert!(files(&a) == before);
    // No folder, or no checkpoint in it.
    let empty = tmp.path().join("empty");
    let o = run(&[p("run"), &sc, p("--restart"), &empty], &[]);
    assert!(!o.status.success() && text(&o).contains("no such folder"));
    std::fs::create_dir(&empty).unwrap();
    let o = run(&[p("run"), &sc, p("--restart"), &empty], &[]);
    assert!(!o.status.success() && text(&o).contains("no checkpoint.bin"));
    // An interrupted run continues only with the scenario (and seed) it started with.
    let b = tmp.path().join("b");
    let o = run(
        &[p("run"), &sc, p("--out"), &b],
        &[("COLLOIDSIM_INTERRUPT_AT_STEP", "400")],
    );
    assert!(!o.status.success());
    let other = tmp.path().join("other.toml");
    std::fs::write(&other, TINY.replace("duration = 1.2", "duration = 1.3")).unwrap();
    let o = run(&[p("run"), &other, p("--restart"), &b], &[]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("differs from the scenario this run started with"),
        "{}",
        text(&o)
    );
    let o = run(
        &[p("run"), &sc, p("--restart"), &b, p("--seed"), p("4")],
        &[],
    );
    assert!(!o.status.success());
    assert!(text(&o).contains("seed = 4 (was 3)"), "{}", text(&o));
    // The refusals left the checkpoint usable.
    let o = run(&[p("run"), &sc, p("--restart"), &b], &[]);
    assert!(o.status.success());
    assert_same_outputs(&a, &b, VOLATILE);
}

/// With `run.integrator = "lm"` an interrupted or killed run continues bitwise too (the
/// Leimkuhler–Matthews deviate kept between steps is drawn again at the restart), and the
/// outputs differ from Euler's.
#[test]
fn leimkuhler_matthews_run_restarts_bitwise() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("lm.toml");
    std::fs::write(
        &sc,
        TINY.replace("dt = 0.004", "dt = 0.004\nintegrator = \"lm\""),
    )
    .unwrap();
    let a = tmp.path().join("a");
    assert!(run(&[p("run"), &sc, p("--out"), &a], &[]).status.success());
    let (_euler, _, e) = setup();
    assert!(files(&a)["profile_1.00.csv"] != files(&e)["profile_1.00.csv"]);
    for (hook, at) in [
        ("COLLOIDSIM_INTERRUPT_AT_STEP", "450"),
        ("COLLOIDSIM_KILL_AT_STEP", "170"),
    ] {
        let b = tmp.path().join(format!("b{at}"));
        let o = run(&[p("run"), &sc, p("--out"), &b], &[(hook, at)]);
        assert!(!o.status.success());
        let o = run(&[p("run"), &sc, p("--restart"), &b], &[]);
        assert!(o.status.success());
        assert_same_outputs(&a, &b, VOLATILE);
    }
}
