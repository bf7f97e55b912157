//! The integration tests of `colloidsim-particles`, one test binary: each file of this folder is a module,
//! so that they are compiled and linked once and their tests share the threads of one run
//! (`cargo test -p colloidsim-particles --test integration MODULE::` runs one file's).

mod gsd_python;
