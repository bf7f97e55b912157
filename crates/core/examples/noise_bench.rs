//! Time the per-particle Gaussian noise kernels: `cargo run --release -p colloidsim-core
//! --example noise_bench -- [PARTICLES] [STEPS] [REPEATS]` (default 1e6 particles x 20 steps,
//! 11 repeats of thread CPU time; the kernels alternate so that both see the same machine load). Each block is
//! drawn into a small buffer that stays in L1, as in the engines; `black_box` keeps it alive.
use colloidsim_core::rng::{BLOCK, WIDE, fill_normal_block_fast, fill_normal_wide};
use colloidsim_core::timing::thread_cpu_seconds;
use std::hint::black_box;

type Fill = fn(u32, u64, u64, &mut [f64]);

/// ns per deviate (of thread CPU time) of filling `n` particles for `steps` steps in blocks
/// of `block` by `fill`.
fn time(n: usize, steps: u64, block: usize, fill: Fill) -> f64 {
    let mut buf = vec![0.0f64; block];
    let t = thread_cpu_seconds();
    for step in 0..steps {
        for (b, lo) in (0..n).step_by(block).enumerate() {
            let m = block.min(n - lo);
            fill(7, step, b as u64, &mut buf[..m]);
            black_box(&mut buf);
        }
    }
    (thread_cpu_seconds() - t) * 1e9 / (n as f64 * steps as f64)
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let n: usize = a.get(1).map_or(1_000_000, |s| s.parse().unwrap());
    let steps: u64 = a.get(2).map_or(20, |s| s.parse().unwrap());
    let repeats: usize = a.get(3).map_or(11, |s| s.parse().unwrap());
    let kernels: [(&str, usize, Fill); 2] = [
        ("fill_normal_block_fast", BLOCK, fill_normal_block_fast),
        ("fill_normal_wide", WIDE, fill_normal_wide),
    ];
    // Warm up (tables, frequency).
    time(n, 2, WIDE, fill_normal_wide);
    let mut ns = vec![Vec::new(); kernels.len()];
    for _ in 0..repeats {
        for (t, &(_, block, fill)) in ns.iter_mut().zip(&kernels) {
            t.push(time(n, steps, block, fill));
        }
    }
    println!("{n} particles x {steps} steps, median (min) of {repeats}:");
    for (t, (name, block, _)) in ns.iter_mut().zip(&kernels) {
        t.sort_by(f64::total_cmp);
        println!(
            "  {name:<22} ({block:>3}-blocks): {:.3} ({:.3}) ns/deviate",
            t[repeats / 2],
            t[0]
        );
    }
}
