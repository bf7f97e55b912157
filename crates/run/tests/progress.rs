//! What a user watching a run sees while it goes: `thermo.csv` grows row by row (every
//! method that writes it) and the progress line gives the step, the simulated time, the
//! temperature and the throughput.

use colloidsim_run::{Control, Progress, RunOptions, Scenario};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// Records, at every progress update, the position and the data rows of `thermo.csv` on disk
/// then, and every status line.
struct Watch {
    thermo: PathBuf,
    seen: Mutex<Vec<(u64, Option<Vec<String>>)>>,
    status: Mutex<Vec<String>>,
}

impl Progress for Watch {
    fn advance(&self, done: u64) {
        let rows = std::fs::read_to_string(&self.thermo)
            .ok()
            .map(|t| t.lines().skip(1).map(str::to_string).collect());
        self.seen.lock().unwrap().push((done, rows));
    }

    fn status(&self, text: &str) {
        self.status.lock().unwrap().push(text.to_string());
    }
}

/// Run `text`; the watcher and the finished `thermo.csv`.
fn watch(text: &str) -> (Arc<Watch>, String) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let w = Arc::new(Watch {
        thermo: out.join("thermo.csv"),
        seen: Mutex::new(Vec::new()),
        status: Mutex::new(Vec::new()),
    });
    let sc = Scenario::from_toml(text, dir.path()).unwrap();
    let opts = RunOptions {
        out: Some(out.clone()),
        ..Default::default()
    };
    colloidsim_run::run(&sc, &opts, &Control::new(w.clone()))
        .unwrap_or_else(|e| panic!("{e:#}\n{text}"));
    let done = std::fs::read_to_string(out.join("thermo.csv")).unwrap();
    (w, done)
}

/// At every update before the last, `thermo.csv` holds exactly the rows due so far
/// (`rows_at(position)`), each equal to the finished file's row.
fn check_grows(w: &Watch, done: &str, rows_at: impl Fn(u64) -> usize) {
    let finished: Vec<&str> = done.lines().skip(1).collect();
    let seen = w.seen.lock().unwrap();
    let end = seen.iter().map(|(pos, _)| *pos).max().unwrap_or(0);
    let mid: Vec<_> = seen.iter().filter(|(pos, _)| *pos < end).collect();
    assert!(
        !mid.is_empty(),
        "no progress update before the end: {seen:?}"
    );
    assert!(
        mid.iter().any(|(pos, _)| rows_at(*pos) > 0),
        "no update after the first row: {seen:?}"
    );
    for (pos, rows) in mid {
        if rows_at(*pos) == 0 && rows.is_none() {
            continue; // no row yet: no file yet
        }
        let rows = rows
            .as_ref()
            .unwrap_or_else(|| panic!("no thermo.csv at position {pos}"));
        assert_eq!(rows.len(), rows_at(*pos), "rows at position {pos}");
        assert_eq!(rows[..], finished[..rows.len()], "at position {pos}");
    }
}

const DPD: &str = r#"
method = "dpd"
seed = 3
[system]
box_length = 8.0
phi = 0.1
kT = 0.1
[run]
dt = 0.001
steps = 400
[observe]
thermo_every = 20
trajectory_every = 0
"#;

#[test]
fn dpd_thermo_grows_as_the_run_goes_and_the_progress_line_says_where_it_is() {
    let (w, done) = watch(DPD);
    check_grows(&w, &done, |pos| (pos / 20) as usize);
    let status = w.status.lock().unwrap();
    let last = status.last().expect("a status line");
    for part in ["step ", "/400", "tau_D", "T = ", "steps/s"] {
        assert!(last.contains(part), "{part:?} not in {last:?}");
    }
}

#[test]
fn mpcd_thermo_grows_as_the_run_goes() {
    let text = r#"
method = "mpcd"
seed = 3
[system]
box = 8
[run]
collisions = 400
equilibrate = 100
[viscosity]
[observe]
every = 10
"#;
    let (w, done) = watch(text);
    // A row at collision 0 and every 10 collisions.
    check_grows(&w, &done, |pos| (pos / 10 + 1) as usize);
    let status = w.status.lock().unwrap();
    let last = status.last().expect("a status line");
    assert!(last.contains("T = ") && last.contains("steps/s"), "{last}");
}

#[test]
fn droplet_mpcd_thermo_grows_as_the_run_goes() {
    let text = r#"
method = "droplet-mpcd"
seed = 3
boundary = "slip"
[system]
radius = 5
[drying]
peclet = 10
duration = 40
[observe]
every = 10
[observe.solvent]
window = 100
"#;
    let (w, done) = watch(text);
    let every = 10;
    check_grows(&w, &done, |pos| (pos / every + 1) as usize);
    let status = w.status.lock().unwrap();
    let last = status.last().expect("a status line");
    assert!(last.contains("R = ") && last.contains("T = "), "{last}");
}
