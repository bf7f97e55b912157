//! The integration tests of `colloidsim-analysis`, one test binary: each file of this folder is a module,
//! so that they are compiled and linked once and their tests share the threads of one run
//! (`cargo test -p colloidsim-analysis --test integration MODULE::` runs one file's).

mod contacts;
mod network;
mod structure_factor;
mod trajectory;
