//! The integration tests of `colloidsim-bcd`, one test binary: each file of this folder is a module,
//! so that they are compiled and linked once and their tests share the threads of one run
//! (`cargo test -p colloidsim-bcd --test integration MODULE::` runs one file's).

mod common;

mod engine;
mod euler_pinned;
mod fragmentation;
mod integrator;
mod paper_cases;
mod reflect;
mod validation;
