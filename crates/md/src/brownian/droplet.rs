//! The drying-droplet scenario: hard-sphere colloids confined by a shrinking spherical harmonic
//! interface (the drying-droplet paper, docs/references.md).
//!
//! [`DropletParams`] are a droplet's resolved parameters (initial radius, evaporation rate, free
//! diffusivity, drying time), plain data: the run layer reads a `method = "droplet-bd"`
//! scenario into them. Both the particle engine (`colloidsim run`) and the radial DDFT
//! (`colloidsim theory`) take them.

use super::hydrodynamic::{HydroBdError, HydroBdParams, HydroBrownian};
use super::scenario::{read_initial, species_from_file};
use super::{BdError, BdParams, Brownian, Integrator};
use crate::init::random_mixture_in_sphere;
use crate::potential::{HarmonicInterface, Pair, SpeciesInterface, SphereAreaLaw};
use crate::state::{Particles, SimBox};
use colloidsim_core::ParamError;
use colloidsim_hydro::direct::DEFAULT_MAX_DIRECT;
use colloidsim_hydro::{
    AnyMobility, DirectRpy, FreeDraining, HydroMethod, HydroModel, HydroParams, Pse, PseGeometry,
    PseParams,
};
use colloidsim_particles::{Interaction, Mixture, PairSpec};
use serde::Serialize;
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

/// Resolved, validated parameters of a drying droplet.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DropletParams {
    /// Seed (32 bits).
    pub seed: u32,
    /// Independent replicas.
    pub replicas: usize,
    /// Number of colloids (of all species).
    pub particles: usize,
    /// Colloid diameter d: the smallest species' (the length of the defaults).
    pub diameter: f64,
    /// The species and their numbers (absent from the resolved parameters when one).
    #[serde(skip_serializing_if = "Mixture::is_single")]
    pub species: Mixture,
    /// The pair interaction (`None`: WCA with eps = kT at each pair's mean diameter).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pair: Option<PairSpec>,
    /// Thermal energy kT.
    pub kt: f64,
    /// Solvent viscosity.
    pub viscosity: f64,
    /// Stokes friction `3 pi eta d` (of the smallest species).
    pub friction: f64,
    /// Free diffusivity `D0 = kT / (3 pi eta d)` (of the smallest species).
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
    /// A hard wall at `R(t) + offset` instead of the spring (the limit of an infinitely stiff
    /// interface; `stiffness` and `range` unused).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub hard_interface: bool,
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

    /// Mean volume fraction `sum_s N_s d_s^3 / (8 R^3)` at radius `r`.
    pub fn volume_fraction_at_radius(&self, r: f64) -> f64 {
        self.species.sum_n_d3() / (8.0 * r.powi(3))
    }

    /// The pair interaction of the species ([`Self::pair`]; WCA with eps = kT by default).
    pub fn interaction(&self) -> Result<Interaction, ParamError> {
        match &self.pair {
            Some(p) => p.build(&self.species.diameters, self.kt),
            None => {
                PairSpec::wca(self.kt, self.species.len()).build(&self.species.diameters, self.kt)
            }
        }
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

/// Errors while setting up a droplet replica (the run layer names the scenario keys).
#[derive(Debug, thiserror::Error)]
pub enum DropletError {
    /// Random insertion failed: the droplet is too dense.
    #[error("phi0: {0}")]
    Packing(#[from] crate::init::PackingError),
    /// The initial GSD file could not be used.
    #[error("initial: {0}")]
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
pub type HydroDropletSim = HydroBrownian<Interaction, SpeciesInterface, AnyMobility>;

/// The engine a droplet replica runs: colloids (WCA by default) inside the moving harmonic
/// interface.
pub type DropletSim = Brownian<Interaction, SpeciesInterface>;

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

    /// The interface as each species meets it: `offset` places it for the smallest spheres,
    /// a sphere of diameter `d` meets it `(d - d_min) / 2` further in.
    pub fn species_interface(&self) -> SpeciesInterface {
        SpeciesInterface {
            interface: self.interface(),
            reference_diameter: self.diameter,
            hard: self.hard_interface,
        }
    }

    /// The radius of each species (half its diameter).
    fn species_radii(&self) -> Vec<f64> {
        self.species.diameters.iter().map(|d| 0.5 * d).collect()
    }

    /// Edge of the (periodic) simulation box: the droplet with its interface range and
    /// two neighbour ranges of margin, so that no interaction crosses the boundary.
    pub fn box_edge(&self) -> f64 {
        let reach = self.r0 + self.offset.max(0.0) + self.range;
        let r_cut = self
            .interaction()
            .map_or(2f64.powf(1.0 / 6.0) * self.diameter, |p| p.r_cut_max());
        2.0 * (reach + 2.0 * (r_cut + self.skin)) + 2.0 * self.species.d_max()
    }

    /// The initial particles of replica `replica`: random insertion (stream index `replica`)
    /// or the last frame of `system.initial`.
    fn initial_particles(&self, replica: u32) -> Result<Particles, DropletError> {
        Ok(match &self.initial {
            None => self.species.particles(random_mixture_in_sphere(
                &self.species.particle_diameters(),
                [0.0; 3],
                self.r0 + self.offset,
                self.seed,
                replica as u64,
            )?),
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
                species_from_file(path, &mut p, "droplet", &self.species)
                    .map_err(DropletError::Initial)?;
                p
            }
        })
    }

    /// The free-draining engine's parameters of replica `replica` (a fresh start and a
    /// restart take them from here alike).
    pub fn bd_params(&self, replica: u32) -> BdParams {
        super::scenario::free_draining(
            self.kt,
            self.viscosity,
            self.dt,
            self.seed,
            replica,
            self.skin,
            self.integrator,
        )
    }

    /// The hydrodynamic engine's parameters of replica `replica`.
    pub fn hydro_bd_params(&self, replica: u32) -> HydroBdParams {
        super::scenario::hydrodynamic(self.kt, self.dt, self.seed, replica, self.skin)
    }

    /// Set up replica `replica` (0-based) at step 0: random insertion (stream index
    /// `replica`) or the last frame of `system.initial`, noise keyed by the replica.
    pub fn build_replica(&self, replica: u32) -> Result<DropletSim, DropletError> {
        let sbox = SimBox::cube(self.box_edge());
        let particles = self.initial_particles(replica)?;
        Ok(Brownian::new(
            particles,
            sbox,
            self.interaction()?,
            self.species_interface(),
            self.bd_params(replica),
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
        let min = self.box_edge() - 2.0 * self.species.d_max();
        if l < min {
            return Err(ParamError::new(
                "box_factor",
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
    pub fn check_hydrodynamics(&self) -> Result<Option<PseGeometry>, ParamError> {
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
                h.check_pse_extent(l, "splitting")?;
                PseGeometry::with_radii(&self.pse_params(h, l), &self.species_radii())
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
                    "method",
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
        self.restart_hydro_replica(
            self.initial_particles(replica)?,
            hydro,
            self.hydro_bd_params(replica),
            0,
        )
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
        let radii: Vec<f64> = particles.diameter.iter().map(|d| 0.5 * d).collect();
        let mobility = match (hydro.model, hydro.method) {
            (HydroModel::FreeDraining, _) => AnyMobility::FreeDraining(
                FreeDraining::new(&radii, self.viscosity).map_err(HydroBdError::from)?,
            ),
            (HydroModel::Rpy, Some(HydroMethod::Pse)) => AnyMobility::Pse(Box::new(
                Pse::with_radii(&radii, self.pse_params(hydro, l)).map_err(HydroBdError::from)?,
            )),
            (HydroModel::Rpy, _) => AnyMobility::Direct(Box::new(
                DirectRpy::with_radii(&radii, self.viscosity, hydro.lanczos(), DEFAULT_MAX_DIRECT)
                    .map_err(HydroBdError::from)?,
            )),
        };
        Ok(HydroBrownian::new(
            particles,
            SimBox::cube(l),
            self.interaction()?,
            self.species_interface(),
            mobility,
            params,
            step,
        )?)
    }
}
