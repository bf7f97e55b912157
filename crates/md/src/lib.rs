//! colloidsim-md: 3D particles (state and box, neighbour search, pair and external forces,
//! Brownian dynamics) and the drying-droplet scenario.

pub mod droplet;

pub use droplet::{DropletParams, DropletScenario};
