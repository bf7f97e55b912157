//! The loop every run shares: output folder, chunks of work between interrupt checks, regular
//! checkpoints, verified restarts, test hooks, progress and `summary.json`.

use crate::checkpoint::{self, CHECKPOINT, Envelope};
use crate::control::Control;
use crate::method::Session;
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
/// checkpoint, after the trajectory reached the disk (`COLLOIDSIM_KILL_AT_STEP`).
struct Hooks {
    interrupt: Option<u64>,
    kill: Option<u64>,
}

impl Hooks {
    fn from_env() -> Self {
        let read = |name: &str| std::env::var(name).ok().and_then(|v| v.parse().ok());
        Self {
            interrupt: read("COLLOIDSIM_INTERRUPT_AT_STEP"),
            kill: read("COLLOIDSIM_KILL_AT_STEP"),
        }
    }
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
    let out = if session.is_writer() {
        let created = (|| -> Result<OutputDir> {
            let out = OutputDir::create(&out_path, opts.force)?;
            if opts.force {
                for w in clear_earlier_outputs(&out, &*session)? {
                    ctl.progress().warning(&w);
                    warnings.push(w);
                }
            }
            out.write_bytes("scenario.toml", sc.text().as_bytes())?;
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
    drive(session, out, envelope, ctl, warnings)
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

/// `--force`: remove the files an earlier run of this method left (so that none mixes with the
/// new run); keep any other file. Returns what to tell the user.
fn clear_earlier_outputs(out: &OutputDir, s: &dyn Session) -> Result<Vec<String>> {
    let mut removed = Vec::new();
    let mut kept = Vec::new();
    let entries =
        std::fs::read_dir(out.path()).with_context(|| out.path().display().to_string())?;
    for e in entries {
        let e = e?;
        let name = e.file_name().to_string_lossy().into_owned();
        if !e.file_type()?.is_file() {
            kept.push(name);
            continue;
        }
        let ours = s.writes(&name)
            || ["summary.json", "scenario.toml", CHECKPOINT].contains(&name.as_str())
            || name.ends_with(".partial");
        if ours {
            std::fs::remove_file(e.path()).with_context(|| e.path().display().to_string())?;
            removed.push(name);
        } else {
            kept.push(name);
        }
    }
    removed.sort();
    kept.sort();
    let mut w = Vec::new();
    if !removed.is_empty() {
        w.push(format!(
            "--force: removed {} file(s) of an earlier run in {}: {}",
            removed.len(),
            out.path().display(),
            removed.join(", ")
        ));
    }
    if !kept.is_empty() {
        w.push(format!(
            "--force: kept what this run does not write in {}: {}",
            out.path().display(),
            kept.join(", ")
        ));
    }
    Ok(w)
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
    let warnings = session.warnings();
    for w in &warnings {
        ctl.progress().warning(w);
    }
    if let Err(e) = session.begin(&out, false) {
        return Err(session.fail_alone(e));
    }
    drive(session, out, envelope, ctl, warnings)
}

/// Write a checkpoint at the session's position (every rank of a decomposed run takes part;
/// the writer writes).
fn save(s: &mut dyn Session, out: &OutputDir, env: &mut Envelope, wall: f64) -> Result<()> {
    s.flush().map_err(|e| s.fail_alone(e))?;
    env.payload = s.save(out)?;
    env.position = s.position();
    env.wall_seconds = wall;
    if s.is_writer() {
        let written = checkpoint::encode(env).and_then(|b| Ok(out.write_bytes(CHECKPOINT, &b)?));
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
                Some(g @ colloidsim_md::gsd::GsdError::NonFinite { .. }) => Some(g.to_string()),
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
) -> Result<Report> {
    let total = s.total();
    let hooks = Hooks::from_env();
    ctl.progress().begin(&s.label(), total, s.position());
    let start = Instant::now();
    let pos0 = s.position();
    let wall0 = env.wall_seconds;
    let wall = || wall0 + start.elapsed().as_secs_f64();
    // The steps run on a worker of the thread pool, so that each step's parallel passes start
    // without a hand-over from this thread.
    let failure = rayon::scope(|_| -> Result<Option<String>> {
        let mut chunk = 16u64;
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
            // The ranks of a decomposed run go on alike: the same chunk, the same interrupt.
            let interrupted;
            (chunk, interrupted) = s.agree(chunk, ctl.interrupted());
            if interrupted && !ctl.interrupted() {
                ctl.interrupt();
            }
            if !draining && interrupted {
                let stop = s.stop_point();
                if stop >= total {
                    draining = true;
                } else {
                    if stop > pos {
                        ctl.progress().message(&format!(
                            "interrupted at step {pos}: running on to step {stop} to write a checkpoint (Ctrl-C again stops at once)"
                        ));
                        if let Some(why) = advance(&mut *s, stop)? {
                            return Ok(Some(why));
                        }
                    }
                    save(&mut *s, &out, &mut env, wall())?;
                    let outputs = s.interim_outputs(&out)?;
                    ctl.progress().end();
                    return Err(Interrupted {
                        at: pos,
                        checkpoint: s.position(),
                        out: out.path().to_path_buf(),
                        outputs,
                    }
                    .into());
                }
            }
            let due = s.next_checkpoint().filter(|&c| c > pos && c < total);
            let mut next = pos.saturating_add(chunk).min(total);
            if let Some(c) = due {
                next = next.min(c);
            }
            for h in [hooks.interrupt, hooks.kill].into_iter().flatten() {
                if h > pos {
                    next = next.min(h);
                }
            }
            let t = Instant::now();
            if let Some(why) = advance(&mut *s, next)? {
                return Ok(Some(why));
            }
            let secs = t.elapsed().as_secs_f64();
            if secs < 0.5 * CHUNK_SECONDS && next - pos == chunk {
                chunk = (chunk * 2).min(1 << 20);
            } else if secs > 2.0 * CHUNK_SECONDS {
                chunk = (chunk / 2).max(1);
            }
            if due == Some(s.position()) {
                save(&mut *s, &out, &mut env, wall())?;
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
    let mut files = vec!["scenario.toml".to_string()];
    files.extend(fin.files.into_iter().filter(|f| f != "scenario.toml"));
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
    if let Some(m) = summary.as_object_mut() {
        if !non_finite.is_empty() {
            m.insert("non_finite".into(), json!(non_finite));
        }
        m.insert("completed".into(), json!(failure.is_none()));
        m.insert("error".into(), json!(failure));
        m.insert("files".into(), json!(files));
    }
    if s_is_writer {
        out.write_json("summary.json", &summary)?;
        // The run is over: its checkpoint is no longer needed (a restart now refuses).
        let _ = std::fs::remove_file(out.join(CHECKPOINT));
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
