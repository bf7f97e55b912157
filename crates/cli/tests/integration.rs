//! The integration tests of `colloidsim-cli`, one test binary: each file of this folder is a module,
//! so that they are compiled and linked once and their tests share the threads of one run
//! (`cargo test -p colloidsim-cli --test integration MODULE::` runs one file's).

mod common;

mod bcd_cli;
mod bd_cli;
mod cluster_cli;
mod dpd_cli;
mod droplet_cli;
mod ensemble_cli;
mod example_headers;
mod examples_golden;
mod finite_cli;
mod hydro_cli;
mod keys_pages;
mod mc_cli;
mod mpcd_cli;
mod mpcd_species;
mod run_folder;
mod trajectory_restart;
