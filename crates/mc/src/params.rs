//! The parameters of a hard-sphere Monte Carlo run ([`McRun`]: plain data, as the run layer
//! reads them from a scenario) and the engine they start.

use crate::engine::{HardSphereMc, McError, McParams};
use crate::geometry::Geometry;
use crate::init::{fcc_in_box, fcc_in_sphere, shuffled};
use colloidsim_core::ParamError;

use serde::Serialize;

use std::path::PathBuf;

/// Highest volume fraction accepted: random close packing.
pub const MAX_PHI: f64 = 0.64;

/// Largest `mc.nselect` (trial moves per sphere per sweep).
pub const NSELECT_MAX: usize = 1000;

/// A validated hard-sphere Monte Carlo run.
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

    /// The engine at `positions` (`key` names where they came from in errors), or on an FCC
    /// lattice (sites in a random order).
    pub fn engine(
        &self,
        positions: Option<&[[f64; 3]]>,
        key: &str,
    ) -> Result<HardSphereMc, McError> {
        let geometry = self.geometry();
        if self.diameter.is_finite() && self.diameter > 0.0 {
            crate::engine::check_cell_count(
                geometry.box_edge(self.diameter),
                self.diameter,
                self.particles,
            )?;
        }
        let lattice;
        let pos = match positions {
            Some(p) => {
                if p.len() != self.particles {
                    return Err(ParamError::new(
                        key,
                        format!("holds {} spheres, the run has {}", p.len(), self.particles),
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
