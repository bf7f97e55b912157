//! Metropolis Monte Carlo of hard rods on a ring in `U = (U0 / 2) cos(2 pi x / lambda)` (the
//! `cosine` field of amplitude U0): the
//! two-particle density at contact `rho2(x, x + sigma + g)` against the gap `g`, with no time
//! step, as an independent check of the exact theory (hard-rods paper Eq. 24) and of BCD's
//! window estimator (Eq. 27). Canonical ensemble (N rods fixed).
//!
//! `cargo run --release -p colloidsim-bcd --example contact_density_mc -- N L U0 SWEEPS SEED`
//! prints, per gap bin of width 0.0025, the contact density pooled over one period
//! (`(1/lambda) int rho2(x, x + sigma + g) dx`, with its block error) and, per x bin (50), the
//! density and the contact density extrapolated to `g = 0` from the first gap bins.

use rand::{RngExt, SeedableRng, rngs::StdRng};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: f64| a.get(i).map_or(d, |s| s.parse().unwrap());
    let n = arg(1, 50.0) as usize;
    let length = arg(2, 100.0);
    let u0 = arg(3, 1.0);
    let sweeps = arg(4, 1e6) as u64;
    let seed = arg(5, 1.0) as u64;
    let (sigma, lambda) = (0.5, 1.0);
    let (xbins, gbins, dg) = (50usize, 16usize, 0.0025);
    let blocks = 20u64;
    let mut rng = StdRng::seed_from_u64(seed);
    let u = |x: f64| 0.5 * u0 * (2.0 * std::f64::consts::PI * x / lambda).cos();
    let mut x: Vec<f64> = (0..n).map(|i| i as f64 * length / n as f64).collect();
    let step = 0.25;
    // Equilibrate.
    for _ in 0..(sweeps / 20).max(1000) * n as u64 {
        mc_move(&mut x, &mut rng, n, length, sigma, step, &u);
    }
    let mut hist = vec![0u64; xbins * gbins];
    let mut dens = vec![0u64; xbins];
    let mut pooled_blocks = vec![vec![0u64; gbins]; blocks as usize];
    let per_block = sweeps / blocks;
    let mut accepted = 0u64;
    for s in 0..per_block * blocks {
        for _ in 0..n {
            accepted += mc_move(&mut x, &mut rng, n, length, sigma, step, &u) as u64;
        }
        let b = (s / per_block) as usize;
        for i in 0..n {
            let right = if i + 1 < n { x[i + 1] } else { x[0] + length };
            let f = x[i].rem_euclid(lambda) / lambda;
            let xb = ((f * xbins as f64) as usize).min(xbins - 1);
            dens[xb] += 1;
            let g = right - x[i] - sigma;
            if g < dg * gbins as f64 {
                let gb = (g / dg) as usize;
                hist[xb * gbins + gb] += 1;
                pooled_blocks[b][gb] += 1;
            }
        }
    }
    let total = per_block * blocks;
    let periods = length / lambda;
    let dx = lambda / xbins as f64;
    eprintln!(
        "acceptance {:.3}",
        accepted as f64 / (total * n as u64) as f64
    );
    println!("# pooled over one period: g_mid, rho2, err");
    for gb in 0..gbins {
        let vals: Vec<f64> = pooled_blocks
            .iter()
            .map(|c| c[gb] as f64 / (per_block as f64 * dg * periods * lambda))
            .collect();
        let m = vals.iter().sum::<f64>() / vals.len() as f64;
        let var = vals.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (vals.len() - 1) as f64;
        println!(
            "{:.5} {:.6} {:.6}",
            (gb as f64 + 0.5) * dg,
            m,
            (var / vals.len() as f64).sqrt()
        );
    }
    println!(
        "# per x bin: x, rho, rho2 in the first gap bin, rho2 over the first 2, over the first 4"
    );
    for xb in 0..xbins {
        let norm = total as f64 * dx * periods;
        let h = &hist[xb * gbins..(xb + 1) * gbins];
        println!(
            "{:.4} {:.6} {:.6} {:.6} {:.6}",
            (xb as f64 + 0.5) * dx,
            dens[xb] as f64 / norm,
            h[0] as f64 / (norm * dg),
            (h[0] + h[1]) as f64 / (norm * 2.0 * dg),
            h[..4].iter().sum::<u64>() as f64 / (norm * 4.0 * dg),
        );
    }
}

/// One Metropolis move of a random rod; true when accepted.
fn mc_move(
    x: &mut [f64],
    rng: &mut StdRng,
    n: usize,
    length: f64,
    sigma: f64,
    step: f64,
    u: &impl Fn(f64) -> f64,
) -> bool {
    let i = rng.random_range(0..n);
    let new = x[i] + step * (2.0 * rng.random::<f64>() - 1.0);
    let left = if i > 0 { x[i - 1] } else { x[n - 1] - length };
    let right = if i + 1 < n { x[i + 1] } else { x[0] + length };
    if new - left < sigma || right - new < sigma {
        return false;
    }
    let du = u(new) - u(x[i]);
    if du > 0.0 && rng.random::<f64>() >= (-du).exp() {
        return false;
    }
    // No wrapping: the neighbours' images keep x[0] < ... < x[n-1] < x[0] + L.
    x[i] = new;
    true
}
