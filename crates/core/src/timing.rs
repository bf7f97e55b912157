//! Timing helpers for benchmarks on shared machines.

/// CPU time of the calling thread in seconds (`/proc/thread-self/schedstat`, Linux), so that
/// time the scheduler gives to other processes does not count; 0 where unavailable.
pub fn thread_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns * 1e-9)
}
