//! Helpers shared by the end-to-end tests of the `colloidsim` binary.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Standard output and standard error of a finished command, together.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Every file of a folder, by name.
pub fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// summary.json without the fields in `volatile` (each must be present).
fn summary(bytes: &[u8], volatile: &[&str]) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
    let m = v.as_object_mut().unwrap();
    for k in volatile {
        assert!(m.remove(*k).is_some(), "summary.json has no {k}");
    }
    v
}

/// The same files in `a` and `b`, byte for byte, except the `volatile` fields of summary.json.
pub fn assert_same_outputs(a: &Path, b: &Path, volatile: &[&str]) {
    let (fa, fb) = (files(a), files(b));
    assert_eq!(
        fa.keys().collect::<Vec<_>>(),
        fb.keys().collect::<Vec<_>>(),
        "different files"
    );
    for (name, bytes) in &fa {
        if name == "summary.json" {
            assert_eq!(
                summary(bytes, volatile),
                summary(&fb[name], volatile),
                "summary.json differs"
            );
        } else {
            assert!(bytes == &fb[name], "{name} differs after restart");
        }
    }
}

/// Run the `colloidsim` binary with `args` (and `--quiet`) and the environment variables `env`;
/// its output is echoed for a failing test.
pub fn colloidsim(args: &[&Path], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_colloidsim"));
    c.args(args).arg("--quiet");
    for (k, v) in env {
        c.env(k, v);
    }
    let o = c.output().unwrap();
    eprintln!("{}", text(&o));
    o
}

/// A path argument from text.
pub fn p(s: &str) -> &Path {
    Path::new(s)
}

/// Write `scenario` as NAME.toml in a temporary folder and run it to completion into `NAME`:
/// (the folder, the scenario file, the run folder).
pub fn complete(name: &str, scenario: &str) -> (tempfile::TempDir, PathBuf, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join(format!("{name}.toml"));
    std::fs::write(&sc, scenario).unwrap();
    let a = tmp.path().join(name);
    let o = colloidsim(&[p("run"), &sc, p("--out"), &a], &[]);
    assert!(o.status.success());
    (tmp, sc, a)
}

/// Interrupted (as by Ctrl-C) or killed without a checkpoint at each position of `stops`
/// (`(hook, step)`), the run of `sc` continues with `--restart` to the same files as the
/// uninterrupted run in `a`, but for the `volatile` fields of summary.json.
pub fn restarts_bitwise(
    tmp: &Path,
    sc: &Path,
    a: &Path,
    stops: &[(&str, &str)],
    volatile: &[&str],
) {
    for (hook, at) in stops {
        let b = tmp.join(format!("b-{hook}-{at}"));
        let o = colloidsim(&[p("run"), sc, p("--out"), &b], &[(hook, at)]);
        assert!(!o.status.success());
        assert!(b.join("checkpoint.bin").exists(), "{hook} {at}");
        assert!(!b.join("summary.json").exists());
        let o = colloidsim(&[p("run"), sc, p("--restart"), &b], &[]);
        assert!(o.status.success());
        assert_same_outputs(a, &b, volatile);
    }
}

/// Every file under `dir`, by path relative to it.
fn tree(dir: &Path, rel: &str, out: &mut Vec<(String, Vec<u8>)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir.join(rel))
        .unwrap()
        .map(|e| e.unwrap())
        .collect();
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let name = format!("{rel}{}", e.file_name().to_string_lossy());
        if e.file_type().unwrap().is_dir() {
            tree(dir, &format!("{name}/"), out);
        } else {
            out.push((name, std::fs::read(e.path()).unwrap()));
        }
    }
}

/// Two folder trees (ensembles) hold the same files, byte for byte, but for the timings in
/// the `summary.json` files (`threads`, `*seconds`, `*_per_second`).
pub fn assert_same_tree(a: &Path, b: &Path) {
    let (mut ta, mut tb) = (Vec::new(), Vec::new());
    tree(a, "", &mut ta);
    tree(b, "", &mut tb);
    let names = |t: &[(String, Vec<u8>)]| t.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&ta), names(&tb));
    for ((name, x), (_, y)) in ta.iter().zip(&tb) {
        if name.ends_with("summary.json") {
            let strip = |b: &[u8]| {
                let mut v: serde_json::Value = serde_json::from_slice(b).unwrap();
                v.as_object_mut()
                    .unwrap()
                    .retain(|k, _| !colloidsim_run::ensemble::is_timing(k));
                v
            };
            assert_eq!(strip(x), strip(y), "{name}");
        } else {
            assert!(x == y, "{name} differs");
        }
    }
}

/// A BCD scenario of a fraction of a second (five rods), for the ensemble and MPI tests.
pub const TINY_BCD: &str = r#"
method = "bcd"
seed = 11
[system]
length = 10.0
particles = 5
diameter = 0.5
[potential]
cosine = { amplitude = 2.0, wavelength = 1.0 }
[run]
dt = 1e-3
equilibrate = 0.2
time = 2.0
[observe]
density = { bins = 20 }
msd = { points = 5 }
"#;

/// `colloidsim ARGS` with extra environment variables; its output is echoed for the log.
pub fn cli(args: &[&str], env: &[(&str, &str)]) -> Output {
    let o = Command::new(env!("CARGO_BIN_EXE_colloidsim"))
        .args(args)
        .envs(env.iter().copied())
        .output()
        .unwrap();
    eprintln!("{}", text(&o));
    o
}

/// A drying MPCD droplet of R0 = 8 cells with 6 colloids of d = 4 (no-slip walls, solvent
/// removed as it shrinks), 300 collisions, profiles and a trajectory (its section last).
pub const MPCD_DROPLET_COLLOIDS: &str = r#"
method = "droplet-mpcd"
seed = 4
boundary = "no-slip"
[system]
particles = 6
diameter = 4
radius = 8
[drying]
peclet = 10
duration = 30
[observe.profile]
bins = 8
[observe.solvent]
window = 50
[observe.trajectory]
every = 50
"#;
