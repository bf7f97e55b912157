//! A bidisperse drying droplet with the radial mixture DDFT (docs/theory-droplet.md, "Mixtures";
//! the run: docs/reports/theory-droplet-validation.md, "A bidisperse drying run").
//!
//! `cargo run --release -p colloidsim-dft --example binary_drying -- [free-draining|rpy] [white-bear|rosenfeld] [dr]`
//!
//! Size ratio 2 (d_s = 1, d_l = 2), R0 = 25 d_s, phi_s0 = phi_l0 = 0.05 (N_s = 6250,
//! N_l = 781.25), Stokes D0 (D0_s = 1), Pe_s = 10, dried to mean phi 0.5; each species' interface
//! at `R - d/2` with stiffness `50 d^2` kT/d_s^2 and range d_s/2. Prints, at 25 / 50 /
//! 75 / 100 % of the drying time, the mean radius of each species over R(t), the small
//! species' share of the particle volume in the outer shell `r > R - 2 d_l` relative to its
//! share overall (> 1: small-on-top), and the wall time.

use std::f64::consts::PI;
use std::time::Instant;

use colloidsim_dft::radial::mixture::{Functional, MixtureSetup, Species, run_mixture_droplet};
use colloidsim_dft::radial::{
    DryingSchedule, EquilibriumOptions, HarmonicInterface, Hydrodynamics, RadialError,
};

fn main() -> Result<(), RadialError> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let hydro = match args.first().map(String::as_str) {
        Some("rpy") => Hydrodynamics::Rpy,
        _ => Hydrodynamics::FreeDraining,
    };
    let functional = match args.get(1).map(String::as_str) {
        Some("rosenfeld") => Functional::Rosenfeld,
        _ => Functional::WhiteBear,
    };
    let dr: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.02);
    let (kt, eta) = (1.0, 1.0 / (3.0 * PI));
    let (r0, phi_s, phi_l, phi_end, pe) = (25.0f64, 0.05, 0.05, 0.5, 10.0);
    // Stiffness k d^2 (50 kT/d_s^2 for the small ones): the same penetration under a pressure.
    let wall = |d: f64| HarmonicInterface::new(50.0 * d * d, 0.5, -0.5 * d);
    let small = Species::stokes(1.0, 8.0 * phi_s * r0.powi(3), kt, eta, wall(1.0)?)?;
    let large = Species::stokes(2.0, 8.0 * phi_l * (r0 / 2.0).powi(3), kt, eta, wall(2.0)?)?;
    let schedule = DryingSchedule::from_peclet(r0, pe, small.d0)?;
    let r_end = r0 * ((phi_s + phi_l) / phi_end).cbrt();
    let setup = MixtureSetup {
        species: vec![small, large],
        r0,
        alpha: schedule.alpha,
        t_end: schedule.time_at_radius(r_end),
        dr,
        functional,
        hydrodynamics: hydro,
        pair: Default::default(),
    };
    println!(
        "N_s = {}, N_l = {}, phi0 = {}, Pe_s = {pe}, Pe_l = {}, {hydro:?}, {functional:?}, dr = {dr}, t_end = {:.4} d_s^2/D0_s",
        small.particles,
        large.particles,
        phi_s + phi_l,
        pe * small.d0 / large.d0,
        setup.t_end
    );
    let fractions = [0.25, 0.5, 0.75, 1.0];
    let times: Vec<f64> = fractions.iter().map(|f| f * setup.t_end).collect();
    let start = Instant::now();
    let mut k = 0;
    let result = run_mixture_droplet(
        &setup,
        &times,
        &setup.ddft_options(),
        &EquilibriumOptions::default(),
        |grid, snap| {
            // Particle volume of each species in the outer shell and overall.
            let v = grid.volumes();
            let cut = snap.radius - 2.0 * large.diameter;
            let share = |outer: bool| {
                let vol = |s: usize, d: f64| -> f64 {
                    (0..grid.len())
                        .filter(|&i| !outer || grid.centres()[i] > cut)
                        .map(|i| v[i] * snap.rho[s][i])
                        .sum::<f64>()
                        * PI
                        * d.powi(3)
                        / 6.0
                };
                let (a, b) = (vol(0, 1.0), vol(1, 2.0));
                a / (a + b)
            };
            let peak = |s: usize| snap.n3_species[s].iter().cloned().fold(0.0, f64::max);
            println!(
                "{:>4.0} %  R = {:.3}  <r>_s/R = {:.4}  <r>_l/R = {:.4}  outer-shell small share / mean = {:.4}  peak n3_s = {:.3}  peak n3_l = {:.3}  max n3 = {:.3}  ({:.1} s)",
                100.0 * fractions[k],
                snap.radius,
                snap.mean_radius[0] / snap.radius,
                snap.mean_radius[1] / snap.radius,
                share(true) / share(false),
                peak(0),
                peak(1),
                snap.n3.iter().cloned().fold(0.0, f64::max),
                start.elapsed().as_secs_f64()
            );
            k += 1;
        },
        |_| {},
    );
    match result {
        Ok(o) => println!(
            "done: {} steps, {} iterations, {} cells, drift {:?}, wall {:.2} s",
            o.steps,
            o.iterations,
            o.cells,
            o.particle_drift,
            start.elapsed().as_secs_f64()
        ),
        Err(e) => println!("stopped after {:.2} s: {e}", start.elapsed().as_secs_f64()),
    }
    Ok(())
}
