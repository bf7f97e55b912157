//! Branch-free pooling of adjacent violators, one rod at a time (the inner loop of
//! [`crate::ring`]).
//!
//! A stream pools the free end-of-step positions `z` of consecutive rods into blocks
//! `[sum of z, rods]` (pool adjacent violators, ties pool). It keeps the open block `o` and the
//! block `b` below it in registers and the blocks below `b` on a stack. Each rod costs exactly
//! two decisions, both taken without a branch (a mispredicted cascade cost more than all the
//! arithmetic of a rod), and both from the state before the rod, so that they run side by
//! side:
//!
//! 1. join: the rod joins `o` when `mean(o) >= z`; otherwise `b` goes onto the stack, `o`
//!    becomes `b` and the rod opens a new `o`;
//! 2. premerge (only after a join): `o + rod` pools with `b` when `mean(b) >= mean(o + rod)`
//!    (fast-bcd Eq. 20, two clusters that meet within the step), and the stack's top becomes
//!    the new `b`.
//!
//! A deeper cascade (the pooled block still violating the one below, about 1% of rods in the
//! benchmark) is left for later: pooling adjacent violators in any order ends in the same
//! partition, so every block of a stream then passes through [`append`], which pools what is
//! left (rarely anything, so its branch predicts well).
//!
//! A chunk runs [`LANES`] streams over consecutive parts of its rods. With AVX2 (what
//! `target-cpu=native` enables on any x86-64 CPU of the last decade) the streams are the four
//! lanes of 256-bit registers, one instruction serving all four; elsewhere they run as
//! interleaved scalar streams ([`portable::Stream`]). Both do the same arithmetic in the same
//! order and give the same bits (tested).

/// A block of rods: `[sum of z, rods]` while pooling (the count is an integer-valued float);
/// the ring step then stores the block's end-of-step position in place of the sum.
pub(crate) type Block = [f64; 2];

/// Zeroed stacks for the [`LANES`] streams of a chunk.
pub(crate) fn new_stacks() -> Box<[[Block; STACK]]> {
    vec![[[0.0; 2]; STACK]; LANES].into_boxed_slice()
}

/// Capacity of one stream's stack: a power of two, so that a masked index needs no bounds
/// check. A stream of `m` rods needs `m + 3` entries.
pub(crate) const STACK: usize = 2048;

/// Interleaved pooling streams per chunk of [`crate::ring`].
pub(crate) const LANES: usize = 4;

/// The bottom of every stack: a block that never pools (its sum is NaN, so every comparison
/// with it is false) and holds no rods.
const SENTINEL: Block = [f64::NAN, 0.0];

/// One pooling stream in scalar code: the fallback without AVX2, the rods left over after
/// the four-lane kernel, and the reference that kernel is tested against.
pub(crate) mod portable {
    use super::{Block, STACK};

    /// A pooling stream: open block `o`, the block `b` below it, and the stack's top.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub(crate) struct Stream {
        pub o: Block,
        pub b: Block,
        pub top: usize,
    }

    impl Stream {
        /// A stream whose first rod is at `z`, over the stack `st` (its entry 0 is set to the
        /// sentinel).
        #[inline(always)]
        pub(crate) fn start(st: &mut [Block; STACK], z: f64) -> Self {
            st[0] = super::SENTINEL;
            Self {
                o: [z, 1.0],
                b: super::SENTINEL,
                top: 0,
            }
        }

        /// Pool the next rod, at `z` (module docs: join, then premerge).
        #[inline(always)]
        pub(crate) fn push(&mut self, st: &mut [Block; STACK], z: f64) {
            let join = self.o[0] >= self.o[1] * z;
            let joined = [z + self.o[0], 1.0 + self.o[1]];
            let pool = join && self.b[0] * joined[1] >= self.b[1] * joined[0];
            let pooled = [joined[0] + self.b[0], joined[1] + self.b[1]];
            let below = st[self.top & (STACK - 1)];
            st[(self.top + 1) & (STACK - 1)] = self.b;
            (self.o, self.b) = match (join, pool) {
                (false, _) => ([z, 1.0], self.o),
                (true, false) => (joined, self.b),
                (true, true) => (pooled, below),
            };
            self.top = self.top + 1 - usize::from(join) - usize::from(pool);
        }

        /// The stream's blocks in order (the stack from entry 1, then `b` and `o`), sentinels
        /// included; `st` must be the stream's stack.
        #[inline]
        pub(crate) fn blocks<'a>(&self, st: &'a mut [Block; STACK]) -> &'a [Block] {
            st[(self.top + 1) & (STACK - 1)] = self.b;
            st[(self.top + 2) & (STACK - 1)] = self.o;
            &st[1..self.top + 3]
        }
    }
}

/// Four streams as the lanes of 256-bit registers.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
mod lanes {
    use super::{Block, STACK, portable};
    use safe_arch::{
        add_i64_m256i, add_m256d, bitand_m256d, blend_varying_m256d, cast_to_m128d_from_m256d,
        cast_to_m256i_from_m256d, cmp_op_mask_m256d, extract_m128d_from_m256d, m128d, m256d, m256i,
        mul_m256d, permute2z_m256d, set_m128d_m256d, set_splat_m256d, unpack_hi_m256d,
        unpack_lo_m256d,
    };

    /// `_CMP_GE_OQ`: `a >= b`, false when either is NaN.
    const GE: i32 = 0x1d;

    /// Four streams: open blocks `o = [os, oc]`, blocks below `b = [bs, bc]` (sums and rods,
    /// one stream per lane) and the stacks' tops.
    pub(crate) struct Streams {
        os: m256d,
        oc: m256d,
        bs: m256d,
        bc: m256d,
        top: m256i,
    }

    impl Streams {
        /// Streams whose first rods are at `z` (one per lane), over `st[..4]`.
        #[inline(always)]
        pub(crate) fn start(st: &mut [[Block; STACK]], z: m256d) -> Self {
            for s in &mut st[..4] {
                s[0] = super::SENTINEL;
            }
            Self {
                os: z,
                oc: set_splat_m256d(1.0),
                bs: set_splat_m256d(super::SENTINEL[0]),
                bc: set_splat_m256d(super::SENTINEL[1]),
                top: m256i::from([0i64; 4]),
            }
        }

        /// Pool the next rod of each stream, at `z` (lane by lane what
        /// [`portable::Stream::push`] does).
        #[inline(always)]
        pub(crate) fn push(&mut self, st: &mut [[Block; STACK]], z: m256d) {
            let one = set_splat_m256d(1.0);
            let join = cmp_op_mask_m256d::<GE>(self.os, mul_m256d(self.oc, z));
            let (js, jc) = (add_m256d(z, self.os), add_m256d(one, self.oc));
            let premerge = cmp_op_mask_m256d::<GE>(mul_m256d(self.bs, jc), mul_m256d(self.bc, js));
            let pool = bitand_m256d(join, premerge);
            let (ps, pc) = (add_m256d(js, self.bs), add_m256d(jc, self.bc));
            // Each lane's stack: read the top, push b above it.
            let t: [i64; 4] = self.top.into();
            let t: [usize; 4] = std::array::from_fn(|j| t[j] as usize & (STACK - 1));
            let (lo, hi) = (
                set_m128d_m256d(m128d::from(st[2][t[2]]), m128d::from(st[0][t[0]])),
                set_m128d_m256d(m128d::from(st[3][t[3]]), m128d::from(st[1][t[1]])),
            );
            let (ls, lc) = (unpack_lo_m256d(lo, hi), unpack_hi_m256d(lo, hi));
            let (lo, hi) = (
                unpack_lo_m256d(self.bs, self.bc),
                unpack_hi_m256d(self.bs, self.bc),
            );
            st[0][(t[0] + 1) & (STACK - 1)] = cast_to_m128d_from_m256d(lo).into();
            st[1][(t[1] + 1) & (STACK - 1)] = cast_to_m128d_from_m256d(hi).into();
            st[2][(t[2] + 1) & (STACK - 1)] = extract_m128d_from_m256d::<1>(lo).into();
            st[3][(t[3] + 1) & (STACK - 1)] = extract_m128d_from_m256d::<1>(hi).into();
            // No join: o becomes b, the rod opens o. Join: o + rod, pooled with b if it meets
            // b (then b comes off the stack).
            let os = blend_varying_m256d(z, blend_varying_m256d(js, ps, pool), join);
            let oc = blend_varying_m256d(one, blend_varying_m256d(jc, pc, pool), join);
            self.bs = blend_varying_m256d(self.os, blend_varying_m256d(self.bs, ls, pool), join);
            self.bc = blend_varying_m256d(self.oc, blend_varying_m256d(self.bc, lc, pool), join);
            (self.os, self.oc) = (os, oc);
            // top + 1 - join - pool (masks are -1 where set).
            let down = add_i64_m256i(
                cast_to_m256i_from_m256d(join),
                cast_to_m256i_from_m256d(pool),
            );
            self.top = add_i64_m256i(add_i64_m256i(self.top, m256i::from([1i64; 4])), down);
        }

        /// Stream `j` as a scalar stream.
        pub(crate) fn lane(&self, j: usize) -> portable::Stream {
            let (os, oc) = (self.os.to_array(), self.oc.to_array());
            let (bs, bc) = (self.bs.to_array(), self.bc.to_array());
            let top: [i64; 4] = self.top.into();
            portable::Stream {
                o: [os[j], oc[j]],
                b: [bs[j], bc[j]],
                top: top[j] as usize,
            }
        }
    }

    /// Rods `k..k + 4` of the four streams `zq`, as four vectors of one rod per stream.
    #[inline(always)]
    pub(crate) fn transposed(zq: &[&[f64]; 4], k: usize) -> [m256d; 4] {
        let r: [m256d; 4] = std::array::from_fn(|j| {
            let v: [f64; 4] = zq[j][k..k + 4].try_into().expect("four rods");
            m256d::from(v)
        });
        let (t0, t1) = (unpack_lo_m256d(r[0], r[1]), unpack_hi_m256d(r[0], r[1]));
        let (t2, t3) = (unpack_lo_m256d(r[2], r[3]), unpack_hi_m256d(r[2], r[3]));
        [
            permute2z_m256d::<0x20>(t0, t2),
            permute2z_m256d::<0x20>(t1, t3),
            permute2z_m256d::<0x31>(t0, t2),
            permute2z_m256d::<0x31>(t1, t3),
        ]
    }

    /// Pool the first `q` rods of each stream `zq`; the streams come back as scalar streams.
    pub(crate) fn pool(
        st: &mut [[Block; STACK]],
        zq: &[&[f64]; 4],
        q: usize,
    ) -> [portable::Stream; 4] {
        let at = |k: usize| m256d::from([zq[0][k], zq[1][k], zq[2][k], zq[3][k]]);
        let mut s = Streams::start(st, at(0));
        let mut k = 1;
        while k + 4 <= q {
            for zk in transposed(zq, k) {
                s.push(st, zk);
            }
            k += 4;
        }
        for k in k..q {
            s.push(st, at(k));
        }
        std::array::from_fn(|j| s.lane(j))
    }
}

use portable::Stream;

/// Pool `z` into `pool` (its first `n` blocks, `n` returned): [`LANES`] streams over
/// consecutive parts (the last one takes the rods left over), then every block of the streams
/// through [`append`], which pools across the streams' joins and whatever the streams left.
/// `stacks` holds at least [`LANES`] stacks, each with room for `z.len() / LANES + LANES + 3`
/// entries, and `pool` room for `z.len()` blocks.
pub(crate) fn pool_chunk(stacks: &mut [[Block; STACK]], z: &[f64], pool: &mut [Block]) -> usize {
    let mut n = 0;
    let q = z.len() / LANES;
    if q == 0 {
        if let Some((&z0, rest)) = z.split_first() {
            let mut s = Stream::start(&mut stacks[0], z0);
            for &zk in rest {
                s.push(&mut stacks[0], zk);
            }
            finish(&s, &mut stacks[0], pool, &mut n);
        }
        return n;
    }
    let zq: [&[f64]; LANES] = std::array::from_fn(|j| &z[j * q..(j + 1) * q]);
    let mut streams = pool_streams(stacks, &zq, q);
    for &zk in &z[LANES * q..] {
        streams[LANES - 1].push(&mut stacks[LANES - 1], zk);
    }
    for (st, s) in stacks.iter_mut().zip(&streams) {
        finish(s, st, pool, &mut n);
    }
    n
}

/// The [`LANES`] streams over the `q >= 1` rods each of `zq`.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline]
fn pool_streams(stacks: &mut [[Block; STACK]], zq: &[&[f64]; LANES], q: usize) -> [Stream; LANES] {
    lanes::pool(stacks, zq, q)
}

/// The [`LANES`] streams over the `q >= 1` rods each of `zq`, interleaved rod by rod
/// (independent dependency chains that the out-of-order core runs side by side).
#[cfg_attr(all(target_arch = "x86_64", target_feature = "avx2"), allow(dead_code))]
fn pool_streams_scalar(
    stacks: &mut [[Block; STACK]],
    zq: &[&[f64]; LANES],
    q: usize,
) -> [Stream; LANES] {
    let mut streams: [Stream; LANES] =
        std::array::from_fn(|j| Stream::start(&mut stacks[j], zq[j][0]));
    for k in 1..q {
        for j in 0..LANES {
            streams[j].push(&mut stacks[j], zq[j][k]);
        }
    }
    streams
}

#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
#[inline]
fn pool_streams(stacks: &mut [[Block; STACK]], zq: &[&[f64]; LANES], q: usize) -> [Stream; LANES] {
    pool_streams_scalar(stacks, zq, q)
}

/// Append a stream's blocks (sentinels dropped) to `pool[..n]` with [`append`].
#[inline]
fn finish(s: &Stream, st: &mut [Block; STACK], pool: &mut [Block], n: &mut usize) {
    let blocks = s.blocks(st);
    let live = blocks
        .iter()
        .position(|b| b[1] != 0.0)
        .unwrap_or(blocks.len());
    *n = append(pool, *n, &blocks[live..]);
}

/// Append `blocks` to `pool[..n]` one by one, pooling each with the blocks before it for as
/// long as they violate (`mean(left) >= mean(right)`); returns the new number of blocks. The
/// last block stays in registers, so the common case (a block that does not pool) costs one
/// comparison and one store.
#[inline]
fn append(pool: &mut [Block], mut n: usize, blocks: &[Block]) -> usize {
    let Some((&first, rest)) = blocks.split_first() else {
        return n;
    };
    // `last` has been compared with its left neighbour `pool[n - 1]` as it stands, unless
    // `recheck`: `last` grew since, or its left neighbour did.
    let (mut last, mut recheck) = (first, true);
    for &b in rest {
        if violates(&last, &b) {
            last = [last[0] + b[0], last[1] + b[1]];
            recheck = true;
        } else {
            if recheck {
                let before = n;
                n = settle(pool, n, last);
                // `b` was compared with `last`; if that pooled to its left, compare again.
                recheck = n <= before;
            } else {
                pool[n] = last;
                n += 1;
            }
            last = b;
        }
    }
    settle(pool, n, last)
}

/// `mean(a) >= mean(b)` for blocks `[sum, rods]`.
#[inline(always)]
fn violates(a: &Block, b: &Block) -> bool {
    a[0] * b[1] >= b[0] * a[1]
}

/// Pool `last` (complete on its right) into `pool[..n]`'s blocks for as long as they violate,
/// then store it; returns the new number of blocks.
#[inline(always)]
fn settle(pool: &mut [Block], mut n: usize, mut last: Block) -> usize {
    while n > 0 && violates(&pool[n - 1], &last) {
        let top = pool[n - 1];
        last = [top[0] + last[0], top[1] + last[1]];
        n -= 1;
    }
    pool[n] = last;
    n + 1
}

/// The pooling of one chunk, for `examples/pool_bench.rs` (not a stable API).
#[doc(hidden)]
pub struct PoolBench {
    stacks: Box<[[Block; STACK]]>,
    pool: Vec<Block>,
}

impl Default for PoolBench {
    fn default() -> Self {
        Self {
            stacks: new_stacks(),
            pool: vec![[0.0; 2]; LANES * (STACK - 8)],
        }
    }
}

impl PoolBench {
    /// Pool `z` (at most `4 (STACK - 8)` rods) as a chunk of the ring step does; returns the
    /// blocks `[sum, rods]`.
    pub fn pool(&mut self, z: &[f64]) -> &[Block] {
        assert!(z.len() <= LANES * (STACK - 8), "PoolBench: too many rods");
        let n = pool_chunk(&mut self.stacks, z, &mut self.pool);
        &self.pool[..n]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Textbook pooling of adjacent violators, one rod at a time.
    fn reference(z: &[f64]) -> Vec<Block> {
        let mut pool: Vec<Block> = Vec::new();
        for &zk in z {
            let mut b = [zk, 1.0];
            while let Some(&top) = pool.last() {
                if !violates(&top, &b) {
                    break;
                }
                b = [top[0] + b[0], top[1] + b[1]];
                pool.pop();
            }
            pool.push(b);
        }
        pool
    }

    fn lcg_z(n: usize, seed: u64, ties: bool) -> Vec<f64> {
        let mut s = seed;
        let mut y = 0.0;
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                let u = (s >> 11) as f64 / (1u64 << 53) as f64;
                y += 0.01;
                if ties {
                    (u * 4.0).floor()
                } else {
                    y + 0.1 * (u - 0.5)
                }
            })
            .collect()
    }

    fn chunk(z: &[f64], scalar: bool) -> Vec<Block> {
        let mut stacks = new_stacks();
        let mut pool = vec![[0.0; 2]; z.len()];
        let n = if scalar {
            let q = z.len() / LANES;
            let zq: [&[f64]; LANES] = std::array::from_fn(|j| &z[j * q..(j + 1) * q]);
            let mut streams = pool_streams_scalar(&mut stacks, &zq, q);
            for &zk in &z[LANES * q..] {
                streams[LANES - 1].push(&mut stacks[LANES - 1], zk);
            }
            let mut n = 0;
            for (st, s) in stacks.iter_mut().zip(&streams) {
                finish(s, st, &mut pool, &mut n);
            }
            n
        } else {
            pool_chunk(&mut stacks, z, &mut pool)
        };
        pool.truncate(n);
        pool
    }

    /// Each stream's blocks (before they are joined), from the scalar or the default kernel.
    fn streams(z: &[f64], scalar: bool) -> Vec<Vec<Block>> {
        let mut stacks = new_stacks();
        let q = z.len() / LANES;
        let zq: [&[f64]; LANES] = std::array::from_fn(|j| &z[j * q..(j + 1) * q]);
        let streams = if scalar {
            pool_streams_scalar(&mut stacks, &zq, q)
        } else {
            pool_streams(&mut stacks, &zq, q)
        };
        // Bit patterns, so that NaN sentinels compare equal.
        let bits = |b: &Block| [b[0].to_bits() as f64, b[1]];
        (stacks.iter_mut().zip(&streams))
            .map(|(st, s)| s.blocks(st).iter().map(bits).collect())
            .collect()
    }

    #[test]
    fn chunks_pool_like_the_textbook_and_the_kernels_agree_bitwise() {
        for (n, seed) in [
            (1, 1),
            (2, 2),
            (3, 3),
            (4, 4),
            (5, 5),
            (7, 6),
            (8, 7),
            (9, 8),
        ]
        .into_iter()
        .chain((0..40).map(|k| (10 + 37 * k, 100 + k as u64)))
        .chain([(4096, 9), (4095, 10)])
        {
            for ties in [false, true] {
                let z = lcg_z(n, seed, ties);
                let want = reference(&z);
                let got = chunk(&z, false);
                assert_eq!(
                    got.len(),
                    want.len(),
                    "n = {n}, ties = {ties}: block count {z:?} {got:?} {want:?}"
                );
                for (g, w) in got.iter().zip(&want) {
                    assert_eq!(g[1], w[1], "n = {n}: rods of a block");
                    assert!(
                        (g[0] - w[0]).abs() <= 1e-12 * w[0].abs().max(1.0),
                        "n = {n}"
                    );
                }
                if n >= LANES {
                    assert_eq!(
                        chunk(&z, true),
                        got,
                        "n = {n}: scalar and SIMD chunks differ"
                    );
                    assert_eq!(
                        streams(&z, true),
                        streams(&z, false),
                        "n = {n}: streams differ"
                    );
                }
            }
        }
    }
}
