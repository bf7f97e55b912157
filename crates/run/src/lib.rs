//! The one run path of colloidsim, used by the CLI and by Python alike.
//!
//! A [`Scenario`] (TOML text) names a method; the [`method`] registry turns it into that
//! method's [`Session`](method::Session) (engine + observers), and [`run`] drives every session
//! the same way: output folder, observers on their triggers, checkpoints every ~10 % and on
//! interrupt, verified restarts, atomic writers and `summary.json`. [`theory`] computes a
//! scenario's continuum counterpart, [`check`] validates it, [`keys`] lists its keys.

pub mod analyse;
pub mod checkpoint;
pub mod control;
mod driver;
pub mod engine;
pub mod ensemble;
pub mod estimate;
pub mod extrapolate;
pub mod keys;
pub mod method;
pub mod methods;
pub mod output;
pub mod registry;
pub mod render;
pub mod scenario;

mod bd_replica;
pub mod two_body;

pub use analyse::{AnalyseOptions, analyse};
pub use control::{Control, Progress, Silent, Stop};
pub use driver::{resume, resume_decomposed, run, run_decomposed};
pub use engine::{Engine, ParticleTypes, StateChange};
pub use ensemble::{EnsembleOptions, ensemble, resume_ensemble};
pub use extrapolate::{ExtrapolateOptions, extrapolate};
pub use method::{Checked, Finished, Method};
pub use render::{RenderOptions, render};
pub use scenario::Scenario;

use std::path::PathBuf;

/// The software name and version written into every summary.
pub fn software() -> String {
    format!("colloidsim {}", env!("CARGO_PKG_VERSION"))
}

/// Options of a run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Output folder (default: the scenario's name, in the current folder).
    pub out: Option<PathBuf>,
    /// Seed replacing the scenario's (0 ..= 4294967295).
    pub seed: Option<u64>,
    /// Write into a folder that already holds files (this method's earlier outputs are
    /// replaced; other files are kept and listed).
    pub force: bool,
}

/// Options of a theory solve.
#[derive(Debug, Clone, Default)]
pub struct TheoryOptions {
    /// Output folder (default: the scenario's name followed by `-theory`).
    pub out: Option<PathBuf>,
    /// Grid spacing (default: fine enough for the scenario).
    pub dx: Option<f64>,
    /// Write into a folder that already holds files.
    pub force: bool,
    /// Droplet DDFT only: `free-draining` (default) or `rpy`.
    pub hydrodynamics: Option<String>,
    /// Droplet DDFT with RPY only (one size or a mixture): the pair correlation of the flux,
    /// `dilute` (default), `trokhymchuk` or `trokhymchuk-n3`.
    pub pair: Option<String>,
}

/// What a finished run or theory solve produced.
#[derive(Debug, Clone)]
pub struct Report {
    /// The output folder.
    pub out: PathBuf,
    /// `summary.json` as written.
    pub summary: serde_json::Value,
    /// The files written (besides `summary.json`).
    pub files: Vec<String>,
    /// Warnings met on the way.
    pub warnings: Vec<String>,
    /// One line saying what was done.
    pub message: String,
}

/// A run stopped on request (Ctrl-C, a signal, the caller's interrupt, the wall-time budget)
/// after writing a checkpoint.
#[derive(Debug, Clone, thiserror::Error)]
#[error(
    "{} at step {at}; checkpoint written at step {checkpoint} in {}{}",
    cause.what(),
    out.display(),
    if outputs.is_empty() { String::new() } else {
        format!(" with the outputs so far ({}; summary.json is written when the run completes)", outputs.join(", "))
    }
)]
pub struct Interrupted {
    /// Why it stopped.
    pub cause: Stop,
    /// Position this process took the run up at (0, or a restart's checkpoint).
    pub started: u64,
    /// Position at which the interrupt was seen.
    pub at: u64,
    /// Position of the checkpoint written.
    pub checkpoint: u64,
    /// The run folder (continue with `--restart` on it).
    pub out: PathBuf,
    /// Outputs written so far.
    pub outputs: Vec<String>,
}

/// A run that could not go on (e.g. non-finite positions, a heating time step); its outputs
/// so far and a `summary.json` with `completed = false` are written.
#[derive(Debug, Clone, thiserror::Error)]
#[error(
    "{message}\nthe outputs up to step {position} are in {} (summary.json says completed = false)",
    out.display()
)]
pub struct Failed {
    /// Why it stopped.
    pub message: String,
    /// Position reached.
    pub position: u64,
    /// The run folder.
    pub out: PathBuf,
}

/// Validate a scenario (`colloidsim check`).
pub fn check(sc: &Scenario) -> anyhow::Result<Checked> {
    let m = registry::of(sc)?;
    let units = unit_warnings(sc, m)?;
    let mut checked = first_the_units(m.check(sc), &units)?;
    checked.warnings.splice(0..0, units);
    Ok(checked)
}

/// Values of `sc` that almost surely mean a unit mistake ([`keys::suspicious`]).
pub(crate) fn unit_warnings(sc: &Scenario, m: &dyn method::Method) -> anyhow::Result<Vec<String>> {
    Ok(keys::suspicious(&sc.table()?, m.keys()))
}

/// A scenario refused where a value also looks like a unit mistake: the unit mistake is
/// reported first (it is the likely cause of the refusal).
pub(crate) fn first_the_units<T>(r: anyhow::Result<T>, units: &[String]) -> anyhow::Result<T> {
    match r {
        Err(e) if !units.is_empty() => Err(e.context(format!(
            "{}\n(probably the cause of what follows)",
            units.join("\n")
        ))),
        other => other,
    }
}

/// The continuum counterpart of a scenario (`colloidsim theory`).
pub fn theory(sc: &Scenario, opts: &TheoryOptions, ctl: &Control) -> anyhow::Result<Report> {
    let m = registry::of(sc)?;
    if opts.hydrodynamics.is_some() && m.names()[0] != "droplet-bd" {
        anyhow::bail!("--hydrodynamics applies to droplet-bd scenarios only");
    }
    if opts.pair.is_some() && m.names()[0] != "droplet-bd" {
        anyhow::bail!("--pair applies to droplet-bd scenarios only");
    }
    let mut report = m.theory(sc, opts, ctl)?;
    // The pictures were drawn in the folder's formats: name the files written.
    report.files = report
        .files
        .iter()
        .flat_map(|f| output::plot::picture_files(&report.out, f))
        .collect();
    Ok(report)
}

/// The output folder of `colloidsim theory` (`--out`, or the scenario's name and `-theory`),
/// created, its pictures in the scenario's `observe.figure_format`.
pub(crate) fn theory_folder(
    src: &Scenario,
    opts: &TheoryOptions,
) -> anyhow::Result<colloidsim_core::output::OutputDir> {
    use anyhow::Context;
    let out = opts
        .out
        .clone()
        .unwrap_or_else(|| format!("{}-theory", src.name()).into());
    let format = keys::shared::figure_format(&src.table()?)?;
    let dir = colloidsim_core::output::OutputDir::create(&out, opts.force)
        .with_context(|| format!("cannot use output folder {}", out.display()))?;
    output::plot::set_figure_format(dir.path(), format);
    Ok(dir)
}

/// Every key of a method's scenarios (`colloidsim keys METHOD`).
pub fn keys(method: &str) -> anyhow::Result<Vec<keys::Key>> {
    Ok(registry::find(method)?
        .keys()
        .iter()
        .map(keys::Key::from)
        .collect())
}

/// The reference page of a method's keys (`colloidsim keys METHOD --format markdown`, kept as
/// `docs/keys/METHOD.md`; a test fails when the page differs from what the binary prints).
pub fn keys_page(method: &str) -> anyhow::Result<String> {
    let m = registry::find(method)?;
    let name = m.names()[0];
    let docs = m.docs().strip_prefix("docs/").unwrap_or(m.docs());
    let listed: Vec<keys::Key> = m.keys().iter().map(keys::Key::from).collect();
    let also = match m.names() {
        [_] => String::new(),
        [_, rest @ ..] => format!(
            " (also `method = {}`)",
            rest.iter()
                .map(|n| format!("\"{n}\""))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        [] => String::new(),
    };
    Ok(format!(
        "# Keys of `{name}` scenarios\n\n\
         <!-- Written by `colloidsim keys {name} --format markdown` from the keys' declarations; \
         do not edit by hand. -->\n\n\
         {}{also}. Every key with its unit, its default (what the method takes when the key is \
         left out) and the values allowed; unknown keys are errors. How to use them: \
         [{docs}](../{docs}).\n\n{}",
        m.about(),
        keys::markdown(&listed)
    ))
}

/// An engine built from a scenario, to be stepped by hand.
pub fn engine(sc: &Scenario, seed: Option<u64>) -> anyhow::Result<Box<dyn Engine>> {
    registry::of(sc)?.engine(sc, seed)
}

/// Validate a seed from the scenario or the caller: the counter-based streams take 32 bits.
pub fn seed32(seed: u64) -> anyhow::Result<u32> {
    Ok(colloidsim_core::param::seed("seed", seed)?)
}
