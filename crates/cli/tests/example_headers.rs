//! The numbers example headers quote from their own seeded run: each `# header-check: PATH =
//! VALUE, ...` line of an example names a value of its summary.json (a dotted path) and the
//! value the header prints; the example is run as a user runs it, and the value must read the
//! same to the digits printed. A header that drifts from what its run gives fails here.
//! `# header-check-slow:` lines name runs of a minute or more: an ignored test checks them
//! (`cargo test --release -p colloidsim-cli --test integration example_headers:: -- --ignored`).

use std::path::Path;
use std::process::Command;

/// The `(path, value as printed)` pairs of an example's `# header-check:` lines, or of its
/// `# header-check-slow:` lines with `slow`.
fn checks(text: &str, slow: bool) -> Vec<(String, String)> {
    let prefix = if slow {
        "# header-check-slow:"
    } else {
        "# header-check:"
    };
    text.lines()
        .filter_map(|l| l.strip_prefix(prefix))
        .flat_map(|l| l.split(','))
        .map(|item| {
            let (path, value) = item.split_once('=').expect("PATH = VALUE");
            (path.trim().to_string(), value.trim().to_string())
        })
        .collect()
}

/// `x` rounded to the decimals of `printed` (`0.7218`: four), as the header prints it.
fn as_printed(x: f64, printed: &str) -> String {
    let decimals = printed.split_once('.').map_or(0, |(_, d)| d.len());
    format!("{x:.decimals$}")
}

#[test]
fn example_headers_quote_what_their_runs_give() {
    let checked = check_headers(false);
    assert!(checked >= 3, "only {checked} header numbers checked");
}

/// The headers' numbers from runs of a minute or more (each example's whole run).
#[test]
#[ignore = "runs of minutes: cargo test --release ... example_headers:: -- --ignored"]
fn slow_example_headers_quote_what_their_runs_give() {
    let checked = check_headers(true);
    assert!(checked >= 3, "only {checked} header numbers checked");
}

/// Run every example with header checks of the kind `slow` and compare; the count checked.
fn check_headers(slow: bool) -> usize {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut checked = 0;
    for dir in std::fs::read_dir(&examples).unwrap() {
        let dir = dir.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        for file in std::fs::read_dir(&dir).unwrap() {
            let file = file.unwrap().path();
            if file.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            let wanted = checks(&std::fs::read_to_string(&file).unwrap(), slow);
            if wanted.is_empty() {
                continue;
            }
            let out = tempfile::tempdir().unwrap();
            let run = Command::new(env!("CARGO_BIN_EXE_colloidsim"))
                .args(["run", "--quiet", "--out"])
                .arg(out.path().join("run"))
                .arg(&file)
                .output()
                .unwrap();
            assert!(
                run.status.success(),
                "{}: {}",
                file.display(),
                String::from_utf8_lossy(&run.stderr)
            );
            let summary: serde_json::Value = serde_json::from_slice(
                &std::fs::read(out.path().join("run/summary.json")).unwrap(),
            )
            .unwrap();
            for (path, printed) in wanted {
                let value = path
                    .split('.')
                    .fold(&summary, |v, k| &v[k])
                    .as_f64()
                    .unwrap_or_else(|| {
                        panic!("{}: summary.json has no number at {path}", file.display())
                    });
                assert_eq!(
                    as_printed(value, &printed),
                    printed,
                    "{}: the header says {path} = {printed}, the run gives {value}",
                    file.display()
                );
                checked += 1;
            }
        }
    }
    checked
}

#[test]
fn header_checks_are_read_and_rounded_as_printed() {
    let text =
        "# x\n# header-check: a.b = 0.7218, c = 12\n# header-check-slow: d = 1.5\nseed = 1\n";
    assert_eq!(
        checks(text, false),
        [("a.b".into(), "0.7218".into()), ("c".into(), "12".into())]
    );
    assert_eq!(checks(text, true), [("d".into(), "1.5".into())]);
    assert_eq!(as_printed(0.721839, "0.7218"), "0.7218");
    assert_eq!(as_printed(0.0496255, "0.0496"), "0.0496");
    assert_ne!(as_printed(0.7229, "0.7218"), "0.7218");
}
