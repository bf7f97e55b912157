//! Multiparticle collision dynamics (MPCD): a stochastic-rotation-dynamics solvent
//! ([`srd`]), colloids as discrete particles that join its collisions ([`colloid`]), and the
//! walls of the drying droplet ([`boundary`]); the transport coefficients of the solvent
//! ([`theory`]). The drying-droplet paper's MPCD model (docs/references.md).
//!
//! Every random number comes from a counter-based stream of `colloidsim_core::rng` with the
//! purpose `Moves`, keyed by (seed, step, [`Draw`] and index): a collision's draws in cell `c`
//! from `(seed, step, Cell, c)`, the grid shift from `(seed, step, Shift, 0)`, and so on, so
//! that results depend neither on the number of threads nor on the order of the work.

pub mod boundary;
pub mod colloid;
pub mod drying;
pub mod measure;
pub mod ranks;
pub mod srd;
pub mod theory;

use colloidsim_core::rng::{Purpose, stream};

pub use boundary::{Confinement, WallKind};
pub use colloid::{
    ColloidParams, ColloidState, DiscreteColloids, MAX_BOND_STRAIN, MpcdSystem, Region,
};
pub use srd::{Acceleration, Embedded, Srd, SrdParams};

/// What a random stream of the MPCD engine is drawn for (the top byte of its index).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u64)]
pub enum Draw {
    /// The collision of one cell (index: the cell): rotation axis, thermostat, virtual particles.
    Cell = 0,
    /// The grid shift of a collision.
    Shift = 1,
    /// The initial solvent (index: block of 64 particles).
    Solvent = 2,
    /// Which reflected solvent particles are removed while the droplet dries.
    Removal = 3,
    /// Initial colloid positions and velocities.
    Colloid = 4,
}

/// The stream for `what` at `step` with `index` (below 2^56).
#[inline]
pub fn draw(seed: u32, step: u64, what: Draw, index: u64) -> impl rand::Rng {
    debug_assert!(index < 1 << 56);
    stream(seed, step, Purpose::Moves, ((what as u64) << 56) | index)
}

/// Why an MPCD engine cannot be built or cannot go on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MpcdError {
    /// Inconsistent input.
    #[error("invalid MPCD input: {0}")]
    Invalid(String),
    /// A position or velocity became NaN or infinite.
    #[error(
        "the run went non-finite at step {step}: {what} particle {index}; reduce the time step or check the forces"
    )]
    NonFinite {
        /// Collision step.
        step: u64,
        /// Solvent or colloid.
        what: &'static str,
        /// Index (storage slot for the solvent, input index for colloid particles).
        index: usize,
    },
}
