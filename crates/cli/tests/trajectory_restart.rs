//! A restart continues `trajectory.gsd` only if its frames are those the checkpoint saw: the
//! frames written after the last checkpoint of a killed run are dropped (the continuation is
//! byte-identical to an uninterrupted run), and a frame damaged since the checkpoint is refused,
//! for every method.

use std::path::Path;
use std::process::{Command, Output};

mod common;
use common::text;

const BCD: &str = r#"
method = "bcd"
seed = 3
[system]
length = 100.0
particles = 50
diameter = 1.0
[run]
dt = 0.001
time = 20.0
checkpoint_every = 3000
[observe]
every = 10
density = { bins = 50 }
trajectory = { every = 1000 }
"#;

const DROPLET: &str = r#"
method = "droplet-bd"
seed = 3
replicas = 2
[system]
particles = 200
phi0 = 0.05
[drying]
peclet = 10
duration = 1.2
[run]
dt = 0.004
[observe]
profile = { bins = 10, fractions = [0, 0.5, 1.0] }
trajectory = { every = 20 }
"#;

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
trajectory_every = 30
msd_every = 20
structure_every = 100
"#;

const MC: &str = r#"
method = "hs-mc"
seed = 3
[system]
geometry = "hard-wall"
particles = 150
radius = 4.0
[mc]
warmup_sweeps = 100
sweeps = 400
sample_every = 5
blocks = 4
[output]
trajectory_every = 25
"#;

/// (scenario, step to kill at: after a checkpoint, with frames written since it).
const CASES: [(&str, &str); 4] = [(BCD, "10500"), (DROPLET, "170"), (DPD, "235"), (MC, "235")];

fn run(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_colloidsim"));
    c.current_dir(dir).args(args).arg("--quiet");
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().unwrap()
}

/// Flip the lowest bit of one coordinate of frame `frame` in a GSD file.
fn damage_position(path: &Path, frame: u64) {
    use hoomd_gsd::file_layer::{GsdFile, Mode};
    let x = {
        let f = GsdFile::open(path, Mode::Read).unwrap();
        f.iter_arrays::<f32, 3>(frame, "particles/position")
            .unwrap()
            .flatten()
            .find(|c| c.abs() > 0.1)
            .unwrap()
    };
    let mut bytes = std::fs::read(path).unwrap();
    let pat = x.to_le_bytes();
    let at = (256..bytes.len() - 4)
        .find(|&i| bytes[i..i + 4] == pat)
        .unwrap();
    bytes[at] ^= 1;
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn killed_runs_continue_their_trajectory_exactly_and_refuse_a_damaged_one() {
    for (scenario, kill_at) in CASES {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        std::fs::write(d.join("s.toml"), scenario).unwrap();
        let o = run(d, &["run", "s.toml", "--out", "a"], &[]);
        assert!(o.status.success(), "{}", text(&o));
        for k in ["k", "damaged"] {
            let o = run(
                d,
                &["run", "s.toml", "--out", k],
                &[("COLLOIDSIM_KILL_AT_STEP", kill_at)],
            );
            assert!(!o.status.success(), "{}", text(&o));
            assert!(d.join(k).join("checkpoint.bin").exists());
        }
        let o = run(d, &["run", "--restart", "k"], &[]);
        assert!(o.status.success(), "{}", text(&o));
        assert_eq!(
            std::fs::read(d.join("a/trajectory.gsd")).unwrap(),
            std::fs::read(d.join("k/trajectory.gsd")).unwrap(),
            "{scenario}"
        );
        // One bit of one position of frame 1, before the checkpoint.
        damage_position(&d.join("damaged/trajectory.gsd"), 1);
        let o = run(d, &["run", "--restart", "damaged"], &[]);
        let t = text(&o);
        assert!(!o.status.success(), "{t}");
        assert!(
            t.contains("trajectory.gsd") && t.contains("differ from those the checkpoint"),
            "{t}"
        );
        assert!(!d.join("damaged/summary.json").exists());
    }
}
