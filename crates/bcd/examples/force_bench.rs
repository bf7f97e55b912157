//! Time the batched external forces `ForceTable::force_block` and `CosineForce::force_block`: `cargo run --release -p
//! colloidsim-bcd --example force_bench -- [RODS] [STEPS] [REPEATS]` (default 1e6 rods in
//! blocks of 256, 20 sweeps, median and minimum of 7 repeats of thread CPU time). The rods sit in order on a ring of 1e6 rod
//! lengths under a cosine field of period 1 (the table has 1024 cells); the result goes to a
//! small buffer kept alive by `black_box`, as in the engine.
use colloidsim_bcd::forces::{CosineForce, ExternalForce, ForceTable};
use colloidsim_core::field1d::{ExternalField, FieldTerm};
use colloidsim_core::timing::thread_cpu_seconds;
use std::hint::black_box;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let n: usize = a.get(1).map_or(1_000_000, |s| s.parse().unwrap());
    let steps: usize = a.get(2).map_or(20, |s| s.parse().unwrap());
    let repeats: usize = a.get(3).map_or(7, |s| s.parse().unwrap());
    let field = ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.3,
    };
    let table = ForceTable::from_field(&field).unwrap();
    // Ordered positions with a little disorder (a cheap LCG; no need for the keyed streams).
    let mut state = 12345u64;
    let x: Vec<f64> = (0..n)
        .map(|i| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            i as f64 + 0.5 * (state >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect();
    let cosine = CosineForce::from_field(&field).unwrap();
    time("ForceTable", &table, &x, steps, repeats);
    time("CosineForce", &cosine, &x, steps, repeats);
}

fn time<F: ExternalForce>(name: &str, force: &F, x: &[f64], steps: usize, repeats: usize) {
    let n = x.len();
    let mut buf = [0.0f64; 256];
    let mut ns: Vec<f64> = (0..repeats + 1)
        .map(|_| {
            let t = thread_cpu_seconds();
            for step in 0..steps {
                let offset = if step % 2 == 1 { -(n as f64) } else { 0.0 };
                for xs in x.chunks(256) {
                    let out = &mut buf[..xs.len()];
                    force.force_block(black_box(xs), offset, out);
                    black_box(&mut *out);
                }
            }
            (thread_cpu_seconds() - t) * 1e9 / (n * steps) as f64
        })
        .skip(1)
        .collect();
    ns.sort_by(f64::total_cmp);
    println!(
        "{n} rods x {steps} sweeps, median (min) of {repeats}: {name}::force_block {:.3} ({:.3}) ns/rod (thread CPU time)",
        ns[repeats / 2],
        ns[0]
    );
}
