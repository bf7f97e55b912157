//! The BCD scenario file (TOML) and its resolution into validated parameters.
//!
//! Every key is documented in `docs/bcd.md` with its unit and default; unknown keys are errors.
//! Units: lengths in the unit of `system.length`, energies in units of the energy scale of the
//! potential (kT = 1 by default), time in (length unit)^2 / D when mobility = kT = 1.

use crate::engine::{BcdConfig, Boundary, Integrator, Update};
use crate::forces::{CosineForce, ForceTable, PairForce, Sticky, TabulatedPair, Yukawa};
use crate::init;
use colloidsim_core::ParamError;
use colloidsim_core::field1d::{ExternalField, FieldTerm, PeriodicSpline};
use colloidsim_core::output::read_table;
use colloidsim_core::param;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The most steps a run may have (2^50).
const MAX_STEPS: f64 = 1_125_899_906_842_624.0;

/// A BCD scenario as written in the TOML file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// `bcd` (premerging) or `bcd-chronological`.
    pub method: String,
    /// Seed of all random streams (0 ..= 4294967295).
    #[serde(default = "one")]
    pub seed: u64,
    /// Physical system.
    pub system: System,
    /// External potential.
    #[serde(default)]
    pub potential: Potential,
    /// Pair interactions beyond the hard core.
    #[serde(default)]
    pub interaction: Interaction,
    /// Initial configuration.
    #[serde(default)]
    pub initial: Initial,
    /// Time stepping.
    pub run: Run,
    /// Observables.
    #[serde(default)]
    pub observe: Observe,
}

fn one() -> u64 {
    1
}
fn unit() -> f64 {
    1.0
}

/// `[system]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct System {
    /// Length L of the ring or channel.
    pub length: f64,
    /// Number of rods N.
    pub particles: usize,
    /// Rod length sigma (the hard-core diameter).
    pub diameter: f64,
    /// Mobility mu (default 1).
    #[serde(default = "unit")]
    pub mobility: f64,
    /// Thermal energy kT (default 1; 0 for deterministic dynamics).
    #[serde(default = "unit", rename = "kT")]
    pub kt: f64,
    /// `periodic` (default) or `walls`.
    #[serde(default = "periodic")]
    pub boundary: Boundary,
}

fn periodic() -> Boundary {
    Boundary::Periodic
}

/// `[potential]`: a sum of the terms given.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Potential {
    /// `U = (amplitude/2) cos(2 pi x / wavelength)`.
    pub cosine: Option<Cosine>,
    /// Constant force (tilted washboard).
    #[serde(default)]
    pub drive: f64,
    /// `U = stiffness/2 (x - centre)^2`.
    pub harmonic: Option<Harmonic>,
    /// `U = sum_n cos[n] cos(2 pi (n+1) x / wavelength) + sin[n] sin(...)`.
    pub fourier: Option<Fourier>,
    /// CSV file with columns `x,U` over exactly one period (last U equal to the first).
    pub table: Option<PathBuf>,
}

/// `potential.cosine`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cosine {
    /// Peak-to-peak height U0.
    pub amplitude: f64,
    /// Period lambda.
    pub wavelength: f64,
}

/// `potential.harmonic`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Harmonic {
    /// Spring constant.
    pub stiffness: f64,
    /// Trap centre (default L/2).
    pub centre: Option<f64>,
}

/// `potential.fourier`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fourier {
    /// Fundamental period.
    pub wavelength: f64,
    /// Cosine amplitudes of modes 1, 2, ...
    #[serde(default)]
    pub cos: Vec<f64>,
    /// Sine amplitudes of modes 1, 2, ...
    #[serde(default)]
    pub sin: Vec<f64>,
}

/// `[interaction]`.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Interaction {
    /// Baxter sticky contact (hard-rods paper Eq. 33).
    pub sticky: Option<StickySpec>,
    /// Screened-Coulomb repulsion of the surfaces.
    pub yukawa: Option<YukawaSpec>,
    /// CSV file with columns `r,f` (pair force, positive repulsive).
    pub table: Option<PathBuf>,
}

/// `interaction.sticky`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StickySpec {
    /// Strength gamma.
    pub gamma: f64,
    /// Virtual range eps (default 0.05).
    #[serde(default = "eps_default")]
    pub range: f64,
    /// Order p (default 3).
    #[serde(default = "order_default")]
    pub order: f64,
}
fn eps_default() -> f64 {
    0.05
}
fn order_default() -> f64 {
    3.0
}

/// `interaction.yukawa`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct YukawaSpec {
    /// Energy at contact.
    pub strength: f64,
    /// Screening length.
    pub screening: f64,
    /// Cutoff (centre distance).
    pub cutoff: f64,
}

/// `[initial]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Initial {
    /// `random` (default), `lattice` or `file`.
    #[serde(default = "random")]
    pub placement: String,
    /// CSV file with a column `x` (placement = "file").
    pub file: Option<PathBuf>,
}
fn random() -> String {
    "random".into()
}
impl Default for Initial {
    fn default() -> Self {
        Self {
            placement: random(),
            file: None,
        }
    }
}

/// `[run]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Run {
    /// Time step.
    pub dt: f64,
    /// Time run before sampling starts (default 0).
    #[serde(default)]
    pub equilibrate: f64,
    /// Time sampled.
    pub time: f64,
    /// Steps between checkpoints (default: about every 10% of the run).
    pub checkpoint_every: Option<u64>,
    /// Integrator of the free motion: `euler` (default) or `lm` (Leimkuhler–Matthews).
    pub integrator: Option<String>,
}

/// `[observe]`.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Observe {
    /// Steps between samples of density, contact density and clusters (default 1).
    pub every: Option<u64>,
    /// Density histogram.
    pub density: Option<Bins>,
    /// Two-particle density at contact.
    pub contact_density: Option<ContactSpec>,
    /// Mean-square displacement.
    pub msd: Option<MsdSpec>,
    /// Mean particle current.
    #[serde(default)]
    pub current: bool,
    /// Cluster-size distribution.
    #[serde(default)]
    pub clusters: bool,
    /// GSD trajectory.
    pub trajectory: Option<Trajectory>,
}

/// `observe.density`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bins {
    /// Number of bins over one period (or over L without a periodic potential).
    pub bins: usize,
}

/// `observe.contact_density`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Number of bins.
    pub bins: usize,
    /// Contact window Delta'.
    pub window: f64,
}

/// `observe.msd`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MsdSpec {
    /// Number of log-spaced lag times (default 40).
    #[serde(default = "msd_points")]
    pub points: usize,
    /// Longest lag time (default: half the sampled time).
    pub max_lag: Option<f64>,
}
fn msd_points() -> usize {
    40
}

/// `observe.trajectory`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Trajectory {
    /// Steps between frames (from the first production step).
    pub every: u64,
    /// Also write frames during equilibration (from step 0).
    #[serde(default)]
    pub equilibration: bool,
}

/// External force as the engine sees it.
#[derive(Debug, Clone)]
pub enum Field {
    /// No field.
    None,
    /// Cosine potentials (and a drive), evaluated exactly.
    Cosine(CosineForce),
    /// Periodic field from a table (exact to 1e-9).
    Table(ForceTable),
    /// Non-periodic field evaluated exactly.
    Exact(ExternalField),
}

impl Field {
    /// The fastest exact form of `field`: none, cosines evaluated directly, other periodic
    /// fields from a table, the rest evaluated term by term.
    pub fn new(field: &ExternalField) -> Self {
        if field.is_zero() {
            Field::None
        } else if let Some(c) = CosineForce::from_field(field) {
            Field::Cosine(c)
        } else if let Some(t) = ForceTable::from_field(field) {
            Field::Table(t)
        } else {
            Field::Exact(field.clone())
        }
    }
}

impl crate::forces::ExternalForce for Field {
    #[inline]
    fn force(&self, x: f64) -> f64 {
        match self {
            Field::None => 0.0,
            Field::Cosine(c) => c.force(x),
            Field::Table(t) => t.force(x),
            Field::Exact(f) => f.force(x),
        }
    }

    /// One dispatch per run of rods, then the field's own batched loop.
    #[inline]
    fn force_block(&self, x: &[f64], offset: f64, out: &mut [f64]) {
        match self {
            Field::None => out.fill(0.0),
            Field::Cosine(c) => c.force_block(x, offset, out),
            Field::Table(t) => t.force_block(x, offset, out),
            Field::Exact(f) => f.force_block(x, offset, out),
        }
    }

    #[inline]
    fn force_block_reduced(&self, y: &[f64], first: usize, sigma: f64, out: &mut [f64]) {
        match self {
            Field::None => out.fill(0.0),
            Field::Cosine(c) => c.force_block_reduced(y, first, sigma, out),
            Field::Table(t) => t.force_block_reduced(y, first, sigma, out),
            Field::Exact(f) => f.force_block_reduced(y, first, sigma, out),
        }
    }
}

/// Pair force as the engine sees it: any combination of the specified terms.
#[derive(Debug, Clone, Default)]
pub struct Pair {
    /// Sticky contact.
    pub sticky: Option<Sticky>,
    /// Yukawa.
    pub yukawa: Option<Yukawa>,
    /// Tabulated.
    pub table: Option<TabulatedPair>,
    range: f64,
}

impl PairForce for Pair {
    #[inline]
    fn range(&self) -> f64 {
        self.range
    }
    #[inline]
    fn force(&self, r: f64) -> f64 {
        let mut f = 0.0;
        if let Some(s) = &self.sticky {
            f += s.force(r);
        }
        if let Some(y) = &self.yukawa {
            f += y.force(r);
        }
        if let Some(t) = &self.table {
            f += t.force(r);
        }
        f
    }
}

/// Resolved, validated scenario.
#[derive(Debug, Clone)]
pub struct Resolved {
    /// Engine configuration.
    pub config: BcdConfig,
    /// Integrator of the free motion (`run.integrator`), for [`crate::Bcd::with_integrator`].
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
    /// Warnings worth showing to the user.
    pub warnings: Vec<String>,
}

impl Scenario {
    /// Validate and resolve. Relative file names are taken relative to `base`.
    pub fn resolve(&self, base: &Path, seed_override: Option<u64>) -> Result<Resolved, ParamError> {
        let update = match self.method.as_str() {
            "bcd" => Update::Premerge,
            "bcd-chronological" => Update::Chronological,
            m => {
                return Err(ParamError::new(
                    "method",
                    format!("'{m}' is not a BCD method (bcd, bcd-chronological)"),
                ));
            }
        };
        let integrator = match self.run.integrator.as_deref() {
            None | Some("euler") => Integrator::Euler,
            Some("lm") => Integrator::Lm,
            Some(other) => {
                return Err(ParamError::new(
                    "run.integrator",
                    format!(
                        "'{other}' is not one of: euler (Euler-Maruyama), lm (Leimkuhler-Matthews)"
                    ),
                ));
            }
        };
        let seed = seed_override.unwrap_or(self.seed);
        let seed = colloidsim_core::param::seed("seed", seed)?;
        let s = &self.system;
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
        config.validate(s.particles)?;
        let mut warnings = Vec::new();
        self.check_memory()?;

        let field = self.field(base)?;
        if let (Some(p), Boundary::Periodic) = (field.period(), s.boundary) {
            let k = s.length / p;
            if (k - k.round()).abs() > 1e-9 * k {
                return Err(ParamError::new(
                    "system.length",
                    format!(
                        "on a ring the length must be a whole number of potential periods ({p}); got {} = {k} periods",
                        s.length
                    ),
                ));
            }
        }
        let engine_field = Field::new(&field);

        let pair = self.pair(base, s.diameter, s.kt)?;
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
                ));
            } else if jump > 0.1 * st.eps {
                warnings.push(format!(
                    "run.dt: mu max|f| dt = {jump:.3e} is not much smaller than the sticky range {} (Eq. 34); results may depend on dt",
                    st.eps
                ));
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
            "random" => init::random(&config, s.particles, seed)?,
            "lattice" => init::lattice(&config, s.particles)?,
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
                    ));
                }
                init::from_positions(&config, x).map_err(naming(&path))?
            }
            p => {
                return Err(ParamError::new(
                    "initial.placement",
                    format!("'{p}' is not one of: random, lattice, file"),
                ));
            }
        };

        param::non_negative("run.equilibrate", self.run.equilibrate)?;
        param::positive("run.time", self.run.time)?;
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
                ));
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
                ));
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
            ));
        }
        if let Some(d) = &o.density {
            param::at_least("observe.density.bins", d.bins, 1)?;
        }
        if let Some(c) = &o.contact_density {
            param::at_least("observe.contact_density.bins", c.bins, 1)?;
            param::positive("observe.contact_density.window", c.window)?;
            // Colliding pairs end a BCD step at exactly zero gap. To leading order the gap is a
            // random walk stopped at contact, whose stationary law is the continuous one with the
            // wall moved out by delta = 0.5826 sqrt(2 D_rel dt), D_rel = 2D (Siegmund's
            // corrected diffusion approximation): rho2 in a window w is too high by ~ delta / w.
            // Leimkuhler–Matthews's correlated noise makes the layer 1.2-1.5x thicker (measured,
            // docs/validation.md).
            let thicker = if integrator == Integrator::Lm {
                1.5
            } else {
                1.0
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
            warnings,
        })
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
        let warn_above = if integrator == Integrator::Lm {
            0.2
        } else {
            0.02
        };
        if kappa > warn_above {
            warnings.push(format!(
                "run.dt: mu max|U''| dt = {kappa:.3}: expect a time-step bias of the density of several per cent (about 4 % at 0.12 with Euler; docs/bcd.md, time-step error); use a smaller run.dt{}",
                if integrator == Integrator::Lm { "" } else { " or run.integrator = \"lm\"" }
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

    fn field(&self, base: &Path) -> Result<ExternalField, ParamError> {
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
            let centre = h.centre.unwrap_or(0.5 * self.system.length);
            param::finite("potential.harmonic.centre", centre)?;
            terms.push(FieldTerm::Harmonic {
                stiffness: h.stiffness,
                centre,
                ring: (self.system.boundary == Boundary::Periodic).then_some(self.system.length),
            });
        }
        if let Some(f) = &p.fourier {
            param::positive("potential.fourier.wavelength", f.wavelength)?;
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
        let range = [
            sticky.as_ref().map(|s| s.range()),
            yukawa.as_ref().map(|y| y.range()),
            table.as_ref().map(|t| t.range()),
        ]
        .into_iter()
        .flatten()
        .fold(0.0, f64::max);
        Ok(Pair {
            sticky,
            yukawa,
            table,
            range,
        })
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

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(run_extra: &str) -> Result<Resolved, ParamError> {
        let text = format!(
            "method = \"bcd\"\n[system]\nlength = 20.0\nparticles = 10\ndiameter = 0.5\n\
             [run]\ndt = 1e-3\ntime = 1.0\n{run_extra}\n"
        );
        let sc: Scenario = toml::from_str(&text).expect("scenario syntax");
        sc.resolve(Path::new("."), None)
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

    #[test]
    fn lm_warns_with_sticky_rods_and_widens_the_contact_warning() {
        let sticky = |integrator: &str| {
            let text = format!(
                "method = \"bcd\"\n[system]\nlength = 20.0\nparticles = 10\ndiameter = 0.5\n\
                 [interaction]\nsticky = {{ gamma = 1.0 }}\n\
                 [run]\ndt = 1e-5\ntime = 1.0\nintegrator = \"{integrator}\"\n"
            );
            let sc: Scenario = toml::from_str(&text).expect("scenario syntax");
            sc.resolve(Path::new("."), None).unwrap().warnings
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
            let sc: Scenario = toml::from_str(&text).expect("scenario syntax");
            sc.resolve(Path::new("."), None).unwrap().warnings
        };
        assert!(contact_at("euler").is_empty());
        assert!(
            contact_at("lm")
                .iter()
                .any(|w| w.contains("observe.contact_density"))
        );
    }
}
