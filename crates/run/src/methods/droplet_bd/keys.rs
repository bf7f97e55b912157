//! Every key of `droplet-bd` scenarios, declared once (the spheres, the solvent, the time
//! stepping and `[hydrodynamics]` are shared with `bd`, `[interface]` with hs-mc and
//! droplet-mpcd: `crate::keys::shared`). [`KEYS`] is what `colloidsim keys droplet-bd` lists and
//! what a scenario is checked against; `params.rs` reads each key through its declaration.
//! (Each constant's documentation is its declaration's `doc`.)
#![allow(missing_docs)]

use crate::keys::Allowed::*;
use crate::keys::Omitted::*;
use crate::keys::shared::{
    self, DIAMETER, DRYING, DRYING_ALPHA, DRYING_PECLET, HYDRO_MAX_ITERATIONS, HYDRO_MODEL, HYDRO_SPLITTING, HYDRO_TOLERANCE, HYDRODYNAMICS,
    INTERFACE, INTERFACE_OFFSET, INTERFACE_RANGE, INTERFACE_STIFFNESS, KT, RUN_DT, RUN_INTEGRATOR,
    RUN_SKIN, TRAJECTORY, TRAJECTORY_EVERY, VISCOSITY,
};
use crate::keys::species::*;
use crate::keys::{MAX_BINS_RADIAL, SEED_KEY, Spec, key};

/// `interface.hard` (with its conditions here).
pub const INTERFACE_HARD: Spec = shared::INTERFACE_HARD
    .also("without interface.stiffness and interface.range; a step reflected along the normal (with RPY along the mobility, moving the neighbours too); not for colloidsim theory");

pub const METHOD: Spec = key("method", "-", Required, OneOf(&["droplet-bd"]),
    "Brownian dynamics of a drying (or static) droplet, free draining or with RPY hydrodynamics");

pub const REPLICAS: Spec = key("replicas", "-", Value("1"), Integer(1, 1_000_000),
    "independent droplets whose profiles are averaged (replica r: initial stream r, noise keyed by (seed, step, r, block))");

pub const SYSTEM: Spec = key("system", "-", Required, Table,
    "particles, solvent and the initial droplet");

pub const SYSTEM_PARTICLES: Spec = key("system.particles", "-", Required, Integer(1, 100_000_000),
    "number of colloids N");

pub const SYSTEM_PHI0: Spec = key("system.phi0", "-",
    Means("give phi0 or radius"), LeftOpen(0.0, 0.64),
    "initial mean volume fraction N d^3 / (8 R0^3)")
    .also("at most 0.3 for random insertion (0.64 with system.initial); give this or system.radius");

pub const SYSTEM_RADIUS: Spec = key("system.radius", "length",
    Means("give phi0 or radius"), Positive,
    "initial droplet radius R0")
    .also("phi0 within the same limits");

pub const SYSTEM_INITIAL: Spec = key("system.initial", "-", Means("random insertion"), Path,
    "start from the last frame of this GSD file (HOOMD schema) instead of random insertion")
    .also("must hold system.particles particles within R0 + offset + range");

pub const DRYING_FINAL_VOLUME_FRACTION: Spec = shared::DRYING_FINAL_VOLUME_FRACTION.also("> phi0");

pub const DRYING_DURATION: Spec = shared::DRYING_DURATION
    .also("before R^2 would turn negative (t < 4 pi R0^2 / alpha)");

pub const RUN: Spec = key("run", "-", Means("defaults"), Table, "time stepping");

pub const OBSERVE: Spec = key("observe", "-", Means("profiles"), Table, "what to measure");

pub const OBSERVE_PROFILE: Spec = key("observe.profile", "-",
    Means("50 bins at 0, 25, 50, 75, 100 %"), Table,
    "radial volume-fraction profiles: profile_<f>.csv");

pub const OBSERVE_PROFILE_BINS: Spec = key("observe.profile.bins", "-",
    Value("50"), Integer(1, MAX_BINS_RADIAL),
    "radial bins of equal width between 0 and R(t)");

pub const OBSERVE_PROFILE_FRACTIONS: Spec = key("observe.profile.fractions", "-",
    Value("[0, 0.25, 0.5, 0.75, 1.0]"), Numbers(0.0, 1.0, None),
    "fractions of the drying time at which profiles are written")
    .also("at least one");

pub const OBSERVE_CROSS_SECTION: Spec = key("observe.cross_section", "-", Means("none"), Table,
    "a slab through the centre of replica 0's last frame: cross_section.csv (x,y,z,r) and cross_section.png");

pub const OBSERVE_CROSS_SECTION_WIDTH: Spec = key("observe.cross_section.width", "length",
    Means("d"), Positive,
    "slab thickness: centres with |z| < width / 2")
    .also("in [0.001 d, 2 R0]");

pub const HYDRO_METHOD: Spec = key("hydrodynamics.method", "-",
    Means("direct up to 2000 particles, pse above"), OneOf(&["direct", "pse"]),
    "RPY in an unbounded fluid by direct O(N^2) sums, or periodic by positively split Ewald")
    .also("model = \"rpy\" only; direct: at most 20000 particles");

pub const HYDRO_BOX_FACTOR: Spec = key("hydrodynamics.box_factor", "droplet diameters",
    Value("2"), Closed(1.2, 20.0),
    "PSE: edge of the periodic box / initial droplet diameter 2 R0 (the paper: 2)")
    .also("method = \"pse\" only; the box must hold the droplet, its interface and two neighbour ranges");

/// The keys of `droplet-bd` scenarios, in the order `colloidsim keys droplet-bd` lists them.
pub static KEYS: &[Spec] = keys_with_pair!(
    [
        METHOD,
        SEED_KEY,
        REPLICAS,
        SYSTEM,
        SYSTEM_PARTICLES,
        DIAMETER,
        SPECIES,
        SPECIES_DIAMETERS,
        SPECIES_COUNTS,
        SPECIES_VOLUME_FRACTIONS,
        KT,
        VISCOSITY,
        SYSTEM_PHI0,
        SYSTEM_RADIUS,
        SYSTEM_INITIAL,
        DRYING,
        DRYING_PECLET,
        DRYING_ALPHA,
        DRYING_FINAL_VOLUME_FRACTION,
        DRYING_DURATION,
        INTERFACE,
        INTERFACE_STIFFNESS,
        INTERFACE_RANGE,
        INTERFACE_OFFSET.also("in [-R0, R0] and R_end + offset > 0"),
        INTERFACE_HARD,
    ],
    PAIR,
    [
        RUN,
        RUN_DT,
        RUN_SKIN,
        RUN_INTEGRATOR,
        OBSERVE,
        crate::keys::shared::FIGURE_FORMAT,
        OBSERVE_PROFILE,
        OBSERVE_PROFILE_BINS,
        OBSERVE_PROFILE_FRACTIONS,
        TRAJECTORY,
        TRAJECTORY_EVERY,
        OBSERVE_CROSS_SECTION,
        OBSERVE_CROSS_SECTION_WIDTH,
        HYDRODYNAMICS,
        HYDRO_MODEL,
        HYDRO_METHOD,
        HYDRO_TOLERANCE,
        HYDRO_SPLITTING,
        HYDRO_BOX_FACTOR,
        HYDRO_MAX_ITERATIONS,
    ]
);
