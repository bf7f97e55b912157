//! The keys of `droplet-mpcd` scenarios, each declared once (docs/keys/droplet-mpcd.md is written from them).

use crate::keys::Allowed::*;
use crate::keys::Omitted::*;
use crate::keys::shared::{self, *};
use crate::keys::{COUNT, SEED_KEY, Spec, key};
pub use crate::keys::species::{SPECIES, SPECIES_COUNTS, SPECIES_DIAMETERS, SPECIES_VOLUME_FRACTIONS};

/// `method`.
pub const METHOD: Spec = key("method", "-", Required, OneOf(&["droplet-mpcd"]),
    "drying droplet of SRD solvent (docs/mpcd.md)");

/// `seed`.
pub const SEED: Spec = SEED_KEY;

/// `boundary`.
pub const BOUNDARY: Spec = key("boundary", "-",
    Means("\"slip\""), OneOf(&["none", "slip", "no-slip"]),
    "the solvent at the moving sphere: none (fills the box, ignores it), slip or no-slip bounce-back");

/// `system`.
pub const SYSTEM: Spec = key("system", "-", Required, Table, "colloids, droplet and box");

/// `system.particles`.
pub const SYSTEM_PARTICLES: Spec = key("system.particles", "-", Value("0"), Integer(0, 10_000_000),
    "colloids N (0: a pure-solvent droplet), placed at random with centres within R0 - d/2")
    .also("they must fit: random sequential addition, at most phi0 = 0.3");

/// `system.diameter`.
pub const SYSTEM_DIAMETER: Spec = key("system.diameter", "length",
    Derived("4 solvent.cell; with system.species, the smallest of its diameters", |r| {
        Ok(crate::keys::species::smallest_diameter(r)?.unwrap_or(4.0 * r.number(&SOLVENT_CELL)?))
    }), Positive,
    "colloid diameter d; sets D0 = kT / (3 pi eta d) with Kikuchi's viscosity, and so Pe")
    .also("held in shape: sqrt(kT / colloid.bond_k) at most 0.1 of the shortest bond 0.273 d");

/// `system.radius`.
pub const SYSTEM_RADIUS: Spec = key("system.radius", "length", Required, Positive,
    "initial droplet radius R0")
    .also("at least 2 cells");

/// `system.phi0`.
pub const SYSTEM_PHI0: Spec = key("system.phi0", "-", Means("from radius"), LeftOpen(0.0, 0.3),
    "initial colloid volume fraction N d^3 / (8 R0^3)")
    .also("with colloids; not with system.radius");

/// `system.box`.
pub const SYSTEM_BOX: Spec = key("system.box", "length",
    Means("smallest whole number of cells >= 2 R0 + 4"), Positive,
    "edge of the periodic box")
    .also("at least 2 R0 + 4 cells, a whole number of cells");

/// `drying.final_volume_fraction` (with its conditions here).
/// Its default applies with colloids only (a pure-solvent droplet has no volume fraction).
pub const DRYING_FINAL_VOLUME_FRACTION: Spec = Spec {
    default: Means("0.55 with colloids; without, give drying.duration"),
    ..shared::DRYING_FINAL_VOLUME_FRACTION.also("> phi0; with colloids only")
};

/// `drying.duration` (with its conditions here).
pub const DRYING_DURATION: Spec = shared::DRYING_DURATION
    .also("required without colloids; R must stay above two cells");

/// `interface.stiffness` (with its condition here).
pub const INTERFACE_STIFFNESS: Spec = shared::INTERFACE_STIFFNESS
    .also("with the bonds, omega dt at most 1 (dt = solvent.tau / colloid.md_steps)");

/// `interface.range` (with its condition here).
pub const INTERFACE_RANGE: Spec = shared::INTERFACE_RANGE.also("at most R0");

/// `interface.offset` (with its condition here).
pub const INTERFACE_OFFSET: Spec = shared::INTERFACE_OFFSET.also("in [-R0, R0]");

/// `interface.hard` (with its conditions here).
pub const INTERFACE_HARD: Spec = shared::INTERFACE_HARD.also(
    "without interface.stiffness and interface.range; the whole colloid reflected when its centre crosses: moved by the centre's mirror step, its centre-of-mass normal velocity reversed in the frame of the wall (moving at dR/dt)",
);

/// `observe`.
pub const OBSERVE: Spec = key("observe", "-", Means("-"), Table, "observables");

/// `observe.every`.
pub const OBSERVE_EVERY: Spec = key("observe.every", "collisions",
    Means("collisions / 200"), Integer(1, COUNT),
    "rows of thermo.csv (radius, solvent count, expected count, removed, bounced, temperature)");

/// `observe.profile`.
pub const OBSERVE_PROFILE: Spec = key("observe.profile", "-", Means("-"), Table,
    "times of the profiles");

/// `observe.profile.bins`.
pub const OBSERVE_PROFILE_BINS: Spec = key("observe.profile.bins", "-",
    Value("50"), Integer(1, 100_000),
    "bins of the colloid volume-fraction profiles (with colloids)");

/// `observe.profile.fractions`.
pub const OBSERVE_PROFILE_FRACTIONS: Spec = key("observe.profile.fractions", "-",
    Value("[0.0, 0.25, 0.5, 0.75, 1.0]"), Numbers(0.0, 1.0, None),
    "fractions of the drying time at which profiles are taken")
    .also("increasing, distinct collisions");

/// `observe.solvent`.
pub const OBSERVE_SOLVENT: Spec = key("observe.solvent", "-", Means("-"), Table,
    "solvent density and radial velocity against r / R(t)");

/// `observe.solvent.bins`.
pub const OBSERVE_SOLVENT_BINS: Spec = key("observe.solvent.bins", "-",
    Value("20"), Integer(1, 10_000),
    "bins over [0, R(t)]");

/// `observe.solvent.window`.
pub const OBSERVE_SOLVENT_WINDOW: Spec = key("observe.solvent.window", "collisions",
    Means("collisions / 10"), Integer(1, COUNT),
    "each solvent profile averages this many collisions ending at its time (10 blocks for the errors)");

/// `observe.trajectory` and its `every`: as in `mpcd`.
pub use crate::methods::mpcd::keys::{OBSERVE_TRAJECTORY, OBSERVE_TRAJECTORY_EVERY};

/// `observe.trajectory.solvent`: as in `mpcd`, the frames logging the droplet radius.
pub const OBSERVE_TRAJECTORY_SOLVENT: Spec = Spec {
    doc: "frames hold the solvent (type S, with velocities; log/radius)",
    ..crate::methods::mpcd::keys::OBSERVE_TRAJECTORY_SOLVENT
};

/// Every key of `droplet-mpcd` scenarios, in the order `colloidsim keys` lists them.
pub static KEYS: &[Spec] = &[
    METHOD,
    SEED,
    BOUNDARY,
    SOLVENT,
    SOLVENT_DENSITY,
    SOLVENT_ANGLE,
    SOLVENT_TAU,
    SOLVENT_KT,
    SOLVENT_MASS,
    SOLVENT_CELL,
    SOLVENT_THERMOSTAT,
    SYSTEM,
    SYSTEM_PARTICLES,
    SYSTEM_DIAMETER,
    SPECIES,
    SPECIES_DIAMETERS,
    SPECIES_COUNTS,
    SPECIES_VOLUME_FRACTIONS,
    SYSTEM_RADIUS,
    SYSTEM_PHI0,
    SYSTEM_BOX,
    DRYING,
    DRYING_PECLET,
    DRYING_ALPHA,
    DRYING_FINAL_VOLUME_FRACTION,
    DRYING_DURATION,
    INTERFACE,
    INTERFACE_STIFFNESS,
    INTERFACE_RANGE,
    INTERFACE_OFFSET,
    INTERFACE_HARD,
    COLLOID,
    COLLOID_VERTEX_MASS,
    COLLOID_CENTRE_MASS,
    COLLOID_BOND_K,
    COLLOID_MD_STEPS,
    OBSERVE,
    crate::keys::shared::FIGURE_FORMAT,
    OBSERVE_EVERY,
    OBSERVE_PROFILE,
    OBSERVE_PROFILE_BINS,
    OBSERVE_PROFILE_FRACTIONS,
    OBSERVE_SOLVENT,
    OBSERVE_SOLVENT_BINS,
    OBSERVE_SOLVENT_WINDOW,
    OBSERVE_TRAJECTORY,
    OBSERVE_TRAJECTORY_EVERY,
    OBSERVE_TRAJECTORY_SOLVENT,
];
