//! colloidsim-particles: the 3D particle state every particle method shares, and no engine —
//! [`state`] (particles and the periodic box, with minimum image, wrapping and Lees–Edwards
//! shifts), [`potential`] (pair and external potentials), [`species`] (the species of a mixture),
//! [`interaction`] (pair interactions per species pair), [`init`] (random non-overlapping
//! starting configurations) and [`gsd`] (GSD frames in the HOOMD schema: writer, reader,
//! checkpoint frames). The engines live in `colloidsim-md` (Brownian dynamics, DPD, MPCD) and
//! `colloidsim-mc` (hard-sphere Monte Carlo); `colloidsim-analysis` reads the frames.

pub mod gsd;
pub mod init;
pub mod interaction;
pub mod potential;
pub mod species;
pub mod state;

pub use interaction::{Interaction, PairSpec};
pub use potential::{
    ConstantForce, External, HarmonicInterface, LennardJones, LjParams, Morse, NoExternal, NoPair,
    Pair, PairSum, SpeciesInterface, SphereAreaLaw,
};
pub use species::Mixture;
pub use state::{Particles, SimBox};
