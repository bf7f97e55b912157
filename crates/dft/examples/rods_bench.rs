//! Benchmark of the exact 1D rods solver (issue 3): sticky rods gamma = 10, sigma = 0.8,
//! mean density 0.8, beta U = 3 cos(2 pi x), period 1, tolerance 1e-10, one core.
//!
//! Second table: DDFT relaxation of the same state from the uniform density to t = 2 (fixed
//! steps), and its distance to the direct solution.
//!
//! `cargo run --release -p colloidsim-dft --example rods_bench [-- RUNS]`
use colloidsim_dft::rods::{
    BetaPotential, DdftProblem, Domain, InitialProfile, RodInteraction, RodsProblem, ddft,
    equilibrium,
};
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
    println!();
    println!(
        "| DDFT to t = 2 | dx | dt | steps | max rel. N change | max rel. distance to direct solution | median wall time [s] |"
    );
    println!("|---|---|---|---|---|---|---|");
    for &(name, gamma, dx, dt) in &[
        ("sticky gamma=10", 10.0, 1e-3, 1e-3),
        ("hard", 0.0, 1e-3, 1e-2),
    ] {
        let rods = RodsProblem::new(0.8, 0.8, Domain::Periodic { period: 1.0 })
            .with_dx(dx)
            .with_interaction(RodInteraction::Sticky { gamma })
            .with_potential(BetaPotential::from_fn(1.0, |x| {
                3.0 * (std::f64::consts::TAU * x).cos()
            }));
        let eq = equilibrium(&rods).expect("converges");
        let scale = eq.rho.iter().cloned().fold(0.0, f64::max);
        let problem = DdftProblem {
            rods,
            diffusion: 1.0,
            beta_drive: 0.0,
            dt,
            step_tolerance: None,
            output_times: vec![2.0],
            initial: InitialProfile::Uniform,
        };
        let mut times = Vec::new();
        let mut dist = 0.0;
        let mut summary = None;
        for _ in 0..runs.min(3) {
            let t = Instant::now();
            let s = ddft(&problem, |f| {
                dist = f
                    .rho
                    .iter()
                    .zip(&eq.rho)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max)
                    / scale;
            })
            .expect("runs");
            times.push(t.elapsed().as_secs_f64());
            summary = Some(s);
        }
        times.sort_by(f64::total_cmp);
        let s = summary.expect("ran");
        println!(
            "| {name} | {dx:.0e} | {dt:.0e} | {} | {:.1e} | {dist:.1e} | {:.3} |",
            s.steps,
            s.max_relative_mass_change,
            times[times.len() / 2]
        );
    }
}
