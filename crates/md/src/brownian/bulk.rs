//! Bulk Brownian dynamics in a periodic cube (`method = "bd"`): spheres of one or more species
//! (WCA or any pair interaction of [`PairSpec`]), an optional constant body force
//! (sedimentation), free draining or with the RPY mobility of the periodic box by positively
//! split Ewald (docs/bd.md).
//!
//! **Species.** Particles are stored species by species ([`Mixture`]); each has its Stokes
//! mobility `1 / (3 pi eta d_i)`, and the body force on a sphere is proportional to its volume,
//! `F_i = F (d_i / d)^3` with `d` the smallest diameter ([`BodyForce`]): spheres of one material
//! in one solvent (the same density difference), so that a free sphere sediments at
//! `U_i = mu_i F_i = F d_i^2 / (3 pi eta d^3)`, Stokes' law. With RPY the mobility is PSE for
//! unequal radii ([`Pse::with_radii`]). One species is the monodisperse run, bit for bit.
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
use super::scenario::{read_initial, species_from_file};
use super::{BdError, BdParams, Brownian, Integrator};
use crate::init::{PackingError, random_mixture_in_box};
use crate::neighbor::{BoxTooSmall, NeighborList};
use crate::potential::{External, Pair};
use crate::state::{Particles, SimBox};
use crate::tune::{SkinTuning, TunePlan, candidate_skins, lists, tune_skin};
use colloidsim_core::ParamError;
use colloidsim_core::param::show;
use colloidsim_core::trigger::log_spaced;
use colloidsim_hydro::ewald::hasimoto;
use colloidsim_hydro::{AnyMobility, HydroModel, HydroParams, Pse, PseGeometry};
use colloidsim_particles::{Interaction, Mixture, PairSpec};
use serde::Serialize;
use std::path::PathBuf;

/// The body force alone may move a particle at most this fraction of its diameter per step.
pub const MAX_BODY_DRIFT: f64 = 0.1;
/// The WCA cut-off `2^(1/6) d`, in diameters.
pub const WCA_RANGE: f64 = 1.122_462_048_309_373;

/// Candidate skins of [`BulkParams::measure_skins`], in diameters of the smallest species (the
/// best of WCA at phi 0.1, dt 1e-4 d^2 / D0 lies near 0.7-0.9: docs/performance.md).
pub const SKIN_FACTORS: [f64; 6] = [0.2, 0.35, 0.5, 0.7, 0.9, 1.2];

/// How [`BulkParams::measure_skins`] times each candidate: 50 steps to settle, then whole list
/// cycles of at least 200 steps ([`TunePlan`]), three interleaved rounds.
pub const SKIN_TUNE_PLAN: TunePlan = TunePlan {
    warmup: 50,
    steps: 200,
    rounds: 3,
};

/// Resolved, validated parameters of a bulk run.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct BulkParams {
    /// Seed (32 bits).
    pub seed: u32,
    /// Independent replicas.
    pub replicas: usize,
    /// Number of spheres N (of all species).
    pub particles: usize,
    /// Box edge L.
    pub box_length: f64,
    /// Sphere diameter d: the smallest species' (the length of the defaults).
    pub diameter: f64,
    /// The species and their numbers (absent from the resolved parameters when one).
    #[serde(skip_serializing_if = "Mixture::is_single")]
    pub species: Mixture,
    /// The pair interaction (`None`: WCA with eps = kT at each pair's mean diameter).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pair: Option<PairSpec>,
    /// Thermal energy kT.
    pub kt: f64,
    /// Solvent viscosity eta.
    pub viscosity: f64,
    /// Stokes friction `3 pi eta d` (`1 / mu0`, of the smallest species).
    pub friction: f64,
    /// Free diffusivity `D0 = kT / (3 pi eta d)` (of the smallest species).
    pub d0: f64,
    /// Diffusion time `d^2 / D0`.
    pub diffusion_time: f64,
    /// Volume fraction `sum_s N_s pi d_s^3 / (6 L^3)`.
    pub phi: f64,
    /// Body force on a sphere of diameter d (on one of diameter `d_i`: `F (d_i / d)^3`).
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
    /// Choose the skin from measured step times before the run ([`crate::tune`]).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub tune_skin: bool,
    /// The tuning that chose `skin`, once made.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skin_tuning: Option<SkinTuning>,
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

/// A constant body force proportional to each sphere's volume: `F (d_i / d_ref)^3` on a sphere
/// of diameter `d_i` (spheres of one material in one solvent: gravity less buoyancy, the same
/// density difference for every size). On spheres of the reference diameter it is exactly
/// `force` (one species: a constant force on every sphere).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyForce {
    /// The force on a sphere of the reference diameter.
    pub force: [f64; 3],
    /// The reference diameter (the smallest species').
    pub reference_diameter: f64,
}

impl BodyForce {
    /// The factor `(d / d_ref)^3` of a sphere of diameter `d` (exactly 1 at the reference).
    #[inline(always)]
    pub fn scale(&self, d: f64) -> f64 {
        if d == self.reference_diameter {
            1.0
        } else {
            (d / self.reference_diameter).powi(3)
        }
    }
}

impl External for BodyForce {
    #[inline(always)]
    fn force(&self, _: [f64; 3], _: f64) -> [f64; 3] {
        self.force
    }
    #[inline]
    fn energy(&self, p: [f64; 3], _: f64) -> f64 {
        -(self.force[0] * p[0] + self.force[1] * p[1] + self.force[2] * p[2])
    }
    #[inline(always)]
    fn force_on(&self, _: [f64; 3], _: f64, d: f64) -> [f64; 3] {
        if d == self.reference_diameter {
            return self.force;
        }
        let s = self.scale(d);
        [self.force[0] * s, self.force[1] * s, self.force[2] * s]
    }
    #[inline]
    fn energy_of(&self, p: [f64; 3], t: f64, d: f64) -> f64 {
        self.scale(d) * self.energy(p, t)
    }
}

/// The virial pressure of a configuration with pair interaction `pair` at temperature `kt`:
///
/// `P = N kT / V + (1 / 3V) sum_{i<j} r_ij . F_ij`,
///
/// the pairs within the cut-off found by a cell list over the wrapped positions (every pair
/// once, with its minimum image; Allen & Tildesley, Computer Simulation of Liquids).
/// The positions must lie in the box (e.g. [`Brownian::snapshot`]); the box must be at least
/// twice the cut-off ([`BoxTooSmall`] otherwise).
pub fn virial_pressure<P: Pair>(
    particles: &Particles,
    sbox: &SimBox,
    pair: &P,
    kt: f64,
) -> Result<f64, BoxTooSmall> {
    let n = particles.len();
    let volume = sbox.volume();
    let r_cut = pair.r_cut_max();
    let mut w = 0.0;
    if n > 1 && r_cut > 0.0 {
        let mut list = NeighborList::new(r_cut, 0.0);
        let key: Vec<u32> = (0..n as u32).collect();
        list.build(sbox, &particles.pos, &key)?;
        let (pos, t, d) = (&particles.pos, &particles.typeid, &particles.diameter);
        for i in 0..n {
            for &j in list.neighbors(i) {
                let j = j as usize;
                if j <= i {
                    continue;
                }
                let v = sbox.min_image([
                    pos[i][0] - pos[j][0],
                    pos[i][1] - pos[j][1],
                    pos[i][2] - pos[j][2],
                ]);
                let r2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                // r . F = r^2 (F / r).
                w += r2 * pair.force_over_r(r2, t[i], t[j], d[i], d[j]);
            }
        }
    }
    Ok((n as f64 * kt + w / 3.0) / volume)
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
pub type BulkSim = Brownian<Interaction, BodyForce>;
/// The engine of a bulk run with RPY (PSE).
pub type HydroBulkSim = HydroBrownian<Interaction, BodyForce, AnyMobility>;

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

    /// The pair interaction of the species ([`Self::pair`]; WCA with `epsilon = kT` at each
    /// pair's mean diameter by default).
    pub fn pair(&self) -> Result<Interaction, ParamError> {
        let d = &self.species.diameters;
        match &self.pair {
            Some(p) => p.build(d, self.kt),
            None => PairSpec::wca(self.kt, self.species.len()).build(d, self.kt),
        }
    }

    /// The body force: `body_force` on a sphere of diameter d, `(d_i / d)^3` times it on one
    /// of diameter `d_i`.
    pub fn body(&self) -> BodyForce {
        BodyForce {
            force: self.body_force,
            reference_diameter: self.diameter,
        }
    }

    /// Stokes self-mobility `mu0 = 1 / (3 pi eta d)`.
    pub fn mu0(&self) -> f64 {
        1.0 / self.friction
    }

    /// Stokes self-mobility of species `s`, `1 / (3 pi eta d_s)`.
    pub fn species_mobility(&self, s: usize) -> f64 {
        1.0 / (3.0 * std::f64::consts::PI * self.viscosity * self.species.diameters[s])
    }

    /// Free diffusivity of species `s`, `D0_s = kT / (3 pi eta d_s)`.
    pub fn species_d0(&self, s: usize) -> f64 {
        self.kt * self.species_mobility(s)
    }

    /// Magnitude of the body force on a sphere of species `s`, `F (d_s / d)^3`.
    pub fn species_force(&self, s: usize) -> f64 {
        self.force * self.body().scale(self.species.diameters[s])
    }

    /// The virial pressure of the configuration `particles` ([`virial_pressure`]).
    pub fn pressure(&self, particles: &Particles, pair: &Interaction) -> Result<f64, BoxTooSmall> {
        virial_pressure(particles, &self.sbox(), pair, self.kt)
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

    /// The radius of each species (half its diameter).
    pub fn species_radii(&self) -> Vec<f64> {
        self.species.diameters.iter().map(|d| 0.5 * d).collect()
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

    /// The initial spheres of replica `replica`: random insertion (stream index `replica`;
    /// species by species) or the last frame of `system.initial` (the same for every replica;
    /// its typeids must be the species', with their counts).
    pub fn initial_particles(&self, replica: u32) -> Result<Particles, BulkError> {
        let sbox = self.sbox();
        Ok(match &self.initial {
            None => self.species.particles(random_mixture_in_box(
                &self.species.particle_diameters(),
                &sbox,
                self.seed,
                replica as u64,
            )?),
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
                species_from_file(path, &mut p, "bulk run", &self.species)
                    .map_err(BulkError::Initial)?;
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

    /// Time the free-draining replica 0 at the candidate skins [`SKIN_FACTORS`] `x d` that fit
    /// the box ([`crate::tune`]: [`SKIN_TUNE_PLAN`], each on its own copy from step 0) and
    /// return what was measured; the caller sets `skin` and `skin_tuning` from it.
    pub fn measure_skins(&self) -> Result<SkinTuning, BulkError> {
        let r_cut = self.pair()?.r_cut_max();
        let max_range = 0.5 * self.box_length * (1.0 - 1e-9);
        let skins = candidate_skins(self.diameter, &SKIN_FACTORS, r_cut, max_range);
        tune_skin(
            &lists(&skins),
            SKIN_TUNE_PLAN,
            |c| {
                let mut p = self.clone();
                p.skin = c.skin;
                p.build_replica(0)
            },
            |sim, n| Ok(sim.run(n)?),
            |sim| sim.neighbor_builds(),
        )
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
    /// order: the whole state of [`HydroBrownian`]; each sphere keeps its diameter, PSE its
    /// radius) and integrator parameters; it continues bitwise as the run that saved them.
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
        // Equal radii: exactly `Pse::new` with that radius.
        let radii: Vec<f64> = particles.diameter.iter().map(|d| 0.5 * d).collect();
        let mobility = AnyMobility::Pse(Box::new(
            Pse::with_radii(&radii, self.pse_params(h)).map_err(HydroBdError::from)?,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::init::random_in_box;
    use crate::potential::{ConstantForce, NoExternal};
    use colloidsim_hydro::HydroMethod;
    use std::f64::consts::PI;

    /// A bulk run of `species` in a cube of edge `l` under `body_force` (free draining unless
    /// `rpy`).
    fn params(species: Mixture, l: f64, body_force: [f64; 3], rpy: bool) -> BulkParams {
        let d = species.d_min();
        let friction = 3.0 * PI * d;
        let force = body_force.iter().map(|f| f * f).sum::<f64>().sqrt();
        BulkParams {
            seed: 7,
            replicas: 1,
            particles: species.total(),
            box_length: l,
            diameter: d,
            pair: None,
            kt: 1.0,
            viscosity: 1.0,
            friction,
            d0: 1.0 / friction,
            diffusion_time: d * d * friction,
            phi: species.particle_volume() / l.powi(3),
            species,
            body_force,
            force,
            peclet: force * d,
            dt: 0.002,
            integrator: Integrator::Euler,
            skin: 0.4,
            tune_skin: false,
            skin_tuning: None,
            equilibrate_steps: 0,
            sampled_steps: 100,
            steps: 100,
            blocks: 1,
            block_steps: 100,
            msd_points: 4,
            msd_max_lag: 25,
            msd_origin_every: 3,
            trajectory_every: 0,
            initial: None,
            hydrodynamics: rpy.then_some(HydroParams {
                model: HydroModel::Rpy,
                method: Some(HydroMethod::Pse),
                tolerance: 1e-3,
                splitting: 0.5 / (0.5 * d),
                box_factor: 2.0,
                max_iterations: 100,
            }),
            pse: None,
        }
    }

    /// One species runs as the monodisperse bulk run did before species: random insertion of
    /// one size, a constant force on every sphere, `Pse::new`; bit for bit, free draining and
    /// with RPY.
    #[test]
    fn one_species_is_the_monodisperse_run_bit_for_bit() {
        let p = params(Mixture::one(1.0, 60), 8.0, [0.0, 0.5, -3.0], false);
        let start =
            || Particles::monodisperse(random_in_box(60, 1.0, &p.sbox(), 7, 0).unwrap(), 1.0);
        let mut before = Brownian::new(
            start(),
            p.sbox(),
            p.pair().unwrap(),
            ConstantForce(p.body_force),
            p.bd_params(0),
            0,
        )
        .unwrap();
        let mut now = p.build_replica(0).unwrap();
        before.run(300).unwrap();
        now.run(300).unwrap();
        assert_eq!(before.snapshot(), now.snapshot());

        let p = params(Mixture::one(1.0, 30), 8.0, [0.0, 0.0, -3.0], true);
        let h = p.hydrodynamics.clone().unwrap();
        let mut before = HydroBrownian::new(
            Particles::monodisperse(start().pos[..30].to_vec(), 1.0),
            p.sbox(),
            p.pair().unwrap(),
            ConstantForce(p.body_force),
            AnyMobility::Pse(Box::new(Pse::new(30, p.pse_params(&h)).unwrap())),
            p.hydro_bd_params(0),
            0,
        )
        .unwrap();
        let mut now = p
            .restart_hydro_replica(
                Particles::monodisperse(start().pos[..30].to_vec(), 1.0),
                p.hydro_bd_params(0),
                0,
            )
            .unwrap();
        before.run(20).unwrap();
        now.run(20).unwrap();
        assert_eq!(before.particles(), now.particles());
    }

    /// A mixture starts species by species with its typeids, names and diameters, every pair
    /// apart by at least its mean diameter; the body force on each sphere is `F (d_i / d)^3`;
    /// with RPY, PSE takes each sphere's radius.
    #[test]
    fn a_mixture_starts_with_its_species_and_pushes_by_volume() {
        let p = params(
            Mixture::new(vec![1.0, 2.0], vec![40, 10]),
            10.0,
            [0.0, 0.0, -2.0],
            false,
        );
        let x = p.initial_particles(3).unwrap();
        assert_eq!(x.typeid, p.species.typeids());
        assert_eq!(x.diameter, p.species.particle_diameters());
        assert_eq!(x.type_names, vec!["A".to_string(), "B".to_string()]);
        let sbox = p.sbox();
        for i in 0..x.len() {
            for j in 0..i {
                let v = sbox.min_image([
                    x.pos[i][0] - x.pos[j][0],
                    x.pos[i][1] - x.pos[j][1],
                    x.pos[i][2] - x.pos[j][2],
                ]);
                let r = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                assert!(r >= 0.5 * (x.diameter[i] + x.diameter[j]), "{i} {j}: {r}");
            }
        }
        let body = p.body();
        assert_eq!(body.force_on([0.0; 3], 0.0, 1.0), [0.0, 0.0, -2.0]);
        assert_eq!(body.force_on([0.0; 3], 0.0, 2.0), [0.0, 0.0, -16.0]);
        assert_eq!(p.species_force(1), 16.0);
        assert_eq!(body.energy_of([0.0, 0.0, 1.0], 0.0, 2.0), 16.0);
        // Stokes: U_B = mu_B F_B = 16 / (6 pi) = 4 U_A.
        let u = |s: usize| p.species_mobility(s) * p.species_force(s);
        assert!((u(1) / u(0) - 4.0).abs() < 1e-14);
        assert!((p.species_d0(1) - 0.5 * p.d0).abs() < 1e-16);
        let mut sim = p.build_replica(0).unwrap();
        sim.run(100).unwrap();
        let mut rpy = params(p.species.clone(), 10.0, [0.0, 0.0, -2.0], true);
        rpy.pse = None;
        let mut h = rpy.build_hydro_replica(0).unwrap();
        h.run(5).unwrap();
        assert_eq!(h.particles().diameter, p.species.particle_diameters());
    }

    /// The virial pressure: an ideal gas (no pair within range) gives `N kT / V`; two spheres
    /// at distance r across the periodic boundary add `r F(r) / (3V)`.
    #[test]
    fn the_virial_pressure_of_an_ideal_gas_and_of_one_pair() {
        let p = params(Mixture::one(1.0, 2), 8.0, [0.0; 3], false);
        let lj = PairSpec::Lj {
            epsilon: vec![1.5],
            cutoff: 2.5,
        }
        .build(&[1.0], 2.0)
        .unwrap();
        let v = 512.0;
        let mut x = Particles::monodisperse(vec![[0.0, 0.0, 0.0], [3.0, 3.0, 3.0]], 1.0);
        assert_eq!(
            virial_pressure(&x, &p.sbox(), &lj, 2.0).unwrap(),
            2.0 * 2.0 / v
        );
        // r = 1.1 through the face at x = +-4.
        x.pos = vec![[-3.95, 0.2, 0.0], [2.95, 0.2, 0.0]];
        let r: f64 = 0.55 + 0.55;
        let f = 24.0 * 1.5 * (2.0 * r.powi(-13) - r.powi(-7));
        let want = (2.0 * 2.0 + r * f / 3.0) / v;
        let got = virial_pressure(&x, &p.sbox(), &lj, 2.0).unwrap();
        assert!((got - want).abs() < 1e-14 * want.abs(), "{got} vs {want}");
        // The engine's own snapshot: the same sum.
        let sim = Brownian::new(
            x.clone(),
            p.sbox(),
            lj.clone(),
            NoExternal,
            p.bd_params(0),
            0,
        )
        .unwrap();
        let again = p.pressure(&sim.snapshot(), &lj).unwrap();
        let want = (2.0 * p.kt + r * f / 3.0) / v;
        assert!(
            (again - want).abs() < 1e-14 * want.abs(),
            "{again} vs {want}"
        );
    }
}
