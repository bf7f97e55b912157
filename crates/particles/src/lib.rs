//! colloidsim-particles: the 3D particle state every particle method shares, and no engine —
//! [`state`] (particles and the periodic box, with minimum image, wrapping and Lees–Edwards
//! shifts), [`potential`] (pair and external potentials), [`init`] (random non-overlapping
//! starting configurations) and [`gsd`] (GSD frames in the HOOMD schema: writer, reader,
//! checkpoint frames). The engines live in `colloidsim-md` (Brownian dynamics, DPD, MPCD) and
//! `colloidsim-mc` (hard-sphere Monte Carlo); `colloidsim-analysis` reads the frames.

pub mod gsd;
pub mod init;
pub mod potential;
pub mod state;

pub use potential::{
    ConstantForce, External, HarmonicInterface, LennardJones, LjParams, Morse, NoExternal, NoPair,
    Pair, PairSum, SphereAreaLaw,
};
pub use state::{Particles, SimBox};
