//! Bulk Brownian dynamics in a periodic cube (`method = "bd"`): WCA spheres, free draining or
//! with the RPY mobility of the periodic box (PSE), an optional constant body force; the
//! mean-square displacement (`msd.csv`), the mean velocity and the sedimentation coefficient,
//! the long-time self-diffusion coefficient, each with its error from block averages and
//! beside Hasimoto's periodic self-mobility and the dilute sedimentation law (docs/bd.md).
//!
//! **Blocks.** The sampled time of each replica is cut into `observe.blocks` equal blocks; the
//! blocks of all replicas are pooled, and every error is the standard error of the mean of the
//! block values (`sd / sqrt(blocks)`), which counts the blocks as independent. A block gives
//! - the velocity of the centre of mass, `U_b = [X(end) - X(start)] / block time` (unwrapped
//!   positions), and
//! - the MSD at each lag from the time origins inside the block whose lag ends inside it
//!   (positions relative to the centre of mass when a body force acts), and from it
//!   `D_b = [MSD(T) - MSD(T/4)] / (6 (3T/4))`, T = `observe.msd.max_lag`.
//!
//! **When a figure is reported.** Each figure needs at least [`MIN_BLOCKS`] blocks. The mean
//! velocity of interacting spheres with RPY depends on the configuration through the
//! long-wavelength density fluctuations of the box, which relax in `L^2 / (4 pi^2 D0)` (the
//! slowest mode, k = 2 pi / L): a block must last at least that for the blocks to count as
//! independent. The long-time self-diffusion coefficient of interacting spheres needs
//! `T / 4 >= a^2 / D0` (a sphere has diffused its radius: past the short-time regime, whose
//! remainder decays like `(a^2 / D0 t)^(3/2)` in a dilute suspension). Otherwise the figure
//! and its error are `null` in `summary.json`, with the reason.

use crate::Scenario as Source;
use crate::bd_replica::{
    BdMethod, BdSession, Observe, Replica as AnyReplica, ReplicaEngine, ReplicaState, Replicas,
    Saved, read_replica_checkpoint,
};
use crate::checkpoint::Envelope;
use crate::keys::Spec;
use crate::keys::shared::RUN_TUNE_SKIN;
use crate::method::{Checked, Finished, Headline, Method, Session, fail_alone_over};
use crate::output::plot::{Scale, Series, line_plot_with_errors, picture};
use crate::output::trajectory::FrameDigest;
use anyhow::{Context, Result, bail};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::msd::Msd;
use colloidsim_core::output::OutputDir;
use colloidsim_mc::observe::mean_and_error;
use colloidsim_md::Brownian;
use colloidsim_md::brownian::bulk::{BodyForce, BulkError, BulkParams};
use colloidsim_md::brownian::lj_eos::{jzg_pressure, lj_tail_pressure};
use colloidsim_md::tune::SkinTuning;
use colloidsim_particles::Interaction;
use colloidsim_particles::PairSpec;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use std::f64::consts::PI;

/// Fewest blocks (over all replicas) from whose scatter an error is given.
pub const MIN_BLOCKS: usize = 8;

/// Virial-pressure samples per block (every `block_steps / 32` steps, at least every step).
pub const PRESSURE_SAMPLES: u64 = 32;

/// The bulk family of scenarios.
pub struct BulkBd;

#[rustfmt::skip] // declarations laid out as a table, one key to a line or three
pub mod keys;
pub mod params;

type Replica = AnyReplica<BodyForce>;

/// Read and check a scenario (`system.initial` relative to the scenario's folder), with `seed`
/// replacing the scenario's.
fn resolve(src: &Source, seed: Option<u64>) -> Result<BulkParams> {
    let table = src.table()?;
    if table
        .get("hydrodynamics")
        .and_then(|h| h.get("box_factor"))
        .is_some()
    {
        bail!(
            "{}: hydrodynamics.box_factor: applies to droplet-bd only (the PSE box of a droplet, \
             in droplet diameters); the periodic box of a bulk run is system.box_length",
            src.label()
        );
    }
    if table
        .get("hydrodynamics")
        .and_then(|h| h.get("method"))
        .and_then(|m| m.as_str())
        == Some("direct")
    {
        bail!(
            "{}: hydrodynamics.method: \"direct\" is RPY in an unbounded fluid (free space); the \
             periodic cube of a bulk run needs \"pse\"",
            src.label()
        );
    }
    if let Some(s) = seed {
        crate::seed32(s)?;
    }
    params::read(&table, src.base(), seed).with_context(|| src.label())
}

/// Replica `replica` of `p` at step 0, with the engine its hydrodynamics ask for.
fn build_replica(p: &BulkParams, replica: u32) -> Result<Replica> {
    Ok(if p.has_hydrodynamics() {
        Replica::Hydro(Box::new(p.build_hydro_replica(replica).map_err(keyed)?))
    } else {
        Replica::Free(Box::new(p.build_replica(replica).map_err(keyed)?))
    })
}

/// A replica's set-up error, naming the scenario key of the input it refuses.
fn keyed(e: BulkError) -> anyhow::Error {
    match e {
        BulkError::Packing(m) => anyhow::anyhow!("{}: {m}", keys::SYSTEM_BOX_LENGTH.path),
        BulkError::Initial(m) => anyhow::anyhow!(
            "{}: {}",
            keys::SYSTEM_INITIAL.path,
            crate::keys::rekey_text(
                &m,
                &[
                    ("particles", &keys::SYSTEM_PARTICLES),
                    ("box_length", &keys::SYSTEM_BOX_LENGTH)
                ]
            )
        ),
        other => other.into(),
    }
}

/// Bulk BD's headline observables (summary.json).
const HEADLINE: &[Headline] = &[
    Headline {
        name: "D",
        path: "self_diffusion.D",
        labels: None,
        unit: "length^2/time",
        doc: "long-time self-diffusion coefficient from the MSD slope between T/4 and T \
              (self_diffusion)",
        absent: "no MSD observed",
    },
    Headline {
        name: "sedimentation_velocity",
        path: "mean_velocity.along_force",
        labels: None,
        unit: "length/time",
        doc: "mean velocity along the body force (mean_velocity)",
        absent: "no body force (system.body_force)",
    },
    Headline {
        name: "sedimentation_coefficient",
        path: "sedimentation_coefficient.K",
        labels: None,
        unit: "-",
        doc: "K = U / (mu0 F), the mean velocity along the force over one sphere's Stokes \
              velocity",
        absent: "no body force (system.body_force)",
    },
    Headline {
        name: "pressure",
        path: "pressure.value",
        labels: None,
        unit: "energy/length^3",
        doc: "virial pressure N kT / V + (1/3V) sum r_ij . F_ij (pressure)",
        absent: "no pressure measured",
    },
];

impl Method for BulkBd {
    fn names(&self) -> &'static [&'static str] {
        &["bd"]
    }

    fn about(&self) -> &'static str {
        "Brownian dynamics of spheres (one or more species, any pair interaction) in a periodic cube, free draining or with RPY (PSE): MSD, self-diffusion, sedimentation under a body force and the virial pressure, per species, beside Hasimoto and the LJ equation of state"
    }

    fn docs(&self) -> &'static str {
        "docs/bd.md"
    }

    fn headline(&self) -> &'static [Headline] {
        HEADLINE
    }

    fn check(&self, src: &Source) -> Result<Checked> {
        let p = resolve(src, None)?;
        // What `run` does before it starts: set up replica 0 (reading system.initial).
        build_replica(&p, 0).with_context(|| src.label())?;
        let mut resolved = serde_json::to_value(&p)?;
        resolved["references"] = references(&p);
        Ok(Checked {
            resolved,
            warnings: Vec::new(),
        })
    }

    fn start(
        &self,
        src: &Source,
        seed: Option<u64>,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Box<dyn Session>> {
        start(src, seed, comm)
    }

    fn restore(
        &self,
        src: &Source,
        seed: u64,
        out: &OutputDir,
        envelope: &Envelope,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Box<dyn Session>> {
        restore(src, seed, out, envelope, comm)
    }

    fn keys(&self) -> &'static [Spec] {
        keys::KEYS
    }

    fn engine(&self, src: &Source, seed: Option<u64>) -> Result<Box<dyn crate::Engine>> {
        let p = resolve(src, seed)?;
        let sim = build_replica(&p, 0).with_context(|| src.label())?;
        let seed = p.seed;
        Ok(Box::new(ReplicaEngine::new(
            "bd",
            sim,
            seed,
            move |x, step, seed| {
                let p = BulkParams { seed, ..p.clone() };
                replica_at(&p, x, p.sbox(), step, None, 0)
            },
        )))
    }
}

/// A fresh session, decomposed over the ranks of `comm` when given.
fn start(
    src: &Source,
    seed: Option<u64>,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Box<dyn Session>> {
    let mut p = resolve(src, seed)?;
    if p.tune_skin {
        if comm.as_ref().is_some_and(|c| c.size() > 1) {
            bail!(
                "{}: {}: the skin is tuned on one process (each rank would time its own and \
                 choose another); tune it in a run on one process and set run.skin to the skin \
                 it chose",
                src.label(),
                RUN_TUNE_SKIN.path
            );
        }
        let t = p
            .measure_skins()
            .map_err(keyed)
            .with_context(|| src.label())?;
        p.skin = t.skin;
        p.skin_tuning = Some(t);
    }
    // Set up replica 0 before the output folder is created: bad input leaves nothing.
    let sim = build_replica(&p, 0).with_context(|| src.label())?;
    let acc = Accum::new(&p);
    Ok(Box::new(BulkObs::session(p, acc, 0, Some((sim, 0)), comm)?))
}

/// The session a checkpoint continues (on any number of ranks when decomposed).
fn restore(
    src: &Source,
    seed: u64,
    out: &OutputDir,
    envelope: &Envelope,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Box<dyn Session>> {
    let mut p = resolve(src, Some(seed))?;
    let saved: Saved<Accum> = crate::checkpoint::decode_payload(&envelope.payload)?;
    // The skin the run chose when it started, not a new tuning (bitwise restarts).
    if let Some(t) = saved.acc.skin_tuning.as_ref().filter(|_| p.tune_skin) {
        p.skin = t.skin;
        p.skin_tuning = Some(t.clone());
    }
    let lags = p.msd_lags().len();
    if saved.replica >= p.replicas
        || saved.acc.velocities.len() > p.replicas * p.blocks
        || saved.acc.msd.iter().any(|m| m.len() != lags)
        || saved
            .acc
            .species_velocities
            .iter()
            .any(|v| v.len() != p.species.len())
        || saved.acc.species_msd.iter().any(|b| {
            b.len() != p.species.len() || b.iter().any(|m| !m.is_empty() && m.len() != lags)
        })
    {
        bail!(
            "checkpoint: replica {} with {} blocks does not fit the scenario",
            saved.replica,
            saved.acc.velocities.len()
        );
    }
    let sim = match &saved.state {
        None => None,
        Some(state) => Some(restore_replica(out, &p, &saved, state)?),
    };
    // Only the writer touches the folder.
    if p.trajectory_every > 0 && comm.as_ref().is_none_or(|c| c.rank() == 0) {
        saved
            .acc
            .digest
            .restore(&out.join("trajectory.gsd"))
            .map_err(|e| fail_alone_over(comm.as_deref(), e))?;
    }
    Ok(Box::new(BulkObs::session(
        p,
        saved.acc,
        saved.replica,
        sim,
        comm,
    )?))
}

/// The simulated time in every trajectory frame (`log/bd/time`).
const TIME_LOG: &str = "bd/time";

/// Restore the running replica from its GSD checkpoint (verified against its CRC first).
fn restore_replica(
    out: &OutputDir,
    p: &BulkParams,
    saved: &Saved<Accum>,
    state: &ReplicaState,
) -> Result<(Replica, u64)> {
    let hydro = p.has_hydrodynamics();
    let f = read_replica_checkpoint(
        out,
        state,
        saved.step,
        saved.replica,
        hydro,
        &p.species.diameters,
    )?;
    let path = out.join(&state.0);
    let sim = replica_at(
        p,
        f.particles,
        f.sbox,
        f.step,
        f.list.as_ref(),
        saved.replica as u32,
    )
    .with_context(|| format!("restart from {}", path.display()))?;
    // The rebuild on restoring is not one the uninterrupted run makes: leave it out.
    let builds = state.2.builds.saturating_sub(sim.neighbor_builds());
    Ok((sim, builds))
}

/// Replica `replica` of `p` from its particles (input order, exact positions and image counts)
/// in `sbox` at `step`, with the free-draining engine's list state when a checkpoint holds one.
fn replica_at(
    p: &BulkParams,
    particles: colloidsim_particles::Particles,
    sbox: colloidsim_particles::SimBox,
    step: u64,
    list: Option<&colloidsim_particles::gsd::ListState>,
    replica: u32,
) -> Result<Replica> {
    Ok(if p.has_hydrodynamics() {
        Replica::Hydro(Box::new(p.restart_hydro_replica(
            particles,
            p.hydro_bd_params(replica),
            step,
        )?))
    } else {
        Replica::Free(Box::new(Brownian::restart(
            particles,
            sbox,
            p.pair()?,
            p.body(),
            p.bd_params(replica),
            step,
            list,
        )?))
    })
}

/// The block under way: its MSD and the centre of mass at its start.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Block {
    /// Step (of the replica) at which the block started.
    start: u64,
    /// Centre of mass (unwrapped) at the start.
    com: [f64; 3],
    /// MSD over the block's origins, per coordinate (`None` when no MSD is taken).
    msd: Option<Msd>,
    /// Two or more species: each species' centre of mass (unwrapped) at the start.
    #[serde(default)]
    species_com: Vec<[f64; 3]>,
    /// Two or more species: each species' MSD (about its own centre of mass under a body
    /// force; none for a species of one sphere under a force).
    #[serde(default)]
    species_msd: Vec<Option<Msd>>,
    /// The sum of the virial pressures sampled in the block, and their number.
    #[serde(default)]
    pressure: (f64, u64),
}

/// Everything a bulk run accumulates across replicas, saved in every checkpoint.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Accum {
    /// Per finished block (replica by replica): the velocity of the centre of mass.
    velocities: Vec<[f64; 3]>,
    /// Per finished block: the 3D MSD at each lag of [`BulkParams::msd_lags`].
    msd: Vec<Vec<f64>>,
    /// Two or more species, per finished block: the velocity of each species' centre of mass.
    #[serde(default)]
    species_velocities: Vec<Vec<[f64; 3]>>,
    /// Two or more species, per finished block: each species' 3D MSD at each lag (empty for
    /// a species without an MSD).
    #[serde(default)]
    species_msd: Vec<Vec<Vec<f64>>>,
    /// Per finished block: the mean virial pressure of its samples.
    #[serde(default)]
    pressures: Vec<f64>,
    /// The block under way.
    block: Option<Block>,
    /// Neighbour-list builds of the finished replicas.
    builds: u64,
    /// `run.tune_skin`: the tuning that chose the run's skin.
    #[serde(default)]
    skin_tuning: Option<SkinTuning>,
    /// Frames in trajectory.gsd.
    frames: u64,
    /// CRC-32 of those frames, checked before a restart appends to the file.
    digest: FrameDigest,
    /// Checkpoints written so far (alternates the GSD file name).
    checkpoints: u64,
}

impl Accum {
    fn new(p: &BulkParams) -> Self {
        let blocks = p.replicas * p.blocks;
        Self {
            velocities: Vec::with_capacity(blocks),
            msd: Vec::with_capacity(blocks),
            species_velocities: Vec::new(),
            species_msd: Vec::new(),
            pressures: Vec::with_capacity(blocks),
            block: None,
            builds: 0,
            skin_tuning: p.skin_tuning.clone(),
            frames: 0,
            digest: FrameDigest::default(),
            checkpoints: 0,
        }
    }
}

/// A bulk run: replicas one after the other.
type BulkSession = BdSession<BodyForce, BulkObs>;

/// What a bulk run observes: blocks (the centre of mass, the MSD), trajectory frames.
struct BulkObs {
    p: BulkParams,
    acc: Accum,
    /// MSD lags (steps).
    lags: Vec<u64>,
    /// Is an MSD taken? Not for one sphere under a body force (its MSD about the centre of
    /// mass is zero).
    msd_on: bool,
    /// Unwrapped positions in input order (reused).
    unwrapped: Vec<[f64; 3]>,
    /// The MSD's coordinates (reused).
    coords: Vec<f64>,
    /// The pair interaction (for the virial pressure).
    pair: Interaction,
    /// Two or more species: the input indices of each (particles are stored species by
    /// species); empty for one.
    ranges: Vec<std::ops::Range<usize>>,
}

impl BulkObs {
    /// The session of `p` at replica `rep` (running `sim`, or not yet built) with `acc`.
    fn session(
        p: BulkParams,
        acc: Accum,
        rep: usize,
        sim: Option<(Replica, u64)>,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<BulkSession> {
        let lags = p.msd_lags();
        let msd_on = !(p.force > 0.0 && p.particles == 1);
        let pair = p.pair()?;
        let ranges = species_ranges(&p);
        Ok(BdSession::new(
            Replicas::new(p.steps, p.replicas, p.trajectory_every, rep, sim, comm)?,
            BulkObs {
                p,
                acc,
                lags,
                msd_on,
                unwrapped: Vec::new(),
                coords: Vec::new(),
                pair,
                ranges,
            },
        ))
    }

    /// Offer each species' MSD of the block the configuration in `self.unwrapped` at step
    /// `s` (relative to the species' centre of mass `com[k]` when a body force acts).
    fn sample_species_msd(&mut self, s: u64, com: &[[f64; 3]]) {
        let relative = self.p.force > 0.0;
        let Some(b) = self.acc.block.as_mut() else {
            return;
        };
        for (k, m) in b.species_msd.iter_mut().enumerate() {
            let Some(m) = m.as_mut() else {
                continue;
            };
            self.coords.clear();
            for u in &self.unwrapped[self.ranges[k].clone()] {
                for a in 0..3 {
                    self.coords
                        .push(if relative { u[a] - com[k][a] } else { u[a] });
                }
            }
            m.sample(s - b.start, &self.coords);
        }
    }

    /// Steps between the virial-pressure samples of a block ([`PRESSURE_SAMPLES`] a block).
    fn pressure_every(&self) -> u64 {
        (self.p.block_steps / PRESSURE_SAMPLES).max(1)
    }

    /// Offer the block's MSD the configuration in `self.unwrapped` at step `s` (relative to
    /// the centre of mass `com` when a body force acts).
    fn sample_msd(&mut self, s: u64, com: [f64; 3]) {
        let relative = self.p.force > 0.0;
        let Some(b) = self.acc.block.as_mut() else {
            return;
        };
        let Some(m) = b.msd.as_mut() else {
            return;
        };
        self.coords.clear();
        for u in &self.unwrapped {
            for k in 0..3 {
                self.coords
                    .push(if relative { u[k] - com[k] } else { u[k] });
            }
        }
        m.sample(s - b.start, &self.coords);
    }
}

impl Observe<BodyForce> for BulkObs {
    fn build(&self, replica: u32) -> Result<Replica> {
        build_replica(&self.p, replica)
    }

    /// The start of sampling, the block's next MSD sample or its end, a trajectory frame, the
    /// end of the replica.
    fn next_event(&self, run: &Replicas<BodyForce>, s: u64) -> u64 {
        let p = &self.p;
        let mut next = p.steps;
        if s < p.equilibrate_steps {
            next = next.min(p.equilibrate_steps);
        }
        if let Some(b) = &self.acc.block {
            next = next.min(b.start + p.block_steps);
            if let Some(m) = &b.msd {
                next = next.min(b.start + m.next_due(s + 1 - b.start));
            }
            // The species' MSDs are due with the whole system's (the same lags and origins).
            next = next.min(b.start + (s + 1 - b.start).next_multiple_of(self.pressure_every()));
        }
        if run.rep == 0 && p.trajectory_every > 0 {
            next = next.min((s / p.trajectory_every + 1) * p.trajectory_every);
        }
        next
    }

    /// Record what is due at step `s`: a trajectory frame, the block's MSD sample, the end of
    /// a block, the start of the next.
    fn record(&mut self, run: &mut Replicas<BodyForce>, s: u64) -> Result<()> {
        let Some((sim, _)) = &run.sim else {
            return Ok(());
        };
        let time = sim.time();
        if run.write_frame(s, None, &[(TIME_LOG, time)])? {
            self.acc.frames += 1;
        }
        let Some((sim, _)) = &run.sim else {
            return Ok(());
        };
        let p = &self.p;
        if s < p.equilibrate_steps {
            return Ok(());
        }
        let k = s - p.equilibrate_steps;
        let (block_steps, sampled_steps) = (p.block_steps, p.sampled_steps);
        let block_time = block_steps as f64 * p.dt;
        let origin_every = p.msd_origin_every;
        let boundary = k.is_multiple_of(block_steps);
        let due = self.acc.block.as_ref().is_some_and(|b| {
            b.msd
                .as_ref()
                .is_some_and(|m| m.next_due(s - b.start) == s - b.start)
        });
        let every = self.pressure_every();
        // A pressure sample: at every `every` steps of the block under way, and at the start
        // of the next.
        let pressure_due = self.acc.block.as_ref().is_some_and(|b| {
            let o = s - b.start;
            o < block_steps && o.is_multiple_of(every)
        }) || (boundary && k < sampled_steps);
        if !boundary && !due && !pressure_due {
            return Ok(());
        }
        let pressure = if pressure_due {
            p.pressure(&sim.snapshot(), &self.pair)
                .map_err(|e| anyhow::anyhow!("the virial pressure: {e}"))?
        } else {
            f64::NAN
        };
        sim.unwrapped_into(&mut self.unwrapped);
        let com = centre(&self.unwrapped);
        let species_com: Vec<[f64; 3]> = self
            .ranges
            .iter()
            .map(|r| centre(&self.unwrapped[r.clone()]))
            .collect();
        if due {
            self.sample_msd(s, com);
            self.sample_species_msd(s, &species_com);
        }
        if boundary && k > 0 {
            // The block ends.
            let b = self.acc.block.take().context("a block under way")?;
            self.acc
                .velocities
                .push(std::array::from_fn(|i| (com[i] - b.com[i]) / block_time));
            self.acc.pressures.push(if b.pressure.1 > 0 {
                b.pressure.0 / b.pressure.1 as f64
            } else {
                f64::NAN
            });
            if !self.ranges.is_empty() {
                self.acc.species_velocities.push(
                    species_com
                        .iter()
                        .zip(&b.species_com)
                        .map(|(c, c0)| std::array::from_fn(|i| (c[i] - c0[i]) / block_time))
                        .collect(),
                );
                let per_species = b
                    .species_msd
                    .iter()
                    .map(|m| m.as_ref().map_or_else(Vec::new, |m| self.per_lag(m)))
                    .collect();
                self.acc.species_msd.push(per_species);
            }
            if let Some(m) = &b.msd {
                let per_lag = self.per_lag(m);
                self.acc.msd.push(per_lag);
            }
        }
        if boundary && k < sampled_steps {
            // The next block starts.
            let force = self.p.force > 0.0;
            self.acc.block = Some(Block {
                start: s,
                com,
                msd: self
                    .msd_on
                    .then(|| Msd::new(self.lags.clone(), origin_every)),
                species_msd: self
                    .ranges
                    .iter()
                    .map(|r| {
                        (!(force && r.len() == 1))
                            .then(|| Msd::new(self.lags.clone(), origin_every))
                    })
                    .collect(),
                species_com,
                pressure: (0.0, 0),
            });
            self.sample_msd(s, com);
            let species_com = self
                .acc
                .block
                .as_ref()
                .map_or_else(Vec::new, |b| b.species_com.clone());
            self.sample_species_msd(s, &species_com);
        }
        if pressure_due && let Some(b) = self.acc.block.as_mut() {
            b.pressure.0 += pressure;
            b.pressure.1 += 1;
        }
        Ok(())
    }

    fn replica_done(&mut self, _run: &Replicas<BodyForce>, builds: u64) -> Result<()> {
        self.acc.builds += builds;
        Ok(())
    }
}

/// The input indices of each species when there are two or more (stored species by species);
/// none for one.
fn species_ranges(p: &BulkParams) -> Vec<std::ops::Range<usize>> {
    if p.species.is_single() {
        return Vec::new();
    }
    let mut start = 0;
    p.species
        .counts
        .iter()
        .map(|&c| {
            start += c;
            start - c..start
        })
        .collect()
}

impl BulkObs {
    /// The 3D MSD of `m` at each of the run's lags (NaN at a lag without samples).
    fn per_lag(&self, m: &Msd) -> Vec<f64> {
        let rows = m.rows();
        self.lags
            .iter()
            .map(|&lag| {
                rows.iter()
                    .find(|r| r.0 == lag)
                    .map_or(f64::NAN, |r| 3.0 * r.1)
            })
            .collect()
    }
}

/// The centre of mass of `x` (a sum in input order: the same bits on any thread count).
fn centre(x: &[[f64; 3]]) -> [f64; 3] {
    let mut c = [0.0; 3];
    for v in x {
        for k in 0..3 {
            c[k] += v[k];
        }
    }
    let n = x.len().max(1) as f64;
    c.map(|s| s / n)
}

impl BdMethod<BodyForce> for BulkObs {
    type Acc = Accum;

    fn acc(&self) -> &Accum {
        &self.acc
    }

    fn bookkeeping(&mut self) -> (u64, &mut FrameDigest, &mut u64) {
        let a = &mut self.acc;
        (a.frames, &mut a.digest, &mut a.checkpoints)
    }

    fn name(&self) -> &'static str {
        "bd"
    }

    fn seed(&self) -> u64 {
        self.p.seed as u64
    }

    fn parameters(&self) -> Value {
        serde_json::to_value(&self.p).unwrap_or_default()
    }

    fn writes(&self, name: &str) -> bool {
        ["msd.csv", "msd.png"].contains(&name)
    }

    fn finish(self, out: &OutputDir, wall_s: f64, _failure: Option<&str>) -> Result<Finished> {
        let BulkObs {
            p,
            acc,
            lags,
            msd_on,
            ..
        } = &self;
        let mut warnings = Vec::new();
        let mut files = Vec::new();
        let r = Results::of(p, acc, lags, *msd_on);
        if let Some(m) = &r.msd {
            let t: Vec<f64> = lags.iter().map(|&l| l as f64 * p.dt).collect();
            let mut cols: Vec<(String, &[f64])> = vec![("t".into(), &t), ("msd".into(), &m.mean)];
            if let Some(e) = &m.err {
                cols.push(("err".into(), e));
            }
            for (name, sm) in p.species.names.iter().zip(&r.species_msd) {
                if let Some(sm) = sm {
                    cols.push((format!("msd_{name}"), &sm.mean));
                    if let Some(e) = &sm.err {
                        cols.push((format!("err_{name}"), e));
                    }
                }
            }
            let cols: Vec<(&str, &[f64])> = cols.iter().map(|(n, c)| (n.as_str(), *c)).collect();
            out.write_table("msd.csv", &cols)?;
            files.push("msd.csv".into());
            msd_picture(out, p, &t, m, &mut files, &mut warnings);
        }
        if acc.frames > 0 {
            files.push("trajectory.gsd".into());
        }
        let particle_steps = (p.steps * p.replicas as u64) as f64 * p.particles as f64;
        if p.force == 0.0 {
            for k in ["along_force", "along_force_error"] {
                out.explain(
                    "summary.json",
                    &format!("mean_velocity.{k}"),
                    "no body force (system.body_force)",
                );
            }
        }
        let mut summary = json!({
            "software": crate::software(),
            "method": "bd",
            "seed": p.seed,
            "parameters": p,
            "steps": p.steps,
            "sampled_time": p.sampled_steps as f64 * p.dt,
            "blocks": acc.velocities.len(),
            "block_time": p.block_steps as f64 * p.dt,
            "mean_velocity": r.velocity,
            "sedimentation_coefficient": r.sedimentation,
            "self_diffusion": r.diffusion,
            "pressure": r.pressure,
            "references": references(p),
            "neighbor_list_builds": acc.builds,
            "wall_seconds": wall_s,
            "particle_steps_per_second": particle_steps / wall_s.max(1e-9),
            "threads": rayon::current_num_threads(),
            "trajectory_frames": acc.frames,
            "warnings": warnings,
        });
        if let Some(species) = r.species {
            summary["species"] = species;
        }
        let message = format!(
            "{} replica(s) x {} steps of {} spheres in {wall_s:.1} s; {}; outputs in {}",
            p.replicas,
            p.steps,
            p.particles,
            r.headline,
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

/// The mean MSD over the blocks at each lag, with its standard error when there are enough
/// blocks.
struct MsdTable {
    mean: Vec<f64>,
    err: Option<Vec<f64>>,
}

impl MsdTable {
    /// The mean over `blocks` (each the MSD at `lags` lags) and its error with two or more.
    fn of(blocks: &[Vec<f64>], lags: usize) -> Self {
        let m = blocks.len();
        let mean: Vec<f64> = (0..lags)
            .map(|j| blocks.iter().map(|b| b[j]).sum::<f64>() / m as f64)
            .collect();
        let err = (m >= 2).then(|| {
            (0..lags)
                .map(|j| {
                    let v: Vec<f64> = blocks.iter().map(|b| b[j]).collect();
                    mean_and_error(&v).1
                })
                .collect()
        });
        Self { mean, err }
    }
}

/// The virial pressure `P = rho kT + (1/3V) sum_{i<j} r_ij . F_ij` ([`PRESSURE_SAMPLES`] a
/// block), its block error, and for Lennard-Jones spheres of one species the equation of state
/// of Johnson, Zollweg and Gubbins beside it with the tail correction of the cut-off.
fn pressure_figure(p: &BulkParams, acc: &Accum, few: Option<&str>, coupled: bool) -> Value {
    let v = p.box_length.powi(3);
    let ideal = p.particles as f64 * p.kt / v;
    let finite = acc.pressures.iter().all(|x| x.is_finite());
    let why = few
        .map(str::to_string)
        .or_else(|| (!finite).then(|| "a block without a pressure sample".to_string()));
    let pe = why.is_none().then(|| mean_and_error(&acc.pressures));
    let note = (p.force > 0.0 && (coupled || !p.species.is_single())).then_some(
        "under a body force with RPY or with species of different sizes the configurations are          not those of equilibrium: the pressure is that of the driven suspension",
    );
    let lj = match &p.pair {
        Some(PairSpec::Lj { epsilon, cutoff }) if p.species.is_single() => {
            let (eps, sigma) = (epsilon[0], p.diameter);
            let rho = p.particles as f64 / v * sigma.powi(3);
            let t = p.kt / eps;
            let unit = eps / sigma.powi(3);
            let jzg = jzg_pressure(rho, t) * unit;
            let tail = lj_tail_pressure(rho, *cutoff) * unit;
            json!({
                "T_star": t,
                "rho_star": rho,
                "jzg_pressure": jzg,
                "tail_correction": tail,
                "pressure_with_tail": pe.map(|x| x.0 + tail),
                "within_fit": (0.7..=6.0).contains(&t),
                "definition": "the full LJ fluid's pressure by the equation of state of Johnson, Zollweg & Gubbins (Mol. Phys. 78, 591, 1993) at T* = kT/eps, rho* = rho d^3; the run's cut-and-shifted fluid plus the mean-field tail (16/3) pi rho^2 eps d^3 [(2/3)(d/rc)^9 - (d/rc)^3] compares with it",
            })
        }
        _ => Value::Null,
    };
    json!({
        "value": pe.map(|x| x.0),
        "error": pe.map(|x| x.1),
        "ideal": ideal,
        "unit": "energy / length^3",
        "samples_per_block": p.block_steps.div_ceil((p.block_steps / PRESSURE_SAMPLES).max(1)),
        "definition": "P = N kT / V + (1/3V) sum_{i<j} r_ij . F_ij over the pairs within the cut-off, averaged over each block",
        "note": note,
        "lennard_jones": lj,
        "why_null": why,
    })
}

/// Each species' long-time self-diffusion (`D_s / D0_s`, `D0_s = kT / (3 pi eta d_s)`) from its
/// MSD, and its mean velocity along the body force against Stokes' `mu_s F_s`.
fn species_figures(p: &BulkParams, acc: &Accum, lags: &[u64], few: Option<&str>) -> Value {
    let (lo, hi) = p.slope_lags();
    let (ilo, ihi) = (
        lags.iter().position(|&l| l == lo),
        lags.iter().position(|&l| l == hi),
    );
    let interacting = p.particles > 1;
    let list: Vec<Value> = (0..p.species.len())
        .map(|k| {
            let (n, dk) = (p.species.counts[k], p.species.diameters[k]);
            let d0 = p.species_d0(k);
            let tau = dk * dk / d0;
            let nf = n as f64;
            let com_factor = if p.force > 0.0 { nf / (nf - 1.0) } else { 1.0 };
            let d_blocks: Vec<f64> = match (ilo, ihi) {
                (Some(a), Some(b)) => acc
                    .species_msd
                    .iter()
                    .filter_map(|m| m.get(k).filter(|m| !m.is_empty()))
                    .map(|m| com_factor * (m[b] - m[a]) / (6.0 * (hi - lo) as f64 * p.dt) / d0)
                    .collect(),
                _ => Vec::new(),
            };
            let why_d = if p.force > 0.0 && n == 1 {
                Some("one sphere of this species under a body force: its MSD about its species' centre of mass is zero".to_string())
            } else if interacting && (lo as f64 * p.dt) < 0.25 * tau {
                Some(format!(
                    "the slope is taken between lags {:.4} and {:.4}; the long-time self-diffusion                      needs the shorter one at least a^2 / D0 = {:.4} of this species                      (observe.msd.max_lag at least d^2 / D0 = {tau:.4})",
                    lo as f64 * p.dt,
                    hi as f64 * p.dt,
                    0.25 * tau
                ))
            } else if d_blocks.is_empty() {
                Some("no block with an MSD".to_string())
            } else {
                few.map(str::to_string)
            };
            let d = why_d.is_none().then(|| mean_and_error(&d_blocks));
            let why_u = few.map(str::to_string);
            let comps: Option<Vec<(f64, f64)>> = why_u.is_none().then(|| {
                (0..3)
                    .map(|a| {
                        let v: Vec<f64> = acc.species_velocities.iter().map(|u| u[k][a]).collect();
                        mean_and_error(&v)
                    })
                    .collect()
            });
            let (mu, fk) = (p.species_mobility(k), p.species_force(k));
            let why_k = if p.force == 0.0 {
                Some("no body force (system.body_force)".to_string())
            } else {
                why_u.clone()
            };
            let along = why_k.is_none().then(|| {
                let v: Vec<f64> = acc
                    .species_velocities
                    .iter()
                    .map(|u| (0..3).map(|a| u[k][a] * p.body_force[a]).sum::<f64>() / p.force)
                    .collect();
                mean_and_error(&v)
            });
            let stokes = mu * fk;
            json!({
                "name": p.species.names[k],
                "diameter": dk,
                "count": n,
                "self_diffusion": {
                    "D_over_D0": d.map(|d| d.0),
                    "error": d.map(|d| d.1),
                    "D": d.map(|d| d.0 * d0),
                    "D0": d0,
                    "definition": "D0 = kT / (3 pi eta d_s); D from this species' MSD as the whole system's (about its own centre of mass under a body force, times N_s / (N_s - 1))",
                    "why_null": why_d,
                },
                "velocity": {
                    "value": comps.as_ref().map(|c| c.iter().map(|x| x.0).collect::<Vec<_>>()),
                    "error": comps.as_ref().map(|c| c.iter().map(|x| x.1).collect::<Vec<_>>()),
                    "along_force": along.map(|a| a.0),
                    "along_force_error": along.map(|a| a.1),
                    "stokes": (p.force > 0.0).then_some(stokes),
                    "K": along.map(|a| a.0 / stokes),
                    "K_error": along.map(|a| a.1 / stokes),
                    "force": fk,
                    "definition": "the mean velocity of this species' centre of mass; along the force against Stokes' U0 = mu_s F_s = F (d_s/d)^3 / (3 pi eta d_s), K = U / U0 (1 for free spheres free draining)",
                    "why_null": why_u,
                    "why_null_along_force": why_k,
                },
            })
        })
        .collect();
    Value::Array(list)
}

/// The figures of a run with their errors and the reasons for any left out.
struct Results {
    velocity: Value,
    sedimentation: Value,
    diffusion: Value,
    /// The virial pressure.
    pressure: Value,
    /// Two or more species: each one's diffusion and sedimentation.
    species: Option<Value>,
    msd: Option<MsdTable>,
    /// Two or more species: each one's MSD table (`None` for a species without one).
    species_msd: Vec<Option<MsdTable>>,
    /// One line for the message.
    headline: String,
}

impl Results {
    fn of(p: &BulkParams, acc: &Accum, lags: &[u64], msd_on: bool) -> Self {
        let blocks = acc.velocities.len();
        let block_time = p.block_steps as f64 * p.dt;
        let few = (blocks < MIN_BLOCKS).then(|| {
            format!(
                "{blocks} block(s) completed; errors need at least {MIN_BLOCKS} (more \
                 observe.blocks, replicas or run.time)"
            )
        });
        // Density fluctuations of the box relax in L^2 / (4 pi^2 D0) (k = 2 pi / L).
        let relax = p.box_length * p.box_length / (4.0 * PI * PI * p.d0);
        let coupled = p.has_hydrodynamics() && p.particles > 1;
        let short = (coupled && block_time < relax).then(|| {
            format!(
                "a block lasts {block_time:.4}, less than the relaxation time L^2 / (4 pi^2 D0) = \
                 {relax:.4} of the box's slowest density fluctuation, on which the mean velocity \
                 of interacting spheres with RPY depends: the blocks are not independent (a \
                 longer run.time or fewer observe.blocks)"
            )
        });
        let why_velocity = few.clone().or(short);
        let (velocity, along) = match &why_velocity {
            None => {
                let comps: Vec<(f64, f64)> = (0..3)
                    .map(|k| {
                        let v: Vec<f64> = acc.velocities.iter().map(|u| u[k]).collect();
                        mean_and_error(&v)
                    })
                    .collect();
                let along = (p.force > 0.0).then(|| {
                    let v: Vec<f64> = acc
                        .velocities
                        .iter()
                        .map(|u| (0..3).map(|k| u[k] * p.body_force[k]).sum::<f64>() / p.force)
                        .collect();
                    mean_and_error(&v)
                });
                (Some(comps), along)
            }
            Some(_) => (None, None),
        };
        let velocity_json = json!({
            "value": velocity.as_ref().map(|c| c.iter().map(|x| x.0).collect::<Vec<_>>()),
            "error": velocity.as_ref().map(|c| c.iter().map(|x| x.1).collect::<Vec<_>>()),
            "along_force": along.map(|a| a.0),
            "along_force_error": along.map(|a| a.1),
            "unit": "length / time",
            "why_null": why_velocity,
        });
        let mu0f = p.force / p.friction;
        let why_k = if p.force == 0.0 {
            Some("no body force (system.body_force)".to_string())
        } else {
            why_velocity.clone()
        };
        let k = along
            .filter(|_| why_k.is_none())
            .map(|(u, e)| (u / mu0f, e / mu0f));
        let sedimentation = json!({
            "K": k.map(|k| k.0),
            "error": k.map(|k| k.1),
            "definition": "K = U / (mu0 F): the mean velocity along the force over the Stokes velocity of one sphere",
            "dilute_reference": p.species.is_single().then(|| p.dilute_sedimentation()),
            "why_null": why_k,
        });

        // The MSD of each block, and D from its slope at long lags.
        let (lo, hi) = p.slope_lags();
        let (ilo, ihi) = (
            lags.iter().position(|&l| l == lo),
            lags.iter().position(|&l| l == hi),
        );
        let n = p.particles as f64;
        // About the centre of mass (body force), the MSD lacks the centre's own, 1/N of it
        // for uncorrelated spheres.
        let com_factor = if p.force > 0.0 { n / (n - 1.0) } else { 1.0 };
        let d_blocks: Vec<f64> = match (ilo, ihi) {
            (Some(a), Some(b)) => acc
                .msd
                .iter()
                .map(|m| com_factor * (m[b] - m[a]) / (6.0 * (hi - lo) as f64 * p.dt) / p.d0)
                .collect(),
            _ => Vec::new(),
        };
        let interacting = p.particles > 1;
        let why_d = if !p.species.is_single() && p.force > 0.0 {
            Some(
                "species of different sizes drift apart under the body force: the MSD about the common centre of mass grows with their relative drift; each species' D is in species[]"
                    .to_string(),
            )
        } else if !msd_on {
            Some(
                "one sphere under a body force: its displacement is the mean velocity, its MSD about the centre of mass is zero"
                    .to_string(),
            )
        } else if interacting && (lo as f64 * p.dt) < 0.25 * p.diffusion_time {
            Some(format!(
                "the slope is taken between lags {:.4} and {:.4}; the long-time self-diffusion of \
                 interacting spheres needs the shorter one at least a^2 / D0 = {:.4}, the time to \
                 diffuse a radius (observe.msd.max_lag at least d^2 / D0 = {:.4})",
                lo as f64 * p.dt,
                hi as f64 * p.dt,
                0.25 * p.diffusion_time,
                p.diffusion_time
            ))
        } else {
            few.clone()
        };
        let d = (why_d.is_none() && !d_blocks.is_empty()).then(|| mean_and_error(&d_blocks));
        // Sedimenting spheres with hydrodynamic interactions move with the concentration
        // fluctuations around them: their MSD holds a hydrodynamic dispersion on top of the
        // Brownian motion.
        let dispersion = p.force > 0.0 && coupled;
        let note = dispersion.then_some(
            "under a body force with RPY, D includes the hydrodynamic dispersion of sedimentation \
             (velocity fluctuations from concentration fluctuations, growing with the Peclet number \
             and the box): it is the long-time self-diffusion of the sedimenting suspension, not \
             comparable with Hasimoto's equilibrium mobility",
        );
        let diffusion = json!({
            "D_over_D0": d.map(|d| d.0),
            "error": d.map(|d| d.1),
            "D": d.map(|d| d.0 * p.d0),
            "lags": [lo as f64 * p.dt, hi as f64 * p.dt],
            "definition": "D = [MSD(T) - MSD(T/4)] / (6 (3T/4)), T = observe.msd.max_lag; about the centre of mass under a body force, times N / (N - 1)",
            "note": note,
            "why_null": why_d,
        });

        let msd = (msd_on && !acc.msd.is_empty()).then(|| MsdTable::of(&acc.msd, lags.len()));
        let species_msd: Vec<Option<MsdTable>> = (0..p.species.len())
            .map(|k| {
                let blocks: Vec<Vec<f64>> = acc
                    .species_msd
                    .iter()
                    .filter_map(|b| b.get(k).filter(|m| !m.is_empty()).cloned())
                    .collect();
                (!blocks.is_empty()).then(|| MsdTable::of(&blocks, lags.len()))
            })
            .collect();
        let pressure = pressure_figure(p, acc, few.as_deref(), coupled);
        let species =
            (!p.species.is_single()).then(|| species_figures(p, acc, lags, few.as_deref()));
        let mut parts = Vec::new();
        if let Some((k, e)) = k {
            parts.push(if p.has_hydrodynamics() {
                format!(
                    "K = {k:.4} +- {e:.4} (dilute RPY {:.4})",
                    p.dilute_sedimentation()
                )
            } else {
                format!("K = {k:.4} +- {e:.4} (free draining: 1)")
            });
        }
        if let Some((d, e)) = d {
            parts.push(if dispersion {
                format!(
                    "D/D0 = {d:.4} +- {e:.4} (with the hydrodynamic dispersion of sedimentation)"
                )
            } else if p.has_hydrodynamics() {
                format!("D/D0 = {d:.4} +- {e:.4} (Hasimoto {:.4})", p.hasimoto())
            } else {
                format!("D/D0 = {d:.4} +- {e:.4} (free draining, one sphere: 1)")
            });
        }
        if let Some((v, e)) = pressure["value"].as_f64().zip(pressure["error"].as_f64()) {
            parts.push(format!("P = {v:.4} +- {e:.4}"));
        }
        if parts.is_empty() {
            parts.push("no figure long enough to report (summary.json says why)".into());
        }
        Self {
            velocity: velocity_json,
            sedimentation,
            diffusion,
            pressure,
            species,
            msd,
            species_msd,
            headline: parts.join(", "),
        }
    }
}

/// The references `summary.json` and `colloidsim check` give beside the figures.
fn references(p: &BulkParams) -> Value {
    json!({
        "hasimoto_mu_over_mu0": p.hasimoto(),
        "hasimoto": "mu(L)/mu0 = 1 - 2.837297 (a/L) + (4 pi/3)(a/L)^3 - 27.4 (a/L)^6: one sphere in the periodic cube (Hasimoto 1959); D/D0 of one sphere with RPY",
        "dilute_sedimentation_K": p.dilute_sedimentation(),
        "dilute_sedimentation": "K = mu(L)/mu0 - 5 phi' - 8 phi' (mu(L)/mu0 - 1), phi' = phi (N - 1)/N: pairwise RPY with hard-sphere exclusion to first order in phi (the paper's 1 - 5 phi with the periodic box's self term)",
        "free_draining": "K = 1 and D/D0 = 1 (one sphere; free draining has no hydrodynamic interactions)",
    })
}

/// `msd.png`: the MSD with its error bars against time in diffusion times, beside free
/// diffusion `6 D0 t` and, with RPY, Hasimoto's `6 mu(L)/mu0 D0 t`.
fn msd_picture(
    out: &OutputDir,
    p: &BulkParams,
    t: &[f64],
    m: &MsdTable,
    files: &mut Vec<String>,
    warnings: &mut Vec<String>,
) {
    let tau = p.diffusion_time;
    let d2 = p.diameter * p.diameter;
    let x: Vec<f64> = t.iter().map(|t| t / tau).collect();
    let y: Vec<f64> = m.mean.iter().map(|v| v / d2).collect();
    let e: Option<Vec<f64>> = m.err.as_ref().map(|e| e.iter().map(|v| v / d2).collect());
    let free: Vec<f64> = x.iter().map(|x| 6.0 * x).collect();
    let hasimoto: Vec<f64> = x.iter().map(|x| 6.0 * p.hasimoto() * x).collect();
    let mut series = vec![
        Series {
            label: "BD (error bars: block standard errors)",
            x: &x,
            y: &y,
            points: true,
        },
        Series {
            label: "free diffusion 6 D0 t",
            x: &x,
            y: &free,
            points: false,
        },
    ];
    if p.has_hydrodynamics() {
        series.push(Series {
            label: "one sphere, periodic RPY: 6 mu(L)/mu0 D0 t",
            x: &x,
            y: &hasimoto,
            points: false,
        });
    }
    let mobility = if p.has_hydrodynamics() {
        "RPY (PSE)"
    } else {
        "free draining"
    };
    let about = if p.force > 0.0 {
        ", about the centre of mass"
    } else {
        ""
    };
    let title = format!(
        "MSD{about}: N = {}, phi = {:.3}, L = {} d, {mobility}",
        p.particles,
        p.phi,
        colloidsim_core::param::show(p.box_length / p.diameter)
    );
    picture(
        line_plot_with_errors(
            &out.join("msd.png"),
            &title,
            "t / (d^2 / D0)",
            "MSD / d^2",
            &series,
            &[e.as_deref()],
            Scale::LogLog,
        ),
        "msd.png",
        files,
        warnings,
    );
}
