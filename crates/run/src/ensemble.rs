//! Ensembles: replicas of a scenario (seeds `seed, seed + 1, ...`) and parameter sweeps (the
//! Cartesian product of `--vary key=[v1, v2, ...]` lists), each member an ordinary run in its own
//! folder, then averaged.
//!
//! The members are independent runs, so an ensemble spreads over MPI ranks without changing a
//! bit of any member (the CLI deals member `k` to rank `k mod size`, `docs/parallel.md`); this
//! module plans, runs one member and combines, and [`ensemble`] does all three in one process.
//!
//! Averages: at each sweep point, every CSV table the replicas share (same header, same first
//! column) is written with each column's mean over replicas and its standard error
//! `s / sqrt(n)` (`COLUMN_err`, `s` the sample standard deviation between replicas; a run's own
//! error columns, `err` and `NAME_err`, are replaced by this spread), and every
//! number in the members' `summary.json` (outside `parameters`) is averaged the same way into
//! `observables.csv` and the ensemble's `summary.json`. The method's headline observables
//! ([`crate::method::Headline`]) go into `headline.csv`, one row per sweep point, and are
//! pictured against the first swept key (`headline_NAME.png`).

use crate::control::Control;
use crate::method::{Headline, HeadlineValue, headline_columns};
use crate::{Report, RunOptions, Scenario};
use anyhow::{Context, Result, bail};
use colloidsim_core::output::{OutputDir, read_table};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Options of an ensemble.
#[derive(Debug, Clone)]
pub struct EnsembleOptions {
    /// Output folder (default: the scenario's name followed by `-ensemble`).
    pub out: Option<PathBuf>,
    /// Replicas per sweep point (seeds `seed .. seed + replicas`), 1 ..= 10000.
    pub replicas: u32,
    /// Swept keys and their values; the points are the Cartesian product, the last key
    /// varying fastest.
    pub vary: Vec<(String, Vec<toml::Value>)>,
    /// Write into a folder that already holds files.
    pub force: bool,
}

impl Default for EnsembleOptions {
    fn default() -> Self {
        Self {
            out: None,
            replicas: 4,
            vary: Vec::new(),
            force: false,
        }
    }
}

/// One member: a scenario at a sweep point with a replica's seed, and its folder.
#[derive(Debug, Clone)]
pub struct Member {
    /// Sweep point (0 without a sweep).
    pub point: usize,
    /// Replica at that point.
    pub replica: u32,
    /// The member's seed.
    pub seed: u64,
    /// The member's folder, relative to the ensemble's.
    pub folder: String,
    scenario: Scenario,
}

/// Where a member stands, from its folder ([`Ensemble::member_state`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MemberState {
    /// Its `summary.json` says `completed = true`.
    Complete,
    /// Its `summary.json` says `completed = false`, with this error.
    Failed(String),
    /// Interrupted: a checkpoint and no summary.
    Checkpointed,
    /// Nothing to continue from (never started, or stopped before its first checkpoint).
    NotStarted,
}

/// A planned ensemble: every member validated, nothing written yet.
#[derive(Debug, Clone)]
pub struct Ensemble {
    scenario: Scenario,
    out: PathBuf,
    force: bool,
    replicas: u32,
    vary: Vec<(String, Vec<toml::Value>)>,
    points: Vec<Vec<(String, toml::Value)>>,
    members: Vec<Member>,
    seed_first: u64,
}

/// The plan of an ensemble in its folder, and the version of its layout.
const PLAN: &str = "ensemble.json";
const PLAN_FORMAT: &str = "colloidsim-ensemble-1";

/// A folder's `summary.json`.
fn read_summary(dir: &Path) -> Result<Value> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))
}

/// Parse `key=[v1, v2, ...]` (a TOML array of at least one value) for `--vary`.
pub fn parse_vary(text: &str) -> Result<(String, Vec<toml::Value>)> {
    let (key, value) = text.split_once('=').with_context(|| {
        format!("--vary {text}: expected KEY=[V1, V2, ...], e.g. system.phi=[0.1, 0.2]")
    })?;
    let key = key.trim().to_string();
    let table: toml::Table =
        toml::from_str(&format!("v = {}", value.trim())).with_context(|| {
            format!("--vary {key}: the values must be a TOML array, e.g. [0.1, 0.2]")
        })?;
    match table.get("v") {
        Some(toml::Value::Array(a)) if !a.is_empty() => Ok((key, a.clone())),
        _ => bail!("--vary {key}: the values must be a non-empty TOML array, e.g. [0.1, 0.2]"),
    }
}

/// A TOML value as written in a table cell (strings without quotes).
fn cell(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

impl Ensemble {
    /// Plan the ensemble of `sc`: every member's scenario is built and validated (as
    /// `colloidsim check` would) before anything is written, so that bad input stops every
    /// rank alike.
    pub fn plan(sc: &Scenario, opts: &EnsembleOptions) -> Result<Self> {
        if !(1..=10_000).contains(&opts.replicas) {
            bail!("--replicas: must lie in 1 ..= 10000, got {}", opts.replicas);
        }
        let mut seen = std::collections::BTreeSet::new();
        for (key, values) in &opts.vary {
            if !seen.insert(key.as_str()) {
                bail!("--vary {key}: the key is given twice");
            }
            if key == "seed" {
                bail!("--vary seed: the seeds of an ensemble are its replicas (--replicas)");
            }
            if values.is_empty() {
                bail!("--vary {key}: no values");
            }
        }
        let members = opts
            .vary
            .iter()
            .try_fold(opts.replicas as usize, |n, (_, v)| n.checked_mul(v.len()))
            .filter(|&n| n <= 100_000);
        if members.is_none() {
            bail!("--vary/--replicas: more than 100000 members (points x replicas)");
        }
        let mut points: Vec<Vec<(String, toml::Value)>> = vec![Vec::new()];
        for (key, values) in &opts.vary {
            points = points
                .into_iter()
                .flat_map(|p| {
                    values.iter().map(move |v| {
                        let mut q = p.clone();
                        q.push((key.clone(), v.clone()));
                        q
                    })
                })
                .collect();
        }
        crate::check(sc)?;
        let seed_first = sc.seed()?;
        crate::seed32(seed_first + opts.replicas as u64 - 1).context(
            "--replicas: the replicas' seeds (seed, seed + 1, ...) must stay below 2^32",
        )?;
        let mut members = Vec::new();
        for (p, values) in points.iter().enumerate() {
            let at = sc
                .with_values(values)
                .with_context(|| format!("sweep point {p}"))?;
            crate::check(&at).with_context(|| {
                let set: Vec<String> = values.iter().map(|(k, v)| format!("{k}={v}")).collect();
                format!("sweep point {p} ({})", set.join(", "))
            })?;
            for r in 0..opts.replicas {
                let folder = if opts.vary.is_empty() {
                    format!("replica-{r}")
                } else {
                    format!("point-{p}/replica-{r}")
                };
                members.push(Member {
                    point: p,
                    replica: r,
                    seed: seed_first + r as u64,
                    folder,
                    scenario: at.clone(),
                });
            }
        }
        let out = opts
            .out
            .clone()
            .unwrap_or_else(|| format!("{}-ensemble", sc.name()).into());
        Ok(Self {
            scenario: sc.clone(),
            out,
            force: opts.force,
            replicas: opts.replicas,
            vary: opts.vary.clone(),
            points,
            members,
            seed_first,
        })
    }

    /// The members, in the order of their index.
    pub fn members(&self) -> &[Member] {
        &self.members
    }

    /// The ensemble's folder.
    pub fn out(&self) -> &Path {
        &self.out
    }

    /// The plan as `ensemble.json` keeps it: the scenario, its folder, the replicas and the
    /// sweep.
    fn plan_json(&self) -> Value {
        json!({
            "format": PLAN_FORMAT,
            "scenario": self.scenario.text(),
            "base": self.scenario.base(),
            "name": self.scenario.name(),
            "replicas": self.replicas,
            "vary": self.vary.iter().map(|(k, v)| json!([k, v])).collect::<Vec<_>>(),
        })
    }

    /// Create the ensemble's folder (refused when it holds files, unless `force`) and write
    /// the plan into it (`ensemble.json`), from which [`Ensemble::reopen`] continues an
    /// interrupted ensemble.
    pub fn create(&self) -> Result<()> {
        let dir = OutputDir::create(&self.out, self.force)?;
        dir.write_json(PLAN, &self.plan_json())?;
        Ok(())
    }

    /// For one member run on its own (`colloidsim ensemble --member K`, a job of a job
    /// array): create the ensemble's folder and its plan if they are not there yet, or else
    /// check that the plan there is this one. Safe when many processes start at once, on one
    /// machine or on several sharing a file system: the plan is written under a name of this
    /// process's own and linked into place only if no plan is there (a hard link does not
    /// replace a file), so the first one wins and every other compares.
    pub fn join(&self) -> Result<()> {
        let path = self.out.join(PLAN);
        let mine = self.plan_json();
        if !path.exists() {
            if self.out.exists() {
                self.refuse_foreign_files()?;
            }
            std::fs::create_dir_all(&self.out)
                .with_context(|| format!("cannot create {}", self.out.display()))?;
            let mut bytes = serde_json::to_vec_pretty(&mine)?;
            bytes.push(b'\n');
            let unique = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos());
            let tmp = self
                .out
                .join(format!("{PLAN}.{}-{unique}.partial", std::process::id()));
            let linked = (|| -> std::io::Result<()> {
                use std::io::Write;
                let mut f = std::fs::File::create_new(&tmp)?;
                f.write_all(&bytes)?;
                f.sync_all()?;
                std::fs::hard_link(&tmp, &path)
            })();
            let _ = std::fs::remove_file(&tmp);
            match linked {
                Ok(()) => return Ok(()),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => {
                    return Err(e).with_context(|| format!("cannot write {}", path.display()));
                }
            }
        }
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let theirs: Value =
            serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
        let differ: Vec<&str> = ["format", "scenario", "base", "name", "replicas", "vary"]
            .into_iter()
            .filter(|k| theirs[*k] != mine[*k])
            .collect();
        if !differ.is_empty() {
            bail!(
                "{}: the ensemble planned in this folder is not this one (its {} differ): give \
                 every member the same scenario, --set, --replicas and --vary, or another --out",
                path.display(),
                differ.join(", ")
            );
        }
        Ok(())
    }

    /// A folder without a plan may hold only what members being started write into it.
    fn refuse_foreign_files(&self) -> Result<()> {
        let mut foreign: Vec<String> = std::fs::read_dir(&self.out)
            .with_context(|| format!("cannot read {}", self.out.display()))?
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| {
                !(n.starts_with(PLAN) && n.ends_with(".partial")
                    || n.starts_with("replica-")
                    || n.starts_with("point-"))
            })
            .collect();
        foreign.sort();
        if !foreign.is_empty() {
            bail!(
                "output folder {} holds files that are not an ensemble's ({}) and no {PLAN}; \
                 choose another --out",
                self.out.display(),
                foreign.join(", ")
            );
        }
        Ok(())
    }

    /// The ensemble planned in folder `dir` by an earlier [`Ensemble::create`], to be
    /// continued: refused when the folder has no plan or the ensemble completed.
    pub fn reopen(dir: &Path) -> Result<Self> {
        let plan = Self::load(dir, "--restart")?;
        let summary = read_summary(dir).ok();
        if summary.as_ref().is_some_and(|s| s["completed"] == true) {
            bail!(
                "--restart {}: this ensemble is complete (summary.json); nothing to continue",
                dir.display()
            );
        }
        Ok(plan)
    }

    /// The ensemble planned in folder `dir` (`flag` names the option that gave it, for the
    /// messages), whether or not it completed (`--collect`).
    pub fn load(dir: &Path, flag: &str) -> Result<Self> {
        let path = dir.join(PLAN);
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!(
                "{flag} {}: no {PLAN} (not the folder of `colloidsim ensemble`)",
                dir.display()
            )
        })?;
        let v: Value =
            serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
        if v["format"] != PLAN_FORMAT {
            bail!(
                "{}: format {} is not {PLAN_FORMAT}",
                path.display(),
                v["format"]
            );
        }
        let field = |k: &str| {
            v[k].as_str()
                .with_context(|| format!("{}: no {k}", path.display()))
        };
        let sc = Scenario::from_toml(field("scenario")?, Path::new(field("base")?))?
            .named(field("name")?);
        let vary: Vec<(String, Vec<toml::Value>)> = serde_json::from_value(v["vary"].clone())
            .with_context(|| format!("{}: vary", path.display()))?;
        let replicas = v["replicas"]
            .as_u64()
            .with_context(|| format!("{}: no replicas", path.display()))?;
        Self::plan(
            &sc,
            &EnsembleOptions {
                out: Some(dir.to_path_buf()),
                replicas: replicas as u32,
                vary,
                force: false,
            },
        )
    }

    /// Run member `k` into its folder (after [`Ensemble::create`]). A member that already
    /// completed is left as it is, one with a checkpoint is continued from it (bitwise the
    /// uninterrupted run), and one that failed or stopped before its first checkpoint is run
    /// again from its start.
    pub fn run_member(&self, k: usize, ctl: &Control) -> Result<()> {
        let m = &self.members[k];
        let dir = self.out.join(&m.folder);
        let summary = read_summary(&dir).ok();
        let outcome = if summary.as_ref().is_some_and(|s| s["completed"] == true) {
            Ok(())
        } else if summary.is_none() && dir.join(crate::checkpoint::CHECKPOINT).exists() {
            crate::resume(&dir, Some(&m.scenario), Some(m.seed), ctl).map(|_| ())
        } else {
            let force = self.force || dir.exists();
            let opts = RunOptions {
                out: Some(dir),
                seed: Some(m.seed),
                force,
            };
            crate::run(&m.scenario, &opts, ctl).map(|_| ())
        };
        outcome.with_context(|| format!("member {} ({})", k, m.folder))
    }

    /// Combine the members' outputs: `errors[k]` is member `k`'s error, if it failed. Writes
    /// the averages and `summary.json`; with a failed member, the summary says `completed =
    /// false`, names the failures and no averages are written, and the result is an error.
    pub fn finish(&self, errors: &[Option<String>], wall_seconds: f64) -> Result<Report> {
        self.combine(errors, &[], wall_seconds)
    }

    /// Where member `k` stands, from its folder.
    pub fn member_state(&self, k: usize) -> MemberState {
        let dir = self.out.join(&self.members[k].folder);
        if dir.join("summary.json").exists() {
            return match read_summary(&dir) {
                Ok(s) if s["completed"] == true => MemberState::Complete,
                Ok(s) => MemberState::Failed(s["error"].as_str().unwrap_or("?").to_string()),
                Err(e) => MemberState::Failed(format!("{e:#}")),
            };
        }
        if dir.join(crate::checkpoint::CHECKPOINT).exists() {
            MemberState::Checkpointed
        } else {
            MemberState::NotStarted
        }
    }

    /// `colloidsim ensemble --collect DIR`: average the members that were run on their own
    /// (`--member K`) exactly as a whole ensemble's [`Ensemble::finish`] does. Refused, naming
    /// them, while members are unfinished (interrupted or not started), unless
    /// `finished_only`: then the members that completed are averaged, the others left out
    /// and named in `summary.json` (`left_out`; `completed = false`, `partial = true`). A
    /// member that failed is reported as a whole ensemble reports it (or left out).
    pub fn collect(&self, finished_only: bool) -> Result<Report> {
        let states: Vec<MemberState> = (0..self.members.len())
            .map(|k| self.member_state(k))
            .collect();
        let name = |k: usize| format!("{k} ({})", self.members[k].folder);
        let unfinished: Vec<String> = states
            .iter()
            .enumerate()
            .filter_map(|(k, st)| match st {
                MemberState::Checkpointed => Some(format!("{} interrupted", name(k))),
                MemberState::NotStarted => Some(format!("{} not run", name(k))),
                _ => None,
            })
            .collect();
        if !unfinished.is_empty() && !finished_only {
            bail!(
                "--collect {}: {} of {} members are not finished: {}; run them (`colloidsim \
                 ensemble --restart {} --member K`), or average the finished ones only with \
                 --finished-only",
                self.out.display(),
                unfinished.len(),
                self.members.len(),
                unfinished.join(", "),
                self.out.display()
            );
        }
        let wall_seconds: f64 = states
            .iter()
            .enumerate()
            .filter(|(_, st)| **st == MemberState::Complete)
            .filter_map(|(k, _)| {
                read_summary(&self.out.join(&self.members[k].folder)).ok()?["wall_seconds"].as_f64()
            })
            .sum();
        if finished_only {
            let left_out: Vec<(usize, String)> = states
                .iter()
                .enumerate()
                .filter_map(|(k, st)| match st {
                    MemberState::Complete => None,
                    MemberState::Failed(e) => Some((k, format!("failed: {e}"))),
                    MemberState::Checkpointed => Some((k, "interrupted".to_string())),
                    MemberState::NotStarted => Some((k, "not run".to_string())),
                })
                .collect();
            if left_out.len() == self.members.len() {
                bail!(
                    "--collect {}: no member has finished; nothing to average",
                    self.out.display()
                );
            }
            let errors = vec![None; self.members.len()];
            let mut r = self.combine(&errors, &left_out, wall_seconds)?;
            r.message = format!(
                "averaged {} of {} members (left out: {}) into {}",
                self.members.len() - left_out.len(),
                self.members.len(),
                left_out
                    .iter()
                    .map(|(k, why)| format!("{}, {why}", name(*k)))
                    .collect::<Vec<_>>()
                    .join("; "),
                self.out.display()
            );
            return Ok(r);
        }
        let errors: Vec<Option<String>> = states
            .iter()
            .enumerate()
            .map(|(k, st)| match st {
                MemberState::Failed(e) => Some(format!("member {}: {e}", name(k))),
                _ => None,
            })
            .collect();
        let mut r = self.combine(&errors, &[], wall_seconds)?;
        r.message = format!(
            "averaged the {} members ({} point(s) x {} replica(s)) into {}",
            self.members.len(),
            self.points.len(),
            self.replicas,
            self.out.display()
        );
        Ok(r)
    }

    /// [`Ensemble::finish`], leaving out the members `left_out` (with why) from the averages.
    fn combine(
        &self,
        errors: &[Option<String>],
        left_out: &[(usize, String)],
        wall_seconds: f64,
    ) -> Result<Report> {
        let out = OutputDir::reopen(&self.out)?;
        let failed: Vec<Value> = errors
            .iter()
            .enumerate()
            .filter_map(|(k, e)| {
                e.as_ref()
                    .map(|e| json!({"member": k, "folder": self.members[k].folder, "error": e}))
            })
            .collect();
        let mut summary = json!({
            "software": crate::software(),
            "method": "ensemble",
            "scenario_method": self.scenario.method()?,
            "replicas": self.replicas,
            "seed_first": self.seed_first,
            "vary": self.vary.iter().map(|(k, v)| (k.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
            "members": self.members.len(),
            "averages": "mean over replicas; errors: standard error s / sqrt(n) between replicas",
            "wall_seconds": wall_seconds,
        });
        if !failed.is_empty() {
            summary["completed"] = json!(false);
            summary["error"] = json!(format!(
                "{} of {} members failed",
                failed.len(),
                self.members.len()
            ));
            summary["failed"] = Value::Array(failed.clone());
            out.write_json("summary.json", &summary)?;
            let lines: Vec<String> = failed
                .iter()
                .map(|f| {
                    format!(
                        "{}: {}",
                        f["folder"].as_str().unwrap_or("?"),
                        f["error"].as_str().unwrap_or("?")
                    )
                })
                .collect();
            bail!(
                "{} of {} members failed (no averages written; summary.json says completed = false):\n{}",
                failed.len(),
                self.members.len(),
                lines.join("\n")
            );
        }
        let mut files = Vec::new();
        let mut warnings = Vec::new();
        let mut observables = Vec::new();
        let mut headline = Vec::new();
        for (p, values) in self.points.iter().enumerate() {
            let folders: Vec<PathBuf> = self
                .members
                .iter()
                .enumerate()
                .filter(|(k, m)| m.point == p && !left_out.iter().any(|(l, _)| l == k))
                .map(|(_, m)| self.out.join(&m.folder))
                .collect();
            let prefix = if self.vary.is_empty() {
                String::new()
            } else {
                format!("point-{p}/")
            };
            if folders.len() >= 2 {
                let dir = OutputDir::reopen(self.out.join(&prefix))?;
                for (name, pooled) in pool(&folders)? {
                    write_pooled(&dir, &name, &pooled)?;
                    files.push(format!("{prefix}{name}"));
                }
            }
            let obs = if folders.is_empty() {
                warnings.push(format!("point {p}: no finished member, no averages"));
                BTreeMap::new()
            } else {
                pool_summaries(&folders)?
            };
            headline.push(
                folders
                    .iter()
                    .map(|f| read_summary(f))
                    .collect::<Result<Vec<Value>>>()?,
            );
            for (k, (m, e, _)) in &obs {
                let at = format!("points[{}].observables.{k}", observables.len());
                for (x, field, why) in [
                    (m, "mean", "no member gave a finite value"),
                    (
                        e,
                        "err",
                        "fewer than 2 replicas gave a finite value: no standard error",
                    ),
                ] {
                    if !x.is_finite() {
                        out.explain("summary.json", &format!("{at}.{field}"), why);
                    }
                }
            }
            observables.push(json!({
                "point": p,
                "set": values.iter().map(|(k, v)| (k.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
                "observables": obs.iter().map(|(k, (m, e, n))| (k.clone(), json!({"mean": m, "err": e, "n": n}))).collect::<serde_json::Map<_, _>>(),
            }));
        }
        if self.replicas < 2 {
            warnings.push("one replica per point: no errors, and no averaged tables".to_string());
        }
        out.write_bytes(
            "observables.csv",
            self.observables_csv(&observables).as_bytes(),
        )?;
        files.push("observables.csv".into());
        let method = crate::registry::of(&self.scenario)?;
        let table = HeadlineTable::pool(method.headline(), &headline);
        for (p, point) in observables.iter_mut().enumerate() {
            point["headline"] = table.point_json(p, &out);
        }
        out.write_bytes("headline.csv", self.headline_csv(&table).as_bytes())?;
        files.push("headline.csv".into());
        crate::output::plot::set_figure_format(
            out.path(),
            crate::keys::shared::figure_format(&self.scenario.table()?)?,
        );
        self.headline_pictures(method, &table, &out, &mut files, &mut warnings);
        summary["headline"] = method
            .headline()
            .iter()
            .enumerate()
            .map(|(k, h)| {
                let mut d = json!({
                    "name": h.name,
                    "unit": h.unit,
                    "doc": h.doc,
                    "path": h.path,
                    "columns": table.columns.iter().filter(|c| c.of == k).map(|c| c.column.clone()).collect::<Vec<_>>(),
                });
                if let Some(labels) = h.labels {
                    d["labels"] = json!(labels);
                }
                d
            })
            .collect();
        summary["completed"] = json!(true);
        summary["error"] = Value::Null;
        if !left_out.is_empty() {
            let named: Vec<String> = left_out
                .iter()
                .map(|(k, why)| format!("{k} ({}, {why})", self.members[*k].folder))
                .collect();
            let error = format!(
                "averages of {} of {} members; left out: {}",
                self.members.len() - left_out.len(),
                self.members.len(),
                named.join(", ")
            );
            warnings.push(error.clone());
            summary["completed"] = json!(false);
            summary["partial"] = json!(true);
            summary["error"] = json!(error);
            summary["left_out"] = left_out
                .iter()
                .map(|(k, why)| json!({"member": k, "folder": self.members[*k].folder, "state": why}))
                .collect();
        }
        summary["points"] = Value::Array(observables);
        summary["files"] = json!(files);
        summary["warnings"] = json!(warnings);
        let nulls = crate::driver::null_reasons(&summary, &out);
        if !nulls.is_empty() {
            summary["nulls"] = json!(nulls);
        }
        out.write_json("summary.json", &summary)?;
        let message = format!(
            "ran {} member(s) ({} point(s) x {} replica(s)) and wrote their averages into {}",
            self.members.len() - left_out.len(),
            self.points.len(),
            self.replicas,
            self.out.display()
        );
        Ok(Report {
            out: self.out.clone(),
            summary,
            files,
            warnings,
            message,
        })
    }

    /// `observables.csv`: one row per sweep point and observable: the point, the swept keys'
    /// values, the observable, its mean, standard error and number of replicas.
    fn observables_csv(&self, points: &[Value]) -> String {
        let quote = |s: &str| {
            if s.contains([',', '"', '\n']) {
                format!("\"{}\"", s.replace('"', "\"\""))
            } else {
                s.to_string()
            }
        };
        let mut s = String::from("point");
        for (k, _) in &self.vary {
            s.push(',');
            s.push_str(&quote(k));
        }
        s.push_str(",observable,mean,err,n\n");
        for (p, point) in points.iter().enumerate() {
            let set: Vec<String> = self.points[p]
                .iter()
                .map(|(_, v)| quote(&cell(v)))
                .collect();
            if let Some(obs) = point["observables"].as_object() {
                for (name, v) in obs {
                    // A number that is not finite (an error of one replica) is an empty
                    // field, as in every table colloidsim writes.
                    let num = |x: &Value| x.as_f64().map_or(String::new(), |x| format!("{x:e}"));
                    s.push_str(&format!("{p}"));
                    for c in &set {
                        s.push(',');
                        s.push_str(c);
                    }
                    s.push_str(&format!(
                        ",{},{},{},{}\n",
                        quote(name),
                        num(&v["mean"]),
                        num(&v["err"]),
                        v["n"]
                    ));
                }
            }
        }
        s
    }
}

/// The headline observables of every sweep point ([`crate::method::Headline`]): per column,
/// per point, the mean over the replicas, its standard error and why a value is missing.
struct HeadlineTable {
    /// The columns, in the order of the method's declaration.
    columns: Vec<HeadlineValue>,
    /// Per point, per column: mean, standard error, replicas with a value, replicas.
    stats: Vec<Vec<(f64, f64, usize, usize)>>,
    /// Per point, per column: why the mean or the error is missing.
    why: Vec<Vec<Option<String>>>,
    /// Per point, the replicas averaged (the finished members).
    replicas: Vec<usize>,
}

impl HeadlineTable {
    /// Pool the members' summaries, per point (`summaries[p]`).
    fn pool(headline: &[Headline], summaries: &[Vec<Value>]) -> Self {
        let values: Vec<Vec<Vec<HeadlineValue>>> = summaries
            .iter()
            .map(|point| {
                point
                    .iter()
                    .map(|s| headline_columns(headline, s))
                    .collect()
            })
            .collect();
        let mut columns: Vec<HeadlineValue> = Vec::new();
        for v in values.iter().flatten().flatten() {
            if !columns.iter().any(|c| c.column == v.column) {
                columns.push(v.clone());
            }
        }
        // Declaration order first, then the order met (a labelled list's elements in turn).
        columns.sort_by_key(|c| c.of);
        let mut stats = Vec::new();
        let mut why = Vec::new();
        for (point, members) in values.iter().zip(summaries) {
            let mut st = Vec::new();
            let mut wh = Vec::new();
            for c in &columns {
                let got: Vec<Option<f64>> = point
                    .iter()
                    .map(|m| {
                        m.iter()
                            .find(|v| v.column == c.column)
                            .and_then(|v| v.value)
                            .filter(|x| x.is_finite())
                    })
                    .collect();
                let n = got.len();
                let finite: Vec<f64> = got.iter().flatten().copied().collect();
                // The member's own reason for its null, from its summary's `nulls`.
                let reason = || {
                    members
                        .iter()
                        .zip(&got)
                        .find(|(_, g)| g.is_none())
                        .and_then(|(m, _)| m["nulls"][&c.path].as_str().map(String::from))
                        .unwrap_or_else(|| format!("{} is not in its summary.json", c.path))
                };
                if n == 0 {
                    st.push((f64::NAN, f64::NAN, 0, 0));
                    wh.push(Some("no finished member at this point".to_string()));
                } else if finite.is_empty() {
                    st.push((f64::NAN, f64::NAN, 0, n));
                    wh.push(Some(format!("no replica gave a value: {}", reason())));
                } else if finite.len() < n {
                    st.push((f64::NAN, f64::NAN, finite.len(), n));
                    wh.push(Some(format!(
                        "{} of {n} replicas gave no value, so no mean of all: {}",
                        n - finite.len(),
                        reason()
                    )));
                } else {
                    let (mean, err) = mean_err(finite.iter().copied(), n as f64);
                    let err = if n >= 2 { err } else { f64::NAN };
                    st.push((mean, err, n, n));
                    wh.push((n < 2).then(|| "one replica: no standard error".to_string()));
                }
            }
            stats.push(st);
            why.push(wh);
        }
        Self {
            columns,
            stats,
            why,
            replicas: summaries.iter().map(Vec::len).collect(),
        }
    }

    /// Point `p` as the ensemble's `summary.json` holds it (`points[p].headline`), the reasons
    /// of its nulls given to `out`.
    fn point_json(&self, p: usize, out: &OutputDir) -> Value {
        let mut m = serde_json::Map::new();
        for (k, c) in self.columns.iter().enumerate() {
            let (mean, err, n, _) = self.stats[p][k];
            if let Some(why) = &self.why[p][k] {
                for (x, field) in [(mean, "mean"), (err, "err")] {
                    if !x.is_finite() {
                        let at = format!("points[{p}].headline.{}.{field}", c.column);
                        out.explain("summary.json", &at, why);
                    }
                }
            }
            m.insert(c.column.clone(), json!({"mean": mean, "err": err, "n": n}));
        }
        Value::Object(m)
    }
}

impl Ensemble {
    /// `headline.csv`: one row per sweep point: the swept keys' values, the replicas averaged,
    /// then each headline observable's mean and standard error (`NAME`, `NAME_err`); a value
    /// missing (see `summary.json`) is an empty field.
    fn headline_csv(&self, t: &HeadlineTable) -> String {
        let mut head: Vec<String> = self.vary.iter().map(|(k, _)| quote(k)).collect();
        head.push("replicas".into());
        for c in &t.columns {
            head.push(quote(&c.column));
            head.push(quote(&format!("{}_err", c.column)));
        }
        let mut s = head.join(",");
        s.push('\n');
        let num = |x: f64| {
            if x.is_finite() {
                format!("{x:e}")
            } else {
                String::new()
            }
        };
        for (p, values) in self.points.iter().enumerate() {
            let mut row: Vec<String> = values.iter().map(|(_, v)| quote(&cell(v))).collect();
            row.push(t.replicas[p].to_string());
            for &(mean, err, _, _) in &t.stats[p] {
                row.push(num(mean));
                row.push(num(err));
            }
            s.push_str(&row.join(","));
            s.push('\n');
        }
        s
    }

    /// `headline_NAME.png`: each headline observable against the first swept key (a number),
    /// with its standard error as bars; one series per value of the other swept keys (and per
    /// label of a labelled observable). Nothing without a sweep, or for an observable with no
    /// value at any point.
    fn headline_pictures(
        &self,
        method: &dyn crate::method::Method,
        t: &HeadlineTable,
        out: &OutputDir,
        files: &mut Vec<String>,
        warnings: &mut Vec<String>,
    ) {
        use crate::output::plot::{Series, picture, picture_files, sweep_plot};
        let Some((key, _)) = self.vary.first() else {
            return;
        };
        let x: Option<Vec<f64>> = self
            .points
            .iter()
            .map(|v| match &v[0].1 {
                toml::Value::Integer(i) => Some(*i as f64),
                toml::Value::Float(f) => Some(*f),
                _ => None,
            })
            .collect();
        let Some(x) = x else {
            return;
        };
        // The points of each combination of the other swept keys, in order.
        let mut groups: Vec<(String, Vec<usize>)> = Vec::new();
        for (p, v) in self.points.iter().enumerate() {
            let label: Vec<String> = v[1..]
                .iter()
                .map(|(k, v)| format!("{k} = {}", cell(v)))
                .collect();
            let label = label.join(", ");
            match groups.iter_mut().find(|g| g.0 == label) {
                Some(g) => g.1.push(p),
                None => groups.push((label, vec![p])),
            }
        }
        let replicas = self.replicas;
        for (of, h) in method.headline().iter().enumerate() {
            let cols: Vec<usize> = (0..t.columns.len())
                .filter(|&k| t.columns[k].of == of)
                .collect();
            let any = cols
                .iter()
                .any(|&k| t.stats.iter().any(|s| s[k].0.is_finite()));
            if !any {
                continue;
            }
            let mut data: Vec<Curve> = Vec::new();
            for &k in &cols {
                let label = t.columns[k]
                    .column
                    .strip_prefix(h.name)
                    .unwrap_or("")
                    .trim_start_matches('_');
                for (g, points) in &groups {
                    let name: Vec<&str> = [label, g.as_str()]
                        .into_iter()
                        .filter(|s| !s.is_empty())
                        .collect();
                    data.push((
                        name.join(", "),
                        points.iter().map(|&p| x[p]).collect(),
                        points.iter().map(|&p| t.stats[p][k].0).collect(),
                        points.iter().map(|&p| t.stats[p][k].1).collect(),
                    ));
                }
            }
            let series: Vec<Series> = data
                .iter()
                .map(|(label, x, y, _)| Series {
                    label: if label.is_empty() {
                        "mean (bars: std. error)"
                    } else {
                        label
                    },
                    x,
                    y,
                    points: true,
                })
                .collect();
            let errors: Vec<Option<&[f64]>> = data.iter().map(|d| Some(d.3.as_slice())).collect();
            let unit = if h.unit == "-" {
                String::new()
            } else {
                format!(" ({})", h.unit)
            };
            let name = format!("headline_{}.png", h.name);
            let drawn = sweep_plot(
                &out.join(&name),
                &format!(
                    "{}: {}, mean +- standard error of {replicas} replica(s)",
                    method.names()[0],
                    h.name
                ),
                key,
                &format!("{}{unit}", h.name),
                &series,
                &errors,
            );
            let mut drawn_files = Vec::new();
            picture(drawn, &name, &mut drawn_files, warnings);
            for f in drawn_files {
                files.extend(picture_files(out.path(), &f));
            }
        }
    }
}

/// One curve of a sweep picture: label, x, mean, standard error.
type Curve = (String, Vec<f64>, Vec<f64>, Vec<f64>);

/// A CSV field: quoted where it holds a comma, a quote or a line break.
fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Run every member of `sc`'s ensemble in this process, one after the other (each member
/// uses the process's threads), and combine them.
pub fn ensemble(sc: &Scenario, opts: &EnsembleOptions, ctl: &Control) -> Result<Report> {
    let start = std::time::Instant::now();
    let plan = Ensemble::plan(sc, opts)?;
    plan.create()?;
    plan.run_all(start, ctl)
}

/// Continue the interrupted ensemble in `dir` in this process (members that completed are
/// kept, interrupted ones continue from their checkpoints).
pub fn resume_ensemble(dir: &Path, ctl: &Control) -> Result<Report> {
    let start = std::time::Instant::now();
    Ensemble::reopen(dir)?.run_all(start, ctl)
}

impl Ensemble {
    /// Run the members `k` with `k mod size == rank` in turn (an MPI rank's share; all of them
    /// for `rank = 0, size = 1`), stopping before the next member once interrupted; returns
    /// the errors of the members that failed, by index.
    ///
    /// Also says whether any member went forward (completed here, or stopped at a checkpoint
    /// beyond where it began): a wall-time budget spent before that is an error, not a stop
    /// to continue from.
    pub fn run_share(
        &self,
        rank: usize,
        size: usize,
        ctl: &Control,
    ) -> (BTreeMap<usize, String>, bool) {
        let mut failed = BTreeMap::new();
        let mut progressed = false;
        for k in (rank..self.members.len()).step_by(size.max(1)) {
            if ctl.interrupted() {
                break;
            }
            let done_before = self.member_state(k) == MemberState::Complete;
            match self.run_member(k, ctl) {
                Ok(()) => progressed |= !done_before,
                Err(e) => {
                    if let Some(i) = e.downcast_ref::<crate::Interrupted>() {
                        progressed |= i.checkpoint > i.started;
                    }
                    failed.insert(k, format!("{e:#}"));
                }
            }
        }
        (failed, progressed)
    }

    /// Run every member in turn and combine them; an interrupt stops after the member running.
    fn run_all(&self, start: std::time::Instant, ctl: &Control) -> Result<Report> {
        let (failed, _) = self.run_share(0, 1, ctl);
        if ctl.interrupted() {
            bail!(
                "interrupted; continue with: colloidsim ensemble --restart {}",
                self.out.display()
            );
        }
        let errors: Vec<Option<String>> = (0..self.members.len())
            .map(|k| failed.get(&k).cloned())
            .collect();
        self.finish(&errors, start.elapsed().as_secs_f64())
    }
}

/// One table pooled over runs: header, first column, and per further column the means and
/// standard errors.
pub(crate) struct Pooled {
    pub header: Vec<String>,
    pub x: Vec<f64>,
    pub means: Vec<Vec<f64>>,
    pub errors: Vec<Vec<f64>>,
}

/// Whether a table column is a run's own error estimate (`err`, `NAME_err`): the pooled
/// tables replace it by the spread between runs.
fn is_error_column(name: &str) -> bool {
    name == "err" || name.ends_with("_err")
}

/// Mean and standard error over runs of each column (but their own error columns) of every
/// CSV table that all `folders` hold with the same header and first column (at least two runs).
pub(crate) fn pool(folders: &[PathBuf]) -> Result<BTreeMap<String, Pooled>> {
    let mut out = BTreeMap::new();
    let mut names: Vec<String> = std::fs::read_dir(&folders[0])
        .with_context(|| format!("cannot read {}", folders[0].display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".csv"))
        .collect();
    names.sort();
    'table: for name in names {
        let mut runs = Vec::new();
        for f in folders {
            match read_table(&f.join(&name)) {
                Ok(t) => runs.push(t),
                Err(_) => continue 'table,
            }
        }
        let (header, first) = (&runs[0].0, &runs[0].1);
        if header.len() < 2 || runs.iter().any(|(h, c)| h != header || c[0] != first[0]) {
            continue;
        }
        let columns: Vec<usize> = (1..header.len())
            .filter(|&c| !is_error_column(&header[c]))
            .collect();
        let rows = first[0].len();
        let k = runs.len() as f64;
        let mut means = Vec::new();
        let mut errors = Vec::new();
        for &c in &columns {
            let (mut m, mut e) = (vec![0.0; rows], vec![0.0; rows]);
            for i in 0..rows {
                let (mean, err) = mean_err(runs.iter().map(|r| r.1[c][i]), k);
                m[i] = mean;
                e[i] = err;
            }
            means.push(m);
            errors.push(e);
        }
        out.insert(
            name,
            Pooled {
                header: std::iter::once(0)
                    .chain(columns)
                    .map(|c| header[c].clone())
                    .collect(),
                x: first[0].clone(),
                means,
                errors,
            },
        );
    }
    Ok(out)
}

/// Mean and standard error `s / sqrt(n)` of `n` values.
fn mean_err(v: impl Iterator<Item = f64> + Clone, n: f64) -> (f64, f64) {
    let mean = v.clone().sum::<f64>() / n;
    let var = v.map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Write a pooled table: the first column, then each column and its error `COLUMN_err`.
pub(crate) fn write_pooled(dir: &OutputDir, name: &str, p: &Pooled) -> Result<()> {
    let mut cols: Vec<(String, &[f64])> = vec![(p.header[0].clone(), &p.x)];
    for c in 0..p.means.len() {
        cols.push((p.header[c + 1].clone(), &p.means[c]));
        cols.push((format!("{}_err", p.header[c + 1]), &p.errors[c]));
    }
    let refs: Vec<(&str, &[f64])> = cols.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    dir.write_table(name, &refs)?;
    Ok(())
}

/// Whether a summary key is about the run rather than the physics: timings and thread counts.
pub fn is_timing(key: &str) -> bool {
    key == "threads" || key == "ranks" || key.ends_with("seconds") || key.ends_with("_per_second")
}

/// Every number in a summary outside its bookkeeping (`parameters`, `seed`, timings
/// ([`is_timing`])), by its dotted path.
fn numbers(v: &Value, path: &str, out: &mut BTreeMap<String, f64>) {
    match v {
        Value::Number(x) => {
            if let Some(x) = x.as_f64() {
                out.insert(path.to_string(), x);
            }
        }
        Value::Object(map) => {
            for (k, v) in map {
                if is_timing(k) || (path.is_empty() && (k == "parameters" || k == "seed")) {
                    continue;
                }
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                numbers(v, &p, out);
            }
        }
        _ => {}
    }
}

/// Mean, standard error and count over `folders` of every number their `summary.json` files
/// all hold.
fn pool_summaries(folders: &[PathBuf]) -> Result<BTreeMap<String, (f64, f64, usize)>> {
    let mut each = Vec::new();
    for f in folders {
        let path = f.join("summary.json");
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let v: Value =
            serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
        let mut n = BTreeMap::new();
        numbers(&v, "", &mut n);
        each.push(n);
    }
    let n = each.len();
    let mut out = BTreeMap::new();
    for key in each[0].keys() {
        if each.iter().all(|m| m.contains_key(key)) {
            let (mean, err) = mean_err(each.iter().map(|m| m[key]), n as f64);
            out.insert(key.clone(), (mean, if n >= 2 { err } else { f64::NAN }, n));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vary_parses_toml_arrays_and_names_the_key_on_errors() {
        let (k, v) = parse_vary("system.phi=[0.1, 0.2]").unwrap();
        assert_eq!(k, "system.phi");
        assert_eq!(v, vec![toml::Value::Float(0.1), toml::Value::Float(0.2)]);
        let (_, v) = parse_vary("system.boundary=[\"walls\", \"periodic\"]").unwrap();
        assert_eq!(cell(&v[1]), "periodic");
        for bad in [
            "system.phi",
            "system.phi=0.1",
            "system.phi=[]",
            "system.phi=[0.1",
        ] {
            let e = format!("{:#}", parse_vary(bad).unwrap_err());
            assert!(e.contains("--vary"), "{bad}: {e}");
        }
    }

    #[test]
    fn the_replicas_take_the_scenario_s_seed_for_every_method() {
        // DPD's resolved parameters do not list the seed: the ensemble once started at 1.
        for text in [
            "method = \"dpd\"\nseed = 7\n[system]\nbox_length = 6.0\n[run]\nsteps = 10\n",
            "method = \"bcd\"\nseed = 7\n[system]\nlength = 10.0\nparticles = 5\ndiameter = 0.5\n[run]\ndt = 1e-4\ntime = 0.01\n",
        ] {
            let sc = Scenario::from_toml(text, std::path::Path::new(".")).unwrap();
            let opts = EnsembleOptions {
                replicas: 2,
                ..Default::default()
            };
            let e = Ensemble::plan(&sc, &opts).unwrap();
            let seeds: Vec<u64> = e.members.iter().map(|m| m.seed).collect();
            assert_eq!(seeds, [7, 8], "{text}");
        }
    }

    #[test]
    fn mean_and_standard_error() {
        let (m, e) = mean_err([1.0, 2.0, 3.0, 6.0].into_iter(), 4.0);
        assert_eq!(m, 3.0);
        // s^2 = (4 + 1 + 0 + 9) / 3
        assert!((e - (14.0f64 / 3.0 / 4.0).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn headline_means_need_every_replica_and_say_why_not() {
        let decl = crate::registry::find("bcd").unwrap().headline();
        let member = |peak: Option<f64>, l1: f64| {
            json!({"peak_density": peak, "theory_l1": l1, "particle_current": null,
                   "mean_contact_density": null,
                   "nulls": {"peak_density": "no density observed (observe.density)"}})
        };
        let t = HeadlineTable::pool(
            decl,
            &[
                vec![member(Some(1.0), 0.1), member(Some(3.0), 0.3)],
                vec![member(Some(2.0), 0.2), member(None, 0.4)],
            ],
        );
        let names: Vec<&str> = t.columns.iter().map(|c| c.column.as_str()).collect();
        assert_eq!(
            names,
            [
                "peak_density",
                "theory_l1",
                "particle_current",
                "mean_contact_density"
            ]
        );
        let (mean, err, n, of) = t.stats[0][0];
        assert_eq!((mean, n, of), (2.0, 2, 2));
        assert!(
            (err - 1.0).abs() < 1e-15,
            "s = sqrt(2), s / sqrt(2) = 1: {err}"
        );
        // One replica of two without a value: no mean, and the member's reason.
        let (mean, _, n, of) = t.stats[1][0];
        assert!(mean.is_nan() && n == 1 && of == 2);
        let why = t.why[1][0].as_deref().unwrap();
        assert!(
            why.contains("1 of 2") && why.contains("observe.density"),
            "{why}"
        );
        assert!(t.stats[1][1].0.is_finite());
        assert!(
            t.why[0][2]
                .as_deref()
                .unwrap()
                .starts_with("no replica gave a value")
        );
    }

    #[test]
    fn summary_numbers_skip_the_bookkeeping() {
        let v = json!({"seed": 3, "wall_seconds": 1.0, "parameters": {"dt": 1e-3}, "threads": 2,
                       "particle_steps_per_second": 1e6,
                       "msd": {"D": 0.5, "n": 2}, "files": ["a.csv"], "completed": true});
        let mut n = BTreeMap::new();
        numbers(&v, "", &mut n);
        assert_eq!(n.keys().collect::<Vec<_>>(), ["msd.D", "msd.n"]);
    }
}
