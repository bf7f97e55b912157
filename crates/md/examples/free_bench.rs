//! Cost of a step without pair forces (noise + integration only).
use colloidsim_md::*;
fn main() {
    let n = 25000;
    let sbox = SimBox::cube(50.8);
    let pos = init::random_in_box(n, 1.0, &sbox, 1, 0).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let mut sim = Brownian::new(
            Particles::monodisperse(pos, 1.0),
            sbox,
            NoPair,
            NoExternal,
            BdParams::new(1e-4, 1),
            0,
        )
        .unwrap();
        sim.run(10).unwrap();
        let t = std::time::Instant::now();
        sim.run(2000).unwrap();
        println!(
            "free: {:.1} ns per particle-step",
            t.elapsed().as_secs_f64() / (n as f64 * 2000.0) * 1e9
        );
    });
}
