//! `run.tune_skin` (bd and dpd): the neighbour search chosen from measured step times is
//! recorded with every candidate's time, the scenario that names the chosen setting is bitwise
//! the same run, and a run stopped halfway continues with the setting it chose (carried by the
//! checkpoint) rather than a new tuning.

use colloidsim_run::{Control, Progress, RunOptions, Scenario};
use serde_json::Value;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

/// Asks the run to stop (as Ctrl-C) once `after` units of work are done.
struct StopAfter {
    after: u64,
    done: AtomicU64,
}

impl Progress for StopAfter {
    fn advance(&self, done: u64) {
        self.done.store(done, Ordering::Relaxed);
    }

    fn poll(&self) -> bool {
        self.done.load(Ordering::Relaxed) >= self.after
    }
}

/// Run `text` in `dir/name`; the summary and the trajectory's bytes.
fn run_in(dir: &Path, name: &str, text: &str) -> (Value, Vec<u8>) {
    let sc = Scenario::from_toml(text, dir).unwrap();
    let opts = RunOptions {
        out: Some(dir.join(name)),
        ..Default::default()
    };
    let r = colloidsim_run::run(&sc, &opts, &Control::default())
        .unwrap_or_else(|e| panic!("{e:#}\n{text}"));
    let traj = std::fs::read(dir.join(name).join("trajectory.gsd")).unwrap();
    (r.summary, traj)
}

/// `base` (with a `[run]` table and a trajectory) run with `run.tune_skin = true`: the tuning
/// is reported and `fixed(tuning)` (the scenario naming what it chose) reproduces the run's
/// trajectory bitwise; the run stopped after `stop` units and resumed reports the tuning of its
/// first session and has the trajectory of the setting it names. Returns the tuning.
fn tuned_run_is_reproduced(base: &str, stop: u64, fixed: impl Fn(&Value) -> String) -> Value {
    let dir = tempfile::tempdir().unwrap();
    let tuned_text = base.replace("[run]\n", "[run]\ntune_skin = true\n");
    let (tuned, traj) = run_in(dir.path(), "tuned", &tuned_text);
    let t = tuned["parameters"]["skin_tuning"].clone();
    let trials = t["trials"].as_array().unwrap();
    assert!(trials.len() >= 4, "{t}");
    assert!(
        trials
            .iter()
            .all(|x| x["seconds_per_step"].as_f64().unwrap() > 0.0),
        "{t}"
    );
    assert!(
        trials
            .iter()
            .any(|x| x["skin"] == t["skin"] && x["cells"] == t["cells"]),
        "{t}"
    );
    assert_eq!(tuned["parameters"]["skin"], t["skin"]);
    let (_, fixed_traj) = run_in(dir.path(), "fixed", &fixed(&t));
    assert_eq!(traj, fixed_traj, "{t}");

    let sc = Scenario::from_toml(&tuned_text, dir.path()).unwrap();
    let out = dir.path().join("stopped");
    let opts = RunOptions {
        out: Some(out.clone()),
        ..Default::default()
    };
    let stopper = std::sync::Arc::new(StopAfter {
        after: stop,
        done: AtomicU64::new(0),
    });
    let e = colloidsim_run::run(&sc, &opts, &Control::new(stopper)).unwrap_err();
    assert!(
        e.downcast_ref::<colloidsim_run::Interrupted>().is_some(),
        "{e:#}"
    );
    let r = colloidsim_run::resume(&out, None, None, &Control::default()).unwrap();
    let again = r.summary["parameters"]["skin_tuning"].clone();
    assert!(again.is_object(), "{}", r.summary["parameters"]);
    assert_eq!(r.summary["parameters"]["skin"], again["skin"]);
    let resumed = std::fs::read(out.join("trajectory.gsd")).unwrap();
    let (_, same) = run_in(dir.path(), "again", &fixed(&again));
    assert_eq!(resumed, same, "{again}");
    t
}

/// bd: the skin among 0.2-1.2 d. Checked to fail: with the restore leaving the checkpoint's
/// tuning out, the resumed run reports none.
#[test]
fn bd_tuned_skin_is_recorded_and_its_run_is_reproduced_bitwise() {
    let base = "method = \"bd\"\nseed = 5\n[system]\nparticles = 150\nbox_length = 10.0\n\
                [run]\ndt = 0.001\ntime = 0.6\n[observe.trajectory]\nevery = 50\n";
    let t = tuned_run_is_reproduced(base, 200, |t| {
        base.replace(
            "[run]\n",
            &format!("[run]\nskin = {:?}\n", t["skin"].as_f64().unwrap()),
        )
    });
    assert_eq!(t["cells"], false);
}

/// dpd: cells every step or Verlet lists with a skin of 0.1-0.8 rc.
#[test]
fn dpd_tuned_neighbour_search_is_recorded_and_its_run_is_reproduced_bitwise() {
    let base = "method = \"dpd\"\nseed = 3\n[system]\nbox_length = 8.0\nphi = 0.05\nkT = 0.1\n\
                [run]\ndt = 0.001\nsteps = 300\n[observe]\ntrajectory_every = 50\n";
    let t = tuned_run_is_reproduced(base, 100, |t| {
        let search = if t["cells"].as_bool().unwrap() {
            "cells"
        } else {
            "verlet"
        };
        base.replace(
            "[run]\n",
            &format!(
                "[run]\nskin = {:?}\nneighbors = \"{search}\"\n",
                t["skin"].as_f64().unwrap()
            ),
        )
    });
    assert!(
        t["trials"]
            .as_array()
            .unwrap()
            .iter()
            .any(|x| x["cells"] == true),
        "{t}"
    );
}
