//! `colloidsim` under `mpirun -n 1, 2, 4` (built with `--features mpi`; `.ci/run` runs these
//! with Open MPI): an ensemble's folder is byte for byte the single-process one on any number
//! of ranks, and a failure on one rank stops every rank with its message instead of a hang.
#![cfg(feature = "mpi")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use common::{TINY_BCD as TINY, assert_same_tree, text};

/// `colloidsim ARGS` on `ranks` MPI ranks (oversubscribed; at most two minutes, so that a
/// hang fails the test with status 124), with extra environment variables.
fn mpirun_env(ranks: usize, args: &[&str], env: &[(&str, &str)]) -> Output {
    let o = Command::new("timeout")
        .args([
            "120",
            "mpirun",
            "--allow-run-as-root",
            "--oversubscribe",
            "-n",
        ])
        .arg(ranks.to_string())
        .arg(env!("CARGO_BIN_EXE_colloidsim"))
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("mpirun (Open MPI) must be installed to run the MPI tests");
    eprintln!("{}", text(&o));
    assert_ne!(o.status.code(), Some(124), "mpirun -n {ranks} hung");
    o
}

fn mpirun(ranks: usize, args: &[&str]) -> Output {
    mpirun_env(ranks, args, &[])
}

/// The tiny scenario, written into `dir`.
fn tiny(dir: &Path) -> PathBuf {
    let sc = dir.join("tiny.toml");
    std::fs::write(&sc, TINY).unwrap();
    sc
}

/// The tiny scenario written into `dir`, and its ensemble with `args` run in one process on one
/// thread into `dir/serial`: (scenario path, reference folder).
fn serial_reference(dir: &Path, args: &[&str]) -> (String, PathBuf) {
    let sc = tiny(dir);
    let (s, reference) = (sc.to_str().unwrap().to_string(), dir.join("serial"));
    let mut a = vec![
        "ensemble",
        &s,
        "--out",
        reference.to_str().unwrap(),
        "--threads",
        "1",
    ];
    a.extend(args);
    assert!(common::cli(&a, &[]).status.success());
    (s, reference)
}

#[test]
fn an_ensemble_on_1_2_and_4_ranks_is_the_single_process_one() {
    let tmp = tempfile::tempdir().unwrap();
    let common_args = [
        "--replicas",
        "3",
        "--vary",
        "system.particles=[4, 5]",
        "--quiet",
    ];
    let (s, reference) = serial_reference(tmp.path(), &common_args);
    let s = s.as_str();
    for ranks in [1, 2, 4] {
        let out = tmp.path().join(format!("ranks-{ranks}"));
        let mut args = vec!["ensemble", s, "--out", out.to_str().unwrap()];
        args.extend(common_args);
        let o = mpirun(ranks, &args);
        assert!(o.status.success(), "mpirun -n {ranks}");
        assert_same_tree(&reference, &out);
    }
}

#[test]
fn bad_input_stops_every_rank_with_one_message() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tiny(tmp.path());
    let out = tmp.path().join("ens");
    let o = mpirun(
        3,
        &[
            "ensemble",
            sc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--set",
            "run.dt=-1",
        ],
    );
    assert!(!o.status.success());
    let t = text(&o);
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(t.contains("dt"), "{t}");
    assert!(!out.exists());
}

#[test]
fn a_member_failing_on_one_rank_stops_all_ranks_without_averages() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tiny(tmp.path());
    let out = tmp.path().join("ens");
    // Member 1 (rank 1 of 2) cannot create its folder: a file holds its name.
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("replica-1"), b"in the way").unwrap();
    let o = mpirun(
        2,
        &[
            "ensemble",
            sc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--replicas",
            "4",
            "--force",
            "--quiet",
        ],
    );
    assert!(!o.status.success());
    let t = text(&o);
    assert!(
        t.contains("1 of 4 members failed") && t.contains("replica-1"),
        "{t}"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["completed"], false);
    assert_eq!(summary["failed"][0]["member"], 1);
    assert!(
        !out.join("density.csv").exists(),
        "averages written despite a failed member"
    );
    assert!(
        out.join("replica-3/summary.json").exists(),
        "rank 1's other member did not run"
    );
}

#[test]
fn run_refuses_several_ranks_until_the_engines_are_decomposed() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tiny(tmp.path());
    let out = tmp.path().join("run");
    let o = mpirun(
        2,
        &["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()],
    );
    assert!(!o.status.success());
    assert!(text(&o).contains("colloidsim ensemble"), "{}", text(&o));
    assert!(!out.exists());
    let one = mpirun(
        1,
        &[
            "run",
            sc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ],
    );
    assert!(one.status.success());
}

#[test]
fn an_ensemble_interrupted_on_2_ranks_continues_on_1_and_4() {
    let tmp = tempfile::tempdir().unwrap();
    let args = ["--replicas", "5", "--quiet"];
    let (s, reference) = serial_reference(tmp.path(), &args);
    let s = s.as_str();
    for ranks in [1, 4] {
        let out = tmp.path().join(format!("continued-on-{ranks}"));
        let mut a = vec!["ensemble", s, "--out", out.to_str().unwrap()];
        a.extend(args);
        let o = mpirun_env(2, &a, &[("COLLOIDSIM_INTERRUPT_AT_STEP", "1000")]);
        assert!(!o.status.success());
        assert!(text(&o).contains("--restart"), "{}", text(&o));
        assert!(out.join("replica-1/checkpoint.bin").exists());
        let r = mpirun(
            ranks,
            &["ensemble", "--restart", out.to_str().unwrap(), "--quiet"],
        );
        assert!(r.status.success(), "restart on {ranks} ranks");
        assert_same_tree(&reference, &out);
    }
}
