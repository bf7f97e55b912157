//! The BCD time step: forces, fragmentation, premerging (or the chronological event-driven
//! update), and the position update.
//!
//! Rods are kept in ring order with unwrapped positions, `x[0] < x[1] < ... < x[N-1]`, and on
//! the ring `x[N-1] < x[0] + L`, so positions are also the displacements needed for the MSD.
//! A *virtual index* `w` counts around the ring from the first cluster start (`origin`);
//! `w >= N` denotes rod `w - N` seen one period further on (position `+ L`).
//!
//! The premerged update on a ring runs in reduced coordinates ([`crate::ring`]). The other
//! updates (walls, the chronological oracle) cut the line into chunks of about [`CHUNK`] rods at
//! cluster boundaries; each chunk computes its forces, fragments its clusters and premerges them
//! independently (in parallel), then one short sequential pass premerges across chunk
//! boundaries and the walls or the periodic seam. Chunking depends only on N and the
//! configuration, never on the thread count, so results are bitwise identical for any number
//! of threads.

use crate::cluster::{Cluster, Hull, Wall, collide, merge, premerge};
use crate::forces::{ExternalForce, PairForce};
use crate::observe::{ClusterSizes, DensityProfile};
use crate::reflect::ReflectStep;
use crate::ring::{Motion, RingStep, SEG, Want, noise_segment};
use colloidsim_core::ParamError;
use colloidsim_core::param;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::{Mutex, OnceLock};
use thiserror::Error;

pub use crate::ring::CHUNK;

/// What bounds the line of rods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Boundary {
    /// A ring of length L.
    Periodic,
    /// Hard walls at 0 and L: rod centres stay in [sigma/2, L - sigma/2].
    Walls,
}

/// How collisions within a step are resolved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Update {
    /// Premerging, O(N) per step (fast-bcd Secs. IV–V).
    Premerge,
    /// Chronological event-driven update, O(N^2) per step (hard-rods paper Sec. III B).
    Chronological,
}

/// How the free motion of a step is integrated: the free velocities `u_i` that fragmentation
/// and premerging act on (the hard-core collisions are resolved exactly for either).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Euler–Maruyama, `u_i = mu F_i(x_n) + sqrt(2 D / dt) xi_{i,n}` (hard-rods paper Eq. 12,
    /// fast-bcd Eq. 3): first order in dt for the stationary distribution.
    #[default]
    Euler,
    /// Leimkuhler–Matthews, `u_i = mu F_i(x_n) + sqrt(2 D / dt) (xi_{i,n} + xi_{i,n+1}) / 2`:
    /// second order in dt for the stationary distribution of overdamped Langevin dynamics
    /// without collisions (Leimkuhler & Matthews, Appl. Math. Res. Express 2013; Leimkuhler,
    /// Matthews & Tretyakov, Proc. R. Soc. A 470, 20140120 (2014)), at one deviate per rod and
    /// step (`xi_{n+1}` is kept for the next step; a restart draws it again from the step
    /// counter). Displacements over `k` free steps have variance `2 D dt (k - 1/2)`, so the MSD
    /// at lag `t` is low by `D dt`. The collision boundary layer (docs/bcd.md, *Time-step
    /// error*) is 1.2–1.5x thicker than Euler's. At kT = 0 it is Euler.
    Lm,
    /// Reflecting (elastic) collisions with Leimkuhler–Matthews in its Markov form
    /// (module `reflect`): the rods take the sorted free end positions in reduced coordinates
    /// (reflected at walls), so there is no collision boundary layer; a chain with full
    /// Brownian increments is the state, the positions are its half kick. Needs kT > 0; rods
    /// never end a step in contact (no clusters). Ignores [`Update`]. The MSD at lag `t` is low
    /// by `D dt`, as LM's. Costs 24 more bytes per rod than Euler.
    Reflect,
}

/// Physical and numerical parameters of a BCD run (units: the scenario's length, time and energy).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BcdConfig {
    /// System length L.
    pub length: f64,
    /// Rod length sigma.
    pub sigma: f64,
    /// Mobility mu (velocity per force).
    pub mobility: f64,
    /// Thermal energy kT (0 gives deterministic cluster dynamics).
    pub kt: f64,
    /// Time step.
    pub dt: f64,
    /// Ring or walls.
    pub boundary: Boundary,
    /// Seed of the counter-based noise.
    pub seed: u32,
    /// Collision resolution.
    pub update: Update,
}

impl BcdConfig {
    /// Check ranges for `n` rods; errors name the parameter (`length`, `sigma`, `mobility`, `kt`,
    /// `dt`, `n`).
    pub fn validate(&self, n: usize) -> Result<(), ParamError> {
        param::positive("length", self.length)?;
        param::positive("sigma", self.sigma)?;
        param::positive("mobility", self.mobility)?;
        param::non_negative("kt", self.kt)?;
        param::positive("dt", self.dt)?;
        param::at_least("n", n, 1)?;
        if n > u32::MAX as usize / 4 {
            return Err(ParamError::new(
                "n",
                format!("at most {} rods, got {n}", u32::MAX / 4),
            ));
        }
        let packed = n as f64 * self.sigma;
        if packed >= self.length {
            return Err(ParamError::new(
                "n",
                format!(
                    "{n} rods of length {} fill {packed} >= the length {}: N sigma must be < L",
                    self.sigma, self.length
                ),
            ));
        }
        Ok(())
    }

    /// Diffusion coefficient D = mu kT.
    pub fn diffusion(&self) -> f64 {
        self.mobility * self.kt
    }
}

/// Errors of the engine.
#[derive(Debug, Error)]
pub enum BcdError {
    /// Invalid parameter.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// Initial positions violate the hard core or the walls.
    #[error("initial positions: {0}")]
    Positions(String),
    /// A force or position became NaN or infinite.
    #[error(
        "the run went non-finite at step {step}: rod {particle} at x = {position} has velocity {velocity}; reduce the time step or check the potential"
    )]
    NonFinite {
        /// Step at which it happened.
        step: u64,
        /// Rod index.
        particle: usize,
        /// Its position.
        position: f64,
        /// Its (non-finite) velocity.
        velocity: f64,
    },
}

/// Dynamic state that a checkpoint must hold (with the config and the step counter).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BcdState {
    /// Unwrapped rod centres in ring order.
    pub x: Vec<f64>,
    /// `bond[i] = 1` when rods i and i+1 (mod N) belong to one cluster.
    pub bond: Vec<u8>,
    /// The first rod is stuck to the left wall.
    pub left_contact: bool,
    /// The last rod is stuck to the right wall.
    pub right_contact: bool,
    /// Steps done.
    pub step: u64,
    /// The premerged ring update's own coordinates, `y_i = x_i - i sigma` with the rods of a
    /// cluster sharing one value bit for bit, or [`Integrator::Reflect`]'s chain `Y` (empty for
    /// the other updates). A restart uses them so that it continues bitwise; `x` is derived
    /// from them (for `Reflect`, `x` is the chain's, not the sampled positions).
    #[serde(default)]
    pub reduced: Vec<f64>,
}

#[derive(Debug, Default, Clone)]
struct Chunk {
    vs: usize,
    ve: usize,
    stack: Vec<Cluster>,
    hull: Hull,
    /// First rod whose velocity went non-finite, with that velocity.
    bad: Option<(usize, f64)>,
}

/// Read-only view of the configuration shared by the chunks of one step.
struct Ring<'a> {
    x: &'a [f64],
    bond: &'a [u8],
    n: usize,
    length: f64,
    periodic: bool,
}

impl Ring<'_> {
    #[inline]
    fn actual(&self, w: usize) -> usize {
        if w < self.n {
            w
        } else if w < 2 * self.n {
            w - self.n
        } else {
            w - 2 * self.n
        }
    }
    /// Unwrapped position of virtual index `w`.
    #[inline]
    fn pos(&self, w: usize) -> f64 {
        if w < self.n {
            self.x[w]
        } else if w < 2 * self.n {
            self.x[w - self.n] + self.length
        } else {
            self.x[w - 2 * self.n] + 2.0 * self.length
        }
    }
    #[inline]
    fn bonded_right(&self, w: usize) -> bool {
        self.bond[self.actual(w)] != 0
    }
}

/// Brownian cluster dynamics of N hard rods, generic over the external and pair forces.
pub struct Bcd<E: ExternalForce, P: PairForce> {
    cfg: BcdConfig,
    ext: E,
    pair: P,
    state: BcdState,
    chunks: Vec<Chunk>,
    global: Vec<Cluster>,
    noise_amp: f64,
    /// The premerged ring update (periodic boundary): it keeps the configuration in reduced
    /// coordinates, and `state.x`/`state.bond` are then empty and derived on demand into `view`.
    ring: Option<RingStep>,
    view: OnceLock<BcdState>,
    positions: OnceLock<Vec<f64>>,
    /// The buffer of the last step's `positions`, reused by the next (no allocation per step).
    spare: Mutex<Vec<f64>>,
    integrator: Integrator,
    /// Leimkuhler–Matthews outside the ring update: the deviates `xi_{n+1}` kept for the next
    /// step, and this step's `xi_n + xi_{n+1}` (empty for Euler and on the ring, whose chunks
    /// keep their own).
    kept: Vec<f64>,
    lm_noise: Vec<f64>,
    /// The step whose deviates `kept` holds (`None`: draw them from the step counter).
    kept_step: Option<u64>,
    /// The reflecting step ([`Integrator::Reflect`]): it keeps the configuration, and
    /// `state.x`/`state.bond` are then empty.
    reflect: Option<ReflectStep>,
    /// A checkpoint's reduced positions between walls (checked against `x`), for
    /// [`Integrator::Reflect`]'s chain; empty otherwise.
    restored: Vec<f64>,
}

impl<E: ExternalForce, P: PairForce> Bcd<E, P> {
    /// Set up a run from rod centres `x` (sorted, non-overlapping; unwrapped on the ring).
    pub fn new(cfg: BcdConfig, x: Vec<f64>, ext: E, pair: P) -> Result<Self, BcdError> {
        Self::new_at(cfg, x, ext, pair, 0)
    }

    /// [`Self::new`] with `step` steps done (the time and the random streams go on from it).
    pub fn new_at(
        cfg: BcdConfig,
        x: Vec<f64>,
        ext: E,
        pair: P,
        step: u64,
    ) -> Result<Self, BcdError> {
        cfg.validate(x.len())?;
        check_positions(&cfg, &x)?;
        let n = x.len();
        let tol = 1e-12 * cfg.sigma.max(cfg.length / n as f64);
        let mut bond = vec![0u8; n];
        for i in 0..n {
            let gap = if i + 1 < n {
                x[i + 1] - x[i]
            } else if cfg.boundary == Boundary::Periodic && n > 1 {
                x[0] + cfg.length - x[n - 1]
            } else {
                f64::INFINITY
            };
            bond[i] = u8::from(gap <= cfg.sigma + tol);
        }
        let (left_contact, right_contact) = match cfg.boundary {
            Boundary::Walls => (
                x[0] <= 0.5 * cfg.sigma + tol,
                x[n - 1] >= cfg.length - 0.5 * cfg.sigma - tol,
            ),
            Boundary::Periodic => (false, false),
        };
        let state = BcdState {
            x,
            bond,
            left_contact,
            right_contact,
            step,
            reduced: Vec::new(),
        };
        Self::from_state(cfg, state, ext, pair)
    }

    /// Continue from a saved state (checkpoint).
    pub fn from_state(cfg: BcdConfig, state: BcdState, ext: E, pair: P) -> Result<Self, BcdError> {
        cfg.validate(state.x.len())?;
        if state.bond.len() != state.x.len() {
            return Err(BcdError::Positions(
                "bond array length differs from N".into(),
            ));
        }
        check_positions(&cfg, &state.x)?;
        let n = state.x.len();
        let noise_amp = (2.0 * cfg.diffusion() / cfg.dt).sqrt();
        let mut state = state;
        let ring = if cfg.boundary == Boundary::Periodic && cfg.update == Update::Premerge {
            let y = reduced_positions(&cfg, &state)?;
            Some(RingStep::new(y, n > 1 && state.bond[n - 1] != 0))
        } else {
            None
        };
        // Between walls a checkpoint's reduced positions are the reflecting step's chain.
        let restored = if ring.is_none() && !state.reduced.is_empty() {
            reduced_positions(&cfg, &state)?
        } else {
            Vec::new()
        };
        // The engine's own copy lives in the ring step; the stored state never holds it, nor,
        // on a ring, the positions and bonds (derived from the ring step when asked for).
        state.reduced = Vec::new();
        if ring.is_some() {
            state.x = Vec::new();
            state.bond = Vec::new();
        }
        let chunks = if ring.is_some() {
            Vec::new()
        } else {
            vec![Chunk::default(); n.div_ceil(CHUNK)]
        };
        Ok(Self {
            cfg,
            ext,
            pair,
            state,
            chunks,
            global: Vec::new(),
            noise_amp,
            ring,
            view: OnceLock::new(),
            positions: OnceLock::new(),
            spare: Mutex::new(Vec::new()),
            integrator: Integrator::Euler,
            kept: Vec::new(),
            lm_noise: Vec::new(),
            kept_step: None,
            reflect: None,
            restored,
        })
    }

    /// Integrate the free motion with `integrator` (the default is [`Integrator::Euler`]).
    /// Leimkuhler–Matthews keeps one deviate per rod (8 bytes) between steps; it is not part of
    /// the state: after [`Bcd::from_state`] it is drawn again from the step counter, so a
    /// restart continues bitwise.
    ///
    /// [`Integrator::Reflect`] keeps its own chain (the state): it starts from the current
    /// positions (a checkpoint's `reduced`, bitwise) and draws the sampled configuration of the
    /// current step from it.
    pub fn with_integrator(mut self, integrator: Integrator) -> Self {
        let n = self.len();
        let sigma = self.cfg.sigma;
        if let Some(r) = self.reflect.take() {
            // Leaving the reflecting step: its chain becomes the positions.
            let y = r.chain;
            if self.cfg.boundary == Boundary::Periodic && self.cfg.update == Update::Premerge {
                let seam = n > 1 && y[n - 1] == y[0] + self.cfg.length - n as f64 * sigma;
                self.ring = Some(RingStep::new(y, seam));
            } else {
                self.state.x = y
                    .iter()
                    .enumerate()
                    .map(|(i, v)| v + i as f64 * sigma)
                    .collect();
                self.state.bond = vec![0; n];
                self.chunks = vec![Chunk::default(); n.div_ceil(CHUNK)];
            }
        }
        self.view = OnceLock::new();
        self.positions = OnceLock::new();
        if integrator == Integrator::Reflect {
            let chain = if let Some(r) = self.ring.take() {
                r.y
            } else if !self.restored.is_empty() {
                std::mem::take(&mut self.restored)
            } else {
                let x = std::mem::take(&mut self.state.x);
                x.iter()
                    .enumerate()
                    .map(|(i, v)| v - i as f64 * sigma)
                    .collect()
            };
            self.state.x = Vec::new();
            self.state.bond = Vec::new();
            self.chunks = Vec::new();
            self.kept = Vec::new();
            self.lm_noise = Vec::new();
            let mut r = ReflectStep::new(chain, &self.cfg);
            r.ensure_kicked(&self.cfg, self.state.step);
            self.reflect = Some(r);
            self.integrator = integrator;
            return self;
        }
        self.integrator = integrator;
        let lm = integrator == Integrator::Lm;
        self.kept_step = None;
        match &mut self.ring {
            Some(r) => r.set_lm(lm),
            None if lm => {
                self.kept = vec![0.0; self.state.x.len()];
                self.lm_noise = vec![0.0; self.state.x.len()];
            }
            None => {
                self.kept = Vec::new();
                self.lm_noise = Vec::new();
            }
        }
        self
    }

    /// The integrator of the free motion.
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    /// The configuration.
    pub fn config(&self) -> &BcdConfig {
        &self.cfg
    }
    /// Number of rods.
    pub fn len(&self) -> usize {
        match (&self.ring, &self.reflect) {
            (Some(r), _) => r.y.len(),
            (_, Some(r)) => r.y.len(),
            _ => self.state.x.len(),
        }
    }

    /// Reduced positions the positions are derived from: the ring update's, or the reflecting
    /// step's sampled configuration.
    fn derived_from(&self) -> Option<&[f64]> {
        match (&self.ring, &self.reflect) {
            (Some(r), _) => Some(&r.y),
            (_, Some(r)) => Some(&r.y),
            _ => None,
        }
    }
    /// Always false (a run has at least one rod).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Unwrapped rod centres in ring order.
    pub fn positions(&self) -> &[f64] {
        match self.derived_from() {
            None => &self.state.x,
            Some(y) => self.positions.get_or_init(|| {
                let mut x =
                    std::mem::take(&mut *self.spare.lock().unwrap_or_else(|e| e.into_inner()));
                centres(y, self.cfg.sigma, &mut x);
                x
            }),
        }
    }
    /// On a ring, the reduced positions `y_i = x_i - i sigma` the step works on (no copy; for
    /// [`Integrator::Reflect`] the sampled configuration); `None` between walls and for the
    /// chronological update.
    pub fn reduced(&self) -> Option<&[f64]> {
        if self.cfg.boundary != Boundary::Periodic {
            return None;
        }
        self.derived_from()
    }

    /// The dynamic state (for checkpoints).
    pub fn state(&self) -> &BcdState {
        if let Some(r) = &self.reflect {
            return self.view.get_or_init(|| {
                let mut x = Vec::new();
                centres(&r.chain, self.cfg.sigma, &mut x);
                BcdState {
                    x,
                    bond: vec![0; r.chain.len()],
                    left_contact: false,
                    right_contact: false,
                    step: self.state.step,
                    reduced: r.chain.clone(),
                }
            });
        }
        match &self.ring {
            None => &self.state,
            Some(r) => self.view.get_or_init(|| {
                let y = &r.y;
                let x = self.positions().to_vec();
                let mut bond: Vec<u8> = y.windows(2).map(|w| u8::from(w[0] == w[1])).collect();
                bond.push(u8::from(r.seam));
                BcdState {
                    x,
                    bond,
                    left_contact: false,
                    right_contact: false,
                    step: self.state.step,
                    reduced: y.clone(),
                }
            }),
        }
    }
    /// Steps done.
    pub fn steps(&self) -> u64 {
        self.state.step
    }
    /// Time reached.
    pub fn time(&self) -> f64 {
        self.state.step as f64 * self.cfg.dt
    }
    /// The external force.
    pub fn external(&self) -> &E {
        &self.ext
    }

    /// Sizes of the clusters present at the end of the last step (rods in contact that moved
    /// together), in ring order starting from the first cluster start.
    pub fn cluster_sizes(&self, visit: impl FnMut(usize)) {
        let n = self.len();
        if let Some(r) = &self.reflect {
            // Rods meet only by chance (equal sampled reduced positions).
            let y = &r.y;
            return cluster_walk(n, false, |i| i + 1 < n && y[i] == y[i + 1], visit);
        }
        match &self.ring {
            // Bonds read off equal reduced positions (no derived state, no allocation).
            Some(r) => cluster_walk(
                n,
                true,
                |i| {
                    if i + 1 < n {
                        r.y[i] == r.y[i + 1]
                    } else {
                        r.seam
                    }
                },
                visit,
            ),
            None => {
                let bond = &self.state.bond;
                let periodic = self.cfg.boundary == Boundary::Periodic;
                cluster_walk(n, periodic, |i| bond[i] != 0, visit)
            }
        }
    }

    /// Add the current clusters to a histogram of sizes (`counts[s]`: clusters of `s` rods;
    /// `counts` grows to N + 1 entries), the same counts as [`Bcd::cluster_sizes`] gives,
    /// without a branch per rod: every rod adds 0 or 1 to the count of the size its cluster
    /// has if it ends there.
    pub fn count_cluster_sizes(&self, counts: &mut Vec<u64>) {
        let n = self.len();
        if counts.len() <= n {
            counts.resize(n + 1, 0);
        }
        if let Some(r) = &self.reflect {
            let ends = r.y.windows(2).map(|w| w[0] != w[1]);
            return histogram_clusters(n, ends, false, counts);
        }
        match &self.ring {
            // Rod i is bonded to rod i + 1 when their reduced positions are equal, the last rod
            // to the first when the seam is bonded.
            // After a step, one count per pooled block; else from the positions.
            Some(r) if r.count_clusters_from_blocks(counts) => {}
            Some(r) => {
                let ends = r.y.windows(2).map(|w| w[0] != w[1]);
                histogram_clusters(n, ends, r.seam, counts);
            }
            None => {
                let bond = &self.state.bond;
                let periodic = self.cfg.boundary == Boundary::Periodic;
                let ends = bond[..n - 1].iter().map(|&b| b == 0);
                histogram_clusters(n, ends, periodic && bond[n - 1] != 0, counts);
            }
        }
    }

    /// The first cluster start in ring order, given the bonds.
    fn origin(&self, bond: &[u8]) -> usize {
        let periodic = self.cfg.boundary == Boundary::Periodic;
        cluster_origin(self.len(), periodic, |i| bond[i] != 0)
    }

    /// The end of a step taken in reduced coordinates (the ring's or the reflecting
    /// integrator's): the rod, velocity and reduced coordinate `y` that went non-finite, or the
    /// step counted and the cached views dropped.
    fn reduced_step_done(&mut self, done: Result<(), (usize, f64, f64)>) -> Result<(), BcdError> {
        if let Err((i, u, y)) = done {
            return Err(BcdError::NonFinite {
                step: self.state.step,
                particle: i,
                position: y + i as f64 * self.cfg.sigma,
                velocity: u,
            });
        }
        self.view = OnceLock::new();
        if let Some(x) = self.positions.take() {
            *self.spare.get_mut().unwrap_or_else(|e| e.into_inner()) = x;
        }
        self.state.step += 1;
        Ok(())
    }

    /// Advance by one time step.
    pub fn step(&mut self) -> Result<(), BcdError> {
        self.step_alone()
    }

    /// Advance by one time step and add the configuration it ends in to a density profile and
    /// a cluster-size histogram: the same counts as [`DensityProfile::sample`] of
    /// [`Bcd::positions`] and [`ClusterSizes::sample`] after [`Bcd::step`]. On a ring with the
    /// premerged update (Euler or LM) the rods are binned and the clusters counted in the
    /// step's own parallel pass, each chunk into its own partial, the partials added in chunk
    /// order (integer counts: the same for any number of threads), and with `positions` the
    /// centres [`Bcd::positions`] returns are written there too (not in a serial pass when
    /// asked for); otherwise all is done after the step. On an error nothing is added.
    pub fn step_observed(
        &mut self,
        density: Option<&mut DensityProfile>,
        clusters: Option<&mut ClusterSizes>,
        positions: bool,
    ) -> Result<(), BcdError> {
        if self.ring.is_none() {
            self.step_alone()?;
            if let Some(d) = density {
                match self.reduced() {
                    Some(y) => d.sample_reduced(y, self.cfg.sigma),
                    None => d.sample(self.positions()),
                }
            }
            if let Some(c) = clusters {
                c.sample(self);
            }
            return Ok(());
        }
        let want = Want {
            density: density.as_ref().map(|d| d.binning()),
            clusters: clusters.is_some(),
            positions,
        };
        let Some(r) = &mut self.ring else {
            unreachable!("a ring step")
        };
        if positions {
            // The last positions' buffer (stale after this step), or the spare one.
            let spare = self.spare.get_mut().unwrap_or_else(|e| e.into_inner());
            r.x = self
                .positions
                .take()
                .unwrap_or_else(|| std::mem::take(spare));
        }
        let step = self.state.step;
        let done = r.step(
            &self.ext,
            &self.pair,
            &self.cfg,
            (self.noise_amp, step),
            want,
        );
        let done = done.map_err(|(i, u)| (i, u, r.y[i]));
        if done.is_ok() {
            if let Some(d) = density {
                d.add_counts(&r.density);
            }
            if let Some(c) = clusters {
                c.add_counts(&r.clusters, r.y.len());
            }
        }
        let x = std::mem::take(&mut r.x);
        self.reduced_step_done(done)?;
        if positions {
            let _ = self.positions.set(x);
        } else if !x.is_empty() {
            *self.spare.get_mut().unwrap_or_else(|e| e.into_inner()) = x;
        }
        Ok(())
    }

    /// One step, no observers.
    fn step_alone(&mut self) -> Result<(), BcdError> {
        if let Some(r) = &mut self.reflect {
            let step = self.state.step;
            if self.noise_amp == 0.0 {
                return Err(ParamError::new(
                    "kt",
                    "the reflecting integrator needs kT > 0 (at kT = 0 rods pressed together \
                     would bounce instead of moving as a cluster); use Euler or LM",
                )
                .into());
            }
            let done = r.step(&self.ext, &self.pair, &self.cfg, step);
            let done = done.map_err(|(i, u)| (i, u, r.y[i]));
            return self.reduced_step_done(done);
        }
        if self.ring.is_some() {
            // The ring step with nothing to observe.
            return self.step_observed(None, None, false);
        }
        let n = self.len();
        let origin = self.origin(&self.state.bond);
        let periodic = self.cfg.boundary == Boundary::Periodic;
        let chronological = self.cfg.update == Update::Chronological;
        let (sigma, dt, length) = (self.cfg.sigma, self.cfg.dt, self.cfg.length);

        // Chunk boundaries at cluster starts, about CHUNK rods apart.
        {
            let ring = Ring {
                x: &self.state.x,
                bond: &self.state.bond,
                n,
                length,
                periodic,
            };
            let end = origin + n;
            let k = self.chunks.len();
            let mut prev = origin;
            for c in 0..k {
                let mut s = (origin + c * CHUNK).min(end);
                while s > origin && s < end && ring.bonded_right(s - 1) {
                    s += 1;
                }
                if c > 0 {
                    self.chunks[c - 1].ve = s;
                }
                self.chunks[c].vs = s.max(prev);
                prev = self.chunks[c].vs;
            }
            self.chunks[k - 1].ve = end;
        }

        // Leimkuhler–Matthews: this step's xi_n + xi_{n+1} of every rod, keeping xi_{n+1}.
        let lm = self.integrator == Integrator::Lm && self.noise_amp > 0.0;
        if lm {
            let (seed, step) = (self.cfg.seed, self.state.step);
            let fresh = self.kept_step != Some(step);
            self.kept
                .par_chunks_mut(SEG)
                .zip(self.lm_noise.par_chunks_mut(SEG))
                .enumerate()
                .for_each(|(b, (kept, sum))| {
                    if fresh {
                        noise_segment(seed, step, b, kept);
                    }
                    noise_segment(seed, step + 1, b, sum);
                    for (s, k) in sum.iter_mut().zip(kept.iter_mut()) {
                        let next = *s;
                        *s += *k;
                        *k = next;
                    }
                });
            self.kept_step = Some(step + 1);
        }

        // Forces, fragmentation and chunk-local premerging, in parallel.
        {
            let ring = Ring {
                x: &self.state.x,
                bond: &self.state.bond,
                n,
                length,
                periodic,
            };
            let ctx = StepCtx::new(
                &ring,
                (&self.ext, &self.pair),
                &self.cfg,
                (self.noise_amp, &self.lm_noise[..if lm { n } else { 0 }]),
                self.state.step,
                [
                    !periodic && self.state.left_contact,
                    !periodic && self.state.right_contact,
                ],
                !chronological,
            );
            self.chunks
                .par_iter_mut()
                .for_each(|c| chunk_phase(c, &ctx));
        }
        if let Some((i, u)) = self.chunks.iter().filter_map(|c| c.bad).min_by_key(|b| b.0) {
            self.kept_step = None;
            return Err(BcdError::NonFinite {
                step: self.state.step,
                particle: i,
                position: self.state.x[i],
                velocity: u,
            });
        }

        // Sequential pass across chunk boundaries, then walls or the periodic seam.
        let g = &mut self.global;
        g.clear();
        if !periodic {
            g.push(Cluster {
                start: 0,
                n: 0,
                left: 0.5 * sigma,
                v: 0.0,
                wall: Wall::Left,
            });
        }
        for c in &self.chunks {
            for &cl in &c.stack {
                if cl.wall == Wall::Left {
                    let top = g.last_mut().expect("left wall sentinel");
                    *top = merge(top, &cl, sigma);
                } else if chronological {
                    g.push(cl);
                } else {
                    premerge(g, cl, sigma, dt);
                }
            }
        }
        let mut head = 0;
        let mut write_dt = dt;
        if !periodic {
            let right = Cluster {
                start: n as u32,
                n: 0,
                left: length + 0.5 * sigma,
                v: 0.0,
                wall: Wall::Right,
            };
            if chronological {
                g.push(right);
            } else {
                premerge(g, right, sigma, dt);
            }
        }
        if chronological {
            head = chronological_events(g, periodic, n, length, sigma, dt);
            write_dt = 0.0;
        } else if periodic {
            head = stitch_seam(g, n, length, sigma, dt);
        }

        // Position and bond update, in parallel over fixed ranges of rods.
        let live = &self.global[head..];
        let first_start = live
            .iter()
            .find(|c| c.n > 0)
            .map_or(0, |c| c.start as usize);
        let back = *live
            .iter()
            .rev()
            .find(|c| c.n > 0)
            .expect("at least one rod");
        let periodic_origin = if periodic { origin } else { 0 };
        let len = length;
        self.state
            .x
            .par_chunks_mut(CHUNK)
            .zip(self.state.bond.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(k, (xs, bs))| {
                let a0 = k * CHUNK;
                let a1 = a0 + xs.len();
                let write = |w0: usize, w1: usize, xs: &mut [f64], bs: &mut [u8]| {
                    write_range(
                        live,
                        &back,
                        first_start,
                        n,
                        len,
                        sigma,
                        write_dt,
                        w0,
                        w1,
                        xs,
                        bs,
                    )
                };
                if periodic_origin > a0 {
                    let m = periodic_origin.min(a1) - a0;
                    let (xl, xr) = xs.split_at_mut(m);
                    let (bl, br) = bs.split_at_mut(m);
                    write(a0 + n, a0 + m + n, xl, bl);
                    if !xr.is_empty() {
                        write(a0 + m, a1, xr, br);
                    }
                } else {
                    write(a0, a1, xs, bs);
                }
            });
        if !periodic {
            self.state.left_contact = live
                .first()
                .is_some_and(|c| c.wall == Wall::Left && c.n > 0);
            self.state.right_contact = back.wall == Wall::Right;
            // The last rod is never bonded to the right (no ring).
            self.state.bond[n - 1] = 0;
        }
        self.state.step += 1;
        Ok(())
    }

    /// Run `steps` steps.
    ///
    /// The steps run on a worker of the thread pool, so that the chunks of each step start
    /// without a hand-over from a foreign thread (two context switches per step, about 1 ns per
    /// particle-step at 10^4 rods).
    pub fn run(&mut self, steps: u64) -> Result<(), BcdError> {
        rayon::scope(|_| (0..steps).try_for_each(|_| self.step()))
    }

    /// The systematic force on every rod at the current positions (external field, drive and
    /// pair forces; no noise, no hard-core constraint), in ring order.
    pub fn systematic_forces(&self) -> Vec<f64> {
        let x = self.positions();
        let n = x.len();
        let periodic = self.cfg.boundary == Boundary::Periodic;
        let (l, range) = (self.cfg.length, self.pair.range());
        (0..n)
            .map(|i| {
                let mut f = self.ext.force(x[i]);
                if range > 0.0 {
                    // Right neighbours push rod i to the left, left neighbours to the right.
                    for k in 1..n {
                        let (j, wrap) = ((i + k) % n, (i + k) / n);
                        if !periodic && wrap > 0 {
                            break;
                        }
                        let r = x[j] + wrap as f64 * l - x[i];
                        if r >= range {
                            break;
                        }
                        f -= self.pair.force(r);
                    }
                    for k in 1..n {
                        if !periodic && k > i {
                            break;
                        }
                        let j = (i + n - k) % n;
                        let r = x[i] - (x[j] - if j > i { l } else { 0.0 });
                        if r >= range {
                            break;
                        }
                        f += self.pair.force(r);
                    }
                }
                f
            })
            .collect()
    }

    /// Check the hard core and the walls (for tests): returns the smallest gap minus sigma.
    pub fn min_clearance(&self) -> f64 {
        let x = self.positions();
        let n = x.len();
        let s = self.cfg.sigma;
        let mut m = f64::INFINITY;
        for i in 0..n.saturating_sub(1) {
            m = m.min(x[i + 1] - x[i] - s);
        }
        match self.cfg.boundary {
            Boundary::Periodic if n > 1 => m.min(x[0] + self.cfg.length - x[n - 1] - s),
            Boundary::Periodic => m,
            Boundary::Walls => m
                .min(x[0] - 0.5 * s)
                .min(self.cfg.length - 0.5 * s - x[n - 1]),
        }
    }
}

/// Centres `x_i = y_i + i sigma` of reduced positions `y` into `x` (resized).
fn centres(y: &[f64], sigma: f64, x: &mut Vec<f64>) {
    x.resize(y.len(), 0.0);
    if y.len() <= i32::MAX as usize {
        // Rod numbers through i32, whose conversion to f64 vectorises (the same values:
        // integers below 2^31 are exact either way).
        for (i, (xi, &yi)) in x.iter_mut().zip(y).enumerate() {
            *xi = yi + (i as i32) as f64 * sigma;
        }
    } else {
        for (i, (xi, &yi)) in x.iter_mut().zip(y).enumerate() {
            *xi = yi + i as f64 * sigma;
        }
    }
}

struct StepCtx<'a, E, P> {
    ring: &'a Ring<'a>,
    ext: &'a E,
    pair: &'a P,
    m: Motion,
    /// Leimkuhler–Matthews: `xi_n + xi_{n+1}` of every rod (empty for Euler).
    lm_noise: &'a [f64],
    left_wall: bool,
    right_wall: bool,
    premerge: bool,
}

impl<'a, E, P> StepCtx<'a, E, P> {
    /// What every chunk of a step reads: the configuration `ring`, the forces, the noise
    /// amplitude with the Leimkuhler–Matthews deviates (empty for Euler), the step's noise key,
    /// whether each end touches its wall, and whether fragments are premerged.
    fn new(
        ring: &'a Ring<'a>,
        (ext, pair): (&'a E, &'a P),
        cfg: &BcdConfig,
        (noise_amp, lm_noise): (f64, &'a [f64]),
        step: u64,
        walls: [bool; 2],
        premerge: bool,
    ) -> Self {
        Self {
            ring,
            ext,
            pair,
            lm_noise,
            m: Motion::new(cfg, noise_amp, step, !lm_noise.is_empty()),
            left_wall: walls[0],
            right_wall: walls[1],
            premerge,
        }
    }
}

/// Free velocities `u_i = mu F_i` (fast-bcd Eq. 3; hard-rods paper Eq. 12) of the chunk's rods,
/// fed rod by rod into the fragmentation hull of their cluster; each cluster's fragments are
/// premerged as soon as the cluster ends. One pass, no per-rod buffers.
fn chunk_phase<E: ExternalForce, P: PairForce>(c: &mut Chunk, ctx: &StepCtx<E, P>) {
    c.stack.clear();
    c.bad = None;
    let (vs, ve) = (c.vs, c.ve);
    let ring = ctx.ring;
    let n = ring.n;
    let range = ctx.pair.range();
    let has_pair = range > ctx.m.sigma;
    let mut noise_block = usize::MAX;
    let mut noise = [0.0f64; SEG];
    let (stack, hull) = (&mut c.stack, &mut c.hull);
    let mut open = false;
    let mut w = vs;
    // Walk in segments of actual indices, so that the ring wrap is not a per-rod branch.
    while w < ve {
        let wraps = w / n;
        let base = wraps * n;
        let seg_end = ve.min(base + n);
        let offset = wraps as f64 * ring.length;
        for a in w - base..seg_end - base {
            let vw = a + base;
            let xi = ring.x[a] + offset;
            // The external force acts at the rod's own (unwrapped) position, whatever frame
            // the cluster is seen in.
            let mut f = ctx.ext.force(ring.x[a]);
            if has_pair {
                f += pair_force(ring, ctx.pair, a, vw, xi, range);
            }
            let mut u = ctx.m.mobility * f;
            if ctx.m.lm {
                u += 0.5 * ctx.m.noise_amp * ctx.lm_noise[a];
            } else if ctx.m.noise_amp > 0.0 {
                let b = a / SEG;
                if b != noise_block {
                    noise_block = b;
                    let m = SEG.min(n - b * SEG);
                    noise_segment(ctx.m.seed, ctx.m.step, b, &mut noise[..m]);
                }
                u += ctx.m.noise_amp * noise[a % SEG];
            }
            if !u.is_finite() {
                c.bad = Some((a, u));
                return;
            }
            if !open {
                hull.begin(ctx.left_wall && vw == 0);
                open = true;
            }
            hull.push(vw as u32, xi, u);
            if ring.bond[a] == 0 || vw + 1 == ve {
                let rw = ctx.right_wall && !ring.periodic && a + 1 == n;
                hull.finish(rw, |cl| {
                    // A fragment stuck to the left wall joins the wall in the sequential pass.
                    if ctx.premerge && cl.wall != Wall::Left {
                        premerge(stack, cl, ctx.m.sigma, ctx.m.dt);
                    } else {
                        stack.push(cl);
                    }
                });
                open = false;
            }
        }
        w = seg_end;
    }
}

/// Pair force on rod `a` (virtual index `vw`, position `xi`) from its neighbours within `range`.
#[inline]
fn pair_force<P: PairForce>(
    ring: &Ring,
    pair: &P,
    a: usize,
    vw: usize,
    xi: f64,
    range: f64,
) -> f64 {
    let n = ring.n;
    let mut f = 0.0;
    // Right neighbours push rod a to the left, left neighbours to the right.
    let mut k = 1;
    while k < n && (ring.periodic || a + k < n) {
        let r = ring.pos(vw + k) - xi;
        if r >= range {
            break;
        }
        f -= pair.force(r);
        k += 1;
    }
    let mut k = 1;
    while k < n && (ring.periodic || a >= k) {
        let r = xi - (ring.pos(vw + n - k) - ring.length);
        if r >= range {
            break;
        }
        f += pair.force(r);
        k += 1;
    }
    f
}

/// Premerge across the periodic seam: the last cluster meets the first one a period further
/// on. Returns how many clusters at the front were absorbed into the last one.
fn stitch_seam(g: &mut Vec<Cluster>, n: usize, length: f64, sigma: f64, dt: f64) -> usize {
    let mut head = 0;
    while g.len() - head >= 2 {
        let last = g.len() - 1;
        let mut front = g[head];
        front.start += n as u32;
        front.left += length;
        if collide(&g[last], &front, sigma, dt) {
            g[last] = merge(&g[last], &front, sigma);
            head += 1;
            // The grown cluster may now reach its left neighbours.
            while g.len() - head >= 2 {
                let l = g.len() - 1;
                if collide(&g[l - 1], &g[l], sigma, dt) {
                    g[l - 1] = merge(&g[l - 1], &g[l], sigma);
                    g.pop();
                } else {
                    break;
                }
            }
        } else {
            break;
        }
    }
    head
}

/// The chronological update of the hard-rods paper (Eqs. 14–20): move every cluster to the
/// earliest collision, merge the colliding pair inelastically, repeat until the step ends.
/// O(N) per collision, O(N^2) per step. Positions are advanced in place; returns the number of
/// front clusters absorbed across the periodic seam.
fn chronological_events(
    g: &mut Vec<Cluster>,
    periodic: bool,
    n: usize,
    length: f64,
    sigma: f64,
    dt: f64,
) -> usize {
    let mut head = 0;
    let mut remaining = dt;
    let shifted = |c: &Cluster| Cluster {
        start: c.start + n as u32,
        left: c.left + length,
        ..*c
    };
    loop {
        let mut best = f64::INFINITY;
        let mut which = usize::MAX;
        let len = g.len();
        let pair_time = |a: &Cluster, b: &Cluster| {
            let closing = a.v - b.v;
            if closing > 0.0 {
                ((b.left - a.left - a.n as f64 * sigma).max(0.0)) / closing
            } else {
                f64::INFINITY
            }
        };
        for k in head..len.saturating_sub(1) {
            let t = pair_time(&g[k], &g[k + 1]);
            if t < best {
                best = t;
                which = k;
            }
        }
        if periodic && len - head >= 2 {
            let t = pair_time(&g[len - 1], &shifted(&g[head]));
            if t < best {
                best = t;
                which = len - 1;
            }
        }
        let t = best.min(remaining);
        for c in &mut g[head..] {
            c.left += c.v * t;
        }
        if best > remaining || which == usize::MAX {
            break;
        }
        remaining -= best;
        if which == len - 1 {
            let f = shifted(&g[head]);
            g[len - 1] = merge(&g[len - 1], &f, sigma);
            head += 1;
        } else {
            g[which] = merge(&g[which], &g[which + 1], sigma);
            g.remove(which + 1);
        }
    }
    head
}

/// Write positions and bonds of the rods with virtual indices `[w0, w1)` from the cluster
/// list `live` (sorted by start); rods before `first_start` belong to `back` one period on.
fn write_range(
    live: &[Cluster],
    back: &Cluster,
    first_start: usize,
    n: usize,
    length: f64,
    sigma: f64,
    dt: f64,
    w0: usize,
    w1: usize,
    xs: &mut [f64],
    bs: &mut [u8],
) {
    // Every virtual index in one call has the same number of wraps around the ring.
    let wraps_of = |w: usize| {
        if w < n {
            0.0
        } else if w < 2 * n {
            1.0
        } else {
            2.0
        }
    };
    // Rods [wa, wb) of cluster c (virtual indices as c counts them) into xs[k0..].
    let mut fill = |c: &Cluster, wa: usize, wb: usize, k0: usize| {
        let start = c.start as usize;
        let base = c.left + c.v * dt - wraps_of(wa) * length + (wa - start) as f64 * sigma;
        let len = wb - wa;
        for (j, x) in xs[k0..k0 + len].iter_mut().enumerate() {
            *x = base + j as f64 * sigma;
        }
        let bonds = &mut bs[k0..k0 + len];
        bonds.fill(1);
        if wb == start + c.n as usize {
            bonds[len - 1] = 0;
        }
    };
    let mut w = w0;
    let head_end = w1.min(first_start);
    if w < head_end {
        fill(back, w + n, head_end + n, 0);
        w = head_end;
    }
    if w >= w1 {
        return;
    }
    let mut idx = live.partition_point(|c| (c.start + c.n) as usize <= w);
    while w < w1 {
        let c = &live[idx];
        let end = ((c.start + c.n) as usize).min(w1);
        fill(c, w, end, w - w0);
        w = end;
        idx += 1;
    }
}

/// The ring update's reduced coordinates `y_i = x_i - i sigma` of a state: its own `reduced`
/// when present (a checkpoint of the ring update; checked against `x`), else derived from `x`
/// with the rods of each cluster (`bond`) set to their first rod's value.
fn reduced_positions(cfg: &BcdConfig, state: &BcdState) -> Result<Vec<f64>, BcdError> {
    let (x, n, sigma) = (&state.x, state.x.len(), cfg.sigma);
    if state.reduced.is_empty() {
        let mut y: Vec<f64> = Vec::with_capacity(n);
        for i in 0..n {
            let fresh = x[i] - i as f64 * sigma;
            y.push(if i > 0 && state.bond[i - 1] != 0 {
                y[i - 1]
            } else {
                fresh
            });
        }
        return Ok(y);
    }
    let y = &state.reduced;
    if y.len() != n {
        return Err(BcdError::Positions(format!(
            "reduced has {} entries for {n} rods",
            y.len()
        )));
    }
    let tol = 1e-9 * cfg.length.max(sigma);
    for i in 0..n {
        let xi = y[i] + i as f64 * sigma;
        if !(xi - x[i]).abs().le(&tol) || (i > 0 && y[i] < y[i - 1]) {
            return Err(BcdError::Positions(format!(
                "reduced position {i} ({}) does not match x = {} (x_i = reduced_i + i sigma, non-decreasing)",
                y[i], x[i]
            )));
        }
    }
    Ok(y.clone())
}

fn check_positions(cfg: &BcdConfig, x: &[f64]) -> Result<(), BcdError> {
    let n = x.len();
    let s = cfg.sigma;
    let tol = 1e-9 * s;
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(BcdError::Positions(format!(
            "rod {i} has a non-finite position"
        )));
    }
    for i in 0..n.saturating_sub(1) {
        if x[i + 1] - x[i] < s - tol {
            return Err(BcdError::Positions(format!(
                "rods {i} (x = {}) and {} (x = {}) overlap: centres closer than the rod length {s} (positions must be sorted and at least sigma apart)",
                x[i],
                i + 1,
                x[i + 1]
            )));
        }
    }
    match cfg.boundary {
        Boundary::Periodic => {
            if n > 1 && x[0] + cfg.length - x[n - 1] < s - tol {
                return Err(BcdError::Positions(format!(
                    "rods {} (x = {}) and 0 (x = {}) overlap across the periodic seam (L = {})",
                    n - 1,
                    x[n - 1],
                    x[0],
                    cfg.length
                )));
            }
        }
        Boundary::Walls => {
            if x[0] < 0.5 * s - tol || x[n - 1] > cfg.length - 0.5 * s + tol {
                return Err(BcdError::Positions(format!(
                    "rod centres must lie in [sigma/2, L - sigma/2] = [{}, {}] between walls; found {} and {}",
                    0.5 * s,
                    cfg.length - 0.5 * s,
                    x[0],
                    x[n - 1]
                )));
            }
        }
    }
    Ok(())
}

/// Visit the sizes of the clusters of `n` rods in ring order, rod `i` bonded to its right
/// neighbour when `bonded(i)` (on a ring, rod `n - 1` to rod 0), starting at the first cluster
/// start.
fn cluster_walk(
    n: usize,
    periodic: bool,
    bonded: impl Fn(usize) -> bool,
    mut visit: impl FnMut(usize),
) {
    let origin = cluster_origin(n, periodic, &bonded);
    let mut size = 0;
    // From the origin to the end, then from the start to the origin (no index wrap per rod).
    for range in [origin..n, 0..origin] {
        for w in range {
            size += 1;
            if !bonded(w) {
                visit(size);
                size = 0;
            }
        }
    }
    if size > 0 {
        visit(size);
    }
}

/// Add the clusters of `n` rods to `counts` (at least `n + 1` long): `ends` says for each of
/// rods 0 to n - 2 whether it ends its cluster (is not bonded to the next); `wraps`: the last
/// rod is bonded to the first. Every rod adds 0 or 1 to the count of the size its cluster has if it ends there (no
/// branch per rod); a cluster across the seam is then moved from its first part's size to its
/// whole size.
fn histogram_clusters(
    n: usize,
    ends: impl Iterator<Item = bool> + Clone,
    wraps: bool,
    counts: &mut [u64],
) {
    let mut start = 0;
    for (i, end) in ends.clone().enumerate() {
        counts[i + 1 - start] += u64::from(end);
        start = if end { i + 1 } else { start };
    }
    // The open cluster [start, n - 1].
    let tail = n - start;
    if !wraps {
        counts[tail] += 1;
    } else if start == 0 {
        // No rod ends a cluster: one cluster round the ring.
        counts[n] += 1;
    } else {
        let first = ends.take_while(|e| !e).count() + 1;
        counts[first] -= 1;
        counts[first + tail] += 1;
    }
}

/// The first cluster start in ring order: the first rod not bonded to its left neighbour (on
/// a ring; 0 between walls, or when every rod is bonded).
fn cluster_origin(n: usize, periodic: bool, bonded: impl Fn(usize) -> bool) -> usize {
    if periodic {
        (0..n).find(|&i| !bonded((i + n - 1) % n)).unwrap_or(0)
    } else {
        0
    }
}

#[cfg(test)]
mod observed_tests {
    use super::*;
    use crate::forces::NoPair;

    /// A rugged field: clusters fragment, collide and cross chunk boundaries every step.
    fn rugged(x: f64) -> f64 {
        3.0 * (2.3 * x).sin() + 1.5 * (7.1 * x + 0.3).cos()
    }

    /// The density and clusters taken in the step's own parallel pass (partials per chunk,
    /// corrected for the stitch), and the positions written there, equal the observers sampled
    /// after a plain step and its positions, bit for bit, on
    /// 1, 2 and 3 threads, with Euler and LM, on a dense ring of several chunks whose stitch
    /// pools blocks and rewrites rods every step.
    #[test]
    fn observed_step_equals_sampling_after_the_step() {
        let n = 3 * CHUNK + 123;
        let cfg = BcdConfig {
            length: n as f64,
            sigma: 0.99,
            mobility: 1.0,
            kt: 1.0,
            dt: 2e-3,
            boundary: Boundary::Periodic,
            seed: 5,
            update: Update::Premerge,
        };
        let x0 = crate::init::random(&cfg, n, 3).unwrap();
        let mut results = Vec::new();
        for integrator in [Integrator::Euler, Integrator::Lm] {
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let make = || {
                    Bcd::new(cfg.clone(), x0.clone(), rugged, NoPair)
                        .unwrap()
                        .with_integrator(integrator)
                };
                let (mut plain, mut fused) = (make(), make());
                // 7 bins over a period of 1.3 (the rods fold into it many times).
                let density = || DensityProfile::new(7, 1.3, n as f64);
                let (mut d_plain, mut d_fused) = (density(), density());
                let (mut c_plain, mut c_fused) = (ClusterSizes::default(), ClusterSizes::default());
                let (mut merges, mut dirty) = (0, 0);
                pool.install(|| {
                    for t in 0..12 {
                        plain.step().unwrap();
                        d_plain.sample(plain.positions());
                        c_plain.sample(&plain);
                        fused
                            .step_observed(Some(&mut d_fused), Some(&mut c_fused), t % 3 != 1)
                            .unwrap();
                        let (m, d) = fused.ring.as_ref().unwrap().stitch_work();
                        merges += m;
                        dirty += d;
                        assert_eq!(plain.positions(), fused.positions());
                        assert_eq!(d_fused.profile(), d_plain.profile());
                        assert_eq!(c_fused.rows(), c_plain.rows());
                    }
                });
                assert!(merges > 0 && dirty > 0, "the stitch had nothing to do");
                results.push((d_fused.profile(), c_fused.rows()));
            }
        }
        for r in &results[1..3] {
            assert_eq!(r, &results[0]);
        }
        for r in &results[4..] {
            assert_eq!(r, &results[3]);
        }
    }

    /// Between walls (no ring step) the observers are sampled after the step: the same counts.
    #[test]
    fn observed_step_between_walls_equals_sampling_after_the_step() {
        let n = 300;
        let cfg = BcdConfig {
            length: 320.0,
            sigma: 1.0,
            mobility: 1.0,
            kt: 1.0,
            dt: 1e-2,
            boundary: Boundary::Walls,
            seed: 2,
            update: Update::Premerge,
        };
        let x0 = crate::init::random(&cfg, n, 1).unwrap();
        let mut plain = Bcd::new(cfg.clone(), x0.clone(), rugged, NoPair).unwrap();
        let mut fused = Bcd::new(cfg, x0, rugged, NoPair).unwrap();
        let (mut d_plain, mut d_fused) = (
            DensityProfile::new(9, 320.0, 320.0),
            DensityProfile::new(9, 320.0, 320.0),
        );
        let (mut c_plain, mut c_fused) = (ClusterSizes::default(), ClusterSizes::default());
        for _ in 0..20 {
            plain.step().unwrap();
            d_plain.sample(plain.positions());
            c_plain.sample(&plain);
            fused
                .step_observed(Some(&mut d_fused), Some(&mut c_fused), true)
                .unwrap();
        }
        assert_eq!(d_fused.profile(), d_plain.profile());
        assert_eq!(c_fused.rows(), c_plain.rows());
        assert_eq!(d_fused.samples(), 20);
    }
}
