//! Rosenfeld fundamental-measure DDFT of hard spheres in spherical symmetry (drying droplet).
//!
//! The drying-droplet paper (docs/references.md), Secs. II.2, III.1, III.4.
//!
//! - [`grid`]: cell-centred radial finite-volume grid.
//! - [`fmt`]: radial weighted densities `n3, n2, nv2` (and `n0, n1, nv1` by proportionality), the
//!   Rosenfeld free-energy density and its functional derivative.
//! - [`interface`]: the harmonic droplet interface and the shrinking radius `R(t)`.
//! - [`equilibrium`]: equilibrium profile at fixed particle number (Picard + Anderson mixing).
//! - [`ddft`]: implicit-Euler DDFT on spherical shells, free-draining or with pairwise RPY flux.
//! - [`droplet`]: a drying droplet end to end (setup validation, equilibrium start, snapshots).
//! - [`rpy`]: the radial RPY kernel of the hydrodynamic flux (dilute or Trokhymchuk pair correlation).
//! - [`g2`]: the RPY kernel of a tabulated inhomogeneous pair correlation `g2(r1, r2, s)`.
//! - [`pair`]: bulk hard-sphere pair correlation `g(r; eta)` (Trokhymchuk et al. 2005).
//! - [`bulk`]: Percus–Yevick (compressibility) bulk equation of state, the FMT bulk limit.
//! - [`mixture`]: the same for a mixture of any number of species (Rosenfeld or White Bear,
//!   free-draining or pairwise unequal-radius RPY flux; engine entry [`mixture::run_mixture_droplet`]).
//!
//! ```no_run
//! use colloidsim_dft::radial::*;
//! // N = 6250 spheres (d = 1), R0 = 25 d, Pe = 10 with D0 = 1, dried to mean phi 0.5.
//! let schedule = DryingSchedule::from_peclet(25.0, 10.0, 1.0)?;
//! let setup = DropletSetup {
//!     particles: 6250.0,
//!     diameter: 1.0,
//!     d0: 1.0,
//!     r0: 25.0,
//!     alpha: schedule.alpha,
//!     interface: HarmonicInterface::new(50.0, 0.5, -0.5)?, // k in kT/d^2, Delta, offset
//!     t_end: schedule.time_at_radius(25.0 * 0.1f64.cbrt()),
//!     dr: 0.01,
//!     hydrodynamics: Hydrodynamics::FreeDraining,
//!     pair: PairCorrelation::Dilute,
//! };
//! let times = [0.5 * setup.t_end, setup.t_end];
//! let opts = DdftOptions::new(1.0, 1.0);
//! run_droplet(&setup, &times, &opts, &EquilibriumOptions::default(),
//!     |grid, snap| println!("t = {}: max n3 = {}", snap.time,
//!         snap.n3.iter().cloned().fold(0.0, f64::max)),
//!     |_step| {})?;
//! # Ok::<(), RadialError>(())
//! ```

pub mod bulk;
pub mod ddft;
pub mod droplet;
pub mod equilibrium;
pub mod fmt;
pub mod g2;
pub mod grid;
pub mod interface;
pub mod mixture;
pub mod pair;
pub mod rpy;

pub use ddft::{Ddft, DdftOptions, EffectiveForce, Hydrodynamics, StepReport};
pub use droplet::{
    DropletOutcome, DropletSetup, Snapshot, bin_average, equilibrium_at, run_droplet,
};
pub use equilibrium::{Equilibrium, EquilibriumOptions, solve_equilibrium};
pub use fmt::Rosenfeld;
pub use g2::TabulatedPair;
pub use grid::RadialGrid;
pub use interface::{DryingSchedule, HarmonicInterface};
pub use rpy::{PairCorrelation, PairTable, RpyKernel};

use colloidsim_core::ParamError;
use thiserror::Error;

/// Errors of the radial DFT/DDFT solvers.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum RadialError {
    /// An input parameter is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// An iterative solve stopped without reaching its tolerance.
    #[error(
        "{what} did not converge after {iterations} iterations: residual {residual:.3e} > tolerance {tolerance:.1e}"
    )]
    NotConverged {
        /// Which solve.
        what: String,
        /// Iterations done.
        iterations: usize,
        /// Final residual.
        residual: f64,
        /// Requested tolerance.
        tolerance: f64,
    },
    /// The density became unphysical (negative, packing fraction >= 1, particles ejected).
    #[error("unphysical solution at t = {time:.6}: {message}")]
    Unphysical {
        /// Time at which it was detected.
        time: f64,
        /// What was detected.
        message: String,
    },
}
