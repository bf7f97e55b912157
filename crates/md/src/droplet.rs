//! The drying-droplet scenario: hard-sphere colloids confined by a shrinking spherical harmonic
//! interface (the drying-droplet paper, docs/references.md).
//!
//! [`DropletScenario`] is the typed form of a `method = "droplet-bd"` scenario file (every key is
//! documented with its unit and default in `docs/droplet.md`); [`DropletScenario::validate`]
//! resolves it into [`DropletParams`] (initial radius, evaporation rate, free diffusivity,
//! drying time) or returns a [`ParamError`] naming the key and the allowed range. Both the
//! particle engine (`colloidsim run`) and the radial DDFT (`colloidsim theory`) read it.

use crate::bd_scenario::{Spheres, one_species, read_initial, resolve_head};
use crate::brownian::{BdError, BdParams, Brownian, Integrator};
use crate::hydro_bd::{HydroBdError, HydroBdParams, HydroBrownian};
use crate::init::random_in_sphere;
use crate::potential::{HarmonicInterface, LennardJones, SphereAreaLaw};
use crate::state::{Particles, SimBox};
use colloidsim_core::ParamError;
use colloidsim_core::param::{at_least, in_range, positive};
use colloidsim_hydro::direct::DEFAULT_MAX_DIRECT;
use colloidsim_hydro::{
    AnyMobility, DirectRpy, FreeDraining, HydroMethod, HydroModel, HydroParams,
    HydrodynamicsSection, Pse, PseGeometry, PseParams,
};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::PathBuf;

/// The interface potential must reach this many kT within a droplet radius beyond the wall
/// (a Boltzmann factor of 2e-9: no colloid leaves).
pub const HOLD_KT: f64 = 20.0;

/// Fewest steps a drying run may take.
pub const MIN_DRYING_STEPS: u64 = 100;

/// Highest initial volume fraction accepted: random insertion of hard spheres in a sphere.
pub const MAX_PHI0: f64 = 0.3;
/// Highest final mean volume fraction accepted (random close packing).
pub const MAX_PHI_FINAL: f64 = 0.64;

/// A `droplet-bd` scenario file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DropletScenario {
    /// Must be `"droplet-bd"`.
    pub method: String,
    /// Seed of the counter-based random streams (0 ..= 2^32 - 1).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Independent droplets whose profiles are averaged.
    #[serde(default = "default_replicas")]
    pub replicas: usize,
    /// Particles, solvent and initial droplet.
    pub system: SystemSection,
    /// Drying law.
    #[serde(default)]
    pub drying: DryingSection,
    /// Harmonic droplet interface.
    #[serde(default)]
    pub interface: InterfaceSection,
    /// Time stepping.
    #[serde(default)]
    pub run: RunSection,
    /// Observables.
    #[serde(default)]
    pub observe: ObserveSection,
    /// Hydrodynamic interactions (absent: free draining, the engine of [`DropletSim`]).
    #[serde(default)]
    pub hydrodynamics: Option<HydrodynamicsSection>,
}

fn default_seed() -> u64 {
    1
}
fn default_replicas() -> usize {
    1
}

/// `[system]`: particles, solvent, initial droplet.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SystemSection {
    /// Number of colloids N.
    pub particles: usize,
    /// Colloid diameter d (length unit).
    #[serde(default = "one")]
    pub diameter: f64,
    /// Thermal energy kT (energy unit).
    #[serde(default = "one", rename = "kT")]
    pub kt: f64,
    /// Solvent viscosity eta.
    #[serde(default = "one")]
    pub viscosity: f64,
    /// Initial volume fraction `phi0 = N d^3 / (8 R0^3)`; give this or `radius`.
    #[serde(default)]
    pub phi0: Option<f64>,
    /// Initial droplet radius R0; give this or `phi0`.
    #[serde(default)]
    pub radius: Option<f64>,
    /// Start from the last frame of this GSD file instead of random insertion.
    #[serde(default)]
    pub initial: Option<PathBuf>,
}

fn one() -> f64 {
    1.0
}

/// `[drying]`: `R(t) = sqrt(R0^2 - alpha t / (4 pi))`. `peclet = 0` with `duration`: a static
/// droplet (fixed R = R0), for equilibrium profiles.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DryingSection {
    /// Peclet number `Pe = R |dR/dt| / D0` (default 10; 0: a static droplet); give this or
    /// `alpha`.
    #[serde(default)]
    pub peclet: Option<f64>,
    /// Rate of loss of surface area `alpha = -dA/dt` (length^2 / time); give this or `peclet`.
    #[serde(default)]
    pub alpha: Option<f64>,
    /// Stop when the mean volume fraction `N d^3 / (8 R^3)` reaches this (default 0.55);
    /// give this or `duration`.
    #[serde(default)]
    pub final_volume_fraction: Option<f64>,
    /// Stop after this time instead (time units).
    #[serde(default)]
    pub duration: Option<f64>,
}

impl DryingSection {
    /// The Peclet number and the rate of loss of surface area `(Pe, alpha)`,
    /// `alpha = 8 pi Pe D0` (`Pe = R |dR/dt| / D0`), from `peclet` (default 10) or `alpha`.
    pub fn rate(&self, d0: f64) -> Result<(f64, f64), ParamError> {
        match (self.peclet, self.alpha) {
            (Some(_), Some(_)) => Err(ParamError::new(
                "drying.peclet",
                "give either drying.peclet or drying.alpha, not both",
            )),
            (None, Some(a)) => {
                let a = positive("drying.alpha", a)?;
                Ok((a / (8.0 * PI * d0), a))
            }
            (pe, None) => {
                let pe = pe.unwrap_or(10.0);
                if !(pe.is_finite() && pe >= 0.0) {
                    return Err(ParamError::new(
                        "drying.peclet",
                        format!(
                            "must be a finite number >= 0 (0: a static droplet), got {}",
                            colloidsim_core::param::show(pe)
                        ),
                    ));
                }
                Ok((pe, 8.0 * PI * pe * d0))
            }
        }
    }
}

/// `[interface]`: harmonic wall `V = k/2 s^2` for `0 <= s < range`, linear beyond, with
/// `s = r - (R(t) + offset)`.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InterfaceSection {
    /// Spring constant k (energy / length^2; default 50 kT / d^2).
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Range Delta of the harmonic part (length; default d / 2).
    #[serde(default)]
    pub range: Option<f64>,
    /// Offset of the wall from R(t) (length; default -d / 2: the surface touches the interface).
    #[serde(default)]
    pub offset: Option<f64>,
}

/// `[run]`: time stepping and neighbour list.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RunSection {
    /// Time step (time units; default 2e-4 d^2 / D0).
    #[serde(default)]
    pub dt: Option<f64>,
    /// Verlet skin (length; default 0.6 d).
    #[serde(default)]
    pub skin: Option<f64>,
    /// `"euler"` (Euler–Maruyama, the default) or `"lm"` (Leimkuhler–Matthews, free draining
    /// only).
    #[serde(default)]
    pub integrator: Option<String>,
}

/// `[observe]`.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ObserveSection {
    /// Radial volume-fraction profiles.
    #[serde(default)]
    pub profile: ProfileSection,
    /// GSD trajectory of the first replica.
    #[serde(default)]
    pub trajectory: TrajectorySection,
    /// Cross-section of the first replica's last frame: a slab through the centre.
    #[serde(default)]
    pub cross_section: Option<CrossSectionSection>,
}

/// `[observe.cross_section]`: the particles of replica 0's last frame whose centres lie in the
/// slab `|z| < width / 2` through the droplet's centre (`cross_section.csv`, `.png`).
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CrossSectionSection {
    /// Slab thickness (length; default d).
    #[serde(default)]
    pub width: Option<f64>,
}

/// `[observe.profile]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProfileSection {
    /// Number of radial bins between 0 and R(t).
    #[serde(default = "default_bins")]
    pub bins: usize,
    /// Fractions of the drying time at which profiles are taken.
    #[serde(default = "default_fractions")]
    pub fractions: Vec<f64>,
}

fn default_bins() -> usize {
    50
}
fn default_fractions() -> Vec<f64> {
    vec![0.0, 0.25, 0.5, 0.75, 1.0]
}

impl Default for ProfileSection {
    fn default() -> Self {
        Self {
            bins: default_bins(),
            fractions: default_fractions(),
        }
    }
}

/// `[observe.trajectory]`.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TrajectorySection {
    /// Write a GSD frame every this many steps (0: no trajectory).
    #[serde(default)]
    pub every: u64,
}

/// Resolved, validated parameters of a drying droplet.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DropletParams {
    /// Seed (32 bits).
    pub seed: u32,
    /// Independent replicas.
    pub replicas: usize,
    /// Number of colloids.
    pub particles: usize,
    /// Colloid diameter d.
    pub diameter: f64,
    /// Thermal energy kT.
    pub kt: f64,
    /// Solvent viscosity.
    pub viscosity: f64,
    /// Stokes friction `3 pi eta d`.
    pub friction: f64,
    /// Free diffusivity `D0 = kT / (3 pi eta d)`.
    pub d0: f64,
    /// Initial volume fraction.
    pub phi0: f64,
    /// Initial radius R0.
    pub r0: f64,
    /// Peclet number.
    pub peclet: f64,
    /// Rate of loss of surface area.
    pub alpha: f64,
    /// Drying time (end of the run).
    pub t_end: f64,
    /// Radius at the end.
    pub r_end: f64,
    /// Mean volume fraction at the end.
    pub phi_end: f64,
    /// Interface spring constant.
    pub stiffness: f64,
    /// Interface harmonic range.
    pub range: f64,
    /// Interface offset.
    pub offset: f64,
    /// Time step.
    pub dt: f64,
    /// Integrator of the free-draining engine ([`Integrator`]).
    pub integrator: Integrator,
    /// Number of steps `ceil(t_end / dt)`.
    pub steps: u64,
    /// Verlet skin.
    pub skin: f64,
    /// Profile bins.
    pub bins: usize,
    /// Profile fractions of the drying time.
    pub fractions: Vec<f64>,
    /// Steps at which profiles are taken (`round(fraction * steps)`).
    pub profile_steps: Vec<u64>,
    /// GSD frame period (0: none).
    pub trajectory_every: u64,
    /// Initial configuration file, if any.
    pub initial: Option<PathBuf>,
    /// Hydrodynamics, when the scenario has a `[hydrodynamics]` table (otherwise free draining
    /// by [`DropletSim`], and the key is absent from the resolved parameters).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hydrodynamics: Option<HydroParams>,
    /// Grid and cut-offs of PSE (`hydrodynamics.method = "pse"`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pse: Option<PseGeometry>,
    /// Slab thickness of the cross-section of replica 0's last frame (`observe.cross_section`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cross_section: Option<f64>,
}

impl DropletParams {
    /// Droplet radius at time `t`.
    pub fn radius_at(&self, t: f64) -> f64 {
        (self.r0 * self.r0 - self.alpha * t / (4.0 * PI))
            .max(0.0)
            .sqrt()
    }

    /// Mean volume fraction `N d^3 / (8 R^3)` at radius `r`.
    pub fn volume_fraction_at_radius(&self, r: f64) -> f64 {
        self.particles as f64 * self.diameter.powi(3) / (8.0 * r.powi(3))
    }

    /// A static droplet (`drying.peclet = 0`): the radius stays R0.
    pub fn is_static(&self) -> bool {
        self.alpha == 0.0
    }

    /// Does a replica run with a hydrodynamic mobility ([`Self::build_hydro_replica`]), rather
    /// than the free-draining engine ([`Self::build_replica`])?
    pub fn has_hydrodynamics(&self) -> bool {
        self.hydrodynamics
            .as_ref()
            .is_some_and(|h| h.model == HydroModel::Rpy)
    }
}

/// Number of particles that fill a sphere of radius `r0` to volume fraction `phi`
/// (`8 phi r0^3 / d^3`).
pub fn particles_for(phi: f64, r0: f64, d: f64) -> f64 {
    8.0 * phi * r0.powi(3) / d.powi(3)
}

impl DropletScenario {
    /// Parse a scenario from TOML text; unknown keys are errors.
    pub fn from_toml(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }

    /// Check every key and resolve the derived parameters.
    pub fn validate(&self) -> Result<DropletParams, ParamError> {
        let (seed, replicas) = resolve_head(&self.method, "droplet-bd", self.seed, self.replicas)?;
        let s = &self.system;
        let Spheres {
            particles,
            d,
            kt,
            eta,
            friction,
            d0,
        } = Spheres::resolve(s.particles, s.diameter, s.kt, s.viscosity)?;
        let n = particles as f64;
        // Random insertion packs to MAX_PHI0; a configuration read from a file may be denser.
        let max_phi0 = if s.initial.is_some() {
            MAX_PHI_FINAL
        } else {
            MAX_PHI0
        };
        let (phi0, r0) = match (s.phi0, s.radius) {
            (Some(phi), None) => {
                if !(phi.is_finite() && phi > 0.0) {
                    return Err(ParamError::new(
                        "system.phi0",
                        format!("must lie in (0, {max_phi0}], got {phi}"),
                    ));
                }
                if phi > max_phi0 {
                    return Err(ParamError::new(
                        "system.phi0",
                        format!(
                            "an initial volume fraction of {phi} cannot be packed by random insertion \
                             of hard spheres (at most {max_phi0}); start from a GSD file (system.initial) \
                             or lower phi0"
                        ),
                    ));
                }
                (phi, d * (n / (8.0 * phi)).cbrt())
            }
            (None, Some(r)) => {
                let r = positive("system.radius", r)?;
                let phi = n * d.powi(3) / (8.0 * r.powi(3));
                if phi > max_phi0 {
                    return Err(ParamError::new(
                        "system.radius",
                        format!(
                            "{particles} particles of diameter {d} in radius {r} give phi0 = {phi:.4}, \
                             which cannot be packed (at most {max_phi0}); \
                             the radius must be at least {:.4}",
                            d * (n / (8.0 * max_phi0)).cbrt()
                        ),
                    ));
                }
                (phi, r)
            }
            (Some(_), Some(_)) => {
                return Err(ParamError::new(
                    "system.phi0",
                    "give either system.phi0 or system.radius, not both",
                ));
            }
            (None, None) => {
                return Err(ParamError::new(
                    "system.phi0",
                    "missing: give system.phi0 (initial volume fraction, (0, 0.3]) or system.radius",
                ));
            }
        };
        if r0 < d {
            return Err(ParamError::new(
                "system.particles",
                format!("the initial droplet radius {r0:.4} is smaller than a diameter {d}"),
            ));
        }

        let dr = &self.drying;
        let (peclet, alpha) = dr.rate(d0)?;
        let fixed = alpha == 0.0;
        if fixed && dr.duration.is_none() {
            let key = if dr.final_volume_fraction.is_some() {
                "drying.final_volume_fraction"
            } else {
                "drying.duration"
            };
            return Err(ParamError::new(
                key,
                "a static droplet (drying.peclet = 0) keeps its volume fraction: give drying.duration \
                 (the time to run) instead of drying.final_volume_fraction",
            ));
        }
        // R(t)^2 = R0^2 - alpha t / (4 pi).
        let t_dry = 4.0 * PI * r0 * r0 / alpha; // time at which R^2 = 0
        let (t_end, r_end) = match (dr.final_volume_fraction, dr.duration) {
            (Some(_), Some(_)) => {
                return Err(ParamError::new(
                    "drying.final_volume_fraction",
                    "give either drying.final_volume_fraction or drying.duration, not both",
                ));
            }
            (None, Some(t)) => {
                let t = positive("drying.duration", t)?;
                if t >= t_dry {
                    return Err(ParamError::new(
                        "drying.duration",
                        format!(
                            "a drying time of {t} would need R^2 = {:.4} < 0 (the droplet vanishes at t = {t_dry:.6}); \
                             use a shorter duration or drying.final_volume_fraction",
                            r0 * r0 - alpha * t / (4.0 * PI)
                        ),
                    ));
                }
                (t, (r0 * r0 - alpha * t / (4.0 * PI)).sqrt())
            }
            (phi_f, None) => {
                let phi_f = phi_f.unwrap_or(0.55);
                if !(phi_f.is_finite() && phi_f > phi0 && phi_f <= MAX_PHI_FINAL) {
                    return Err(ParamError::new(
                        "drying.final_volume_fraction",
                        format!(
                            "must lie in (phi0 = {phi0:.4}, {MAX_PHI_FINAL}], got {phi_f}: \
                             the drying would end before it starts"
                        ),
                    ));
                }
                let r_end = r0 * (phi0 / phi_f).cbrt();
                ((r0 * r0 - r_end * r_end) * 4.0 * PI / alpha, r_end)
            }
        };
        let phi_end = n * d.powi(3) / (8.0 * r_end.powi(3));
        if phi_end > MAX_PHI_FINAL {
            return Err(ParamError::new(
                "drying.duration",
                format!(
                    "the mean volume fraction would reach {phi_end:.4} > {MAX_PHI_FINAL} (random close packing)"
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
                    "{} is more than the initial droplet radius R0 = {r0:.4}: the harmonic part of the interface must be thinner than the droplet",
                    colloidsim_core::param::show(range)
                ),
            ));
        }
        let offset = in_range("interface.offset", it.offset.unwrap_or(-0.5 * d), -r0, r0)?;
        // The interface must hold the colloids: V = k s^2 / 2 up to the range, then linear
        // with force k * range; the distance beyond the wall where V reaches
        // HOLD_KT kT must be smaller than the droplet (else the colloids leave it, and the
        // continuum theory's domain grows without bound).
        let hold = HOLD_KT * kt;
        let reach = if hold <= 0.5 * stiffness * range * range {
            (2.0 * hold / stiffness).sqrt()
        } else {
            range + (hold - 0.5 * stiffness * range * range) / (stiffness * range)
        };
        if reach > r0 {
            return Err(ParamError::new(
                "interface.stiffness",
                format!(
                    "{} (with interface.range = {}) does not hold the colloids: the interface \
                     potential reaches {HOLD_KT} kT only {reach:.3} beyond the wall, more than \
                     the droplet radius R0 = {r0:.4}; use at least stiffness * range = {:.3} \
                     (the default is 50 kT/d^2 with range d/2)",
                    colloidsim_core::param::show(stiffness),
                    colloidsim_core::param::show(range),
                    hold / (r0 - 0.5 * range)
                ),
            ));
        }
        if r_end + offset <= 0.0 {
            return Err(ParamError::new(
                "interface.offset",
                format!(
                    "the wall R(t) + offset would reach {:.4} <= 0",
                    r_end + offset
                ),
            ));
        }

        let dt = positive("run.dt", self.run.dt.unwrap_or(2e-4 * d * d / d0))?;
        let steps = (t_end / dt).ceil();
        if steps > 1e12 {
            return Err(ParamError::new(
                "run.dt",
                format!("{steps:e} steps: dt = {dt} is far too small for a drying time {t_end}"),
            ));
        }
        let steps = (steps as u64).max(1);
        // The drying must be resolved in time, and its last step must still have a droplet.
        if steps < MIN_DRYING_STEPS {
            return Err(ParamError::new(
                if dr.peclet.is_some() {
                    "drying.peclet"
                } else {
                    "run.dt"
                },
                format!(
                    "the droplet would dry in {steps} steps of run.dt = {dt:.3e} (at least {MIN_DRYING_STEPS} are needed to follow it); lower drying.peclet or run.dt"
                ),
            ));
        }
        // A step must not overshoot the interface's harmonic well: (D0 / kT) k dt < 1.
        let kappa = d0 / kt * stiffness * dt;
        if kappa >= 1.0 {
            return Err(ParamError::new(
                if it.stiffness.is_some() {
                    "interface.stiffness"
                } else {
                    "run.dt"
                },
                format!(
                    "an interface of stiffness {} is too stiff for run.dt = {}: D0 k dt / kT = \
                     {kappa:.3e} >= 1, so a step overshoots the interface's well; use run.dt < \
                     {:.3e} or a softer interface",
                    colloidsim_core::param::show(stiffness),
                    colloidsim_core::param::show(dt),
                    kt / (d0 * stiffness)
                ),
            ));
        }
        let r_last_sq = r0 * r0 - alpha * (steps as f64 * dt) / (4.0 * PI);
        if r_last_sq.is_nan() || r_last_sq <= 0.0 {
            return Err(ParamError::new(
                "run.dt",
                format!(
                    "the last step ends at t = {:.4e}, after the droplet has vanished (t = {t_dry:.4e}); use a smaller run.dt",
                    steps as f64 * dt
                ),
            ));
        }
        let skin = in_range(
            "run.skin",
            self.run.skin.unwrap_or(0.6 * d),
            1e-3 * d,
            5.0 * d,
        )?;

        let hydrodynamics = self
            .hydrodynamics
            .as_ref()
            .map(|h| h.validate(particles, 0.5 * d, false))
            .transpose()?;
        let integrator = Integrator::from_scenario(
            self.run.integrator.as_deref(),
            hydrodynamics
                .as_ref()
                .is_some_and(|h| h.model == HydroModel::Rpy),
        )?;

        let p = &self.observe.profile;
        let bins = at_least("observe.profile.bins", p.bins, 1)?;
        if p.fractions.is_empty() {
            return Err(ParamError::new(
                "observe.profile.fractions",
                "must list at least one fraction in [0, 1]",
            ));
        }
        for &f in &p.fractions {
            in_range("observe.profile.fractions", f, 0.0, 1.0)?;
        }
        let profile_steps = p
            .fractions
            .iter()
            .map(|f| (f * steps as f64).round() as u64)
            .collect();
        let cross_section = self
            .observe
            .cross_section
            .as_ref()
            .map(|c| {
                in_range(
                    "observe.cross_section.width",
                    c.width.unwrap_or(d),
                    1e-3 * d,
                    2.0 * r0,
                )
            })
            .transpose()?;

        let mut params = DropletParams {
            seed,
            replicas,
            particles,
            diameter: d,
            kt,
            viscosity: eta,
            friction,
            d0,
            phi0,
            r0,
            peclet,
            alpha,
            t_end,
            r_end,
            phi_end,
            stiffness,
            range,
            offset,
            dt,
            integrator,
            steps,
            skin,
            bins,
            fractions: p.fractions.clone(),
            profile_steps,
            trajectory_every: self.observe.trajectory.every,
            initial: s.initial.clone(),
            hydrodynamics,
            pse: None,
            cross_section,
        };
        // Memory before anything is allocated: about 400 B per particle (state, lists,
        // copies), 24 B per neighbour cell of the box, the profile sums.
        let cells = (params.box_edge() / (2f64.powf(1.0 / 6.0) * d + skin)).powi(3);
        let bytes =
            400.0 * particles as f64 + 24.0 * cells + 8.0 * (bins * p.fractions.len()) as f64;
        colloidsim_core::resources::ensure_fits(
            "system.particles",
            &format!("{particles} colloids in a box of {cells:.3e} neighbour cells"),
            bytes,
        )?;
        params.pse = params.check_hydrodynamics()?;
        Ok(params)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PAPER: &str = r#"
method = "droplet-bd"
seed = 3
replicas = 4
[system]
particles = 6250
phi0 = 0.05
[drying]
peclet = 10
final_volume_fraction = 0.5
"#;

    #[test]
    fn paper_case_resolves_to_r0_25_and_alpha_8_pi_pe_d0() {
        let p = DropletScenario::from_toml(PAPER)
            .unwrap()
            .validate()
            .unwrap();
        assert!((p.r0 - 25.0).abs() < 1e-12, "R0 {}", p.r0);
        let d0 = 1.0 / (3.0 * PI);
        assert!((p.d0 - d0).abs() < 1e-15);
        assert!((p.alpha - 8.0 * PI * 10.0 * d0).abs() < 1e-12);
        // Pe = R |dR/dt| / D0 = alpha / (8 pi D0) at every time.
        let t = 0.3 * p.t_end;
        let h = 1e-6 * p.t_end;
        let drdt = (p.radius_at(t + h) - p.radius_at(t - h)) / (2.0 * h);
        assert!((p.radius_at(t) * drdt.abs() / p.d0 - 10.0).abs() < 1e-5);
        assert!((p.volume_fraction_at_radius(p.radius_at(p.t_end)) - 0.5).abs() < 1e-9);
        assert_eq!(p.profile_steps.len(), 5);
        assert_eq!(*p.profile_steps.last().unwrap(), p.steps);
    }

    fn err_key(text: &str) -> String {
        match DropletScenario::from_toml(text) {
            Err(e) => format!("parse: {e}"),
            Ok(s) => s.validate().unwrap_err().key,
        }
    }

    #[test]
    fn bad_input_names_the_key() {
        // Unknown key.
        let e = err_key(&PAPER.replace("peclet = 10", "peclet = 10\nspeed = 3"));
        assert!(e.starts_with("parse") && e.contains("speed"), "{e}");
        // Cannot be packed.
        assert_eq!(
            err_key(&PAPER.replace("phi0 = 0.05", "phi0 = 0.45")),
            "system.phi0"
        );
        assert_eq!(
            err_key(&PAPER.replace("phi0 = 0.05", "radius = 10.0")),
            "system.radius"
        );
        // Ends before it starts.
        assert_eq!(
            err_key(&PAPER.replace(
                "final_volume_fraction = 0.5",
                "final_volume_fraction = 0.04"
            )),
            "drying.final_volume_fraction"
        );
        // R^2 < 0.
        assert_eq!(
            err_key(&PAPER.replace("final_volume_fraction = 0.5", "duration = 1e6")),
            "drying.duration"
        );
        assert_eq!(
            err_key(&PAPER.replace("peclet = 10", "peclet = -1")),
            "drying.peclet"
        );
        assert_eq!(
            err_key(&PAPER.replace("[drying]", "[run]\ndt = 0\n[drying]")),
            "run.dt"
        );
    }

    #[test]
    fn a_static_droplet_keeps_its_radius_and_needs_a_duration() {
        let text = PAPER.replace(
            "peclet = 10\nfinal_volume_fraction = 0.5",
            "peclet = 0\nduration = 50.0",
        );
        let p = DropletScenario::from_toml(&text)
            .unwrap()
            .validate()
            .unwrap();
        assert!(p.is_static() && p.alpha == 0.0);
        assert_eq!(p.radius_at(p.t_end), p.r0);
        assert_eq!((p.r_end, p.phi_end), (p.r0, p.phi0));
        assert_eq!(p.steps, (50.0 / p.dt).ceil() as u64);
        assert!(p.interface().radius.radius(40.0) == p.r0);
        // Pe = 0 cannot reach a final volume fraction.
        assert_eq!(
            err_key(&PAPER.replace("peclet = 10", "peclet = 0")),
            "drying.final_volume_fraction"
        );
        assert_eq!(
            err_key(&PAPER.replace("peclet = 10\nfinal_volume_fraction = 0.5", "peclet = 0")),
            "drying.duration"
        );
    }

    #[test]
    fn the_integrator_is_euler_or_lm_and_lm_is_free_draining_only() {
        let with = |run: &str, h: &str| format!("{PAPER}[run]\n{run}\n{h}");
        let integrator = |text: &str| {
            DropletScenario::from_toml(text)
                .unwrap()
                .validate()
                .map(|p| p.integrator)
        };
        assert_eq!(integrator(PAPER), Ok(Integrator::Euler));
        assert_eq!(
            integrator(&with("integrator = \"euler\"", "")),
            Ok(Integrator::Euler)
        );
        assert_eq!(
            integrator(&with("integrator = \"lm\"", "")),
            Ok(Integrator::Lm)
        );
        let free = "[hydrodynamics]\nmodel = \"free-draining\"";
        assert_eq!(
            integrator(&with("integrator = \"lm\"", free)),
            Ok(Integrator::Lm)
        );
        assert_eq!(
            err_key(&with("integrator = \"heun\"", "")),
            "run.integrator"
        );
        let rpy = "[hydrodynamics]\nmodel = \"rpy\"";
        let e = integrator(&with("integrator = \"lm\"", rpy)).unwrap_err();
        assert_eq!(e.key, "run.integrator");
        assert!(e.to_string().contains("rpy"), "{e}");
        assert!(integrator(&with("integrator = \"euler\"", rpy)).is_ok());
    }

    #[test]
    fn hydrodynamics_are_checked_against_the_droplet() {
        let with = |h: &str| format!("{PAPER}[hydrodynamics]\n{h}\n");
        let p = DropletScenario::from_toml(&with("model = \"rpy\""))
            .unwrap()
            .validate()
            .unwrap();
        // 6250 particles: PSE by default, in a box of two droplet diameters.
        let h = p.hydrodynamics.as_ref().unwrap();
        assert_eq!(h.method, Some(HydroMethod::Pse));
        assert!(p.has_hydrodynamics());
        let g = p.pse.unwrap();
        assert!((g.spacing * g.grid as f64 - 4.0 * p.r0).abs() < 1e-9);
        // Free draining named explicitly: the free-draining engine.
        let p = DropletScenario::from_toml(&with("model = \"free-draining\""))
            .unwrap()
            .validate()
            .unwrap();
        assert!(!p.has_hydrodynamics() && p.pse.is_none());
        // A box too small for the droplet, a splitting whose cut-off exceeds half the box.
        assert_eq!(
            err_key(
                &with("model = \"rpy\"\nmethod = \"pse\"\nbox_factor = 1.2").replace("6250", "300")
            ),
            "hydrodynamics.box_factor"
        );
        assert_eq!(
            err_key(&with("model = \"rpy\"\nmethod = \"pse\"\nsplitting = 0.02")),
            "hydrodynamics.splitting"
        );
        // Absurd splittings are refused before the grid is sized (this panicked in the grid
        // arithmetic: fuzz regression).
        assert_eq!(
            err_key(&with(
                "model = \"rpy\"\nmethod = \"pse\"\nsplitting = 1e300"
            )),
            "hydrodynamics.splitting"
        );
        assert_eq!(
            err_key(&with("model = \"rpy\"\ntolerance = 0.5")),
            "hydrodynamics.tolerance"
        );
        // Too many particles for the direct method: refused, suggesting PSE with its memory.
        let big = with("model = \"rpy\"\nmethod = \"direct\"").replace("6250", "30000");
        let e = DropletScenario::from_toml(&big)
            .unwrap()
            .validate()
            .unwrap_err();
        assert_eq!(e.key, "hydrodynamics.method");
        let m = e.to_string();
        assert!(
            m.contains("at most 20000") && m.contains("\"pse\"") && m.contains("GiB"),
            "{m}"
        );
    }
}

/// Errors while setting up a droplet replica.
#[derive(Debug, thiserror::Error)]
pub enum DropletError {
    /// Random insertion failed.
    #[error("system.phi0: {0}")]
    Packing(#[from] crate::init::PackingError),
    /// The initial GSD file could not be used.
    #[error("system.initial: {0}")]
    Initial(String),
    /// The engine refused the configuration.
    #[error(transparent)]
    Engine(#[from] BdError),
    /// The hydrodynamic engine or its mobility refused the configuration.
    #[error(transparent)]
    Hydro(#[from] HydroBdError),
    /// A hydrodynamics parameter does not fit the droplet.
    #[error(transparent)]
    Param(#[from] ParamError),
}

/// The engine of a droplet replica with hydrodynamics (`[hydrodynamics]`): WCA colloids inside
/// the moving harmonic interface, moved by the chosen mobility.
pub type HydroDropletSim = HydroBrownian<LennardJones, HarmonicInterface, AnyMobility>;

/// The engine a droplet replica runs: WCA colloids inside the moving harmonic interface.
pub type DropletSim = Brownian<LennardJones, HarmonicInterface>;

impl DropletParams {
    /// The droplet interface (centred on the origin).
    pub fn interface(&self) -> HarmonicInterface {
        HarmonicInterface {
            centre: [0.0; 3],
            radius: SphereAreaLaw {
                r0: self.r0,
                alpha: self.alpha,
            },
            stiffness: self.stiffness,
            range: self.range,
            offset: self.offset,
        }
    }

    /// Edge of the (periodic) simulation box: the droplet with its interface range and
    /// two neighbour ranges of margin, so that no interaction crosses the boundary.
    pub fn box_edge(&self) -> f64 {
        let reach = self.r0 + self.offset.max(0.0) + self.range;
        2.0 * (reach + 2.0 * (2f64.powf(1.0 / 6.0) * self.diameter + self.skin))
            + 2.0 * self.diameter
    }

    /// The initial particles of replica `replica`: random insertion (stream index `replica`)
    /// or the last frame of `system.initial`.
    fn initial_particles(&self, replica: u32) -> Result<Particles, DropletError> {
        Ok(match &self.initial {
            None => Particles::monodisperse(
                random_in_sphere(
                    self.particles,
                    self.diameter,
                    [0.0; 3],
                    self.r0 + self.offset,
                    self.seed,
                    replica as u64,
                )?,
                self.diameter,
            ),
            Some(path) => {
                let f = read_initial(path, self.particles).map_err(DropletError::Initial)?;
                let mut p = f.particles;
                // Unwrap with the file's box; the droplet is centred on the origin.
                for (x, img) in p.pos.iter_mut().zip(p.image.iter_mut()) {
                    *x = f.sbox.unwrap(*x, *img);
                    *img = [0; 3];
                }
                let limit = self.r0 + self.offset + self.range;
                if let Some(i) = p
                    .pos
                    .iter()
                    .position(|x| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() > limit)
                {
                    return Err(DropletError::Initial(format!(
                        "{}: particle {i} lies outside the initial droplet (|r| > R0 + offset + range = {limit:.4})",
                        path.display()
                    )));
                }
                one_species(path, &mut p, "droplet", self.diameter)
                    .map_err(DropletError::Initial)?;
                p
            }
        })
    }

    /// Set up replica `replica` (0-based) at step 0: random insertion (stream index
    /// `replica`) or the last frame of `system.initial`, noise keyed by the replica.
    pub fn build_replica(&self, replica: u32) -> Result<DropletSim, DropletError> {
        let sbox = SimBox::cube(self.box_edge());
        let particles = self.initial_particles(replica)?;
        let params = BdParams {
            kt: self.kt,
            viscosity: self.viscosity,
            dt: self.dt,
            seed: self.seed,
            replica,
            skin: self.skin,
            sort_every: 500,
            max_drift: 0.2,
            integrator: self.integrator,
        };
        Ok(Brownian::new(
            particles,
            sbox,
            LennardJones::wca(self.kt, self.diameter),
            self.interface(),
            params,
            0,
        )?)
    }
}

impl DropletParams {
    /// Edge of the simulation box with hydrodynamics: `box_factor` times the initial droplet
    /// diameter for PSE (the periodic hydrodynamic box; the paper: 2), [`Self::box_edge`]
    /// otherwise. A PSE box must hold the droplet with its interface and two neighbour ranges
    /// of margin (`hydrodynamics.box_factor`, with the least allowed value in the message).
    pub fn hydro_box_edge(&self, hydro: &HydroParams) -> Result<f64, ParamError> {
        if hydro.method != Some(HydroMethod::Pse) {
            return Ok(self.box_edge());
        }
        let l = hydro.box_factor * 2.0 * self.r0;
        let min = self.box_edge() - 2.0 * self.diameter;
        if l < min {
            return Err(ParamError::new(
                "hydrodynamics.box_factor",
                format!(
                    "a box of {} droplet diameters (edge {l:.4}) cannot hold the droplet with its interface \
                     and neighbour margins (edge {min:.4}); box_factor must be at least {:.4}",
                    hydro.box_factor,
                    min / (2.0 * self.r0)
                ),
            ));
        }
        Ok(l)
    }

    /// The PSE parameters of a periodic box of edge `l` with the settings of `hydro`.
    fn pse_params(&self, hydro: &HydroParams, l: f64) -> PseParams {
        hydro.pse_params(0.5 * self.diameter, self.viscosity, l)
    }

    /// Check that the hydrodynamics fit the droplet before anything is built: the direct
    /// method's particle limit (the error suggests PSE with the memory it would need) and, for
    /// PSE, the box ([`Self::hydro_box_edge`]) and its grid and cut-offs ([`PseGeometry`],
    /// returned).
    fn check_hydrodynamics(&self) -> Result<Option<PseGeometry>, ParamError> {
        let Some(h) = self
            .hydrodynamics
            .as_ref()
            .filter(|h| h.model == HydroModel::Rpy)
        else {
            return Ok(None);
        };
        let as_param = |e: colloidsim_hydro::HydroError| match e {
            colloidsim_hydro::HydroError::Param(p) => p,
            other => ParamError::new("hydrodynamics", other.to_string()),
        };
        match h.method {
            Some(HydroMethod::Pse) => {
                let l = self.hydro_box_edge(h)?;
                h.check_pse_extent(l, "hydrodynamics.splitting")?;
                PseGeometry::new(&self.pse_params(h, l))
                    .map(Some)
                    .map_err(as_param)
            }
            _ => {
                let n = self.particles;
                if n <= DEFAULT_MAX_DIRECT {
                    return Ok(None);
                }
                let nf = n as f64;
                let gib = |b: f64| b / (1u64 << 30) as f64;
                let pse = h.box_factor * 2.0 * self.r0;
                let alternative = PseGeometry::new(&self.pse_params(h, pse))
                    .map(|g| {
                        format!(
                            "; method = \"pse\" (a periodic box of box_factor = {} droplet diameters, \
                             O(N log N)) would need a {}^3 grid, about {:.2} GiB",
                            h.box_factor,
                            g.grid,
                            gib(g.grid_bytes() as f64 + 4.1e3 * nf)
                        )
                    })
                    .unwrap_or_else(|e| format!("; method = \"pse\" is the alternative ({e})"));
                Err(ParamError::new(
                    "hydrodynamics.method",
                    format!(
                        "\"direct\" takes at most {DEFAULT_MAX_DIRECT} particles, got {n}: each product \
                         costs N^2 = {:.2e} pair tensors (about 8 per step), and a stored 3N x 3N matrix \
                         would need {:.1} GiB{alternative}",
                        nf * nf,
                        gib(72.0 * nf * nf)
                    ),
                ))
            }
        }
    }

    /// Set up replica `replica` at step 0 with the mobility of `hydro` (free draining, RPY by
    /// direct free-space sums, or RPY by PSE in a periodic box of `box_factor` droplet
    /// diameters), noise keyed by the replica.
    pub fn build_hydro_replica(
        &self,
        replica: u32,
        hydro: &HydroParams,
    ) -> Result<HydroDropletSim, DropletError> {
        let params = HydroBdParams {
            kt: self.kt,
            dt: self.dt,
            seed: self.seed,
            replica,
            skin: self.skin,
            max_drift: 0.2,
        };
        self.restart_hydro_replica(self.initial_particles(replica)?, hydro, params, 0)
    }

    /// A replica with hydrodynamics at `step` from its particles (positions and image counts,
    /// in input order: the whole state of [`HydroBrownian`]) and integrator parameters; it
    /// continues bitwise as the run that saved them.
    pub fn restart_hydro_replica(
        &self,
        particles: Particles,
        hydro: &HydroParams,
        params: HydroBdParams,
        step: u64,
    ) -> Result<HydroDropletSim, DropletError> {
        let l = self.hydro_box_edge(hydro)?;
        let n = particles.len();
        let a = 0.5 * self.diameter;
        let mobility = match (hydro.model, hydro.method) {
            (HydroModel::FreeDraining, _) => AnyMobility::FreeDraining(
                FreeDraining::new(&vec![a; n], self.viscosity).map_err(HydroBdError::from)?,
            ),
            (HydroModel::Rpy, Some(HydroMethod::Pse)) => AnyMobility::Pse(Box::new(
                Pse::new(n, self.pse_params(hydro, l)).map_err(HydroBdError::from)?,
            )),
            (HydroModel::Rpy, _) => AnyMobility::Direct(Box::new(
                DirectRpy::new(n, a, self.viscosity, hydro.lanczos(), DEFAULT_MAX_DIRECT)
                    .map_err(HydroBdError::from)?,
            )),
        };
        Ok(HydroBrownian::new(
            particles,
            SimBox::cube(l),
            LennardJones::wca(self.kt, self.diameter),
            self.interface(),
            mobility,
            params,
            step,
        )?)
    }
}
