//! Metropolis Monte Carlo of sticky rods on a ring in `U = (U0 / 2) cos(2 pi x)`
//! ([`colloidsim_bcd::mc::StickyRing`]): the density profile without a time step, as an
//! independent check of BCD and of the exact theory for strongly sticky dense rods (hard-rods
//! paper Fig. 6).
//!
//! `cargo run --release -p colloidsim-bcd --example sticky_profile_mc -- N L U0 SIGMA GAMMA EPS SWEEPS SEED BINS [FINAL]`
//! prints `x,rho,err` on BINS (default 50) bins over one period (errors from 20 blocks), after
//! SWEEPS / 4 sweeps of equilibration. `scripts/sticky_profiles_mc.py` runs it for the panels
//! of Fig. 6. With FINAL, the last configuration is written there as a CSV column `x` (a BCD
//! scenario's `initial.file`). On stderr: the pairs closer than `sigma + eps` per rod.

use colloidsim_bcd::mc::StickyRing;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: f64| a.get(i).map_or(d, |s| s.parse().unwrap());
    let n = arg(1, 80.0) as usize;
    let length = arg(2, 100.0);
    let u0 = arg(3, 6.0);
    let sigma = arg(4, 0.8);
    let gamma = arg(5, 10.0);
    let eps = arg(6, 0.05);
    let sweeps = arg(7, 1e6) as u64;
    let seed = arg(8, 1.0) as u64;
    let bins = arg(9, 50.0) as usize;
    let mut ring = StickyRing::new(n, length, u0, sigma, gamma, eps, seed);
    for _ in 0..sweeps / 4 {
        ring.sweep();
    }
    let blocks = 20u64;
    let per_block = sweeps / blocks;
    let mut profiles = vec![vec![0.0; bins]; blocks as usize];
    let mut bound = vec![0.0; blocks as usize];
    for (p, bound) in profiles.iter_mut().zip(bound.iter_mut()) {
        for _ in 0..per_block {
            ring.sweep();
            ring.histogram(p);
            *bound += ring.pairs_within(eps) as f64 / (n as f64 * per_block as f64);
        }
        let norm = per_block as f64 * length / bins as f64;
        p.iter_mut().for_each(|v| *v /= norm);
    }
    if let Some(path) = a.get(10) {
        let mut text = String::from("x\n");
        for x in &ring.x {
            text.push_str(&format!("{}\n", x.rem_euclid(length)));
        }
        std::fs::write(path, text).expect("final configuration");
    }
    let m = bound.iter().sum::<f64>() / bound.len() as f64;
    let var = bound.iter().map(|b| (b - m).powi(2)).sum::<f64>() / (bound.len() - 1) as f64;
    eprintln!(
        "pairs closer than sigma + eps, per rod: {m:.5} +- {:.5}",
        (var / bound.len() as f64).sqrt()
    );
    println!("x,rho,err");
    for b in 0..bins {
        let v: Vec<f64> = profiles.iter().map(|p| p[b]).collect();
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
        println!(
            "{},{m},{}",
            (b as f64 + 0.5) / bins as f64,
            (var / v.len() as f64).sqrt()
        );
    }
}
