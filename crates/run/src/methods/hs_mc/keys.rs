//! Every key of `hs-mc` scenarios, declared once (the `[interface]` section is shared with
//! droplet-bd and droplet-mpcd: `crate::keys::shared`). [`KEYS`] is what `colloidsim keys hs-mc`
//! lists and what a scenario is checked against; `params.rs` reads each key through its
//! declaration. (Each constant's documentation is its declaration's `doc`.)
#![allow(missing_docs)]

use crate::keys::Allowed::*;
use crate::keys::Omitted::*;
use crate::keys::shared::{INTERFACE, INTERFACE_OFFSET, INTERFACE_RANGE, INTERFACE_STIFFNESS};
use crate::keys::species::{SPECIES, SPECIES_COUNTS, SPECIES_DIAMETERS, SPECIES_VOLUME_FRACTIONS};
use crate::keys::species::{PAIR, keys_with_pair};
use crate::keys::{COUNT, MAX_BINS_RADIAL, SEED_KEY, Spec, key};

pub const METHOD: Spec = key("method", "-", Required, OneOf(&["hs-mc"]),
    "hard-sphere NVT Monte Carlo, checkerboard cells (docs/mc.md)");

pub const SYSTEM: Spec = key("system", "-", Required, Table, "spheres and container");

pub const SYSTEM_GEOMETRY: Spec = key("system.geometry", "-",
    Required, OneOf(&["bulk", "hard-wall", "interface"]),
    "periodic cube; hard spherical wall (centres within radius - d/2); the BD droplet's harmonic interface ([interface])");

pub const SYSTEM_PARTICLES: Spec = key("system.particles", "-",
    Means("from the other two"), Integer(1, 100_000_000),
    "number of spheres N")
    .also("give exactly two of particles, volume_fraction and box (bulk) or radius (droplet); at least 2 in bulk; required with system.species");

pub const SYSTEM_VOLUME_FRACTION: Spec = key("system.volume_fraction", "-",
    Means("from the other two"), LeftOpen(0.0, colloidsim_mc::params::MAX_PHI),
    "N pi d^3 / (6 L^3) in bulk, N d^3 / (8 R^3) in a droplet (a mixture: summed over species); at most random close packing");

pub const SYSTEM_DIAMETER: Spec = key("system.diameter", "length",
    Derived("1; with system.species, the smallest of its diameters",
        |r| Ok(crate::keys::species::smallest_diameter(r)?.unwrap_or(1.0))),
    Positive,
    "sphere diameter d");

pub const SYSTEM_RADIUS: Spec = key("system.radius", "length",
    Means("from the other two"), Positive,
    "droplet radius R (hard-wall, interface)")
    .also("above d/2; not with geometry = \"bulk\"");

pub const SYSTEM_BOX: Spec = key("system.box", "length", Means("from the other two"), Positive,
    "edge L of the periodic cube (bulk)")
    .also("at least 2 d; bulk only");

pub const SYSTEM_KT: Spec = key("system.kT", "energy", Value("1"), Positive,
    "thermal energy (the interface's stiffness is in energy / length^2)");

pub const SYSTEM_INITIAL: Spec = key("system.initial", "-", Means("FCC lattice"), Path,
    "start from the last frame of this GSD file")
    .also("N spheres, no overlap, centres inside the wall");

/// `[pair]` as the BD methods declare it, in place of the hard cores.
pub const MC_PAIR: Spec = Spec {
    default: Means("hard spheres: additive cores at each pair's mean diameter"),
    doc: "a pair interaction of every species pair in place of the hard cores: the spheres sample exp(-U/kT), U as BD integrates it (docs/mc.md, \"Pair interactions\")",
    also: "local moves only; its range at most half the box (bulk) or 8 of the largest diameters (droplets)",
    ..PAIR
};

pub const MC: Spec = key("mc", "-", Means("-"), Table, "sweeps, warm-up and tuning");

pub const MC_SWEEPS: Spec = key("mc.sweeps", "sweeps", Value("10000"), Integer(1, COUNT),
    "sampling sweeps (nselect N trial moves each) after the warm-up");

pub const MC_NSELECT: Spec = key("mc.nselect", "-",
    Value("1"), Integer(1, colloidsim_mc::params::NSELECT_MAX as i64),
    "trial moves per sphere per sweep, all on one binning of the cells (HOOMD-blue's nselect; docs/mc.md)");

pub const MC_MOVE: Spec = key("mc.move", "-",
    Word("local"), OneOf(&["local", "event-chain"]),
    "local: single-sphere Metropolis displacements; event-chain: rejection-free event chains (Bernard, Krauth & Wilson 2009), with the exact pressure in bulk (docs/mc.md)");

pub const MC_CHAIN_LENGTH: Spec = key("mc.chain_length", "length",
    Means("N^(1/3) d / 2"), Positive,
    "displacement of one event chain (event-chain only); a sweep is max(1, round(N lambda / chain_length)) chains, lambda the Carnahan-Starling free path between lifts, about N lifts")
    .also("at most 1e6 d");

pub const MC_WARMUP_SWEEPS: Spec = key("mc.warmup_sweeps", "sweeps",
    Value("2000"), Integer(0, COUNT),
    "warm-up sweeps, delta tuned every tune_every, then frozen");

pub const MC_TARGET_ACCEPTANCE: Spec = key("mc.target_acceptance", "-",
    Value("0.3"), LeftOpen(0.0, 1.0),
    "acceptance the warm-up tunes delta towards")
    .also("below 1");

pub const MC_TUNE_EVERY: Spec = key("mc.tune_every", "sweeps", Value("100"), Integer(1, COUNT),
    "sweeps between tunings: delta *= acceptance / target (factor in [1/2, 2])");

pub const MC_SAMPLE_EVERY: Spec = key("mc.sample_every", "sweeps", Value("10"), Integer(1, COUNT),
    "sweeps between samples of the observables");

pub const MC_DELTA: Spec = key("mc.delta", "length",
    Derived("d / 10", |r| Ok(0.1 * r.number(&SYSTEM_DIAMETER)?)), Positive,
    "initial half-width of the displacement cube (at most half a cell side)");

pub const MC_BLOCKS: Spec = key("mc.blocks", "-", Value("20"), Integer(2, 100_000),
    "blocks of the sampling sweeps whose scatter gives the standard errors")
    .also("at most sweeps / sample_every");

pub const OUTPUT: Spec = key("output", "-", Means("-"), Table, "observables and files");

pub const OUTPUT_PROFILE_BINS: Spec = key("output.profile_bins", "-",
    Value("50"), Integer(1, MAX_BINS_RADIAL),
    "radial bins between 0 and R (droplets: profile_mean.csv)");

pub const OUTPUT_GR_BINS: Spec = key("output.gr_bins", "-", Value("200"), Integer(1, MAX_BINS_RADIAL),
    "bins of g(r) between 0 and gr_max (bulk: g_r.csv)");

pub const OUTPUT_GR_MAX: Spec = key("output.gr_max", "length", Means("0.49 L"), Positive,
    "range of g(r)")
    .also("above the diameter, at most L/2 (the default stays under it: freud's RDF refuses L/2)");

pub const OUTPUT_TRAJECTORY_EVERY: Spec = key("output.trajectory_every", "sweeps",
    Value("0"), Integer(0, COUNT),
    "sweeps between frames of trajectory.gsd (0: none)");

pub const OUTPUT_RHO2_R_BINS: Spec = key("output.rho2_r_bins", "-", Value("0"), Integer(0, 1000),
    "radial bins over [0, R] of the two-body density rho2(r1, r2, cos theta) and g2 (g2.csv; all pairs, O(N^2) per sample; 0: none)")
    .also("droplets of one species only");

pub const OUTPUT_RHO2_COS_BINS: Spec = key("output.rho2_cos_bins", "-",
    Value("20"), Integer(1, 1000),
    "bins of cos theta over [-1, 1] of the two-body density");

pub const OBSERVE: Spec = key("observe", "-", Means("PNG pictures"), Table,
    "how the pictures are written (the observables are under [output])");

/// The keys of `hs-mc` scenarios, in the order `colloidsim keys hs-mc` lists them.
pub static KEYS: &[Spec] = keys_with_pair!(
    [
        METHOD,
        SEED_KEY,
        SYSTEM,
        SYSTEM_GEOMETRY,
        SYSTEM_PARTICLES,
        SYSTEM_VOLUME_FRACTION,
        SYSTEM_DIAMETER,
        SPECIES,
        SPECIES_DIAMETERS,
        SPECIES_COUNTS,
        SPECIES_VOLUME_FRACTIONS,
        SYSTEM_RADIUS,
        SYSTEM_BOX,
        SYSTEM_KT,
        SYSTEM_INITIAL,
        INTERFACE,
        INTERFACE_STIFFNESS,
        INTERFACE_RANGE,
        INTERFACE_OFFSET.also("above -radius"),
    ],
    MC_PAIR,
    [
        MC,
        MC_SWEEPS,
        MC_NSELECT,
        MC_MOVE,
        MC_CHAIN_LENGTH,
        MC_WARMUP_SWEEPS,
        MC_TARGET_ACCEPTANCE,
        MC_TUNE_EVERY,
        MC_SAMPLE_EVERY,
        MC_DELTA,
        MC_BLOCKS,
        OUTPUT,
        OUTPUT_PROFILE_BINS,
        OUTPUT_GR_BINS,
        OUTPUT_GR_MAX,
        OUTPUT_TRAJECTORY_EVERY,
        OUTPUT_RHO2_R_BINS,
        OUTPUT_RHO2_COS_BINS,
        OBSERVE,
        crate::keys::shared::FIGURE_FORMAT,
    ]
);

