//! `colloidsim bench bcd`'s case for the three integrators: the fast-bcd scaling case (sigma = 0.99,
//! U0 = 6 kT, one rod per wavelength, dt = 1e-3, periodic, rods started on a lattice, 50 warm-up
//! steps, about `WORK` particle-steps per measurement), nanoseconds per particle-step, median of
//! `REPEATS`. The bench command lives in the CLI; this example runs the same engine and force
//! (`Field::new` of the cosine, as `colloidsim run` and the bench evaluate it) with
//! `Integrator::Euler`, `Integrator::Lm` and `Integrator::Reflect`, alternating them within each
//! repeat. Besides wall
//! time it reports the CPU time of the pool worker that runs the steps (with one thread, all of
//! the work), which time given to other processes on a shared machine does not inflate.
//!
//! `RAYON_NUM_THREADS=1 taskset -c 0 cargo run --release -p colloidsim-bcd --example
//! integrator_bench -- [N,N,..] [REPEATS] [WORK]` (default 10000,100000, 5, 2e7).
use colloidsim_bcd::forces::Field;
use colloidsim_bcd::forces::NoPair;
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Integrator, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};
use colloidsim_core::timing::thread_cpu_seconds;
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let ns: Vec<usize> = a.get(1).map_or(vec![10_000, 100_000], |s| {
        s.split(',').map(|v| v.parse().expect("N")).collect()
    });
    let repeats: usize = a.get(2).map_or(5, |s| s.parse().expect("REPEATS"));
    let work: u64 = a.get(3).map_or(20_000_000, |s| s.parse().expect("WORK"));
    let force = Field::new(&ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    });
    println!(
        "# integrator_bench: sigma = 0.99, U0 = 6 kT, rho = 1, dt = 1e-3, periodic; {} threads, median of {repeats}",
        rayon::current_num_threads()
    );
    println!("integrator\tN\tsteps\tns_per_particle_step\tmin\tmax\tcpu_ns_per_particle_step");
    for &n in &ns {
        let cfg = BcdConfig {
            length: n as f64,
            sigma: 0.99,
            mobility: 1.0,
            kt: 1.0,
            dt: 1e-3,
            boundary: Boundary::Periodic,
            seed: 1,
            update: Update::Premerge,
        };
        let steps = (work / n as u64).max(20);
        let x0 = init::lattice(&cfg, n).expect("lattice");
        let schemes = [Integrator::Euler, Integrator::Lm, Integrator::Reflect];
        let mut times = vec![Vec::new(); schemes.len()];
        let mut cpu = vec![Vec::new(); schemes.len()];
        for _ in 0..repeats.max(1) {
            for (k, &scheme) in schemes.iter().enumerate() {
                let mut b = Bcd::new(cfg.clone(), x0.clone(), force.clone(), NoPair)
                    .expect("engine")
                    .with_integrator(scheme);
                b.run(steps.min(50)).expect("warm-up");
                // Inside a scope the steps run on this pool worker, whose CPU time is read.
                let (wall, busy) = rayon::scope(|_| {
                    let (t, c) = (Instant::now(), thread_cpu_seconds());
                    b.run(steps).expect("run");
                    (t.elapsed().as_secs_f64(), thread_cpu_seconds() - c)
                });
                let per = 1e9 / (steps as f64 * n as f64);
                times[k].push(wall * per);
                cpu[k].push(busy * per);
            }
        }
        for (k, scheme) in schemes.iter().enumerate() {
            let t = &mut times[k];
            t.sort_by(f64::total_cmp);
            cpu[k].sort_by(f64::total_cmp);
            println!(
                "{scheme:?}\t{n}\t{steps}\t{:.2}\t{:.2}\t{:.2}\t{:.2}",
                t[t.len() / 2],
                t[0],
                t[t.len() - 1],
                cpu[k][cpu[k].len() / 2]
            );
        }
    }
}
