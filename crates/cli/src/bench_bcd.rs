//! `colloidsim bench bcd`: the fast-bcd scaling case (fast-bcd Fig. 6).

use anyhow::Result;
use colloidsim_bcd::forces::NoPair;
use colloidsim_bcd::scenario::Field;
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};
use std::time::Instant;

/// Arguments of `colloidsim bench bcd`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Particle numbers for the premerging update.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1000,10000,100000,1000000"
    )]
    pub n: Vec<usize>,
    /// Particle numbers for the chronological update (O(N^2)); 0 skips it.
    #[arg(long, value_delimiter = ',', default_value = "100,300,1000,3000,10000")]
    pub chronological: Vec<usize>,
    /// Particle-steps per measurement (steps = this / N, at least 20).
    #[arg(long, default_value_t = 20_000_000)]
    pub work: u64,
    /// Repetitions; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
}

fn rss_bytes() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: f64 = s.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096.0)
}

/// `colloidsim bench bcd`: the fast-bcd scaling case (sigma = 0.99, U0 = 6 kT, density 1 per
/// wavelength, dt = 1e-3, periodic), nanoseconds per particle-step.
pub fn bench(a: &BenchArgs) -> Result<()> {
    let field = ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    };
    // The force as `colloidsim run` evaluates this field.
    let force = Field::new(&field);
    println!(
        "# colloidsim bench bcd: sigma = 0.99, U0 = 6 kT, rho = 1, dt = 1e-3, periodic; {} threads, median of {}",
        rayon::current_num_threads(),
        a.repeats
    );
    println!("method\tN\tsteps\tns_per_particle_step\tmin\tmax\tRSS_bytes_per_particle");
    let run = |n: usize, update: Update| -> Result<()> {
        let cfg = BcdConfig {
            length: n as f64,
            sigma: 0.99,
            mobility: 1.0,
            kt: 1.0,
            dt: 1e-3,
            boundary: Boundary::Periodic,
            seed: 1,
            update,
        };
        let steps = (a.work / n as u64).max(20);
        let mut times = Vec::new();
        let mut mem = f64::NAN;
        let x0 = init::lattice(&cfg, n)?;
        for rep in 0..a.repeats.max(1) {
            let before = rss_bytes();
            let mut b = Bcd::new(cfg.clone(), x0.clone(), force.clone(), NoPair)?;
            b.run(steps.min(50))?; // warm-up: clusters form, buffers reach their size
            let t = Instant::now();
            b.run(steps)?;
            times.push(t.elapsed().as_secs_f64() * 1e9 / (steps as f64 * n as f64));
            if rep == 0
                && let (Some(b0), Some(b1)) = (before, rss_bytes())
            {
                mem = (b1 - b0) / n as f64;
            }
            drop(b);
        }
        times.sort_by(f64::total_cmp);
        let name = match update {
            Update::Premerge => "premerge",
            Update::Chronological => "chronological",
        };
        println!(
            "{name}\t{n}\t{steps}\t{:.2}\t{:.2}\t{:.2}\t{:.0}",
            times[times.len() / 2],
            times[0],
            times[times.len() - 1],
            mem
        );
        Ok(())
    };
    // A 0 in a list skips that method.
    for &n in a.n.iter().filter(|&&n| n > 0) {
        run(n, Update::Premerge)?;
    }
    for &n in a.chronological.iter().filter(|&&n| n > 0) {
        run(n, Update::Chronological)?;
    }
    Ok(())
}
