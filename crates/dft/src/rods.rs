//! Exact 1D equilibrium theory of hard rods (Percus) and sticky rods (Baxter), and 1D DDFT.
//!
//! - [`equilibrium()`]: solves the structure equation `delta Omega / delta rho = 0` at fixed mean
//!   density directly (Picard + Anderson mixing, grid sequencing, O(M) window integrals);
//!   paper `bcd-hard-rods-sticky.md` Eqs. (21)–(24) (hard) and (35a)–(35c) (sticky).
//! - [`ddft()`]: `d rho / dt = d/dx [D rho d/dx (delta beta F / delta rho + beta U) - D beta f rho]`
//!   by finite volumes with Scharfetter–Gummel fluxes (particle number conserved to rounding;
//!   stabilised linearly implicit steps).
//! - [`bulk`]: exact homogeneous results (Tonks gas, Baxter sticky rods) for checks.
//!
//! Units: lengths in the scenario's length unit, energies in kT (the potential is passed as
//! `beta U`), time in the unit of `length^2 / D`. Equations and numerics: `docs/theory-rods.md`.

pub mod bulk;
pub mod ddft;
pub mod equilibrium;
mod functional;
mod grid;

pub use ddft::{
    DdftFrame, DdftProblem, DdftSummary, InitialProfile, ddft, ideal_washboard_current,
};
pub use equilibrium::{BinnedProfile, Equilibrium, EquilibriumSummary, equilibrium};

use colloidsim_core::param::{self, ParamError};
use std::fmt;
use std::sync::Arc;
use thiserror::Error;

/// Errors of the rods theory.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum RodsError {
    /// A parameter outside its allowed range (the message names it and the range).
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The solver stopped before the residual reached the tolerance.
    #[error(
        "rods equilibrium did not converge: residual {residual:.3e} (max-norm of the structure \
         equation in ln rho form) after {iterations} iterations, tolerance {tolerance:.1e}{}",
        jam_hint(*min_vacancy)
    )]
    NotConverged {
        /// Iterations done on the finest grid (both attempts: the default one and the retry with a
        /// longer Anderson history).
        iterations: usize,
        /// Residual reached.
        residual: f64,
        /// Tolerance asked for.
        tolerance: f64,
        /// Smallest `1 - eta(x + sigma)` of the last iterate (probability that a window of length
        /// sigma holds no rod centre); near 0 the state is nearly jammed.
        min_vacancy: f64,
    },
    /// The DDFT time step was too large (a window `int rho` reached close packing).
    #[error("ddft: {0}")]
    Ddft(String),
}

fn jam_hint(min_vacancy: f64) -> String {
    if min_vacancy > 0.0 && min_vacancy < 1e-6 {
        format!(
            ". The state is nearly jammed (min 1 - eta = {min_vacancy:.1e}): rounding limits the \
             residual to about 1e-16 / min(1 - eta); lower the density or the potential amplitude"
        )
    } else {
        "; a coarser grid (colloidsim theory --dx) converges faster".into()
    }
}

/// Rod–rod interaction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RodInteraction {
    /// Hard rods of length `sigma` (Percus functional, Eq. 21a).
    Hard,
    /// Baxter sticky rods, `exp(-beta V(r)) = Theta(r - sigma) + gamma delta(r - sigma)` (Eq. 30),
    /// in the exact `epsilon -> 0` limit (structure equation Eqs. 35a–35c). `gamma >= 0` is a
    /// length; `gamma = 0` is the hard rod.
    Sticky {
        /// Stickiness `gamma` (length unit).
        gamma: f64,
    },
}

impl RodInteraction {
    /// Stickiness `gamma` (0 for hard rods).
    pub fn gamma(&self) -> f64 {
        match self {
            Self::Hard => 0.0,
            Self::Sticky { gamma } => *gamma,
        }
    }
}

/// Geometry of the 1D system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Domain {
    /// Periodic: the solution on one period `[0, period)` of the potential (an infinite or ring
    /// system whose length is a multiple of the period).
    Periodic {
        /// Period of the potential (and of the density).
        period: f64,
    },
    /// Hard walls at 0 and `length`: rod centres in `[sigma/2, length - sigma/2]`.
    Walls {
        /// Distance between the walls.
        length: f64,
    },
}

/// The external potential in units of kT, `beta U(x)`.
#[derive(Clone)]
pub enum BetaPotential {
    /// No potential.
    Zero,
    /// A function of position (evaluated on the grid, also on the coarse grids).
    Function(Arc<dyn Fn(f64) -> f64 + Send + Sync>),
    /// Values on the solver grid ([`RodsProblem::grid_points`]); disables grid sequencing.
    OnGrid(Vec<f64>),
}

impl fmt::Debug for BetaPotential {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Zero => write!(f, "Zero"),
            Self::Function(_) => write!(f, "Function(..)"),
            Self::OnGrid(v) => write!(f, "OnGrid({} values)", v.len()),
        }
    }
}

impl BetaPotential {
    /// `beta U(x) = U(x) / kT` from a closure giving `U(x)`.
    pub fn from_fn(kt: f64, u: impl Fn(f64) -> f64 + Send + Sync + 'static) -> Self {
        Self::Function(Arc::new(move |x| u(x) / kt))
    }

    /// `beta U` of a scenario's external field, ignoring its drive (for DDFT, which takes the
    /// drive as [`DdftProblem::beta_drive`] = `field.drive / kT`).
    pub fn from_field(field: &colloidsim_core::field1d::ExternalField, kt: f64) -> Self {
        let f = field.clone();
        Self::Function(Arc::new(move |x| f.potential(x) / kt))
    }

    /// `beta U` of a field for the equilibrium solver: an error if the field has a drive (a
    /// tilted potential has no equilibrium; use [`ddft()`] for the driven steady state) or if
    /// `kT <= 0`.
    pub fn for_equilibrium(
        field: &colloidsim_core::field1d::ExternalField,
        kt: f64,
    ) -> Result<Self, RodsError> {
        param::positive("kT", kt)?;
        if field.drive != 0.0 {
            return Err(ParamError::new(
                "field.drive",
                format!(
                    "a driven system (drive = {}) has no equilibrium; the equilibrium theory needs \
                     drive = 0 (use the DDFT for the driven steady state)",
                    field.drive
                ),
            )
            .into());
        }
        Ok(Self::from_field(field, kt))
    }
}

/// An equilibrium problem for rods in an external potential at fixed mean density.
#[derive(Debug, Clone)]
pub struct RodsProblem {
    /// Rod length `sigma` > 0.
    pub sigma: f64,
    /// Mean density `N / L` (per period, or between the walls); `mean_density * sigma < 1`.
    pub mean_density: f64,
    /// Periodic or between walls.
    pub domain: Domain,
    /// Requested grid spacing; the grid uses the nearest spacing that divides the period (or
    /// `length - sigma`), reported as [`Equilibrium::dx`]. `sigma / dx >= 10` is required.
    pub dx: f64,
    /// External potential `beta U(x)`.
    pub beta_u: BetaPotential,
    /// Hard or sticky rods.
    pub interaction: RodInteraction,
    /// Convergence: max-norm of the structure equation in `ln rho` form (default 1e-10).
    pub tolerance: f64,
    /// Iteration limit on the finest grid (default 5000).
    pub max_iterations: usize,
    /// Anderson memory (default 20); 0 gives damped Picard. If the solve does not converge it
    /// is repeated once with memory 40 and mixing 0.1.
    pub anderson_memory: usize,
    /// Anderson / Picard mixing parameter in (0, 1] (default 0.5).
    pub mixing: f64,
}

/// Minimum number of grid points per rod length.
pub const MIN_POINTS_PER_SIGMA: f64 = 10.0;

impl RodsProblem {
    /// Hard rods, no potential, `dx = sigma / 100`, tolerance 1e-10.
    pub fn new(sigma: f64, mean_density: f64, domain: Domain) -> Self {
        Self {
            sigma,
            mean_density,
            domain,
            dx: sigma / 100.0,
            beta_u: BetaPotential::Zero,
            interaction: RodInteraction::Hard,
            tolerance: 1e-10,
            max_iterations: 5000,
            anderson_memory: 20,
            mixing: 0.5,
        }
    }

    /// Sets the grid spacing.
    pub fn with_dx(mut self, dx: f64) -> Self {
        self.dx = dx;
        self
    }

    /// Sets the potential.
    pub fn with_potential(mut self, beta_u: BetaPotential) -> Self {
        self.beta_u = beta_u;
        self
    }

    /// Sets the interaction.
    pub fn with_interaction(mut self, interaction: RodInteraction) -> Self {
        self.interaction = interaction;
        self
    }

    /// Sets the tolerance.
    pub fn with_tolerance(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }

    /// Checks every parameter; the error names the field and the allowed range.
    pub fn validate(&self) -> Result<(), RodsError> {
        param::positive("sigma", self.sigma)?;
        param::positive("mean_density", self.mean_density)?;
        if self.mean_density * self.sigma >= 1.0 {
            return Err(ParamError::new(
                "mean_density",
                format!(
                    "mean_density * sigma must be < 1 (close packing), got {} * {} = {}",
                    self.mean_density,
                    self.sigma,
                    self.mean_density * self.sigma
                ),
            )
            .into());
        }
        param::positive("dx", self.dx)?;
        param::positive("tolerance", self.tolerance)?;
        param::at_least("max_iterations", self.max_iterations, 1)?;
        param::in_range("mixing", self.mixing, f64::MIN_POSITIVE, 1.0)?;
        if let RodInteraction::Sticky { gamma } = self.interaction {
            param::non_negative("gamma", gamma)?;
        }
        match self.domain {
            Domain::Periodic { period } => {
                param::positive("period", period)?;
            }
            Domain::Walls { length } => {
                param::positive("length", length)?;
                let fit = (length / self.sigma * (1.0 + 1e-12)).floor();
                if length > self.sigma && self.mean_density * length >= fit {
                    return Err(ParamError::new(
                        "mean_density",
                        format!(
                            "between walls at most {fit} rods of length {} fit in length {length}; \
                             mean_density * length must be < {fit}, got {}",
                            self.sigma,
                            self.mean_density * length
                        ),
                    )
                    .into());
                }
                if length <= self.sigma {
                    return Err(ParamError::new(
                        "length",
                        format!(
                            "the walls must be further apart than one rod: length > sigma = {}, got {length}",
                            self.sigma
                        ),
                    )
                    .into());
                }
            }
        }
        let g = self.grid(self.dx)?;
        if let (BetaPotential::Function(f), Domain::Periodic { period }) =
            (&self.beta_u, self.domain)
        {
            // The density is solved on one period: the potential must repeat with that period.
            for k in 0..4 {
                let x = period * k as f64 / 4.0 + 0.1234 * period;
                let (a, b) = (f(x), f(x + period));
                if (a - b).abs() > 1e-6 * (1.0 + a.abs()) {
                    return Err(ParamError::new(
                        "period",
                        format!(
                            "beta_u does not repeat with period {period}: beta U({x}) = {a} but \
                             beta U({}) = {b}; use the potential's period (or a multiple)",
                            x + period
                        ),
                    )
                    .into());
                }
            }
        }
        if let BetaPotential::OnGrid(v) = &self.beta_u
            && v.len() != g.active
        {
            return Err(ParamError::new(
                "beta_u",
                format!(
                    "sampled potential must have one value per grid point ({}), got {}",
                    g.active,
                    v.len()
                ),
            )
            .into());
        }
        Ok(())
    }

    /// Positions of the grid points that carry density (the points of [`Equilibrium::x`]).
    pub fn grid_points(&self) -> Result<Vec<f64>, RodsError> {
        let g = self.grid(self.dx)?;
        Ok((0..g.active).map(|i| g.x(i)).collect())
    }

    /// The grid for spacing `dx` (validated: `sigma / dx >= 10`).
    pub(crate) fn grid(&self, dx: f64) -> Result<grid::Grid, RodsError> {
        let (x0, span, periodic) = match self.domain {
            Domain::Periodic { period } => (0.0, period, true),
            Domain::Walls { length } => (0.5 * self.sigma, length - self.sigma, false),
        };
        let intervals = (span / dx).round().max(1.0);
        let dx_eff = span / intervals;
        let ratio = self.sigma / dx_eff;
        if ratio.is_nan() || ratio < MIN_POINTS_PER_SIGMA {
            return Err(ParamError::new(
                "dx",
                format!(
                    "the grid must resolve the rod: sigma / dx >= {MIN_POINTS_PER_SIGMA}, got \
                     sigma / dx = {} / {dx_eff} = {ratio:.3}",
                    self.sigma
                ),
            )
            .into());
        }
        // The solve keeps about 2 (anderson_memory + 4) arrays of the grid (the retry's longer
        // history counted): refuse a grid the machine cannot hold before allocating it.
        let bytes = intervals * 8.0 * 2.0 * (self.anderson_memory.max(40) as f64 + 4.0);
        colloidsim_core::resources::ensure_fits(
            "dx",
            &format!(
                "the theory grid of {intervals:e} points (spacing {dx_eff:.3e}; a larger --dx makes it smaller)"
            ),
            bytes,
        )?;
        let mut n = ratio.floor();
        let mut f = ratio - n;
        if f > 1.0 - 1e-9 {
            n += 1.0;
            f = 0.0;
        } else if f < 1e-9 {
            f = 0.0;
        }
        let n = n as usize;
        let (m, active) = if periodic {
            (intervals as usize, intervals as usize)
        } else {
            // Active points 0..=intervals, then an empty gap of n + 3 points: the rods nearest
            // across the gap stay more than sigma apart even with the one-cell smearing of the
            // wall jump, so the periodic grid is exactly a box between walls.
            let active = intervals as usize + 1;
            (active + n + 3, active)
        };
        Ok(grid::Grid {
            m,
            dx: dx_eff,
            x0,
            n,
            f,
            active,
        })
    }

    /// Number of particles in the domain (per period if periodic).
    pub(crate) fn particles(&self) -> f64 {
        match self.domain {
            Domain::Periodic { period } => self.mean_density * period,
            Domain::Walls { length } => self.mean_density * length,
        }
    }

    /// `beta U` on the active points of `g` (checked finite).
    pub(crate) fn sample_potential(
        &self,
        g: &grid::Grid,
        out: &mut [f64],
    ) -> Result<(), RodsError> {
        for i in 0..g.active {
            let x = g.x(i);
            let v = match &self.beta_u {
                BetaPotential::Zero => 0.0,
                BetaPotential::Function(f) => f(x),
                BetaPotential::OnGrid(v) => v[i],
            };
            if !v.is_finite() {
                return Err(ParamError::new(
                    "beta_u",
                    format!("the potential must be finite on the grid, got {v} at x = {x}"),
                )
                .into());
            }
            out[i] = v;
        }
        for o in out.iter_mut().take(g.m).skip(g.active) {
            *o = 0.0;
        }
        Ok(())
    }
}
