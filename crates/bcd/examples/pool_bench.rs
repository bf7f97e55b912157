//! Time the pooling kernel of the premerged ring step on its own: `cargo run --release -p
//! colloidsim-bcd --example pool_bench -- [SAMPLES] [REPEATS]` (default 64 chunks of 4096
//! rods, median and minimum of 9 repeats of 200 passes, thread CPU time, in ns per rod).
//!
//! The free end-of-step positions come from a small stand-alone BCD of one chunk between
//! walls in the benchmark case (sigma = 0.99, density 1, U0 = 6 kT, wavelength 1, dt = 1e-3,
//! D = 1), run 300 steps before the samples are taken (then one every 10 steps), so that the
//! pooling sees the clusters of the real run. The noise is Box–Muller on a cheap LCG: this
//! is a timing harness, not a simulation.
use colloidsim_bcd::PoolBench;
use colloidsim_core::timing::thread_cpu_seconds;
use std::f64::consts::PI;
use std::hint::black_box;

const RODS: usize = 4096;
/// Passes over the samples per timing (the thread clock ticks in milliseconds).
const SWEEPS: usize = 200;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let samples: usize = a.get(1).map_or(64, |s| s.parse().unwrap());
    let repeats: usize = a.get(2).map_or(9, |s| s.parse().unwrap());
    let zs = sample_free_positions(samples);
    let mut pb = PoolBench::default();
    let blocks: usize = zs.iter().map(|z| pb.pool(z).len()).sum();
    let mut ns: Vec<f64> = (0..repeats + 1)
        .map(|_| {
            let t = thread_cpu_seconds();
            for _ in 0..SWEEPS {
                for z in &zs {
                    black_box(pb.pool(black_box(z)));
                }
            }
            (thread_cpu_seconds() - t) * 1e9 / (SWEEPS * samples * RODS) as f64
        })
        .skip(1)
        .collect();
    ns.sort_by(f64::total_cmp);
    println!(
        "pooling: {:.2} ns per rod (median of {repeats}; min {:.2}), {:.3} blocks per rod",
        ns[ns.len() / 2],
        ns[0],
        blocks as f64 / (samples * RODS) as f64
    );
}

/// `samples` arrays of free end-of-step positions `z` (relative to the first rod) of a chunk.
fn sample_free_positions(samples: usize) -> Vec<Vec<f64>> {
    let (sigma, dt, u0): (f64, f64, f64) = (0.99, 1e-3, 6.0);
    let amp = (2.0 / dt).sqrt();
    let mut lcg = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = move || {
        lcg = lcg
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((lcg >> 11) + 1) as f64 / (1u64 << 53) as f64
    };
    let mut y: Vec<f64> = (0..RODS).map(|i| i as f64 * (1.0 - sigma)).collect();
    let mut z = vec![0.0; RODS];
    let mut pb = PoolBench::default();
    let mut out = Vec::new();
    for step in 0..300 + 10 * samples {
        for (i, (zi, &yi)) in z.iter_mut().zip(&y).enumerate() {
            let x = yi + i as f64 * sigma;
            let g = (-2.0 * uniform().ln()).sqrt() * (2.0 * PI * uniform()).cos();
            *zi = (yi - y[0]) + (u0 * PI * (2.0 * PI * x).sin() + amp * g) * dt;
        }
        if step >= 300 && (step - 300) % 10 == 0 {
            out.push(z.clone());
        }
        let y0 = y[0];
        let mut at = 0;
        for b in pb.pool(&z) {
            let n = b[1] as usize;
            y[at..at + n].fill(y0 + b[0] / b[1]);
            at += n;
        }
    }
    out
}
