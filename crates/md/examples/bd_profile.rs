//! Profile the Brownian engine on the `bench bd` system: `cargo run --release -p colloidsim-md
//! --example bd_profile -- STEPS SKIN` (WCA, 25,000 particles at phi = 0.1, dt = 1e-4).
use colloidsim_md::bench::wca_periodic_skin;
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let steps: u64 = a.get(1).map_or(2000, |s| s.parse().unwrap());
    let skin: f64 = a.get(2).map_or(0.3, |s| s.parse().unwrap());
    let mut sim = wca_periodic_skin(25_000, 0.1, 1e-4, 1, skin).unwrap();
    sim.run(200).unwrap();
    let b0 = sim.neighbor_builds();
    let (t, c) = (Instant::now(), cpu_seconds());
    sim.run(steps).unwrap();
    let (s, cpu) = (t.elapsed().as_secs_f64(), cpu_seconds() - c);
    println!(
        "{steps} steps, skin {skin}: {:.3e} particle-steps/s ({:.3e} per CPU second), {:.2} steps per build",
        25_000.0 * steps as f64 / s,
        25_000.0 * steps as f64 / cpu,
        steps as f64 / (sim.neighbor_builds() - b0) as f64,
    );
}

/// User + system CPU time of this process (Linux `/proc/self/stat`, clock ticks of 10 ms).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = after
        .split_whitespace()
        .map(|x| x.parse().unwrap_or(0.0))
        .collect();
    (f.get(11).copied().unwrap_or(0.0) + f.get(12).copied().unwrap_or(0.0)) / 100.0
}
