//! The key tables of the methods not yet moved into their folders under `crate::methods`
//! (issue 41): each moves beside its method as the method is converted to read its keys
//! through a [`super::Reader`].

use super::Allowed::*;
use super::Omitted::*;
use super::shared::{
    DIAMETER, HYDRO_MAX_ITERATIONS, HYDRO_MODEL, HYDRO_SPLITTING, HYDRO_TOLERANCE, HYDRODYNAMICS,
    INTERFACE, INTERFACE_OFFSET, INTERFACE_RANGE, INTERFACE_STIFFNESS, KT, RUN_DT, RUN_INTEGRATOR,
    RUN_SKIN, TRAJECTORY, TRAJECTORY_EVERY, VISCOSITY,
};
use super::{COUNT, SEED_KEY, Spec, key};

/// The keys of `bd` scenarios.
pub static BULK: &[Spec] = &[
    key(
        "method",
        "-",
        Required,
        OneOf(&["bd"]),
        "Brownian dynamics of WCA spheres in a periodic cube, free draining or with RPY (PSE)",
    ),
    SEED_KEY,
    key(
        "replicas",
        "-",
        Value("1"),
        Integer(1, 1_000_000),
        "independent systems run one after the other, their blocks pooled (replica r: initial stream r, noise keyed by (seed, step, r, block))",
    ),
    key(
        "system",
        "-",
        Required,
        Table,
        "spheres, solvent, the periodic cube and the body force",
    ),
    key(
        "system.particles",
        "-",
        Required,
        Integer(1, 100_000_000),
        "number of spheres N",
    ),
    key(
        "system.box_length",
        "length",
        Required,
        Positive,
        "edge L of the periodic cube",
    )
    .also("phi = N pi d^3 / (6 L^3) at most 0.3 (random insertion; 0.64 with system.initial); L > 2 (2^(1/6) d + run.skin); with RPY the PSE cut-off below L/2"),
    DIAMETER,
    KT,
    VISCOSITY,
    key(
        "system.body_force",
        "energy / length",
        Value("[0, 0, 0]"),
        Numbers(f64::MIN, f64::MAX, Some(3)),
        "constant force F on every sphere (gravity less buoyancy): the mean velocity along it gives K = U / (mu0 F)",
    )
    .also("its drift F dt / (3 pi eta d) at most 0.1 d per step"),
    key(
        "system.initial",
        "-",
        Means("random insertion"),
        Path,
        "start every replica from the last frame of this GSD file (HOOMD schema) instead of random insertion",
    )
    .also("must hold system.particles spheres of typeid 0 in a cube of edge system.box_length"),
    key("run", "-", Required, Table, "time stepping"),
    key(
        "run.time",
        "time",
        Required,
        Positive,
        "sampled time per replica (rounded up to whole blocks)",
    )
    .also("at least 4 steps per block; at most 1e12 steps"),
    RUN_DT,
    key(
        "run.equilibrate",
        "time",
        Value("0"),
        NonNegative,
        "time run before sampling starts (random insertion is the hard-sphere equilibrium to first order in phi)",
    ),
    RUN_SKIN,
    RUN_INTEGRATOR,
    key("observe", "-", Means("defaults"), Table, "what to measure"),
    key(
        "observe.blocks",
        "-",
        Value("8"),
        Integer(1, 10_000),
        "blocks per replica of the sampled time; every error is the standard error of the block values, given with at least 8 blocks in all",
    ),
    key(
        "observe.msd",
        "-",
        Means("30 lags up to a quarter of a block"),
        Table,
        "mean-square displacement of the unwrapped positions (about the centre of mass under a body force): msd.csv, msd.png",
    ),
    key(
        "observe.msd.points",
        "-",
        Value("30"),
        Integer(2, 1000),
        "log-spaced lags from one step to max_lag",
    ),
    key(
        "observe.msd.max_lag",
        "time",
        Means("a quarter of a block (at least 4 run.dt)"),
        Positive,
        "longest lag T; D is the slope of the MSD between T/4 and T",
    )
    .also("in [4 run.dt, run.time / observe.blocks]"),
    TRAJECTORY,
    TRAJECTORY_EVERY,
    HYDRODYNAMICS,
    HYDRO_MODEL,
    key(
        "hydrodynamics.method",
        "-",
        Word("pse"),
        OneOf(&["pse"]),
        "RPY in the periodic cube by positively split Ewald (\"direct\" is the unbounded fluid: refused here)",
    )
    .also("model = \"rpy\" only"),
    HYDRO_TOLERANCE,
    HYDRO_SPLITTING,
    HYDRO_MAX_ITERATIONS,
];

/// The keys of `dpd` scenarios.
pub static DPD: &[Spec] = &[
    key(
        "method",
        "-",
        Required,
        OneOf(&["dpd"]),
        "DPD colloids in explicit solvent",
    ),
    SEED_KEY,
    key("system", "-", Required, Table, "box, solvent and colloids"),
    key(
        "system.box_length",
        "rc",
        Means("give box_length or box_edges"),
        Positive,
        "cube edge",
    )
    .also("each edge must hold 3 neighbour cells and twice the colloid range"),
    key(
        "system.box_edges",
        "rc",
        Means("give box_length or box_edges"),
        Numbers(0.0, f64::MAX, Some(3)),
        "[Lx, Ly, Lz]",
    )
    .also("each > 0, the same conditions as box_length"),
    key(
        "system.density",
        "1/rc^3",
        Value("3"),
        Closed(1e-3, 20.0),
        "solvent beads per volume the colloids leave free",
    ),
    key(
        "system.phi",
        "-",
        Value("0"),
        Closed(0.0, 0.35),
        "colloid volume fraction (random insertion)",
    ),
    key(
        "system.kT",
        "energy",
        Value("0.1"),
        Positive,
        "thermal energy",
    ),
    key(
        "system.colloid_radius",
        "rc",
        Value("1"),
        Positive,
        "mean colloid radius R_c",
    ),
    key(
        "system.radius_distribution",
        "-",
        Word("monodisperse"),
        OneOf(&["monodisperse", "gaussian", "lognormal", "uniform"]),
        "distribution of the colloid radii (gaussian truncated at +-3 sd)",
    ),
    key(
        "system.radius_spread",
        "-",
        Value("0"),
        Closed(0.0, 0.5),
        "relative sd (gaussian, lognormal) or half-width (uniform)",
    ),
    key(
        "system.solvent_mass",
        "bead mass",
        Value("1"),
        Positive,
        "m_s (colloid mass: 4/3 pi R^3 density m_s)",
    ),
    key("dpd", "-", Means("defaults"), Table, "DPD pair forces"),
    key(
        "dpd.cutoff",
        "rc",
        Value("1"),
        Positive,
        "solvent cut-off rc (the length unit)",
    ),
    key(
        "dpd.repulsion",
        "kT / rc",
        Value("25"),
        NonNegative,
        "solvent-solvent conservative amplitude a",
    ),
    key(
        "dpd.repulsion_colloid_solvent",
        "kT / rc'",
        Value("25"),
        NonNegative,
        "colloid-solvent amplitude a_cs",
    ),
    key(
        "dpd.gamma",
        "mass / time",
        Value("4.5"),
        LeftOpen(0.0, 200.0),
        "dissipation gamma (below 4.5: a warning)",
    ),
    key(
        "colloids",
        "-",
        Means("defaults"),
        Table,
        "colloid-colloid forces",
    ),
    key(
        "colloids.cutoff",
        "rc",
        Value("1"),
        Positive,
        "colloid-colloid surface cut-off",
    )
    .also("> contact_range"),
    key(
        "colloids.contact",
        "kT / rc",
        Value("10000"),
        NonNegative,
        "contact modulus f_contact",
    ),
    key(
        "colloids.contact_range",
        "rc",
        Value("0.001"),
        Positive,
        "contact range Delta",
    ),
    key(
        "colloids.morse_depth",
        "kT",
        Value("0"),
        NonNegative,
        "Morse depth D0 (0: no attraction; ~12 for gels)",
    ),
    key(
        "colloids.morse_kappa",
        "1/rc",
        Value("30"),
        Positive,
        "Morse kappa",
    ),
    key(
        "colloids.morse_r0",
        "rc",
        Value("0"),
        NonNegative,
        "Morse r0",
    )
    .also("<= colloids.cutoff"),
    key(
        "colloids.eta0",
        "mass / (rc time)",
        Value("0.3"),
        NonNegative,
        "background viscosity of the squeeze lubrication (and the time unit)",
    ),
    key(
        "colloids.lubrication",
        "-",
        Value("true"),
        Bool,
        "squeeze lubrication on or off",
    ),
    key(
        "colloids.lubrication_gap",
        "rc",
        Value("0.001"),
        Positive,
        "smallest gap delta of the lubrication",
    )
    .also("< colloids.cutoff"),
    key(
        "colloids.lubrication_noise",
        "-",
        Word("exact"),
        OneOf(&["exact", "authors"]),
        "the lubrication pair's own noise (exact equilibrium) or the authors' weighted noise",
    ),
    key("run", "-", Means("defaults"), Table, "time stepping"),
    key("run.dt", "DPD time", Value("0.001"), Positive, "time step"),
    key("run.steps", "-", Value("10000"), Integer(0, COUNT), "steps"),
    key(
        "run.skin",
        "rc",
        Value("0.4"),
        Closed(0.05, 2.0),
        "neighbour-list skin",
    ),
    key(
        "run.max_temperature_drift",
        "-",
        Value("0.1"),
        LeftOpen(0.0, 10.0),
        "stop when the window-averaged kinetic temperature differs from kT by more than this fraction",
    ),
    key(
        "run.temperature_window",
        "steps",
        Value("1000"),
        Integer(1, COUNT),
        "window of that check",
    ),
    key(
        "run.neighbors",
        "-",
        Word("auto"),
        OneOf(&["auto", "verlet", "cells"]),
        "how solvent pairs are found: Verlet lists, cells every step, or chosen by the list lifetime",
    ),
    key(
        "run.shear_rate",
        "1 / DPD time",
        Value("0"),
        Closed(0.0, 10.0),
        "Lees-Edwards shear rate gamma_dot: flow along x, gradient along y (0: no shear); the run reports the shear stress, the viscosity and velocity_profile.csv",
    ),
    key(
        "run.rank_grid",
        "ranks",
        Means("unset"),
        Numbers(1.0, 1e6, Some(2)),
        "MPI runs: the grid [py, pz] of ranks, columns along y by slabs along z, product the number of ranks (unset: the grid with the fewest ghost cells; slabs when sheared); the run is bitwise the same on any grid",
    ),
    key("observe", "-", Means("defaults"), Table, "what to measure"),
    key(
        "observe.thermo_every",
        "steps",
        Value("100"),
        Integer(0, COUNT),
        "steps between rows of thermo.csv (0: none)",
    ),
    key(
        "observe.trajectory_every",
        "steps",
        Value("1000"),
        Integer(0, COUNT),
        "steps between GSD frames (0: none)",
    ),
    key(
        "observe.msd_every",
        "steps",
        Value("100"),
        Integer(0, COUNT),
        "steps between the positions kept for msd.csv (0: none)",
    ),
    key(
        "observe.msd_solvent_beads",
        "-",
        Value("1000"),
        Integer(0, 100_000_000),
        "solvent beads followed for the solvent MSD",
    ),
    key(
        "observe.structure_every",
        "steps",
        Value("1000"),
        Integer(0, COUNT),
        "steps between g(r), S(q), contacts and clusters (0: none)",
    ),
    key(
        "observe.gr_bins",
        "-",
        Value("200"),
        Integer(1, 10_000_000),
        "bins of g(r)",
    ),
    key(
        "observe.gr_max",
        "rc",
        Means("0.49 L"),
        Positive,
        "range of g(r)",
    )
    .also(
        "at most half the shortest box edge (the default stays under it: freud's RDF refuses L/2)",
    ),
    key(
        "observe.contact_gap",
        "rc",
        Means("3 / morse_kappa"),
        Positive,
        "a contact is a surface gap below this",
    ),
    key(
        "observe.viscosity_every",
        "steps",
        Value("0"),
        Integer(0, COUNT),
        "steps averaged into one pressure-tensor sample of the Green-Kubo viscosity, stress_acf.csv (0: off)",
    ),
    key(
        "observe.viscosity_time",
        "DPD time",
        Value("5"),
        Positive,
        "longest lag of the stress autocorrelation, the upper limit of the Green-Kubo integral",
    )
    .also("at least one sample interval viscosity_every x dt, at most 100000 of them"),
    key(
        "observe.profile_bins",
        "-",
        Value("16"),
        Integer(1, 1000),
        "bins along y of velocity_profile.csv (shear runs)",
    ),
];

/// The `[solvent]` keys of both MPCD methods (MPCD units).
macro_rules! solvent_keys {
    () => {
        [
            key(
                "solvent",
                "-",
                Means("-"),
                Table,
                "the SRD solvent (MPCD units: cell edge a, solvent mass m, kT)",
            ),
            key(
                "solvent.density",
                "particles / cell",
                Value("5"),
                LeftOpen(0.0, 1000.0),
                "mean particles per cell M",
            ),
            key(
                "solvent.angle",
                "degrees",
                Value("130"),
                LeftOpen(0.0, 180.0),
                "SRD rotation angle about a random axis per cell",
            ),
            key(
                "solvent.tau",
                "time",
                Value("0.1"),
                Positive,
                "collision time (the streaming step)",
            ),
            key(
                "solvent.kT",
                "energy",
                Value("1"),
                Positive,
                "thermal energy",
            ),
            key(
                "solvent.mass",
                "mass",
                Value("1"),
                Positive,
                "solvent particle mass m",
            ),
            key(
                "solvent.cell",
                "length",
                Value("1"),
                Positive,
                "collision cell edge a",
            )
            .also("every box edge a whole number of cells"),
            key(
                "solvent.thermostat",
                "-",
                Value("true"),
                Bool,
                "cell-level Maxwell-Boltzmann thermostat (Huang et al. 2010)",
            ),
        ]
    };
}

const SOLVENT: [Spec; 8] = solvent_keys!();

/// The `[colloid]` keys of both MPCD methods (the discrete-particle colloid; defaults chosen,
/// docs/mpcd.md).
const COLLOID: [Spec; 5] = [
    key(
        "colloid",
        "-",
        Means("-"),
        Table,
        "the discrete-particle colloid: 42 vertices and a centre, harmonic bonds (defaults chosen, docs/mpcd.md)",
    ),
    key(
        "colloid.vertex_mass",
        "mass",
        Value("5"),
        Positive,
        "mass of each of the 42 vertices (they join the collisions)",
    ),
    key(
        "colloid.centre_mass",
        "mass",
        Value("5"),
        Positive,
        "mass of the central particle (WCA between centres, the droplet's interface acts on it)",
    ),
    key(
        "colloid.bond_k",
        "energy / length^2",
        Value("5000"),
        Positive,
        "spring constant of the 120 edge and 42 spoke bonds (5000 kT / a^2 at kT = 1)",
    ),
    key(
        "colloid.md_steps",
        "-",
        Value("50"),
        Integer(1, 100_000),
        "velocity Verlet steps per collision time",
    ),
];

/// The keys of `mpcd` scenarios.
pub static MPCD: &[Spec] = &[
    key(
        "method",
        "-",
        Required,
        OneOf(&["mpcd"]),
        "SRD solvent in a periodic cube (docs/mpcd.md)",
    ),
    SEED_KEY,
    SOLVENT[0],
    SOLVENT[1],
    SOLVENT[2],
    SOLVENT[3],
    SOLVENT[4],
    SOLVENT[5],
    SOLVENT[6],
    SOLVENT[7],
    key("system", "-", Required, Table, "the periodic box"),
    key(
        "system.box",
        "length",
        Required,
        Positive,
        "edge L of the periodic cube",
    )
    .also("a whole number of cells, 2 to 4096 of them"),
    key("system.colloids", "-", Value("0"), Integer(0, 1_000_000), "discrete-particle colloids placed at random; their diffusivity by Green-Kubo (vacf.csv, summary colloid_diffusion)")
        .also("not with [viscosity]; they must fit"),
    key("system.diameter", "length", Value("4"), Positive, "colloid diameter d")
        .also("the box above twice the WCA cut-off 2^(1/6) d"),
    COLLOID[0],
    COLLOID[1],
    COLLOID[2],
    COLLOID[3],
    COLLOID[4],
    key("run", "-", Required, Table, "collisions"),
    key(
        "run.collisions",
        "-",
        Required,
        Integer(1, COUNT),
        "collisions in all (equilibration included)",
    ),
    key(
        "run.equilibrate",
        "-",
        Means("6 flow relaxation times rho / (eta k^2) with [viscosity], else 100 (at most half the run)"),
        Integer(0, COUNT),
        "collisions before sampling",
    )
    .also("below run.collisions"),
    key(
        "viscosity",
        "-",
        Means("absent: no drive"),
        Table,
        "shear viscosity by periodic Poiseuille flow (body force g0 cos(2 pi z / L) along x)",
    ),
    key(
        "viscosity.drive",
        "force / mass",
        Means("flow amplitude 0.25 sqrt(kT/m) by Kikuchi's viscosity"),
        Positive,
        "drive amplitude g0",
    )
    .also("flow amplitude at most 0.6 sqrt(kT/m)"),
    key(
        "viscosity.blocks",
        "-",
        Value("10"),
        Integer(2, 10_000),
        "blocks of the standard errors",
    )
    .also("at most the sampling collisions"),
    key("observe", "-", Means("-"), Table, "observables"),
    key(
        "observe.every",
        "collisions",
        Means("collisions / 200"),
        Integer(1, COUNT),
        "rows of thermo.csv (temperature, flow amplitude, momentum)",
    ),
    key("observe.vacf_lags", "collisions", Means("5 L^2 / (4 pi^2 nu tau)"), Integer(1, COUNT), "lags of the colloids' velocity autocorrelation summed by Green-Kubo (five decay times of the box's slowest shear mode)")
        .also("at most half the sampling collisions"),
    key("observe.trajectory", "-", Means("-"), Table, "GSD trajectory"),
    key(
        "observe.trajectory.every",
        "collisions",
        Value("0"),
        Integer(0, COUNT),
        "collisions between frames (0: none)",
    ),
    key(
        "observe.trajectory.solvent",
        "-",
        Value("false"),
        Bool,
        "frames hold the solvent (type S, with velocities; colloids are types A and V)",
    )
    .also("true when frames are written without colloids"),
];

/// The keys of `droplet-mpcd` scenarios.
pub static DROPLET_MPCD: &[Spec] = &[
    key(
        "method",
        "-",
        Required,
        OneOf(&["droplet-mpcd"]),
        "drying droplet of SRD solvent (docs/mpcd.md)",
    ),
    SEED_KEY,
    key(
        "boundary",
        "-",
        Means("\"slip\""),
        OneOf(&["none", "slip", "no-slip"]),
        "the solvent at the moving sphere: none (fills the box, ignores it), slip or no-slip bounce-back",
    ),
    SOLVENT[0],
    SOLVENT[1],
    SOLVENT[2],
    SOLVENT[3],
    SOLVENT[4],
    SOLVENT[5],
    SOLVENT[6],
    SOLVENT[7],
    key("system", "-", Required, Table, "colloids, droplet and box"),
    key(
        "system.particles",
        "-",
        Value("0"),
        Integer(0, 10_000_000),
        "colloids N (0: a pure-solvent droplet), placed at random with centres within R0 - d/2",
    )
    .also("they must fit: random sequential addition, at most phi0 = 0.3"),
    key(
        "system.diameter",
        "length",
        Value("4"),
        Positive,
        "colloid diameter d; sets D0 = kT / (3 pi eta d) with Kikuchi's viscosity, and so Pe",
    ),
    key(
        "system.radius",
        "length",
        Required,
        Positive,
        "initial droplet radius R0",
    )
    .also("at least 2 cells"),
    key(
        "system.phi0",
        "-",
        Means("from radius"),
        LeftOpen(0.0, 0.3),
        "initial colloid volume fraction N d^3 / (8 R0^3)",
    )
    .also("with colloids; not with system.radius"),
    key(
        "system.box",
        "length",
        Means("smallest whole number of cells >= 2 R0 + 4"),
        Positive,
        "edge of the periodic box",
    )
    .also("at least 2 R0 + 4 cells, a whole number of cells"),
    key(
        "drying",
        "-",
        Means("-"),
        Table,
        "the drying law R(t) = sqrt(R0^2 - alpha t / (4 pi)), as droplet-bd's",
    ),
    key(
        "drying.peclet",
        "-",
        Value("10"),
        NonNegative,
        "Pe = R |dR/dt| / D0 (0: a static droplet)",
    )
    .also("not with drying.alpha"),
    key(
        "drying.alpha",
        "length^2 / time",
        Means("8 pi Pe D0"),
        Positive,
        "rate of loss of surface area",
    ),
    key(
        "drying.final_volume_fraction",
        "-",
        Means("0.55 with colloids"),
        LeftOpen(0.0, 0.64),
        "stop at this mean colloid volume fraction",
    )
    .also("with colloids; not with drying.duration"),
    key(
        "drying.duration",
        "time",
        Means("required without colloids"),
        Positive,
        "stop after this time",
    )
    .also("R must stay above two cells"),
    INTERFACE,
    INTERFACE_STIFFNESS,
    INTERFACE_RANGE.also("at most R0"),
    INTERFACE_OFFSET.also("in [-R0, R0]"),
    COLLOID[0],
    COLLOID[1],
    COLLOID[2],
    COLLOID[3],
    COLLOID[4],
    key("observe", "-", Means("-"), Table, "observables"),
    key(
        "observe.every",
        "collisions",
        Means("collisions / 200"),
        Integer(1, COUNT),
        "rows of thermo.csv (radius, solvent count, expected count, removed, bounced, temperature)",
    ),
    key(
        "observe.profile",
        "-",
        Means("-"),
        Table,
        "times of the profiles",
    ),
    key(
        "observe.profile.bins",
        "-",
        Value("50"),
        Integer(1, 100_000),
        "bins of the colloid volume-fraction profiles (with colloids)",
    ),
    key(
        "observe.profile.fractions",
        "-",
        Value("[0.0, 0.25, 0.5, 0.75, 1.0]"),
        Numbers(0.0, 1.0, None),
        "fractions of the drying time at which profiles are taken",
    )
    .also("increasing, distinct collisions"),
    key(
        "observe.solvent",
        "-",
        Means("-"),
        Table,
        "solvent density and radial velocity against r / R(t)",
    ),
    key(
        "observe.solvent.bins",
        "-",
        Value("20"),
        Integer(1, 10_000),
        "bins over [0, R(t)]",
    ),
    key(
        "observe.solvent.window",
        "collisions",
        Means("collisions / 10"),
        Integer(1, COUNT),
        "each solvent profile averages this many collisions ending at its time (10 blocks for the errors)",
    ),
    key(
        "observe.trajectory",
        "-",
        Means("-"),
        Table,
        "GSD trajectory",
    ),
    key(
        "observe.trajectory.every",
        "collisions",
        Value("0"),
        Integer(0, COUNT),
        "collisions between frames (0: none)",
    ),
    key(
        "observe.trajectory.solvent",
        "-",
        Value("false"),
        Bool,
        "frames hold the solvent (type S, with velocities; log/radius)",
    )
    .also("true when frames are written without colloids"),
];
