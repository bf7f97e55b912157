//! The premerged BCD step on a ring, in reduced coordinates (the fast path of [`crate::engine`]).
//!
//! In reduced coordinates `y_i = x_i - i sigma` hard rods are points that may not pass each
//! other, and the rods of a cluster share one `y`: here bit for bit, because a cluster is stored
//! as one value written to all its rods. Fragmentation (fast-bcd Eqs. 4a/4b: the lower convex
//! hull of the cumulative free velocities) followed by binary premerging (Sec. IV, Eq. 20:
//! clusters `a`, `b` merge when `y_a + v_a dt >= y_b + v_b dt`, at the centre of mass, Eq. 6)
//! is the pooling of adjacent violators of the free end-of-step positions `z_i = y_i + u_i dt`
//! (free velocities `u_i`, Eq. 3): inside a cluster (equal `y`) it compares mean velocities,
//! across clusters it detects the collisions within `dt`, and pooling in any order reaches the
//! same unique result. Each block of pooled rods ends the step in contact at the mean `z` of
//! its rods.
//!
//! The ring is cut into chunks of [`CHUNK`] rods at fixed indices. Each chunk (in parallel)
//! computes its `z`, pools them in [`LANES`] interleaved streams (independent dependency chains
//! that the out-of-order core runs side by side), joins the streams' blocks and writes its rods;
//! a short sequential stitch then pools across chunk boundaries and the periodic seam and
//! rewrites the rods of the blocks that grew. Chunks and streams depend only on N, never on the
//! thread count, so results are bitwise identical for any number of threads.

use crate::forces::{ExternalForce, PairForce};
use crate::observe::Binning;
use crate::pava::{self, Block, LANES, STACK};
use colloidsim_core::rng::{WIDE, fill_normal_wide};
use rayon::prelude::*;
use std::sync::Mutex;

/// Rods per chunk of the parallel step (a multiple of [`SEG`]).
pub const CHUNK: usize = 4096;
/// Rods per noise and force segment.
pub const SEG: usize = 256;
const _: () = assert!(STACK >= CHUNK / LANES + LANES + 3);
const _: () = assert!(CHUNK.is_multiple_of(SEG) && SEG == WIDE);

/// Standard normal deviates of rods `[seg * SEG, seg * SEG + out.len())` at `step` (the noise
/// of every BCD update, so that all of them see the same numbers).
#[inline]
pub(crate) fn noise_segment(seed: u32, step: u64, seg: usize, out: &mut [f64]) {
    fill_normal_wide(seed, step, seg as u64, out);
}

/// `n` as an index, for an integer `0 <= n < 2^52` (branch-free: the integer is read off the
/// mantissa of `n + 2^52`).
#[inline(always)]
fn count(n: f64) -> usize {
    const TWO52: f64 = (1u64 << 52) as f64;
    ((n + TWO52).to_bits() & ((1u64 << 52) - 1)) as usize
}

/// What a step of any update reads from the configuration besides the forces.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Motion {
    pub mobility: f64,
    /// Noise amplitude `sqrt(2 D / dt)`.
    pub noise_amp: f64,
    /// Leimkuhler–Matthews noise `(xi_n + xi_{n+1}) / 2` instead of Euler's `xi_n` (only with
    /// noise, `noise_amp > 0`).
    pub lm: bool,
    pub seed: u32,
    pub step: u64,
    pub sigma: f64,
    pub dt: f64,
    /// Ring length (or wall distance) L.
    pub length: f64,
}

impl Motion {
    pub fn new(cfg: &crate::engine::BcdConfig, noise_amp: f64, step: u64, lm: bool) -> Self {
        Self {
            mobility: cfg.mobility,
            noise_amp,
            lm: lm && noise_amp > 0.0,
            seed: cfg.seed,
            step,
            sigma: cfg.sigma,
            dt: cfg.dt,
            length: cfg.length,
        }
    }
}

/// What a ring step tallies for the observers in its own chunk pass: each chunk into its own
/// partial, the partials added in chunk order after the stitch and corrected for what the
/// stitch changed (integer counts: the totals do not depend on the thread count).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Want {
    /// Bin the rods' end-of-step centres `x_i = y_i + i sigma`.
    pub density: Option<Binning>,
    /// Count the pooled blocks (the clusters at the end of the step) by size.
    pub clusters: bool,
    /// Write the rods' end-of-step centres into [`RingStep::x`].
    pub positions: bool,
}

/// What every chunk of a ring step reads.
pub(crate) struct RingCtx<'a, E, P> {
    /// Reduced positions at the start of the step.
    pub y: &'a [f64],
    pub ext: &'a E,
    pub pair: &'a P,
    pub m: Motion,
    /// Leimkuhler–Matthews only: the chunks' kept deviates are not those of this step (first
    /// step, restart, or after an error) and are drawn afresh from the step counter.
    pub fresh: bool,
    /// The observers' tallies to take in the chunk pass.
    pub want: Want,
}

impl<E: ExternalForce, P: PairForce> RingCtx<'_, E, P> {
    /// Reduced period `L - N sigma`: rod `a` one period on sits at `y_a + L - N sigma`.
    fn reduced_period(&self) -> f64 {
        self.m.length - self.y.len() as f64 * self.m.sigma
    }

    /// Forces `f` on rods `[a0, a0 + f.len())` (external and pair) and their noise deviates
    /// `xi` of step `step`, within one segment. Euler's free velocities are
    /// `u = mu f + sqrt(2D/dt) xi` (fast-bcd Eq. 3).
    fn forces(&self, a0: usize, f: &mut [f64], xi: &mut [f64], step: u64) {
        let (sigma, len) = (self.m.sigma, f.len());
        self.ext
            .force_block_reduced(&self.y[a0..a0 + len], a0, sigma, f);
        let range = self.pair.range();
        if range > sigma {
            for (k, fk) in f.iter_mut().enumerate() {
                *fk += self.pair_force(a0 + k, range);
            }
        }
        if self.m.noise_amp > 0.0 {
            noise_segment(self.m.seed, step, a0 / SEG, xi);
        } else {
            xi.fill(0.0);
        }
    }

    /// Pair force on rod `a` from its neighbours within `range` (centre distances
    /// `r = y_b - y_a + (b - a) sigma`, across the seam with the reduced period).
    fn pair_force(&self, a: usize, range: f64) -> f64 {
        let (y, n, sigma) = (self.y, self.y.len(), self.m.sigma);
        let lred = self.reduced_period();
        let mut f = 0.0;
        // Right neighbours push rod a to the left, left neighbours to the right.
        for k in 1..n {
            let b = a + k;
            let yb = if b < n { y[b] } else { y[b - n] + lred };
            let r = (yb - y[a]) + k as f64 * sigma;
            if r >= range {
                break;
            }
            f -= self.pair.force(r);
        }
        for k in 1..n {
            let yb = if a >= k {
                y[a - k]
            } else {
                y[a + n - k] - lred
            };
            let r = (y[a] - yb) + k as f64 * sigma;
            if r >= range {
                break;
            }
            f += self.pair.force(r);
        }
        f
    }
}

/// Per-thread scratch of the chunk pass.
struct Scratch {
    /// Free end-of-step reduced positions of the chunk's rods, relative to its first rod.
    z: Vec<f64>,
    /// One stack of `[sum of z, rods]` per stream; entry 0 is a sentinel that never pools.
    stacks: Box<[[[f64; 2]; STACK]]>,
    /// The chunk's pooled blocks `[sum of z, rods]`.
    blocks: Vec<Block>,
    /// Noise deviates of one segment (kept here: zeroing a fresh array per chunk showed in
    /// small runs).
    noise: [f64; SEG],
    /// The density bins of the chunk's rods ([`Want::density`]).
    bins: Vec<u32>,
}

impl Scratch {
    fn new() -> Self {
        Self {
            z: vec![0.0; CHUNK],
            stacks: pava::new_stacks(),
            blocks: vec![[0.0; 2]; CHUNK],
            noise: [0.0; SEG],
            bins: vec![0; CHUNK],
        }
    }
}

#[derive(Debug, Default, Clone)]
struct Chunk {
    /// Rods `[a0, a1)`.
    a0: usize,
    a1: usize,
    /// The chunk's blocks in ring order; `pool[head..end]` are live during the stitch.
    pool: Vec<Block>,
    head: usize,
    end: usize,
    /// First rod of `pool[end - 1]` (its rods may reach past N, i.e. round the seam, after the
    /// stitch).
    last_start: usize,
    /// The last live block grew in the stitch: its rods must be rewritten.
    dirty: bool,
    /// First rod whose free velocity went non-finite, with that velocity.
    bad: Option<(usize, f64)>,
    /// Leimkuhler–Matthews: the deviates `xi_{n+1}` of the chunk's rods, drawn in step n and
    /// kept for step n + 1 (empty for Euler).
    kept: Vec<f64>,
    /// [`Want::density`]: the chunk's rods per density bin, as the chunk pass wrote them.
    density: Vec<u64>,
    /// [`Want::clusters`]: the chunk's pooled blocks by size, before the stitch.
    sizes: Vec<u64>,
}

/// State and buffers of the ring step.
pub(crate) struct RingStep {
    /// Reduced positions `y_i = x_i - i sigma` (unwrapped); rods of one cluster share `y`.
    pub y: Vec<f64>,
    y_next: Vec<f64>,
    /// Rods N-1 and 0 belong to one cluster (across the seam).
    pub seam: bool,
    chunks: Vec<Chunk>,
    live: Vec<usize>,
    scratch: Vec<Mutex<Option<Scratch>>>,
    /// Leimkuhler–Matthews noise (the chunks keep the next step's deviates).
    lm: bool,
    /// The step whose deviates the chunks keep (`None`: draw them from the step counter).
    kept_step: Option<u64>,
    /// The chunks' live blocks are the clusters of `y` (the last thing done was a step).
    blocks_current: bool,
    /// Scratch of [`RingStep::count_clusters_from_blocks`]: one size histogram per worker.
    cluster_parts: Mutex<Vec<Vec<u64>>>,
    /// The sizes `[a, b]` of the blocks pooled by the last stitch, in order.
    merges: Vec<[usize; 2]>,
    /// The last step's [`Want`] tallies: rods per density bin, clusters by size (the totals).
    pub density: Vec<u64>,
    pub clusters: Vec<u64>,
    /// [`Want::positions`]: the centres `x_i = y_i + i sigma` at the end of the last step (a
    /// buffer the caller lends and takes back).
    pub x: Vec<f64>,
}

impl RingStep {
    /// Start from reduced positions `y` (rods of a cluster with equal values).
    pub fn new(y: Vec<f64>, seam: bool) -> Self {
        let n = y.len();
        let chunks = (0..n.div_ceil(CHUNK))
            .map(|c| Chunk {
                a0: c * CHUNK,
                a1: ((c + 1) * CHUNK).min(n),
                ..Chunk::default()
            })
            .collect();
        Self {
            y_next: vec![0.0; n],
            y,
            seam,
            chunks,
            live: Vec::new(),
            scratch: Vec::new(),
            lm: false,
            kept_step: None,
            blocks_current: false,
            cluster_parts: Mutex::new(Vec::new()),
            merges: Vec::new(),
            density: Vec::new(),
            clusters: Vec::new(),
            x: Vec::new(),
        }
    }

    /// Add the sizes of the clusters of the current configuration to `counts` (indexed by
    /// size, at least N + 1 long) from the last step's pooled blocks, one per cluster:
    /// O(clusters) rather than O(N). `false` (and nothing added) when there was no step since
    /// the positions were set.
    pub fn count_clusters_from_blocks(&self, counts: &mut [u64]) -> bool {
        if !self.blocks_current {
            return false;
        }
        // The chunks in contiguous parts over the workers, each into its own histogram (as long
        // as its largest cluster), then added in order: integer counts, the same for any number
        // of workers.
        if self.chunks.is_empty() {
            return true;
        }
        let per = self
            .chunks
            .len()
            .div_ceil(rayon::current_num_threads().max(1));
        let parts = self.chunks.len().div_ceil(per);
        let mut hists = self.cluster_parts.lock().unwrap_or_else(|e| e.into_inner());
        hists.resize_with(parts, Vec::new);
        let tally = |h: &mut Vec<u64>, cs: &[Chunk]| {
            h.clear();
            for c in cs {
                for b in &c.pool[c.head..c.end] {
                    let k = count(b[1]);
                    if k >= h.len() {
                        h.resize(k + 1, 0);
                    }
                    h[k] += 1;
                }
            }
        };
        if parts == 1 {
            tally(&mut hists[0], &self.chunks);
        } else {
            hists
                .par_iter_mut()
                .zip(self.chunks.par_chunks(per))
                .for_each(|(h, cs)| tally(h, cs));
        }
        for h in hists.iter() {
            for (c, &v) in counts.iter_mut().zip(h) {
                *c += v;
            }
        }
        true
    }

    /// The chunks' partial tallies added in chunk order into the totals; the cluster sizes
    /// corrected for the stitch's poolings (each replaces blocks of `a` and `b` rods by one of
    /// `a + b`).
    fn add_partials(&mut self, want: Want) {
        if let Some(b) = &want.density {
            self.density.clear();
            self.density.resize(b.bins, 0);
            for c in &self.chunks {
                for (t, &q) in self.density.iter_mut().zip(&c.density) {
                    *t += q;
                }
            }
        }
        if want.clusters {
            let h = &mut self.clusters;
            h.clear();
            for c in &self.chunks {
                if h.len() < c.sizes.len() {
                    h.resize(c.sizes.len(), 0);
                }
                for (t, &q) in h.iter_mut().zip(&c.sizes) {
                    *t += q;
                }
            }
            // In the order of the stitch, every pooled block is present when it pools.
            for &[a, b] in &self.merges {
                if h.len() <= a + b {
                    h.resize(a + b + 1, 0);
                }
                h[a] -= 1;
                h[b] -= 1;
                h[a + b] += 1;
            }
        }
    }

    /// The last stitch's poolings and the chunks whose last block it grew (for tests).
    #[cfg(test)]
    pub(crate) fn stitch_work(&self) -> (usize, usize) {
        (
            self.merges.len(),
            self.chunks.iter().filter(|c| c.dirty).count(),
        )
    }

    /// Use the Leimkuhler–Matthews noise (`true`) or Euler's (`false`). Costs 8 bytes per rod
    /// for the kept deviates, which are drawn again from the step counter at the next step.
    pub fn set_lm(&mut self, lm: bool) {
        self.lm = lm;
        self.kept_step = None;
        for c in &mut self.chunks {
            if lm {
                c.kept.resize(c.a1 - c.a0, 0.0);
            } else {
                c.kept = Vec::new();
            }
        }
    }

    /// One premerged step, taking the tallies `want` of its end configuration into
    /// [`RingStep::density`] and [`RingStep::clusters`]; on a non-finite free velocity, returns
    /// the first such rod and its velocity and leaves the state unchanged.
    pub fn step<E: ExternalForce, P: PairForce>(
        &mut self,
        ext: &E,
        pair: &P,
        cfg: &crate::engine::BcdConfig,
        (noise_amp, step): (f64, u64),
        want: Want,
    ) -> Result<(), (usize, f64)> {
        let threads = rayon::current_num_threads().max(1);
        if self.scratch.len() < threads {
            self.scratch.resize_with(threads, || Mutex::new(None));
        }
        self.blocks_current = false;
        let m = Motion::new(cfg, noise_amp, step, self.lm);
        let ctx = RingCtx {
            y: &self.y,
            ext,
            pair,
            m,
            fresh: m.lm && self.kept_step != Some(step),
            want,
        };
        let scratch = &self.scratch;
        let pass = |c: &mut Chunk, out: &mut [f64], xs: Option<&mut [f64]>| {
            let slot = rayon::current_thread_index().unwrap_or(0) % scratch.len();
            let mut guard = scratch[slot].lock().unwrap_or_else(|e| e.into_inner());
            let s = guard.get_or_insert_with(Scratch::new);
            chunk_pass(c, out, xs, s, &ctx);
        };
        let parts = self
            .chunks
            .par_iter_mut()
            .zip(self.y_next.par_chunks_mut(CHUNK));
        if want.positions {
            self.x.resize(self.y.len(), 0.0);
            parts
                .zip(self.x.par_chunks_mut(CHUNK))
                .for_each(|((c, out), xs)| pass(c, out, Some(xs)));
        } else {
            parts.for_each(|(c, out)| pass(c, out, None));
        }
        if let Some(bad) = self.chunks.iter().find_map(|c| c.bad) {
            // Some chunks have moved on to the next step's deviates: draw them again.
            self.kept_step = None;
            return Err(bad);
        }
        self.kept_step = m.lm.then_some(step + 1);
        let n = self.y.len();
        let lred = cfg.length - n as f64 * cfg.sigma;
        self.merges.clear();
        stitch(&mut self.chunks, &mut self.live, lred, &mut self.merges);
        self.add_partials(want);
        // Rewrite the rods of the blocks that grew in the stitch (always a chunk's last block),
        // moving their density counts from the bins the chunk pass found to the new ones.
        let mut seam = false;
        let sigma = cfg.sigma;
        for c in &self.chunks {
            if c.head < c.end {
                let [pos, cnt] = c.pool[c.end - 1];
                let (start, cnt) = (c.last_start, count(cnt));
                seam |= start + cnt > n;
                if c.dirty {
                    for w in start..start + cnt {
                        let wraps = w / n;
                        let i = w - wraps * n;
                        let y = pos - wraps as f64 * lred;
                        let at = (i as i32) as f64 * sigma;
                        if let Some(b) = &want.density {
                            self.density[b.bin(self.y_next[i] + at) as usize] -= 1;
                            self.density[b.bin(y + at) as usize] += 1;
                        }
                        if want.positions {
                            self.x[i] = y + at;
                        }
                        self.y_next[i] = y;
                    }
                }
            }
        }
        std::mem::swap(&mut self.y, &mut self.y_next);
        self.seam = seam && n > 1;
        self.blocks_current = true;
        Ok(())
    }
}

/// The chunk's step: free end-of-step positions, pooling in [`LANES`] streams, joining the
/// streams, writing the rods' end-of-step reduced positions into `out` (and their centres into
/// `xs` when given), taking the tallies of [`RingCtx::want`].
fn chunk_pass<E: ExternalForce, P: PairForce>(
    c: &mut Chunk,
    out: &mut [f64],
    xs: Option<&mut [f64]>,
    s: &mut Scratch,
    ctx: &RingCtx<E, P>,
) {
    c.bad = None;
    let (a0, a1) = (c.a0, c.a1);
    let len = a1 - a0;
    let yref = ctx.y[a0];
    let dt = ctx.m.dt;
    // Free end-of-step reduced positions relative to the chunk's first rod.
    let z = &mut s.z[..len];
    let noise = &mut s.noise;
    let (mu, amp) = (ctx.m.mobility, ctx.m.noise_amp);
    for (k, zs) in z.chunks_mut(SEG).enumerate() {
        let a = a0 + k * SEG;
        let m = zs.len();
        if !ctx.m.lm {
            ctx.forces(a, zs, &mut noise[..m], ctx.m.step);
            let rods = ctx.y[a..a + m].iter().zip(&noise[..m]);
            for (zk, (&yk, &g)) in zs.iter_mut().zip(rods) {
                *zk = (yk - yref) + (mu * *zk + amp * g) * dt;
            }
        } else {
            // Leimkuhler–Matthews: u = mu f + sqrt(2D/dt) (xi_n + xi_{n+1}) / 2, with xi_n kept
            // from the last step and xi_{n+1} kept for the next one (one deviate per rod and step).
            let kept = &mut c.kept[k * SEG..k * SEG + m];
            if ctx.fresh {
                noise_segment(ctx.m.seed, ctx.m.step, a / SEG, kept);
            }
            ctx.forces(a, zs, &mut noise[..m], ctx.m.step + 1);
            let half = 0.5 * amp;
            let rods = ctx.y[a..a + m].iter().zip(kept.iter_mut().zip(&noise[..m]));
            for (zk, (&yk, (xi_n, &xi_next))) in zs.iter_mut().zip(rods) {
                *zk = (yk - yref) + (mu * *zk + half * (*xi_n + xi_next)) * dt;
                *xi_n = xi_next;
            }
        }
    }
    let blocks = pava::pool_chunk(&mut s.stacks, z, &mut s.blocks);
    // End-of-step reduced positions: every rod of a block at the block's mean z. Short blocks
    // are written as a fixed run of FILL values (no data-dependent loop exit); the next block
    // overwrites the excess.
    const FILL: usize = 8;
    let pool = &mut c.pool;
    pool.clear();
    pool.extend(
        s.blocks[..blocks]
            .iter()
            .map(|b| [yref + b[0] / b[1], b[1]]),
    );
    // Without short-circuit, so that it vectorises.
    let finite = pool.iter().fold(true, |ok, b| ok & b[0].is_finite());
    let mut at = 0;
    for b in pool.iter() {
        let m = count(b[1]);
        if m <= FILL && at + FILL <= len {
            out[at..at + FILL].copy_from_slice(&[b[0]; FILL]);
        } else {
            out[at..at + m].fill(b[0]);
        }
        at += m;
    }
    c.head = 0;
    c.end = blocks;
    c.last_start = a1 - pool.last().map_or(0, |b| count(b[1]));
    // The rods' centres x_i = y_i + i sigma exactly as `Bcd::positions` forms them.
    let sigma = ctx.m.sigma;
    if let Some(xs) = xs {
        for (k, (x, &yk)) in xs.iter_mut().zip(&out[..len]).enumerate() {
            *x = yk + ((a0 + k) as i32) as f64 * sigma;
        }
    }
    if let Some(b) = &ctx.want.density {
        // Binned while the chunk is in cache (a vectorised pass), then counted.
        let bins = &mut s.bins[..len];
        for (k, (o, &yk)) in bins.iter_mut().zip(&out[..len]).enumerate() {
            *o = b.bin(yk + ((a0 + k) as i32) as f64 * sigma);
        }
        c.density.clear();
        c.density.resize(b.bins, 0);
        for &o in bins.iter() {
            c.density[o as usize] += 1;
        }
    }
    if ctx.want.clusters {
        let h = &mut c.sizes;
        h.clear();
        for b in pool.iter() {
            let k = count(b[1]);
            if k >= h.len() {
                h.resize(k + 1, 0);
            }
            h[k] += 1;
        }
    }
    if !finite || at != len {
        c.bad = first_non_finite(a0, a1, ctx);
    }
}

/// The first rod of `[a0, a1)` with a non-finite free velocity, and that velocity (the slow
/// path behind the chunk's finiteness check).
fn first_non_finite<E: ExternalForce, P: PairForce>(
    a0: usize,
    a1: usize,
    ctx: &RingCtx<E, P>,
) -> Option<(usize, f64)> {
    let mut u = [0.0f64; SEG];
    let mut noise = [0.0f64; SEG];
    let mut next = [0.0f64; SEG];
    let mut a = a0;
    while a < a1 {
        let m = (a1 - a).min(SEG);
        ctx.forces(a, &mut u[..m], &mut noise[..m], ctx.m.step);
        if ctx.m.lm {
            noise_segment(ctx.m.seed, ctx.m.step + 1, a / SEG, &mut next[..m]);
            for (uk, (&g, &h)) in u[..m].iter_mut().zip(noise[..m].iter().zip(&next[..m])) {
                *uk = ctx.m.mobility * *uk + 0.5 * ctx.m.noise_amp * (g + h);
            }
        } else {
            for (uk, &g) in u[..m].iter_mut().zip(&noise[..m]) {
                *uk = ctx.m.mobility * *uk + ctx.m.noise_amp * g;
            }
        }
        if let Some(k) = u[..m].iter().position(|v| !v.is_finite()) {
            return Some((a + k, u[k]));
        }
        a += m;
    }
    // Finite velocities can still overflow the position.
    Some((a0, f64::NAN))
}

/// Pool the chunks' blocks across chunk boundaries and the periodic seam (pooling at the
/// centre of mass, fast-bcd Eq. 6). Sets each chunk's live range `pool[head..end]`; grown
/// blocks are marked dirty. `lred = L - N sigma` is the reduced period.
/// The sizes of the pooled pairs are appended to `merges`.
fn stitch(chunks: &mut [Chunk], live: &mut Vec<usize>, lred: f64, merges: &mut Vec<[usize; 2]>) {
    live.clear();
    for c in chunks.iter_mut() {
        c.dirty = false;
    }
    for ci in 0..chunks.len() {
        while chunks[ci].head < chunks[ci].end {
            let Some(&pi) = live.last() else { break };
            let first = chunks[ci].pool[chunks[ci].head];
            if !absorb(&mut chunks[pi], &first, merges) {
                break;
            }
            chunks[ci].head += 1;
            cascade(chunks, live, 0, merges);
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
        let [pos, cnt] = chunks[fi].pool[chunks[fi].head];
        if !absorb(&mut chunks[li], &[pos + lred, cnt], merges) {
            break;
        }
        chunks[fi].head += 1;
        if chunks[fi].head == chunks[fi].end {
            lf += 1;
        }
        cascade(chunks, live, lf, merges);
    }
}

/// Pool `block` into chunk `c`'s last block when they meet (marking the chunk dirty); false
/// when they do not.
fn absorb(c: &mut Chunk, block: &Block, merges: &mut Vec<[usize; 2]>) -> bool {
    let last = &mut c.pool[c.end - 1];
    if !meet(last, block) {
        return false;
    }
    merges.push([count(last[1]), count(block[1])]);
    *last = pool_pair(last, block);
    c.dirty = true;
    true
}

/// Pool the last live block into its left neighbours for as long as they meet (live chunks
/// `live[lf..]`).
fn cascade(chunks: &mut [Chunk], live: &mut Vec<usize>, lf: usize, merges: &mut Vec<[usize; 2]>) {
    loop {
        let pi = live[live.len() - 1];
        let c = &mut chunks[pi];
        let top = c.pool[c.end - 1];
        if c.end - c.head >= 2 {
            let prev = c.pool[c.end - 2];
            if !meet(&prev, &top) {
                return;
            }
            c.end -= 1;
            merges.push([count(prev[1]), count(top[1])]);
            c.pool[c.end - 1] = pool_pair(&prev, &top);
            c.last_start -= count(prev[1]);
            c.dirty = true;
        } else {
            if live.len() - lf < 2 {
                return;
            }
            let qc = &mut chunks[live[live.len() - 2]];
            let prev = &mut qc.pool[qc.end - 1];
            if !meet(prev, &top) {
                return;
            }
            merges.push([count(prev[1]), count(top[1])]);
            *prev = pool_pair(prev, &top);
            qc.dirty = true;
            chunks[pi].end -= 1;
            live.pop();
        }
    }
}

/// Do blocks `a` (left) and `b` (right), given by end-of-step reduced positions, meet?
#[inline]
fn meet(a: &Block, b: &Block) -> bool {
    b[0] <= a[0]
}

/// Pool two blocks at their centre of mass (fast-bcd Eq. 6).
#[inline]
fn pool_pair(a: &Block, b: &Block) -> Block {
    let n = a[1] + b[1];
    [a[0] + (b[0] - a[0]) * (b[1] / n), n]
}
