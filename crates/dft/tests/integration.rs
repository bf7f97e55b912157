//! The integration tests of `colloidsim-dft`, one test binary: each file of this folder is a module,
//! so that they are compiled and linked once and their tests share the threads of one run
//! (`cargo test -p colloidsim-dft --test integration MODULE::` runs one file's).

mod radial_bulk;
mod radial_ddft;
mod radial_equilibrium;
mod radial_mixture;
mod radial_rpy;
mod rods_ddft;
mod rods_equilibrium;
mod rods_transfer;
