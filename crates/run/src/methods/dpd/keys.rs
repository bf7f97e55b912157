//! Every key of `dpd` scenarios, declared once: unit, default, allowed values and meaning.
//! [`KEYS`] is what `colloidsim keys dpd` lists and what a scenario is checked against;
//! `params.rs` reads each key through its declaration. (Each constant's documentation is its
//! declaration's `doc`, which `colloidsim keys` prints.)
#![allow(missing_docs)]

use crate::keys::Allowed::*;
use crate::keys::Omitted::*;
use crate::keys::{COUNT, Reader, SEED_KEY, Spec, key};
use anyhow::Result;

/// The shortest box edge: `system.box_length`, or the least of `system.box_edges`.
pub(super) fn shortest_edge(r: &Reader) -> Result<f64> {
    match r.opt_number(&SYSTEM_BOX_LENGTH)? {
        Some(l) => Ok(l),
        None => Ok(r
            .numbers(&SYSTEM_BOX_EDGES)?
            .into_iter()
            .fold(f64::INFINITY, f64::min)),
    }
}

pub const METHOD: Spec = key("method", "-", Required, OneOf(&["dpd"]),
    "DPD colloids in explicit solvent");

pub const SEED: Spec = SEED_KEY;

pub const SYSTEM: Spec = key("system", "-", Required, Table, "box, solvent and colloids");

pub const SYSTEM_BOX_LENGTH: Spec = key("system.box_length", "rc",
    Means("give box_length or box_edges"), Positive,
    "cube edge")
    .also("each edge must hold 3 neighbour cells and twice the colloid range");

pub const SYSTEM_BOX_EDGES: Spec = key("system.box_edges", "rc",
    Means("give box_length or box_edges"), Numbers(0.0, f64::MAX, Some(3)),
    "[Lx, Ly, Lz]")
    .also("each > 0, the same conditions as box_length");

pub const SYSTEM_DENSITY: Spec = key("system.density", "1/rc^3", Value("3"), Closed(1e-3, 20.0),
    "solvent beads per volume the colloids leave free");

pub const SYSTEM_PHI: Spec = key("system.phi", "-", Value("0"), Closed(0.0, 0.35),
    "colloid volume fraction (random insertion)");

pub const SYSTEM_KT: Spec = key("system.kT", "energy", Value("0.1"), Positive, "thermal energy");

pub const SYSTEM_COLLOID_RADIUS: Spec = key("system.colloid_radius", "rc", Value("1"), Positive,
    "mean colloid radius R_c");

pub const SYSTEM_RADIUS_DISTRIBUTION: Spec = key("system.radius_distribution", "-",
    Word("monodisperse"), OneOf(&["monodisperse", "gaussian", "lognormal", "uniform"]),
    "distribution of the colloid radii (gaussian truncated at +-3 sd)");

pub const SYSTEM_RADIUS_SPREAD: Spec = key("system.radius_spread", "-",
    Value("0"), Closed(0.0, 0.5),
    "relative sd (gaussian, lognormal) or half-width (uniform)");

pub const SYSTEM_SOLVENT_MASS: Spec = key("system.solvent_mass", "bead mass", Value("1"), Positive,
    "m_s (colloid mass: 4/3 pi R^3 density m_s)");

pub const DPD: Spec = key("dpd", "-", Means("defaults"), Table, "DPD pair forces");

pub const DPD_CUTOFF: Spec = key("dpd.cutoff", "rc", Value("1"), Positive,
    "solvent cut-off rc (the length unit)");

pub const DPD_REPULSION: Spec = key("dpd.repulsion", "kT / rc", Value("25"), NonNegative,
    "solvent-solvent conservative amplitude a");

pub const DPD_REPULSION_COLLOID_SOLVENT: Spec = key("dpd.repulsion_colloid_solvent", "kT / rc'",
    Value("25"), NonNegative,
    "colloid-solvent amplitude a_cs");

pub const DPD_GAMMA: Spec = key("dpd.gamma", "mass / time", Value("4.5"), LeftOpen(0.0, 200.0),
    "dissipation gamma (below 4.5: a warning)");

pub const COLLOIDS: Spec = key("colloids", "-", Means("defaults"), Table, "colloid-colloid forces");

pub const COLLOIDS_CUTOFF: Spec = key("colloids.cutoff", "rc", Value("1"), Positive,
    "colloid-colloid surface cut-off")
    .also("> contact_range");

pub const COLLOIDS_CONTACT: Spec = key("colloids.contact", "kT / rc", Value("10000"), NonNegative,
    "contact modulus f_contact");

pub const COLLOIDS_CONTACT_RANGE: Spec = key("colloids.contact_range", "rc",
    Value("0.001"), Positive,
    "contact range Delta");

pub const COLLOIDS_MORSE_DEPTH: Spec = key("colloids.morse_depth", "kT", Value("0"), NonNegative,
    "Morse depth D0 (0: no attraction; ~12 for gels)");

pub const COLLOIDS_MORSE_KAPPA: Spec = key("colloids.morse_kappa", "1/rc", Value("30"), Positive,
    "Morse kappa");

pub const COLLOIDS_MORSE_R0: Spec = key("colloids.morse_r0", "rc", Value("0"), NonNegative,
    "Morse r0")
    .also("<= colloids.cutoff");

pub const COLLOIDS_ETA0: Spec = key("colloids.eta0", "mass / (rc time)", Value("0.3"), Positive,
    "background viscosity of the squeeze lubrication (and the time unit)");

pub const COLLOIDS_LUBRICATION: Spec = key("colloids.lubrication", "-", Value("true"), Bool,
    "squeeze lubrication on or off");

pub const COLLOIDS_LUBRICATION_GAP: Spec = key("colloids.lubrication_gap", "rc",
    Value("0.001"), Positive,
    "smallest gap delta of the lubrication")
    .also("< colloids.cutoff");

pub const COLLOIDS_LUBRICATION_NOISE: Spec = key("colloids.lubrication_noise", "-",
    Word("exact"), OneOf(&["exact", "authors"]),
    "the lubrication pair's own noise (exact equilibrium) or the authors' weighted noise");

pub const RUN: Spec = key("run", "-", Means("defaults"), Table, "time stepping");

pub const RUN_DT: Spec = key("run.dt", "DPD time", Value("0.001"), Positive, "time step")
    .also("at least 1e-6");

pub const RUN_STEPS: Spec = key("run.steps", "-", Value("10000"), Integer(0, COUNT), "steps");

pub const RUN_SKIN: Spec = key("run.skin", "rc", Value("0.4"), Closed(0.05, 2.0),
    "neighbour-list skin");

pub const RUN_TUNE_SKIN: Spec = key("run.tune_skin", "-", Value("false"), Bool,
    "choose the neighbour search from measured step times before the run (cells every step, or Verlet lists with skins 0.1-0.8 rc; each on a discarded copy of the start): run.skin and run.neighbors are then ignored, the choice and every candidate's time are in summary.json and the checkpoint (a rerun with run.skin and run.neighbors set to them is bitwise the same run); one process");

pub const RUN_MAX_TEMPERATURE_DRIFT: Spec = key("run.max_temperature_drift", "-",
    Value("0.1"), LeftOpen(0.0, 10.0),
    "stop when the window-averaged kinetic temperature differs from kT by more than this fraction");

pub const RUN_TEMPERATURE_WINDOW: Spec = key("run.temperature_window", "steps",
    Value("1000"), Integer(1, COUNT),
    "window of that check");

pub const RUN_NEIGHBORS: Spec = key("run.neighbors", "-",
    Word("auto"), OneOf(&["auto", "verlet", "cells"]),
    "how solvent pairs are found: Verlet lists, cells every step, or chosen by the list lifetime");

pub const RUN_SHEAR_RATE: Spec = key("run.shear_rate", "1 / DPD time",
    Value("0"), Closed(0.0, 10.0),
    "Lees-Edwards shear rate gamma_dot: flow along x, gradient along y (0: no shear); the run reports the shear stress, the viscosity and velocity_profile.csv");

pub const RUN_RANK_GRID: Spec = key("run.rank_grid", "ranks",
    Means("unset"), Numbers(1.0, 1e6, Some(2)),
    "MPI runs: the grid [py, pz] of ranks, columns along y by slabs along z, product the number of ranks (unset: the grid with the fewest ghost cells; slabs when sheared); the run is bitwise the same on any grid");

pub const OBSERVE: Spec = key("observe", "-", Means("defaults"), Table, "what to measure");

pub const OBSERVE_THERMO_EVERY: Spec = key("observe.thermo_every", "steps",
    Value("100"), Integer(0, COUNT),
    "steps between rows of thermo.csv (0: none)");

pub const OBSERVE_TRAJECTORY_EVERY: Spec = key("observe.trajectory_every", "steps",
    Value("1000"), Integer(0, COUNT),
    "steps between GSD frames (0: none)");

pub const OBSERVE_MSD_EVERY: Spec = key("observe.msd_every", "steps",
    Value("100"), Integer(0, COUNT),
    "steps between the positions kept for msd.csv (0: none)");

pub const OBSERVE_MSD_SOLVENT_BEADS: Spec = key("observe.msd_solvent_beads", "-",
    Value("1000"), Integer(0, 100_000_000),
    "solvent beads followed for the solvent MSD");

pub const OBSERVE_STRUCTURE_EVERY: Spec = key("observe.structure_every", "steps",
    Value("1000"), Integer(0, COUNT),
    "steps between g(r), S(q), contacts and clusters (0: none)");

pub const OBSERVE_GR_BINS: Spec = key("observe.gr_bins", "-", Value("200"), Integer(2, 100_000),
    "bins of g(r) (at least 2: S(q) needs two)")
    .also("at most 1e5: bins of 1e-3 rc over the widest range, finer than the contact range; S(q) takes at most 1000 wave numbers");

pub const OBSERVE_GR_MAX: Spec = key("observe.gr_max", "rc",
    Derived("0.49 L", |r| Ok(0.49 * shortest_edge(r)?)), Positive,
    "range of g(r)")
    .also("at most half the shortest box edge (the default stays under it: freud's RDF refuses L/2)");

pub const OBSERVE_CONTACT_GAP: Spec = key(
    "observe.contact_gap",
    "rc",
    Derived("3 / morse_kappa", |r| {
        Ok(3.0 / r.number(&COLLOIDS_MORSE_KAPPA)?)
    }),
    Positive,
    "a contact is a surface gap below this",
);

pub const OBSERVE_VISCOSITY_EVERY: Spec = key("observe.viscosity_every", "steps",
    Value("0"), Integer(0, COUNT),
    "steps averaged into one pressure-tensor sample of the Green-Kubo viscosity, stress_acf.csv (0: off)");

pub const OBSERVE_VISCOSITY_TIME: Spec = key("observe.viscosity_time", "DPD time",
    Value("5"), Positive,
    "longest lag of the stress autocorrelation, the upper limit of the Green-Kubo integral")
    .also("at least one sample interval viscosity_every x dt, at most 100000 of them");

pub const OBSERVE_PROFILE_BINS: Spec = key("observe.profile_bins", "-",
    Value("16"), Integer(1, 1000),
    "bins along y of velocity_profile.csv (shear runs)");

/// The keys of `dpd` scenarios, in the order `colloidsim keys dpd` lists them.
pub static KEYS: &[Spec] = &[
    METHOD,
    SEED,
    SYSTEM,
    SYSTEM_BOX_LENGTH,
    SYSTEM_BOX_EDGES,
    SYSTEM_DENSITY,
    SYSTEM_PHI,
    SYSTEM_KT,
    SYSTEM_COLLOID_RADIUS,
    SYSTEM_RADIUS_DISTRIBUTION,
    SYSTEM_RADIUS_SPREAD,
    SYSTEM_SOLVENT_MASS,
    DPD,
    DPD_CUTOFF,
    DPD_REPULSION,
    DPD_REPULSION_COLLOID_SOLVENT,
    DPD_GAMMA,
    COLLOIDS,
    COLLOIDS_CUTOFF,
    COLLOIDS_CONTACT,
    COLLOIDS_CONTACT_RANGE,
    COLLOIDS_MORSE_DEPTH,
    COLLOIDS_MORSE_KAPPA,
    COLLOIDS_MORSE_R0,
    COLLOIDS_ETA0,
    COLLOIDS_LUBRICATION,
    COLLOIDS_LUBRICATION_GAP,
    COLLOIDS_LUBRICATION_NOISE,
    RUN,
    RUN_DT,
    RUN_STEPS,
    RUN_SKIN,
    RUN_TUNE_SKIN,
    RUN_MAX_TEMPERATURE_DRIFT,
    RUN_TEMPERATURE_WINDOW,
    RUN_NEIGHBORS,
    RUN_SHEAR_RATE,
    RUN_RANK_GRID,
    OBSERVE,
    crate::keys::shared::FIGURE_FORMAT,
    OBSERVE_THERMO_EVERY,
    OBSERVE_TRAJECTORY_EVERY,
    OBSERVE_MSD_EVERY,
    OBSERVE_MSD_SOLVENT_BEADS,
    OBSERVE_STRUCTURE_EVERY,
    OBSERVE_GR_BINS,
    OBSERVE_GR_MAX,
    OBSERVE_CONTACT_GAP,
    OBSERVE_VISCOSITY_EVERY,
    OBSERVE_VISCOSITY_TIME,
    OBSERVE_PROFILE_BINS,
];
