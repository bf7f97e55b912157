//! Brownian cluster dynamics (BCD) of hard and sticky rods in one dimension.
//!
//! Implements the exact treatment of hard-core collisions in overdamped Langevin dynamics of
//! Antonov, Schweers, Ryabov and Maass (hard-rods paper, PRE 2022) with the fast O(N)
//! fragmentation and premerging of the fast-bcd paper:
//!
//! - [`cluster`]: fragmentation by successive pair splitting and binary premerging;
//! - [`forces`]: external fields and pair forces (Baxter sticky rods, Yukawa, tabulated);
//! - [`engine`]: the time step on a ring or between walls, and the chronological oracle;
//! - [`observe`]: density, contact density, MSD, current and cluster statistics;
//! - [`init`]: initial configurations;
//! - [`mc`]: Metropolis Monte Carlo of hard and sticky rods, the time-step-free reference.

pub mod cluster;
pub mod engine;
pub mod forces;
pub mod init;
pub mod mc;
pub mod observe;
mod pava;
#[doc(hidden)]
pub use pava::PoolBench;
mod reflect;
mod ring;

pub use engine::{Bcd, BcdConfig, BcdError, BcdState, Boundary, Integrator, Update};
