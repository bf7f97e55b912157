//! Scenarios of the MPCD engine, in MPCD units (lengths in the cell edge `a`, masses in the
//! solvent mass `m`, energies in `kT`, times in `a sqrt(m / kT)`):
//!
//! - `method = "mpcd"`: the SRD solvent in a periodic cube; with `[viscosity]`, the periodic
//!   Poiseuille drive of [`super::measure`] and the measured shear viscosity.
//! - `method = "droplet-mpcd"`: the drying droplet of `droplet-bd` (the same radius law
//!   `R(t) = sqrt(R0^2 - alpha t / (4 pi))`) filled with the SRD solvent, whose boundary at the
//!   moving sphere is `none` (the solvent fills the box and ignores it), `slip` or `no-slip`
//!   ([`super::boundary`]).
//!
//! Every key is checked here with a message that names it and its allowed range.

use super::colloid::ColloidParams;
use super::srd::SrdParams;
use super::theory;
use crate::droplet::{DryingSection, InterfaceSection, ProfileSection};
use crate::potential::SphereAreaLaw;
use colloidsim_core::param::{ParamError, positive, show};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Target flow amplitude of the default viscosity drive, in thermal speeds `sqrt(kT / m)`
/// (the drive heats the fluid by an amount quadratic in the amplitude; docs/mpcd.md).
pub const DEFAULT_FLOW: f64 = 0.25;

/// Relaxation times `rho / (eta k^2)` of the Poiseuille flow before sampling starts.
pub const RELAXATION_TIMES: f64 = 6.0;

/// `[solvent]`: the SRD fluid (defaults: the drying-droplet paper, docs/references.md, the group's usual values).
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SolventSection {
    /// Mean particles per cell M (default 5).
    pub density: Option<f64>,
    /// Rotation angle in degrees, (0, 180] (default 130).
    pub angle: Option<f64>,
    /// Collision time tau (default 0.1).
    pub tau: Option<f64>,
    /// Thermal energy kT (default 1).
    #[serde(rename = "kT")]
    pub kt: Option<f64>,
    /// Solvent particle mass m (default 1).
    pub mass: Option<f64>,
    /// Cell edge a (default 1; every box edge must be a whole number of cells).
    pub cell: Option<f64>,
    /// Cell-level Maxwell–Boltzmann thermostat (default true).
    pub thermostat: Option<bool>,
}

impl SolventSection {
    /// The engine's parameters, every key checked.
    pub fn params(&self, seed: u32) -> Result<SrdParams, ParamError> {
        let std = SrdParams::standard(seed);
        let angle = self.angle.unwrap_or(std.angle.to_degrees());
        if !(angle.is_finite() && angle > 0.0 && angle <= 180.0) {
            return Err(ParamError::new(
                "solvent.angle",
                format!("must lie in (0, 180] degrees, got {}", show(angle)),
            ));
        }
        let density = positive("solvent.density", self.density.unwrap_or(std.density))?;
        if density > 1000.0 {
            return Err(ParamError::new(
                "solvent.density",
                format!(
                    "must lie in (0, 1000] particles per cell, got {}",
                    show(density)
                ),
            ));
        }
        Ok(SrdParams {
            cell: positive("solvent.cell", self.cell.unwrap_or(std.cell))?,
            density,
            angle: angle.to_radians(),
            tau: positive("solvent.tau", self.tau.unwrap_or(std.tau))?,
            kt: positive("solvent.kT", self.kt.unwrap_or(std.kt))?,
            mass: positive("solvent.mass", self.mass.unwrap_or(std.mass))?,
            thermostat: self.thermostat.unwrap_or(std.thermostat),
            seed,
        })
    }
}

/// Resolved description of a solvent, as `summary.json` records it.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SolventParams {
    /// The engine's parameters (`angle` in radians).
    pub srd: SrdParams,
    /// Rotation angle in degrees.
    pub angle_degrees: f64,
    /// Number density `M / a^3`.
    pub number_density: f64,
    /// Mass density `M m / a^3`.
    pub mass_density: f64,
    /// Kikuchi et al.'s shear viscosity of this solvent (kinetic + collisional).
    pub viscosity_theory: f64,
}

impl SolventParams {
    fn of(srd: SrdParams) -> Self {
        let n = srd.density / srd.cell.powi(3);
        Self {
            srd,
            angle_degrees: srd.angle.to_degrees(),
            number_density: n,
            mass_density: n * srd.mass,
            viscosity_theory: theory::viscosity(&srd).total(),
        }
    }
}

/// Peak bytes of a solvent of `n` particles in `cells` cells: `Srd::new` holds the particles
/// in `f64` before encoding them (about twice the 56 bytes per particle of a running engine).
fn ensure_solvent_fits(key: &str, n: f64, cells: f64) -> Result<(), ParamError> {
    let bytes = 112.0 * n + 8.0 * cells;
    colloidsim_core::resources::ensure_fits(key, &format!("{n:e} solvent particles"), bytes)
}

/// Box edge `l` (key `key`) as a whole number of cells of edge `a`, at least `min` cells.
fn box_edge(key: &str, l: f64, a: f64, min: usize) -> Result<f64, ParamError> {
    let l = positive(key, l)?;
    let cells = l / a;
    if (cells - cells.round()).abs() > 1e-9 * cells.max(1.0) {
        return Err(ParamError::new(
            key,
            format!(
                "{} is not a whole number of cells of edge solvent.cell = {}",
                show(l),
                show(a)
            ),
        ));
    }
    if (cells.round() as usize) < min {
        return Err(ParamError::new(
            key,
            format!("must hold at least {min} cells, got {}", show(cells)),
        ));
    }
    if cells > 4096.0 {
        return Err(ParamError::new(
            key,
            format!("at most 4096 cells per edge, got {}", show(cells)),
        ));
    }
    Ok(cells.round() * a)
}

/// `[system]` of a bulk scenario.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BulkSystem {
    /// Edge of the periodic cube (a whole number of cells).
    #[serde(rename = "box")]
    pub box_edge: f64,
    /// Discrete-particle colloids placed at random (default 0).
    #[serde(default)]
    pub colloids: usize,
    /// Colloid diameter d (default 4 cells).
    pub diameter: Option<f64>,
}

/// `[run]` of a bulk scenario.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BulkRunSection {
    /// Collisions in all (the sampling ones follow the equilibration).
    pub collisions: u64,
    /// Collisions before sampling (default: six relaxation times of the flow with a drive,
    /// else 100).
    pub equilibrate: Option<u64>,
}

/// `[viscosity]`: the periodic Poiseuille measurement.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ViscositySection {
    /// Drive amplitude `g0` of the body force `g0 cos(2 pi z / L)` along x (force per unit
    /// mass; default: the drive whose flow amplitude is 0.25 thermal speeds by the theory's
    /// viscosity).
    pub drive: Option<f64>,
    /// Blocks of the standard error (default 10).
    pub blocks: Option<u64>,
}

/// `[observe]` of a bulk scenario.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BulkObserve {
    /// A row of `thermo.csv` every this many collisions (default: 200 rows over the run).
    pub every: Option<u64>,
    /// Lags (collisions) of the colloids' velocity autocorrelation summed by Green–Kubo
    /// (default: five decay times `L^2 / (4 pi^2 nu)` of the box's slowest shear mode).
    pub vacf_lags: Option<u64>,
    /// GSD trajectory.
    #[serde(default)]
    pub trajectory: TrajectorySection,
}

/// `[observe]` of a droplet scenario.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ObserveSection {
    /// A row of `thermo.csv` every this many collisions (default: 200 rows over the run).
    pub every: Option<u64>,
    /// Radial profiles (droplet only).
    pub profile: Option<ProfileSection>,
    /// Solvent radial profiles (droplet only).
    pub solvent: Option<SolventObserve>,
    /// GSD trajectory.
    #[serde(default)]
    pub trajectory: TrajectorySection,
}

/// `[observe.solvent]`: solvent density and radial velocity against `r / R(t)`.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SolventObserve {
    /// Bins between 0 and R(t) (default 20).
    pub bins: Option<usize>,
    /// Each solvent profile averages the collisions of this window ending at its time
    /// (default: a tenth of the run, at least 1).
    pub window: Option<u64>,
}

/// `[observe.trajectory]`.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TrajectorySection {
    /// A GSD frame every this many collisions (0: none, the default).
    #[serde(default)]
    pub every: u64,
    /// Write the solvent particles too (type `S`; default false).
    #[serde(default)]
    pub solvent: bool,
}

/// A bulk `mpcd` scenario as written.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BulkScenario {
    /// Must be `"mpcd"`.
    pub method: String,
    /// Seed of the counter-based random streams (0 ..= 2^32 - 1).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// The SRD solvent.
    #[serde(default)]
    pub solvent: SolventSection,
    /// The periodic box.
    pub system: BulkSystem,
    /// Collisions.
    pub run: BulkRunSection,
    /// Shear-viscosity measurement (absent: none, the solvent at rest).
    pub viscosity: Option<ViscositySection>,
    /// The discrete-particle colloid.
    #[serde(default)]
    pub colloid: ColloidSection,
    /// Observables.
    #[serde(default)]
    pub observe: BulkObserve,
}

fn default_seed() -> u64 {
    1
}

/// A validated bulk run.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct BulkRun {
    /// Seed.
    pub seed: u32,
    /// The solvent.
    pub solvent: SolventParams,
    /// Box edge.
    pub box_edge: f64,
    /// Solvent particles `round(M (L / a)^3)`.
    pub particles: usize,
    /// Collisions in all.
    pub collisions: u64,
    /// Collisions before sampling.
    pub equilibrate: u64,
    /// The viscosity drive `g0` (absent: no measurement).
    pub drive: Option<f64>,
    /// Flow amplitude the drive gives by the theory's viscosity.
    pub expected_flow: Option<f64>,
    /// Blocks of the standard errors.
    pub blocks: u64,
    /// `thermo.csv` period.
    pub thermo_every: u64,
    /// GSD frame period (0: none).
    pub trajectory_every: u64,
    /// Frames hold the solvent.
    pub trajectory_solvent: bool,
    /// Colloids.
    pub colloids: usize,
    /// The colloid model.
    pub colloid: ColloidParams,
    /// Lags of the Green–Kubo sum of the colloids' centre-of-mass velocity autocorrelation.
    pub vacf_lags: u64,
    /// Stokes–Einstein–Hasimoto diffusivity `kT / (3 pi eta d) (1 - 2.837297 a/L)` of a sphere
    /// of radius `a = d/2` with the theory's viscosity (Hasimoto's leading finite-size term, as
    /// Dünweg & Kremer; docs/mpcd.md, "Colloids: diffusion").
    pub stokes_einstein_hasimoto: f64,
}

fn thermo_every(every: Option<u64>, collisions: u64) -> Result<u64, ParamError> {
    match every {
        Some(0) => Err(ParamError::new(
            "observe.every",
            "must be an integer >= 1 (collisions between rows of thermo.csv), got 0",
        )),
        Some(e) => Ok(e),
        None => Ok((collisions / 200).max(1)),
    }
}

impl BulkScenario {
    /// Parse the TOML text.
    pub fn from_toml(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }

    /// Check every key and resolve the derived parameters.
    pub fn validate(&self) -> Result<BulkRun, ParamError> {
        if self.method != "mpcd" {
            return Err(ParamError::new(
                "method",
                format!("must be \"mpcd\", got \"{}\"", self.method),
            ));
        }
        let seed = colloidsim_core::param::seed("seed", self.seed)?;
        let srd = self.solvent.params(seed)?;
        let solvent = SolventParams::of(srd);
        let l = box_edge("system.box", self.system.box_edge, srd.cell, 2)?;
        let particles = (srd.density * (l / srd.cell).powi(3)).round();
        if particles >= (1u64 << 31) as f64 {
            return Err(ParamError::new(
                "system.box",
                format!(
                    "{particles:e} solvent particles: at most 2^31 - 1 are supported (a smaller box or density)"
                ),
            ));
        }
        ensure_solvent_fits("system.box", particles, (l / srd.cell).powi(3))?;
        let collisions = self.run.collisions;
        if !(1..=1 << 53).contains(&collisions) {
            return Err(ParamError::new(
                "run.collisions",
                format!("must be an integer in [1, 2^53], got {collisions}"),
            ));
        }
        let eta = solvent.viscosity_theory;
        let k = 2.0 * PI / l;
        let rho = solvent.mass_density;
        let thermal = (srd.kt / srd.mass).sqrt();
        let (drive, expected_flow, relax) = match &self.viscosity {
            None => (None, None, 100),
            Some(v) => {
                let g0 = match v.drive {
                    Some(g) => positive("viscosity.drive", g)?,
                    None => DEFAULT_FLOW * thermal * eta * k * k / rho,
                };
                let flow = rho * g0 / (eta * k * k);
                if flow > 0.6 * thermal {
                    return Err(ParamError::new(
                        "viscosity.drive",
                        format!(
                            "{} drives a flow of amplitude {flow:.3} (by the theory's viscosity), more than 0.6 thermal speeds \
                             ({:.3}): the measurement would be dominated by viscous heating; at most {:.4}",
                            show(g0),
                            0.6 * thermal,
                            0.6 * thermal * eta * k * k / rho
                        ),
                    ));
                }
                let relax = (RELAXATION_TIMES * rho / (eta * k * k) / srd.tau).ceil() as u64;
                (Some(g0), Some(flow), relax)
            }
        };
        let equilibrate = self.run.equilibrate.unwrap_or(relax.min(collisions / 2));
        if equilibrate >= collisions {
            return Err(ParamError::new(
                "run.equilibrate",
                format!("must be below run.collisions = {collisions}, got {equilibrate}"),
            ));
        }
        let blocks = self.viscosity.as_ref().and_then(|v| v.blocks).unwrap_or(10);
        if !(2..=10_000).contains(&blocks) || blocks > collisions - equilibrate {
            return Err(ParamError::new(
                "viscosity.blocks",
                format!(
                    "must be an integer in [2, min(10000, sampling collisions = {})], got {blocks}",
                    collisions - equilibrate
                ),
            ));
        }
        let o = &self.observe;
        let t = &o.trajectory;
        let nc = self.system.colloids;
        if t.every > 0 && !t.solvent && nc == 0 {
            return Err(ParamError::new(
                "observe.trajectory.solvent",
                "a bulk solvent without colloids: a trajectory (observe.trajectory.every > 0) needs observe.trajectory.solvent = true",
            ));
        }
        if nc > 1_000_000 {
            return Err(ParamError::new(
                "system.colloids",
                format!("must be an integer in [0, 1000000], got {nc}"),
            ));
        }
        if nc > 0 && self.viscosity.is_some() {
            return Err(ParamError::new(
                "viscosity",
                "the Poiseuille drive acts on the solvent alone: with colloids it would measure neither the solvent nor the suspension; measure the solvent without colloids (system.colloids = 0)",
            ));
        }
        let d = positive(
            "system.diameter",
            self.system.diameter.unwrap_or(4.0 * srd.cell),
        )?;
        if nc > 0 && 2.0 * 2f64.powf(1.0 / 6.0) * d >= l {
            return Err(ParamError::new(
                "system.box",
                format!(
                    "{} must exceed twice the colloids' WCA cut-off 2^(1/6) d = {:.4}",
                    show(l),
                    2f64.powf(1.0 / 6.0) * d
                ),
            ));
        }
        let colloid = self.colloid.params(d, srd.kt)?;
        let nu = eta / rho;
        let slowest = l * l / (4.0 * PI * PI * nu);
        let vacf_lags = o
            .vacf_lags
            .unwrap_or((5.0 * slowest / srd.tau).round().max(1.0) as u64);
        let sampling = collisions - equilibrate;
        if nc > 0 && !(1..=sampling / 2).contains(&vacf_lags) {
            return Err(ParamError::new(
                "observe.vacf_lags",
                format!(
                    "must be an integer in [1, half the sampling collisions = {}], got {vacf_lags}: run longer",
                    sampling / 2
                ),
            ));
        }
        let x = 0.5 * d / l;
        let stokes_einstein_hasimoto = srd.kt / (3.0 * PI * eta * d) * (1.0 - 2.837297 * x);
        Ok(BulkRun {
            seed,
            solvent,
            box_edge: l,
            particles: particles as usize,
            collisions,
            equilibrate,
            drive,
            expected_flow,
            blocks,
            thermo_every: thermo_every(o.every, collisions)?,
            trajectory_every: t.every,
            trajectory_solvent: t.solvent,
            colloids: nc,
            colloid,
            vacf_lags,
            stokes_einstein_hasimoto,
        })
    }
}

/// The solvent's boundary at the droplet's sphere.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Boundary {
    /// The solvent fills the periodic box and ignores the interface.
    None,
    /// Bounce-back reversing the normal part of the velocity relative to the wall.
    Slip,
    /// Bounce-back reversing the whole velocity relative to the wall.
    NoSlip,
}

/// `[system]` of a droplet scenario.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DropletSystem {
    /// Colloids (0: a pure-solvent droplet; default 0).
    #[serde(default)]
    pub particles: usize,
    /// Colloid diameter d (default 4 cells); it sets `D0` and with it the Peclet number.
    pub diameter: Option<f64>,
    /// Initial droplet radius R0 (give this or `phi0`).
    pub radius: Option<f64>,
    /// Initial colloid volume fraction `N d^3 / (8 R0^3)` (give this or `radius`).
    pub phi0: Option<f64>,
    /// Periodic box edge (default: the smallest whole number of cells >= 2 R0 + 4 a).
    #[serde(rename = "box")]
    pub box_edge: Option<f64>,
}

/// `[colloid]`: the discrete-particle colloid (defaults `ColloidParams::standard`, chosen:
/// the paper's values were lost; docs/mpcd.md).
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ColloidSection {
    /// Mass of each of the 42 vertices (default 5 m).
    pub vertex_mass: Option<f64>,
    /// Mass of the central particle (default 5 m).
    pub centre_mass: Option<f64>,
    /// Spring constant of the bonds (default 5000 kT / a^2).
    pub bond_k: Option<f64>,
    /// Velocity Verlet steps per collision time (default 50).
    pub md_steps: Option<u32>,
}

impl ColloidSection {
    /// The colloid model of diameter `d`, every key checked.
    pub fn params(&self, d: f64, kt: f64) -> Result<ColloidParams, ParamError> {
        let std = ColloidParams::standard(d, kt);
        let md_steps = self.md_steps.unwrap_or(std.md_steps);
        if !(1..=100_000).contains(&md_steps) {
            return Err(ParamError::new(
                "colloid.md_steps",
                format!("must be an integer in [1, 100000], got {md_steps}"),
            ));
        }
        Ok(ColloidParams {
            diameter: d,
            vertex_mass: positive(
                "colloid.vertex_mass",
                self.vertex_mass.unwrap_or(std.vertex_mass),
            )?,
            centre_mass: positive(
                "colloid.centre_mass",
                self.centre_mass.unwrap_or(std.centre_mass),
            )?,
            bond_k: positive("colloid.bond_k", self.bond_k.unwrap_or(std.bond_k))?,
            md_steps,
            wca_epsilon: std.wca_epsilon,
        })
    }
}

/// A `droplet-mpcd` scenario as written.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DropletScenario {
    /// Must be `"droplet-mpcd"`.
    pub method: String,
    /// Seed of the counter-based random streams.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// The solvent's boundary at the sphere (default `"slip"`).
    pub boundary: Option<Boundary>,
    /// The SRD solvent.
    #[serde(default)]
    pub solvent: SolventSection,
    /// Colloids, droplet and box.
    pub system: DropletSystem,
    /// The drying law, as droplet-bd's.
    #[serde(default)]
    pub drying: DryingSection,
    /// The harmonic interface on the colloid centres, as droplet-bd's.
    #[serde(default)]
    pub interface: InterfaceSection,
    /// The discrete-particle colloid.
    #[serde(default)]
    pub colloid: ColloidSection,
    /// Observables.
    #[serde(default)]
    pub observe: ObserveSection,
}

/// A validated drying droplet of MPCD solvent.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DropletRun {
    /// Seed.
    pub seed: u32,
    /// Boundary at the sphere.
    pub boundary: Boundary,
    /// The solvent.
    pub solvent: SolventParams,
    /// Colloids.
    pub particles: usize,
    /// Colloid diameter d.
    pub diameter: f64,
    /// Stokes–Einstein diffusivity `kT / (3 pi eta d)` with the theory's viscosity (the
    /// paper's estimate at infinite dilution).
    pub d0: f64,
    /// Initial radius R0.
    pub r0: f64,
    /// Initial colloid volume fraction.
    pub phi0: f64,
    /// Box edge.
    pub box_edge: f64,
    /// Peclet number `R |dR/dt| / D0`.
    pub peclet: f64,
    /// Rate of loss of surface area.
    pub alpha: f64,
    /// Drying time (end of the run).
    pub t_end: f64,
    /// Radius at the end.
    pub r_end: f64,
    /// Mean colloid volume fraction `N d^3 / (8 R^3)` at the end.
    pub phi_end: f64,
    /// The colloid model (also resolved without colloids).
    pub colloid: ColloidParams,
    /// Interface spring constant, range and offset (`s = r - (R(t) + offset)`).
    pub interface: [f64; 3],
    /// Collisions `ceil(t_end / tau)`.
    pub collisions: u64,
    /// Solvent particles at the start.
    pub solvent_particles: usize,
    /// Colloid-profile bins and fractions of the run at which profiles are taken.
    pub profile: ProfileSection,
    /// Collisions at which the profiles are taken (`round(fraction * collisions)`).
    pub profile_collisions: Vec<u64>,
    /// Solvent-profile bins.
    pub solvent_bins: usize,
    /// Collisions each solvent profile averages.
    pub solvent_window: u64,
    /// `thermo.csv` period.
    pub thermo_every: u64,
    /// GSD frame period (0: none).
    pub trajectory_every: u64,
    /// Frames hold the solvent.
    pub trajectory_solvent: bool,
}

impl DropletRun {
    /// The harmonic interface on the colloid centres.
    pub fn harmonic(&self) -> crate::potential::HarmonicInterface {
        crate::potential::HarmonicInterface {
            centre: [0.0; 3],
            radius: self.law(),
            stiffness: self.interface[0],
            range: self.interface[1],
            offset: self.interface[2],
        }
    }

    /// The radius law.
    pub fn law(&self) -> SphereAreaLaw {
        SphereAreaLaw {
            r0: self.r0,
            alpha: self.alpha,
        }
    }
}

impl DropletScenario {
    /// Parse the TOML text.
    pub fn from_toml(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }

    /// Check every key and resolve the derived parameters.
    pub fn validate(&self) -> Result<DropletRun, ParamError> {
        if self.method != "droplet-mpcd" {
            return Err(ParamError::new(
                "method",
                format!("must be \"droplet-mpcd\", got \"{}\"", self.method),
            ));
        }
        let seed = colloidsim_core::param::seed("seed", self.seed)?;
        let srd = self.solvent.params(seed)?;
        let solvent = SolventParams::of(srd);
        let a = srd.cell;
        let s = &self.system;
        if s.particles > 10_000_000 {
            return Err(ParamError::new(
                "system.particles",
                format!("must be an integer in [0, 10000000], got {}", s.particles),
            ));
        }
        let d = positive("system.diameter", s.diameter.unwrap_or(4.0 * a))?;
        let kt = srd.kt;
        let colloid = self.colloid.params(d, kt)?;
        let n = s.particles as f64;
        let (r0, phi0) = match (s.radius, s.phi0) {
            (Some(_), Some(_)) => {
                return Err(ParamError::new(
                    "system.phi0",
                    "give either system.phi0 or system.radius, not both",
                ));
            }
            (Some(r), None) => {
                let r = positive("system.radius", r)?;
                let phi = n * d.powi(3) / (8.0 * r.powi(3));
                if phi > 0.3 {
                    return Err(ParamError::new(
                        "system.radius",
                        format!(
                            "{} colloids of diameter {} in radius {} give phi0 = {phi:.4}, more than random insertion packs (0.3): the radius must be at least {:.4}",
                            s.particles,
                            show(d),
                            show(r),
                            d * (n / 2.4).cbrt()
                        ),
                    ));
                }
                (r, phi)
            }
            (None, Some(phi)) => {
                if s.particles == 0 {
                    return Err(ParamError::new(
                        "system.phi0",
                        "a pure-solvent droplet (system.particles = 0) has no volume fraction: give system.radius",
                    ));
                }
                if !(phi.is_finite() && phi > 0.0 && phi <= 0.3) {
                    return Err(ParamError::new(
                        "system.phi0",
                        format!("must lie in (0, 0.3], got {}", show(phi)),
                    ));
                }
                (d * (n / (8.0 * phi)).cbrt(), phi)
            }
            (None, None) => {
                return Err(ParamError::new(
                    "system.radius",
                    "missing: give system.radius (the initial droplet radius, in cells) or system.phi0",
                ));
            }
        };
        if r0 < 2.0 * a {
            return Err(ParamError::new(
                "system.radius",
                format!(
                    "the initial droplet radius {} must be at least two cells ({})",
                    show(r0),
                    show(2.0 * a)
                ),
            ));
        }
        if r0 < d && s.particles > 0 {
            return Err(ParamError::new(
                "system.radius",
                format!(
                    "the initial droplet radius {} is smaller than a colloid diameter {}",
                    show(r0),
                    show(d)
                ),
            ));
        }
        let it = &self.interface;
        let stiffness = positive(
            "interface.stiffness",
            it.stiffness.unwrap_or(50.0 * kt / (d * d)),
        )?;
        let range = positive("interface.range", it.range.unwrap_or(0.5 * d))?;
        if range > r0 {
            return Err(ParamError::new(
                "interface.range",
                format!(
                    "{} is more than the initial droplet radius R0 = {r0:.4}",
                    show(range)
                ),
            ));
        }
        let offset = it.offset.unwrap_or(-0.5 * d);
        if !(offset.is_finite() && offset.abs() <= r0) {
            return Err(ParamError::new(
                "interface.offset",
                format!(
                    "must lie in [-R0, R0] = [{:.4}, {r0:.4}], got {}",
                    -r0,
                    show(offset)
                ),
            ));
        }
        let min_box = 2.0 * r0 + 4.0 * a;
        let l = match s.box_edge {
            Some(l) => {
                let l = box_edge("system.box", l, a, 2)?;
                if l < min_box {
                    return Err(ParamError::new(
                        "system.box",
                        format!(
                            "{} cannot hold the droplet: at least 2 R0 + 4 cells = {}",
                            show(l),
                            show(min_box)
                        ),
                    ));
                }
                l
            }
            None => box_edge("system.box", (min_box / a).ceil() * a, a, 2)?,
        };
        let d0 = srd.kt / (3.0 * PI * solvent.viscosity_theory * d);
        let dr = &self.drying;
        let (peclet, alpha) = dr.rate(d0)?;
        let t_end = match (dr.final_volume_fraction, dr.duration) {
            (Some(_), _) if s.particles == 0 => {
                return Err(ParamError::new(
                    "drying.final_volume_fraction",
                    "a pure-solvent droplet (system.particles = 0) has no volume fraction: give drying.duration",
                ));
            }
            (Some(_), Some(_)) => {
                return Err(ParamError::new(
                    "drying.final_volume_fraction",
                    "give either drying.final_volume_fraction or drying.duration, not both",
                ));
            }
            (_, Some(t)) => positive("drying.duration", t)?,
            (phi_f, None) => {
                if s.particles == 0 {
                    return Err(ParamError::new(
                        "drying.duration",
                        "missing: a pure-solvent droplet needs drying.duration (the time to run)",
                    ));
                }
                let phi_f = phi_f.unwrap_or(0.55);
                if !(phi_f.is_finite() && phi_f > phi0 && phi_f <= 0.64) {
                    return Err(ParamError::new(
                        "drying.final_volume_fraction",
                        format!("must lie in (phi0 = {phi0:.4}, 0.64], got {}", show(phi_f)),
                    ));
                }
                if alpha == 0.0 {
                    return Err(ParamError::new(
                        "drying.final_volume_fraction",
                        "a static droplet (drying.peclet = 0) keeps its volume fraction: give drying.duration",
                    ));
                }
                let r_end = r0 * (phi0 / phi_f).cbrt();
                (r0 * r0 - r_end * r_end) * 4.0 * PI / alpha
            }
        };
        let r_end2 = r0 * r0 - alpha * t_end / (4.0 * PI);
        if r_end2 < 4.0 * a * a {
            return Err(ParamError::new(
                "drying.duration",
                format!(
                    "the droplet would shrink below two cells (R^2 = {:.4} at t = {}): a shorter drying.duration or a smaller drying.peclet",
                    r_end2,
                    show(t_end)
                ),
            ));
        }
        let r_end = r_end2.sqrt();
        let phi_end = n * d.powi(3) / (8.0 * r_end.powi(3));
        if phi_end > 0.64 {
            return Err(ParamError::new(
                "drying.duration",
                format!(
                    "the mean volume fraction would reach {phi_end:.4} > 0.64 (random close packing)"
                ),
            ));
        }
        let collisions = (t_end / srd.tau).ceil();
        if collisions > (1u64 << 40) as f64 {
            return Err(ParamError::new(
                "drying.duration",
                format!("{collisions:e} collisions: at most 2^40"),
            ));
        }
        let collisions = (collisions as u64).max(1);
        let volume = match self.boundary.unwrap_or(Boundary::Slip) {
            Boundary::None => l.powi(3),
            _ => 4.0 / 3.0 * PI * r0.powi(3),
        };
        let solvent_particles = (srd.density / a.powi(3) * volume).round();
        if solvent_particles >= (1u64 << 31) as f64 {
            return Err(ParamError::new(
                "system.box",
                format!("{solvent_particles:e} solvent particles: at most 2^31 - 1"),
            ));
        }
        ensure_solvent_fits("system.box", solvent_particles, (l / a).powi(3))?;
        let o = &self.observe;
        let profile = o.profile.clone().unwrap_or_default();
        if !(1..=100_000).contains(&profile.bins) {
            return Err(ParamError::new(
                "observe.profile.bins",
                format!("must be an integer in [1, 100000], got {}", profile.bins),
            ));
        }
        if profile.fractions.is_empty()
            || profile.fractions.iter().any(|f| !(0.0..=1.0).contains(f))
        {
            return Err(ParamError::new(
                "observe.profile.fractions",
                "must be a non-empty list of numbers in [0, 1] (fractions of the drying time)",
            ));
        }
        let mut profile_collisions: Vec<u64> = profile
            .fractions
            .iter()
            .map(|f| (f * collisions as f64).round() as u64)
            .collect();
        profile_collisions.dedup();
        if profile_collisions.windows(2).any(|w| w[1] <= w[0]) {
            return Err(ParamError::new(
                "observe.profile.fractions",
                "must increase and name distinct collisions",
            ));
        }
        let so = o.solvent.clone().unwrap_or_default();
        let solvent_bins = so.bins.unwrap_or(20);
        if !(1..=10_000).contains(&solvent_bins) {
            return Err(ParamError::new(
                "observe.solvent.bins",
                format!("must be an integer in [1, 10000], got {solvent_bins}"),
            ));
        }
        let solvent_window = so.window.unwrap_or((collisions / 10).max(1));
        if !(1..=collisions).contains(&solvent_window) {
            return Err(ParamError::new(
                "observe.solvent.window",
                format!(
                    "must be an integer in [1, collisions = {collisions}], got {solvent_window}"
                ),
            ));
        }
        let t = &o.trajectory;
        if t.every > 0 && !t.solvent && s.particles == 0 {
            return Err(ParamError::new(
                "observe.trajectory.solvent",
                "a pure-solvent droplet has no colloids: a trajectory needs observe.trajectory.solvent = true",
            ));
        }
        Ok(DropletRun {
            seed,
            boundary: self.boundary.unwrap_or(Boundary::Slip),
            solvent,
            particles: s.particles,
            diameter: d,
            d0,
            r0,
            phi0,
            box_edge: l,
            peclet,
            alpha,
            t_end,
            r_end,
            phi_end,
            colloid,
            interface: [stiffness, range, offset],
            collisions,
            solvent_particles: solvent_particles as usize,
            profile,
            profile_collisions,
            solvent_bins,
            solvent_window,
            thermo_every: thermo_every(o.every, collisions)?,
            trajectory_every: t.every,
            trajectory_solvent: t.solvent,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn droplet(extra: &str) -> Result<DropletRun, ParamError> {
        let text = format!(
            "method = \"droplet-mpcd\"\n[system]\nradius = 6\n[drying]\nduration = 20\n{extra}"
        );
        DropletScenario::from_toml(&text).unwrap().validate()
    }

    #[test]
    fn droplet_defaults_resolve_and_bad_keys_name_themselves() {
        let r = droplet("").unwrap();
        assert_eq!(r.boundary, Boundary::Slip);
        assert_eq!(r.box_edge, 16.0);
        assert_eq!(r.collisions, 200);
        assert_eq!(
            r.solvent_particles,
            (5.0 * 4.0 / 3.0 * PI * 216.0f64).round() as usize
        );
        // Pe = R |dR/dt| / D0 = alpha / (8 pi D0).
        assert!((r.alpha / (8.0 * PI * r.d0) - 10.0).abs() < 1e-12);
        for (extra, key) in [
            ("[solvent]\nangle = 0", "solvent.angle"),
            ("[solvent]\nangle = 181", "solvent.angle"),
            ("[solvent]\ndensity = -1", "solvent.density"),
            ("[solvent]\ntau = 0", "solvent.tau"),
            ("[drying]\nduration = 1e9", "drying.duration"),
        ] {
            let text = format!("method = \"droplet-mpcd\"\n[system]\nradius = 6\n{extra}");
            let text = if extra.starts_with("[drying]") {
                text
            } else {
                format!("{text}\n[drying]\nduration = 20")
            };
            let e = DropletScenario::from_toml(&text)
                .unwrap()
                .validate()
                .unwrap_err();
            assert_eq!(e.key, key, "{extra}: {e}");
        }
        let e = DropletScenario::from_toml(
            "method = \"droplet-mpcd\"\n[system]\nradius = 6\nbox = 12\n[drying]\nduration = 20",
        )
        .unwrap()
        .validate()
        .unwrap_err();
        assert_eq!(e.key, "system.box");
        assert!(e.message.contains("cannot hold the droplet"), "{e}");
        let e = DropletScenario::from_toml(
            "method = \"droplet-mpcd\"\n[system]\nradius = 6\nbox = 16.5\n[drying]\nduration = 20",
        )
        .unwrap()
        .validate()
        .unwrap_err();
        assert!(e.message.contains("whole number of cells"), "{e}");
    }

    #[test]
    fn bulk_default_drive_gives_the_target_flow() {
        let b = BulkScenario::from_toml(
            "method = \"mpcd\"\n[system]\nbox = 16\n[run]\ncollisions = 2000\n[viscosity]\n",
        )
        .unwrap()
        .validate()
        .unwrap();
        assert!((b.expected_flow.unwrap() - DEFAULT_FLOW).abs() < 1e-12);
        assert_eq!(b.particles, 5 * 4096);
        // Six relaxation times rho / (eta k^2) of collision time 0.1.
        let k = 2.0 * PI / 16.0;
        let relax = 6.0 * 5.0 / (b.solvent.viscosity_theory * k * k) / 0.1;
        assert_eq!(b.equilibrate, relax.ceil() as u64);
        let e = BulkScenario::from_toml(
            "method = \"mpcd\"\n[system]\nbox = 16\n[run]\ncollisions = 2000\n[viscosity]\ndrive = 1",
        )
        .unwrap()
        .validate()
        .unwrap_err();
        assert_eq!(e.key, "viscosity.drive");
    }
}
