//! The interface every method implements once ([`Method`], [`Session`]); the methods are listed
//! in [`crate::registry`].
//!
//! A [`Method`] turns a scenario into a [`Session`] (a fresh one, or one restored from a
//! checkpoint); the driver ([`crate::run`]) then owns everything every run shares: the output
//! folder, Ctrl-C, the checkpoint cadence and envelope, restart checks, test hooks, progress and
//! `summary.json`. A session owns its engine and its observers, and writes its own tables.

use crate::checkpoint::Envelope;
use crate::control::Control;
use crate::keys::Spec;
use crate::{Report, TheoryOptions};
use anyhow::{Result, bail};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::OutputDir;

/// The outcome of `check`: the resolved parameters and any warnings.
#[derive(Debug, Clone)]
pub struct Checked {
    /// The resolved parameters (what `colloidsim check` prints).
    pub resolved: serde_json::Value,
    /// Warnings about the scenario.
    pub warnings: Vec<String>,
}

/// What a finished (or failed) session leaves: the summary fields of the method, the files it
/// wrote and the line the CLI prints.
#[derive(Debug, Clone)]
pub struct Finished {
    /// The method's summary fields (the driver adds `completed`, `error` and `files`).
    pub summary: serde_json::Value,
    /// Files written beside `summary.json`.
    pub files: Vec<String>,
    /// One line saying what was done.
    pub message: String,
    /// Warnings met while writing (e.g. a picture that could not be drawn).
    pub warnings: Vec<String>,
}

impl Finished {
    /// What a rank that does not write reports (a decomposed run's ranks but 0).
    pub fn nothing_written() -> Self {
        Self {
            summary: serde_json::json!({}),
            files: Vec::new(),
            message: String::new(),
            warnings: Vec::new(),
        }
    }
}

/// One method's family of scenarios (`method = "..."`).
pub trait Method: Sync {
    /// The `method` values this method answers to (the first is its name).
    fn names(&self) -> &'static [&'static str];
    /// One line for `colloidsim --help`.
    fn about(&self) -> &'static str;
    /// Where its scenario keys and outputs are documented.
    fn docs(&self) -> &'static str;
    /// Validate a scenario (everything `run` would validate before it starts).
    fn check(&self, sc: &Scenario) -> Result<Checked>;
    /// A fresh session; nothing is written.
    ///
    /// With `comm`, the session is decomposed in space over its ranks (docs/parallel.md):
    /// every rank calls this and then drives its session in step; rank 0 writes. A method that
    /// runs on one rank refuses it ([`on_one_rank`]).
    fn start(
        &self,
        sc: &Scenario,
        seed: Option<u64>,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Box<dyn Session>>;
    /// The session a verified checkpoint continues, run with `seed` (the checkpoint's, or the
    /// one asked for); decomposed over the ranks of `comm` when given, which need not be as
    /// many as the interrupted run's.
    fn restore(
        &self,
        sc: &Scenario,
        seed: u64,
        out: &OutputDir,
        envelope: &Envelope,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Box<dyn Session>>;
    /// Does `colloidsim theory` apply?
    fn has_theory(&self) -> bool {
        false
    }
    /// The continuum counterpart of a scenario on the run's grid and file names.
    fn theory(&self, sc: &Scenario, _opts: &TheoryOptions, _ctl: &Control) -> Result<Report> {
        bail!(
            "{}: method '{}' has no theory counterpart",
            sc.label(),
            self.names()[0]
        )
    }
    /// Every scenario key, declared once: unit, default, allowed range and meaning.
    fn keys(&self) -> &'static [Spec];
    /// An engine a script can step by hand (Python's engine classes).
    fn engine(&self, sc: &Scenario, seed: Option<u64>) -> Result<Box<dyn crate::Engine>>;
    /// Its headline observables, declared once: the numbers of `summary.json` that an ensemble
    /// tabulates and pictures against the swept key (`headline.csv`, docs/parallel.md).
    fn headline(&self) -> &'static [Headline];
}

/// One headline observable of a method: a number (or a labelled list of numbers) of its
/// `summary.json`, which `colloidsim ensemble` writes per sweep point with its error between
/// replicas (`headline.csv`) and pictures against the first swept key.
#[derive(Debug, Clone, Copy)]
pub struct Headline {
    /// Its column in `headline.csv` (`NAME`, `NAME_err`); with `labels`, one column per label
    /// (`NAME_LABEL`).
    pub name: &'static str,
    /// Where it sits in `summary.json`: the keys from the top, joined by dots
    /// (`compressibility.value`). A number or `null`; with `labels`, a list of them.
    pub path: &'static str,
    /// The path of the list of texts that name the elements of a list value (e.g. the output
    /// times `t0.25`), or `None` for one number.
    pub labels: Option<&'static str>,
    /// Its unit.
    pub unit: &'static str,
    /// What it is.
    pub doc: &'static str,
    /// Why it is `null` in a run that does not measure it: where the method's summary lacks
    /// it, the driver writes `null` with this reason ([`complete_headline`]).
    pub absent: &'static str,
}

/// The value at the dotted `path` of `v` (`None` when a key is missing).
pub fn at<'a>(v: &'a serde_json::Value, path: &str) -> Option<&'a serde_json::Value> {
    path.split('.').try_fold(v, |v, k| v.get(k))
}

/// One column of the headline observables a summary gives ([`headline_columns`]).
#[derive(Debug, Clone, PartialEq)]
pub struct HeadlineValue {
    /// The column: `NAME`, or `NAME_LABEL` for an element of a labelled list.
    pub column: String,
    /// The observable's index in the method's declaration.
    pub of: usize,
    /// Where the value sits in `summary.json` (`compressibility.value`, `outer_shell.phi[2]`).
    pub path: String,
    /// The value (`None` where it is `null` or absent).
    pub value: Option<f64>,
}

/// The columns a summary gives a method's headline observables, in declaration order: a
/// number gives `NAME`; a labelled list `NAME_LABEL` per label, nothing when it is absent.
pub fn headline_columns(headline: &[Headline], summary: &serde_json::Value) -> Vec<HeadlineValue> {
    let mut cols = Vec::new();
    for (of, h) in headline.iter().enumerate() {
        let value = at(summary, h.path);
        match h.labels {
            None => cols.push(HeadlineValue {
                column: h.name.to_string(),
                of,
                path: h.path.to_string(),
                value: value.and_then(|v| v.as_f64()),
            }),
            Some(labels) => {
                let labels = at(summary, labels).and_then(|l| l.as_array());
                let values = value.and_then(|v| v.as_array());
                if let (Some(labels), Some(values)) = (labels, values) {
                    for (i, (l, v)) in labels.iter().zip(values).enumerate() {
                        let l = l.as_str().map_or_else(|| l.to_string(), String::from);
                        cols.push(HeadlineValue {
                            column: format!("{}_{l}", h.name),
                            of,
                            path: format!("{}[{i}]", h.path),
                            value: v.as_f64(),
                        });
                    }
                }
            }
        }
    }
    cols
}

/// Give every declared headline observable a place in `summary`: one the method did not write
/// becomes `null` with its declared reason (`absent`), so that every summary of a method holds
/// all of them (a labelled one is left to its method).
pub(crate) fn complete_headline(
    headline: &[Headline],
    summary: &mut serde_json::Value,
    out: &OutputDir,
) {
    if !summary.is_object() {
        return;
    }
    for h in headline.iter().filter(|h| h.labels.is_none()) {
        if at(summary, h.path).is_some() {
            continue;
        }
        let mut v = &mut *summary;
        let keys: Vec<&str> = h.path.split('.').collect();
        for (i, k) in keys.iter().enumerate() {
            let Some(map) = v.as_object_mut() else {
                break;
            };
            let last = i + 1 == keys.len();
            let next = map.entry(k.to_string()).or_insert_with(|| {
                if last {
                    serde_json::Value::Null
                } else {
                    serde_json::json!({})
                }
            });
            v = next;
        }
        out.explain("summary.json", h.path, h.absent);
    }
}

/// A run of one scenario: its engine, its observers and where it stands. Progress is counted
/// in *positions* (steps, over all replicas), which is also what test hooks and checkpoints use.
pub trait Session: Send {
    /// Label of the progress bar.
    fn label(&self) -> String;
    /// Positions of the whole run.
    fn total(&self) -> u64;
    /// Positions done.
    fn position(&self) -> u64;
    /// The run's seed.
    fn seed(&self) -> u64;
    /// Where the run stands beyond its position, for the progress line: the simulated time
    /// with its unit, and the temperature where the method has one (e.g. `t = 0.12 tau_D,
    /// T = 1.003`).
    fn status(&self) -> String {
        String::new()
    }
    /// The resolved parameters (JSON; `parameters` of `summary.json`).
    fn parameters(&self) -> serde_json::Value;
    /// Warnings about the scenario, printed before the run.
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// Does this session write the file `name` (so that `--force` replaces it)?
    fn writes(&self, name: &str) -> bool;
    /// The output folder is ready: open trajectories; on a fresh run take the observations of
    /// position 0.
    fn begin(&mut self, out: &OutputDir, fresh: bool) -> Result<()>;
    /// The next position after the current one at which a regular checkpoint is due.
    fn next_checkpoint(&self) -> Option<u64>;
    /// The first position from the current one at which a checkpoint can be written (some
    /// engines restart bitwise only at list rebuilds).
    fn stop_point(&self) -> u64 {
        self.position()
    }
    /// Run up to position `until`, taking every observation due on the way. `Ok(Some(why))`:
    /// the run cannot go on (e.g. it went non-finite); the driver writes the outputs so far and
    /// a summary saying so.
    fn advance(&mut self, until: u64) -> Result<Option<String>>;
    /// Bring trajectories to the disk.
    fn flush(&mut self) -> Result<()>;
    /// The method's checkpoint state at the current position (the driver wraps and writes it).
    fn save(&mut self, out: &OutputDir) -> Result<Vec<u8>>;
    /// `checkpoint.bin` now names the state just saved: remove what the previous checkpoint
    /// needed beside it.
    fn after_save(&mut self, _out: &OutputDir) {}
    /// Outputs written when the run is interrupted (the tables so far); their names.
    fn interim_outputs(&mut self, _out: &OutputDir) -> Result<Vec<String>> {
        Ok(Vec::new())
    }
    /// The ranks a decomposed run is spread over (`None` on one process); the three methods
    /// below follow from it.
    fn exchange(&self) -> Option<&dyn Exchange> {
        None
    }
    /// Whether this rank writes the outputs (rank 0 of a decomposed run; always otherwise).
    fn is_writer(&self) -> bool {
        self.exchange().is_none_or(|c| c.rank() == 0)
    }
    /// Decomposed runs: every rank's chunk of positions and the stop it saw ([`Stop::code`],
    /// 0 for none), combined so that all ranks go on alike (rank 0's chunk; the largest code,
    /// so that every rank stops, for the same cause, if any rank was asked to).
    ///
    /// [`Stop::code`]: crate::Stop::code
    fn agree(&mut self, chunk: u64, stop: u8) -> (u64, u8) {
        agree_over(self.exchange(), chunk, stop)
    }
    /// An error on this rank alone (a file the writer could not write): returned as it is on
    /// one rank; in a decomposed run, where the other ranks cannot learn of it, printed and the
    /// job ended on every rank.
    fn fail_alone(&self, e: anyhow::Error) -> anyhow::Error {
        fail_alone_over(self.exchange(), e)
    }
    /// Write every output; `failure` says why the run stopped early.
    fn finish(
        self: Box<Self>,
        out: &OutputDir,
        wall_seconds: f64,
        failure: Option<&str>,
    ) -> Result<Finished>;
}

pub use crate::scenario::Scenario;

/// [`Session::agree`] over the ranks of `comm` (unchanged on one process).
pub(crate) fn agree_over(comm: Option<&dyn Exchange>, chunk: u64, stop: u8) -> (u64, u8) {
    let Some(c) = comm else {
        return (chunk, stop);
    };
    let mut all = Vec::new();
    c.all_gather(&[chunk as f64, stop as f64], &mut all);
    let code = all.chunks_exact(2).map(|r| r[1] as u8).max().unwrap_or(0);
    (all[0] as u64, code)
}

/// [`Session::fail_alone`] over the ranks of `comm`: the error as it is on one process; the
/// message printed and the job ended on every rank otherwise.
pub(crate) fn fail_alone_over(comm: Option<&dyn Exchange>, e: anyhow::Error) -> anyhow::Error {
    match comm {
        Some(c) => c.abort(&format!("{e:#}")),
        None => e,
    }
}

/// For a method that runs on one rank: refuse the ranks of `comm` (before anything is written).
pub(crate) fn on_one_rank(
    comm: Option<Box<dyn Exchange>>,
    sc: &Scenario,
    method: &str,
) -> Result<()> {
    if comm.is_some() {
        bail!(not_decomposed(sc, method));
    }
    Ok(())
}

/// Why `colloidsim run` under `mpirun -n N` refuses a method.
fn not_decomposed(sc: &Scenario, method: &str) -> String {
    format!(
        "{}: method '{method}' runs on one rank: only 'dpd', free-draining 'bd' and \
         'droplet-bd', 'mpcd' and 'droplet-mpcd' are decomposed over MPI ranks so far (docs/parallel.md); spread replicas \
         and sweeps over ranks with `colloidsim ensemble`",
        sc.label()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    const DECLARED: &[Headline] = &[
        Headline {
            name: "Z",
            path: "compressibility.value",
            labels: None,
            unit: "-",
            doc: "",
            absent: "bulk only",
        },
        Headline {
            name: "phi",
            path: "shell.phi",
            labels: Some("shell.labels"),
            unit: "-",
            doc: "",
            absent: "no profile",
        },
    ];

    #[test]
    fn headline_columns_name_a_labelled_list_element_by_element() {
        let s = json!({"compressibility": {"value": 1.5},
                       "shell": {"labels": ["t0.00", "t1.00"], "phi": [0.1, null]}});
        let cols = headline_columns(DECLARED, &s);
        let got: Vec<(&str, &str, Option<f64>)> = cols
            .iter()
            .map(|c| (c.column.as_str(), c.path.as_str(), c.value))
            .collect();
        assert_eq!(
            got,
            [
                ("Z", "compressibility.value", Some(1.5)),
                ("phi_t0.00", "shell.phi[0]", Some(0.1)),
                ("phi_t1.00", "shell.phi[1]", None),
            ]
        );
    }

    #[test]
    fn a_headline_the_method_did_not_write_becomes_null_with_its_reason() {
        let dir = tempfile::tempdir().unwrap();
        let out = OutputDir::create(dir.path().join("o"), false).unwrap();
        let mut s = json!({"steps": 3});
        complete_headline(DECLARED, &mut s, &out);
        assert_eq!(s, json!({"steps": 3, "compressibility": {"value": null}}));
        let nulls = crate::driver::null_reasons(&s, &out);
        assert_eq!(nulls["compressibility.value"], "bulk only");
        // A value the method wrote is left as it is.
        let mut s = json!({"compressibility": {"value": 2.0}});
        complete_headline(DECLARED, &mut s, &out);
        assert_eq!(s, json!({"compressibility": {"value": 2.0}}));
    }
}
