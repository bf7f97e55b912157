//! Benchmark of the exact 1D rods solver (issue 3): sticky rods gamma = 10, sigma = 0.8,
//! mean density 0.8, beta U = 3 cos(2 pi x), period 1, tolerance 1e-10, one core.
//!
//! `cargo run --release -p colloidsim-dft --example rods_bench [-- RUNS]`
use colloidsim_dft::rods::{BetaPotential, Domain, RodInteraction, RodsProblem, equilibrium};
use std::time::Instant;

fn main() {
    let runs: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(7);
    println!(
        "| interaction | dx | grid points | levels | iterations (finest / all) | residual | median wall time [s] |"
    );
    println!("|---|---|---|---|---|---|---|");
    for &(name, gamma) in &[("sticky gamma=10", 10.0), ("hard", 0.0)] {
        for &dx in &[1e-3, 1e-4, 1e-5] {
            let problem = RodsProblem::new(0.8, 0.8, Domain::Periodic { period: 1.0 })
                .with_dx(dx)
                .with_interaction(if gamma > 0.0 {
                    RodInteraction::Sticky { gamma }
                } else {
                    RodInteraction::Hard
                })
                .with_potential(BetaPotential::from_fn(1.0, |x| {
                    3.0 * (std::f64::consts::TAU * x).cos()
                }));
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..runs {
                let t = Instant::now();
                let eq = equilibrium(&problem).expect("converges");
                times.push(t.elapsed().as_secs_f64());
                last = Some(eq);
            }
            times.sort_by(f64::total_cmp);
            let eq = last.expect("at least one run");
            println!(
                "| {name} | {dx:.0e} | {} | {} | {} / {} | {:.2e} | {:.4} |",
                eq.x.len(),
                eq.levels,
                eq.iterations,
                eq.total_iterations,
                eq.residual,
                times[times.len() / 2]
            );
        }
    }
}
