//! Sections that several methods share, declared once: every method that has them lists these
//! declarations (adding its own cross-key condition with [`Spec::also`] where it has one) and
//! reads them with the functions here, so that their defaults are computed in one place.

use super::Allowed::*;
use super::Omitted::*;
use super::{Reader, Spec, key};
use anyhow::Result;

/// `[interface]`: the harmonic interface of a droplet (docs/droplet.md).
pub const INTERFACE: Spec = key(
    "interface",
    "-",
    Means("k = 50 kT/d^2, range d/2, offset -d/2"),
    Table,
    "harmonic interface V = k/2 s^2 for 0 <= s < range, linear beyond, s = r - (R(t) + offset)",
);

/// `interface.stiffness`.
pub const INTERFACE_STIFFNESS: Spec = key(
    "interface.stiffness",
    "energy / length^2",
    Means("50 kT / d^2"),
    Positive,
    "spring constant k",
);

/// `interface.range`.
pub const INTERFACE_RANGE: Spec = key(
    "interface.range",
    "length",
    Means("d / 2"),
    Positive,
    "range of the harmonic part Delta",
);

/// `interface.offset`.
pub const INTERFACE_OFFSET: Spec = key(
    "interface.offset",
    "length",
    Means("-d / 2"),
    Finite,
    "wall position relative to R(t) (-d/2: the colloid surface at R(t))",
);

/// The interface's parameters as read: the keys given, else the defaults of the declarations
/// for spheres of diameter `d` at thermal energy `kt`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interface {
    /// Spring constant k (energy / length^2).
    pub stiffness: f64,
    /// Range of the harmonic part Delta (length).
    pub range: f64,
    /// Wall position relative to R(t) (length).
    pub offset: f64,
}

/// Read `[interface]` for spheres of diameter `d` at thermal energy `kt`.
pub fn interface(r: &Reader, d: f64, kt: f64) -> Result<Interface> {
    Ok(Interface {
        stiffness: r
            .opt_number(&INTERFACE_STIFFNESS)?
            .unwrap_or(50.0 * kt / (d * d)),
        range: r.opt_number(&INTERFACE_RANGE)?.unwrap_or(0.5 * d),
        offset: r.opt_number(&INTERFACE_OFFSET)?.unwrap_or(-0.5 * d),
    })
}
