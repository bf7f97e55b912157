//! Time per rod of each observer of the main example, on a 10^4-rod ring after equilibration:
//! `cargo run --release -p colloidsim-bcd --example observer_bench` (wall time, median of
//! 7 rounds of 500 samples; compare with `colloidsim bench bcd`'s ns per particle-step).

use colloidsim_bcd::forces::Field;
use colloidsim_bcd::forces::NoPair;
use colloidsim_bcd::observe::{ClusterSizes, DensityProfile};
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};
use std::time::Instant;

fn main() {
    let n = 10_000;
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
    let field = Field::new(&ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    });
    let mut b = Bcd::new(
        cfg.clone(),
        init::random(&cfg, n, 1).unwrap(),
        field,
        NoPair,
    )
    .unwrap();
    b.run(200).unwrap();
    let reps = 500;
    let time = |f: &mut dyn FnMut()| {
        let mut v: Vec<f64> = (0..7)
            .map(|_| {
                let t = Instant::now();
                for _ in 0..reps {
                    f();
                }
                t.elapsed().as_secs_f64() * 1e9 / (reps * n) as f64
            })
            .collect();
        v.sort_by(f64::total_cmp);
        v[3]
    };
    let step = time(&mut || b.run(1).unwrap());
    let x = b.positions().to_vec();
    let mut d = DensityProfile::new(100, 1.0, n as f64);
    let density = time(&mut || d.sample(&x));
    let mut c = ClusterSizes::default();
    let clusters = time(&mut || c.sample(&b));
    let (sizes, p) = c.rows();
    let mean: f64 = sizes.iter().zip(&p).map(|(s, p)| s * p).sum();
    println!(
        "ns per rod: step {step:.2}, density {density:.2}, clusters {clusters:.2};  mean cluster size {mean:.2}"
    );
}
