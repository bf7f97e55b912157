//! The BCD time step: forces, fragmentation, premerging (or the chronological event-driven
//! update), and the position update.
//!
//! Rods are kept in ring order with unwrapped positions, `x[0] < x[1] < ... < x[N-1]`, and on
//! the ring `x[N-1] < x[0] + L`, so positions are also the displacements needed for the MSD.
//! A *virtual index* `w` counts around the ring from the first cluster start (`origin`);
//! `w >= N` denotes rod `w - N` seen one period further on (position `+ L`).
//!
//! The ring is cut into chunks of about [`CHUNK`] rods at cluster boundaries; each chunk computes
//! its forces, fragments its clusters and premerges them independently (in parallel), then one
//! short sequential pass premerges across chunk boundaries and the periodic seam. Chunking
//! depends only on N and the configuration, never on the thread count, so results are
//! bitwise identical for any number of threads.

use crate::cluster::{Cluster, Hull, Wall, collide, merge, premerge};
use crate::forces::{ExternalForce, PairForce};
use colloidsim_core::ParamError;
use colloidsim_core::param;
use colloidsim_core::rng::{BLOCK, fill_normal_block_fast};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Rods per chunk of the parallel step.
pub const CHUNK: usize = 4096;

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
    /// Check ranges for `n` rods; errors name the scenario key.
    pub fn validate(&self, n: usize) -> Result<(), ParamError> {
        param::positive("system.length", self.length)?;
        param::positive("system.diameter", self.sigma)?;
        param::positive("system.mobility", self.mobility)?;
        param::non_negative("system.kT", self.kt)?;
        param::positive("run.dt", self.dt)?;
        param::at_least("system.particles", n, 1)?;
        if n > u32::MAX as usize / 4 {
            return Err(ParamError::new(
                "system.particles",
                format!("at most {} rods, got {n}", u32::MAX / 4),
            ));
        }
        let packed = n as f64 * self.sigma;
        if packed >= self.length {
            return Err(ParamError::new(
                "system.particles",
                format!(
                    "{n} rods of length {} fill {packed} >= system.length {}: N sigma must be < L",
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
        "the run went non-finite at step {step}: rod {particle} at x = {position} has velocity {velocity}; reduce run.dt or check the potential"
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
}

#[derive(Debug, Default, Clone)]
struct Chunk {
    vs: usize,
    ve: usize,
    stack: Vec<Cluster>,
    hull: Hull,
    /// Blocks of the ring step; `pool[0]` is a sentinel, `pool[head..end]` the live ones.
    pool: Vec<Pool>,
    head: usize,
    end: usize,
    /// The last live block grew in the stitch: its rods must be rewritten.
    dirty: bool,
    /// Per rod of the ring step, the index of the block it starts (0 inside a block).
    marks: Vec<u32>,
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
    /// Positions and bonds being written by the ring step (swapped with the state's).
    x_next: Vec<f64>,
    bond_next: Vec<u8>,
    /// Chunks with live blocks during the ring stitch.
    live: Vec<usize>,
}

impl<E: ExternalForce, P: PairForce> Bcd<E, P> {
    /// Set up a run from rod centres `x` (sorted, non-overlapping; unwrapped on the ring).
    pub fn new(cfg: BcdConfig, x: Vec<f64>, ext: E, pair: P) -> Result<Self, BcdError> {
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
            step: 0,
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
        let chunks = vec![Chunk::default(); n.div_ceil(CHUNK)];
        let noise_amp = (2.0 * cfg.diffusion() / cfg.dt).sqrt();
        let ring = cfg.boundary == Boundary::Periodic && cfg.update == Update::Premerge;
        let spare = if ring { n } else { 0 };
        Ok(Self {
            cfg,
            ext,
            pair,
            state,
            chunks,
            global: Vec::new(),
            noise_amp,
            x_next: vec![0.0; spare],
            bond_next: vec![0; spare],
            live: Vec::new(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &BcdConfig {
        &self.cfg
    }
    /// Number of rods.
    pub fn len(&self) -> usize {
        self.state.x.len()
    }
    /// Always false (a run has at least one rod).
    pub fn is_empty(&self) -> bool {
        self.state.x.is_empty()
    }
    /// Unwrapped rod centres in ring order.
    pub fn positions(&self) -> &[f64] {
        &self.state.x
    }
    /// The dynamic state (for checkpoints).
    pub fn state(&self) -> &BcdState {
        &self.state
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
    pub fn cluster_sizes(&self, mut visit: impl FnMut(usize)) {
        let n = self.len();
        let origin = self.origin();
        let mut size = 0;
        for w in origin..origin + n {
            size += 1;
            if self.state.bond[w % n] == 0 {
                visit(size);
                size = 0;
            }
        }
        if size > 0 {
            visit(size);
        }
    }

    fn origin(&self) -> usize {
        let n = self.len();
        match self.cfg.boundary {
            Boundary::Walls => 0,
            Boundary::Periodic => (0..n)
                .find(|&i| self.state.bond[(i + n - 1) % n] == 0)
                .unwrap_or(0),
        }
    }

    /// Advance by one time step.
    pub fn step(&mut self) -> Result<(), BcdError> {
        let n = self.len();
        let origin = self.origin();
        let periodic = self.cfg.boundary == Boundary::Periodic;
        let chronological = self.cfg.update == Update::Chronological;
        // Ring with premerging: one pooling pass on end-of-step positions (`chunk_phase_ring`).
        let fast = periodic && !chronological;
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

        if fast {
            return self.step_ring(origin);
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
                self.noise_amp,
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

    /// The premerged step on a ring: each chunk pools its rods and writes their end-of-step
    /// positions and bonds (in parallel); a short sequential pass then pools the blocks that meet
    /// across chunk boundaries and the periodic seam and rewrites only their rods.
    fn step_ring(&mut self, origin: usize) -> Result<(), BcdError> {
        let n = self.len();
        let (sigma, length) = (self.cfg.sigma, self.cfg.length);
        {
            let ring = Ring {
                x: &self.state.x,
                bond: &self.state.bond,
                n,
                length,
                periodic: true,
            };
            let ctx = StepCtx::new(
                &ring,
                (&self.ext, &self.pair),
                &self.cfg,
                self.noise_amp,
                self.state.step,
                [false; 2],
                true,
            );
            // Virtual indices [origin, n) are rods origin.., [n, n + origin) rods 0.. one period on.
            let (xl, xr) = self.x_next.split_at_mut(origin);
            let (bl, br) = self.bond_next.split_at_mut(origin);
            let first = Out {
                x: xr,
                b: br,
                v0: origin,
            };
            let second = Out {
                x: xl,
                b: bl,
                v0: n,
            };
            ring_chunks(&mut self.chunks, first, second, &ctx);
        }
        if let Some((i, u)) = self.chunks.iter().filter_map(|c| c.bad).min_by_key(|b| b.0) {
            return Err(BcdError::NonFinite {
                step: self.state.step,
                particle: i,
                position: self.state.x[i],
                velocity: u,
            });
        }
        stitch_ring(&mut self.chunks, &mut self.live, n, length, sigma);
        // Rewrite the rods of the blocks that grew in the stitch (always a chunk's last block).
        for c in &self.chunks {
            if c.head < c.end && c.dirty {
                let p = c.pool[c.end - 1];
                let (start, cnt) = (p.start as usize, p.n as usize);
                for w in start..start + cnt {
                    let a = w % n;
                    self.x_next[a] = p.pos + (w - start) as f64 * sigma - (w / n) as f64 * length;
                    self.bond_next[a] = u8::from(w + 1 < start + cnt);
                }
            }
        }
        std::mem::swap(&mut self.state.x, &mut self.x_next);
        std::mem::swap(&mut self.state.bond, &mut self.bond_next);
        self.state.step += 1;
        Ok(())
    }

    /// Run `steps` steps.
    pub fn run(&mut self, steps: u64) -> Result<(), BcdError> {
        for _ in 0..steps {
            self.step()?;
        }
        Ok(())
    }

    /// Check the hard core and the walls (for tests): returns the smallest gap minus sigma.
    pub fn min_clearance(&self) -> f64 {
        let x = &self.state.x;
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

struct StepCtx<'a, E, P> {
    ring: &'a Ring<'a>,
    ext: &'a E,
    pair: &'a P,
    mobility: f64,
    noise_amp: f64,
    seed: u32,
    step: u64,
    sigma: f64,
    dt: f64,
    left_wall: bool,
    right_wall: bool,
    premerge: bool,
}

impl<'a, E, P> StepCtx<'a, E, P> {
    /// What every chunk of a step reads: the configuration `ring`, the forces, the step's noise
    /// key, whether each end touches its wall, and whether fragments are premerged.
    fn new(
        ring: &'a Ring<'a>,
        (ext, pair): (&'a E, &'a P),
        cfg: &BcdConfig,
        noise_amp: f64,
        step: u64,
        walls: [bool; 2],
        premerge: bool,
    ) -> Self {
        Self {
            ring,
            ext,
            pair,
            mobility: cfg.mobility,
            noise_amp,
            seed: cfg.seed,
            step,
            sigma: cfg.sigma,
            dt: cfg.dt,
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
    let has_pair = range > ctx.sigma;
    let mut noise_block = usize::MAX;
    let mut noise = [0.0f64; BLOCK];
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
            let mut f = ctx.ext.force(xi);
            if has_pair {
                f += pair_force(ring, ctx.pair, a, vw, xi, range);
            }
            let mut u = ctx.mobility * f;
            if ctx.noise_amp > 0.0 {
                let b = a / BLOCK;
                if b != noise_block {
                    noise_block = b;
                    let m = BLOCK.min(n - b * BLOCK);
                    fill_normal_block_fast(ctx.seed, ctx.step, b as u64, &mut noise[..m]);
                }
                u += ctx.noise_amp * noise[a % BLOCK];
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
                        premerge(stack, cl, ctx.sigma, ctx.dt);
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

/// A block of rods that end the step together, in the pooling pass of [`chunk_phase_ring`]:
/// `n` rods from virtual index `start`. `pos` is the end-of-step reduced position `z` relative
/// to the chunk's first rod while pooling, then the end-of-step centre of the block's first rod
/// (unwrapped, in the frame of its virtual index).
#[derive(Debug, Clone, Copy, Default)]
struct Pool {
    pos: f64,
    n: f64,
    start: u32,
}

/// Output rods of virtual indices `[v0, v0 + x.len())`.
struct Out<'a> {
    x: &'a mut [f64],
    b: &'a mut [u8],
    v0: usize,
}

impl<'a> Out<'a> {
    /// Split at virtual index `v`.
    fn split(self, v: usize) -> (Out<'a>, Out<'a>) {
        let k = v.saturating_sub(self.v0).min(self.x.len());
        let (xa, xb) = self.x.split_at_mut(k);
        let (ba, bb) = self.b.split_at_mut(k);
        (
            Out {
                x: xa,
                b: ba,
                v0: self.v0,
            },
            Out {
                x: xb,
                b: bb,
                v0: self.v0 + k,
            },
        )
    }
}

/// Run [`chunk_phase_ring`] on every chunk in parallel, handing each the parts of the output
/// arrays that hold its rods (`first`: virtual indices below N, `second`: one period on).
fn ring_chunks<E: ExternalForce, P: PairForce>(
    chunks: &mut [Chunk],
    first: Out,
    second: Out,
    ctx: &StepCtx<E, P>,
) {
    if chunks.len() == 1 {
        chunk_phase_ring(&mut chunks[0], first, second, ctx);
        return;
    }
    let mid = chunks.len() / 2;
    let v = chunks[mid].vs;
    let (f1, f2) = first.split(v);
    let (s1, s2) = second.split(v);
    let (c1, c2) = chunks.split_at_mut(mid);
    rayon::join(
        || ring_chunks(c1, f1, s1, ctx),
        || ring_chunks(c2, f2, s2, ctx),
    );
}

/// The premerged step of the chunk's rods on a ring in one pooling pass.
///
/// In reduced coordinates `y_i = x_i - i sigma` hard rods are points that may not pass each
/// other, and a cluster of rods in contact shares one `y`. Fragmentation (fast-bcd Eqs. 4a/4b:
/// the lower convex hull of the cumulative free velocities, see [`Hull`]) followed by binary
/// premerging (Sec. IV, Eq. 20: clusters `a`, `b` merge when `y_a + v_a dt >= y_b + v_b dt`,
/// into the centre of mass, Eq. 6) is the same pooling of adjacent violators applied to the free
/// end-of-step positions `z_i = y_i + u_i dt`: inside a cluster (equal `y`) it compares mean
/// velocities, across clusters it detects the collisions within `dt`, and pooling in any order
/// reaches the same unique result. So one stack over `z` does both, left to right; rods of one
/// block end in contact. The chunk then writes its rods' end-of-step positions and bonds.
fn chunk_phase_ring<E: ExternalForce, P: PairForce>(
    c: &mut Chunk,
    first: Out,
    second: Out,
    ctx: &StepCtx<E, P>,
) {
    c.bad = None;
    let (vs, ve) = (c.vs, c.ve);
    let ring = ctx.ring;
    let n = ring.n;
    let range = ctx.pair.range();
    let has_pair = range > ctx.sigma;
    let (sigma, dt, mobility, amp) = (ctx.sigma, ctx.dt, ctx.mobility, ctx.noise_amp);
    let xref = ring.pos(vs);
    let len_c = ve - vs;
    // Finished blocks pool[1..=top] above a sentinel that never pools (its mean is NaN), each
    // with the sum `pos` of its z and its size `n` while pooling; the open block (sum `s`,
    // size `m`, first rod `first_rod`) stays in registers.
    let pool = &mut c.pool;
    if pool.is_empty() {
        pool.push(Pool::default());
    }
    pool[0] = Pool {
        pos: f64::NAN,
        n: 1.0,
        start: vs as u32,
    };
    let mut top = 0;
    let (mut s, mut m, mut first_rod) = (0.0f64, 0.0f64, vs as u32);
    let mut noise = [0.0f64; BLOCK];
    let mut zbuf = [0.0f64; BLOCK];
    // Reduced start-of-step position of the current cluster; the chunk starts a cluster.
    let mut y = 0.0f64;
    let mut bonded = false;
    let mut w = vs;
    while w < ve {
        // One segment: rods of one noise block, without crossing the ring's end.
        let wraps = w / n;
        let base = wraps * n;
        let a0 = w - base;
        let b = a0 / BLOCK;
        let a1 = (ve - base).min(n).min((b + 1) * BLOCK);
        let len = a1 - a0;
        let offset = wraps as f64 * ring.length;
        if amp > 0.0 {
            let mm = BLOCK.min(n - b * BLOCK);
            fill_normal_block_fast(ctx.seed, ctx.step, b as u64, &mut noise[..mm]);
        }
        // Free end-of-step reduced positions z (free velocities: fast-bcd Eq. 3).
        let xs = &ring.x[a0..a1];
        let fbuf = &mut zbuf[..len];
        ctx.ext.force_block(xs, offset, fbuf);
        if has_pair {
            for (k, f) in fbuf.iter_mut().enumerate() {
                *f += pair_force(ring, ctx.pair, a0 + k, w + k, xs[k] + offset, range);
            }
        }
        let mut kf = (w - vs) as f64;
        let rods = xs
            .iter()
            .zip(&ring.bond[a0..a1])
            .zip(&noise[a0 - b * BLOCK..a1 - b * BLOCK]);
        for (z, ((&xa, &bd), &g)) in fbuf.iter_mut().zip(rods) {
            let u = mobility * *z + amp * g;
            // A rod bonded to its left neighbour keeps the cluster's y bit for bit (select
            // without a branch: the bonds are data-dependent).
            let fresh = (xa + offset - xref) - kf * sigma;
            let keep = u64::from(bonded).wrapping_neg();
            y = f64::from_bits((y.to_bits() & keep) | (fresh.to_bits() & !keep));
            bonded = bd != 0;
            *z = y + u * dt;
            kf += 1.0;
        }
        // Pool adjacent violators. The common decision (does rod k join the open block, i.e.
        // is the open block's mean z >= z_k?) is taken without a branch: the open block is
        // always stored one above the stack top and the top index advances only when it is
        // closed. Only the rarer cascade into the blocks below branches. Ties pool.
        // Room for the open block above every block this segment can add.
        if pool.len() < top + len + 2 {
            pool.resize(top + len + 2, Pool::default());
        }
        let st = pool.as_mut_slice();
        for (k, &z) in zbuf[..len].iter().enumerate() {
            let join = s >= z * m;
            st[top + 1] = Pool {
                pos: s,
                n: m,
                start: first_rod,
            };
            let jf = f64::from(u8::from(join));
            top += usize::from(!join);
            s = z + jf * s;
            m = 1.0 + jf * m;
            let keep = u32::from(join).wrapping_neg();
            first_rod = (first_rod & keep) | ((w + k) as u32 & !keep);
            loop {
                let below = st[top];
                if below.pos * m >= s * below.n {
                    s += below.pos;
                    m += below.n;
                    first_rod = below.start;
                    top -= 1;
                } else {
                    break;
                }
            }
        }
        w = a1 + base;
    }
    if m > 0.0 {
        top += 1;
        if top == pool.len() {
            pool.push(Pool::default());
        }
        pool[top] = Pool {
            pos: s,
            n: m,
            start: first_rod,
        };
    }
    c.end = top + 1;
    // Each block's rods end at x_k = base + k sigma (k counted from the chunk's first rod);
    // rods are marked with the index of the block they start.
    let marks = &mut c.marks;
    if marks.len() < len_c + 1 {
        marks.resize(len_c + 1, 0);
    }
    marks[..len_c].fill(0);
    marks[len_c] = 1;
    let mut finite = true;
    for (i, p) in pool[1..=top].iter_mut().enumerate() {
        marks[p.start as usize - vs] = i as u32 + 1;
        p.pos = xref + p.pos / p.n;
        finite &= p.pos.is_finite();
    }
    if !finite {
        c.bad = first_non_finite(vs, ve, ctx);
        return;
    }
    let la = first.x.len();
    let mut cur = 0;
    write_rods(
        first.x,
        first.b,
        &marks[..=la],
        pool,
        &mut cur,
        0.0,
        sigma,
        0.0,
    );
    write_rods(
        second.x,
        second.b,
        &marks[la..=len_c],
        pool,
        &mut cur,
        la as f64,
        sigma,
        ring.length,
    );
    // For the stitch: the end-of-step centre of each block's first rod.
    for p in &mut pool[1..=top] {
        p.pos += f64::from(p.start - vs as u32) * sigma;
    }
}

/// Positions `base + k sigma - wrap` and bonds of consecutive rods (`k` from `k0`), where
/// `base` is that of the last block started at or before the rod (`marks`, one longer than
/// `xs`, holds the block index at each block's first rod and 0 elsewhere). Branch-free.
#[inline]
fn write_rods(
    xs: &mut [f64],
    bs: &mut [u8],
    marks: &[u32],
    pool: &[Pool],
    cur: &mut usize,
    k0: f64,
    sigma: f64,
    wrap: f64,
) {
    let mut kf = k0;
    let ends = marks.iter().zip(&marks[1..]);
    for ((x, b), (&mk, &next)) in xs.iter_mut().zip(bs.iter_mut()).zip(ends) {
        *cur = (*cur).max(mk as usize);
        *x = pool[*cur].pos + kf * sigma - wrap;
        *b = u8::from(next == 0);
        kf += 1.0;
    }
}

/// The first rod of virtual range `[vs, ve)` with a non-finite free velocity, and that
/// velocity (the slow path behind the ring step's finiteness check).
fn first_non_finite<E: ExternalForce, P: PairForce>(
    vs: usize,
    ve: usize,
    ctx: &StepCtx<E, P>,
) -> Option<(usize, f64)> {
    let ring = ctx.ring;
    let n = ring.n;
    let range = ctx.pair.range();
    let mut noise = [0.0f64; BLOCK];
    for w in vs..ve {
        let a = w % n;
        let xi = ring.x[a] + (w / n) as f64 * ring.length;
        let mut f = ctx.ext.force(xi);
        if range > ctx.sigma {
            f += pair_force(ring, ctx.pair, a, w, xi, range);
        }
        let mut g = 0.0;
        if ctx.noise_amp > 0.0 {
            let b = a / BLOCK;
            let mm = BLOCK.min(n - b * BLOCK);
            fill_normal_block_fast(ctx.seed, ctx.step, b as u64, &mut noise[..mm]);
            g = noise[a % BLOCK];
        }
        let u = ctx.mobility * f + ctx.noise_amp * g;
        if !(u * ctx.dt).is_finite() {
            return Some((a, u));
        }
    }
    Some((ring.actual(vs), f64::NAN))
}

/// Pool the chunks' blocks across chunk boundaries and the periodic seam (blocks given by
/// end-of-step positions; pooling at the centre of mass, fast-bcd Eq. 6). Sets each chunk's
/// live range `pool[head..end]`; grown blocks are marked dirty.
fn stitch_ring(chunks: &mut [Chunk], live: &mut Vec<usize>, n: usize, length: f64, sigma: f64) {
    live.clear();
    for c in chunks.iter_mut() {
        c.head = 1;
        c.dirty = false;
    }
    for ci in 0..chunks.len() {
        while chunks[ci].head < chunks[ci].end {
            let Some(&pi) = live.last() else { break };
            let first = chunks[ci].pool[chunks[ci].head];
            if !absorb(&mut chunks[pi], &first, sigma) {
                break;
            }
            chunks[ci].head += 1;
            cascade(chunks, live, 0, sigma);
        }
        if chunks[ci].head < chunks[ci].end {
            live.push(ci);
        }
    }
    // The seam: the last block meets the first one a period further on.
    let mut lf = 0;
    while live.len() > lf {
        let (fi, li) = (live[lf], live[live.len() - 1]);
        if fi == li && chunks[fi].end - chunks[fi].head < 2 {
            break;
        }
        let mut front = chunks[fi].pool[chunks[fi].head];
        front.start += n as u32;
        front.pos += length;
        if !absorb(&mut chunks[li], &front, sigma) {
            break;
        }
        chunks[fi].head += 1;
        if chunks[fi].head == chunks[fi].end {
            lf += 1;
        }
        cascade(chunks, live, lf, sigma);
    }
}

/// Pool `block` into chunk `c`'s last block when they overlap (marking the chunk dirty); false
/// when they do not.
fn absorb(c: &mut Chunk, block: &Pool, sigma: f64) -> bool {
    let last = &mut c.pool[c.end - 1];
    if !overlap(last, block, sigma) {
        return false;
    }
    *last = pool_pair(last, block, sigma);
    c.dirty = true;
    true
}

/// Pool the last live block into its left neighbours for as long as they overlap (live chunks
/// `live[lf..]`).
fn cascade(chunks: &mut [Chunk], live: &mut Vec<usize>, lf: usize, sigma: f64) {
    loop {
        let pi = live[live.len() - 1];
        let c = &mut chunks[pi];
        let top = c.pool[c.end - 1];
        if c.end - c.head >= 2 {
            let prev = c.pool[c.end - 2];
            if !overlap(&prev, &top, sigma) {
                return;
            }
            c.end -= 1;
            c.pool[c.end - 1] = pool_pair(&prev, &top, sigma);
            c.dirty = true;
        } else {
            if live.len() - lf < 2 {
                return;
            }
            let qc = &mut chunks[live[live.len() - 2]];
            let prev = &mut qc.pool[qc.end - 1];
            if !overlap(prev, &top, sigma) {
                return;
            }
            *prev = pool_pair(prev, &top, sigma);
            qc.dirty = true;
            chunks[pi].end -= 1;
            live.pop();
        }
    }
}

/// Do blocks `a` (left) and `b` (right), given by end-of-step positions, overlap or touch?
#[inline]
fn overlap(a: &Pool, b: &Pool, sigma: f64) -> bool {
    b.pos - a.pos - a.n * sigma <= 0.0
}

/// Pool two blocks given by end-of-step positions at their centre of mass (fast-bcd Eq. 6).
#[inline]
fn pool_pair(a: &Pool, b: &Pool, sigma: f64) -> Pool {
    let n = a.n + b.n;
    Pool {
        pos: a.pos + (b.pos - a.n * sigma - a.pos) * (b.n / n),
        n,
        start: a.start,
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
