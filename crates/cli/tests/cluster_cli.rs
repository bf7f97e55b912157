//! Runs that live on a cluster (docs/cluster.md): SIGTERM and SIGUSR1 handled as Ctrl-C (a
//! checkpoint, then an exit status per cause), the wall-time budget (`--walltime`), and job
//! arrays (`ensemble --member K`, then `--collect`).
//!
//! Nothing here depends on timing: a run waits at a known step (`COLLOIDSIM_PAUSE_AT_STEP`)
//! until the signal sent to it arrives or its budget runs out, and the budget's stops are
//! placed on a fake clock (`COLLOIDSIM_FAKE_STEP_SECONDS`).

use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::process::{Command, Output, Stdio};

use crate::common;
use common::{TINY_BCD as TINY, assert_same_outputs, assert_same_tree, cli, text};

/// The summary fields of a BCD run that differ between runs of the same scenario.
const VOLATILE: &[&str] = &["wall_seconds", "particle_steps_per_second"];

/// The tiny scenario written into a temporary folder, and its uninterrupted run `a`.
fn setup() -> (tempfile::TempDir, String, std::path::PathBuf) {
    let (tmp, sc, a) = common::complete("tiny", TINY);
    (tmp, sc.to_str().unwrap().to_string(), a)
}

/// Start `colloidsim ARGS` with `COLLOIDSIM_PAUSE_AT_STEP=at`, wait until it says it waits at
/// step `at`, send it `signal` with the `kill` command, and return its output.
fn signalled(args: &[&str], at: u64, signal: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_colloidsim"))
        .args(args)
        .env("COLLOIDSIM_PAUSE_AT_STEP", at.to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    loop {
        let mut line = String::new();
        assert!(
            err.read_line(&mut line).unwrap() > 0,
            "the run ended before it paused: {seen}"
        );
        seen.push_str(&line);
        if line.contains(&format!("paused at step {at}")) {
            break;
        }
    }
    let pid = child.id().to_string();
    let sent = Command::new("kill").args(["-s", signal, &pid]).status();
    assert!(sent.unwrap().success(), "kill -s {signal} {pid}");
    err.read_to_string(&mut seen).unwrap();
    let mut o = child.wait_with_output().unwrap();
    o.stderr = seen.into_bytes();
    eprintln!("{}", text(&o));
    o
}

#[test]
fn sigterm_sigusr1_and_ctrl_c_write_a_checkpoint_and_exit_with_their_own_status() {
    let (tmp, sc, a) = setup();
    for (signal, status, what) in [
        ("TERM", 81, "stopped by SIGTERM"),
        ("USR1", 82, "stopped by SIGUSR1"),
        ("INT", 80, "interrupted"),
    ] {
        let b = tmp.path().join(format!("b-{signal}"));
        let bs = b.to_str().unwrap();
        let o = signalled(&["run", &sc, "--out", bs, "--quiet"], 700, signal);
        assert_eq!(o.status.code(), Some(status), "SIG{signal}: {}", text(&o));
        assert!(
            text(&o).contains(&format!(
                "{what} at step 700; checkpoint written at step 700 in {bs}"
            )),
            "{}",
            text(&o)
        );
        assert!(
            text(&o).contains(&format!("Continue with: colloidsim run --restart {bs}")),
            "{}",
            text(&o)
        );
        assert!(b.join("checkpoint.bin").exists(), "SIG{signal}");
        assert!(!b.join("summary.json").exists(), "SIG{signal}");
        let o = cli(&["run", "--restart", bs, "--quiet"], &[]);
        assert!(o.status.success(), "SIG{signal}");
        assert_same_outputs(&a, &b, VOLATILE);
    }
}

#[test]
fn a_signalled_ensemble_stops_with_the_signal_s_status_and_continues_to_the_same_folder() {
    let (tmp, sc, _) = setup();
    let (reference, out) = (tmp.path().join("reference"), tmp.path().join("ens"));
    let args = ["--replicas", "2", "--threads", "1", "--quiet"];
    let mut a = vec!["ensemble", &sc, "--out", reference.to_str().unwrap()];
    a.extend(args);
    assert!(cli(&a, &[]).status.success());
    let o = out.to_str().unwrap();
    let mut a = vec!["ensemble", &sc, "--out", o];
    a.extend(args);
    let stopped = signalled(&a, 900, "TERM");
    assert_eq!(stopped.status.code(), Some(81), "{}", text(&stopped));
    assert!(
        text(&stopped).contains(&format!(
            "stopped by SIGTERM; continue with: colloidsim ensemble --restart {o}"
        )),
        "{}",
        text(&stopped)
    );
    assert!(out.join("replica-0/checkpoint.bin").exists());
    assert!(!out.join("summary.json").exists());
    assert!(
        cli(&["ensemble", "--restart", o, "--quiet"], &[])
            .status
            .success()
    );
    assert_same_tree(&reference, &out);
}

/// `colloidsim ARGS` on the fake clock: each step 1/8 s, each checkpoint `checkpoint` s.
fn on_fake_clock(args: &[&str], checkpoint: &str) -> Output {
    cli(
        args,
        &[
            ("COLLOIDSIM_FAKE_STEP_SECONDS", "0.125"),
            ("COLLOIDSIM_FAKE_CHECKPOINT_SECONDS", checkpoint),
        ],
    )
}

/// The step of the checkpoint a stopped run names.
fn checkpoint_step(o: &Output) -> u64 {
    let t = text(o);
    let at = t
        .find("checkpoint written at step ")
        .expect("no checkpoint named")
        + 27;
    t[at..].split(' ').next().unwrap().parse().unwrap()
}

#[test]
fn the_walltime_budget_stops_at_the_last_checkpoint_that_fits_and_a_restart_loop_finishes() {
    let (tmp, sc, a) = setup();
    // 64 s, less the margin of 10 s: 54 s hold 432 steps of 1/8 s and a checkpoint of 0 s.
    let b = tmp.path().join("b");
    let bs = b.to_str().unwrap();
    let o = on_fake_clock(
        &["run", &sc, "--out", bs, "--walltime", "64", "--quiet"],
        "0",
    );
    assert_eq!(o.status.code(), Some(83), "{}", text(&o));
    assert!(
        text(&o).contains("stopped by the wall-time budget at step 432"),
        "{}",
        text(&o)
    );
    assert!(
        text(&o).contains(&format!("colloidsim run --restart {bs} --walltime 64")),
        "{}",
        text(&o)
    );
    assert!(b.join("checkpoint.bin").exists());
    assert!(!b.join("summary.json").exists());
    // The loop of a batch script: continue while the status says the budget ran out.
    let mut rounds = 1;
    loop {
        let o = on_fake_clock(
            &["run", "--restart", bs, "--walltime", "64", "--quiet"],
            "0",
        );
        rounds += 1;
        match o.status.code() {
            Some(83) => assert_eq!(checkpoint_step(&o), 432 * rounds as u64),
            Some(0) => break,
            other => panic!("status {other:?}: {}", text(&o)),
        }
        assert!(rounds < 10, "the restarts do not finish");
    }
    assert_eq!(rounds, 6, "2200 steps in rounds of 432");
    assert_same_outputs(&a, &b, VOLATILE);

    // Checkpoints of 4 s each, every 200 steps: the one at step 200 is paid for, and the
    // last must fit too. At most 64 - 10 - 4 - 4 = 46 s of steps (368), and no more than a
    // chunk less.
    let c = tmp.path().join("c");
    let cs = c.to_str().unwrap();
    let o = on_fake_clock(
        &[
            "run",
            &sc,
            "--out",
            cs,
            "--walltime",
            "64",
            "--set",
            "run.checkpoint_every=200",
            "--quiet",
        ],
        "4",
    );
    assert_eq!(o.status.code(), Some(83), "{}", text(&o));
    let at = checkpoint_step(&o);
    assert!((360..=368).contains(&at), "stopped at step {at}");
}

#[test]
fn a_real_budget_stops_a_long_run_and_one_too_short_for_a_step_is_an_error() {
    let (tmp, sc, a) = setup();
    // The run waits at step 500 as long as it is let: the 1 s budget stops it there.
    let b = tmp.path().join("b");
    let bs = b.to_str().unwrap();
    let o = cli(
        &["run", &sc, "--out", bs, "--walltime", "00:00:01", "--quiet"],
        &[("COLLOIDSIM_PAUSE_AT_STEP", "500")],
    );
    assert_eq!(o.status.code(), Some(83), "{}", text(&o));
    assert!(b.join("checkpoint.bin").exists());
    let o = cli(&["run", "--restart", bs, "--quiet"], &[]);
    assert!(o.status.success());
    assert_same_outputs(&a, &b, VOLATILE);
    // A microsecond is spent before the first step: status 1 (a loop of restarts stops), the
    // message says why, and the checkpoint of step 0 is there to continue with more time.
    let c = tmp.path().join("c");
    let cs = c.to_str().unwrap();
    let o = cli(
        &["run", &sc, "--out", cs, "--walltime", "0.000001", "--quiet"],
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("ran out before a step could be made"),
        "{}",
        text(&o)
    );
    assert!(c.join("checkpoint.bin").exists());
}

/// An ensemble (or one member of it) whose budget is spent before any member makes a step
/// is an error, status 1, as a run's is: a job loop of restarts with that budget would never
/// end. A longer budget then continues it.
#[test]
fn an_ensemble_budget_too_short_for_a_step_is_an_error() {
    let (tmp, sc, _) = setup();
    let out = tmp.path().join("e");
    let o = cli(&sweep(&sc, &out, &["--walltime", "0.000001"]), &[]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("ran out before any member could make a step"),
        "{}",
        text(&o)
    );
    let os = out.to_str().unwrap();
    let o = cli(
        &[
            "ensemble",
            "--restart",
            os,
            "--member",
            "1",
            "--walltime",
            "0.000001",
            "--quiet",
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o)
            .contains("member 1: the wall-time budget (--walltime 0.000001) ran out before a step"),
        "{}",
        text(&o)
    );
    let o = cli(&["ensemble", "--restart", os, "--quiet"], &[]);
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn bad_walltimes_are_refused_naming_the_flag_and_slurm_s_forms_are_accepted() {
    let (tmp, sc, _) = setup();
    for bad in [
        "abc",
        "1:61:00",
        "0",
        "-5",
        "00:00:00",
        "400-00:00:00",
        "1:2",
        "nan",
    ] {
        let flag = format!("--walltime={bad}");
        let o = cli(&["run", &sc, &flag, "--quiet"], &[]);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", text(&o));
        assert!(text(&o).contains("--walltime"), "{bad}: {}", text(&o));
        assert!(!tmp.path().join("tiny-x").exists());
    }
    for good in ["1-00:00:00", "48:00:00", "3600", "90.5"] {
        let out = tmp
            .path()
            .join(format!("ok-{}", good.replace([':', '.'], "_")));
        let o = cli(
            &[
                "run",
                &sc,
                "--out",
                out.to_str().unwrap(),
                "--walltime",
                good,
                "--quiet",
            ],
            &[],
        );
        assert!(o.status.success(), "{good}: {}", text(&o));
    }
}

/// `colloidsim ensemble TINY --out OUT --replicas 2 --vary system.particles=[4, 5]` with
/// `more` arguments.
fn sweep<'a>(sc: &'a str, out: &'a Path, more: &[&'a str]) -> Vec<&'a str> {
    let mut a = vec![
        "ensemble",
        sc,
        "--out",
        out.to_str().unwrap(),
        "--replicas",
        "2",
        "--vary",
        "system.particles=[4, 5]",
        "--threads",
        "1",
        "--quiet",
    ];
    a.extend_from_slice(more);
    a
}

#[test]
fn members_run_as_separate_jobs_at_once_then_collected_equal_one_ensemble_run() {
    let (tmp, sc, _) = setup();
    let (reference, out) = (tmp.path().join("reference"), tmp.path().join("array"));
    assert!(cli(&sweep(&sc, &reference, &[]), &[]).status.success());
    // A job array: the four members start at once into the same folder (the first creates
    // the folder and the plan, the others check it).
    let children: Vec<_> = (0..4)
        .map(|k| {
            let k = k.to_string();
            Command::new(env!("CARGO_BIN_EXE_colloidsim"))
                .args(sweep(&sc, &out, &["--member", &k]))
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for (k, c) in children.into_iter().enumerate() {
        let o = c.wait_with_output().unwrap();
        assert!(o.status.success(), "member {k}: {}", text(&o));
    }
    assert!(!out.join("summary.json").exists());
    let o = out.to_str().unwrap();
    let c = cli(&["ensemble", "--collect", o], &[]);
    assert!(c.status.success());
    assert!(text(&c).contains("averaged the 4 members"), "{}", text(&c));
    assert_same_tree(&reference, &out);
    // Again: the same averages.
    assert!(cli(&["ensemble", "--collect", o], &[]).status.success());
    assert_same_tree(&reference, &out);
    // A member of another plan into this folder is refused, naming what differs.
    let vary = "system.particles=[4, 5]";
    let other = [
        "ensemble",
        &sc,
        "--out",
        o,
        "--replicas",
        "3",
        "--vary",
        vary,
    ];
    let r = cli(&[&other[..], &["--member", "0", "--quiet"]].concat(), &[]);
    assert!(!r.status.success());
    assert!(text(&r).contains("replicas"), "{}", text(&r));
    let r = cli(&sweep(&sc, &out, &["--member", "4"]), &[]);
    assert!(
        text(&r).contains("--member: must lie in 0 ..= 3"),
        "{}",
        text(&r)
    );
}

#[test]
fn collect_refuses_unfinished_members_by_name_or_averages_the_finished_ones_when_told() {
    let (tmp, sc, _) = setup();
    let (reference, out) = (tmp.path().join("reference"), tmp.path().join("array"));
    assert!(cli(&sweep(&sc, &reference, &[]), &[]).status.success());
    let o = out.to_str().unwrap();
    // Member 1 interrupted (as by Ctrl-C), member 2 never run.
    for k in ["0", "3"] {
        assert!(
            cli(&sweep(&sc, &out, &["--member", k]), &[])
                .status
                .success()
        );
    }
    let r = cli(
        &sweep(&sc, &out, &["--member", "1"]),
        &[("COLLOIDSIM_INTERRUPT_AT_STEP", "300")],
    );
    assert_eq!(r.status.code(), Some(80), "{}", text(&r));
    assert!(
        text(&r).contains(&format!(
            "Continue with: colloidsim ensemble --restart {o} --member 1"
        )),
        "{}",
        text(&r)
    );
    let c = cli(&["ensemble", "--collect", o], &[]);
    assert!(!c.status.success());
    assert!(
        text(&c).contains("2 of 4 members are not finished: 1 (point-0/replica-1) interrupted, 2 (point-1/replica-0) not run"),
        "{}",
        text(&c)
    );
    assert!(!out.join("summary.json").exists());
    // The finished ones only: said in the summary, which does not claim completion.
    let c = cli(&["ensemble", "--collect", o, "--finished-only"], &[]);
    assert!(c.status.success());
    assert!(text(&c).contains("averaged 2 of 4 members"), "{}", text(&c));
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["completed"], false);
    assert_eq!(s["partial"], true);
    let left: Vec<u64> = s["left_out"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["member"].as_u64().unwrap())
        .collect();
    assert_eq!(left, [1, 2]);
    // The rest run (the interrupted one continued as printed), then the whole collected.
    assert!(
        cli(
            &["ensemble", "--restart", o, "--member", "1", "--quiet"],
            &[]
        )
        .status
        .success()
    );
    assert!(
        cli(&sweep(&sc, &out, &["--member", "2"]), &[])
            .status
            .success()
    );
    assert!(cli(&["ensemble", "--collect", o], &[]).status.success());
    assert_same_tree(&reference, &out);
}
