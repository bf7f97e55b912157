//! `colloidsim run|theory|check|bench` for Brownian cluster dynamics scenarios.

use crate::common::{RunOptions, progress};
use crate::plot::{Scale, Series, line_plot};
use anyhow::{Context, Result, bail};
use colloidsim_bcd::forces::{NoField, NoPair};
use colloidsim_bcd::observe::{ClusterSizes, ContactDensity, DensityProfile, Msd};
use colloidsim_bcd::scenario::{Field, Resolved, Scenario};
use colloidsim_bcd::{Bcd, BcdConfig, BcdState, Boundary, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};
use colloidsim_core::output::OutputDir;
use colloidsim_core::trigger::log_spaced;
use colloidsim_dft::rods::{self, BetaPotential, Domain, RodInteraction, RodsProblem};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);
const CHECKPOINT: &str = "checkpoint.bin";

fn parse(path: &Path, text: &str) -> Result<Scenario> {
    toml::from_str(text).with_context(|| format!("scenario {}", path.display()))
}

fn resolve(path: &Path, sc: &Scenario, seed: Option<u64>) -> Result<Resolved> {
    let base = path.parent().unwrap_or(Path::new("."));
    sc.resolve(base, seed)
        .with_context(|| format!("scenario {}", path.display()))
}

/// `colloidsim check`: validate and print the resolved parameters.
pub fn check(path: &Path, text: &str) -> Result<()> {
    let sc = parse(path, text)?;
    let r = resolve(path, &sc, None)?;
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    // Building the engine checks the initial positions (overlaps, walls).
    Bcd::new(r.config.clone(), r.initial.clone(), NoField, NoPair)
        .with_context(|| format!("scenario {}", path.display()))?;
    println!("{}", serde_json::to_string_pretty(&resolved_json(&sc, &r))?);
    println!("scenario {} is valid", path.display());
    Ok(())
}

fn resolved_json(sc: &Scenario, r: &Resolved) -> serde_json::Value {
    let c = &r.config;
    json!({
        "method": sc.method,
        "seed": c.seed,
        "system": {
            "length": c.length, "particles": r.initial.len(), "diameter": c.sigma,
            "mobility": c.mobility, "kT": c.kt, "D": c.diffusion(), "boundary": c.boundary,
            "mean_density": r.initial.len() as f64 / c.length,
            "packing_fraction": r.initial.len() as f64 * c.sigma / c.length,
        },
        "potential": sc.potential,
        "interaction": sc.interaction,
        "run": {
            "dt": c.dt, "equilibrate_steps": r.equilibrate_steps,
            "sampled_steps": r.sampled_steps, "equilibrate": sc.run.equilibrate, "time": sc.run.time,
        },
        "observe": sc.observe,
        "profile_period": r.period,
        "external_force": match &r.engine_field {
            Field::None => "none",
            Field::Cosine(_) => "exact cosine (vectorised sine)",
            Field::Table(_) => "cubic Hermite table (error < 1e-9 of the largest force)",
            Field::Exact(_) => "exact, term by term",
        },
        "external_force_table_spacing": match &r.engine_field {
            Field::Table(t) => Some(t.spacing()),
            _ => None,
        },
    })
}

/// Mean displacement per rod since sampling started, for the particle current.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Current {
    x0_sum: f64,
    t: Vec<f64>,
    displacement: Vec<f64>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Observers {
    density: Option<DensityProfile>,
    contact: Option<ContactDensity>,
    msd: Option<Msd>,
    clusters: Option<ClusterSizes>,
    current: Option<Current>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Checkpoint {
    version: String,
    scenario: String,
    seed: u64,
    state: BcdState,
    observers: Observers,
    wall_seconds: f64,
    frames: u64,
}

fn observers(sc: &Scenario, r: &Resolved) -> Observers {
    let c = &r.config;
    let o = &sc.observe;
    let n = r.initial.len() as f64;
    let msd = o.msd.as_ref().map(|m| {
        let max_lag = m.max_lag.unwrap_or(0.5 * sc.run.time);
        let max_steps = ((max_lag / c.dt).round() as u64).max(1);
        let lags = log_spaced(1, max_steps, m.points);
        // ~100 time origins over the sampled run.
        Msd::new(lags, (r.sampled_steps / 100).max(1))
    });
    Observers {
        density: o
            .density
            .as_ref()
            .map(|d| DensityProfile::new(d.bins, r.period, c.length)),
        contact: o.contact_density.as_ref().map(|d| {
            ContactDensity::new(d.bins, d.window, r.period, c.sigma, c.length, c.boundary)
        }),
        msd,
        clusters: o.clusters.then(ClusterSizes::default),
        current: o.current.then(|| Current {
            x0_sum: r.initial.iter().sum::<f64>() / n,
            t: Vec::new(),
            displacement: Vec::new(),
        }),
    }
}

/// `colloidsim run` for BCD scenarios.
pub fn run(path: &Path, text: &str, opts: &RunOptions) -> Result<()> {
    let sc = parse(path, text)?;
    let r = resolve(path, &sc, opts.seed)?;
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    let (out, ckpt) = match &opts.restart {
        Some(dir) => {
            let out = OutputDir::reopen(dir)?;
            let bytes = std::fs::read(out.join(CHECKPOINT)).with_context(|| {
                format!(
                    "--restart {}: no {CHECKPOINT} to continue from",
                    dir.display()
                )
            })?;
            crate::common::check_checkpoint_version(&bytes, &out.join(CHECKPOINT))?;
            let ck: Checkpoint = bincode::deserialize(&bytes)
                .with_context(|| format!("{}: unreadable checkpoint", dir.display()))?;
            if ck.scenario != text {
                bail!(
                    "--restart {}: the scenario differs from the one this run started with (saved as {}/scenario.toml)",
                    dir.display(),
                    dir.display()
                );
            }
            if ck.seed != r.config.seed as u64 {
                bail!(
                    "--restart: seed {} differs from the checkpoint's {}",
                    r.config.seed,
                    ck.seed
                );
            }
            (out, Some(ck))
        }
        None => {
            let out = OutputDir::create(&opts.out, opts.force)?;
            out.write_bytes("scenario.toml", text.as_bytes())?;
            (out, None)
        }
    };
    let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
    match (&r.engine_field, r.pair.range() > 0.0) {
        (Field::None, false) => simulate(&sc, &r, &out, ckpt, opts, Field::None, NoPair),
        (f, false) => simulate(&sc, &r, &out, ckpt, opts, f.clone(), NoPair),
        (f, true) => simulate(&sc, &r, &out, ckpt, opts, f.clone(), r.pair.clone()),
    }
}

use colloidsim_bcd::forces::PairForce;

fn simulate<P: PairForce + Clone>(
    sc: &Scenario,
    r: &Resolved,
    out: &OutputDir,
    ckpt: Option<Checkpoint>,
    opts: &RunOptions,
    field: Field,
    pair: P,
) -> Result<()> {
    let cfg = r.config.clone();
    let n = r.initial.len();
    let (mut bcd, mut obs, mut wall_before, mut frames) = match ckpt {
        Some(ck) => (
            Bcd::from_state(cfg.clone(), ck.state, field, pair)?,
            ck.observers,
            ck.wall_seconds,
            ck.frames,
        ),
        None => (
            Bcd::new(cfg.clone(), r.initial.clone(), field, pair)?,
            observers(sc, r),
            0.0,
            0,
        ),
    };
    let total = r.equilibrate_steps + r.sampled_steps;
    let every = sc.observe.every.unwrap_or(1);
    let ck_every = sc.run.checkpoint_every.unwrap_or((total / 10).max(1000));
    let current_every = (r.sampled_steps / 200).max(1);
    let traj_every = sc.observe.trajectory.as_ref().map(|t| t.every);
    let mut gsd = match traj_every {
        Some(_) => Some(open_trajectory(out, frames > 0 || bcd.steps() > 0)?),
        None => None,
    };
    // Test hook: behave as if Ctrl-C arrived at this step.
    let stop_at: Option<u64> = std::env::var("COLLOIDSIM_INTERRUPT_AT_STEP")
        .ok()
        .and_then(|v| v.parse().ok());
    let pb = progress(total, opts.quiet, "bcd");
    pb.set_position(bcd.steps());
    let start = Instant::now();
    // Checkpoint: flush the trajectory first, so that the file holds every frame the state knows.
    let save = |bcd: &Bcd<Field, P>,
                obs: &Observers,
                gsd: &mut Option<hoomd_gsd::hoomd::HoomdGsdFile>,
                wall: f64,
                frames: u64|
     -> Result<()> {
        if let Some(g) = gsd.as_mut() {
            g.sync_all()?;
        }
        let ck = Checkpoint {
            version: crate::common::checkpoint_version(),
            scenario: std::fs::read_to_string(out.join("scenario.toml"))?,
            seed: cfg.seed as u64,
            state: bcd.state().clone(),
            observers: obs.clone(),
            wall_seconds: wall,
            frames,
        };
        out.write_bytes(CHECKPOINT, &bincode::serialize(&ck)?)?;
        Ok(())
    };
    // The steps run on a worker of the thread pool, so that each step's chunks start without a
    // hand-over from this thread (see `Bcd::run`).
    rayon::scope(|_| -> Result<()> {
        while bcd.steps() < total {
            if stop_at == Some(bcd.steps()) {
                INTERRUPTED.store(true, Ordering::SeqCst);
            }
            if INTERRUPTED.load(Ordering::Relaxed) {
                let wall = wall_before + start.elapsed().as_secs_f64();
                save(&bcd, &obs, &mut gsd, wall, frames)?;
                pb.abandon();
                bail!(
                    "interrupted at step {}; checkpoint written. Continue with: colloidsim run SCENARIO --restart {}",
                    bcd.steps(),
                    out.path().display()
                );
            }
            bcd.step()?;
            let s = bcd.steps();
            if s > r.equilibrate_steps {
                let k = s - r.equilibrate_steps;
                let x = bcd.positions();
                if k.is_multiple_of(every) {
                    if let Some(d) = obs.density.as_mut() {
                        d.sample(x);
                    }
                    if let Some(c) = obs.contact.as_mut() {
                        c.sample(x);
                    }
                    if let Some(c) = obs.clusters.as_mut() {
                        c.sample(&bcd);
                    }
                }
                if let Some(m) = obs.msd.as_mut() {
                    m.sample(k - 1, x);
                }
                if let Some(c) = obs.current.as_mut()
                    && k.is_multiple_of(current_every)
                {
                    c.t.push(k as f64 * cfg.dt);
                    c.displacement
                        .push(x.iter().sum::<f64>() / n as f64 - c.x0_sum);
                }
            } else if s == r.equilibrate_steps
                && let Some(c) = obs.current.as_mut()
            {
                c.x0_sum = bcd.positions().iter().sum::<f64>() / n as f64;
            }
            if let (Some(g), Some(e)) = (gsd.as_mut(), traj_every)
                && s.is_multiple_of(e)
            {
                write_frame(g, &bcd)?;
                frames += 1;
            }
            if s.is_multiple_of(ck_every) && s < total {
                let wall = wall_before + start.elapsed().as_secs_f64();
                save(&bcd, &obs, &mut gsd, wall, frames)?;
            }
            if s.is_multiple_of(256) {
                pb.set_position(s);
            }
        }
        Ok(())
    })?;
    pb.finish_and_clear();
    wall_before += start.elapsed().as_secs_f64();
    save(&bcd, &obs, &mut gsd, wall_before, frames)?;
    write_outputs(sc, r, out, &bcd, &obs, wall_before, frames)
}

fn open_trajectory(out: &OutputDir, append: bool) -> Result<hoomd_gsd::hoomd::HoomdGsdFile> {
    let path = out.join("trajectory.gsd");
    Ok(if append && path.exists() {
        hoomd_gsd::hoomd::HoomdGsdFile::open(&path)?
    } else {
        hoomd_gsd::hoomd::HoomdGsdFile::create(&path)?
    })
}

/// One GSD frame in the HOOMD schema: rods on the x axis of a 2D box of size L x L, positions
/// wrapped into [-L/2, L/2); the unwrapped positions go to `log/particles/x_unwrapped`.
fn write_frame<E, P>(g: &mut hoomd_gsd::hoomd::HoomdGsdFile, bcd: &Bcd<E, P>) -> Result<()>
where
    E: colloidsim_bcd::forces::ExternalForce,
    P: PairForce,
{
    let c = bcd.config();
    let l = c.length;
    let x = bcd.positions();
    g.append_frame(bcd.steps())?
        .configuration_dimensions(hoomd_gsd::hoomd::Dimensions::Two)?
        .configuration_box([l, l, 0.0, 0.0, 0.0, 0.0])?
        .particles_position(x.iter().map(|&xi| {
            let w = (xi + 0.5 * l).rem_euclid(l) - 0.5 * l;
            [w, 0.0, 0.0].into()
        }))?
        .particles_diameter(x.iter().map(|_| c.sigma))?
        .log_scalars("particles/x_unwrapped", x.iter().copied())?
        .end()?;
    Ok(())
}

fn write_outputs<E, P>(
    sc: &Scenario,
    r: &Resolved,
    out: &OutputDir,
    bcd: &Bcd<E, P>,
    obs: &Observers,
    wall: f64,
    frames: u64,
) -> Result<()>
where
    E: colloidsim_bcd::forces::ExternalForce,
    P: PairForce,
{
    let c = &r.config;
    let n = r.initial.len();
    let mut files = vec![
        "scenario.toml".to_string(),
        CHECKPOINT.to_string(),
        "final_configuration.csv".to_string(),
    ];
    out.write_table("final_configuration.csv", &[("x", bcd.positions())])?;
    // The theory is a companion: if it fails, the simulation's outputs are still written.
    let (theory, theory_error) = match equilibrium_counterpart(sc, r, None, obs) {
        Ok(t) => (t, None),
        Err(e) => {
            eprintln!("warning: no theory curve: {e:#}");
            (None, Some(format!("{e:#}")))
        }
    };
    if let Some(d) = &obs.density {
        let (x, rho) = d.profile();
        out.write_table("density.csv", &[("x", &x), ("rho", &rho)])?;
        files.push("density.csv".into());
        let mut series = vec![Series {
            label: "BCD",
            x: &x,
            y: &rho,
            points: true,
        }];
        if let Some((t, _)) = &theory {
            out.write_table("density_theory.csv", &[("x", &t.centres), ("rho", &t.rho)])?;
            files.push("density_theory.csv".into());
            series.push(Series {
                label: "exact theory",
                x: &t.centres,
                y: &t.rho,
                points: false,
            });
        }
        line_plot(
            &out.join("density.png"),
            &format!(
                "density profile, N = {n}, L = {}, sigma = {}",
                c.length, c.sigma
            ),
            "x",
            "rho(x)",
            &series,
            Scale::Linear,
        )?;
        files.push("density.png".into());
    }
    if let Some(cd) = &obs.contact {
        let (x, rho2) = cd.profile();
        out.write_table("contact_density.csv", &[("x", &x), ("rho2", &rho2)])?;
        files.push("contact_density.csv".into());
        if let Some((t, hard)) = &theory
            && *hard
        {
            out.write_table(
                "contact_density_theory.csv",
                &[("x", &t.centres), ("rho2", &t.contact_density)],
            )?;
            files.push("contact_density_theory.csv".into());
        }
    }
    if let Some(m) = &obs.msd {
        let rows = m.rows();
        let t: Vec<f64> = rows.iter().map(|r| r.0 as f64 * c.dt).collect();
        let msd: Vec<f64> = rows.iter().map(|r| r.1).collect();
        let err: Vec<f64> = rows.iter().map(|r| r.2).collect();
        out.write_table("msd.csv", &[("t", &t), ("msd", &msd), ("err", &err)])?;
        files.push("msd.csv".into());
        if t.len() > 1 {
            let free: Vec<f64> = t.iter().map(|t| 2.0 * c.diffusion() * t).collect();
            let mut series = vec![
                Series {
                    label: "BCD",
                    x: &t,
                    y: &msd,
                    points: true,
                },
                Series {
                    label: "free diffusion 2Dt",
                    x: &t,
                    y: &free,
                    points: false,
                },
            ];
            let rho = n as f64 / c.length;
            let sf: Vec<f64> = t
                .iter()
                .map(|t| {
                    (1.0 - rho * c.sigma) / rho
                        * (4.0 * c.diffusion() * t / std::f64::consts::PI).sqrt()
                })
                .collect();
            if r.field.is_zero() && c.boundary == Boundary::Periodic {
                series.push(Series {
                    label: "single file (1-rho sigma)/rho sqrt(4Dt/pi)",
                    x: &t,
                    y: &sf,
                    points: false,
                });
            }
            line_plot(
                &out.join("msd.png"),
                "mean-square displacement",
                "t",
                "MSD",
                &series,
                Scale::LogLog,
            )?;
            files.push("msd.png".into());
        }
    }
    let mut mean_velocity = None;
    if let Some(cur) = &obs.current {
        let v: Vec<f64> = cur
            .t
            .iter()
            .zip(&cur.displacement)
            .map(|(t, d)| d / t)
            .collect();
        let rho = n as f64 / c.length;
        let j: Vec<f64> = v.iter().map(|v| rho * v).collect();
        out.write_table(
            "current.csv",
            &[
                ("t", &cur.t),
                ("displacement", &cur.displacement),
                ("velocity", &v),
                ("current", &j),
            ],
        )?;
        files.push("current.csv".into());
        mean_velocity = v.last().copied();
    }
    if let Some(cl) = &obs.clusters {
        let (s, p) = cl.rows();
        out.write_table("clusters.csv", &[("size", &s), ("probability", &p)])?;
        files.push("clusters.csv".into());
    }
    if frames > 0 {
        files.push("trajectory.gsd".into());
    }
    let steps = bcd.steps();
    let summary = json!({
        "software": format!("colloidsim {}", env!("CARGO_PKG_VERSION")),
        "method": sc.method,
        "seed": c.seed,
        "parameters": resolved_json(sc, r),
        "steps": steps,
        "time": bcd.time(),
        "wall_seconds": wall,
        "particle_steps_per_second": (steps as f64 * n as f64) / wall.max(1e-9),
        "threads": rayon::current_num_threads(),
        "mean_velocity": mean_velocity,
        "particle_current": mean_velocity.map(|v| v * n as f64 / c.length),
        "theory": theory.as_ref().map(|(_, _)| "density_theory.csv: exact equilibrium (colloidsim theory) on the same bins"),
        "theory_error": theory_error,
        "files": files,
    });
    out.write_json("summary.json", &summary)?;
    println!(
        "{} steps of {n} rods in {wall:.2} s ({:.3e} particle-steps/s); outputs in {}",
        steps,
        (steps as f64 * n as f64) / wall.max(1e-9),
        out.path().display()
    );
    Ok(())
}

/// The exact equilibrium profile averaged over the scenario's density bins, when the scenario
/// has an equilibrium (no drive, kT > 0, a density observable). Returns (profile, hard rods?).
fn equilibrium_counterpart(
    sc: &Scenario,
    r: &Resolved,
    dx: Option<f64>,
    obs: &Observers,
) -> Result<Option<(rods::BinnedProfile, bool)>> {
    let c = &r.config;
    if r.field.drive != 0.0 || c.kt <= 0.0 || obs.density.is_none() {
        return Ok(None);
    }
    if r.pair.yukawa.is_some() || r.pair.table.is_some() {
        return Ok(None);
    }
    let bins = sc.observe.density.as_ref().map_or(100, |d| d.bins);
    let eq = solve_theory(r, dx)?;
    let b = eq.bin_average(bins, r.period)?;
    Ok(Some((b, r.pair.sticky.is_none())))
}

fn solve_theory(r: &Resolved, dx: Option<f64>) -> Result<rods::Equilibrium> {
    let c = &r.config;
    let n = r.initial.len() as f64;
    let domain = match c.boundary {
        Boundary::Periodic => Domain::Periodic { period: r.period },
        Boundary::Walls => Domain::Walls { length: c.length },
    };
    let interaction = match &r.pair.sticky {
        Some(s) => RodInteraction::Sticky { gamma: s.gamma },
        None => RodInteraction::Hard,
    };
    let dx = dx.unwrap_or((c.sigma / 200.0).min(r.period / 2000.0));
    let problem = RodsProblem::new(c.sigma, n / c.length, domain)
        .with_dx(dx)
        .with_potential(BetaPotential::from_field(&r.field, c.kt))
        .with_interaction(interaction);
    Ok(rods::equilibrium(&problem)?)
}

/// `colloidsim theory`: the exact equilibrium of a BCD scenario on the simulation's bins.
pub fn theory(path: &Path, text: &str, out: &Path, dx: Option<f64>, force: bool) -> Result<()> {
    let sc = parse(path, text)?;
    let r = resolve(path, &sc, None)?;
    let c = &r.config;
    if r.field.drive != 0.0 {
        bail!(
            "potential.drive = {}: a driven system has no equilibrium; the exact theory needs drive = 0",
            r.field.drive
        );
    }
    if c.kt <= 0.0 {
        bail!("system.kT = 0: the exact theory is an equilibrium at kT > 0");
    }
    if r.pair.yukawa.is_some() || r.pair.table.is_some() {
        bail!(
            "interaction: the exact theory covers hard and sticky rods only (no yukawa or table)"
        );
    }
    if let Some(dx) = dx {
        colloidsim_core::param::positive("--dx", dx)?;
    }
    let start = Instant::now();
    let eq = solve_theory(&r, dx)?;
    let wall = start.elapsed().as_secs_f64();
    let outdir = OutputDir::create(out, force)?;
    let bins = sc.observe.density.as_ref().map_or(1000, |d| d.bins);
    let b = eq.bin_average(bins, r.period)?;
    let mut files = vec!["density.csv"];
    outdir.write_table("density.csv", &[("x", &b.centres), ("rho", &b.rho)])?;
    let cbins = sc.observe.contact_density.as_ref().map_or(bins, |d| d.bins);
    let bc = eq.bin_average(cbins, r.period)?;
    if r.pair.sticky.is_none() {
        outdir.write_table(
            "contact_density.csv",
            &[("x", &bc.centres), ("rho2", &bc.contact_density)],
        )?;
        files.push("contact_density.csv");
    } else if let Some(bp) = &bc.bonded_pair_density {
        outdir.write_table(
            "bonded_pair_density.csv",
            &[("x", &bc.centres), ("rho2", bp)],
        )?;
        files.push("bonded_pair_density.csv");
    }
    outdir.write_table(
        "profile_grid.csv",
        &[
            ("x", &eq.x),
            ("rho", &eq.rho),
            ("rho2", &eq.contact_density),
        ],
    )?;
    files.push("profile_grid.csv");
    line_plot(
        &outdir.join("density.png"),
        &format!("exact equilibrium density, sigma = {}", c.sigma),
        "x",
        "rho(x)",
        &[Series {
            label: "exact theory",
            x: &eq.x,
            y: &eq.rho,
            points: false,
        }],
        Scale::Linear,
    )?;
    files.push("density.png");
    outdir.write_json(
        "summary.json",
        &json!({
            "software": format!("colloidsim {}", env!("CARGO_PKG_VERSION")),
            "method": "exact 1D density functional (Percus hard rods / Baxter sticky rods)",
            "parameters": resolved_json(&sc, &r),
            "dx": eq.dx,
            "grid_points": eq.x.len(),
            "iterations": eq.iterations,
            "total_iterations": eq.total_iterations,
            "residual": eq.residual,
            "tolerance": eq.tolerance,
            "converged": true,
            "beta_mu": eq.beta_mu,
            "wall_seconds": wall,
            "files": files,
        }),
    )?;
    println!(
        "exact equilibrium: {} grid points, residual {:.2e} after {} iterations in {:.3} s; outputs in {}",
        eq.x.len(),
        eq.residual,
        eq.iterations,
        wall,
        outdir.path().display()
    );
    Ok(())
}

/// Arguments of `colloidsim bench bcd`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Particle numbers for the premerging update.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1000,10000,100000,1000000"
    )]
    pub n: Vec<usize>,
    /// Particle numbers for the chronological update (O(N^2)); 0 skips it.
    #[arg(long, value_delimiter = ',', default_value = "100,300,1000,3000,10000")]
    pub chronological: Vec<usize>,
    /// Particle-steps per measurement (steps = this / N, at least 20).
    #[arg(long, default_value_t = 20_000_000)]
    pub work: u64,
    /// Repetitions; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
}

fn rss_bytes() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: f64 = s.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096.0)
}

/// `colloidsim bench bcd`: the fast-bcd scaling case (sigma = 0.99, U0 = 6 kT, density 1 per
/// wavelength, dt = 1e-3, periodic), nanoseconds per particle-step.
pub fn bench(a: &BenchArgs) -> Result<()> {
    let field = ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    };
    // The force as `colloidsim run` evaluates this field.
    let force = Field::new(&field);
    println!(
        "# colloidsim bench bcd: sigma = 0.99, U0 = 6 kT, rho = 1, dt = 1e-3, periodic; {} threads, median of {}",
        rayon::current_num_threads(),
        a.repeats
    );
    println!("method\tN\tsteps\tns_per_particle_step\tmin\tmax\tRSS_bytes_per_particle");
    let run = |n: usize, update: Update| -> Result<()> {
        let cfg = BcdConfig {
            length: n as f64,
            sigma: 0.99,
            mobility: 1.0,
            kt: 1.0,
            dt: 1e-3,
            boundary: Boundary::Periodic,
            seed: 1,
            update,
        };
        let steps = (a.work / n as u64).max(20);
        let mut times = Vec::new();
        let mut mem = f64::NAN;
        let x0 = init::lattice(&cfg, n)?;
        for rep in 0..a.repeats.max(1) {
            let before = rss_bytes();
            let mut b = Bcd::new(cfg.clone(), x0.clone(), force.clone(), NoPair)?;
            b.run(steps.min(50))?; // warm-up: clusters form, buffers reach their size
            let t = Instant::now();
            b.run(steps)?;
            times.push(t.elapsed().as_secs_f64() * 1e9 / (steps as f64 * n as f64));
            if rep == 0
                && let (Some(b0), Some(b1)) = (before, rss_bytes())
            {
                mem = (b1 - b0) / n as f64;
            }
            drop(b);
        }
        times.sort_by(f64::total_cmp);
        let name = match update {
            Update::Premerge => "premerge",
            Update::Chronological => "chronological",
        };
        println!(
            "{name}\t{n}\t{steps}\t{:.2}\t{:.2}\t{:.2}\t{:.0}",
            times[times.len() / 2],
            times[0],
            times[times.len() - 1],
            mem
        );
        Ok(())
    };
    // A 0 in a list skips that method.
    for &n in a.n.iter().filter(|&&n| n > 0) {
        run(n, Update::Premerge)?;
    }
    for &n in a.chronological.iter().filter(|&&n| n > 0) {
        run(n, Update::Chronological)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Engine states round-trip through the checkpoint encoding bit for bit, with and without
    /// the ring update's reduced coordinates (bincode is not self-describing, so every field
    /// must always be written).
    #[test]
    fn engine_states_round_trip_through_bincode() {
        for boundary in [Boundary::Periodic, Boundary::Walls] {
            let cfg = BcdConfig {
                length: 50.0,
                sigma: 1.0,
                mobility: 1.0,
                kt: 1.0,
                dt: 1e-3,
                boundary,
                seed: 3,
                update: Update::Premerge,
            };
            let x = init::random(&cfg, 30, 3).unwrap();
            let mut b = Bcd::new(cfg, x, NoField, NoPair).unwrap();
            b.run(10).unwrap();
            let state = b.state().clone();
            assert_eq!(state.reduced.is_empty(), boundary == Boundary::Walls);
            let bytes = bincode::serialize(&(state.clone(), 7u64)).unwrap();
            let (back, tail): (BcdState, u64) = bincode::deserialize(&bytes).unwrap();
            assert_eq!(back, state);
            assert_eq!(tail, 7);
        }
    }
}
