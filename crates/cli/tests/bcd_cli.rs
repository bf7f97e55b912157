//! End-to-end tests of `colloidsim run|theory|check` on BCD scenarios.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common;
use common::text;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_colloidsim"))
}

fn write_scenario(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const SMALL: &str = r#"
method = "bcd"
seed = 5
[system]
length = 20.0
particles = 10
diameter = 0.5
[potential]
cosine = { amplitude = 6.0, wavelength = 1.0 }
[run]
dt = 1e-3
equilibrate = 0.5
time = 5.0
checkpoint_every = 1000
[observe]
density = { bins = 50 }
contact_density = { bins = 50, window = 0.15 }
msd = { points = 10 }
clusters = true
current = true
trajectory = { every = 500 }
"#;

fn run(args: &[&str]) -> Output {
    let o = bin().args(args).output().unwrap();
    eprintln!(
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

#[test]
fn run_writes_documented_outputs_and_refuses_to_overwrite() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = write_scenario(tmp.path(), "small.toml", SMALL);
    let out = tmp.path().join("out");
    let o = run(&[
        "run",
        sc.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success());
    for f in [
        "summary.json",
        "density.csv",
        "density_theory.csv",
        "density.png",
        "contact_density.csv",
        "contact_density_theory.csv",
        "contact_density.png",
        "msd.csv",
        "msd.png",
        "current.csv",
        "current.png",
        "clusters.csv",
        "trajectory.gsd",
        "final_configuration.csv",
    ] {
        assert!(out.join(f).exists(), "missing {f}");
    }
    let head = |f: &str| {
        std::fs::read_to_string(out.join(f))
            .unwrap()
            .lines()
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(head("density.csv"), "x,rho,err");
    assert_eq!(head("contact_density.csv"), "x,rho2,err");
    assert_eq!(head("contact_density_theory.csv"), "x,rho2,rho2_window");
    assert_eq!(head("msd.csv"), "t,msd,err");
    assert_eq!(head("clusters.csv"), "size,probability");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["steps"], 5500);
    assert_eq!(summary["seed"], 5);
    assert!(summary["particle_steps_per_second"].as_f64().unwrap() > 0.0);
    assert!(summary["wall_seconds"].as_f64().unwrap() > 0.0);
    // Mean of the density profile is N / L.
    let rho: Vec<f64> = std::fs::read_to_string(out.join("density.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    let mean = rho.iter().sum::<f64>() / rho.len() as f64;
    assert!((mean - 0.5).abs() < 1e-9, "{mean}");

    let before = std::fs::read(out.join("density.csv")).unwrap();
    let o = run(&[
        "run",
        sc.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(!o.status.success());
    assert!(text(&o).contains("already exists"), "{}", text(&o));
    assert_eq!(std::fs::read(out.join("density.csv")).unwrap(), before);
}

#[test]
fn interrupted_run_restarts_bitwise() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = write_scenario(tmp.path(), "small.toml", SMALL);
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    assert!(
        run(&[
            "run",
            sc.to_str().unwrap(),
            "--out",
            a.to_str().unwrap(),
            "--quiet"
        ])
        .status
        .success()
    );
    let o = bin()
        .args([
            "run",
            sc.to_str().unwrap(),
            "--out",
            b.to_str().unwrap(),
            "--quiet",
        ])
        .env("COLLOIDSIM_INTERRUPT_AT_STEP", "2345")
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        text(&o).contains("interrupted at step 2345"),
        "{}",
        text(&o)
    );
    assert!(!b.join("summary.json").exists());
    let o = run(&[
        "run",
        sc.to_str().unwrap(),
        "--restart",
        b.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success());
    for f in [
        "final_configuration.csv",
        "density.csv",
        "contact_density.csv",
        "msd.csv",
        "clusters.csv",
        "current.csv",
    ] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f} differs after restart"
        );
    }
    // A different scenario cannot continue this run.
    let other = write_scenario(
        tmp.path(),
        "other.toml",
        &SMALL.replace("seed = 5", "seed = 6"),
    );
    let o = run(&[
        "run",
        other.to_str().unwrap(),
        "--restart",
        b.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
}

/// Read `out/trajectory.gsd` with the `gsd` package and run `checks` (Python, with `t` the
/// trajectory, `f` its last frame, `x` the final configuration's positions and `gsd`, `np`
/// imported) on it.
fn check_gsd(out: &Path, checks: &str) {
    let script = format!(
        r#"
import sys, gsd.hoomd, gsd.fl, numpy as np
with gsd.fl.open(sys.argv[1], 'r') as fl:
    application = fl.application
t = gsd.hoomd.open(sys.argv[1], 'r')
f = t[-1]
x = np.loadtxt(sys.argv[2], delimiter=',', skiprows=1, ndmin=1)
{checks}
print('gsd ok', len(t))
"#
    );
    let o = Command::new("python3")
        .args([
            "-c",
            &script,
            out.join("trajectory.gsd").to_str().unwrap(),
            out.join("final_configuration.csv").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
}

/// The trajectory looks like one HOOMD-blue writes: colloidsim as the application, types
/// and typeids, positions in the box with their images (position + image L is the rod's
/// unwrapped position), frames from the first production step (step 500) unless the
/// equilibration is asked for; between walls a box twice as long, images zero and the walls
/// logged.
#[test]
fn gsd_trajectory_is_readable_by_the_gsd_package() {
    if !colloidsim_core::tools::python_module_or_skip(
        "gsd.hoomd",
        "gsd_trajectory_is_readable_by_the_gsd_package",
    ) {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let sc = write_scenario(tmp.path(), "small.toml", SMALL);
    let go = |name: &str, set: &[&str]| {
        let out = tmp.path().join(name);
        let mut args = vec!["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.push("--quiet");
        for s in set {
            args.extend(["--set", s]);
        }
        assert!(run(&args).status.success());
        out
    };
    let common = r#"
assert application == 'colloidsim ' + application.split()[-1] and application.split()[-1][0].isdigit(), application
assert f.configuration.step == 5500, f.configuration.step
assert f.particles.N == 10
assert f.configuration.dimensions == 2
assert list(f.particles.types) == ['rod'], f.particles.types
assert np.all(f.particles.typeid == 0)
assert np.allclose(f.particles.diameter, 0.5)
assert 'particles/x_unwrapped' not in f.log, list(f.log)
L = f.configuration.box[0]
assert np.all(f.particles.position[:, 0] >= -L / 2) and np.all(f.particles.position[:, 0] < L / 2)
assert np.all(f.particles.position[:, 1:] == 0) and np.all(f.particles.image[:, 1:] == 0)
"#;
    let ring = go("ring", &[]);
    check_gsd(
        &ring,
        &format!(
            "{common}
assert len(t) == 11, len(t)
assert [s.configuration.step for s in t] == list(range(500, 5501, 500))
assert L == 20.0, L
xu = f.particles.position[:, 0] + f.particles.image[:, 0] * L
assert np.allclose(xu, x, atol=1e-4), (xu, x)
assert np.any(np.concatenate([s.particles.image[:, 0] for s in t]) != 0)
assert 'bcd/walls' not in f.log
"
        ),
    );
    let warmup = go("warmup", &["observe.trajectory.equilibration=true"]);
    check_gsd(
        &warmup,
        &format!(
            "{common}
assert [s.configuration.step for s in t] == list(range(0, 5501, 500)), [s.configuration.step for s in t]
"
        ),
    );
    let walls = go("walls", &["system.boundary=\"walls\""]);
    check_gsd(
        &walls,
        &format!(
            "{common}
assert L == 40.0, L
assert np.all(f.particles.image == 0)
assert np.allclose(f.particles.position[:, 0] + 10.0, x, atol=1e-4)
assert np.allclose(f.log['bcd/walls'], [-10.0, 10.0]), f.log['bcd/walls']
"
        ),
    );
}

#[test]
fn bad_input_is_refused_with_the_key() {
    let tmp = tempfile::tempdir().unwrap();
    let cases = [
        (
            SMALL.replace("diameter = 0.5", "diameter = 0.5\ncolour = 1"),
            "colour",
        ),
        (
            SMALL.replace("particles = 10", "particles = 40"),
            "system.particles",
        ),
        (SMALL.replace("dt = 1e-3", "dt = -1e-3"), "run.dt"),
        (
            SMALL.replace("length = 20.0", "length = 20.5"),
            "whole number of potential periods",
        ),
        (SMALL.replace("seed = 5", "seed = 99999999999"), "seed"),
        (
            SMALL.replace("bins = 50 }\ncontact", "bins = 0 }\ncontact"),
            "observe.density.bins",
        ),
        (
            SMALL.replace(
                "[run]",
                "[interaction]\nsticky = { gamma = 1.0, range = 0.001 }\n[run]",
            ),
            "run.dt",
        ),
    ];
    for (k, (sc, key)) in cases.iter().enumerate() {
        let p = write_scenario(tmp.path(), &format!("bad{k}.toml"), sc);
        for cmd in ["check", "run"] {
            let out = tmp.path().join(format!("out{k}"));
            let o = run(&[cmd, p.to_str().unwrap(), "--out", out.to_str().unwrap()]
                [..if cmd == "check" { 2 } else { 4 }]);
            assert!(!o.status.success(), "case {k} accepted");
            assert!(
                text(&o).contains(key),
                "case {k}: '{key}' not in {}",
                text(&o)
            );
            assert!(!out.join("summary.json").exists());
        }
    }
    // Overlapping positions in an input file name the rods.
    std::fs::write(tmp.path().join("pos.csv"), "x\n1.0\n1.2\n").unwrap();
    let sc = SMALL.replace("particles = 10", "particles = 2").replace(
        "[run]",
        "[initial]\nplacement = \"file\"\nfile = \"pos.csv\"\n[run]",
    );
    let p = write_scenario(tmp.path(), "overlap.toml", &sc);
    let o = run(&["check", p.to_str().unwrap()]);
    assert!(
        !o.status.success() && text(&o).contains("overlap"),
        "{}",
        text(&o)
    );
}

#[test]
fn theory_writes_converged_profiles_on_the_simulation_bins() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = write_scenario(tmp.path(), "small.toml", SMALL);
    let out = tmp.path().join("th");
    let o = run(&[
        "theory",
        sc.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(s["residual"].as_f64().unwrap() < 1e-10);
    let rows = std::fs::read_to_string(out.join("density.csv")).unwrap();
    assert_eq!(rows.lines().count(), 51);
    // A driven system has no equilibrium: the theory is the DDFT's steady state, with its
    // current (crates/run/tests/theory_driven.rs checks the numbers).
    let driven = write_scenario(
        tmp.path(),
        "driven.toml",
        &SMALL.replace("[potential]", "[potential]\ndrive = 0.5"),
    );
    let d = tmp.path().join("d");
    let o = run(&[
        "theory",
        driven.to_str().unwrap(),
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("DDFT steady state"), "{}", text(&o));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap()).unwrap();
    assert!(s["mean_current"].as_f64().unwrap() > 0.0);
    assert_eq!(s["converged"], true);
    // A driven run draws that steady state beside its density, on the same bins.
    let dr = tmp.path().join("dr");
    let o = run(&[
        "run",
        driven.to_str().unwrap(),
        "--out",
        dr.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(dr.join("density.png").exists());
    let ddft = columns(&dr.join("density_ddft.csv"));
    let theory = columns(&d.join("density.csv"));
    assert_eq!(ddft[1].len(), 50);
    for (a, b) in ddft[1].iter().zip(&theory[1]) {
        assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} vs {b}");
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dr.join("summary.json")).unwrap()).unwrap();
    assert!(s["ddft"]["mean_current"].as_f64().unwrap() > 0.0, "{s}");
    assert!(!dr.join("density_theory.csv").exists());
}

/// Columns of a CSV file (after its header) as numbers.
fn columns(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (0..rows[0].len())
        .map(|j| rows.iter().map(|r| r[j]).collect())
        .collect()
}

/// The density's block standard errors (density.csv's `err`) are sane: the exact profile lies
/// within 4 of them in nearly every bin of a run that samples its equilibrium (low barriers),
/// and a run 4 times longer has errors about half as large.
#[test]
fn density_errors_cover_the_exact_profile_and_shrink_with_the_run() {
    let tmp = tempfile::tempdir().unwrap();
    let text_of = |time: f64| {
        SMALL
            .replace("amplitude = 6.0", "amplitude = 1.0")
            .replace("time = 5.0", &format!("time = {time}"))
            .replace("checkpoint_every = 1000", "")
            .replace("particles = 10", "particles = 20")
            .replace(
                "density = { bins = 50 }",
                "density = { bins = 20 }\nevery = 10",
            )
    };
    let mut mean_err = Vec::new();
    for time in [50.0, 200.0] {
        let sc = write_scenario(tmp.path(), &format!("t{time}.toml"), &text_of(time));
        let out = tmp.path().join(format!("out{time}"));
        let o = run(&[
            "run",
            sc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", text(&o));
        let d = columns(&out.join("density.csv"));
        let t = columns(&out.join("density_theory.csv"));
        let (rho, err, exact) = (&d[1], &d[2], &t[1]);
        assert!(err.iter().all(|e| e.is_finite() && *e > 0.0), "{err:?}");
        let within = (0..rho.len())
            .filter(|&a| (rho[a] - exact[a]).abs() < 4.0 * err[a])
            .count();
        assert!(
            within >= rho.len() - 1,
            "{within} of {} bins within 4 SE",
            rho.len()
        );
        mean_err.push(err.iter().sum::<f64>() / err.len() as f64);
        let c = columns(&out.join("contact_density.csv"));
        assert!(
            c[2].iter().all(|e| e.is_finite() && *e >= 0.0),
            "{:?}",
            c[2]
        );
    }
    let ratio = mean_err[0] / mean_err[1];
    assert!(
        (1.4..2.8).contains(&ratio),
        "errors shrank by {ratio} over a 4 times longer run"
    );
}

/// A run large enough that the density is binned in parts over the workers (10,000 rods) writes
/// the same density.csv and contact_density.csv, errors included, on 1 and 2 threads.
#[test]
fn density_errors_are_the_same_on_one_and_two_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let scenario = SMALL
        .replace("length = 20.0", "length = 20000.0")
        .replace("particles = 10", "particles = 10000")
        .replace("time = 5.0", "time = 1.0")
        .replace("equilibrate = 0.5", "equilibrate = 0.1")
        .replace("checkpoint_every = 1000", "")
        .replace("trajectory = { every = 500 }", "")
        .replace("msd = { points = 10 }", "")
        .replace(
            "density = { bins = 50 }",
            "density = { bins = 50 }\nevery = 10",
        );
    let sc = write_scenario(tmp.path(), "big.toml", &scenario);
    let mut outs = Vec::new();
    for threads in ["1", "2"] {
        let out = tmp.path().join(format!("t{threads}"));
        let o = run(&[
            "run",
            sc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--threads",
            threads,
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", text(&o));
        outs.push(out);
    }
    for f in ["density.csv", "contact_density.csv"] {
        let a = std::fs::read(outs[0].join(f)).unwrap();
        assert_eq!(a, std::fs::read(outs[1].join(f)).unwrap(), "{f}");
        assert!(!String::from_utf8_lossy(&a).contains("NaN"), "{f}");
    }
}

/// `--threads 100000` started a pool of 100,000 OS threads (run, extrapolate, ensemble): now
/// refused above 8 per core (and 4096) before any thread starts or any output is written.
#[test]
fn thread_counts_beyond_the_bound_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = write_scenario(tmp.path(), "small.toml", SMALL);
    let out = tmp.path().join("out");
    for cmd in ["run", "extrapolate", "ensemble"] {
        let o = run(&[
            cmd,
            sc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--threads",
            "100000",
        ]);
        assert!(!o.status.success());
        let t = text(&o);
        assert!(
            t.contains("--threads 100000: at most") && t.contains("per available core"),
            "{cmd}: {t}"
        );
        assert!(!out.exists(), "{cmd}");
    }
}

/// `colloidsim check` prints the scenario's keys with their values and units, defaults
/// marked, not the engine's names; `--json` the resolved parameters.
#[test]
fn check_prints_keys_values_and_units() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = write_scenario(tmp.path(), "small.toml", SMALL);
    let o = run(&["check", sc.to_str().unwrap(), "--set", "run.dt=2e-3"]);
    assert!(o.status.success());
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    let line = |key: &str| {
        out.lines()
            .find(|l| l.starts_with(&format!("{key} ")))
            .unwrap_or_else(|| panic!("no {key} in\n{out}"))
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    };
    assert_eq!(
        line("system.length"),
        "system.length = 20.0 length",
        "{out}"
    );
    assert_eq!(line("run.dt"), "run.dt = 0.002 time", "{out}");
    assert!(line("system.boundary").ends_with("(default)"), "{out}");
    assert!(
        line("observe.trajectory.every").contains("= 500 steps"),
        "{out}"
    );
    assert!(!out.contains("vectorised") && !out.contains('{'), "{out}");
    let o = run(&["check", sc.to_str().unwrap(), "--json"]);
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    let v: serde_json::Value = serde_json::from_str(&out[..=out.rfind('}').unwrap()]).unwrap();
    assert_eq!(v["run"]["dt"], 1e-3);
}

/// `check` prints the run's estimated cost after validating it, in a temporary folder of its
/// own that it removes; `--no-estimate` and `--json` leave it out.
#[test]
fn check_estimates_the_cost_and_leaves_nothing_behind() {
    let tmp = tempfile::tempdir().unwrap();
    let scratch = tempfile::tempdir().unwrap();
    let sc = write_scenario(tmp.path(), "small.toml", SMALL);
    let check = |extra: &[&str]| {
        let o = bin()
            .args(["check", sc.to_str().unwrap()])
            .args(extra)
            .env("TMPDIR", scratch.path())
            .current_dir(tmp.path())
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", text(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let out = check(&[]);
    // 500 equilibration steps and 5000 of the run.
    assert!(
        out.contains("estimate: about") && out.contains("of 5500"),
        "{out}"
    );
    assert!(!check(&["--no-estimate"]).contains("estimate"));
    assert!(!check(&["--json"]).contains("estimate"));
    assert_eq!(std::fs::read_dir(scratch.path()).unwrap().count(), 0);
    let mut left: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    left.sort();
    assert_eq!(left, ["small.toml"]);
}
