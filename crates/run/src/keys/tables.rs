//! The key tables of the methods not yet moved into their folders under `crate::methods`
//! (issue 41): each moves beside its method as the method is converted to read its keys
//! through a [`super::Reader`].

use super::Allowed::*;
use super::Omitted::*;
use super::shared::{INTERFACE, INTERFACE_OFFSET, INTERFACE_RANGE, INTERFACE_STIFFNESS};
use super::{COUNT, SEED_KEY, Spec, key};

/// Keys that `droplet-bd` and `bd` share (the same engines and units).
const DIAMETER: Spec = key(
    "system.diameter",
    "length",
    Value("1"),
    Positive,
    "colloid diameter d",
);

const KT: Spec = key(
    "system.kT",
    "energy",
    Value("1"),
    Positive,
    "thermal energy",
);

const VISCOSITY: Spec = key(
    "system.viscosity",
    "energy time / length^3",
    Value("1"),
    Positive,
    "solvent viscosity eta; friction 3 pi eta d, D0 = kT / (3 pi eta d)",
);

const RUN_DT: Spec = key(
    "run.dt",
    "time",
    Means("2e-4 d^2 / D0"),
    Positive,
    "time step (too large a step for the WCA core stops the run naming the step and particle)",
)
.also("at most 1e12 steps");

const RUN_SKIN: Spec = key(
    "run.skin",
    "length",
    Means("0.6 d"),
    Positive,
    "Verlet skin",
)
.also("in [0.001 d, 5 d]");

const RUN_INTEGRATOR: Spec = key(
        "run.integrator",
        "-",
        Word("euler"),
        OneOf(&["euler", "lm"]),
        "Euler-Maruyama, or Leimkuhler-Matthews (noise (xi_n + xi_n+1)/2: second order for the equilibrium profile, same cost; see docs/droplet.md)",
    )
    .also("lm needs free draining (not hydrodynamics.model = \"rpy\")");

const TRAJECTORY: Spec = key(
    "observe.trajectory",
    "-",
    Means("none"),
    Table,
    "GSD frames of replica 0: trajectory.gsd",
);

const TRAJECTORY_EVERY: Spec = key(
    "observe.trajectory.every",
    "steps",
    Value("0"),
    Integer(0, COUNT),
    "steps between frames (0: none)",
);

/// The `[hydrodynamics]` keys that `droplet-bd` and `bd` share (`method` and `box_factor`
/// differ).
const HYDRO: [Spec; 5] = [
    key(
        "hydrodynamics",
        "-",
        Means("free draining"),
        Table,
        "hydrodynamic interactions; without this table the free-draining engine runs",
    ),
    key(
        "hydrodynamics.model",
        "-",
        Word("free-draining"),
        OneOf(&["free-draining", "rpy"]),
        "mobility: free draining (the free-draining engine) or Rotne-Prager-Yamakawa (no drift term: divergence-free)",
    ),
    key(
        "hydrodynamics.tolerance",
        "-",
        Value("1e-3"),
        LeftOpen(0.0, 0.1),
        "relative error of the PSE product and of each Lanczos square root",
    ),
    key(
        "hydrodynamics.splitting",
        "1 / length",
        Means("0.5 / a = 1 / d"),
        Positive,
        "PSE splitting parameter xi",
    )
    .also("method = \"pse\" only; real-space cut-off < half the box, grid <= 1024^3"),
    key(
        "hydrodynamics.max_iterations",
        "-",
        Value("200"),
        Integer(1, 1000),
        "Lanczos iteration limit; reaching it stops the run naming the step",
    ),
];

/// The keys of `droplet-bd` scenarios.
pub static DROPLET: &[Spec] = &[
    key(
        "method",
        "-",
        Required,
        OneOf(&["droplet-bd"]),
        "Brownian dynamics of a drying (or static) droplet, free draining or with RPY hydrodynamics",
    ),
    SEED_KEY,
    key(
        "replicas",
        "-",
        Value("1"),
        Integer(1, 1_000_000),
        "independent droplets whose profiles are averaged (replica r: initial stream r, noise keyed by (seed, step, r, block))",
    ),
    key(
        "system",
        "-",
        Required,
        Table,
        "particles, solvent and the initial droplet",
    ),
    key(
        "system.particles",
        "-",
        Required,
        Integer(1, 100_000_000),
        "number of colloids N",
    ),
    DIAMETER,
    KT,
    VISCOSITY,
    key(
        "system.phi0",
        "-",
        Means("give phi0 or radius"),
        LeftOpen(0.0, 0.64),
        "initial mean volume fraction N d^3 / (8 R0^3)",
    )
    .also(
        "at most 0.3 for random insertion (0.64 with system.initial); give this or system.radius",
    ),
    key(
        "system.radius",
        "length",
        Means("give phi0 or radius"),
        Positive,
        "initial droplet radius R0",
    )
    .also("phi0 within the same limits"),
    key(
        "system.initial",
        "-",
        Means("random insertion"),
        Path,
        "start from the last frame of this GSD file (HOOMD schema) instead of random insertion",
    )
    .also("must hold system.particles particles within R0 + offset + range"),
    key(
        "drying",
        "-",
        Means("Pe = 10 to phi = 0.55"),
        Table,
        "the drying law R(t) = sqrt(R0^2 - alpha t / (4 pi))",
    ),
    key(
        "drying.peclet",
        "-",
        Value("10"),
        NonNegative,
        "Pe = R |dR/dt| / D0, constant in time; give this or drying.alpha. 0: a static droplet (R = R0), for equilibrium profiles",
    )
    .also("0 needs drying.duration"),
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
        Value("0.55"),
        LeftOpen(0.0, 0.64),
        "run until the mean volume fraction reaches this; or give drying.duration",
    )
    .also("> phi0"),
    key(
        "drying.duration",
        "time",
        Means("until final_volume_fraction"),
        Positive,
        "run for this time",
    )
    .also("before R^2 would turn negative (t < 4 pi R0^2 / alpha)"),
    INTERFACE,
    INTERFACE_STIFFNESS,
    INTERFACE_RANGE,
    INTERFACE_OFFSET.also("in [-R0, R0] and R_end + offset > 0"),
    key("run", "-", Means("defaults"), Table, "time stepping"),
    RUN_DT,
    RUN_SKIN,
    RUN_INTEGRATOR,
    key("observe", "-", Means("profiles"), Table, "what to measure"),
    key(
        "observe.profile",
        "-",
        Means("50 bins at 0, 25, 50, 75, 100 %"),
        Table,
        "radial volume-fraction profiles: profile_<f>.csv",
    ),
    key(
        "observe.profile.bins",
        "-",
        Value("50"),
        Integer(1, 10_000_000),
        "radial bins of equal width between 0 and R(t)",
    ),
    key(
        "observe.profile.fractions",
        "-",
        Value("[0, 0.25, 0.5, 0.75, 1.0]"),
        Numbers(0.0, 1.0, None),
        "fractions of the drying time at which profiles are written",
    )
    .also("at least one"),
    TRAJECTORY,
    TRAJECTORY_EVERY,
    key(
        "observe.cross_section",
        "-",
        Means("none"),
        Table,
        "a slab through the centre of replica 0's last frame: cross_section.csv (x,y,z,r) and cross_section.png",
    ),
    key(
        "observe.cross_section.width",
        "length",
        Means("d"),
        Positive,
        "slab thickness: centres with |z| < width / 2",
    )
    .also("in [0.001 d, 2 R0]"),
    HYDRO[0],
    HYDRO[1],
    key(
        "hydrodynamics.method",
        "-",
        Means("direct up to 2000 particles, pse above"),
        OneOf(&["direct", "pse"]),
        "RPY in an unbounded fluid by direct O(N^2) sums, or periodic by positively split Ewald",
    )
    .also("model = \"rpy\" only; direct: at most 20000 particles"),
    HYDRO[2],
    HYDRO[3],
    key(
        "hydrodynamics.box_factor",
        "droplet diameters",
        Value("2"),
        Closed(1.2, 20.0),
        "PSE: edge of the periodic box / initial droplet diameter 2 R0 (the paper: 2)",
    )
    .also("method = \"pse\" only; the box must hold the droplet, its interface and two neighbour ranges"),
    HYDRO[4],
];

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
    HYDRO[0],
    HYDRO[1],
    key(
        "hydrodynamics.method",
        "-",
        Word("pse"),
        OneOf(&["pse"]),
        "RPY in the periodic cube by positively split Ewald (\"direct\" is the unbounded fluid: refused here)",
    )
    .also("model = \"rpy\" only"),
    HYDRO[2],
    HYDRO[3],
    HYDRO[4],
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

/// The keys of `hs-mc` scenarios.
pub static MC: &[Spec] = &[
    key(
        "method",
        "-",
        Required,
        OneOf(&["hs-mc"]),
        "hard-sphere NVT Monte Carlo, checkerboard cells (docs/mc.md)",
    ),
    SEED_KEY,
    key("system", "-", Required, Table, "spheres and container"),
    key(
        "system.geometry",
        "-",
        Required,
        OneOf(&["bulk", "hard-wall", "interface"]),
        "periodic cube; hard spherical wall (centres within radius - d/2); the BD droplet's harmonic interface ([interface])",
    ),
    key(
        "system.particles",
        "-",
        Means("from the other two"),
        Integer(1, 100_000_000),
        "number of spheres N",
    )
    .also("give exactly two of particles, volume_fraction and box (bulk) or radius (droplet); at least 2 in bulk"),
    key(
        "system.volume_fraction",
        "-",
        Means("from the other two"),
        LeftOpen(0.0, 0.64),
        "N pi d^3 / (6 L^3) in bulk, N d^3 / (8 R^3) in a droplet; at most random close packing",
    ),
    key("system.diameter", "length", Value("1"), Positive, "sphere diameter d"),
    key(
        "system.radius",
        "length",
        Means("from the other two"),
        Positive,
        "droplet radius R (hard-wall, interface)",
    )
    .also("above d/2; not with geometry = \"bulk\""),
    key(
        "system.box",
        "length",
        Means("from the other two"),
        Positive,
        "edge L of the periodic cube (bulk)",
    )
    .also("at least 2 d; bulk only"),
    key(
        "system.kT",
        "energy",
        Value("1"),
        Positive,
        "thermal energy (the interface's stiffness is in energy / length^2)",
    ),
    key(
        "system.initial",
        "-",
        Means("FCC lattice"),
        Path,
        "start from the last frame of this GSD file",
    )
    .also("N spheres, no overlap, centres inside the wall"),
    INTERFACE,
    INTERFACE_STIFFNESS,
    INTERFACE_RANGE,
    INTERFACE_OFFSET.also("above -radius"),
    key("mc", "-", Means("-"), Table, "sweeps, warm-up and tuning"),
    key(
        "mc.sweeps",
        "sweeps",
        Value("10000"),
        Integer(1, COUNT),
        "sampling sweeps (nselect N trial moves each) after the warm-up",
    ),
    key(
        "mc.nselect",
        "-",
        Value("1"),
        Integer(1, colloidsim_mc::scenario::NSELECT_MAX as i64),
        "trial moves per sphere per sweep, all on one binning of the cells (HOOMD-blue's nselect; docs/mc.md)",
    ),
    key(
        "mc.warmup_sweeps",
        "sweeps",
        Value("2000"),
        Integer(0, COUNT),
        "warm-up sweeps, delta tuned every tune_every, then frozen",
    ),
    key(
        "mc.target_acceptance",
        "-",
        Value("0.3"),
        LeftOpen(0.0, 1.0),
        "acceptance the warm-up tunes delta towards",
    )
    .also("below 1"),
    key(
        "mc.tune_every",
        "sweeps",
        Value("100"),
        Integer(1, COUNT),
        "sweeps between tunings: delta *= acceptance / target (factor in [1/2, 2])",
    ),
    key(
        "mc.sample_every",
        "sweeps",
        Value("10"),
        Integer(1, COUNT),
        "sweeps between samples of the observables",
    ),
    key(
        "mc.delta",
        "length",
        Means("d / 10"),
        Positive,
        "initial half-width of the displacement cube (at most half a cell side)",
    ),
    key(
        "mc.blocks",
        "-",
        Value("20"),
        Integer(2, 100_000),
        "blocks of the sampling sweeps whose scatter gives the standard errors",
    )
    .also("at most sweeps / sample_every"),
    key("output", "-", Means("-"), Table, "observables and files"),
    key(
        "output.profile_bins",
        "-",
        Value("50"),
        Integer(1, 1_000_000),
        "radial bins between 0 and R (droplets: profile_mean.csv)",
    ),
    key(
        "output.gr_bins",
        "-",
        Value("200"),
        Integer(1, 1_000_000),
        "bins of g(r) between 0 and gr_max (bulk: g_r.csv)",
    ),
    key("output.gr_max", "length", Means("0.49 L"), Positive, "range of g(r)")
        .also("at most L/2 (the default stays under it: freud's RDF refuses L/2)"),
    key(
        "output.trajectory_every",
        "sweeps",
        Means("0 (none)"),
        Integer(0, COUNT),
        "sweeps between frames of trajectory.gsd",
    ),
    key(
        "output.rho2_r_bins",
        "-",
        Means("0 (none)"),
        Integer(0, 10_000),
        "radial bins over [0, R] of the two-body density rho2(r1, r2, cos theta) and g2 (g2.csv; all pairs, O(N^2) per sample)",
    )
    .also("droplets only"),
    key(
        "output.rho2_cos_bins",
        "-",
        Value("20"),
        Integer(1, 10_000),
        "bins of cos theta over [-1, 1] of the two-body density",
    ),
];
