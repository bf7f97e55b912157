//! The drying droplet of MPCD solvent (`method = "droplet-mpcd"`, docs/mpcd.md): the solvent's
//! boundary at the moving sphere `none`, `slip` or `no-slip`; its density and radial velocity
//! against `r / R(t)` and its count against the droplet volume.

use crate::Scenario as Source;
use crate::checkpoint::Envelope;
use crate::keys::Spec;
use crate::method::{Checked, Finished, Headline, Method, Session};
use crate::methods::mpcd::common::*;
use crate::output::plot::{
    SHELL_PARTICLES, Scale, Series, Style, line_plot, line_plot_styled, merged_shells, picture,
};
use crate::output::species::{SpeciesAccum, SpeciesRun};
use crate::output::trajectory::FrameDigest;
use anyhow::{Context, Result, bail};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::{CsvLog, OutputDir};
use colloidsim_md::mpcd::colloid::{ColloidState, DiscreteColloids, Region};
use colloidsim_md::mpcd::drying::{SolventProfile, remove_excess};
use colloidsim_md::mpcd::{Acceleration, Confinement, Srd, WallKind};
use colloidsim_particles::SimBox;
use colloidsim_particles::gsd::GsdWriter;
use params::{Boundary, DropletRun};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::f64::consts::PI;

#[rustfmt::skip] // declarations laid out as a table, one key to a line or three
pub mod keys;
pub mod params;

/// The drying droplet of MPCD solvent (`method = "droplet-mpcd"`).
pub struct DropletMpcd;

fn resolve_droplet(src: &Source, seed: Option<u64>) -> Result<DropletRun> {
    params::read(&src.table()?, seed).with_context(|| src.label())
}

/// Why an error over replicas is missing: a droplet-mpcd run is one replica.
const ONE_RUN: &str =
    "one run: droplet-mpcd has one replica; compare runs of several seeds for the spread";

/// What the species outputs need of a droplet-mpcd run.
fn species_run(p: &DropletRun) -> SpeciesRun<'_> {
    let tau = p.solvent.srd.tau;
    let times: Vec<f64> = p
        .profile_collisions
        .iter()
        .map(|&c| c as f64 * tau)
        .collect();
    SpeciesRun {
        mixture: &p.species,
        bins: p.profile.bins,
        fractions: &p.profile.fractions,
        radii: times.iter().map(|&t| p.law().radius(t)).collect(),
        times,
        replicas: 1,
        one_replica: ONE_RUN,
    }
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

/// The colloids at the start: random sequential addition with centres within `R0 - d_s/2`
/// (one species: `place_colloids`, as always).
fn build_colloids(p: &DropletRun) -> Result<Option<DiscreteColloids>> {
    let region = Region::Sphere { radius: p.r0 };
    if p.species.is_single() || p.particles == 0 {
        return place_colloids(
            p.particles,
            p.colloid,
            p.box_edge,
            region,
            p.solvent.srd.kt,
            p.seed,
        )
        .context("system.particles");
    }
    Ok(Some(
        DiscreteColloids::random_mixture(
            p.colloid,
            &p.species,
            SimBox::cube(p.box_edge),
            region,
            p.solvent.srd.kt,
            p.seed,
        )
        .context("system.particles")?,
    ))
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

    fn headline(&self) -> &'static [Headline] {
        crate::methods::droplet_bd::HEADLINE
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
        let colloids = match (&saved.colloids, p.species.is_single()) {
            (Some(state), false) => Some(
                DiscreteColloids::from_state_mixture(
                    p.colloid,
                    &p.species,
                    SimBox::cube(p.box_edge),
                    state,
                )
                .context("checkpoint.bin: the colloids")?,
            ),
            (saved, _) => restore_colloids(saved.as_ref(), p.particles, p.colloid, p.box_edge)?,
        };
        if p.trajectory_every > 0 && writer {
            saved
                .acc
                .digest
                .restore(&out.join("trajectory.gsd"))
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
        keys::KEYS
    }

    fn engine(&self, src: &Source, seed: Option<u64>) -> Result<Box<dyn crate::Engine>> {
        let p = resolve_droplet(src, seed)?;
        Ok(Box::new(SolventEngine {
            srd: build_droplet(&p, None)?,
            colloids: build_colloids(&p)?,
            interface: Some(p.species_interface()),
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

/// The colloid profiles: per profile time, the centre density times the sphere volume per bin
/// (`phi`), the volume fraction by sphere-shell overlap (`overlap`; empty when continued from
/// a checkpoint written without it), the bin centres and the radius when taken.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
struct ColloidProfiles {
    phi: Vec<Vec<f64>>,
    #[serde(default)]
    overlap: Vec<Vec<f64>>,
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
    /// Two or more species: their profiles and the stratification.
    species: SpeciesAccum,
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
                    overlap: vec![Vec::new(); k],
                    r: vec![Vec::new(); k],
                    radius: vec![0.0; k],
                    taken: vec![false; k],
                    max_excursion: f64::NEG_INFINITY,
                    outside_final: 0,
                }
            },
            species: SpeciesAccum::default(),
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
                && let Err(e) = col.advance(step as f64 * tau, tau, &self.p.species_interface())
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
            // Each species meets the wall (d_s - d) / 2 further in (its surface at R + offset).
            let wall = r + p.interface[2];
            let diameters = col.diameters();
            for (x, ds) in col.centre_positions().iter().zip(&diameters) {
                let d = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
                cp.max_excursion = cp.max_excursion.max(d - (wall - 0.5 * (ds - p.diameter)));
            }
            for (j, &cf) in p.profile_collisions.iter().enumerate() {
                if cf == c {
                    let pos = col.centre_positions();
                    let prof = colloidsim_analysis::radial_profile(
                        pos,
                        &diameters,
                        [0.0; 3],
                        r,
                        p.profile.bins,
                    );
                    self.acc
                        .species
                        .record(&species_run(p), j, pos, &diameters, col.species(), r);
                    let o = colloidsim_analysis::overlap_profile(
                        pos,
                        &diameters,
                        [0.0; 3],
                        r,
                        p.profile.bins,
                    );
                    if let Some(slot) = cp.overlap.get_mut(j) {
                        *slot = o;
                    }
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
            "species_profiles.png",
            "stratification.csv",
            "stratification.png",
        ]
        .contains(&name)
            || name
                .strip_prefix("species_")
                .unwrap_or(name)
                .strip_prefix("profile_")
                .and_then(|r| r.strip_suffix(".csv"))
                .is_some_and(|f| f.parse::<f64>().is_ok())
    }

    fn begin(&mut self, out: &OutputDir, fresh: bool) -> Result<()> {
        if DropletSession::is_writer(self) {
            if self.colloids.is_none() {
                out.explain("thermo.csv", "colloid_temperature", "no colloids");
            }
            self.gsd = open_trajectory(out, self.p.trajectory_every, fresh)?;
            self.thermo_log = Some(CsvLog::start_in(
                out,
                "thermo.csv",
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
            let mut by_overlap = true;
            for j in (0..cp.taken.len()).filter(|&j| cp.taken[j]) {
                let name = crate::output::profile_name(p.profile.fractions[j]);
                // rho_v: the centre density times the sphere volume (above 1 where a shell is
                // thinner than a sphere); phi_overlap: the volume fraction by sphere-shell
                // overlap (as droplet-bd's).
                let overlap = cp.overlap.get(j).filter(|o| o.len() == cp.phi[j].len());
                match overlap {
                    Some(o) => out.write_table(
                        &name,
                        &[("r", &cp.r[j]), ("rho_v", &cp.phi[j]), ("phi_overlap", o)],
                    )?,
                    None => out.write_table(&name, &[("r", &cp.r[j]), ("rho_v", &cp.phi[j])])?,
                };
                files.push(name);
                labels.push(format!(
                    "t = {:.0} % (R = {:.2})",
                    p.profile.fractions[j] * 100.0,
                    cp.radius[j]
                ));
                // The picture shows the volume fraction by overlap; without it (an older
                // checkpoint) the centre density with the small inner shells merged.
                let (x, y) = match overlap {
                    Some(o) => (cp.r[j].clone(), o.clone()),
                    None => {
                        let vp = std::f64::consts::PI / 6.0 * p.diameter.powi(3);
                        merged_shells(&cp.r[j], &cp.phi[j], vp, 1.0, SHELL_PARTICLES)
                    }
                };
                by_overlap &= overlap.is_some();
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
                    if by_overlap {
                        "r / R(t)"
                    } else {
                        "r / R(t) (inner shells merged to >= 10 particles)"
                    },
                    if by_overlap {
                        "volume fraction (sphere-shell overlap)"
                    } else {
                        "pi d^3 rho / 6 (centre density x sphere volume)"
                    },
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
        // Two or more species: their profiles and the stratification (droplet-bd's files).
        let taken: Vec<usize> = (0..cp.taken.len()).filter(|&j| cp.taken[j]).collect();
        let stratification = self.acc.species.write(
            out,
            &species_run(p),
            &taken,
            &vec![1; cp.taken.len()],
            &cp.radius,
            &cp.r,
            &mut files,
            &mut warnings,
        )?;
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
            if worst.is_nan() {
                out.explain(
                    "summary.json",
                    &format!(
                        "solvent_uniformity[{}].max_relative_density_deviation",
                        uniformity.len()
                    ),
                    "no bin with a standard error yet (too few samples for blocks)",
                );
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
            for c in ["radial_velocity", "radial_velocity_err", "density_err"] {
                out.explain(
                    "solvent_profiles.csv",
                    c,
                    "a shell that held no solvent in the window (no velocity to average) or one block (no error)",
                );
            }
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
                "final_mean_volume_fraction": p.species.sum_n_d3() / (8.0 * r.powi(3)),
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
        if !stratification.is_null() {
            summary["stratification"] = stratification;
        }
        let cp = &self.acc.colloid_profiles;
        let profiles: Vec<Result<(&[f64], f64), &str>> = (0..p.profile.fractions.len())
            .map(|j| match (&self.colloids, cp.taken.get(j)) {
                (None, _) => Err("no colloids"),
                (Some(_), Some(true)) => Ok((cp.phi[j].as_slice(), cp.radius[j])),
                _ => Err("no profile at this time (the run stopped before it)"),
            })
            .collect();
        summary["outer_shell"] = crate::methods::droplet_bd::outer_shell(
            &p.profile.fractions,
            &profiles,
            p.diameter,
            out,
        );
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
