//! Every key of `bcd` scenarios, declared once: unit, default, allowed values and meaning.
//! [`KEYS`] is what `colloidsim keys bcd` lists and what a scenario is checked against;
//! `params.rs` reads each key through its declaration. (Each constant's documentation is its
//! declaration's `doc`, which `colloidsim keys` prints.)
#![allow(missing_docs)]

use crate::keys::Allowed::*;
use crate::keys::Omitted::*;
use crate::keys::{COUNT, MAX_BINS_1D, SEED_RANGE, Spec, key};

pub const METHOD: Spec = key("method", "-", Required, OneOf(&["bcd", "bcd-chronological"]),
    "premerging BCD, O(N) per step, or the chronological event-driven update, O(N^2) (test oracle)");

pub const SEED: Spec = key("seed", "-", Value("1"), SEED_RANGE,
    "seed of all random streams (--seed overrides)");

pub const SYSTEM: Spec = key("system", "-", Required, Table, "the rods and their ring or channel");

pub const SYSTEM_LENGTH: Spec = key("system.length", "length", Required, Positive,
    "L: ring circumference or distance between the walls")
    .also("a whole number of potential periods on a ring");

pub const SYSTEM_PARTICLES: Spec = key("system.particles", "-", Required, Integer(1, COUNT),
    "N, the number of rods")
    .also("N diameter < length");

pub const SYSTEM_DIAMETER: Spec = key("system.diameter", "length", Required, Positive,
    "rod length sigma (the hard core)");

pub const SYSTEM_MOBILITY: Spec = key("system.mobility", "length^2 / (energy time)",
    Value("1"), Positive,
    "mu; D = mu kT");

pub const SYSTEM_KT: Spec = key("system.kT", "energy", Value("1"), NonNegative,
    "thermal energy; 0 gives deterministic cluster dynamics");

pub const SYSTEM_BOUNDARY: Spec = key("system.boundary", "-",
    Word("periodic"), OneOf(&["periodic", "walls"]),
    "a ring, or hard walls at 0 and L (centres in [sigma/2, L - sigma/2])");

pub const POTENTIAL: Spec = key("potential", "-", Means("none"), Table,
    "external potential: the sum of the terms given");

pub const POTENTIAL_COSINE: Spec = key("potential.cosine", "-", Means("none"), Table,
    "U = (U0/2) cos(2 pi x / lambda)");

pub const POTENTIAL_COSINE_AMPLITUDE: Spec = key("potential.cosine.amplitude", "energy",
    Required, Finite,
    "U0, peak to peak");

pub const POTENTIAL_COSINE_WAVELENGTH: Spec = key("potential.cosine.wavelength", "length",
    Required, Positive,
    "lambda");

pub const POTENTIAL_DRIVE: Spec = key("potential.drive", "energy / length", Value("0"), Finite,
    "constant force f (tilted washboard; the system then has no equilibrium)");

pub const POTENTIAL_HARMONIC: Spec = key("potential.harmonic", "-", Means("none"), Table,
    "U = k/2 (x - x0)^2 (minimum image on a ring)");

pub const POTENTIAL_HARMONIC_STIFFNESS: Spec = key("potential.harmonic.stiffness", "energy / length^2",
    Required, NonNegative,
    "k");

pub const POTENTIAL_HARMONIC_CENTRE: Spec = key("potential.harmonic.centre", "length",
    Derived("L/2", |r| Ok(0.5 * r.number(&SYSTEM_LENGTH)?)), Finite,
    "x0");

pub const POTENTIAL_FOURIER: Spec = key("potential.fourier", "-", Means("none"), Table,
    "U = sum_n a_n cos(2 pi n x / lambda) + b_n sin(2 pi n x / lambda)");

pub const POTENTIAL_FOURIER_WAVELENGTH: Spec = key("potential.fourier.wavelength", "length",
    Required, Positive,
    "lambda, the fundamental period");

pub const POTENTIAL_FOURIER_COS: Spec = key("potential.fourier.cos", "energy",
    Value("[]"), Numbers(f64::MIN, f64::MAX, None),
    "a_1, a_2, ...")
    .also("at most 256 terms (finer shapes: potential.table)");

pub const POTENTIAL_FOURIER_SIN: Spec = key("potential.fourier.sin", "energy",
    Value("[]"), Numbers(f64::MIN, f64::MAX, None),
    "b_1, b_2, ...")
    .also("at most 256 terms (finer shapes: potential.table)");

pub const POTENTIAL_TABLE: Spec = key("potential.table", "-", Means("none"), Path,
    "CSV with columns x,U over exactly one period (last U equal to the first); periodic cubic spline");

pub const INTERACTION: Spec = key("interaction", "-", Means("hard rods"), Table,
    "pair interactions beyond the hard core");

pub const INTERACTION_STICKY: Spec = key("interaction.sticky", "-", Means("none"), Table,
    "Baxter adhesion by the power law of the hard-rods paper's Eq. (33) on [sigma, sigma + eps]");

pub const INTERACTION_STICKY_GAMMA: Spec = key("interaction.sticky.gamma", "-", Required, Positive,
    "stickiness gamma")
    .also("run.dt must satisfy Eq. (34): mu max|f| dt < eps");

pub const INTERACTION_STICKY_RANGE: Spec = key("interaction.sticky.range", "length",
    Value("0.05"), Positive,
    "virtual range eps")
    .plausible();

pub const INTERACTION_STICKY_ORDER: Spec = key("interaction.sticky.order", "-",
    Value("3"), Closed(1.0, 100.0),
    "power p");

pub const INTERACTION_YUKAWA: Spec = key("interaction.yukawa", "-", Means("none"), Table,
    "U = A exp(-(r - sigma)/l), force-shifted at the cut-off");

pub const INTERACTION_YUKAWA_STRENGTH: Spec = key("interaction.yukawa.strength", "energy",
    Required, Finite,
    "A, the energy at contact")
    .also("mu |A| / l run.dt at most system.length");

pub const INTERACTION_YUKAWA_SCREENING: Spec = key("interaction.yukawa.screening", "length",
    Required, Positive,
    "l");

pub const INTERACTION_YUKAWA_CUTOFF: Spec = key("interaction.yukawa.cutoff", "length",
    Required, Positive,
    "cut-off rc (centre distance)")
    .also("> diameter");

pub const INTERACTION_TABLE: Spec = key("interaction.table", "-", Means("none"), Path,
    "CSV with columns r,f (pair force, positive repulsive), linear interpolation, last f = 0");

pub const INITIAL: Spec = key("initial", "-", Means("random placement"), Table,
    "the initial configuration");

pub const INITIAL_PLACEMENT: Spec = key("initial.placement", "-",
    Word("random"), OneOf(&["random", "lattice", "file"]),
    "random (the exact hard-rod equilibrium without field), a lattice, or a file");

pub const INITIAL_FILE: Spec = key("initial.file", "-", Means("none"), Path,
    "CSV with a column x (e.g. an earlier run's final_configuration.csv)")
    .also("needs placement = \"file\"");

pub const RUN: Spec = key("run", "-", Required, Table, "time stepping");

pub const RUN_DT: Spec = key("run.dt", "time", Required, Positive, "time step");

pub const RUN_INTEGRATOR: Spec = key("run.integrator", "-", Word("euler"), OneOf(&["euler", "lm", "reflect"]),
    "free motion: Euler-Maruyama, Leimkuhler-Matthews (noise (xi_n + xi_n+1)/2, second order for the forces, the same collisions), or reflect (elastic collisions, no boundary layer, with LM in its Markov form; needs kT > 0, no sticky rods, no cluster statistics, method bcd); see docs/bcd.md");

pub const RUN_EQUILIBRATE: Spec = key("run.equilibrate", "time", Value("0"), NonNegative,
    "time run before sampling");

pub const RUN_TIME: Spec = key("run.time", "time", Required, Positive, "sampled time");

pub const RUN_CHECKPOINT_EVERY: Spec = key("run.checkpoint_every", "steps",
    Means("10 % of the run (at least 1000)"), Integer(1, COUNT),
    "steps between checkpoints");

pub const OBSERVE: Spec = key("observe", "-", Means("no observables"), Table, "what to measure");

pub const OBSERVE_EVERY: Spec = key("observe.every", "steps", Value("1"), Integer(1, COUNT),
    "steps between samples of density, contact density and clusters");

pub const OBSERVE_DENSITY: Spec = key("observe.density", "-", Means("off"), Table,
    "density histogram over one period of the potential (or over L): density.csv");

pub const OBSERVE_DENSITY_BINS: Spec = key("observe.density.bins", "-",
    Required, Integer(1, MAX_BINS_1D),
    "number of bins");

pub const OBSERVE_CONTACT_DENSITY: Spec = key("observe.contact_density", "-", Means("off"), Table,
    "two-particle density at contact (hard-rods paper Eq. 27): contact_density.csv");

pub const OBSERVE_CONTACT_DENSITY_BINS: Spec = key("observe.contact_density.bins", "-",
    Required, Integer(1, MAX_BINS_1D),
    "number of bins");

pub const OBSERVE_CONTACT_DENSITY_WINDOW: Spec = key("observe.contact_density.window", "length",
    Required, Positive,
    "contact window Delta'")
    .also("at least 1e-9 system.length")
    .plausible();

pub const OBSERVE_MSD: Spec = key("observe.msd", "-", Means("off"), Table,
    "mean-square displacement at log-spaced lags: msd.csv");

pub const OBSERVE_MSD_POINTS: Spec = key("observe.msd.points", "-",
    Value("40"), Integer(2, 100_000),
    "number of lag times");

pub const OBSERVE_MSD_MAX_LAG: Spec = key("observe.msd.max_lag", "time",
    Derived("run.time / 2", |r| Ok(0.5 * r.number(&RUN_TIME)?)), Positive,
    "longest lag")
    .also("in [run.dt, run.time]");

pub const OBSERVE_CURRENT: Spec = key("observe.current", "-", Value("false"), Bool,
    "mean displacement and particle current: current.csv");

pub const OBSERVE_CLUSTERS: Spec = key("observe.clusters", "-", Value("false"), Bool,
    "cluster-size distribution: clusters.csv");

pub const OBSERVE_TRAJECTORY: Spec = key("observe.trajectory", "-", Means("off"), Table,
    "GSD frames: trajectory.gsd");

pub const OBSERVE_TRAJECTORY_EVERY: Spec = key("observe.trajectory.every", "steps",
    Required, Integer(1, COUNT),
    "steps between frames, the first at the first production step");

pub const OBSERVE_TRAJECTORY_EQUILIBRATION: Spec = key("observe.trajectory.equilibration", "-",
    Value("false"), Bool,
    "also write frames during equilibration (every `every` steps from step 0)");

/// The keys of `bcd` scenarios, in the order `colloidsim keys bcd` lists them.
pub static KEYS: &[Spec] = &[
    METHOD,
    SEED,
    SYSTEM,
    SYSTEM_LENGTH,
    SYSTEM_PARTICLES,
    SYSTEM_DIAMETER,
    SYSTEM_MOBILITY,
    SYSTEM_KT,
    SYSTEM_BOUNDARY,
    POTENTIAL,
    POTENTIAL_COSINE,
    POTENTIAL_COSINE_AMPLITUDE,
    POTENTIAL_COSINE_WAVELENGTH,
    POTENTIAL_DRIVE,
    POTENTIAL_HARMONIC,
    POTENTIAL_HARMONIC_STIFFNESS,
    POTENTIAL_HARMONIC_CENTRE,
    POTENTIAL_FOURIER,
    POTENTIAL_FOURIER_WAVELENGTH,
    POTENTIAL_FOURIER_COS,
    POTENTIAL_FOURIER_SIN,
    POTENTIAL_TABLE,
    INTERACTION,
    INTERACTION_STICKY,
    INTERACTION_STICKY_GAMMA,
    INTERACTION_STICKY_RANGE,
    INTERACTION_STICKY_ORDER,
    INTERACTION_YUKAWA,
    INTERACTION_YUKAWA_STRENGTH,
    INTERACTION_YUKAWA_SCREENING,
    INTERACTION_YUKAWA_CUTOFF,
    INTERACTION_TABLE,
    INITIAL,
    INITIAL_PLACEMENT,
    INITIAL_FILE,
    RUN,
    RUN_DT,
    RUN_INTEGRATOR,
    RUN_EQUILIBRATE,
    RUN_TIME,
    RUN_CHECKPOINT_EVERY,
    OBSERVE,
    crate::keys::shared::FIGURE_FORMAT,
    OBSERVE_EVERY,
    OBSERVE_DENSITY,
    OBSERVE_DENSITY_BINS,
    OBSERVE_CONTACT_DENSITY,
    OBSERVE_CONTACT_DENSITY_BINS,
    OBSERVE_CONTACT_DENSITY_WINDOW,
    OBSERVE_MSD,
    OBSERVE_MSD_POINTS,
    OBSERVE_MSD_MAX_LAG,
    OBSERVE_CURRENT,
    OBSERVE_CLUSTERS,
    OBSERVE_TRAJECTORY,
    OBSERVE_TRAJECTORY_EVERY,
    OBSERVE_TRAJECTORY_EQUILIBRATION,
];
