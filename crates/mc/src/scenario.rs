//! The `method = "hs-mc"` scenario: its typed form ([`McScenario`], every key documented in
//! docs/mc.md and listed by `colloidsim keys hs-mc`) and its validation into [`McRun`], each
//! error naming the key and the allowed range.

use crate::engine::{HardSphereMc, McError, McParams};
use crate::geometry::Geometry;
use crate::init::{fcc_in_box, fcc_in_sphere, shuffled};
use colloidsim_core::ParamError;
use colloidsim_core::param::{at_least, positive, show};
use colloidsim_core::resources::ensure_fits;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::PathBuf;

/// Highest volume fraction accepted: random close packing.
pub const MAX_PHI: f64 = 0.64;

/// Largest `mc.nselect` (trial moves per sphere per sweep).
pub const NSELECT_MAX: usize = 1000;

/// An `hs-mc` scenario file.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct McScenario {
    /// Must be `"hs-mc"`.
    pub method: String,
    /// Seed of the counter-based random streams (0 ..= 2^32 - 1).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Spheres and container.
    pub system: SystemSection,
    /// The harmonic interface (`system.geometry = "interface"` only).
    #[serde(default)]
    pub interface: InterfaceSection,
    /// Sweeps, warm-up and tuning.
    #[serde(default)]
    pub mc: McSection,
    /// Observables and files.
    #[serde(default)]
    pub output: OutputSection,
}

fn default_seed() -> u64 {
    1
}
fn one() -> f64 {
    1.0
}

/// `[system]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SystemSection {
    /// `"bulk"` (periodic cube), `"hard-wall"` (droplet, centres within `radius - d/2`) or
    /// `"interface"` (the BD droplet's harmonic interface).
    pub geometry: String,
    /// Number of spheres N (two of `particles`, `volume_fraction` and the size).
    #[serde(default)]
    pub particles: Option<usize>,
    /// Volume fraction: `N pi d^3 / (6 L^3)` in bulk, `N d^3 / (8 R^3)` in the droplet.
    #[serde(default)]
    pub volume_fraction: Option<f64>,
    /// Sphere diameter d (length unit).
    #[serde(default = "one")]
    pub diameter: f64,
    /// Droplet radius R (droplet geometries).
    #[serde(default)]
    pub radius: Option<f64>,
    /// Edge of the periodic cube (bulk).
    #[serde(default, rename = "box")]
    pub box_edge: Option<f64>,
    /// Thermal energy kT (energy unit; the interface's stiffness is in energy / length^2).
    #[serde(default = "one", rename = "kT")]
    pub kt: f64,
    /// Start from the last frame of this GSD file instead of an FCC lattice.
    #[serde(default)]
    pub initial: Option<PathBuf>,
}

/// `[interface]`: `V = k s^2 / 2` for `0 <= s < range`, linear beyond,
/// `s = |r| - (R + offset)` (as droplet-bd's `[interface]`).
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InterfaceSection {
    /// Spring constant k (energy / length^2; default 50 kT / d^2).
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Range of the harmonic part (length; default d / 2).
    #[serde(default)]
    pub range: Option<f64>,
    /// Offset of the wall from R (length; default -d / 2).
    #[serde(default)]
    pub offset: Option<f64>,
}

/// `[mc]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct McSection {
    /// Sampling sweeps (`nselect N` trial moves each), after the warm-up.
    #[serde(default = "default_sweeps")]
    pub sweeps: u64,
    /// Trial moves per sphere per sweep (HOOMD-blue's `nselect`).
    #[serde(default = "default_nselect")]
    pub nselect: usize,
    /// Warm-up sweeps, during which delta is tuned.
    #[serde(default = "default_warmup")]
    pub warmup_sweeps: u64,
    /// Acceptance the warm-up tunes delta towards, in (0, 1).
    #[serde(default = "default_target")]
    pub target_acceptance: f64,
    /// Sweeps between tunings of delta in the warm-up.
    #[serde(default = "default_tune_every")]
    pub tune_every: u64,
    /// Sweeps between samples of the observables.
    #[serde(default = "default_sample_every")]
    pub sample_every: u64,
    /// Initial half-width of the displacement cube (length; default d / 10).
    #[serde(default)]
    pub delta: Option<f64>,
    /// Blocks of the sampling sweeps whose averages give the standard errors.
    #[serde(default = "default_blocks")]
    pub blocks: usize,
}

fn default_sweeps() -> u64 {
    10_000
}
fn default_nselect() -> usize {
    1
}
fn default_warmup() -> u64 {
    2_000
}
fn default_target() -> f64 {
    0.3
}
fn default_tune_every() -> u64 {
    100
}
fn default_sample_every() -> u64 {
    10
}
fn default_blocks() -> usize {
    20
}

impl Default for McSection {
    fn default() -> Self {
        Self {
            sweeps: default_sweeps(),
            nselect: default_nselect(),
            warmup_sweeps: default_warmup(),
            target_acceptance: default_target(),
            tune_every: default_tune_every(),
            sample_every: default_sample_every(),
            delta: None,
            blocks: default_blocks(),
        }
    }
}

/// `[output]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// Radial bins between 0 and R (droplet profiles).
    #[serde(default = "default_profile_bins")]
    pub profile_bins: usize,
    /// Bins of g(r) between 0 and `gr_max` (bulk).
    #[serde(default = "default_gr_bins")]
    pub gr_bins: usize,
    /// Range of g(r) (length; default and at most L / 2).
    #[serde(default)]
    pub gr_max: Option<f64>,
    /// Sweeps between frames of `trajectory.gsd` (0: none).
    #[serde(default)]
    pub trajectory_every: u64,
    /// Radial bins of the two-body density `rho2(r1, r2, cos theta)` over [0, R] (droplets;
    /// 0: not measured).
    #[serde(default)]
    pub rho2_r_bins: usize,
    /// `cos theta` bins of the two-body density.
    #[serde(default = "default_rho2_cos_bins")]
    pub rho2_cos_bins: usize,
}

fn default_rho2_cos_bins() -> usize {
    20
}

fn default_profile_bins() -> usize {
    50
}
fn default_gr_bins() -> usize {
    200
}

impl Default for OutputSection {
    fn default() -> Self {
        Self {
            profile_bins: default_profile_bins(),
            gr_bins: default_gr_bins(),
            gr_max: None,
            trajectory_every: 0,
            rho2_r_bins: 0,
            rho2_cos_bins: default_rho2_cos_bins(),
        }
    }
}

/// A validated `hs-mc` run.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct McRun {
    /// Seed of the streams.
    pub seed: u32,
    /// Spheres N.
    pub particles: usize,
    /// Diameter d.
    pub diameter: f64,
    /// `bulk`, `hard-wall` or `interface`.
    pub geometry: String,
    /// Volume fraction (bulk: of the box; droplet: `N d^3 / (8 R^3)`).
    pub volume_fraction: f64,
    /// Droplet radius R (droplets).
    pub radius: Option<f64>,
    /// Edge of the periodic box the cells tile.
    pub box_edge: f64,
    /// kT.
    pub kt: f64,
    /// Interface (stiffness, range, offset), `interface` geometry only.
    pub interface: Option<[f64; 3]>,
    /// Sampling sweeps.
    pub sweeps: u64,
    /// Trial moves per sphere per sweep.
    pub nselect: usize,
    /// Warm-up sweeps.
    pub warmup_sweeps: u64,
    /// Target acceptance of the tuning.
    pub target_acceptance: f64,
    /// Sweeps between tunings.
    pub tune_every: u64,
    /// Sweeps between samples.
    pub sample_every: u64,
    /// Initial delta.
    pub delta: f64,
    /// Blocks of the error estimate.
    pub blocks: usize,
    /// Profile bins.
    pub profile_bins: usize,
    /// g(r) bins.
    pub gr_bins: usize,
    /// g(r) range.
    pub gr_max: f64,
    /// Sweeps between trajectory frames (0: none).
    pub trajectory_every: u64,
    /// Two-body density bins (r, cos theta); `None`: not measured.
    pub rho2_bins: Option<(usize, usize)>,
    /// Starting configuration file, if any.
    pub initial: Option<PathBuf>,
}

impl McScenario {
    /// Parse a scenario file's text.
    pub fn from_toml(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }

    /// Check every key and resolve the run (no file is read).
    pub fn validate(&self) -> Result<McRun, ParamError> {
        if self.method != "hs-mc" {
            return Err(ParamError::new(
                "method",
                format!("must be \"hs-mc\", got \"{}\"", self.method),
            ));
        }
        let seed = colloidsim_core::param::seed("seed", self.seed)?;
        let s = &self.system;
        let d = positive("system.diameter", s.diameter)?;
        let kt = positive("system.kT", s.kt)?;
        let bulk = match s.geometry.as_str() {
            "bulk" => true,
            "hard-wall" | "interface" => false,
            g => {
                return Err(ParamError::new(
                    "system.geometry",
                    format!("must be one of \"bulk\", \"hard-wall\", \"interface\", got \"{g}\""),
                ));
            }
        };
        let (size_key, size, other_key, other) = if bulk {
            ("system.box", s.box_edge, "system.radius", s.radius)
        } else {
            ("system.radius", s.radius, "system.box", s.box_edge)
        };
        if other.is_some() {
            return Err(ParamError::new(
                other_key,
                format!(
                    "does not apply to system.geometry = \"{}\" (give {size_key})",
                    s.geometry
                ),
            ));
        }
        if let Some(n) = s.particles {
            at_least("system.particles", n, if bulk { 2 } else { 1 })?;
        }
        if let Some(v) = size {
            positive(size_key, v)?;
        }
        if let Some(phi) = s.volume_fraction
            && !(phi.is_finite() && phi > 0.0 && phi <= MAX_PHI)
        {
            return Err(ParamError::new(
                "system.volume_fraction",
                format!(
                    "must lie in (0, {MAX_PHI}] (random close packing), got {}",
                    show(phi)
                ),
            ));
        }
        // phi of N spheres in a size, and its inverses.
        let unit = if bulk { PI / 6.0 } else { 1.0 / 8.0 };
        let (particles, size) = match (s.particles, s.volume_fraction, size) {
            (Some(n), None, Some(l)) => (n, l),
            (Some(n), Some(phi), None) => (n, (n as f64 * unit * d.powi(3) / phi).cbrt()),
            (None, Some(phi), Some(l)) => {
                let n = (phi * l.powi(3) / (unit * d.powi(3))).round();
                if !(1.0..=1e8).contains(&n) {
                    return Err(ParamError::new(
                        "system.volume_fraction",
                        format!(
                            "gives {} spheres in {size_key} = {}; between 1 and 1e8 are allowed",
                            show(n),
                            show(l)
                        ),
                    ));
                }
                (n as usize, l)
            }
            _ => {
                return Err(ParamError::new(
                    "system",
                    format!(
                        "give exactly two of system.particles, system.volume_fraction and {size_key}"
                    ),
                ));
            }
        };
        let phi = particles as f64 * unit * d.powi(3) / size.powi(3);
        if phi > MAX_PHI {
            return Err(ParamError::new(
                "system.volume_fraction",
                format!(
                    "{particles} spheres in {size_key} = {} pack to {:.4}, above random close packing {MAX_PHI}",
                    show(size),
                    phi
                ),
            ));
        }
        let i = &self.interface;
        let interface = if s.geometry == "interface" {
            Some([
                i.stiffness.unwrap_or(50.0 * kt / (d * d)),
                i.range.unwrap_or(0.5 * d),
                i.offset.unwrap_or(-0.5 * d),
            ])
        } else {
            if i != &InterfaceSection::default() {
                return Err(ParamError::new(
                    "interface",
                    format!(
                        "applies to system.geometry = \"interface\" only, not \"{}\"",
                        s.geometry
                    ),
                ));
            }
            None
        };
        let geometry = if bulk {
            Geometry::Bulk { edge: size }
        } else if let Some([k, range, offset]) = interface {
            Geometry::interface(size, k, range, offset, kt)?
        } else {
            if size <= 0.5 * d {
                return Err(ParamError::new(
                    "system.radius",
                    format!("must exceed d/2 = {}, got {}", show(0.5 * d), show(size)),
                ));
            }
            Geometry::HardWall { radius: size }
        };
        let box_edge = geometry.box_edge(d);
        if bulk && box_edge < 2.0 * d {
            return Err(ParamError::new(
                "system.box",
                format!(
                    "must be at least 2 d = {} (the cells need two per edge), got {}",
                    show(2.0 * d),
                    show(box_edge)
                ),
            ));
        }
        let m = &self.mc;
        at_least("mc.sweeps", m.sweeps as usize, 1)?;
        if !(1..=NSELECT_MAX).contains(&m.nselect) {
            return Err(ParamError::new(
                "mc.nselect",
                format!(
                    "must be an integer in [1, {NSELECT_MAX}], got {}",
                    m.nselect
                ),
            ));
        }
        at_least("mc.tune_every", m.tune_every as usize, 1)?;
        at_least("mc.sample_every", m.sample_every as usize, 1)?;
        if !(m.target_acceptance > 0.0 && m.target_acceptance < 1.0) {
            return Err(ParamError::new(
                "mc.target_acceptance",
                format!(
                    "must lie strictly between 0 and 1, got {}",
                    show(m.target_acceptance)
                ),
            ));
        }
        let delta = positive("mc.delta", m.delta.unwrap_or(0.1 * d))?;
        at_least("mc.blocks", m.blocks, 2)?;
        let samples = m.sweeps.div_ceil(m.sample_every);
        if m.blocks as u64 > samples {
            return Err(ParamError::new(
                "mc.blocks",
                format!(
                    "must be at most the number of samples, mc.sweeps / mc.sample_every = {samples}, got {}",
                    m.blocks
                ),
            ));
        }
        let o = &self.output;
        at_least("output.profile_bins", o.profile_bins, 1)?;
        at_least("output.gr_bins", o.gr_bins, 1)?;
        let half = 0.5 * box_edge;
        // Just under half the box: freud's RDF (and any AABB query) refuses exactly L/2.
        let gr_max = o.gr_max.unwrap_or(0.98 * half);
        if !(gr_max.is_finite() && gr_max > 0.0 && gr_max <= half * (1.0 + 1e-12)) {
            return Err(ParamError::new(
                "output.gr_max",
                format!(
                    "must lie in (0, L/2 = {}], got {}",
                    show(half),
                    show(gr_max)
                ),
            ));
        }
        at_least("output.rho2_cos_bins", o.rho2_cos_bins, 1)?;
        let rho2_bins = (o.rho2_r_bins > 0).then_some((o.rho2_r_bins, o.rho2_cos_bins));
        if bulk && rho2_bins.is_some() {
            return Err(ParamError::new(
                "output.rho2_r_bins",
                "applies to the droplet geometries only (give 0 or leave it out in bulk)",
            ));
        }
        let rho2_cells = rho2_bins.map_or(0.0, |(r, c)| (r * r * c) as f64);
        // Positions (particle order, scratch and slots), histograms of every block.
        let bytes = particles as f64 * 200.0
            + m.blocks as f64 * 8.0 * ((o.profile_bins + o.gr_bins + 100) as f64 + rho2_cells);
        ensure_fits("system.particles", &format!("{particles} spheres"), bytes)?;
        Ok(McRun {
            seed,
            particles,
            diameter: d,
            geometry: s.geometry.clone(),
            volume_fraction: phi,
            radius: (!bulk).then_some(size),
            box_edge,
            kt,
            interface,
            sweeps: m.sweeps,
            nselect: m.nselect,
            warmup_sweeps: m.warmup_sweeps,
            target_acceptance: m.target_acceptance,
            tune_every: m.tune_every,
            sample_every: m.sample_every,
            delta,
            blocks: m.blocks,
            profile_bins: o.profile_bins,
            gr_bins: o.gr_bins,
            gr_max,
            trajectory_every: o.trajectory_every,
            rho2_bins,
            initial: s.initial.clone(),
        })
    }
}

impl McRun {
    /// The container.
    pub fn geometry(&self) -> Geometry {
        match (self.radius, self.interface) {
            (None, _) => Geometry::Bulk {
                edge: self.box_edge,
            },
            (Some(r), Some([k, range, offset])) => {
                Geometry::interface(r, k, range, offset, self.kt).expect("validated interface")
            }
            (Some(r), None) => Geometry::HardWall { radius: r },
        }
    }

    /// Is this a bulk run?
    pub fn is_bulk(&self) -> bool {
        self.radius.is_none()
    }

    /// The engine at `positions` (`key` names them in errors), or on an FCC lattice (sites in
    /// a random order).
    pub fn engine(
        &self,
        positions: Option<&[[f64; 3]]>,
        key: &str,
    ) -> Result<HardSphereMc, McError> {
        let geometry = self.geometry();
        let lattice;
        let pos = match positions {
            Some(p) => {
                if p.len() != self.particles {
                    return Err(ParamError::new(
                        key,
                        format!(
                            "holds {} spheres, the scenario has system.particles = {}",
                            p.len(),
                            self.particles
                        ),
                    )
                    .into());
                }
                p
            }
            None => {
                lattice = shuffled(
                    match self.radius {
                        None => fcc_in_box(self.particles, self.diameter, self.box_edge)?,
                        Some(_) => fcc_in_sphere(
                            self.particles,
                            self.diameter,
                            geometry
                                .confinement(self.diameter)
                                .unwrap_or(0.0)
                                .min(self.radius.unwrap_or(0.0) - 0.5 * self.diameter),
                        )?,
                    },
                    self.seed,
                );
                &lattice
            }
        };
        let params = McParams {
            diameter: self.diameter,
            geometry,
            seed: self.seed,
            delta: self.delta,
        };
        let mut mc = HardSphereMc::new(&params, pos, key)?;
        mc.set_nselect(self.nselect);
        Ok(mc)
    }
}
