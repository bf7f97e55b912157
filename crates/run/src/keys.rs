//! Every scenario key of every method: unit, default, allowed values and meaning, in one table
//! per method. The same table
//! - checks a scenario before its method reads it ([`validate`]: unknown keys, types and the
//!   range of each key, each error naming the key and what is allowed), and
//! - is what `colloidsim keys METHOD` prints (and what docs/ quotes),
//!
//! so the listing cannot drift from the validation. Checks that relate several keys (a drying
//! time against the droplet's lifetime, a skin against the diameter) stay with each method and
//! are described in the key's `allowed` text. Tests check that every key the method's parser
//! knows is in its table, that every table key is known to the parser, and that each
//! documented default is the one the method uses.

use anyhow::{Result, bail};
use serde::Serialize;

/// What values a key takes (checked on the key alone).
#[derive(Debug, Clone, Copy)]
pub enum Allowed {
    /// A table of further keys.
    Table,
    /// A finite number > 0.
    Positive,
    /// A finite number >= 0.
    NonNegative,
    /// Any finite number.
    Finite,
    /// A finite number in `[lo, hi]`.
    Closed(f64, f64),
    /// A finite number in `(lo, hi]`.
    LeftOpen(f64, f64),
    /// An integer in `[lo, hi]`.
    Integer(i64, i64),
    /// One of these words.
    OneOf(&'static [&'static str]),
    /// `true` or `false`.
    Bool,
    /// A file name (relative to the scenario file).
    Path,
    /// A list of finite numbers in `[lo, hi]`, of length `len` (any when `None`).
    Numbers(f64, f64, Option<usize>),
}

impl Allowed {
    /// The allowed values, as a user reads them.
    pub fn describe(&self) -> String {
        match *self {
            Allowed::Table => "a table".into(),
            Allowed::Positive => "> 0".into(),
            Allowed::NonNegative => ">= 0".into(),
            Allowed::Finite => "any finite number".into(),
            Allowed::Closed(lo, hi) => format!("[{lo}, {hi}]"),
            Allowed::LeftOpen(lo, hi) => format!("({lo}, {hi}]"),
            Allowed::Integer(lo, hi) if hi == i64::MAX => format!("integer >= {lo}"),
            Allowed::Integer(lo, hi) => format!("integer in [{lo}, {hi}]"),
            Allowed::OneOf(words) => words
                .iter()
                .map(|w| format!("\"{w}\""))
                .collect::<Vec<_>>()
                .join(", "),
            Allowed::Bool => "true, false".into(),
            Allowed::Path => "a file name".into(),
            Allowed::Numbers(lo, hi, len) => {
                let n = len.map_or("a list".to_string(), |n| format!("{n} numbers"));
                if lo == f64::MIN && hi == f64::MAX {
                    format!("{n} of finite numbers")
                } else if hi == f64::MAX {
                    format!("{n} of numbers > {lo}")
                } else {
                    format!("{n} of numbers in [{lo}, {hi}]")
                }
            }
        }
    }

    /// Check `v`; the message says what is allowed and what was given.
    fn check(&self, v: &toml::Value) -> Result<(), String> {
        let number = |v: &toml::Value| match v {
            toml::Value::Float(x) => Some(*x),
            toml::Value::Integer(i) => Some(*i as f64),
            _ => None,
        };
        let got = || match v {
            toml::Value::String(s) => format!("\"{s}\""),
            other => other.to_string(),
        };
        let must = |what: String| Err(format!("must be {what}, got {}", got()));
        match *self {
            Allowed::Table => match v {
                toml::Value::Table(_) => Ok(()),
                _ => must("a table (e.g. { key = value })".into()),
            },
            Allowed::Positive => match number(v) {
                Some(x) if x.is_finite() && x > 0.0 => Ok(()),
                _ => must("a finite number > 0".into()),
            },
            Allowed::NonNegative => match number(v) {
                Some(x) if x.is_finite() && x >= 0.0 => Ok(()),
                _ => must("a finite number >= 0".into()),
            },
            Allowed::Finite => match number(v) {
                Some(x) if x.is_finite() => Ok(()),
                _ => must("a finite number".into()),
            },
            Allowed::Closed(lo, hi) => match number(v) {
                Some(x) if x.is_finite() && x >= lo && x <= hi => Ok(()),
                _ => must(format!("a number in [{lo}, {hi}]")),
            },
            Allowed::LeftOpen(lo, hi) => match number(v) {
                Some(x) if x.is_finite() && x > lo && x <= hi => Ok(()),
                _ => must(format!("a number in ({lo}, {hi}]")),
            },
            Allowed::Integer(lo, hi) => match v {
                toml::Value::Integer(i) if *i >= lo && *i <= hi => Ok(()),
                _ => must(format!("an {}", self.describe())),
            },
            Allowed::OneOf(words) => match v {
                toml::Value::String(s) if words.contains(&s.as_str()) => Ok(()),
                _ => must(format!("one of {}", self.describe())),
            },
            Allowed::Bool => match v {
                toml::Value::Boolean(_) => Ok(()),
                _ => must("true or false".into()),
            },
            Allowed::Path => match v {
                toml::Value::String(s) if !s.is_empty() => Ok(()),
                _ => must("a file name in quotes".into()),
            },
            Allowed::Numbers(lo, hi, len) => {
                let ok = match v {
                    toml::Value::Array(a) => {
                        len.is_none_or(|n| a.len() == n)
                            && a.iter().all(|x| {
                                number(x).is_some_and(|x| x.is_finite() && x >= lo && x <= hi)
                            })
                    }
                    _ => false,
                };
                if ok { Ok(()) } else { must(self.describe()) }
            }
        }
    }
}

/// One key of a method's scenarios.
#[derive(Debug, Clone, Copy)]
pub struct Spec {
    /// Dotted path.
    pub path: &'static str,
    /// Unit (`-` for a pure number or a word).
    pub unit: &'static str,
    /// Default (`required`, or how it is derived).
    pub default: &'static str,
    /// Allowed values of the key alone.
    pub allowed: Allowed,
    /// Further conditions that involve other keys (checked by the method).
    pub also: &'static str,
    /// What it sets.
    pub doc: &'static str,
}

/// One scenario key as listed by `colloidsim keys`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Key {
    /// Dotted path, e.g. `run.dt`.
    pub path: String,
    /// Unit, or `-` for a pure number or a word.
    pub unit: String,
    /// Default, or `required`.
    pub default: String,
    /// Allowed values.
    pub range: String,
    /// What it sets.
    pub doc: String,
}

impl From<&Spec> for Key {
    fn from(s: &Spec) -> Self {
        let mut range = s.allowed.describe();
        if !s.also.is_empty() {
            range = format!("{range}; {}", s.also);
        }
        Key {
            path: s.path.into(),
            unit: s.unit.into(),
            default: s.default.into(),
            range,
            doc: s.doc.into(),
        }
    }
}

const fn key(
    path: &'static str,
    unit: &'static str,
    default: &'static str,
    allowed: Allowed,
    doc: &'static str,
) -> Spec {
    Spec {
        path,
        unit,
        default,
        allowed,
        also: "",
        doc,
    }
}

impl Spec {
    const fn also(mut self, also: &'static str) -> Self {
        self.also = also;
        self
    }
}

use Allowed::*;

const SEED: Allowed = Integer(0, u32::MAX as i64);
/// The `seed` key of the methods with counter-based random streams.
const SEED_KEY: Spec = key(
    "seed",
    "-",
    "1",
    SEED,
    "seed of the counter-based random streams (--seed overrides)",
);
/// Step counts and other integers a run can hold.
const COUNT: i64 = 1 << 53;

/// The keys of `bcd` scenarios.
pub static BCD: &[Spec] = &[
    key(
        "method",
        "-",
        "required",
        OneOf(&["bcd", "bcd-chronological"]),
        "premerging BCD, O(N) per step, or the chronological event-driven update, O(N^2) (test oracle)",
    ),
    key(
        "seed",
        "-",
        "1",
        SEED,
        "seed of all random streams (--seed overrides)",
    ),
    key(
        "system",
        "-",
        "required",
        Table,
        "the rods and their ring or channel",
    ),
    key(
        "system.length",
        "length",
        "required",
        Positive,
        "L: ring circumference or distance between the walls",
    )
    .also("a whole number of potential periods on a ring"),
    key(
        "system.particles",
        "-",
        "required",
        Integer(1, COUNT),
        "N, the number of rods",
    )
    .also("N diameter < length"),
    key(
        "system.diameter",
        "length",
        "required",
        Positive,
        "rod length sigma (the hard core)",
    ),
    key(
        "system.mobility",
        "length^2 / (energy time)",
        "1",
        Positive,
        "mu; D = mu kT",
    ),
    key(
        "system.kT",
        "energy",
        "1",
        NonNegative,
        "thermal energy; 0 gives deterministic cluster dynamics",
    ),
    key(
        "system.boundary",
        "-",
        "periodic",
        OneOf(&["periodic", "walls"]),
        "a ring, or hard walls at 0 and L (centres in [sigma/2, L - sigma/2])",
    ),
    key(
        "potential",
        "-",
        "none",
        Table,
        "external potential: the sum of the terms given",
    ),
    key(
        "potential.cosine",
        "-",
        "none",
        Table,
        "U = (U0/2) cos(2 pi x / lambda)",
    ),
    key(
        "potential.cosine.amplitude",
        "energy",
        "required",
        Finite,
        "U0, peak to peak",
    ),
    key(
        "potential.cosine.wavelength",
        "length",
        "required",
        Positive,
        "lambda",
    ),
    key(
        "potential.drive",
        "energy / length",
        "0",
        Finite,
        "constant force f (tilted washboard; the system then has no equilibrium)",
    ),
    key(
        "potential.harmonic",
        "-",
        "none",
        Table,
        "U = k/2 (x - x0)^2 (minimum image on a ring)",
    ),
    key(
        "potential.harmonic.stiffness",
        "energy / length^2",
        "required",
        NonNegative,
        "k",
    ),
    key("potential.harmonic.centre", "length", "L/2", Finite, "x0"),
    key(
        "potential.fourier",
        "-",
        "none",
        Table,
        "U = sum_n a_n cos(2 pi n x / lambda) + b_n sin(2 pi n x / lambda)",
    ),
    key(
        "potential.fourier.wavelength",
        "length",
        "required",
        Positive,
        "lambda, the fundamental period",
    ),
    key(
        "potential.fourier.cos",
        "energy",
        "[]",
        Numbers(f64::MIN, f64::MAX, None),
        "a_1, a_2, ...",
    ),
    key(
        "potential.fourier.sin",
        "energy",
        "[]",
        Numbers(f64::MIN, f64::MAX, None),
        "b_1, b_2, ...",
    ),
    key(
        "potential.table",
        "-",
        "none",
        Path,
        "CSV with columns x,U over exactly one period (last U equal to the first); periodic cubic spline",
    ),
    key(
        "interaction",
        "-",
        "hard rods",
        Table,
        "pair interactions beyond the hard core",
    ),
    key(
        "interaction.sticky",
        "-",
        "none",
        Table,
        "Baxter adhesion by the power law of the hard-rods paper's Eq. (33) on [sigma, sigma + eps]",
    ),
    key(
        "interaction.sticky.gamma",
        "-",
        "required",
        Positive,
        "stickiness gamma",
    )
    .also("run.dt must satisfy Eq. (34): mu max|f| dt < eps"),
    key(
        "interaction.sticky.range",
        "length",
        "0.05",
        Positive,
        "virtual range eps",
    ),
    key(
        "interaction.sticky.order",
        "-",
        "3",
        Closed(1.0, 100.0),
        "power p",
    ),
    key(
        "interaction.yukawa",
        "-",
        "none",
        Table,
        "U = A exp(-(r - sigma)/l), force-shifted at the cut-off",
    ),
    key(
        "interaction.yukawa.strength",
        "energy",
        "required",
        Finite,
        "A, the energy at contact",
    ),
    key(
        "interaction.yukawa.screening",
        "length",
        "required",
        Positive,
        "l",
    ),
    key(
        "interaction.yukawa.cutoff",
        "length",
        "required",
        Positive,
        "cut-off rc (centre distance)",
    )
    .also("> diameter"),
    key(
        "interaction.table",
        "-",
        "none",
        Path,
        "CSV with columns r,f (pair force, positive repulsive), linear interpolation, last f = 0",
    ),
    key(
        "initial",
        "-",
        "random placement",
        Table,
        "the initial configuration",
    ),
    key(
        "initial.placement",
        "-",
        "random",
        OneOf(&["random", "lattice", "file"]),
        "random (the exact hard-rod equilibrium without field), a lattice, or a file",
    ),
    key(
        "initial.file",
        "-",
        "none",
        Path,
        "CSV with a column x (e.g. an earlier run's final_configuration.csv)",
    )
    .also("needs placement = \"file\""),
    key("run", "-", "required", Table, "time stepping"),
    key("run.dt", "time", "required", Positive, "time step"),
    key(
        "run.integrator",
        "-",
        "euler",
        OneOf(&["euler", "lm"]),
        "free motion: Euler-Maruyama, or Leimkuhler-Matthews (noise (xi_n + xi_n+1)/2, second order for the forces, the same collisions; see docs/bcd.md)",
    ),
    key(
        "run.equilibrate",
        "time",
        "0",
        NonNegative,
        "time run before sampling",
    ),
    key("run.time", "time", "required", Positive, "sampled time"),
    key(
        "run.checkpoint_every",
        "steps",
        "10 % of the run (at least 1000)",
        Integer(1, COUNT),
        "steps between checkpoints",
    ),
    key("observe", "-", "no observables", Table, "what to measure"),
    key(
        "observe.every",
        "steps",
        "1",
        Integer(1, COUNT),
        "steps between samples of density, contact density and clusters",
    ),
    key(
        "observe.density",
        "-",
        "off",
        Table,
        "density histogram over one period of the potential (or over L): density.csv",
    ),
    key(
        "observe.density.bins",
        "-",
        "required",
        Integer(1, 100_000_000),
        "number of bins",
    ),
    key(
        "observe.contact_density",
        "-",
        "off",
        Table,
        "two-particle density at contact (hard-rods paper Eq. 27): contact_density.csv",
    ),
    key(
        "observe.contact_density.bins",
        "-",
        "required",
        Integer(1, 100_000_000),
        "number of bins",
    ),
    key(
        "observe.contact_density.window",
        "length",
        "required",
        Positive,
        "contact window Delta'",
    ),
    key(
        "observe.msd",
        "-",
        "off",
        Table,
        "mean-square displacement at log-spaced lags: msd.csv",
    ),
    key(
        "observe.msd.points",
        "-",
        "40",
        Integer(2, 100_000),
        "number of lag times",
    ),
    key(
        "observe.msd.max_lag",
        "time",
        "run.time / 2",
        Positive,
        "longest lag",
    )
    .also("in [run.dt, run.time]"),
    key(
        "observe.current",
        "-",
        "false",
        Bool,
        "mean displacement and particle current: current.csv",
    ),
    key(
        "observe.clusters",
        "-",
        "false",
        Bool,
        "cluster-size distribution: clusters.csv",
    ),
    key(
        "observe.trajectory",
        "-",
        "off",
        Table,
        "GSD frames: trajectory.gsd",
    ),
    key(
        "observe.trajectory.every",
        "steps",
        "required",
        Integer(1, COUNT),
        "steps between frames, the first at the first production step",
    ),
    key(
        "observe.trajectory.equilibration",
        "-",
        "false",
        Bool,
        "also write frames during equilibration (every `every` steps from step 0)",
    ),
];

/// Keys that `droplet-bd` and `bd` share (the same engines and units).
const DIAMETER: Spec = key(
    "system.diameter",
    "length",
    "1",
    Positive,
    "colloid diameter d",
);

const KT: Spec = key("system.kT", "energy", "1", Positive, "thermal energy");

const VISCOSITY: Spec = key(
    "system.viscosity",
    "energy time / length^3",
    "1",
    Positive,
    "solvent viscosity eta; friction 3 pi eta d, D0 = kT / (3 pi eta d)",
);

const RUN_DT: Spec = key(
    "run.dt",
    "time",
    "2e-4 d^2 / D0",
    Positive,
    "time step (too large a step for the WCA core stops the run naming the step and particle)",
)
.also("at most 1e12 steps");

const RUN_SKIN: Spec =
    key("run.skin", "length", "0.6 d", Positive, "Verlet skin").also("in [0.001 d, 5 d]");

const RUN_INTEGRATOR: Spec = key(
        "run.integrator",
        "-",
        "euler",
        OneOf(&["euler", "lm"]),
        "Euler-Maruyama, or Leimkuhler-Matthews (noise (xi_n + xi_n+1)/2: second order for the equilibrium profile, same cost; see docs/droplet.md)",
    )
    .also("lm needs free draining (not hydrodynamics.model = \"rpy\")");

const TRAJECTORY: Spec = key(
    "observe.trajectory",
    "-",
    "none",
    Table,
    "GSD frames of replica 0: trajectory.gsd",
);

const TRAJECTORY_EVERY: Spec = key(
    "observe.trajectory.every",
    "steps",
    "0",
    Integer(0, COUNT),
    "steps between frames (0: none)",
);

/// The `[hydrodynamics]` keys that `droplet-bd` and `bd` share (`method` and `box_factor`
/// differ).
const HYDRO: [Spec; 5] = [
    key(
        "hydrodynamics",
        "-",
        "free draining",
        Table,
        "hydrodynamic interactions; without this table the free-draining engine runs",
    ),
    key(
        "hydrodynamics.model",
        "-",
        "free-draining",
        OneOf(&["free-draining", "rpy"]),
        "mobility: free draining (the free-draining engine) or Rotne-Prager-Yamakawa (no drift term: divergence-free)",
    ),
    key(
        "hydrodynamics.tolerance",
        "-",
        "1e-3",
        LeftOpen(0.0, 0.1),
        "relative error of the PSE product and of each Lanczos square root",
    ),
    key(
        "hydrodynamics.splitting",
        "1 / length",
        "0.5 / a = 1 / d",
        Positive,
        "PSE splitting parameter xi",
    )
    .also("method = \"pse\" only; real-space cut-off < half the box, grid <= 1024^3"),
    key(
        "hydrodynamics.max_iterations",
        "-",
        "200",
        Integer(1, 1000),
        "Lanczos iteration limit; reaching it stops the run naming the step",
    ),
];

/// The keys of `droplet-bd` scenarios.
pub static DROPLET: &[Spec] = &[
    key(
        "method",
        "-",
        "required",
        OneOf(&["droplet-bd"]),
        "Brownian dynamics of a drying (or static) droplet, free draining or with RPY hydrodynamics",
    ),
    SEED_KEY,
    key(
        "replicas",
        "-",
        "1",
        Integer(1, 1_000_000),
        "independent droplets whose profiles are averaged (replica r: initial stream r, noise keyed by (seed, step, r, block))",
    ),
    key(
        "system",
        "-",
        "required",
        Table,
        "particles, solvent and the initial droplet",
    ),
    key(
        "system.particles",
        "-",
        "required",
        Integer(1, 100_000_000),
        "number of colloids N",
    ),
    DIAMETER,
    KT,
    VISCOSITY,
    key(
        "system.phi0",
        "-",
        "give phi0 or radius",
        LeftOpen(0.0, 0.64),
        "initial mean volume fraction N d^3 / (8 R0^3)",
    )
    .also(
        "at most 0.3 for random insertion (0.64 with system.initial); give this or system.radius",
    ),
    key(
        "system.radius",
        "length",
        "give phi0 or radius",
        Positive,
        "initial droplet radius R0",
    )
    .also("phi0 within the same limits"),
    key(
        "system.initial",
        "-",
        "random insertion",
        Path,
        "start from the last frame of this GSD file (HOOMD schema) instead of random insertion",
    )
    .also("must hold system.particles particles within R0 + offset + range"),
    key(
        "drying",
        "-",
        "Pe = 10 to phi = 0.55",
        Table,
        "the drying law R(t) = sqrt(R0^2 - alpha t / (4 pi))",
    ),
    key(
        "drying.peclet",
        "-",
        "10",
        NonNegative,
        "Pe = R |dR/dt| / D0, constant in time; give this or drying.alpha. 0: a static droplet (R = R0), for equilibrium profiles",
    )
    .also("0 needs drying.duration"),
    key(
        "drying.alpha",
        "length^2 / time",
        "8 pi Pe D0",
        Positive,
        "rate of loss of surface area",
    ),
    key(
        "drying.final_volume_fraction",
        "-",
        "0.55",
        LeftOpen(0.0, 0.64),
        "run until the mean volume fraction reaches this; or give drying.duration",
    )
    .also("> phi0"),
    key(
        "drying.duration",
        "time",
        "until final_volume_fraction",
        Positive,
        "run for this time",
    )
    .also("before R^2 would turn negative (t < 4 pi R0^2 / alpha)"),
    key(
        "interface",
        "-",
        "k = 50 kT/d^2, range d/2, offset -d/2",
        Table,
        "harmonic interface V = k/2 s^2 for 0 <= s < range, linear beyond, s = r - (R(t) + offset)",
    ),
    key(
        "interface.stiffness",
        "energy / length^2",
        "50 kT / d^2",
        Positive,
        "spring constant k",
    ),
    key(
        "interface.range",
        "length",
        "d / 2",
        Positive,
        "range of the harmonic part Delta",
    ),
    key(
        "interface.offset",
        "length",
        "-d / 2",
        Finite,
        "wall position relative to R(t) (-d/2: the colloid surface at R(t))",
    )
    .also("in [-R0, R0] and R_end + offset > 0"),
    key("run", "-", "defaults", Table, "time stepping"),
    RUN_DT,
    RUN_SKIN,
    RUN_INTEGRATOR,
    key("observe", "-", "profiles", Table, "what to measure"),
    key(
        "observe.profile",
        "-",
        "50 bins at 0, 25, 50, 75, 100 %",
        Table,
        "radial volume-fraction profiles: profile_<f>.csv",
    ),
    key(
        "observe.profile.bins",
        "-",
        "50",
        Integer(1, 10_000_000),
        "radial bins of equal width between 0 and R(t)",
    ),
    key(
        "observe.profile.fractions",
        "-",
        "[0, 0.25, 0.5, 0.75, 1.0]",
        Numbers(0.0, 1.0, None),
        "fractions of the drying time at which profiles are written",
    )
    .also("at least one"),
    TRAJECTORY,
    TRAJECTORY_EVERY,
    key(
        "observe.cross_section",
        "-",
        "none",
        Table,
        "a slab through the centre of replica 0's last frame: cross_section.csv (x,y,z,r) and cross_section.png",
    ),
    key(
        "observe.cross_section.width",
        "length",
        "d",
        Positive,
        "slab thickness: centres with |z| < width / 2",
    )
    .also("in [0.001 d, 2 R0]"),
    HYDRO[0],
    HYDRO[1],
    key(
        "hydrodynamics.method",
        "-",
        "direct up to 2000 particles, pse above",
        OneOf(&["direct", "pse"]),
        "RPY in an unbounded fluid by direct O(N^2) sums, or periodic by positively split Ewald",
    )
    .also("model = \"rpy\" only; direct: at most 20000 particles"),
    HYDRO[2],
    HYDRO[3],
    key(
        "hydrodynamics.box_factor",
        "droplet diameters",
        "2",
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
        "required",
        OneOf(&["bd"]),
        "Brownian dynamics of WCA spheres in a periodic cube, free draining or with RPY (PSE)",
    ),
    SEED_KEY,
    key(
        "replicas",
        "-",
        "1",
        Integer(1, 1_000_000),
        "independent systems run one after the other, their blocks pooled (replica r: initial stream r, noise keyed by (seed, step, r, block))",
    ),
    key(
        "system",
        "-",
        "required",
        Table,
        "spheres, solvent, the periodic cube and the body force",
    ),
    key(
        "system.particles",
        "-",
        "required",
        Integer(1, 100_000_000),
        "number of spheres N",
    ),
    key(
        "system.box_length",
        "length",
        "required",
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
        "[0, 0, 0]",
        Numbers(f64::MIN, f64::MAX, Some(3)),
        "constant force F on every sphere (gravity less buoyancy): the mean velocity along it gives K = U / (mu0 F)",
    )
    .also("its drift F dt / (3 pi eta d) at most 0.1 d per step"),
    key(
        "system.initial",
        "-",
        "random insertion",
        Path,
        "start every replica from the last frame of this GSD file (HOOMD schema) instead of random insertion",
    )
    .also("must hold system.particles spheres of typeid 0 in a cube of edge system.box_length"),
    key("run", "-", "required", Table, "time stepping"),
    key(
        "run.time",
        "time",
        "required",
        Positive,
        "sampled time per replica (rounded up to whole blocks)",
    )
    .also("at least 4 steps per block; at most 1e12 steps"),
    RUN_DT,
    key(
        "run.equilibrate",
        "time",
        "0",
        NonNegative,
        "time run before sampling starts (random insertion is the hard-sphere equilibrium to first order in phi)",
    ),
    RUN_SKIN,
    RUN_INTEGRATOR,
    key("observe", "-", "defaults", Table, "what to measure"),
    key(
        "observe.blocks",
        "-",
        "8",
        Integer(1, 10_000),
        "blocks per replica of the sampled time; every error is the standard error of the block values, given with at least 8 blocks in all",
    ),
    key(
        "observe.msd",
        "-",
        "30 lags up to a quarter of a block",
        Table,
        "mean-square displacement of the unwrapped positions (about the centre of mass under a body force): msd.csv, msd.png",
    ),
    key(
        "observe.msd.points",
        "-",
        "30",
        Integer(2, 1000),
        "log-spaced lags from one step to max_lag",
    ),
    key(
        "observe.msd.max_lag",
        "time",
        "a quarter of a block (at least 4 run.dt)",
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
        "pse",
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
        "required",
        OneOf(&["dpd"]),
        "DPD colloids in explicit solvent",
    ),
    SEED_KEY,
    key(
        "system",
        "-",
        "required",
        Table,
        "box, solvent and colloids",
    ),
    key(
        "system.box_length",
        "rc",
        "give box_length or box_edges",
        Positive,
        "cube edge",
    )
    .also("each edge must hold 3 neighbour cells and twice the colloid range"),
    key(
        "system.box_edges",
        "rc",
        "give box_length or box_edges",
        Numbers(0.0, f64::MAX, Some(3)),
        "[Lx, Ly, Lz]",
    )
    .also("each > 0, the same conditions as box_length"),
    key(
        "system.density",
        "1/rc^3",
        "3",
        Closed(1e-3, 20.0),
        "solvent beads per volume the colloids leave free",
    ),
    key(
        "system.phi",
        "-",
        "0",
        Closed(0.0, 0.35),
        "colloid volume fraction (random insertion)",
    ),
    key("system.kT", "energy", "0.1", Positive, "thermal energy"),
    key(
        "system.colloid_radius",
        "rc",
        "1",
        Positive,
        "mean colloid radius R_c",
    ),
    key(
        "system.radius_distribution",
        "-",
        "monodisperse",
        OneOf(&["monodisperse", "gaussian", "lognormal", "uniform"]),
        "distribution of the colloid radii (gaussian truncated at +-3 sd)",
    ),
    key(
        "system.radius_spread",
        "-",
        "0",
        Closed(0.0, 0.5),
        "relative sd (gaussian, lognormal) or half-width (uniform)",
    ),
    key(
        "system.solvent_mass",
        "bead mass",
        "1",
        Positive,
        "m_s (colloid mass: 4/3 pi R^3 density m_s)",
    ),
    key("dpd", "-", "defaults", Table, "DPD pair forces"),
    key(
        "dpd.cutoff",
        "rc",
        "1",
        Positive,
        "solvent cut-off rc (the length unit)",
    ),
    key(
        "dpd.repulsion",
        "kT / rc",
        "25",
        NonNegative,
        "solvent-solvent conservative amplitude a",
    ),
    key(
        "dpd.repulsion_colloid_solvent",
        "kT / rc'",
        "25",
        NonNegative,
        "colloid-solvent amplitude a_cs",
    ),
    key(
        "dpd.gamma",
        "mass / time",
        "4.5",
        LeftOpen(0.0, 200.0),
        "dissipation gamma (below 4.5: a warning)",
    ),
    key("colloids", "-", "defaults", Table, "colloid-colloid forces"),
    key(
        "colloids.cutoff",
        "rc",
        "1",
        Positive,
        "colloid-colloid surface cut-off",
    )
    .also("> contact_range"),
    key(
        "colloids.contact",
        "kT / rc",
        "10000",
        NonNegative,
        "contact modulus f_contact",
    ),
    key(
        "colloids.contact_range",
        "rc",
        "0.001",
        Positive,
        "contact range Delta",
    ),
    key(
        "colloids.morse_depth",
        "kT",
        "0",
        NonNegative,
        "Morse depth D0 (0: no attraction; ~12 for gels)",
    ),
    key(
        "colloids.morse_kappa",
        "1/rc",
        "30",
        Positive,
        "Morse kappa",
    ),
    key("colloids.morse_r0", "rc", "0", NonNegative, "Morse r0").also("<= colloids.cutoff"),
    key(
        "colloids.eta0",
        "mass / (rc time)",
        "0.3",
        NonNegative,
        "background viscosity of the squeeze lubrication (and the time unit)",
    ),
    key(
        "colloids.lubrication",
        "-",
        "true",
        Bool,
        "squeeze lubrication on or off",
    ),
    key(
        "colloids.lubrication_gap",
        "rc",
        "0.001",
        Positive,
        "smallest gap delta of the lubrication",
    )
    .also("< colloids.cutoff"),
    key(
        "colloids.lubrication_noise",
        "-",
        "exact",
        OneOf(&["exact", "authors"]),
        "the lubrication pair's own noise (exact equilibrium) or the authors' weighted noise",
    ),
    key("run", "-", "defaults", Table, "time stepping"),
    key("run.dt", "DPD time", "0.001", Positive, "time step"),
    key("run.steps", "-", "10000", Integer(0, COUNT), "steps"),
    key(
        "run.skin",
        "rc",
        "0.4",
        Closed(0.05, 2.0),
        "neighbour-list skin",
    ),
    key(
        "run.max_temperature_drift",
        "-",
        "0.1",
        LeftOpen(0.0, 10.0),
        "stop when the window-averaged kinetic temperature differs from kT by more than this fraction",
    ),
    key(
        "run.temperature_window",
        "steps",
        "1000",
        Integer(1, COUNT),
        "window of that check",
    ),
    key(
        "run.neighbors",
        "-",
        "auto",
        OneOf(&["auto", "verlet", "cells"]),
        "how solvent pairs are found: Verlet lists, cells every step, or chosen by the list lifetime",
    ),
    key(
        "run.shear_rate",
        "1 / DPD time",
        "0",
        Closed(0.0, 10.0),
        "Lees-Edwards shear rate gamma_dot: flow along x, gradient along y (0: no shear); the run reports the shear stress, the viscosity and velocity_profile.csv",
    ),
    key(
        "run.rank_grid",
        "ranks",
        "unset",
        Numbers(1.0, 1e6, Some(2)),
        "MPI runs: the grid [py, pz] of ranks, columns along y by slabs along z, product the number of ranks (unset: the grid with the fewest ghost cells; slabs when sheared); the run is bitwise the same on any grid",
    ),
    key("observe", "-", "defaults", Table, "what to measure"),
    key(
        "observe.thermo_every",
        "steps",
        "100",
        Integer(0, COUNT),
        "steps between rows of thermo.csv (0: none)",
    ),
    key(
        "observe.trajectory_every",
        "steps",
        "1000",
        Integer(0, COUNT),
        "steps between GSD frames (0: none)",
    ),
    key(
        "observe.msd_every",
        "steps",
        "100",
        Integer(0, COUNT),
        "steps between the positions kept for msd.csv (0: none)",
    ),
    key(
        "observe.msd_solvent_beads",
        "-",
        "1000",
        Integer(0, 100_000_000),
        "solvent beads followed for the solvent MSD",
    ),
    key(
        "observe.structure_every",
        "steps",
        "1000",
        Integer(0, COUNT),
        "steps between g(r), S(q), contacts and clusters (0: none)",
    ),
    key(
        "observe.gr_bins",
        "-",
        "200",
        Integer(1, 10_000_000),
        "bins of g(r)",
    ),
    key("observe.gr_max", "rc", "0.49 L", Positive, "range of g(r)").also(
        "at most half the shortest box edge (the default stays under it: freud's RDF refuses L/2)",
    ),
    key(
        "observe.contact_gap",
        "rc",
        "3 / morse_kappa",
        Positive,
        "a contact is a surface gap below this",
    ),
    key(
        "observe.viscosity_every",
        "steps",
        "0",
        Integer(0, COUNT),
        "steps averaged into one pressure-tensor sample of the Green-Kubo viscosity, stress_acf.csv (0: off)",
    ),
    key(
        "observe.viscosity_time",
        "DPD time",
        "5",
        Positive,
        "longest lag of the stress autocorrelation, the upper limit of the Green-Kubo integral",
    )
    .also("at least one sample interval viscosity_every x dt, at most 100000 of them"),
    key(
        "observe.profile_bins",
        "-",
        "16",
        Integer(1, 1000),
        "bins along y of velocity_profile.csv (shear runs)",
    ),
];

/// The keys of `hs-mc` scenarios.
pub static MC: &[Spec] = &[
    key(
        "method",
        "-",
        "required",
        OneOf(&["hs-mc"]),
        "hard-sphere NVT Monte Carlo, checkerboard cells (docs/mc.md)",
    ),
    SEED_KEY,
    key("system", "-", "required", Table, "spheres and container"),
    key(
        "system.geometry",
        "-",
        "required",
        OneOf(&["bulk", "hard-wall", "interface"]),
        "periodic cube; hard spherical wall (centres within radius - d/2); the BD droplet's harmonic interface ([interface])",
    ),
    key(
        "system.particles",
        "-",
        "from the other two",
        Integer(1, 100_000_000),
        "number of spheres N",
    )
    .also("give exactly two of particles, volume_fraction and box (bulk) or radius (droplet); at least 2 in bulk"),
    key(
        "system.volume_fraction",
        "-",
        "from the other two",
        LeftOpen(0.0, 0.64),
        "N pi d^3 / (6 L^3) in bulk, N d^3 / (8 R^3) in a droplet; at most random close packing",
    ),
    key("system.diameter", "length", "1", Positive, "sphere diameter d"),
    key(
        "system.radius",
        "length",
        "from the other two",
        Positive,
        "droplet radius R (hard-wall, interface)",
    )
    .also("above d/2; not with geometry = \"bulk\""),
    key(
        "system.box",
        "length",
        "from the other two",
        Positive,
        "edge L of the periodic cube (bulk)",
    )
    .also("at least 2 d; bulk only"),
    key(
        "system.kT",
        "energy",
        "1",
        Positive,
        "thermal energy (the interface's stiffness is in energy / length^2)",
    ),
    key(
        "system.initial",
        "-",
        "FCC lattice",
        Path,
        "start from the last frame of this GSD file",
    )
    .also("N spheres, no overlap, centres inside the wall"),
    key(
        "interface",
        "-",
        "-",
        Table,
        "the harmonic interface, as droplet-bd's (geometry = \"interface\" only)",
    ),
    key(
        "interface.stiffness",
        "energy / length^2",
        "50 kT / d^2",
        Positive,
        "spring constant k of V = k s^2 / 2, s = r - (R + offset)",
    ),
    key(
        "interface.range",
        "length",
        "d / 2",
        Positive,
        "range of the harmonic part (linear beyond)",
    ),
    key(
        "interface.offset",
        "length",
        "-d / 2",
        Finite,
        "wall position relative to R (-d/2: the surface touches R)",
    )
    .also("above -radius"),
    key("mc", "-", "-", Table, "sweeps, warm-up and tuning"),
    key(
        "mc.sweeps",
        "sweeps",
        "10000",
        Integer(1, COUNT),
        "sampling sweeps (nselect N trial moves each) after the warm-up",
    ),
    key(
        "mc.nselect",
        "-",
        "1",
        Integer(1, colloidsim_mc::scenario::NSELECT_MAX as i64),
        "trial moves per sphere per sweep, all on one binning of the cells (HOOMD-blue's nselect; docs/mc.md)",
    ),
    key(
        "mc.warmup_sweeps",
        "sweeps",
        "2000",
        Integer(0, COUNT),
        "warm-up sweeps, delta tuned every tune_every, then frozen",
    ),
    key(
        "mc.target_acceptance",
        "-",
        "0.3",
        LeftOpen(0.0, 1.0),
        "acceptance the warm-up tunes delta towards",
    )
    .also("below 1"),
    key(
        "mc.tune_every",
        "sweeps",
        "100",
        Integer(1, COUNT),
        "sweeps between tunings: delta *= acceptance / target (factor in [1/2, 2])",
    ),
    key(
        "mc.sample_every",
        "sweeps",
        "10",
        Integer(1, COUNT),
        "sweeps between samples of the observables",
    ),
    key(
        "mc.delta",
        "length",
        "d / 10",
        Positive,
        "initial half-width of the displacement cube (at most half a cell side)",
    ),
    key(
        "mc.blocks",
        "-",
        "20",
        Integer(2, 100_000),
        "blocks of the sampling sweeps whose scatter gives the standard errors",
    )
    .also("at most sweeps / sample_every"),
    key("output", "-", "-", Table, "observables and files"),
    key(
        "output.profile_bins",
        "-",
        "50",
        Integer(1, 1_000_000),
        "radial bins between 0 and R (droplets: profile_mean.csv)",
    ),
    key(
        "output.gr_bins",
        "-",
        "200",
        Integer(1, 1_000_000),
        "bins of g(r) between 0 and gr_max (bulk: g_r.csv)",
    ),
    key("output.gr_max", "length", "0.49 L", Positive, "range of g(r)")
        .also("at most L/2 (the default stays under it: freud's RDF refuses L/2)"),
    key(
        "output.trajectory_every",
        "sweeps",
        "0 (none)",
        Integer(0, COUNT),
        "sweeps between frames of trajectory.gsd",
    ),
    key(
        "output.rho2_r_bins",
        "-",
        "0 (none)",
        Integer(0, 10_000),
        "radial bins over [0, R] of the two-body density rho2(r1, r2, cos theta) and g2 (g2.csv; all pairs, O(N^2) per sample)",
    )
    .also("droplets only"),
    key(
        "output.rho2_cos_bins",
        "-",
        "20",
        Integer(1, 10_000),
        "bins of cos theta over [-1, 1] of the two-body density",
    ),
];

/// The `[solvent]` keys of both MPCD methods (MPCD units).
macro_rules! solvent_keys {
    () => {
        [
            key(
                "solvent",
                "-",
                "-",
                Table,
                "the SRD solvent (MPCD units: cell edge a, solvent mass m, kT)",
            ),
            key(
                "solvent.density",
                "particles / cell",
                "5",
                LeftOpen(0.0, 1000.0),
                "mean particles per cell M",
            ),
            key(
                "solvent.angle",
                "degrees",
                "130",
                LeftOpen(0.0, 180.0),
                "SRD rotation angle about a random axis per cell",
            ),
            key(
                "solvent.tau",
                "time",
                "0.1",
                Positive,
                "collision time (the streaming step)",
            ),
            key("solvent.kT", "energy", "1", Positive, "thermal energy"),
            key(
                "solvent.mass",
                "mass",
                "1",
                Positive,
                "solvent particle mass m",
            ),
            key(
                "solvent.cell",
                "length",
                "1",
                Positive,
                "collision cell edge a",
            )
            .also("every box edge a whole number of cells"),
            key(
                "solvent.thermostat",
                "-",
                "true",
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
        "-",
        Table,
        "the discrete-particle colloid: 42 vertices and a centre, harmonic bonds (defaults chosen, docs/mpcd.md)",
    ),
    key(
        "colloid.vertex_mass",
        "mass",
        "5",
        Positive,
        "mass of each of the 42 vertices (they join the collisions)",
    ),
    key(
        "colloid.centre_mass",
        "mass",
        "5",
        Positive,
        "mass of the central particle (WCA between centres, the droplet's interface acts on it)",
    ),
    key(
        "colloid.bond_k",
        "energy / length^2",
        "5000",
        Positive,
        "spring constant of the 120 edge and 42 spoke bonds (5000 kT / a^2 at kT = 1)",
    ),
    key(
        "colloid.md_steps",
        "-",
        "50",
        Integer(1, 100_000),
        "velocity Verlet steps per collision time",
    ),
];

/// The keys of `mpcd` scenarios.
pub static MPCD: &[Spec] = &[
    key(
        "method",
        "-",
        "required",
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
    key("system", "-", "required", Table, "the periodic box"),
    key(
        "system.box",
        "length",
        "required",
        Positive,
        "edge L of the periodic cube",
    )
    .also("a whole number of cells, 2 to 4096 of them"),
    key("system.colloids", "-", "0", Integer(0, 1_000_000), "discrete-particle colloids placed at random; their diffusivity by Green-Kubo (vacf.csv, summary colloid_diffusion)")
        .also("not with [viscosity]; they must fit"),
    key("system.diameter", "length", "4", Positive, "colloid diameter d")
        .also("the box above twice the WCA cut-off 2^(1/6) d"),
    COLLOID[0],
    COLLOID[1],
    COLLOID[2],
    COLLOID[3],
    COLLOID[4],
    key("run", "-", "required", Table, "collisions"),
    key(
        "run.collisions",
        "-",
        "required",
        Integer(1, COUNT),
        "collisions in all (equilibration included)",
    ),
    key(
        "run.equilibrate",
        "-",
        "6 flow relaxation times rho / (eta k^2) with [viscosity], else 100 (at most half the run)",
        Integer(0, COUNT),
        "collisions before sampling",
    )
    .also("below run.collisions"),
    key(
        "viscosity",
        "-",
        "absent: no drive",
        Table,
        "shear viscosity by periodic Poiseuille flow (body force g0 cos(2 pi z / L) along x)",
    ),
    key(
        "viscosity.drive",
        "force / mass",
        "flow amplitude 0.25 sqrt(kT/m) by Kikuchi's viscosity",
        Positive,
        "drive amplitude g0",
    )
    .also("flow amplitude at most 0.6 sqrt(kT/m)"),
    key(
        "viscosity.blocks",
        "-",
        "10",
        Integer(2, 10_000),
        "blocks of the standard errors",
    )
    .also("at most the sampling collisions"),
    key("observe", "-", "-", Table, "observables"),
    key(
        "observe.every",
        "collisions",
        "collisions / 200",
        Integer(1, COUNT),
        "rows of thermo.csv (temperature, flow amplitude, momentum)",
    ),
    key("observe.vacf_lags", "collisions", "5 L^2 / (4 pi^2 nu tau)", Integer(1, COUNT), "lags of the colloids' velocity autocorrelation summed by Green-Kubo (five decay times of the box's slowest shear mode)")
        .also("at most half the sampling collisions"),
    key("observe.trajectory", "-", "-", Table, "GSD trajectory"),
    key(
        "observe.trajectory.every",
        "collisions",
        "0",
        Integer(0, COUNT),
        "collisions between frames (0: none)",
    ),
    key(
        "observe.trajectory.solvent",
        "-",
        "false",
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
        "required",
        OneOf(&["droplet-mpcd"]),
        "drying droplet of SRD solvent (docs/mpcd.md)",
    ),
    SEED_KEY,
    key(
        "boundary",
        "-",
        "\"slip\"",
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
    key(
        "system",
        "-",
        "required",
        Table,
        "colloids, droplet and box",
    ),
    key(
        "system.particles",
        "-",
        "0",
        Integer(0, 10_000_000),
        "colloids N (0: a pure-solvent droplet), placed at random with centres within R0 - d/2",
    )
    .also("they must fit: random sequential addition, at most phi0 = 0.3"),
    key(
        "system.diameter",
        "length",
        "4",
        Positive,
        "colloid diameter d; sets D0 = kT / (3 pi eta d) with Kikuchi's viscosity, and so Pe",
    ),
    key(
        "system.radius",
        "length",
        "required",
        Positive,
        "initial droplet radius R0",
    )
    .also("at least 2 cells"),
    key(
        "system.phi0",
        "-",
        "from radius",
        LeftOpen(0.0, 0.3),
        "initial colloid volume fraction N d^3 / (8 R0^3)",
    )
    .also("with colloids; not with system.radius"),
    key(
        "system.box",
        "length",
        "smallest whole number of cells >= 2 R0 + 4",
        Positive,
        "edge of the periodic box",
    )
    .also("at least 2 R0 + 4 cells, a whole number of cells"),
    key(
        "drying",
        "-",
        "-",
        Table,
        "the drying law R(t) = sqrt(R0^2 - alpha t / (4 pi)), as droplet-bd's",
    ),
    key(
        "drying.peclet",
        "-",
        "10",
        NonNegative,
        "Pe = R |dR/dt| / D0 (0: a static droplet)",
    )
    .also("not with drying.alpha"),
    key(
        "drying.alpha",
        "length^2 / time",
        "8 pi Pe D0",
        Positive,
        "rate of loss of surface area",
    ),
    key(
        "drying.final_volume_fraction",
        "-",
        "0.55 with colloids",
        LeftOpen(0.0, 0.64),
        "stop at this mean colloid volume fraction",
    )
    .also("with colloids; not with drying.duration"),
    key(
        "drying.duration",
        "time",
        "required without colloids",
        Positive,
        "stop after this time",
    )
    .also("R must stay above two cells"),
    key(
        "interface",
        "-",
        "-",
        Table,
        "the harmonic interface on the colloid centres, as droplet-bd's",
    ),
    key(
        "interface.stiffness",
        "energy / length^2",
        "50 kT / d^2",
        Positive,
        "spring constant k of V = k s^2 / 2, s = r - (R(t) + offset)",
    ),
    key(
        "interface.range",
        "length",
        "d / 2",
        Positive,
        "range of the harmonic part (linear beyond)",
    )
    .also("at most R0"),
    key(
        "interface.offset",
        "length",
        "-d / 2",
        Finite,
        "offset of the wall from R(t) (-d/2: the surface touches R)",
    )
    .also("in [-R0, R0]"),
    COLLOID[0],
    COLLOID[1],
    COLLOID[2],
    COLLOID[3],
    COLLOID[4],
    key("observe", "-", "-", Table, "observables"),
    key(
        "observe.every",
        "collisions",
        "collisions / 200",
        Integer(1, COUNT),
        "rows of thermo.csv (radius, solvent count, expected count, removed, bounced, temperature)",
    ),
    key("observe.profile", "-", "-", Table, "times of the profiles"),
    key(
        "observe.profile.bins",
        "-",
        "50",
        Integer(1, 100_000),
        "bins of the colloid volume-fraction profiles (with colloids)",
    ),
    key(
        "observe.profile.fractions",
        "-",
        "[0.0, 0.25, 0.5, 0.75, 1.0]",
        Numbers(0.0, 1.0, None),
        "fractions of the drying time at which profiles are taken",
    )
    .also("increasing, distinct collisions"),
    key(
        "observe.solvent",
        "-",
        "-",
        Table,
        "solvent density and radial velocity against r / R(t)",
    ),
    key(
        "observe.solvent.bins",
        "-",
        "20",
        Integer(1, 10_000),
        "bins over [0, R(t)]",
    ),
    key(
        "observe.solvent.window",
        "collisions",
        "collisions / 10",
        Integer(1, COUNT),
        "each solvent profile averages this many collisions ending at its time (10 blocks for the errors)",
    ),
    key("observe.trajectory", "-", "-", Table, "GSD trajectory"),
    key(
        "observe.trajectory.every",
        "collisions",
        "0",
        Integer(0, COUNT),
        "collisions between frames (0: none)",
    ),
    key(
        "observe.trajectory.solvent",
        "-",
        "false",
        Bool,
        "frames hold the solvent (type S, with velocities; log/radius)",
    )
    .also("true when frames are written without colloids"),
];

/// The keys of `mpcd` scenarios, as listed.
pub fn mpcd() -> Vec<Key> {
    MPCD.iter().map(Key::from).collect()
}

/// The keys of `droplet-mpcd` scenarios, as listed.
pub fn droplet_mpcd() -> Vec<Key> {
    DROPLET_MPCD.iter().map(Key::from).collect()
}

/// The keys of `hs-mc` scenarios, as listed.
pub fn mc() -> Vec<Key> {
    MC.iter().map(Key::from).collect()
}

/// The keys of `bcd` scenarios, as listed.
pub fn bcd() -> Vec<Key> {
    BCD.iter().map(Key::from).collect()
}

/// The keys of `droplet-bd` scenarios, as listed.
pub fn droplet() -> Vec<Key> {
    DROPLET.iter().map(Key::from).collect()
}

/// The keys of `bd` scenarios, as listed.
pub fn bulk() -> Vec<Key> {
    BULK.iter().map(Key::from).collect()
}

/// The keys of `dpd` scenarios, as listed.
pub fn dpd() -> Vec<Key> {
    DPD.iter().map(Key::from).collect()
}

/// Check a scenario's table against a method's keys: unknown keys (with the keys of that
/// table), types and each key's own range. `prefix` is the path of `table` (empty at the top).
pub fn validate(table: &toml::Table, spec: &[Spec]) -> Result<()> {
    walk(table, "", spec)
}

fn walk(table: &toml::Table, prefix: &str, spec: &[Spec]) -> Result<()> {
    for (k, v) in table {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        let Some(s) = spec.iter().find(|s| s.path == path) else {
            let siblings: Vec<&str> = spec
                .iter()
                .filter_map(|s| {
                    let rest = if prefix.is_empty() {
                        Some(s.path)
                    } else {
                        s.path
                            .strip_prefix(prefix)
                            .and_then(|r| r.strip_prefix('.'))
                    }?;
                    (!rest.contains('.')).then_some(rest)
                })
                .collect();
            let place = if prefix.is_empty() {
                "the top level".to_string()
            } else {
                format!("[{prefix}]")
            };
            bail!(
                "{path}: unknown key (the keys of {place} are: {}); see colloidsim keys",
                siblings.join(", ")
            );
        };
        if let Err(m) = s.allowed.check(v) {
            bail!("{path}: {m}");
        }
        if let (Allowed::Table, toml::Value::Table(t)) = (s.allowed, v) {
            walk(t, &path, spec)?;
        }
    }
    Ok(())
}

/// The keys as aligned text columns.
pub fn text(keys: &[Key]) -> String {
    let w = keys.iter().map(|k| k.path.len()).max().unwrap_or(4).max(4);
    let mut s = String::new();
    for k in keys {
        s.push_str(&format!(
            "{:<w$}  {}\n{:<w$}  unit: {}; default: {}; allowed: {}\n",
            k.path, k.doc, "", k.unit, k.default, k.range
        ));
    }
    s
}

/// A scenario's keys with their values and units, as `colloidsim check` prints them: every
/// key the scenario sets, then beside them the defaults it leaves (marked `(default)`), in the
/// order of the key table; keys inside an optional table the scenario leaves out, and
/// required keys it lacks, are not listed. Tables themselves are listed by their keys.
pub fn values(table: &toml::Table, keys: &[Key]) -> String {
    let lookup = |path: &str| -> Option<&toml::Value> {
        let mut parts = path.split('.');
        let mut v = table.get(parts.next()?)?;
        for p in parts {
            v = v.as_table()?.get(p)?;
        }
        Some(v)
    };
    let is_table = |k: &Key| k.range == Allowed::Table.describe();
    let tables: Vec<&Key> = keys.iter().filter(|k| is_table(k)).collect();
    let mut rows = Vec::new();
    for k in keys.iter().filter(|k| !is_table(k)) {
        let unit = if k.unit == "-" { "" } else { &k.unit };
        match lookup(&k.path) {
            Some(v) => rows.push((k.path.as_str(), v.to_string(), unit, "")),
            None => {
                let inside_absent = tables.iter().any(|t| {
                    k.path.starts_with(&format!("{}.", t.path)) && lookup(&t.path).is_none()
                });
                if !inside_absent && k.default != "required" {
                    rows.push((k.path.as_str(), k.default.clone(), unit, "(default)"));
                }
            }
        }
    }
    let wp = rows.iter().map(|r| r.0.len()).max().unwrap_or(0);
    let wv = rows.iter().map(|r| r.1.len()).max().unwrap_or(0).min(40);
    let wu = rows.iter().map(|r| r.2.len()).max().unwrap_or(0);
    let mut s = String::new();
    for (path, value, unit, mark) in rows {
        let line = format!("{path:<wp$} = {value:<wv$}  {unit:<wu$}  {mark}");
        s.push_str(line.trim_end());
        s.push('\n');
    }
    s
}

/// The keys as a Markdown table.
pub fn markdown(keys: &[Key]) -> String {
    let mut s =
        String::from("| key | unit | default | allowed | meaning |\n|---|---|---|---|---|\n");
    for k in keys {
        s.push_str(&format!(
            "| `{}` | {} | {} | {} | {} |\n",
            k.path,
            k.unit,
            k.default,
            k.range.replace('|', "\\|"),
            k.doc.replace('|', "\\|")
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> toml::Table {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn each_key_is_checked_alone_with_its_name_and_range() {
        let ok = table(
            "method = \"bcd\"\n[system]\nlength = 10\nparticles = 3\ndiameter = 0.5\n[run]\ndt = 1e-3\ntime = 1.0\n",
        );
        validate(&ok, BCD).unwrap();
        for (bad, words) in [
            (
                "[run]\ndt = -1",
                "run.dt: must be a finite number > 0, got -1",
            ),
            (
                "[run]\ndt = nan",
                "run.dt: must be a finite number > 0, got nan",
            ),
            (
                "[system]\nparticles = 2.5",
                "system.particles: must be an integer in [1,",
            ),
            (
                "[system]\nboundary = \"ring\"",
                "one of \"periodic\", \"walls\", got \"ring\"",
            ),
            (
                "[observe]\ncurrent = 1",
                "observe.current: must be true or false",
            ),
            (
                "[observe]\nnonsense = 1",
                "observe.nonsense: unknown key (the keys of [observe] are: every, density",
            ),
            (
                "sedd = 3",
                "sedd: unknown key (the keys of the top level are: method, seed, system",
            ),
            (
                "[potential]\ncosine = 3",
                "potential.cosine: must be a table",
            ),
            (
                "[potential.fourier]\nwavelength = 1\ncos = [1, \"a\"]",
                "potential.fourier.cos: must be a list of finite numbers",
            ),
            (
                "seed = 4294967296",
                "seed: must be an integer in [0, 4294967295]",
            ),
        ] {
            let e = validate(&table(bad), BCD).unwrap_err().to_string();
            assert!(e.contains(words), "{bad}: {e}");
        }
    }

    #[test]
    fn every_path_is_listed_once_under_a_listed_table() {
        for spec in [BCD, DROPLET, BULK, DPD, MC, MPCD, DROPLET_MPCD] {
            for (i, s) in spec.iter().enumerate() {
                assert!(
                    spec[..i].iter().all(|t| t.path != s.path),
                    "{} twice",
                    s.path
                );
                if let Some((parent, _)) = s.path.rsplit_once('.') {
                    assert!(
                        spec.iter()
                            .any(|t| t.path == parent && matches!(t.allowed, Allowed::Table)),
                        "{}: no table {parent}",
                        s.path
                    );
                }
            }
        }
    }
}
