//! Engines know no input format: no string literal in the engine crates (bcd, md, mc, hydro,
//! dft) or the state they share (particles) names a scenario key of any method. An engine names its own parameters (`dt`,
//! `particles`) and the run layer renames them to keys (`colloidsim_run::keys::rekey`).

use std::path::{Path, PathBuf};

/// The string literals of a Rust source (plain `"..."` and raw `r"..."`/`r#"..."#`), comments
/// skipped, each with its line.
fn literals(src: &str) -> Vec<(usize, String)> {
    let b = src.as_bytes();
    let (mut i, mut line, mut out) = (0, 1, Vec::new());
    while i < b.len() {
        match b[i] {
            b'\n' => line += 1,
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                    line += usize::from(b[i] == b'\n');
                    i += 1;
                }
                i += 2;
                continue;
            }
            b'\'' => {
                // A char literal ('"', '\'') or a lifetime: skip a char literal whole.
                if b.get(i + 2) == Some(&b'\'') {
                    i += 3;
                    continue;
                }
                if b.get(i + 1) == Some(&b'\\')
                    && let Some(k) = b[i + 2..].iter().position(|&c| c == b'\'')
                {
                    i += k + 3;
                    continue;
                }
            }
            b'r' if matches!(b.get(i + 1), Some(b'"' | b'#'))
                && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_')) =>
            {
                let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
                let open = i + 1 + hashes;
                if b.get(open) == Some(&b'"') {
                    let close = format!("\"{}", "#".repeat(hashes));
                    let end = src[open + 1..]
                        .find(&close)
                        .map_or(b.len(), |k| open + 1 + k);
                    let text = &src[open + 1..end];
                    out.push((line, text.to_string()));
                    line += text.matches('\n').count();
                    i = end + close.len();
                    continue;
                }
            }
            b'"' => {
                let start = i + 1;
                let mut j = start;
                while j < b.len() && b[j] != b'"' {
                    j += if b[j] == b'\\' { 2 } else { 1 };
                }
                let text = &src[start..j.min(b.len())];
                out.push((line, text.to_string()));
                line += text.matches('\n').count();
                i = j + 1;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// Does `text` name `key` as a word (not inside a longer name such as `run.dt_max` or
/// `xrun.dt`; a full stop after it ends a sentence)?
fn names(text: &str, key: &str) -> bool {
    let name = |c: char| c.is_ascii_alphanumeric() || c == '_';
    text.match_indices(key).any(|(at, _)| {
        let before = text[..at].chars().next_back();
        let mut after = text[at + key.len()..].chars();
        let (next, then) = (after.next(), after.next());
        let longer = before.is_some_and(|c| name(c) || c == '.')
            || next.is_some_and(name)
            || next == Some('.') && then.is_some_and(name);
        !longer
    })
}

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The dotted key paths (`run.dt`, `system.particles`) of every method, and the `theory.`
/// labels of `colloidsim theory`'s own parameters. (Single words such as `seed` or `method`
/// are ordinary engine parameter names too.)
fn keys() -> Vec<String> {
    let mut keys: Vec<String> = colloidsim_run::registry::all()
        .iter()
        .flat_map(|m| m.keys().iter().map(|s| s.path.to_string()))
        .filter(|p| p.contains('.'))
        .collect();
    keys.sort();
    keys.dedup();
    keys
}

#[test]
fn the_scanner_finds_keys_in_literals_and_not_in_comments() {
    let src = "// run.dt here\nlet a = \"reduce run.dt or\";\n/* system.particles */ let b = r#\"x \"system.particles\"\"#;\nlet c = \"run.dt_max\"; let d = '\"'; let e = \"run.dt.\";";
    let lits = literals(src);
    let hits: Vec<(usize, &str)> = lits
        .iter()
        .filter_map(|(l, t)| {
            ["run.dt", "system.particles"]
                .into_iter()
                .find(|k| names(t, k))
                .map(|k| (*l, k))
        })
        .collect();
    assert_eq!(
        hits,
        [(2, "run.dt"), (3, "system.particles"), (4, "run.dt")],
        "{lits:?}"
    );
}

#[test]
fn no_engine_crate_names_a_scenario_key() {
    let keys = keys();
    assert!(
        keys.iter().any(|k| k == "run.dt") && keys.len() > 100,
        "{keys:?}"
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut found = Vec::new();
    for krate in ["bcd", "particles", "md", "mc", "hydro", "dft"] {
        let mut files = Vec::new();
        sources(&root.join("crates").join(krate).join("src"), &mut files);
        files.sort();
        for f in files {
            let src = std::fs::read_to_string(&f).unwrap();
            for (line, text) in literals(&src) {
                let theory = text.contains("theory.");
                if let Some(k) = keys.iter().find(|k| names(&text, k)) {
                    found.push(format!("{}:{line}: {k} in {text:?}", f.display()));
                } else if theory {
                    found.push(format!(
                        "{}:{line}: a theory. label in {text:?}",
                        f.display()
                    ));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "engine crates name scenario keys (name the engine's parameter and rekey in the run layer):\n{}",
        found.join("\n")
    );
}
