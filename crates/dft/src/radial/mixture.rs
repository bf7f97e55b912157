//! Fundamental-measure DDFT of a hard-sphere mixture (any number of species) in a drying droplet.
//!
//! - [`fmt`]: [`MixtureFmt`], the Rosenfeld or White Bear (mark I) functional of a mixture on the
//!   radial grid (weighted densities summed over species, each with its own radius).
//! - [`bulk`]: the equations of state they imply (Percus–Yevick / scaled-particle and BMCSL).
//! - [`equilibrium`]: equilibrium at fixed numbers of each species.
//! - [`ddft`]: [`MixtureDdft`], free-draining fluxes per species (`D0_s`) or plus the pairwise
//!   RPY flux of [`rpy`] (unequal-radius RPY tensor, dilute `g_ij = Theta(r - (d_i + d_j)/2)`
//!   or Trokhymchuk's one-size `g` scaled to each pair's BMCSL contact value).
//!
//! Each species feels its own harmonic interface ([`Species::interface`]; the one-size droplet
//! puts the wall at `R + offset` with `offset = -d/2`, so the colloid surface sits at `R`: give
//! each species `offset = -d_s/2` for the same convention), the drying schedule `R(t)` is the
//! one-size [`DryingSchedule`]. One species reproduces [`crate::radial::run_droplet`] to rounding
//! (tested).
//!
//! Engine entry: [`run_mixture_droplet`] (equilibrium at `R0`, then DDFT, a
//! [`MixtureSnapshot`] per output time with each species' `rho_s(r)`, `phi_s(r) = pi d_s^3 rho_s / 6`,
//! its share of the weighted `n3`, and its mean radius).
//!
//! ```no_run
//! use colloidsim_dft::radial::*;
//! use colloidsim_dft::radial::mixture::*;
//! // Size ratio 2, kT = 1, viscosity 1/(3 pi) (D0 = 1 for d = 1), R0 = 20, Pe_s = 10.
//! let (kt, eta) = (1.0, 1.0 / (3.0 * std::f64::consts::PI));
//! let small = Species::stokes(1.0, 2000.0, kt, eta, HarmonicInterface::new(50.0, 0.5, -0.5)?)?;
//! let large = Species::stokes(2.0, 250.0, kt, eta, HarmonicInterface::new(50.0, 0.5, -1.0)?)?;
//! let schedule = DryingSchedule::from_peclet(20.0, 10.0, small.d0)?;
//! let setup = MixtureSetup {
//!     species: vec![small, large],
//!     r0: 20.0,
//!     alpha: schedule.alpha,
//!     t_end: schedule.time_at_radius(20.0 * 0.2f64.cbrt()),
//!     dr: 0.05,
//!     functional: Functional::WhiteBear,
//!     hydrodynamics: Hydrodynamics::FreeDraining,
//!     pair: PairCorrelation::Dilute,
//! };
//! let times = [0.5 * setup.t_end, setup.t_end];
//! run_mixture_droplet(&setup, &times, &setup.ddft_options(), &EquilibriumOptions::default(),
//!     |_grid, snap| println!("t = {}: <r>_s = {:?}", snap.time, snap.mean_radius),
//!     |_step| {})?;
//! # Ok::<(), RadialError>(())
//! ```

pub mod bulk;
pub mod ddft;
pub mod equilibrium;
pub mod fmt;
pub mod rpy;

pub use ddft::MixtureDdft;
pub use equilibrium::{MixtureEquilibrium, solve_mixture_equilibrium};
pub use fmt::{Functional, MixtureFmt};
pub use rpy::MixtureRpy;

use std::f64::consts::PI;

use colloidsim_core::{ParamError, param};

use super::droplet::CLOSE_PACKING;
use super::{
    DdftOptions, DryingSchedule, EquilibriumOptions, HarmonicInterface, Hydrodynamics,
    PairCorrelation, RadialError, RadialGrid, StepReport,
};

/// One species of a mixture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Species {
    /// Diameter `d_s` (length).
    pub diameter: f64,
    /// Number of particles `N_s` (need not be an integer).
    pub particles: f64,
    /// Bare diffusion coefficient `D0_s` (Stokes: `kT / (3 pi eta d_s)`).
    pub d0: f64,
    /// The interface this species feels (`stiffness` in kT / length^2).
    pub interface: HarmonicInterface,
}

impl Species {
    /// A species with Stokes' `D0 = kT / (3 pi eta d)` (errors name `diameter`, `particles`,
    /// `kT`, `viscosity`).
    pub fn stokes(
        diameter: f64,
        particles: f64,
        kt: f64,
        viscosity: f64,
        interface: HarmonicInterface,
    ) -> Result<Self, RadialError> {
        param::positive("diameter", diameter)?;
        param::positive("particles", particles)?;
        param::positive("kT", kt)?;
        param::positive("viscosity", viscosity)?;
        Ok(Self {
            diameter,
            particles,
            d0: kt / (3.0 * PI * viscosity * diameter),
            interface,
        })
    }
}

/// A drying droplet of a hard-sphere mixture (energies in kT).
#[derive(Debug, Clone, PartialEq)]
pub struct MixtureSetup {
    /// The species (at least one).
    pub species: Vec<Species>,
    /// Initial radius `R0`.
    pub r0: f64,
    /// Rate of loss of surface area (0: static droplet); `DryingSchedule::from_peclet` gives it
    /// from a Péclet number of a chosen species.
    pub alpha: f64,
    /// End time.
    pub t_end: f64,
    /// Grid spacing (at most the smallest diameter / 10).
    pub dr: f64,
    /// Rosenfeld or White Bear.
    pub functional: Functional,
    /// Free draining, or plus the pairwise RPY flux (needs Stokes `D0_s`, one viscosity).
    pub hydrodynamics: Hydrodynamics,
    /// Pair correlations of the RPY flux ([`rpy`]; unused when free-draining).
    pub pair: PairCorrelation,
}

/// Mean volume fraction `sum_s N_s d_s^3 / (8 R^3)` of `species` in a sphere of `radius`.
pub fn mixture_volume_fraction(species: &[Species], radius: f64) -> f64 {
    species
        .iter()
        .map(|s| s.particles * s.diameter.powi(3))
        .sum::<f64>()
        / (8.0 * radius.powi(3))
}

impl MixtureSetup {
    /// Check the setup; errors name the parameter (`species`, `species[s].diameter`,
    /// `species[s].particles`, `species[s].d0`, `species[s].interface.stiffness|range|offset`,
    /// `r0`, `alpha`, `t_end`, `dr`, `particles` for an initial packing beyond close packing,
    /// `final_volume_fraction` for the end). RPY needs `D0_s d_s` equal (naming `species[s].d0`).
    pub fn validate(&self) -> Result<DryingSchedule, RadialError> {
        if self.species.is_empty() {
            return Err(ParamError::new("species", "at least one species is needed").into());
        }
        for (s, sp) in self.species.iter().enumerate() {
            param::positive(&format!("species[{s}].diameter"), sp.diameter)?;
            param::positive(&format!("species[{s}].particles"), sp.particles)?;
            param::positive(&format!("species[{s}].d0"), sp.d0)?;
            param::positive(
                &format!("species[{s}].interface.stiffness"),
                sp.interface.stiffness,
            )?;
            param::positive(&format!("species[{s}].interface.range"), sp.interface.range)?;
            param::finite(
                &format!("species[{s}].interface.offset"),
                sp.interface.offset,
            )?;
            if sp.diameter / self.dr < super::fmt::MIN_CELLS_PER_DIAMETER {
                return Err(ParamError::new(
                    "dr",
                    format!(
                        "grid spacing {} does not resolve species {s}: need dr <= diameter / {} = {}",
                        self.dr,
                        super::fmt::MIN_CELLS_PER_DIAMETER,
                        sp.diameter / super::fmt::MIN_CELLS_PER_DIAMETER
                    ),
                )
                .into());
            }
        }
        param::positive("dr", self.dr)?;
        param::non_negative("t_end", self.t_end)?;
        if self.hydrodynamics == Hydrodynamics::Rpy {
            let d: Vec<f64> = self.species.iter().map(|s| s.diameter).collect();
            let d0: Vec<f64> = self.species.iter().map(|s| s.d0).collect();
            ddft::check_stokes(&d, &d0, |s| format!("species[{s}].d0"))?;
        }
        let schedule = DryingSchedule::new(self.r0, self.alpha)?;
        let phi0 = mixture_volume_fraction(&self.species, self.r0);
        if phi0 > CLOSE_PACKING {
            return Err(ParamError::new(
                "particles",
                format!("initial mean volume fraction {phi0:.4} of all species is beyond close packing ({CLOSE_PACKING})"),
            )
            .into());
        }
        if self.t_end >= schedule.collapse_time() {
            return Err(ParamError::new(
                "t_end",
                format!(
                    "the drying schedule passes R = 0 at t = {:.6} before the end t = {}",
                    schedule.collapse_time(),
                    self.t_end
                ),
            )
            .into());
        }
        let r_end = schedule.radius(self.t_end)?;
        let phi_end = mixture_volume_fraction(&self.species, r_end);
        if phi_end > CLOSE_PACKING * 1.01 {
            return Err(ParamError::new(
                "final_volume_fraction",
                format!(
                    "the mean volume fraction reaches {phi_end:.4} at the end (R = {r_end:.4}), beyond close packing ({CLOSE_PACKING})"
                ),
            )
            .into());
        }
        for (s, sp) in self.species.iter().enumerate() {
            if r_end + sp.interface.offset < 0.5 * sp.diameter {
                return Err(ParamError::new(
                    "t_end",
                    format!(
                        "the droplet (R = {r_end:.4}) becomes smaller than one particle of species {s}"
                    ),
                )
                .into());
            }
        }
        Ok(schedule)
    }

    /// Species diameters.
    pub fn diameters(&self) -> Vec<f64> {
        self.species.iter().map(|s| s.diameter).collect()
    }

    /// Grid from 0 to where every species' interface potential at `R0` reaches `cutoff` kT,
    /// plus the largest diameter.
    pub fn grid(&self, cutoff: f64) -> Result<RadialGrid, RadialError> {
        let dmax = self.species.iter().map(|s| s.diameter).fold(0.0, f64::max);
        let edge = self
            .species
            .iter()
            .map(|s| self.r0 + s.interface.offset + s.interface.reach(cutoff))
            .fold(0.0, f64::max)
            + dmax;
        RadialGrid::covering(self.dr, edge)
    }

    /// Default solver settings, scaled by the fastest species' time `d_s^2 / D0_s`.
    pub fn ddft_options(&self) -> DdftOptions {
        let fastest = self
            .species
            .iter()
            .min_by(|a, b| {
                (a.diameter * a.diameter / a.d0).total_cmp(&(b.diameter * b.diameter / b.d0))
            })
            .copied()
            .unwrap_or(Species {
                diameter: 1.0,
                particles: 1.0,
                d0: 1.0,
                interface: HarmonicInterface {
                    stiffness: 1.0,
                    range: 1.0,
                    offset: 0.0,
                },
            });
        let mut o = DdftOptions::new(fastest.d0, fastest.diameter);
        o.hydrodynamics = self.hydrodynamics;
        o.pair = self.pair;
        o
    }

    /// Every species' interface potential at radius `radius`, species after species.
    fn potentials(&self, grid: &RadialGrid, radius: f64) -> Vec<f64> {
        let n = grid.len();
        let mut v = vec![0.0; n * self.species.len()];
        for (s, sp) in self.species.iter().enumerate() {
            sp.interface
                .fill(grid.centres(), radius, &mut v[s * n..(s + 1) * n]);
        }
        v
    }
}

/// Densities of a mixture at one output time.
#[derive(Debug, Clone, PartialEq)]
pub struct MixtureSnapshot {
    /// Time.
    pub time: f64,
    /// Droplet radius `R(t)`.
    pub radius: f64,
    /// Number density `rho_s(r)` of each species at the cell centres.
    pub rho: Vec<Vec<f64>>,
    /// Volume fraction of each species' centres, `phi_s(r) = pi d_s^3 rho_s(r) / 6` (the
    /// quantity a particle run's centre histogram measures, as `phi` of the one-size theory).
    pub phi: Vec<Vec<f64>>,
    /// Each species' share `n3_s` of the FMT weighted packing fraction (its density averaged
    /// over a particle's volume; `sum_s n3_species[s] = n3`).
    pub n3_species: Vec<Vec<f64>>,
    /// Total local packing fraction `n3`.
    pub n3: Vec<f64>,
    /// Mean distance from the centre of each species, `int r rho_s dV / N_s`.
    pub mean_radius: Vec<f64>,
}

impl MixtureSnapshot {
    /// Number of particles of species `s` whose centres lie beyond `r` (cells piecewise
    /// constant, the cell containing `r` counted by its overlap): with `r = radius - w` the
    /// outer-shell composition the stratification measures use.
    pub fn particles_beyond(&self, grid: &RadialGrid, s: usize, r: f64) -> f64 {
        let faces = grid.faces();
        (0..grid.len())
            .filter(|&i| faces[i + 1] > r)
            .map(|i| {
                let lo = faces[i].max(r);
                4.0 * PI / 3.0 * (faces[i + 1].powi(3) - lo.powi(3)) * self.rho[s][i]
            })
            .sum()
    }
}

/// Summary of a mixture run.
#[derive(Debug, Clone, PartialEq)]
pub struct MixtureOutcome {
    /// Iterations of the initial equilibrium.
    pub equilibrium_iterations: usize,
    /// Its residual.
    pub equilibrium_residual: f64,
    /// Accepted DDFT steps.
    pub steps: usize,
    /// Fixed-point iterations of all steps.
    pub iterations: usize,
    /// Particle number of each species at the start.
    pub particles_initial: Vec<f64>,
    /// Largest relative change of each species' number seen at the output times.
    pub particle_drift: Vec<f64>,
    /// Grid cells.
    pub cells: usize,
}

/// Equilibrium of `setup`'s numbers of each species in a static droplet of radius `radius`
/// (grid to `beta V = 100 kT`); `setup` is validated as a static droplet.
pub fn mixture_equilibrium_at(
    setup: &MixtureSetup,
    radius: f64,
    eq_opts: &EquilibriumOptions,
) -> Result<(RadialGrid, MixtureEquilibrium), RadialError> {
    let s = MixtureSetup {
        r0: radius,
        alpha: 0.0,
        t_end: 0.0,
        ..setup.clone()
    };
    s.validate()?;
    let grid = s.grid(100.0)?;
    let mut fmt = MixtureFmt::new(&grid, &s.diameters(), s.functional)?;
    let v = s.potentials(&grid, radius);
    let n: Vec<f64> = s.species.iter().map(|x| x.particles).collect();
    let eq = solve_mixture_equilibrium(&grid, &mut fmt, &v, &n, None, eq_opts)?;
    Ok((grid, eq))
}

/// Equilibrium at `R0` (fixed `N_s`), then DDFT to each of `times` (ascending within
/// `[0, t_end]`); `on_snapshot` receives every output, `on_step` every accepted step. `opts`:
/// see [`MixtureSetup::ddft_options`] (its `d0`, `hydrodynamics` and `pair` are taken from the
/// setup: `D0_s` per species; `pair_table` from `opts`).
///
/// Stops with [`RadialError::Unphysical`] (ejection, negative density) or
/// [`RadialError::NotConverged`] after the snapshots reached so far.
pub fn run_mixture_droplet(
    setup: &MixtureSetup,
    times: &[f64],
    opts: &DdftOptions,
    eq_opts: &EquilibriumOptions,
    mut on_snapshot: impl FnMut(&RadialGrid, &MixtureSnapshot),
    mut on_step: impl FnMut(&StepReport),
) -> Result<MixtureOutcome, RadialError> {
    let schedule = setup.validate()?;
    if times
        .iter()
        .any(|t| !(t.is_finite() && *t >= 0.0 && *t <= setup.t_end * (1.0 + 1e-12)))
        || times.windows(2).any(|w| w[1] < w[0])
    {
        return Err(ParamError::new(
            "times",
            format!("output times must ascend within [0, {}]", setup.t_end),
        )
        .into());
    }
    let grid = setup.grid(opts.potential_cutoff)?;
    let diameters = setup.diameters();
    let mut fmt = MixtureFmt::new(&grid, &diameters, setup.functional)?;
    let v = setup.potentials(&grid, setup.r0);
    let numbers: Vec<f64> = setup.species.iter().map(|s| s.particles).collect();
    let eq = solve_mixture_equilibrium(&grid, &mut fmt, &v, &numbers, None, eq_opts)?;
    let mut o = *opts;
    o.hydrodynamics = setup.hydrodynamics;
    o.pair = setup.pair;
    let d0: Vec<f64> = setup.species.iter().map(|s| s.d0).collect();
    let walls: Vec<HarmonicInterface> = setup.species.iter().map(|s| s.interface).collect();
    let mut ddft = MixtureDdft::new(grid.clone(), fmt, &d0, &walls, schedule, &eq.rho, o)?;
    let n0 = ddft.initial_particles().to_vec();
    let ns = setup.species.len();
    let n = grid.len();
    let mut drift = vec![0.0f64; ns];
    for &t in times {
        ddft.advance_to(t.min(setup.t_end), &mut on_step)?;
        let radius = schedule.radius(ddft.time())?;
        let time = ddft.time();
        let rho: Vec<Vec<f64>> = (0..ns).map(|s| ddft.rho_of(s).to_vec()).collect();
        let f = ddft.functional_now()?;
        let n3_species: Vec<Vec<f64>> = (0..ns).map(|s| f.n3_of(s).to_vec()).collect();
        let phi: Vec<Vec<f64>> = (0..ns)
            .map(|s| {
                let c = PI * diameters[s].powi(3) / 6.0;
                rho[s].iter().map(|r| c * r).collect()
            })
            .collect();
        let n3 = f.n3().to_vec();
        let mut mean_radius = vec![0.0; ns];
        for s in 0..ns {
            let num = grid.integrate(&rho[s]);
            drift[s] = drift[s].max((num / n0[s] - 1.0).abs());
            let first: f64 = (0..n)
                .map(|i| grid.volumes()[i] * grid.centres()[i] * rho[s][i])
                .sum();
            mean_radius[s] = first / num;
        }
        on_snapshot(
            &grid,
            &MixtureSnapshot {
                time,
                radius,
                rho,
                phi,
                n3_species,
                n3,
                mean_radius,
            },
        );
    }
    Ok(MixtureOutcome {
        equilibrium_iterations: eq.iterations,
        equilibrium_residual: eq.residual,
        steps: ddft.steps(),
        iterations: ddft.iterations(),
        particles_initial: n0,
        particle_drift: drift,
        cells: n,
    })
}
