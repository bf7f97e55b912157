//! Bulk Brownian dynamics in a periodic cube (`method = "bd"`): WCA spheres, an optional
//! constant body force (sedimentation), free draining or with the RPY mobility of the periodic
//! box by positively split Ewald (docs/bd.md).
//!
//! [`BulkParams`] are a bulk run's resolved parameters, plain data: the run layer reads a
//! `method = "bd"` scenario into them. The engines are those of the droplet: [`Brownian`] (free
//! draining, Euler or Leimkuhler–Matthews) and [`HydroBrownian`] with [`Pse`].
//!
//! Units: lengths in those of `system.diameter` (d), energies in those of `system.kT`, time in
//! `length^2 viscosity / energy` (as `droplet-bd`); with the defaults `d = kT = eta = 1` the
//! free diffusivity is `D0 = kT / (3 pi eta d) = 1 / (3 pi)` and the diffusion time
//! `d^2 / D0 = 9.42`.

use super::hydrodynamic::{HydroBdError, HydroBdParams, HydroBrownian};
use super::scenario::{one_species, read_initial};
use super::{BdError, BdParams, Brownian, Integrator};
use crate::init::{PackingError, random_in_box};
use crate::potential::ConstantForce;
use crate::state::{Particles, SimBox};
use colloidsim_core::ParamError;
use colloidsim_core::param::show;
use colloidsim_core::trigger::log_spaced;
use colloidsim_hydro::ewald::hasimoto;
use colloidsim_hydro::{AnyMobility, HydroModel, HydroParams, Pse, PseGeometry};
use colloidsim_particles::{Interaction, PairSpec};
use serde::Serialize;
use std::path::PathBuf;

/// The body force alone may move a particle at most this fraction of its diameter per step.
pub const MAX_BODY_DRIFT: f64 = 0.1;
/// The WCA cut-off `2^(1/6) d`, in diameters.
pub const WCA_RANGE: f64 = 1.122_462_048_309_373;

/// Resolved, validated parameters of a bulk run.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct BulkParams {
    /// Seed (32 bits).
    pub seed: u32,
    /// Independent replicas.
    pub replicas: usize,
    /// Number of spheres N.
    pub particles: usize,
    /// Box edge L.
    pub box_length: f64,
    /// Sphere diameter d.
    pub diameter: f64,
    /// The pair interaction (`None`: WCA with eps = kT at the diameter).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pair: Option<PairSpec>,
    /// Thermal energy kT.
    pub kt: f64,
    /// Solvent viscosity eta.
    pub viscosity: f64,
    /// Stokes friction `3 pi eta d` (`1 / mu0`).
    pub friction: f64,
    /// Free diffusivity `D0 = kT / (3 pi eta d)`.
    pub d0: f64,
    /// Diffusion time `d^2 / D0`.
    pub diffusion_time: f64,
    /// Volume fraction `N pi d^3 / (6 L^3)`.
    pub phi: f64,
    /// Body force on every sphere.
    pub body_force: [f64; 3],
    /// Its magnitude `F`.
    pub force: f64,
    /// Peclet number `F d / kT` (drift across a diameter against diffusion).
    pub peclet: f64,
    /// Time step.
    pub dt: f64,
    /// Integrator of the free-draining engine.
    pub integrator: Integrator,
    /// Verlet skin.
    pub skin: f64,
    /// Steps before sampling (per replica).
    pub equilibrate_steps: u64,
    /// Sampled steps per replica (`blocks * block_steps`).
    pub sampled_steps: u64,
    /// Steps per replica (`equilibrate_steps + sampled_steps`).
    pub steps: u64,
    /// Blocks per replica.
    pub blocks: usize,
    /// Steps per block.
    pub block_steps: u64,
    /// Log-spaced MSD lags asked for.
    pub msd_points: usize,
    /// Longest MSD lag (steps, at least 4).
    pub msd_max_lag: u64,
    /// Steps between MSD time origins (`max(1, msd_max_lag / 8)`).
    pub msd_origin_every: u64,
    /// GSD frame period of replica 0 (0: none).
    pub trajectory_every: u64,
    /// Initial configuration file, if any.
    pub initial: Option<PathBuf>,
    /// Hydrodynamics, when the scenario has a `[hydrodynamics]` table.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hydrodynamics: Option<HydroParams>,
    /// Grid and cut-offs of PSE (`model = "rpy"`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pse: Option<PseGeometry>,
}

/// The mean sedimentation coefficient `K = U / (mu0 F)` of a dilute suspension of `n` spheres
/// of radius `a` at volume fraction `phi` in a periodic cube of edge `l`, with pairwise RPY
/// hydrodynamics and hard-sphere exclusion:
///
/// `K = mu(L)/mu0 - 5 phi' - 8 phi' (mu(L)/mu0 - 1)`, `phi' = phi (N - 1) / N`,
///
/// with Hasimoto's self-mobility `mu(L)` ([`hasimoto`]). The self term carries the periodic
/// images; the pair sum, against the zero-mean-flow backflow of the periodic box, leaves the
/// excluded overlap region `int_{r<2a} n (A + B/3) d^3r = 5 phi` (the paper's `1 - 5 phi`),
/// and inside it the periodic tensor exceeds the free one by the images' `(mu(L) - mu0) I`,
/// which removes a further `8 phi (mu(L)/mu0 - 1)`. `phi'` counts the other spheres only.
/// Leading order in `phi` (the O(phi^2) terms are left out).
pub fn dilute_sedimentation(phi: f64, n: usize, a: f64, l: f64) -> f64 {
    let mu = hasimoto(a, l);
    let phi_n = phi * (n.saturating_sub(1)) as f64 / n.max(1) as f64;
    mu - 5.0 * phi_n - 8.0 * phi_n * (mu - 1.0)
}

/// Errors while setting up a replica (the run layer names the scenario keys).
#[derive(Debug, thiserror::Error)]
pub enum BulkError {
    /// Random insertion failed: the box is too small for the spheres.
    #[error("box_length: {0}")]
    Packing(#[from] PackingError),
    /// The initial GSD file could not be used.
    #[error("initial: {0}")]
    Initial(String),
    /// The free-draining engine refused the configuration.
    #[error(transparent)]
    Engine(#[from] BdError),
    /// The hydrodynamic engine or its mobility refused the configuration.
    #[error(transparent)]
    Hydro(#[from] HydroBdError),
    /// A parameter of the pair interaction is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
}

/// The free-draining engine of a bulk run.
pub type BulkSim = Brownian<Interaction, ConstantForce>;
/// The engine of a bulk run with RPY (PSE).
pub type HydroBulkSim = HydroBrownian<Interaction, ConstantForce, AnyMobility>;

impl BulkParams {
    /// Does a replica run with RPY ([`Self::build_hydro_replica`]) rather than free draining
    /// ([`Self::build_replica`])?
    pub fn has_hydrodynamics(&self) -> bool {
        self.hydrodynamics
            .as_ref()
            .is_some_and(|h| h.model == HydroModel::Rpy)
    }

    /// The periodic cube.
    pub fn sbox(&self) -> SimBox {
        SimBox::cube(self.box_length)
    }

    /// The pair interaction ([`Self::pair`]; WCA with `epsilon = kT`, `sigma = d` by default).
    pub fn pair(&self) -> Result<Interaction, ParamError> {
        let d = [self.diameter];
        match &self.pair {
            Some(p) => p.build(&d, self.kt),
            None => PairSpec::wca(self.kt, 1).build(&d, self.kt),
        }
    }

    /// The body force.
    pub fn body(&self) -> ConstantForce {
        ConstantForce(self.body_force)
    }

    /// Stokes self-mobility `mu0 = 1 / (3 pi eta d)`.
    pub fn mu0(&self) -> f64 {
        1.0 / self.friction
    }

    /// Hasimoto's `mu(L) / mu0` of this box ([`hasimoto`]).
    pub fn hasimoto(&self) -> f64 {
        hasimoto(0.5 * self.diameter, self.box_length)
    }

    /// The dilute sedimentation coefficient of this system ([`dilute_sedimentation`]).
    pub fn dilute_sedimentation(&self) -> f64 {
        dilute_sedimentation(
            self.phi,
            self.particles,
            0.5 * self.diameter,
            self.box_length,
        )
    }

    /// The MSD lags (steps): `msd_points` log-spaced from 1 to `msd_max_lag`, and
    /// `msd_max_lag / 4`; the diffusion coefficient is the slope between the last two
    /// ([`Self::slope_lags`]).
    pub fn msd_lags(&self) -> Vec<u64> {
        let mut v = log_spaced(1, self.msd_max_lag, self.msd_points);
        v.push(self.msd_max_lag / 4);
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The lags `(T / 4, T)` whose MSDs give the diffusion coefficient
    /// `D = [MSD(T) - MSD(T/4)] / (6 (3T/4))`: the slope at long times, without the constant
    /// offset of the short-time regime (or of the Leimkuhler–Matthews noise).
    pub fn slope_lags(&self) -> (u64, u64) {
        (self.msd_max_lag / 4, self.msd_max_lag)
    }

    /// The PSE parameters of `h` for these spheres in this box.
    pub fn pse_params(&self, h: &HydroParams) -> colloidsim_hydro::PseParams {
        h.pse_params(0.5 * self.diameter, self.viscosity, self.box_length)
    }

    /// The free-draining engine's parameters of replica `replica`.
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

    /// The initial spheres of replica `replica`: random insertion (stream index `replica`)
    /// or the last frame of `system.initial` (the same for every replica).
    pub fn initial_particles(&self, replica: u32) -> Result<Particles, BulkError> {
        let sbox = self.sbox();
        Ok(match &self.initial {
            None => Particles::monodisperse(
                random_in_box(
                    self.particles,
                    self.diameter,
                    &sbox,
                    self.seed,
                    replica as u64,
                )?,
                self.diameter,
            ),
            Some(path) => {
                let f = read_initial(path, self.particles).map_err(BulkError::Initial)?;
                let mut p = f.particles;
                let bad = |m: String| BulkError::Initial(format!("{}: {m}", path.display()));
                if f.sbox
                    .l
                    .iter()
                    .any(|e| (e / self.box_length - 1.0).abs() > 1e-6)
                {
                    return Err(bad(format!(
                        "its box {:?} is not the cube of `box_length` = {}",
                        f.sbox.l,
                        show(self.box_length)
                    )));
                }
                if let Some(i) = p.pos.iter().flatten().position(|x| !x.is_finite()) {
                    return Err(bad(format!("particle {} has a non-finite position", i / 3)));
                }
                one_species(path, &mut p, "bulk run", self.diameter).map_err(BulkError::Initial)?;
                p
            }
        })
    }

    /// Replica `replica` at step 0 with the free-draining engine.
    pub fn build_replica(&self, replica: u32) -> Result<BulkSim, BulkError> {
        Ok(Brownian::new(
            self.initial_particles(replica)?,
            self.sbox(),
            self.pair()?,
            self.body(),
            self.bd_params(replica),
            0,
        )?)
    }

    /// Replica `replica` at step 0 with RPY by PSE in the box.
    pub fn build_hydro_replica(&self, replica: u32) -> Result<HydroBulkSim, BulkError> {
        self.restart_hydro_replica(
            self.initial_particles(replica)?,
            self.hydro_bd_params(replica),
            0,
        )
    }

    /// A replica with RPY at `step` from its particles (positions and image counts, in input
    /// order: the whole state of [`HydroBrownian`]) and integrator parameters; it continues
    /// bitwise as the run that saved them.
    pub fn restart_hydro_replica(
        &self,
        particles: Particles,
        params: HydroBdParams,
        step: u64,
    ) -> Result<HydroBulkSim, BulkError> {
        let h = self
            .hydrodynamics
            .as_ref()
            .filter(|_| self.has_hydrodynamics())
            .ok_or_else(|| HydroBdError::Invalid("no RPY hydrodynamics in the scenario".into()))?;
        let mobility = AnyMobility::Pse(Box::new(
            Pse::new(particles.len(), self.pse_params(h)).map_err(HydroBdError::from)?,
        ));
        Ok(HydroBrownian::new(
            particles,
            self.sbox(),
            self.pair()?,
            self.body(),
            mobility,
            params,
            step,
        )?)
    }
}
