//! Quick timing of the direct product: `cargo run --release -p colloidsim-hydro --example
//! direct_bench -- N THREADS`.

use colloidsim_hydro::bench::{box_edge, random_system, time_direct};

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let (n, t) = (
        args.first().copied().unwrap_or(2000),
        args.get(1).copied().unwrap_or(1),
    );
    let (p, f) = random_system(n, box_edge(n, 0.1), 1);
    let (timing, _) = time_direct(&p, &f, t, 5);
    println!("{timing:?}");
}
