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
