//! Multiparticle collision dynamics (`crates/md/src/mpcd`, docs/mpcd.md), in MPCD units:
//!
//! - `method = "mpcd"`: the SRD solvent in a periodic cube; with `[viscosity]` the periodic
//!   Poiseuille drive, and `summary.json` reports the measured shear viscosity with its standard
//!   error beside Kikuchi et al.'s formula.
//! - `method = "droplet-mpcd"`: the drying droplet filled with the solvent, boundary `none`,
//!   `slip` or `no-slip`; the solvent's density and radial velocity against `r / R(t)` and its
//!   count against the droplet volume.
//!
//! Checkpoints hold the solvent exactly (fixed-point positions, velocities, storage order):
//! a restart continues bitwise. Results do not depend on the number of threads.

use crate::Scenario as Source;
use crate::checkpoint::Envelope;
use crate::keys::Spec;
use crate::method::{Checked, Finished, Method, Session};
use crate::plot::{
    SHELL_PARTICLES, Scale, Series, Style, line_plot, line_plot_styled, merged_shells, picture,
};
use crate::trajectory::FrameDigest;
use crate::trajectory::trim_trajectory;
use anyhow::{Context, Result, bail};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::{CsvLog, OutputDir};
use colloidsim_md::gsd::GsdWriter;
use colloidsim_md::mpcd::colloid::{ColloidState, DiscreteColloids, Region, VERTICES};
use colloidsim_md::mpcd::drying::{SolventProfile, remove_excess};
use colloidsim_md::mpcd::measure::{BlockAverage, PoiseuilleProbe};
use colloidsim_md::mpcd::scenario::{Boundary, BulkRun, BulkScenario, DropletRun, DropletScenario};
use colloidsim_md::mpcd::{Acceleration, Confinement, Srd, WallKind};
use colloidsim_md::{Particles, SimBox};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::f64::consts::PI;

/// The exact state of the solvent, as checkpoints hold it.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct SolventState {
    step: u64,
    sort_every: u64,
    pos: Vec<[u32; 3]>,
    vel: Vec<[f64; 3]>,
}

impl SolventState {
    /// The whole solvent in the canonical order ([`Srd::gathered_state`]; collective when
    /// decomposed), for a bulk run, whose steps do not depend on the storage order: the same
    /// checkpoint on any number of ranks.
    fn gathered(srd: &Srd) -> Self {
        let (pos, vel) = srd.gathered_state();
        Self {
            step: srd.step(),
            sort_every: srd.sort_every(),
            pos,
            vel,
        }
    }

    fn engine(self, params: colloidsim_md::mpcd::SrdParams, sbox: SimBox) -> Result<Srd> {
        let mut srd = Srd::from_raw(params, sbox, &self.pos, &self.vel, self.step)
            .context("checkpoint.bin: the solvent state")?;
        srd.set_sort_every(self.sort_every);
        Ok(srd)
    }
}

/// A GSD frame of the solvent (type `S`, diameter 0.2 cells, velocities and masses) at the
/// given positions and velocities.
fn solvent_frame(
    w: &mut GsdWriter,
    srd: &Srd,
    pos: Vec<[f64; 3]>,
    vel: Vec<[f64; 3]>,
    log: &[(&str, f64)],
) -> Result<()> {
    let n = pos.len();
    let mut p = Particles::monodisperse(pos, 0.2 * srd.params().cell);
    p.type_names = vec!["S".into()];
    p.vel = vel;
    p.mass = vec![srd.params().mass; n];
    w.write_frame(srd.step(), srd.sbox(), &p, false, log)?;
    Ok(())
}

/// The positions and velocities of the solvent in a frame.
type SolventFrame = (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// A GSD frame with colloids: the centres (type `A`, diameter d), the vertices (type `V`) and,
/// when given, the solvent (type `S`).
fn colloid_frame(
    w: &mut GsdWriter,
    srd: &Srd,
    col: &DiscreteColloids,
    solvent: Option<SolventFrame>,
    log: &[(&str, f64)],
) -> Result<()> {
    let sbox = *srd.sbox();
    let cp = col.params();
    let mut pos: Vec<[f64; 3]> = col.centre_positions().to_vec();
    let mut vel: Vec<[f64; 3]> = col.centre_velocities().to_vec();
    let mut typeid = vec![0u32; pos.len()];
    let mut diameter = vec![cp.diameter; pos.len()];
    let mut mass = vec![cp.centre_mass; pos.len()];
    for (x, v) in col.vertex_positions().iter().zip(col.vertex_velocities()) {
        let mut x = *x;
        let mut image = [0; 3];
        sbox.wrap(&mut x, &mut image);
        pos.push(x);
        vel.push(*v);
        typeid.push(1);
        diameter.push(0.25 * srd.params().cell);
        mass.push(cp.vertex_mass);
    }
    if let Some((sp, sv)) = solvent {
        let n = sp.len();
        pos.extend(sp);
        vel.extend(sv);
        typeid.extend(std::iter::repeat_n(2, n));
        diameter.extend(std::iter::repeat_n(0.2 * srd.params().cell, n));
        mass.extend(std::iter::repeat_n(srd.params().mass, n));
    }
    let n = pos.len();
    let frame = Particles {
        pos,
        image: vec![[0; 3]; n],
        typeid,
        diameter,
        vel,
        mass,
        type_names: vec!["A".into(), "V".into(), "S".into()],
    };
    w.write_frame(srd.step(), &sbox, &frame, false, log)?;
    Ok(())
}

/// The Green–Kubo diffusivity of colloids from their centre-of-mass velocities `V`, which only
/// the collisions change (bonds are internal; the colloids fly straight between collisions
/// apart from WCA contacts): `D = (tau / 3) (C_0 / 2 + sum_{k=1}^{K} C_k)`, `C_k = <V_n . V_{n+k}>`
/// over colloids and origins, per block of the sampling collisions (docs/mpcd.md, "Colloids:
/// diffusion").
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Vacf {
    lags: usize,
    /// The last `lags + 1` velocity sets, a ring; `head` is the newest.
    history: Vec<Vec<[f64; 3]>>,
    head: usize,
    filled: usize,
    /// Per block: sums of `V_n . V_{n-k}` over colloids and origins, and their counts.
    sums: Vec<Vec<f64>>,
    counts: Vec<Vec<f64>>,
}

impl Vacf {
    fn new(lags: u64, blocks: u64) -> Self {
        let lags = lags as usize;
        Self {
            lags,
            history: vec![Vec::new(); lags + 1],
            head: 0,
            filled: 0,
            sums: vec![vec![0.0; lags + 1]; blocks as usize],
            counts: vec![vec![0.0; lags + 1]; blocks as usize],
        }
    }

    /// Add the velocities of one collision to block `block`.
    fn push(&mut self, v: &[[f64; 3]], block: usize) {
        let slots = self.lags + 1;
        self.head = (self.head + 1) % slots;
        let slot = &mut self.history[self.head];
        slot.clear();
        slot.extend_from_slice(v);
        self.filled = (self.filled + 1).min(slots);
        for k in 0..self.filled {
            let old = &self.history[(self.head + slots - k) % slots];
            let c: f64 = v
                .iter()
                .zip(old)
                .map(|(a, b)| a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
                .sum();
            self.sums[block][k] += c;
            self.counts[block][k] += v.len() as f64;
        }
    }

    /// `(D, its standard error from the block scatter, C_k / 3 over all blocks)`.
    fn estimate(&self, tau: f64) -> (f64, f64, Vec<f64>) {
        let per_block: Vec<f64> = (0..self.sums.len())
            .filter(|&b| self.counts[b][self.lags] > 0.0)
            .map(|b| {
                let c = |k: usize| self.sums[b][k] / self.counts[b][k];
                tau / 3.0 * (0.5 * c(0) + (1..=self.lags).map(c).sum::<f64>())
            })
            .collect();
        let m = per_block.len() as f64;
        let d = per_block.iter().sum::<f64>() / m;
        let se = if per_block.len() >= 2 {
            (per_block.iter().map(|x| (x - d).powi(2)).sum::<f64>() / (m - 1.0) / m).sqrt()
        } else {
            f64::NAN
        };
        let curve = (0..=self.lags)
            .map(|k| {
                let (s, n) = self
                    .sums
                    .iter()
                    .zip(&self.counts)
                    .fold((0.0, 0.0), |(s, n), (a, b)| (s + a[k], n + b[k]));
                s / n.max(1.0) / 3.0
            })
            .collect();
        (d, se, curve)
    }
}

/// Open (fresh) or reopen (restart) the trajectory when frames are due.
fn open_trajectory(out: &OutputDir, every: u64, fresh: bool) -> Result<Option<GsdWriter>> {
    if every == 0 {
        return Ok(None);
    }
    let path = out.join("trajectory.gsd");
    Ok(Some(if path.exists() && !fresh {
        GsdWriter::append(&path)?.with_velocities()
    } else {
        GsdWriter::create_new(&path)?.with_velocities()
    }))
}

/// The first position at or after `pos` past which a regular checkpoint (every ~10 %) is due.
fn tenth_after(pos: u64, total: u64) -> Option<u64> {
    let every = (total / 10).max(1);
    let next = (pos / every + 1) * every;
    (next < total).then_some(next)
}

// ------------------------------------------------------------------------------------------
// Bulk solvent.

/// The bulk SRD solvent (`method = "mpcd"`).
pub struct MpcdBulk;

fn resolve_bulk(src: &Source, seed: Option<u64>) -> Result<BulkRun> {
    crate::keys::validate(&src.table()?, crate::keys::MPCD).with_context(|| src.label())?;
    let mut sc = BulkScenario::from_toml(src.text()).with_context(|| src.label())?;
    if let Some(s) = seed {
        crate::seed32(s)?;
        sc.seed = s;
    }
    sc.validate().with_context(|| src.label())
}

fn build_bulk(p: &BulkRun) -> Result<Srd> {
    new_solvent(p.solvent.srd, p.box_edge, &Confinement::None, None)
}

/// A fresh solvent in the cube of edge `l`; over the ranks of `comm`, each drawing and holding
/// its share only.
fn new_solvent(
    params: colloidsim_md::mpcd::SrdParams,
    l: f64,
    conf: &Confinement,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Srd> {
    Ok(match comm {
        None => Srd::new(params, SimBox::cube(l), conf, 0.0)?,
        Some(c) => Srd::new_decomposed(params, SimBox::cube(l), conf, 0.0, c)?,
    })
}

/// The bulk's colloids: random sequential addition in the box.
fn build_bulk_colloids(p: &BulkRun) -> Result<Option<DiscreteColloids>> {
    place_colloids(
        p.colloids,
        p.colloid,
        p.box_edge,
        Region::Box,
        p.solvent.srd.kt,
        p.seed,
    )
    .context("system.colloids")
}

/// `n` colloids placed by random sequential addition in `region` of the cube of edge `l`
/// (none when `n = 0`).
fn place_colloids(
    n: usize,
    params: colloidsim_md::mpcd::colloid::ColloidParams,
    l: f64,
    region: Region,
    kt: f64,
    seed: u32,
) -> Result<Option<DiscreteColloids>> {
    if n == 0 {
        return Ok(None);
    }
    Ok(Some(DiscreteColloids::random(
        params,
        SimBox::cube(l),
        n,
        region,
        kt,
        seed,
    )?))
}

/// The colloids a checkpoint holds, checked against the scenario's `n`.
fn restore_colloids(
    saved: Option<&ColloidState>,
    n: usize,
    params: colloidsim_md::mpcd::colloid::ColloidParams,
    l: f64,
) -> Result<Option<DiscreteColloids>> {
    match saved {
        Some(state) if state.centre_pos.len() == n && n > 0 => Ok(Some(
            DiscreteColloids::from_state(params, SimBox::cube(l), state)
                .context("checkpoint.bin: the colloids")?,
        )),
        None if n == 0 => Ok(None),
        _ => bail!("checkpoint: its colloids do not fit the scenario"),
    }
}

impl Method for MpcdBulk {
    fn names(&self) -> &'static [&'static str] {
        &["mpcd"]
    }

    fn about(&self) -> &'static str {
        "MPCD (stochastic rotation dynamics) solvent in a periodic cube; its shear viscosity by periodic Poiseuille flow"
    }

    fn docs(&self) -> &'static str {
        "docs/mpcd.md"
    }

    fn check(&self, src: &Source) -> Result<Checked> {
        let p = resolve_bulk(src, None)?;
        build_bulk_colloids(&p).with_context(|| src.label())?;
        Ok(Checked {
            resolved: serde_json::to_value(&p)?,
            warnings: Vec::new(),
        })
    }

    fn start(
        &self,
        src: &Source,
        seed: Option<u64>,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Box<dyn Session>> {
        start_bulk(src, seed, comm)
    }

    fn restore(
        &self,
        src: &Source,
        seed: u64,
        out: &OutputDir,
        envelope: &Envelope,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Box<dyn Session>> {
        restore_bulk(src, seed, out, envelope, comm)
    }

    fn keys(&self) -> &'static [Spec] {
        crate::keys::MPCD
    }

    fn engine(&self, src: &Source, seed: Option<u64>) -> Result<Box<dyn crate::Engine>> {
        let p = resolve_bulk(src, seed)?;
        let drive = p.drive.map(|g0| Acceleration::CosineX {
            amplitude: g0,
            wavenumber: 2.0 * PI / p.box_edge,
        });
        Ok(Box::new(SolventEngine {
            srd: build_bulk(&p)?,
            colloids: build_bulk_colloids(&p)?,
            interface: None,
            method: "mpcd",
            conf: Confinement::None,
            drive: drive.unwrap_or(Acceleration::None),
            scratch: Vec::new(),
        }))
    }
}

/// Under several ranks: the solvent decomposed over them (the colloids, few, are replicated
/// on every rank).
fn decompose(srd: Srd, comm: Option<Box<dyn Exchange>>) -> Result<Srd> {
    match comm {
        None => Ok(srd),
        Some(comm) => Ok(srd.decomposed(comm)?),
    }
}

/// A fresh bulk session, decomposed over the ranks of `comm` when given.
fn start_bulk(
    src: &Source,
    seed: Option<u64>,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Box<dyn Session>> {
    let p = resolve_bulk(src, seed)?;
    let colloids = build_bulk_colloids(&p).with_context(|| src.label())?;
    let srd = new_solvent(p.solvent.srd, p.box_edge, &Confinement::None, comm)
        .with_context(|| src.label())?;
    let acc = BulkAccum::new(&p);
    Ok(Box::new(BulkSession {
        momentum: [0.0; 3],
        p,
        srd,
        colloids,
        acc,
        gsd: None,
        thermo_log: None,
        com_scratch: Vec::new(),
    }))
}

/// A bulk session from its checkpoint, on any number of ranks.
fn restore_bulk(
    src: &Source,
    seed: u64,
    out: &OutputDir,
    envelope: &Envelope,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Box<dyn Session>> {
    let p = resolve_bulk(src, Some(seed))?;
    let saved: BulkSaved = crate::checkpoint::decode_payload(&envelope.payload)?;
    if saved.solvent.pos.len() != p.particles {
        bail!("checkpoint: its solvent does not fit the scenario");
    }
    let srd = saved
        .solvent
        .engine(p.solvent.srd, SimBox::cube(p.box_edge))?;
    let writer = comm.as_ref().is_none_or(|c| c.rank() == 0);
    let srd = decompose(srd, comm)?;
    let colloids = restore_colloids(saved.colloids.as_ref(), p.colloids, p.colloid, p.box_edge)?;
    if p.trajectory_every > 0 && writer {
        saved
            .acc
            .digest
            .restore(&out.join("trajectory.gsd"), |path, frames| {
                trim_trajectory(path, frames, &[], true)
            })
            .map_err(|e| crate::method::fail_alone_over(srd.exchange(), e))?;
    }
    Ok(Box::new(BulkSession {
        momentum: [0.0; 3],
        p,
        srd,
        colloids,
        acc: saved.acc,
        gsd: None,
        thermo_log: None,
        com_scratch: Vec::new(),
    }))
}

/// One row of `thermo.csv` (bulk).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct BulkRow {
    collision: u64,
    temperature: f64,
    flow: f64,
    /// Of the solvent and the colloids.
    momentum: [f64; 3],
    /// Kinetic temperature of the colloids' centre-of-mass velocities (NaN without).
    colloid_temperature: f64,
}

/// What a bulk run accumulates (saved in every checkpoint).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct BulkAccum {
    rows: Vec<BulkRow>,
    /// The flow amplitude samples (with a drive).
    probe: Option<PoiseuilleProbe>,
    /// Mean flow amplitudes just before and after the collisions, summed over the samples.
    before_after: [f64; 2],
    /// Temperature of the sampling part, per collision in blocks.
    temperature: BlockAverage,
    /// `v_x` summed in slabs along z over the profile samples, and the samples.
    flow_profile: Vec<f64>,
    flow_counts: Vec<f64>,
    /// The colloids' velocity autocorrelation (with colloids).
    vacf: Option<Vacf>,
    frames: u64,
    digest: FrameDigest,
}

impl BulkAccum {
    fn new(p: &BulkRun) -> Self {
        let sampling = p.collisions - p.equilibrate;
        let block = (sampling / p.blocks).max(1);
        let k = 2.0 * PI / p.box_edge;
        let slabs = (p.box_edge / p.solvent.srd.cell).round() as usize;
        Self {
            rows: Vec::new(),
            probe: p
                .drive
                .map(|g0| PoiseuilleProbe::new(g0, k, p.solvent.mass_density, block)),
            before_after: [0.0; 2],
            temperature: BlockAverage::new(block.div_ceil(p.thermo_every).max(1)),
            flow_profile: vec![0.0; slabs],
            flow_counts: vec![0.0; slabs],
            vacf: (p.colloids > 0).then(|| Vacf::new(p.vacf_lags, p.blocks)),
            frames: 0,
            digest: FrameDigest::default(),
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct BulkSaved {
    solvent: SolventState,
    colloids: Option<ColloidState>,
    acc: BulkAccum,
}

struct BulkSession {
    p: BulkRun,
    srd: Srd,
    colloids: Option<DiscreteColloids>,
    acc: BulkAccum,
    gsd: Option<GsdWriter>,
    /// `thermo.csv`, appended row by row as the run goes.
    thermo_log: Option<CsvLog>,
    /// The colloids' centre-of-mass velocities of the current collision (reused).
    com_scratch: Vec<[f64; 3]>,
    /// The total momentum at the end of the last chunk of collisions (for the summary, which
    /// is written without messages between ranks).
    momentum: [f64; 3],
}

impl BulkSession {
    /// The collisions up to `until`; `Some(why)` when the run stops early.
    fn advance_to(&mut self, until: u64) -> Result<Option<String>> {
        let tau = self.p.solvent.srd.tau;
        let k = self.wavenumber();
        let drive = match self.p.drive {
            Some(g0) => Acceleration::CosineX {
                amplitude: g0,
                wavenumber: k,
            },
            None => Acceleration::None,
        };
        let conf = Confinement::None;
        let thermostat = self.p.solvent.srd.thermostat;
        while self.srd.step() < until.min(self.p.collisions) {
            let t = (self.srd.step() + 1) as f64 * tau;
            if let Err(e) = self.srd.stream(t, &conf, &drive) {
                return Ok(Some(e.to_string()));
            }
            if let Some(col) = self.colloids.as_mut()
                && let Err(e) = col.advance(t - tau, tau, &colloidsim_md::NoExternal)
            {
                return Ok(Some(e.to_string()));
            }
            let sampling = self.srd.step() >= self.p.equilibrate;
            let before = match (&self.acc.probe, sampling) {
                (Some(_), true) => PoiseuilleProbe::amplitude_of(&self.srd, k),
                _ => 0.0,
            };
            let emb = self.colloids.as_mut().map(|c| c.embedded());
            self.srd.collide(t, &conf, emb);
            if sampling && let (Some(col), Some(vacf)) = (&self.colloids, self.acc.vacf.as_mut()) {
                // Sample j of the sampling part belongs to block j * blocks / sampling.
                let j = self.srd.step() - self.p.equilibrate - 1;
                let n = self.p.collisions - self.p.equilibrate;
                let b = ((j as u128 * self.p.blocks as u128) / n as u128) as usize;
                // Relative to the solvent's mean velocity: the frame of Hasimoto's theory.
                let (ps, ms) = (
                    self.srd.momentum(),
                    self.srd.particles() as f64 * self.srd.params().mass,
                );
                col.com_velocities_into(&mut self.com_scratch);
                for v in &mut self.com_scratch {
                    *v = std::array::from_fn(|k| v[k] - ps[k] / ms);
                }
                vacf.push(&self.com_scratch, b);
            }
            if let Some(probe) = self.acc.probe.as_mut() {
                if !thermostat {
                    // Without the cell thermostat the viscous heat leaves by a global
                    // rescaling about the flow (measure::poiseuille_viscosity).
                    let a = PoiseuilleProbe::amplitude_of(&self.srd, k);
                    self.srd.rescale_about(|x| [a * (k * x[2]).cos(), 0.0, 0.0]);
                }
                if sampling {
                    let after = PoiseuilleProbe::amplitude_of(&self.srd, k);
                    self.acc.before_after[0] += before;
                    self.acc.before_after[1] += after;
                    probe.push(0.5 * (before + after));
                }
            }
            self.record(self.srd.step())?;
        }
        Ok(None)
    }

    /// Momentum of the solvent and the colloids (collective when decomposed).
    fn total_momentum(&self) -> [f64; 3] {
        let mut momentum = self.srd.momentum();
        if let Some(col) = &self.colloids {
            let pc = col.momentum();
            momentum = std::array::from_fn(|k| momentum[k] + pc[k]);
        }
        momentum
    }

    fn wavenumber(&self) -> f64 {
        2.0 * PI / self.p.box_edge
    }

    /// Observations after `c` collisions.
    fn record(&mut self, c: u64) -> Result<()> {
        let p = &self.p;
        if c.is_multiple_of(p.thermo_every) {
            let k = 2.0 * PI / p.box_edge;
            let flow = PoiseuilleProbe::amplitude_of(&self.srd, k);
            let m = p.solvent.srd.mass;
            let temperature = if p.drive.is_some() {
                // Relative to the driven flow.
                let n = self.srd.particles() as f64;
                let twice = self.srd.sum(|x, v| {
                    let w = [v[0] - flow * (k * x[2]).cos(), v[1], v[2]];
                    [m * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2])]
                })[0];
                twice / (3.0 * (n - 1.0))
            } else {
                self.srd.temperature()
            };
            let mut momentum = self.srd.momentum();
            if let Some(col) = &self.colloids {
                let pc = col.momentum();
                momentum = std::array::from_fn(|k| momentum[k] + pc[k]);
            }
            self.acc.rows.push(BulkRow {
                collision: c,
                temperature,
                flow,
                momentum,
                colloid_temperature: self
                    .colloids
                    .as_ref()
                    .map_or(f64::NAN, |c| c.com_temperature()),
            });
            if let (Some(log), Some(row)) = (self.thermo_log.as_mut(), self.acc.rows.last()) {
                log.append(&row.values(p.solvent.srd.tau))
                    .map_err(|e| crate::method::fail_alone_over(self.srd.exchange(), e.into()))?;
            }
            if c > p.equilibrate {
                self.acc.temperature.push(temperature);
                let slabs = self.acc.flow_profile.len();
                let (vx, counts) = self.srd.z_profile(slabs, |_, v| v[0]);
                for b in 0..slabs {
                    self.acc.flow_profile[b] += vx[b];
                    self.acc.flow_counts[b] += counts[b];
                }
            }
        }
        if p.trajectory_every > 0 && c.is_multiple_of(p.trajectory_every) {
            // Every rank takes part in gathering the solvent; the writer writes.
            let solvent = (self.colloids.is_none() || p.trajectory_solvent).then(|| {
                let (pos, vel) = self.srd.gathered_state();
                let fixed = *self.srd.fixed_point();
                (pos.iter().map(|x| fixed.decode(*x)).collect(), vel)
            });
            if let Some(w) = self.gsd.as_mut() {
                let written = match (&self.colloids, solvent) {
                    (Some(col), solvent) => colloid_frame(w, &self.srd, col, solvent, &[]),
                    (None, Some((pos, vel))) => solvent_frame(w, &self.srd, pos, vel, &[]),
                    (None, None) => unreachable!("a bulk frame without colloids has the solvent"),
                };
                written.map_err(|e| crate::method::fail_alone_over(self.srd.exchange(), e))?;
            }
            self.acc.frames += 1;
        }
        Ok(())
    }
}

impl Session for BulkSession {
    fn label(&self) -> String {
        "mpcd".into()
    }

    fn total(&self) -> u64 {
        self.p.collisions
    }

    fn position(&self) -> u64 {
        self.srd.step()
    }

    fn seed(&self) -> u64 {
        self.p.seed as u64
    }

    fn status(&self) -> String {
        let t = self.srd.step() as f64 * self.p.solvent.srd.tau;
        let mut s = format!("t = {}", crate::driver::significant(t));
        if let Some(r) = self.acc.rows.last() {
            s.push_str(&format!(", T = {:.4}", r.temperature));
        }
        s
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::to_value(&self.p).unwrap_or_default()
    }

    fn writes(&self, name: &str) -> bool {
        [
            "thermo.csv",
            "flow_profile.csv",
            "flow_profile.png",
            "vacf.csv",
            "trajectory.gsd",
        ]
        .contains(&name)
    }

    fn begin(&mut self, out: &OutputDir, fresh: bool) -> Result<()> {
        if BulkSession::is_writer(self) {
            self.gsd = open_trajectory(out, self.p.trajectory_every, fresh)?;
            self.thermo_log = Some(CsvLog::start(
                out.join("thermo.csv"),
                &BULK_THERMO,
                fresh,
                || thermo_rows(self.p.solvent.srd.tau, &self.acc.rows),
            )?);
        }
        if fresh {
            self.record(0)?;
        }
        self.momentum = self.total_momentum();
        Ok(())
    }

    fn next_checkpoint(&self) -> Option<u64> {
        tenth_after(self.position(), self.p.collisions)
    }

    fn exchange(&self) -> Option<&dyn Exchange> {
        self.srd.exchange()
    }

    fn advance(&mut self, until: u64) -> Result<Option<String>> {
        let stopped = self.advance_to(until)?;
        self.momentum = self.total_momentum();
        Ok(stopped)
    }

    fn flush(&mut self) -> Result<()> {
        if let Some(w) = self.gsd.as_mut() {
            w.sync()?;
        }
        Ok(())
    }

    fn save(&mut self, out: &OutputDir) -> Result<Vec<u8>> {
        if self.p.trajectory_every > 0 && BulkSession::is_writer(self) {
            let extended = self.flush().and_then(|_| {
                self.acc
                    .digest
                    .extend(&out.join("trajectory.gsd"), self.acc.frames)
            });
            extended.map_err(|e| crate::method::fail_alone_over(self.srd.exchange(), e))?;
        }
        Ok(bincode::serialize(&BulkSaved {
            solvent: SolventState::gathered(&self.srd),
            colloids: self.colloids.as_ref().map(|c| c.state()),
            acc: self.acc.clone(),
        })?)
    }

    fn interim_outputs(&mut self, out: &OutputDir) -> Result<Vec<String>> {
        if !BulkSession::is_writer(self) {
            return Ok(Vec::new());
        }
        write_thermo(out, self.p.solvent.srd.tau, &self.acc.rows)?;
        Ok(vec!["thermo.csv".into()])
    }

    fn finish(
        mut self: Box<Self>,
        out: &OutputDir,
        wall_s: f64,
        failure: Option<&str>,
    ) -> Result<Finished> {
        if !BulkSession::is_writer(&self) {
            return Ok(Finished::nothing_written());
        }
        self.flush()?;
        let p = &self.p;
        let solvent_particles = p.particles;
        let mut files = Vec::new();
        let mut warnings = Vec::new();
        write_thermo(out, p.solvent.srd.tau, &self.acc.rows)?;
        files.push("thermo.csv".into());
        let collisions = self.srd.step();
        let sampled = collisions.saturating_sub(p.equilibrate);
        let (t_mean, t_se) = (
            self.acc.temperature.mean(),
            self.acc.temperature.standard_error(),
        );
        let mut summary = json!({
            "software": crate::software(),
            "method": "mpcd",
            "seed": p.seed,
            "parameters": p,
            "units": "MPCD: lengths in the cell edge a, masses in the solvent mass m, energies in kT, times in a sqrt(m / kT)",
            "collisions": collisions,
            "sampled_collisions": sampled,
            "time": collisions as f64 * p.solvent.srd.tau,
            "solvent_particles": solvent_particles,
            "temperature": { "value": t_mean, "standard_error": t_se, "target": p.solvent.srd.kt },
            "momentum": self.momentum,
            "viscosity_theory": p.solvent.viscosity_theory,
            "wall_seconds": wall_s,
            "particle_updates_per_second": collisions as f64 * solvent_particles as f64 / wall_s.max(1e-9),
            "threads": rayon::current_num_threads(),
            "trajectory_frames": self.acc.frames,
        });
        if self.srd.rank().1 > 1 {
            summary["ranks"] = json!(self.srd.rank().1);
        }
        if let Some(probe) = &self.acc.probe {
            let (eta, se) = probe.viscosity();
            let blocks = probe.flow.blocks.len();
            let n = (sampled as f64).max(1.0);
            let theory = p.solvent.viscosity_theory;
            if blocks < 2 {
                warnings.push(format!(
                    "viscosity: only {blocks} complete block(s) of the flow amplitude, no standard error"
                ));
            }
            summary["viscosity"] = json!({
                "value": eta,
                "standard_error": se,
                "theory": theory,
                "relative_deviation": eta / theory - 1.0,
                "method": "periodic Poiseuille flow (Backer et al. 2005): eta = rho g0 / (k^2 A), A the flow amplitude averaged over the free flight",
                "drive": probe.amplitude,
                "flow_amplitude": probe.flow.mean(),
                "flow_before_after_collisions": [self.acc.before_after[0] / n, self.acc.before_after[1] / n],
                "blocks": blocks,
            });
            // The flow profile against A cos(k z).
            let slabs = self.acc.flow_profile.len();
            let l = p.box_edge;
            let k = self.wavenumber();
            let z: Vec<f64> = (0..slabs)
                .map(|b| ((b as f64 + 0.5) / slabs as f64 - 0.5) * l)
                .collect();
            let vx: Vec<f64> = (0..slabs)
                .map(|b| self.acc.flow_profile[b] / self.acc.flow_counts[b].max(1.0))
                .collect();
            let a = probe.flow.mean();
            let fit: Vec<f64> = z.iter().map(|z| a * (k * z).cos()).collect();
            if self.acc.flow_counts.iter().any(|&c| c > 0.0) {
                out.write_table(
                    "flow_profile.csv",
                    &[("z", &z), ("vx", &vx), ("a_cos_kz", &fit)],
                )?;
                files.push("flow_profile.csv".into());
                let title = format!(
                    "MPCD periodic Poiseuille flow: eta = {eta:.4} +- {se:.4} (Kikuchi {theory:.4})"
                );
                picture(
                    line_plot(
                        &out.join("flow_profile.png"),
                        &title,
                        "z / a",
                        "v_x sqrt(m / kT)",
                        &[
                            Series {
                                label: "measured",
                                x: &z,
                                y: &vx,
                                points: true,
                            },
                            Series {
                                label: "A cos(2 pi z / L)",
                                x: &z,
                                y: &fit,
                                points: false,
                            },
                        ],
                        Scale::Linear,
                    ),
                    "flow_profile.png",
                    &mut files,
                    &mut warnings,
                );
            }
        }
        if let Some(vacf) = &self.acc.vacf {
            let tau = p.solvent.srd.tau;
            let (d, se, curve) = vacf.estimate(tau);
            let lag: Vec<f64> = (0..curve.len()).map(|k| k as f64 * tau).collect();
            let mut running = Vec::with_capacity(curve.len());
            let mut acc = 0.0;
            for (k, c) in curve.iter().enumerate() {
                acc += if k == 0 { 0.5 * c } else { *c };
                running.push(tau * acc);
            }
            out.write_table(
                "vacf.csv",
                &[
                    ("lag", &lag),
                    ("vacf_over_3", &curve),
                    ("d_running", &running),
                ],
            )?;
            files.push("vacf.csv".into());
            let theory = p.stokes_einstein_hasimoto;
            summary["colloid_diffusion"] = json!({
                "value": d,
                "standard_error": se,
                "method": "Green-Kubo of the colloids' centre-of-mass velocities relative to the solvent's mean velocity, D = (tau/3) (C_0/2 + sum_k C_k), blocks for the error",
                "lags": p.vacf_lags,
                "stokes_einstein_hasimoto": theory,
                "relative_deviation": d / theory - 1.0,
                "hydrodynamic_radius_assumed": 0.5 * p.colloid.diameter,
                "viscosity_used": p.solvent.viscosity_theory,
            });
            if let Some(col) = &self.colloids {
                summary["colloids"] = json!({
                    "particles": col.len(),
                    "temperature_centre_of_mass": col.com_temperature(),
                    "temperature_all_particles": col.temperature(),
                    "bond_strain_rms": col.bond_strain_rms(),
                });
            }
        }
        if self.acc.frames > 0 {
            files.push("trajectory.gsd".into());
        }
        summary["warnings"] = json!(warnings);
        let message = match (failure, summary.get("viscosity")) {
            (Some(f), _) => format!("mpcd stopped at collision {collisions}: {f}"),
            (None, None) if summary.get("colloid_diffusion").is_some() => format!(
                "mpcd: {collisions} collisions of {} solvent particles and {} colloids; D = {:.6} +- {:.6} (Stokes-Einstein-Hasimoto at a = d/2: {:.6})",
                solvent_particles,
                p.colloids,
                summary["colloid_diffusion"]["value"]
                    .as_f64()
                    .unwrap_or(f64::NAN),
                summary["colloid_diffusion"]["standard_error"]
                    .as_f64()
                    .unwrap_or(f64::NAN),
                p.stokes_einstein_hasimoto
            ),
            (None, Some(v)) => format!(
                "mpcd: {collisions} collisions of {} solvent particles; viscosity {:.4} +- {:.4} (Kikuchi et al. {:.4})",
                solvent_particles,
                v["value"].as_f64().unwrap_or(f64::NAN),
                v["standard_error"].as_f64().unwrap_or(f64::NAN),
                p.solvent.viscosity_theory
            ),
            (None, None) => format!(
                "mpcd: {collisions} collisions of {} solvent particles; T = {t_mean:.4} +- {t_se:.4}",
                solvent_particles
            ),
        };
        Ok(Finished {
            summary,
            files,
            message,
            warnings,
        })
    }
}

/// The columns of a bulk run's `thermo.csv`.
const BULK_THERMO: [&str; 8] = [
    "collision",
    "time",
    "temperature",
    "flow_amplitude",
    "px",
    "py",
    "pz",
    "colloid_temperature",
];

impl ThermoRow for BulkRow {
    const COLUMNS: &'static [&'static str] = &BULK_THERMO;
    fn values(&self, tau: f64) -> Vec<f64> {
        vec![
            self.collision as f64,
            self.collision as f64 * tau,
            self.temperature,
            self.flow,
            self.momentum[0],
            self.momentum[1],
            self.momentum[2],
            self.colloid_temperature,
        ]
    }
}

/// A row of `thermo.csv` (bulk or droplet).
trait ThermoRow {
    /// The columns.
    const COLUMNS: &'static [&'static str];
    /// The row, with the collision time `tau`.
    fn values(&self, tau: f64) -> Vec<f64>;
}

fn thermo_rows<R: ThermoRow>(tau: f64, rows: &[R]) -> Vec<Vec<f64>> {
    rows.iter().map(|r| r.values(tau)).collect()
}

/// `thermo.csv` complete (it is also appended row by row as the run goes).
fn write_thermo<R: ThermoRow>(out: &OutputDir, tau: f64, rows: &[R]) -> Result<()> {
    out.write_rows("thermo.csv", R::COLUMNS, &thermo_rows(tau, rows))?;
    Ok(())
}

// ------------------------------------------------------------------------------------------
// Drying droplet.

/// The drying droplet of MPCD solvent (`method = "droplet-mpcd"`).
pub struct DropletMpcd;

fn resolve_droplet(src: &Source, seed: Option<u64>) -> Result<DropletRun> {
    crate::keys::validate(&src.table()?, crate::keys::DROPLET_MPCD).with_context(|| src.label())?;
    let mut sc = DropletScenario::from_toml(src.text()).with_context(|| src.label())?;
    if let Some(s) = seed {
        crate::seed32(s)?;
        sc.seed = s;
    }
    sc.validate().with_context(|| src.label())
}

/// Where the solvent streams (the sphere, or nothing for `boundary = "none"`).
fn confinement(p: &DropletRun) -> Confinement {
    let law = p.law();
    match p.boundary {
        Boundary::None => Confinement::None,
        Boundary::Slip => Confinement::Sphere {
            law,
            kind: WallKind::Slip,
        },
        Boundary::NoSlip => Confinement::Sphere {
            law,
            kind: WallKind::NoSlip,
        },
    }
}

fn build_droplet(p: &DropletRun, comm: Option<Box<dyn Exchange>>) -> Result<Srd> {
    new_solvent(p.solvent.srd, p.box_edge, &confinement(p), comm)
}

/// The colloids at the start: random sequential addition with centres within `R0 - d/2`.
fn build_colloids(p: &DropletRun) -> Result<Option<DiscreteColloids>> {
    place_colloids(
        p.particles,
        p.colloid,
        p.box_edge,
        Region::Sphere { radius: p.r0 },
        p.solvent.srd.kt,
        p.seed,
    )
    .context("system.particles")
}

impl Method for DropletMpcd {
    fn names(&self) -> &'static [&'static str] {
        &["droplet-mpcd"]
    }

    fn about(&self) -> &'static str {
        "drying droplet of MPCD solvent with a none, slip or no-slip boundary at the moving interface"
    }

    fn docs(&self) -> &'static str {
        "docs/mpcd.md"
    }

    fn check(&self, src: &Source) -> Result<Checked> {
        let p = resolve_droplet(src, None)?;
        build_colloids(&p).with_context(|| src.label())?;
        Ok(Checked {
            resolved: serde_json::to_value(&p)?,
            warnings: Vec::new(),
        })
    }

    fn start(
        &self,
        src: &Source,
        seed: Option<u64>,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Box<dyn Session>> {
        let p = resolve_droplet(src, seed)?;
        let colloids = build_colloids(&p).with_context(|| src.label())?;
        let srd = build_droplet(&p, comm).with_context(|| src.label())?;
        let acc = DropletAccum::new(&p, srd.particles());
        Ok(Box::new(DropletSession {
            now: (0, f64::NAN),
            p,
            srd,
            colloids,
            acc,
            gsd: None,
            thermo_log: None,
            scratch: Vec::new(),
        }))
    }

    fn restore(
        &self,
        src: &Source,
        seed: u64,
        out: &OutputDir,
        envelope: &Envelope,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Box<dyn Session>> {
        let p = resolve_droplet(src, Some(seed))?;
        let saved: DropletSaved = crate::checkpoint::decode_payload(&envelope.payload)?;
        if saved.acc.profiles.len() != p.profile_collisions.len() {
            bail!("checkpoint: its profiles do not fit the scenario");
        }
        let srd = saved
            .solvent
            .engine(p.solvent.srd, SimBox::cube(p.box_edge))?;
        let writer = comm.as_ref().is_none_or(|c| c.rank() == 0);
        let srd = decompose(srd, comm)?;
        let colloids =
            restore_colloids(saved.colloids.as_ref(), p.particles, p.colloid, p.box_edge)?;
        if p.trajectory_every > 0 && writer {
            saved
                .acc
                .digest
                .restore(&out.join("trajectory.gsd"), |path, frames| {
                    trim_trajectory(path, frames, &["radius"], true)
                })
                .map_err(|e| crate::method::fail_alone_over(srd.exchange(), e))?;
        }
        Ok(Box::new(DropletSession {
            now: (0, f64::NAN),
            p,
            srd,
            colloids,
            acc: saved.acc,
            gsd: None,
            thermo_log: None,
            scratch: Vec::new(),
        }))
    }

    fn keys(&self) -> &'static [Spec] {
        crate::keys::DROPLET_MPCD
    }

    fn engine(&self, src: &Source, seed: Option<u64>) -> Result<Box<dyn crate::Engine>> {
        let p = resolve_droplet(src, seed)?;
        Ok(Box::new(SolventEngine {
            srd: build_droplet(&p, None)?,
            colloids: build_colloids(&p)?,
            interface: Some(p.harmonic()),
            method: "droplet-mpcd",
            conf: confinement(&p),
            drive: Acceleration::None,
            scratch: Vec::new(),
        }))
    }
}

/// One row of `thermo.csv` (droplet).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct DropletRow {
    collision: u64,
    radius: f64,
    solvent: u64,
    expected: u64,
    removed: u64,
    bounced: u64,
    temperature: f64,
    /// Kinetic temperature of the colloids' centre-of-mass velocities (NaN without).
    colloid_temperature: f64,
}

/// The colloid volume-fraction profiles: per profile time, phi per bin, the bin centres and
/// the radius when taken.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
struct ColloidProfiles {
    phi: Vec<Vec<f64>>,
    r: Vec<Vec<f64>>,
    radius: Vec<f64>,
    taken: Vec<bool>,
    /// Largest distance of a centre beyond the interface's wall `R(t) + offset`.
    max_excursion: f64,
    /// Centres beyond R(t) at the end.
    outside_final: u64,
}

/// What a droplet run accumulates (saved in every checkpoint).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct DropletAccum {
    rows: Vec<DropletRow>,
    /// One solvent profile per profile time.
    profiles: Vec<SolventProfile>,
    solvent0: u64,
    removed: u64,
    /// Largest residual excess after a removal, and the last one.
    residual_max: u64,
    residual_last: u64,
    bounced: u64,
    reflections: u64,
    stuck: u64,
    virtual_particles: u64,
    colloid_profiles: ColloidProfiles,
    frames: u64,
    digest: FrameDigest,
}

impl DropletAccum {
    fn new(p: &DropletRun, solvent: usize) -> Self {
        let blocks = |c: u64| p.solvent_window.min(c + 1).min(10) as usize;
        Self {
            rows: Vec::new(),
            profiles: p
                .profile_collisions
                .iter()
                .map(|&c| SolventProfile::new(p.solvent_bins, blocks(c)))
                .collect(),
            solvent0: solvent as u64,
            removed: 0,
            residual_max: 0,
            residual_last: 0,
            bounced: 0,
            reflections: 0,
            stuck: 0,
            virtual_particles: 0,
            colloid_profiles: {
                let k = p.profile_collisions.len();
                ColloidProfiles {
                    phi: vec![Vec::new(); k],
                    r: vec![Vec::new(); k],
                    radius: vec![0.0; k],
                    taken: vec![false; k],
                    max_excursion: f64::NEG_INFINITY,
                    outside_final: 0,
                }
            },
            frames: 0,
            digest: FrameDigest::default(),
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct DropletSaved {
    solvent: SolventState,
    colloids: Option<ColloidState>,
    acc: DropletAccum,
}

struct DropletSession {
    p: DropletRun,
    srd: Srd,
    colloids: Option<DiscreteColloids>,
    acc: DropletAccum,
    gsd: Option<GsdWriter>,
    /// `thermo.csv`, appended row by row as the run goes.
    thermo_log: Option<CsvLog>,
    scratch: Vec<(u32, u32)>,
    /// The solvent count and temperature at the end of the last chunk of collisions (for the
    /// summary, which is written without messages between ranks).
    now: (usize, f64),
}

impl DropletSession {
    /// The collisions up to `until`; `Some(why)` when the run stops early.
    fn advance_to(&mut self, until: u64) -> Result<Option<String>> {
        let tau = self.p.solvent.srd.tau;
        let conf = confinement(&self.p);
        let walls = self.p.boundary != Boundary::None;
        while self.srd.step() < until.min(self.p.collisions) {
            let step = self.srd.step();
            let t = (step + 1) as f64 * tau;
            let st = match self.srd.stream(t, &conf, &Acceleration::None) {
                Ok(st) => st,
                Err(e) => return Ok(Some(e.to_string())),
            };
            if let Some(col) = self.colloids.as_mut()
                && let Err(e) = col.advance(step as f64 * tau, tau, &self.p.harmonic())
            {
                return Ok(Some(e.to_string()));
            }
            self.acc.bounced += st.bounced;
            self.acc.reflections += st.reflections;
            self.acc.stuck += st.stuck;
            if walls {
                let expected = self.expected(step + 1) as usize;
                let r = remove_excess(&mut self.srd, expected, step, &mut self.scratch);
                self.acc.removed += r.removed;
                self.acc.residual_max = self.acc.residual_max.max(r.residual);
                self.acc.residual_last = r.residual;
            }
            let emb = self.colloids.as_mut().map(|c| c.embedded());
            let cs = self.srd.collide(t, &conf, emb);
            self.acc.virtual_particles += cs.virtual_particles;
            if let Some(why) = self.record(step + 1, st.bounced)? {
                return Ok(Some(why));
            }
        }
        Ok(None)
    }

    fn radius(&self, c: u64) -> f64 {
        self.p.law().radius(c as f64 * self.p.solvent.srd.tau)
    }

    /// The expected solvent count at collision `c`: `round(n V)` of the fluid region.
    fn expected(&self, c: u64) -> u64 {
        let t = c as f64 * self.p.solvent.srd.tau;
        let v = confinement(&self.p).volume(t, [self.p.box_edge; 3]);
        (self.p.solvent.number_density * v).round() as u64
    }

    /// Observations after `c` collisions; `Some(why)` if the solvent has left the droplet.
    fn record(&mut self, c: u64, bounced: u64) -> Result<Option<String>> {
        let r = self.radius(c);
        let p = &self.p;
        if let Some(col) = &self.colloids {
            let cp = &mut self.acc.colloid_profiles;
            let wall = r + p.interface[2];
            for x in col.centre_positions() {
                let d = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
                cp.max_excursion = cp.max_excursion.max(d - wall);
            }
            for (j, &cf) in p.profile_collisions.iter().enumerate() {
                if cf == c {
                    let pos = col.centre_positions();
                    let prof = colloidsim_analysis::radial_profile(
                        pos,
                        &vec![p.diameter; pos.len()],
                        [0.0; 3],
                        r,
                        p.profile.bins,
                    );
                    cp.phi[j] = prof.phi;
                    cp.r[j] = prof.r;
                    cp.radius[j] = r;
                    cp.taken[j] = true;
                    if c == p.collisions {
                        cp.outside_final = prof.outside as u64;
                    }
                }
            }
        }
        for (j, &cf) in p.profile_collisions.iter().enumerate() {
            let w = p.solvent_window;
            let first = cf.saturating_sub(w - 1);
            if c >= first && c <= cf {
                let prof = &mut self.acc.profiles[j];
                let blocks = prof.samples.len() as u64;
                let span = cf - first + 1;
                let b = ((c - first) * blocks / span) as usize;
                prof.sample(&self.srd, r, b);
            }
        }
        if c.is_multiple_of(p.thermo_every) || c == p.collisions {
            if p.boundary != Boundary::None {
                // The farthest particle of all (a maximum: the same on any number of ranks).
                let view = self.srd.view();
                let far = (0..view.len())
                    .map(|i| {
                        let x = view.position(i);
                        x[0] * x[0] + x[1] * x[1] + x[2] * x[2]
                    })
                    .fold(0.0, f64::max);
                let far = match self.srd.exchange() {
                    None => far,
                    Some(comm) => {
                        let mut all = Vec::new();
                        comm.all_gather_same(&[far], &mut all);
                        all.into_iter().fold(0.0, f64::max)
                    }
                };
                if far > r * r * (1.0 + 1e-9) {
                    return Ok(Some(format!(
                        "a solvent particle is outside the droplet at collision {c} (|x| = {:.6}, R = {r:.6})",
                        far.sqrt()
                    )));
                }
            }
            self.acc.rows.push(DropletRow {
                collision: c,
                radius: r,
                solvent: self.srd.particles() as u64,
                expected: self.expected(c),
                removed: self.acc.removed,
                bounced,
                temperature: self.srd.temperature(),
                colloid_temperature: self
                    .colloids
                    .as_ref()
                    .map_or(f64::NAN, |c| c.com_temperature()),
            });
            if let (Some(log), Some(row)) = (self.thermo_log.as_mut(), self.acc.rows.last()) {
                log.append(&row.values(p.solvent.srd.tau))
                    .map_err(|e| crate::method::fail_alone_over(self.srd.exchange(), e.into()))?;
            }
        }
        if p.trajectory_every > 0 && c.is_multiple_of(p.trajectory_every) {
            // Every rank takes part in gathering the solvent; the writer writes.
            let solvent = (self.colloids.is_none() || p.trajectory_solvent).then(|| {
                let (pos, vel) = self.srd.gathered_state();
                let fixed = *self.srd.fixed_point();
                (pos.iter().map(|x| fixed.decode(*x)).collect(), vel)
            });
            if let Some(w) = self.gsd.as_mut() {
                let log = [("radius", r)];
                let written = match (&self.colloids, solvent) {
                    (Some(col), solvent) => colloid_frame(w, &self.srd, col, solvent, &log),
                    (None, Some((pos, vel))) => solvent_frame(w, &self.srd, pos, vel, &log),
                    (None, None) => unreachable!("a frame without colloids has the solvent"),
                };
                written.map_err(|e| crate::method::fail_alone_over(self.srd.exchange(), e))?;
            }
            self.acc.frames += 1;
        }
        Ok(None)
    }
}

impl Session for DropletSession {
    fn label(&self) -> String {
        "droplet-mpcd".into()
    }

    fn total(&self) -> u64 {
        self.p.collisions
    }

    fn position(&self) -> u64 {
        self.srd.step()
    }

    fn seed(&self) -> u64 {
        self.p.seed as u64
    }

    fn status(&self) -> String {
        let t = self.srd.step() as f64 * self.p.solvent.srd.tau;
        let mut s = format!("t = {}", crate::driver::significant(t));
        if let Some(r) = self.acc.rows.last() {
            s.push_str(&format!(", R = {:.4}, T = {:.4}", r.radius, r.temperature));
        }
        s
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::to_value(&self.p).unwrap_or_default()
    }

    fn writes(&self, name: &str) -> bool {
        [
            "thermo.csv",
            "solvent_profiles.csv",
            "solvent_density.png",
            "solvent_velocity.png",
            "profiles.png",
            "trajectory.gsd",
        ]
        .contains(&name)
            || name
                .strip_prefix("profile_")
                .and_then(|r| r.strip_suffix(".csv"))
                .is_some_and(|f| f.parse::<f64>().is_ok())
    }

    fn begin(&mut self, out: &OutputDir, fresh: bool) -> Result<()> {
        if DropletSession::is_writer(self) {
            self.gsd = open_trajectory(out, self.p.trajectory_every, fresh)?;
            self.thermo_log = Some(CsvLog::start(
                out.join("thermo.csv"),
                &DROPLET_THERMO,
                fresh,
                || thermo_rows(self.p.solvent.srd.tau, &self.acc.rows),
            )?);
        }
        if fresh && let Some(why) = self.record(0, 0)? {
            bail!("{why}");
        }
        self.now = (self.srd.particles(), self.srd.temperature());
        Ok(())
    }

    fn next_checkpoint(&self) -> Option<u64> {
        tenth_after(self.position(), self.p.collisions)
    }

    fn exchange(&self) -> Option<&dyn Exchange> {
        self.srd.exchange()
    }

    fn advance(&mut self, until: u64) -> Result<Option<String>> {
        let stopped = self.advance_to(until)?;
        self.now = (self.srd.particles(), self.srd.temperature());
        Ok(stopped)
    }
    fn flush(&mut self) -> Result<()> {
        if let Some(w) = self.gsd.as_mut() {
            w.sync()?;
        }
        Ok(())
    }

    fn save(&mut self, out: &OutputDir) -> Result<Vec<u8>> {
        if self.p.trajectory_every > 0 && DropletSession::is_writer(self) {
            let extended = self.flush().and_then(|_| {
                self.acc
                    .digest
                    .extend(&out.join("trajectory.gsd"), self.acc.frames)
            });
            extended.map_err(|e| crate::method::fail_alone_over(self.srd.exchange(), e))?;
        }
        Ok(bincode::serialize(&DropletSaved {
            solvent: SolventState::gathered(&self.srd),
            colloids: self.colloids.as_ref().map(|c| c.state()),
            acc: self.acc.clone(),
        })?)
    }

    fn interim_outputs(&mut self, out: &OutputDir) -> Result<Vec<String>> {
        if !DropletSession::is_writer(self) {
            return Ok(Vec::new());
        }
        write_thermo(out, self.p.solvent.srd.tau, &self.acc.rows)?;
        Ok(vec!["thermo.csv".into()])
    }

    fn finish(
        mut self: Box<Self>,
        out: &OutputDir,
        wall_s: f64,
        failure: Option<&str>,
    ) -> Result<Finished> {
        if !DropletSession::is_writer(&self) {
            return Ok(Finished::nothing_written());
        }
        self.flush()?;
        let (solvent_final, temperature_final) = self.now;
        let p = &self.p;
        let tau = p.solvent.srd.tau;
        let n0 = p.solvent.number_density;
        let mut files = Vec::new();
        let mut warnings = Vec::new();
        write_thermo(out, p.solvent.srd.tau, &self.acc.rows)?;
        files.push("thermo.csv".into());
        let collisions = self.srd.step();
        let boundary = match p.boundary {
            Boundary::None => "none",
            Boundary::Slip => "slip",
            Boundary::NoSlip => "no-slip",
        };
        // The colloid profiles, on droplet-bd's file names and columns.
        let cp = &self.acc.colloid_profiles;
        if self.colloids.is_some() {
            let mut labels = Vec::new();
            let mut xs = Vec::new();
            let mut drawn = Vec::new();
            for j in (0..cp.taken.len()).filter(|&j| cp.taken[j]) {
                let name = crate::theory_droplet::profile_name(p.profile.fractions[j]);
                out.write_table(&name, &[("r", &cp.r[j]), ("phi", &cp.phi[j])])?;
                files.push(name);
                labels.push(format!(
                    "t = {:.0} % (R = {:.2})",
                    p.profile.fractions[j] * 100.0,
                    cp.radius[j]
                ));
                // The picture merges the small inner shells (plot::merged_shells).
                let vp = std::f64::consts::PI / 6.0 * p.diameter.powi(3);
                let (x, y) = merged_shells(&cp.r[j], &cp.phi[j], vp, 1.0, SHELL_PARTICLES);
                xs.push((x.iter().map(|x| x / cp.radius[j]).collect::<Vec<f64>>(), y));
                drawn.push(j);
            }
            let series: Vec<Series> = drawn
                .iter()
                .enumerate()
                .map(|(k, _)| Series {
                    label: &labels[k],
                    x: &xs[k].0,
                    y: &xs[k].1,
                    points: false,
                })
                .collect();
            picture(
                line_plot_styled(
                    &out.join("profiles.png"),
                    &format!(
                        "Drying droplet, MPCD ({boundary}): N = {}, Pe = {}",
                        p.particles, p.peclet
                    ),
                    "r / R(t) (inner shells merged to >= 10 particles)",
                    "volume fraction phi(r)",
                    &series,
                    &[],
                    Scale::Linear,
                    Style {
                        legend_outside: true,
                    },
                ),
                "profiles.png",
                &mut files,
                &mut warnings,
            );
        }
        // The solvent profiles taken (complete windows only).
        let mut cols: [Vec<f64>; 9] = Default::default();
        let mut curves: Vec<Curve> = Vec::new();
        let mut uniformity = Vec::new();
        for (j, prof) in self.acc.profiles.iter().enumerate() {
            let cf = p.profile_collisions[j];
            if cf > collisions || prof.total_samples() == 0 {
                continue;
            }
            let f = p.profile.fractions[j];
            let (rows, rho) = prof.table();
            let (mut x, mut dens, mut vr) = (Vec::new(), Vec::new(), Vec::new());
            let (mut worst, mut chi2, mut dof) = (f64::NAN, 0.0, 0usize);
            for row in &rows {
                let [xr, n, ne, v, ve] = *row;
                for (c, val) in cols.iter_mut().zip([
                    f,
                    cf as f64 * tau,
                    prof.mean_radius(),
                    xr,
                    n,
                    ne,
                    v,
                    ve,
                    prof.total_samples() as f64,
                ]) {
                    c.push(val);
                }
                x.push(xr);
                dens.push(n / n0);
                vr.push(v);
                if ne.is_finite() && ne > 0.0 {
                    worst = (n / n0 - 1.0)
                        .abs()
                        .max(if worst.is_nan() { 0.0 } else { worst });
                    chi2 += ((n - n0) / ne).powi(2);
                    dof += 1;
                }
            }
            uniformity.push(json!({
                "fraction": f,
                "collision": cf,
                "samples": prof.total_samples(),
                "max_relative_density_deviation": if worst.is_nan() { serde_json::Value::Null } else { json!(worst) },
                "chi2_uniform": chi2,
                "bins_with_errors": dof,
                "block_correlation": rho,
            }));
            if rho > 0.5 {
                warnings.push(format!(
                    "solvent profile at {:.0} %: consecutive blocks correlated (rho = {rho:.2}); its errors are widened for it, but a longer observe.solvent.window gives more honest ones",
                    f * 100.0
                ));
            }
            curves.push((format!("t = {:.0} %", f * 100.0), x, dens, vr));
        }
        if !cols[0].is_empty() {
            let names = [
                "fraction",
                "time",
                "radius",
                "r_over_R",
                "density",
                "density_err",
                "radial_velocity",
                "radial_velocity_err",
                "samples",
            ];
            let table: Vec<(&str, &[f64])> = names
                .iter()
                .zip(cols.iter())
                .map(|(n, c)| (*n, c.as_slice()))
                .collect();
            out.write_table("solvent_profiles.csv", &table)?;
            files.push("solvent_profiles.csv".into());
            for (name, ylabel, pick) in [
                ("solvent_density.png", "solvent density n(r) / n0", 2usize),
                (
                    "solvent_velocity.png",
                    "mean radial velocity <v_r> sqrt(m / kT)",
                    3,
                ),
            ] {
                let series: Vec<Series> = curves
                    .iter()
                    .map(|(l, x, d, v)| Series {
                        label: l,
                        x,
                        y: if pick == 2 { d } else { v },
                        points: true,
                    })
                    .collect();
                picture(
                    line_plot(
                        &out.join(name),
                        &format!(
                            "Drying MPCD droplet, boundary {boundary}: R0 = {:.2}, Pe = {}",
                            p.r0, p.peclet
                        ),
                        "r / R(t)",
                        ylabel,
                        &series,
                        Scale::Linear,
                    ),
                    name,
                    &mut files,
                    &mut warnings,
                );
            }
        }
        if self.acc.frames > 0 {
            files.push("trajectory.gsd".into());
        }
        let t = collisions as f64 * tau;
        let r = p.law().radius(t);
        let expected = self.expected(collisions);
        let colloids = self.colloids.as_ref().map(|c| {
            json!({
                "particles": c.len(),
                "final_mean_volume_fraction": p.particles as f64 * p.diameter.powi(3) / (8.0 * r.powi(3)),
                "max_excursion_beyond_wall": cp.max_excursion,
                "centres_beyond_R_at_end": cp.outside_final,
                "temperature_centre_of_mass": c.com_temperature(),
                "temperature_all_particles": c.temperature(),
                "bond_strain_rms": c.bond_strain_rms(),
                "stokes_einstein_d0": p.d0,
            })
        });
        let mut summary = json!({
            "colloids": colloids,
            "software": crate::software(),
            "method": "droplet-mpcd",
            "seed": p.seed,
            "parameters": p,
            "units": "MPCD: lengths in the cell edge a, masses in the solvent mass m, energies in kT, times in a sqrt(m / kT)",
            "collisions": collisions,
            "time": t,
            "final_radius": r,
            "wall_speed_at_end": -p.alpha / (8.0 * PI * r),
            "solvent": {
                "initial": self.acc.solvent0,
                "final": solvent_final,
                "expected_final": expected,
                "removed": self.acc.removed,
                "residual_excess_max": self.acc.residual_max,
                "residual_excess_last": self.acc.residual_last,
                "bounced": self.acc.bounced,
                "reflections": self.acc.reflections,
                "stuck": self.acc.stuck,
                "virtual_particles_per_collision": self.acc.virtual_particles as f64 / collisions.max(1) as f64,
                "temperature_final": temperature_final,
            },
            "solvent_uniformity": uniformity,
            "wall_seconds": wall_s,
            "particle_updates_per_second": collisions as f64 * solvent_final as f64 / wall_s.max(1e-9),
            "threads": rayon::current_num_threads(),
            "trajectory_frames": self.acc.frames,
            "warnings": warnings,
        });
        if self.srd.rank().1 > 1 {
            summary["ranks"] = json!(self.srd.rank().1);
        }
        let message = match failure {
            Some(f) => format!("droplet-mpcd stopped at collision {collisions}: {f}"),
            None => format!(
                "droplet-mpcd: {collisions} collisions, R {:.3} -> {r:.3}; solvent {} -> {} (expected {expected}, {} removed)",
                p.r0, self.acc.solvent0, solvent_final, self.acc.removed
            ),
        };
        Ok(Finished {
            summary,
            files,
            message,
            warnings,
        })
    }
}

/// One solvent profile drawn: label, r/R, n/n0, <v_r>.
type Curve = (String, Vec<f64>, Vec<f64>, Vec<f64>);

/// The columns of a drying run's `thermo.csv`.
const DROPLET_THERMO: [&str; 9] = [
    "collision",
    "time",
    "radius",
    "solvent",
    "expected",
    "removed",
    "bounced",
    "temperature",
    "colloid_temperature",
];

impl ThermoRow for DropletRow {
    const COLUMNS: &'static [&'static str] = &DROPLET_THERMO;
    fn values(&self, tau: f64) -> Vec<f64> {
        vec![
            self.collision as f64,
            self.collision as f64 * tau,
            self.radius,
            self.solvent as f64,
            self.expected as f64,
            self.removed as f64,
            self.bounced as f64,
            self.temperature,
            self.colloid_temperature,
        ]
    }
}

// ------------------------------------------------------------------------------------------
// An engine a script steps by hand.

/// The solvent stepped by hand: one step is one streaming step, the removal of the excess
/// solvent of a confined droplet, and one collision (the bulk's viscosity drive acts, the
/// measurement's rescaling without the cell thermostat does not).
struct SolventEngine {
    srd: Srd,
    /// The discrete-particle colloids, if any.
    colloids: Option<DiscreteColloids>,
    /// The droplet's interface on the colloid centres (droplet-mpcd).
    interface: Option<colloidsim_md::potential::HarmonicInterface>,
    method: &'static str,
    conf: Confinement,
    drive: Acceleration,
    scratch: Vec<(u32, u32)>,
}

impl crate::Engine for SolventEngine {
    fn method(&self) -> &str {
        self.method
    }
    fn dimensions(&self) -> usize {
        3
    }
    fn particles(&self) -> usize {
        self.srd.len()
            + self
                .colloids
                .as_ref()
                .map_or(0, |c| c.len() * (1 + VERTICES))
    }
    fn step(&mut self, steps: u64) -> Result<()> {
        let tau = self.srd.params().tau;
        for _ in 0..steps {
            let t = (self.srd.step() + 1) as f64 * tau;
            let step = self.srd.step();
            self.srd.stream(t, &self.conf, &self.drive)?;
            if let Some(col) = self.colloids.as_mut() {
                match &self.interface {
                    Some(h) => col.advance(t - tau, tau, h)?,
                    None => col.advance(t - tau, tau, &colloidsim_md::NoExternal)?,
                }
            }
            if !matches!(self.conf, Confinement::None) {
                let l = self.srd.sbox().l;
                let n = self.srd.params().density / self.srd.params().cell.powi(3);
                let expected = (n * self.conf.volume(t, l)).round() as usize;
                remove_excess(&mut self.srd, expected, step, &mut self.scratch);
            }
            let emb = self.colloids.as_mut().map(|c| c.embedded());
            self.srd.collide(t, &self.conf, emb);
        }
        Ok(())
    }
    fn steps(&self) -> u64 {
        self.srd.step()
    }
    fn time(&self) -> f64 {
        self.srd.step() as f64 * self.srd.params().tau
    }
    fn dt(&self) -> f64 {
        self.srd.params().tau
    }
    /// The solvent's, then the colloids' centres (unwrapped), then their vertices.
    fn positions(&self) -> Vec<f64> {
        let mut x = self.srd.positions();
        if let Some(c) = &self.colloids {
            x.extend(c.unwrapped_centres());
            let (centres, unwrapped) = (c.centre_positions(), c.unwrapped_centres());
            for (k, v) in c.vertex_positions().iter().enumerate() {
                let (a, b) = (centres[k / VERTICES], unwrapped[k / VERTICES]);
                x.push(std::array::from_fn(|i| v[i] - a[i] + b[i]));
            }
        }
        crate::engine::flat(&x)
    }
    fn velocities(&self) -> Option<Vec<f64>> {
        let mut v = self.srd.velocities();
        if let Some(c) = &self.colloids {
            v.extend_from_slice(c.centre_velocities());
            v.extend_from_slice(c.vertex_velocities());
        }
        Some(crate::engine::flat(&v))
    }
    /// Zero on the solvent (it streams freely between collisions); on the colloids' particles
    /// the bonds, the WCA between centres and the droplet's interface.
    fn forces(&self) -> Result<Vec<f64>> {
        let mut f = vec![[0.0; 3]; self.srd.len()];
        if let Some(c) = &self.colloids {
            let t = self.time();
            f.extend(match &self.interface {
                Some(h) => c.forces_at(t, h),
                None => c.forces_at(t, &colloidsim_md::NoExternal),
            });
        }
        Ok(crate::engine::flat(&f))
    }
    fn box_lengths(&self) -> Vec<f64> {
        self.srd.sbox().l.to_vec()
    }
}
