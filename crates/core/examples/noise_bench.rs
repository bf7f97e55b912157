//! Time the per-particle Gaussian noise kernels: `cargo run --release -p colloidsim-core
//! --example noise_bench -- [PARTICLES] [STEPS] [REPEATS]` (default 1e6 particles x 20 steps,
//! median of 7 repeats). Each block is drawn into a small buffer that stays in L1, as in the
//! engines; `black_box` keeps the buffer alive.
use colloidsim_core::rng::{BLOCK, WIDE, fill_normal_block_fast, fill_normal_wide};
use std::hint::black_box;
use std::time::Instant;

/// Median over `repeats` of the ns per deviate of filling `n` particles for `steps` steps in
/// blocks of `block` particles by `fill`.
fn time(
    n: usize,
    steps: u64,
    repeats: usize,
    block: usize,
    fill: fn(u32, u64, u64, &mut [f64]),
) -> f64 {
    let mut buf = vec![0.0f64; block];
    let mut ns: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            for step in 0..steps {
                for (b, lo) in (0..n).step_by(block).enumerate() {
                    let m = block.min(n - lo);
                    fill(7, step, b as u64, &mut buf[..m]);
                    black_box(&mut buf);
                }
            }
            t.elapsed().as_secs_f64() * 1e9 / (n as f64 * steps as f64)
        })
        .collect();
    ns.sort_by(f64::total_cmp);
    ns[repeats / 2]
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let n: usize = a.get(1).map_or(1_000_000, |s| s.parse().unwrap());
    let steps: u64 = a.get(2).map_or(20, |s| s.parse().unwrap());
    let repeats: usize = a.get(3).map_or(7, |s| s.parse().unwrap());
    // Warm up (tables, frequency).
    time(n, 2, 1, WIDE, fill_normal_wide);
    let old = time(n, steps, repeats, BLOCK, fill_normal_block_fast);
    let wide = time(n, steps, repeats, WIDE, fill_normal_wide);
    println!("{n} particles x {steps} steps, median of {repeats}:");
    println!("  fill_normal_block_fast ({BLOCK}-blocks): {old:.3} ns/deviate");
    println!(
        "  fill_normal_wide       ({WIDE}-blocks): {wide:.3} ns/deviate ({:.2}x)",
        old / wide
    );
}
