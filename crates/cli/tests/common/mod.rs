//! Helpers shared by the end-to-end tests of the `colloidsim` binary.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Output;

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
