//! End-to-end tests of `colloidsim run` on hs-mc scenarios: killed and interrupted runs continue
//! bitwise (every output file and summary.json the same), the examples are valid, and bad input
//! is refused with the key and its range.

use std::path::Path;
use std::process::{Command, Output};

use crate::common;
use common::{assert_same_outputs, text};

/// summary.json fields that depend on the session's timing.
const VOLATILE: &[&str] = &["wall_seconds", "trial_moves_per_second"];

/// The same for event chains.
const VOLATILE_CHAINS: &[&str] = &["wall_seconds", "lifts_per_second"];

/// 500 spheres at phi 0.3 in bulk, 500 warm-up and 600 sampling sweeps (checkpoints every 110).
const BULK: &str = r#"
method = "hs-mc"
seed = 5
[system]
geometry = "bulk"
particles = 500
volume_fraction = 0.3
[mc]
warmup_sweeps = 500
sweeps = 600
sample_every = 5
blocks = 6
[output]
gr_bins = 40
trajectory_every = 50
"#;

/// 300 spheres in the BD droplet's harmonic interface, R = 5 d.
const INTERFACE: &str = r#"
method = "hs-mc"
seed = 5
[system]
geometry = "interface"
particles = 300
radius = 5.0
[interface]
stiffness = 50.0
[mc]
warmup_sweeps = 500
sweeps = 600
sample_every = 5
blocks = 6
[output]
rho2_r_bins = 5
rho2_cos_bins = 4
"#;

fn run(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_colloidsim"));
    c.current_dir(dir).args(args);
    if args[0] == "run" {
        c.arg("--quiet");
    }
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().unwrap()
}

#[test]
fn killed_and_interrupted_runs_continue_bitwise() {
    for scenario in [BULK, INTERFACE] {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        std::fs::write(d.join("s.toml"), scenario).unwrap();
        let o = run(d, &["run", "s.toml", "--out", "a"], &[]);
        assert!(o.status.success(), "{}", text(&o));
        for (k, hook) in [
            ("k", "COLLOIDSIM_KILL_AT_STEP"),
            ("i", "COLLOIDSIM_INTERRUPT_AT_STEP"),
        ] {
            let o = run(d, &["run", "s.toml", "--out", k], &[(hook, "333")]);
            assert!(!o.status.success(), "{hook}: {}", text(&o));
            let o = run(d, &["run", "--restart", k], &[]);
            assert!(o.status.success(), "{}", text(&o));
            assert_same_outputs(&d.join("a"), &d.join(k), VOLATILE);
        }
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.join("a/summary.json")).unwrap()).unwrap();
        let acc = s["acceptance"].as_f64().unwrap();
        assert!((acc - 0.3).abs() < 0.05, "acceptance {acc} after tuning");
        if scenario == BULK {
            let z = &s["compressibility"];
            let (v, e) = (
                z["value"].as_f64().unwrap(),
                z["standard_error"].as_f64().unwrap(),
            );
            assert!(e > 0.0 && (v - 3.9738).abs() < 5.0 * e, "Z {v} +- {e}");
            assert!(d.join("a/g_r.csv").exists());
        } else {
            assert!(d.join("a/profile_mean.csv").exists() && d.join("a/g2.csv").exists());
        }
    }
}

/// Event chains (`mc.move = "event-chain"`) in bulk and in the hard-wall and interface
/// droplets: killed and interrupted runs continue bitwise; in bulk the exact event-chain
/// pressure is the summary's `compressibility` (Carnahan–Starling within 5 of its standard
/// errors, and the contact-value estimate kept beside it); the local moves' keys are refused
/// beside it, and `mc.chain_length` beside local moves.
#[test]
fn event_chain_runs_continue_bitwise_and_give_the_pressure() {
    let chain = "move = \"event-chain\"\nchain_length = 4.0\n";
    let wall = INTERFACE
        .replace("geometry = \"interface\"", "geometry = \"hard-wall\"")
        .replace("[interface]\nstiffness = 50.0\n", "");
    for scenario in [BULK, INTERFACE, &wall] {
        let scenario = scenario.replace("[mc]\n", &format!("[mc]\n{chain}"));
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        std::fs::write(d.join("s.toml"), &scenario).unwrap();
        let o = run(d, &["run", "s.toml", "--out", "a"], &[]);
        assert!(o.status.success(), "{}", text(&o));
        for (k, hook) in [
            ("k", "COLLOIDSIM_KILL_AT_STEP"),
            ("i", "COLLOIDSIM_INTERRUPT_AT_STEP"),
        ] {
            let o = run(d, &["run", "s.toml", "--out", k], &[(hook, "333")]);
            assert!(!o.status.success(), "{hook}: {}", text(&o));
            let o = run(d, &["run", "--restart", k], &[]);
            assert!(o.status.success(), "{}", text(&o));
            assert_same_outputs(&d.join("a"), &d.join(k), VOLATILE_CHAINS);
        }
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.join("a/summary.json")).unwrap()).unwrap();
        assert!(s.get("acceptance").is_none(), "{s}");
        assert!(s["event_chain"]["lifts"].as_u64().unwrap() > 0, "{s}");
        assert_eq!(s["parameters"]["chain_length"].as_f64(), Some(4.0));
        if scenario.contains("bulk") {
            let z = &s["compressibility"];
            let (v, e) = (
                z["value"].as_f64().unwrap(),
                z["standard_error"].as_f64().unwrap(),
            );
            assert!(e > 0.0 && (v - 3.9738).abs() < 5.0 * e, "Z {v} +- {e}");
            assert!(
                s["compressibility_from_contact"]["value"]
                    .as_f64()
                    .is_some()
            );
        } else {
            assert!(s["event_chain"]["reversals"].as_u64().unwrap() > 0, "{s}");
            assert!(d.join("a/profile_mean.csv").exists() && d.join("a/g2.csv").exists());
        }
    }
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    for (extra, key) in [
        ("move = \"event-chain\"\nnselect = 4\n", "mc.nselect"),
        ("chain_length = 2.0\n", "mc.chain_length"),
        (
            "move = \"event-chain\"\nchain_length = -1.0\n",
            "mc.chain_length",
        ),
        ("move = \"chains\"\n", "mc.move"),
    ] {
        std::fs::write(
            d.join("s.toml"),
            BULK.replace("[mc]\n", &format!("[mc]\n{extra}")),
        )
        .unwrap();
        let o = run(d, &["check", "s.toml"], &[]);
        assert!(!o.status.success(), "{extra}");
        assert!(text(&o).contains(key), "{extra}: {}", text(&o));
    }
}

#[test]
fn the_examples_are_valid() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/mc");
    for name in ["bulk.toml", "droplet-static.toml"] {
        let tmp = tempfile::tempdir().unwrap();
        let o = run(
            tmp.path(),
            &["check", root.join(name).to_str().unwrap()],
            &[],
        );
        assert!(o.status.success(), "{name}: {}", text(&o));
    }
}

/// Write a GSD frame with these positions (a starting configuration).
fn gsd_with(path: &Path, pos: Vec<[f64; 3]>) {
    use colloidsim_particles::gsd::GsdWriter;
    use colloidsim_particles::{Particles, SimBox};
    let mut w = GsdWriter::create_new(path).unwrap();
    w.write_frame(
        0,
        &SimBox::cube(20.0),
        &Particles::monodisperse(pos, 1.0),
        true,
        &[],
    )
    .unwrap();
    w.sync().unwrap();
}

#[test]
fn bad_input_is_refused_naming_the_key_and_range() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let wall = |extra: &str, mc: &str| {
        format!(
            "method = \"hs-mc\"\n[system]\ngeometry = \"hard-wall\"\nradius = 4.0\n{extra}\n[mc]\nsweeps = 1000\n{mc}\n"
        )
    };
    gsd_with(&d.join("overlap.gsd"), vec![[0.0; 3], [0.5, 0.0, 0.0]]);
    gsd_with(&d.join("outside.gsd"), vec![[0.0; 3], [3.7, 0.0, 0.0]]);
    let cases = [
        (
            wall("particles = 100", "target_acceptance = 1.0"),
            "mc.target_acceptance",
        ),
        (
            wall("particles = 100", "target_acceptance = 0.0"),
            "mc.target_acceptance",
        ),
        (wall("particles = 100", "nselect = 0"), "mc.nselect"),
        (wall("particles = 100", "nselect = 1001"), "mc.nselect"),
        (wall("volume_fraction = 0.7", ""), "system.volume_fraction"),
        (wall("particles = 400", ""), "random close packing"),
        (
            wall("particles = 2\ninitial = \"overlap.gsd\"", ""),
            "system.initial",
        ),
        (
            wall("particles = 2\ninitial = \"outside.gsd\"", ""),
            "beyond the allowed",
        ),
        (wall("particles = 100\nbox = 10.0", ""), "system.box"),
        (
            wall("particles = 100", "blocks = 200\nsample_every = 10"),
            "mc.blocks",
        ),
        (
            "method = \"hs-mc\"\n[system]\ngeometry = \"bulk\"\nparticles = 2\nbox = 1e7\n".into(),
            "more than this machine can give",
        ),
        (
            "method = \"hs-mc\"\n[system]\ngeometry = \"bulk\"\nparticles = 10\nbox = 1.5\n".into(),
            "system.",
        ),
        (
            wall("particles = 10\n[interface]\nstiffness = 5.0", ""),
            "interface",
        ),
    ];
    for (k, (scenario, want)) in cases.iter().enumerate() {
        let name = format!("bad{k}.toml");
        std::fs::write(d.join(&name), scenario).unwrap();
        let o = run(d, &["check", &name], &[]);
        let t = text(&o);
        assert!(!o.status.success(), "{scenario}: accepted");
        assert!(t.contains(want), "{scenario}: {t}");
        assert!(!t.contains("panicked"), "{t}");
    }
}
