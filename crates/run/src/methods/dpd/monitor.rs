//! The run's temperature check: a DPD step too large heats the system.

/// Stops a run whose kinetic temperature drifts: the mean of the samples in each window of
/// `window` steps must stay within `max_drift` (relative) of kT. The first window (relaxation of
/// the start) is not judged.
#[derive(Debug, Clone)]
pub struct TemperatureMonitor {
    kt: f64,
    max_drift: f64,
    window: u64,
    window_end: Option<u64>,
    sum: f64,
    count: u64,
    judged: bool,
}

impl TemperatureMonitor {
    /// A monitor for `kt`.
    pub fn new(kt: f64, max_drift: f64, window: u64) -> Self {
        Self {
            kt,
            max_drift,
            window: window.max(1),
            window_end: None,
            sum: 0.0,
            count: 0,
            judged: false,
        }
    }

    /// Feed the kinetic temperature sampled at `step`; an error message when a window's mean
    /// has drifted.
    pub fn push(&mut self, step: u64, temperature: f64) -> Result<(), String> {
        let end = *self.window_end.get_or_insert(step + self.window);
        self.sum += temperature;
        self.count += 1;
        if step < end {
            return Ok(());
        }
        let mean = self.sum / self.count as f64;
        let judged = std::mem::replace(&mut self.judged, true);
        self.window_end = Some(step + self.window);
        self.sum = 0.0;
        self.count = 0;
        if judged && (mean / self.kt - 1.0).abs() > self.max_drift {
            return Err(format!(
                "the kinetic temperature averaged over the {} steps before step {step} is {mean:.4}, {:+.1}% from kT = {}: the time step heats (or cools) the system; reduce run.dt (or raise run.max_temperature_drift = {})",
                self.window,
                100.0 * (mean / self.kt - 1.0),
                self.kt,
                self.max_drift
            ));
        }
        Ok(())
    }
}
