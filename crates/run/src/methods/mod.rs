//! One folder per method: its key declarations, how it reads them into the engine's
//! parameters, its session and its outputs. The registry in [`crate::method`] lists them.

pub mod bcd;
pub mod droplet_bd;
pub mod hs_mc;
