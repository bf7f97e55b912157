//! End-to-end tests of `colloidsim run|check` on DPD scenarios, checkpoints and `--restart`
//! included.

use std::path::Path;
use std::process::{Command, Output};

use crate::common;
use common::{assert_same_outputs, files, text};

/// summary.json fields that depend on the session (timing); neighbor_builds must match.
const TIMING: &[&str] = &["wall_seconds", "particle_steps_per_second"];

const SMALL: &str = r#"
method = "dpd"
seed = 3
[system]
box_length = 8.0
phi = 0.1
kT = 0.1
[colloids]
morse_depth = 12.0
[run]
dt = 0.001
steps = 400
[observe]
thermo_every = 20
trajectory_every = 200
msd_every = 20
structure_every = 100
"#;

fn run(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_colloidsim"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// `run` with environment variables (the hidden test hooks).
fn run_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_colloidsim"));
    c.current_dir(dir).args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().unwrap()
}

#[test]
fn a_small_suspension_runs_and_writes_every_output() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("s.toml"), SMALL).unwrap();
    let o = run(d, &["run", "s.toml", "--out", "out", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    for f in [
        "thermo.csv",
        "msd.csv",
        "msd.png",
        "gr.csv",
        "sq.csv",
        "gr.png",
        "coordination.csv",
        "clusters.csv",
        "trajectory.gsd",
        "summary.json",
    ] {
        assert!(d.join("out").join(f).is_file(), "missing {f}");
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/summary.json")).unwrap())
            .unwrap();
    assert_eq!(s["completed"], true);
    assert_eq!(s["steps"], 400);
    // 400 steps are 0.007 tau_D: no long-time diffusion coefficient, and the reason.
    assert!(s["colloid_diffusion_long_time"].is_null());
    let note = s["colloid_diffusion_note"].as_str().unwrap();
    assert!(
        note.contains("not measured") && note.contains("tau_D"),
        "{note}"
    );
    // g(r) stops under half the box by default (freud's RDF refuses r_max = L/2).
    let (_, gr) = colloidsim_core::output::read_table(&d.join("out/gr.csv")).unwrap();
    let r = &gr[0];
    let (r_last, r_prev) = (r[r.len() - 1], r[r.len() - 2]);
    let edge = r_last + 0.5 * (r_last - r_prev);
    assert!((edge - 0.49 * 8.0).abs() < 1e-9, "g(r) ends at {edge}");
    let (head, rows) = colloidsim_core::output::read_table(&d.join("out/thermo.csv")).unwrap();
    assert_eq!(
        head[..6],
        ["step", "time", "time_tau", "T", "T_solvent", "T_colloid"]
    );
    assert_eq!(rows[0].len(), 20);
    // Time in colloid diffusion times: tau_D = R^2 6 pi eta0 R / kT = 56.55 DPD times.
    let tau = 6.0 * std::f64::consts::PI * 0.3 / 0.1;
    assert!((rows[2][19] - 0.4 / tau).abs() < 1e-9);
    // The same command again refuses to overwrite.
    let o = run(d, &["run", "s.toml", "--out", "out", "--quiet"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("--force"), "{}", text(&o));
    // The same seed gives the same trajectory, bitwise.
    let o = run(
        d,
        &[
            "run",
            "s.toml",
            "--out",
            "again",
            "--quiet",
            "--threads",
            "1",
        ],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(
        std::fs::read(d.join("out/thermo.csv")).unwrap(),
        std::fs::read(d.join("again/thermo.csv")).unwrap()
    );
}

#[test]
fn bad_scenarios_name_the_key() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    for (patch, key) in [
        ("[dpd]\ngamma = 300.0\n", "dpd.gamma"),
        ("[colloids]\ncutoff = 0.0001\n", "colloids.cutoff"),
        ("[run]\nskin = 0.0\n", "run.skin"),
        ("[observe]\nfoo = 1\n", "observe.foo: unknown key"),
    ] {
        let sc = SMALL.replace("[run]\ndt = 0.001", &format!("{patch}[run]\ndt = 0.001"));
        // Duplicate tables are invalid TOML; put the patch in a fresh file instead.
        let sc = if SMALL.contains(patch.lines().next().unwrap()) {
            let table = patch.lines().next().unwrap();
            SMALL.replacen(table, patch.trim_end(), 1)
        } else {
            sc
        };
        std::fs::write(d.join("bad.toml"), &sc).unwrap();
        let o = run(d, &["check", "bad.toml"]);
        assert!(!o.status.success(), "{patch} accepted");
        assert!(text(&o).contains(key), "{patch}: {}", text(&o));
    }
    // A low gamma is accepted with a warning.
    let sc = SMALL.replace("[run]\ndt = 0.001", "[dpd]\ngamma = 2.0\n[run]\ndt = 0.001");
    std::fs::write(d.join("warn.toml"), sc).unwrap();
    let o = run(d, &["check", "warn.toml"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("warning: dpd.gamma"), "{}", text(&o));
}

#[test]
fn a_heating_time_step_stops_the_run_and_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // DPD water at dt = 0.1: far too hot.
    let sc = "method = \"dpd\"\n[system]\nbox_length = 8.0\nkT = 1.0\n[run]\ndt = 0.1\nsteps = 3000\ntemperature_window = 200\n[observe]\nthermo_every = 10\nstructure_every = 0\ntrajectory_every = 0\n";
    std::fs::write(d.join("hot.toml"), sc).unwrap();
    let o = run(d, &["run", "hot.toml", "--out", "hot", "--quiet"]);
    assert!(!o.status.success());
    let t = text(&o);
    assert!(t.contains("run.dt"), "{t}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("hot/summary.json")).unwrap())
            .unwrap();
    assert_eq!(s["completed"], false);
}

/// SMALL with a trajectory frame every 30 steps (frames fall between checkpoints). 400 steps:
/// lists synchronised, and checkpoints written, every 40 steps.
fn restart_scenario(d: &Path) -> String {
    std::fs::write(
        d.join("r.toml"),
        // The Green–Kubo correlator is part of the checkpoint: 200 samples of 2 steps, 3 lags.
        SMALL.replace(
            "trajectory_every = 200",
            "trajectory_every = 30\nviscosity_every = 2\nviscosity_time = 0.004",
        ),
    )
    .unwrap();
    "r.toml".into()
}

#[test]
fn an_interrupted_run_restarts_bitwise() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sc = restart_scenario(d);
    let o = run(d, &["run", &sc, "--out", "a", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    let names: Vec<String> = files(&d.join("a")).into_keys().collect();
    assert!(names.iter().any(|n| n == "scenario.toml"), "{names:?}");
    assert!(
        !names.iter().any(|n| n.starts_with("checkpoint")),
        "{names:?}"
    );
    // Ctrl-C at step 123 runs on to step 160 (a multiple of the synchronisation period, 40);
    // at step 0 and at 200 it stops at once.
    for (at, ck) in [("123", 160), ("0", 0), ("200", 200)] {
        let b = format!("b{at}");
        let o = run_env(
            d,
            &["run", &sc, "--out", &b, "--quiet"],
            &[("COLLOIDSIM_INTERRUPT_AT_STEP", at)],
        );
        assert!(!o.status.success());
        let t = text(&o);
        assert!(
            t.contains(&format!(
                "interrupted at step {at}; checkpoint written at step {ck}"
            )),
            "{t}"
        );
        assert!(t.contains(&format!("--restart {b}")), "{t}");
        let bp = d.join(&b);
        assert!(bp.join("checkpoint.bin").exists());
        assert!(!bp.join("summary.json").exists());
        let o = run(d, &["run", &sc, "--restart", &b, "--quiet"]);
        assert!(o.status.success(), "{}", text(&o));
        assert_same_outputs(&d.join("a"), &bp, TIMING);
    }
    // Interrupted twice: the second session is itself interrupted (at 250, checkpoint at 280).
    let o = run_env(
        d,
        &["run", &sc, "--out", "c", "--quiet"],
        &[("COLLOIDSIM_INTERRUPT_AT_STEP", "50")],
    );
    assert!(!o.status.success());
    let o = run_env(
        d,
        &["run", &sc, "--restart", "c", "--quiet"],
        &[("COLLOIDSIM_INTERRUPT_AT_STEP", "250")],
    );
    assert!(
        text(&o).contains("interrupted at step 250; checkpoint written at step 280"),
        "{}",
        text(&o)
    );
    let o = run(d, &["run", &sc, "--restart", "c", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_same_outputs(&d.join("a"), &d.join("c"), TIMING);
}

#[test]
fn a_killed_run_restarts_from_the_last_periodic_checkpoint() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sc = restart_scenario(d);
    let o = run(d, &["run", &sc, "--out", "a", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    // Killed without a checkpoint at step 235: the last checkpoint is at step 200, and
    // trajectory.gsd already holds the frames of steps 210 and 230, which the restart drops
    // and writes again.
    let o = run_env(
        d,
        &["run", &sc, "--out", "k", "--quiet"],
        &[("COLLOIDSIM_KILL_AT_STEP", "235")],
    );
    assert!(!o.status.success());
    assert!(d.join("k/checkpoint.bin").exists());
    let o = run(d, &["run", &sc, "--restart", "k", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_same_outputs(&d.join("a"), &d.join("k"), TIMING);
}

#[test]
fn restart_refuses_without_checkpoint_changed_scenario_or_finished_run() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sc = restart_scenario(d);
    let o = run(d, &["run", &sc, "--out", "a", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    // A completed run is left alone.
    let before = files(&d.join("a"));
    let o = run(d, &["run", &sc, "--restart", "a", "--quiet"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("complete"), "{}", text(&o));
    assert!(files(&d.join("a")) == before);
    // No folder; a run killed before its first checkpoint (step 40).
    let o = run(d, &["run", &sc, "--restart", "none", "--quiet"]);
    assert!(!o.status.success() && text(&o).contains("no such folder"));
    let o = run_env(
        d,
        &["run", &sc, "--out", "early", "--quiet"],
        &[("COLLOIDSIM_KILL_AT_STEP", "30")],
    );
    assert!(!o.status.success());
    let o = run(d, &["run", &sc, "--restart", "early", "--quiet"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("no checkpoint.bin"), "{}", text(&o));
    // An interrupted run continues only with the scenario and seed it started with.
    let o = run_env(
        d,
        &["run", &sc, "--out", "b", "--quiet"],
        &[("COLLOIDSIM_INTERRUPT_AT_STEP", "100")],
    );
    assert!(!o.status.success());
    let other = SMALL
        .replace("trajectory_every = 200", "trajectory_every = 30")
        .replace("morse_depth = 12.0", "morse_depth = 11.0");
    std::fs::write(d.join("other.toml"), other).unwrap();
    let o = run(d, &["run", "other.toml", "--restart", "b", "--quiet"]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("differs from the scenario this run started with"),
        "{}",
        text(&o)
    );
    let o = run(d, &["run", &sc, "--restart", "b", "--seed", "4", "--quiet"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("seed = 4 (was 3)"), "{}", text(&o));
    // The refusals left the checkpoint usable.
    let o = run(d, &["run", &sc, "--restart", "b", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_same_outputs(&d.join("a"), &d.join("b"), TIMING);
}

#[test]
fn a_restarted_run_stops_where_the_uninterrupted_one_does() {
    // DPD water at dt = 0.08 heats by ~10 %: the temperature monitor (windows of 100 steps, the
    // first not judged) stops the run at step 210. Interrupted at 150, checkpointed at 200
    // (1000 steps: synchronisation every 100), the restart must stop at the same step with the
    // same message: the monitor's state is part of the checkpoint.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sc = "method = \"dpd\"\n[system]\nbox_length = 6.0\nkT = 1.0\n[run]\ndt = 0.08\nsteps = 1000\ntemperature_window = 100\n[observe]\nthermo_every = 10\nstructure_every = 0\ntrajectory_every = 0\nmsd_every = 0\n";
    std::fs::write(d.join("hot.toml"), sc).unwrap();
    let o = run(d, &["run", "hot.toml", "--out", "a", "--quiet"]);
    assert!(!o.status.success());
    let t = text(&o);
    assert!(t.contains("before step 210"), "{t}");
    let o = run_env(
        d,
        &["run", "hot.toml", "--out", "b", "--quiet"],
        &[("COLLOIDSIM_INTERRUPT_AT_STEP", "150")],
    );
    assert!(
        text(&o).contains("checkpoint written at step 200"),
        "{}",
        text(&o)
    );
    let o = run(d, &["run", "hot.toml", "--restart", "b", "--quiet"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("before step 210"), "{}", text(&o));
    assert_same_outputs(&d.join("a"), &d.join("b"), TIMING);
    // A failed run keeps no checkpoint: it cannot be continued.
    assert!(!d.join("b/checkpoint.bin").exists());
    let o = run(d, &["run", "hot.toml", "--restart", "b", "--quiet"]);
    assert!(!o.status.success());
    assert!(text(&o).contains("stopped with an error"), "{}", text(&o));
}

/// `thermo.csv` is written as the run goes: a run killed at step 150 (after its checkpoint at
/// 120, without one of its own) leaves the rows of steps 20 to 140, exactly the first rows
/// of the finished run's file, and no summary.json; continued from its checkpoint, the run
/// drops the row written after it and ends with every output of an uninterrupted run.
#[test]
fn a_killed_run_leaves_the_thermo_rows_written_so_far() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sc = restart_scenario(d);
    let o = run(d, &["run", &sc, "--out", "a", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    let full = std::fs::read_to_string(d.join("a/thermo.csv")).unwrap();
    let o = run_env(
        d,
        &["run", &sc, "--out", "k", "--quiet"],
        &[("COLLOIDSIM_KILL_AT_STEP", "150")],
    );
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(!d.join("k/summary.json").exists());
    let part = std::fs::read_to_string(d.join("k/thermo.csv"))
        .expect("thermo.csv of the rows written before the kill");
    let lines: Vec<&str> = part.lines().collect();
    assert_eq!(lines.len(), 1 + 7, "header and steps 20..=140:\n{part}");
    assert!(lines[7].starts_with("140,"), "{part}");
    assert!(
        full.starts_with(&part),
        "not the first rows of\n{full}\n{part}"
    );
    let o = run(d, &["run", &sc, "--restart", "k", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_same_outputs(&d.join("a"), &d.join("k"), TIMING);
}

/// DPD frames carry what HOOMD-blue's ThermodynamicQuantities logs (kinetic temperature,
/// pressure, its tensor, potential energy), read with the `gsd` package: equal to the
/// thermo.csv row of the same step, and the application is colloidsim.
#[test]
fn gsd_frames_carry_hoomd_thermodynamic_log_quantities() {
    if !colloidsim_core::tools::python_module_or_skip(
        "gsd.hoomd",
        "gsd_frames_carry_hoomd_thermodynamic_log_quantities",
    ) {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // Frames every 30 steps, thermo rows every 20: frames at 60, 120, ... meet a row.
    let sc = restart_scenario(d);
    let o = run(d, &["run", &sc, "--out", "a", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    let script = r#"
import sys, gsd.hoomd, gsd.fl, numpy as np
with gsd.fl.open(sys.argv[1] + '/trajectory.gsd', 'r') as fl:
    assert fl.application.startswith('colloidsim '), fl.application
th = np.genfromtxt(sys.argv[1] + '/thermo.csv', delimiter=',', names=True)
q = 'md/compute/ThermodynamicQuantities/'
t = gsd.hoomd.open(sys.argv[1] + '/trajectory.gsd', 'r')
assert len(t) == 14, len(t)
checked = 0
for f in t[1:]:
    step = f.configuration.step
    for k in ['kinetic_temperature', 'pressure', 'potential_energy']:
        assert q + k in f.log, (step, list(f.log))
    assert f.log[q + 'pressure_tensor'].shape == (6,), f.log[q + 'pressure_tensor'].shape
    row = th[th['step'] == step]
    if len(row):
        assert np.isclose(f.log[q + 'kinetic_temperature'][0], row['T'][0], rtol=1e-12)
        assert np.isclose(f.log[q + 'pressure'][0], row['p'][0], rtol=1e-12)
        pt = f.log[q + 'pressure_tensor']
        assert np.allclose(pt[[0, 3, 5, 1, 2, 4]], [row[c][0] for c in ['pxx', 'pyy', 'pzz', 'pxy', 'pxz', 'pyz']], rtol=1e-12)
        assert np.isclose(f.log[q + 'potential_energy'][0], row['energy_potential'][0], rtol=1e-12)
        checked += 1
assert checked == 6, checked
f0 = t[0].log
# Step 0 too: its virial is computed for the frame (it used to be NaN).
assert f0[q + 'kinetic_temperature'][0] > 0, f0
assert all(np.isfinite(f0[q + k]).all() for k in ['pressure', 'pressure_tensor', 'potential_energy']), f0
print('ok')
"#;
    let o = Command::new("python3")
        .args(["-c", script, d.join("a").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
}

/// `--quiet`: nothing on stdout, no informational line (here: that an interrupted run goes on
/// to the next point where it can write a checkpoint), the error still printed.
#[test]
fn quiet_keeps_errors_and_drops_information() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let sc = restart_scenario(d);
    let o = run(d, &["run", &sc, "--out", "q", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(o.stdout.is_empty() && o.stderr.is_empty(), "{}", text(&o));
    let hook = [("COLLOIDSIM_INTERRUPT_AT_STEP", "123")];
    let o = run_env(d, &["run", &sc, "--out", "i", "--quiet"], &hook);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(!o.status.success() && o.stdout.is_empty(), "{}", text(&o));
    assert!(err.contains("error: interrupted at step 123"), "{err}");
    assert!(!err.contains("running on to step"), "{err}");
    let o = run_env(d, &["run", &sc, "--out", "v"], &hook);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("running on to step 160"),
        "{}",
        text(&o)
    );
}

/// DPD water (kT = 1) in a small box with the Green–Kubo viscosity observed.
fn water_viscosity(steps: u64, extra: &str) -> String {
    format!(
        "method = \"dpd\"\nseed = 5\n[system]\nbox_length = 6.0\nkT = 1.0\n[run]\ndt = 0.02\nsteps = {steps}\n[observe]\nthermo_every = 100\ntrajectory_every = 0\nstructure_every = 0\nmsd_every = 0\nviscosity_every = 2\nviscosity_time = 1.0\n{extra}"
    )
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn the_green_kubo_viscosity_is_written_with_its_error() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("w.toml"), water_viscosity(3000, "")).unwrap();
    let mut eta = Vec::new();
    for threads in ["1", "2"] {
        let out = format!("w{threads}");
        let o = run(
            d,
            &[
                "run",
                "w.toml",
                "--out",
                &out,
                "--quiet",
                "--threads",
                threads,
            ],
        );
        assert!(o.status.success(), "{}", text(&o));
        let s = summary(&d.join(&out));
        let (v, e) = (
            s["viscosity"].as_f64().unwrap(),
            s["viscosity_error"].as_f64().unwrap(),
        );
        // 120 DPD times of 648 beads: a rough number (the tests of crates/md measure it).
        assert!(v > 0.5 && v < 1.3 && e > 0.0 && e < 0.3 * v, "{v} +- {e}");
        assert!(s["viscosity_off_diagonal"].as_f64().is_some());
        assert!(
            s["viscosity_note"].as_str().unwrap().contains("Green-Kubo"),
            "{s}"
        );
        let theory = s["parameters"]["solvent_viscosity_kinetic_theory"]
            .as_f64()
            .unwrap();
        assert!((theory - 0.957_35).abs() < 1e-4, "{theory}");
        let (head, cols) =
            colloidsim_core::output::read_table(&d.join(&out).join("stress_acf.csv")).unwrap();
        assert_eq!(
            head,
            [
                "lag_steps",
                "time",
                "acf",
                "viscosity_integral",
                "acf_off_diagonal",
                "viscosity_integral_off_diagonal"
            ]
        );
        // 1.0 / (2 x 0.02) + 1 lags; the integral ends at the summary's viscosity.
        assert_eq!(cols[0].len(), 26);
        assert_eq!(cols[0][25], 50.0);
        let last = cols[3][25];
        assert!((last - v).abs() < 1e-6 * v, "{last} vs {v}");
        eta.push(std::fs::read(d.join(&out).join("stress_acf.csv")).unwrap());
    }
    assert!(d.join("w1/stress_acf.png").is_file());
    // The correlator is serial and the engine bitwise: the same for 1 and 2 threads.
    assert!(
        eta[0] == eta[1],
        "stress_acf.csv differs between 1 and 2 threads"
    );
    // Too short a run: the correlation function, but no viscosity, and the reason.
    std::fs::write(d.join("short.toml"), water_viscosity(600, "")).unwrap();
    let o = run(d, &["run", "short.toml", "--out", "short", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    let s = summary(&d.join("short"));
    assert!(s["viscosity"].is_null() && s["viscosity_error"].is_null());
    let note = s["viscosity_note"].as_str().unwrap();
    assert!(
        note.contains("not measured") && note.contains("1090 steps"),
        "{note}"
    );
    assert!(d.join("short/stress_acf.csv").is_file());
    // Off by default: no file, a null viscosity and a note.
    let plain = water_viscosity(200, "").replace("viscosity_every = 2\n", "");
    std::fs::write(d.join("off.toml"), plain).unwrap();
    let o = run(d, &["run", "off.toml", "--out", "off", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    let s = summary(&d.join("off"));
    assert!(s["viscosity"].is_null());
    assert!(
        s["viscosity_note"]
            .as_str()
            .unwrap()
            .contains("not observed"),
        "{s}"
    );
    assert!(!d.join("off/stress_acf.csv").exists());
}

#[test]
fn bad_viscosity_keys_are_refused_with_the_key() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    for (sc, want) in [
        // Shorter than one sample interval (2 x 0.02).
        (
            water_viscosity(100, "").replace("viscosity_time = 1.0", "viscosity_time = 0.01"),
            "observe.viscosity_time",
        ),
        (
            water_viscosity(100, "").replace("viscosity_time = 1.0", "viscosity_time = -1.0"),
            "observe.viscosity_time",
        ),
        // More than 100,000 lags.
        (
            water_viscosity(100, "").replace("viscosity_time = 1.0", "viscosity_time = 5000.0"),
            "observe.viscosity_time",
        ),
        (
            water_viscosity(100, "").replace("viscosity_every = 2", "viscosity_every = -2"),
            "observe.viscosity_every",
        ),
    ] {
        std::fs::write(d.join("bad.toml"), &sc).unwrap();
        let o = run(d, &["check", "bad.toml"]);
        assert!(!o.status.success(), "accepted: {sc}");
        assert!(text(&o).contains(want), "{want}: {}", text(&o));
    }
}

/// DPD water (kT = 1) under Lees–Edwards shear in a small box.
fn water_shear(steps: u64, extra: &str) -> String {
    format!(
        "method = \"dpd\"\nseed = 5\n[system]\nbox_length = 6.0\nkT = 1.0\n[run]\ndt = 0.02\nsteps = {steps}\nshear_rate = 0.5\n[observe]\nthermo_every = 50\ntrajectory_every = 0\nstructure_every = 0\nmsd_every = 0\nprofile_bins = 6\n{extra}"
    )
}

#[test]
fn a_shear_run_writes_its_viscosity_and_profile_and_restarts_bitwise() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("s.toml"), water_shear(2000, "")).unwrap();
    let o = run(d, &["run", "s.toml", "--out", "a", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    let s = summary(&d.join("a"));
    let (eta, err) = (
        s["shear_viscosity"].as_f64().unwrap(),
        s["shear_viscosity_error"].as_f64().unwrap(),
    );
    // 20 DPD times of 648 beads at gamma_dot = 0.5: a rough number (crates/md measures it).
    assert!(
        eta > 0.4 && eta < 1.4 && err > 0.0 && err < 0.5 * eta,
        "{eta} +- {err}"
    );
    let stress = s["shear_stress"].as_f64().unwrap();
    assert!((stress / 0.5 - eta).abs() < 1e-12 * eta);
    // Its parts sum to it; water has no colloid parts. The dissipative part lies below the
    // mean-field value of Marsh, Backx & Ernst, 2 pi gamma rho^2 rc^5 / 1575 = 0.1616 (g = 1;
    // the conservative repulsion thins the pairs at short range: 0.135 +- 0.0014 here), and
    // the kinetic part is the largest (gas-like DPD at kT = 1).
    let parts = &s["shear_stress_parts"];
    let part = |name: &str| parts[name]["stress"].as_f64().unwrap();
    let names = colloidsim_md::dpd::PRESSURE_PARTS;
    let sum: f64 = names.iter().map(|n| part(n)).sum();
    assert!(
        (sum - stress).abs() < 1e-9 * stress.abs(),
        "{sum} against {stress}"
    );
    for n in [
        "kinetic_colloid",
        "conservative_colloid",
        "dissipative_colloid",
        "contact",
        "morse",
        "lubrication",
    ] {
        assert_eq!(part(n), 0.0, "{n}");
    }
    let eta_d = part("dissipative_solvent") / 0.5;
    let marsh = 2.0 * std::f64::consts::PI * 4.5 * 9.0 / 1575.0;
    assert!(
        eta_d > 0.7 * marsh && eta_d < marsh,
        "{eta_d} against {marsh}"
    );
    assert!(
        names.iter().all(|n| part(n) <= part("kinetic_solvent")),
        "{parts}"
    );
    assert_eq!(s["shear_rate"].as_f64(), Some(0.5));
    assert!(
        s["shear_viscosity_note"]
            .as_str()
            .unwrap()
            .contains("second half")
    );
    let slope = s["velocity_profile_slope"].as_f64().unwrap();
    assert!((slope - 0.5).abs() < 0.1, "{slope}");
    let (head, cols) =
        colloidsim_core::output::read_table(&d.join("a/velocity_profile.csv")).unwrap();
    assert_eq!(
        head,
        [
            "y",
            "v_x",
            "v_x_imposed",
            "particle_samples",
            "profile_samples"
        ]
    );
    assert_eq!(cols[0].len(), 6);
    assert!((cols[2][0] - 0.5 * cols[0][0]).abs() < 1e-12);
    // Interrupted at step 700 (checkpoint at the next multiple of 200) and continued: the
    // same outputs, byte for byte.
    let o = run_env(
        d,
        &["run", "s.toml", "--out", "b", "--quiet"],
        &[("COLLOIDSIM_INTERRUPT_AT_STEP", "700")],
    );
    assert!(!o.status.success());
    let o = run(d, &["run", "s.toml", "--restart", "b", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_same_outputs(&d.join("a"), &d.join("b"), TIMING);
    // Without shear: no profile, null viscosity and a note.
    std::fs::write(
        d.join("n.toml"),
        water_shear(200, "").replace("shear_rate = 0.5", "shear_rate = 0.0"),
    )
    .unwrap();
    let o = run(d, &["run", "n.toml", "--out", "n", "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    let s = summary(&d.join("n"));
    assert!(s["shear_viscosity"].is_null());
    assert!(!d.join("n/velocity_profile.csv").exists());
    // Bad rates are refused naming the key.
    for bad in ["-0.5", "nan", "inf"] {
        let sc = water_shear(100, "").replace("shear_rate = 0.5", &format!("shear_rate = {bad}"));
        std::fs::write(d.join("bad.toml"), &sc).unwrap();
        let o = run(d, &["check", "bad.toml"]);
        assert!(!o.status.success(), "accepted: {bad}");
        assert!(text(&o).contains("run.shear_rate"), "{bad}: {}", text(&o));
    }
}
