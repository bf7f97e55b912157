//! The keys of `mpcd` scenarios, each declared once (docs/keys/mpcd.md is written from them).

use crate::keys::Allowed::*;
use crate::keys::Omitted::*;
use crate::keys::shared::*;
use crate::keys::{COUNT, SEED_KEY, Spec, key};

/// `method`.
pub const METHOD: Spec = key("method", "-", Required, OneOf(&["mpcd"]),
    "SRD solvent in a periodic cube (docs/mpcd.md)");

/// `seed`.
pub const SEED: Spec = SEED_KEY;

/// `system`.
pub const SYSTEM: Spec = key("system", "-", Required, Table, "the periodic box");

/// `system.box`.
pub const SYSTEM_BOX: Spec = key("system.box", "length", Required, Positive,
    "edge L of the periodic cube")
    .also("a whole number of cells, 2 to 4096 of them");

/// `system.colloids`.
pub const SYSTEM_COLLOIDS: Spec = key("system.colloids", "-", Value("0"), Integer(0, 1_000_000),
    "discrete-particle colloids placed at random; their diffusivity by Green-Kubo (vacf.csv, summary colloid_diffusion)")
    .also("not with [viscosity]; they must fit");

/// `system.diameter`.
pub const SYSTEM_DIAMETER: Spec = key("system.diameter", "length",
    Derived("4 solvent.cell", |r| Ok(4.0 * r.number(&SOLVENT_CELL)?)), Positive,
    "colloid diameter d")
    .also("the box above twice the WCA cut-off 2^(1/6) d; held in shape: sqrt(kT / colloid.bond_k) at most 0.1 of the shortest bond 0.273 d");

/// `run`.
pub const RUN: Spec = key("run", "-", Required, Table, "collisions");

/// `run.collisions`.
pub const RUN_COLLISIONS: Spec = key("run.collisions", "-", Required, Integer(1, COUNT),
    "collisions in all (equilibration included)");

/// `run.equilibrate`.
pub const RUN_EQUILIBRATE: Spec = key(
    "run.equilibrate",
    "-",
    Means(
        "6 flow relaxation times rho / (eta k^2) with [viscosity], else 100 (at most half the run)",
    ),
    Integer(0, COUNT),
    "collisions before sampling",
)
.also("below run.collisions");

/// `viscosity`.
pub const VISCOSITY: Spec = key("viscosity", "-", Means("absent: no drive"), Table,
    "shear viscosity by periodic Poiseuille flow (body force g0 cos(2 pi z / L) along x)");

/// `viscosity.drive`.
pub const VISCOSITY_DRIVE: Spec = key(
    "viscosity.drive",
    "force / mass",
    Derived(
        "flow amplitude 0.25 sqrt(kT/m) by Kikuchi's viscosity",
        super::params::default_drive,
    ),
    Positive,
    "drive amplitude g0",
)
.also("flow amplitude at most 0.6 sqrt(kT/m)");

/// `viscosity.blocks`.
pub const VISCOSITY_BLOCKS: Spec = key("viscosity.blocks", "-", Value("10"), Integer(2, 10_000),
    "blocks of the standard errors")
    .also("at most the sampling collisions");

/// `observe`.
pub const OBSERVE: Spec = key("observe", "-", Means("-"), Table, "observables");

/// `observe.every`.
pub const OBSERVE_EVERY: Spec = key("observe.every", "collisions",
    Means("collisions / 200"), Integer(1, COUNT),
    "rows of thermo.csv (temperature, flow amplitude, momentum)");

/// `observe.vacf_lags`.
pub const OBSERVE_VACF_LAGS: Spec = key("observe.vacf_lags", "collisions",
    Means("5 L^2 / (4 pi^2 nu tau)"), Integer(1, COUNT),
    "lags of the colloids' velocity autocorrelation summed by Green-Kubo (five decay times of the box's slowest shear mode)")
    .also("at most half the sampling collisions");

/// `observe.trajectory`.
pub const OBSERVE_TRAJECTORY: Spec = key("observe.trajectory", "-", Means("-"), Table,
    "GSD trajectory");

/// `observe.trajectory.every`.
pub const OBSERVE_TRAJECTORY_EVERY: Spec = key("observe.trajectory.every", "collisions",
    Value("0"), Integer(0, COUNT),
    "collisions between frames (0: none)");

/// `observe.trajectory.solvent`.
pub const OBSERVE_TRAJECTORY_SOLVENT: Spec = key("observe.trajectory.solvent", "-",
    Value("false"), Bool,
    "frames hold the solvent (type S, with velocities; colloids are types A and V)")
    .also("true when frames are written without colloids");

/// Every key of `mpcd` scenarios, in the order `colloidsim keys` lists them.
pub static KEYS: &[Spec] = &[
    METHOD,
    SEED,
    SOLVENT,
    SOLVENT_DENSITY,
    SOLVENT_ANGLE,
    SOLVENT_TAU,
    SOLVENT_KT,
    SOLVENT_MASS,
    SOLVENT_CELL,
    SOLVENT_THERMOSTAT,
    SYSTEM,
    SYSTEM_BOX,
    SYSTEM_COLLOIDS,
    SYSTEM_DIAMETER,
    COLLOID,
    COLLOID_VERTEX_MASS,
    COLLOID_CENTRE_MASS,
    COLLOID_BOND_K,
    COLLOID_MD_STEPS,
    RUN,
    RUN_COLLISIONS,
    RUN_EQUILIBRATE,
    VISCOSITY,
    VISCOSITY_DRIVE,
    VISCOSITY_BLOCKS,
    OBSERVE,
    crate::keys::shared::FIGURE_FORMAT,
    OBSERVE_EVERY,
    OBSERVE_VACF_LAGS,
    OBSERVE_TRAJECTORY,
    OBSERVE_TRAJECTORY_EVERY,
    OBSERVE_TRAJECTORY_SOLVENT,
];
