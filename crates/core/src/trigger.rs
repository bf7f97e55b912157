//! Triggers: when an observer samples.

/// Sample every `every` steps (step 0 included).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Every(pub u64);

impl Every {
    /// Does the trigger fire at `step`?
    #[inline]
    pub fn fires(&self, step: u64) -> bool {
        self.0 > 0 && step.is_multiple_of(self.0)
    }
}

/// `points` integer lags spaced logarithmically between `min` and `max` (inclusive, sorted,
/// without duplicates).
pub fn log_spaced(min: u64, max: u64, points: usize) -> Vec<u64> {
    let min = min.max(1);
    if max <= min || points <= 1 {
        return vec![min.min(max.max(1))];
    }
    let (a, b) = ((min as f64).ln(), (max as f64).ln());
    let mut v: Vec<u64> = (0..points)
        .map(|i| (a + (b - a) * i as f64 / (points - 1) as f64).exp().round() as u64)
        .map(|x| x.clamp(min, max))
        .collect();
    v.dedup();
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_spacing_is_sorted_unique_and_spans() {
        let v = log_spaced(1, 10_000, 30);
        assert_eq!(v[0], 1);
        assert_eq!(*v.last().unwrap(), 10_000);
        assert!(v.windows(2).all(|w| w[0] < w[1]));
        assert!(Every(10).fires(20) && !Every(10).fires(21) && !Every(0).fires(0));
    }
}
