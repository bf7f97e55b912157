//! Observables of a BCD run, sampled on triggers: density profile (hard-rods paper Eq. 26),
//! two-particle density at contact (Eq. 27), mean-square displacement, particle current and
//! cluster-size statistics.

use crate::engine::{Bcd, Boundary};
use crate::forces::{ExternalForce, PairForce};
pub use colloidsim_core::msd::Msd;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// `x` folded into one `period`, `[0, period]` up to rounding (callers clamp the bin), given
/// `inv = 1 / period`. Not `rem_euclid`, which calls `fmod` and took a sixth of the time of a
/// small run; a multiplication by `inv`, not a division by `period`, which took half of the
/// density binning's time.
#[inline]
fn fold(x: f64, period: f64, inv: f64) -> f64 {
    x - (x * inv).floor() * period
}

/// `1.5 * 2^52`: for an integer-valued `v` in `[0, 2^31)`, the low 32 bits of `v + MANTISSA_SHIFT`
/// are `v`.
const MANTISSA_SHIFT: f64 = 6_755_399_441_055_744.0;

/// Rods per part of a configuration binned on its own worker (below this, one part).
const PART_MIN: usize = 4096;

/// The bins and counts of one contiguous part of a configuration (scratch of
/// [`DensityProfile`]: reused between samples).
#[derive(Debug, Clone, Default)]
struct Part {
    bins: Vec<u32>,
    counts: Vec<u64>,
}

/// Histogram of rod centres over `[0, period)`, folded when the system is longer.
/// `rho(x_a + dx/2) = p_a / (M dx (L / period))`, so its mean is the mean density N/L.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DensityProfile {
    period: f64,
    counts: Vec<u64>,
    samples: u64,
    folds: f64,
    /// Samples per block of the block standard errors ([`DensityProfile::with_blocks`]; 0:
    /// no blocks).
    block: u64,
    /// The cumulative counts at the end of each full block.
    marks: Vec<Vec<u64>>,
    /// Scratch: the configuration in contiguous parts, one per worker, each binned (a
    /// vectorised pass) and counted on its own; integer counts, so the sum does not depend on
    /// the number of parts.
    #[serde(skip)]
    parts: Vec<Part>,
}

/// The bin of `x` among `m` over one period: clamped to `[0, top = m - 1]` and floored in
/// f64, then read off the mantissa after adding 1.5 * 2^52 (exact for integers below 2^31):
/// the same bin as a truncation to usize clamped to the last bin (NaN to bin 0), in a loop that
/// vectorises (a float-to-int conversion does not).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Binning {
    period: f64,
    inv: f64,
    scale: f64,
    top: f64,
    /// Number of bins.
    pub(crate) bins: usize,
}

impl Binning {
    #[inline]
    pub(crate) fn bin(&self, x: f64) -> u32 {
        let v = (fold(x, self.period, self.inv) * self.scale)
            .max(0.0)
            .min(self.top)
            .floor();
        (v + MANTISSA_SHIFT).to_bits() as u32
    }
}

impl DensityProfile {
    /// `bins` bins over one `period` of a system of length `length`.
    pub fn new(bins: usize, period: f64, length: f64) -> Self {
        Self {
            period,
            counts: vec![0; bins],
            samples: 0,
            folds: length / period,
            block: 0,
            marks: Vec::new(),
            parts: Vec::new(),
        }
    }

    /// Keep the counts of every `samples / blocks` samples (at least one) apart, for the block
    /// standard errors of [`DensityProfile::errors`]; `samples` is the number of samples the
    /// run will take. The blocks hold integer counts, so the errors do not depend on the number
    /// of workers either.
    pub fn with_blocks(mut self, samples: u64, blocks: u64) -> Self {
        self.block = (samples / blocks.max(1)).max(1);
        self
    }

    /// Close a block when its last sample has just been taken.
    fn close_block(&mut self) {
        if self.block > 0 && self.samples.is_multiple_of(self.block) {
            self.marks.push(self.counts.clone());
        }
    }

    /// Standard error of each bin's density from the spread of the full blocks' profiles
    /// (`s / sqrt(B)` with `s` the sample standard deviation of the `B` block means); NaN
    /// where fewer than two blocks are full. The blocks are consecutive stretches of the run,
    /// so they are independent when a block is longer than the density's correlation time.
    pub fn errors(&self) -> Vec<f64> {
        let m = self.counts.len();
        let b = self.marks.len();
        if b < 2 {
            return vec![f64::NAN; m];
        }
        let dx = self.period / m as f64;
        let norm = 1.0 / (self.block as f64 * dx * self.folds);
        (0..m)
            .map(|a| {
                let block = |k: usize| {
                    let before = if k == 0 { 0 } else { self.marks[k - 1][a] };
                    (self.marks[k][a] - before) as f64 * norm
                };
                let mean = (0..b).map(block).sum::<f64>() / b as f64;
                let ss = (0..b).map(|k| (block(k) - mean).powi(2)).sum::<f64>();
                (ss / (b * (b - 1)) as f64).sqrt()
            })
            .collect()
    }

    /// Full blocks of [`DensityProfile::errors`] so far.
    pub fn blocks(&self) -> usize {
        self.marks.len()
    }

    pub(crate) fn binning(&self) -> Binning {
        let m = self.counts.len();
        Binning {
            period: self.period,
            inv: 1.0 / self.period,
            scale: m as f64 / self.period,
            top: (m - 1).min(i32::MAX as usize) as f64,
            bins: m,
        }
    }

    /// Add one configuration's counts per bin (from a step that binned its rods in its own
    /// parallel pass, [`Bcd::step_observed`]).
    pub(crate) fn add_counts(&mut self, counts: &[u64]) {
        for (c, &q) in self.counts.iter_mut().zip(counts) {
            *c += q;
        }
        self.samples += 1;
        self.close_block();
    }

    /// Count the `n` rods whose bins `bins_of(start, out)` writes for rods `start..start +
    /// out.len()`, in parts of at least [`PART_MIN`] rods over the thread pool.
    fn count(&mut self, n: usize, bins_of: impl Fn(usize, &mut [u32]) + Sync) {
        let m = self.counts.len();
        let parts = rayon::current_num_threads().min(n / PART_MIN).max(1);
        let chunk = n.div_ceil(parts);
        self.parts.resize_with(parts, Part::default);
        let tally = |p: usize, part: &mut Part| {
            let start = (p * chunk).min(n);
            part.bins.resize(chunk.min(n - start), 0);
            part.counts.clear();
            part.counts.resize(m, 0);
            bins_of(start, &mut part.bins);
            for &b in &part.bins {
                part.counts[b as usize] += 1;
            }
        };
        if parts == 1 {
            tally(0, &mut self.parts[0]);
        } else {
            self.parts
                .par_iter_mut()
                .enumerate()
                .for_each(|(p, part)| tally(p, part));
        }
        for part in &self.parts[..parts] {
            for (c, &q) in self.counts.iter_mut().zip(&part.counts) {
                *c += q;
            }
        }
        self.samples += 1;
        self.close_block();
    }

    /// Add one configuration.
    pub fn sample(&mut self, x: &[f64]) {
        let b = self.binning();
        self.count(x.len(), |start, out| {
            for (o, &xi) in out.iter_mut().zip(&x[start..]) {
                *o = b.bin(xi);
            }
        });
    }

    /// Add one configuration given by reduced positions `y_i = x_i - i sigma` (a ring's
    /// [`Bcd::reduced`]): the same counts as [`DensityProfile::sample`] of
    /// `x_i = y_i + i sigma`, without building `x`.
    pub fn sample_reduced(&mut self, y: &[f64], sigma: f64) {
        if y.len() > i32::MAX as usize {
            let x: Vec<f64> = y
                .iter()
                .enumerate()
                .map(|(i, &yi)| yi + i as f64 * sigma)
                .collect();
            return self.sample(&x);
        }
        let b = self.binning();
        self.count(y.len(), |start, out| {
            for (k, (o, &yi)) in out.iter_mut().zip(&y[start..]).enumerate() {
                // x_i exactly as Bcd::positions forms it.
                let xi = yi + ((start + k) as i32) as f64 * sigma;
                *o = b.bin(xi);
            }
        });
    }

    /// Bin centres and densities.
    pub fn profile(&self) -> (Vec<f64>, Vec<f64>) {
        let m = self.counts.len();
        let dx = self.period / m as f64;
        let norm = 1.0 / (self.samples.max(1) as f64 * dx * self.folds);
        (
            (0..m).map(|a| (a as f64 + 0.5) * dx).collect(),
            self.counts.iter().map(|&p| p as f64 * norm).collect(),
        )
    }

    /// Number of configurations sampled.
    pub fn samples(&self) -> u64 {
        self.samples
    }
}

/// Two-particle density at contact, `rho2(x, x + sigma)`: a rod in bin `a` whose right
/// neighbour lies within `[x + sigma, x + sigma + window)` counts once,
/// `rho2 = q_a / (M dx window (L / period))` (hard-rods paper Eq. 27).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ContactDensity {
    inner: DensityProfile,
    window: f64,
    sigma: f64,
    length: f64,
    periodic: bool,
}

impl ContactDensity {
    /// `bins` bins over `period`, contact window `window` (Delta').
    pub fn new(
        bins: usize,
        window: f64,
        period: f64,
        sigma: f64,
        length: f64,
        boundary: Boundary,
    ) -> Self {
        Self {
            inner: DensityProfile::new(bins, period, length),
            window,
            sigma,
            length,
            periodic: boundary == Boundary::Periodic,
        }
    }

    /// Add one configuration.
    pub fn sample(&mut self, x: &[f64]) {
        let n = x.len();
        let m = self.inner.counts.len();
        let scale = m as f64 / self.inner.period;
        let inv = 1.0 / self.inner.period;
        let reach = self.sigma + self.window;
        for i in 0..n {
            let right = if i + 1 < n {
                x[i + 1]
            } else if self.periodic && n > 1 {
                x[0] + self.length
            } else {
                continue;
            };
            if right - x[i] < reach {
                let b = (fold(x[i], self.inner.period, inv) * scale) as usize;
                self.inner.counts[b.min(m - 1)] += 1;
            }
        }
        self.inner.samples += 1;
        self.inner.close_block();
    }

    /// Block standard errors as [`DensityProfile::with_blocks`] for the density.
    pub fn with_blocks(mut self, samples: u64, blocks: u64) -> Self {
        self.inner = self.inner.with_blocks(samples, blocks);
        self
    }

    /// Standard error of each bin's contact density ([`DensityProfile::errors`]).
    pub fn errors(&self) -> Vec<f64> {
        self.inner
            .errors()
            .into_iter()
            .map(|e| e / self.window)
            .collect()
    }

    /// Bin centres and contact densities.
    pub fn profile(&self) -> (Vec<f64>, Vec<f64>) {
        let (x, mut r) = self.inner.profile();
        for v in &mut r {
            *v /= self.window;
        }
        (x, r)
    }
}

/// Histogram of cluster sizes (rods in contact moving together).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct ClusterSizes {
    counts: Vec<u64>,
}

impl ClusterSizes {
    /// Add the clusters of the current configuration.
    pub fn sample<E: ExternalForce, P: PairForce>(&mut self, bcd: &Bcd<E, P>) {
        bcd.count_cluster_sizes(&mut self.counts);
    }

    /// Add a histogram of cluster sizes of a configuration of `n` rods (as
    /// [`ClusterSizes::sample`] does: the counts grow to `n + 1` entries).
    pub(crate) fn add_counts(&mut self, counts: &[u64], n: usize) {
        if self.counts.len() <= n {
            self.counts.resize(n + 1, 0);
        }
        for (c, &q) in self.counts.iter_mut().zip(counts) {
            *c += q;
        }
    }

    /// Rows `(size, probability)`: the fraction of clusters of each size.
    pub fn rows(&self) -> (Vec<f64>, Vec<f64>) {
        let total: u64 = self.counts.iter().sum();
        let mut s = Vec::new();
        let mut p = Vec::new();
        for (size, &c) in self.counts.iter().enumerate() {
            if c > 0 {
                s.push(size as f64);
                p.push(c as f64 / total.max(1) as f64);
            }
        }
        (s, p)
    }
}

#[cfg(test)]
mod bin_tests {
    use super::*;

    /// The vectorised binning puts every position in the bin of the plain truncation,
    /// including the edges, out-of-range and non-finite values.
    #[test]
    fn density_bins_equal_truncation_clamped_to_the_last_bin() {
        let (period, m) = (1.0f64, 100usize);
        let mut x: Vec<f64> = (0..20_000).map(|i| -3.0 + i as f64 * 3.7e-4).collect();
        x.extend([
            0.0,
            1.0,
            -0.0,
            0.01,
            0.99,
            0.999_999_999_999_999_9,
            1e300,
            -1e300,
        ]);
        x.extend([
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            12345.678,
            -1e-320,
        ]);
        let mut d = DensityProfile::new(m, period, 10.0);
        d.sample(&x);
        let mut want = vec![0u64; m];
        let scale = m as f64 / period;
        let inv = 1.0 / period;
        for &xi in &x {
            let b = (fold(xi, period, inv) * scale) as usize;
            want[b.min(m - 1)] += 1;
        }
        assert_eq!(d.counts, want);
    }

    /// Binning from reduced positions gives the counts of binning the positions.
    #[test]
    fn density_from_reduced_positions_equals_density_from_positions() {
        let sigma = 0.37;
        let y: Vec<f64> = (0..5000)
            .map(|i| (i as f64 * 0.618).sin() * 3.0 + 0.001 * i as f64)
            .collect();
        let x: Vec<f64> = y
            .iter()
            .enumerate()
            .map(|(i, &yi)| yi + i as f64 * sigma)
            .collect();
        let mut a = DensityProfile::new(73, 1.3, 100.0);
        let mut b = DensityProfile::new(73, 1.3, 100.0);
        a.sample(&x);
        b.sample_reduced(&y, sigma);
        assert_eq!(a.counts, b.counts);
        assert_eq!(a.samples, b.samples);
    }

    /// The block errors are the same bit for bit on 1, 2 and 3 workers, equal the spread of the
    /// block profiles computed by hand, and are NaN until two blocks are full.
    #[test]
    fn density_block_errors_do_not_depend_on_the_number_of_workers() {
        let (m, period, sigma, n) = (17, 1.0, 0.99, 2 * PART_MIN + 5);
        let config = |t: usize| -> Vec<f64> {
            (0..n)
                .map(|i| ((i * 7 + t * 13) as f64 * 0.618).sin() * 5.0)
                .collect()
        };
        let mut runs = Vec::new();
        for workers in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(workers)
                .build()
                .unwrap();
            let mut d = DensityProfile::new(m, period, 1e4).with_blocks(12, 4);
            pool.install(|| {
                for t in 0..3 {
                    d.sample_reduced(&config(t), sigma);
                }
                assert!(d.errors().iter().all(|e| e.is_nan()), "one block only");
                for t in 3..12 {
                    d.sample_reduced(&config(t), sigma);
                }
            });
            assert_eq!(d.blocks(), 4);
            runs.push(d.errors());
        }
        let bits = |v: &Vec<f64>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&runs[0]), bits(&runs[1]));
        assert_eq!(bits(&runs[0]), bits(&runs[2]));
        // By hand: four blocks of three samples each.
        let mut blocks = vec![vec![0.0f64; m]; 4];
        for t in 0..12 {
            let mut one = DensityProfile::new(m, period, 1e4);
            one.sample_reduced(&config(t), sigma);
            let (_, rho) = one.profile();
            for a in 0..m {
                blocks[t / 3][a] += rho[a] / 3.0;
            }
        }
        for a in 0..m {
            let mean = blocks.iter().map(|b| b[a]).sum::<f64>() / 4.0;
            let var = blocks.iter().map(|b| (b[a] - mean).powi(2)).sum::<f64>() / 3.0;
            let want = (var / 4.0).sqrt();
            assert!((runs[0][a] - want).abs() <= 1e-12 * (want + mean), "{a}");
        }
    }

    /// Counts in parts over a pool of 1, 2 and 3 workers equal the counts of the plain loop.
    #[test]
    fn density_counts_do_not_depend_on_the_number_of_workers() {
        let (m, period, sigma) = (61, 1.0, 0.99);
        let y: Vec<f64> = (0..3 * PART_MIN + 17)
            .map(|i| (i as f64 * 0.618).sin() * 40.0)
            .collect();
        let mut want = vec![0u64; m];
        for (i, &yi) in y.iter().enumerate() {
            let x = yi + (i as i32) as f64 * sigma;
            let b = (fold(x, period, 1.0 / period) * m as f64 / period) as usize;
            want[b.min(m - 1)] += 1;
        }
        for workers in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(workers)
                .build()
                .unwrap();
            let mut d = DensityProfile::new(m, period, 1e4);
            pool.install(|| {
                d.sample_reduced(&y, sigma);
                d.sample_reduced(&y, sigma);
            });
            assert_eq!(d.parts.len(), workers);
            let twice: Vec<u64> = want.iter().map(|c| 2 * c).collect();
            assert_eq!(d.counts, twice, "{workers} workers");
        }
    }
}
