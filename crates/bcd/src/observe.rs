//! Observables of a BCD run, sampled on triggers: density profile (hard-rods paper Eq. 26),
//! two-particle density at contact (Eq. 27), mean-square displacement, particle current and
//! cluster-size statistics.

use crate::engine::{Bcd, Boundary};
use crate::forces::{ExternalForce, PairForce};
pub use colloidsim_core::msd::Msd;
use serde::{Deserialize, Serialize};

/// `x` folded into one `period`, `[0, period]` up to rounding (callers clamp the bin). Not
/// `rem_euclid`, which calls `fmod` and took a sixth of the time of a small run.
#[inline]
fn fold(x: f64, period: f64) -> f64 {
    x - (x / period).floor() * period
}

/// `1.5 * 2^52`: for an integer-valued `v` in `[0, 2^31)`, the low 32 bits of `v + MANTISSA_SHIFT`
/// are `v`.
const MANTISSA_SHIFT: f64 = 6_755_399_441_055_744.0;

/// Histogram of rod centres over `[0, period)`, folded when the system is longer.
/// `rho(x_a + dx/2) = p_a / (M dx (L / period))`, so its mean is the mean density N/L.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DensityProfile {
    period: f64,
    counts: Vec<u64>,
    samples: u64,
    folds: f64,
    /// The bins of one configuration (scratch: the bin arithmetic runs as its own,
    /// vectorised pass before the counting).
    #[serde(skip)]
    scratch: Vec<u32>,
}

impl DensityProfile {
    /// `bins` bins over one `period` of a system of length `length`.
    pub fn new(bins: usize, period: f64, length: f64) -> Self {
        Self {
            period,
            counts: vec![0; bins],
            samples: 0,
            folds: length / period,
            scratch: Vec::new(),
        }
    }

    /// Add one configuration.
    pub fn sample(&mut self, x: &[f64]) {
        let m = self.counts.len();
        let scale = m as f64 / self.period;
        let (period, top) = (self.period, (m - 1).min(i32::MAX as usize) as f64);
        // Clamped to [0, last bin] and floored in f64, then read off the mantissa after adding
        // 1.5 * 2^52 (exact for integers below 2^31): the same bins as a truncation to usize
        // clamped to the last bin (NaN to bin 0), in a loop that vectorises (a float-to-int
        // conversion does not).
        self.scratch.resize(x.len(), 0);
        for (b, &xi) in self.scratch.iter_mut().zip(x) {
            let v = (fold(xi, period) * scale).max(0.0).min(top).floor();
            *b = (v + MANTISSA_SHIFT).to_bits() as u32;
        }
        for &b in &self.scratch {
            self.counts[b as usize] += 1;
        }
        self.samples += 1;
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
        let m = self.counts.len();
        let scale = m as f64 / self.period;
        let (period, top) = (self.period, (m - 1).min(i32::MAX as usize) as f64);
        self.scratch.resize(y.len(), 0);
        for (i, (b, &yi)) in self.scratch.iter_mut().zip(y).enumerate() {
            // x_i exactly as Bcd::positions forms it.
            let xi = yi + (i as i32) as f64 * sigma;
            let v = (fold(xi, period) * scale).max(0.0).min(top).floor();
            *b = (v + MANTISSA_SHIFT).to_bits() as u32;
        }
        for &b in &self.scratch {
            self.counts[b as usize] += 1;
        }
        self.samples += 1;
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
                let b = (fold(x[i], self.inner.period) * scale) as usize;
                self.inner.counts[b.min(m - 1)] += 1;
            }
        }
        self.inner.samples += 1;
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
        for &xi in &x {
            let b = (fold(xi, period) * scale) as usize;
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
}
