//! The loop every run shares: output folder, chunks of work between interrupt checks, regular
//! checkpoints, verified restarts, test hooks, progress and `summary.json`.

use crate::checkpoint::{self, CHECKPOINT, Envelope};
use crate::control::{Control, Stop};
use crate::keys::shared::figure_format;
use crate::method::Session;
use crate::output::plot::{picture_files, png_name, set_figure_format};
use crate::registry;
use crate::{Failed, Interrupted, Report, RunOptions, Scenario};
use anyhow::{Context, Result, bail};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::OutputDir;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Test hooks read from the environment: behave as if Ctrl-C arrived at this position
/// (`COLLOIDSIM_INTERRUPT_AT_STEP`), or as if the process were killed there, without a
/// checkpoint, after the trajectory reached the disk (`COLLOIDSIM_KILL_AT_STEP`); wait there
/// (`COLLOIDSIM_PAUSE_AT_STEP`, after printing `paused at step N (test hook)` on stderr) until
/// the run is asked to stop or the wall-time budget runs out (at most a minute), so that a
/// test can send a signal to a run it knows is running, or let a real budget run out at a
/// known step; and a fake
/// clock for the wall-time budget, on which each position advanced takes
/// `COLLOIDSIM_FAKE_STEP_SECONDS` and each checkpoint `COLLOIDSIM_FAKE_CHECKPOINT_SECONDS`
/// (default 0) and nothing else takes time, so that where a budget stops a run does not
/// depend on the machine.
struct Hooks {
    interrupt: Option<u64>,
    kill: Option<u64>,
    pause: Option<u64>,
    fake_step: Option<f64>,
    fake_checkpoint: f64,
}

impl Hooks {
    fn from_env() -> Self {
        fn read<T: std::str::FromStr>(name: &str) -> Option<T> {
            std::env::var(name).ok().and_then(|v| v.parse().ok())
        }
        Self {
            interrupt: read("COLLOIDSIM_INTERRUPT_AT_STEP"),
            kill: read("COLLOIDSIM_KILL_AT_STEP"),
            pause: read("COLLOIDSIM_PAUSE_AT_STEP"),
            fake_step: read::<f64>("COLLOIDSIM_FAKE_STEP_SECONDS").filter(|x| *x >= 0.0),
            fake_checkpoint: read::<f64>("COLLOIDSIM_FAKE_CHECKPOINT_SECONDS")
                .filter(|x| *x >= 0.0)
                .unwrap_or(0.0),
        }
    }
}

/// The wall-time budget's clock and what the driver has measured against it: the seconds per
/// position and per checkpoint, and how far ahead the next point a checkpoint can be written
/// at has been seen to lie.
struct Timer<'a> {
    ctl: &'a Control,
    fake_step: Option<f64>,
    fake_checkpoint: f64,
    /// Seconds per position of the last chunk and of everything this process ran.
    last_rate: Option<f64>,
    positions: u64,
    stepping: f64,
    /// The longest checkpoint written by this process, in seconds.
    checkpoint: f64,
    /// The most positions seen from a position to its stop point.
    reach: u64,
}

/// The safety margin of the wall-time budget: 1 % of it, at least 10 s, at most half of it.
pub(crate) fn walltime_margin(budget: f64) -> f64 {
    (0.01 * budget).max(10.0).min(0.5 * budget)
}

impl<'a> Timer<'a> {
    fn new(ctl: &'a Control, hooks: &Hooks) -> Self {
        Self {
            ctl,
            fake_step: hooks.fake_step,
            fake_checkpoint: hooks.fake_checkpoint,
            last_rate: None,
            positions: 0,
            stepping: 0.0,
            checkpoint: 0.0,
            reach: 0,
        }
    }

    /// Seconds of the budget spent so far.
    fn now(&self) -> f64 {
        self.ctl.spent(self.fake_step.is_some())
    }

    /// `n` positions were run in `real` seconds; returns the seconds they took on the
    /// budget's clock.
    fn stepped(&mut self, n: u64, real: f64) -> f64 {
        let secs = match self.fake_step {
            Some(x) => {
                self.ctl.spend_fake(x * n as f64);
                x * n as f64
            }
            None => real,
        };
        if n > 0 {
            self.last_rate = Some(secs / n as f64);
            self.positions += n;
            self.stepping += secs;
        }
        secs
    }

    /// A checkpoint was written in `real` seconds.
    fn saved(&mut self, real: f64) {
        let secs = match self.fake_step {
            Some(_) => {
                self.ctl.spend_fake(self.fake_checkpoint);
                self.fake_checkpoint
            }
            None => real,
        };
        self.checkpoint = self.checkpoint.max(secs);
    }

    /// With a budget: would running `n` more positions from `pos` still leave the time to go
    /// on to the next point a checkpoint can be written at and write it, within the budget
    /// less its margin? The time per position is the larger of the last chunk's and the mean.
    fn must_stop(&mut self, pos: u64, stop_point: u64, n: u64) -> bool {
        let Some(budget) = self.ctl.walltime() else {
            return false;
        };
        self.reach = self.reach.max(stop_point.saturating_sub(pos));
        let rate = match self.last_rate {
            Some(r) => r.max(self.stepping / self.positions.max(1) as f64),
            None => 0.0,
        };
        let need = (n + self.reach) as f64 * rate + self.checkpoint + walltime_margin(budget);
        self.now() + need > budget
    }
}

/// The reason of a `null` in `summary.json` that its method did not explain.
pub const UNEXPLAINED_NULL: &str =
    "no value: not measured or not applicable in this run, or not a finite number";

/// Every `null` among a method's summary values (`parameters`, the resolved input where `null`
/// means "not set", and the texts `error`, `why_null`, `note` and `*_note` aside), by path (`viscosity`, `momentum[2]`, `temperature.value`), with its
/// reason: the method's ([`OutputDir::explain`] with file `summary.json`), a pointer to the
/// `why_null` beside it, or [`UNEXPLAINED_NULL`]. JSON has no NaN or infinity: serde writes them as `null`, and
/// this says so wherever one is.
pub(crate) fn null_reasons(
    summary: &serde_json::Value,
    out: &OutputDir,
) -> std::collections::BTreeMap<String, String> {
    use serde_json::Value;
    fn walk(
        v: &Value,
        path: String,
        why: Option<&str>,
        out: &OutputDir,
        found: &mut std::collections::BTreeMap<String, String>,
    ) {
        match v {
            Value::Null => {
                let reason = out
                    .reason("summary.json", &path)
                    .or(why.map(String::from))
                    .unwrap_or_else(|| UNEXPLAINED_NULL.into());
                found.insert(path, reason);
            }
            Value::Object(m) => {
                let why = m
                    .get("why_null")
                    .filter(|w| w.is_string())
                    .map(|_| format!("see {path}.why_null"));
                // The texts that say why (null: nothing to say) are not values.
                let says_why = |k: &str| k == "why_null" || k == "note" || k.ends_with("_note");
                for (k, x) in m.iter().filter(|(k, x)| !(x.is_null() && says_why(k))) {
                    let p = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}.{k}")
                    };
                    walk(x, p, why.as_deref(), out, found);
                }
            }
            Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    walk(x, format!("{path}[{i}]"), why, out, found);
                }
            }
            _ => {}
        }
    }
    let mut found = std::collections::BTreeMap::new();
    if let Some(m) = summary.as_object() {
        for (k, v) in m
            .iter()
            .filter(|(k, _)| !["parameters", "error"].contains(&k.as_str()))
        {
            walk(v, k.clone(), None, out, &mut found);
        }
    }
    found
}

/// The resolved parameters and seed as a restart compares them.
fn resolved(s: &dyn Session) -> Result<String> {
    Ok(serde_json::to_string(
        &json!({ "seed": s.seed(), "parameters": s.parameters() }),
    )?)
}

/// The keys of two resolved-parameter JSON strings that differ, as `key = now (was then)`.
fn changed_keys(now: &str, then: &str) -> String {
    let parse = |s: &str| serde_json::from_str::<serde_json::Value>(s).unwrap_or_default();
    let (now, then) = (parse(now), parse(then));
    let mut out = Vec::new();
    if now["seed"] != then["seed"] {
        out.push(format!("seed = {} (was {})", now["seed"], then["seed"]));
    }
    if let Some(m) = now["parameters"].as_object() {
        for (k, v) in m {
            let old = &then["parameters"][k.as_str()];
            if old != v {
                out.push(format!("{k} = {v} (was {old})"));
            }
        }
    }
    out.join(", ")
}

fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

/// Run a scenario from the start. Everything is validated and the engine built before the
/// output folder is touched, so bad input leaves nothing behind.
pub fn run(sc: &Scenario, opts: &RunOptions, ctl: &Control) -> Result<Report> {
    run_with(sc, opts, ctl, None)
}

/// [`run`] decomposed in space over the ranks of `comm` (docs/parallel.md): every rank calls
/// it; rank 0 writes the folder, which is the one [`run`] writes.
pub fn run_decomposed(
    sc: &Scenario,
    opts: &RunOptions,
    ctl: &Control,
    comm: Box<dyn Exchange>,
) -> Result<Report> {
    run_with(sc, opts, ctl, Some(comm))
}

fn run_with(
    sc: &Scenario,
    opts: &RunOptions,
    ctl: &Control,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Report> {
    let m = registry::of(sc)?;
    if let Some(s) = opts.seed {
        crate::seed32(s)?;
    }
    let units = crate::unit_warnings(sc, m)?;
    let mut session = crate::first_the_units(m.start(sc, opts.seed, comm), &units)?;
    // Saved (scenario.toml, checkpoint) with the seed it ran with, so that it reruns this run.
    let sc = &as_run(sc, opts.seed)?;
    let mut warnings = units;
    warnings.extend(session.warnings());
    for w in &warnings {
        ctl.progress().warning(w);
    }
    let out_path = opts.out.clone().unwrap_or_else(|| PathBuf::from(sc.name()));
    let mut kept = Vec::new();
    let out = if session.is_writer() {
        let created = (|| -> Result<OutputDir> {
            let input_copy = input_in_folder(sc, &out_path)?;
            let out = OutputDir::create(&out_path, opts.force)?;
            set_figure_format(out.path(), figure_format(&sc.table()?)?);
            if opts.force {
                let keep = input_copy.then_some("scenario.toml");
                let (w, k) = clear_earlier_outputs(&out, &*session, keep)?;
                for w in w {
                    ctl.progress().warning(&w);
                    warnings.push(w);
                }
                kept = k;
            }
            if input_copy {
                // The user's file, which is the scenario as run: left as it is, never recorded
                // as this run's (a later --force keeps it).
                if !kept.iter().any(|k| k == "scenario.toml") {
                    kept.push("scenario.toml".into());
                }
            } else {
                out.write_bytes("scenario.toml", sc.text().as_bytes())?;
            }
            record_files(&out, &*session, &kept)?;
            Ok(out)
        })();
        created.map_err(|e| session.fail_alone(e))?
    } else {
        OutputDir::unwritten(&out_path)
    };
    let envelope = Envelope {
        method: sc.method()?,
        scenario: sc.text().to_string(),
        base: absolute(sc.base()),
        seed: session.seed(),
        resolved: resolved(&*session)?,
        position: 0,
        wall_seconds: 0.0,
        payload: Vec::new(),
    };
    if let Err(e) = session.begin(&out, true) {
        return Err(session.fail_alone(e));
    }
    if let Err(e) = record_files(&out, &*session, &kept) {
        return Err(session.fail_alone(e));
    }
    drive(session, out, envelope, ctl, warnings, kept, m.headline())
}

/// The scenario as a run with `seed` runs it: with its `seed` key set when `--seed` (or an
/// ensemble member's seed) differs from it, so that the saved `scenario.toml` reruns the run.
fn as_run(sc: &Scenario, seed: Option<u64>) -> Result<Scenario> {
    match seed {
        Some(s) if sc.seed()? != s => {
            sc.with_values(&[("seed".to_string(), toml::Value::Integer(s as i64))])
        }
        _ => Ok(sc.clone()),
    }
}

/// The file in which a run records, from its start and at each checkpoint, the files it has
/// written in its folder (with those it found there and kept), so that a later `--force`
/// removes those and nothing else; removed once `summary.json`, which lists them, is written.
pub const MANIFEST: &str = "manifest.json";

/// Files the driver itself writes in every run folder.
const DRIVER_FILES: [&str; 4] = ["scenario.toml", "summary.json", CHECKPOINT, MANIFEST];

/// Is the scenario file the run reads the `scenario.toml` of its output folder `out`? Then
/// the run leaves it as it is when it is the scenario as run, byte for byte (`true`), and is
/// refused otherwise: its as-run copy would overwrite the user's file.
fn input_in_folder(sc: &Scenario, out: &Path) -> Result<bool> {
    let (Some(origin), copy) = (sc.origin(), out.join("scenario.toml")) else {
        return Ok(false);
    };
    let same = match (std::fs::canonicalize(origin), std::fs::canonicalize(&copy)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if !same {
        return Ok(false);
    }
    if std::fs::read(&copy).is_ok_and(|b| b == sc.text().as_bytes()) {
        return Ok(true);
    }
    bail!(
        "{} is the scenario this run reads, and it lies in the output folder {}, where the run \
         writes the scenario as run (with its seed and any --set) as {}: that would overwrite \
         your file. Keep the scenario outside the output folder (move or copy it elsewhere and \
         run that), or choose another --out",
        origin.display(),
        out.display(),
        copy.display()
    )
}

/// The files an earlier run in `out` recorded as its own: the `files` of its summary.json (a
/// finished or failed run) and of its manifest (an interrupted or killed one), with those two.
fn recorded_files(out: &OutputDir) -> std::collections::BTreeSet<String> {
    let mut r = std::collections::BTreeSet::new();
    for name in ["summary.json", MANIFEST] {
        let v = std::fs::read(out.join(name))
            .ok()
            .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok());
        if let Some(files) = v.as_ref().and_then(|v| v["files"].as_array()) {
            r.insert(name.to_string());
            r.extend(files.iter().filter_map(|f| f.as_str().map(String::from)));
        }
    }
    r
}

/// `--force`: remove the files that an earlier run in `out` recorded as its own
/// ([`recorded_files`]), keep every other (and `keep`, the scenario the run reads). A kept file
/// this run would overwrite is refused before anything is removed. Returns what to tell the
/// user and the names kept.
fn clear_earlier_outputs(
    out: &OutputDir,
    s: &dyn Session,
    keep: Option<&str>,
) -> Result<(Vec<String>, Vec<String>)> {
    let recorded = recorded_files(out);
    let stem = |n: &str| Path::new(n).file_stem().map(|x| x.to_os_string());
    let mut removed = Vec::new();
    let mut kept = Vec::new();
    let mut clash = Vec::new();
    let entries =
        std::fs::read_dir(out.path()).with_context(|| out.path().display().to_string())?;
    for e in entries {
        let e = e?;
        let name = e.file_name().to_string_lossy().into_owned();
        if !e.file_type()?.is_file() {
            kept.push(name);
            continue;
        }
        // A temporary file of an atomic write (`NAME.partial`) of a recorded file.
        let partial = name.ends_with(".partial")
            && recorded
                .iter()
                .map(String::as_str)
                .chain(DRIVER_FILES)
                .any(|r| stem(r) == stem(&name))
            && !recorded.is_empty();
        if Some(name.as_str()) != keep && (recorded.contains(&name) || partial) {
            removed.push(name);
        } else {
            if Some(name.as_str()) != keep
                && (writes(s, &name) || DRIVER_FILES.contains(&name.as_str()))
            {
                clash.push(name.clone());
            }
            kept.push(name);
        }
    }
    removed.sort();
    kept.sort();
    clash.sort();
    if !clash.is_empty() {
        bail!(
            "--force: {} holds {}, which this run would overwrite, but no earlier colloidsim run \
             there recorded as its own (in summary.json or {MANIFEST}); nothing was removed. \
             Move them out of the folder, or choose another --out",
            out.path().display(),
            clash.join(", ")
        );
    }
    for name in &removed {
        let path = out.join(name);
        std::fs::remove_file(&path).with_context(|| path.display().to_string())?;
    }
    let mut w = Vec::new();
    if !removed.is_empty() {
        w.push(format!(
            "--force: removed {} file(s) an earlier run recorded as its own in {}: {}",
            removed.len(),
            out.path().display(),
            removed.join(", ")
        ));
    }
    if !kept.is_empty() {
        w.push(format!(
            "--force: kept what no earlier run recorded as its own in {}: {}",
            out.path().display(),
            kept.join(", ")
        ));
    }
    Ok((w, kept))
}

/// Does the session write the file `name`? Its pictures, which it names `NAME.png`, may be
/// written as `NAME.svg` too (`observe.figure_format`).
fn writes(s: &dyn Session, name: &str) -> bool {
    s.writes(name) || png_name(name).is_some_and(|png| s.writes(&png))
}

/// Record in [`MANIFEST`] the files of the run in `out` so far: those there now that the run
/// writes, but not the `kept` ones it found there (the writer; atomically).
fn record_files(out: &OutputDir, s: &dyn Session, kept: &[String]) -> Result<()> {
    if !s.is_writer() {
        return Ok(());
    }
    let mut files = Vec::new();
    for e in std::fs::read_dir(out.path()).with_context(|| out.path().display().to_string())? {
        let e = e?;
        let name = e.file_name().to_string_lossy().into_owned();
        let ours = writes(s, &name) || DRIVER_FILES.contains(&name.as_str());
        if e.file_type()?.is_file() && ours && name != MANIFEST && !kept.contains(&name) {
            files.push(name);
        }
    }
    write_manifest(out, files, kept)
}

/// Write [`MANIFEST`]: `files` (with those it already lists) and `kept`.
fn write_manifest(out: &OutputDir, files: Vec<String>, kept: &[String]) -> Result<()> {
    let mut all: std::collections::BTreeSet<String> = files.into_iter().collect();
    if let Some(old) = std::fs::read(out.join(MANIFEST))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        && let Some(f) = old["files"].as_array()
    {
        all.extend(f.iter().filter_map(|x| x.as_str().map(String::from)));
    }
    out.write_json(
        MANIFEST,
        &json!({ "software": crate::software(), "files": all, "kept": kept }),
    )?;
    Ok(())
}

/// The names a run found in its folder and kept (from its manifest).
fn kept_files(out: &OutputDir) -> Vec<String> {
    std::fs::read(out.join(MANIFEST))
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
        .and_then(|v| {
            v["kept"].as_array().map(|k| {
                k.iter()
                    .filter_map(|x| x.as_str().map(String::from))
                    .collect()
            })
        })
        .unwrap_or_default()
}

/// A restart puts back `scenario.toml` as the run started with it (the checkpoint's
/// `scenario`) when it was deleted or edited; an edited copy is kept as
/// `scenario.toml.edited` (or `.edited.2`, ... : never over another file). Returns the
/// warning to give.
fn restore_scenario(out: &OutputDir, text: &str) -> Result<Option<String>> {
    let path = out.join("scenario.toml");
    match std::fs::read(&path) {
        Ok(b) if b == text.as_bytes() => Ok(None),
        Ok(_) => {
            let mut k = 1;
            let kept = loop {
                let name = if k == 1 {
                    "scenario.toml.edited".to_string()
                } else {
                    format!("scenario.toml.edited.{k}")
                };
                match std::fs::hard_link(&path, out.join(&name)) {
                    Ok(()) => break name,
                    Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && k < 1000 => k += 1,
                    Err(e) => {
                        return Err(anyhow::anyhow!(
                            "{}: edited since the run started, and it cannot be kept as {name} \
                             ({e}); move it away and restart",
                            path.display()
                        ));
                    }
                }
            };
            out.write_bytes("scenario.toml", text.as_bytes())?;
            Ok(Some(format!(
                "{} was edited: restored the one the run started with; the edited copy kept \
                 as {kept}",
                path.display()
            )))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            out.write_bytes("scenario.toml", text.as_bytes())?;
            Ok(Some(format!(
                "{} was missing: restored the one the run started with",
                path.display()
            )))
        }
        Err(e) => Err(anyhow::anyhow!("{}: {e}", path.display())),
    }
}

/// Continue the interrupted run in `dir` from its checkpoint, bitwise as if it had never
/// stopped. `sc`, when given, must be the scenario the run started with (by default the one
/// saved in the checkpoint); `seed`, when given, must be the run's.
pub fn resume(
    dir: &Path,
    sc: Option<&Scenario>,
    seed: Option<u64>,
    ctl: &Control,
) -> Result<Report> {
    resume_with(dir, sc, seed, ctl, None)
}

/// [`resume`] decomposed over the ranks of `comm`, however many ranks the interrupted run had.
pub fn resume_decomposed(
    dir: &Path,
    sc: Option<&Scenario>,
    seed: Option<u64>,
    ctl: &Control,
    comm: Box<dyn Exchange>,
) -> Result<Report> {
    resume_with(dir, sc, seed, ctl, Some(comm))
}

fn resume_with(
    dir: &Path,
    sc: Option<&Scenario>,
    seed: Option<u64>,
    ctl: &Control,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Report> {
    if !dir.is_dir() {
        bail!("--restart {}: no such folder", dir.display());
    }
    let out = OutputDir::reopen(dir)?;
    let summary = out.join("summary.json");
    if summary.exists() {
        let failed = std::fs::read(&summary)
            .ok()
            .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
            .is_some_and(|v| v["completed"] == false);
        if failed {
            bail!(
                "--restart {}: this run stopped with an error (summary.json says completed = false) and keeps no checkpoint; start a new run with --out",
                dir.display()
            );
        }
        bail!(
            "--restart {}: this run is complete (summary.json is written); nothing to continue. Start a new run with --out",
            dir.display()
        );
    }
    let file = out.join(CHECKPOINT);
    if !file.exists() {
        bail!(
            "--restart {}: no {CHECKPOINT} to continue from (checkpoints are written every 10 % of a run and on Ctrl-C)",
            dir.display()
        );
    }
    let envelope = checkpoint::read(&file)?;
    let sc = match sc {
        Some(given) => {
            // The checkpoint keeps the scenario with the run's seed (since 2026-12-04; before,
            // without a `--seed` override): either matches.
            let seeded = as_run(given, Some(seed.unwrap_or(envelope.seed)))?;
            let s = if seeded.text() == envelope.scenario {
                seeded
            } else {
                given.clone()
            };
            if s.text() != envelope.scenario {
                bail!(
                    "--restart {}: {} differs from the scenario this run started with (saved as {})",
                    dir.display(),
                    s.origin()
                        .map_or("the scenario given".into(), |p| p.display().to_string()),
                    out.join("scenario.toml").display()
                );
            }
            s.clone()
        }
        None => Scenario::from_toml(&envelope.scenario, &envelope.base)?,
    };
    if let Some(s) = seed {
        crate::seed32(s)?;
    }
    let m = registry::of(&sc)?;
    set_figure_format(out.path(), figure_format(&sc.table()?)?);
    let seed = seed.unwrap_or(envelope.seed);
    let mut session = m
        .restore(&sc, seed, &out, &envelope, comm)
        .with_context(|| format!("--restart {}", dir.display()))?;
    let now = resolved(&*session)?;
    if now != envelope.resolved {
        bail!(
            "--restart {}: the resolved scenario differs from the checkpoint's: {}",
            dir.display(),
            changed_keys(&now, &envelope.resolved)
        );
    }
    if session.position() != envelope.position {
        bail!(
            "{}: the state is at step {}, the checkpoint says {}",
            file.display(),
            session.position(),
            envelope.position
        );
    }
    let mut warnings = session.warnings();
    let kept = kept_files(&out);
    if session.is_writer() {
        let restored = restore_scenario(&out, &envelope.scenario);
        if let Some(w) = restored.map_err(|e| session.fail_alone(e))? {
            warnings.push(w);
        }
    }
    for w in &warnings {
        ctl.progress().warning(w);
    }
    if let Err(e) = session.begin(&out, false) {
        return Err(session.fail_alone(e));
    }
    drive(session, out, envelope, ctl, warnings, kept, m.headline())
}

/// Write a checkpoint at the session's position (every rank of a decomposed run takes part;
/// the writer writes).
fn save(
    s: &mut dyn Session,
    out: &OutputDir,
    env: &mut Envelope,
    wall: f64,
    kept: &[String],
) -> Result<()> {
    s.flush().map_err(|e| s.fail_alone(e))?;
    env.payload = s.save(out)?;
    env.position = s.position();
    env.wall_seconds = wall;
    if s.is_writer() {
        let written = checkpoint::encode(env)
            .and_then(|b| Ok(out.write_bytes(CHECKPOINT, &b)?))
            .and_then(|_| record_files(out, s, kept));
        written.map_err(|e| s.fail_alone(e))?;
    }
    env.payload = Vec::new();
    s.after_save(out);
    Ok(())
}

/// The progress line: step and total, the session's own status (simulated time,
/// temperature) and the throughput since this process took the run up at `pos0`.
fn status_line(s: &dyn Session, pos0: u64, seconds: f64) -> String {
    let pos = s.position();
    let mut line = format!("step {pos}/{}", s.total());
    let own = s.status();
    if !own.is_empty() {
        line.push_str(", ");
        line.push_str(&own);
    }
    if seconds > 0.0 {
        let rate = (pos - pos0) as f64 / seconds;
        line.push_str(&format!(", {} steps/s", significant(rate)));
    }
    line
}

/// `x` to three significant digits, without an exponent below a million.
pub(crate) fn significant(x: f64) -> String {
    if !x.is_finite() || x == 0.0 || x.abs() >= 1e6 || x.abs() < 1e-3 {
        return format!("{x:.3e}");
    }
    let digits = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.digits$}")
}

/// [`Session::advance`], with a trajectory frame refused for a state that is not finite taken
/// as the reason the run stops (completed = false, naming the step and the particle), as an
/// engine's own non-finite check is.
fn advance(s: &mut dyn Session, until: u64) -> Result<Option<String>> {
    match s.advance(until) {
        Err(e) => {
            let non_finite = e.chain().find_map(|c| match c.downcast_ref() {
                Some(g @ colloidsim_particles::gsd::GsdError::NonFinite { .. }) => {
                    Some(g.to_string())
                }
                _ => None,
            });
            match non_finite {
                Some(why) => Ok(Some(why)),
                None => Err(e),
            }
        }
        other => other,
    }
}

/// Work units per chunk are adapted so that a chunk takes about this long: interrupts are
/// seen within it and the progress moves. Outputs never depend on the chunks.
const CHUNK_SECONDS: f64 = 0.2;

fn drive(
    mut s: Box<dyn Session>,
    out: OutputDir,
    mut env: Envelope,
    ctl: &Control,
    mut warnings: Vec<String>,
    kept: Vec<String>,
    headline: &'static [crate::method::Headline],
) -> Result<Report> {
    let total = s.total();
    let hooks = Hooks::from_env();
    ctl.progress().begin(&s.label(), total, s.position());
    let start = Instant::now();
    let pos0 = s.position();
    let wall0 = env.wall_seconds;
    let wall = || wall0 + start.elapsed().as_secs_f64();
    let mut timer = Timer::new(ctl, &hooks);
    // The steps run on a worker of the thread pool, so that each step's parallel passes start
    // without a hand-over from this thread.
    let failure = rayon::scope(|_| -> Result<Option<String>> {
        // One unit first (a unit can be long: an MC sweep over 1e8 cells), so that an interrupt
        // is seen soon; the chunk doubles while chunks are short.
        let mut chunk = 1u64;
        // Interrupted where no checkpoint can be written before the end: run to the end.
        let mut draining = false;
        loop {
            let pos = s.position();
            if pos >= total {
                return Ok(None);
            }
            if hooks.kill == Some(pos) {
                s.flush()?;
                eprintln!("killed at step {pos} (test hook)");
                std::process::exit(3);
            }
            if hooks.interrupt == Some(pos) {
                ctl.interrupt();
            }
            if hooks.pause == Some(pos) {
                // One write, so that the lines of several ranks on one pipe do not interleave.
                let line = format!("paused at step {pos} (test hook)\n");
                let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
                let waited = Instant::now();
                while !ctl.interrupted()
                    && !timer.must_stop(pos, s.stop_point(), 0)
                    && waited.elapsed().as_secs() < 60
                {
                    std::thread::sleep(std::time::Duration::from_millis(5));
                }
            }
            // The next chunk ends at a due checkpoint or a test hook's position, if sooner.
            let due = s.next_checkpoint().filter(|&c| c > pos && c < total);
            let end_of = |chunk: u64| {
                let mut next = pos.saturating_add(chunk).min(total);
                for c in [due, hooks.interrupt, hooks.kill, hooks.pause]
                    .into_iter()
                    .flatten()
                {
                    if c > pos {
                        next = next.min(c);
                    }
                }
                next
            };
            if !draining && timer.must_stop(pos, s.stop_point(), end_of(chunk) - pos) {
                ctl.stop(Stop::WallTime);
            }
            // The ranks of a decomposed run go on alike: the same chunk, the same stop.
            let code;
            (chunk, code) = s.agree(chunk, ctl.stop_cause().map_or(0, Stop::code));
            let agreed = Stop::from_code(code);
            if let Some(cause) = agreed
                && !ctl.interrupted()
            {
                ctl.stop(cause);
            }
            if let Some(cause) = agreed.filter(|_| !draining) {
                let stop = s.stop_point();
                if stop >= total {
                    draining = true;
                } else {
                    if stop > pos {
                        ctl.progress().message(&format!(
                            "{} at step {pos}: running on to step {stop} to write a checkpoint ({})",
                            cause.what(),
                            cause.again()
                        ));
                        let t = Instant::now();
                        if let Some(why) = advance(&mut *s, stop)? {
                            return Ok(Some(why));
                        }
                        timer.stepped(stop - pos, t.elapsed().as_secs_f64());
                    }
                    save(&mut *s, &out, &mut env, wall(), &kept)?;
                    let outputs = s.interim_outputs(&out)?;
                    record_files(&out, &*s, &kept)?;
                    ctl.progress().end();
                    return Err(Interrupted {
                        cause,
                        started: pos0,
                        at: pos,
                        checkpoint: s.position(),
                        out: out.path().to_path_buf(),
                        outputs,
                    }
                    .into());
                }
            }
            let next = end_of(chunk);
            let t = Instant::now();
            if let Some(why) = advance(&mut *s, next)? {
                return Ok(Some(why));
            }
            let secs = timer.stepped(next - pos, t.elapsed().as_secs_f64());
            if secs < 0.5 * CHUNK_SECONDS && next - pos == chunk {
                chunk = (chunk * 2).min(1 << 20);
            } else if secs > 2.0 * CHUNK_SECONDS {
                chunk = (chunk / 2).max(1);
            }
            if due == Some(s.position()) {
                let t = Instant::now();
                save(&mut *s, &out, &mut env, wall(), &kept)?;
                timer.saved(t.elapsed().as_secs_f64());
            }
            ctl.progress().advance(s.position());
            ctl.progress()
                .status(&status_line(&*s, pos0, start.elapsed().as_secs_f64()));
        }
    });
    ctl.progress().end();
    let failure = failure?;
    s.flush()?;
    let wall_seconds = wall();
    let position = s.position();
    // No rank exchanges anything from here on: an error on the writer alone reaches the
    // command's last agreement like any other.
    let s_is_writer = s.is_writer();
    let fin = s.finish(&out, wall_seconds, failure.as_deref())?;
    for w in &fin.warnings {
        ctl.progress().warning(w);
    }
    warnings.extend(fin.warnings);
    let mut summary = fin.summary;
    if s_is_writer {
        crate::method::complete_headline(headline, &mut summary, &out);
    }
    // The scenario.toml the run was given, in its folder, is the user's, not the run's.
    let mut files = Vec::new();
    if !kept.iter().any(|k| k == "scenario.toml") {
        files.push("scenario.toml".to_string());
    }
    // The pictures the method names NAME.png, as the files of the folder's format.
    files.extend(
        fin.files
            .into_iter()
            .filter(|f| f != "scenario.toml")
            .flat_map(|f| picture_files(out.path(), &f)),
    );
    // Every number is written finite or as an empty field (JSON: null): say where and why.
    let non_finite = out.non_finite();
    for n in non_finite.iter().filter(|n| n.reason.is_none()) {
        let w = format!(
            "{}: column '{}' has {} row(s) that are not numbers (from data row {}), written as empty fields; see non_finite in summary.json",
            n.file, n.column, n.rows, n.first_row
        );
        ctl.progress().warning(&w);
        warnings.push(w);
    }
    let nulls = null_reasons(&summary, &out);
    if let Some(m) = summary.as_object_mut() {
        if !non_finite.is_empty() {
            m.insert("non_finite".into(), json!(non_finite));
        }
        if !nulls.is_empty() {
            m.insert("nulls".into(), json!(nulls));
        }
        m.insert("completed".into(), json!(failure.is_none()));
        m.insert("error".into(), json!(failure));
        m.insert("files".into(), json!(files));
    }
    if s_is_writer {
        write_manifest(&out, files.clone(), &kept)?;
        out.write_json("summary.json", &summary)?;
        // The run is over: its checkpoint is no longer needed (a restart now refuses), and
        // summary.json lists its files.
        let _ = std::fs::remove_file(out.join(CHECKPOINT));
        let _ = std::fs::remove_file(out.join(MANIFEST));
    }
    if let Some(message) = failure {
        return Err(Failed {
            message,
            position,
            out: out.path().to_path_buf(),
        }
        .into());
    }
    Ok(Report {
        out: out.path().to_path_buf(),
        summary,
        files,
        warnings,
        message: fin.message,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A NaN or infinity becomes `null` in JSON: every such value of a summary is listed with
    /// the method's reason, the `why_null` beside it, or the generic one; the resolved
    /// parameters and the texts that say why are not values.
    #[test]
    fn every_null_of_a_summary_has_its_reason() {
        let dir = tempfile::tempdir().unwrap();
        let out = OutputDir::create(dir.path().join("o"), false).unwrap();
        out.explain("summary.json", "viscosity", "not observed");
        let summary = json!({
            "parameters": { "drive": null },
            "viscosity": f64::NAN,
            "temperature": [1.0, f64::INFINITY],
            "k": { "value": null, "why_null": "no force", "note": null },
            "d": { "value": 2.0, "why_null": null, "velocity_note": null },
            "steps": 10,
        });
        let nulls = null_reasons(&summary, &out);
        let want: std::collections::BTreeMap<String, String> = [
            ("k.value", "see k.why_null"),
            ("temperature[1]", UNEXPLAINED_NULL),
            ("viscosity", "not observed"),
        ]
        .into_iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
        assert_eq!(nulls, want);
    }
}
