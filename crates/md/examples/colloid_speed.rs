//! Cost of the discrete-particle colloids in a coupled MPCD step (a development benchmark, not
//! a test): `colloid_speed [L] [N] [D] [STEPS]` (defaults 16, 1, 4, 2000) runs the standard
//! solvent in a periodic cube of `L` cells with `N` random colloids of diameter `D` (default
//! colloid parameters: 50 Verlet steps per collision) for 100 warm-up and `STEPS` timed
//! collisions on `RAYON_NUM_THREADS` threads, and prints the wall time per collision of the
//! solvent's streaming, the colloids' MD and the collision (with the vertices embedded), and the
//! colloid MD per colloid and Verlet step. Build with `--release`.
use colloidsim_md::SimBox;
use colloidsim_md::mpcd::{
    Acceleration, ColloidParams, Confinement, DiscreteColloids, MpcdSystem, Region, Srd, SrdParams,
};
use colloidsim_md::potential::NoExternal;
use std::time::Instant;

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("numbers: L N D STEPS"))
        .collect();
    let arg = |i: usize, v: f64| args.get(i).copied().unwrap_or(v);
    let (l, n, d, steps) = (
        arg(0, 16.0),
        arg(1, 1.0) as usize,
        arg(2, 4.0),
        arg(3, 2000.0) as u64,
    );
    let p = SrdParams::standard(1);
    let sbox = SimBox::cube(l);
    let srd = Srd::new(p, sbox, &Confinement::None, 0.0).expect("solvent");
    let cp = ColloidParams::standard(d, p.kt);
    let c = DiscreteColloids::random(cp, sbox, n, Region::Box, p.kt, 1).expect("colloids");
    let mut sys = MpcdSystem::new(srd, c, Confinement::None, None).expect("system");
    for _ in 0..100 {
        sys.step(&Acceleration::None).expect("step");
    }
    let mut t = [0.0f64; 3];
    for _ in 0..steps {
        let t0 = sys.time();
        let clock = Instant::now();
        sys.srd
            .stream(t0 + p.tau, &Confinement::None, &Acceleration::None)
            .expect("stream");
        t[0] += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        sys.colloids
            .advance(t0, p.tau, &NoExternal)
            .expect("colloid MD");
        t[1] += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        sys.collide();
        t[2] += clock.elapsed().as_secs_f64();
    }
    let per = |x: f64| 1e3 * x / steps as f64;
    println!(
        "L {l}, {} solvent, {n} colloids of d {d}, {steps} collisions on {} threads: ms per collision: stream {:.3}, colloid MD {:.3}, collide {:.3}; colloid MD {:.1} ns per colloid and Verlet step",
        sys.srd.len(),
        rayon::current_num_threads(),
        per(t[0]),
        per(t[1]),
        per(t[2]),
        1e9 * t[1] / (steps as f64 * n.max(1) as f64 * cp.md_steps as f64)
    );
}
