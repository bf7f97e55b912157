//! Counter-based random streams.
//!
//! A stream is keyed by (seed, step, purpose, index): the same key always gives the same
//! numbers, whatever thread draws them and in whatever order, which makes runs independent
//! of thread scheduling and restarts bitwise identical. The generator is HOOMD's SFC64
//! counter-based RNG (`hoomd-rand`), which discards 12 outputs after keying.
//!
//! Per-particle noise is drawn in blocks of [`BLOCK`] consecutive particles sharing one
//! keyed stream (key index = particle / BLOCK): keying costs ~12 generator steps, so a block
//! amortises it while keeping the result a pure function of (seed, step, particle).

use hoomd_rand::Counter;
use rand::{Rng, RngExt};
use rand_distr::StandardNormal;
use std::sync::LazyLock;

/// Number of consecutive particles that share one keyed stream.
pub const BLOCK: usize = 64;

/// What a stream is used for; different purposes never share numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum Purpose {
    /// Thermal noise of a dynamics step.
    Noise = 0,
    /// Initial configuration.
    Initial = 1,
    /// Monte Carlo moves and other method-specific draws.
    Moves = 2,
    /// Thermal noise drawn by [`fill_normal_wide`]: four lock-step lane streams per block.
    WideNoise = 3,
    /// The per-particle streams that finish a ziggurat rejection in [`fill_normal_wide`].
    WideNoiseTail = 4,
}

/// A keyed random stream: `seed` fixes the run, `step` the time step, `index` the particle
/// (or block, or any other counter the caller chooses).
pub fn stream(seed: u32, step: u64, purpose: Purpose, index: u64) -> impl Rng {
    Counter::new(step, purpose as u32, seed)
        .index(index)
        .make_rng()
}

/// Fill `out` with standard normal deviates for the particles of block `block` (particles
/// `block * BLOCK ..`, `out.len() <= BLOCK`) at `step`.
#[inline]
pub fn fill_normal_block(seed: u32, step: u64, block: u64, out: &mut [f64]) {
    debug_assert!(out.len() <= BLOCK);
    let mut rng = stream(seed, step, Purpose::Noise, block);
    for x in out.iter_mut() {
        *x = rng.sample(StandardNormal);
    }
}

/// Fill `out[i]` with the standard normal deviate of particle `i` at `step` (serial).
pub fn fill_normals(seed: u32, step: u64, out: &mut [f64]) {
    for (b, chunk) in out.chunks_mut(BLOCK).enumerate() {
        fill_normal_block(seed, step, b as u64, chunk);
    }
}

/// Layers of the ziggurat of [`Ziggurat`].
const LAYERS: usize = 1024;

/// Unnormalised standard normal density `f(x) = exp(-x^2/2)`.
#[inline]
fn gauss(x: f64) -> f64 {
    (-0.5 * x * x).exp()
}

/// `int_r^inf exp(-t^2/2) dt` for `r >= 2`, from the continued fraction of Mills' ratio
/// `exp(-r^2/2) / (r + 1/(r + 2/(r + 3/(r + ...))))`, evaluated bottom-up.
fn gauss_tail(r: f64) -> f64 {
    let mut d = r;
    for k in (1..=200).rev() {
        d = r + k as f64 / d;
    }
    gauss(r) / d
}

/// Tables of the Marsaglia–Tsang ziggurat for the standard normal distribution
/// (J. Stat. Softw. 5(8), 2000), computed at start-up.
///
/// [`LAYERS`] strips of equal area `v` cover `f(x) = exp(-x^2/2)` on `x >= 0`: strip 0 is the
/// rectangle `[0, r] x [0, f(r)]` plus the tail `x > r` (virtual width `x_0 = v / f(r)`), strip
/// `i >= 1` the rectangle `[0, x_i] x [f(x_i), f(x_{i+1})]` with `x_1 = r > x_2 > ... > x_1024 = 0`.
/// The base `r` is found by bisection so that the recursion
/// `x_{i+1} = f^{-1}(f(x_i) + v / x_i)` closes at `x_1024 = 0`. (1024 strips rather than the
/// usual 128 or 256: the fast path then fails for 0.43% of deviates instead of 1.2%, which
/// made the BCD noise about 20% cheaper; the 24 KiB of tables stay in L1/L2.)
pub struct Ziggurat {
    /// Per strip `i`: `[x_i, x_{i+1} / x_i]` (the width and the fraction of it that lies under
    /// the curve for every height in the strip).
    strips: [[f64; 2]; LAYERS],
    /// `f(x_i)`, with `f(x_1024) = 1`.
    fx: [f64; LAYERS + 1],
    r: f64,
}

static ZIGGURAT: LazyLock<Ziggurat> = LazyLock::new(Ziggurat::build);

impl Ziggurat {
    /// The shared tables (built on first use).
    #[inline]
    pub fn get() -> &'static Ziggurat {
        &ZIGGURAT
    }

    /// Widths `x_0..=x_1024` for base `r`, or `None` when the strips reach the mode early
    /// (`r` too small).
    fn widths(r: f64) -> (Option<[f64; LAYERS + 1]>, f64) {
        let v = r * gauss(r) + gauss_tail(r);
        let mut x = [0.0; LAYERS + 1];
        x[0] = v / gauss(r);
        x[1] = r;
        for i in 1..LAYERS {
            let y = gauss(x[i]) + v / x[i];
            if i < LAYERS - 1 && y >= 1.0 {
                return (None, 1.0);
            }
            // Residual of the closure condition at the top strip.
            if i == LAYERS - 1 {
                return (Some(x), y - 1.0);
            }
            x[i + 1] = (-2.0 * y.ln()).sqrt();
        }
        unreachable!()
    }

    fn build() -> Self {
        let (mut lo, mut hi) = (3.0f64, 4.5f64);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            match Self::widths(mid) {
                (Some(_), res) if res <= 0.0 => hi = mid,
                _ => lo = mid,
            }
            if hi - lo <= f64::EPSILON * hi {
                break;
            }
        }
        let r = hi;
        let (x, _) = Self::widths(r);
        let mut x = x.expect("ziggurat closes");
        x[LAYERS] = 0.0;
        let mut strips = [[0.0; 2]; LAYERS];
        let mut fx = [1.0; LAYERS + 1];
        for i in 0..LAYERS {
            strips[i] = [x[i], x[i + 1] / x[i]];
            fx[i] = if i == 0 { gauss(r) } else { gauss(x[i]) };
        }
        Self { strips, fx, r }
    }

    /// One standard normal deviate. The fast path (99.6% of calls) costs one 64-bit draw, a
    /// table load, a multiply and a compare: bits 0..10 pick the strip, bits 11..64 give a
    /// signed uniform `u` in [-1, 1), and `x = u x_i` is accepted when `|u| < x_{i+1} / x_i`.
    #[inline(always)]
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let bits = rng.next_u64();
        let i = (bits & (LAYERS as u64 - 1)) as usize;
        let u = ((bits as i64) >> 11) as f64 * (1.0 / (1u64 << 52) as f64);
        let [w, k] = self.strips[i];
        if u.abs() < k {
            return u * w;
        }
        self.sample_slow(rng, i, u)
    }

    /// The rare paths: the tail beyond `r` (strip 0) and the wedges above the curve. Inlined
    /// (but cold) so that the caller's generator state can stay in registers.
    #[cold]
    #[inline(always)]
    fn sample_slow<R: Rng + ?Sized>(&self, rng: &mut R, mut i: usize, mut u: f64) -> f64 {
        let unit = |rng: &mut R| ((rng.next_u64() >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64);
        loop {
            if i == 0 {
                // Marsaglia's tail method: r + a with density proportional to exp(-(r+a)^2/2).
                loop {
                    let a = -unit(rng).ln() / self.r;
                    let b = -unit(rng).ln();
                    if 2.0 * b > a * a {
                        return (self.r + a).copysign(u);
                    }
                }
            }
            let x = u * self.strips[i][0];
            let y = self.fx[i] + unit(rng) * (self.fx[i + 1] - self.fx[i]);
            if y < gauss(x) {
                return x;
            }
            let bits = rng.next_u64();
            i = (bits & (LAYERS as u64 - 1)) as usize;
            u = ((bits as i64) >> 11) as f64 * (1.0 / (1u64 << 52) as f64);
            if u.abs() < self.strips[i][1] {
                return u * self.strips[i][0];
            }
        }
    }
}

/// Fill `out` with standard normal deviates for the particles of block `block` (particles
/// `block * BLOCK ..`, `out.len() <= BLOCK`) at `step`, by the ziggurat of [`Ziggurat`] on the
/// same keyed stream as [`fill_normal_block`] (a different, equally valid, sequence of
/// deviates; inlined, about 4x cheaper).
#[inline]
pub fn fill_normal_block_fast(seed: u32, step: u64, block: u64, out: &mut [f64]) {
    debug_assert!(out.len() <= BLOCK);
    let zig = Ziggurat::get();
    let mut rng = stream(seed, step, Purpose::Noise, block);
    for x in out.iter_mut() {
        *x = zig.sample(&mut rng);
    }
}

/// Particles per wide noise block (see [`fill_normal_wide`]).
pub const WIDE: usize = 256;

/// Lock-step SFC64 lanes of [`fill_normal_wide`].
const LANES: usize = 4;

/// `N` keyed SFC64 streams advanced in lock-step, lane `l` being exactly
/// `stream(seed, step, purpose, first + l)` (hoomd-rand's SFC64: state
/// `[step, (purpose << 32) | seed, index]`, counter 0, 12 outputs discarded). The lanes are plain
/// `[u64; N]` arithmetic so that LLVM keeps them in vector registers.
#[derive(Clone)]
struct SfcLanes<const N: usize> {
    a: [u64; N],
    b: [u64; N],
    c: [u64; N],
    /// `c >> 40`, carried along so that `c.rotate_left(24)` is `(c << 24) + h` (see
    /// [`SfcLanes::step`]).
    h: [u64; N],
    /// The Weyl counter, equal in all lanes.
    counter: u64,
}

/// The four lanes of a block of [`fill_normal_wide`].
type Sfc64x4 = SfcLanes<LANES>;

impl<const N: usize> SfcLanes<N> {
    #[inline(always)]
    fn new(seed: u32, step: u64, purpose: Purpose, first: u64) -> Self {
        let key = (u64::from(purpose as u32) << 32) | u64::from(seed);
        let c: [u64; N] = std::array::from_fn(|l| first.wrapping_add(l as u64));
        let mut rng = Self {
            a: [step; N],
            b: [key; N],
            c,
            h: c.map(|c| c >> 40),
            counter: 0,
        };
        for _ in 0..12 {
            rng.next();
        }
        rng
    }

    /// Lanes `M * part ..M * (part + 1)` alone, in their current state.
    #[inline(always)]
    fn part<const M: usize>(&self, part: usize) -> SfcLanes<M> {
        let pick = |x: &[u64; N]| std::array::from_fn(|l| x[M * part + l]);
        SfcLanes {
            a: pick(&self.a),
            b: pick(&self.b),
            c: pick(&self.c),
            h: pick(&self.h),
            counter: self.counter,
        }
    }

    /// The next output of every lane.
    #[inline(always)]
    fn next(&mut self) -> [u64; N] {
        self.step::<{ cfg!(target_feature = "avx2") }>()
    }

    /// The next output of every lane, with `c.rotate_left(24)` computed as `(c << 24) + h` from
    /// the carried `h = c >> 40` (`CARRY`: LLVM keeps the lanes in AVX2 registers, where a plain
    /// rotate stays scalar) or as a scalar rotate (without AVX2 the lanes are scalar anyway).
    #[inline(always)]
    fn step<const CARRY: bool>(&mut self) -> [u64; N] {
        let mut out = [0u64; N];
        for l in 0..N {
            let (a, b, c) = (self.a[l], self.b[l], self.c[l]);
            out[l] = a.wrapping_add(b).wrapping_add(self.counter);
            self.a[l] = b ^ (b >> 11);
            self.b[l] = c.wrapping_add(c << 3);
            let c = if CARRY {
                (c << 24).wrapping_add(self.h[l]).wrapping_add(out[l])
            } else {
                c.rotate_left(24).wrapping_add(out[l])
            };
            self.c[l] = c;
            self.h[l] = c >> 40;
        }
        self.counter = self.counter.wrapping_add(1);
        out
    }
}

/// The fast-path uniform of [`fill_normal_wide`]: `u` in [-1, 1) on a 2^-51 grid from bits
/// 12..64, exactly (the bits become the mantissa of a number in [2, 4); no integer-to-float
/// conversion, which AVX2 lacks for 64-bit integers).
#[inline(always)]
fn wide_uniform(bits: u64) -> f64 {
    f64::from_bits((bits >> 12) | 0x4000_0000_0000_0000) - 3.0
}

impl Ziggurat {
    /// Finish the ziggurat for a fast-path rejection of [`fill_normal_wide`] (strip from bits
    /// 0..10, `u` from [`wide_uniform`]): the wedge or tail test with the same `u`, further
    /// uniforms from particle `p`'s own stream `stream(seed, step, WideNoiseTail, p)`.
    #[cold]
    #[inline(never)]
    fn wide_reject(&self, seed: u32, step: u64, p: u64, bits: u64) -> f64 {
        let mut rng = stream(seed, step, Purpose::WideNoiseTail, p);
        let i = (bits & (LAYERS as u64 - 1)) as usize;
        self.sample_slow(&mut rng, i, wide_uniform(bits))
    }
}

/// Fill `out[k]` with the standard normal deviate of particle `block * WIDE + k` at `step`
/// (`out.len() <= WIDE`), by the ziggurat of [`Ziggurat`] on four lock-step streams.
///
/// Particle `p = WIDE * b + k` takes draw `k / 4` of lane `l = k % 4`, the stream
/// `stream(seed, step, Purpose::WideNoise, 4 * b + l)`: each draw of the four lanes gives the
/// 64 bits of four consecutive particles, bits 0..10 picking the strip and bits 12..64 the
/// uniform `u` in [-1, 1) of [`wide_uniform`]. About 0.43% of particles fail the fast-path test
/// `|u| < x_{i+1} / x_i`; they continue the exact ziggurat (wedge, tail, retries) on their own
/// stream `stream(seed, step, Purpose::WideNoiseTail, p)`, which keeps the lanes in lock-step.
/// The result is a pure function of `(seed, step, p)`: a block may be filled whole or in
/// pieces (each piece a prefix of its block) and gives the same numbers.
///
/// Never inlined: the vectorisation of the lanes depends on LLVM's cost model, and a
/// stand-alone copy keeps the code measured in `examples/noise_bench.rs` whatever the caller
/// (the call costs nothing next to 256 deviates).
#[inline(never)]
pub fn fill_normal_wide(seed: u32, step: u64, block: u64, out: &mut [f64]) {
    let zig = Ziggurat::get();
    fill_wide_with::<FUSED>(seed, step, block, out, |p, bits| {
        zig.wide_reject(seed, step, p, bits)
    });
}

/// The fast path of [`fill_normal_wide`] for the four particles of one draw `r` of the lanes:
/// their values, and a mask with bit `l` set where particle `l` is rejected.
#[inline(always)]
fn wide_fast(zig: &Ziggurat, r: &[u64; LANES]) -> ([f64; LANES], u8) {
    let strips: [[f64; 2]; LANES] =
        std::array::from_fn(|l| zig.strips[(r[l] & (LAYERS as u64 - 1)) as usize]);
    let mut v = [0.0; LANES];
    let mut rejected = 0u8;
    for l in 0..LANES {
        let u = wide_uniform(r[l]);
        v[l] = u * strips[l][0];
        rejected |= u8::from(u.abs() >= strips[l][1]) << l;
    }
    (v, rejected)
}

/// Whether [`fill_normal_wide`] draws and transforms in one pass (best where the lanes live in
/// vector registers) or draws all bits first (fewer live registers for scalar code).
const FUSED: bool = cfg!(target_feature = "avx2");

/// [`fill_normal_wide`] with the fast-path rejections of particle `p` (64 bits `bits`) finished
/// by `reject(p, bits)` (the tests swap in broken variants).
#[inline(always)]
fn fill_wide_with<const FUSED_PASS: bool>(
    seed: u32,
    step: u64,
    block: u64,
    out: &mut [f64],
    mut reject: impl FnMut(u64, u64) -> f64,
) {
    assert!(
        out.len() <= WIDE,
        "fill_normal_wide: at most {WIDE} particles"
    );
    let zig = Ziggurat::get();
    let n = out.len();
    let mut rng = Sfc64x4::new(
        seed,
        step,
        Purpose::WideNoise,
        block.wrapping_mul(LANES as u64),
    );
    // One draw of the lanes gives the bits of four particles; the fast path for each,
    // branch-free, sets bit `l` of `rejected[d]` where particle `4 d + l` fails it (bits past
    // `n` stay 0).
    let mut bits = [0u64; WIDE];
    let mut rejected = [0u8; WIDE / LANES];
    let draws = n.div_ceil(LANES);
    if !FUSED_PASS {
        // Two lanes at a time, so that scalar code keeps the state in registers.
        for part in 0..LANES / 2 {
            let mut pair = rng.part::<2>(part);
            for b in bits[..draws * LANES].chunks_exact_mut(LANES) {
                b[2 * part..2 * part + 2].copy_from_slice(&pair.next());
            }
        }
    }
    let whole = n / LANES;
    let (head, tail) = out.split_at_mut(whole * LANES);
    for ((o, b), r) in head
        .chunks_exact_mut(LANES)
        .zip(bits.chunks_exact_mut(LANES))
        .zip(&mut rejected)
    {
        let b: &mut [u64; LANES] = b.try_into().expect("4 lanes");
        if FUSED_PASS {
            *b = rng.next();
        }
        let (v, rr) = wide_fast(zig, b);
        o.copy_from_slice(&v);
        *r = rr;
    }
    if !tail.is_empty() {
        let b: &mut [u64; LANES] = (&mut bits[whole * LANES..draws * LANES])
            .try_into()
            .expect("4 lanes");
        if FUSED_PASS {
            *b = rng.next();
        }
        let (v, rr) = wide_fast(zig, b);
        tail.copy_from_slice(&v[..tail.len()]);
        rejected[whole] = rr & ((1 << tail.len()) - 1);
    }
    // The rare rejections, found eight draws (32 particles) at a time: bit `t` of word `j`
    // is particle `4 (8 j + t / 8) + t % 8`.
    let first = block.wrapping_mul(WIDE as u64);
    for (j, flags) in rejected
        .chunks_exact(8)
        .take(n.div_ceil(8 * LANES))
        .enumerate()
    {
        let mut m = u64::from_le_bytes(flags.try_into().expect("8 draws"));
        while m != 0 {
            let t = m.trailing_zeros() as usize;
            let k = LANES * (8 * j + t / 8) + t % 8;
            m &= m - 1;
            out[k] = reject(first.wrapping_add(k as u64), bits[k]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_key_same_numbers_and_different_keys_differ() {
        let mut a = vec![0.0; 200];
        let mut b = vec![0.0; 200];
        fill_normals(7, 3, &mut a);
        fill_normals(7, 3, &mut b);
        assert_eq!(a, b);
        fill_normals(7, 4, &mut b);
        assert_ne!(a, b);
        fill_normals(8, 3, &mut b);
        assert_ne!(a, b);
        // A block drawn alone equals the same block inside the full fill.
        let mut blk = vec![0.0; BLOCK];
        fill_normal_block(7, 3, 1, &mut blk);
        assert_eq!(&a[BLOCK..2 * BLOCK], &blk[..]);
    }

    #[test]
    fn moments_are_standard_normal() {
        let n = 200_000;
        let mut x = vec![0.0; n];
        fill_normals(1, 0, &mut x);
        let mean = x.iter().sum::<f64>() / n as f64;
        let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
        // Standard errors: 1/sqrt(n) ~ 0.0022 for the mean, sqrt(2/n) ~ 0.0032 for the variance.
        assert!(mean.abs() < 5.0 * (1.0 / n as f64).sqrt(), "mean {mean}");
        assert!(
            (var - 1.0).abs() < 5.0 * (2.0 / n as f64).sqrt(),
            "var {var}"
        );
    }
    /// Exact standard normal CDF: Taylor series of the integral below |x| = 3, Mills' ratio
    /// continued fraction above.
    fn normal_cdf(x: f64) -> f64 {
        let a = x.abs();
        let upper = if a > 3.0 {
            gauss_tail(a) / (2.0 * std::f64::consts::PI).sqrt()
        } else {
            // int_0^a exp(-t^2/2) dt = sum_n (-1)^n a^(2n+1) / (2^n n! (2n+1))
            let (mut term, mut sum) = (a, 0.0);
            for n in 0..200 {
                sum += term / (2 * n + 1) as f64;
                term *= -a * a / (2.0 * (n + 1) as f64);
            }
            0.5 - sum / (2.0 * std::f64::consts::PI).sqrt()
        };
        if x >= 0.0 { 1.0 - upper } else { upper }
    }

    fn ks_statistic(mut x: Vec<f64>) -> f64 {
        x.sort_by(f64::total_cmp);
        let n = x.len() as f64;
        x.iter()
            .enumerate()
            .map(|(i, &v)| {
                let c = normal_cdf(v);
                (c - i as f64 / n).abs().max((c - (i + 1) as f64 / n).abs())
            })
            .fold(0.0, f64::max)
    }

    fn fast_normals(n: usize, seed: u32) -> Vec<f64> {
        let mut x = vec![0.0; n];
        for (b, chunk) in x.chunks_mut(BLOCK).enumerate() {
            fill_normal_block_fast(seed, 5, b as u64, chunk);
        }
        x
    }

    #[test]
    fn ziggurat_tables_close() {
        let z = Ziggurat::get();
        // Every strip has the same area v (Marsaglia & Tsang's construction; for 256 strips it
        // gives their r = 3.6541528853610088, for our 1024 strips r = 4.03885).
        let v = z.r * gauss(z.r) + gauss_tail(z.r);
        assert!((z.strips[0][0] * z.fx[0] - v).abs() < 1e-15 * v, "strip 0");
        for i in 1..LAYERS {
            let area = z.strips[i][0] * (z.fx[i + 1] - z.fx[i]);
            assert!((area - v).abs() < 1e-9 * v, "strip {i}: area {area} vs {v}");
        }
        assert!((z.r - 4.038_849_846_109_5).abs() < 1e-9, "r = {}", z.r);
        assert!(z.strips[LAYERS - 1][1] == 0.0 && z.fx[LAYERS] == 1.0);
        assert!((normal_cdf(1.0) - 0.841_344_746_068_542_9).abs() < 1e-13);
        assert!((normal_cdf(-4.0) - 3.167_124_183_311_992e-5).abs() < 1e-17);
    }

    /// All checks of a standard normal sample: moments 1–4, tail counts (including the
    /// strip-0 tail beyond r = 4.04), tail symmetry, a chi-square test on 0.25-wide bins over
    /// [-5, 5] and the Kolmogorov–Smirnov distance to the exact CDF, each at about 5 standard
    /// errors (or the 1e-4 level).
    fn check_standard_normal(x: Vec<f64>) -> Result<(), String> {
        let nf = x.len() as f64;
        let m = |k: i32| x.iter().map(|v| v.powi(k)).sum::<f64>() / nf;
        // Standard errors sqrt(Var x^k / n) with Var x^k = 1, 2, 15, 96.
        for (k, exact, sd) in [
            (1, 0.0, 1.0),
            (2, 1.0, 2f64.sqrt()),
            (3, 0.0, 15f64.sqrt()),
            (4, 3.0, 96f64.sqrt()),
        ] {
            let got = m(k);
            if (got - exact).abs() > 5.0 * sd / nf.sqrt() {
                return Err(format!("moment {k}: {got}"));
            }
        }
        let r = Ziggurat::get().r;
        for t in [2.0, 3.0, r, 4.5] {
            let expect = 2.0 * normal_cdf(-t) * nf;
            let got = x.iter().filter(|v| v.abs() > t).count() as f64;
            if (got - expect).abs() > 5.0 * expect.sqrt() + 2.0 {
                return Err(format!("|x| > {t}: {got} vs {expect}"));
            }
        }
        let pos = x.iter().filter(|&&v| v > r).count() as f64;
        let neg = x.iter().filter(|&&v| v < -r).count() as f64;
        if (pos - neg).abs() > 5.0 * (pos + neg).sqrt() {
            return Err(format!("tail asymmetry {pos} vs {neg}"));
        }
        // 40 bins of width 0.25 on [-5, 5] plus the two outer ones: 41 degrees of freedom,
        // chi2 > 41 + 6 sqrt(82) has p below 1e-4.
        let mut counts = [0.0f64; 42];
        for &v in &x {
            let b = ((v + 5.0) / 0.25).floor() + 1.0;
            counts[b.clamp(0.0, 41.0) as usize] += 1.0;
        }
        let edge = |b: usize| -5.0 + 0.25 * b as f64;
        let chi2: f64 = (0..42)
            .map(|b| {
                let lo = if b == 0 { 0.0 } else { normal_cdf(edge(b - 1)) };
                let hi = if b == 41 { 1.0 } else { normal_cdf(edge(b)) };
                let e = (hi - lo) * nf;
                (counts[b] - e).powi(2) / e
            })
            .sum();
        if chi2 > 41.0 + 6.0 * 82f64.sqrt() {
            return Err(format!("chi2 {chi2} for 41 degrees of freedom"));
        }
        // Kolmogorov–Smirnov: 2/sqrt(n) is about the 0.07% critical value.
        let d = ks_statistic(x);
        if d > 2.0 / nf.sqrt() {
            return Err(format!("KS distance {d}"));
        }
        Ok(())
    }

    #[test]
    fn fast_normals_are_keyed_and_standard_normal() {
        let n = 1 << 21;
        let x = fast_normals(n, 11);
        assert_eq!(x, fast_normals(n, 11));
        let mut blk = vec![0.0; BLOCK];
        fill_normal_block_fast(11, 5, 3, &mut blk);
        assert_eq!(&x[3 * BLOCK..4 * BLOCK], &blk[..]);
        check_standard_normal(x).unwrap();
        check_standard_normal(fast_normals(n, 12)).unwrap();
        // The checks accept the reference sampler too.
        let mut reference = vec![0.0; n];
        fill_normals(11, 5, &mut reference);
        check_standard_normal(reference).unwrap();
    }

    #[test]
    fn normality_checks_reject_broken_ziggurats() {
        let z = Ziggurat::get();
        let n = 1 << 21;
        let mut rng = stream(3, 0, Purpose::Noise, 0);
        let strip = |rng: &mut dyn Rng| {
            let bits = rng.next_u64();
            let i = (bits & 255) as usize;
            let u = ((bits as i64) >> 11) as f64 * (1.0 / (1u64 << 52) as f64);
            (i, u)
        };
        // Fast path only (wedges and tail dropped, retried).
        let no_wedges: Vec<f64> = (0..n)
            .map(|_| {
                loop {
                    let (i, u) = strip(&mut rng);
                    if u.abs() < z.strips[i][1] {
                        break u * z.strips[i][0];
                    }
                }
            })
            .collect();
        let e = check_standard_normal(no_wedges).unwrap_err();
        // Tail replaced by an exponential of the wrong scale (rate 1 instead of r).
        let bad_tail: Vec<f64> = (0..n)
            .map(|_| {
                let (i, u) = strip(&mut rng);
                if i == 0 && u.abs() >= z.strips[0][1] {
                    let a = -(((rng.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64).ln();
                    (z.r + a).copysign(u)
                } else {
                    z.sample(&mut rng)
                }
            })
            .collect();
        let e2 = check_standard_normal(bad_tail).unwrap_err();
        eprintln!("rejected: {e}; {e2}");
        // Nor may the fast sampler coincide with the reference one.
        let mut a = vec![0.0; BLOCK];
        let mut b = vec![0.0; BLOCK];
        fill_normal_block(3, 0, 0, &mut a);
        fill_normal_block_fast(3, 0, 0, &mut b);
        assert_ne!(a, b);
    }

    /// Raw draws `0..draws` of the four lanes of wide block `block`, by both forms of the
    /// rotate.
    fn wide_lane_draws(seed: u32, step: u64, block: u64, draws: usize) -> Vec<[u64; LANES]> {
        let mut rng = Sfc64x4::new(seed, step, Purpose::WideNoise, block.wrapping_mul(4));
        let mut carry = rng.clone();
        let mut plain = rng.clone();
        (0..draws)
            .map(|_| {
                let (a, b, c) = (rng.next(), carry.step::<true>(), plain.step::<false>());
                assert!(a == b && b == c, "the rotate forms differ");
                a
            })
            .collect()
    }

    #[test]
    fn wide_lanes_are_the_scalar_streams() {
        for (seed, step, block) in [
            (0, 0, 0),
            (7, 3, 1),
            (u32::MAX, u64::MAX, 12345),
            (9, 1 << 40, 1 << 61),
        ] {
            let lanes = wide_lane_draws(seed, step, block, 100);
            for l in 0..LANES {
                let mut rng = stream(seed, step, Purpose::WideNoise, 4 * block + l as u64);
                for (d, draw) in lanes.iter().enumerate() {
                    assert_eq!(
                        draw[l],
                        rng.next_u64(),
                        "seed {seed} step {step} block {block} lane {l} draw {d}"
                    );
                }
            }
        }
    }

    /// Particle `p`'s wide deviate recomputed alone, straight from the definition.
    fn wide_reference(seed: u32, step: u64, p: u64) -> (f64, bool) {
        let (b, k) = (p / WIDE as u64, p % WIDE as u64);
        let mut rng = stream(seed, step, Purpose::WideNoise, 4 * b + k % 4);
        for _ in 0..k / 4 {
            rng.next_u64();
        }
        let bits = rng.next_u64();
        let i = (bits & 1023) as usize;
        let u = (bits >> 12) as f64 / (1u64 << 51) as f64 - 1.0;
        let z = Ziggurat::get();
        if u.abs() < z.strips[i][1] {
            (u * z.strips[i][0], false)
        } else {
            let mut tail = stream(seed, step, Purpose::WideNoiseTail, p);
            (z.sample_slow(&mut tail, i, u), true)
        }
    }

    #[test]
    fn wide_blocks_are_pure_functions_of_the_particle() {
        let (seed, step) = (21, 1_000_003);
        let (mut slow, mut tail) = (0, 0);
        let blocks: Vec<u64> = (0..400).chain([1 << 20, (1 << 56) - 1]).collect();
        for &block in &blocks {
            let mut whole = [0.0; WIDE];
            fill_normal_wide(seed, step, block, &mut whole);
            for (k, &v) in whole.iter().enumerate() {
                let p = block * WIDE as u64 + k as u64;
                let (r, rejected) = wide_reference(seed, step, p);
                assert_eq!(v.to_bits(), r.to_bits(), "block {block} particle {k}");
                slow += rejected as usize;
                tail += (rejected && v.abs() > Ziggurat::get().r) as usize;
            }
            // Partial fills are prefixes of the block, in both loop shapes.
            for m in [0, 1, 3, 4, 5, 63, 128, 255, 256] {
                for fused in [false, true] {
                    let mut part = vec![f64::NAN; m];
                    let reject = |p, bits| Ziggurat::get().wide_reject(seed, step, p, bits);
                    if fused {
                        fill_wide_with::<true>(seed, step, block, &mut part, reject);
                    } else {
                        fill_wide_with::<false>(seed, step, block, &mut part, reject);
                    }
                    assert!(
                        part.iter()
                            .zip(&whole)
                            .all(|(a, b)| a.to_bits() == b.to_bits()),
                        "block {block} prefix {m}, fused {fused}"
                    );
                }
                let mut part = vec![f64::NAN; m];
                fill_normal_wide(seed, step, block, &mut part);
                assert!(
                    part.iter()
                        .zip(&whole)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "block {block} prefix {m}"
                );
            }
        }
        // Both rare paths were exercised, as often as the tables say: a particle fails the
        // fast path with probability mean_i (1 - x_{i+1}/x_i) (about 0.3%), and goes to the tail
        // when that happens in strip 0.
        let z = Ziggurat::get();
        let n = (blocks.len() * WIDE) as f64;
        let p_slow = z.strips.iter().map(|s| 1.0 - s[1]).sum::<f64>() / LAYERS as f64;
        let (e_slow, e_tail) = (n * p_slow, n * (1.0 - z.strips[0][1]) / LAYERS as f64);
        eprintln!("{slow} rejections ({e_slow:.1} expected), {tail} tails ({e_tail:.1})");
        assert!(
            (slow as f64 - e_slow).abs() < 5.0 * e_slow.sqrt(),
            "{slow} vs {e_slow}"
        );
        assert!(tail > 0 && (tail as f64 - e_tail).abs() < 5.0 * e_tail.sqrt() + 2.0);
        // Keys matter.
        let (mut a, mut b) = ([0.0; WIDE], [0.0; WIDE]);
        fill_normal_wide(seed, step, 3, &mut a);
        fill_normal_wide(seed, step + 1, 3, &mut b);
        assert_ne!(a, b);
        fill_normal_wide(seed + 1, step, 3, &mut b);
        assert_ne!(a, b);
        fill_normal_wide(seed, step, 4, &mut b);
        assert_ne!(a, b);
    }

    fn wide_normals(n: usize, seed: u32, reject: &mut dyn FnMut(u64, u64) -> f64) -> Vec<f64> {
        let mut x = vec![0.0; n];
        for (b, chunk) in x.chunks_mut(WIDE).enumerate() {
            fill_wide_with::<FUSED>(seed, 5, b as u64, chunk, &mut *reject);
        }
        x
    }

    #[test]
    fn wide_normals_are_standard_normal() {
        let z = Ziggurat::get();
        let n = 1 << 20;
        for seed in [11, 12] {
            let exact = wide_normals(n, seed, &mut |p, bits| z.wide_reject(seed, 5, p, bits));
            let mut public = vec![0.0; n];
            for (b, chunk) in public.chunks_mut(WIDE).enumerate() {
                fill_normal_wide(seed, 5, b as u64, chunk);
            }
            assert_eq!(exact, public);
            check_standard_normal(exact).unwrap();
        }
    }

    #[test]
    fn normality_checks_reject_broken_wide_ziggurats() {
        let z = Ziggurat::get();
        let n = 1 << 20;
        let seed = 11;
        // Fast path only: a rejection retries the fast path on the particle's tail stream.
        let no_wedges = wide_normals(n, seed, &mut |p, _| {
            let mut rng = stream(seed, 5, Purpose::WideNoiseTail, p);
            loop {
                let bits = rng.next_u64();
                let (i, u) = ((bits & 255) as usize, wide_uniform(bits));
                if u.abs() < z.strips[i][1] {
                    break u * z.strips[i][0];
                }
            }
        });
        let e = check_standard_normal(no_wedges).unwrap_err();
        // Rejections kept as fast-path values (no slow path at all).
        let no_slow = wide_normals(n, seed, &mut |_, bits| {
            wide_uniform(bits) * z.strips[(bits & 255) as usize][0]
        });
        let e2 = check_standard_normal(no_slow).unwrap_err();
        eprintln!("rejected: {e}; {e2}");
    }
}
