//! colloidsim-mc: hard-sphere Monte Carlo (NVT, single-particle displacement moves).
//!
//! - [`geometry`]: the periodic cube (bulk), the hard spherical wall of radius R (the droplet;
//!   centres within `R - d/2`) and the BD droplet's harmonic interface (Metropolis on the
//!   `HarmonicInterface` energy of `colloidsim-particles`, the one BD uses).
//! - [`engine`]: [`HardSphereMc`] (one species, or an additive mixture of `colloidsim_particles::Mixture`,
//!   overlap below the pair's mean diameter), checkerboard cell sweeps (Anderson et al., J. Comput. Phys.
//!   254, 27 (2013)) with counter-based random streams keyed by (seed, sweep, cell), so that a
//!   run is fixed by its seed whatever the number of threads; move-size tuning in the warm-up.
//! - [`engine::pair`]: a pair interaction of `colloidsim-particles` (the BD engines' `[pair]`)
//!   in place of the hard cores, local moves with the Metropolis test on the pair energy, and
//!   the pair virial.
//! - [`engine::chain`]: event-chain Monte Carlo (Bernard, Krauth & Wilson 2009), the move type
//!   beside the local moves, with its exact pressure.
//! - [`init`]: lattice starting configurations (melted by the warm-up).
//! - [`observe`]: pair-distance and radial histograms (per species too), contact values
//!   extrapolated to contact, block-average errors, the Carnahan–Starling and BMCSL references.
//! - [`radial_pairs`]: the droplet's two-body density in the `(r1, r2, s)` bins of the DDFT's RPY
//!   flux kernel (issue #15 item 4).
//! - [`params`]: the parameters of a run ([`params::McRun`]) and the engine they start.
//! - [`bench`]: trial moves per second (`colloidsim bench mc`).
//!
//! Conventions: docs/mc.md; validation numbers: docs/reports/mc-validation.md.

pub mod bench;
pub mod engine;
pub mod geometry;
pub mod init;
pub mod observe;
pub mod params;
pub mod radial_pairs;

pub use engine::chain::{ChainStats, EventChain};
pub use engine::{HardSphereMc, McError, McParams, SweepStats};
pub use geometry::{Geometry, RadialPotential};
