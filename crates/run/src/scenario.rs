//! A scenario as the run path receives it: the TOML text, where relative paths in it are taken
//! from, and a name for messages and default output folders.
//!
//! A scenario comes from a file, from a TOML string or from a TOML table (Python passes a
//! dict), and `key.path=value` overrides (`--set`) are applied to its table before any method
//! reads it, so that an override meets exactly the validation of the key it replaces.

use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};

/// A scenario's text and its provenance.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    text: String,
    base: PathBuf,
    origin: Option<PathBuf>,
    name: String,
}

impl Scenario {
    /// Read a scenario file; relative paths inside it are taken from the file's folder.
    pub fn from_path(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read scenario {}", path.display()))?;
        let base = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_path_buf();
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "colloidsim".into());
        let sc = Self {
            text,
            base,
            origin: Some(path.to_path_buf()),
            name,
        };
        sc.table()?;
        Ok(sc)
    }

    /// A scenario given as TOML text; relative paths inside it are taken from `base`.
    pub fn from_toml(text: &str, base: &Path) -> Result<Self> {
        let sc = Self {
            text: text.to_string(),
            base: base.to_path_buf(),
            origin: None,
            name: "scenario".into(),
        };
        sc.table()?;
        Ok(sc)
    }

    /// A scenario given as a TOML table (e.g. a Python dict); relative paths are taken from
    /// `base`.
    pub fn from_table(table: &toml::Table, base: &Path) -> Result<Self> {
        let text = toml::to_string(table).context("scenario: cannot be written as TOML")?;
        Self::from_toml(&text, base)
    }

    /// The same scenario under another name (used for default output folders).
    pub fn named(mut self, name: &str) -> Self {
        self.name = name.to_string();
        self
    }

    /// The scenario with `key.path=value` overrides applied, in order. The value is read as a
    /// TOML value (`3`, `1e-4`, `"walls"`, `[0.25, 0.5]`, `{ bins = 50 }`); a bare word that
    /// is not TOML is taken as a string. The text is written again from the table (comments
    /// are not kept), so the saved `scenario.toml` of a run is exactly what it ran.
    pub fn with_overrides(&self, overrides: &[String]) -> Result<Self> {
        if overrides.is_empty() {
            return Ok(self.clone());
        }
        let values = overrides
            .iter()
            .map(|o| parse_override(o))
            .collect::<Result<Vec<_>>>()?;
        self.with_values(&values)
    }

    /// The scenario with `(key.path, value)` overrides applied, in order (Python's
    /// `overrides={"run.dt": 1e-4}`).
    pub fn with_values(&self, values: &[(String, toml::Value)]) -> Result<Self> {
        if values.is_empty() {
            return Ok(self.clone());
        }
        let mut table = self.table()?;
        for (key, value) in values {
            check_key_path(key)?;
            set_key(&mut table, key, value.clone()).with_context(|| format!("--set {key}"))?;
        }
        let text = toml::to_string(&table).context("scenario: cannot be written as TOML")?;
        Ok(Self {
            text,
            ..self.clone()
        })
    }

    /// The scenario's TOML text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The folder relative paths are taken from.
    pub fn base(&self) -> &Path {
        &self.base
    }

    /// The file the scenario was read from, if any.
    pub fn origin(&self) -> Option<&Path> {
        self.origin.as_deref()
    }

    /// The name used for the default output folder: the file's stem.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// How messages name the scenario: `scenario path/to/file.toml` or `scenario`.
    pub fn label(&self) -> String {
        match &self.origin {
            Some(p) => format!("scenario {}", p.display()),
            None => "scenario".into(),
        }
    }

    /// The parsed table.
    pub fn table(&self) -> Result<toml::Table> {
        toml::from_str(&self.text).with_context(|| match &self.origin {
            Some(p) => format!("{} is not valid TOML", p.display()),
            None => "the scenario is not valid TOML".into(),
        })
    }

    /// The top-level `seed` key (1 when absent; its range is checked with the scenario). Read
    /// from the scenario itself, not from a method's resolved parameters, which need not
    /// list it.
    pub fn seed(&self) -> Result<u64> {
        match self.table()?.get("seed") {
            None => Ok(1),
            Some(toml::Value::Integer(k)) if *k >= 0 => Ok(*k as u64),
            Some(other) => bail!(
                "{}: key 'seed' must be a non-negative integer, got {other}",
                self.label()
            ),
        }
    }

    /// The `method` key.
    pub fn method(&self) -> Result<String> {
        let t = self.table()?;
        match t.get("method") {
            Some(toml::Value::String(s)) => Ok(s.clone()),
            Some(other) => bail!(
                "{}: key 'method' must be a string, got {}",
                self.label(),
                other.type_str()
            ),
            None => bail!(
                "{}: missing key 'method' (one of: {})",
                self.label(),
                crate::registry::names().join(", ")
            ),
        }
    }
}

/// Split `key.path=value` and read the value as TOML.
fn parse_override(o: &str) -> Result<(String, toml::Value)> {
    let Some((key, value)) = o.split_once('=') else {
        bail!("--set {o}: expected key.path=value, e.g. --set run.dt=1e-4");
    };
    let key = key.trim();
    check_key_path(key).with_context(|| format!("--set {o}"))?;
    let value = value.trim();
    let parsed = toml::from_str::<toml::Table>(&format!("v = {value}"))
        .ok()
        .and_then(|mut t| t.remove("v"));
    let value = match parsed {
        Some(v) => v,
        None if !value.is_empty()
            && value
                .chars()
                .all(|c| c.is_alphanumeric() || "-_./".contains(c)) =>
        {
            toml::Value::String(value.to_string())
        }
        None => {
            bail!("--set {o}: '{value}' is not a TOML value (quote strings: --set 'key=\"text\"')")
        }
    };
    Ok((key.to_string(), value))
}

/// A key path is names separated by dots.
fn check_key_path(key: &str) -> Result<()> {
    if key.is_empty()
        || key
            .split('.')
            .any(|part| part.is_empty() || part.contains(char::is_whitespace))
    {
        bail!("'{key}' is not a key path (names separated by dots, e.g. run.dt)");
    }
    Ok(())
}

/// Set `key` (dotted) in `table`, creating the tables on the way.
fn set_key(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<()> {
    let mut parts: Vec<&str> = key.split('.').collect();
    let last = parts.pop().expect("a key has at least one part");
    let mut t = table;
    let mut path = String::new();
    for p in parts {
        if !path.is_empty() {
            path.push('.');
        }
        path.push_str(p);
        let entry = t
            .entry(p.to_string())
            .or_insert_with(|| toml::Value::Table(Default::default()));
        t = match entry {
            toml::Value::Table(inner) => inner,
            other => bail!(
                "'{path}' is a {}, not a table, so it has no key '{last}'",
                other.type_str()
            ),
        };
    }
    t.insert(last.to_string(), value);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_set_nested_keys_with_toml_values() {
        let sc = Scenario::from_toml(
            "method = \"bcd\"\n[run]\ndt = 1e-3\n[observe]\ndensity = { bins = 10 }\n",
            Path::new("."),
        )
        .unwrap();
        let o = sc
            .with_overrides(&[
                "run.dt=1e-4".into(),
                "observe.density.bins = 50".into(),
                "system.boundary=walls".into(),
                "observe.profile.fractions=[0.5, 1.0]".into(),
            ])
            .unwrap();
        let t = o.table().unwrap();
        assert_eq!(t["run"]["dt"].as_float(), Some(1e-4));
        assert_eq!(t["observe"]["density"]["bins"].as_integer(), Some(50));
        assert_eq!(t["system"]["boundary"].as_str(), Some("walls"));
        assert_eq!(
            t["observe"]["profile"]["fractions"]
                .as_array()
                .unwrap()
                .len(),
            2
        );
        // The original is untouched.
        assert_eq!(sc.table().unwrap()["run"]["dt"].as_float(), Some(1e-3));
    }

    #[test]
    fn malformed_overrides_are_refused_by_name() {
        let sc = Scenario::from_toml("method = \"bcd\"\nseed = 3\n", Path::new(".")).unwrap();
        for bad in ["run.dt", "=3", "a..b=1", "seed.x=1", "run.dt=1e-4 junk"] {
            let e = sc.with_overrides(&[bad.into()]).unwrap_err();
            assert!(format!("{e:#}").contains("--set"), "{bad}: {e:#}");
        }
    }
}
