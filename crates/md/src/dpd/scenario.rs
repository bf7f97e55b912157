//! The `method = "dpd"` scenario: hard colloids in a DPD solvent (every key, its unit and
//! default: `docs/dpd.md`).
//!
//! [`DpdScenario::validate`] resolves the file into [`DpdSetup`] (engine parameters, box,
//! particle numbers, the colloid diffusion time) or returns a [`ParamError`] naming the key and
//! the allowed range; [`DpdSetup::build`] places the particles and returns the engine.

use super::{
    ColloidForces, Dpd, DpdError, DpdParams, LubricationNoise, NeighborMode, colloid_solvent_cutoff,
};
use crate::state::{Particles, SimBox};
use colloidsim_core::ParamError;
use colloidsim_core::exchange::Exchange;
use colloidsim_core::param::{in_range, non_negative, positive};
use colloidsim_core::rng::{Purpose, stream};
use rand::RngExt;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A `dpd` scenario file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DpdScenario {
    /// Must be `"dpd"`.
    pub method: String,
    /// Seed (0 ..= 2^32 - 1).
    #[serde(default = "one")]
    pub seed: u64,
    /// Box, densities, temperature, colloid sizes.
    pub system: SystemSection,
    /// DPD solvent forces.
    #[serde(default)]
    pub dpd: DpdSection,
    /// Colloid–colloid forces.
    #[serde(default)]
    pub colloids: ColloidSection,
    /// Time stepping.
    #[serde(default)]
    pub run: RunSection,
    /// Observables.
    #[serde(default)]
    pub observe: ObserveSection,
}

fn one() -> u64 {
    1
}

/// `[system]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SystemSection {
    /// Box edge (a cube) in `rc`.
    #[serde(default)]
    pub box_length: Option<f64>,
    /// Box edges `[Lx, Ly, Lz]` in `rc` (instead of `box_length`).
    #[serde(default)]
    pub box_edges: Option<[f64; 3]>,
    /// Number density of solvent beads in the volume the colloids leave free (per `rc^3`).
    #[serde(default = "d_density")]
    pub density: f64,
    /// Colloid volume fraction (0 for pure solvent).
    #[serde(default)]
    pub phi: f64,
    /// Thermal energy.
    #[serde(rename = "kT", default = "d_kt")]
    pub kt: f64,
    /// Mean colloid radius `R_c` in `rc`.
    #[serde(default = "d_one")]
    pub colloid_radius: f64,
    /// Radius distribution: `"monodisperse"`, `"gaussian"`, `"lognormal"` or `"uniform"`.
    #[serde(default = "d_mono")]
    pub radius_distribution: String,
    /// Relative spread of the radii: standard deviation / mean (gaussian, lognormal) or
    /// half-width / mean (uniform).
    #[serde(default)]
    pub radius_spread: f64,
    /// Mass of a solvent bead (colloid mass = `(4/3) pi R^3 density m_s`).
    #[serde(default = "d_one")]
    pub solvent_mass: f64,
}

fn d_density() -> f64 {
    3.0
}
fn d_kt() -> f64 {
    0.1
}
fn d_one() -> f64 {
    1.0
}
fn d_mono() -> String {
    "monodisperse".into()
}

/// `[dpd]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DpdSection {
    /// Solvent–solvent cut-off `rc` (the length unit; keep 1).
    #[serde(default = "d_one")]
    pub cutoff: f64,
    /// Solvent–solvent repulsion `a` in `kT / rc`.
    #[serde(default = "d_rep")]
    pub repulsion: f64,
    /// Colloid–solvent repulsion in `kT / rc'`.
    #[serde(default = "d_rep")]
    pub repulsion_colloid_solvent: f64,
    /// Dissipation `gamma`, (0, 200]; below 4.5 the thermostat is weak (warning).
    #[serde(default = "d_gamma")]
    pub gamma: f64,
}

fn d_rep() -> f64 {
    25.0
}
fn d_gamma() -> f64 {
    4.5
}

impl Default for DpdSection {
    fn default() -> Self {
        Self {
            cutoff: 1.0,
            repulsion: 25.0,
            repulsion_colloid_solvent: 25.0,
            gamma: 4.5,
        }
    }
}

/// `[colloids]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ColloidSection {
    /// Colloid–colloid surface cut-off (dissipative, random, Morse, lubrication) in `rc`.
    #[serde(default = "d_one")]
    pub cutoff: f64,
    /// Contact modulus `f_contact` in `kT / rc`.
    #[serde(default = "d_contact")]
    pub contact: f64,
    /// Contact range `Delta` in `rc`.
    #[serde(default = "d_gap")]
    pub contact_range: f64,
    /// Morse depth `D0` in `kT` (0: no attraction).
    #[serde(default)]
    pub morse_depth: f64,
    /// Morse `kappa` in `1 / rc`.
    #[serde(default = "d_kappa")]
    pub morse_kappa: f64,
    /// Morse `r0` (surface gap) in `rc`.
    #[serde(default)]
    pub morse_r0: f64,
    /// Background viscosity `eta0` (lubrication and the Stokes–Einstein time unit).
    #[serde(default = "d_eta0")]
    pub eta0: f64,
    /// Squeeze-mode lubrication on or off.
    #[serde(default = "d_true")]
    pub lubrication: bool,
    /// Lubrication gap `delta` in `rc`.
    #[serde(default = "d_gap")]
    pub lubrication_gap: f64,
    /// `"exact"` (fluctuation–dissipation at every gap) or `"authors"` (noise weighted by w).
    #[serde(default)]
    pub lubrication_noise: LubricationNoise,
}

fn d_contact() -> f64 {
    10_000.0
}
fn d_gap() -> f64 {
    1e-3
}
fn d_kappa() -> f64 {
    30.0
}
fn d_eta0() -> f64 {
    0.3
}
fn d_true() -> bool {
    true
}

impl Default for ColloidSection {
    fn default() -> Self {
        Self {
            cutoff: 1.0,
            contact: d_contact(),
            contact_range: d_gap(),
            morse_depth: 0.0,
            morse_kappa: d_kappa(),
            morse_r0: 0.0,
            eta0: d_eta0(),
            lubrication: true,
            lubrication_gap: d_gap(),
            lubrication_noise: LubricationNoise::Exact,
        }
    }
}

/// `[run]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RunSection {
    /// Time step (DPD time).
    #[serde(default = "d_dt")]
    pub dt: f64,
    /// Steps to run.
    #[serde(default = "d_steps")]
    pub steps: u64,
    /// Neighbour-list skin in `rc`.
    #[serde(default = "d_skin")]
    pub skin: f64,
    /// Largest accepted relative deviation of the running kinetic temperature from kT (after
    /// the first `temperature_window` steps); beyond it the run stops: the step heats the system.
    #[serde(default = "d_drift")]
    pub max_temperature_drift: f64,
    /// Steps over which the kinetic temperature is averaged for that check.
    #[serde(default = "d_window")]
    pub temperature_window: u64,
    /// How solvent pairs are found: `"auto"`, `"verlet"` (lists with a skin) or `"cells"`
    /// (re-sorted every step, no lists).
    #[serde(default = "d_auto")]
    pub neighbors: String,
    /// Lees–Edwards shear rate `gamma_dot` (1 / DPD time; 0: no shear): flow along x,
    /// gradient along y.
    #[serde(default)]
    pub shear_rate: f64,
    /// The grid of MPI ranks `[py, pz]` of a decomposed run: columns along y by slabs along z
    /// (their product the number of ranks); unset: the grid with the fewest ghost cells. Not
    /// physics: the run is bitwise the same on any grid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rank_grid: Option<[usize; 2]>,
}

fn d_auto() -> String {
    "auto".into()
}

fn d_dt() -> f64 {
    1e-3
}
fn d_steps() -> u64 {
    10_000
}
fn d_skin() -> f64 {
    0.4
}
fn d_drift() -> f64 {
    0.1
}
fn d_window() -> u64 {
    1000
}

impl Default for RunSection {
    fn default() -> Self {
        Self {
            dt: d_dt(),
            steps: d_steps(),
            skin: d_skin(),
            max_temperature_drift: d_drift(),
            temperature_window: d_window(),
            neighbors: d_auto(),
            shear_rate: 0.0,
            rank_grid: None,
        }
    }
}

/// `[observe]` (periods in steps; 0 switches an output off).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ObserveSection {
    /// `thermo.csv` period.
    #[serde(default = "d_thermo")]
    pub thermo_every: u64,
    /// GSD trajectory period (positions, velocities, images).
    #[serde(default = "d_traj")]
    pub trajectory_every: u64,
    /// Period of the stored unwrapped positions for the MSD.
    #[serde(default = "d_thermo")]
    pub msd_every: u64,
    /// Solvent beads followed for the solvent MSD (the first tags).
    #[serde(default = "d_msd_solvent")]
    pub msd_solvent_beads: usize,
    /// Period of the structure samples (g(r), S(q), contacts, clusters).
    #[serde(default = "d_traj")]
    pub structure_every: u64,
    /// Bins of the colloid g(r).
    #[serde(default = "d_bins")]
    pub gr_bins: usize,
    /// Range of g(r) in `rc` (default: half the shortest box edge).
    #[serde(default)]
    pub gr_max: Option<f64>,
    /// Contact gap of the coordination number and clusters, in `rc` (default `3 / kappa`).
    #[serde(default)]
    pub contact_gap: Option<f64>,
    /// Steps averaged into one stress sample of the Green–Kubo viscosity (0: off).
    #[serde(default)]
    pub viscosity_every: u64,
    /// Longest lag of the stress autocorrelation, the upper limit of the Green–Kubo integral
    /// (DPD time).
    #[serde(default = "d_viscosity_time")]
    pub viscosity_time: f64,
    /// Bins along y of the velocity profile `v_x(y)` of a shear run (`run.shear_rate > 0`).
    #[serde(default = "d_profile_bins")]
    pub profile_bins: usize,
}

fn d_profile_bins() -> usize {
    16
}

/// Most sample intervals in the stress autocorrelation (`observe.viscosity_time`): each sample
/// costs that many products of six components.
pub const MAX_VISCOSITY_LAGS: usize = 100_000;

fn d_viscosity_time() -> f64 {
    5.0
}

fn d_thermo() -> u64 {
    100
}
fn d_traj() -> u64 {
    1000
}
fn d_msd_solvent() -> usize {
    1000
}
fn d_bins() -> usize {
    200
}

impl Default for ObserveSection {
    fn default() -> Self {
        Self {
            thermo_every: d_thermo(),
            trajectory_every: d_traj(),
            msd_every: d_thermo(),
            msd_solvent_beads: d_msd_solvent(),
            structure_every: d_traj(),
            gr_bins: d_bins(),
            gr_max: None,
            contact_gap: None,
            viscosity_every: 0,
            viscosity_time: d_viscosity_time(),
            profile_bins: d_profile_bins(),
        }
    }
}

/// Radii of the colloids.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RadiusDistribution {
    /// All equal.
    Monodisperse,
    /// Normal with relative standard deviation `spread` (truncated at +-3 sd).
    Gaussian(f64),
    /// Log-normal with relative standard deviation `spread` of the radius.
    LogNormal(f64),
    /// Uniform on `mean (1 +- spread)`.
    Uniform(f64),
}

/// A validated scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct DpdSetup {
    /// Engine parameters.
    pub params: DpdParams,
    /// Box.
    pub sbox: SimBox,
    /// Number of colloids.
    pub colloids: usize,
    /// Number of solvent beads.
    pub solvent: usize,
    /// Mean colloid radius.
    pub radius: f64,
    /// Radius distribution.
    pub distribution: RadiusDistribution,
    /// Solvent density.
    pub density: f64,
    /// Solvent bead mass.
    pub solvent_mass: f64,
    /// Stokes–Einstein diffusion coefficient `D0 = kT / (6 pi eta0 R_c)` of a bare colloid.
    pub d0: f64,
    /// Colloid diffusion time `tau_D = R_c^2 / D0`: the unit of the reported times.
    pub tau: f64,
    /// Steps.
    pub steps: u64,
    /// Temperature-drift limit (relative).
    pub max_temperature_drift: f64,
    /// Temperature window (steps).
    pub temperature_window: u64,
    /// Observables.
    pub observe: ObserveSection,
    /// Contact gap of the coordination number.
    pub contact_gap: f64,
    /// g(r) range.
    pub gr_max: f64,
    /// Lags of the stress autocorrelation (`observe.viscosity_time / (viscosity_every dt)`
    /// + 1; 0 when the viscosity is not observed).
    pub viscosity_lags: usize,
    /// Warnings to show the user (valid but questionable settings).
    pub warnings: Vec<String>,
}

impl DpdScenario {
    /// Parse a scenario file.
    pub fn from_toml(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }

    /// Check every key and resolve the setup.
    pub fn validate(&self) -> Result<DpdSetup, ParamError> {
        if self.method != "dpd" {
            return Err(ParamError::new(
                "method",
                format!("must be \"dpd\", got \"{}\"", self.method),
            ));
        }
        let seed = colloidsim_core::param::seed("seed", self.seed)?;
        let mut warnings = Vec::new();
        let s = &self.system;
        let l = match (s.box_length, s.box_edges) {
            (Some(l), None) => [positive("system.box_length", l)?; 3],
            (None, Some(e)) => {
                for x in e {
                    positive("system.box_edges", x)?;
                }
                e
            }
            (None, None) => {
                return Err(ParamError::new(
                    "system.box_length",
                    "give the box as box_length (cube) or box_edges = [Lx, Ly, Lz]",
                ));
            }
            (Some(_), Some(_)) => {
                return Err(ParamError::new(
                    "system.box_edges",
                    "give either box_length or box_edges, not both",
                ));
            }
        };
        let density = in_range("system.density", s.density, 1e-3, 20.0)?;
        let phi = in_range("system.phi", s.phi, 0.0, 0.35)?;
        let kt = positive("system.kT", s.kt)?;
        let radius = positive("system.colloid_radius", s.colloid_radius)?;
        let ms = positive("system.solvent_mass", s.solvent_mass)?;
        let spread = in_range("system.radius_spread", s.radius_spread, 0.0, 0.5)?;
        let distribution = match s.radius_distribution.as_str() {
            "monodisperse" => RadiusDistribution::Monodisperse,
            "gaussian" => RadiusDistribution::Gaussian(spread),
            "lognormal" => RadiusDistribution::LogNormal(spread),
            "uniform" => RadiusDistribution::Uniform(spread),
            other => {
                return Err(ParamError::new(
                    "system.radius_distribution",
                    format!(
                        "must be \"monodisperse\", \"gaussian\", \"lognormal\" or \"uniform\", got \"{other}\""
                    ),
                ));
            }
        };
        if spread > 0.0 && distribution == RadiusDistribution::Monodisperse {
            return Err(ParamError::new(
                "system.radius_spread",
                "a spread needs radius_distribution = \"gaussian\", \"lognormal\" or \"uniform\"",
            ));
        }
        let d = &self.dpd;
        let rc = positive("dpd.cutoff", d.cutoff)?;
        let repulsion = non_negative("dpd.repulsion", d.repulsion)?;
        let repulsion_cs =
            non_negative("dpd.repulsion_colloid_solvent", d.repulsion_colloid_solvent)?;
        let gamma = d.gamma;
        if !(gamma.is_finite() && gamma > 0.0 && gamma <= 200.0) {
            return Err(ParamError::new(
                "dpd.gamma",
                format!("must lie in (0, 200], got {gamma}"),
            ));
        }
        if gamma < 4.5 {
            warnings.push(format!(
                "dpd.gamma = {gamma} is below 4.5: too little dissipation to hold the temperature (notes: 4.5 <= gamma <= 200)"
            ));
        }
        let c = &self.colloids;
        let cc_cut = positive("colloids.cutoff", c.cutoff)?;
        let contact = non_negative("colloids.contact", c.contact)? * kt / rc;
        let delta = positive("colloids.contact_range", c.contact_range)?;
        if cc_cut <= delta {
            return Err(ParamError::new(
                "colloids.cutoff",
                format!(
                    "the colloid cut-off {cc_cut} must exceed the contact range colloids.contact_range = {delta}"
                ),
            ));
        }
        let morse_depth = non_negative("colloids.morse_depth", c.morse_depth)? * kt;
        let kappa = positive("colloids.morse_kappa", c.morse_kappa)?;
        let r0 = in_range("colloids.morse_r0", c.morse_r0, 0.0, cc_cut)?;
        let eta0 = positive("colloids.eta0", c.eta0)?;
        let lub_gap = positive("colloids.lubrication_gap", c.lubrication_gap)?;
        if lub_gap >= cc_cut {
            return Err(ParamError::new(
                "colloids.lubrication_gap",
                format!("must be smaller than colloids.cutoff = {cc_cut}, got {lub_gap}"),
            ));
        }
        if morse_depth > 0.0 && (kappa * cc_cut) < 5.0 {
            warnings.push(format!(
                "the Morse force at the cut-off is exp(-{:.1}) of its range: raise colloids.cutoff or colloids.morse_kappa",
                kappa * cc_cut
            ));
        }
        let r = &self.run;
        let dt = positive("run.dt", r.dt)?;
        let skin = in_range("run.skin", r.skin, 0.05, 2.0)?;
        let shear_rate = in_range("run.shear_rate", r.shear_rate, 0.0, 10.0)?;
        if let Some([py, pz]) = r.rank_grid {
            if py == 0 || pz == 0 {
                return Err(ParamError::new(
                    "run.rank_grid",
                    format!("[{py}, {pz}]: ranks along y and along z, each at least 1"),
                ));
            }
            if py > 1 && shear_rate > 0.0 {
                return Err(ParamError::new(
                    "run.rank_grid",
                    format!("[{py}, {pz}]: a sheared run is cut along z only (py = 1)"),
                ));
            }
        }
        let max_drift = in_range(
            "run.max_temperature_drift",
            r.max_temperature_drift,
            0.0,
            10.0,
        )?;
        let neighbors = match r.neighbors.as_str() {
            "auto" => NeighborMode::Auto,
            "verlet" => NeighborMode::Verlet,
            "cells" => NeighborMode::Cells,
            other => {
                return Err(ParamError::new(
                    "run.neighbors",
                    format!("must be \"auto\", \"verlet\" or \"cells\", got \"{other}\""),
                ));
            }
        };
        if r.temperature_window == 0 {
            return Err(ParamError::new("run.temperature_window", "must be >= 1"));
        }
        let o = &self.observe;
        let shortest = l.iter().cloned().fold(f64::INFINITY, f64::min);
        let gr_max = match o.gr_max {
            Some(g) => in_range("observe.gr_max", g, 1e-6, 0.5 * shortest)?,
            // Just under half the box: freud's RDF (and any AABB query) refuses exactly L/2.
            None => 0.49 * shortest,
        };
        if o.gr_bins == 0 {
            return Err(ParamError::new("observe.gr_bins", "must be >= 1"));
        }
        if !(1..=1000).contains(&o.profile_bins) {
            return Err(ParamError::new(
                "observe.profile_bins",
                format!("must lie in [1, 1000], got {}", o.profile_bins),
            ));
        }
        let contact_gap = match o.contact_gap {
            Some(g) => positive("observe.contact_gap", g)?,
            None => 3.0 / kappa,
        };
        let viscosity_time = positive("observe.viscosity_time", o.viscosity_time)?;
        let viscosity_lags = if o.viscosity_every > 0 {
            let delta = o.viscosity_every as f64 * dt;
            let intervals = (viscosity_time / delta).round();
            if intervals < 1.0 {
                return Err(ParamError::new(
                    "observe.viscosity_time",
                    format!(
                        "must be at least one sample interval, viscosity_every x dt = {delta}, got {viscosity_time}"
                    ),
                ));
            }
            if intervals > MAX_VISCOSITY_LAGS as f64 {
                return Err(ParamError::new(
                    "observe.viscosity_time",
                    format!(
                        "spans {intervals} sample intervals of {delta}; at most {MAX_VISCOSITY_LAGS} (raise observe.viscosity_every)"
                    ),
                ));
            }
            intervals as usize + 1
        } else {
            0
        };
        let sbox = SimBox::new(l);
        let vc = 4.0 / 3.0 * PI * radius.powi(3);
        // Memory before the counts become integers (a cast saturates) and anything is
        // allocated: about 600 B per bead (state, forces, Verlet lists at density 3, copies).
        let beads = sbox.volume() * (phi / vc + density * (1.0 - phi));
        colloidsim_core::resources::ensure_fits(
            "system.box_length",
            &format!("{beads:.3e} beads (density x box volume)"),
            600.0 * beads,
        )?;
        let colloids = (phi * sbox.volume() / vc).round() as usize;
        let free = sbox.volume() * (1.0 - phi);
        let solvent = (density * free).round() as usize;
        if colloids + solvent < 2 {
            return Err(ParamError::new(
                "system.density",
                "the box holds fewer than 2 particles",
            ));
        }
        // Box must hold 3 cells of the fluid range and twice the colloid range.
        let rmax = match distribution {
            RadiusDistribution::Monodisperse => radius,
            RadiusDistribution::Gaussian(s) => radius * (1.0 + 3.0 * s),
            RadiusDistribution::LogNormal(s) => radius * (1.0 + 6.0 * s),
            RadiusDistribution::Uniform(s) => radius * (1.0 + s),
        };
        let fluid = rc.max(if colloids > 0 {
            rmax + colloid_solvent_cutoff(rc, rmax)
        } else {
            0.0
        }) + skin;
        let need = (3.0 * fluid).max(if colloids > 0 {
            2.0 * (cc_cut + 2.0 * rmax + skin)
        } else {
            0.0
        });
        if shortest < need {
            return Err(ParamError::new(
                "system.box_length",
                format!(
                    "the shortest box edge {shortest} is below {need:.3} (three neighbour cells of rc' + skin and twice the colloid range)"
                ),
            ));
        }
        let d0 = kt / (6.0 * PI * eta0 * radius);
        let params = DpdParams {
            kt,
            gamma,
            rc,
            repulsion,
            repulsion_cs,
            colloid_cutoff: cc_cut,
            colloid: ColloidForces {
                contact,
                contact_range: delta,
                morse_depth,
                morse_kappa: kappa,
                morse_r0: r0,
                eta0: if c.lubrication { eta0 } else { 0.0 },
                lubrication_gap: lub_gap,
            },
            lubrication_noise: c.lubrication_noise,
            dt,
            skin,
            neighbors,
            seed,
            shear_rate,
            rank_grid: r.rank_grid,
        };
        Ok(DpdSetup {
            params,
            sbox,
            colloids,
            solvent,
            radius,
            distribution,
            density,
            solvent_mass: ms,
            d0,
            tau: radius * radius / d0,
            steps: r.steps,
            max_temperature_drift: max_drift,
            temperature_window: r.temperature_window,
            observe: o.clone(),
            contact_gap,
            gr_max,
            viscosity_lags,
            warnings,
        })
    }
}

/// The colloids overlap more deeply than the contact range allows.
pub fn check_overlaps(
    p: &Particles,
    sbox: &SimBox,
    is_colloid_type: &[bool],
    contact_range: f64,
) -> Result<(), DpdError> {
    let idx: Vec<usize> = (0..p.len())
        .filter(|&i| is_colloid_type[p.typeid[i] as usize])
        .collect();
    for (a, &i) in idx.iter().enumerate() {
        for &j in &idx[..a] {
            let (x, y) = (p.pos[i], p.pos[j]);
            let d = sbox.min_image([x[0] - y[0], x[1] - y[1], x[2] - y[2]]);
            let h = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
                - 0.5 * (p.diameter[i] + p.diameter[j]);
            if h < -contact_range {
                return Err(DpdError::Invalid(format!(
                    "colloids {j} and {i} overlap by {:.4} at the start, more than the contact range {contact_range}",
                    -h
                )));
            }
        }
    }
    Ok(())
}

impl DpdSetup {
    /// Colloid type index (solvent is type 0 `"S"`, colloids type 1 `"C"`).
    pub const COLLOID_TYPE: u32 = 1;

    /// Radii drawn from the distribution (largest first), deterministic in the seed.
    pub fn radii(&self) -> Vec<f64> {
        let mut rng = stream(self.params.seed, 0, Purpose::Initial, 1);
        let r = self.radius;
        let mut out: Vec<f64> = (0..self.colloids)
            .map(|_| match self.distribution {
                RadiusDistribution::Monodisperse => r,
                RadiusDistribution::Gaussian(s) => loop {
                    let z: f64 = rng.sample(StandardNormal);
                    if z.abs() <= 3.0 && 1.0 + s * z > 0.05 {
                        break r * (1.0 + s * z);
                    }
                },
                RadiusDistribution::LogNormal(s) => {
                    let sig2 = (1.0 + s * s).ln();
                    let z: f64 = rng.sample(StandardNormal);
                    r * (z * sig2.sqrt() - 0.5 * sig2).exp()
                }
                RadiusDistribution::Uniform(s) => r * (1.0 + s * (2.0 * rng.random::<f64>() - 1.0)),
            })
            .collect();
        out.sort_by(|a, b| b.total_cmp(a));
        out
    }

    /// Place the colloids by random sequential insertion (no overlaps), the solvent uniformly in
    /// the space they leave, Maxwell–Boltzmann velocities at kT with zero total momentum.
    pub fn initial_particles(&self) -> Result<Particles, DpdError> {
        let sbox = self.sbox;
        let l = sbox.l;
        let radii = self.radii();
        let amax = radii.first().copied().unwrap_or(0.0);
        let mut rng = stream(self.params.seed, 0, Purpose::Initial, 2);
        // Cell grid for overlap checks, cells >= 2 amax.
        let cell = (2.0 * amax).max(1e-9);
        let nc = l.map(|x| ((x / cell).floor() as usize).clamp(1, 256));
        let cell_of = |x: [f64; 3]| -> [usize; 3] {
            let mut c = [0; 3];
            for k in 0..3 {
                c[k] = ((((x[k] / l[k]) + 0.5) * nc[k] as f64) as usize).min(nc[k] - 1);
            }
            c
        };
        let mut grid: Vec<Vec<u32>> = vec![Vec::new(); nc[0] * nc[1] * nc[2]];
        let index = |c: [usize; 3]| (c[2] * nc[1] + c[1]) * nc[0] + c[0];
        let mut cpos: Vec<[f64; 3]> = Vec::with_capacity(radii.len());
        let near = |grid: &Vec<Vec<u32>>, x: [f64; 3], mut f: Box<dyn FnMut(u32) -> bool + '_>| {
            let c = cell_of(x);
            let span = |n: usize| {
                if n >= 3 {
                    [n - 1, 0, 1].to_vec()
                } else {
                    (0..n).collect()
                }
            };
            for dz in span(nc[2]) {
                for dy in span(nc[1]) {
                    for dx in span(nc[0]) {
                        let cc = [
                            if nc[0] >= 3 { (c[0] + dx) % nc[0] } else { dx },
                            if nc[1] >= 3 { (c[1] + dy) % nc[1] } else { dy },
                            if nc[2] >= 3 { (c[2] + dz) % nc[2] } else { dz },
                        ];
                        for &j in &grid[index(cc)] {
                            if !f(j) {
                                return false;
                            }
                        }
                    }
                }
            }
            true
        };
        for (k, &a) in radii.iter().enumerate() {
            let mut placed = false;
            for _ in 0..200_000 {
                let x = [
                    (rng.random::<f64>() - 0.5) * l[0],
                    (rng.random::<f64>() - 0.5) * l[1],
                    (rng.random::<f64>() - 0.5) * l[2],
                ];
                let ok = near(
                    &grid,
                    x,
                    Box::new(|j| {
                        let y = cpos[j as usize];
                        let d = sbox.min_image([x[0] - y[0], x[1] - y[1], x[2] - y[2]]);
                        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                        r2 >= (a + radii[j as usize]).powi(2)
                    }),
                );
                if ok {
                    grid[index(cell_of(x))].push(k as u32);
                    cpos.push(x);
                    placed = true;
                    break;
                }
            }
            if !placed {
                return Err(DpdError::Invalid(format!(
                    "random insertion placed only {k} of {} colloids; lower system.phi",
                    radii.len()
                )));
            }
        }
        let mut pos = Vec::with_capacity(self.solvent + radii.len());
        let mut typeid = Vec::with_capacity(pos.capacity());
        let mut diameter = Vec::with_capacity(pos.capacity());
        let mut mass = Vec::with_capacity(pos.capacity());
        for (x, &a) in cpos.iter().zip(&radii) {
            pos.push(*x);
            typeid.push(Self::COLLOID_TYPE);
            diameter.push(2.0 * a);
            mass.push(4.0 / 3.0 * PI * a.powi(3) * self.density * self.solvent_mass);
        }
        // Solvent on a jittered simple-cubic lattice over the free volume (a random start
        // overlaps beads strongly, and the energy it releases heats the system for several
        // DPD times): sites inside a colloid or within half its colloid-solvent cut-off of the
        // surface are left empty, the lattice is refined until enough sites remain, and a
        // random subset of them is used.
        let free_vol = (sbox.volume()
            - radii
                .iter()
                .map(|a| {
                    4.0 / 3.0 * PI * (a + 0.5 * colloid_solvent_cutoff(self.params.rc, *a)).powi(3)
                })
                .sum::<f64>())
        .max(0.05 * sbox.volume());
        let mut spacing = (free_vol / self.solvent.max(1) as f64).cbrt();
        let mut sites: Vec<[f64; 3]> = Vec::new();
        for _ in 0..200 {
            sites.clear();
            let n = l.map(|x| ((x / spacing).ceil() as usize).max(1));
            let h = [l[0] / n[0] as f64, l[1] / n[1] as f64, l[2] / n[2] as f64];
            for iz in 0..n[2] {
                for iy in 0..n[1] {
                    for ix in 0..n[0] {
                        let mut x = [
                            (ix as f64 + 0.5) * h[0] - 0.5 * l[0],
                            (iy as f64 + 0.5) * h[1] - 0.5 * l[1],
                            (iz as f64 + 0.5) * h[2] - 0.5 * l[2],
                        ];
                        for k in 0..3 {
                            x[k] += 0.2 * h[k] * (rng.random::<f64>() - 0.5);
                        }
                        let free = radii.is_empty()
                            || near(
                                &grid,
                                x,
                                Box::new(|j| {
                                    let a = radii[j as usize];
                                    let y = cpos[j as usize];
                                    let d = sbox.min_image([x[0] - y[0], x[1] - y[1], x[2] - y[2]]);
                                    let excl = a + 0.5 * colloid_solvent_cutoff(self.params.rc, a);
                                    d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= excl * excl
                                }),
                            );
                        if free {
                            sites.push(x);
                        }
                    }
                }
            }
            if sites.len() >= self.solvent {
                break;
            }
            spacing *= 0.98;
        }
        if sites.len() < self.solvent {
            return Err(DpdError::Invalid(format!(
                "could not fit {} solvent beads between the colloids",
                self.solvent
            )));
        }
        // Keep a random subset of `solvent` sites (partial Fisher-Yates), in lattice order.
        let mut keep: Vec<u32> = (0..sites.len() as u32).collect();
        for k in 0..self.solvent {
            let r = k + (rng.random::<f64>() * (sites.len() - k) as f64) as usize;
            keep.swap(k, r.min(sites.len() - 1));
        }
        keep.truncate(self.solvent);
        keep.sort_unstable();
        for &k in &keep {
            pos.push(sites[k as usize]);
            typeid.push(0);
            diameter.push(1.0);
            mass.push(self.solvent_mass);
        }
        let n = pos.len();
        let kt = self.params.kt;
        let mut vrng = stream(self.params.seed, 0, Purpose::Initial, 3);
        let mut vel: Vec<[f64; 3]> = mass
            .iter()
            .map(|m| {
                let sd = (kt / m).sqrt();
                [
                    sd * vrng.sample::<f64, _>(StandardNormal),
                    sd * vrng.sample::<f64, _>(StandardNormal),
                    sd * vrng.sample::<f64, _>(StandardNormal),
                ]
            })
            .collect();
        let mtot: f64 = mass.iter().sum();
        let mut p = [0.0; 3];
        for (v, m) in vel.iter().zip(&mass) {
            for k in 0..3 {
                p[k] += m * v[k];
            }
        }
        for v in vel.iter_mut() {
            for k in 0..3 {
                v[k] -= p[k] / mtot;
            }
        }
        // Under shear the start has the streaming profile u_x = gamma_dot y (y wrapped).
        let shear = self.params.shear_rate;
        if shear != 0.0 {
            let ly = self.sbox.l[1];
            for (v, x) in vel.iter_mut().zip(&pos) {
                let y = x[1] - ly * (x[1] / ly + 0.5).floor();
                v[0] += shear * y;
            }
        }
        Ok(Particles {
            pos,
            image: vec![[0; 3]; n],
            typeid,
            diameter,
            vel,
            mass,
            type_names: vec!["S".into(), "C".into()],
        })
    }

    /// Which types are colloids: `[false, true]` (solvent `"S"`, colloid `"C"`).
    pub fn colloid_types() -> Vec<bool> {
        vec![false, true]
    }

    /// The engine on a fresh configuration.
    pub fn build(&self) -> Result<Dpd, DpdError> {
        let p = self.initial_particles()?;
        self.build_from(p, 0)
    }

    /// The engine on given particles (types `"S"`, `"C"`) at `step`, after checking colloid
    /// overlaps.
    pub fn build_from(&self, p: Particles, step: u64) -> Result<Dpd, DpdError> {
        self.build_on(p, step, None)
    }

    /// [`Self::build`] decomposed over the ranks of `comm` ([`Dpd::decomposed`]): every rank
    /// generates the same start and keeps its layers.
    pub fn build_decomposed(&self, comm: Box<dyn Exchange>) -> Result<Dpd, DpdError> {
        let p = self.initial_particles()?;
        self.build_on(p, 0, Some(comm))
    }

    fn build_on(
        &self,
        p: Particles,
        step: u64,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Dpd, DpdError> {
        check_overlaps(
            &p,
            &self.sbox,
            &Self::colloid_types(),
            self.params.colloid.contact_range,
        )?;
        let (sbox, params, types) = (self.sbox, self.params, Self::colloid_types());
        match comm {
            None => Dpd::new(p, sbox, params, types, step),
            Some(c) => Dpd::decomposed(p, sbox, params, types, step, c),
        }
    }
}

/// Stops a run whose kinetic temperature drifts: the mean of the samples in each window of
/// `window` steps must stay within `max_drift` (relative) of kT. The first window (relaxation of
/// the start) is not judged.
#[derive(Debug, Clone)]
pub struct TemperatureMonitor {
    kt: f64,
    max_drift: f64,
    window: u64,
    window_end: Option<u64>,
    sum: f64,
    count: u64,
    judged: bool,
}

impl TemperatureMonitor {
    /// A monitor for `kt`.
    pub fn new(kt: f64, max_drift: f64, window: u64) -> Self {
        Self {
            kt,
            max_drift,
            window: window.max(1),
            window_end: None,
            sum: 0.0,
            count: 0,
            judged: false,
        }
    }

    /// Feed the kinetic temperature sampled at `step`; an error message when a window's mean
    /// has drifted.
    pub fn push(&mut self, step: u64, temperature: f64) -> Result<(), String> {
        let end = *self.window_end.get_or_insert(step + self.window);
        self.sum += temperature;
        self.count += 1;
        if step < end {
            return Ok(());
        }
        let mean = self.sum / self.count as f64;
        let judged = std::mem::replace(&mut self.judged, true);
        self.window_end = Some(step + self.window);
        self.sum = 0.0;
        self.count = 0;
        if judged && (mean / self.kt - 1.0).abs() > self.max_drift {
            return Err(format!(
                "the kinetic temperature averaged over the {} steps before step {step} is {mean:.4}, {:+.1}% from kT = {}: the time step heats (or cools) the system; reduce run.dt (or raise run.max_temperature_drift = {})",
                self.window,
                100.0 * (mean / self.kt - 1.0),
                self.kt,
                self.max_drift
            ));
        }
        Ok(())
    }
}
