//! Hard-sphere Monte Carlo (`method = "hs-mc"`, crate `colloidsim-mc`): a warm-up that tunes
//! the move size, then sampling sweeps with delta frozen; in bulk g(r), the contact value and
//! the compressibility factor with block-average errors; in a droplet the radial volume-fraction
//! profile on droplet-bd's file names (and, with a hard wall, the exact virial sum rule at the
//! wall). A mixture (`[system.species]`) adds each species' profile, its partial contact values
//! and the virial Z beside BMCSL (docs/mc.md, "Mixtures"). A pair interaction (`[pair]`)
//! replaces the hard cores: Z and the wall's sum rule from the pair virial, the mean pair energy
//! (docs/mc.md, "Pair interactions"). Checkpoints hold the positions
//! exactly: a restart continues bitwise.

use crate::checkpoint::Envelope;
#[rustfmt::skip] // declarations laid out as a table, one key to a line or three
pub mod keys;
pub mod params;

use crate::engine::flat;
use crate::keys::Spec;
use crate::method::{Checked, Finished, Headline, Method, Session};
use crate::output::plot::{
    Scale, Series, Style, line_plot, line_plot_styled, line_plot_with_errors, picture,
};
use crate::output::trajectory::FrameDigest;
use crate::{Scenario as Source, seed32};
use anyhow::{Context, Result, bail};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::OutputDir;
use colloidsim_mc::observe::{
    CONTACT_BINS, CONTACT_WINDOW, PairDensity, PairHistogram, PartialContacts, RadialHistogram,
    bmcsl, bulk_contact, carnahan_starling, carnahan_starling_contact, compressibility,
    contact_pairs, mean_and_error, wall_contact_density,
};
use colloidsim_mc::params::McRun;
use colloidsim_mc::{ChainStats, HardSphereMc, McError, SweepStats};
use colloidsim_particles::gsd::{self, GsdWriter};
use colloidsim_particles::{Particles, SimBox};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::f64::consts::PI;

/// Hard-sphere Monte Carlo scenarios.
pub struct HsMc;

/// Read and check a scenario (`system.initial` relative to the scenario's folder), with `seed`
/// replacing the scenario's.
fn resolve(src: &Source, seed: Option<u64>) -> Result<McRun> {
    if let Some(s) = seed {
        seed32(s)?;
    }
    params::read(&src.table()?, src.base(), seed).with_context(|| src.label())
}

/// The engine at the start: the last frame of `system.initial`, or an FCC lattice.
fn build(p: &McRun) -> Result<HardSphereMc> {
    let positions = match &p.initial {
        Some(path) => {
            let f = gsd::read_frame(path, None)
                .with_context(|| format!("{}: {}", keys::SYSTEM_INITIAL.path, path.display()))?;
            if let Some(m) = &p.mixture
                && f.particles.typeid != m.typeids()
            {
                bail!(colloidsim_core::ParamError::new(
                    keys::SYSTEM_INITIAL.path,
                    format!(
                        "{}: its typeids must be the species of system.species in order, {:?} spheres of typeid 0, 1, ... (the particles stored species by species)",
                        path.display(),
                        m.counts
                    ),
                ));
            }
            Some(f.particles.pos)
        }
        None => None,
    };
    p.engine(positions.as_deref(), keys::SYSTEM_INITIAL.path)
        .map_err(|e| match e {
            McError::Param(e) => params::keyed(e).into(),
            e => e.into(),
        })
}

/// Hard-sphere MC's headline observables (summary.json).
const HEADLINE: &[Headline] = &[
    Headline {
        name: "Z",
        path: "compressibility.value",
        labels: None,
        unit: "-",
        doc: "compressibility factor Z = P / (rho kT), from the contact value (from the \
              event chains' pressure with mc.chain_length; from the pair virial with [pair])",
        absent: "measured in the bulk only (system.geometry = \"bulk\")",
    },
    Headline {
        name: "contact_g",
        path: "contact_value.value",
        labels: None,
        unit: "-",
        doc: "contact value g(d+) of the pair correlation",
        absent: "measured in a one-component bulk only (system.geometry = \"bulk\"; a \
                 mixture's are per pair, contact_values)",
    },
];

impl Method for HsMc {
    fn names(&self) -> &'static [&'static str] {
        &["hs-mc"]
    }

    fn about(&self) -> &'static str {
        "hard-sphere Monte Carlo (NVT, checkerboard cells) in bulk, in a hard spherical wall or in the BD droplet's interface"
    }

    fn docs(&self) -> &'static str {
        "docs/mc.md"
    }

    fn headline(&self) -> &'static [Headline] {
        HEADLINE
    }

    fn check(&self, src: &Source) -> Result<Checked> {
        let p = resolve(src, None)?;
        build(&p).with_context(|| src.label())?;
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
        crate::method::on_one_rank(comm, src, self.names()[0])?;
        let p = resolve(src, seed)?;
        let mc = build(&p).with_context(|| src.label())?;
        let acc = Accum::new(&p, &mc);
        Ok(Box::new(McSession::new(p, mc, acc)))
    }

    fn restore(
        &self,
        src: &Source,
        seed: u64,
        out: &OutputDir,
        envelope: &Envelope,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Box<dyn Session>> {
        crate::method::on_one_rank(comm, src, self.names()[0])?;
        let p = resolve(src, Some(seed))?;
        let saved: Saved = crate::checkpoint::decode_payload(&envelope.payload)?;
        if saved.pos.iter().any(|c| c.len() != p.particles)
            || saved.acc.blocks.len() != p.blocks
            || saved.acc.chains.len()
                != if p.chain_length.is_some() {
                    p.blocks
                } else {
                    0
                }
        {
            bail!("checkpoint: its state does not fit the scenario");
        }
        let rows: Vec<[f64; 3]> = (0..p.particles)
            .map(|i| [saved.pos[0][i], saved.pos[1][i], saved.pos[2][i]])
            .collect();
        let mut mc = p.engine(Some(&rows), "checkpoint.bin")?;
        mc.restore(saved.pos, saved.sweeps, saved.delta);
        if p.trajectory_every > 0 {
            saved.acc.digest.restore(&out.join("trajectory.gsd"))?;
        }
        Ok(Box::new(McSession::new(p, mc, saved.acc)))
    }

    fn keys(&self) -> &'static [Spec] {
        keys::KEYS
    }

    fn engine(&self, src: &Source, seed: Option<u64>) -> Result<Box<dyn crate::Engine>> {
        let p = resolve(src, seed)?;
        Ok(Box::new(McEngine {
            mc: build(&p)?,
            run: p,
        }))
    }
}

/// One block of the sampling sweeps: its histograms.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Block {
    /// Pair distances next to contact.
    contact: PairHistogram,
    /// g(r) (bulk).
    gr: Option<PairHistogram>,
    /// Centre distances from the droplet centre over [0, R] (droplets).
    profile: Option<RadialHistogram>,
    /// Centre distances next to the hard wall (hard wall).
    wall: Option<RadialHistogram>,
    /// The two-body density and the one-body density on its radial bins (droplets, optional).
    rho2: Option<(PairDensity, RadialHistogram)>,
    /// Each species' centre distances over [0, R] (droplets of a mixture).
    #[serde(default)]
    species: Option<Vec<RadialHistogram>>,
    /// Pair distances next to contact of every pair of species (mixtures).
    #[serde(default)]
    partial: Option<PartialContacts>,
    /// Each species' centre distances next to its own wall `R - d_s/2` (hard wall, mixtures).
    #[serde(default)]
    species_wall: Option<Vec<RadialHistogram>>,
    /// The sum over the samples of the volume fraction by sphere-shell overlap on the
    /// profile's shells, and the samples (droplets; `None` when continued from a checkpoint
    /// written without it).
    #[serde(default)]
    overlap: Option<(Vec<f64>, u64)>,
    /// The pair energy and virial summed over the samples (with `[pair]`).
    #[serde(default)]
    pair: Option<PairSums>,
}

/// Sums over a block's samples of the pair energy `U` and the pair virial
/// `W = sum_{i<j} r_ij F(r_ij)`.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
struct PairSums {
    energy: f64,
    virial: f64,
    samples: u64,
}

impl PairSums {
    /// The block's mean `(U, W)` (NaN without samples).
    fn means(&self) -> (f64, f64) {
        let k = self.samples as f64;
        (self.energy / k, self.virial / k)
    }
}

/// Everything a run accumulates, saved in every checkpoint.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Accum {
    /// Counts of the current tuning window (warm-up).
    window: SweepStats,
    /// Counts of the sampling sweeps.
    sampling: SweepStats,
    /// Delta at the end of the warm-up (frozen).
    frozen_delta: Option<f64>,
    blocks: Vec<Block>,
    /// Frames in trajectory.gsd and their CRC-32.
    frames: u64,
    digest: FrameDigest,
    /// Event chains: the counts of the sampling sweeps of each block (empty with local moves).
    #[serde(default)]
    chains: Vec<ChainStats>,
}

impl Accum {
    fn new(p: &McRun, mc: &HardSphereMc) -> Self {
        let d = p.diameter;
        let contact_max = d * (1.0 + CONTACT_WINDOW);
        let rc = mc.geometry().confinement(d);
        let block = Block {
            contact: PairHistogram::new(d, contact_max, CONTACT_BINS),
            gr: p
                .is_bulk()
                .then(|| PairHistogram::new(0.0, p.gr_max, p.gr_bins)),
            profile: p
                .radius
                .map(|r| RadialHistogram::new(0.0, r, p.profile_bins)),
            overlap: p.radius.map(|_| (vec![0.0; p.profile_bins], 0)),
            wall: (p.geometry == "hard-wall")
                .then(|| {
                    rc.map(|rc| RadialHistogram::new(rc - CONTACT_WINDOW * d, rc, CONTACT_BINS))
                })
                .flatten(),
            rho2: p.radius.zip(p.rho2_bins).map(|(r, (nr, nc))| {
                (
                    PairDensity::new(r, nr, nc),
                    RadialHistogram::new(0.0, r, nr),
                )
            }),
            species: p
                .mixture
                .as_ref()
                .zip(p.radius)
                .map(|(m, r)| vec![RadialHistogram::new(0.0, r, p.profile_bins); m.len()]),
            partial: p.mixture.as_ref().map(|_| PartialContacts::new(mc)),
            pair: p.pair.as_ref().map(|_| PairSums::default()),
            species_wall: p
                .mixture
                .as_ref()
                .filter(|_| p.geometry == "hard-wall")
                .map(|m| {
                    m.diameters
                        .iter()
                        .map(|&ds| {
                            let c = mc.geometry().confinement_of(ds, d).unwrap_or(0.0);
                            RadialHistogram::new(c - CONTACT_WINDOW * ds, c, CONTACT_BINS)
                        })
                        .collect()
                }),
        };
        Self {
            window: SweepStats::default(),
            sampling: SweepStats::default(),
            frozen_delta: None,
            blocks: vec![block; p.blocks],
            frames: 0,
            digest: FrameDigest::default(),
            chains: if p.chain_length.is_some() {
                vec![ChainStats::default(); p.blocks]
            } else {
                Vec::new()
            },
        }
    }
}

/// The method's part of `checkpoint.bin`: the exact positions, sweeps, delta and accumulators.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Saved {
    sweeps: u64,
    delta: f64,
    pos: [Vec<f64>; 3],
    acc: Accum,
}

/// A Monte Carlo run: warm-up sweeps, then sampling sweeps.
struct McSession {
    p: McRun,
    mc: HardSphereMc,
    acc: Accum,
    gsd: Option<GsdWriter>,
    traj: Option<std::path::PathBuf>,
}

impl McSession {
    fn new(p: McRun, mc: HardSphereMc, acc: Accum) -> Self {
        Self {
            p,
            mc,
            acc,
            gsd: None,
            traj: None,
        }
    }

    fn total(&self) -> u64 {
        self.p.warmup_sweeps + self.p.sweeps
    }

    /// Observations after `sweep` sweeps: samples of the sampling part, trajectory frames.
    fn record(&mut self, sweep: u64) -> Result<()> {
        let p = &self.p;
        if sweep > p.warmup_sweeps && (sweep - p.warmup_sweeps - 1).is_multiple_of(p.sample_every) {
            // Sample k of the sampling part belongs to block k * blocks / sweeps.
            let k = sweep - p.warmup_sweeps - 1;
            let b = ((k as u128 * p.blocks as u128) / p.sweeps as u128) as usize;
            self.mc.bin();
            let block = &mut self.acc.blocks[b.min(p.blocks - 1)];
            block.contact.sample(&self.mc);
            if let Some(h) = block.gr.as_mut() {
                h.sample(&self.mc);
            }
            if let Some(h) = block.profile.as_mut() {
                h.sample(&self.mc);
            }
            if let (Some((sum, n)), Some(r)) = (block.overlap.as_mut(), p.radius) {
                let mc = &self.mc;
                let d = mc.diameters();
                let pos: Vec<[f64; 3]> = (0..mc.len()).map(|i| mc.position(i)).collect();
                let dia: Vec<f64> = mc.types().iter().map(|&t| d[t as usize]).collect();
                let o = colloidsim_analysis::overlap_profile(&pos, &dia, [0.0; 3], r, sum.len());
                sum.iter_mut().zip(o).for_each(|(s, v)| *s += v);
                *n += 1;
            }
            if let Some(h) = block.wall.as_mut() {
                h.sample(&self.mc);
            }
            if let Some((h, rho)) = block.rho2.as_mut() {
                h.sample(&self.mc);
                rho.sample(&self.mc);
            }
            for (s, h) in block.species.iter_mut().flatten().enumerate() {
                h.sample_species(&self.mc, s as u32);
            }
            for (s, h) in block.species_wall.iter_mut().flatten().enumerate() {
                h.sample_species(&self.mc, s as u32);
            }
            if let Some(h) = block.partial.as_mut() {
                h.sample(&self.mc);
            }
            if let (Some(s), Some((u, w))) = (block.pair.as_mut(), self.mc.pair_energy_and_virial())
            {
                s.energy += u;
                s.virial += w;
                s.samples += 1;
            }
        }
        if let Some(w) = self.gsd.as_mut()
            && sweep.is_multiple_of(p.trajectory_every)
        {
            let pos: Vec<[f64; 3]> = (0..self.mc.len()).map(|i| self.mc.position(i)).collect();
            let particles = match &p.mixture {
                Some(m) => m.particles(pos),
                None => Particles::monodisperse(pos, p.diameter),
            };
            w.write_frame(
                sweep,
                &SimBox::cube(self.mc.box_edge()),
                &particles,
                false,
                &[],
            )?;
            self.acc.frames += 1;
        }
        Ok(())
    }
}

impl Session for McSession {
    fn label(&self) -> String {
        "hs-mc".into()
    }

    fn total(&self) -> u64 {
        McSession::total(self)
    }

    fn position(&self) -> u64 {
        self.mc.sweeps()
    }

    fn seed(&self) -> u64 {
        self.p.seed as u64
    }

    fn parameters(&self) -> serde_json::Value {
        serde_json::to_value(&self.p).unwrap_or_default()
    }

    fn writes(&self, name: &str) -> bool {
        [
            "g_r.csv",
            "profile_mean.csv",
            "profiles.png",
            "g_r.png",
            "g2.csv",
            "trajectory.gsd",
            "species_profile_mean.csv",
            "species_profiles.png",
        ]
        .contains(&name)
    }

    fn begin(&mut self, out: &OutputDir, fresh: bool) -> Result<()> {
        let traj = out.join("trajectory.gsd");
        if self.p.trajectory_every > 0 {
            self.gsd = Some(crate::output::trajectory::writer(&traj, !fresh)?);
        }
        self.traj = Some(traj);
        if fresh {
            self.record(0)?;
        }
        Ok(())
    }

    fn next_checkpoint(&self) -> Option<u64> {
        let total = McSession::total(self);
        let every = (total / 10).max(1);
        let next = (self.position() / every + 1) * every;
        (next < total).then_some(next)
    }

    fn advance(&mut self, until: u64) -> Result<Option<String>> {
        let p = self.p.clone();
        while self.mc.sweeps() < until.min(self.total()) {
            let s = self.mc.sweep();
            let done = self.mc.sweeps();
            if p.chain_length.is_some() {
                // Event chains: nothing to tune; the sampling sweeps' chains go to their block.
                if done > p.warmup_sweeps {
                    let k = done - p.warmup_sweeps - 1;
                    let b = ((k as u128 * p.blocks as u128) / p.sweeps as u128) as usize;
                    self.acc.chains[b.min(p.blocks - 1)] += self.mc.last_chains();
                }
            } else if done <= p.warmup_sweeps {
                self.acc.window += s;
                if done.is_multiple_of(p.tune_every) {
                    self.mc
                        .tune(self.acc.window.acceptance(), p.target_acceptance);
                    self.acc.window = SweepStats::default();
                }
                if done == p.warmup_sweeps {
                    self.acc.frozen_delta = Some(self.mc.delta());
                }
            } else {
                self.acc.sampling += s;
            }
            self.record(done)?;
        }
        Ok(None)
    }

    fn flush(&mut self) -> Result<()> {
        if let Some(w) = self.gsd.as_mut() {
            w.sync()?;
        }
        Ok(())
    }

    fn save(&mut self, out: &OutputDir) -> Result<Vec<u8>> {
        if self.p.trajectory_every > 0 {
            self.flush()?;
            self.acc
                .digest
                .extend(&out.join("trajectory.gsd"), self.acc.frames)?;
        }
        let [x, y, z] = self.mc.positions();
        let saved = Saved {
            sweeps: self.mc.sweeps(),
            delta: self.mc.delta(),
            pos: [x.to_vec(), y.to_vec(), z.to_vec()],
            acc: self.acc.clone(),
        };
        Ok(bincode::serialize(&saved)?)
    }

    fn finish(
        mut self: Box<Self>,
        out: &OutputDir,
        wall_s: f64,
        _failure: Option<&str>,
    ) -> Result<Finished> {
        self.flush()?;
        let p = &self.p;
        let d = p.diameter;
        let n = self.mc.len();
        let mut files = Vec::new();
        let mut warnings = Vec::new();
        let blocks: Vec<&Block> = self
            .acc
            .blocks
            .iter()
            .filter(|b| b.contact.samples() > 0)
            .collect();
        let mut summary = json!({
            "software": crate::software(),
            "method": "hs-mc",
            "seed": p.seed,
            "parameters": p,
            "sweeps": self.mc.sweeps(),
            "trial_moves": self.acc.sampling.trials,
            "acceptance": self.acc.sampling.acceptance(),
            "left_cell_fraction": self.acc.sampling.left_cell as f64 / self.acc.sampling.trials.max(1) as f64,
            "delta": self.acc.frozen_delta.unwrap_or(self.mc.delta()),
            "cell_side": self.mc.cell_side(),
            "blocks": blocks.len(),
            "samples": blocks.iter().map(|b| b.contact.samples()).sum::<u64>(),
            "wall_seconds": wall_s,
            "trial_moves_per_second": (self.mc.sweeps() * n as u64) as f64 / wall_s.max(1e-9),
            "threads": rayon::current_num_threads(),
            "trajectory_frames": self.acc.frames,
        });
        let value_error = |v: &[f64]| {
            let (m, e) = mean_and_error(v);
            json!({ "value": m, "standard_error": e })
        };
        // Event chains: their counts instead of the local moves' (no trial moves, no delta).
        let chain_blocks: Vec<&ChainStats> =
            self.acc.chains.iter().filter(|c| c.chains > 0).collect();
        if let (Some(length), Some(obj)) = (p.chain_length, summary.as_object_mut()) {
            for k in [
                "trial_moves",
                "acceptance",
                "left_cell_fraction",
                "delta",
                "trial_moves_per_second",
            ] {
                obj.remove(k);
            }
            let mut total = ChainStats::default();
            for c in &chain_blocks {
                total += **c;
            }
            obj.insert(
                "event_chain".into(),
                json!({
                    "chain_length": length,
                    "chains_per_sweep": self.mc.event_chain().map_or(0, |c| c.chains_per_sweep),
                    "chains": total.chains,
                    "lifts": total.lifts,
                    "lifts_per_chain": total.lifts as f64 / total.chains.max(1) as f64,
                    "reversals": total.reversals,
                }),
            );
            obj.insert(
                "lifts_per_second".into(),
                json!(total.lifts as f64 / wall_s.max(1e-9)),
            );
        }
        if p.is_bulk() {
            let volume = self.mc.box_edge().powi(3);
            if p.pair.is_some() {
                // beta P / rho = 1 + beta W / (3 N) per block.
                let z: Vec<f64> = pair_means(&blocks)
                    .iter()
                    .map(|(_, w)| 1.0 + w / (3.0 * n as f64 * p.kt))
                    .collect();
                summary["compressibility"] = value_error_or(out, "compressibility", &z, NO_PAIR);
                summary["contact_value"] = json!({ "value": null });
                out.explain(
                    "summary.json",
                    "contact_value.value",
                    "no contact with [pair]: the spheres have no hard core (compressibility is from the pair virial)",
                );
            } else if let Some(m) = &p.mixture {
                mixture_bulk(m, &blocks, volume, &mut summary, out);
            } else {
                let contact: Vec<f64> = blocks
                    .iter()
                    .map(|b| bulk_contact(&b.contact, n, volume, d))
                    .collect();
                let z: Vec<f64> = contact
                    .iter()
                    .map(|&g| compressibility(p.volume_fraction, n, g))
                    .collect();
                summary["contact_value"] = value_error(&contact);
                summary["compressibility"] = value_error(&z);
                summary["carnahan_starling"] = json!({
                    "compressibility": carnahan_starling(p.volume_fraction),
                    "contact_value": carnahan_starling_contact(p.volume_fraction),
                });
            }
            if p.chain_length.is_some() {
                // The exact event-chain pressure replaces the contact-value estimate, which is
                // kept beside it.
                let z: Vec<f64> = chain_blocks.iter().map(|c| c.compressibility()).collect();
                let contact = summary["compressibility"].clone();
                summary["compressibility_from_contact"] = contact;
                summary["compressibility"] = value_error_or(
                    out,
                    "compressibility",
                    &z,
                    "no sampling sweep of event chains in some block",
                );
            }
            let per_block: Vec<Vec<f64>> = blocks
                .iter()
                .filter_map(|b| b.gr.as_ref().map(|h| h.pair_correlation(n, volume)))
                .collect();
            if let Some(h) = blocks.first().and_then(|b| b.gr.as_ref()) {
                let r = h.centres();
                let (g, err) = columns(&per_block, r.len());
                out.write_table("g_r.csv", &[("r", &r), ("g", &g), ("err", &err)])?;
                files.push("g_r.csv".into());
                let z = &summary["compressibility"];
                let z = (
                    z["value"].as_f64().unwrap_or(f64::NAN),
                    z["standard_error"].as_f64().unwrap_or(f64::NAN),
                );
                let drawn = if p.mixture.is_some() || p.pair.is_some() {
                    // No one-component hard-sphere reference for the pairs of a mixture or a
                    // pair interaction.
                    let x: Vec<f64> = r.iter().map(|v| v / d).collect();
                    let label = format!("Monte Carlo, Z = {}", value_with_error(z.0, z.1));
                    line_plot_styled(
                        &out.join("g_r.png"),
                        &format!(
                            "{} (all pairs): N = {n}, phi = {:.3}; bars: standard errors over the blocks",
                            spheres(p),
                            p.volume_fraction
                        ),
                        "r / d",
                        "g(r)",
                        &[Series {
                            label: &label,
                            x: &x,
                            y: &g,
                            points: false,
                        }],
                        &[Some(err.as_slice())],
                        Scale::Linear,
                        Style {
                            legend_outside: true,
                        },
                    )
                } else {
                    gr_picture(out, n, p.volume_fraction, d, (&r, &g, &err), z)
                };
                picture(drawn, "g_r.png", &mut files, &mut warnings);
            }
        } else {
            let vol = PI / 6.0 * d.powi(3);
            // A mixture's total volume fraction is the sum of its species'.
            let per_block: Vec<Vec<f64>> = match &p.mixture {
                Some(m) => blocks
                    .iter()
                    .filter_map(|b| b.species.as_ref())
                    .map(|hs| {
                        species_phi(hs, &m.diameters)
                            .iter()
                            .fold(vec![0.0; p.profile_bins], |acc, phi| {
                                acc.iter().zip(phi).map(|(a, b)| a + b).collect()
                            })
                    })
                    .collect(),
                None => blocks
                    .iter()
                    .filter_map(|b| {
                        b.profile
                            .as_ref()
                            .map(|h| h.density().iter().map(|rho| rho * vol).collect())
                    })
                    .collect(),
            };
            if let Some(h) = blocks.first().and_then(|b| b.profile.as_ref()) {
                let r = h.centres();
                let (phi, err) = columns(&per_block, r.len());
                // rho_v: the centre density times the sphere volume (above 1 at a hard wall's
                // contact layer); phi_overlap: the volume fraction by sphere-shell overlap,
                // each with its standard error over the blocks.
                let overlap_blocks: Vec<Vec<f64>> = blocks
                    .iter()
                    .filter_map(|b| b.overlap.as_ref())
                    .filter(|(_, n)| *n > 0)
                    .map(|(s, n)| s.iter().map(|v| v / *n as f64).collect())
                    .collect();
                let overlap = (overlap_blocks.len() == blocks.len())
                    .then(|| columns(&overlap_blocks, r.len()));
                match &overlap {
                    Some((o, oe)) => out.write_table(
                        "profile_mean.csv",
                        &[
                            ("r", &r),
                            ("rho_v", &phi),
                            ("rho_v_err", &err),
                            ("phi_overlap", o),
                            ("phi_overlap_err", oe),
                        ],
                    )?,
                    None => out.write_table(
                        "profile_mean.csv",
                        &[("r", &r), ("rho_v", &phi), ("rho_v_err", &err)],
                    )?,
                };
                files.push("profile_mean.csv".into());
                let ((y, ey), y_label) = match overlap {
                    Some(o) => (o, "volume fraction (sphere-shell overlap)"),
                    None => (
                        (phi, err),
                        "pi d^3 rho / 6 (centre density x sphere volume)",
                    ),
                };
                let radius = p.radius.unwrap_or(1.0);
                let x: Vec<f64> = r.iter().map(|v| v / radius).collect();
                let title = format!(
                    "Static droplet, {} ({}): N = {n}, phi = {:.3}",
                    method_name(p),
                    p.geometry,
                    p.volume_fraction
                );
                let series = [Series {
                    label: "equilibrium (bars: standard error over the blocks)",
                    x: &x,
                    y: &y,
                    points: false,
                }];
                picture(
                    line_plot_with_errors(
                        &out.join("profiles.png"),
                        &title,
                        "r / R",
                        y_label,
                        &series,
                        &[Some(ey.as_slice())],
                        Scale::Linear,
                    ),
                    "profiles.png",
                    &mut files,
                    &mut warnings,
                );
            }
            if let Some((h0, _)) = blocks.first().and_then(|b| b.rho2.as_ref()) {
                // rho2 and g2 = rho2 / (rho(r1) rho(r2)) per block, then mean and error.
                let per_block: Vec<(Vec<f64>, Vec<f64>)> = blocks
                    .iter()
                    .filter_map(|b| b.rho2.as_ref())
                    .map(|(h, rho)| {
                        let r2 = h.rho2();
                        let rho = rho.density();
                        let (nr, nc) = (h.r_bins(), h.cos_bins());
                        let g2 = (0..r2.len())
                            .map(|k| {
                                let (a, b) = (k / (nr * nc), (k / nc) % nr);
                                let den = rho[a] * rho[b];
                                if den > 0.0 { r2[k] / den } else { 0.0 }
                            })
                            .collect();
                        (r2, g2)
                    })
                    .collect();
                let cells = per_block[0].0.len();
                let rho2s: Vec<Vec<f64>> = per_block.iter().map(|b| b.0.clone()).collect();
                let g2s: Vec<Vec<f64>> = per_block.iter().map(|b| b.1.clone()).collect();
                let (rho2, rho2_err) = columns(&rho2s, cells);
                let (g2, g2_err) = columns(&g2s, cells);
                let (rs, cs) = (h0.r_centres(), h0.cos_centres());
                let (nr, nc) = (h0.r_bins(), h0.cos_bins());
                // Eq. 17 on the same grid, at the blocks' mean density of each radial bin.
                let rhos: Vec<Vec<f64>> = blocks
                    .iter()
                    .filter_map(|b| b.rho2.as_ref())
                    .map(|(_, rho)| rho.density())
                    .collect();
                let (rho_mean, _) = columns(&rhos, nr);
                let r_max = p.radius.context("g2 needs a droplet radius")?;
                let eq = crate::two_body::eq17(r_max, nr, nc, d, &rho_mean)?;
                let r1: Vec<f64> = (0..cells).map(|k| rs[k / (nr * nc)]).collect();
                let r2: Vec<f64> = (0..cells).map(|k| rs[(k / nc) % nr]).collect();
                let cos: Vec<f64> = (0..cells).map(|k| cs[k % nc]).collect();
                out.write_table(
                    "g2.csv",
                    &[
                        ("r1", &r1),
                        ("r2", &r2),
                        ("cos_theta", &cos),
                        ("rho2", &rho2),
                        ("rho2_err", &rho2_err),
                        ("g2", &g2),
                        ("g2_err", &g2_err),
                        ("g2_eq17_dilute", &eq.dilute),
                        ("g2_eq17_trokhymchuk", &eq.trokhymchuk),
                    ],
                )?;
                files.push("g2.csv".into());
                picture(
                    draw_g2(out, &rs, &cs, &rho_mean, &g2, &eq, d),
                    "g2.png",
                    &mut files,
                    &mut warnings,
                );
            }
            if let Some(m) = &p.mixture {
                mixture_droplet(p, m, &blocks, out, &mut summary, &mut files, &mut warnings)?;
            }
            if let Some(rc) = self
                .mc
                .geometry()
                .confinement(d)
                .filter(|_| p.geometry == "hard-wall" && p.mixture.is_none())
            {
                // 4 pi Rc^3 rho(Rc) = 3 N + d n_c (docs/mc.md), per block.
                let wall: Vec<f64> = blocks
                    .iter()
                    .filter_map(|b| b.wall.as_ref())
                    .map(|h| 4.0 * PI * rc.powi(3) * wall_contact_density(h, rc))
                    .collect();
                let virial: Vec<f64> = match p.pair {
                    Some(_) => pair_means(&blocks)
                        .iter()
                        .map(|(_, w)| 3.0 * n as f64 + w / p.kt)
                        .collect(),
                    None => blocks
                        .iter()
                        .map(|b| 3.0 * n as f64 + d * contact_pairs(&b.contact, d))
                        .collect(),
                };
                let ratio: Vec<f64> = wall.iter().zip(&virial).map(|(a, b)| a / b - 1.0).collect();
                let contact: Vec<f64> = blocks
                    .iter()
                    .filter_map(|b| b.wall.as_ref())
                    .map(|h| wall_contact_density(h, rc))
                    .collect();
                summary["wall_contact_density"] = value_error(&contact);
                summary["wall_sum_rule"] = json!({
                    "wall": value_error(&wall),
                    "virial": value_error(&virial),
                    "relative_difference": value_error(&ratio),
                });
            }
        }
        if p.pair.is_some() {
            let u: Vec<f64> = pair_means(&blocks)
                .iter()
                .map(|(u, _)| u / n as f64)
                .collect();
            summary["pair_energy_per_sphere"] =
                value_error_or(out, "pair_energy_per_sphere", &u, NO_PAIR);
        }
        if self.acc.frames > 0 {
            files.push("trajectory.gsd".into());
        }
        summary["warnings"] = json!(warnings);
        let message = if p.chain_length.is_some() {
            format!(
                "{} sweeps of event chains, {n} hard spheres ({}) in {wall_s:.1} s; outputs in {}",
                self.mc.sweeps(),
                p.geometry,
                out.path().display()
            )
        } else {
            format!(
                "{} sweeps of {n} {} ({}) in {wall_s:.1} s ({:.3e} trial moves/s), acceptance {:.3}; outputs in {}",
                self.mc.sweeps(),
                spheres(p).to_lowercase(),
                p.geometry,
                (self.mc.sweeps() * n as u64) as f64 / wall_s.max(1e-9),
                self.acc.sampling.acceptance(),
                out.path().display()
            )
        };
        Ok(Finished {
            summary,
            files,
            message,
            warnings,
        })
    }
}

/// Each species' volume fraction `pi d_s^3 rho_s(r) / 6` per bin of one block.
fn species_phi(hs: &[RadialHistogram], diameters: &[f64]) -> Vec<Vec<f64>> {
    hs.iter()
        .zip(diameters)
        .map(|(h, ds)| {
            let v = PI / 6.0 * ds.powi(3);
            h.density().iter().map(|rho| rho * v).collect()
        })
        .collect()
}

/// `{"value", "standard_error"}` over blocks, each `null` with a reason (recorded as `path`
/// in summary.json) when it is not a finite number.
fn value_error_or(out: &OutputDir, path: &str, v: &[f64], why: &str) -> serde_json::Value {
    let (m, e) = mean_and_error(v);
    for (x, k) in [(m, "value"), (e, "standard_error")] {
        if !x.is_finite() {
            out.explain("summary.json", &format!("{path}.{k}"), why);
        }
    }
    json!({ "value": m, "standard_error": e })
}

/// What the spheres are, for titles: hard spheres or the kind of `[pair]`.
fn spheres(p: &McRun) -> String {
    match &p.pair {
        None => "Hard spheres".into(),
        Some(pair) => format!("Spheres with the {} pair interaction", pair.kind()),
    }
}

/// The method in a droplet picture's title: hard-sphere MC, or MC with the kind of `[pair]`.
fn method_name(p: &McRun) -> String {
    match &p.pair {
        None => "hard-sphere MC".into(),
        Some(pair) => format!("MC with the {} pair interaction", pair.kind()),
    }
}

/// Each block's mean pair energy and virial (with `[pair]`).
fn pair_means(blocks: &[&Block]) -> Vec<(f64, f64)> {
    blocks
        .iter()
        .filter_map(|b| b.pair.as_ref())
        .map(PairSums::means)
        .collect()
}

/// Why the pair virial's pressure or the pair energy is missing.
const NO_PAIR: &str = "a block without samples of the pair virial (sample longer)";

/// Why a partial contact value is missing.
const NO_CONTACT: &str = "no pair of this species pair (a species of one sphere), or a block without pairs in some bin within 10 % of contact: nothing to extrapolate to contact (sample longer or more spheres)";

/// A bulk mixture's summary: the partial contact values `g_ab(d_ab+)` and the virial Z per
/// block (mean and standard error), beside BMCSL at the same number densities.
fn mixture_bulk(
    m: &colloidsim_particles::Mixture,
    blocks: &[&Block],
    volume: f64,
    summary: &mut serde_json::Value,
    out: &OutputDir,
) {
    let partial: Vec<&PartialContacts> = blocks.iter().filter_map(|b| b.partial.as_ref()).collect();
    let per_block: Vec<Vec<Vec<f64>>> = partial.iter().map(|h| h.contact_values(volume)).collect();
    let z: Vec<f64> = partial.iter().map(|h| h.compressibility(volume)).collect();
    let rho: Vec<f64> = m.counts.iter().map(|&c| c as f64 / volume).collect();
    let (z_bmcsl, g_bmcsl) = bmcsl(&rho, &m.diameters);
    let (mut contact, mut reference) = (serde_json::Map::new(), serde_json::Map::new());
    for a in 0..m.len() {
        for b in a..m.len() {
            let name = m.pair_name(a, b);
            let v: Vec<f64> = per_block.iter().map(|g| g[a][b]).collect();
            let path = format!("contact_values.{name}");
            contact.insert(name.clone(), value_error_or(out, &path, &v, NO_CONTACT));
            reference.insert(name, json!(g_bmcsl[a][b]));
        }
    }
    summary["contact_values"] = serde_json::Value::Object(contact);
    summary["compressibility"] = value_error_or(out, "compressibility", &z, NO_CONTACT);
    summary["bmcsl"] = json!({
        "compressibility": z_bmcsl,
        "contact_values": reference,
    });
}

/// A droplet of a mixture: `species_profile_mean.csv` and `species_profiles.png` (each
/// species' volume-fraction profile, mean and standard error over the blocks), each
/// species' mean centre distance in summary.json, and with a hard wall the sum rule
/// `sum_s 4 pi Rc_s^3 rho_s(Rc_s) = 3 N + sum_{a <= b} d_ab n_c,ab` (docs/mc.md).
fn mixture_droplet(
    p: &McRun,
    m: &colloidsim_particles::Mixture,
    blocks: &[&Block],
    out: &OutputDir,
    summary: &mut serde_json::Value,
    files: &mut Vec<String>,
    warnings: &mut Vec<String>,
) -> Result<()> {
    let per_block: Vec<Vec<Vec<f64>>> = blocks
        .iter()
        .filter_map(|b| b.species.as_ref())
        .map(|hs| species_phi(hs, &m.diameters))
        .collect();
    let Some(h0) = blocks.first().and_then(|b| b.species.as_ref()) else {
        return Ok(());
    };
    let r = h0[0].centres();
    let (mut phi, mut err) = (Vec::new(), Vec::new());
    for s in 0..m.len() {
        let one: Vec<Vec<f64>> = per_block.iter().map(|b| b[s].clone()).collect();
        let (a, e) = columns(&one, r.len());
        phi.push(a);
        err.push(e);
    }
    crate::output::species::write_species_profile(
        out,
        "species_profile_mean.csv",
        &r,
        &m.names,
        &phi,
        &err,
        None,
        files,
    )?;
    let radius = p.radius.unwrap_or(1.0);
    let x: Vec<f64> = r.iter().map(|v| v / radius).collect();
    let shown: Vec<(String, Vec<f64>, Vec<f64>)> = m
        .names
        .iter()
        .zip(&m.diameters)
        .zip(&phi)
        .map(|((name, ds), y)| (format!("{name} (d = {ds})"), x.clone(), y.clone()))
        .collect();
    let bars: Vec<Option<&[f64]>> = err.iter().map(|e| Some(e.as_slice())).collect();
    crate::output::species::draw_species_profiles(
        out,
        &format!(
            "Static droplet, {} ({}): species {}, N = {:?}, phi = {:.3} (bars: standard error over the blocks)",
            method_name(p),
            p.geometry,
            m.names.join(", "),
            m.counts,
            p.volume_fraction
        ),
        "r / R",
        &shown,
        &bars,
        files,
        warnings,
    );
    // Mean centre distance of each species over R, per block.
    let mut mean_radius = serde_json::Map::new();
    for s in 0..m.len() {
        let v: Vec<f64> = blocks
            .iter()
            .filter_map(|b| b.species.as_ref())
            .map(|hs| {
                let (c, r) = (hs[s].counts(), hs[s].centres());
                let total: u64 = c.iter().sum();
                c.iter().zip(&r).map(|(&k, r)| k as f64 * r).sum::<f64>()
                    / total.max(1) as f64
                    / radius
            })
            .collect();
        mean_radius.insert(m.names[s].clone(), {
            let (a, e) = mean_and_error(&v);
            json!({ "value": a, "standard_error": e })
        });
    }
    summary["mean_radius_over_r"] = serde_json::Value::Object(mean_radius);
    if p.geometry == "hard-wall" {
        let geometry = p.geometry();
        let n = m.total() as f64;
        let (mut wall, mut virial) = (Vec::new(), Vec::new());
        let mut contact = vec![Vec::new(); m.len()];
        for b in blocks {
            let (Some(hs), Some(pc)) = (b.species_wall.as_ref(), b.partial.as_ref()) else {
                continue;
            };
            let mut w = 0.0;
            for (s, h) in hs.iter().enumerate() {
                let rc = geometry
                    .confinement_of(m.diameters[s], p.diameter)
                    .unwrap_or(0.0);
                let rho = wall_contact_density(h, rc);
                contact[s].push(rho);
                w += 4.0 * PI * rc.powi(3) * rho;
            }
            let mut v = 3.0 * n;
            if let Some(sums) = &b.pair {
                v += sums.means().1 / p.kt;
            } else {
                for a in 0..m.len() {
                    for c in a..m.len() {
                        let dab = 0.5 * (m.diameters[a] + m.diameters[c]);
                        if pc.pair(a, c).counts().iter().any(|&k| k > 0) {
                            v += dab * contact_pairs(pc.pair(a, c), dab);
                        }
                    }
                }
            }
            wall.push(w);
            virial.push(v);
        }
        let ratio: Vec<f64> = wall.iter().zip(&virial).map(|(a, b)| a / b - 1.0).collect();
        let why = "a block without centres in some bin within 0.1 d_s of a species' wall, or without pairs next to contact: nothing to extrapolate (sample longer)";
        let mut per = serde_json::Map::new();
        for (s, v) in contact.iter().enumerate() {
            let path = format!("wall_contact_density.{}", m.names[s]);
            per.insert(m.names[s].clone(), value_error_or(out, &path, v, why));
        }
        summary["wall_contact_density"] = serde_json::Value::Object(per);
        summary["wall_sum_rule"] = json!({
            "wall": value_error_or(out, "wall_sum_rule.wall", &wall, why),
            "virial": value_error_or(out, "wall_sum_rule.virial", &virial, why),
            "relative_difference": value_error_or(out, "wall_sum_rule.relative_difference", &ratio, why),
        });
    }
    Ok(())
}

/// Mean and standard error per bin over blocks.
/// `g2.png` (the paper's Fig. 7): measured `g2` against Eq. 17 for pairs in one shell, against the
/// pair distance `s = r sqrt(2 (1 - cos theta))` up to 4 d, in a shell a third of the way out and
/// in the densest shell (the contact layer at the interface).
fn draw_g2(
    out: &OutputDir,
    rs: &[f64],
    cs: &[f64],
    rho: &[f64],
    g2: &[f64],
    eq: &crate::two_body::Eq17,
    diameter: f64,
) -> Result<()> {
    let (nr, nc) = (rs.len(), cs.len());
    let dense = (0..nr)
        .max_by(|&a, &b| rho[a].total_cmp(&rho[b]))
        .unwrap_or(0);
    let inner = nr / 3;
    let mut data = Vec::new();
    for (a, place) in [(inner, "inner"), (dense, "densest")] {
        // Pair distances up to 4 d, where the structure is.
        let near: Vec<usize> = (0..nc)
            .filter(|&c| rs[a] * (2.0 * (1.0 - cs[c])).sqrt() <= 4.0 * diameter)
            .collect();
        let s: Vec<f64> = near
            .iter()
            .map(|&c| rs[a] * (2.0 * (1.0 - cs[c])).sqrt())
            .collect();
        let pick =
            |v: &[f64]| -> Vec<f64> { near.iter().map(|&c| v[(a * nr + a) * nc + c]).collect() };
        data.push((
            format!("MC, {place} shell r = {:.2}", rs[a]),
            format!("Eq. 17 Trokhymchuk, r = {:.2}", rs[a]),
            format!("Eq. 17 dilute, r = {:.2}", rs[a]),
            s,
            pick(g2),
            pick(&eq.trokhymchuk),
            pick(&eq.dilute),
        ));
    }
    let mut series = Vec::new();
    for (l_mc, l_tk, l_dil, s, mc, tk, dil) in &data {
        series.push(Series {
            label: l_mc,
            x: s,
            y: mc,
            points: true,
        });
        series.push(Series {
            label: l_tk,
            x: s,
            y: tk,
            points: false,
        });
        series.push(Series {
            label: l_dil,
            x: s,
            y: dil,
            points: false,
        });
    }
    line_plot(
        &out.path().join("g2.png"),
        "Pair correlation in the droplet: Monte Carlo against Eq. 17",
        "pair distance s",
        "g2 (same shell)",
        &series,
        Scale::Linear,
    )
}

/// `g_r.png` of a one-component fluid: the Monte Carlo `g(r)` with its block errors, the
/// Percus–Yevick `g(r)` at the same packing fraction (`colloidsim_dft::oz`, solved numerically)
/// and, inside its fitted range, Trokhymchuk et al.'s simulation-fitted `g(r)`; the title gives
/// the measured `Z` with its error beside Carnahan–Starling's.
fn gr_picture(
    out: &OutputDir,
    n: usize,
    eta: f64,
    d: f64,
    (r, g, err): (&[f64], &[f64], &[f64]),
    (z, z_err): (f64, f64),
) -> Result<()> {
    use colloidsim_dft::oz;
    use colloidsim_dft::radial::pair::{ETA_FIT_MAX, ETA_FIT_MIN, Trokhymchuk};
    let x: Vec<f64> = r.iter().map(|v| v / d).collect();
    let x_max = x.iter().cloned().fold(0.0, f64::max);
    let mut series = vec![Series {
        label: "Monte Carlo (bars: standard error of the blocks)",
        x: &x,
        y: g,
        points: true,
    }];
    let mut errors = vec![Some(err)];
    // The PY curve from contact out to the MC's last bin (inside the core g = 0, as the MC's
    // points show); a packing fraction PY is not solved at draws none.
    let py = oz::solve(eta, &oz::PyOptions::default()).ok();
    let (px, pg): (Vec<f64>, Vec<f64>) = py
        .iter()
        .flat_map(|s| s.r.iter().zip(&s.g))
        .filter(|(r, _)| (1.0..=x_max).contains(*r))
        .map(|(r, g)| (*r, *g))
        .unzip();
    if !px.is_empty() {
        series.push(Series {
            label: "Percus-Yevick (Ornstein-Zernike, numerical)",
            x: &px,
            y: &pg,
            points: false,
        });
        errors.push(None);
    }
    let (tx, tg): (Vec<f64>, Vec<f64>) = match Trokhymchuk::new(eta) {
        Ok(t) if (ETA_FIT_MIN..=ETA_FIT_MAX).contains(&eta) => {
            let m = 400;
            (0..=m)
                .map(|i| 1.0 + (x_max - 1.0) * i as f64 / m as f64)
                .map(|x| (x, t.g(x)))
                .unzip()
        }
        _ => (Vec::new(), Vec::new()),
    };
    if !tx.is_empty() {
        series.push(Series {
            label: "Trokhymchuk et al. 2005 (fit to simulations)",
            x: &tx,
            y: &tg,
            points: false,
        });
        errors.push(None);
    }
    let title = format!(
        "Hard spheres, Monte Carlo: N = {n}, phi = {eta:.3}, Z = {} (Carnahan-Starling {:.3})",
        value_with_error(z, z_err),
        carnahan_starling(eta)
    );
    line_plot_styled(
        &out.join("g_r.png"),
        &title,
        "r / d",
        "g(r)",
        &series,
        &errors,
        Scale::Linear,
        Style {
            legend_outside: true,
        },
    )
}

/// `v +- e` with the error to two significant digits and the value to the same decimal place
/// (`v` alone to four significant digits when the error is not finite or zero).
fn value_with_error(v: f64, e: f64) -> String {
    if !(e.is_finite() && e > 0.0 && v.is_finite()) {
        return format!("{v:.4}");
    }
    let decimals = (1 - e.log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$} ± {e:.decimals$}")
}

fn columns(per_block: &[Vec<f64>], bins: usize) -> (Vec<f64>, Vec<f64>) {
    (0..bins)
        .map(|b| {
            let v: Vec<f64> = per_block.iter().map(|x| x[b]).collect();
            let (m, e) = mean_and_error(&v);
            (m, if e.is_finite() { e } else { 0.0 })
        })
        .unzip()
}

/// The engine of a scenario, stepped by hand (a step is a sweep, without tuning), with the
/// run it sets up afresh from ([`crate::Engine::set_state`]).
struct McEngine {
    mc: HardSphereMc,
    run: McRun,
}

impl crate::Engine for McEngine {
    fn method(&self) -> &str {
        "hs-mc"
    }
    fn dimensions(&self) -> usize {
        3
    }
    fn particles(&self) -> usize {
        self.mc.len()
    }
    fn step(&mut self, steps: u64) -> Result<()> {
        self.mc.run(steps);
        Ok(())
    }
    fn steps(&self) -> u64 {
        self.mc.sweeps()
    }
    fn time(&self) -> f64 {
        self.mc.sweeps() as f64
    }
    fn dt(&self) -> f64 {
        1.0
    }
    fn positions(&self) -> Vec<f64> {
        let pos: Vec<[f64; 3]> = (0..self.mc.len()).map(|i| self.mc.position(i)).collect();
        flat(&pos)
    }
    fn velocities(&self) -> Option<Vec<f64>> {
        None
    }
    /// The pair interaction's forces with `[pair]`; hard spheres exert no systematic force
    /// away from contact: zeros.
    fn forces(&self) -> Result<Vec<f64>> {
        Ok(match self.mc.pair_forces() {
            Some(f) => f.concat(),
            None => vec![0.0; 3 * self.mc.len()],
        })
    }
    fn box_lengths(&self) -> Vec<f64> {
        vec![self.mc.box_edge(); 3]
    }
    fn seed(&self) -> u32 {
        self.mc.seed()
    }
    fn types(&self) -> Option<crate::engine::ParticleTypes> {
        let d = self.mc.diameters();
        let names = match &self.run.mixture {
            Some(m) => m.names.clone(),
            None => vec!["A".into()],
        };
        Some(crate::engine::ParticleTypes {
            names,
            typeid: self.mc.types().to_vec(),
            diameter: self.mc.types().iter().map(|&t| d[t as usize]).collect(),
        })
    }
    /// Positions relative to the box centre, species by species as `positions` gives them;
    /// overlapping spheres or centres outside the wall are refused (as at the start). The
    /// move size is kept.
    fn set_state(&mut self, change: crate::StateChange) -> Result<()> {
        change.check(self.particles(), 3, false, "hs-mc")?;
        let mut run = self.run.clone();
        run.seed = change.seed.unwrap_or(run.seed);
        let pos: Vec<[f64; 3]> = match &change.positions {
            Some(x) => crate::engine::rows(x),
            None => (0..self.mc.len()).map(|i| self.mc.position(i)).collect(),
        };
        let mut mc = run.engine(Some(&pos), "positions").map_err(|e| match e {
            McError::Param(e) => anyhow::Error::from(params::keyed(e)),
            e => e.into(),
        })?;
        let [x, y, z] = mc.positions().map(<[f64]>::to_vec);
        let step = change.step.unwrap_or(self.mc.sweeps());
        mc.restore([x, y, z], step, self.mc.delta());
        (self.mc, self.run) = (mc, run);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::value_with_error;

    /// The error to two significant digits, the value to the same place.
    #[test]
    fn a_value_is_written_with_its_error() {
        assert_eq!(
            value_with_error(3.968951672741633, 0.0401153),
            "3.969 ± 0.040"
        );
        assert_eq!(value_with_error(12.3456, 0.5), "12.35 ± 0.50");
        assert_eq!(value_with_error(250.0, 12.0), "250 ± 12");
        assert_eq!(value_with_error(3.96897, f64::INFINITY), "3.9690");
    }
}
