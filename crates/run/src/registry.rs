//! The one place methods are registered: every method, in the order `--help` lists them.
//! Adding a method is one line here (and its folder under `crate::methods`).

use crate::method::{Method, Scenario};
use anyhow::Result;

/// Every method, in the order `--help` lists them. New methods register here.
static METHODS: &[&dyn Method] = &[
    &crate::methods::bcd::BcdMethod,
    &crate::methods::droplet_bd::DropletBd,
    &crate::methods::bd::BulkBd,
    &crate::methods::dpd::DpdMethod,
    &crate::methods::hs_mc::HsMc,
    &crate::methods::mpcd::MpcdBulk,
    &crate::methods::droplet_mpcd::DropletMpcd,
];

/// Every registered method.
pub fn all() -> &'static [&'static dyn Method] {
    METHODS
}

/// Every `method` value a scenario may name.
pub fn names() -> Vec<&'static str> {
    METHODS
        .iter()
        .flat_map(|m| m.names().iter().copied())
        .collect()
}

/// The method a scenario names.
pub fn find(name: &str) -> Result<&'static dyn Method> {
    METHODS
        .iter()
        .copied()
        .find(|m| m.names().contains(&name))
        .ok_or_else(|| anyhow::anyhow!("unknown method '{name}' (one of: {})", names().join(", ")))
}

/// The method of a scenario, with the scenario named in the error.
pub fn of(sc: &Scenario) -> Result<&'static dyn Method> {
    let name = sc.method()?;
    find(&name).map_err(|e| anyhow::anyhow!("{}: {e}", sc.label()))
}
