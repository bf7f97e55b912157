//! Sections that several methods share, declared once: every method that has them lists these
//! declarations (adding its own cross-key condition with [`Spec::also`] where it has one) and
//! reads them with the functions here, so that their defaults are computed in one place.

use super::Allowed::*;
use super::Omitted::*;
use super::{Reader, Spec, key};
use anyhow::Result;
use colloidsim_md::mpcd::{ColloidParams, SrdParams};

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

/// `[solvent]`: the SRD solvent of both MPCD methods (MPCD units).
pub const SOLVENT: Spec = key(
    "solvent",
    "-",
    Means("-"),
    Table,
    "the SRD solvent (MPCD units: cell edge a, solvent mass m, kT)",
);

/// `solvent.density`.
pub const SOLVENT_DENSITY: Spec = key(
    "solvent.density",
    "particles / cell",
    Value("5"),
    LeftOpen(0.0, 1000.0),
    "mean particles per cell M",
);

/// `solvent.angle`.
pub const SOLVENT_ANGLE: Spec = key(
    "solvent.angle",
    "degrees",
    Value("130"),
    LeftOpen(0.0, 180.0),
    "SRD rotation angle about a random axis per cell",
);

/// `solvent.tau`.
pub const SOLVENT_TAU: Spec = key(
    "solvent.tau",
    "time",
    Value("0.1"),
    Positive,
    "collision time (the streaming step)",
);

/// `solvent.kT`.
pub const SOLVENT_KT: Spec = key(
    "solvent.kT",
    "energy",
    Value("1"),
    Positive,
    "thermal energy",
);

/// `solvent.mass`.
pub const SOLVENT_MASS: Spec = key(
    "solvent.mass",
    "mass",
    Value("1"),
    Positive,
    "solvent particle mass m",
);

/// `solvent.cell`.
pub const SOLVENT_CELL: Spec = key(
    "solvent.cell",
    "length",
    Value("1"),
    Positive,
    "collision cell edge a",
)
.also("every box edge a whole number of cells");

/// `solvent.thermostat`.
pub const SOLVENT_THERMOSTAT: Spec = key(
    "solvent.thermostat",
    "-",
    Value("true"),
    Bool,
    "cell-level Maxwell-Boltzmann thermostat (Huang et al. 2010)",
);

/// `[colloid]`: the discrete-particle colloid of both MPCD methods (defaults chosen,
/// docs/mpcd.md).
pub const COLLOID: Spec = key(
    "colloid",
    "-",
    Means("-"),
    Table,
    "the discrete-particle colloid: 42 vertices and a centre, harmonic bonds (defaults chosen, docs/mpcd.md)",
);

/// `colloid.vertex_mass`.
pub const COLLOID_VERTEX_MASS: Spec = key(
    "colloid.vertex_mass",
    "mass",
    Value("5"),
    Positive,
    "mass of each of the 42 vertices (they join the collisions)",
);

/// `colloid.centre_mass`.
pub const COLLOID_CENTRE_MASS: Spec = key(
    "colloid.centre_mass",
    "mass",
    Value("5"),
    Positive,
    "mass of the central particle (WCA between centres, the droplet's interface acts on it)",
);

/// `colloid.bond_k`.
pub const COLLOID_BOND_K: Spec = key(
    "colloid.bond_k",
    "energy / length^2",
    Derived("5000 solvent.kT", |r| Ok(5000.0 * r.number(&SOLVENT_KT)?)),
    Positive,
    "spring constant of the 120 edge and 42 spoke bonds",
);

/// `colloid.md_steps`.
pub const COLLOID_MD_STEPS: Spec = key(
    "colloid.md_steps",
    "-",
    Value("50"),
    Integer(1, 100_000),
    "velocity Verlet steps per collision time",
);

/// Read `[solvent]` into the engine's parameters, with the run's `seed`.
pub fn solvent(r: &Reader, seed: u32) -> Result<SrdParams> {
    Ok(SrdParams {
        cell: r.number(&SOLVENT_CELL)?,
        density: r.number(&SOLVENT_DENSITY)?,
        angle: r.number(&SOLVENT_ANGLE)?.to_radians(),
        tau: r.number(&SOLVENT_TAU)?,
        kt: r.number(&SOLVENT_KT)?,
        mass: r.number(&SOLVENT_MASS)?,
        thermostat: r.flag(&SOLVENT_THERMOSTAT)?,
        seed,
    })
}

/// Read `[colloid]` into the model of colloids of diameter `d` (WCA energy kT).
pub fn colloid(r: &Reader, d: f64) -> Result<ColloidParams> {
    Ok(ColloidParams {
        diameter: d,
        vertex_mass: r.number(&COLLOID_VERTEX_MASS)?,
        centre_mass: r.number(&COLLOID_CENTRE_MASS)?,
        bond_k: r.number(&COLLOID_BOND_K)?,
        md_steps: r.integer(&COLLOID_MD_STEPS)? as u32,
        wca_epsilon: r.number(&SOLVENT_KT)?,
    })
}
