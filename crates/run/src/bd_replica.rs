//! The running system of the Brownian-dynamics methods (`droplet-bd`, `bd`): WCA spheres in an
//! external field `E` (the droplet's interface, a constant body force), moved by the
//! free-draining engine or by Brownian dynamics with a hydrodynamic mobility; its GSD checkpoint
//! beside `checkpoint.bin`, the verified read of that checkpoint, and the engine Python steps.

use crate::checkpoint::file_crc;
use crate::engine::{StateChange, check_array, flat, rows};
use crate::keys::shared::{HYDRO_MAX_ITERATIONS, RUN_DT};
use crate::keys::{Spec, rekey_text};
use crate::method::{Finished, Session};
use crate::output::trajectory::FrameDigest;
use anyhow::{Result, bail};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::OutputDir;
use colloidsim_md::hydro::AnyMobility;
use colloidsim_md::{Brownian, HydroBrownian};
use colloidsim_particles::gsd::{self, GsdFrame, GsdWriter};
use colloidsim_particles::{External, Interaction, Particles, SimBox};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The Brownian engines' names of the parameters their run-time errors advise changing, and
/// the keys (shared by `bd` and `droplet-bd`) that set them.
const ENGINE_NAMES: &[(&str, &Spec)] =
    &[("dt", &RUN_DT), ("max_iterations", &HYDRO_MAX_ITERATIONS)];

/// A running replica: the free-draining engine (bitwise the engine of every free-draining run),
/// or Brownian dynamics with a hydrodynamic mobility.
pub(crate) enum Replica<E: External> {
    /// Free draining ([`Brownian`]: cell-ordered lists, Euler or Leimkuhler–Matthews).
    Free(Box<Brownian<Interaction, E>>),
    /// `dx = M F dt + sqrt(2 kT dt) M^(1/2) xi` ([`HydroBrownian`]).
    Hydro(Box<HydroBrownian<Interaction, E, AnyMobility>>),
}

impl<E: External> Replica<E> {
    pub(crate) fn step(&self) -> u64 {
        match self {
            Self::Free(s) => s.step,
            Self::Hydro(s) => s.step,
        }
    }

    pub(crate) fn time(&self) -> f64 {
        match self {
            Self::Free(s) => s.time(),
            Self::Hydro(s) => s.time(),
        }
    }

    pub(crate) fn dt(&self) -> f64 {
        match self {
            Self::Free(s) => s.params().dt,
            Self::Hydro(s) => s.params().dt,
        }
    }

    pub(crate) fn sbox(&self) -> &SimBox {
        match self {
            Self::Free(s) => &s.sbox,
            Self::Hydro(s) => &s.sbox,
        }
    }

    /// The particles in the engine's order (this rank's slots when decomposed).
    pub(crate) fn particles(&self) -> &Particles {
        match self {
            Self::Free(s) => s.particles(),
            Self::Hydro(s) => s.particles(),
        }
    }

    /// This replica decomposed in space over the ranks of `comm` (free draining only).
    pub(crate) fn decomposed(self, comm: Box<dyn Exchange>) -> Result<Self> {
        match self {
            Self::Free(s) => Ok(Self::Free(Box::new(s.decomposed(comm)?))),
            Self::Hydro(_) => bail!(
                "Brownian dynamics with hydrodynamics runs on one rank: only free-draining \
                 Brownian dynamics is decomposed over MPI ranks (docs/parallel.md); spread \
                 replicas over ranks with `colloidsim ensemble`"
            ),
        }
    }

    /// The ranks of a decomposed replica.
    fn exchange(&self) -> Option<&dyn Exchange> {
        match self {
            Self::Free(s) => s.exchange(),
            Self::Hydro(_) => None,
        }
    }

    /// The replica is done with: the ranks it ran on, for the next one.
    fn into_exchange(self) -> Option<Box<dyn Exchange>> {
        match self {
            Self::Free(s) => s.into_exchange(),
            Self::Hydro(_) => None,
        }
    }

    /// The particles in input order, positions wrapped into the box (collective when
    /// decomposed).
    pub(crate) fn snapshot(&self) -> Particles {
        match self {
            Self::Free(s) => s.snapshot(),
            Self::Hydro(s) => s.particles().clone(),
        }
    }

    /// The unwrapped positions `x + image L` in input order, into `out` (no allocation once
    /// `out` has its length on one process; collective when decomposed).
    pub(crate) fn unwrapped_into(&self, out: &mut Vec<[f64; 3]>) {
        match self {
            Self::Free(s) => s.unwrapped_into(out),
            Self::Hydro(s) => {
                let (p, sbox) = (s.particles(), &s.sbox);
                out.resize(p.len(), [0.0; 3]);
                for ((x, img), u) in p.pos.iter().zip(&p.image).zip(out.iter_mut()) {
                    *u = sbox.unwrap(*x, *img);
                }
            }
        }
    }

    pub(crate) fn neighbor_builds(&self) -> u64 {
        match self {
            Self::Free(s) => s.neighbor_builds(),
            Self::Hydro(s) => s.neighbor_builds(),
        }
    }

    /// Run `n` steps; the error says why the run cannot go on (and names the step), and the
    /// keys (`run.dt`, `hydrodynamics.max_iterations`) where the engine names its parameters.
    pub(crate) fn run(&mut self, n: u64) -> Result<(), String> {
        let rekeyed = |e: &dyn std::fmt::Display| rekey_text(&e.to_string(), ENGINE_NAMES);
        match self {
            Self::Free(s) => s.run(n).map_err(|e| rekeyed(&e)),
            Self::Hydro(s) => s.run(n).map_err(|e| rekeyed(&e)),
        }
    }

    /// Add `forces` (input order; empty: none) to the systematic forces of every step.
    pub(crate) fn set_extra_forces(&mut self, forces: &[[f64; 3]]) -> Result<()> {
        match self {
            Self::Free(s) => s.set_extra_forces(forces)?,
            Self::Hydro(s) => s.set_extra_forces(forces)?,
        }
        Ok(())
    }

    /// The systematic forces at the current positions, in input order.
    pub(crate) fn forces(&self) -> Vec<[f64; 3]> {
        match self {
            Self::Free(s) => s.forces(),
            Self::Hydro(s) => s.systematic_forces(),
        }
    }

    /// The checkpoint of this replica at its step into a new GSD file at `path`: exact
    /// positions and images, and for the free-draining engine its list state
    /// (`GsdWriter::write_checkpoint`); the hydrodynamic engine's whole state is its exact
    /// positions and images (its noise is keyed by (seed, step, replica, particle) and its
    /// pair forces do not depend on when the list was built). Decomposed: every rank gathers
    /// the state, the writer alone writes (`path` is `None` on the others).
    pub(crate) fn write_checkpoint(&self, path: Option<&Path>) -> Result<()> {
        match self {
            Self::Free(s) => {
                let (snap, list) = (s.snapshot(), s.list_state());
                if let Some(path) = path {
                    let mut w = GsdWriter::create_new(path)?;
                    w.write_checkpoint(s.step, &s.sbox, &snap, &list, &[])?;
                    w.sync()?;
                }
            }
            Self::Hydro(s) => {
                if let Some(path) = path {
                    let mut w = GsdWriter::create_new(path)?;
                    w.write_frame(s.step, &s.sbox, s.particles(), true, &[])?;
                    w.sync()?;
                }
            }
        }
        Ok(())
    }
}

/// What the checkpoint keeps of the running replica beyond its GSD file. Its engine parameters
/// are not here: a restart takes every parameter from the scenario saved with the run (the
/// driver refuses one that resolves to other parameters), as a fresh start does.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub(crate) struct EngineState {
    /// Neighbour-list builds of this replica so far.
    pub(crate) builds: u64,
}

/// A replica's GSD checkpoint as `checkpoint.bin` names it: file name, its CRC-32 and the
/// replica's list builds.
pub(crate) type ReplicaState = (String, u32, EngineState);

/// Checkpoint `sim` (the running replica and its list builds before this session), if any,
/// into the GSD file (`checkpoint-0.gsd` / `checkpoint-1.gsd`, alternating with
/// `checkpoints`, the count including this one) that the current `checkpoint.bin` does not
/// name. Returns its state and the files to remove once `checkpoint.bin` names it, so that a
/// run killed at any moment leaves a consistent checkpoint. Decomposed: every rank takes part,
/// the writer writes (the others' CRC is 0; their state is not written).
fn save_replica<E: External>(
    out: &OutputDir,
    checkpoints: u64,
    sim: Option<(&Replica<E>, u64)>,
    writer: bool,
) -> Result<(Option<ReplicaState>, Vec<String>)> {
    let name = format!("checkpoint-{}.gsd", checkpoints % 2);
    let old = format!("checkpoint-{}.gsd", (checkpoints + 1) % 2);
    let mut stale = vec![old];
    let state = match sim {
        Some((s, builds)) => {
            let path = out.join(&name);
            let crc = if writer {
                let _ = std::fs::remove_file(&path);
                s.write_checkpoint(Some(&path))?;
                file_crc(&path)?
            } else {
                s.write_checkpoint(None)?;
                0
            };
            Some((
                name,
                crc,
                EngineState {
                    builds: builds + s.neighbor_builds(),
                },
            ))
        }
        None => {
            stale.push(name);
            None
        }
    };
    Ok((state, stale))
}

/// The GSD files of [`save_replica`] (a completed run removes them).
pub(crate) const CHECKPOINT_FILES: [&str; 2] = ["checkpoint-0.gsd", "checkpoint-1.gsd"];

/// Read the GSD checkpoint `state` names for replica `replica` at `step`, verified against its
/// CRC-32, its step, its exactness and its engine (`hydro`: positions and images only; free
/// draining: with the list state); each particle gets its species' diameter from `diameters`
/// (GSD stores them in single precision).
pub(crate) fn read_replica_checkpoint(
    out: &OutputDir,
    state: &ReplicaState,
    step: u64,
    replica: usize,
    hydro: bool,
    diameters: &[f64],
) -> Result<GsdFrame> {
    let (name, crc, _) = state;
    let path = out.join(name);
    let found = file_crc(&path)?;
    if found != *crc {
        bail!(
            "{}: damaged: checksum {found:08x}, the checkpoint recorded {crc:08x}",
            path.display()
        );
    }
    let mut f = gsd::read_frame(&path, None)?;
    if f.step != step || !f.exact || f.list.is_none() != hydro {
        bail!(
            "{}: not the checkpoint of replica {replica} at step {step} that checkpoint.bin names",
            path.display(),
        );
    }
    let p = &mut f.particles;
    for (d, &t) in p.diameter.iter_mut().zip(&p.typeid) {
        match diameters.get(t as usize) {
            Some(&x) => *d = x,
            None => bail!(
                "{}: particle typeid {t} is not a species of the scenario",
                path.display()
            ),
        }
    }
    Ok(f)
}

/// What a method observes of its replicas ([`Replicas::advance`] calls it).
pub(crate) trait Observe<E: External> {
    /// Replica `replica` at step 0.
    fn build(&self, replica: u32) -> Result<Replica<E>>;
    /// The first step after `s` of the running replica at which something is due (at most
    /// the replica's last step).
    fn next_event(&self, run: &Replicas<E>, s: u64) -> u64;
    /// Record what is due at step `s` of the running replica (`run.sim`), at step 0 of each
    /// replica and at each event.
    fn record(&mut self, run: &mut Replicas<E>, s: u64) -> Result<()>;
    /// The running replica has reached its last step (its trajectory is synced); `builds`:
    /// its neighbour-list builds.
    fn replica_done(&mut self, run: &Replicas<E>, builds: u64) -> Result<()>;
}

/// The replicas of a Brownian-dynamics run, one after the other: where the run stands (the
/// driver's position counts steps over the replicas), the running replica, replica 0's
/// trajectory writer and the GSD checkpoint files. Decomposed over MPI ranks
/// (docs/parallel.md), each replica runs on all ranks, every rank takes part in what is
/// gathered (frames, checkpoints) and rank 0 writes.
pub(crate) struct Replicas<E: External> {
    /// Steps per replica.
    pub(crate) steps: u64,
    pub(crate) replicas: usize,
    /// Steps between trajectory frames of replica 0 (0: none).
    trajectory_every: u64,
    /// The running replica (or the next one, when `sim` is `None`).
    pub(crate) rep: usize,
    /// The running replica and its neighbour-list builds before this session.
    pub(crate) sim: Option<(Replica<E>, u64)>,
    /// Steps between a replica's regular checkpoints.
    ck_every: u64,
    /// Replica 0's trajectory, while it runs.
    pub(crate) gsd: Option<GsdWriter>,
    /// The trajectory's path, once the folder is known.
    traj: Option<PathBuf>,
    /// GSD file the previous checkpoint named, removed once the next one is in place.
    stale: Vec<String>,
    /// The ranks of a decomposed run while no replica holds them (between replicas).
    parked: Option<Box<dyn Exchange>>,
    /// This process's rank and the number of ranks (0 and 1 on one process).
    rank: (usize, usize),
}

impl<E: External> Replicas<E> {
    /// `replicas` replicas of `steps` steps each, standing at replica `rep` (running `sim`, or
    /// not yet built), each decomposed over the ranks of `comm` when given.
    pub(crate) fn new(
        steps: u64,
        replicas: usize,
        trajectory_every: u64,
        rep: usize,
        sim: Option<(Replica<E>, u64)>,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Self> {
        let rank = comm.as_ref().map_or((0, 1), |c| (c.rank(), c.size()));
        let (sim, parked) = match (sim, comm) {
            (Some((s, b)), Some(c)) => (Some((s.decomposed(c)?, b)), None),
            (sim, comm) => (sim, comm),
        };
        Ok(Self {
            steps,
            replicas,
            trajectory_every,
            rep,
            sim,
            ck_every: (steps / 10).max(1),
            gsd: None,
            traj: None,
            stale: Vec::new(),
            parked,
            rank,
        })
    }

    /// Does this process write the outputs (rank 0; always on one process)?
    pub(crate) fn is_writer(&self) -> bool {
        self.rank.0 == 0
    }

    /// The number of ranks the run is decomposed over (1 on one process).
    pub(crate) fn ranks(&self) -> usize {
        self.rank.1
    }

    /// The ranks of a decomposed run (`None` on one process).
    pub(crate) fn exchange(&self) -> Option<&dyn Exchange> {
        match &self.sim {
            Some((s, _)) => s.exchange(),
            None => self.parked.as_deref(),
        }
    }

    /// An error on this rank alone: see [`Session::fail_alone`].
    pub(crate) fn fail_alone(&self, e: anyhow::Error) -> anyhow::Error {
        crate::method::fail_alone_over(self.exchange(), e)
    }

    /// Is a trajectory frame due at step `s` of the running replica (replica 0, every
    /// `trajectory_every` steps, once the folder is known)?
    pub(crate) fn frame_due(&self, s: u64) -> bool {
        self.rep == 0
            && self.trajectory_every > 0
            && self.traj.is_some()
            && s.is_multiple_of(self.trajectory_every)
    }

    /// A trajectory frame of the running replica at step `s` with `logs`, when one is due
    /// ([`Self::frame_due`]); `snap` is its snapshot when the caller has taken one. Every rank
    /// of a decomposed run gathers the frame; the writer writes it. Returns whether a frame
    /// was due.
    pub(crate) fn write_frame(
        &mut self,
        s: u64,
        snap: Option<&Particles>,
        logs: &[(&str, f64)],
    ) -> Result<bool> {
        if !self.frame_due(s) {
            return Ok(false);
        }
        let Some((sim, _)) = &self.sim else {
            return Ok(false);
        };
        let taken;
        let snap = match snap {
            Some(p) => p,
            None => {
                taken = sim.snapshot();
                &taken
            }
        };
        let written = match self.gsd.as_mut() {
            Some(w) => w.write_frame(s, sim.sbox(), snap, false, logs),
            None => Ok(()),
        };
        written.map_err(|e| self.fail_alone(e.into()))?;
        Ok(true)
    }

    /// Steps of the whole run.
    pub(crate) fn total(&self) -> u64 {
        self.steps * self.replicas as u64
    }

    /// Steps done over the replicas.
    pub(crate) fn position(&self) -> u64 {
        self.rep as u64 * self.steps + self.step()
    }

    /// Step of the running replica (0 before it is built).
    pub(crate) fn step(&self) -> u64 {
        self.sim.as_ref().map_or(0, |(s, _)| s.step())
    }

    /// Every 10 % of a replica, and between replicas.
    pub(crate) fn next_checkpoint(&self) -> Option<u64> {
        let steps = self.steps;
        let pos = self.position();
        let (rep, local) = (pos / steps, pos % steps);
        let k = local / self.ck_every + 1;
        if k <= 9 && k * self.ck_every < steps {
            Some(rep * steps + k * self.ck_every)
        } else if rep + 1 < self.replicas as u64 {
            Some((rep + 1) * steps)
        } else {
            None
        }
    }

    /// Open (or reopen) the trajectory when replica 0 runs (the writer).
    fn open_trajectory(&mut self) -> Result<()> {
        if self.rep == 0
            && self.is_writer()
            && self.trajectory_every > 0
            && let Some(traj) = &self.traj
        {
            // On a restart the file holds exactly the checkpoint's frames (FrameDigest::restore).
            self.gsd = Some(crate::output::trajectory::writer(traj, true)?);
        }
        Ok(())
    }

    /// The output folder is ready: open the trajectory; on a fresh run record step 0.
    pub(crate) fn begin(
        &mut self,
        obs: &mut impl Observe<E>,
        out: &OutputDir,
        fresh: bool,
    ) -> Result<()> {
        self.traj = Some(out.join("trajectory.gsd"));
        if self.sim.is_some() {
            self.open_trajectory()?;
            if fresh {
                obs.record(self, 0)?;
            }
        }
        Ok(())
    }

    /// Run up to position `until`, building each replica when it starts and recording every
    /// event on the way; `Ok(Some(why))` when the engine cannot go on (the message names the
    /// replica and the step).
    pub(crate) fn advance(
        &mut self,
        obs: &mut impl Observe<E>,
        until: u64,
    ) -> Result<Option<String>> {
        let steps = self.steps;
        while self.position() < until {
            if self.sim.is_none() {
                let mut sim = obs.build(self.rep as u32)?;
                if let Some(c) = self.parked.take() {
                    sim = sim.decomposed(c)?;
                }
                self.sim = Some((sim, 0));
                // The writer's files: an error there ends the job on every rank.
                let opened = self.open_trajectory();
                opened.map_err(|e| self.fail_alone(e))?;
                obs.record(self, 0)?;
            }
            let local_until = until.min((self.rep as u64 + 1) * steps) - self.rep as u64 * steps;
            loop {
                let step = self.step();
                if step >= local_until {
                    break;
                }
                let event = obs.next_event(self, step);
                let target = event.min(local_until);
                let (s, _) = self.sim.as_mut().expect("a running replica");
                if let Err(e) = s.run(target - step) {
                    return Ok(Some(format!("replica {}: {e}", self.rep)));
                }
                if target == event {
                    obs.record(self, event)?;
                }
            }
            if local_until == steps {
                // The replica is complete.
                if let Some(mut w) = self.gsd.take() {
                    let synced = w.sync();
                    synced.map_err(|e| self.fail_alone(e.into()))?;
                }
                let builds = self
                    .sim
                    .as_ref()
                    .map_or(0, |(s, b)| b + s.neighbor_builds());
                obs.replica_done(self, builds)?;
                if let Some((s, _)) = self.sim.take() {
                    self.parked = s.into_exchange();
                }
                self.rep += 1;
            }
        }
        Ok(None)
    }

    /// Bring the trajectory to the disk (the writer; an error ends the job on every rank).
    pub(crate) fn flush(&mut self) -> Result<()> {
        let synced = match self.gsd.as_mut() {
            Some(w) => w.sync(),
            None => Ok(()),
        };
        synced.map_err(|e| self.fail_alone(e.into()))
    }

    /// Checkpoint the running replica ([`save_replica`], `checkpoints` counting this one);
    /// its state and step for `checkpoint.bin`.
    pub(crate) fn save(
        &mut self,
        out: &OutputDir,
        checkpoints: u64,
    ) -> Result<(Option<ReplicaState>, u64)> {
        let writer = self.is_writer();
        let (state, stale) = save_replica(
            out,
            checkpoints,
            self.sim.as_ref().map(|(s, b)| (s, *b)),
            writer,
        )?;
        self.stale = stale;
        Ok((state, self.step()))
    }

    /// `checkpoint.bin` names the new state: remove the previous GSD checkpoint (the writer).
    pub(crate) fn after_save(&mut self, out: &OutputDir) {
        let writer = self.is_writer();
        for f in self.stale.drain(..) {
            if writer {
                let _ = std::fs::remove_file(out.join(&f));
            }
        }
    }
}

/// The method's part of `checkpoint.bin` for a run of replicas: where it stands and what it
/// has accumulated (`A`). The running replica's particles are in the GSD file `state` names,
/// whose CRC-32 it keeps.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct Saved<A> {
    /// Replica to continue.
    pub(crate) replica: usize,
    /// Its step: every event up to and including this step is in `acc`.
    pub(crate) step: u64,
    /// GSD checkpoint of the replica at `step`, its CRC-32 and its engine parameters; `None`:
    /// the replica has not started (step 0, built afresh).
    pub(crate) state: Option<ReplicaState>,
    pub(crate) acc: A,
}

/// A method of replicas: its observers ([`Observe`]), what it accumulates, and what it says
/// and writes; [`BdSession`] does the rest.
pub(crate) trait BdMethod<E: External>: Observe<E> + Send + Sized {
    /// What a checkpoint keeps of the observations.
    type Acc: Serialize + Clone;
    /// The accumulators.
    fn acc(&self) -> &Self::Acc;
    /// Trajectory frames written, their digest and the checkpoints written, in the
    /// accumulators.
    fn bookkeeping(&mut self) -> (u64, &mut FrameDigest, &mut u64);
    /// The method's name (the progress bar's label and `summary.json`'s method).
    fn name(&self) -> &'static str;
    /// The run's seed.
    fn seed(&self) -> u64;
    /// The resolved parameters.
    fn parameters(&self) -> serde_json::Value;
    /// Does the method write `name` (besides trajectory.gsd and the GSD checkpoints)?
    fn writes(&self, name: &str) -> bool;
    /// The output folder is known.
    fn output_folder(&mut self, _out: &OutputDir) {}
    /// Write every output; `failure` says why the run stopped early.
    fn finish(self, out: &OutputDir, wall_seconds: f64, failure: Option<&str>) -> Result<Finished>;
}

/// A run of replicas of a Brownian-dynamics method `O`.
pub(crate) struct BdSession<E: External, O> {
    run: Replicas<E>,
    obs: O,
}

impl<E: External, O: BdMethod<E>> BdSession<E, O> {
    pub(crate) fn new(run: Replicas<E>, obs: O) -> Self {
        Self { run, obs }
    }

    /// [`Session::save`] of this rank.
    fn save_state(&mut self, out: &OutputDir) -> Result<Vec<u8>> {
        let writer = self.run.is_writer();
        let (frames, digest, checkpoints) = self.obs.bookkeeping();
        if self.run.trajectory_every > 0 && writer {
            digest.extend(&out.join("trajectory.gsd"), frames)?;
        }
        *checkpoints += 1;
        let count = *checkpoints;
        let (state, step) = self.run.save(out, count)?;
        let saved = Saved {
            replica: self.run.rep,
            step,
            state,
            acc: self.obs.acc(),
        };
        Ok(bincode::serialize(&saved)?)
    }
}

impl<E: External + 'static, O: BdMethod<E>> Session for BdSession<E, O>
where
    Replicas<E>: Send,
{
    fn label(&self) -> String {
        self.obs.name().into()
    }

    fn total(&self) -> u64 {
        self.run.total()
    }

    fn position(&self) -> u64 {
        self.run.position()
    }

    fn seed(&self) -> u64 {
        self.obs.seed()
    }

    fn status(&self) -> String {
        let r = &self.run;
        let mut s = match &r.sim {
            Some((sim, _)) => format!("t = {}", crate::driver::significant(sim.time())),
            None => String::new(),
        };
        if r.replicas > 1 {
            if !s.is_empty() {
                s.push_str(", ");
            }
            s.push_str(&format!("replica {}/{}", r.rep + 1, r.replicas));
        }
        s
    }

    fn parameters(&self) -> serde_json::Value {
        self.obs.parameters()
    }

    fn writes(&self, name: &str) -> bool {
        self.obs.writes(name) || name == "trajectory.gsd" || CHECKPOINT_FILES.contains(&name)
    }

    fn begin(&mut self, out: &OutputDir, fresh: bool) -> Result<()> {
        self.obs.output_folder(out);
        self.run.begin(&mut self.obs, out, fresh)
    }

    fn next_checkpoint(&self) -> Option<u64> {
        self.run.next_checkpoint()
    }

    fn advance(&mut self, until: u64) -> Result<Option<String>> {
        self.run.advance(&mut self.obs, until)
    }

    fn flush(&mut self) -> Result<()> {
        self.run.flush()
    }

    /// The running replica to the GSD file the current checkpoint does not name, then (by the
    /// driver) `checkpoint.bin` naming it, then [`Session::after_save`] removes the older one:
    /// a run killed at any point leaves a consistent checkpoint.
    fn save(&mut self, out: &OutputDir) -> Result<Vec<u8>> {
        // Only the writer touches the folder; its errors end the job on every rank.
        self.save_state(out).map_err(|e| self.run.fail_alone(e))
    }

    fn after_save(&mut self, out: &OutputDir) {
        self.run.after_save(out);
    }

    fn exchange(&self) -> Option<&dyn Exchange> {
        self.run.exchange()
    }

    fn finish(
        self: Box<Self>,
        out: &OutputDir,
        wall_seconds: f64,
        failure: Option<&str>,
    ) -> Result<Finished> {
        if !self.run.is_writer() {
            return Ok(Finished {
                summary: serde_json::json!({}),
                files: Vec::new(),
                message: String::new(),
                warnings: Vec::new(),
            });
        }
        let ranks = self.run.ranks();
        let Self { obs, .. } = *self;
        let mut fin = obs.finish(out, wall_seconds, failure)?;
        if let Some(m) = fin.summary.as_object_mut() {
            m.insert("ranks".into(), serde_json::json!(ranks));
        }
        // The run is over: the replica checkpoints are no longer needed.
        for f in CHECKPOINT_FILES {
            let _ = std::fs::remove_file(out.join(f));
        }
        Ok(fin)
    }
}

/// Replica 0 of a scenario built afresh from its particles (input order, exact positions and
/// image counts) at a step with a seed, as a checkpoint restores it.
pub(crate) type Rebuild<E> = Box<dyn Fn(Particles, u64, u32) -> Result<Replica<E>> + Send>;

/// Replica 0 of a Brownian-dynamics scenario, stepped by hand (Python's `BrownianDynamics`).
pub(crate) struct ReplicaEngine<E: External> {
    /// The scenario's method.
    pub(crate) method: &'static str,
    pub(crate) sim: Replica<E>,
    /// The seed of its random streams.
    pub(crate) seed: u32,
    /// How its state is set ([`crate::Engine::set_state`]).
    pub(crate) rebuild: Rebuild<E>,
    /// The script's forces ([`crate::Engine::set_extra_forces`]), kept across a rebuild.
    pub(crate) extra: Vec<[f64; 3]>,
}

impl<E: External> ReplicaEngine<E> {
    /// Replica 0 at step 0 with seed `seed`, its state set by `rebuild`.
    pub(crate) fn new(
        method: &'static str,
        sim: Replica<E>,
        seed: u32,
        rebuild: impl Fn(Particles, u64, u32) -> Result<Replica<E>> + Send + 'static,
    ) -> Self {
        Self {
            method,
            sim,
            seed,
            rebuild: Box::new(rebuild),
            extra: Vec::new(),
        }
    }
}

impl<E: External> crate::Engine for ReplicaEngine<E> {
    fn method(&self) -> &str {
        self.method
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
    fn seed(&self) -> u32 {
        self.seed
    }
    fn types(&self) -> Option<crate::engine::ParticleTypes> {
        Some(crate::engine::ParticleTypes::of(&self.sim.snapshot()))
    }
    fn set_state(&mut self, change: StateChange) -> Result<()> {
        change.check(self.particles(), 3, false, self.method)?;
        let mut p = self.sim.snapshot();
        if let Some(x) = &change.positions {
            for ((q, img), x) in p.pos.iter_mut().zip(&mut p.image).zip(rows(x)) {
                *q = x;
                *img = [0; 3];
            }
        }
        let (step, seed) = (
            change.step.unwrap_or(self.sim.step()),
            change.seed.unwrap_or(self.seed),
        );
        let mut sim = (self.rebuild)(p, step, seed)?;
        sim.set_extra_forces(&self.extra)?;
        (self.sim, self.seed) = (sim, seed);
        Ok(())
    }
    fn set_extra_forces(&mut self, forces: &[f64]) -> Result<()> {
        let n = self.particles();
        if !forces.is_empty() {
            check_array("forces", forces, n, 3)?;
        }
        self.extra.clear();
        self.extra
            .extend(forces.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        self.sim.set_extra_forces(&self.extra)?;
        Ok(())
    }
}
