//! The integration tests of `colloidsim-hydro`, one test binary: each file of this folder is a module,
//! so that they are compiled and linked once and their tests share the threads of one run
//! (`cargo test -p colloidsim-hydro --test integration MODULE::` runs one file's).

mod common;

mod direct;
mod pse;
