//! Every key of `bd` scenarios, declared once (the spheres, the solvent, the time stepping,
//! `[observe.trajectory]` and `[hydrodynamics]` are shared with `droplet-bd`:
//! `crate::keys::shared`). [`KEYS`] is what `colloidsim keys bd` lists and what a scenario is
//! checked against; `params.rs` reads each key through its declaration. (Each constant's
//! documentation is its declaration's `doc`.)
#![allow(missing_docs)]

use crate::keys::Allowed::*;
use crate::keys::Omitted::*;
use crate::keys::shared::{
    DIAMETER, HYDRO_MAX_ITERATIONS, HYDRO_MODEL, HYDRO_SPLITTING, HYDRO_TOLERANCE, HYDRODYNAMICS,
    KT, RUN_DT, RUN_INTEGRATOR, RUN_SKIN, RUN_TUNE_SKIN, TRAJECTORY, TRAJECTORY_EVERY, VISCOSITY,
};
use crate::keys::species::*;
use crate::keys::{SEED_KEY, Spec, key};

pub const METHOD: Spec = key("method", "-", Required, OneOf(&["bd"]),
    "Brownian dynamics of spheres (one or more species, WCA or [pair]) in a periodic cube, free draining or with RPY (PSE)");

pub const REPLICAS: Spec = key("replicas", "-", Value("1"), Integer(1, 1_000_000),
    "independent systems run one after the other, their blocks pooled (replica r: initial stream r, noise keyed by (seed, step, r, block))");

pub const SYSTEM: Spec = key("system", "-", Required, Table,
    "spheres, solvent, the periodic cube and the body force");

pub const SYSTEM_PARTICLES: Spec = key("system.particles", "-", Required, Integer(1, 100_000_000),
    "number of spheres N (of all species)");

pub const SYSTEM_BOX_LENGTH: Spec = key("system.box_length", "length", Required, Positive,
    "edge L of the periodic cube")
    .also("phi = sum_s N_s pi d_s^3 / (6 L^3) at most 0.3 (random insertion; 0.64 with system.initial); L > 2 (2^(1/6) d + run.skin); with RPY the PSE cut-off below L/2");

pub const SYSTEM_BODY_FORCE: Spec = key("system.body_force", "energy / length",
    Value("[0, 0, 0]"), Numbers(f64::MIN, f64::MAX, Some(3)),
    "constant force F on a sphere of diameter d (gravity less buoyancy), F (d_s / d)^3 on one of species s (the same density): the mean velocity along it gives K = U / (mu0 F), each species' U_s / (mu_s F_s)")
    .also("its drift F dt / (3 pi eta d) at most 0.1 d per step (of the largest species, relative to its diameter)");

pub const SYSTEM_INITIAL: Spec = key("system.initial", "-", Means("random insertion"), Path,
    "start every replica from the last frame of this GSD file (HOOMD schema) instead of random insertion")
    .also("must hold system.particles spheres, with the typeids and counts of system.species (typeid 0 for one), in a cube of edge system.box_length");

pub const RUN: Spec = key("run", "-", Required, Table, "time stepping");

pub const RUN_TIME: Spec = key("run.time", "time", Required, Positive,
    "sampled time per replica (rounded up to whole blocks)")
    .also("at least 4 steps per block; at most 1e12 steps");

pub const RUN_EQUILIBRATE: Spec = key("run.equilibrate", "time", Value("0"), NonNegative,
    "time run before sampling starts (random insertion is the hard-sphere equilibrium to first order in phi)");

pub const OBSERVE: Spec = key("observe", "-", Means("defaults"), Table, "what to measure");

pub const OBSERVE_BLOCKS: Spec = key("observe.blocks", "-", Value("8"), Integer(1, 10_000),
    "blocks per replica of the sampled time; every error is the standard error of the block values, given with at least 8 blocks in all");

pub const OBSERVE_MSD: Spec = key("observe.msd", "-",
    Means("30 lags up to a quarter of a block"), Table,
    "mean-square displacement of the unwrapped positions (about the centre of mass under a body force), and of each species: msd.csv, msd.png");

pub const OBSERVE_MSD_POINTS: Spec = key("observe.msd.points", "-", Value("30"), Integer(2, 1000),
    "log-spaced lags from one step to max_lag");

pub const OBSERVE_MSD_MAX_LAG: Spec = key("observe.msd.max_lag", "time",
    Means("a quarter of a block (at least 4 run.dt)"), Positive,
    "longest lag T; D is the slope of the MSD between T/4 and T")
    .also("in [4 run.dt, run.time / observe.blocks]");

pub const HYDRO_METHOD: Spec = key("hydrodynamics.method", "-", Word("pse"), OneOf(&["pse"]),
    "RPY in the periodic cube by positively split Ewald (\"direct\" is the unbounded fluid: refused here)")
    .also("model = \"rpy\" only");

/// The keys of `bd` scenarios, in the order `colloidsim keys bd` lists them.
pub static KEYS: &[Spec] = keys_with_pair!(
    [
        METHOD,
        SEED_KEY,
        REPLICAS,
        SYSTEM,
        SYSTEM_PARTICLES,
        SYSTEM_BOX_LENGTH,
        DIAMETER,
        SPECIES,
        SPECIES_DIAMETERS,
        SPECIES_COUNTS,
        SPECIES_VOLUME_FRACTIONS,
        KT,
        VISCOSITY,
        SYSTEM_BODY_FORCE,
        SYSTEM_INITIAL,
    ],
    PAIR,
    [
        RUN,
        RUN_TIME,
        RUN_DT,
        RUN_EQUILIBRATE,
        RUN_SKIN,
        RUN_TUNE_SKIN,
        RUN_INTEGRATOR,
        OBSERVE,
        crate::keys::shared::FIGURE_FORMAT,
        OBSERVE_BLOCKS,
        OBSERVE_MSD,
        OBSERVE_MSD_POINTS,
        OBSERVE_MSD_MAX_LAG,
        TRAJECTORY,
        TRAJECTORY_EVERY,
        HYDRODYNAMICS,
        HYDRO_MODEL,
        HYDRO_METHOD,
        HYDRO_TOLERANCE,
        HYDRO_SPLITTING,
        HYDRO_MAX_ITERATIONS,
    ]
);
