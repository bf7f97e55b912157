//! Quick throughput probe: `cargo run --release -p colloidsim-md --example bd_bench -- N STEPS THREADS`.
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let n: usize = a.get(1).map_or(25_000, |s| s.parse().unwrap());
    let steps: u64 = a.get(2).map_or(2000, |s| s.parse().unwrap());
    let threads: usize = a.get(3).map_or(1, |s| s.parse().unwrap());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut sim = colloidsim_md::bench::wca_periodic_skin(
            n,
            0.1,
            1e-4,
            1,
            std::env::var("SKIN").map_or(0.3, |s| s.parse().unwrap()),
        )
        .unwrap();
        sim.run(100).unwrap();
        let c0 = cpu();
        let t = std::time::Instant::now();
        sim.run(steps).unwrap();
        let s = t.elapsed().as_secs_f64();
        let c = cpu() - c0;
        println!("cpu-time rate {:.3e}", n as f64 * steps as f64 / c);
        let pos = sim.particles().pos.clone();
        let mut nl = colloidsim_md::NeighborList::new(2f64.powf(1.0 / 6.0), 0.3);
        let t2 = std::time::Instant::now();
        for _ in 0..50 {
            nl.build(&sim.sbox, &pos, sim.order()).unwrap();
        }
        println!(
            "build: {:.1} ns/particle",
            t2.elapsed().as_secs_f64() / 50.0 / n as f64 * 1e9
        );
        let t2 = std::time::Instant::now();
        for _ in 0..50 {
            nl.bin(&sim.sbox, &pos);
        }
        println!(
            "bin: {:.1} ns/particle",
            t2.elapsed().as_secs_f64() / 50.0 / n as f64 * 1e9
        );
        let nn: usize = (0..n).map(|i| nl.neighbors(i).len()).sum();
        println!("mean neighbours {}", nn as f64 / n as f64);
        println!(
            "{n} particles, {threads} threads: {:.3e} particle-steps/s, {} builds",
            n as f64 * steps as f64 / s,
            sim.neighbor_builds()
        );
    });
}

#[allow(dead_code)]
fn unused() {}

fn cpu() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap();
    let rest = &s[s.rfind(')').unwrap() + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    (f[11].parse::<f64>().unwrap() + f[12].parse::<f64>().unwrap()) / 100.0
}
