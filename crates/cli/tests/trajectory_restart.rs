//! A restart continues `trajectory.gsd` only if its frames are those the checkpoint saw: the
//! frames written after the last checkpoint of a killed run are dropped (the continuation is
//! byte-identical to an uninterrupted run), and a frame damaged since the checkpoint (a flipped
//! bit in any of its chunks) is refused, for every method.

use std::path::Path;
use std::process::{Command, Output};

use crate::common;
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

/// Scenarios of every method that writes a trajectory, with a frame every step or two, so that
/// the GSD index and name list grow (move to the end of the file) between checkpoints; and
/// where to interrupt and where to kill each: after an index growth, with frames written since
/// the last checkpoint.
const MANY_FRAMES: [(&str, &str, &str, &str); 7] = [
    (
        "bcd",
        r#"
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
trajectory = { every = 100 }
"#,
        "5750",
        "10500",
    ),
    (
        "dpd",
        r#"
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
trajectory_every = 4
msd_every = 20
structure_every = 100
"#,
        "135",
        "235",
    ),
    (
        "droplet-bd",
        r#"
method = "droplet-bd"
seed = 3
replicas = 2
[system]
particles = 50
phi0 = 0.05
[drying]
peclet = 10
duration = 1.2
[run]
dt = 0.004
[observe]
profile = { bins = 10, fractions = [0, 0.5, 1.0] }
trajectory = { every = 2 }
"#,
        "25",
        "170",
    ),
    (
        "bd",
        r#"
method = "bd"
seed = 4
[system]
particles = 20
box_length = 7.0
[run]
dt = 0.005
time = 2.0
integrator = "lm"
[observe.trajectory]
every = 2
"#,
        "75",
        "235",
    ),
    (
        "mpcd",
        r#"
method = "mpcd"
seed = 6
[system]
box = 6
colloids = 2
diameter = 2
[run]
collisions = 400
equilibrate = 100
[observe]
every = 10
[observe.trajectory]
every = 2
"#,
        "175",
        "235",
    ),
    (
        "droplet-mpcd",
        r#"
method = "droplet-mpcd"
seed = 4
boundary = "no-slip"
[system]
particles = 3
diameter = 2
radius = 5
[drying]
peclet = 10
duration = 30
[observe.trajectory]
every = 2
"#,
        "75",
        "175",
    ),
    (
        "hs-mc",
        r#"
method = "hs-mc"
seed = 3
[system]
geometry = "hard-wall"
particles = 50
radius = 4.0
[mc]
warmup_sweeps = 100
sweeps = 400
sample_every = 5
blocks = 4
[output]
trajectory_every = 2
"#,
        "235",
        "235",
    ),
];

/// Interrupted (as by Ctrl-C) or killed, and continued with --restart, every method writes the
/// trajectory of the uninterrupted run byte for byte, index and name list included (before,
/// the layout followed when the file was synced: a checkpoint at an interrupt, or the trim of
/// a killed run's file, moved the index, up to 8 % larger).
#[test]
fn restarted_trajectories_are_byte_identical_for_every_method() {
    for (method, scenario, interrupt, kill) in MANY_FRAMES {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        std::fs::write(d.join("s.toml"), scenario).unwrap();
        let o = run(d, &["run", "s.toml", "--out", "a"], &[]);
        assert!(o.status.success(), "{method}: {}", text(&o));
        let a = std::fs::read(d.join("a/trajectory.gsd")).unwrap();
        for (k, hook, at) in [
            ("i", "COLLOIDSIM_INTERRUPT_AT_STEP", interrupt),
            ("k", "COLLOIDSIM_KILL_AT_STEP", kill),
        ] {
            let o = run(d, &["run", "s.toml", "--out", k], &[(hook, at)]);
            assert!(!o.status.success(), "{method} {hook}: {}", text(&o));
            let o = run(d, &["run", "--restart", k], &[]);
            assert!(o.status.success(), "{method} {hook}: {}", text(&o));
            let b = std::fs::read(d.join(k).join("trajectory.gsd")).unwrap();
            assert!(
                a == b,
                "{method}: {hook}={at}: trajectory.gsd differs after the restart ({} bytes, \
                 uninterrupted {})",
                b.len(),
                a.len()
            );
        }
    }
}

/// One bit flipped in any chunk of a frame before the checkpoint (every chunk name the frame
/// has: step, box, N, types, typeid, diameter, position, image, velocity, mass, logs) is refused
/// at --restart, for a method of each family.
#[test]
fn a_flipped_bit_in_any_chunk_of_a_frame_is_refused() {
    use colloidsim_particles::gsd::GsdIndex;
    for method in ["dpd", "droplet-bd", "mpcd"] {
        let (_, scenario, _, kill) = MANY_FRAMES.iter().find(|c| c.0 == method).unwrap();
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        std::fs::write(d.join("s.toml"), scenario).unwrap();
        let o = run(
            d,
            &["run", "s.toml", "--out", "k"],
            &[("COLLOIDSIM_KILL_AT_STEP", kill)],
        );
        assert!(!o.status.success(), "{method}: {}", text(&o));
        let traj = d.join("k/trajectory.gsd");
        let clean = std::fs::read(&traj).unwrap();
        let g = GsdIndex::open(&traj).unwrap();
        let mut names = Vec::new();
        for e in g.frames(1, 2) {
            let name = g.names[e.id as usize].clone();
            let bytes = e.bytes().unwrap();
            if bytes == 0 {
                continue;
            }
            // The last byte's lowest bit: a type name's terminator, a mass, an image...
            let mut b = clean.clone();
            b[(e.location + bytes - 1) as usize] ^= 1;
            std::fs::write(&traj, &b).unwrap();
            let o = run(d, &["run", "--restart", "k"], &[]);
            let t = text(&o);
            assert!(
                !o.status.success(),
                "{method}: a flip in {name} accepted: {t}"
            );
            assert!(
                t.contains("trajectory.gsd") && t.contains("differ from those the checkpoint"),
                "{method}: {name}: {t}"
            );
            assert!(!d.join("k/summary.json").exists());
            names.push(name);
        }
        for must in [
            "configuration/step",
            "configuration/box",
            "particles/N",
            "particles/types",
            "particles/typeid",
            "particles/diameter",
            "particles/position",
            "particles/image",
        ] {
            assert!(
                names.iter().any(|n| n == must),
                "{method}: {must} not tried"
            );
        }
        if method != "droplet-bd" {
            assert!(names.iter().any(|n| n == "particles/mass"), "{method}");
            assert!(names.iter().any(|n| n == "particles/velocity"), "{method}");
        }
        // Undamaged, the same folder continues.
        std::fs::write(&traj, &clean).unwrap();
        let o = run(d, &["run", "--restart", "k"], &[]);
        assert!(o.status.success(), "{method}: {}", text(&o));
    }
}
