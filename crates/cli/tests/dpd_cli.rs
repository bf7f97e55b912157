//! End-to-end tests of `colloidsim run|check` on DPD scenarios.

use std::path::Path;
use std::process::{Command, Output};

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

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
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
        ("[observe]\nfoo = 1\n", "unknown field"),
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
