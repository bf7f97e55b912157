//! DPD colloids in explicit solvent (`method = "dpd"`): velocity Verlet with DPD pair forces
//! as the thermostat; thermodynamics, MSD, g(r), S(q), coordination and clusters, GSD frames.
//! Its keys are declared in [`keys`] and read in [`params`].

#[rustfmt::skip] // declarations laid out as a table, one key to a line or three
pub mod keys;
pub mod monitor;
pub mod params;

use crate::Scenario as Source;
use crate::checkpoint::Envelope;
use crate::engine::{flat, rows};
use crate::keys::{Spec, rekey_text};
use crate::method::{Checked, Finished, Headline, Method, Session};
use crate::output::plot::{Scale, Series, line_plot, picture};
use crate::output::trajectory::FrameDigest;
use crate::output::{PairStructure, write_pair_structure};
use anyhow::{Context, Result, bail};
use colloidsim_analysis::{
    cluster_stats, contacts, coordination_histogram, coordination_numbers, pair_distribution,
};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::{CsvLog, OutputDir};
use colloidsim_dft::oz;
use colloidsim_md::dpd::setup::{DpdSetup, with_candidate};
use colloidsim_md::dpd::{Dpd, PRESSURE_PARTS, StressAcf, Thermo};
use colloidsim_md::tune::SkinTuning;
use colloidsim_particles::gsd::GsdWriter;
use colloidsim_particles::{Particles, SimBox};
use monitor::TemperatureMonitor;
use params::Resolved;
use serde::{Deserialize, Serialize};
use serde_json::json;

/// The DPD engine's names of the parameters its errors advise changing, and their keys.
const ENGINE_NAMES: &[(&str, &Spec)] =
    &[("dt", &keys::RUN_DT), ("rank_grid", &keys::RUN_RANK_GRID)];

/// An engine error as the user reads it: its parameters named by their keys.
fn rekeyed(e: colloidsim_md::DpdError) -> String {
    rekey_text(&e.to_string(), ENGINE_NAMES)
}

/// The DPD family of scenarios.
pub struct DpdMethod;

/// The scenario read and resolved, with the seed given if any.
fn resolve(src: &Source, seed: Option<u64>) -> Result<Resolved> {
    let (_, r) = params::read(&src.table()?, seed).with_context(|| src.label())?;
    Ok(r)
}

/// DPD's headline observables (summary.json).
const HEADLINE: &[Headline] = &[
    Headline {
        name: "T",
        path: "mean_temperature_second_half",
        labels: None,
        unit: "energy (kT units)",
        doc: "kinetic temperature averaged over the second half of the run (thermo.csv)",
        absent: "no thermo sample in the second half",
    },
    Headline {
        name: "P",
        path: "mean_pressure_second_half",
        labels: None,
        unit: "energy/rc^3",
        doc: "pressure (trace of the pressure tensor / 3) averaged over the second half",
        absent: "no thermo sample in the second half",
    },
    Headline {
        name: "D",
        path: "colloid_diffusion_long_time",
        labels: None,
        unit: "rc^2/time (DPD time)",
        doc: "long-time colloid self-diffusion coefficient from the MSD slope over the second \
              half of the lags (colloid_diffusion_note)",
        absent: "no colloids or no MSD",
    },
    Headline {
        name: "viscosity",
        path: "viscosity",
        labels: None,
        unit: "energy time/rc^3",
        doc: "Green-Kubo shear viscosity from the stress autocorrelation (viscosity_note)",
        absent: "not observed (observe.viscosity_every = 0)",
    },
    Headline {
        name: "shear_viscosity",
        path: "shear_viscosity",
        labels: None,
        unit: "energy time/rc^3",
        doc: "viscosity under steady shear, <-P_xy> / shear_rate (shear_viscosity_note)",
        absent: "no shear (run.shear_rate = 0)",
    },
];

impl Method for DpdMethod {
    fn names(&self) -> &'static [&'static str] {
        &["dpd"]
    }

    fn about(&self) -> &'static str {
        "DPD colloids in explicit solvent (contact, Morse and squeeze-lubrication forces)"
    }

    fn docs(&self) -> &'static str {
        "docs/dpd.md"
    }

    fn headline(&self) -> &'static [Headline] {
        HEADLINE
    }

    fn check(&self, src: &Source) -> Result<Checked> {
        let s = resolve(src, None)?;
        // What `run` does before it starts: build the system.
        s.setup.build().with_context(|| src.label())?;
        Ok(Checked {
            resolved: describe(&s),
            warnings: s.warnings.clone(),
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
        let s = resolve(src, seed)?;
        Ok(Box::new(DpdEngine {
            sim: s.setup.build()?,
            setup: s.setup,
        }))
    }
}

/// A fresh session, decomposed over the ranks of `comm` when given.
fn start(
    src: &Source,
    seed: Option<u64>,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Box<dyn Session>> {
    let mut s = resolve(src, seed)?;
    let (sync_every, _) = periods(s.steps);
    if s.tune_skin {
        if comm.as_ref().is_some_and(|c| c.size() > 1) {
            bail!(
                "{}: {}: the neighbour search is tuned on one process (each rank would time its \
                 own and choose another); tune it in a run on one process and set run.skin and \
                 run.neighbors to what it chose",
                src.label(),
                keys::RUN_TUNE_SKIN.path
            );
        }
        let t = s
            .setup
            .measure_neighbors(sync_every)
            .map_err(|e| anyhow::anyhow!(rekeyed(e)))
            .with_context(|| src.label())?;
        apply_tuning(&mut s, t);
    }
    let mut sim = match comm {
        None => s.setup.build()?,
        Some(c) => s
            .setup
            .build_decomposed(c)
            .map_err(|e| anyhow::anyhow!(rekeyed(e)))?,
    };
    sim.set_sync_every(sync_every);
    DpdSession::new(s, sim, Observed::default(), 0).map(|d| Box::new(d) as Box<dyn Session>)
}

/// The neighbour search `run.tune_skin` chose, into the engine's parameters.
fn apply_tuning(s: &mut Resolved, t: SkinTuning) {
    s.setup.params = with_candidate(s.setup.params, t.choice());
    s.skin_tuning = Some(t);
}

/// The session a checkpoint continues (on any number of ranks).
fn restore(
    src: &Source,
    seed: u64,
    out: &OutputDir,
    envelope: &Envelope,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Box<dyn Session>> {
    let mut s = resolve(src, Some(seed))?;
    let ck: Saved = crate::checkpoint::decode_payload(&envelope.payload)?;
    // The search the run chose when it started, not a new tuning (bitwise restarts).
    if let Some(t) = ck.skin_tuning.clone().filter(|_| s.tune_skin) {
        apply_tuning(&mut s, t);
    }
    if ck.sync_every != periods(s.steps).0 {
        bail!(
            "checkpoint: synchronisation period {} does not fit the scenario's {}",
            ck.sync_every,
            periods(s.steps).0
        );
    }
    let (sbox, types) = (SimBox::new(ck.box_l), DpdSetup::colloid_types());
    let (p, f, step, sync) = (ck.particles, &ck.forces, ck.step, ck.sync_every);
    let sim = Dpd::restart_on(p, f, sbox, s.setup.params, types, step, sync, comm)?;
    // Only the writer touches the folder.
    if sim.rank().0 == 0 {
        ck.obs
            .digest
            .restore(&out.join("trajectory.gsd"))
            .map_err(|e| fail_alone(&sim, e))?;
    }
    // Restoring builds the lists the interrupted run built at this step: count them once.
    let builds0 = ck.neighbor_builds.saturating_sub(sim.neighbor_builds());
    DpdSession::new(s, sim, ck.obs, builds0).map(|d| Box::new(d) as Box<dyn Session>)
}

/// An error on this rank alone: see [`Session::fail_alone`].
fn fail_alone(sim: &Dpd, e: anyhow::Error) -> anyhow::Error {
    crate::method::fail_alone_over(sim.exchange(), e)
}

/// The method's part of `checkpoint.bin`: everything a run needs to continue bitwise from
/// step `step`, a multiple of `sync_every` (`O` is `&Observed` when written, `Observed` when
/// read).
#[derive(Serialize, Deserialize)]
struct Checkpoint<O> {
    /// The engine rebuilds every list at multiples of this many steps.
    sync_every: u64,
    /// Steps done; every observation up to and including this step is in `obs`.
    step: u64,
    box_l: [f64; 3],
    /// The particles in tag order, exactly.
    particles: Particles,
    /// Forces of step `step`, tag order.
    forces: Vec<[f64; 3]>,
    /// Neighbour-list builds so far.
    neighbor_builds: u64,
    /// `run.tune_skin`: the neighbour search the run chose.
    skin_tuning: Option<SkinTuning>,
    obs: O,
}

type Saved = Checkpoint<Observed>;

/// A DPD run: the engine, its observations, the trajectory and the temperature monitor.
struct DpdSession {
    s: Resolved,
    sim: Dpd,
    obs: Observed,
    builds0: u64,
    sync_every: u64,
    checkpoint_every: u64,
    colloid_tags: Vec<u32>,
    solvent_tags: Vec<u32>,
    radii: Vec<f64>,
    gsd: Option<GsdWriter>,
    /// `thermo.csv`, appended row by row as the run goes.
    thermo_log: Option<CsvLog>,
    /// The thermodynamics of the step just taken when a GSD frame is due at it.
    frame_thermo: Option<Thermo>,
    monitor: TemperatureMonitor,
}

impl DpdSession {
    fn new(s: Resolved, sim: Dpd, obs: Observed, builds0: u64) -> Result<Self> {
        let (sync_every, checkpoint_every) = periods(s.steps);
        let p = sim.snapshot();
        let colloid_tags: Vec<u32> = (0..p.len() as u32)
            .filter(|&t| p.typeid[t as usize] == DpdSetup::COLLOID_TYPE)
            .collect();
        let solvent_tags: Vec<u32> = (0..p.len() as u32)
            .filter(|&t| p.typeid[t as usize] != DpdSetup::COLLOID_TYPE)
            .take(s.observe.msd_solvent_beads)
            .collect();
        let radii: Vec<f64> = colloid_tags
            .iter()
            .map(|&t| 0.5 * p.diameter[t as usize])
            .collect();
        let mut obs = obs;
        if s.setup.params.shear_rate != 0.0 && obs.shear.is_none() {
            obs.shear = Some(ShearObserved::new(s.steps, s.observe.profile_bins));
        }
        if s.viscosity_lags > 0 && obs.stress_acf.is_none() {
            obs.stress_acf = Some(StressAcf::new(
                s.observe.viscosity_every,
                s.viscosity_lags,
                s.setup.params.dt,
                sim.sbox.volume(),
                s.setup.params.kt,
            ));
        }
        let mut monitor = TemperatureMonitor::new(
            s.setup.params.kt,
            s.max_temperature_drift,
            s.temperature_window,
        );
        for &(step, t) in &obs.monitor {
            monitor
                .push(step, t)
                .map_err(|e| anyhow::anyhow!("the checkpoint's temperatures: {e}"))?;
        }
        Ok(Self {
            s,
            sim,
            obs,
            builds0,
            sync_every,
            checkpoint_every,
            colloid_tags,
            solvent_tags,
            radii,
            gsd: None,
            thermo_log: None,
            frame_thermo: None,
            monitor,
        })
    }

    /// Record what is due at the engine's current step.
    fn record(&mut self) -> Result<()> {
        let frame_due = self.s.observe.trajectory_every > 0
            && self
                .sim
                .step
                .is_multiple_of(self.s.observe.trajectory_every);
        if frame_due
            && self
                .frame_thermo
                .as_ref()
                .is_none_or(|t| t.step != self.sim.step)
        {
            // No step was taken with the virial (the first frame): compute it here, so that
            // every frame logs a pressure and a potential energy.
            self.frame_thermo = Some(self.sim.thermo_with_virial());
        }
        let (s, sim, obs, o) = (&self.s, &self.sim, &mut self.obs, &self.s.observe);
        let (dt, tau) = (s.setup.params.dt, s.setup.tau);
        let step = sim.step;
        if o.msd_every > 0 && step.is_multiple_of(o.msd_every) {
            let mut a = Vec::new();
            sim.unwrapped(&self.colloid_tags, &mut a);
            let mut b = Vec::new();
            sim.unwrapped(&self.solvent_tags, &mut b);
            obs.msd_steps.push(step);
            obs.colloid_frames.push(a);
            obs.solvent_frames.push(b);
        }
        if o.structure_every > 0 && step.is_multiple_of(o.structure_every) && self.radii.len() >= 2
        {
            let snap = sim.snapshot();
            let pos: Vec<[f64; 3]> = self
                .colloid_tags
                .iter()
                .map(|&t| snap.pos[t as usize])
                .collect();
            let (r, g) = pair_distribution(&pos, sim.sbox.l, s.gr_max, o.gr_bins);
            if obs.gr_sum.is_empty() {
                obs.gr_sum = vec![0.0; g.len()];
                obs.gr_sum_sq = vec![0.0; g.len()];
                obs.gr_r = r;
            }
            for ((a, q), b) in obs.gr_sum.iter_mut().zip(&mut obs.gr_sum_sq).zip(&g) {
                *a += b;
                *q += b * b;
            }
            obs.gr_samples += 1;
            let bonds = contacts(&pos, &self.radii, sim.sbox.l, s.contact_gap);
            let z = coordination_numbers(pos.len(), &bonds);
            let h = coordination_histogram(&z);
            if obs.coordination.len() < h.len() {
                obs.coordination.resize(h.len(), 0);
            }
            for (a, b) in obs.coordination.iter_mut().zip(&h) {
                *a += b;
            }
            let cs = cluster_stats(pos.len(), &bonds);
            obs.clusters.push([
                step as f64,
                step as f64 * dt / tau,
                cs.n_clusters as f64,
                cs.largest as f64,
                cs.mean_degree,
            ]);
        }
        // Every rank of a decomposed run gathers the frame; the writer writes it.
        if o.trajectory_every > 0 && step.is_multiple_of(o.trajectory_every) {
            let snap = sim.snapshot();
            // What HOOMD-blue's ThermodynamicQuantities compute logs, under its names
            // (FRAME_LOGS), from the step's virial (taken above where no step carried it).
            let t = self
                .frame_thermo
                .take()
                .filter(|t| t.step == step)
                .ok_or_else(|| {
                    anyhow::anyhow!("no thermodynamic state for the frame of step {step}")
                })?;
            let q = &t.pressure;
            let (kinetic, pressure, tensor, potential) = (
                t.temperature,
                (q[0] + q[1] + q[2]) / 3.0,
                [q[0], q[3], q[4], q[1], q[5], q[2]],
                t.potential_energy,
            );
            let values: [&[f64]; 5] = [
                &[step as f64 * dt / tau],
                &[kinetic],
                &[pressure],
                &tensor,
                &[potential],
            ];
            let log: Vec<(&str, &[f64])> = FRAME_LOGS.iter().copied().zip(values).collect();
            if let Some(w) = self.gsd.as_mut() {
                w.write_frame_log(step, &sim.sbox, &snap, &log)
                    .map_err(|e| fail_alone(sim, e.into()))?;
            }
            obs.frames += 1;
        }
        Ok(())
    }

    /// One step with its thermodynamics and temperature check; `Some(why)` when the run
    /// cannot go on.
    fn step(&mut self) -> Result<Option<String>> {
        let o = &self.s.observe;
        let dt = self.s.setup.params.dt;
        let next = self.sim.step + 1;
        let thermo_due = o.thermo_every > 0 && next.is_multiple_of(o.thermo_every);
        let frame_due = o.trajectory_every > 0 && next.is_multiple_of(o.trajectory_every);
        let acf = self.obs.stress_acf.as_mut();
        let shear = self.obs.shear.as_mut();
        let result = if thermo_due || frame_due {
            self.sim.advance_with_thermo().map(|th| {
                if let Some(acf) = acf {
                    acf.push(&th.pressure);
                }
                if let Some(sh) = shear {
                    sh.push(next, &th.pressure);
                }
                if thermo_due {
                    self.obs.thermo.push((next as f64 * dt, th.clone()));
                }
                if frame_due {
                    self.frame_thermo = Some(th);
                }
            })
        } else if acf.is_some() || shear.is_some() {
            // The Green–Kubo samples average the pressure tensor over every step, and so does
            // the mean shear stress.
            self.sim.advance_with_pressure().map(|p| {
                if let Some(acf) = acf {
                    acf.push(&p);
                }
                if let Some(sh) = shear {
                    sh.push(next, &p);
                }
            })
        } else {
            self.sim.advance()
        };
        if let Err(e) = result {
            return Ok(Some(rekeyed(e)));
        }
        // The shear stress by part (kinetic, each pair force class) from the same step.
        if let Some(sh) = self.obs.shear.as_mut() {
            sh.push_parts(next, &self.sim.pressure_parts());
        }
        // The velocity profile over the second half, every thermo_every (or 100) steps.
        let profile_every = if o.thermo_every > 0 {
            o.thermo_every
        } else {
            100
        };
        if let Some(sh) = self.obs.shear.as_mut()
            && next > self.s.steps / 2
            && next.is_multiple_of(profile_every)
        {
            self.sim
                .add_velocity_profile(&mut sh.profile_sum, &mut sh.profile_count);
            sh.profile_samples += 1;
        }
        if let Some(log) = self.thermo_log.as_mut()
            && let Some((time, th)) = self.obs.thermo.last().filter(|(_, th)| th.step == next)
        {
            log.append(&thermo_row(
                *time,
                th,
                self.sim.sbox.volume(),
                self.s.setup.tau,
            ))
            .map_err(|e| fail_alone(&self.sim, e.into()))?;
        }
        let check_every = if o.thermo_every > 0 {
            o.thermo_every
        } else {
            100
        };
        if next.is_multiple_of(check_every) {
            let t = self
                .obs
                .thermo
                .last()
                .filter(|(_, th)| th.step == next)
                .map(|(_, th)| th.temperature)
                .unwrap_or_else(|| self.sim.thermo().temperature);
            self.obs.monitor.push((next, t));
            if let Err(e) = self.monitor.push(next, t) {
                return Ok(Some(e));
            }
        }
        self.record()?;
        Ok(None)
    }
}

impl Session for DpdSession {
    fn label(&self) -> String {
        "dpd".into()
    }

    fn total(&self) -> u64 {
        self.s.steps
    }

    fn position(&self) -> u64 {
        self.sim.step
    }

    fn seed(&self) -> u64 {
        self.s.setup.params.seed as u64
    }

    fn status(&self) -> String {
        let t = self.sim.step as f64 * self.s.setup.params.dt / self.s.setup.tau;
        let mut s = format!("t = {} tau_D", crate::driver::significant(t));
        if let Some((_, th)) = self.obs.thermo.last() {
            s.push_str(&format!(", T = {:.4}", th.temperature));
        }
        s
    }

    fn parameters(&self) -> serde_json::Value {
        describe(&self.s)
    }

    fn warnings(&self) -> Vec<String> {
        self.s.warnings.clone()
    }

    fn writes(&self, name: &str) -> bool {
        [
            "thermo.csv",
            "msd.csv",
            "msd.png",
            "gr.csv",
            "gr_percus_yevick.csv",
            "gr.png",
            "sq.csv",
            "coordination.csv",
            "clusters.csv",
            "stress_acf.csv",
            "stress_acf.png",
            "velocity_profile.csv",
            "trajectory.gsd",
        ]
        .contains(&name)
    }

    fn begin(&mut self, out: &OutputDir, fresh: bool) -> Result<()> {
        if !self.is_writer() {
            if fresh {
                self.record()?;
            }
            return Ok(());
        }
        if self.s.setup.colloids == 0 {
            out.explain("thermo.csv", "T_colloid", "no colloids");
        }
        if self.s.setup.solvent == 0 {
            out.explain("thermo.csv", "T_solvent", "no solvent beads");
        }
        if self.s.observe.thermo_every > 0 {
            let (vol, tau) = (self.sim.sbox.volume(), self.s.setup.tau);
            self.thermo_log = Some(CsvLog::start_in(
                out,
                "thermo.csv",
                &THERMO_COLUMNS,
                fresh,
                || thermo_rows_of(&self.obs, vol, tau),
            )?);
        }
        if self.s.observe.trajectory_every > 0 {
            let traj = out.join("trajectory.gsd");
            self.gsd = Some(crate::output::trajectory::writer(&traj, !fresh)?.with_velocities());
        }
        if fresh {
            self.record()?;
        }
        Ok(())
    }

    fn next_checkpoint(&self) -> Option<u64> {
        Some((self.sim.step / self.checkpoint_every + 1) * self.checkpoint_every)
    }

    fn exchange(&self) -> Option<&dyn Exchange> {
        self.sim.exchange()
    }

    /// The engine restarts bitwise only where it rebuilds every list.
    fn stop_point(&self) -> u64 {
        self.sim
            .step
            .next_multiple_of(self.sync_every)
            .min(self.s.steps)
    }

    fn advance(&mut self, until: u64) -> Result<Option<String>> {
        while self.sim.step < until {
            if let Some(why) = self.step()? {
                return Ok(Some(why));
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

    fn save(&mut self, out: &OutputDir) -> Result<Vec<u8>> {
        if self.s.observe.trajectory_every > 0 && self.is_writer() {
            self.obs
                .digest
                .extend(&out.join("trajectory.gsd"), self.obs.frames)
                .map_err(|e| fail_alone(&self.sim, e))?;
        }
        let ck = Checkpoint {
            sync_every: self.sync_every,
            step: self.sim.step,
            box_l: self.sim.sbox.l,
            particles: self.sim.snapshot(),
            forces: self.sim.forces(),
            neighbor_builds: self.builds0 + self.sim.neighbor_builds(),
            skin_tuning: self.s.skin_tuning.clone(),
            obs: &self.obs,
        };
        Ok(bincode::serialize(&ck)?)
    }

    fn interim_outputs(&mut self, out: &OutputDir) -> Result<Vec<String>> {
        if !self.is_writer() {
            return Ok(Vec::new());
        }
        let mut warnings = Vec::new();
        Ok(write_outputs(out, &self.s, &self.sim, &self.obs, &mut warnings)?.0)
    }

    fn finish(
        self: Box<Self>,
        out: &OutputDir,
        wall: f64,
        _failure: Option<&str>,
    ) -> Result<Finished> {
        if !self.is_writer() {
            return Ok(Finished::nothing_written());
        }
        let mut warnings = Vec::new();
        let (files, diffusion) = write_outputs(out, &self.s, &self.sim, &self.obs, &mut warnings)?;
        let builds = self.builds0 + self.sim.neighbor_builds();
        let summary = summary(
            &self.s, &self.sim, &self.obs, diffusion, builds, wall, &warnings,
        );
        // A value left null has its reason in the note beside it (summary.json's nulls).
        for (note, keys) in [
            ("viscosity_note", &NOTED_VISCOSITY[..]),
            ("shear_viscosity_note", &NOTED_SHEAR[..]),
            ("colloid_diffusion_note", &NOTED_DIFFUSION[..]),
        ] {
            if summary[note].is_string() {
                for k in keys {
                    out.explain("summary.json", k, &format!("see {note}"));
                }
            }
        }
        if self.s.setup.colloids == 0 {
            for k in [
                "final_temperature_by_type[1]",
                "mean_colloid_temperature_second_half",
            ] {
                out.explain("summary.json", k, "no colloids");
            }
        }
        let (s, dt, tau) = (&self.s, self.s.setup.params.dt, self.s.setup.tau);
        let message = format!(
            "dpd: {} colloids + {} solvent beads, {} steps ({:.3} tau_D) in {:.1} s -> {}\nwrote {}",
            s.setup.colloids,
            s.setup.solvent,
            self.sim.step,
            self.sim.step as f64 * dt / tau,
            wall,
            out.path().display(),
            files.join(", ")
        );
        Ok(Finished {
            summary,
            files,
            message,
            warnings,
        })
    }
}

/// A DPD engine stepped by hand, with what sets it up afresh ([`crate::Engine::set_state`]).
struct DpdEngine {
    sim: Dpd,
    setup: colloidsim_md::dpd::setup::DpdSetup,
}

impl crate::Engine for DpdEngine {
    fn method(&self) -> &str {
        "dpd"
    }
    fn dimensions(&self) -> usize {
        3
    }
    fn particles(&self) -> usize {
        self.sim.snapshot().len()
    }
    fn step(&mut self, steps: u64) -> Result<()> {
        for _ in 0..steps {
            self.sim
                .advance()
                .map_err(|e| anyhow::anyhow!(rekeyed(e)))?;
        }
        Ok(())
    }
    fn steps(&self) -> u64 {
        self.sim.step
    }
    fn time(&self) -> f64 {
        self.sim.step as f64 * self.sim.params().dt
    }
    fn dt(&self) -> f64 {
        self.sim.params().dt
    }
    fn positions(&self) -> Vec<f64> {
        let n = self.sim.snapshot().len() as u32;
        let mut x = Vec::new();
        self.sim.unwrapped(&(0..n).collect::<Vec<_>>(), &mut x);
        flat(&x)
    }
    fn velocities(&self) -> Option<Vec<f64>> {
        Some(flat(&self.sim.snapshot().vel))
    }
    fn forces(&self) -> Result<Vec<f64>> {
        Ok(flat(&self.sim.forces()))
    }
    fn box_lengths(&self) -> Vec<f64> {
        self.sim.sbox.l.to_vec()
    }
    fn seed(&self) -> u32 {
        self.sim.params().seed
    }
    fn types(&self) -> Option<crate::engine::ParticleTypes> {
        Some(crate::engine::ParticleTypes::of(&self.sim.snapshot()))
    }
    /// Colloids given overlapping positions are refused (as at the start).
    fn set_state(&mut self, change: crate::StateChange) -> Result<()> {
        change.check(self.particles(), 3, true, "dpd")?;
        let mut p = self.sim.snapshot();
        if let Some(x) = &change.positions {
            for ((q, img), x) in p.pos.iter_mut().zip(&mut p.image).zip(rows(x)) {
                *q = x;
                *img = [0; 3];
            }
        }
        if let Some(v) = &change.velocities {
            p.vel = rows(v);
        }
        let mut setup = self.setup.clone();
        setup.params.seed = change.seed.unwrap_or(self.seed());
        let step = change.step.unwrap_or(self.sim.step);
        self.sim = setup
            .build_from(p, step)
            .map_err(|e| match change.positions {
                Some(_) => anyhow::anyhow!("positions: {}", rekeyed(e)),
                None => anyhow::anyhow!(rekeyed(e)),
            })?;
        self.setup = setup;
        Ok(())
    }
}

fn describe(s: &Resolved) -> serde_json::Value {
    let p = &s.setup.params;
    let c = &p.colloid;
    let mut v = json!({
        "box": s.setup.sbox.l,
        "colloids": s.setup.colloids,
        "solvent_beads": s.setup.solvent,
        "colloid_radius": s.setup.radius,
        "radius_distribution": format!("{:?}", s.setup.distribution),
        "density": s.setup.density,
        "solvent_mass": s.setup.solvent_mass,
        "kT": p.kt,
        "gamma": p.gamma,
        "rc": p.rc,
        "repulsion_solvent_solvent": p.repulsion * p.kt / p.rc,
        "colloid_solvent_surface_cutoff": colloidsim_md::dpd::colloid_solvent_cutoff(p.rc, s.setup.radius),
        "colloid_solvent_centre_cutoff": s.setup.radius + colloidsim_md::dpd::colloid_solvent_cutoff(p.rc, s.setup.radius),
        "repulsion_colloid_solvent": p.repulsion_cs * p.kt / colloidsim_md::dpd::colloid_solvent_cutoff(p.rc, s.setup.radius),
        "colloid_colloid_surface_cutoff": p.colloid_cutoff,
        "contact_modulus": c.contact,
        "contact_range": c.contact_range,
        "morse_depth": c.morse_depth,
        "morse_kappa": c.morse_kappa,
        "morse_r0": c.morse_r0,
        "eta0_lubrication": c.eta0,
        "lubrication_gap": c.lubrication_gap,
        "lubrication_noise": format!("{:?}", p.lubrication_noise).to_lowercase(),
        "dt": p.dt,
        "skin": p.skin,
        "steps": s.steps,
        "stokes_einstein_diffusion_D0": s.setup.d0,
        "diffusion_time_tau": s.setup.tau,
        "steps_per_tau": s.setup.tau / p.dt,
        "contact_gap": s.contact_gap,
        "solvent_viscosity_kinetic_theory": solvent_viscosity_kinetic_theory(s),
        "shear_rate": p.shear_rate,
    });
    if let Some(t) = &s.skin_tuning {
        v["skin_tuning"] = json!(t);
    }
    v
}

/// What a run accumulates; all of it is saved in every checkpoint.
#[derive(Default, Serialize, Deserialize)]
struct Observed {
    #[serde(with = "thermo_rows")]
    thermo: Vec<(f64, Thermo)>,
    msd_steps: Vec<u64>,
    colloid_frames: Vec<Vec<[f64; 3]>>,
    solvent_frames: Vec<Vec<[f64; 3]>>,
    gr_sum: Vec<f64>,
    /// Sums of g(r)^2 over the samples, for the standard error of g(r).
    gr_sum_sq: Vec<f64>,
    gr_r: Vec<f64>,
    gr_samples: usize,
    coordination: Vec<u64>,
    clusters: Vec<[f64; 5]>,
    /// Every (step, temperature) fed to the temperature monitor: a restart feeds them again,
    /// which restores its state exactly.
    monitor: Vec<(u64, f64)>,
    /// Frames in trajectory.gsd.
    frames: u64,
    /// CRC-32 of those frames, checked before a restart appends to the file.
    digest: FrameDigest,
    /// The running stress autocorrelation (`observe.viscosity_every > 0`).
    stress_acf: Option<StressAcf>,
    /// Shear stress and velocity profile of a Lees–Edwards run (`run.shear_rate > 0`).
    shear: Option<ShearObserved>,
}

/// What a shear run accumulates (in the checkpoint): the shear stress `-P_xy` of every step
/// summed over chunks of steps, and the velocity profile over the second half.
#[derive(Default, Serialize, Deserialize)]
struct ShearObserved {
    /// Steps per chunk: `max(1, steps / 1000)`.
    chunk: u64,
    /// `sum -P_xy` over the steps `k chunk + 1 ..= (k + 1) chunk` (entry `k`).
    stress: Vec<f64>,
    /// The same sums of each part of `-P_xy` ([`PRESSURE_PARTS`]); empty in a checkpoint
    /// written before the parts were recorded.
    #[serde(default)]
    parts: Vec<[f64; PRESSURE_PARTS.len()]>,
    /// `sum v_x` and the number of particles per y bin, over the profile samples.
    profile_sum: Vec<f64>,
    profile_count: Vec<f64>,
    /// Profile samples taken.
    profile_samples: u64,
}

impl ShearObserved {
    fn new(steps: u64, bins: usize) -> Self {
        Self {
            chunk: (steps / 1000).max(1),
            stress: Vec::new(),
            parts: Vec::new(),
            profile_sum: vec![0.0; bins],
            profile_count: vec![0.0; bins],
            profile_samples: 0,
        }
    }

    /// Add the shear stress `-P_xy` of step `step` (1-based).
    fn push(&mut self, step: u64, pressure: &[f64; 6]) {
        let k = ((step - 1) / self.chunk) as usize;
        if self.stress.len() <= k {
            self.stress.resize(k + 1, 0.0);
        }
        self.stress[k] -= pressure[3];
    }

    /// Add the parts of `-P_xy` of step `step` (1-based), [`Dpd::pressure_parts`]' xy
    /// components.
    fn push_parts(&mut self, step: u64, parts: &[[f64; 6]; PRESSURE_PARTS.len()]) {
        let k = ((step - 1) / self.chunk) as usize;
        if self.parts.len() <= k {
            self.parts.resize(k + 1, [0.0; PRESSURE_PARTS.len()]);
        }
        for (s, p) in self.parts[k].iter_mut().zip(parts) {
            *s -= p[3];
        }
    }

    /// Mean shear stress `<-P_xy>` over the complete chunks of the second half of `steps`
    /// steps and the standard error of 10 block means (at least 10 chunks), or why not.
    fn mean_stress(&self, steps: u64) -> std::result::Result<(f64, f64, u64), String> {
        self.block_mean(&self.stress, steps)
    }

    /// [`Self::mean_stress`] of each part, or why not (also when a run continued from a
    /// checkpoint without the parts).
    fn mean_parts(&self, steps: u64) -> std::result::Result<Vec<(f64, f64)>, String> {
        if self.parts.len() != self.stress.len() {
            return Err("the run continued from a checkpoint that did not record the parts".into());
        }
        (0..PRESSURE_PARTS.len())
            .map(|p| {
                let part: Vec<f64> = self.parts.iter().map(|c| c[p]).collect();
                self.block_mean(&part, steps).map(|(m, e, _)| (m, e))
            })
            .collect()
    }

    /// Mean of the per-step values whose chunk sums are `sums` over the complete chunks of
    /// the second half, with the standard error of 10 block means.
    fn block_mean(&self, sums: &[f64], steps: u64) -> std::result::Result<(f64, f64, u64), String> {
        let complete = (steps / self.chunk) as usize;
        let first = complete / 2;
        let chunks = &sums[first.min(sums.len())..complete.min(sums.len())];
        if chunks.len() < 10 {
            return Err(format!(
                "the second half holds {} chunks of {} steps; need 10 (a run of at least 20 steps)",
                chunks.len(),
                self.chunk
            ));
        }
        let per = chunks.len() / 10;
        let means: Vec<f64> = (0..10)
            .map(|b| {
                chunks[b * per..(b + 1) * per].iter().sum::<f64>()
                    / (per as u64 * self.chunk) as f64
            })
            .collect();
        let mean = means.iter().sum::<f64>() / 10.0;
        let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / 9.0;
        Ok((mean, (var / 10.0).sqrt(), 10 * per as u64 * self.chunk))
    }

    /// Bin centres, mean `v_x` per bin (NaN in an empty bin) and the least-squares slope.
    fn profile(&self, ly: f64) -> (Vec<f64>, Vec<f64>, Option<f64>) {
        let bins = self.profile_sum.len();
        let y: Vec<f64> = (0..bins)
            .map(|b| -0.5 * ly + (b as f64 + 0.5) * ly / bins as f64)
            .collect();
        let v: Vec<f64> = self
            .profile_sum
            .iter()
            .zip(&self.profile_count)
            .map(|(s, &c)| if c > 0.0 { s / c } else { f64::NAN })
            .collect();
        let pts: Vec<(f64, f64)> = y
            .iter()
            .zip(&v)
            .filter(|(_, v)| v.is_finite())
            .map(|(&a, &b)| (a, b))
            .collect();
        let slope = (pts.len() >= 2).then(|| {
            let n = pts.len() as f64;
            let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
            let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
            let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
            let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
            sxy / sxx
        });
        (y, v, slope)
    }
}

/// `(time, Thermo)` rows through a serialisable mirror of [`Thermo`].
mod thermo_rows {
    use colloidsim_md::dpd::{PairVirial, Thermo};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    #[derive(Serialize, Deserialize)]
    struct Row {
        time: f64,
        step: u64,
        temperature_by_type: Vec<f64>,
        temperature: f64,
        kinetic: [f64; 6],
        /// Conservative, dissipative, random, contact, Morse, lubrication.
        virial: [[f64; 6]; 6],
        /// Conservative, contact, Morse energies.
        energies: [f64; 3],
        pressure: [f64; 6],
        potential_energy: f64,
        momentum: [f64; 3],
    }

    pub fn serialize<S: Serializer>(rows: &[(f64, Thermo)], s: S) -> Result<S::Ok, S::Error> {
        let rows: Vec<Row> = rows
            .iter()
            .map(|(time, t)| {
                let v = &t.virial;
                Row {
                    time: *time,
                    step: t.step,
                    temperature_by_type: t.temperature_by_type.clone(),
                    temperature: t.temperature,
                    kinetic: t.kinetic,
                    virial: [
                        v.conservative,
                        v.dissipative,
                        v.random,
                        v.contact,
                        v.morse,
                        v.lubrication,
                    ],
                    energies: [v.energy_conservative, v.energy_contact, v.energy_morse],
                    pressure: t.pressure,
                    potential_energy: t.potential_energy,
                    momentum: t.momentum,
                }
            })
            .collect();
        rows.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<(f64, Thermo)>, D::Error> {
        let rows = Vec::<Row>::deserialize(d)?;
        Ok(rows
            .into_iter()
            .map(|r| {
                let [
                    conservative,
                    dissipative,
                    random,
                    contact,
                    morse,
                    lubrication,
                ] = r.virial;
                let [energy_conservative, energy_contact, energy_morse] = r.energies;
                let thermo = Thermo {
                    step: r.step,
                    temperature_by_type: r.temperature_by_type,
                    temperature: r.temperature,
                    kinetic: r.kinetic,
                    virial: PairVirial {
                        conservative,
                        dissipative,
                        random,
                        contact,
                        morse,
                        lubrication,
                        energy_conservative,
                        energy_contact,
                        energy_morse,
                        // Not kept in checkpoints: parts of the classes above.
                        ..PairVirial::default()
                    },
                    pressure: r.pressure,
                    potential_energy: r.potential_energy,
                    momentum: r.momentum,
                };
                (r.time, thermo)
            })
            .collect())
    }
}

/// The synchronisation period and the period of the regular checkpoints (a multiple of it,
/// about 10 % of the run): the engine rebuilds every list at multiples of the first, so that a
/// run restarted there continues bitwise; Ctrl-C runs on to the next such step.
fn periods(steps: u64) -> (u64, u64) {
    let tenth = (steps / 10).max(1);
    let sync = tenth.min(SYNC_MAX);
    let every = ((tenth as f64 / sync as f64).round() as u64).max(1) * sync;
    (sync, every)
}

/// Longest synchronisation period (steps).
const SYNC_MAX: u64 = 1000;

/// MSD at lags of whole frames, averaged over at most ~200 time origins per lag.
fn msd(frames: &[Vec<[f64; 3]>]) -> Vec<f64> {
    let f = frames.len();
    let stride = (f / 200).max(1);
    (1..f)
        .map(|lag| {
            let mut s = 0.0;
            let mut c = 0usize;
            for t0 in (0..f - lag).step_by(stride) {
                for (a, b) in frames[t0].iter().zip(&frames[t0 + lag]) {
                    s += (0..3).map(|k| (b[k] - a[k]).powi(2)).sum::<f64>();
                }
                c += frames[t0].len();
            }
            if c > 0 { s / c as f64 } else { f64::NAN }
        })
        .collect()
}

/// The log quantities of every GSD frame: the time in tau_D, then HOOMD-blue's names for the
/// kinetic temperature, the pressure, the pressure tensor (xx, xy, xz, yy, yz, zz) and the
/// potential energy.
const FRAME_LOGS: [&str; 5] = [
    "time_tau",
    "md/compute/ThermodynamicQuantities/kinetic_temperature",
    "md/compute/ThermodynamicQuantities/pressure",
    "md/compute/ThermodynamicQuantities/pressure_tensor",
    "md/compute/ThermodynamicQuantities/potential_energy",
];

/// The columns of `thermo.csv`.
const THERMO_COLUMNS: [&str; 24] = [
    "step",
    "time",
    "time_tau",
    "T",
    "T_solvent",
    "T_colloid",
    "p",
    "pxx",
    "pyy",
    "pzz",
    "pxy",
    "pxz",
    "pyz",
    "p_kinetic",
    "p_conservative",
    "p_dissipative",
    "p_random",
    "p_contact",
    "p_morse",
    "p_lubrication",
    "energy_conservative",
    "energy_contact",
    "energy_morse",
    "energy_potential",
];

/// One row of `thermo.csv`: the thermodynamics `t` at simulated time `time`, in a box of
/// volume `vol`, with the colloid diffusion time `tau`.
fn thermo_row(time: f64, t: &Thermo, vol: f64, tau: f64) -> Vec<f64> {
    let tr = |v: &[f64; 6]| (v[0] + v[1] + v[2]) / (3.0 * vol);
    let v = &t.virial;
    let p = &t.pressure;
    vec![
        t.step as f64,
        time,
        time / tau,
        t.temperature,
        t.temperature_by_type[0],
        t.temperature_by_type.get(1).copied().unwrap_or(f64::NAN),
        (p[0] + p[1] + p[2]) / 3.0,
        p[0],
        p[1],
        p[2],
        p[3],
        p[4],
        p[5],
        (t.kinetic[0] + t.kinetic[1] + t.kinetic[2]) / 3.0,
        tr(&v.conservative),
        tr(&v.dissipative),
        tr(&v.random),
        tr(&v.contact),
        tr(&v.morse),
        tr(&v.lubrication),
        v.energy_conservative,
        v.energy_contact,
        v.energy_morse,
        t.potential_energy,
    ]
}

fn thermo_rows_of(obs: &Observed, vol: f64, tau: f64) -> Vec<Vec<f64>> {
    obs.thermo
        .iter()
        .map(|(time, t)| thermo_row(*time, t, vol, tau))
        .collect()
}

/// The tables and pictures of what has been observed so far; returns their names and the
/// long-time colloid diffusion coefficient.
fn write_outputs(
    out: &OutputDir,
    s: &Resolved,
    sim: &Dpd,
    obs: &Observed,
    warnings: &mut Vec<String>,
) -> Result<(Vec<String>, Option<f64>)> {
    let dt = s.setup.params.dt;
    let tau = s.setup.tau;
    let mut files = Vec::new();
    let vol = sim.sbox.volume();
    // thermo.csv (also written row by row as the run goes: `DpdSession::step`)
    if !obs.thermo.is_empty() {
        let rows = thermo_rows_of(obs, vol, tau);
        out.write_rows("thermo.csv", &THERMO_COLUMNS, &rows)?;
        files.push("thermo.csv".to_string());
    }
    // msd.csv
    let mut diffusion = None;
    // A kind of particle that is not followed (no colloids, observe.msd_solvent_beads = 0)
    // has no MSD: its column is left out rather than written as not a number.
    let has_colloids = s.setup.colloids > 0;
    let has_beads = obs.solvent_frames.first().is_some_and(|f| !f.is_empty());
    if obs.msd_steps.len() >= 2 && (has_colloids || has_beads) {
        let mc = msd(&obs.colloid_frames);
        let ms = msd(&obs.solvent_frames);
        let lag_steps: Vec<f64> = (1..obs.msd_steps.len())
            .map(|k| (obs.msd_steps[k] - obs.msd_steps[0]) as f64)
            .collect();
        let time: Vec<f64> = lag_steps.iter().map(|l| l * dt).collect();
        let time_tau: Vec<f64> = time.iter().map(|t| t / tau).collect();
        let mut columns: Vec<(&str, &[f64])> = vec![
            ("lag_steps", &lag_steps),
            ("time", &time),
            ("time_tau", &time_tau),
        ];
        if has_colloids {
            columns.push(("msd_colloid", &mc));
        }
        if has_beads {
            columns.push(("msd_solvent", &ms));
        }
        out.write_table("msd.csv", &columns)?;
        files.push("msd.csv".into());
        // Long-time colloid diffusion: slope of the MSD over the second half of the lags
        // (least squares), D = slope / 6; only when that half starts at a lag of at least one
        // colloid diffusion time tau_D = R^2 / D0 (before it the slope is the short-time
        // motion, not the long-time self-diffusion).
        let n = mc.len();
        if s.setup.colloids > 0 && n >= 4 && time_tau[n / 2] >= 1.0 {
            let (a, b) = (n / 2, n);
            let xs = &time[a..b];
            let ys = &mc[a..b];
            let mx = xs.iter().sum::<f64>() / xs.len() as f64;
            let my = ys.iter().sum::<f64>() / ys.len() as f64;
            let sxy: f64 = xs.iter().zip(ys).map(|(x, y)| (x - mx) * (y - my)).sum();
            let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
            if sxx > 0.0 {
                diffusion = Some(sxy / sxx / 6.0);
            }
        }
        let series = [
            Series {
                label: "colloids",
                x: &time_tau,
                y: &mc,
                points: false,
            },
            Series {
                label: "solvent beads",
                x: &time_tau,
                y: &ms,
                points: false,
            },
        ];
        let shown: Vec<Series> = series
            .into_iter()
            .zip([has_colloids, has_beads])
            .filter_map(|(series, followed)| followed.then_some(series))
            .collect();
        picture(
            line_plot(
                &out.join("msd.png"),
                &format!(
                    "MSD, DPD colloids (phi = {:.3}, {} colloids)",
                    s.setup.colloids as f64 * 4.0 / 3.0
                        * std::f64::consts::PI
                        * s.setup.radius.powi(3)
                        / vol,
                    s.setup.colloids
                ),
                "t / tau_D",
                "mean-squared displacement [rc^2]",
                &shown,
                Scale::LogLog,
            ),
            "msd.png",
            &mut files,
            warnings,
        );
    }
    // g(r), S(q), coordination, clusters
    if obs.gr_samples > 0 {
        let g: Vec<f64> = obs
            .gr_sum
            .iter()
            .map(|x| x / obs.gr_samples as f64)
            .collect();
        let r = &obs.gr_r;
        // Standard error of the mean over the structure samples (their scatter; samples closer
        // than the structural relaxation time are correlated, so this is a lower bound then).
        let m = obs.gr_samples as f64;
        let err: Vec<f64> = obs
            .gr_sum_sq
            .iter()
            .zip(&g)
            .map(|(q, mean)| {
                if obs.gr_samples < 2 {
                    f64::NAN
                } else {
                    ((q / m - mean * mean).max(0.0) / (m - 1.0)).sqrt()
                }
            })
            .collect();
        if obs.gr_samples < 2 {
            out.explain("gr.csv", "err", "one sample: no standard error");
        }
        // The hard-sphere reference: Percus–Yevick at the colloids' volume fraction (the
        // contact force is hard to 1e-3 diameters; docs/dpd.md).
        let phi =
            s.setup.colloids as f64 * 4.0 / 3.0 * std::f64::consts::PI * s.setup.radius.powi(3)
                / vol;
        let py = (phi > 0.0 && phi <= oz::ETA_MAX)
            .then(|| oz::solve(phi, &oz::PyOptions::default()).ok())
            .flatten();
        write_pair_structure(
            out,
            &PairStructure {
                r,
                g: &g,
                err: &err,
                diameter: 2.0 * s.setup.radius,
                rho: s.setup.colloids as f64 / vol,
                r_max: s.gr_max,
                percus_yevick: py.as_ref(),
                label: "colloids (bars: standard error)",
                title: &format!("Colloid g(r), phi = {phi:.3}, {} samples", obs.gr_samples),
                xlabel: "r / (2 R_c) (colloid diameters)",
            },
            &mut files,
            warnings,
        )?;
        let total: u64 = obs.coordination.iter().sum();
        let z: Vec<f64> = (0..obs.coordination.len()).map(|k| k as f64).collect();
        let pz: Vec<f64> = obs
            .coordination
            .iter()
            .map(|&c| c as f64 / total.max(1) as f64)
            .collect();
        out.write_table("coordination.csv", &[("z", &z), ("probability", &pz)])?;
        files.push("coordination.csv".into());
        let col = |k: usize| obs.clusters.iter().map(|r| r[k]).collect::<Vec<f64>>();
        out.write_table(
            "clusters.csv",
            &[
                ("step", &col(0)),
                ("time_tau", &col(1)),
                ("clusters", &col(2)),
                ("largest", &col(3)),
                ("mean_degree", &col(4)),
            ],
        )?;
        files.push("clusters.csv".into());
    }
    // stress_acf.csv: the Green–Kubo correlation function and its running integral.
    if let Some(acf) = &obs.stress_acf
        && acf.counted() > 0
    {
        let t = acf.table();
        out.write_table(
            "stress_acf.csv",
            &[
                ("lag_steps", &t.lag_steps),
                ("time", &t.time),
                ("acf", &t.acf),
                ("viscosity_integral", &t.integral),
                ("acf_off_diagonal", &t.acf_off_diagonal),
                ("viscosity_integral_off_diagonal", &t.integral_off_diagonal),
            ],
        )?;
        files.push("stress_acf.csv".into());
        let series = [
            Series {
                label: "all components (traceless stress)",
                x: &t.time,
                y: &t.integral,
                points: false,
            },
            Series {
                label: "off-diagonal components",
                x: &t.time,
                y: &t.integral_off_diagonal,
                points: false,
            },
        ];
        picture(
            line_plot(
                &out.join("stress_acf.png"),
                &format!(
                    "Green-Kubo viscosity, {} samples of {} steps",
                    acf.counted(),
                    s.observe.viscosity_every
                ),
                "upper limit t_max [DPD time]",
                "viscosity up to t_max [m_s / (rc DPD time)]",
                &series,
                Scale::Linear,
            ),
            "stress_acf.png",
            &mut files,
            warnings,
        );
    }
    // velocity_profile.csv: v_x(y) of a shear run, beside the imposed gamma_dot y.
    if let Some(sh) = &obs.shear
        && sh.profile_samples > 0
    {
        let (y, v, _) = sh.profile(sim.sbox.l[1]);
        let imposed: Vec<f64> = y.iter().map(|y| s.setup.params.shear_rate * y).collect();
        let samples = vec![sh.profile_samples as f64; y.len()];
        if v.iter().any(|x| !x.is_finite()) {
            out.explain(
                "velocity_profile.csv",
                "v_x",
                "no particle sampled in the bin (particle_samples = 0)",
            );
        }
        out.write_table(
            "velocity_profile.csv",
            &[
                ("y", &y),
                ("v_x", &v),
                ("v_x_imposed", &imposed),
                ("particle_samples", &sh.profile_count),
                ("profile_samples", &samples),
            ],
        )?;
        files.push("velocity_profile.csv".into());
    }
    if s.observe.trajectory_every > 0 {
        files.push("trajectory.gsd".into());
    }
    Ok((files, diffusion))
}

/// The summary values that `viscosity_note`, `shear_viscosity_note` and
/// `colloid_diffusion_note` explain when they are null.
const NOTED_VISCOSITY: [&str; 4] = [
    "viscosity",
    "viscosity_error",
    "viscosity_off_diagonal",
    "viscosity_off_diagonal_error",
];
const NOTED_SHEAR: [&str; 6] = [
    "shear_stress",
    "shear_stress_error",
    "shear_viscosity",
    "shear_viscosity_error",
    "shear_stress_parts",
    "velocity_profile_slope",
];
const NOTED_DIFFUSION: [&str; 2] = [
    "colloid_diffusion_long_time",
    "colloid_diffusion_over_stokes_einstein",
];

/// The method's summary fields.
fn summary(
    s: &Resolved,
    sim: &Dpd,
    obs: &Observed,
    diffusion: Option<f64>,
    neighbor_builds: u64,
    wall: f64,
    warnings: &[String],
) -> serde_json::Value {
    let (dt, tau) = (s.setup.params.dt, s.setup.tau);
    let last = obs.thermo.last().map(|(_, t)| t.clone());
    let n = (s.setup.colloids + s.setup.solvent) as f64;
    let eta = obs.stress_acf.as_ref().map(|a| a.viscosity());
    let value = |e: Option<colloidsim_md::dpd::viscosity::Estimate>| e.map(|e| e.value);
    let error = |e: Option<colloidsim_md::dpd::viscosity::Estimate>| e.map(|e| e.error);
    let all = eta.as_ref().and_then(|e| e.all);
    let off = eta.as_ref().and_then(|e| e.off_diagonal);
    let eta_note = eta.as_ref().map_or_else(
        || "not observed (observe.viscosity_every = 0)".to_string(),
        |e| e.note.clone(),
    );
    // Lees–Edwards: <-P_xy> over the second half, eta = <-P_xy> / gamma_dot.
    let rate = s.setup.params.shear_rate;
    let (stress, shear_note) = match &obs.shear {
        None => (None, "no shear (run.shear_rate = 0)".to_string()),
        Some(sh) => match sh.mean_stress(s.steps) {
            Ok((m, e, n)) => (
                Some((m, e)),
                format!(
                    "<-P_xy> over the last {n} steps of the second half (every step), error: standard error of 10 block means; eta = <-P_xy> / shear_rate"
                ),
            ),
            Err(why) => (None, why),
        },
    };
    // Each part of the stress: its mean and error, and its share of the viscosity.
    let shear_parts = match &obs.shear {
        None => json!(null),
        Some(sh) => match sh.mean_parts(s.steps) {
            Ok(parts) => {
                let mut m = serde_json::Map::new();
                for (name, (mean, err)) in PRESSURE_PARTS.iter().zip(parts) {
                    m.insert(
                        name.to_string(),
                        json!({
                            "stress": mean,
                            "error": err,
                            "viscosity": mean / rate,
                            "viscosity_error": err / rate,
                        }),
                    );
                }
                m.insert(
                    "note".into(),
                    json!("-P_xy split into the kinetic stress of solvent and colloids (peculiar velocities) and the pair virial by force class, conservative and dissipative split into solvent-solvent pairs and pairs with a colloid; the same steps and blocks as shear_stress, which they sum to (errors of the parts are not independent)"),
                );
                serde_json::Value::Object(m)
            }
            Err(why) => json!({ "note": why }),
        },
    };
    let slope = obs
        .shear
        .as_ref()
        .filter(|sh| sh.profile_samples > 0)
        .and_then(|sh| sh.profile(sim.sbox.l[1]).2);
    json!({
        "software": crate::software(),
        "method": "dpd",
        "seed": s.setup.params.seed,
        "parameters": describe(s),
        "steps": sim.step,
        "time": sim.step as f64 * dt,
        "time_tau": sim.step as f64 * dt / tau,
        "wall_seconds": wall,
        "particle_steps_per_second": n * sim.step as f64 / wall,
        "threads": rayon::current_num_threads(),
        "ranks": sim.rank().1,
        "neighbor_builds": neighbor_builds,
        "final_temperature": last.as_ref().map(|t| t.temperature),
        "final_temperature_by_type": last.as_ref().map(|t| t.temperature_by_type.clone()),
        "mean_temperature_second_half": mean_second_half(&obs.thermo, |t| t.temperature),
        "mean_colloid_temperature_second_half": mean_second_half(&obs.thermo, |t| t.temperature_by_type.get(1).copied().unwrap_or(f64::NAN)),
        "mean_pressure_second_half": mean_second_half(&obs.thermo, |t| (t.pressure[0] + t.pressure[1] + t.pressure[2]) / 3.0),
        "colloid_diffusion_long_time": diffusion,
        "colloid_diffusion_over_stokes_einstein": diffusion.map(|d| d / s.setup.d0),
        "colloid_diffusion_note": diffusion_note(s, obs, diffusion),
        "viscosity": value(all),
        "viscosity_error": error(all),
        "viscosity_off_diagonal": value(off),
        "viscosity_off_diagonal_error": error(off),
        "viscosity_note": eta_note,
        "shear_rate": rate,
        "shear_stress": stress.map(|x| x.0),
        "shear_stress_error": stress.map(|x| x.1),
        "shear_viscosity": stress.map(|x| x.0 / rate),
        "shear_viscosity_error": stress.map(|x| x.1 / rate),
        "shear_viscosity_note": shear_note,
        "shear_stress_parts": shear_parts,
        "velocity_profile_slope": slope,
        "warnings": warnings,
    })
}

/// Why `colloid_diffusion_long_time` is null, or how it was measured.
fn diffusion_note(s: &Resolved, obs: &Observed, diffusion: Option<f64>) -> String {
    let lags = obs.msd_steps.len().saturating_sub(1);
    let longest = obs
        .msd_steps
        .last()
        .zip(obs.msd_steps.first())
        .map_or(0.0, |(b, a)| {
            (b - a) as f64 * s.setup.params.dt / s.setup.tau
        });
    match diffusion {
        Some(_) => format!(
            "slope of the colloid MSD / 6 over the second half of its {lags} lags (up to {longest:.3} tau_D)"
        ),
        None if s.setup.colloids == 0 => "no colloids".into(),
        None => format!(
            "not measured: the MSD's lags reach {longest:.3} tau_D; the long-time diffusion \
             needs the second half of the lags to start at 1 tau_D or later (a run of at least \
             about 2 tau_D)"
        ),
    }
}

fn mean_second_half(rows: &[(f64, Thermo)], f: impl Fn(&Thermo) -> f64) -> Option<f64> {
    let h = &rows[rows.len() / 2..];
    if h.is_empty() {
        None
    } else {
        Some(h.iter().map(|(_, t)| f(t)).sum::<f64>() / h.len() as f64)
    }
}

/// The viscosity of the pure solvent from the kinetic theory of Marsh, Backx & Ernst (1997),
/// which neglects the conservative force (docs/dpd.md, *Viscosity*): with the weight
/// `w_D(r) = (1 - r/rc)^2`, `eta_K = d m kT / (2 gamma int w_D d^3r) = 45 m kT / (4 pi gamma
/// rc^3)` (velocities relax at `2 zeta / m`, `zeta = gamma rho int w_D d^3r / d`) and `eta_D =
/// gamma rho^2 / (2 d (d + 2)) int r^2 w_D d^3r = 2 pi gamma rho^2 rc^5 / 1575`.
fn solvent_viscosity_kinetic_theory(s: &Resolved) -> f64 {
    let p = &s.setup.params;
    let (m, rho) = (s.setup.solvent_mass, s.setup.density);
    let pi = std::f64::consts::PI;
    45.0 * m * p.kt / (4.0 * pi * p.gamma * p.rc.powi(3))
        + 2.0 * pi * p.gamma * rho * rho * p.rc.powi(5) / 1575.0
}

#[cfg(test)]
mod engine_names {
    /// The engine advises changing `dt`; the user reads the key.
    #[test]
    fn dpd_errors_name_the_keys() {
        let e = colloidsim_md::DpdError::NonFinite {
            step: 7,
            tag: 2,
            what: "position",
        };
        assert_eq!(
            super::rekeyed(e),
            "the run went non-finite at step 7: particle 2 (position); reduce run.dt or check the forces"
        );
    }
}
