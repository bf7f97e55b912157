//! Robustness sweep of the rods equilibrium solver over 400 random states: rod length
//! 0.05–2 (log-uniform), packing fraction 0.01–0.9, gamma 0 (30%) or up to 20, cosine potential
//! U0 = 0–8 kT with period 1, sigma/dx = 10–50, periodic (70%) or walls 1–11 apart.
//! Prints every state that fails (non-convergence or a rejected start) and the totals.
//!
//! `cargo run --release -p colloidsim-dft --example rods_sweep`
use colloidsim_dft::rods::{
    BetaPotential, Domain, RodInteraction, RodsError, RodsProblem, equilibrium,
};
use std::time::Instant;

fn main() {
    // xorshift64, fixed seed: the same 400 states every run
    let mut seed: u64 = 12345;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut failed, mut rejected, mut worst) = (0, 0, 0.0f64);
    let total = Instant::now();
    let n = 400;
    for case in 0..n {
        let sigma = 0.05 * 40f64.powf(rnd());
        let eta = 0.01 + 0.89 * rnd();
        let gamma = if rnd() < 0.3 {
            0.0
        } else {
            20.0 * rnd() * rnd()
        };
        let u0 = 8.0 * rnd();
        let dx = sigma / (10.0 + 40.0 * rnd());
        let domain = if rnd() < 0.3 {
            Domain::Walls {
                length: 1.0 + 10.0 * rnd(),
            }
        } else {
            Domain::Periodic { period: 1.0 }
        };
        let p = RodsProblem::new(sigma, eta / sigma, domain)
            .with_dx(dx)
            .with_interaction(RodInteraction::Sticky { gamma })
            .with_potential(BetaPotential::from_fn(1.0, move |x| {
                0.5 * u0 * (std::f64::consts::TAU * x).cos()
            }));
        let t = Instant::now();
        let state = format!(
            "sigma {sigma:.3} eta {eta:.3} gamma {gamma:.2} U0 {u0:.2} dx {dx:.2e} {domain:?}"
        );
        match equilibrium(&p) {
            Ok(_) => worst = worst.max(t.elapsed().as_secs_f64()),
            Err(RodsError::Param(e)) => {
                rejected += 1;
                println!("rejected {case}: {state}: {e}");
            }
            Err(e) => {
                failed += 1;
                println!("failed {case}: {state}: {e}");
            }
        }
    }
    println!(
        "{n} states: {} converged, {failed} not converged, {rejected} rejected; slowest converged \
         {worst:.2} s; total {:.1} s",
        n - failed - rejected,
        total.elapsed().as_secs_f64()
    );
}
