//! colloidsim-md: 3D particles (state and box, neighbour search, pair and external forces,
//! Brownian dynamics, initial configurations, GSD input/output), the drying-droplet scenario
//! and the bulk periodic Brownian-dynamics scenario.

mod bd_scenario;
pub mod bench;
pub mod brownian;
pub mod bulk;
mod cells;
mod domain;
pub mod dpd;
pub mod droplet;
pub mod hydro_bd;
pub mod mpcd;
pub mod neighbor;

pub use brownian::{BdError, BdParams, Brownian, Integrator};
pub use colloidsim_hydro as hydro;
pub use dpd::{Dpd, DpdError, DpdParams};
pub use droplet::DropletParams;
pub use hydro_bd::{HydroBdError, HydroBdParams, HydroBrownian};
pub use neighbor::NeighborList;
pub use colloidsim_particles::potential::{
    ConstantForce, External, HarmonicInterface, LennardJones, LjParams, Morse, NoExternal, NoPair,
    Pair, PairSum, SphereAreaLaw,
};
pub use colloidsim_particles::state::{Particles, SimBox};
pub use colloidsim_particles::{gsd, init, potential, state};
