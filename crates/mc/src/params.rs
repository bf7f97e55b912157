//! The parameters of a hard-sphere Monte Carlo run ([`McRun`]: plain data, as the run layer
//! reads them from a scenario) and the engine they start.

use crate::engine::chain::EventChain;
use crate::engine::{HardSphereMc, McError, McParams, Mixture};
use crate::geometry::Geometry;
use crate::init::{fcc_in_box, fcc_in_sphere, shuffled};
use colloidsim_core::ParamError;
use colloidsim_particles::PairSpec;

use serde::Serialize;

use std::path::PathBuf;

/// Highest volume fraction accepted: random close packing.
pub const MAX_PHI: f64 = 0.64;

/// Largest `mc.nselect` (trial moves per sphere per sweep).
pub const NSELECT_MAX: usize = 1000;

/// Most sweeps [`HardSphereMc::grow`] may take to inflate a mixture's compressed lattice.
pub const GROW_SWEEPS: u64 = 100_000;

/// A validated hard-sphere Monte Carlo run.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct McRun {
    /// Seed of the streams.
    pub seed: u32,
    /// Spheres N (of every species).
    pub particles: usize,
    /// Diameter d; with a mixture, the reference diameter the interface's offset was given for
    /// (see [`Geometry::confinement_of`]).
    pub diameter: f64,
    /// The species (`None`: one species, every sphere of `diameter`; not serialised then):
    /// `counts[s]` spheres of diameter `diameters[s]`, the first `counts[0]` spheres (in the
    /// order of `system.initial`, or of the shuffled lattice) of species 0, and so on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mixture: Option<Mixture>,
    /// `bulk`, `hard-wall` or `interface`.
    pub geometry: String,
    /// Volume fraction (bulk: of the box; droplet: `N d^3 / (8 R^3)`; a mixture: the sum over
    /// species).
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
    /// Event chains of this length instead of local moves (`None`: local moves; not
    /// serialised then).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chain_length: Option<f64>,
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
    /// A pair interaction in place of the hard cores (`None`: hard spheres; not serialised
    /// then): the spheres sample `exp(-U / kT)` ([`HardSphereMc::with_pair`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pair: Option<PairSpec>,
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

    /// Event chains per sweep at chain length `length`: `max(1, round(N lambda / length))`,
    /// `lambda` the Carnahan–Starling free path between lifts at the run's volume fraction
    /// ([`crate::engine::chain::free_path`]), so that a sweep makes about N lifts.
    pub fn chains_per_sweep(&self, length: f64) -> u64 {
        let lambda = crate::engine::chain::free_path(self.volume_fraction, self.diameter);
        let k = (self.particles as f64 * lambda / length).round();
        if k.is_finite() { (k as u64).max(1) } else { 1 }
    }

    /// Is this a bulk run?
    pub fn is_bulk(&self) -> bool {
        self.radius.is_none()
    }

    /// Diameter of each species (one species: `[diameter]`).
    pub fn diameters(&self) -> Vec<f64> {
        match &self.mixture {
            None => vec![self.diameter],
            Some(m) => m.diameters.clone(),
        }
    }

    /// The engine at `positions` (`key` names where they came from in errors), or on an FCC
    /// lattice (sites in a random order; a mixture's species assigned in blocks of `counts` to
    /// the shuffled sites, so at random). The lattice's neighbour distance is at least the
    /// largest diameter when that fits (one species always does, below `MAX_PHI`); else the
    /// mixture starts on a lattice at every diameter scaled down to fit and is inflated to its
    /// full diameters by Monte Carlo sweeps ([`HardSphereMc::grow`], at most [`GROW_SWEEPS`]);
    /// with a pair interaction it starts at full diameters on that closer lattice (soft cores
    /// may overlap; the warm-up relaxes them).
    pub fn engine(
        &self,
        positions: Option<&[[f64; 3]]>,
        key: &str,
    ) -> Result<HardSphereMc, McError> {
        let geometry = self.geometry();
        let d = self.diameter;
        let diameters = self.diameters();
        let d_max = diameters.iter().fold(0.0f64, |a, &b| a.max(b));
        let mixture = self.mixture.clone();
        if diameters.iter().all(|d| d.is_finite() && *d > 0.0) && d.is_finite() && d > 0.0 {
            crate::engine::check_cell_count(
                geometry.box_edge_of(d, &diameters),
                d_max,
                self.particles,
            )?;
        }
        let params = McParams {
            diameter: d,
            geometry,
            seed: self.seed,
            delta: self.delta,
            mixture,
        };
        let lattice;
        let mut scale = 1.0;
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
                // Centres of spheres of every diameter times `f` within the droplet.
                let within = |f: f64| {
                    diameters
                        .iter()
                        .map(|&ds| {
                            let c = geometry.confinement(d).unwrap_or(0.0);
                            let c = if f == 1.0 {
                                geometry.confinement_of(ds, d).unwrap_or(0.0)
                            } else if geometry.shrinks() {
                                c - (0.5 * ds * f - 0.5 * d)
                            } else {
                                c
                            };
                            c.min(self.radius.unwrap_or(0.0) - 0.5 * ds * f)
                        })
                        .fold(f64::INFINITY, f64::min)
                };
                let place = |f: f64| match self.radius {
                    None => fcc_in_box(self.particles, f * d_max, self.box_edge),
                    Some(_) => fcc_in_sphere(self.particles, f * d_max, within(f)),
                };
                let sites = match (place(1.0), self.mixture.is_some()) {
                    (Ok(s), _) => s,
                    (Err(e), false) => return Err(e),
                    (Err(e), true) => {
                        // The largest factor whose lattice fits (bisection).
                        let (mut lo, mut hi) = (0.0, 1.0);
                        for _ in 0..40 {
                            let mid = 0.5 * (lo + hi);
                            if place(mid).is_ok() {
                                lo = mid;
                            } else {
                                hi = mid;
                            }
                        }
                        if lo == 0.0 {
                            return Err(e);
                        }
                        scale = lo;
                        place(lo)?
                    }
                };
                lattice = shuffled(sites, self.seed);
                &lattice
            }
        };
        let mut mc = match &self.pair {
            None => HardSphereMc::new_scaled(&params, pos, key, scale, None)?,
            Some(pair) => {
                scale = 1.0;
                HardSphereMc::with_pair(&params, pos, key, pair, self.kt)?
            }
        };
        if scale < 1.0 {
            mc.grow(GROW_SWEEPS, self.delta)?;
        }
        mc.set_nselect(self.nselect);
        if let Some(length) = self.chain_length {
            mc.set_event_chain(Some(EventChain {
                length,
                chains_per_sweep: self.chains_per_sweep(length),
            }))?;
        }
        Ok(mc)
    }
}
