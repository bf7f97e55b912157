//! What a run does with the files of its folder: `--force` removes only the files an earlier
//! colloidsim run recorded as its own (its summary.json, or the manifest.json of a run that
//! did not finish) and never the scenario it reads; a restart puts back a deleted or edited
//! scenario.toml (keeping the edited text).

use std::path::Path;
use std::process::{Command, Output};

use crate::common;
use common::text;

/// A small hard-sphere Monte Carlo run (a fraction of a second) with a trajectory.
const MC: &str = r#"# my scenario, with my comments
method = "hs-mc"
seed = 3
[system]
geometry = "hard-wall"
particles = 50
radius = 4.0
[mc]
warmup_sweeps = 100
sweeps = 400
sample_every = 5
blocks = 4
[output]
trajectory_every = 25
"#;

/// The same without a trajectory.
fn no_trajectory() -> String {
    MC.replace("trajectory_every = 25", "trajectory_every = 0")
}

fn run(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_colloidsim"));
    c.current_dir(dir).args(args).arg("--quiet");
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().unwrap()
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The reproduction of issue 42: the scenario given lies in the output folder as
/// scenario.toml and `--set` changes it: refused, naming it, and the file is left as it was
/// (before, --force deleted it and wrote the as-run copy in its place). Unchanged (the as-run
/// copy is the file, byte for byte) the run goes on and leaves it, and so does a --force rerun.
#[test]
fn force_never_touches_the_scenario_it_reads() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir(d.join("inout")).unwrap();
    std::fs::write(d.join("inout/scenario.toml"), MC).unwrap();
    let args = [
        "run",
        "inout/scenario.toml",
        "--out",
        "inout",
        "--force",
        "--set",
        "seed=9",
    ];
    let o = run(d, &args, &[]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("inout/scenario.toml is the scenario this run reads") && t.contains("--out"),
        "{t}"
    );
    assert_eq!(
        std::fs::read_to_string(d.join("inout/scenario.toml")).unwrap(),
        MC
    );
    assert_eq!(names(&d.join("inout")), ["scenario.toml"]);
    for _ in 0..2 {
        let o = run(d, &args[..5], &[]);
        assert!(o.status.success(), "{}", text(&o));
        assert_eq!(
            std::fs::read_to_string(d.join("inout/scenario.toml")).unwrap(),
            MC
        );
        assert!(d.join("inout/summary.json").exists());
    }
}

/// `--force` over a finished run: its files (summary.json lists them) are removed, a file of
/// the user's is kept and named; a user's file the new run would overwrite is refused before
/// anything is removed.
#[test]
fn force_removes_a_finished_runs_files_and_keeps_the_users() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("s.toml"), MC).unwrap();
    std::fs::write(d.join("plain.toml"), no_trajectory()).unwrap();
    let o = run(d, &["run", "s.toml", "--out", "out"], &[]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(d.join("out/trajectory.gsd").exists());
    assert!(!d.join("out/manifest.json").exists());
    std::fs::write(d.join("out/notes.txt"), "mine").unwrap();
    let o = run(d, &["run", "plain.toml", "--out", "out", "--force"], &[]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("kept") && t.contains("notes.txt"), "{t}");
    assert!(t.contains("removed") && t.contains("trajectory.gsd"), "{t}");
    assert!(!d.join("out/trajectory.gsd").exists());
    assert_eq!(std::fs::read(d.join("out/notes.txt")).unwrap(), b"mine");
    // A user's file of a name the run writes, which no run recorded: refused, nothing removed.
    let before = names(&d.join("out"));
    std::fs::remove_file(d.join("out/summary.json")).unwrap();
    let o = run(d, &["run", "s.toml", "--out", "out", "--force"], &[]);
    let t = text(&o);
    assert!(!o.status.success(), "{t}");
    assert!(
        t.contains("which this run would overwrite") && t.contains("scenario.toml"),
        "{t}"
    );
    let mut now = names(&d.join("out"));
    now.push("summary.json".into());
    now.sort();
    assert_eq!(now, before);
}

/// `--force` over an interrupted run (checkpoint.bin, no summary.json) and over one killed
/// before its first checkpoint: the files it recorded in manifest.json are removed, the user's
/// kept.
#[test]
fn force_removes_an_unfinished_runs_files() {
    for (hook, at) in [
        ("COLLOIDSIM_INTERRUPT_AT_STEP", "230"),
        ("COLLOIDSIM_KILL_AT_STEP", "3"),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        std::fs::write(d.join("s.toml"), MC).unwrap();
        std::fs::write(d.join("plain.toml"), no_trajectory()).unwrap();
        let o = run(d, &["run", "s.toml", "--out", "out"], &[(hook, at)]);
        assert!(!o.status.success(), "{}", text(&o));
        assert!(d.join("out/manifest.json").exists(), "{hook}");
        assert!(d.join("out/trajectory.gsd").exists(), "{hook}");
        assert!(!d.join("out/summary.json").exists(), "{hook}");
        std::fs::write(d.join("out/notes.txt"), "mine").unwrap();
        let o = run(d, &["run", "plain.toml", "--out", "out", "--force"], &[]);
        let t = text(&o);
        assert!(o.status.success(), "{hook}: {t}");
        assert!(!d.join("out/trajectory.gsd").exists(), "{hook}: {t}");
        assert!(!d.join("out/checkpoint.bin").exists(), "{hook}: {t}");
        assert!(!d.join("out/manifest.json").exists(), "{hook}: {t}");
        assert_eq!(std::fs::read(d.join("out/notes.txt")).unwrap(), b"mine");
        assert_eq!(
            std::fs::read_to_string(d.join("out/scenario.toml")).unwrap(),
            no_trajectory()
        );
    }
}

/// scenario.toml deleted or edited in an interrupted run's folder: the restart continues from
/// the checkpoint's scenario, puts it back and says so; the edited text is kept beside it.
#[test]
fn a_restart_restores_a_deleted_or_edited_scenario() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("s.toml"), MC).unwrap();
    let o = run(d, &["run", "s.toml", "--out", "a"], &[]);
    assert!(o.status.success(), "{}", text(&o));
    let edited = MC.replace("particles = 50", "particles = 70");
    for case in ["missing", "edited"] {
        let out = d.join(case);
        let o = run(
            d,
            &["run", "s.toml", "--out", case],
            &[("COLLOIDSIM_INTERRUPT_AT_STEP", "230")],
        );
        assert!(!o.status.success(), "{}", text(&o));
        if case == "missing" {
            std::fs::remove_file(out.join("scenario.toml")).unwrap();
        } else {
            std::fs::write(out.join("scenario.toml"), &edited).unwrap();
        }
        let o = run(d, &["run", "--restart", case], &[]);
        let t = text(&o);
        assert!(o.status.success(), "{t}");
        assert!(
            t.contains(&format!(
                "scenario.toml was {case}: restored the one the run started with"
            )),
            "{t}"
        );
        assert_eq!(
            std::fs::read_to_string(out.join("scenario.toml")).unwrap(),
            MC
        );
        if case == "edited" {
            assert!(t.contains("kept as scenario.toml.edited"), "{t}");
            assert_eq!(
                std::fs::read_to_string(out.join("scenario.toml.edited")).unwrap(),
                edited
            );
        }
        assert_eq!(
            std::fs::read(d.join("a/trajectory.gsd")).unwrap(),
            std::fs::read(out.join("trajectory.gsd")).unwrap()
        );
    }
}
