//! What the integrator does to dynamical observables: the mean-square displacement of a tagged
//! rod with Euler and Leimkuhler–Matthews at several dt (issue #21).
//!
//! ```text
//! nice -n 10 cargo run --release -p colloidsim-bcd --example lm_dynamics -- [REPLICAS]
//! ```
//!
//! - `single-file`: hard rods without field, sigma = rho = 0.5, L = 400 (the hard-rods paper's
//!   Fig. 7 system), against the exact short-time law 2 D t and the single-file law
//!   `(1 - rho sigma) / rho sqrt(4 D t / pi)` (its ratio to the MSD is printed; it approaches 1
//!   for t >> (1/rho - sigma)^2 / D = 2.25);
//! - `cosine`: the Fig. 3 case sigma = rho = 0.5 in U0 = 6 kT (L = 100) against Euler at
//!   dt = 1e-5 as the reference (there is no exact MSD): relaxation in the wells (t ~ 1/U'' =
//!   0.008) and hopping between them (t ~ 10).
//!
//! Each replica (default 16) starts from an exact hard-rod configuration without field, relaxes
//! 20 time units with the scheme and dt it is run with, then samples the MSD over 100 time
//! units with time origins every 5 time units. Errors are standard errors over the replicas.

use colloidsim_bcd::forces::Field;
use colloidsim_bcd::forces::NoPair;
use colloidsim_bcd::observe::Msd;
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Integrator, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};
use rayon::prelude::*;

const LAGS: [f64; 7] = [0.01, 0.03, 0.1, 1.0, 3.0, 10.0, 50.0];

/// MSD at the lag times `LAGS` of one replica.
fn replica(length: f64, n: usize, u0: f64, scheme: Integrator, dt: f64, seed: u32) -> Vec<f64> {
    let cfg = BcdConfig {
        length,
        sigma: 0.5,
        mobility: 1.0,
        kt: 1.0,
        dt,
        boundary: Boundary::Periodic,
        seed,
        update: Update::Premerge,
    };
    let field = ExternalField {
        terms: if u0 > 0.0 {
            vec![FieldTerm::Cosine {
                amplitude: u0,
                wavelength: 1.0,
            }]
        } else {
            vec![]
        },
        drive: 0.0,
    };
    let x0 = init::random(&cfg, n, seed).expect("initial configuration");
    let mut b = Bcd::new(cfg, x0, Field::new(&field), NoPair)
        .expect("engine")
        .with_integrator(scheme);
    b.run((20.0 / dt).round() as u64).expect("relaxation");
    let lags: Vec<u64> = LAGS.iter().map(|t| (t / dt).round() as u64).collect();
    let mut msd = Msd::new(lags.clone(), (5.0 / dt).round() as u64);
    let steps = (100.0 / dt).round() as u64;
    for k in 0..steps {
        b.step().expect("step");
        msd.sample(k, b.positions());
    }
    let rows = msd.rows();
    lags.iter()
        .map(|&l| rows.iter().find(|r| r.0 == l).map_or(f64::NAN, |r| r.1))
        .collect()
}

fn mean_and_error(v: &[f64]) -> (f64, f64) {
    let k = v.len() as f64;
    let m = v.iter().sum::<f64>() / k;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k - 1.0);
    (m, (var / k).sqrt())
}

/// Mean MSD and its error at each lag over `replicas` seeds.
fn msd(
    length: f64,
    n: usize,
    u0: f64,
    scheme: Integrator,
    dt: f64,
    replicas: u32,
) -> Vec<(f64, f64)> {
    let runs: Vec<Vec<f64>> = (0..replicas)
        .into_par_iter()
        .map(|r| replica(length, n, u0, scheme, dt, 1000 + r))
        .collect();
    (0..LAGS.len())
        .map(|k| mean_and_error(&runs.iter().map(|r| r[k]).collect::<Vec<_>>()))
        .collect()
}

fn main() {
    let replicas: u32 = std::env::args()
        .nth(1)
        .map_or(16, |s| s.parse().expect("REPLICAS"));
    let runs = [
        (Integrator::Euler, 1e-2),
        (Integrator::Lm, 1e-2),
        (Integrator::Euler, 1e-3),
        (Integrator::Lm, 1e-3),
        (Integrator::Euler, 1e-4),
        (Integrator::Lm, 1e-4),
    ];
    let header = |what: &str| {
        print!("| t | {what} |");
        for (s, dt) in runs {
            print!(" {s:?} {dt:e} |");
        }
        println!();
        println!("|---|---|{}", "---|".repeat(runs.len()));
    };

    // Single file: MSD relative to 2 D t at short lags, to the single-file law at long ones.
    let (length, n, sigma) = (400.0, 200, 0.5);
    let rho = n as f64 / length;
    println!(
        "single file (sigma = rho = 0.5, L = 400): MSD / law, law = 2Dt for t <= 0.1, single-file law for t >= 1"
    );
    header("law");
    let cols: Vec<Vec<(f64, f64)>> = runs
        .iter()
        .map(|&(s, dt)| msd(length, n, 0.0, s, dt, replicas))
        .collect();
    for (k, &t) in LAGS.iter().enumerate() {
        let law = if t <= 0.1 {
            2.0 * t
        } else {
            (1.0 - rho * sigma) / rho * (4.0 * t / std::f64::consts::PI).sqrt()
        };
        print!("| {t} | {law:.4} |");
        for c in &cols {
            print!(" {:.4} ± {:.4} |", c[k].0 / law, c[k].1 / law);
        }
        println!();
    }

    // Cosine potential: MSD relative to Euler at dt = 1e-5.
    let (length, n) = (100.0, 50);
    let reference = msd(length, n, 6.0, Integrator::Euler, 1e-5, replicas);
    println!();
    println!("cosine U0 = 6 kT (sigma = rho = 0.5, L = 100): MSD / MSD(Euler, dt = 1e-5)");
    header("reference MSD");
    let cols: Vec<Vec<(f64, f64)>> = runs
        .iter()
        .map(|&(s, dt)| msd(length, n, 6.0, s, dt, replicas))
        .collect();
    for (k, &t) in LAGS.iter().enumerate() {
        let (r, re) = reference[k];
        print!("| {t} | {r:.4e} ± {re:.1e} |");
        for c in &cols {
            print!(" {:.4} ± {:.4} |", c[k].0 / r, c[k].1 / r);
        }
        println!();
    }
}
