//! A `bcd` scenario read through its key declarations ([`super::keys`]) into the parameters
//! the engine takes, with every check that relates several keys.
//!
//! Units: lengths in the unit of `system.length`, energies in units of the energy scale of the
//! potential (kT = 1 by default), time in (length unit)^2 / D when mobility = kT = 1.

use super::keys::*;
use crate::keys::{Reader, rekey};
use colloidsim_bcd::forces::{Field, Pair, Sticky, TabulatedPair, Yukawa};
use colloidsim_bcd::init;
use colloidsim_bcd::{BcdConfig, Boundary, Integrator, Update};
use colloidsim_core::ParamError;
use colloidsim_core::field1d::{ExternalField, FieldTerm, PeriodicSpline};
use colloidsim_core::output::read_table;
use colloidsim_core::param;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The most steps a run may have (2^50).
const MAX_STEPS: f64 = 1_125_899_906_842_624.0;

/// The most terms of each list of `potential.fourier`: the check of the time step samples the
/// force at 4096 points of a period, 16 per wavelength of the 256th harmonic, and the force
/// table a run uses (and `check` builds) resolves it with some 64,000 cells per period, built
/// from 5 evaluations of every term per cell (a few seconds); the 2e5 terms this once allowed
/// took hours. Finer shapes are a table (`potential.table`, a spline).
pub const MAX_FOURIER_TERMS: usize = 256;

/// A BCD scenario as given (the sections `summary.json` records as written; optional keys the
/// scenario leaves out stay `None`, their defaults come from the declarations).
#[derive(Debug, Clone, Serialize)]
pub struct Scenario {
    /// `bcd` (premerging) or `bcd-chronological`.
    pub method: String,
    /// Seed of all random streams.
    pub seed: u64,
    /// Physical system.
    pub system: System,
    /// External potential.
    pub potential: Potential,
    /// Pair interactions beyond the hard core.
    pub interaction: Interaction,
    /// Initial configuration.
    pub initial: Initial,
    /// Time stepping.
    pub run: Run,
    /// Observables.
    pub observe: Observe,
}

/// `[system]`.
#[derive(Debug, Clone, Serialize)]
pub struct System {
    /// Length L of the ring or channel.
    pub length: f64,
    /// Number of rods N.
    pub particles: usize,
    /// Rod length sigma (the hard-core diameter).
    pub diameter: f64,
    /// Mobility mu.
    pub mobility: f64,
    /// Thermal energy kT (0 for deterministic dynamics).
    #[serde(rename = "kT")]
    pub kt: f64,
    /// A ring or hard walls.
    pub boundary: Boundary,
}

/// `[potential]`: a sum of the terms given.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Potential {
    /// `U = (amplitude/2) cos(2 pi x / wavelength)`.
    pub cosine: Option<Cosine>,
    /// Constant force (tilted washboard).
    pub drive: f64,
    /// `U = stiffness/2 (x - centre)^2`.
    pub harmonic: Option<Harmonic>,
    /// `U = sum_n cos[n] cos(2 pi (n+1) x / wavelength) + sin[n] sin(...)`.
    pub fourier: Option<Fourier>,
    /// CSV file with columns `x,U` over exactly one period (last U equal to the first).
    pub table: Option<PathBuf>,
}

/// `potential.cosine`.
#[derive(Debug, Clone, Serialize)]
pub struct Cosine {
    /// Peak-to-peak height U0.
    pub amplitude: f64,
    /// Period lambda.
    pub wavelength: f64,
}

/// `potential.harmonic`.
#[derive(Debug, Clone, Serialize)]
pub struct Harmonic {
    /// Spring constant.
    pub stiffness: f64,
    /// Trap centre, if given.
    pub centre: Option<f64>,
}

/// `potential.fourier`.
#[derive(Debug, Clone, Serialize)]
pub struct Fourier {
    /// Fundamental period.
    pub wavelength: f64,
    /// Cosine amplitudes of modes 1, 2, ...
    pub cos: Vec<f64>,
    /// Sine amplitudes of modes 1, 2, ...
    pub sin: Vec<f64>,
}

/// `[interaction]`.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Interaction {
    /// Baxter sticky contact (hard-rods paper Eq. 33).
    pub sticky: Option<StickySpec>,
    /// Screened-Coulomb repulsion of the surfaces.
    pub yukawa: Option<YukawaSpec>,
    /// CSV file with columns `r,f` (pair force, positive repulsive).
    pub table: Option<PathBuf>,
}

/// `interaction.sticky`.
#[derive(Debug, Clone, Serialize)]
pub struct StickySpec {
    /// Strength gamma.
    pub gamma: f64,
    /// Virtual range eps.
    pub range: f64,
    /// Order p.
    pub order: f64,
}

/// `interaction.yukawa`.
#[derive(Debug, Clone, Serialize)]
pub struct YukawaSpec {
    /// Energy at contact.
    pub strength: f64,
    /// Screening length.
    pub screening: f64,
    /// Cutoff (centre distance).
    pub cutoff: f64,
}

/// `[initial]`.
#[derive(Debug, Clone, Serialize)]
pub struct Initial {
    /// `random`, `lattice` or `file`.
    pub placement: String,
    /// CSV file with a column `x` (placement = "file").
    pub file: Option<PathBuf>,
}

/// `[run]`.
#[derive(Debug, Clone, Serialize)]
pub struct Run {
    /// Time step.
    pub dt: f64,
    /// Time run before sampling starts.
    pub equilibrate: f64,
    /// Time sampled.
    pub time: f64,
    /// Steps between checkpoints, if given.
    pub checkpoint_every: Option<u64>,
    /// Integrator of the free motion: `euler` or `lm` (Leimkuhler–Matthews).
    pub integrator: Option<String>,
}

/// `[observe]`.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Observe {
    /// Steps between samples of density, contact density and clusters, if given.
    pub every: Option<u64>,
    /// Density histogram.
    pub density: Option<Bins>,
    /// Two-particle density at contact.
    pub contact_density: Option<ContactSpec>,
    /// Mean-square displacement.
    pub msd: Option<MsdSpec>,
    /// Mean particle current.
    pub current: bool,
    /// Cluster-size distribution.
    pub clusters: bool,
    /// GSD trajectory.
    pub trajectory: Option<Trajectory>,
}

/// `observe.density`.
#[derive(Debug, Clone, Serialize)]
pub struct Bins {
    /// Number of bins over one period (or over L without a periodic potential).
    pub bins: usize,
}

/// `observe.contact_density`.
#[derive(Debug, Clone, Serialize)]
pub struct ContactSpec {
    /// Number of bins.
    pub bins: usize,
    /// Contact window Delta'.
    pub window: f64,
}

/// `observe.msd`.
#[derive(Debug, Clone, Serialize)]
pub struct MsdSpec {
    /// Number of log-spaced lag times.
    pub points: usize,
    /// Longest lag time, if given.
    pub max_lag: Option<f64>,
}

/// `observe.trajectory`.
#[derive(Debug, Clone, Serialize)]
pub struct Trajectory {
    /// Steps between frames (from the first production step).
    pub every: u64,
    /// Also write frames during equilibration (from step 0).
    pub equilibration: bool,
}

impl Scenario {
    /// The scenario as given, read through the declarations of [`super::keys`] (which have
    /// checked every key's type and range).
    pub fn read(r: &Reader) -> anyhow::Result<Self> {
        let count = |k| -> anyhow::Result<usize> { Ok(r.count(k)? as usize) };
        Ok(Self {
            method: r.word(&METHOD)?,
            seed: r.count(&SEED)?,
            system: System {
                length: r.number(&SYSTEM_LENGTH)?,
                particles: count(&SYSTEM_PARTICLES)?,
                diameter: r.number(&SYSTEM_DIAMETER)?,
                mobility: r.number(&SYSTEM_MOBILITY)?,
                kt: r.number(&SYSTEM_KT)?,
                boundary: match r.word(&SYSTEM_BOUNDARY)?.as_str() {
                    "walls" => Boundary::Walls,
                    _ => Boundary::Periodic,
                },
            },
            potential: Potential {
                cosine: r.section(&POTENTIAL_COSINE, || {
                    Ok(Cosine {
                        amplitude: r.number(&POTENTIAL_COSINE_AMPLITUDE)?,
                        wavelength: r.number(&POTENTIAL_COSINE_WAVELENGTH)?,
                    })
                })?,
                drive: r.number(&POTENTIAL_DRIVE)?,
                harmonic: r.section(&POTENTIAL_HARMONIC, || {
                    Ok(Harmonic {
                        stiffness: r.number(&POTENTIAL_HARMONIC_STIFFNESS)?,
                        centre: r.if_given(&POTENTIAL_HARMONIC_CENTRE, Reader::number)?,
                    })
                })?,
                fourier: r.section(&POTENTIAL_FOURIER, || {
                    Ok(Fourier {
                        wavelength: r.number(&POTENTIAL_FOURIER_WAVELENGTH)?,
                        cos: r.numbers(&POTENTIAL_FOURIER_COS)?,
                        sin: r.numbers(&POTENTIAL_FOURIER_SIN)?,
                    })
                })?,
                table: r.file(&POTENTIAL_TABLE),
            },
            interaction: Interaction {
                sticky: r.section(&INTERACTION_STICKY, || {
                    Ok(StickySpec {
                        gamma: r.number(&INTERACTION_STICKY_GAMMA)?,
                        range: r.number(&INTERACTION_STICKY_RANGE)?,
                        order: r.number(&INTERACTION_STICKY_ORDER)?,
                    })
                })?,
                yukawa: r.section(&INTERACTION_YUKAWA, || {
                    Ok(YukawaSpec {
                        strength: r.number(&INTERACTION_YUKAWA_STRENGTH)?,
                        screening: r.number(&INTERACTION_YUKAWA_SCREENING)?,
                        cutoff: r.number(&INTERACTION_YUKAWA_CUTOFF)?,
                    })
                })?,
                table: r.file(&INTERACTION_TABLE),
            },
            initial: Initial {
                placement: r.word(&INITIAL_PLACEMENT)?,
                file: r.file(&INITIAL_FILE),
            },
            run: Run {
                dt: r.number(&RUN_DT)?,
                equilibrate: r.number(&RUN_EQUILIBRATE)?,
                time: r.number(&RUN_TIME)?,
                checkpoint_every: r.opt_count(&RUN_CHECKPOINT_EVERY)?,
                integrator: r.if_given(&RUN_INTEGRATOR, Reader::word)?,
            },
            observe: Observe {
                every: r.if_given(&OBSERVE_EVERY, Reader::count)?,
                density: r.section(&OBSERVE_DENSITY, || {
                    Ok(Bins {
                        bins: count(&OBSERVE_DENSITY_BINS)?,
                    })
                })?,
                contact_density: r.section(&OBSERVE_CONTACT_DENSITY, || {
                    Ok(ContactSpec {
                        bins: count(&OBSERVE_CONTACT_DENSITY_BINS)?,
                        window: r.number(&OBSERVE_CONTACT_DENSITY_WINDOW)?,
                    })
                })?,
                msd: r.section(&OBSERVE_MSD, || {
                    Ok(MsdSpec {
                        points: count(&OBSERVE_MSD_POINTS)?,
                        max_lag: r.if_given(&OBSERVE_MSD_MAX_LAG, Reader::number)?,
                    })
                })?,
                current: r.flag(&OBSERVE_CURRENT)?,
                clusters: r.flag(&OBSERVE_CLUSTERS)?,
                trajectory: r.section(&OBSERVE_TRAJECTORY, || {
                    Ok(Trajectory {
                        every: r.count(&OBSERVE_TRAJECTORY_EVERY)?,
                        equilibration: r.flag(&OBSERVE_TRAJECTORY_EQUILIBRATION)?,
                    })
                })?,
            },
        })
    }
}

/// Resolved, validated scenario.
#[derive(Debug, Clone)]
pub struct Resolved {
    /// Engine configuration.
    pub config: BcdConfig,
    /// Integrator of the free motion (`run.integrator`), for [`colloidsim_bcd::Bcd::with_integrator`].
    pub integrator: Integrator,
    /// The external field (potential and drive).
    pub field: ExternalField,
    /// Force as evaluated by the engine.
    pub engine_field: Field,
    /// Pair forces.
    pub pair: Pair,
    /// Initial rod centres.
    pub initial: Vec<f64>,
    /// Steps before sampling.
    pub equilibrate_steps: u64,
    /// Sampled steps.
    pub sampled_steps: u64,
    /// Folding period of profiles (the potential's period, or L).
    pub period: f64,
    /// Steps between samples of density, contact density and clusters.
    pub every: u64,
    /// Longest lag time of the MSD.
    pub msd_max_lag: f64,
    /// Warnings worth showing to the user.
    pub warnings: Vec<String>,
}

/// The engine's names of its parameters, and the keys that set them.
const ENGINE_NAMES: &[(&str, &crate::keys::Spec)] = &[
    ("length", &SYSTEM_LENGTH),
    ("sigma", &SYSTEM_DIAMETER),
    ("mobility", &SYSTEM_MOBILITY),
    ("kt", &SYSTEM_KT),
    ("dt", &RUN_DT),
    ("n", &SYSTEM_PARTICLES),
    ("positions", &INITIAL_FILE),
    ("gamma", &INTERACTION_STICKY_GAMMA),
    ("eps", &INTERACTION_STICKY_RANGE),
    ("order", &INTERACTION_STICKY_ORDER),
    ("strength", &INTERACTION_YUKAWA_STRENGTH),
    ("screening", &INTERACTION_YUKAWA_SCREENING),
    ("cutoff", &INTERACTION_YUKAWA_CUTOFF),
    ("table", &INTERACTION_TABLE),
];

/// An engine's error about one of its parameters, naming the scenario key instead.
fn keyed(e: ParamError) -> ParamError {
    rekey(e, ENGINE_NAMES)
}

impl Scenario {
    /// Validate and resolve; `r` gives the defaults the scenario leaves out. Relative file
    /// names are taken relative to `base`.
    pub fn resolve(
        &self,
        r: &Reader,
        base: &Path,
        seed_override: Option<u64>,
    ) -> anyhow::Result<Resolved> {
        let update = match self.method.as_str() {
            "bcd" => Update::Premerge,
            "bcd-chronological" => Update::Chronological,
            m => {
                return Err(ParamError::new(
                    "method",
                    format!("'{m}' is not a BCD method (bcd, bcd-chronological)"),
                )
                .into());
            }
        };
        let integrator = match self.run.integrator.as_deref() {
            None | Some("euler") => Integrator::Euler,
            Some("lm") => Integrator::Lm,
            Some("reflect") => Integrator::Reflect,
            Some(other) => {
                return Err(ParamError::new(
                    "run.integrator",
                    format!(
                        "'{other}' is not one of: euler (Euler-Maruyama), lm (Leimkuhler-Matthews), reflect (elastic collisions with LM)"
                    ),
                )
                .into());
            }
        };
        let seed = seed_override.unwrap_or(self.seed);
        let seed = colloidsim_core::param::seed("seed", seed)?;
        let s = &self.system;
        if integrator == Integrator::Reflect {
            self.check_reflect(update)?;
        }
        let config = BcdConfig {
            length: s.length,
            sigma: s.diameter,
            mobility: s.mobility,
            kt: s.kt,
            dt: self.run.dt,
            boundary: s.boundary,
            seed,
            update,
        };
        config.validate(s.particles).map_err(keyed)?;
        let mut warnings = Vec::new();
        self.check_memory()?;

        let field = self.field(r, base)?;
        if let (Some(p), Boundary::Periodic) = (field.period(), s.boundary) {
            let k = s.length / p;
            if (k - k.round()).abs() > 1e-9 * k {
                return Err(ParamError::new(
                    "system.length",
                    format!(
                        "on a ring the length must be a whole number of potential periods ({p}); got {} = {k} periods",
                        s.length
                    ),
                ).into());
            }
        }
        let engine_field = Field::new(&field);

        let pair = self.pair(base, s.diameter, s.kt).map_err(keyed)?;
        if let Some(st) = &pair.sticky {
            // Time-step criterion, hard-rods paper Eq. (34): mu max|f| dt << eps.
            let jump = s.mobility * st.max_force() * self.run.dt;
            if jump > st.eps {
                return Err(ParamError::new(
                    "run.dt",
                    format!(
                        "too large for the sticky range: mu max|f| dt = {jump:.3e} exceeds eps = {} (Eq. 34 needs << eps); use dt <= {:.2e}",
                        st.eps,
                        0.1 * st.eps / (s.mobility * st.max_force())
                    ),
                ).into());
            } else if jump > 0.1 * st.eps {
                warnings.push(format!(
                    "run.dt: mu max|f| dt = {jump:.3e} is not much smaller than the sticky range {} (Eq. 34); results may depend on dt",
                    st.eps
                ));
            }
        }

        if let Some(y) = &self.interaction.yukawa {
            // A rod at contact must not be thrown across the system in one step: beyond that the
            // force only measures rounding (the ring's net force of 1e-16 of it drifts every rod).
            let jump = s.mobility * (y.strength / y.screening).abs() * self.run.dt;
            if jump > s.length {
                return Err(ParamError::new(
                    "interaction.yukawa.strength",
                    format!(
                        "{} moves a rod at contact by mu |A| / l dt = {jump:.3e} in one step, more than the system length {}; use |A| <= {:.3e} (or a smaller run.dt)",
                        param::show(y.strength),
                        s.length,
                        s.length * y.screening / (s.mobility * self.run.dt)
                    ),
                )
                .into());
            }
        }

        if integrator == Integrator::Lm && pair.sticky.is_some() {
            warnings.push(
                "run.integrator = \"lm\" with interaction.sticky: the stiff contact force is outside \
                 LM's smooth regime; measured 2-5x less accurate than Euler at dt >= 3e-5 \
                 (docs/bcd.md, Time-step error); use integrator = \"euler\""
                    .to_string(),
            );
        }

        let initial = match self.initial.placement.as_str() {
            "random" => init::random(&config, s.particles, seed).map_err(keyed)?,
            "lattice" => init::lattice(&config, s.particles).map_err(keyed)?,
            "file" => {
                let f = self.initial.file.as_ref().ok_or_else(|| {
                    ParamError::new("initial.file", "placement = \"file\" needs a file name")
                })?;
                let path = base.join(f);
                let x = read_column(&path, "x", "initial.file")?;
                if x.len() != s.particles {
                    return Err(ParamError::new(
                        "initial.file",
                        format!(
                            "{} holds {} positions but system.particles = {}",
                            f.display(),
                            x.len(),
                            s.particles
                        ),
                    )
                    .into());
                }
                init::from_positions(&config, x)
                    .map_err(keyed)
                    .map_err(naming(&path))?
            }
            p => {
                return Err(ParamError::new(
                    "initial.placement",
                    format!("'{p}' is not one of: random, lattice, file"),
                )
                .into());
            }
        };

        param::non_negative("run.equilibrate", self.run.equilibrate)?;
        param::positive("run.time", self.run.time)?;
        if self.run.time < self.run.dt {
            return Err(ParamError::new(
                "run.time",
                format!(
                    "{:e} is less than one step (run.dt = {:e}): nothing would be sampled",
                    self.run.time, self.run.dt
                ),
            )
            .into());
        }
        // Step counts are checked as numbers before they become integers (a cast saturates).
        for (key, t) in [
            ("run.equilibrate", self.run.equilibrate),
            ("run.time", self.run.time),
        ] {
            let steps = (t / self.run.dt).round();
            if steps > MAX_STEPS {
                return Err(ParamError::new(
                    key,
                    format!("{key} / run.dt = {steps:e} steps is too many (at most 2^50)"),
                )
                .into());
            }
        }
        let equilibrate_steps = (self.run.equilibrate / self.run.dt).round() as u64;
        let sampled_steps = (self.run.time / self.run.dt).round().max(1.0) as u64;
        let o = &self.observe;
        if let Some(e) = o.every {
            param::at_least("observe.every", e as usize, 1)?;
            let sampled = o.density.is_some() || o.contact_density.is_some() || o.clusters;
            if sampled && e > sampled_steps {
                return Err(ParamError::new(
                    "observe.every",
                    format!(
                        "{e} steps between samples, but the run samples only {sampled_steps} steps (run.time / run.dt): no density, contact density or cluster sample would be taken"
                    ),
                ).into());
            }
        }
        if let Some(t) = &o.trajectory
            && t.every > equilibrate_steps + sampled_steps
        {
            return Err(ParamError::new(
                "observe.trajectory.every",
                format!(
                    "{} steps between frames, but the run has only {} steps: no frame would be written",
                    t.every,
                    equilibrate_steps + sampled_steps
                ),
            ).into());
        }
        if let Some(d) = &o.density {
            param::at_least("observe.density.bins", d.bins, 1)?;
        }
        if let Some(c) = &o.contact_density {
            param::at_least("observe.contact_density.bins", c.bins, 1)?;
            param::positive("observe.contact_density.window", c.window)?;
            // Gaps are resolved to the rounding of positions (1e-16 of the system length): a
            // window near it counts rounding, and rho2 = count / window overflows.
            if c.window < 1e-9 * s.length {
                return Err(ParamError::new(
                    "observe.contact_density.window",
                    format!(
                        "{} is below what the positions resolve: at least 1e-9 of the system length, {:e}",
                        param::show(c.window),
                        1e-9 * s.length
                    ),
                )
                .into());
            }
            // Colliding pairs end a BCD step at exactly zero gap. To leading order the gap is a
            // random walk stopped at contact, whose stationary law is the continuous one with the
            // wall moved out by delta = 0.5826 sqrt(2 D_rel dt), D_rel = 2D (Siegmund's
            // corrected diffusion approximation): rho2 in a window w is too high by ~ delta / w.
            // Leimkuhler–Matthews's correlated noise makes the layer 1.2-1.5x thicker (measured,
            // docs/validation.md).
            let thicker = match integrator {
                Integrator::Lm => 1.5,
                Integrator::Euler => 1.0,
                // Reflecting collisions leave no boundary layer.
                Integrator::Reflect => 0.0,
            };
            let delta = thicker * 0.5826 * (4.0 * s.mobility * s.kt * self.run.dt).sqrt();
            let bias = delta / c.window;
            if bias > 0.05 {
                warnings.push(format!(
                    "observe.contact_density: rho2 in a window of {} is biased upwards by about {:.0}% at run.dt = {} (time-step boundary layer {delta:.2e}); widen the window or use dt <= {:.1e}",
                    c.window,
                    100.0 * bias,
                    self.run.dt,
                    (0.05 * c.window / (thicker * 0.5826)).powi(2)
                        / (4.0 * s.mobility * s.kt.max(1e-300))
                ));
            }
        }
        if let Some(m) = &o.msd {
            param::at_least("observe.msd.points", m.points, 2)?;
            if let Some(l) = m.max_lag {
                param::in_range("observe.msd.max_lag", l, self.run.dt, self.run.time)?;
            }
        }
        if let Some(t) = &o.trajectory {
            param::at_least("observe.trajectory.every", t.every as usize, 1)?;
        }
        let period = match (field.period(), s.boundary) {
            (Some(p), Boundary::Periodic) => p,
            _ => s.length,
        };
        self.check_time_step(
            &field,
            period,
            integrator,
            equilibrate_steps + sampled_steps,
            &mut warnings,
        )?;
        Ok(Resolved {
            config,
            integrator,
            field,
            engine_field,
            pair,
            initial,
            equilibrate_steps,
            sampled_steps,
            period,
            every: r.count(&OBSERVE_EVERY)?,
            msd_max_lag: r.number(&OBSERVE_MSD_MAX_LAG)?,
            warnings,
        })
    }

    /// What `run.integrator = "reflect"` cannot do (yet), refused naming the keys.
    fn check_reflect(&self, update: Update) -> Result<(), ParamError> {
        let why = |key: &str, what: &str| {
            Err(ParamError::new(
                key,
                format!(
                    "run.integrator = \"reflect\" {what}; use run.integrator = \"euler\" or \"lm\" (docs/bcd.md, Which to use)"
                ),
            ))
        };
        if update == Update::Chronological {
            return why(
                "method",
                "replaces the collision rule, so it has no chronological (inelastic) variant: use method = \"bcd\"",
            );
        }
        if self.system.kt == 0.0 {
            return why(
                "system.kT",
                "needs kT > 0: without noise, rods pressed together would bounce off each other instead of moving as a cluster",
            );
        }
        if self.interaction.sticky.is_some() {
            return why(
                "interaction.sticky",
                "is not validated for sticky rods (their contact force is stiff, and no rods end a step in contact)",
            );
        }
        if self.observe.clusters {
            return why(
                "observe.clusters",
                "never leaves rods in contact at the end of a step (collisions are elastic), so there are no clusters to count",
            );
        }
        Ok(())
    }

    /// Refuse a run whose rods and observers would not fit in the machine's memory, before
    /// anything is allocated: about 96 B per rod for the engine and its copies, 8 B per rod for
    /// each stored MSD origin (at most about 100), 16 B per histogram bin.
    fn check_memory(&self) -> Result<(), ParamError> {
        let n = self.system.particles as f64;
        let o = &self.observe;
        let msd_origins = if o.msd.is_some() { 101.0 } else { 0.0 };
        let bins = o.density.as_ref().map_or(0, |d| d.bins)
            + o.contact_density.as_ref().map_or(0, |d| d.bins);
        let bytes = n * (96.0 + 8.0 * msd_origins) + 16.0 * bins as f64;
        let what = if msd_origins > 0.0 {
            format!("{n} rods with their MSD time origins")
        } else {
            format!("{n} rods")
        };
        colloidsim_core::resources::ensure_fits("system.particles", &what, bytes)
    }

    /// The time step against the field (the Euler step's bias of the density grows with
    /// `kappa = mu max|U''| dt`: about 4 % at kappa = 0.12, hard-rods paper Fig. 3 case; the
    /// step overshoots a well at kappa >= 1) and against the precision of the positions the
    /// run reaches (f64 must resolve the rod diameter there).
    fn check_time_step(
        &self,
        field: &ExternalField,
        period: f64,
        integrator: Integrator,
        steps: u64,
        warnings: &mut Vec<String>,
    ) -> Result<(), ParamError> {
        let s = &self.system;
        let dt = self.run.dt;
        // max |dF/dx| and max |F| sampled on 4096 points of one period (or of L).
        let m = 4096;
        let h = period / m as f64;
        let (mut curv, mut fmax) = (0.0f64, field.drive.abs());
        let mut f0 = field.force(0.0);
        for k in 1..=m {
            let f1 = field.force(k as f64 * h);
            curv = curv.max(((f1 - f0) / h).abs());
            fmax = fmax.max(f1.abs());
            f0 = f1;
        }
        let kappa = s.mobility * curv * dt;
        if !kappa.is_finite() || kappa >= 1.0 {
            return Err(ParamError::new(
                "run.dt",
                format!(
                    "too large for the potential: mu max|U''| dt = {kappa:.3e} >= 1, so a step overshoots its well and the density would be wrong by tens of per cent; use run.dt <= {:.2e} (docs/bcd.md, time-step error)",
                    0.02 / (s.mobility * curv)
                ),
            ));
        }
        let warn_above = if integrator == Integrator::Euler {
            0.02
        } else {
            0.2
        };
        if kappa > warn_above {
            warnings.push(format!(
                "run.dt: mu max|U''| dt = {kappa:.3}: expect a time-step bias of the density of several per cent (about 4 % at 0.12 with Euler; docs/bcd.md, time-step error); use a smaller run.dt{}",
                if integrator == Integrator::Euler { " or run.integrator = \"lm\"" } else { "" }
            ));
        }
        // How far the positions go: the system, the drift and the noise over the run.
        let t = steps as f64 * dt;
        let extent = s.length + s.mobility * fmax * t + 10.0 * (2.0 * s.mobility * s.kt * t).sqrt();
        let resolution = extent * f64::EPSILON;
        if !extent.is_finite() || resolution * 1e6 > s.diameter {
            return Err(ParamError::new(
                "system.diameter",
                format!(
                    "positions would reach about {extent:.3e}, where f64 resolves only {resolution:.1e}: not enough for rods of diameter {} (the hard core would be lost to rounding); lower the forces, the mobility or the run time",
                    s.diameter
                ),
            ));
        }
        Ok(())
    }

    fn field(&self, r: &Reader, base: &Path) -> Result<ExternalField, ParamError> {
        let p = &self.potential;
        let mut terms = Vec::new();
        if let Some(c) = &p.cosine {
            param::finite("potential.cosine.amplitude", c.amplitude)?;
            param::positive("potential.cosine.wavelength", c.wavelength)?;
            terms.push(FieldTerm::Cosine {
                amplitude: c.amplitude,
                wavelength: c.wavelength,
            });
        }
        if let Some(h) = &p.harmonic {
            param::non_negative("potential.harmonic.stiffness", h.stiffness)?;
            let centre = r
                .number(&POTENTIAL_HARMONIC_CENTRE)
                .map_err(|e| ParamError::new(POTENTIAL_HARMONIC_CENTRE.path, format!("{e:#}")))?;
            param::finite("potential.harmonic.centre", centre)?;
            terms.push(FieldTerm::Harmonic {
                stiffness: h.stiffness,
                centre,
                ring: (self.system.boundary == Boundary::Periodic).then_some(self.system.length),
            });
        }
        if let Some(f) = &p.fourier {
            param::positive("potential.fourier.wavelength", f.wavelength)?;
            for (key, terms) in [
                (POTENTIAL_FOURIER_COS.path, &f.cos),
                (POTENTIAL_FOURIER_SIN.path, &f.sin),
            ] {
                if terms.len() > MAX_FOURIER_TERMS {
                    return Err(ParamError::new(
                        key,
                        format!(
                            "{} terms: at most {MAX_FOURIER_TERMS} (every force evaluation sums them all, and the run tabulates the force on up to 2^22 points per period before it starts); give a finer shape as potential.table",
                            terms.len()
                        ),
                    ));
                }
            }
            for v in f.cos.iter().chain(&f.sin) {
                param::finite("potential.fourier", *v)?;
            }
            let m = f.cos.len().max(f.sin.len());
            let mut c = f.cos.clone();
            let mut s = f.sin.clone();
            c.resize(m, 0.0);
            s.resize(m, 0.0);
            terms.push(FieldTerm::Fourier {
                wavelength: f.wavelength,
                cos: c,
                sin: s,
            });
        }
        if let Some(t) = &p.table {
            let path = base.join(t);
            let (x, u) = read_pair(&path, ("x", "U"), "potential.table")?;
            terms.push(FieldTerm::Tabulated(
                PeriodicSpline::new("potential.table", x, u).map_err(naming(&path))?,
            ));
        }
        param::finite("potential.drive", p.drive)?;
        Ok(ExternalField {
            terms,
            drive: p.drive,
        })
    }

    fn pair(&self, base: &Path, sigma: f64, kt: f64) -> Result<Pair, ParamError> {
        let i = &self.interaction;
        let sticky = i
            .sticky
            .as_ref()
            .map(|s| Sticky::new(s.gamma, s.range, s.order, sigma, kt))
            .transpose()?;
        let yukawa = i
            .yukawa
            .as_ref()
            .map(|y| Yukawa::new(y.strength, y.screening, y.cutoff, sigma))
            .transpose()?;
        let table = match &i.table {
            Some(t) => {
                let path = base.join(t);
                let (r, f) = read_pair(&path, ("r", "f"), "interaction.table")?;
                Some(TabulatedPair::new(r, f, sigma).map_err(naming(&path))?)
            }
            None => None,
        };
        Ok(Pair::new(sticky, yukawa, table))
    }
}

/// An error about the content of an input file, with the file named first.
fn naming(path: &Path) -> impl Fn(ParamError) -> ParamError + '_ {
    move |e| {
        let file = path.display().to_string();
        if e.message.contains(&file) {
            e
        } else {
            ParamError::new(e.key, format!("{file}: {}", e.message))
        }
    }
}

fn read_column(path: &Path, name: &str, key: &str) -> Result<Vec<f64>, ParamError> {
    let (h, cols) = read_table(path).map_err(|e| ParamError::new(key, e))?;
    let j = h.iter().position(|c| c == name).ok_or_else(|| {
        ParamError::new(
            key,
            format!(
                "{} has no column '{name}' (header: {})",
                path.display(),
                h.join(",")
            ),
        )
    })?;
    Ok(cols[j].clone())
}

fn read_pair(
    path: &Path,
    names: (&str, &str),
    key: &str,
) -> Result<(Vec<f64>, Vec<f64>), ParamError> {
    Ok((
        read_column(path, names.0, key)?,
        read_column(path, names.1, key)?,
    ))
}

/// A scenario's table checked against [`KEYS`], read, and resolved (with `seed` replacing the
/// scenario's); relative file names are taken from `base`.
pub fn read(
    table: &toml::Table,
    base: &Path,
    seed: Option<u64>,
) -> anyhow::Result<(Scenario, Resolved)> {
    let r = Reader::new(table, KEYS)?;
    let sc = Scenario::read(&r)?;
    let resolved = sc.resolve(&r, base, seed)?;
    Ok((sc, resolved))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario_text(run_extra: &str) -> String {
        format!(
            "method = \"bcd\"\n[system]\nlength = 20.0\nparticles = 10\ndiameter = 0.5\n\
             [run]\ndt = 1e-3\ntime = 1.0\n{run_extra}\n"
        )
    }

    fn scenario(run_extra: &str) -> anyhow::Result<Resolved> {
        let text = scenario_text(run_extra);
        read(
            &toml::from_str(&text).expect("scenario syntax"),
            Path::new("."),
            None,
        )
        .map(|(_, r)| r)
    }

    /// A scenario with every table, so that every key is read.
    const FULL: &str = r#"
method = "bcd"
seed = 1
[system]
length = 20.0
particles = 10
diameter = 0.5
[potential]
cosine = { amplitude = 1.0, wavelength = 1.0 }
harmonic = { stiffness = 0.1 }
fourier = { wavelength = 2.0, cos = [0.1] }
[interaction]
sticky = { gamma = 1.0 }
yukawa = { strength = 1.0, screening = 0.5, cutoff = 2.0 }
[run]
dt = 1e-5
time = 0.01
[observe]
density = { bins = 10 }
contact_density = { bins = 10, window = 0.1 }
msd = { points = 40 }
trajectory = { every = 10 }
"#;

    #[test]
    fn every_declared_key_is_read() {
        let table: toml::Table = toml::from_str(FULL).unwrap();
        let r = Reader::new(&table, KEYS).unwrap();
        let sc = Scenario::read(&r).unwrap();
        sc.resolve(&r, Path::new("."), None).unwrap();
        assert_eq!(r.unread(), Vec::<&str>::new());
        // Without the optional tables their keys are not read (the check can fail).
        let bare: toml::Table = toml::from_str(&scenario_text("")).unwrap();
        let r = Reader::new(&bare, KEYS).unwrap();
        Scenario::read(&r).unwrap();
        assert!(r.unread().contains(&"potential.cosine.amplitude"));
    }

    #[test]
    fn derived_defaults_are_computed_from_the_keys_they_name() {
        let table: toml::Table = toml::from_str(FULL).unwrap();
        let (sc, resolved) = read(&table, Path::new("."), None).unwrap();
        // observe.msd.max_lag: run.time / 2.
        assert_eq!(resolved.msd_max_lag, 0.5 * sc.run.time);
        // potential.harmonic.centre: L/2.
        let r = Reader::new(&table, KEYS).unwrap();
        assert_eq!(
            r.number(&POTENTIAL_HARMONIC_CENTRE).unwrap(),
            0.5 * sc.system.length
        );
    }

    #[test]
    fn the_engine_s_checks_name_the_scenario_key() {
        let refused = |text: &str| {
            let e = read(&toml::from_str(text).unwrap(), Path::new("."), None).unwrap_err();
            format!("{e:#}")
        };
        let crowded = "method = \"bcd\"\n[system]\nlength = 5.0\nparticles = 10\n\
                       diameter = 0.5\n[run]\ndt = 1e-3\ntime = 1.0\n";
        let e = refused(crowded);
        assert!(e.contains("system.particles: 10 rods"), "{e}");
        let wide = "method = \"bcd\"\n[system]\nlength = 20.0\nparticles = 10\n\
                    diameter = 0.5\n[interaction]\nsticky = { gamma = 1.0, range = 0.6 }\n\
                    [run]\ndt = 1e-6\ntime = 1.0\n";
        let e = refused(wide);
        assert!(
            e.contains("interaction.sticky.range: must be much smaller"),
            "{e}"
        );
    }

    /// A run shorter than one step samples nothing (it used to take one step and write NaN
    /// error bars).
    #[test]
    fn a_run_shorter_than_one_step_is_refused() {
        let run = |time: &str| {
            let text = format!(
                "method = \"bcd\"\n[system]\nlength = 20.0\nparticles = 10\ndiameter = 0.5\n\
                 [run]\ndt = 1e-3\ntime = {time}\n"
            );
            read(&toml::from_str(&text).unwrap(), Path::new("."), None)
        };
        let e = format!("{:#}", run("1e-300").unwrap_err());
        assert!(e.contains("run.time: 1e-300 is less than one step"), "{e}");
        run("1e-3").unwrap();
    }

    #[test]
    fn run_integrator_is_parsed_and_defaults_to_euler() {
        assert_eq!(scenario("").unwrap().integrator, Integrator::Euler);
        let euler = scenario("integrator = \"euler\"").unwrap();
        assert_eq!(euler.integrator, Integrator::Euler);
        assert_eq!(
            scenario("integrator = \"lm\"").unwrap().integrator,
            Integrator::Lm
        );
    }

    #[test]
    fn unknown_integrator_names_the_key_and_the_choices() {
        let e = scenario("integrator = \"rk4\"").unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("run.integrator") && msg.contains("rk4"),
            "{msg}"
        );
        assert!(msg.contains("euler") && msg.contains("lm"), "{msg}");
        // Names are case-sensitive, like every other choice in a scenario.
        assert!(scenario("integrator = \"LM\"").is_err());
    }

    /// `run.integrator = "reflect"` is read, and what it cannot do is refused naming the key.
    #[test]
    fn reflect_is_read_and_refuses_what_it_cannot_do() {
        assert_eq!(
            scenario("integrator = \"reflect\"").unwrap().integrator,
            Integrator::Reflect
        );
        let refused = |method: &str, system: &str, extra: &str| {
            let text = format!(
                "method = \"{method}\"\n[system]\nlength = 20.0\nparticles = 10\ndiameter = 0.5\n{system}\n\
                 {extra}\n[run]\ndt = 1e-5\ntime = 1.0\nintegrator = \"reflect\"\n"
            );
            read(
                &toml::from_str(&text).expect("scenario syntax"),
                Path::new("."),
                None,
            )
            .map(|_| ())
            .unwrap_err()
            .to_string()
        };
        for (method, system, extra, key) in [
            ("bcd", "kT = 0.0", "", "system.kT"),
            (
                "bcd",
                "",
                "[interaction]\nsticky = { gamma = 1.0 }",
                "interaction.sticky",
            ),
            ("bcd", "", "[observe]\nclusters = true", "observe.clusters"),
            ("bcd-chronological", "", "", "method"),
        ] {
            let msg = refused(method, system, extra);
            assert!(msg.contains(key) && msg.contains("reflect"), "{key}: {msg}");
        }
    }

    #[test]
    fn lm_warns_with_sticky_rods_and_widens_the_contact_warning() {
        let sticky = |integrator: &str| {
            let text = format!(
                "method = \"bcd\"\n[system]\nlength = 20.0\nparticles = 10\ndiameter = 0.5\n\
                 [interaction]\nsticky = {{ gamma = 1.0 }}\n\
                 [run]\ndt = 1e-5\ntime = 1.0\nintegrator = \"{integrator}\"\n"
            );
            read(
                &toml::from_str(&text).expect("scenario syntax"),
                Path::new("."),
                None,
            )
            .unwrap()
            .1
            .warnings
        };
        assert!(sticky("lm").iter().any(|w| w.contains("sticky")));
        assert!(!sticky("euler").iter().any(|w| w.contains("run.integrator")));
        // delta / w at window 0.02 and dt = 5e-7: 0.5826 sqrt(2e-6) / 0.02 = 4.1% for Euler
        // (no warning), 1.5 times that for LM (warned).
        let contact_at = |integrator: &str| {
            let text = format!(
                "method = \"bcd\"\n[system]\nlength = 20.0\nparticles = 10\ndiameter = 0.5\n\
                 [run]\ndt = 5e-7\ntime = 1.0\nintegrator = \"{integrator}\"\n\
                 [observe]\ncontact_density = {{ bins = 10, window = 0.02 }}\n"
            );
            read(
                &toml::from_str(&text).expect("scenario syntax"),
                Path::new("."),
                None,
            )
            .unwrap()
            .1
            .warnings
        };
        assert!(contact_at("euler").is_empty());
        assert!(
            contact_at("lm")
                .iter()
                .any(|w| w.contains("observe.contact_density"))
        );
    }
}
