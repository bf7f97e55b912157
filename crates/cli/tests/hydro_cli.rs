//! End-to-end tests of `colloidsim run` with hydrodynamics: droplets with RPY (direct and PSE)
//! restart bitwise after an interrupt or a kill (checked to fail when the checkpoint rounds the
//! positions to single precision), a Lanczos square root that does not converge stops the run
//! through the failure path, naming the step, and bad `[hydrodynamics]` input is refused before
//! anything is written.

use crate::common;
use common::{colloidsim as run, complete, files, p, restarts_bitwise, text};

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

/// 100 colloids with RPY by PSE in a box of two droplet diameters, 100 steps (main refuses
/// fewer than 100 drying steps).
const PSE: &str = r#"
method = "droplet-bd"
seed = 5
[system]
particles = 100
phi0 = 0.05
[drying]
peclet = 10
duration = 0.4
[run]
dt = 0.004
[observe]
profile = { bins = 8, fractions = [0, 1.0] }
[hydrodynamics]
model = "rpy"
method = "pse"
box_factor = 2.0
"#;

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
        VOLATILE,
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
        VOLATILE,
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
            "hydrodynamics.tolerance: must be a number in (0, 0.01]",
        ),
        (
            "tolerance = 0",
            "hydrodynamics.tolerance: must be a number in (0, 0.01]",
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

/// A static droplet (`drying.peclet = 0`) with RPY: the radius stays R0, and the mean of the
/// profiles after the start is written with its standard error; Pe < 0, and Pe = 0 with a final
/// volume fraction (never reached), are refused naming the key.
const STATIC: &str = r#"
method = "droplet-bd"
seed = 2
[system]
particles = 64
phi0 = 0.2
[drying]
peclet = 0
duration = 4.0
[run]
dt = 1.885e-3
[observe]
profile = { bins = 8, fractions = [0, 0.25, 0.5, 0.75, 1.0] }
[hydrodynamics]
model = "rpy"
"#;

#[test]
fn a_static_droplet_with_rpy_keeps_its_radius_and_writes_the_mean_profile() {
    let (_tmp, _sc, a) = complete("static", STATIC);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("summary.json")).unwrap()).unwrap();
    let par = &summary["parameters"];
    assert_eq!(par["hydrodynamics"]["method"], "direct");
    assert_eq!(summary["final_radius"], par["r0"]);
    assert_eq!(par["r_end"], par["r0"]);
    let mean = std::fs::read_to_string(a.join("profile_mean.csv")).unwrap();
    let mut lines = mean.lines();
    assert_eq!(lines.next(), Some("r,rho_v,rho_v_err"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 8);
    assert!(
        rows.iter()
            .all(|r| r[1] >= 0.0 && r[2].is_finite() && r[2] >= 0.0)
    );
    // The mean of the four later profiles, bin by bin.
    let later: Vec<Vec<f64>> = ["0.25", "0.50", "0.75", "1.00"]
        .iter()
        .map(|f| {
            std::fs::read_to_string(a.join(format!("profile_{f}.csv")))
                .unwrap()
                .lines()
                .skip(1)
                .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
                .collect()
        })
        .collect();
    for (b, r) in rows.iter().enumerate() {
        let m = later.iter().map(|p| p[b]).sum::<f64>() / 4.0;
        assert!((r[1] - m).abs() < 1e-12, "bin {b}: {} vs {m}", r[1]);
    }
    let tmp = tempfile::tempdir().unwrap();
    for (change, key) in [
        ("peclet = -1", "drying.peclet"),
        (
            "peclet = 0\nfinal_volume_fraction = 0.3",
            "drying.final_volume_fraction",
        ),
    ] {
        let text_ = STATIC.replace("peclet = 0\nduration = 4.0", change);
        let sc = tmp.path().join("bad.toml");
        std::fs::write(&sc, &text_).unwrap();
        let out = tmp.path().join("never");
        let o = run(&[p("run"), &sc, p("--out"), &out], &[]);
        assert!(!o.status.success());
        assert!(text(&o).contains(key), "{change}: {}", text(&o));
        assert!(!out.exists());
    }
}
