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
