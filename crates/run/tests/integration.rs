//! The integration tests of `colloidsim-run`, one test binary: each file of this folder is a module,
//! so that they are compiled and linked once and their tests share the threads of one run
//! (`cargo test -p colloidsim-run --test integration MODULE::` runs one file's).

/// The helpers of the md tests (a DPD or BD system and its checks), shared with them.
#[path = "../../md/tests/common/mod.rs"]
mod common;
mod dt_error;

mod bcd_observers;
mod bd;
mod bd_domains;
mod consistency;
mod dpd_domains;
mod dpd_engine;
mod dpd_shear;
mod dpd_viscosity;
mod droplet;
mod droplet_dt_error;
mod droplet_equilibrium;
mod engine_keys;
mod estimate;
mod extrapolate;
mod figures;
mod fuzz;
mod hs_mc_pair;
mod hs_mc_species;
mod hydro_bd;
mod keys;
mod mpcd_engine;
mod progress;
mod render;
mod resources;
mod seed;
mod skin_tuning;
mod species;
mod theory_driven;
mod theory_pair;
