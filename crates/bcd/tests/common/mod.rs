//! Shared helpers of the validation tests: BCD density histograms against the exact theory.

use colloidsim_bcd::forces::{CosineForce, ForceTable, NoPair, PairForce, Sticky};
use colloidsim_bcd::observe::DensityProfile;
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};
use colloidsim_dft::rods::{self, BetaPotential, Domain, RodInteraction, RodsProblem};

/// The hard-rods paper's cosine potential of 6 kT and period 1 (the integrator tests').
#[allow(dead_code)]
pub fn cosine_field() -> ExternalField {
    ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    }
}

/// Its force.
#[allow(dead_code)]
pub fn cosine() -> CosineForce {
    CosineForce::from_field(&cosine_field()).unwrap()
}

/// Mean and standard error of independent samples.
pub fn mean_and_error(samples: &[f64]) -> (f64, f64) {
    let k = samples.len() as f64;
    let m = samples.iter().sum::<f64>() / k;
    let var = samples.iter().map(|s| (s - m).powi(2)).sum::<f64>() / (k - 1.0);
    (m, (var / k).sqrt())
}

/// One comparison of a BCD density profile in `U = 3 cos(2 pi x)` with the exact theory.
pub struct Case {
    pub sigma: f64,
    pub rho: f64,
    pub gamma: Option<f64>,
    pub length: f64,
    pub dt: f64,
    pub bins: usize,
    pub equilibrate_steps: u64,
    pub blocks: usize,
    pub block_steps: u64,
    pub seed: u32,
}

/// Outcome: largest deviation in standard errors, and chi^2 against the theory for a rod
/// length 10% off (which a working test must reject).
pub struct Outcome {
    pub worst: f64,
    pub chi2_wrong_sigma: f64,
    pub bins: usize,
}

fn field() -> ExternalField {
    ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    }
}

fn theory(c: &Case, sigma: f64) -> Vec<f64> {
    let interaction = match c.gamma {
        Some(gamma) => RodInteraction::Sticky { gamma },
        None => RodInteraction::Hard,
    };
    let p = RodsProblem::new(sigma, c.rho, Domain::Periodic { period: 1.0 })
        .with_dx(1e-3_f64.min(sigma / 50.0))
        .with_potential(BetaPotential::from_field(&field(), 1.0))
        .with_interaction(interaction);
    rods::equilibrium(&p)
        .unwrap()
        .bin_average(c.bins, 1.0)
        .unwrap()
        .rho
}

fn simulate<P: PairForce>(c: &Case, pair: P) -> Vec<Vec<f64>> {
    let n = (c.rho * c.length).round() as usize;
    let cfg = BcdConfig {
        length: c.length,
        sigma: c.sigma,
        mobility: 1.0,
        kt: 1.0,
        dt: c.dt,
        boundary: Boundary::Periodic,
        seed: c.seed,
        update: Update::Premerge,
    };
    let x0 = init::random(&cfg, n, c.seed).unwrap();
    let table = ForceTable::from_field(&field()).unwrap();
    let mut b = Bcd::new(cfg, x0, table, pair).unwrap();
    b.run(c.equilibrate_steps).unwrap();
    (0..c.blocks)
        .map(|_| {
            let mut d = DensityProfile::new(c.bins, 1.0, c.length);
            for _ in 0..c.block_steps {
                b.step().unwrap();
                d.sample(b.positions());
            }
            d.profile().1
        })
        .collect()
}

fn run(c: &Case) -> Vec<Vec<f64>> {
    match c.gamma {
        Some(gamma) => simulate(c, Sticky::new(gamma, 0.05, 3.0, c.sigma, 1.0).unwrap()),
        None => simulate(c, NoPair),
    }
}

/// Root-mean-square deviation of the run's profile (all blocks) from the exact one.
#[allow(dead_code)]
pub fn rms_deviation(c: &Case) -> f64 {
    let blocks = run(c);
    let exact = theory(c, c.sigma);
    let k = blocks.len() as f64;
    let ss: f64 = (0..c.bins)
        .map(|i| (blocks.iter().map(|b| b[i]).sum::<f64>() / k - exact[i]).powi(2))
        .sum();
    (ss / c.bins as f64).sqrt()
}

/// Run the case and compare bin by bin (batch means over `blocks`).
pub fn compare(c: &Case) -> Outcome {
    let blocks = run(c);
    let exact = theory(c, c.sigma);
    let wrong = theory(c, 1.1 * c.sigma);
    let (mut worst, mut chi2) = (0.0f64, 0.0);
    for k in 0..c.bins {
        let col: Vec<f64> = blocks.iter().map(|b| b[k]).collect();
        let (m, err) = mean_and_error(&col);
        let err = err.max(1e-3 * m.abs()).max(1e-12);
        worst = worst.max((m - exact[k]).abs() / err);
        chi2 += ((m - wrong[k]) / err).powi(2);
    }
    Outcome {
        worst,
        chi2_wrong_sigma: chi2,
        bins: c.bins,
    }
}
