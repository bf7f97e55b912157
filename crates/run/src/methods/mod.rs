//! One folder per method: its key declarations, how it reads them into the engine's
//! parameters, its session and its outputs. The registry in [`crate::registry`] lists them.

pub mod bcd;
pub mod bd;
pub mod dpd;
pub mod droplet_bd;
pub mod droplet_mpcd;
pub mod hs_mc;
pub mod mpcd;
