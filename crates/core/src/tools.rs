//! The external tools some tests check our outputs with (the `gsd` Python package reads our
//! trajectories as HOOMD-blue, freud and OVITO do).
//!
//! On a developer's machine a missing tool skips such a check with a notice. Where the
//! environment variable [`REQUIRE_TOOLS`] is set (CI sets it), a missing tool fails the test
//! instead, so that a check that must run is never skipped silently.

use std::process::Command;

/// Set (to anything) to make a missing external tool a test failure.
pub const REQUIRE_TOOLS: &str = "COLLOIDSIM_REQUIRE_TOOLS";

/// Can `python3` import `module`? `false` (after a notice naming `test`) when it cannot and
/// [`REQUIRE_TOOLS`] is unset; a panic when it cannot and [`REQUIRE_TOOLS`] is set.
pub fn python_module_or_skip(module: &str, test: &str) -> bool {
    let found = Command::new("python3")
        .args(["-c", &format!("import {module}")])
        .output()
        .is_ok_and(|o| o.status.success());
    if found {
        return true;
    }
    if std::env::var_os(REQUIRE_TOOLS).is_some() {
        panic!(
            "{test}: python3 cannot import {module}, and {REQUIRE_TOOLS} says this check must run \
             (pip install the package that provides {module})"
        );
    }
    eprintln!(
        "NOTICE: {test}: python3 cannot import {module}; skipped (set {REQUIRE_TOOLS}=1 to make \
         this a failure)"
    );
    false
}
