//! The mean-square displacement of a running simulation at chosen lags, averaged over particles
//! and over time origins, taking a configuration only at the steps it needs
//! ([`Msd::next_due`]). Coordinates are a flat slice: one number per rod, or `x, y, z` per
//! sphere (the mean is then per coordinate; three times it is the 3D MSD).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Mean-square displacement per coordinate at log-spaced lags (in steps), averaged over the
/// coordinates (particles) and over time origins taken every `origin_every` steps.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Msd {
    lags: Vec<u64>,
    origin_every: u64,
    /// Stored origins: (step, positions).
    origins: std::collections::VecDeque<(u64, Vec<f64>)>,
    spare: Vec<Vec<f64>>,
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
    count: Vec<u64>,
    /// Scratch: the sums of squared displacements of each block of [`BLOCK`] coordinates.
    #[serde(skip)]
    partials: Vec<f64>,
}

impl Msd {
    /// MSD at the given lags (steps, sorted ascending), origins every `origin_every` steps.
    pub fn new(lags: Vec<u64>, origin_every: u64) -> Self {
        let k = lags.len();
        Self {
            lags,
            origin_every: origin_every.max(1),
            origins: Default::default(),
            spare: Vec::new(),
            sum: vec![0.0; k],
            sum_sq: vec![0.0; k],
            count: vec![0; k],
            partials: Vec::new(),
        }
    }

    /// Offer the configuration at `step` (call every step of the sampled part of the run).
    pub fn sample(&mut self, step: u64, x: &[f64]) {
        let max_lag = *self.lags.last().unwrap_or(&0);
        for (t0, x0) in &self.origins {
            let lag = step - t0;
            if let Ok(k) = self.lags.binary_search(&lag) {
                let m = mean_square_difference(x, x0, &mut self.partials);
                self.sum[k] += m;
                self.sum_sq[k] += m * m;
                self.count[k] += 1;
            }
        }
        while self
            .origins
            .front()
            .is_some_and(|(t0, _)| step - t0 >= max_lag)
        {
            let (_, v) = self.origins.pop_front().expect("non-empty");
            self.spare.push(v);
        }
        if step.is_multiple_of(self.origin_every) {
            let mut v = self.spare.pop().unwrap_or_default();
            v.clear();
            v.extend_from_slice(x);
            self.origins.push_back((step, v));
        }
    }

    /// The first step from `step` on at which [`Msd::sample`] uses the configuration (a time
    /// origin, or an origin plus a lag); calling `sample` only there gives the same sums as
    /// calling it every step.
    pub fn next_due(&self, step: u64) -> u64 {
        let mut due = step.next_multiple_of(self.origin_every);
        for (t0, _) in &self.origins {
            let need = step.saturating_sub(*t0);
            let k = self.lags.partition_point(|&l| l < need);
            if let Some(&lag) = self.lags.get(k) {
                due = due.min(t0 + lag);
            }
        }
        due
    }

    /// Rows `(lag steps, msd, standard error)`; the error treats origin averages separated by
    /// more than the lag as independent.
    pub fn rows(&self) -> Vec<(u64, f64, f64)> {
        let mut out = Vec::new();
        for (k, &lag) in self.lags.iter().enumerate() {
            let c = self.count[k];
            if c == 0 {
                continue;
            }
            let mean = self.sum[k] / c as f64;
            let var = (self.sum_sq[k] / c as f64 - mean * mean).max(0.0);
            let independent =
                (c as f64 * (self.origin_every as f64 / lag as f64).min(1.0)).max(1.0);
            out.push((lag, mean, (var / independent).sqrt()));
        }
        out
    }
}

/// Lanes of [`sum_square_difference`]: independent partial sums, so the loop vectorises (a
/// single running sum is bound by the latency of one addition per element).
const LANES: usize = 8;

/// Coordinates per block of [`mean_square_difference`]: the blocks are summed over the thread
/// pool, then their sums in order, so the result does not depend on the number of workers.
const BLOCK: usize = 4096;

/// `sum_i (x_i - x0_i)^2` in [`LANES`] interleaved partial sums.
fn sum_square_difference(x: &[f64], x0: &[f64]) -> f64 {
    let mut acc = [0.0f64; LANES];
    let (xc, x0c) = (x.chunks_exact(LANES), x0.chunks_exact(LANES));
    let (xr, x0r) = (xc.remainder(), x0c.remainder());
    for (a, b) in xc.zip(x0c) {
        for j in 0..LANES {
            let d = a[j] - b[j];
            acc[j] += d * d;
        }
    }
    for (j, (a, b)) in xr.iter().zip(x0r).enumerate() {
        acc[j] += (a - b) * (a - b);
    }
    acc.iter().sum()
}

/// `sum_i (x_i - x0_i)^2 / N`, by blocks of [`BLOCK`] coordinates (`partials`: scratch).
fn mean_square_difference(x: &[f64], x0: &[f64], partials: &mut Vec<f64>) -> f64 {
    let n = x.len().min(x0.len());
    let (x, x0) = (&x[..n], &x0[..n]);
    if n <= 2 * BLOCK {
        partials.clear();
        partials.extend(
            x.chunks(BLOCK)
                .zip(x0.chunks(BLOCK))
                .map(|(a, b)| sum_square_difference(a, b)),
        );
    } else {
        x.par_chunks(BLOCK)
            .zip(x0.par_chunks(BLOCK))
            .map(|(a, b)| sum_square_difference(a, b))
            .collect_into_vec(partials);
    }
    partials.iter().sum::<f64>() / n.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Offering the MSD only the configurations it uses ([`Msd::next_due`]) gives the same
    /// rows, bit for bit, as offering every step.
    #[test]
    fn mean_square_difference_equals_the_plain_sum() {
        for n in [0usize, 1, 7, 8, 9, 100, 1001, 3 * BLOCK + 5] {
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() * 3.0).collect();
            let x0: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
            let plain = x
                .iter()
                .zip(&x0)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                / n.max(1) as f64;
            let lanes = mean_square_difference(&x, &x0, &mut Vec::new());
            assert!(
                (lanes - plain).abs() <= 1e-13 * plain.abs().max(1.0),
                "n = {n}"
            );
        }
    }

    #[test]
    fn msd_sampled_when_due_equals_msd_sampled_every_step() {
        let lags = crate::trigger::log_spaced(1, 300, 12);
        let mut every = Msd::new(lags.clone(), 7);
        let mut due = Msd::new(lags, 7);
        let mut next = due.next_due(0);
        let mut offered = 0;
        let mut x = vec![0.0f64; 5];
        for step in 0..2000u64 {
            for (i, xi) in x.iter_mut().enumerate() {
                *xi += ((step * 31 + i as u64 * 17) % 13) as f64 * 0.01 - 0.06;
            }
            every.sample(step, &x);
            if step == next {
                due.sample(step, &x);
                offered += 1;
                next = due.next_due(step + 1);
                assert!(next > step);
            }
        }
        assert_eq!(every.rows(), due.rows());
        assert!(offered < 2000, "offered {offered} of 2000 steps");
        assert!(!every.rows().is_empty());
    }

    /// The same MSD from a pool of 1, 2 and 3 workers, to the bit.
    #[test]
    fn mean_square_difference_does_not_depend_on_the_number_of_workers() {
        let n = 5 * BLOCK + 3;
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() * 3.0).collect();
        let x0: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
        let got: Vec<f64> = [1, 2, 3]
            .iter()
            .map(|&w| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(w)
                    .build()
                    .unwrap();
                pool.install(|| mean_square_difference(&x, &x0, &mut Vec::new()))
            })
            .collect();
        assert_eq!(got[0].to_bits(), got[1].to_bits());
        assert_eq!(got[0].to_bits(), got[2].to_bits());
    }
}
