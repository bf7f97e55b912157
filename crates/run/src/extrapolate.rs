//! Richardson extrapolation in the time step: a scenario run at `dt` and `dt / 2` with several
//! seeds each, and every table the runs share extrapolated to `dt -> 0` with its error.
//!
//! A bias `A(h) = A(0) + c h^p` gives `A(0) = (2^p A(h/2) - A(h)) / (2^p - 1)`. Euler's bias of
//! equilibrium averages is first order (`p = 1`, the default; the Leimkuhler–Matthews scheme's
//! is second order for the forces). The hard-core collisions of BCD leave a boundary layer of
//! thickness ~sqrt(dt) (docs/bcd.md): contact densities need `p = 0.5`, and the density right at
//! a wall carries both. Errors: each table's columns are averaged over the seeds, with standard
//! errors from the spread between seeds, propagated through the extrapolation.

use crate::control::Control;
use crate::ensemble::{Pooled, pool, write_pooled};
use crate::{Report, RunOptions, Scenario};
use anyhow::{Context, Result, bail};
use colloidsim_core::output::OutputDir;
use serde_json::json;
use std::path::PathBuf;

/// Options of an extrapolation.
#[derive(Debug, Clone)]
pub struct ExtrapolateOptions {
    /// Output folder (default: the scenario's name followed by `-extrapolated`).
    pub out: Option<PathBuf>,
    /// Seeds per time step (>= 2, for the errors).
    pub seeds: u32,
    /// Order `p` of the bias in `dt`.
    pub order: f64,
    /// Write into a folder that holds files.
    pub force: bool,
}

impl Default for ExtrapolateOptions {
    fn default() -> Self {
        Self {
            out: None,
            seeds: 4,
            order: 1.0,
            force: false,
        }
    }
}

/// The range of `--order`: below it the extrapolation only amplifies noise.
const MIN_ORDER: f64 = 0.25;
const MAX_ORDER: f64 = 4.0;

/// A warning for the columns whose means are >= 0 at both time steps (a density, a volume
/// fraction, a probability) but negative somewhere once extrapolated: the extrapolation of
/// noise, which a user must not take for a physical value.
fn negative_where_runs_are_not(
    name: &str,
    coarse: &Pooled,
    fine: &Pooled,
    extrapolated: &Pooled,
) -> Option<String> {
    let mut found = Vec::new();
    for (j, col) in extrapolated.means.iter().enumerate() {
        let non_negative = |p: &Pooled| p.means[j].iter().all(|&v| v >= 0.0);
        if !(non_negative(coarse) && non_negative(fine)) {
            continue;
        }
        let below: Vec<usize> = (0..col.len()).filter(|&i| col[i] < 0.0).collect();
        if let Some(&worst) = below.iter().min_by(|&&a, &&b| col[a].total_cmp(&col[b])) {
            found.push(format!(
                "{} ({} of {} rows, down to {:.3e} +- {:.1e} at {} = {})",
                extrapolated.header[j + 1],
                below.len(),
                col.len(),
                col[worst],
                extrapolated.errors[j][worst],
                extrapolated.header[0],
                extrapolated.x[worst]
            ));
        }
    }
    (!found.is_empty()).then(|| {
        format!(
            "{name}: extrapolated values below 0 where both time steps give none: {}; the extrapolation amplifies the noise between seeds (use more --seeds, or the half-dt table)",
            found.join("; ")
        )
    })
}

/// The scenario's time step, from its resolved parameters.
fn time_step(sc: &Scenario) -> Result<f64> {
    let r = crate::check(sc)?.resolved;
    r["run"]["dt"]
        .as_f64()
        .or_else(|| r["dt"].as_f64())
        .context("the scenario's resolved parameters name no time step (run.dt)")
}

/// The most seeds per time step `extrapolate` runs: its runs go one after the other in one
/// process (the standard errors shrink as `1/sqrt(seeds)`: 1000 seeds already give 3 % of one
/// run's spread); an ensemble spreads more over ranks and restarts member by member.
pub const MAX_SEEDS: u32 = 1000;

/// Run `sc` at its time step and at half of it, `opts.seeds` seeds each, and write every table
/// the runs share extrapolated to `dt -> 0` (`NAME.csv`: the first column, then each column and
/// its standard error `COLUMN_err`), the per-step means beside it (`dt/NAME.csv`,
/// `half-dt/NAME.csv`) and the runs themselves (`runs/`).
pub fn extrapolate(sc: &Scenario, opts: &ExtrapolateOptions, ctl: &Control) -> Result<Report> {
    if opts.seeds < 2 {
        bail!(
            "--seeds: at least 2 seeds per time step are needed for the errors, got {}",
            opts.seeds
        );
    }
    if opts.seeds > MAX_SEEDS {
        bail!(
            "--seeds {}: at most {MAX_SEEDS} (each seed is two complete runs, one after the other in this process, {} runs in all, and every run's tables are held together for the averages); for more replicas use colloidsim ensemble",
            opts.seeds,
            2 * opts.seeds as u64
        );
    }
    if !(opts.order.is_finite() && opts.order >= MIN_ORDER && opts.order <= MAX_ORDER) {
        bail!(
            "--order: must lie in [{MIN_ORDER}, {MAX_ORDER}], got {}: the extrapolation multiplies the difference between the two time steps by 2^p / (2^p - 1), {:.3} at p = {MIN_ORDER} and without bound as p goes to 0 (the usual orders: 0.5 contact densities, 1 Euler's averages, 2 Leimkuhler-Matthews' forces)",
            opts.order,
            2f64.powf(MIN_ORDER) / (2f64.powf(MIN_ORDER) - 1.0)
        );
    }
    let dt = time_step(sc)?;
    let out_path = opts
        .out
        .clone()
        .unwrap_or_else(|| format!("{}-extrapolated", sc.name()).into());
    let base_seed = sc.seed()?;
    crate::seed32(base_seed + opts.seeds as u64 - 1)
        .context("--seeds: the seeds (seed, seed + 1, ...) must stay below 2^32")?;
    let out = OutputDir::create(&out_path, opts.force)?;
    let mut folders: [Vec<PathBuf>; 2] = [Vec::new(), Vec::new()];
    let mut warnings = Vec::new();
    for (j, h) in [dt, 0.5 * dt].into_iter().enumerate() {
        let at = sc.with_values(&[("run.dt".into(), toml::Value::Float(h))])?;
        for k in 0..opts.seeds {
            let dir = out.join(&format!("runs/{}-seed-{k}", ["dt", "half-dt"][j]));
            if ctl.interrupted() {
                bail!(
                    "interrupted: the runs so far are in {}",
                    out.path().display()
                );
            }
            let r = crate::run(
                &at,
                &RunOptions {
                    out: Some(dir.clone()),
                    seed: Some(base_seed + k as u64),
                    force: opts.force,
                },
                ctl,
            )?;
            warnings.extend(r.warnings);
            folders[j].push(dir);
        }
    }
    let coarse = pool(&folders[0])?;
    let fine = pool(&folders[1])?;
    let gain = 2f64.powf(opts.order);
    let mut files = Vec::new();
    let mut skipped = Vec::new();
    for (name, c) in &coarse {
        let Some(f) = fine.get(name) else {
            skipped.push(name.clone());
            continue;
        };
        if f.header != c.header || f.x != c.x {
            // e.g. an MSD whose lags are whole steps: other times at another dt.
            skipped.push(name.clone());
            continue;
        }
        let extrapolated = Pooled {
            header: c.header.clone(),
            x: c.x.clone(),
            means: (0..c.means.len())
                .map(|j| {
                    (0..c.x.len())
                        .map(|i| (gain * f.means[j][i] - c.means[j][i]) / (gain - 1.0))
                        .collect()
                })
                .collect(),
            errors: (0..c.means.len())
                .map(|j| {
                    (0..c.x.len())
                        .map(|i| {
                            (gain * gain * f.errors[j][i].powi(2) + c.errors[j][i].powi(2)).sqrt()
                                / (gain - 1.0)
                        })
                        .collect()
                })
                .collect(),
        };
        if let Some(w) = negative_where_runs_are_not(name, c, f, &extrapolated) {
            warnings.push(w);
        }
        write_pooled(&out, name, &extrapolated)?;
        files.push(name.clone());
        for (sub, p) in [("dt", c), ("half-dt", f)] {
            std::fs::create_dir_all(out.join(sub))?;
            write_pooled(&OutputDir::reopen(out.join(sub))?, name, p)?;
        }
    }
    if !skipped.is_empty() {
        warnings.push(format!(
            "not extrapolated (their first column differs between the time steps): {}",
            skipped.join(", ")
        ));
    }
    let summary = json!({
        "software": crate::software(),
        "method": "richardson extrapolation in dt",
        "scenario_method": sc.method()?,
        "dt": [dt, 0.5 * dt],
        "order": opts.order,
        "seeds": opts.seeds,
        "seed_first": base_seed,
        "formula": "A(0) = (2^p A(dt/2) - A(dt)) / (2^p - 1); errors: standard errors over seeds, propagated",
        "files": files,
        "skipped": skipped,
        "warnings": warnings,
        "completed": true,
    });
    out.write_json("summary.json", &summary)?;
    let message = format!(
        "extrapolated {} table(s) from dt = {dt:e} and {:e} ({} seeds each, order {}) into {}",
        files.len(),
        0.5 * dt,
        opts.seeds,
        opts.order,
        out.path().display()
    );
    Ok(Report {
        out: out.path().to_path_buf(),
        summary,
        files,
        warnings,
        message,
    })
}
