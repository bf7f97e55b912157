//! When does the RPY DDFT of a drying droplet fail, and how does that depend on the pair
//! correlation of its two-body density (docs/theory-droplet.md, "Beyond the dilute pair
//! correlation")?
//!
//! `cargo run --release -p colloidsim-dft --example pair_sensitivity -- [r0 dr phi0 phi_end pe]`
//! (defaults `25 0.02 0.05 0.5 10`: the paper's droplet, lengths in d). For the dilute `g` and
//! for Trokhymchuk's `g` with several tabulation ranges and clamps it prints the fraction of the
//! drying time at which particles are ejected (or "completed"), the mean volume fraction then,
//! the largest local packing fraction `n3` at the last 1 % snapshot before, and the wall time.

use std::time::Instant;

use colloidsim_dft::radial::{
    DdftOptions, DropletSetup, DryingSchedule, EquilibriumOptions, HarmonicInterface,
    Hydrodynamics, PairCorrelation, PairTable, RadialError, pair::ETA_FIT_MAX, run_droplet,
};

fn main() {
    let defaults = [25.0, 0.02, 0.05, 0.5, 10.0];
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("numeric arguments"))
        .collect();
    let arg = |i: usize| args.get(i).copied().unwrap_or(defaults[i]);
    let (r0, dr, phi0, phi_end, pe) = (arg(0), arg(1), arg(2), arg(3), arg(4));
    let d0 = 1.0;
    let schedule = DryingSchedule::from_peclet(r0, pe, d0).expect("schedule");
    let r_end = r0 * (phi0 / phi_end).cbrt();
    let t_end = schedule.time_at_radius(r_end);
    let table = |range: f64, eta_max: f64| PairTable { range, eta_max };
    let configs = [
        ("dilute", PairCorrelation::Dilute, PairTable::default()),
        (
            "trokhymchuk (default: range 8 d, clamp 0.6)",
            PairCorrelation::Trokhymchuk,
            PairTable::default(),
        ),
        (
            "trokhymchuk range 8 d, clamp 0.471",
            PairCorrelation::Trokhymchuk,
            table(8.0, ETA_FIT_MAX),
        ),
        (
            "trokhymchuk range 3 d, clamp 0.6",
            PairCorrelation::Trokhymchuk,
            table(3.0, 0.6),
        ),
        (
            "trokhymchuk range 2 d, clamp 0.6",
            PairCorrelation::Trokhymchuk,
            table(2.0, 0.6),
        ),
        (
            "trokhymchuk range 2 d, clamp 0.471",
            PairCorrelation::Trokhymchuk,
            table(2.0, ETA_FIT_MAX),
        ),
        (
            "trokhymchuk-n3 (range 8 d, clamp 0.6)",
            PairCorrelation::TrokhymchukWeighted,
            PairTable::default(),
        ),
    ];
    println!(
        "R0 = {r0} d, dr = {dr} d, phi {phi0} -> {phi_end}, Pe = {pe}, t_end = {t_end:.3} d^2/D0"
    );
    for (name, pair, table) in configs {
        let setup = DropletSetup {
            particles: 8.0 * phi0 * r0.powi(3),
            diameter: 1.0,
            d0,
            r0,
            alpha: schedule.alpha,
            interface: HarmonicInterface::new(50.0, 0.5, -0.5).expect("interface"),
            t_end,
            dr,
            hydrodynamics: Hydrodynamics::Rpy,
            pair,
        };
        let mut opts = DdftOptions::new(d0, 1.0);
        opts.pair_table = table;
        let times: Vec<f64> = (1..=100).map(|k| k as f64 / 100.0 * t_end).collect();
        let start = Instant::now();
        let mut last = (0.0, 0.0);
        let out = run_droplet(
            &setup,
            &times,
            &opts,
            &EquilibriumOptions::default(),
            |_, s| last = (s.time, s.n3.iter().cloned().fold(0.0, f64::max)),
            |_| {},
        );
        let wall = start.elapsed().as_secs_f64();
        let mean_phi = |t: f64| phi0 * (r0 / schedule.radius(t).expect("radius")).powi(3);
        match out {
            Ok(_) => println!(
                "{name}: completed; mean phi {:.3}, max n3 at the end {:.3} ({wall:.1} s)",
                mean_phi(t_end),
                last.1
            ),
            Err(RadialError::Unphysical { time, message }) => println!(
                "{name}: unphysical at {:.1} % of the drying time (mean phi {:.3}; max n3 {:.3} at {:.0} %) ({wall:.1} s): {message}",
                100.0 * time / t_end,
                mean_phi(time),
                last.1,
                100.0 * last.0 / t_end
            ),
            Err(e) => println!("{name}: failed: {e} ({wall:.1} s)"),
        }
    }
}
