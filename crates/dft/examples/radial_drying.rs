//! Benchmark of the radial DDFT: a full free-draining drying run.
//!
//! `cargo run --release -p colloidsim-dft --example radial_drying -- [r0 dr phi0 phi_end pe dt_max repeats]`
//! (defaults `25 0.01 0.05 0.5 10 0.01 5`, lengths in d, times in d^2/D0). Prints the wall time of
//! each repeat and the median, the steps and fixed-point iterations, and the largest `n3` at the end.

use std::time::Instant;

use colloidsim_dft::radial::{
    DdftOptions, DropletSetup, DryingSchedule, EquilibriumOptions, HarmonicInterface,
    Hydrodynamics, run_droplet,
};

fn main() {
    let defaults = [25.0, 0.01, 0.05, 0.5, 10.0, 0.01, 5.0];
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("numeric arguments"))
        .collect();
    let arg = |i: usize| args.get(i).copied().unwrap_or(defaults[i]);
    let (r0, dr, phi0, phi_end, pe, dt_max, repeats) = (
        arg(0),
        arg(1),
        arg(2),
        arg(3),
        arg(4),
        arg(5),
        arg(6) as usize,
    );
    let d0 = 1.0;
    let schedule = DryingSchedule::from_peclet(r0, pe, d0).expect("schedule");
    let r_end = r0 * (phi0 / phi_end).cbrt();
    let setup = DropletSetup {
        particles: 8.0 * phi0 * r0.powi(3),
        diameter: 1.0,
        d0,
        r0,
        alpha: schedule.alpha,
        interface: HarmonicInterface::new(50.0, 0.5, -0.5).expect("interface"),
        t_end: schedule.time_at_radius(r_end),
        dr,
        hydrodynamics: Hydrodynamics::FreeDraining,
        pair: Default::default(),
    };
    let mut opts = DdftOptions::new(d0, 1.0);
    opts.dt_max = dt_max;
    let times: Vec<f64> = [0.25, 0.5, 0.75, 1.0]
        .iter()
        .map(|f| f * setup.t_end)
        .collect();
    let mut walls = Vec::new();
    for rep in 0..repeats {
        let start = Instant::now();
        let mut n3max = 0.0f64;
        let out = run_droplet(
            &setup,
            &times,
            &opts,
            &EquilibriumOptions::default(),
            |_, s| n3max = s.n3.iter().cloned().fold(0.0, f64::max),
            |_| {},
        )
        .expect("run");
        let wall = start.elapsed().as_secs_f64();
        walls.push(wall);
        println!(
            "run {rep}: {wall:.3} s, cells {}, steps {}, iterations {}, N drift {:.1e}, max n3 at end {n3max:.4}",
            out.cells, out.steps, out.iterations, out.particle_drift
        );
    }
    walls.sort_by(f64::total_cmp);
    println!(
        "median wall time {:.3} s over {repeats} runs (R0 = {r0} d, dr = {dr} d, phi {phi0} -> {phi_end}, Pe = {pe}, dt_max = {dt_max} d^2/D0, t_end = {:.4} d^2/D0)",
        walls[walls.len() / 2],
        setup.t_end
    );
}
