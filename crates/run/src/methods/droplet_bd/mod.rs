//! The drying droplet (`method = "droplet-bd"`): Brownian dynamics of WCA spheres in a
//! shrinking (or, with `drying.peclet = 0`, static) harmonic interface, free draining by the
//! free-draining engine or with RPY hydrodynamics (`[hydrodynamics]`: direct free-space sums or
//! PSE in a periodic box), replicas one after the other, radial volume-fraction profiles at
//! fractions of the drying time; `theory` is the radial FMT DDFT ([`theory`]).

use crate::bd_replica::{
    BdMethod, BdSession, Observe, ReplicaEngine, Replicas, Saved, read_replica_checkpoint,
};
use crate::checkpoint::Envelope;
use crate::control::Control;
use crate::keys::Spec;
use crate::method::{Checked, Finished, Headline, Method, Session, fail_alone_over};
use crate::output::plot::{
    Disc, SHELL_PARTICLES, Scale, SectionLabels, Series, Style, cross_section, line_plot_styled,
    merged_shells, picture,
};
use crate::output::profile_name;
use crate::output::trajectory::FrameDigest;
use crate::{Report, Scenario as Source, TheoryOptions};
use anyhow::{Context, Result, bail};
use colloidsim_analysis::{overlap_profile, radial_profile};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::OutputDir;
use colloidsim_md::DropletParams;
use colloidsim_md::brownian::droplet::{DropletError, DropletSim};
use colloidsim_particles::{Particles, SpeciesInterface};
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::path::Path;

/// The drying-droplet family of scenarios.
pub struct DropletBd;

/// The fraction of colloid centres beyond R at the end of drying above which the run warns
/// that the interface left them behind (a compacted droplet at phi = 0.5 has none; at
/// Pe = 100 in a 100 kT/d^2 interface free draining leaves 3-12 %, RPY 35-60 %).
const LEFT_BEHIND: f64 = 0.01;

#[rustfmt::skip] // declarations laid out as a table, one key to a line or three
pub mod keys;
pub mod params;

pub mod theory;
mod theory_mixture;

/// What the species outputs need of a droplet-bd run.
fn species_run(p: &DropletParams) -> crate::output::species::SpeciesRun<'_> {
    let times: Vec<f64> = p
        .fractions
        .iter()
        .map(|f| (f * p.steps as f64).round() * p.dt)
        .collect();
    crate::output::species::SpeciesRun {
        mixture: &p.species,
        bins: p.bins,
        fractions: &p.fractions,
        radii: times.iter().map(|&t| p.radius_at(t)).collect(),
        times,
        replicas: p.replicas,
        one_replica: crate::output::species::ONE_REPLICA,
    }
}

/// Read and check a scenario (`system.initial` relative to the scenario's folder), with `seed`
/// replacing the scenario's.
pub(crate) fn resolve(src: &Source, seed: Option<u64>) -> Result<DropletParams> {
    if let Some(s) = seed {
        crate::seed32(s)?;
    }
    params::read(&src.table()?, src.base(), seed).with_context(|| src.label())
}

/// `outer_shell` of a droplet's summary (its headline, [`HEADLINE`]): at each profile time
/// (`fractions`), the volume fraction by centre count in the outer shell `R - w < r < R`, `w`
/// the outermost `max(1, round(d / dr))` of the profile's equal shells of `[0, R]` (about one
/// diameter `d`): the shells' `phi` (centres per shell volume times the particle volume)
/// averaged with their volumes as weights, i.e. `sum v_i / V_shell` over the centres in it.
/// `profiles[j]`: the profile `phi` and radius `R` at time `j`, or why there is none.
pub(crate) fn outer_shell(
    fractions: &[f64],
    profiles: &[Result<(&[f64], f64), &str>],
    d: f64,
    out: &OutputDir,
) -> serde_json::Value {
    let mut labels = Vec::new();
    let (mut phi, mut inner, mut radius) = (Vec::new(), Vec::new(), Vec::new());
    for (j, (&f, prof)) in fractions.iter().zip(profiles).enumerate() {
        let name = profile_name(f);
        let label = name
            .strip_prefix("profile_")
            .and_then(|n| n.strip_suffix(".csv"))
            .unwrap_or(&name);
        labels.push(format!("t{label}"));
        match prof {
            Ok((p, r)) if !p.is_empty() && *r > 0.0 => {
                let bins = p.len();
                let dr = r / bins as f64;
                let k = ((d / dr).round() as usize).clamp(1, bins);
                let (mut num, mut vol) = (0.0, 0.0);
                for (b, v) in p.iter().enumerate().skip(bins - k) {
                    let w = ((b + 1) as f64 * dr).powi(3) - (b as f64 * dr).powi(3);
                    num += v * w;
                    vol += w;
                }
                phi.push(Some(num / vol));
                inner.push(Some(r - k as f64 * dr));
                radius.push(Some(*r));
            }
            Ok(_) => {
                for (key, v) in [
                    ("phi", &mut phi),
                    ("inner_radius", &mut inner),
                    ("radius", &mut radius),
                ] {
                    out.explain(
                        "summary.json",
                        &format!("outer_shell.{key}[{j}]"),
                        "an empty profile",
                    );
                    v.push(None);
                }
            }
            Err(why) => {
                for (key, v) in [
                    ("phi", &mut phi),
                    ("inner_radius", &mut inner),
                    ("radius", &mut radius),
                ] {
                    out.explain("summary.json", &format!("outer_shell.{key}[{j}]"), why);
                    v.push(None);
                }
            }
        }
    }
    serde_json::json!({
        "definition": "volume fraction by centre count in the outer shell inner_radius < r < radius: the outermost max(1, round(d / dr)) shells of the profile (about one diameter), sum of the centres' particle volumes over the shell volume",
        "labels": labels,
        "fraction": fractions,
        "radius": radius,
        "inner_radius": inner,
        "phi": phi,
    })
}

/// Droplet BD's headline observables (summary.json).
pub(crate) const HEADLINE: &[Headline] = &[Headline {
    name: "outer_shell_phi",
    path: "outer_shell.phi",
    labels: Some("outer_shell.labels"),
    unit: "-",
    doc: "volume fraction (centre count) in the droplet's outer shell, about one diameter \
          thick, at each profile time (label tF: a fraction F of the drying time)",
    absent: "no profile taken",
}];

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

    fn headline(&self) -> &'static [Headline] {
        HEADLINE
    }

    fn check(&self, src: &Source) -> Result<Checked> {
        let p = resolve(src, None)?;
        // What `run` does before it starts: set up replica 0 (reading system.initial).
        p.build_replica(0)
            .map_err(keyed)
            .with_context(|| src.label())?;
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

    fn has_theory(&self) -> bool {
        true
    }

    fn theory(&self, src: &Source, opts: &TheoryOptions, ctl: &Control) -> Result<Report> {
        theory::theory(src, opts, ctl)
    }

    fn keys(&self) -> &'static [Spec] {
        keys::KEYS
    }

    fn engine(&self, src: &Source, seed: Option<u64>) -> Result<Box<dyn crate::Engine>> {
        let p = resolve(src, seed)?;
        let sim = build_replica(&p, 0)?;
        let seed = p.seed;
        Ok(Box::new(ReplicaEngine::new(
            "droplet-bd",
            sim,
            seed,
            move |x, step, seed| {
                let p = DropletParams { seed, ..p.clone() };
                replica_at(
                    &p,
                    x,
                    colloidsim_particles::SimBox::cube(p.box_edge()),
                    step,
                    None,
                    0,
                )
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
    let p = resolve(src, seed)?;
    // Set up replica 0 before the output folder is created: bad input leaves nothing.
    let sim = build_replica(&p, 0)?;
    let acc = Accum::new(&p);
    Ok(Box::new(DropletObs::session(
        p,
        acc,
        0,
        Some((sim, 0)),
        comm,
    )?))
}

/// The session a checkpoint continues (on any number of ranks when decomposed).
fn restore(
    src: &Source,
    seed: u64,
    out: &OutputDir,
    envelope: &Envelope,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Box<dyn Session>> {
    let p = resolve(src, Some(seed))?;
    let saved: Saved<Accum> = crate::checkpoint::decode_payload(&envelope.payload)?;
    if saved.replica >= p.replicas || saved.acc.sums.len() != p.fractions.len() {
        bail!(
            "checkpoint: replica {} of {} with {} profiles does not fit the scenario",
            saved.replica,
            p.replicas,
            saved.acc.sums.len()
        );
    }
    let sim = restore_replica(out, &p, &saved)?;
    // Only the writer touches the folder.
    if p.trajectory_every > 0 && comm.as_ref().is_none_or(|c| c.rank() == 0) {
        saved
            .acc
            .digest
            .restore(&out.join("trajectory.gsd"))
            .map_err(|e| fail_alone_over(comm.as_deref(), e))?;
    }
    Ok(Box::new(DropletObs::session(
        p,
        saved.acc,
        saved.replica,
        sim,
        comm,
    )?))
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
    /// Two or more species: their profiles and the stratification.
    #[serde(default)]
    species: crate::output::species::SpeciesAccum,
    /// Per profile fraction: sum over the replicas of the volume-fraction profile by
    /// sphere–shell overlap (empty when continued from a checkpoint written without it).
    #[serde(default)]
    overlap: Vec<Vec<f64>>,
    /// Per profile fraction: the sum of its squares, for the error over the replicas (empty
    /// when continued from a checkpoint written without it).
    #[serde(default)]
    overlap_squares: Vec<Vec<f64>>,
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
            species: Default::default(),
            overlap: vec![vec![0.0; p.bins]; n_frac],
            overlap_squares: vec![vec![0.0; p.bins]; n_frac],
        }
    }
}

/// The standard error of the mean `s / sqrt(n)` of `n` samples per point from their `mean`
/// and the sum of their squares (`s` the sample standard deviation).
fn standard_errors(mean: &[f64], squares: &[f64], n: u64) -> Vec<f64> {
    let n = n as f64;
    mean.iter()
        .zip(squares)
        .map(|(m, q)| ((q / n - m * m).max(0.0) / (n - 1.0)).sqrt())
        .collect()
}

/// Restore the running replica from a checkpoint (verified against its CRC first).
fn restore_replica(
    out: &OutputDir,
    p: &DropletParams,
    saved: &Saved<Accum>,
) -> Result<Option<(Replica, u64)>> {
    let Some(state) = &saved.state else {
        return Ok(None);
    };
    // The hydrodynamic engine's state is its exact positions and images; the free-draining
    // engine's also holds its storage order and list reference positions.
    let hydro = p.hydrodynamics.as_ref().filter(|_| p.has_hydrodynamics());
    let f = read_replica_checkpoint(
        out,
        state,
        saved.step,
        saved.replica,
        hydro.is_some(),
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
    Ok(Some((sim, builds)))
}

/// Replica `replica` of `p` from its particles (input order, exact positions and image counts)
/// in `sbox` at `step`, with the free-draining engine's list state when a checkpoint holds one.
fn replica_at(
    p: &DropletParams,
    particles: colloidsim_particles::Particles,
    sbox: colloidsim_particles::SimBox,
    step: u64,
    list: Option<&colloidsim_particles::gsd::ListState>,
    replica: u32,
) -> Result<Replica> {
    Ok(
        match p.hydrodynamics.as_ref().filter(|_| p.has_hydrodynamics()) {
            None => Replica::Free(Box::new(DropletSim::restart(
                particles,
                sbox,
                p.interaction()?,
                p.species_interface(),
                p.bd_params(replica),
                step,
                list,
            )?)),
            Some(h) => Replica::Hydro(Box::new(p.restart_hydro_replica(
                particles,
                h,
                p.hydro_bd_params(replica),
                step,
            )?)),
        },
    )
}

/// A running droplet replica, in the moving harmonic interface.
type Replica = crate::bd_replica::Replica<SpeciesInterface>;

/// Replica `replica` of `p` at step 0, with the engine its hydrodynamics ask for.
fn build_replica(p: &DropletParams, replica: u32) -> Result<Replica> {
    Ok(match &p.hydrodynamics {
        Some(h) if p.has_hydrodynamics() => {
            Replica::Hydro(Box::new(p.build_hydro_replica(replica, h).map_err(keyed)?))
        }
        _ => Replica::Free(Box::new(p.build_replica(replica).map_err(keyed)?)),
    })
}

/// A replica's set-up error, naming the scenario key of the input it refuses.
fn keyed(e: DropletError) -> anyhow::Error {
    match e {
        DropletError::Packing(m) => anyhow::anyhow!("{}: {m}", keys::SYSTEM_PHI0.path),
        DropletError::Initial(m) => anyhow::anyhow!(
            "{}: {}",
            keys::SYSTEM_INITIAL.path,
            crate::keys::rekey_text(&m, &[("particles", &keys::SYSTEM_PARTICLES)])
        ),
        DropletError::Param(e) => params::keyed(e).into(),
        other => other.into(),
    }
}

/// A droplet run: replicas one after the other.
type DropletSession = BdSession<SpeciesInterface, DropletObs>;

/// What a droplet run observes: profiles, the excursion beyond the wall, trajectory frames,
/// the cross-section of replica 0.
struct DropletObs {
    p: DropletParams,
    acc: Accum,
    /// Steps of a replica at which something is recorded (profiles, frames, the end).
    stops: Vec<u64>,
    /// The output folder, once known (the cross-section is written when replica 0 ends).
    folder: Option<std::path::PathBuf>,
}

impl DropletObs {
    /// The session of `p` at replica `rep` (running `sim`, or not yet built) with `acc`,
    /// decomposed over the ranks of `comm` when given.
    fn session(
        p: DropletParams,
        acc: Accum,
        rep: usize,
        sim: Option<(Replica, u64)>,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<DropletSession> {
        let mut stops: Vec<u64> = p.profile_steps.clone();
        if p.trajectory_every > 0 {
            stops.extend((0..=p.steps).step_by(p.trajectory_every as usize));
        }
        stops.push(p.steps);
        stops.sort_unstable();
        stops.dedup();
        Ok(BdSession::new(
            Replicas::new(p.steps, p.replicas, p.trajectory_every, rep, sim, comm)?,
            DropletObs {
                p,
                acc,
                stops,
                folder: None,
            },
        ))
    }
}

impl Observe<SpeciesInterface> for DropletObs {
    fn build(&self, replica: u32) -> Result<Replica> {
        build_replica(&self.p, replica)
    }

    fn next_event(&self, run: &Replicas<SpeciesInterface>, step: u64) -> u64 {
        let k = self.stops.partition_point(|&e| e <= step);
        self.stops.get(k).copied().unwrap_or(run.steps)
    }

    /// Record what is due at step `ev` of the running replica: profiles, the excursion
    /// beyond the wall, trajectory frames.
    fn record(&mut self, run: &mut Replicas<SpeciesInterface>, ev: u64) -> Result<()> {
        let Some((s, _)) = &run.sim else {
            return Ok(());
        };
        if self.stops.binary_search(&ev).is_err() {
            return Ok(());
        }
        let p = &self.p;
        let acc = &mut self.acc;
        let t = s.time();
        let radius = p.radius_at(t);
        let wall_r = radius + p.offset;
        // In input order and wrapped: the same on any number of ranks (collective).
        let part = s.snapshot();
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
                if let Some(sum) = acc.overlap.get_mut(j) {
                    let phi = overlap_profile(&part.pos, &part.diameter, [0.0; 3], radius, p.bins);
                    for (a, b) in sum.iter_mut().zip(&phi) {
                        *a += b;
                    }
                    if let Some(sq) = acc.overlap_squares.get_mut(j) {
                        for (a, b) in sq.iter_mut().zip(&phi) {
                            *a += b * b;
                        }
                    }
                }
                acc.counts[j] += 1;
                acc.radii[j] = radius;
                acc.r_axes[j] = prof.r;
                acc.species.record(
                    &species_run(p),
                    j,
                    &part.pos,
                    &part.diameter,
                    &part.typeid,
                    radius,
                );
                if ev == p.steps {
                    acc.outside_final += prof.outside as u64;
                }
            }
        }
        let logs = [("droplet/radius", radius), ("droplet/time", t)];
        if run.write_frame(ev, Some(&part), &logs)? {
            acc.frames += 1;
        }
        Ok(())
    }

    fn replica_done(&mut self, run: &Replicas<SpeciesInterface>, builds: u64) -> Result<()> {
        if run.rep == 0
            && let (Some(width), Some(out), Some((s, _))) =
                (self.p.cross_section, &self.folder, &run.sim)
        {
            let snap = s.snapshot();
            if run.is_writer() {
                write_cross_section(out, &self.p, s.time(), &snap, width)
                    .map_err(|e| run.fail_alone(e))?;
            }
        }
        self.acc.builds += builds;
        Ok(())
    }
}

impl BdMethod<SpeciesInterface> for DropletObs {
    type Acc = Accum;

    fn acc(&self) -> &Accum {
        &self.acc
    }

    fn bookkeeping(&mut self) -> (u64, &mut FrameDigest, &mut u64) {
        let a = &mut self.acc;
        (a.frames, &mut a.digest, &mut a.checkpoints)
    }

    fn name(&self) -> &'static str {
        "droplet-bd"
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
            || profile("species_profile_")
            || [
                "profiles.png",
                "profile_mean.csv",
                "species_profiles.png",
                "stratification.csv",
                "stratification.png",
                "cross_section.csv",
                "cross_section.png",
            ]
            .contains(&name)
    }

    fn output_folder(&mut self, out: &OutputDir) {
        self.folder = Some(out.path().to_path_buf());
    }

    fn finish(self, out: &OutputDir, wall_s: f64, _failure: Option<&str>) -> Result<Finished> {
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
            species,
            overlap,
            overlap_squares,
            ..
        } = self.acc;
        let mut warnings = Vec::new();
        let mut files = Vec::new();
        let mut means: Vec<Vec<f64>> = Vec::new();
        let mut drawn = Vec::new();
        let mut overlaps: Vec<Vec<f64>> = Vec::new();
        // The standard error of the overlap profile over the replicas (two or more).
        let mut overlap_errors: Vec<Option<Vec<f64>>> = Vec::new();
        for j in 0..n_frac {
            if counts[j] == 0 {
                continue;
            }
            let reps = counts[j] as f64;
            let phi: Vec<f64> = sums[j].iter().map(|v| v / reps).collect();
            let name = profile_name(p.fractions[j]);
            // rho_v: centres per shell volume times the particle volume (centre density, more
            // than 1 where a shell is thinner than a sphere); phi_overlap: the volume fraction
            // by sphere-shell overlap.
            match overlap.get(j).filter(|o| o.len() == phi.len()) {
                Some(o) => {
                    let o: Vec<f64> = o.iter().map(|v| v / reps).collect();
                    let err: Option<Vec<f64>> = overlap_squares
                        .get(j)
                        .filter(|q| q.len() == o.len() && counts[j] >= 2)
                        .map(|q| standard_errors(&o, q, counts[j]));
                    match &err {
                        Some(e) => out.write_table(
                            &name,
                            &[
                                ("r", &r_axes[j]),
                                ("rho_v", &phi),
                                ("phi_overlap", &o),
                                ("phi_overlap_err", e),
                            ],
                        )?,
                        None => out.write_table(
                            &name,
                            &[("r", &r_axes[j]), ("rho_v", &phi), ("phi_overlap", &o)],
                        )?,
                    };
                    overlaps.push(o);
                    overlap_errors.push(err);
                }
                None => {
                    out.write_table(&name, &[("r", &r_axes[j]), ("rho_v", &phi)])?;
                }
            }
            files.push(name);
            means.push(phi);
            drawn.push(j);
        }
        let labels: Vec<String> = drawn
            .iter()
            .map(|&j| format!("t = {:.0} % (R = {:.2})", p.fractions[j] * 100.0, radii[j]))
            .collect();
        // The picture shows the volume fraction by sphere-shell overlap; without it (a run
        // continued from an older checkpoint) the centre density with the small inner shells
        // merged (plot::merged_shells). The CSV files keep every shell.
        let by_overlap = overlaps.len() == drawn.len();
        let vp = std::f64::consts::PI / 6.0 * p.diameter.powi(3);
        let merged: Vec<(Vec<f64>, Vec<f64>)> = drawn
            .iter()
            .enumerate()
            .map(|(k, &j)| {
                if by_overlap {
                    let x = r_axes[j].iter().map(|x| x / radii[j]).collect();
                    return (x, overlaps[k].clone());
                }
                let (x, y) = merged_shells(
                    &r_axes[j],
                    &means[k],
                    vp,
                    p.replicas as f64,
                    SHELL_PARTICLES,
                );
                (x.iter().map(|x| x / radii[j]).collect(), y)
            })
            .collect();
        let series: Vec<Series> = (0..drawn.len())
            .map(|k| Series {
                label: &labels[k],
                x: &merged[k].0,
                y: &merged[k].1,
                points: false,
            })
            .collect();
        let errors: Vec<Option<&[f64]>> = match by_overlap {
            true => overlap_errors.iter().map(|e| e.as_deref()).collect(),
            false => Vec::new(),
        };
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
                    &[("r", r), ("rho_v", &mean), ("rho_v_err", &err)],
                )?;
                files.push("profile_mean.csv".into());
            }
        }
        let stratification = species.write(
            out,
            &species_run(p),
            &drawn,
            &counts,
            &radii,
            &r_axes,
            &mut files,
            &mut warnings,
        )?;
        if p.cross_section.is_some() && out.join("cross_section.csv").exists() {
            files.push("cross_section.csv".into());
            if ["png", "svg"]
                .iter()
                .any(|ext| out.join(&format!("cross_section.{ext}")).exists())
            {
                files.push("cross_section.png".into());
            }
        }
        picture(
            line_plot_styled(
                &out.join("profiles.png"),
                &title,
                if by_overlap {
                    "r / R(t)"
                } else {
                    "r / R(t) (inner shells merged to >= 10 particles)"
                },
                if by_overlap {
                    if errors.iter().any(Option::is_some) {
                        "volume fraction (sphere-shell overlap; bars: error over replicas)"
                    } else {
                        "volume fraction (sphere-shell overlap)"
                    }
                } else {
                    "centre density x particle volume"
                },
                &series,
                &errors,
                Scale::Linear,
                Style {
                    legend_outside: true,
                },
            ),
            "profiles.png",
            &mut files,
            &mut warnings,
        );
        if frames > 0 {
            files.push("trajectory.gsd".into());
        }
        // A droplet whose interface left colloids behind did not compact: say so.
        let beyond = outside_final as f64 / (p.particles * p.replicas) as f64;
        if beyond > LEFT_BEHIND {
            warnings.push(format!(
                "{:.1} % of the colloid centres are beyond R at the end of drying: the interface \
                 (interface.stiffness = {} kT/d^2) did not hold them at drying.peclet = {}, so the \
                 last profiles and stratification are not those of a compacted droplet; stiffen \
                 the interface or dry more slowly",
                100.0 * beyond,
                p.stiffness * p.diameter * p.diameter / p.kt,
                p.peclet
            ));
        }
        let particle_steps = (p.steps * p.replicas as u64) as f64 * p.particles as f64;
        let mut summary = json!({
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
        if !stratification.is_null() {
            summary["stratification"] = stratification;
        }
        let mut k = 0;
        let profiles: Vec<Result<(&[f64], f64), &str>> = (0..n_frac)
            .map(|j| {
                if drawn.get(k) == Some(&j) {
                    k += 1;
                    Ok((means[k - 1].as_slice(), radii[j]))
                } else {
                    Err("no profile at this time (the run stopped before it)")
                }
            })
            .collect();
        summary["outer_shell"] = outer_shell(&p.fractions, &profiles, p.diameter, out);
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
fn write_cross_section(
    dir: &Path,
    p: &DropletParams,
    time: f64,
    snap: &Particles,
    width: f64,
) -> Result<()> {
    let out = OutputDir::reopen(dir)?;
    let radius = p.radius_at(time);
    let a = 0.5 * p.diameter;
    let mut cols: [Vec<f64>; 4] = Default::default();
    let mut discs = Vec::new();
    for x in &snap.pos {
        if x[2].abs() < 0.5 * width {
            let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
            for (c, v) in cols.iter_mut().zip([x[0], x[1], x[2], r]) {
                c.push(v);
            }
            // The section of the sphere by z = 0 (a sphere cut off-centre by the slab still
            // shows as a small disc), drawn in units of the diameter.
            let rc = (a * a - x[2] * x[2]).max(0.04 * a * a).sqrt();
            discs.push(Disc {
                x: x[0] / p.diameter,
                y: x[1] / p.diameter,
                r: rc / p.diameter,
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
        "{}: slab |z| < {} d at t = {:.1} (R = {:.2} d), replica 0",
        mobility_label(p).unwrap_or_else(|| "free-draining BD".into()),
        0.5 * width / p.diameter,
        time,
        radius / p.diameter
    );
    let labels = SectionLabels {
        colours: &["centre deeper than d below R(t)", "centre within d of R(t)"],
        outline: "droplet radius R(t)",
        x: "x / d",
        y: "y / d",
    };
    // A picture that cannot be drawn leaves the table; the run goes on.
    let _ = cross_section(
        &out.join("cross_section.png"),
        &title,
        &discs,
        radius / p.diameter,
        &labels,
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    /// The error of the replicas' mean from running sums equals `s / sqrt(n)` from the samples.
    #[test]
    fn standard_errors_from_sums_are_those_of_the_samples() {
        let samples = [[0.31, 0.0, 0.12], [0.27, 0.0, 0.18], [0.36, 0.0, 0.09]];
        let n = samples.len() as f64;
        let mean: Vec<f64> = (0..3)
            .map(|b| samples.iter().map(|s| s[b]).sum::<f64>() / n)
            .collect();
        let squares: Vec<f64> = (0..3)
            .map(|b| samples.iter().map(|s| s[b] * s[b]).sum())
            .collect();
        let got = super::standard_errors(&mean, &squares, samples.len() as u64);
        for b in 0..3 {
            let var = samples
                .iter()
                .map(|s| (s[b] - mean[b]).powi(2))
                .sum::<f64>()
                / (n - 1.0);
            assert!((got[b] - (var / n).sqrt()).abs() < 1e-12, "{b}: {got:?}");
        }
        assert_eq!(got[1], 0.0);
    }
}
