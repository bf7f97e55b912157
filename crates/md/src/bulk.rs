//! Bulk Brownian dynamics in a periodic cube (`method = "bd"`): WCA spheres, an optional
//! constant body force (sedimentation), free draining or with the RPY mobility of the periodic
//! box by positively split Ewald (docs/bd.md).
//!
//! [`BulkScenario`] is the typed scenario file; [`BulkScenario::validate`] resolves it into
//! [`BulkParams`] or returns a [`ParamError`] naming the key and the allowed range, before
//! anything is built. The engines are those of the droplet: [`Brownian`] (free draining, Euler
//! or Leimkuhler–Matthews) and [`HydroBrownian`] with [`Pse`].
//!
//! Units: lengths in those of `system.diameter` (d), energies in those of `system.kT`, time in
//! `length^2 viscosity / energy` (as `droplet-bd`); with the defaults `d = kT = eta = 1` the
//! free diffusivity is `D0 = kT / (3 pi eta d) = 1 / (3 pi)` and the diffusion time
//! `d^2 / D0 = 9.42`.

use crate::bd_scenario::{Spheres, one_species, read_initial, resolve_head};
use crate::brownian::{BdError, BdParams, Brownian, Integrator};
use crate::droplet::{MAX_PHI_FINAL, MAX_PHI0, TrajectorySection};
use crate::hydro_bd::{HydroBdError, HydroBdParams, HydroBrownian};
use crate::init::{PackingError, random_in_box};
use crate::potential::{ConstantForce, LennardJones};
use crate::state::{Particles, SimBox};
use colloidsim_core::ParamError;
use colloidsim_core::param::{in_range, non_negative, positive, show};
use colloidsim_core::trigger::log_spaced;
use colloidsim_hydro::ewald::hasimoto;
use colloidsim_hydro::{
    AnyMobility, HydroModel, HydroParams, HydrodynamicsSection, Pse, PseGeometry,
};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::PathBuf;

/// The body force alone may move a particle at most this fraction of its diameter per step.
pub const MAX_BODY_DRIFT: f64 = 0.1;
/// The WCA cut-off `2^(1/6) d`, in diameters.
const WCA_RANGE: f64 = 1.122_462_048_309_373;

/// A `bd` scenario file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BulkScenario {
    /// Must be `"bd"`.
    pub method: String,
    /// Seed of the counter-based random streams (0 ..= 2^32 - 1).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Independent systems run one after the other; their blocks are pooled.
    #[serde(default = "default_replicas")]
    pub replicas: usize,
    /// Particles, solvent, box, body force.
    pub system: BulkSystem,
    /// Time stepping.
    pub run: BulkRun,
    /// Observables.
    #[serde(default)]
    pub observe: BulkObserve,
    /// Hydrodynamic interactions (absent: free draining).
    #[serde(default)]
    pub hydrodynamics: Option<BulkHydrodynamics>,
}

fn default_seed() -> u64 {
    1
}
fn default_replicas() -> usize {
    1
}
fn one() -> f64 {
    1.0
}

/// `[system]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BulkSystem {
    /// Number of spheres N.
    pub particles: usize,
    /// Edge L of the periodic cube (length).
    pub box_length: f64,
    /// Sphere diameter d (length unit).
    #[serde(default = "one")]
    pub diameter: f64,
    /// Thermal energy kT (energy unit).
    #[serde(default = "one", rename = "kT")]
    pub kt: f64,
    /// Solvent viscosity eta.
    #[serde(default = "one")]
    pub viscosity: f64,
    /// Constant force on every sphere (energy / length), e.g. gravity less buoyancy.
    #[serde(default)]
    pub body_force: Option<[f64; 3]>,
    /// Start from the last frame of this GSD file instead of random insertion.
    #[serde(default)]
    pub initial: Option<PathBuf>,
}

/// `[run]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BulkRun {
    /// Sampled time per replica (time units).
    pub time: f64,
    /// Time step (default 2e-4 d^2 / D0).
    #[serde(default)]
    pub dt: Option<f64>,
    /// Time run before sampling starts (default 0).
    #[serde(default)]
    pub equilibrate: Option<f64>,
    /// Verlet skin (default 0.6 d).
    #[serde(default)]
    pub skin: Option<f64>,
    /// `"euler"` (default) or `"lm"` (free draining only).
    #[serde(default)]
    pub integrator: Option<String>,
}

/// `[observe]`.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BulkObserve {
    /// Blocks per replica of the sampled time (default 8): the errors of the mean velocity and
    /// of the diffusion coefficient come from the scatter of the block values.
    #[serde(default)]
    pub blocks: Option<usize>,
    /// Mean-square displacement.
    #[serde(default)]
    pub msd: MsdSection,
    /// GSD trajectory of replica 0.
    #[serde(default)]
    pub trajectory: TrajectorySection,
}

/// `[observe.msd]`.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MsdSection {
    /// Log-spaced lags (default 30).
    #[serde(default)]
    pub points: Option<usize>,
    /// Longest lag (time; default a quarter of a block).
    #[serde(default)]
    pub max_lag: Option<f64>,
}

/// `[hydrodynamics]` of a periodic bulk: the droplet's keys without `box_factor` (the box is
/// `system.box_length`).
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BulkHydrodynamics {
    /// `"free-draining"` (default) or `"rpy"`.
    #[serde(default)]
    pub model: Option<String>,
    /// `"pse"` (the only method of a periodic box).
    #[serde(default)]
    pub method: Option<String>,
    /// Relative tolerance, (0, 0.1].
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// PSE splitting xi (1 / length).
    #[serde(default)]
    pub splitting: Option<f64>,
    /// Lanczos iteration limit.
    #[serde(default)]
    pub max_iterations: Option<usize>,
}

impl BulkHydrodynamics {
    /// The common `[hydrodynamics]` section.
    fn section(&self) -> HydrodynamicsSection {
        HydrodynamicsSection {
            model: self.model.clone(),
            method: self.method.clone(),
            tolerance: self.tolerance,
            splitting: self.splitting,
            box_factor: None,
            max_iterations: self.max_iterations,
        }
    }
}

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

impl BulkScenario {
    /// Parse a scenario from TOML text; unknown keys are errors.
    pub fn from_toml(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }

    /// Check every key and resolve the derived parameters.
    pub fn validate(&self) -> Result<BulkParams, ParamError> {
        let (seed, replicas) = resolve_head(&self.method, "bd", self.seed, self.replicas)?;
        let s = &self.system;
        let Spheres {
            particles,
            d,
            kt,
            eta,
            friction,
            d0,
        } = Spheres::resolve(s.particles, s.diameter, s.kt, s.viscosity)?;
        let l = positive("system.box_length", s.box_length)?;
        let n = particles as f64;
        let phi = n * PI * d.powi(3) / (6.0 * l.powi(3));
        // Random insertion packs to MAX_PHI0; a configuration read from a file may be denser.
        let (max_phi, how) = if s.initial.is_some() {
            (MAX_PHI_FINAL, "random close packing")
        } else {
            (
                MAX_PHI0,
                "random insertion of hard spheres; start from a GSD file (system.initial) for more",
            )
        };
        if phi > max_phi {
            return Err(ParamError::new(
                "system.box_length",
                format!(
                    "{particles} spheres of diameter {} in a cube of edge {} give phi = {phi:.4}, \
                     above {max_phi} ({how}); the edge must be at least {:.4}",
                    show(d),
                    show(l),
                    d * (n * PI / (6.0 * max_phi)).cbrt()
                ),
            ));
        }

        let r = &self.run;
        let dt = positive("run.dt", r.dt.unwrap_or(2e-4 * d * d / d0))?;
        let time = positive("run.time", r.time)?;
        let equilibrate = non_negative("run.equilibrate", r.equilibrate.unwrap_or(0.0))?;
        let skin = in_range("run.skin", r.skin.unwrap_or(0.6 * d), 1e-3 * d, 5.0 * d)?;
        let range = WCA_RANGE * d + skin;
        if l <= 2.0 * range {
            return Err(ParamError::new(
                "system.box_length",
                format!(
                    "an edge of {} is too small for the neighbour range 2^(1/6) d + run.skin = {range:.4}: \
                     it must exceed twice that, {:.4} (or lower run.skin)",
                    show(l),
                    2.0 * range
                ),
            ));
        }
        let blocks = in_range(
            "observe.blocks",
            self.observe.blocks.unwrap_or(8) as f64,
            1.0,
            10_000.0,
        )? as usize;
        let per_block = (time / dt / blocks as f64).ceil();
        let equilibrate_steps = (equilibrate / dt).round();
        if per_block * blocks as f64 + equilibrate_steps > 1e12 {
            return Err(ParamError::new(
                "run.dt",
                format!(
                    "{:.3e} steps per replica: run.dt = {} is far too small for run.time = {} \
                     (and run.equilibrate); at most 1e12 steps",
                    per_block * blocks as f64 + equilibrate_steps,
                    show(dt),
                    show(time)
                ),
            ));
        }
        let block_steps = per_block as u64;
        if block_steps < 4 {
            return Err(ParamError::new(
                "run.time",
                format!(
                    "{} in {blocks} block(s) of run.dt = {} is {block_steps} step(s) per block; \
                     at least 4 are needed (a longer run.time, a smaller run.dt or fewer observe.blocks)",
                    show(time),
                    show(dt)
                ),
            ));
        }
        let sampled_steps = block_steps * blocks as u64;
        let equilibrate_steps = equilibrate_steps as u64;

        let body_force = s.body_force.unwrap_or([0.0; 3]);
        if let Some(k) = body_force.iter().position(|f| !f.is_finite()) {
            return Err(ParamError::new(
                "system.body_force",
                format!("component {k} is {}: must be finite", body_force[k]),
            ));
        }
        let force = body_force.iter().map(|f| f * f).sum::<f64>().sqrt();
        let drift = force * dt / friction;
        if drift > MAX_BODY_DRIFT * d {
            return Err(ParamError::new(
                "system.body_force",
                format!(
                    "a force of magnitude {} moves a sphere {} per step of run.dt = {} (F dt / (3 pi eta d)), \
                     more than {MAX_BODY_DRIFT} d: at most {:.4e} at this time step, or a smaller run.dt",
                    show(force),
                    show(drift),
                    show(dt),
                    MAX_BODY_DRIFT * d * friction / dt
                ),
            ));
        }

        let hydrodynamics = self
            .hydrodynamics
            .as_ref()
            .map(|h| h.section().validate(particles, 0.5 * d, true))
            .transpose()?;
        let rpy = hydrodynamics
            .as_ref()
            .is_some_and(|h| h.model == HydroModel::Rpy);
        let integrator = match r.integrator.as_deref() {
            Some("lm") => Integrator::Lm,
            _ => Integrator::Euler,
        }
        .check(rpy)
        .map_err(|e| ParamError::new("run.integrator", e.message))?;

        let m = &self.observe.msd;
        let msd_points = in_range(
            "observe.msd.points",
            m.points.unwrap_or(30) as f64,
            2.0,
            1000.0,
        )? as usize;
        let msd_max_lag = match m.max_lag {
            None => (block_steps / 4).max(4),
            Some(t) => {
                let t = positive("observe.msd.max_lag", t)?;
                (t / dt).round().min(1e12) as u64
            }
        };
        if msd_max_lag < 4 || msd_max_lag > block_steps {
            return Err(ParamError::new(
                "observe.msd.max_lag",
                format!(
                    "{msd_max_lag} steps: must lie in [4 run.dt, one block of the sampled time] = [{}, {}] \
                     (run.time / observe.blocks; the diffusion coefficient is the slope between a \
                     quarter of it and itself)",
                    show(4.0 * dt),
                    show(block_steps as f64 * dt)
                ),
            ));
        }
        let msd_origin_every = (msd_max_lag / 8).max(1);

        let mut p = BulkParams {
            seed,
            replicas,
            particles,
            box_length: l,
            diameter: d,
            kt,
            viscosity: eta,
            friction,
            d0,
            diffusion_time: d * d / d0,
            phi,
            body_force,
            force,
            peclet: force * d / kt,
            dt,
            integrator,
            skin,
            equilibrate_steps,
            sampled_steps,
            steps: equilibrate_steps + sampled_steps,
            blocks,
            block_steps,
            msd_points,
            msd_max_lag,
            msd_origin_every,
            trajectory_every: self.observe.trajectory.every,
            initial: s.initial.clone(),
            hydrodynamics,
            pse: None,
        };
        if let Some(h) = p.hydrodynamics.as_ref().filter(|_| rpy) {
            let key = if self
                .hydrodynamics
                .as_ref()
                .is_some_and(|h| h.splitting.is_some())
            {
                "hydrodynamics.splitting"
            } else {
                "system.box_length"
            };
            h.check_pse_extent(l, key)?;
            let g = PseGeometry::new(&p.pse_params(h)).map_err(|e| match e {
                colloidsim_hydro::HydroError::Param(e) => e,
                other => ParamError::new("hydrodynamics", other.to_string()),
            })?;
            p.pse = Some(g);
        }
        // Memory before anything is allocated: about 400 B per particle (state, lists,
        // copies), 24 B per neighbour cell, the stored MSD origins, the PSE grids and lists.
        let cells = (l / range).powi(3);
        let origins = (msd_max_lag / msd_origin_every + 2) as f64;
        let pse = p.pse.map_or(0.0, |g| g.grid_bytes() as f64 + 4.1e3 * n);
        colloidsim_core::resources::ensure_fits(
            "system.particles",
            &format!(
                "{particles} spheres in a box of {cells:.3e} neighbour cells with {origins} MSD origins"
            ),
            400.0 * n + 24.0 * cells + 24.0 * n * origins + pse,
        )?;
        Ok(p)
    }
}

/// Errors while setting up a replica.
#[derive(Debug, thiserror::Error)]
pub enum BulkError {
    /// Random insertion failed.
    #[error("system.box_length: {0}")]
    Packing(#[from] PackingError),
    /// The initial GSD file could not be used.
    #[error("system.initial: {0}")]
    Initial(String),
    /// The free-draining engine refused the configuration.
    #[error(transparent)]
    Engine(#[from] BdError),
    /// The hydrodynamic engine or its mobility refused the configuration.
    #[error(transparent)]
    Hydro(#[from] HydroBdError),
}

/// The free-draining engine of a bulk run.
pub type BulkSim = Brownian<LennardJones, ConstantForce>;
/// The engine of a bulk run with RPY (PSE).
pub type HydroBulkSim = HydroBrownian<LennardJones, ConstantForce, AnyMobility>;

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

    /// The WCA pair potential (`epsilon = kT`, `sigma = d`).
    pub fn pair(&self) -> LennardJones {
        LennardJones::wca(self.kt, self.diameter)
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

    fn pse_params(&self, h: &HydroParams) -> colloidsim_hydro::PseParams {
        h.pse_params(0.5 * self.diameter, self.viscosity, self.box_length)
    }

    /// The free-draining engine's parameters of replica `replica`.
    pub fn bd_params(&self, replica: u32) -> BdParams {
        BdParams {
            kt: self.kt,
            viscosity: self.viscosity,
            dt: self.dt,
            seed: self.seed,
            replica,
            skin: self.skin,
            sort_every: 500,
            max_drift: 0.2,
            integrator: self.integrator,
        }
    }

    /// The hydrodynamic engine's parameters of replica `replica`.
    pub fn hydro_bd_params(&self, replica: u32) -> HydroBdParams {
        HydroBdParams {
            kt: self.kt,
            dt: self.dt,
            seed: self.seed,
            replica,
            skin: self.skin,
            max_drift: 0.2,
        }
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
                        "its box {:?} is not the cube of system.box_length = {}",
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
            self.pair(),
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
            self.pair(),
            self.body(),
            mobility,
            params,
            step,
        )?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
method = "bd"
seed = 3
[system]
particles = 40
box_length = 8.87
body_force = [0.0, 0.0, -5.0]
[run]
dt = 0.005
time = 4.0
[hydrodynamics]
model = "rpy"
"#;

    fn err(text: &str) -> ParamError {
        BulkScenario::from_toml(text)
            .unwrap()
            .validate()
            .unwrap_err()
    }

    #[test]
    fn a_scenario_resolves_to_blocks_lags_and_pse() {
        let p = BulkScenario::from_toml(BASE).unwrap().validate().unwrap();
        assert!((p.phi - 40.0 * PI / 6.0 / 8.87f64.powi(3)).abs() < 1e-15);
        assert!((p.d0 - 1.0 / (3.0 * PI)).abs() < 1e-15);
        // 4.0 / 0.005 = 800 steps in 8 blocks of 100; lags up to 25 steps, origins every 3.
        assert_eq!((p.blocks, p.block_steps, p.sampled_steps), (8, 100, 800));
        assert_eq!((p.msd_max_lag, p.msd_origin_every), (25, 3));
        assert!(p.has_hydrodynamics());
        let g = p.pse.unwrap();
        assert!(g.r_cut < 0.5 * 8.87 && g.grid >= 8);
        assert!((p.peclet - 5.0).abs() < 1e-15);
        // K at phi' = 0.03 * 39/40 in this box.
        let k = p.dilute_sedimentation();
        assert!((k - 0.732).abs() < 2e-3, "K = {k}");
        assert_eq!(dilute_sedimentation(0.1, 1, 0.5, 1e9), hasimoto(0.5, 1e9));
    }

    #[test]
    fn bad_input_names_the_key() {
        for (from, to, key) in [
            ("box_length = 8.87", "box_length = 4.0", "system.box_length"),
            ("box_length = 8.87", "box_length = 3.4", "system.box_length"),
            (
                "box_length = 8.87",
                "box_length = 1e300",
                "system.box_length",
            ),
            (
                "model = \"rpy\"",
                "model = \"rpy\"\nsplitting = 1e300",
                "hydrodynamics.splitting",
            ),
            (
                "[0.0, 0.0, -5.0]",
                "[0.0, 0.0, -500.0]",
                "system.body_force",
            ),
            ("time = 4.0", "time = 0.01", "run.time"),
            ("dt = 0.005", "dt = 1e-12", "run.dt"),
            (
                "model = \"rpy\"",
                "model = \"rpy\"\nmethod = \"direct\"",
                "hydrodynamics.method",
            ),
            (
                "model = \"rpy\"",
                "model = \"rpy\"\nsplitting = 0.2",
                "hydrodynamics.splitting",
            ),
            (
                "model = \"rpy\"",
                "model = \"rpy\"\ntolerance = 0.5",
                "hydrodynamics.tolerance",
            ),
            (
                "time = 4.0",
                "time = 4.0\nintegrator = \"lm\"",
                "run.integrator",
            ),
            (
                "[run]",
                "[observe.msd]\nmax_lag = 0.001\n[run]",
                "observe.msd.max_lag",
            ),
            ("[run]", "[observe]\nblocks = 0\n[run]", "observe.blocks"),
            ("method = \"bd\"", "method = \"bulk\"", "method"),
        ] {
            assert!(BASE.contains(from), "{from}");
            let e = err(&BASE.replace(from, to));
            assert_eq!(e.key, key, "{to}: {e}");
        }
        // Direct (free space) is refused in the periodic box, with the reason.
        let e = err(&BASE.replace("model = \"rpy\"", "model = \"rpy\"\nmethod = \"direct\""));
        assert!(e.to_string().contains("periodic"), "{e}");
        // Packing: the least edge is named.
        let e = err(&BASE.replace("box_length = 8.87", "box_length = 4.0"));
        assert!(e.to_string().contains("at least"), "{e}");
        // box_factor is the droplet's.
        assert!(
            BulkScenario::from_toml(&BASE.replace("model = \"rpy\"", "box_factor = 2.0")).is_err()
        );
    }
}
