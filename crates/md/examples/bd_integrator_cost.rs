//! Cost per step of the free-draining BD integrators, Euler against Leimkuhler–Matthews, on
//! WCA particles in a periodic box (`colloidsim_md::bench::wca_periodic`), alternating A/B:
//!
//! `cargo run --release -p colloidsim-md --example bd_integrator_cost -- N PHI STEPS ROUNDS`
//!
//! prints the median and the spread of the wall time per step of each over ROUNDS rounds.

use colloidsim_md::Integrator;
use colloidsim_md::bench::wca_periodic;
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = a.first().map_or(2000, |s| s.parse().unwrap());
    let phi: f64 = a.get(1).map_or(0.25, |s| s.parse().unwrap());
    let steps: u64 = a.get(2).map_or(2000, |s| s.parse().unwrap());
    let rounds: usize = a.get(3).map_or(7, |s| s.parse().unwrap());
    let mut times = [Vec::new(), Vec::new()];
    for _ in 0..rounds {
        for (k, integrator) in [Integrator::Euler, Integrator::Lm].into_iter().enumerate() {
            let mut sim = wca_periodic(n, phi, 1e-4, 3)
                .unwrap()
                .with_integrator(integrator);
            sim.run(200).unwrap();
            let t = Instant::now();
            sim.run(steps).unwrap();
            times[k].push(t.elapsed().as_secs_f64() / steps as f64);
        }
    }
    for (k, name) in ["euler", "lm"].iter().enumerate() {
        let t = &mut times[k];
        t.sort_by(f64::total_cmp);
        println!(
            "{name}: median {:.3} us/step ({:.1} ns per particle), min {:.3}, max {:.3} (N = {n}, {rounds} rounds of {steps} steps)",
            1e6 * t[t.len() / 2],
            1e9 * t[t.len() / 2] / n as f64,
            1e6 * t[0],
            1e6 * t[t.len() - 1]
        );
    }
}
