//! The reflecting step ([`crate::Integrator::Reflect`]): elastic collisions in reduced
//! coordinates with Leimkuhler–Matthews in its Markov form.
//!
//! In reduced coordinates `y_i = x_i - i sigma` hard rods are points that may not pass each
//! other: the configurations are the ordered set `y_0 <= ... <= y_{N-1}` (on a ring also
//! `y_{N-1} <= y_0 + L - N sigma`, between walls `sigma/2 <= y_0`, `y_{N-1} <= L - sigma/2 -
//! (N-1) sigma`). BCD's pooling stops a colliding pair at contact, which leaves a boundary layer
//! of width `0.58 sqrt(4 D dt)` in the stationary law (docs/bcd.md, *Time-step error*).
//! Reflecting the free end-of-step point at the faces of the set instead is the symmetrised
//! Euler scheme of reflected diffusions (Bossy, Gobet & Talay, J. Appl. Probab. 41, 877
//! (2004)); a reflection at the face `y_i = y_{i+1}` exchanges the two values, at a wall it is
//! `y -> 2 a - y`, across the ring's seam it exchanges `y_0` and `y_{N-1}` shifted by a period,
//! so folding a point back into the set is: reflect each value into the walls, then sort (the
//! rods take the sorted free end positions). Without forces this is exact at any dt.
//!
//! The forces are integrated as Leimkuhler–Matthews in its Markov form (the "BAOAB limit",
//! Leimkuhler & Matthews, Appl. Math. Res. Express 2013): a chain `Y` carries full Brownian
//! increments, and the configuration sampled and used for the forces is a half kick of it,
//!
//! ```text
//! y_n     = fold(Y_n + sqrt(D dt / 2) R_n),
//! Y_{n+1} = fold(Y_n + mu F(y_n) dt + sqrt(2 D dt) R_n),
//! ```
//!
//! with `R_n` the standard normal deviates of step n keyed by (seed, step, block of 256 chain
//! slots) as every BCD update's. Chain slot `i` takes the force of the slot its kicked point
//! landed in: the fold of the kicked points carries each point's `Y_i + sqrt(2 D dt) R_i`
//! along. Without collisions this is the sequence of [`crate::Integrator::Lm`]. The chain is
//! the state (the checkpoint holds it); `y_n` is derived from it and the step counter.
//!
//! Sorting is O(N) per step in practice (a step moves a rod by a fraction of the spacing): an
//! insertion sort per chunk of [`CHUNK`] rods (in parallel; [`sort_near`] inserts by selects into a
//! window of the last few sorted values instead of a loop with a mispredicted exit: in the crowded
//! bench case, sigma = 0.99 at density 1, the whole step takes 40 % less time), then a sequential fix-up across the
//! chunk boundaries, left to right, and the seam. Chunks are fixed by N, so the result does not
//! depend on the thread count.

use crate::engine::{BcdConfig, Boundary};
use crate::forces::{ExternalForce, PairForce};
use crate::ring::{CHUNK, SEG, noise_segment};
use rayon::prelude::*;

/// An element sorted by its key: a reduced position, or a kicked point with the chain's free
/// end point it carries.
trait Folded: Copy + Send + Sync {
    /// The carried value (0 for none).
    fn carried(&self) -> f64;
    /// An element from its key and carried value.
    fn from_parts(key: f64, carried: f64) -> Self;
    fn key(&self) -> f64;
    /// Set the key (a reflection at a wall; a carried value stays).
    fn set_key(&mut self, k: f64);
    /// Move by `d` (one reduced period of the ring, key and carried value alike).
    fn shift(&mut self, d: f64);
}

impl Folded for f64 {
    #[inline(always)]
    fn carried(&self) -> f64 {
        0.0
    }
    #[inline(always)]
    fn from_parts(key: f64, _: f64) -> Self {
        key
    }
    #[inline(always)]
    fn key(&self) -> f64 {
        *self
    }
    #[inline(always)]
    fn set_key(&mut self, k: f64) {
        *self = k;
    }
    #[inline(always)]
    fn shift(&mut self, d: f64) {
        *self += d;
    }
}

impl Folded for [f64; 2] {
    #[inline(always)]
    fn carried(&self) -> f64 {
        self[1]
    }
    #[inline(always)]
    fn from_parts(key: f64, carried: f64) -> Self {
        [key, carried]
    }
    #[inline(always)]
    fn key(&self) -> f64 {
        self[0]
    }
    #[inline(always)]
    fn set_key(&mut self, k: f64) {
        self[0] = k;
    }
    #[inline(always)]
    fn shift(&mut self, d: f64) {
        self[0] += d;
        self[1] += d;
    }
}

/// Where the reduced positions live.
#[derive(Debug, Clone, Copy)]
enum Domain {
    /// A ring: `y_{N-1} <= y_0 + period`, `period = L - N sigma`.
    Ring { period: f64 },
    /// Hard walls: every `y` in `[lo, hi]`, `hi - lo = L - N sigma`.
    Walls { lo: f64, hi: f64 },
}

/// State and buffers of the reflecting step.
pub(crate) struct ReflectStep {
    /// The chain `Y_n` (reduced positions, folded: sorted, within the walls; on a ring
    /// unwrapped). This is the state.
    pub chain: Vec<f64>,
    /// The sampled configuration `y_n = fold(Y_n + sqrt(D dt / 2) R_n)` (reduced, folded).
    pub y: Vec<f64>,
    /// Per slot of `y`: its kicked point and the carried `Y_i + sqrt(2 D dt) R_i`.
    kicked: Vec<[f64; 2]>,
    /// The next chain, before its fold.
    next: Vec<f64>,
    /// The step whose kick `y` and `kicked` hold (`None`: not yet drawn).
    kicked_step: Option<u64>,
    domain: Domain,
}

impl ReflectStep {
    /// Start from the chain `Y` (reduced positions, sorted).
    pub fn new(chain: Vec<f64>, cfg: &BcdConfig) -> Self {
        let n = chain.len();
        let span = cfg.length - n as f64 * cfg.sigma;
        let domain = match cfg.boundary {
            Boundary::Periodic => Domain::Ring { period: span },
            Boundary::Walls => Domain::Walls {
                lo: 0.5 * cfg.sigma,
                hi: 0.5 * cfg.sigma + span,
            },
        };
        Self {
            y: vec![0.0; n],
            kicked: vec![[0.0; 2]; n],
            next: vec![0.0; n],
            chain,
            kicked_step: None,
            domain,
        }
    }

    /// Draw the sampled configuration of `step` from the chain (if not yet done): `y` for
    /// positions between steps.
    pub fn ensure_kicked(&mut self, cfg: &BcdConfig, step: u64) {
        if self.kicked_step == Some(step) {
            return;
        }
        let d = cfg.diffusion();
        let (h, s) = ((0.5 * d * cfg.dt).sqrt(), (2.0 * d * cfg.dt).sqrt());
        let (chain, seed) = (&self.chain, cfg.seed);
        self.kicked
            .par_chunks_mut(SEG)
            .enumerate()
            .for_each(|(b, out)| {
                let mut r = [0.0f64; SEG];
                let r = &mut r[..out.len()];
                noise_segment(seed, step, b, r);
                let ys = &chain[b * SEG..b * SEG + out.len()];
                for ((o, &yc), &g) in out.iter_mut().zip(ys).zip(r.iter()) {
                    *o = [yc + h * g, yc + s * g];
                }
            });
        fold(&mut self.kicked, self.domain);
        self.y
            .par_chunks_mut(CHUNK)
            .zip(self.kicked.par_chunks(CHUNK))
            .for_each(|(y, k)| {
                for (yi, ki) in y.iter_mut().zip(k) {
                    *yi = ki[0];
                }
            });
        self.kicked_step = Some(step);
    }

    /// One step from `step` to `step + 1`; on a non-finite force returns the first such slot
    /// and its drift velocity `mu F` and leaves the state unchanged.
    pub fn step<E: ExternalForce, P: PairForce>(
        &mut self,
        ext: &E,
        pair: &P,
        cfg: &BcdConfig,
        step: u64,
    ) -> Result<(), (usize, f64)> {
        self.ensure_kicked(cfg, step);
        let (mu, dt, sigma) = (cfg.mobility, cfg.dt, cfg.sigma);
        let range = pair.range();
        let has_pair = range > sigma;
        let period = match self.domain {
            Domain::Ring { period } => Some(period),
            Domain::Walls { .. } => None,
        };
        let (y, kicked) = (&self.y, &self.kicked);
        // Y_i + sqrt(2 D dt) R_i + mu F(y) dt, each slot's force at its sampled position.
        let bad = self
            .next
            .par_chunks_mut(CHUNK)
            .enumerate()
            .filter_map(|(c, out)| {
                let a0 = c * CHUNK;
                for (k, seg) in out.chunks_mut(SEG).enumerate() {
                    let a = a0 + k * SEG;
                    let m = seg.len();
                    ext.force_block_reduced(&y[a..a + m], a, sigma, seg);
                    if has_pair {
                        for (j, f) in seg.iter_mut().enumerate() {
                            *f += pair_force(y, a + j, sigma, range, period, pair);
                        }
                    }
                    // Without short-circuit, so that it vectorises.
                    let finite = seg.iter().fold(true, |ok, f| ok & f.is_finite());
                    if !finite {
                        let j = seg.iter().position(|f| !f.is_finite()).unwrap_or(0);
                        return Some((a + j, mu * seg[j]));
                    }
                    for (f, kp) in seg.iter_mut().zip(&kicked[a..a + m]) {
                        *f = kp[1] + mu * *f * dt;
                    }
                }
                None
            })
            .min_by_key(|b| b.0);
        if let Some(b) = bad {
            return Err(b);
        }
        if let Some(j) = self.next.iter().position(|v| !v.is_finite()) {
            return Err((j, f64::NAN));
        }
        fold(&mut self.next, self.domain);
        std::mem::swap(&mut self.chain, &mut self.next);
        self.ensure_kicked(cfg, step + 1);
        Ok(())
    }
}

/// Pair force on slot `a` of the sampled configuration `y` from its neighbours within `range`
/// (centre distances `y_b - y_a + (b - a) sigma`; on a ring across the seam with the reduced
/// `period`).
#[inline]
fn pair_force<P: PairForce>(
    y: &[f64],
    a: usize,
    sigma: f64,
    range: f64,
    period: Option<f64>,
    pair: &P,
) -> f64 {
    let n = y.len();
    let mut f = 0.0;
    // Right neighbours push rod a to the left, left neighbours to the right.
    for k in 1..n {
        let b = a + k;
        let yb = match (b < n, period) {
            (true, _) => y[b],
            (false, Some(p)) => y[b - n] + p,
            (false, None) => break,
        };
        let r = (yb - y[a]) + k as f64 * sigma;
        if r >= range {
            break;
        }
        f -= pair.force(r);
    }
    for k in 1..n {
        let yb = match (a >= k, period) {
            (true, _) => y[a - k],
            (false, Some(p)) => y[a + n - k] - p,
            (false, None) => break,
        };
        let r = (y[a] - yb) + k as f64 * sigma;
        if r >= range {
            break;
        }
        f += pair.force(r);
    }
    f
}

/// A value outside the walls `[lo, hi]` reflected back in (at the nearer wall; a value beyond a
/// whole width is folded with the period `2 (hi - lo)` of the reflections).
#[inline]
fn reflect_into(k: f64, lo: f64, hi: f64) -> f64 {
    let r = if k < lo { 2.0 * lo - k } else { 2.0 * hi - k };
    if r >= lo && r <= hi {
        return r;
    }
    let w = hi - lo;
    let t = (k - lo).rem_euclid(2.0 * w);
    (lo + if t > w { 2.0 * w - t } else { t }).clamp(lo, hi)
}

/// Fold `v` into the ordered set of `domain`: reflect into the walls and insertion-sort each
/// chunk (in parallel), then insert across the chunk boundaries left to right, then exchange
/// across the ring's seam until `v_{N-1} <= v_0 + period`. Stable; the carried values travel
/// with their keys.
fn fold<T: Folded>(v: &mut [T], domain: Domain) {
    let n = v.len();
    v.par_chunks_mut(CHUNK).for_each(|c| {
        if let Domain::Walls { lo, hi } = domain {
            for e in c.iter_mut() {
                let k = e.key();
                if k < lo || k > hi {
                    e.set_key(reflect_into(k, lo, hi));
                }
            }
        }
        sort_near(c);
    });
    // Chunk by chunk: [0, b) is sorted and so is [b, end); the points of [b, end) below the
    // largest of [0, b) are a prefix of it.
    let mut b = CHUNK;
    while b < n {
        let end = (b + CHUNK).min(n);
        let mut i = b;
        while i < end && v[i].key() < v[i - 1].key() {
            sift_left(v, i);
            i += 1;
        }
        b = end;
    }
    if let Domain::Ring { period } = domain {
        // Reflection at the seam face y_{N-1} = y_0 + period: the two exchange, each moved by a
        // period (their sum, the centre of mass, is kept).
        while n > 1 && v[n - 1].key() > v[0].key() + period {
            let (mut first, mut last) = (v[n - 1], v[0]);
            first.shift(-period);
            last.shift(period);
            v[0] = first;
            v[n - 1] = last;
            sift_right(&mut v[..n - 1], 0);
            sift_left(v, n - 1);
        }
    }
}

/// Rank displacements a window insertion handles without branching (larger ones fall back to
/// [`sift_left`]).
const WINDOW: usize = 4;

/// Stable insertion sort of `v` for small rank displacements (the result of [`sift_left`] on
/// every element): the largest [`WINDOW`] elements sorted so far stay in registers and each new
/// element is inserted among them by selects, without the mispredicted branch that ends an
/// insertion loop; an element that belongs before the window takes the loop.
fn sort_near<T: Folded>(v: &mut [T]) {
    const K: usize = WINDOW;
    let n = v.len();
    for i in 1..n.min(K) {
        if v[i].key() < v[i - 1].key() {
            sift_left(v, i);
        }
    }
    if n <= K {
        return;
    }
    // The window's keys and carried values, apart (selects on plain f64).
    let mut wk: [f64; K] = std::array::from_fn(|j| v[j].key());
    let mut wc: [f64; K] = std::array::from_fn(|j| v[j].carried());
    let flush = |v: &mut [T], at: usize, wk: &[f64; K], wc: &[f64; K]| {
        for j in 0..K {
            v[at + j] = T::from_parts(wk[j], wc[j]);
        }
    };
    for i in K..n {
        let e = v[i];
        let (k, c) = (e.key(), e.carried());
        if k < wk[0] {
            flush(v, i - K, &wk, &wc);
            sift_left(v, i);
            wk = std::array::from_fn(|j| v[i + 1 - K + j].key());
            wc = std::array::from_fn(|j| v[i + 1 - K + j].carried());
            continue;
        }
        // gt[j]: w[j] moves right of e (false...false true...true; gt[0] is false).
        let gt: [bool; K] = std::array::from_fn(|j| wk[j] > k);
        v[i - K] = T::from_parts(wk[0], wc[0]);
        let pick = |w: &[f64; K], e: f64| -> [f64; K] {
            std::array::from_fn(|j| {
                let next = if j + 1 < K {
                    if gt[j + 1] { e } else { w[j + 1] }
                } else {
                    e
                };
                if gt[j] { w[j] } else { next }
            })
        };
        wk = pick(&wk, k);
        wc = pick(&wc, c);
    }
    flush(v, n - K, &wk, &wc);
}

/// Move `v[i]` left to its place in the sorted `v[..i]`.
#[inline]
fn sift_left<T: Folded>(v: &mut [T], i: usize) {
    let e = v[i];
    let k = e.key();
    let mut j = i;
    while j > 0 && v[j - 1].key() > k {
        v[j] = v[j - 1];
        j -= 1;
    }
    v[j] = e;
}

/// Move `v[i]` right to its place in the sorted `v[i + 1..]`.
#[inline]
fn sift_right<T: Folded>(v: &mut [T], i: usize) {
    let e = v[i];
    let k = e.key();
    let mut j = i;
    while j + 1 < v.len() && v[j + 1].key() < k {
        v[j] = v[j + 1];
        j += 1;
    }
    v[j] = e;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sorted_ring(v: &[f64], period: f64) -> bool {
        v.windows(2).all(|w| w[0] <= w[1]) && v[v.len() - 1] <= v[0] + period
    }

    /// Uniform numbers in [0, 1) from a 64-bit LCG seeded with `state` (test data only).
    fn uniform(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The chunked fold equals a plain sort of the multiset, across chunk boundaries, with
    /// points displaced over several neighbours; walls reflect; the seam keeps the sum.
    #[test]
    fn fold_sorts_across_chunks_walls_and_the_seam() {
        let n = 3 * CHUNK + 17;
        let mut rnd = uniform(12345);
        // Walls [0, n]: points 1 apart displaced by up to +-3.
        let mut v: Vec<f64> = (0..n)
            .map(|i| i as f64 + 0.5 + 6.0 * (rnd() - 0.5))
            .collect();
        let mut want: Vec<f64> = v
            .iter()
            .map(|&k| {
                if (0.0..=n as f64).contains(&k) {
                    k
                } else {
                    reflect_into(k, 0.0, n as f64)
                }
            })
            .collect();
        want.sort_by(f64::total_cmp);
        fold(
            &mut v,
            Domain::Walls {
                lo: 0.0,
                hi: n as f64,
            },
        );
        assert_eq!(v, want);
        assert!(v[0] >= 0.0 && v[n - 1] <= n as f64);
        // Ring of period n: the end points cross the seam.
        let mut v: Vec<f64> = (0..n)
            .map(|i| i as f64 + 0.5 + 6.0 * (rnd() - 0.5))
            .collect();
        let sum: f64 = v.iter().sum();
        fold(&mut v, Domain::Ring { period: n as f64 });
        assert!(sorted_ring(&v, n as f64));
        let folded: f64 = v.iter().sum();
        assert!((folded - sum).abs() < 1e-9 * sum);
        // Carried values travel with their keys.
        let mut p: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let k = i as f64 + 6.0 * (rnd() - 0.5);
                [k, 2.0 * k]
            })
            .collect();
        fold(&mut p, Domain::Ring { period: n as f64 });
        let off = |e: &[f64; 2]| (e[1] - 2.0 * e[0]).abs();
        assert!(
            p.iter()
                .all(|e| off(e) < 1e-9 || (off(e) - n as f64).abs() < 1e-9)
        );
        assert!(p.windows(2).all(|w| w[0][0] <= w[1][0]));
    }

    /// The window insertion sort equals a stable sort, with rank displacements below and far
    /// above its window (the fallback), and on short slices.
    #[test]
    fn sort_near_is_a_stable_sort() {
        let mut rnd = uniform(7);
        for (n, spread) in [
            (1, 1.0),
            (5, 3.0),
            (8, 3.0),
            (9, 30.0),
            (1000, 3.0),
            (1000, 40.0),
        ] {
            // Keys on a coarse grid (ties), carried values number the elements.
            let mut v: Vec<[f64; 2]> = (0..n)
                .map(|i| [(i as f64 + spread * (rnd() - 0.5)).round(), i as f64])
                .collect();
            let mut want = v.clone();
            // A stable sort by `<` (-0 and 0 are equal keys).
            want.sort_by(|a, b| a[0].partial_cmp(&b[0]).expect("finite"));
            sort_near(&mut v);
            assert!(v == want, "n = {n}, spread = {spread}");
        }
    }

    #[test]
    fn reflect_into_folds_far_values() {
        assert_eq!(reflect_into(-0.25, 0.0, 1.0), 0.25);
        assert_eq!(reflect_into(1.25, 0.0, 1.0), 0.75);
        assert!((reflect_into(2.5, 0.0, 1.0) - 0.5).abs() < 1e-15);
        assert!((reflect_into(-1.75, 0.0, 1.0) - 0.25).abs() < 1e-15);
    }
}
