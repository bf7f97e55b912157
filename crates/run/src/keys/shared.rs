//! Sections that several methods share, declared once: every method that has them lists these
//! declarations (adding its own cross-key condition with [`Spec::also`] where it has one) and
//! reads them with the functions here, so that their defaults are computed in one place.

use super::Allowed::*;
use super::Omitted::*;
use super::{COUNT, Reader, Spec, key, rekey};
use anyhow::{Result, bail};
use colloidsim_core::ParamError;
use colloidsim_core::param::show;
use colloidsim_md::brownian::Integrator;
use colloidsim_md::hydro::params::{DEFAULT_BOX_FACTOR, DEFAULT_DIRECT_MAX};
use colloidsim_md::hydro::{HydroMethod, HydroModel, HydroParams};
use colloidsim_md::mpcd::{ColloidParams, MAX_BOND_STRAIN, SrdParams};

/// `[interface]`: the harmonic interface of a droplet (docs/droplet.md).
pub const INTERFACE: Spec = key(
    "interface",
    "-",
    Means("k = 50 kT/d^2, range d/2, offset -d/2"),
    Table,
    "harmonic interface V = k/2 s^2 for 0 <= s < range, linear beyond, s = r - (R(t) + offset)",
);

/// `interface.stiffness`.
pub const INTERFACE_STIFFNESS: Spec = key(
    "interface.stiffness",
    "energy / length^2",
    Means("50 kT / d^2"),
    Positive,
    "spring constant k",
);

/// `interface.range`.
pub const INTERFACE_RANGE: Spec = key(
    "interface.range",
    "length",
    Means("d / 2"),
    Positive,
    "range of the harmonic part Delta",
);

/// `interface.offset`.
pub const INTERFACE_OFFSET: Spec = key(
    "interface.offset",
    "length",
    Means("-d / 2"),
    Finite,
    "wall position relative to R(t) (-d/2: the colloid surface at R(t))",
);

/// `interface.hard` (the methods that have it say how they reflect, with [`Spec::also`]).
pub const INTERFACE_HARD: Spec = key(
    "interface.hard",
    "-",
    Value("false"),
    Bool,
    "a hard wall at R(t) + offset instead of the spring, the limit of an infinitely stiff interface: a centre that a step leaves a distance s beyond the wall ends s inside it; no interface force",
);

/// The interface's parameters as read: the keys given, else the defaults of the declarations
/// for spheres of diameter `d` at thermal energy `kt`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interface {
    /// Spring constant k (energy / length^2); 0 for a hard wall.
    pub stiffness: f64,
    /// Range of the harmonic part Delta (length); 0 for a hard wall.
    pub range: f64,
    /// Wall position relative to R(t) (length).
    pub offset: f64,
    /// A hard wall instead of the spring (`interface.hard`).
    pub hard: bool,
}

/// Read `[interface]` for spheres of diameter `d` at thermal energy `kt`; `hard` is the
/// method's declaration of `interface.hard` where it has one (a hard wall has no spring, so
/// `interface.stiffness` and `interface.range` are refused beside it).
pub fn interface(r: &Reader, d: f64, kt: f64, hard: Option<&Spec>) -> Result<Interface> {
    let offset = r.opt_number(&INTERFACE_OFFSET)?.unwrap_or(-0.5 * d);
    if let Some(h) = hard
        && r.flag(h)?
    {
        let spring = [&INTERFACE_STIFFNESS, &INTERFACE_RANGE];
        if let Some(k) = spring.into_iter().find(|k| r.has(k)) {
            bail!(ParamError::new(
                k.path,
                "a hard interface (interface.hard = true) has no spring: leave it out",
            ));
        }
        return Ok(Interface {
            stiffness: 0.0,
            range: 0.0,
            offset,
            hard: true,
        });
    }
    Ok(Interface {
        stiffness: r
            .opt_number(&INTERFACE_STIFFNESS)?
            .unwrap_or(50.0 * kt / (d * d)),
        range: r.opt_number(&INTERFACE_RANGE)?.unwrap_or(0.5 * d),
        offset,
        hard: false,
    })
}

/// `[drying]`: the radius law of both droplet methods (docs/droplet.md).
pub const DRYING: Spec = key(
    "drying",
    "-",
    Means("Pe = 10 to phi = 0.55"),
    Table,
    "the drying law R(t) = sqrt(R0^2 - alpha t / (4 pi))",
);

/// `drying.peclet`.
pub const DRYING_PECLET: Spec = key(
    "drying.peclet",
    "-",
    Value("10"),
    NonNegative,
    "Pe = R |dR/dt| / D0, constant in time; give this or drying.alpha. 0: a static droplet (R = R0), for equilibrium profiles",
)
.also("0 needs drying.duration");

/// `drying.alpha`.
pub const DRYING_ALPHA: Spec = key(
    "drying.alpha",
    "length^2 / time",
    Means("8 pi Pe D0"),
    Positive,
    "rate of loss of surface area",
);

/// `drying.final_volume_fraction` (each method adds its conditions with [`Spec::also`]).
pub const DRYING_FINAL_VOLUME_FRACTION: Spec = key(
    "drying.final_volume_fraction",
    "-",
    Value("0.55"),
    LeftOpen(0.0, 0.64),
    "run until the mean volume fraction reaches this; or give drying.duration",
);

/// `drying.duration` (each method adds its conditions with [`Spec::also`]).
pub const DRYING_DURATION: Spec = key(
    "drying.duration",
    "time",
    Means("until final_volume_fraction"),
    Positive,
    "run for this time",
);

/// The drying rate as read: `(peclet, alpha)` with `alpha = 8 pi Pe D0` for spheres of
/// diffusion coefficient `d0`, from `drying.peclet` or `drying.alpha` (not both).
pub fn drying_rate(r: &Reader, d0: f64) -> Result<(f64, f64)> {
    match r.opt_number(&DRYING_ALPHA)? {
        Some(_) if r.has(&DRYING_PECLET) => bail!(ParamError::new(
            DRYING_PECLET.path,
            "give either drying.peclet or drying.alpha, not both",
        )),
        Some(alpha) => Ok((alpha / (8.0 * std::f64::consts::PI * d0), alpha)),
        None => {
            let pe = r.number(&DRYING_PECLET)?;
            Ok((pe, 8.0 * std::f64::consts::PI * pe * d0))
        }
    }
}

/// `[solvent]`: the SRD solvent of both MPCD methods (MPCD units).
pub const SOLVENT: Spec = key(
    "solvent",
    "-",
    Means("-"),
    Table,
    "the SRD solvent (MPCD units: cell edge a, solvent mass m, kT)",
);

/// `solvent.density`.
pub const SOLVENT_DENSITY: Spec = key(
    "solvent.density",
    "particles / cell",
    Value("5"),
    LeftOpen(0.0, 1000.0),
    "mean particles per cell M",
)
.also("at least 3 (with fewer, most cells hold 0 or 1 particle and collide nothing)");

/// `solvent.angle`.
pub const SOLVENT_ANGLE: Spec = key(
    "solvent.angle",
    "degrees",
    Value("130"),
    LeftOpen(0.0, 180.0),
    "SRD rotation angle about a random axis per cell",
)
.suspicious(&[super::RADIANS]);

/// `solvent.tau`.
pub const SOLVENT_TAU: Spec = key(
    "solvent.tau",
    "time",
    Value("0.1"),
    Positive,
    "collision time (the streaming step)",
);

/// `solvent.kT`.
pub const SOLVENT_KT: Spec = key(
    "solvent.kT",
    "energy",
    Value("1"),
    Positive,
    "thermal energy",
)
.also("mean free path tau sqrt(kT/m) in [1e-4, 10] cells");

/// `solvent.mass`.
pub const SOLVENT_MASS: Spec = key(
    "solvent.mass",
    "mass",
    Value("1"),
    Positive,
    "solvent particle mass m",
);

/// `solvent.cell`.
pub const SOLVENT_CELL: Spec = key(
    "solvent.cell",
    "length",
    Value("1"),
    Positive,
    "collision cell edge a",
)
.also("every box edge a whole number of cells");

/// `solvent.thermostat`.
pub const SOLVENT_THERMOSTAT: Spec = key(
    "solvent.thermostat",
    "-",
    Value("true"),
    Bool,
    "cell-level Maxwell-Boltzmann thermostat (Huang et al. 2010)",
);

/// `[colloid]`: the discrete-particle colloid of both MPCD methods (defaults chosen,
/// docs/mpcd.md).
pub const COLLOID: Spec = key(
    "colloid",
    "-",
    Means("-"),
    Table,
    "the discrete-particle colloid: 42 vertices and a centre, harmonic bonds (defaults chosen, docs/mpcd.md)",
);

/// `colloid.vertex_mass`.
pub const COLLOID_VERTEX_MASS: Spec = key(
    "colloid.vertex_mass",
    "mass",
    Value("5"),
    Positive,
    "mass of each of the 42 vertices (they join the collisions)",
);

/// `colloid.centre_mass`.
pub const COLLOID_CENTRE_MASS: Spec = key(
    "colloid.centre_mass",
    "mass",
    Value("5"),
    Positive,
    "mass of the central particle (WCA between centres, the droplet's interface acts on it)",
);

/// `colloid.bond_k`.
pub const COLLOID_BOND_K: Spec = key(
    "colloid.bond_k",
    "energy / length^2",
    Derived("5000 solvent.kT", |r| Ok(5000.0 * r.number(&SOLVENT_KT)?)),
    Positive,
    "spring constant of the 120 edge and 42 spoke bonds",
);

/// `colloid.md_steps`.
pub const COLLOID_MD_STEPS: Spec = key(
    "colloid.md_steps",
    "-",
    Value("50"),
    Integer(1, 100_000),
    "velocity Verlet steps per collision time",
)
.also("resolve the bonds: omega dt at most 1, omega their fastest vibration");

/// The fewest mean particles per collision cell an SRD solvent may have.
pub const MIN_SOLVENT_DENSITY: f64 = 3.0;
/// The range of the mean free path `tau sqrt(kT/m)`, in cells.
pub const MEAN_FREE_PATH: (f64, f64) = (1e-4, 10.0);

/// Read `[solvent]` into the engine's parameters, with the run's `seed`: refused where the
/// solvent is too dilute to collide, or its particles stream absurdly far (or not at all)
/// between collisions.
pub fn solvent(r: &Reader, seed: u32) -> Result<SrdParams> {
    let density = r.number(&SOLVENT_DENSITY)?;
    if density < MIN_SOLVENT_DENSITY {
        bail!(
            "{}: {} particles per cell is below the minimum {MIN_SOLVENT_DENSITY}: with fewer, most collision cells hold 0 or 1 particle, which exchange no momentum, so the solvent has no SRD viscosity and its observables are not defined (use 3 to 10)",
            SOLVENT_DENSITY.path,
            show(density)
        );
    }
    let (kt, mass, tau, cell) = (
        r.number(&SOLVENT_KT)?,
        r.number(&SOLVENT_MASS)?,
        r.number(&SOLVENT_TAU)?,
        r.number(&SOLVENT_CELL)?,
    );
    let free_path = tau * (kt / mass).sqrt() / cell;
    if !(MEAN_FREE_PATH.0..=MEAN_FREE_PATH.1).contains(&free_path) {
        bail!(
            "{}: {} gives a mean free path tau sqrt(kT/m) = {free_path:.3e} cells (tau = {}, m = {}, cell = {}); it must be in [{}, {}] cells: {} (the usual SRD solvent: kT = 1, m = 1, tau = 0.1, a free path of 0.1 cells)",
            SOLVENT_KT.path,
            show(kt),
            show(tau),
            show(mass),
            show(cell),
            MEAN_FREE_PATH.0,
            MEAN_FREE_PATH.1,
            if free_path > MEAN_FREE_PATH.1 {
                "a particle would cross that many cells in one streaming step, and thermal velocities that large lose the positions' precision"
            } else {
                "the particles would not move between collisions"
            }
        );
    }
    Ok(SrdParams {
        cell: r.number(&SOLVENT_CELL)?,
        density: r.number(&SOLVENT_DENSITY)?,
        angle: r.number(&SOLVENT_ANGLE)?.to_radians(),
        tau: r.number(&SOLVENT_TAU)?,
        kt: r.number(&SOLVENT_KT)?,
        mass: r.number(&SOLVENT_MASS)?,
        thermostat: r.flag(&SOLVENT_THERMOSTAT)?,
        seed,
    })
}

/// Read `[colloid]` into the model of colloids of diameter `d` (WCA energy kT).
/// With `colloids` (any to simulate), the bonds must hold the sphere: a thermal bond strain
/// above [`MAX_BOND_STRAIN`] (a `d` far below the cell or a soft `colloid.bond_k`) is refused,
/// naming `diameter` (the key the caller read `d` from) unless only `colloid.bond_k` was given.
pub fn colloid(r: &Reader, diameter: &Spec, d: f64, colloids: bool) -> Result<ColloidParams> {
    let p = ColloidParams {
        diameter: d,
        vertex_mass: r.number(&COLLOID_VERTEX_MASS)?,
        centre_mass: r.number(&COLLOID_CENTRE_MASS)?,
        bond_k: r.number(&COLLOID_BOND_K)?,
        md_steps: r.integer(&COLLOID_MD_STEPS)? as u32,
        wca_epsilon: r.number(&SOLVENT_KT)?,
    };
    let kt = r.number(&SOLVENT_KT)?;
    let strain = p.thermal_bond_strain(kt);
    if colloids && (strain > MAX_BOND_STRAIN || strain.is_nan()) {
        let key = if r.has(&COLLOID_BOND_K) && !r.has(diameter) {
            &COLLOID_BOND_K
        } else {
            diameter
        };
        let stretch = (kt / p.bond_k).sqrt();
        let k_min = kt / (MAX_BOND_STRAIN * stretch / strain).powi(2);
        let stiffer = match k_min.is_finite() {
            true => format!(", or k at least {:.4e} at this diameter", k_min),
            false => String::new(),
        };
        return Err(ParamError::new(
            key.path,
            format!(
                "a colloid of diameter {} with {} = {} is not held in shape: its bonds stretch by sqrt(kT/k) = {stretch:.3e}, \
                 {strain:.3e} of the shortest bond (at most {MAX_BOND_STRAIN}); the diameter must be at least {:.4} at this k{stiffer}",
                show(d),
                COLLOID_BOND_K.path,
                show(p.bond_k),
                d * strain / MAX_BOND_STRAIN,
            ),
        )
        .into());
    }
    // Velocity Verlet over the bonds: omega dt at most 1 (stable below 2; at 1 the vibration's
    // frequency is already 5 % off).
    let tau = r.number(&SOLVENT_TAU)?;
    let omega = p.highest_bond_frequency();
    let dt = tau / p.md_steps as f64;
    if colloids && omega * dt > 1.0 {
        let key = [
            &COLLOID_BOND_K,
            &SOLVENT_TAU,
            &COLLOID_VERTEX_MASS,
            &COLLOID_CENTRE_MASS,
        ]
        .into_iter()
        .find(|k| r.has(k) && !r.has(&COLLOID_MD_STEPS))
        .unwrap_or(&COLLOID_MD_STEPS);
        let steps = (omega * tau).ceil();
        let more = match steps <= 100_000.0 {
            true => format!("at least {steps} {} at this k, or ", COLLOID_MD_STEPS.path),
            false => String::new(),
        };
        return Err(ParamError::new(
            key.path,
            format!(
                "{} Verlet steps per collision time {} = {} (dt = {}) do not resolve the colloid bonds' fastest \
                 vibration, omega = {:.4e} per time ({} = {}, masses {} and {}): omega dt = {:.4e}, at most 1 \
                 (velocity Verlet diverges above 2); {more}a softer {} (at most {:.4e})",
                p.md_steps,
                SOLVENT_TAU.path,
                show(tau),
                show(dt),
                omega,
                COLLOID_BOND_K.path,
                show(p.bond_k),
                show(p.vertex_mass),
                show(p.centre_mass),
                omega * dt,
                COLLOID_BOND_K.path,
                p.bond_k / (omega * dt).powi(2),
            ),
        )
        .into());
    }
    Ok(p)
}

// The spheres, the solvent, the time stepping and the hydrodynamics of the Brownian-dynamics
// methods (`droplet-bd`, `bd`): the same engines, units and defaults.

/// `system.diameter`.
pub const DIAMETER: Spec = key(
    "system.diameter",
    "length",
    Derived(
        "1; with system.species, the smallest of its diameters",
        |r| Ok(super::species::smallest_diameter(r)?.unwrap_or(1.0)),
    ),
    Positive,
    "colloid diameter d",
);

/// `system.kT`.
pub const KT: Spec = key(
    "system.kT",
    "energy",
    Value("1"),
    Positive,
    "thermal energy",
);

/// `system.viscosity`.
pub const VISCOSITY: Spec = key(
    "system.viscosity",
    "energy time / length^3",
    Value("1"),
    Positive,
    "solvent viscosity eta; friction 3 pi eta d, D0 = kT / (3 pi eta d)",
);

/// `run.dt`: by default `2e-4 d^2 / D0`.
pub const RUN_DT: Spec = key(
    "run.dt",
    "time",
    Derived("2e-4 d^2 / D0", |r| {
        let s = spheres(r)?;
        Ok(2e-4 * s.d * s.d / s.d0)
    }),
    Positive,
    "time step (too large a step for the WCA core stops the run naming the step and particle)",
)
.also("at most 1e12 steps");

/// `run.skin`: by default `0.6 d`.
pub const RUN_SKIN: Spec = key(
    "run.skin",
    "length",
    Derived("0.6 d", |r| Ok(0.6 * r.number(&DIAMETER)?)),
    Positive,
    "Verlet skin",
)
.also("in [0.001 d, 5 d]");

/// `run.tune_skin`.
pub const RUN_TUNE_SKIN: Spec = key(
    "run.tune_skin",
    "-",
    Value("false"),
    Bool,
    "choose the Verlet skin from measured step times before the run (candidates 0.2-1.2 d on copies of replica 0, discarded): run.skin is then ignored, the chosen skin and every candidate's time are in summary.json's parameters and the checkpoint (a rerun with run.skin set to it is bitwise the same run); free draining on one process",
);

/// `run.integrator`.
pub const RUN_INTEGRATOR: Spec = key(
        "run.integrator",
        "-",
        Word("euler"),
        OneOf(&["euler", "lm"]),
        "Euler-Maruyama, or Leimkuhler-Matthews (noise (xi_n + xi_n+1)/2: second order for the equilibrium profile, same cost; see docs/droplet.md)",
    )
    .also("lm needs free draining (not hydrodynamics.model = \"rpy\")");

/// `[observe.trajectory]`.
pub const TRAJECTORY: Spec = key(
    "observe.trajectory",
    "-",
    Means("none"),
    Table,
    "GSD frames of replica 0: trajectory.gsd",
);

/// `observe.trajectory.every`.
pub const TRAJECTORY_EVERY: Spec = key(
    "observe.trajectory.every",
    "steps",
    Value("0"),
    Integer(0, COUNT),
    "steps between frames (0: none)",
);

/// `[hydrodynamics]` (each method declares its own `method`, and `box_factor` where it has one).
pub const HYDRODYNAMICS: Spec = key(
    "hydrodynamics",
    "-",
    Means("free draining"),
    Table,
    "hydrodynamic interactions; without this table the free-draining engine runs",
);

/// `hydrodynamics.model`.
pub const HYDRO_MODEL: Spec = key(
    "hydrodynamics.model",
    "-",
    Word("free-draining"),
    OneOf(&["free-draining", "rpy"]),
    "mobility: free draining (the free-draining engine) or Rotne-Prager-Yamakawa (no drift term: divergence-free)",
);

/// `hydrodynamics.tolerance`.
pub const HYDRO_TOLERANCE: Spec = key(
    "hydrodynamics.tolerance",
    "-",
    Value("1e-3"),
    LeftOpen(0.0, colloidsim_md::hydro::params::MAX_TOLERANCE),
    "relative error of the PSE product and of each Lanczos square root",
);

/// `hydrodynamics.splitting`.
pub const HYDRO_SPLITTING: Spec = key(
    "hydrodynamics.splitting",
    "1 / length",
    Means("0.5 / a = 1 / d"),
    Positive,
    "PSE splitting parameter xi",
)
.also("method = \"pse\" only; real-space cut-off < half the box, grid <= 1024^3");

/// `hydrodynamics.max_iterations`.
pub const HYDRO_MAX_ITERATIONS: Spec = key(
    "hydrodynamics.max_iterations",
    "-",
    Value("200"),
    Integer(1, 1000),
    "Lanczos iteration limit; reaching it stops the run naming the step",
);

/// The Brownian spheres and their solvent as read, with the Stokes friction and the free
/// diffusivity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spheres {
    /// Diameter d.
    pub d: f64,
    /// kT.
    pub kt: f64,
    /// Viscosity eta.
    pub eta: f64,
    /// Stokes friction `3 pi eta d`.
    pub friction: f64,
    /// `D0 = kT / (3 pi eta d)` (Stokes–Einstein).
    pub d0: f64,
}

/// How far from overflow and underflow the scales of [`spheres`] must stay.
const SCALE_MARGIN: f64 = 1e30;

/// Read `system.diameter`, `system.kT` and `system.viscosity` (refused where the volume, time
/// and force scales they make are near overflow or underflow).
pub fn spheres(r: &Reader) -> Result<Spheres> {
    let d = r.number(&DIAMETER)?;
    let kt = r.number(&KT)?;
    let eta = r.number(&VISCOSITY)?;
    let friction = 3.0 * std::f64::consts::PI * eta * d;
    // Volumes (of many spheres: a droplet, a box), the time d^2/D0 and the force kT/d must
    // stay numbers with room to spare, or every length written comes out inf or 0.
    let volume = d.powi(3);
    let time = d * d * friction / kt;
    let force = kt / d;
    let fine = |x: f64| (x * SCALE_MARGIN).is_finite() && (x / SCALE_MARGIN).is_normal();
    if !(fine(volume) && fine(time) && fine(force)) {
        bail!(
            "{} = {}, {} = {}, {} = {}: the scales they make (the volume d^3 = {volume:e}, the time d^2/D0 = {time:e}, the force kT/d = {force:e}) must stay within 1e{} of the largest and smallest numbers; the Brownian methods work in units near the diameter (e.g. d = 1, kT = 1, viscosity = 1)",
            DIAMETER.path,
            show(d),
            KT.path,
            show(kt),
            VISCOSITY.path,
            show(eta),
            SCALE_MARGIN.log10()
        );
    }
    Ok(Spheres {
        d,
        kt,
        eta,
        friction,
        d0: kt / friction,
    })
}

/// Read `run.integrator`; `rpy`: the run has RPY hydrodynamics (for which the engine refuses
/// Leimkuhler–Matthews), the engine's error naming the key.
pub fn integrator(r: &Reader, rpy: bool) -> Result<Integrator> {
    let choice = match r.word(&RUN_INTEGRATOR)?.as_str() {
        "lm" => Integrator::Lm,
        _ => Integrator::Euler,
    };
    Ok(choice
        .check(rpy)
        .map_err(|e| rekey(e, &[("integrator", &RUN_INTEGRATOR)]))?)
}

/// Read `[hydrodynamics]` (`None` without the table) for `particles` spheres of radius
/// `radius`; `method` is the method's `hydrodynamics.method` key and `box_factor` its
/// `hydrodynamics.box_factor` (a droplet's periodic box), if it has one. `periodic`: the system
/// is a periodic cube, so RPY needs PSE; otherwise both methods are allowed and the default is
/// direct up to [`DEFAULT_DIRECT_MAX`] particles.
pub fn hydrodynamics(
    r: &Reader,
    method: &Spec,
    box_factor: Option<&Spec>,
    particles: usize,
    radius: f64,
    periodic: bool,
) -> Result<Option<HydroParams>> {
    if !r.has(&HYDRODYNAMICS) {
        return Ok(None);
    }
    let model = match r.word(&HYDRO_MODEL)?.as_str() {
        "rpy" => HydroModel::Rpy,
        _ => HydroModel::FreeDraining,
    };
    let chosen = r.opt_word(method)?.filter(|_| r.has(method));
    let method_of = match (model, chosen.as_deref()) {
        (HydroModel::FreeDraining, None) => None,
        (HydroModel::FreeDraining, Some(m)) => bail!(ParamError::new(
            method.path,
            format!("\"{m}\" needs model = \"rpy\" (free draining has no method)"),
        )),
        (HydroModel::Rpy, None) => Some(if periodic || particles > DEFAULT_DIRECT_MAX {
            HydroMethod::Pse
        } else {
            HydroMethod::Direct
        }),
        (HydroModel::Rpy, Some("direct")) if periodic => bail!(ParamError::new(
            method.path,
            "\"direct\" is the unbounded fluid; a periodic box needs \"pse\"",
        )),
        (HydroModel::Rpy, Some("direct")) => Some(HydroMethod::Direct),
        (HydroModel::Rpy, _) => Some(HydroMethod::Pse),
    };
    let tolerance = r.number(&HYDRO_TOLERANCE)?;
    let splitting = r.opt_number(&HYDRO_SPLITTING)?.unwrap_or(0.5 / radius);
    let factor = match box_factor {
        Some(k) => r.number(k)?,
        None => DEFAULT_BOX_FACTOR,
    };
    let p = HydroParams {
        model,
        method: method_of,
        tolerance,
        splitting,
        box_factor: factor,
        max_iterations: r.count(&HYDRO_MAX_ITERATIONS)? as usize,
    };
    let pse_only = [Some(&HYDRO_SPLITTING), box_factor];
    for k in pse_only.into_iter().flatten() {
        if r.has(k) && method_of != Some(HydroMethod::Pse) {
            bail!(ParamError::new(k.path, "applies only to method = \"pse\""));
        }
    }
    Ok(Some(p))
}

/// `observe.figure_format`: declared by every method, read once by the driver
/// ([`figure_format`]) for the pictures of the shared plotting module.
pub const FIGURE_FORMAT: Spec = key(
    "observe.figure_format",
    "-",
    Word("png"),
    OneOf(&["png", "svg", "both"]),
    "format of every picture: NAME.png (raster), NAME.svg (vector, for a paper) or both",
);

/// Keys every method declares that the driver, not the method's parameters, reads.
pub const DRIVER_KEYS: &[&str] = &[FIGURE_FORMAT.path];

/// `observe.figure_format` of a scenario's table (PNG when left out); a value not allowed is
/// refused naming the key.
pub fn figure_format(table: &toml::Table) -> Result<crate::output::plot::FigureFormat> {
    use crate::output::plot::FigureFormat;
    let Some(v) = table
        .get("observe")
        .and_then(|o| o.as_table())
        .and_then(|o| o.get("figure_format"))
    else {
        return Ok(FigureFormat::default());
    };
    if let Err(m) = FIGURE_FORMAT.allowed.check(v) {
        bail!("{}: {m}", FIGURE_FORMAT.path);
    }
    v.as_str()
        .and_then(FigureFormat::from_word)
        .ok_or_else(|| anyhow::anyhow!("{}: not a format", FIGURE_FORMAT.path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::droplet_bd::keys::{HYDRO_BOX_FACTOR, HYDRO_METHOD, KEYS};

    /// `[hydrodynamics]` with `text` read for `particles` spheres of radius 0.5 (the droplet's
    /// keys, which allow both methods and `box_factor`).
    fn read(text: &str, particles: usize, periodic: bool) -> Result<Option<HydroParams>> {
        let t: toml::Table = toml::from_str(&format!("[hydrodynamics]\n{text}")).unwrap();
        let r = Reader::new(&t, KEYS)?;
        hydrodynamics(
            &r,
            &HYDRO_METHOD,
            Some(&HYDRO_BOX_FACTOR),
            particles,
            0.5,
            periodic,
        )
    }

    /// The key an error names (a [`ParamError`]'s, or the declaration check's).
    fn key(text: &str, periodic: bool) -> String {
        let e = read(text, 100, periodic).unwrap_err();
        match e.downcast_ref::<ParamError>() {
            Some(p) => p.key.clone(),
            None => e.to_string().split(':').next().unwrap().to_string(),
        }
    }

    #[test]
    fn hydrodynamics_defaults_and_errors_name_the_key() {
        let t = toml::Table::new();
        let r = Reader::new(&t, KEYS).unwrap();
        let none = hydrodynamics(&r, &HYDRO_METHOD, None, 10, 0.5, false).unwrap();
        assert_eq!(none, None);
        let p = read("", 1000, false).unwrap().unwrap();
        assert_eq!((p.model, p.method), (HydroModel::FreeDraining, None));
        let p = read("model = \"rpy\"", 1000, false).unwrap().unwrap();
        assert_eq!(p.method, Some(HydroMethod::Direct));
        assert_eq!(
            (p.splitting, p.tolerance, p.max_iterations),
            (1.0, 1e-3, 200)
        );
        assert_eq!(p.box_factor, DEFAULT_BOX_FACTOR);
        let p = read("model = \"rpy\"", 50_000, false).unwrap().unwrap();
        assert_eq!(p.method, Some(HydroMethod::Pse));
        let p = read("model = \"rpy\"", 10, true).unwrap().unwrap();
        assert_eq!(p.method, Some(HydroMethod::Pse));
        for (text, periodic, k) in [
            ("model = \"oseen\"", false, "hydrodynamics.model"),
            (
                "model = \"rpy\"\ntolerance = 0.2",
                false,
                "hydrodynamics.tolerance",
            ),
            (
                "model = \"rpy\"\ntolerance = 0.0",
                false,
                "hydrodynamics.tolerance",
            ),
            (
                "model = \"rpy\"\nmethod = \"pse\"\nsplitting = -1",
                false,
                "hydrodynamics.splitting",
            ),
            (
                "model = \"rpy\"\nmethod = \"direct\"",
                true,
                "hydrodynamics.method",
            ),
            ("method = \"pse\"", false, "hydrodynamics.method"),
            (
                "model = \"rpy\"\nmethod = \"pse\"\nbox_factor = 1.0",
                false,
                "hydrodynamics.box_factor",
            ),
            (
                "model = \"rpy\"\nmethod = \"direct\"\nbox_factor = 2.0",
                false,
                "hydrodynamics.box_factor",
            ),
            (
                "model = \"rpy\"\nmethod = \"direct\"\nsplitting = 1.0",
                false,
                "hydrodynamics.splitting",
            ),
            (
                "model = \"rpy\"\nmax_iterations = 0",
                false,
                "hydrodynamics.max_iterations",
            ),
            ("speed = 1", false, "hydrodynamics.speed"),
        ] {
            assert_eq!(key(text, periodic), k, "{text}");
        }
        let e = read("model = \"rpy\"\ntolerance = 0.5", 10, false).unwrap_err();
        assert!(e.to_string().contains("(0, 0.01]"), "{e}");
    }
}
