//! Keyed Gaussian noise and deterministic reductions.
//!
//! The Brownian displacement of a step is `sqrt(2 kT dt) M^(1/2) z` with `z` a vector of 3N
//! standard normal deviates. Particle `p`'s three deviates come from the counter-based stream
//! `stream(seed, step, Purpose::Noise, key0 | p / BLOCK)` of `colloidsim_core::rng`, drawn in
//! order for the particles of its block, so that `z` is a pure function of
//! (seed, step, particle) whatever the thread count. Wave-space noise of the positively split
//! Ewald method uses the key space with [`GRID_KEY`] set.

use colloidsim_core::rng::{BLOCK, Purpose, Ziggurat, stream};
use rayon::prelude::*;

/// Bit set in the stream index of grid (wave-space) noise, so that it never shares a stream
/// with the particle noise of the same step.
pub const GRID_KEY: u64 = 1 << 62;

/// Which noise a Brownian displacement uses: the stream keys (seed, step) and the key offset
/// `key0` (e.g. `replica << 32`) of its particles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NoiseKey {
    /// Seed of the run.
    pub seed: u32,
    /// Time step.
    pub step: u64,
    /// Offset of the stream index (below bit 62): distinguishes replicas of one seed.
    pub key0: u64,
}

/// Fill `z` (3 deviates per particle, particles in the order given) with the standard normal
/// deviates of `key`; parallel over blocks of [`BLOCK`] particles.
pub fn fill_particle_noise(key: NoiseKey, z: &mut [[f64; 3]]) {
    let zig = Ziggurat::get();
    z.par_chunks_mut(BLOCK).enumerate().for_each(|(b, out)| {
        let mut rng = stream(key.seed, key.step, Purpose::Noise, key.key0 | b as u64);
        for x in out.iter_mut() {
            *x = [
                zig.sample(&mut rng),
                zig.sample(&mut rng),
                zig.sample(&mut rng),
            ];
        }
    });
}

/// Entries per partial sum of [`dot`]: the summation order is fixed by this, not by the
/// thread count.
const DOT_CHUNK: usize = 2048;

/// `x . y` with a summation order independent of the thread count: sequential partial sums
/// over fixed chunks (computed in parallel), then the partials added in order. `partials` is
/// scratch (no allocation once it has grown).
pub fn dot(x: &[f64], y: &[f64], partials: &mut Vec<f64>) -> f64 {
    debug_assert_eq!(x.len(), y.len());
    x.par_chunks(DOT_CHUNK)
        .zip(y.par_chunks(DOT_CHUNK))
        .map(|(a, b)| {
            // Four interleaved sums: vectorisable, and a fixed order.
            let mut s = [0.0f64; 4];
            let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
            let (ra, rb) = (ca.remainder(), cb.remainder());
            for (u, v) in ca.zip(cb) {
                for l in 0..4 {
                    s[l] += u[l] * v[l];
                }
            }
            for (l, (u, v)) in ra.iter().zip(rb).enumerate() {
                s[l] += u * v;
            }
            (s[0] + s[1]) + (s[2] + s[3])
        })
        .collect_into_vec(partials);
    partials.iter().sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_a_function_of_the_key_and_particle_alone() {
        let key = NoiseKey {
            seed: 7,
            step: 12,
            key0: 0,
        };
        let mut a = vec![[0.0; 3]; 300];
        fill_particle_noise(key, &mut a);
        let mut b = vec![[0.0; 3]; 200];
        fill_particle_noise(key, &mut b);
        assert_eq!(&a[..200], &b[..]);
        let mut c = vec![[0.0; 3]; 300];
        fill_particle_noise(NoiseKey { step: 13, ..key }, &mut c);
        assert_ne!(a, c);
        let mean: f64 = a.iter().flatten().sum::<f64>() / 900.0;
        let var: f64 = a.iter().flatten().map(|x| x * x).sum::<f64>() / 900.0;
        // 900 deviates: standard errors 0.033 (mean) and 0.047 (variance).
        assert!(
            mean.abs() < 0.17 && (var - 1.0).abs() < 0.24,
            "{mean} {var}"
        );
    }

    #[test]
    fn dot_is_exact_on_integers_and_thread_independent() {
        let x: Vec<f64> = (0..10_001).map(|i| (i % 17) as f64).collect();
        let y: Vec<f64> = (0..10_001).map(|i| (i % 5) as f64 - 2.0).collect();
        let want: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
        let mut p = Vec::new();
        assert_eq!(dot(&x, &y, &mut p), want);
        let z: Vec<f64> = (0..10_001).map(|i| (i as f64 * 0.37).sin()).collect();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| dot(&z, &x, &mut Vec::new()));
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap()
            .install(|| dot(&z, &x, &mut Vec::new()));
        assert_eq!(one.to_bits(), two.to_bits());
    }
}
