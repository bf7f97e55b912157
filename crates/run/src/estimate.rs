//! The cost of a run before it runs (`colloidsim check` prints it): the run's own session is
//! started and driven, observers and all, for a fraction of a second on this machine and with
//! this thread count, and its time per step is extrapolated to the whole run. Nothing is
//! written where the user looks: the session's files go to a temporary folder of our own,
//! removed afterwards.

use crate::registry;
use crate::scenario::Scenario;
use anyhow::Result;
use colloidsim_core::output::OutputDir;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Above this a run gets a warning.
pub const LONG_RUN_SECONDS: f64 = 3600.0;

/// What a run will cost, measured on its first steps.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Estimate {
    /// Steps of the whole run (over all replicas).
    pub steps: u64,
    /// Steps timed (after the first, which carries one-off costs).
    pub measured_steps: u64,
    /// Seconds per step over the measured steps.
    pub seconds_per_step: f64,
    /// Seconds from the scenario to the first step (initial configuration, tables, tuning).
    pub startup_seconds: f64,
    /// The whole run: start-up plus every step at the measured rate.
    pub total_seconds: f64,
    /// Peak resident memory of this process while measuring, in bytes (Linux; else none).
    pub peak_memory_bytes: Option<f64>,
    /// Worker threads the measurement ran on.
    pub threads: usize,
    /// The measurement ended early: the run itself would stop there (why).
    pub stopped: Option<String>,
}

impl Estimate {
    /// One line: the time, the rate it rests on, the memory.
    pub fn line(&self) -> String {
        let memory = self
            .peak_memory_bytes
            .map(|b| format!("; memory about {}", colloidsim_core::resources::human(b)))
            .unwrap_or_default();
        format!(
            "estimate: about {} on this machine ({} thread{}: {:.3e} s per step over {} steps timed of {}, start-up {:.2} s){memory}",
            duration(self.total_seconds),
            self.threads,
            if self.threads == 1 { "" } else { "s" },
            self.seconds_per_step,
            self.measured_steps,
            self.steps,
            self.startup_seconds
        )
    }

    /// The warning for a run longer than [`LONG_RUN_SECONDS`].
    pub fn warning(&self) -> Option<String> {
        (self.total_seconds > LONG_RUN_SECONDS).then(|| {
            format!(
                "this run will take about {} on this machine: consider more threads, MPI ranks (docs/parallel.md), a shorter run.time or fewer particles; checkpoints let it continue after a stop (docs/cluster.md)",
                duration(self.total_seconds)
            )
        })
    }
}

/// Seconds as a person reads them.
pub fn duration(s: f64) -> String {
    if !s.is_finite() {
        return "an unknown time".into();
    }
    if s < 60.0 {
        format!("{s:.1} s")
    } else if s < 3600.0 {
        format!("{:.1} min", s / 60.0)
    } else if s < 2.0 * 86400.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.1} days", s / 86400.0)
    }
}

/// Peak resident memory of this process (VmHWM), bytes.
fn peak_memory() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let kb: f64 = s
        .lines()
        .find(|l| l.starts_with("VmHWM:"))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()?;
    Some(kb * 1024.0)
}

/// A folder of our own under the system's temporary folder, removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The first steps of a session, timed.
struct Timed {
    startup_seconds: f64,
    total: u64,
    measured_steps: u64,
    seconds_per_step: f64,
    stopped: Option<String>,
}

/// Start the run `sc` describes and time its steps for about `budget` after the first.
fn time_steps(sc: &Scenario, budget: Duration) -> Result<Timed> {
    let m = registry::of(sc)?;
    let started = Instant::now();
    let mut session = m.start(sc, None, None)?;
    let stamp = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    let scratch = Scratch(std::env::temp_dir().join(format!(
        "colloidsim-estimate-{}-{stamp}",
        std::process::id()
    )));
    let out = OutputDir::create(&scratch.0, false)?;
    session.begin(&out, true)?;
    let total = session.total();
    let mut stopped = None;
    // The first step carries one-off costs (lists, tables): counted with the start-up.
    if session.position() < total {
        stopped = session.advance(session.position() + 1)?;
    }
    let startup_seconds = started.elapsed().as_secs_f64();
    let (from, timer) = (session.position(), Instant::now());
    let mut chunk = 1;
    while stopped.is_none() && session.position() < total && timer.elapsed() < budget {
        let until = (session.position() + chunk).min(total);
        stopped = session.advance(until)?;
        chunk *= 2;
    }
    let measured_steps = session.position() - from;
    let seconds = timer.elapsed().as_secs_f64();
    Ok(Timed {
        startup_seconds,
        total,
        measured_steps,
        seconds_per_step: if measured_steps > 0 {
            seconds / measured_steps as f64
        } else {
            0.0
        },
        stopped,
    })
}

/// Keys of a warm-up whose steps cost less than the production's (no sampling): the run is
/// timed once as it is and once without its warm-up, and each phase counted at its own rate.
const WARM_UP_KEYS: [&str; 2] = ["run.equilibrate", "mc.warmup_sweeps"];

/// The scenario without its warm-up: each key set to 0, as an integer where the method takes
/// one (MPCD's collisions, MC's sweeps) and else as a time; `None` where neither is valid.
fn without_warm_up(sc: &Scenario, keys: &[&str]) -> Option<Scenario> {
    let mut sc = sc.clone();
    for k in keys {
        sc = [toml::Value::Integer(0), toml::Value::Float(0.0)]
            .into_iter()
            .find_map(|zero| {
                let v = sc.with_values(&[(k.to_string(), zero)]).ok()?;
                crate::check(&v).ok().map(|_| v)
            })?;
    }
    Some(sc)
}

/// Time the run `sc` describes on its first steps (and, where it has a warm-up, on the first
/// steps after it) for about `budget` in all; extrapolate to the whole run.
pub fn estimate(sc: &Scenario, budget: Duration) -> Result<Estimate> {
    let m = registry::of(sc)?;
    let warm_up: Vec<&str> = WARM_UP_KEYS
        .into_iter()
        .filter(|k| m.keys().iter().any(|s| s.path == *k))
        .collect();
    let whole = time_steps(sc, budget / 2)?;
    let mut steps = (whole.measured_steps, whole.seconds_per_step);
    let mut total_seconds =
        whole.startup_seconds + whole.seconds_per_step * whole.total.saturating_sub(1) as f64;
    let production = (!warm_up.is_empty() && whole.stopped.is_none())
        .then(|| without_warm_up(sc, &warm_up))
        .flatten();
    // The production's timing is a refinement: where it cannot be had, the whole run's rate
    // stands.
    if let Some(p) = production.and_then(|p| time_steps(&p, budget / 2).ok())
        && p.total < whole.total
        && p.stopped.is_none()
    {
        let warm = whole.total - p.total;
        total_seconds = whole.startup_seconds
            + whole.seconds_per_step * warm.saturating_sub(1) as f64
            + p.seconds_per_step * p.total as f64;
        // The rate quoted: the whole run's mean.
        steps = (
            whole.measured_steps + p.measured_steps,
            (total_seconds - whole.startup_seconds) / whole.total.max(1) as f64,
        );
    }
    Ok(Estimate {
        steps: whole.total,
        measured_steps: steps.0,
        seconds_per_step: steps.1,
        startup_seconds: whole.startup_seconds,
        total_seconds,
        peak_memory_bytes: peak_memory(),
        threads: rayon::current_num_threads(),
        stopped: whole.stopped,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_as_people_read_them() {
        assert_eq!(duration(12.34), "12.3 s");
        assert_eq!(duration(90.0), "1.5 min");
        assert_eq!(duration(7200.0), "2.0 h");
        assert_eq!(duration(3.0 * 86400.0), "3.0 days");
        assert_eq!(duration(f64::NAN), "an unknown time");
    }
}
