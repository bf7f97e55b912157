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
use crate::method::{Checked, Finished, Headline, Method, Session};
use crate::output::plot::{Scale, Series, line_plot, picture};
use crate::output::trajectory::FrameDigest;
use anyhow::{Context, Result, bail};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::{CsvLog, OutputDir};
use colloidsim_md::mpcd::colloid::{ColloidState, DiscreteColloids, Region};
use colloidsim_md::mpcd::measure::{BlockAverage, PoiseuilleProbe};
use colloidsim_md::mpcd::{Acceleration, Confinement, Srd};
use colloidsim_particles::SimBox;
use colloidsim_particles::gsd::GsdWriter;
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::f64::consts::PI;

pub mod common;
#[rustfmt::skip] // declarations laid out as a table, one key to a line or three
pub mod keys;
pub mod params;

use common::*;
use params::BulkRun;

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

// Bulk solvent.

/// The bulk SRD solvent (`method = "mpcd"`).
pub struct MpcdBulk;

fn resolve_bulk(src: &Source, seed: Option<u64>) -> Result<BulkRun> {
    params::read(&src.table()?, seed).with_context(|| src.label())
}

fn build_bulk(p: &BulkRun) -> Result<Srd> {
    new_solvent(p.solvent.srd, p.box_edge, &Confinement::None, None)
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

/// Bulk MPCD's headline observables (summary.json).
const HEADLINE: &[Headline] = &[
    Headline {
        name: "viscosity",
        path: "viscosity.value",
        labels: None,
        unit: "sqrt(m kT)/a^2",
        doc: "solvent viscosity from periodic Poiseuille flow (viscosity)",
        absent: "not measured: no Poiseuille drive (the viscosity key)",
    },
    Headline {
        name: "D",
        path: "colloid_diffusion.value",
        labels: None,
        unit: "a sqrt(kT/m)",
        doc: "colloid self-diffusion coefficient, Green-Kubo of the centre-of-mass velocities \
              (colloid_diffusion)",
        absent: "not measured: no colloids (or no velocity autocorrelation observed)",
    },
];

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

    fn headline(&self) -> &'static [Headline] {
        HEADLINE
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
        keys::KEYS
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
            .restore(&out.join("trajectory.gsd"))
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
                && let Err(e) = col.advance(t - tau, tau, &colloidsim_particles::NoExternal)
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
            if self.p.colloids == 0 {
                out.explain("thermo.csv", "colloid_temperature", "no colloids");
            }
            self.gsd = open_trajectory(out, self.p.trajectory_every, fresh)?;
            self.thermo_log = Some(CsvLog::start_in(
                out,
                "thermo.csv",
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
