//! The scenario keys of every method, with unit, default and allowed range.

use serde::Serialize;

/// One scenario key.
#[derive(Debug, Clone, Serialize)]
pub struct Key {
    /// Dotted path, e.g. `run.dt`.
    pub path: &'static str,
    /// Unit, or `-` for a pure number or a word.
    pub unit: &'static str,
    /// Default, or `required`.
    pub default: &'static str,
    /// Allowed values.
    pub range: &'static str,
    /// What it sets.
    pub doc: &'static str,
}

/// The keys of `bcd` scenarios.
pub fn bcd() -> Vec<Key> {
    Vec::new()
}

/// The keys of `droplet-bd` scenarios.
pub fn droplet() -> Vec<Key> {
    Vec::new()
}

/// The keys of `dpd` scenarios.
pub fn dpd() -> Vec<Key> {
    Vec::new()
}

/// The keys as aligned text columns.
pub fn text(keys: &[Key]) -> String {
    let w = keys.iter().map(|k| k.path.len()).max().unwrap_or(4).max(4);
    let mut s = String::new();
    for k in keys {
        s.push_str(&format!(
            "{:<w$}  {}\n{:<w$}  unit: {}; default: {}; allowed: {}\n",
            k.path, k.doc, "", k.unit, k.default, k.range
        ));
    }
    s
}

/// The keys as a Markdown table.
pub fn markdown(keys: &[Key]) -> String {
    let mut s =
        String::from("| key | unit | default | allowed | meaning |\n|---|---|---|---|---|\n");
    for k in keys {
        s.push_str(&format!(
            "| `{}` | {} | {} | {} | {} |\n",
            k.path,
            k.unit,
            k.default,
            k.range.replace('|', "\\|"),
            k.doc.replace('|', "\\|")
        ));
    }
    s
}
