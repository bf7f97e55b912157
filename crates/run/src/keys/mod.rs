//! Every scenario key of every method: unit, default, allowed values and meaning, in one table
//! per method. The same table
//! - checks a scenario before its method reads it ([`validate`]: unknown keys, types and the
//!   range of each key, each error naming the key and what is allowed), and
//! - is what `colloidsim keys METHOD` prints (and what docs/ quotes),
//!
//! so the listing cannot drift from the validation. Checks that relate several keys (a drying
//! time against the droplet's lifetime, a skin against the diameter) stay with each method and
//! are described in the key's `allowed` text. Tests check that every key the method's parser
//! knows is in its table, that every table key is known to the parser, and that each
//! documented default is the one the method uses.

use anyhow::{Result, bail};
use serde::Serialize;

/// What values a key takes (checked on the key alone).
#[derive(Debug, Clone, Copy)]
pub enum Allowed {
    /// A table of further keys.
    Table,
    /// A finite number > 0.
    Positive,
    /// A finite number >= 0.
    NonNegative,
    /// Any finite number.
    Finite,
    /// A finite number in `[lo, hi]`.
    Closed(f64, f64),
    /// A finite number in `(lo, hi]`.
    LeftOpen(f64, f64),
    /// An integer in `[lo, hi]`.
    Integer(i64, i64),
    /// One of these words.
    OneOf(&'static [&'static str]),
    /// `true` or `false`.
    Bool,
    /// A file name (relative to the scenario file).
    Path,
    /// A list of finite numbers in `[lo, hi]`, of length `len` (any when `None`).
    Numbers(f64, f64, Option<usize>),
}

impl Allowed {
    /// The allowed values, as a user reads them.
    pub fn describe(&self) -> String {
        match *self {
            Allowed::Table => "a table".into(),
            Allowed::Positive => "> 0".into(),
            Allowed::NonNegative => ">= 0".into(),
            Allowed::Finite => "any finite number".into(),
            Allowed::Closed(lo, hi) => format!("[{lo}, {hi}]"),
            Allowed::LeftOpen(lo, hi) => format!("({lo}, {hi}]"),
            Allowed::Integer(lo, hi) if hi == i64::MAX => format!("integer >= {lo}"),
            Allowed::Integer(lo, hi) => format!("integer in [{lo}, {hi}]"),
            Allowed::OneOf(words) => words
                .iter()
                .map(|w| format!("\"{w}\""))
                .collect::<Vec<_>>()
                .join(", "),
            Allowed::Bool => "true, false".into(),
            Allowed::Path => "a file name".into(),
            Allowed::Numbers(lo, hi, len) => {
                let n = len.map_or("a list".to_string(), |n| format!("{n} numbers"));
                if lo == f64::MIN && hi == f64::MAX {
                    format!("{n} of finite numbers")
                } else if hi == f64::MAX {
                    format!("{n} of numbers > {lo}")
                } else {
                    format!("{n} of numbers in [{lo}, {hi}]")
                }
            }
        }
    }

    /// Check `v`; the message says what is allowed and what was given.
    fn check(&self, v: &toml::Value) -> Result<(), String> {
        let number = |v: &toml::Value| match v {
            toml::Value::Float(x) => Some(*x),
            toml::Value::Integer(i) => Some(*i as f64),
            _ => None,
        };
        let got = || match v {
            toml::Value::String(s) => format!("\"{s}\""),
            other => shown(other),
        };
        let must = |what: String| Err(format!("must be {what}, got {}", got()));
        match *self {
            Allowed::Table => match v {
                toml::Value::Table(_) => Ok(()),
                _ => must("a table (e.g. { key = value })".into()),
            },
            Allowed::Positive => match number(v) {
                Some(x) if x.is_finite() && x > 0.0 => Ok(()),
                _ => must("a finite number > 0".into()),
            },
            Allowed::NonNegative => match number(v) {
                Some(x) if x.is_finite() && x >= 0.0 => Ok(()),
                _ => must("a finite number >= 0".into()),
            },
            Allowed::Finite => match number(v) {
                Some(x) if x.is_finite() => Ok(()),
                _ => must("a finite number".into()),
            },
            Allowed::Closed(lo, hi) => match number(v) {
                Some(x) if x.is_finite() && x >= lo && x <= hi => Ok(()),
                _ => must(format!("a number in [{lo}, {hi}]")),
            },
            Allowed::LeftOpen(lo, hi) => match number(v) {
                Some(x) if x.is_finite() && x > lo && x <= hi => Ok(()),
                _ => must(format!("a number in ({lo}, {hi}]")),
            },
            Allowed::Integer(lo, hi) => match v {
                toml::Value::Integer(i) if *i >= lo && *i <= hi => Ok(()),
                _ => must(format!("an {}", self.describe())),
            },
            Allowed::OneOf(words) => match v {
                toml::Value::String(s) if words.contains(&s.as_str()) => Ok(()),
                _ => must(format!("one of {}", self.describe())),
            },
            Allowed::Bool => match v {
                toml::Value::Boolean(_) => Ok(()),
                _ => must("true or false".into()),
            },
            Allowed::Path => match v {
                toml::Value::String(s) if !s.is_empty() => Ok(()),
                _ => must("a file name in quotes".into()),
            },
            Allowed::Numbers(lo, hi, len) => {
                let ok = match v {
                    toml::Value::Array(a) => {
                        len.is_none_or(|n| a.len() == n)
                            && a.iter().all(|x| {
                                number(x).is_some_and(|x| x.is_finite() && x >= lo && x <= hi)
                            })
                    }
                    _ => false,
                };
                if ok { Ok(()) } else { must(self.describe()) }
            }
        }
    }
}

/// What a method takes for a key the scenario leaves out: declared once, beside the key, and
/// used by the [`Reader`] (literal and derived defaults) as well as listed by `colloidsim keys`.
#[derive(Debug, Clone, Copy)]
pub enum Omitted {
    /// The scenario must give the key.
    Required,
    /// This value, written as in a scenario (`1e-3`, `true`, `[0, 0.5]`): the reader parses it.
    Value(&'static str),
    /// This word (one of the key's allowed words).
    Word(&'static str),
    /// Computed from other keys by the code given (the text is how `keys` shows it).
    Derived(&'static str, fn(&Reader) -> Result<f64>),
    /// What leaving the key out means, in words (an optional table that is then off, or a
    /// choice the method makes from the rest of the scenario).
    Means(&'static str),
}

impl Omitted {
    /// How `colloidsim keys` shows it.
    pub fn describe(&self) -> &'static str {
        match *self {
            Required => "required",
            Value(v) | Word(v) | Means(v) | Derived(v, _) => v,
        }
    }
}

/// One key of a method's scenarios.
#[derive(Debug, Clone, Copy)]
pub struct Spec {
    /// Dotted path.
    pub path: &'static str,
    /// Unit (`-` for a pure number or a word).
    pub unit: &'static str,
    /// What the method takes when the key is left out.
    pub default: Omitted,
    /// Allowed values of the key alone.
    pub allowed: Allowed,
    /// Further conditions that involve other keys (checked by the method).
    pub also: &'static str,
    /// What it sets.
    pub doc: &'static str,
    /// Values inside the range that almost surely mean a unit mistake ([`Spec::suspicions`]);
    /// empty: those of the key's unit ([`by_unit`]).
    pub suspicious: &'static [Suspicion],
    /// No unit-mistake warning for this key (a length that is legitimately tiny).
    pub plausible: bool,
}

/// Values of a key, inside its range, that almost surely mean a unit mistake: a warning names
/// the key and the likely intent.
#[derive(Debug, Clone, Copy)]
pub struct Suspicion {
    /// Lowest suspicious value.
    pub lo: f64,
    /// Highest suspicious value.
    pub hi: f64,
    /// The likely intent and what the key means instead.
    pub hint: &'static str,
}

/// kT given in kelvin.
pub const KELVIN: Suspicion = Suspicion {
    lo: 250.0,
    hi: 400.0,
    hint: "kelvin? kT is an energy in the scenario's units (kT = 1: the thermal energy), not a temperature; room temperature is kT = 1",
};
/// kT given in joules.
pub const JOULES: Suspicion = Suspicion {
    lo: 1e-23,
    hi: 1e-19,
    hint: "joules? kT is an energy in the scenario's units (kT = 1: the thermal energy), not SI (4.1e-21 J is kT = 1 at room temperature)",
};
/// A length given in metres.
pub const METRES: Suspicion = Suspicion {
    lo: 1e-10,
    hi: 1e-5,
    hint: "metres? lengths are in the scenario's units (the diameter, the cut-off or the cell, e.g. 1), not SI",
};
/// A viscosity given in pascal seconds.
pub const PASCAL_SECONDS: Suspicion = Suspicion {
    lo: 5e-4,
    hi: 2e-3,
    hint: "Pa s (water: 1e-3)? the viscosity is in the scenario's reduced units (energy time / length^3, e.g. 1)",
};
/// An angle in degrees given in radians.
pub const RADIANS: Suspicion = Suspicion {
    lo: 0.0,
    hi: 2.0 * std::f64::consts::PI,
    hint: "radians? the key is in degrees (the usual 130 degrees is 2.27 rad)",
};

/// The unit mistakes a key's unit invites: kT in kelvin or joules, lengths in metres,
/// viscosities in Pa s, degrees given in radians.
pub fn by_unit(s: &Spec) -> &'static [Suspicion] {
    match s.unit {
        "energy" if s.path.ends_with("kT") => &[KELVIN, JOULES],
        "length" | "rc" => &[METRES],
        "energy time / length^3" => &[PASCAL_SECONDS],
        "degrees" => &[RADIANS],
        _ => &[],
    }
}

impl Spec {
    /// The values of this key that warn of a unit mistake.
    pub fn suspicions(&self) -> &'static [Suspicion] {
        if self.plausible {
            &[]
        } else if self.suspicious.is_empty() {
            by_unit(self)
        } else {
            self.suspicious
        }
    }
}

/// Warnings for the values of `table` that almost surely mean a unit mistake (`check` and `run`
/// print them; a scenario they make fail reports them first).
pub fn suspicious(table: &toml::Table, spec: &[Spec]) -> Vec<String> {
    let mut out = Vec::new();
    for s in spec {
        let mut parts = s.path.split('.');
        let mut v = parts.next().and_then(|p| table.get(p));
        for p in parts {
            v = v.and_then(|v| v.as_table()).and_then(|t| t.get(p));
        }
        let x = match v {
            Some(toml::Value::Float(x)) => *x,
            Some(toml::Value::Integer(i)) => *i as f64,
            _ => continue,
        };
        if let Some(w) = s.suspicions().iter().find(|w| x > w.lo && x <= w.hi) {
            out.push(format!(
                "{} = {}: {} (unit: {})",
                s.path,
                colloidsim_core::param::show(x),
                w.hint,
                s.unit
            ));
        }
    }
    out
}

/// One scenario key as listed by `colloidsim keys`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Key {
    /// Dotted path, e.g. `run.dt`.
    pub path: String,
    /// Unit, or `-` for a pure number or a word.
    pub unit: String,
    /// Default, or `required`.
    pub default: String,
    /// Allowed values.
    pub range: String,
    /// What it sets.
    pub doc: String,
}

impl From<&Spec> for Key {
    fn from(s: &Spec) -> Self {
        let mut range = s.allowed.describe();
        if !s.also.is_empty() {
            range = format!("{range}; {}", s.also);
        }
        Key {
            path: s.path.into(),
            unit: s.unit.into(),
            default: s.default.describe().into(),
            range,
            doc: s.doc.into(),
        }
    }
}

pub(crate) const fn key(
    path: &'static str,
    unit: &'static str,
    default: Omitted,
    allowed: Allowed,
    doc: &'static str,
) -> Spec {
    Spec {
        path,
        unit,
        default,
        allowed,
        also: "",
        doc,
        suspicious: &[],
        plausible: false,
    }
}

impl Spec {
    pub(crate) const fn also(mut self, also: &'static str) -> Self {
        self.also = also;
        self
    }

    /// Warn of a unit mistake for these values (instead of those of the key's unit).
    pub(crate) const fn suspicious(mut self, values: &'static [Suspicion]) -> Self {
        self.suspicious = values;
        self
    }

    /// No unit-mistake warning: tiny values of this length are meant.
    pub(crate) const fn plausible(mut self) -> Self {
        self.plausible = true;
        self
    }
}

use Allowed::*;
use Omitted::*;

pub(crate) const SEED_RANGE: Allowed = Integer(0, u32::MAX as i64);
/// The `seed` key of the methods with counter-based random streams.
pub(crate) const SEED_KEY: Spec = key(
    "seed",
    "-",
    Value("1"),
    SEED_RANGE,
    "seed of the counter-based random streams (--seed overrides)",
);
/// Step counts and other integers a run can hold.
pub(crate) const COUNT: i64 = 1 << 53;
/// The most bins of a one-dimensional profile (a density along a ring, a radial profile): a
/// million rows are some 25 MB of CSV per file, far finer than any run resolves. More would fill
/// a disk with tables, not resolve anything (a fuzzed 1e8 bins wrote GBs).
pub(crate) const MAX_BINS_1D: i64 = 1_000_000;
/// The most radial bins of a droplet's profiles and g(r), of which several files are written.
pub(crate) const MAX_BINS_RADIAL: i64 = 100_000;

pub mod shared;
pub mod species;

/// Check a scenario's table against a method's keys: unknown keys (with the keys of that
/// table), types and each key's own range. `prefix` is the path of `table` (empty at the top).
pub fn validate(table: &toml::Table, spec: &[Spec]) -> Result<()> {
    walk(table, "", spec)
}

fn walk(table: &toml::Table, prefix: &str, spec: &[Spec]) -> Result<()> {
    for (k, v) in table {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        let Some(s) = spec.iter().find(|s| s.path == path) else {
            let siblings: Vec<&str> = spec
                .iter()
                .filter_map(|s| {
                    let rest = if prefix.is_empty() {
                        Some(s.path)
                    } else {
                        s.path
                            .strip_prefix(prefix)
                            .and_then(|r| r.strip_prefix('.'))
                    }?;
                    (!rest.contains('.')).then_some(rest)
                })
                .collect();
            let place = if prefix.is_empty() {
                "the top level".to_string()
            } else {
                format!("[{prefix}]")
            };
            bail!(
                "{path}: unknown key (the keys of {place} are: {}); see colloidsim keys",
                siblings.join(", ")
            );
        };
        if let Err(m) = s.allowed.check(v) {
            bail!("{path}: {m}");
        }
        if let (Allowed::Table, toml::Value::Table(t)) = (s.allowed, v) {
            walk(t, &path, spec)?;
        }
    }
    Ok(())
}

/// A scenario's table read through a method's key declarations: [`Reader::new`] checks every
/// key against its declaration (unknown keys, types, each key's range), and every read takes
/// the declared default when the key is left out. The methods build their typed parameters
/// with it, so that a key's default and range are written once, in its [`Spec`].
pub struct Reader<'a> {
    table: &'a toml::Table,
    spec: &'a [Spec],
    /// The keys consulted so far (tests check that a method reads every key it declares).
    consulted: std::cell::RefCell<Vec<&'static str>>,
}

impl<'a> Reader<'a> {
    /// Check `table` against the method's keys `spec`.
    pub fn new(table: &'a toml::Table, spec: &'a [Spec]) -> Result<Self> {
        validate(table, spec)?;
        Ok(Self {
            table,
            spec,
            consulted: Default::default(),
        })
    }

    /// The declared keys (tables, `method`, which the registry reads, and the driver's
    /// [`shared::DRIVER_KEYS`] aside) not consulted
    /// so far, in declaration order: a method that declares a key it never reads shows it here.
    pub fn unread(&self) -> Vec<&'static str> {
        let consulted = self.consulted.borrow();
        self.spec
            .iter()
            .filter(|s| !matches!(s.allowed, Table) && s.path != "method")
            .filter(|s| !shared::DRIVER_KEYS.contains(&s.path))
            .filter(|s| !consulted.contains(&s.path))
            .map(|s| s.path)
            .collect()
    }

    /// The value the scenario gives for `k`, if any.
    pub fn given(&self, k: &Spec) -> Option<&'a toml::Value> {
        debug_assert!(
            self.spec.iter().any(|s| s.path == k.path),
            "{} is not declared for this method",
            k.path
        );
        self.consulted.borrow_mut().push(k.path);
        let mut parts = k.path.split('.');
        let mut v = self.table.get(parts.next()?)?;
        for p in parts {
            v = v.as_table()?.get(p)?;
        }
        Some(v)
    }

    /// Is `k` one of this method's keys?
    pub fn declares(&self, k: &Spec) -> bool {
        self.spec.iter().any(|s| s.path == k.path)
    }

    /// Does the scenario give `k` (a key, or a table)?
    pub fn has(&self, k: &Spec) -> bool {
        self.given(k).is_some()
    }

    /// The value of `k`: as given, or its literal default; `None` for a key whose omission
    /// means something in words ([`Omitted::Means`]); an error for a required key left out.
    fn value(&self, k: &Spec) -> Result<Option<toml::Value>> {
        if let Some(v) = self.given(k) {
            return Ok(Some(v.clone()));
        }
        match k.default {
            Required => bail!("{}: required ({}); see colloidsim keys", k.path, k.doc),
            Value(text) => {
                let t: toml::Table = toml::from_str(&format!("v = {text}"))
                    .unwrap_or_else(|e| panic!("{}: default {text} is not TOML: {e}", k.path));
                Ok(t.get("v").cloned())
            }
            Word(w) => Ok(Some(toml::Value::String(w.into()))),
            Derived(..) | Means(_) => Ok(None),
        }
    }

    /// `read` of a key the scenario may leave out ([`Omitted::Means`]: the method decides what
    /// its absence means), `None` when it does.
    fn optional<T>(&self, k: &Spec, read: fn(&Self, &Spec) -> Result<T>) -> Result<Option<T>> {
        match self.given(k) {
            None if matches!(k.default, Means(_)) => Ok(None),
            _ => read(self, k).map(Some),
        }
    }

    /// `read` of a key only where the scenario gives it (a record of what was written; the
    /// value used, with its default, comes from `read` itself).
    pub fn if_given<T>(&self, k: &Spec, read: fn(&Self, &Spec) -> Result<T>) -> Result<Option<T>> {
        match self.given(k) {
            Some(_) => read(self, k).map(Some),
            None => Ok(None),
        }
    }

    /// `read` of an optional table's keys when the scenario has the table `k`.
    pub fn section<T>(&self, k: &Spec, read: impl FnOnce() -> Result<T>) -> Result<Option<T>> {
        if self.has(k) {
            read().map(Some)
        } else {
            Ok(None)
        }
    }

    /// A number: as given, its literal default, or its derived default.
    pub fn number(&self, k: &Spec) -> Result<f64> {
        if let (None, Derived(_, f)) = (self.given(k), k.default) {
            return f(self);
        }
        match self.value(k)? {
            Some(toml::Value::Float(x)) => Ok(x),
            Some(toml::Value::Integer(i)) => Ok(i as f64),
            other => bail!("{}: expected a number, got {other:?}", k.path),
        }
    }

    /// A number the scenario may leave out ([`Omitted::Means`]: the method decides).
    pub fn opt_number(&self, k: &Spec) -> Result<Option<f64>> {
        self.optional(k, Self::number)
    }

    /// A whole number (checked as an integer of its declared range).
    pub fn integer(&self, k: &Spec) -> Result<i64> {
        match self.value(k)? {
            Some(toml::Value::Integer(i)) => Ok(i),
            other => bail!("{}: expected an integer, got {other:?}", k.path),
        }
    }

    /// A whole number the scenario may leave out ([`Omitted::Means`]).
    pub fn opt_integer(&self, k: &Spec) -> Result<Option<i64>> {
        self.optional(k, Self::integer)
    }

    /// A count (an integer declared >= 0).
    pub fn count(&self, k: &Spec) -> Result<u64> {
        let i = self.integer(k)?;
        u64::try_from(i).map_err(|_| anyhow::anyhow!("{}: must be >= 0, got {i}", k.path))
    }

    /// A count the scenario may leave out ([`Omitted::Means`]).
    pub fn opt_count(&self, k: &Spec) -> Result<Option<u64>> {
        self.optional(k, Self::count)
    }

    /// A word (one of the key's allowed words).
    pub fn word(&self, k: &Spec) -> Result<String> {
        match self.value(k)? {
            Some(toml::Value::String(w)) => Ok(w),
            other => bail!("{}: expected a word, got {other:?}", k.path),
        }
    }

    /// A word the scenario may leave out ([`Omitted::Means`]).
    pub fn opt_word(&self, k: &Spec) -> Result<Option<String>> {
        self.optional(k, Self::word)
    }

    /// `true` or `false`.
    pub fn flag(&self, k: &Spec) -> Result<bool> {
        match self.value(k)? {
            Some(toml::Value::Boolean(b)) => Ok(b),
            other => bail!("{}: expected true or false, got {other:?}", k.path),
        }
    }

    /// A list of numbers.
    pub fn numbers(&self, k: &Spec) -> Result<Vec<f64>> {
        match self.value(k)? {
            Some(toml::Value::Array(a)) => a
                .iter()
                .map(|x| match x {
                    toml::Value::Float(x) => Ok(*x),
                    toml::Value::Integer(i) => Ok(*i as f64),
                    other => bail!("{}: expected numbers, got {other}", k.path),
                })
                .collect(),
            other => bail!("{}: expected a list of numbers, got {other:?}", k.path),
        }
    }

    /// A list of numbers the scenario may leave out ([`Omitted::Means`]).
    pub fn opt_numbers(&self, k: &Spec) -> Result<Option<Vec<f64>>> {
        self.optional(k, Self::numbers)
    }

    /// A file name as written (relative to the scenario's folder), if given.
    pub fn file(&self, k: &Spec) -> Option<std::path::PathBuf> {
        match self.given(k) {
            Some(toml::Value::String(s)) => Some(s.into()),
            _ => None,
        }
    }
}

/// An engine's error about one of its parameters (named as the engine names it, e.g. `dt`),
/// naming instead the scenario key that sets it; `names` pairs the engine's names with the
/// keys. An error about a parameter not listed is returned as it is.
pub fn rekey(
    e: colloidsim_core::ParamError,
    names: &[(&str, &Spec)],
) -> colloidsim_core::ParamError {
    match names.iter().find(|(name, _)| *name == e.key) {
        Some((_, k)) => colloidsim_core::ParamError::new(k.path, e.message),
        None => e,
    }
}

/// An engine's message that names its parameters in backticks (``reduce `dt` ``), naming
/// instead the scenario keys that set them (`reduce run.dt`); `names` pairs the engine's
/// names with the keys. A name not listed is shown without its backticks.
pub fn rekey_text(message: &str, names: &[(&str, &Spec)]) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(open) = rest.find('`') {
        let Some(len) = rest[open + 1..].find('`') else {
            break;
        };
        let name = &rest[open + 1..open + 1 + len];
        out.push_str(&rest[..open]);
        match names.iter().find(|(n, _)| *n == name) {
            Some((_, k)) => out.push_str(k.path),
            None => out.push_str(name),
        }
        rest = &rest[open + len + 2..];
    }
    out.push_str(rest);
    out
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

/// `v` as the scenario would write it, but a float far from 1 in exponent form (`1e-300`, not
/// three hundred digits).
fn shown(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(x) if x.is_finite() && *x != 0.0 && !(1e-6..1e15).contains(&x.abs()) => {
            format!("{x:e}")
        }
        toml::Value::Array(a) => {
            format!("[{}]", a.iter().map(shown).collect::<Vec<_>>().join(", "))
        }
        other => other.to_string(),
    }
}

/// A scenario's keys with their values and units, as `colloidsim check` prints them: every
/// key the scenario sets, then beside them the defaults it leaves (marked `(default)`), in the
/// order of the key table; keys inside an optional table the scenario leaves out, and
/// required keys it lacks, are not listed. Tables themselves are listed by their keys.
pub fn values(table: &toml::Table, keys: &[Key]) -> String {
    let lookup = |path: &str| -> Option<&toml::Value> {
        let mut parts = path.split('.');
        let mut v = table.get(parts.next()?)?;
        for p in parts {
            v = v.as_table()?.get(p)?;
        }
        Some(v)
    };
    let is_table = |k: &Key| k.range == Allowed::Table.describe();
    let tables: Vec<&Key> = keys.iter().filter(|k| is_table(k)).collect();
    let mut rows = Vec::new();
    for k in keys.iter().filter(|k| !is_table(k)) {
        let unit = if k.unit == "-" { "" } else { &k.unit };
        match lookup(&k.path) {
            Some(v) => rows.push((k.path.as_str(), shown(v), unit, "")),
            None => {
                let inside_absent = tables.iter().any(|t| {
                    k.path.starts_with(&format!("{}.", t.path)) && lookup(&t.path).is_none()
                });
                if !inside_absent && k.default != Required.describe() {
                    rows.push((k.path.as_str(), k.default.clone(), unit, "(default)"));
                }
            }
        }
    }
    let wp = rows.iter().map(|r| r.0.len()).max().unwrap_or(0);
    let wv = rows.iter().map(|r| r.1.len()).max().unwrap_or(0).min(40);
    let wu = rows.iter().map(|r| r.2.len()).max().unwrap_or(0);
    let mut s = String::new();
    for (path, value, unit, mark) in rows {
        let line = format!("{path:<wp$} = {value:<wv$}  {unit:<wu$}  {mark}");
        s.push_str(line.trim_end());
        s.push('\n');
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::bcd::keys::KEYS as BCD;

    fn table(text: &str) -> toml::Table {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn each_key_is_checked_alone_with_its_name_and_range() {
        let ok = table(
            "method = \"bcd\"\n[system]\nlength = 10\nparticles = 3\ndiameter = 0.5\n[run]\ndt = 1e-3\ntime = 1.0\n",
        );
        validate(&ok, BCD).unwrap();
        for (bad, words) in [
            (
                "[run]\ndt = -1",
                "run.dt: must be a finite number > 0, got -1",
            ),
            (
                "[run]\ndt = nan",
                "run.dt: must be a finite number > 0, got nan",
            ),
            (
                "[system]\nparticles = 2.5",
                "system.particles: must be an integer in [1,",
            ),
            (
                "[system]\nboundary = \"ring\"",
                "one of \"periodic\", \"walls\", got \"ring\"",
            ),
            (
                "[observe]\ncurrent = 1",
                "observe.current: must be true or false",
            ),
            (
                "[observe]\nnonsense = 1",
                "observe.nonsense: unknown key (the keys of [observe] are: figure_format, every, density",
            ),
            (
                "sedd = 3",
                "sedd: unknown key (the keys of the top level are: method, seed, system",
            ),
            (
                "[potential]\ncosine = 3",
                "potential.cosine: must be a table",
            ),
            (
                "[potential.fourier]\nwavelength = 1\ncos = [1, \"a\"]",
                "potential.fourier.cos: must be a list of finite numbers",
            ),
            (
                "seed = 4294967296",
                "seed: must be an integer in [0, 4294967295]",
            ),
        ] {
            let e = validate(&table(bad), BCD).unwrap_err().to_string();
            assert!(e.contains(words), "{bad}: {e}");
        }
    }

    #[test]
    fn engine_names_in_backticks_become_keys() {
        use crate::keys::shared::{HYDRO_MAX_ITERATIONS, RUN_DT};
        let names: &[(&str, &Spec)] = &[("dt", &RUN_DT), ("max_iterations", &HYDRO_MAX_ITERATIONS)];
        assert_eq!(
            rekey_text(
                "step 3: reduce `dt` (or raise `max_iterations`; `other`)",
                names
            ),
            "step 3: reduce run.dt (or raise hydrodynamics.max_iterations; other)"
        );
        assert_eq!(
            rekey_text("no names, one ` tick", names),
            "no names, one ` tick"
        );
    }

    #[test]
    fn every_path_is_listed_once_under_a_listed_table() {
        for spec in crate::registry::all().iter().map(|m| m.keys()) {
            for (i, s) in spec.iter().enumerate() {
                assert!(
                    spec[..i].iter().all(|t| t.path != s.path),
                    "{} twice",
                    s.path
                );
                if let Some((parent, _)) = s.path.rsplit_once('.') {
                    assert!(
                        spec.iter()
                            .any(|t| t.path == parent && matches!(t.allowed, Allowed::Table)),
                        "{}: no table {parent}",
                        s.path
                    );
                }
            }
        }
    }
}
