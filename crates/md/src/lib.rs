//! colloidsim-md: the particle dynamics engines, each in its folder —
//!
//! - [`brownian`]: Brownian dynamics, free draining ([`Brownian`]) or with hydrodynamic
//!   interactions ([`HydroBrownian`]), and its two scenarios: the drying droplet
//!   ([`brownian::droplet`]) and the bulk periodic box ([`brownian::bulk`]);
//! - [`dpd`]: dissipative particle dynamics of colloids in an explicit solvent;
//! - [`mpcd`]: multiparticle collision dynamics (SRD solvent, discrete colloids, droplet walls);
//!
//! and what the engines share: the cell sort and half stencil (`cells`), the Verlet list
//! ([`neighbor`]), the slab decomposition over ranks (`domain`), benchmark setups ([`mod@bench`]).
//! The state they move (particles and box, potentials, initial configurations, GSD frames) is
//! `colloidsim-particles`, re-exported here as [`state`], [`potential`], [`init`] and [`gsd`].

pub mod bench;
pub mod brownian;
mod cells;
mod domain;
pub mod dpd;
pub mod mpcd;
pub mod neighbor;
pub mod tune;

pub use brownian::droplet::DropletParams;
pub use brownian::hydrodynamic::{HydroBdError, HydroBdParams, HydroBrownian};
pub use brownian::{BdError, BdParams, Brownian, Integrator};
pub use colloidsim_hydro as hydro;
pub use colloidsim_particles::potential::{
    ConstantForce, External, HarmonicInterface, LennardJones, LjParams, Morse, NoExternal, NoPair,
    Pair, PairSum, SphereAreaLaw,
};
pub use colloidsim_particles::state::{Particles, SimBox};
pub use colloidsim_particles::{gsd, init, potential, state};
pub use dpd::{Dpd, DpdError, DpdParams};
pub use neighbor::NeighborList;
