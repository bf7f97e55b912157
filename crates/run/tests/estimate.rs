//! The cost estimate of `colloidsim check`: the whole run's steps, every step after the first
//! timed when the run is short (with and without its warm-up), a long run warned of.

use colloidsim_run::Scenario;
use colloidsim_run::estimate::{LONG_RUN_SECONDS, estimate};
use std::time::Duration;

fn bcd(time: f64, particles: usize, length: f64) -> Scenario {
    Scenario::from_toml(
        &format!(
            "method = \"bcd\"\nseed = 1\n[system]\nlength = {length}\nparticles = {particles}\n\
             diameter = 0.5\n[run]\ndt = 1e-3\nequilibrate = 0.01\ntime = {time}\n\
             [observe]\ndensity = {{ bins = 20 }}\n"
        ),
        std::path::Path::new("."),
    )
    .unwrap()
}

#[test]
fn a_short_run_is_timed_whole_and_a_long_one_warned_of() {
    // 10 equilibration steps and 40 of the run: all but the first are timed, and the 40 again
    // without the equilibration (the production's own rate) but for their first.
    let e = estimate(&bcd(0.04, 10, 20.0), Duration::from_secs(30)).unwrap();
    assert_eq!(e.steps, 50);
    assert_eq!(e.measured_steps, 49 + 39);
    assert!(e.stopped.is_none());
    assert!(e.seconds_per_step > 0.0 && e.total_seconds >= e.startup_seconds);
    assert!(e.warning().is_none());
    assert!(e.line().contains("of 50"), "{}", e.line());
    // 1e11 steps of 1000 rods: far beyond an hour on any machine (7 ns per rod-step, the
    // fastest measured, gives 7e5 s).
    let e = estimate(&bcd(1e8, 1000, 2000.0), Duration::from_millis(100)).unwrap();
    assert_eq!(e.steps, 100_000_000_010);
    assert!(e.measured_steps < e.steps);
    assert!(e.total_seconds > LONG_RUN_SECONDS, "{}", e.line());
    assert!(e.warning().unwrap().contains("will take about"));
}
