//! The integration tests of `colloidsim-mc`, one test binary: each file of this folder is a module,
//! so that they are compiled and linked once and their tests share the threads of one run
//! (`cargo test -p colloidsim-mc --test integration MODULE::` runs one file's).

mod event_chain;
mod mixture;
mod pair;
mod trokhymchuk;
mod validation;
