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
