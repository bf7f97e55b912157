//! The mean-square displacement of a running simulation at chosen lags, averaged over particles
//! and over time origins, taking a configuration only at the steps it needs
//! ([`Msd::next_due`]). Coordinates are a flat slice: one number per rod, or `x, y, z` per
//! sphere (the mean is then per coordinate; three times it is the 3D MSD).

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
        }
    }

    /// Offer the configuration at `step` (call every step of the sampled part of the run).
    pub fn sample(&mut self, step: u64, x: &[f64]) {
        let max_lag = *self.lags.last().unwrap_or(&0);
        for (t0, x0) in &self.origins {
            let lag = step - t0;
            if let Ok(k) = self.lags.binary_search(&lag) {
                let n = x.len() as f64;
                let m: f64 = x
                    .iter()
                    .zip(x0)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    / n;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Offering the MSD only the configurations it uses ([`Msd::next_due`]) gives the same
    /// rows, bit for bit, as offering every step.
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
}
