//! Quick timing of PSE: `cargo run --release -p colloidsim-hydro --example pse_bench -- N
//! THREADS REPEATS`.

use colloidsim_hydro::bench::time_pse;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let n = args.first().copied().unwrap_or(25_000);
    let t = args.get(1).copied().unwrap_or(1);
    let r = args.get(2).copied().unwrap_or(3);
    let p = time_pse(n, 0.1, 1e-3, t, r).unwrap();
    println!("{p:#?}");
}
