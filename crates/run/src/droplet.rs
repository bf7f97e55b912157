//! The drying droplet (`method = "droplet-bd"`): Brownian dynamics of WCA spheres in a
//! shrinking (or, with `drying.peclet = 0`, static) harmonic interface, free draining by the
//! free-draining engine or with RPY hydrodynamics (`[hydrodynamics]`: direct free-space sums or
//! PSE in a periodic box), replicas one after the other, radial volume-fraction profiles at
//! fractions of the drying time; `theory` is the radial FMT DDFT ([`crate::theory_droplet`]).

use crate::checkpoint::{Envelope, file_crc};
use crate::control::Control;
use crate::keys::Key;
use crate::method::{Checked, Finished, Method, Session};
use crate::plot::{Disc, Scale, Series, cross_section, line_plot, picture};
use crate::theory_droplet::profile_name;
use crate::trajectory::FrameDigest;
use crate::{Report, Scenario as Source, TheoryOptions};
use anyhow::{Context, Result, bail};
use colloidsim_analysis::radial_profile;
use colloidsim_core::output::OutputDir;
use colloidsim_md::brownian::Integrator;
use colloidsim_md::droplet::{DropletSim, HydroDropletSim};
use colloidsim_md::gsd::{self, GsdWriter};
use colloidsim_md::{
    BdParams, DropletParams, DropletScenario, HydroBdParams, LennardJones, Particles, SimBox,
};
use hoomd_gsd::file_layer::Mode;
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::path::Path;

/// The drying-droplet family of scenarios.
pub struct DropletBd;

/// Parse and validate a scenario; `system.initial` is taken relative to the scenario's folder.
pub(crate) fn resolve(src: &Source, seed: Option<u64>) -> Result<(DropletScenario, DropletParams)> {
    crate::keys::validate(&src.table()?, crate::keys::DROPLET).with_context(|| src.label())?;
    let mut sc = DropletScenario::from_toml(src.text()).with_context(|| src.label())?;
    if let Some(s) = seed {
        crate::seed32(s)?;
        sc.seed = s;
    }
    if let Some(init) = &sc.system.initial
        && init.is_relative()
    {
        sc.system.initial = Some(src.base().join(init));
    }
    let p = sc.validate().with_context(|| src.label())?;
    Ok((sc, p))
}

impl Method for DropletBd {
    fn names(&self) -> &'static [&'static str] {
        &["droplet-bd"]
    }

    fn about(&self) -> &'static str {
        "a drying (or static) droplet of hard-sphere colloids, Brownian dynamics free draining or with RPY hydrodynamics, beside its FMT DDFT"
    }

    fn docs(&self) -> &'static str {
        "docs/droplet.md"
    }

    fn check(&self, src: &Source) -> Result<Checked> {
        let (_, p) = resolve(src, None)?;
        // What `run` does before it starts: set up replica 0 (reading system.initial).
        p.build_replica(0).with_context(|| src.label())?;
        Ok(Checked {
            resolved: serde_json::to_value(&p)?,
            warnings: Vec::new(),
        })
    }

    fn start(&self, src: &Source, seed: Option<u64>) -> Result<Box<dyn Session>> {
        let (_, p) = resolve(src, seed)?;
        // Set up replica 0 before the output folder is created: bad input leaves nothing.
        let sim = Replica::build(&p, 0)?;
        let acc = Accum::new(&p);
        Ok(Box::new(DropletSession::new(p, acc, 0, Some((sim, 0)))))
    }

    fn restore(
        &self,
        src: &Source,
        seed: u64,
        out: &OutputDir,
        envelope: &Envelope,
    ) -> Result<Box<dyn Session>> {
        let (_, p) = resolve(src, Some(seed))?;
        let saved: Saved = crate::checkpoint::decode_payload(&envelope.payload)?;
        if saved.replica >= p.replicas || saved.acc.sums.len() != p.fractions.len() {
            bail!(
                "checkpoint: replica {} of {} with {} profiles does not fit the scenario",
                saved.replica,
                p.replicas,
                saved.acc.sums.len()
            );
        }
        let sim = restore_replica(out, &p, &saved)?;
        if p.trajectory_every > 0 {
            saved
                .acc
                .digest
                .restore(&out.join("trajectory.gsd"), |path, frames| {
                    trim_trajectory(path, frames, &["droplet/radius", "droplet/time"], false)
                })?;
        }
        Ok(Box::new(DropletSession::new(
            p,
            saved.acc,
            saved.replica,
            sim,
        )))
    }

    fn has_theory(&self) -> bool {
        true
    }

    fn theory(&self, src: &Source, opts: &TheoryOptions, ctl: &Control) -> Result<Report> {
        crate::theory_droplet::theory(src, opts, ctl)
    }

    fn keys(&self) -> Vec<Key> {
        crate::keys::droplet()
    }

    fn engine(&self, src: &Source, seed: Option<u64>) -> Result<Box<dyn crate::Engine>> {
        let (_, p) = resolve(src, seed)?;
        let sim = Replica::build(&p, 0)?;
        Ok(Box::new(BdEngine { sim }))
    }
}

/// Everything a droplet run accumulates across replicas, saved in every checkpoint.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Accum {
    /// Per profile fraction: sum over the replicas that reached it of the volume-fraction
    /// profile.
    sums: Vec<Vec<f64>>,
    /// Per profile fraction: how many replicas reached it.
    counts: Vec<u64>,
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
    /// CRC-32 of those frames, checked before a restart appends to the file.
    digest: FrameDigest,
    /// Checkpoints written so far (alternates the GSD file name).
    checkpoints: u64,
}

impl Accum {
    fn new(p: &DropletParams) -> Self {
        let n_frac = p.fractions.len();
        Self {
            sums: vec![vec![0.0; p.bins]; n_frac],
            counts: vec![0; n_frac],
            radii: vec![0.0; n_frac],
            r_axes: vec![Vec::new(); n_frac],
            max_excursion: f64::NEG_INFINITY,
            outside_final: 0,
            builds: 0,
            frames: 0,
            digest: FrameDigest::default(),
            checkpoints: 0,
        }
    }
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
    fn of(s: &Replica, builds: u64) -> Self {
        match s {
            Replica::Free(s) => {
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
            Replica::Hydro(s) => {
                let b = s.params();
                Self {
                    kt: b.kt,
                    viscosity: 0.0,
                    dt: b.dt,
                    seed: b.seed,
                    replica: b.replica,
                    skin: b.skin,
                    sort_every: 0,
                    max_drift: b.max_drift,
                    builds,
                }
            }
        }
    }

    fn hydro_params(&self) -> HydroBdParams {
        HydroBdParams {
            kt: self.kt,
            dt: self.dt,
            seed: self.seed,
            replica: self.replica,
            skin: self.skin,
            max_drift: self.max_drift,
        }
    }

    /// The free-draining engine's parameters with `integrator` (the scenario's
    /// `run.integrator`: a restart runs the scenario it started with, so the checkpoint need not
    /// hold it; nor the Leimkuhler–Matthews deviates, which the engine draws again from (seed,
    /// step, particle)).
    fn params(&self, integrator: Integrator) -> BdParams {
        BdParams {
            kt: self.kt,
            viscosity: self.viscosity,
            dt: self.dt,
            seed: self.seed,
            replica: self.replica,
            skin: self.skin,
            sort_every: self.sort_every,
            max_drift: self.max_drift,
            integrator,
        }
    }
}

/// The method's part of `checkpoint.bin`. The running replica's particles (exact positions,
/// images, box, storage order, list reference positions) are in the GSD file it names, whose
/// CRC-32 it keeps.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Saved {
    /// Replica to continue.
    replica: usize,
    /// Its step: every event (profile, frame) up to and including this step is in `acc`.
    step: u64,
    /// GSD checkpoint of the replica at `step`, its CRC-32 and its engine parameters; `None`:
    /// the replica has not started (step 0, built afresh).
    state: Option<(String, u32, Engine)>,
    acc: Accum,
}

/// Restore the running replica from a checkpoint (verified against its CRC first).
fn restore_replica(
    out: &OutputDir,
    p: &DropletParams,
    saved: &Saved,
) -> Result<Option<(Replica, u64)>> {
    let Some((name, crc, engine)) = &saved.state else {
        return Ok(None);
    };
    let path = out.join(name);
    let found = file_crc(&path)?;
    if found != *crc {
        bail!(
            "{}: damaged: checksum {found:08x}, the checkpoint recorded {crc:08x}",
            path.display()
        );
    }
    let mut f = gsd::read_frame(&path, None)?;
    // The hydrodynamic engine's state is its exact positions and images; the free-draining
    // engine's also holds its storage order and list reference positions.
    let hydro = p.hydrodynamics.as_ref().filter(|_| p.has_hydrodynamics());
    if f.step != saved.step
        || !f.exact
        || f.list.is_none() != hydro.is_some()
        || engine.replica as usize != saved.replica
    {
        bail!(
            "{}: not the checkpoint of replica {} at step {} that checkpoint.bin names",
            path.display(),
            saved.replica,
            saved.step
        );
    }
    // GSD stores diameters in single precision: every colloid has the scenario's.
    f.particles.diameter.fill(p.diameter);
    let sim = match hydro {
        None => Replica::Free(Box::new(
            DropletSim::restart(
                f.particles,
                f.sbox,
                LennardJones::wca(p.kt, p.diameter),
                p.interface(),
                engine.params(p.integrator),
                f.step,
                f.list.as_ref(),
            )
            .with_context(|| format!("restart from {}", path.display()))?,
        )),
        Some(h) => Replica::hydro(
            p.restart_hydro_replica(f.particles, h, engine.hydro_params(), f.step)
                .with_context(|| format!("restart from {}", path.display()))?,
        ),
    };
    // The rebuild on restoring is not one the uninterrupted run makes: leave it out.
    let builds = engine.builds.saturating_sub(sim.neighbor_builds());
    Ok(Some((sim, builds)))
}

/// A running droplet replica: the free-draining engine (bitwise the engine of every
/// free-draining run), or Brownian dynamics with a hydrodynamic mobility.
enum Replica {
    Free(Box<DropletSim>),
    Hydro(Box<HydroDropletSim>),
}

impl Replica {
    /// Replica `replica` of `p` at step 0, with the engine its hydrodynamics ask for.
    fn build(p: &DropletParams, replica: u32) -> Result<Self> {
        Ok(match &p.hydrodynamics {
            Some(h) if p.has_hydrodynamics() => Self::hydro(p.build_hydro_replica(replica, h)?),
            _ => Self::Free(Box::new(p.build_replica(replica)?)),
        })
    }

    fn hydro(s: HydroDropletSim) -> Self {
        Self::Hydro(Box::new(s))
    }

    fn step(&self) -> u64 {
        match self {
            Self::Free(s) => s.step,
            Self::Hydro(s) => s.step,
        }
    }

    fn time(&self) -> f64 {
        match self {
            Self::Free(s) => s.time(),
            Self::Hydro(s) => s.time(),
        }
    }

    fn dt(&self) -> f64 {
        match self {
            Self::Free(s) => s.params().dt,
            Self::Hydro(s) => s.params().dt,
        }
    }

    fn sbox(&self) -> &SimBox {
        match self {
            Self::Free(s) => &s.sbox,
            Self::Hydro(s) => &s.sbox,
        }
    }

    /// The particles in the engine's order (for profiles, where the order does not matter).
    fn particles(&self) -> &Particles {
        match self {
            Self::Free(s) => s.particles(),
            Self::Hydro(s) => s.particles(),
        }
    }

    /// The particles in input order, positions wrapped into the box.
    fn snapshot(&self) -> Particles {
        match self {
            Self::Free(s) => s.snapshot(),
            Self::Hydro(s) => s.particles().clone(),
        }
    }

    fn neighbor_builds(&self) -> u64 {
        match self {
            Self::Free(s) => s.neighbor_builds(),
            Self::Hydro(s) => s.neighbor_builds(),
        }
    }

    /// Run `n` steps; the error says why the run cannot go on.
    fn run(&mut self, n: u64) -> Result<(), String> {
        match self {
            Self::Free(s) => s.run(n).map_err(|e| e.to_string()),
            Self::Hydro(s) => s.run(n).map_err(|e| e.to_string()),
        }
    }

    /// The systematic forces at the current positions, in input order.
    fn forces(&self) -> Vec<[f64; 3]> {
        match self {
            Self::Free(s) => s.forces(),
            Self::Hydro(s) => s.systematic_forces(),
        }
    }

    /// The checkpoint of this replica at its step into a new GSD file at `path`.
    fn write_checkpoint(&self, path: &Path) -> Result<()> {
        let mut w = GsdWriter::create_new(path)?;
        match self {
            Self::Free(s) => {
                w.write_checkpoint(s.step, &s.sbox, &s.snapshot(), &s.list_state(), &[])?
            }
            Self::Hydro(s) => w.write_frame(s.step, &s.sbox, s.particles(), true, &[])?,
        }
        w.sync()?;
        Ok(())
    }
}

/// A droplet run: replicas one after the other.
struct DropletSession {
    p: DropletParams,
    acc: Accum,
    /// The running replica (or the next one, when `sim` is `None`).
    rep: usize,
    /// The running replica and its neighbour-list builds before this session.
    sim: Option<(Replica, u64)>,
    /// Steps of a replica at which something is recorded (profiles, frames, the end).
    stops: Vec<u64>,
    /// Steps between a replica's regular checkpoints.
    ck_every: u64,
    gsd: Option<GsdWriter>,
    /// The trajectory's path, once the folder is known.
    traj: Option<std::path::PathBuf>,
    /// The output folder, once known (the cross-section is written when replica 0 ends).
    folder: Option<std::path::PathBuf>,
    /// GSD file the previous checkpoint named, removed once the next one is in place.
    stale: Vec<String>,
}

impl DropletSession {
    fn new(p: DropletParams, acc: Accum, rep: usize, sim: Option<(Replica, u64)>) -> Self {
        let mut stops: Vec<u64> = p.profile_steps.clone();
        if p.trajectory_every > 0 {
            stops.extend((0..=p.steps).step_by(p.trajectory_every as usize));
        }
        stops.push(p.steps);
        stops.sort_unstable();
        stops.dedup();
        let ck_every = (p.steps / 10).max(1);
        Self {
            p,
            acc,
            rep,
            sim,
            stops,
            ck_every,
            gsd: None,
            traj: None,
            folder: None,
            stale: Vec::new(),
        }
    }

    /// Open (or reopen) the trajectory when replica 0 runs.
    fn open_trajectory(&mut self) -> Result<()> {
        if self.rep == 0
            && self.p.trajectory_every > 0
            && let Some(traj) = &self.traj
        {
            // On a restart the file holds exactly the checkpoint's frames (trim_trajectory).
            self.gsd = Some(if traj.exists() {
                GsdWriter::append(traj)?
            } else {
                GsdWriter::create_new(traj)?
            });
        }
        Ok(())
    }

    /// Record what is due at step `ev` of the running replica: profiles, the excursion
    /// beyond the wall, trajectory frames.
    fn record(&mut self, ev: u64) -> Result<()> {
        let Some((s, _)) = &self.sim else {
            return Ok(());
        };
        let p = &self.p;
        let acc = &mut self.acc;
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
                let prof = radial_profile(&part.pos, &part.diameter, [0.0; 3], radius, p.bins);
                for (a, b) in acc.sums[j].iter_mut().zip(&prof.phi) {
                    *a += b;
                }
                acc.counts[j] += 1;
                acc.radii[j] = radius;
                acc.r_axes[j] = prof.r;
                if ev == p.steps {
                    acc.outside_final += prof.outside as u64;
                }
            }
        }
        if let Some(w) = self.gsd.as_mut()
            && ev.is_multiple_of(p.trajectory_every)
        {
            w.write_frame(
                ev,
                s.sbox(),
                &s.snapshot(),
                false,
                &[("droplet/radius", radius), ("droplet/time", t)],
            )?;
            acc.frames += 1;
        }
        Ok(())
    }
}

impl Session for DropletSession {
    fn label(&self) -> String {
        "droplet-bd".into()
    }

    fn total(&self) -> u64 {
        self.p.steps * self.p.replicas as u64
    }

    fn position(&self) -> u64 {
        self.rep as u64 * self.p.steps + self.sim.as_ref().map_or(0, |(s, _)| s.step())
    }

    fn seed(&self) -> u64 {
        self.p.seed as u64
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::to_value(&self.p).unwrap_or_default()
    }

    fn writes(&self, name: &str) -> bool {
        let profile = |prefix: &str| {
            name.strip_prefix(prefix)
                .and_then(|r| r.strip_suffix(".csv"))
                .is_some_and(|f| f.parse::<f64>().is_ok())
        };
        profile("profile_")
            || [
                "profiles.png",
                "profile_mean.csv",
                "cross_section.csv",
                "cross_section.png",
                "trajectory.gsd",
                "checkpoint-0.gsd",
                "checkpoint-1.gsd",
            ]
            .contains(&name)
    }

    fn begin(&mut self, out: &OutputDir, fresh: bool) -> Result<()> {
        self.traj = Some(out.join("trajectory.gsd"));
        self.folder = Some(out.path().to_path_buf());
        if self.sim.is_some() {
            self.open_trajectory()?;
            if fresh && self.stops.first() == Some(&0) {
                self.record(0)?;
            }
        }
        Ok(())
    }

    fn next_checkpoint(&self) -> Option<u64> {
        let steps = self.p.steps;
        let pos = self.position();
        let (rep, local) = (pos / steps, pos % steps);
        // Every 10 % of a replica, and between replicas.
        let k = local / self.ck_every + 1;
        if k <= 9 && k * self.ck_every < steps {
            Some(rep * steps + k * self.ck_every)
        } else if rep + 1 < self.p.replicas as u64 {
            Some((rep + 1) * steps)
        } else {
            None
        }
    }

    fn advance(&mut self, until: u64) -> Result<Option<String>> {
        let steps = self.p.steps;
        while self.position() < until {
            if self.sim.is_none() {
                self.sim = Some((Replica::build(&self.p, self.rep as u32)?, 0));
                self.open_trajectory()?;
                if self.stops.first() == Some(&0) {
                    self.record(0)?;
                }
            }
            let local_until = until.min((self.rep as u64 + 1) * steps) - self.rep as u64 * steps;
            loop {
                let step = self.sim.as_ref().map_or(0, |(s, _)| s.step());
                if step >= local_until {
                    break;
                }
                let k = self.stops.partition_point(|&e| e <= step);
                let stop = self.stops.get(k).copied().unwrap_or(steps);
                let target = stop.min(local_until);
                let (s, _) = self.sim.as_mut().expect("a running replica");
                if let Err(e) = s.run(target - step) {
                    return Ok(Some(format!("replica {}: {e}", self.rep)));
                }
                if target == stop {
                    self.record(stop)?;
                }
            }
            if local_until == steps {
                // The replica is complete.
                if let Some(mut w) = self.gsd.take() {
                    w.sync()?;
                }
                if self.rep == 0
                    && let (Some(width), Some(out), Some((s, _))) =
                        (self.p.cross_section, &self.folder, &self.sim)
                {
                    write_cross_section(out, &self.p, s, width)?;
                }
                let (s, builds0) = self.sim.take().expect("a running replica");
                self.acc.builds += builds0 + s.neighbor_builds();
                self.rep += 1;
            }
        }
        Ok(None)
    }

    fn flush(&mut self) -> Result<()> {
        if let Some(w) = self.gsd.as_mut() {
            w.sync()?;
        }
        Ok(())
    }

    /// The running replica to the GSD file the current checkpoint does not name, then (by the
    /// driver) `checkpoint.bin` naming it, then [`Session::after_save`] removes the older one:
    /// a run killed at any point leaves a consistent checkpoint.
    fn save(&mut self, out: &OutputDir) -> Result<Vec<u8>> {
        if self.p.trajectory_every > 0 {
            self.acc
                .digest
                .extend(&out.join("trajectory.gsd"), self.acc.frames)?;
        }
        self.acc.checkpoints += 1;
        let name = format!("checkpoint-{}.gsd", self.acc.checkpoints % 2);
        let old = format!("checkpoint-{}.gsd", (self.acc.checkpoints + 1) % 2);
        self.stale = vec![old];
        let state = match &self.sim {
            Some((s, builds)) => {
                let path = out.join(&name);
                let _ = std::fs::remove_file(&path);
                s.write_checkpoint(&path)?;
                let crc = file_crc(&path)?;
                Some((name, crc, Engine::of(s, builds + s.neighbor_builds())))
            }
            None => {
                self.stale.push(name);
                None
            }
        };
        let saved = Saved {
            replica: self.rep,
            step: self.sim.as_ref().map_or(0, |(s, _)| s.step()),
            state,
            acc: self.acc.clone(),
        };
        Ok(bincode::serialize(&saved)?)
    }

    fn after_save(&mut self, out: &OutputDir) {
        for f in self.stale.drain(..) {
            let _ = std::fs::remove_file(out.join(&f));
        }
    }

    fn finish(
        self: Box<Self>,
        out: &OutputDir,
        wall_s: f64,
        _failure: Option<&str>,
    ) -> Result<Finished> {
        let p = &self.p;
        let n_frac = p.fractions.len();
        let Accum {
            sums,
            counts,
            radii,
            r_axes,
            max_excursion,
            outside_final,
            builds,
            frames,
            ..
        } = self.acc;
        let mut warnings = Vec::new();
        let mut files = Vec::new();
        let mut means: Vec<Vec<f64>> = Vec::new();
        let mut drawn = Vec::new();
        for j in 0..n_frac {
            if counts[j] == 0 {
                continue;
            }
            let reps = counts[j] as f64;
            let phi: Vec<f64> = sums[j].iter().map(|v| v / reps).collect();
            let name = profile_name(p.fractions[j]);
            out.write_table(&name, &[("r", &r_axes[j]), ("phi", &phi)])?;
            files.push(name);
            means.push(phi);
            drawn.push(j);
        }
        let labels: Vec<String> = drawn
            .iter()
            .map(|&j| format!("t = {:.0} % (R = {:.2})", p.fractions[j] * 100.0, radii[j]))
            .collect();
        let xs: Vec<Vec<f64>> = drawn
            .iter()
            .map(|&j| r_axes[j].iter().map(|x| x / radii[j]).collect())
            .collect();
        let series: Vec<Series> = (0..drawn.len())
            .map(|k| Series {
                label: &labels[k],
                x: &xs[k],
                y: &means[k],
                points: false,
            })
            .collect();
        let title = match (p.is_static(), mobility_label(p)) {
            (false, None) => format!(
                "Drying droplet, free-draining BD: N = {}, Pe = {}, {} replica(s)",
                p.particles, p.peclet, p.replicas
            ),
            (false, Some(m)) => format!(
                "Drying droplet, {m}: N = {}, Pe = {}, {} replica(s)",
                p.particles, p.peclet, p.replicas
            ),
            (true, m) => format!(
                "Static droplet, {}: N = {}, phi = {:.3}, {} replica(s)",
                m.as_deref().unwrap_or("free-draining BD"),
                p.particles,
                p.phi0,
                p.replicas
            ),
        };
        if p.is_static() {
            // Every profile after the start samples the same equilibrium: their mean, with the
            // standard error from their scatter (profiles taken further apart than the
            // relaxation time are independent).
            let later: Vec<usize> = (0..drawn.len())
                .filter(|&k| p.profile_steps[drawn[k]] > 0)
                .collect();
            if later.len() >= 2 {
                let m = later.len() as f64;
                let bins = means[later[0]].len();
                let (mut mean, mut err) = (vec![0.0; bins], vec![0.0; bins]);
                for b in 0..bins {
                    let v: Vec<f64> = later.iter().map(|&k| means[k][b]).collect();
                    let mu = v.iter().sum::<f64>() / m;
                    let var = v.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (m - 1.0);
                    mean[b] = mu;
                    err[b] = (var / m).sqrt();
                }
                let r = &r_axes[drawn[later[0]]];
                out.write_table(
                    "profile_mean.csv",
                    &[("r", r), ("phi", &mean), ("err", &err)],
                )?;
                files.push("profile_mean.csv".into());
            }
        }
        if p.cross_section.is_some() && out.join("cross_section.csv").exists() {
            files.push("cross_section.csv".into());
            if out.join("cross_section.png").exists() {
                files.push("cross_section.png".into());
            }
        }
        picture(
            line_plot(
                &out.join("profiles.png"),
                &title,
                "r / R(t)",
                "volume fraction phi(r)",
                &series,
                Scale::Linear,
            ),
            "profiles.png",
            &mut files,
            &mut warnings,
        );
        if frames > 0 {
            files.push("trajectory.gsd".into());
        }
        let particle_steps = (p.steps * p.replicas as u64) as f64 * p.particles as f64;
        let summary = json!({
            "software": crate::software(),
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
            "warnings": warnings,
        });
        // The run is over: the replica checkpoints are no longer needed.
        for f in ["checkpoint-0.gsd", "checkpoint-1.gsd"] {
            let _ = std::fs::remove_file(out.join(f));
        }
        let message = format!(
            "{} replica(s) x {} steps of {} colloids in {wall_s:.1} s ({:.3e} particle-steps/s); outputs in {}",
            p.replicas,
            p.steps,
            p.particles,
            particle_steps / wall_s.max(1e-9),
            out.path().display()
        );
        Ok(Finished {
            summary,
            files,
            message,
            warnings,
        })
    }
}

/// What moves the particles, for titles: `None` for free draining.
fn mobility_label(p: &DropletParams) -> Option<String> {
    use colloidsim_md::hydro::HydroMethod;
    let h = p.hydrodynamics.as_ref().filter(|_| p.has_hydrodynamics())?;
    Some(match h.method {
        Some(HydroMethod::Pse) => format!("BD + RPY (PSE, box {} droplet diameters)", h.box_factor),
        _ => "BD + RPY (free space)".to_string(),
    })
}

/// The cross-section of a replica at its end: the particles whose centres lie within
/// `width / 2` of the plane z = 0 through the droplet's centre, as `cross_section.csv`
/// (columns `x,y,z,r`: centre and distance from the droplet's centre) and `cross_section.png`
/// (the circles where the slab's mid-plane cuts the spheres, inside the circle of R(t)).
fn write_cross_section(dir: &Path, p: &DropletParams, s: &Replica, width: f64) -> Result<()> {
    let out = OutputDir::reopen(dir)?;
    let radius = p.radius_at(s.time());
    let a = 0.5 * p.diameter;
    let snap = s.snapshot();
    let mut cols: [Vec<f64>; 4] = Default::default();
    let mut discs = Vec::new();
    for x in &snap.pos {
        if x[2].abs() < 0.5 * width {
            let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
            for (c, v) in cols.iter_mut().zip([x[0], x[1], x[2], r]) {
                c.push(v);
            }
            // The section of the sphere by z = 0 (a sphere cut off-centre by the slab still
            // shows as a small disc).
            let rc = (a * a - x[2] * x[2]).max(0.04 * a * a).sqrt();
            discs.push(Disc {
                x: x[0],
                y: x[1],
                r: rc,
                colour: usize::from(r > radius - p.diameter),
            });
        }
    }
    out.write_table(
        "cross_section.csv",
        &[
            ("x", &cols[0]),
            ("y", &cols[1]),
            ("z", &cols[2]),
            ("r", &cols[3]),
        ],
    )?;
    let title = format!(
        "{}: slab |z| < {} at t = {:.1} (R = {:.2}), replica 0",
        mobility_label(p).unwrap_or_else(|| "free-draining BD".into()),
        0.5 * width,
        s.time(),
        radius
    );
    // A picture that cannot be drawn leaves the table; the run goes on.
    let _ = cross_section(&out.join("cross_section.png"), &title, &discs, radius);
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
        let file = gsd::open_checked(path, Mode::Read)?;
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

/// Replica 0 of a droplet scenario, stepped by hand.
struct BdEngine {
    sim: Replica,
}

/// Flatten `[x, y, z]` rows.
pub(crate) fn flat(v: &[[f64; 3]]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}

impl crate::Engine for BdEngine {
    fn method(&self) -> &str {
        "droplet-bd"
    }
    fn dimensions(&self) -> usize {
        3
    }
    fn particles(&self) -> usize {
        self.sim.particles().len()
    }
    fn step(&mut self, steps: u64) -> Result<()> {
        self.sim.run(steps).map_err(anyhow::Error::msg)
    }
    fn steps(&self) -> u64 {
        self.sim.step()
    }
    fn time(&self) -> f64 {
        self.sim.time()
    }
    fn dt(&self) -> f64 {
        self.sim.dt()
    }
    fn positions(&self) -> Vec<f64> {
        flat(&self.sim.snapshot().pos)
    }
    fn velocities(&self) -> Option<Vec<f64>> {
        None
    }
    fn forces(&self) -> Result<Vec<f64>> {
        Ok(flat(&self.sim.forces()))
    }
    fn box_lengths(&self) -> Vec<f64> {
        self.sim.sbox().l.to_vec()
    }
}
