//! Brownian cluster dynamics scenarios (`method = "bcd"`, `"bcd-chronological"`): the run's
//! session (engine, observers on their triggers, GSD frames), its outputs beside the exact
//! theory, and `theory`. Its keys are declared in [`keys`] and read in [`params`].

#[rustfmt::skip] // declarations laid out as a table, one key to a line or three
pub mod keys;
pub mod params;

use crate::checkpoint::Envelope;
use crate::control::Control;
use crate::keys::Spec;
use crate::method::{Checked, Finished, Headline, Method, Session};
use crate::output::plot::{
    Labels, Scale, Series, Style, line_plot, line_plot_styled, line_plot_with_errors,
    linear_picture, picture,
};
use crate::output::trajectory::FrameDigest;
use crate::{Report, Scenario as Source, TheoryOptions};
use anyhow::{Context, Result, bail};
use colloidsim_bcd::forces::Field;
use colloidsim_bcd::forces::{ExternalForce, NoPair, PairForce};
use colloidsim_bcd::observe::{ClusterSizes, ContactDensity, DensityProfile, Msd};
use colloidsim_bcd::{Bcd, BcdState, Boundary, Integrator};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::OutputDir;
use colloidsim_core::trigger::log_spaced;
use colloidsim_dft::rods::{self, BetaPotential, Domain, RodInteraction, RodsProblem, bulk};
use colloidsim_particles::gsd::GsdFileWriter as GsdFile;
use params::{Resolved, Scenario};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::time::Instant;

/// The BCD family of scenarios.
pub struct BcdMethod;

/// The scenario as given and resolved (with `seed` replacing the scenario's).
fn read(src: &Source, seed: Option<u64>) -> Result<(Scenario, Resolved)> {
    params::read(&src.table()?, src.base(), seed).with_context(|| src.label())
}

/// BCD's headline observables (summary.json).
const HEADLINE: &[Headline] = &[
    Headline {
        name: "peak_density",
        path: "peak_density",
        labels: None,
        unit: "1/length",
        doc: "the largest value of the density profile (density.csv)",
        absent: "no density observed (observe.density)",
    },
    Headline {
        name: "theory_l1",
        path: "theory_l1",
        labels: None,
        unit: "-",
        doc: "L1 distance of the density profile to the exact equilibrium on the same bins, \
              sum of abs(rho - rho_exact) over sum of rho_exact (density.csv, density_theory.csv)",
        absent: "no exact equilibrium beside the density",
    },
    Headline {
        name: "particle_current",
        path: "particle_current",
        labels: None,
        unit: "1/time",
        doc: "mean particle current rho v through a cross-section over the sampled time \
              (current.csv)",
        absent: "no current observed (observe.current)",
    },
    Headline {
        name: "mean_contact_density",
        path: "mean_contact_density",
        labels: None,
        unit: "1/length^2",
        doc: "the two-particle density at contact rho2(x, x + sigma) averaged over x \
              (contact_density.csv)",
        absent: "no contact density observed (observe.contact_density)",
    },
];

impl Method for BcdMethod {
    fn names(&self) -> &'static [&'static str] {
        &["bcd", "bcd-chronological"]
    }

    fn about(&self) -> &'static str {
        "1D Brownian cluster dynamics of hard and sticky rods, beside the exact theory"
    }

    fn docs(&self) -> &'static str {
        "docs/bcd.md"
    }

    fn headline(&self) -> &'static [Headline] {
        HEADLINE
    }

    fn check(&self, src: &Source) -> Result<Checked> {
        let (sc, r) = read(src, None)?;
        // Building the engine checks the initial positions (overlaps, walls).
        Bcd::new(r.config.clone(), r.initial.clone(), Field::None, NoPair)
            .with_context(|| src.label())?;
        Ok(Checked {
            resolved: resolved_json(&sc, &r),
            warnings: r.warnings.clone(),
        })
    }

    fn start(
        &self,
        src: &Source,
        seed: Option<u64>,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Box<dyn Session>> {
        crate::method::on_one_rank(comm, src, self.names()[0])?;
        let (sc, r) = read(src, seed)?;
        session(sc, r, None)
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
        let (sc, r) = read(src, Some(seed))?;
        let saved: Saved = crate::checkpoint::decode_payload(&envelope.payload)?;
        if sc.observe.trajectory.is_some() {
            saved.digest.restore(&out.join("trajectory.gsd"))?;
        }
        session(sc, r, Some(saved))
    }

    fn has_theory(&self) -> bool {
        true
    }

    fn theory(&self, src: &Source, opts: &TheoryOptions, _ctl: &Control) -> Result<Report> {
        theory(src, opts)
    }

    fn keys(&self) -> &'static [Spec] {
        keys::KEYS
    }

    fn engine(&self, src: &Source, seed: Option<u64>) -> Result<Box<dyn crate::Engine>> {
        let (sc, r) = read(src, seed)?;
        let bcd = Bcd::new(
            r.config.clone(),
            r.initial.clone(),
            r.engine_field.clone(),
            r.pair.clone(),
        )?
        .with_integrator(r.integrator);
        Ok(Box::new(BcdEngine {
            bcd,
            method: sc.method,
            field: r.engine_field,
            pair: r.pair,
            integrator: r.integrator,
        }))
    }
}

/// The session of a scenario, fresh or from a checkpoint's state, with the engine specialised
/// for the pair force present (hard rods: no pair loop at all).
fn session(sc: Scenario, r: Resolved, saved: Option<Saved>) -> Result<Box<dyn Session>> {
    if r.pair.range() > 0.0 {
        let pair = r.pair.clone();
        build(sc, r, pair, saved)
    } else {
        build(sc, r, NoPair, saved)
    }
}

fn build<P: PairForce + Clone + Send + 'static>(
    sc: Scenario,
    r: Resolved,
    pair: P,
    saved: Option<Saved>,
) -> Result<Box<dyn Session>> {
    let field = r.engine_field.clone();
    let (bcd, obs, frames, digest) = match saved {
        Some(s) => (
            Bcd::from_state(r.config.clone(), s.state, field, pair)?.with_integrator(r.integrator),
            s.observers,
            s.frames,
            s.digest,
        ),
        None => (
            Bcd::new(r.config.clone(), r.initial.clone(), field, pair)?
                .with_integrator(r.integrator),
            observers(&sc, &r),
            0,
            FrameDigest::default(),
        ),
    };
    let triggers = Triggers::of(&sc, &r);
    // The next offer the MSD uses, from the sampled steps already done.
    let sampled = bcd.steps().saturating_sub(triggers.equilibrate);
    let msd_due = obs.msd.as_ref().map_or(0, |m| m.next_due(sampled));
    Ok(Box::new(BcdSession {
        sc,
        r,
        bcd,
        obs,
        frames,
        digest,
        gsd: None,
        triggers,
        msd_due,
    }))
}

fn resolved_json(sc: &Scenario, r: &Resolved) -> serde_json::Value {
    let c = &r.config;
    let t = Triggers::of(sc, r);
    let mut v = json!({
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
            "dt": c.dt, "integrator": r.integrator, "equilibrate_steps": r.equilibrate_steps,
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
    });
    // The values the run uses where the scenario left them out.
    v["observe"]["every"] = json!(t.every);
    v["run"]["checkpoint_every"] = json!(t.checkpoint_every);
    v
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

/// The method's part of `checkpoint.bin`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Saved {
    state: BcdState,
    observers: Observers,
    /// Frames in trajectory.gsd.
    frames: u64,
    /// CRC-32 of those frames, checked before a restart appends to the file.
    digest: FrameDigest,
}

/// Blocks of the production run whose spread gives the density's and the contact density's
/// standard errors (`err` in density.csv and contact_density.csv).
const DENSITY_BLOCKS: u64 = 20;

fn observers(sc: &Scenario, r: &Resolved) -> Observers {
    let c = &r.config;
    let o = &sc.observe;
    let n = r.initial.len() as f64;
    let msd = o.msd.as_ref().map(|m| {
        let max_lag = r.msd_max_lag;
        let max_steps = ((max_lag / c.dt).round() as u64).max(1);
        let lags = log_spaced(1, max_steps, m.points);
        // ~100 time origins over the sampled run.
        Msd::new(lags, (r.sampled_steps / 100).max(1))
    });
    // Density and contact density samples over the run, in DENSITY_BLOCKS blocks.
    let samples = r.sampled_steps / r.every.max(1);
    Observers {
        density: o.density.as_ref().map(|d| {
            DensityProfile::new(d.bins, r.period, c.length).with_blocks(samples, DENSITY_BLOCKS)
        }),
        contact: o.contact_density.as_ref().map(|d| {
            ContactDensity::new(d.bins, d.window, r.period, c.sigma, c.length, c.boundary)
                .with_blocks(samples, DENSITY_BLOCKS)
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

/// When observations are due, in steps.
#[derive(Debug, Clone, Copy)]
struct Triggers {
    /// Steps before sampling starts.
    equilibrate: u64,
    total: u64,
    /// Density, contact density and clusters: every this many sampled steps.
    every: u64,
    /// The particle current: every this many sampled steps.
    current_every: u64,
    /// GSD frames: every this many steps from the first production step.
    trajectory: Option<u64>,
    /// GSD frames also during equilibration (every `trajectory` steps from step 0).
    trajectory_equilibration: bool,
    /// Regular checkpoints.
    checkpoint_every: u64,
}

impl Triggers {
    fn of(sc: &Scenario, r: &Resolved) -> Self {
        let total = r.equilibrate_steps + r.sampled_steps;
        Self {
            equilibrate: r.equilibrate_steps,
            total,
            every: r.every,
            current_every: (r.sampled_steps / 200).max(1),
            trajectory: sc.observe.trajectory.as_ref().map(|t| t.every),
            trajectory_equilibration: sc
                .observe
                .trajectory
                .as_ref()
                .is_some_and(|t| t.equilibration),
            checkpoint_every: sc.run.checkpoint_every.unwrap_or((total / 10).max(1000)),
        }
    }
}

impl Triggers {
    /// Is a GSD frame due at step `s`? At the first production step (`equilibrate`) and
    /// every `trajectory` steps after it; during equilibration only when asked, from step 0.
    fn frame_due(&self, s: u64) -> bool {
        let Some(e) = self.trajectory else {
            return false;
        };
        if s >= self.equilibrate {
            (s - self.equilibrate).is_multiple_of(e)
        } else {
            self.trajectory_equilibration && s.is_multiple_of(e)
        }
    }

    /// The first step after `s` at which a GSD frame is due.
    fn next_frame_after(&self, s: u64) -> Option<u64> {
        let e = self.trajectory?;
        Some(if s >= self.equilibrate {
            self.equilibrate + next_multiple_after(s - self.equilibrate, e)
        } else if self.trajectory_equilibration {
            next_multiple_after(s, e).min(self.equilibrate)
        } else {
            self.equilibrate
        })
    }
}

/// First multiple of `m` strictly after `s`.
fn next_multiple_after(s: u64, m: u64) -> u64 {
    (s / m + 1) * m
}

/// A BCD run: the engine, its observers and the trajectory file.
struct BcdSession<P: PairForce> {
    sc: Scenario,
    r: Resolved,
    bcd: Bcd<Field, P>,
    obs: Observers,
    frames: u64,
    digest: FrameDigest,
    gsd: Option<GsdFile>,
    triggers: Triggers,
    /// The next sampled step the MSD uses (from [`Msd::next_due`], kept between samples).
    msd_due: u64,
}

impl<P: PairForce + Clone + Send> BcdSession<P> {
    /// The first step after `s` at which an observation is due.
    fn next_observation(&self, s: u64) -> u64 {
        let t = &self.triggers;
        let o = &self.obs;
        let mut next = t.total;
        if let Some(f) = t.next_frame_after(s) {
            next = next.min(f);
        }
        if s < t.equilibrate {
            if o.current.is_some() {
                next = next.min(t.equilibrate);
            }
            // Sampling starts after equilibration: the first sampled step is equilibrate + 1.
            return next.min(t.equilibrate + 1);
        }
        let k = s - t.equilibrate;
        if o.density.is_some() || o.contact.is_some() || o.clusters.is_some() {
            next = next.min(t.equilibrate + next_multiple_after(k, t.every));
        }
        if o.current.is_some() {
            next = next.min(t.equilibrate + next_multiple_after(k, t.current_every));
        }
        if o.msd.is_some() {
            // The MSD is offered sampled step k' - 1 at step equilibrate + k'.
            next = next.min(t.equilibrate + self.msd_due + 1);
        }
        next
    }

    /// Are the density and the clusters due at step `s`?
    fn every_due(&self, s: u64) -> bool {
        let t = &self.triggers;
        s > t.equilibrate && (s - t.equilibrate).is_multiple_of(t.every)
    }

    /// Does an observation at step `s` read the positions (the MSD, the current, the contact
    /// density, a GSD frame)?
    fn positions_due(&self, s: u64) -> bool {
        let t = &self.triggers;
        let o = &self.obs;
        let sampled = s > t.equilibrate && {
            let k = s - t.equilibrate;
            (o.msd.is_some() && self.msd_due == k - 1)
                || (o.current.is_some() && k.is_multiple_of(t.current_every))
                || (o.contact.is_some() && k.is_multiple_of(t.every))
        };
        sampled
            || (s == t.equilibrate && o.current.is_some())
            || (self.gsd.is_some() && t.frame_due(s))
    }

    /// Take the observations due at step `s` (just reached); `tallied`: the step into `s`
    /// already added the density and the clusters ([`Bcd::step_observed`]).
    fn observe(&mut self, s: u64, tallied: bool) -> Result<()> {
        let t = self.triggers;
        let n = self.r.initial.len() as f64;
        let dt = self.r.config.dt;
        if s > t.equilibrate {
            let k = s - t.equilibrate;
            let every = k.is_multiple_of(t.every);
            let (density, clusters) = if tallied {
                (None, None)
            } else {
                (self.obs.density.as_mut(), self.obs.clusters.as_mut())
            };
            let msd = self.obs.msd.is_some() && self.msd_due == k - 1;
            let current = self.obs.current.is_some() && k.is_multiple_of(t.current_every);
            let reduced = self.bcd.reduced();
            let contact = every && self.obs.contact.is_some();
            if every && !msd && !current && !contact && reduced.is_some() {
                // Density and clusters only: straight from the ring's reduced positions.
                if let (Some(d), Some(y)) = (density, reduced) {
                    d.sample_reduced(y, self.r.config.sigma);
                }
                if let Some(c) = clusters {
                    c.sample(&self.bcd);
                }
            } else if (every && (density.is_some() || clusters.is_some() || contact))
                || msd
                || current
            {
                let x = self.bcd.positions();
                if every {
                    if let Some(d) = density {
                        d.sample(x);
                    }
                    if let Some(c) = self.obs.contact.as_mut() {
                        c.sample(x);
                    }
                    if let Some(c) = clusters {
                        c.sample(&self.bcd);
                    }
                }
                if msd && let Some(m) = self.obs.msd.as_mut() {
                    m.sample(k - 1, x);
                    self.msd_due = m.next_due(k);
                }
                if current && let Some(c) = self.obs.current.as_mut() {
                    c.t.push(k as f64 * dt);
                    c.displacement.push(x.iter().sum::<f64>() / n - c.x0_sum);
                }
            }
        } else if s == t.equilibrate
            && let Some(c) = self.obs.current.as_mut()
        {
            c.x0_sum = self.bcd.positions().iter().sum::<f64>() / n;
        }
        if t.frame_due(s) {
            self.write_frame()?;
        }
        Ok(())
    }

    /// A GSD frame of the current configuration.
    fn write_frame(&mut self) -> Result<()> {
        if let Some(g) = self.gsd.as_mut() {
            let b = RodBox::of(self.bcd.config());
            let (x, image) = b.place(self.bcd.positions());
            write_frame(g, self.bcd.steps(), &b, &x, &image)?;
            self.frames += 1;
        }
        Ok(())
    }
}

impl<P: PairForce + Clone + Send> Session for BcdSession<P> {
    fn label(&self) -> String {
        "bcd".into()
    }

    fn total(&self) -> u64 {
        self.triggers.total
    }

    fn position(&self) -> u64 {
        self.bcd.steps()
    }

    fn seed(&self) -> u64 {
        self.r.config.seed as u64
    }

    fn status(&self) -> String {
        format!("t = {}", crate::driver::significant(self.bcd.time()))
    }

    fn parameters(&self) -> serde_json::Value {
        resolved_json(&self.sc, &self.r)
    }

    fn warnings(&self) -> Vec<String> {
        self.r.warnings.clone()
    }

    fn writes(&self, name: &str) -> bool {
        [
            "final_configuration.csv",
            "density.csv",
            "density_theory.csv",
            "density_ddft.csv",
            "density.png",
            "contact_density.csv",
            "contact_density_theory.csv",
            "msd.csv",
            "msd.png",
            "current.csv",
            "clusters.csv",
            "trajectory.gsd",
        ]
        .contains(&name)
    }

    fn begin(&mut self, out: &OutputDir, fresh: bool) -> Result<()> {
        if self.triggers.trajectory.is_some() {
            self.gsd = Some(open_trajectory(
                out,
                self.frames > 0 || self.bcd.steps() > 0,
            )?);
            if fresh && self.triggers.frame_due(0) {
                self.write_frame()?;
            }
        }
        Ok(())
    }

    fn next_checkpoint(&self) -> Option<u64> {
        Some(next_multiple_after(
            self.bcd.steps(),
            self.triggers.checkpoint_every,
        ))
    }

    fn advance(&mut self, until: u64) -> Result<Option<String>> {
        // The whole chunk on a worker of the thread pool: `Bcd::run` then enters it once per
        // chunk, not once per observation (entering from outside the pool wakes a worker and
        // waits for it, which cost more than the observers themselves when they sample every
        // step).
        rayon::scope(|_| {
            while self.bcd.steps() < until {
                let s = self.bcd.steps();
                let next = self.next_observation(s).min(until);
                // The density and the clusters of step `next` are taken in that step's own
                // parallel pass.
                // parallel pass, and so are the positions when an observer reads them.
                let positions = self.positions_due(next);
                let tally = self.every_due(next)
                    && (self.obs.density.is_some() || self.obs.clusters.is_some());
                let fused = tally || positions;
                let mut done = self.bcd.run(next - s - u64::from(fused));
                if fused && done.is_ok() {
                    let o = &mut self.obs;
                    done = if tally {
                        self.bcd
                            .step_observed(o.density.as_mut(), o.clusters.as_mut(), positions)
                    } else {
                        self.bcd.step_observed(None, None, true)
                    };
                }
                if let Err(e) = done {
                    return Ok(Some(e.to_string()));
                }
                self.observe(next, tally)?;
            }
            Ok(None)
        })
    }

    fn flush(&mut self) -> Result<()> {
        if let Some(g) = self.gsd.as_mut() {
            g.sync_all()?;
        }
        Ok(())
    }

    fn save(&mut self, out: &OutputDir) -> Result<Vec<u8>> {
        if self.gsd.is_some() {
            self.digest
                .extend(&out.join("trajectory.gsd"), self.frames)?;
        }
        Ok(bincode::serialize(&Saved {
            state: self.bcd.state().clone(),
            observers: self.obs.clone(),
            frames: self.frames,
            digest: self.digest,
        })?)
    }

    fn finish(
        self: Box<Self>,
        out: &OutputDir,
        wall_seconds: f64,
        _failure: Option<&str>,
    ) -> Result<Finished> {
        write_outputs(
            &self.sc,
            &self.r,
            out,
            &self.bcd,
            &self.obs,
            wall_seconds,
            self.frames,
        )
    }
}

fn open_trajectory(out: &OutputDir, append: bool) -> Result<GsdFile> {
    let path = out.join("trajectory.gsd");
    Ok(if append && path.exists() {
        GsdFile::append(&path)?
    } else {
        create_trajectory(&path)?
    })
}

fn create_trajectory(path: &std::path::Path) -> Result<GsdFile> {
    Ok(GsdFile::create_new(
        path,
        &crate::software(),
        "hoomd",
        (1, 4),
    )?)
}

/// What the frames of a BCD trajectory look like in the HOOMD schema (`docs/bcd.md`).
#[derive(Debug, Clone, Copy)]
struct RodBox {
    /// L.
    length: f64,
    /// Hard walls at 0 and L (else a ring).
    walls: bool,
    sigma: f64,
}

impl RodBox {
    fn of(c: &colloidsim_bcd::BcdConfig) -> Self {
        Self {
            length: c.length,
            walls: c.boundary == Boundary::Walls,
            sigma: c.sigma,
        }
    }

    /// Edge of the (periodic) GSD box along x: L on a ring; 2L between walls, so that no rod
    /// sits within L of a periodic image of another (HOOMD boxes are always periodic).
    fn edge(&self) -> f64 {
        if self.walls {
            2.0 * self.length
        } else {
            self.length
        }
    }

    /// Positions in the box and their images: on a ring wrapped into [-L/2, L/2) with the
    /// image counting the turns (x = position + image L); between walls shifted by -L/2,
    /// image 0.
    fn place(&self, x: &[f64]) -> (Vec<f32>, Vec<i32>) {
        let l = self.length;
        let half = (0.5 * l) as f32;
        x.iter()
            .map(|&xi| {
                if self.walls {
                    return ((xi - 0.5 * l) as f32, 0);
                }
                let turns = ((xi + 0.5 * l) / l).floor();
                let mut w = (xi - turns * l) as f32;
                let mut image = turns as i32;
                if w >= half {
                    w -= 2.0 * half;
                    image += 1;
                } else if w < -half {
                    w += 2.0 * half;
                    image -= 1;
                }
                (w, image)
            })
            .unzip()
    }
}

/// One GSD frame in the HOOMD schema: rods of type `rod` (diameter `sigma`) on the x axis of a
/// 2D box, positions in the box with their images (`RodBox::place`); between walls the walls'
/// x positions go to `log/bcd/walls`.
fn write_frame(g: &mut GsdFile, step: u64, b: &RodBox, x: &[f32], image: &[i32]) -> Result<()> {
    let e = b.edge() as f32;
    let n = u32::try_from(x.len()).context("too many rods for a GSD frame")?;
    let mut name = [0u8; 64];
    name[..3].copy_from_slice(b"rod");
    g.write_scalars("configuration/step", [step])?;
    g.write_scalars("configuration/dimensions", [2u8])?;
    g.write_scalars("configuration/box", [e, e, 0.0, 0.0, 0.0, 0.0])?;
    g.write_scalars("particles/N", [n])?;
    g.write_arrays("particles/types", [name])?;
    g.write_scalars("particles/typeid", x.iter().map(|_| 0u32))?;
    g.write_scalars("particles/diameter", x.iter().map(|_| b.sigma as f32))?;
    g.write_arrays("particles/position", x.iter().map(|&w| [w, 0.0, 0.0]))?;
    g.write_arrays("particles/image", image.iter().map(|&i| [i, 0, 0]))?;
    if b.walls {
        let h = 0.5 * b.length;
        g.write_scalars("log/bcd/walls", [-h, h])?;
    }
    g.end_frame()?;
    Ok(())
}

/// A BCD engine stepped by hand, with what sets it up afresh ([`crate::Engine::set_state`]).
struct BcdEngine {
    bcd: Bcd<Field, colloidsim_bcd::forces::Pair>,
    method: String,
    field: Field,
    pair: colloidsim_bcd::forces::Pair,
    integrator: Integrator,
}

impl crate::Engine for BcdEngine {
    fn method(&self) -> &str {
        &self.method
    }
    fn dimensions(&self) -> usize {
        1
    }
    fn particles(&self) -> usize {
        self.bcd.len()
    }
    fn step(&mut self, steps: u64) -> Result<()> {
        Ok(self.bcd.run(steps)?)
    }
    fn steps(&self) -> u64 {
        self.bcd.steps()
    }
    fn time(&self) -> f64 {
        self.bcd.time()
    }
    fn dt(&self) -> f64 {
        self.bcd.config().dt
    }
    fn positions(&self) -> Vec<f64> {
        self.bcd.positions().to_vec()
    }
    fn velocities(&self) -> Option<Vec<f64>> {
        None
    }
    fn forces(&self) -> Result<Vec<f64>> {
        Ok(self.bcd.systematic_forces())
    }
    fn box_lengths(&self) -> Vec<f64> {
        vec![self.bcd.config().length]
    }
    fn seed(&self) -> u32 {
        self.bcd.config().seed
    }
    fn types(&self) -> Option<crate::engine::ParticleTypes> {
        Some(crate::engine::ParticleTypes {
            names: vec!["rod".into()],
            typeid: vec![0; self.bcd.len()],
            diameter: vec![self.bcd.config().sigma; self.bcd.len()],
        })
    }
    /// Positions are rod centres in ring order (unwrapped on the ring), as `positions` gives
    /// them: sorted, without overlap.
    fn set_state(&mut self, change: crate::StateChange) -> Result<()> {
        change.check(self.particles(), 1, false, &self.method)?;
        let mut cfg = self.bcd.config().clone();
        cfg.seed = change.seed.unwrap_or(cfg.seed);
        let step = change.step.unwrap_or(self.bcd.steps());
        let given = change.positions.is_some();
        let x = change
            .positions
            .unwrap_or_else(|| self.bcd.positions().to_vec());
        let (field, pair) = (self.field.clone(), self.pair.clone());
        self.bcd = Bcd::new_at(cfg, x, field, pair, step)
            .map_err(|e| match given {
                true => anyhow::anyhow!("positions: {e}"),
                false => e.into(),
            })?
            .with_integrator(self.integrator);
        Ok(())
    }
}

fn write_outputs<E, P>(
    sc: &Scenario,
    r: &Resolved,
    out: &OutputDir,
    bcd: &Bcd<E, P>,
    obs: &Observers,
    wall: f64,
    frames: u64,
) -> Result<Finished>
where
    E: ExternalForce,
    P: PairForce,
{
    let c = &r.config;
    let n = r.initial.len();
    let mut warnings = Vec::new();
    let mut files = vec!["final_configuration.csv".to_string()];
    out.write_table("final_configuration.csv", &[("x", bcd.positions())])?;
    // The theory is a companion: if it fails, the simulation's outputs are still written.
    let (theory, theory_error) = match equilibrium_counterpart(sc, r, None, obs) {
        Ok(t) => (t, None),
        Err(e) => {
            warnings.push(format!("no theory curve: {e:#}"));
            (None, Some(format!("{e:#}")))
        }
    };
    let rods = rods_label(r);
    // A driven ring: its DDFT steady state beside the density, when it comes cheaply.
    let ddft = match (&obs.density, driven_companion(r)) {
        (Some(_), Some(Ok(st))) => Some(st),
        (Some(_), Some(Err(e))) => {
            warnings.push(format!("no DDFT steady state beside the density: {e:#}"));
            None
        }
        _ => None,
    };
    // Headline observables (Method::headline): the profile's peak, its L1 distance to the
    // exact theory, the mean contact density.
    let mut peak_density = None;
    let mut theory_l1 = None;
    let mut mean_contact_density = None;
    if let Some(d) = &obs.density {
        let (x, rho) = d.profile();
        let err = d.errors();
        peak_density = Some(rho.iter().copied().fold(f64::NEG_INFINITY, f64::max));
        theory_l1 = theory
            .as_ref()
            .filter(|t| t.density.rho.len() == rho.len())
            .map(|t| {
                let diff: f64 = rho
                    .iter()
                    .zip(&t.density.rho)
                    .map(|(a, b)| (a - b).abs())
                    .sum();
                diff / t.density.rho.iter().sum::<f64>()
            });
        out.write_table("density.csv", &[("x", &x), ("rho", &rho), ("err", &err)])?;
        files.push("density.csv".into());
        let mut series = vec![Series {
            label: "BCD (bars: standard error)",
            x: &x,
            y: &rho,
            points: true,
        }];
        if let Some(t) = theory.as_ref().map(|t| &t.density) {
            out.write_table("density_theory.csv", &[("x", &t.centres), ("rho", &t.rho)])?;
            files.push("density_theory.csv".into());
            series.push(Series {
                label: theory_label(r),
                x: &t.centres,
                y: &t.rho,
                points: false,
            });
        }
        let ddft_bins = ddft
            .as_ref()
            .map(|st| bin_means(&st.x, &st.rho, r.period, x.len()));
        if let Some((centres, means)) = &ddft_bins {
            out.write_table("density_ddft.csv", &[("x", centres), ("rho", means)])?;
            files.push("density_ddft.csv".into());
            series.push(Series {
                label: "1D DDFT steady state (adiabatic)",
                x: centres,
                y: means,
                points: false,
            });
        }
        let errors = [Some(err.as_slice()), None];
        picture(
            line_plot_with_errors(
                &out.join("density.png"),
                &format!(
                    "density of {rods}, N = {n}, L = {}, sigma = {}",
                    c.length, c.sigma
                ),
                "x (length)",
                "rho(x) (1/length)",
                &series,
                &errors[..series.len().min(2)],
                Scale::Linear,
            ),
            "density.png",
            &mut files,
            &mut warnings,
        );
    }
    if let Some(cd) = &obs.contact {
        let (x, rho2) = cd.profile();
        let err = cd.errors();
        mean_contact_density = Some(rho2.iter().sum::<f64>() / rho2.len().max(1) as f64);
        out.write_table(
            "contact_density.csv",
            &[("x", &x), ("rho2", &rho2), ("err", &err)],
        )?;
        files.push("contact_density.csv".into());
        let mut series = vec![Series {
            label: "BCD (bars: std. error)",
            x: &x,
            y: &rho2,
            points: true,
        }];
        if let Some(t) = theory.as_ref().and_then(|t| t.contact.as_ref()) {
            out.write_table(
                "contact_density_theory.csv",
                &[
                    ("x", &t.centres),
                    ("rho2", &t.contact),
                    ("rho2_window", &t.window),
                ],
            )?;
            files.push("contact_density_theory.csv".into());
            series.push(Series {
                label: "exact, window average",
                x: &t.centres,
                y: &t.window,
                points: false,
            });
            series.push(Series {
                label: "exact at contact (Eq. 24)",
                x: &t.centres,
                y: &t.contact,
                points: false,
            });
        }
        let errors = [Some(err.as_slice()), None, None];
        picture(
            line_plot_styled(
                &out.join("contact_density.png"),
                &format!("contact density of {rods}, sigma = {}", c.sigma),
                "x (length)",
                "rho2(x, x + sigma) (1/length^2)",
                &series,
                &errors[..series.len()],
                Scale::Linear,
                Style {
                    legend_outside: true,
                },
            ),
            "contact_density.png",
            &mut files,
            &mut warnings,
        );
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
            // The long-time single-file law (2/rho) sqrt(S(0) D t / pi) (Kollmann 2003) on a
            // ring without a field, for hard rods (S(0) = (1 - rho sigma)^2) and for sticky rods
            // (S(0) of the simulated finite-range contact, colloidsim_dft::rods::bulk).
            let rho = n as f64 / c.length;
            let s0 = match (&r.pair.sticky, &r.pair.yukawa, &r.pair.table) {
                (None, None, None) => Some(bulk::structure_factor_zero(c.sigma, 0.0, rho)),
                (Some(st), None, None) => Some(bulk::structure_factor_zero_finite_range(
                    c.sigma, st.gamma, st.eps, st.order, rho,
                )),
                _ => None,
            };
            let sf: Vec<f64> = s0.map_or(Vec::new(), |s0| {
                t.iter()
                    .map(|&t| bulk::single_file_msd(s0, rho, c.diffusion(), t))
                    .collect()
            });
            let label = format!(
                "single file (2/rho) sqrt(S(0) D t/pi), S(0) = {:.4}",
                s0.unwrap_or(f64::NAN)
            );
            if r.field.is_zero() && c.boundary == Boundary::Periodic && s0.is_some() {
                series.push(Series {
                    label: &label,
                    x: &t,
                    y: &sf,
                    points: false,
                });
            }
            // Error bars on the BCD points (msd.csv's err); the theory curves have none.
            let errors = [Some(err.as_slice()), None, None];
            picture(
                line_plot_with_errors(
                    &out.join("msd.png"),
                    &format!("mean-square displacement of {rods} (bars: standard error)"),
                    "t (time)",
                    "MSD (length^2)",
                    &series,
                    &errors[..series.len()],
                    Scale::LogLog,
                ),
                "msd.png",
                &mut files,
                &mut warnings,
            );
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
        let title = format!(
            "current of {rods} (running mean since sampling began), drive f = {} energy/length",
            r.field.drive
        );
        let labels = Labels {
            title: &title,
            x: "t (time)",
            y: "current rho v (1/time)",
        };
        let series = [Series {
            label: "BCD",
            x: &cur.t,
            y: &j,
            points: false,
        }];
        linear_picture(
            out.path(),
            "current.png",
            &labels,
            &series,
            &mut files,
            &mut warnings,
        );
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
    for (key, why) in [
        (
            "mean_velocity",
            "no current observed (observe.current off, or no sample yet)",
        ),
        (
            "particle_current",
            "no current observed (observe.current off, or no sample yet)",
        ),
        (
            "theory",
            "no exact equilibrium beside this run (see theory_error and warnings)",
        ),
        (
            "ddft",
            "no DDFT steady state: the ring is not driven, or the density is not observed",
        ),
        ("theory_error", "no error"),
        ("peak_density", "no density observed (observe.density)"),
        (
            "theory_l1",
            "no exact equilibrium beside the density: not observed (observe.density), a driven \
             ring, kT = 0, a Yukawa or table pair force, or the theory failed (theory_error)",
        ),
        (
            "mean_contact_density",
            "no contact density observed (observe.contact_density)",
        ),
    ] {
        out.explain("summary.json", key, why);
    }
    let summary = json!({
        "software": crate::software(),
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
        "theory": theory.as_ref().map(|_| "density_theory.csv: exact equilibrium (colloidsim theory) on the same bins"),
        "ddft": ddft.as_ref().map(|st| json!({
            "file": "density_ddft.csv: 1D DDFT steady state (colloidsim theory, adiabatic approximation) on the same bins",
            "mean_current": st.current,
            "mean_velocity": st.current * c.length / n as f64,
            "relaxation_times": st.time / st.relaxation_time,
        })),
        "theory_error": theory_error,
        "peak_density": peak_density,
        "theory_l1": theory_l1,
        "mean_contact_density": mean_contact_density,
        "warnings": warnings,
    });
    let message = format!(
        "{} steps of {n} rods in {wall:.2} s ({:.3e} particle-steps/s); outputs in {}",
        steps,
        (steps as f64 * n as f64) / wall.max(1e-9),
        out.path().display()
    );
    Ok(Finished {
        summary,
        files,
        message,
        warnings,
    })
}

/// What the rods are, for titles: "hard rods", or the sticky rods with their parameters, or
/// the rods with a soft pair force.
fn rods_label(r: &Resolved) -> String {
    let p = &r.pair;
    let mut parts = Vec::new();
    if let Some(s) = &p.sticky {
        parts.push(format!(
            "gamma = {}, eps = {}, p = {}",
            s.gamma, s.eps, s.order
        ));
    }
    if p.yukawa.is_some() {
        parts.push("Yukawa".to_string());
    }
    if p.table.is_some() {
        parts.push("tabulated pair force".to_string());
    }
    match (p.sticky.is_some(), parts.is_empty()) {
        (_, true) => "hard rods".to_string(),
        (true, false) => format!("sticky rods ({})", parts.join(", ")),
        (false, false) => format!("rods ({})", parts.join(", ")),
    }
}

/// The legend of the exact theory's curve.
fn theory_label(r: &Resolved) -> &'static str {
    if r.pair.sticky.is_some() {
        "exact theory (Baxter sticky rods, eps -> 0)"
    } else {
        "exact theory (Percus hard rods)"
    }
}

/// Wall-clock budget of the DDFT steady state drawn beside a driven run's density.
const DRIVEN_COMPANION_SECONDS: f64 = 5.0;

/// The DDFT steady state beside a driven run (`None` when the run is not a driven ring of hard
/// or sticky rods at kT > 0); an error when it fails or takes longer than
/// [`DRIVEN_COMPANION_SECONDS`].
fn driven_companion(r: &Resolved) -> Option<Result<DrivenState>> {
    let c = &r.config;
    if r.field.drive == 0.0
        || c.kt <= 0.0
        || c.boundary != Boundary::Periodic
        || r.pair.yukawa.is_some()
        || r.pair.table.is_some()
    {
        return None;
    }
    let points = r.period / default_dx(r);
    if points > MAX_COMPANION_POINTS {
        return Some(Err(anyhow::anyhow!(
            "its grid would have {points:.2e} points; compute it with colloidsim theory"
        )));
    }
    Some(driven_steady_state(r, None, Some(DRIVEN_COMPANION_SECONDS)))
}

/// The exact equilibrium beside a run: the density on the scenario's density bins and, for hard
/// rods with a contact-density observable, the contact density on its bins.
struct Counterpart {
    density: rods::BinnedProfile,
    contact: Option<ContactTheory>,
}

/// The exact contact density of hard rods on the contact-density bins.
struct ContactTheory {
    centres: Vec<f64>,
    /// Eq. 24, `rho2(x, x + sigma)`, bin-averaged.
    contact: Vec<f64>,
    /// What the window estimator (Eq. 27) reads in exact equilibrium
    /// ([`rods::Equilibrium::window_contact_average`]).
    window: Vec<f64>,
}

/// The exact equilibrium averaged over the scenario's bins, when the scenario has an
/// equilibrium (no drive, kT > 0, a density observable).
fn equilibrium_counterpart(
    sc: &Scenario,
    r: &Resolved,
    dx: Option<f64>,
    obs: &Observers,
) -> Result<Option<Counterpart>> {
    let c = &r.config;
    if r.field.drive != 0.0 || c.kt <= 0.0 || obs.density.is_none() {
        return Ok(None);
    }
    if r.pair.yukawa.is_some() || r.pair.table.is_some() {
        return Ok(None);
    }
    let bins = sc.observe.density.as_ref().map_or(100, |d| d.bins);
    // Beside a run the theory is a companion: it must not cost more than the run.
    let span = match c.boundary {
        Boundary::Periodic => r.period,
        Boundary::Walls => c.length,
    };
    let points = span / default_dx(r);
    if points > MAX_COMPANION_POINTS {
        bail!(
            "its grid would have {points:.2e} points (more than {MAX_COMPANION_POINTS:e} beside a run); compute it with colloidsim theory SCENARIO --dx {:.2e}",
            span / MAX_COMPANION_POINTS
        );
    }
    let eq = solve_theory(r, dx)?;
    let density = eq.bin_average(bins, r.period)?;
    let contact = match (&sc.observe.contact_density, &r.pair.sticky) {
        (Some(spec), None) => {
            let b = eq.bin_average(spec.bins, r.period)?;
            eq.window_contact_average(spec.bins, r.period, spec.window)?
                .map(|window| ContactTheory {
                    centres: b.centres,
                    contact: b.contact_density,
                    window,
                })
        }
        _ => None,
    };
    Ok(Some(Counterpart { density, contact }))
}

/// Largest grid of the exact theory written beside a run.
const MAX_COMPANION_POINTS: f64 = 2e6;

/// The theory's default grid spacing: 200 points per rod, at least 2000 per period.
fn default_dx(r: &Resolved) -> f64 {
    (r.config.sigma / 200.0).min(r.period / 2000.0)
}

/// The rods, potential, domain and grid of a scenario for the exact theory and the DDFT.
fn rods_problem(r: &Resolved, dx: Option<f64>) -> RodsProblem {
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
    RodsProblem::new(c.sigma, n / c.length, domain)
        .with_dx(dx.unwrap_or(default_dx(r)))
        .with_potential(BetaPotential::from_field(&r.field, c.kt))
        .with_interaction(interaction)
}

/// Relative change of the density (max-norm over `max rho`) and of the mean current between
/// two DDFT states one relaxation time apart below which the state counts as steady.
const STEADY_TOLERANCE: f64 = 1e-8;

/// Longest DDFT run for a steady state, in relaxation times `period^2 / D`.
const STEADY_MAX_TIMES: usize = 400;

/// The steady state of a driven scenario by 1D DDFT (`rods::ddft`, adiabatic approximation):
/// from the Boltzmann profile, one relaxation time `period^2 / D` at a time, until the density
/// and the mean current change by less than [`STEADY_TOLERANCE`] over one. Returns the grid,
/// the density, the mean current, the time run and the last changes; an error when no steady
/// state is reached within [`STEADY_MAX_TIMES`] relaxation times.
fn driven_steady_state(
    r: &Resolved,
    dx: Option<f64>,
    budget_seconds: Option<f64>,
) -> Result<DrivenState> {
    let start = Instant::now();
    let c = &r.config;
    let diffusion = c.mobility * c.kt;
    let tau = r.period * r.period / diffusion;
    let mut problem = rods::DdftProblem {
        rods: rods_problem(r, dx),
        diffusion,
        beta_drive: r.field.drive / c.kt,
        dt: 1e-3 * tau,
        step_tolerance: Some(1e-6),
        output_times: vec![tau],
        initial: rods::InitialProfile::Boltzmann,
    };
    let (mut x, mut rho, mut current) = (Vec::new(), Vec::new(), f64::NAN);
    let mut steps = 0;
    for k in 1..=STEADY_MAX_TIMES {
        let (mut new_rho, mut new_current) = (Vec::new(), f64::NAN);
        let s = rods::ddft(&problem, |f| {
            x = f.x.to_vec();
            new_rho = f.rho.to_vec();
            new_current = f.mean_current;
        })?;
        steps += s.steps;
        if !new_rho.iter().all(|v| v.is_finite()) || !new_current.is_finite() {
            bail!("the DDFT went non-finite after {k} relaxation times ({steps} steps)");
        }
        if k > 1 {
            let top = new_rho.iter().fold(0.0f64, |m, &v| m.max(v.abs()));
            let drho = new_rho
                .iter()
                .zip(&rho)
                .fold(0.0f64, |m, (a, b): (&f64, &f64)| m.max((a - b).abs()))
                / top;
            let dj = (new_current - current).abs() / new_current.abs().max(f64::MIN_POSITIVE);
            if drho < STEADY_TOLERANCE && dj < STEADY_TOLERANCE {
                return Ok(DrivenState {
                    x,
                    rho: new_rho,
                    current: new_current,
                    time: k as f64 * tau,
                    relaxation_time: tau,
                    steps,
                    density_change: drho,
                    current_change: dj,
                });
            }
        }
        if let Some(b) = budget_seconds
            && start.elapsed().as_secs_f64() > b
        {
            bail!(
                "not steady after {k} relaxation times and {b} s (the budget beside a run); compute it with colloidsim theory"
            );
        }
        rho = new_rho;
        current = new_current;
        problem.initial = rods::InitialProfile::Given(rho.clone());
    }
    bail!(
        "the DDFT reached no steady state in {STEADY_MAX_TIMES} relaxation times (period^2 / D = {tau}): the density still changes by more than {STEADY_TOLERANCE} (relative) per relaxation time"
    )
}

/// A DDFT steady state ([`driven_steady_state`]).
struct DrivenState {
    x: Vec<f64>,
    rho: Vec<f64>,
    current: f64,
    time: f64,
    relaxation_time: f64,
    steps: usize,
    density_change: f64,
    current_change: f64,
}

/// Mean of the periodic piecewise-linear interpolant of `(x, y)` (grid spacing uniform, period
/// `period`) over `bins` equal bins of `[0, period)`, from 16 points per bin.
fn bin_means(x: &[f64], y: &[f64], period: f64, bins: usize) -> (Vec<f64>, Vec<f64>) {
    let m = y.len();
    let h = period / m as f64;
    let x0 = x.first().copied().unwrap_or(0.0);
    let at = |t: f64| {
        let u = ((t - x0) / h).rem_euclid(m as f64);
        let i = (u.floor() as usize).min(m - 1);
        let w = u - i as f64;
        (1.0 - w) * y[i] + w * y[(i + 1) % m]
    };
    let width = period / bins as f64;
    let centres: Vec<f64> = (0..bins).map(|k| (k as f64 + 0.5) * width).collect();
    let means = (0..bins)
        .map(|k| {
            (0..16)
                .map(|j| at((k as f64 + (j as f64 + 0.5) / 16.0) * width))
                .sum::<f64>()
                / 16.0
        })
        .collect();
    (centres, means)
}

/// Write `summary.json` last and report `what` with the folder.
fn theory_report(
    outdir: &OutputDir,
    summary: serde_json::Value,
    files: Vec<String>,
    warnings: Vec<String>,
    what: String,
) -> Result<Report> {
    outdir.write_json("summary.json", &summary)?;
    Ok(Report {
        out: outdir.path().to_path_buf(),
        message: format!("{what}; outputs in {}", outdir.path().display()),
        summary,
        files,
        warnings,
    })
}

/// `colloidsim theory` of a driven scenario: the DDFT steady state on the simulation's bins.
fn driven_theory(
    src: &Source,
    sc: &Scenario,
    r: &Resolved,
    opts: &TheoryOptions,
) -> Result<Report> {
    let c = &r.config;
    if c.boundary != Boundary::Periodic {
        bail!(
            "potential.drive = {} between walls: the steady state is the equilibrium in the tilted potential, which the exact theory does not take yet; drive a ring (system.boundary = \"periodic\")",
            r.field.drive
        );
    }
    let start = Instant::now();
    let st = driven_steady_state(r, opts.dx, None)?;
    let wall = start.elapsed().as_secs_f64();
    let outdir = crate::theory_folder(src, opts)?;
    let bins = sc.observe.density.as_ref().map_or(1000, |d| d.bins);
    let (centres, means) = bin_means(&st.x, &st.rho, r.period, bins);
    outdir.write_table("density.csv", &[("x", &centres), ("rho", &means)])?;
    outdir.write_table("profile_grid.csv", &[("x", &st.x), ("rho", &st.rho)])?;
    let mut files: Vec<String> = vec!["density.csv".into(), "profile_grid.csv".into()];
    let mut warnings = Vec::new();
    picture(
        line_plot(
            &outdir.join("density.png"),
            &format!(
                "DDFT steady state of {}, sigma = {}, drive f = {} kT/length",
                rods_label(r),
                c.sigma,
                r.field.drive / c.kt
            ),
            "x (length)",
            "rho(x) (1/length)",
            &[Series {
                label: "1D DDFT steady state",
                x: &st.x,
                y: &st.rho,
                points: false,
            }],
            Scale::Linear,
        ),
        "density.png",
        &mut files,
        &mut warnings,
    );
    let mean_density = r.initial.len() as f64 / c.length;
    let summary = json!({
        "software": crate::software(),
        "method": "1D DDFT steady state of a driven system (exact Percus / Baxter functional, adiabatic approximation: not exact out of equilibrium)",
        "parameters": resolved_json(sc, r),
        "dx": st.x.get(1).map_or(f64::NAN, |x1| x1 - st.x[0]),
        "grid_points": st.x.len(),
        "mean_current": st.current,
        "mean_velocity": st.current / mean_density,
        "time": st.time,
        "relaxation_time": st.relaxation_time,
        "steps": st.steps,
        "density_change_last_relaxation_time": st.density_change,
        "current_change_last_relaxation_time": st.current_change,
        "steady_tolerance": STEADY_TOLERANCE,
        "converged": true,
        "wall_seconds": wall,
        "files": files,
        "warnings": warnings,
    });
    let what = format!(
        "DDFT steady state: mean current {:.6e} (mean velocity {:.6e}) after {:.3} relaxation times, {} grid points, in {:.3} s",
        st.current,
        st.current / mean_density,
        st.time / st.relaxation_time,
        st.x.len(),
        wall,
    );
    theory_report(&outdir, summary, files, warnings, what)
}

fn solve_theory(r: &Resolved, dx: Option<f64>) -> Result<rods::Equilibrium> {
    Ok(rods::equilibrium(&rods_problem(r, dx))?)
}

/// `colloidsim theory`: the exact equilibrium of a BCD scenario on the simulation's bins.
fn theory(src: &Source, opts: &TheoryOptions) -> Result<Report> {
    let (sc, r) = read(src, None)?;
    let dx = opts.dx;
    let c = &r.config;
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
    if r.field.drive != 0.0 {
        // No equilibrium: the steady state by DDFT.
        return driven_theory(src, &sc, &r, opts);
    }
    let start = Instant::now();
    let eq = solve_theory(&r, dx)?;
    let wall = start.elapsed().as_secs_f64();
    let outdir = crate::theory_folder(src, opts)?;
    let bins = sc.observe.density.as_ref().map_or(1000, |d| d.bins);
    let b = eq.bin_average(bins, r.period)?;
    let mut files = vec!["density.csv"];
    outdir.write_table("density.csv", &[("x", &b.centres), ("rho", &b.rho)])?;
    let cbins = sc.observe.contact_density.as_ref().map_or(bins, |d| d.bins);
    let bc = eq.bin_average(cbins, r.period)?;
    if r.pair.sticky.is_none() {
        // With a contact window, also what the window estimator (Eq. 27) reads.
        let window = match &sc.observe.contact_density {
            Some(spec) => eq.window_contact_average(cbins, r.period, spec.window)?,
            None => None,
        };
        let mut columns: Vec<(&str, &[f64])> =
            vec![("x", &bc.centres), ("rho2", &bc.contact_density)];
        if let Some(w) = &window {
            columns.push(("rho2_window", w));
        }
        outdir.write_table("contact_density.csv", &columns)?;
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
    let mut files: Vec<String> = files.into_iter().map(String::from).collect();
    let mut warnings = Vec::new();
    picture(
        line_plot(
            &outdir.join("density.png"),
            &format!(
                "exact equilibrium density of {}, sigma = {}",
                rods_label(&r),
                c.sigma
            ),
            "x (length)",
            "rho(x) (1/length)",
            &[Series {
                label: theory_label(&r),
                x: &eq.x,
                y: &eq.rho,
                points: false,
            }],
            Scale::Linear,
        ),
        "density.png",
        &mut files,
        &mut warnings,
    );
    let summary = json!({
            "software": crate::software(),
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
            "warnings": warnings,
    });
    let what = format!(
        "exact equilibrium: {} grid points, residual {:.2e} after {} iterations in {:.3} s",
        eq.x.len(),
        eq.residual,
        eq.iterations,
        wall,
    );
    theory_report(&outdir, summary, files, warnings, what)
}

#[cfg(test)]
mod tests {
    use super::*;
    use colloidsim_bcd::forces::NoField;
    use colloidsim_bcd::{BcdConfig, Update, init};

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
