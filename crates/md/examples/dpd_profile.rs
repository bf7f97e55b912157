//! Profile the DPD engine on DPD water: `cargo run --release -p colloidsim-md --example
//! dpd_profile -- L STEPS SKIN` (density 3, kT = 1, dt = 0.04, a lattice start relaxed for 100 steps).
use colloidsim_md::SimBox;
use colloidsim_md::dpd::DpdParams;
use colloidsim_md::dpd::setup::{DpdSetup, RadiusDistribution};
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let l: f64 = a.get(1).map_or(20.0, |s| s.parse().unwrap());
    let steps: u64 = a.get(2).map_or(200, |s| s.parse().unwrap());
    let skin: f64 = a.get(3).map_or(0.4, |s| s.parse().unwrap());
    let params = DpdParams {
        skin,
        ..DpdParams::water(0.04, 1)
    };
    let setup = DpdSetup {
        params,
        sbox: SimBox::new([l; 3]),
        colloids: 0,
        solvent: (3.0 * l * l * l).round() as usize,
        radius: 1.0,
        distribution: RadiusDistribution::Monodisperse,
        density: 3.0,
        solvent_mass: 1.0,
        d0: f64::NAN,
        tau: f64::NAN,
    };
    let mut sim = setup.build().unwrap();
    sim.run(100).unwrap();
    let b0 = sim.neighbor_builds();
    let t = Instant::now();
    sim.run(steps).unwrap();
    let s = t.elapsed().as_secs_f64();
    println!(
        "N = {}, {steps} steps, skin {skin}: {:.3e} particle-steps/s, {:.2} steps per build, T = {:.4}",
        sim.len(),
        sim.len() as f64 * steps as f64 / s,
        steps as f64 / (sim.neighbor_builds() - b0) as f64,
        sim.thermo().temperature
    );
}
