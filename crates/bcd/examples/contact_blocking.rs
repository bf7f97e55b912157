//! How long must the blocks of a contact-density error be? Hard rods on a ring in a cosine
//! potential (50 rods, sigma = 0.5, on a ring of 100; window and time step as arguments): the
//! number of rods whose right neighbour lies within `sigma + w` is recorded every 1e-5 time
//! units, and the standard error of its mean is estimated from blocks of increasing length
//! (Flyvbjerg–Petersen): where the estimate stops growing, the blocks are independent.
//!
//! `cargo run --release -p colloidsim-bcd --example contact_blocking -- DT TIME SEED W U0`

use colloidsim_bcd::forces::Field;
use colloidsim_bcd::forces::NoPair;
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: f64| a.get(i).map_or(d, |s| s.parse().unwrap());
    let dt = arg(1, 1.25e-7);
    let time = arg(2, 10.0);
    let seed = arg(3, 2.0) as u32;
    let w = arg(4, 0.005);
    let u0 = arg(5, 1.0);
    let (n, length, sigma) = (50usize, 100.0, 0.5);
    let every = (1e-5 / dt).round().max(1.0) as u64;
    let cfg = BcdConfig {
        length,
        sigma,
        mobility: 1.0,
        kt: 1.0,
        dt,
        boundary: Boundary::Periodic,
        seed,
        update: Update::Premerge,
    };
    let field = Field::new(&ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: u0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    });
    let x0 = init::random(&cfg, n, seed).expect("initial configuration");
    let mut b = Bcd::new(cfg, x0, field, NoPair).expect("engine");
    b.run((1.0 / dt) as u64).expect("equilibration");
    let samples = (time / dt) as u64 / every;
    let mut counts = Vec::with_capacity(samples as usize);
    for _ in 0..samples {
        b.run(every).expect("run");
        let x = b.positions();
        let mut c = 0u32;
        for i in 0..n {
            let right = if i + 1 < n { x[i + 1] } else { x[0] + length };
            c += u32::from(right - x[i] < sigma + w);
        }
        counts.push(f64::from(c));
    }
    let mean = counts.iter().sum::<f64>() / counts.len() as f64;
    // Pooled contact density over one period: count / (w L) per unit length... as Eq. 27 with
    // one bin spanning the ring.
    let rho2 = mean / (w * length);
    println!(
        "# dt {dt} time {time} seed {seed} w {w} U0 {u0}: mean count {mean:.5}, rho2 {rho2:.5}"
    );
    println!("# block length (time), blocks, relative standard error of rho2");
    let mut x = counts;
    let mut block_time = every as f64 * dt;
    while x.len() >= 8 {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        let var = x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64;
        let se = (var / x.len() as f64).sqrt();
        println!("{block_time:.3e} {} {:.4}", x.len(), se / mean);
        x = x.chunks_exact(2).map(|p| 0.5 * (p[0] + p[1])).collect();
        block_time *= 2.0;
    }
}
