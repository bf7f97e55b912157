//! `colloidsim bench mc`: hard-sphere Monte Carlo trial moves per second in a periodic cube.

use crate::common::{cpu_seconds, median};
use anyhow::{Context, Result};
use std::time::Instant;

/// Arguments of `colloidsim bench mc`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Number of spheres (an FCC lattice of 4 m^3 sites is filled evenly).
    #[arg(long, default_value_t = 10_976)]
    pub n: usize,
    /// Volume fractions to measure.
    #[arg(long, value_delimiter = ',', default_value = "0.3,0.5")]
    pub phi: Vec<f64>,
    /// Timed sweeps (N trial moves each) per measurement.
    #[arg(long, default_value_t = 200)]
    pub sweeps: u64,
    /// Warm-up sweeps before timing (delta tuned every 100 towards acceptance 0.3, then frozen).
    #[arg(long, default_value_t = 1000)]
    pub warmup: u64,
    /// Repetitions per case, alternating the thread counts; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Thread counts to measure.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
}

/// `colloidsim bench mc`: for each volume fraction, one warmed-up system (FCC start, delta
/// tuned then frozen) is copied for every measurement, and the thread counts alternate within
/// each repetition (A/B on a shared machine); trial moves per second of wall time and of CPU
/// time, medians, and the speed-up over the first thread count.
pub fn bench(a: &BenchArgs) -> Result<()> {
    println!(
        "# colloidsim bench mc: hard spheres d = 1, N = {}, periodic cube, checkerboard cells; {} sweeps per run, median (min-max) of {}",
        a.n, a.sweeps, a.repeats
    );
    println!("# cpu_rate: trial moves per second of CPU time (user + system, all threads)");
    println!(
        "phi\tthreads\tmoves_per_s\tmin\tmax\tcpu_rate\tacceptance\tdelta\tleft_cell\tspeedup"
    );
    let pools = a
        .threads
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .context("thread pool")
        })
        .collect::<Result<Vec<_>>>()?;
    for &phi in &a.phi {
        let warm = colloidsim_mc::bench::bulk_system(a.n, phi, 1, a.warmup)?;
        let mut rates = vec![Vec::new(); pools.len()];
        let mut cpu_rates = vec![Vec::new(); pools.len()];
        let mut stats = vec![Default::default(); pools.len()];
        for _ in 0..a.repeats.max(1) {
            for (k, pool) in pools.iter().enumerate() {
                let mut mc = warm.clone();
                let c0 = cpu_seconds();
                let start = Instant::now();
                let s: colloidsim_mc::SweepStats = pool.install(|| mc.run(a.sweeps));
                let wall = start.elapsed().as_secs_f64();
                let cpu = cpu_seconds().zip(c0).map(|(c1, c0)| c1 - c0);
                rates[k].push(s.trials as f64 / wall);
                cpu_rates[k].push(cpu.map_or(f64::NAN, |c| s.trials as f64 / c));
                stats[k] = s;
            }
        }
        let mut first = None;
        for (k, &t) in a.threads.iter().enumerate() {
            let (m, lo, hi) = median(rates[k].clone());
            let (mc, _, _) = median(cpu_rates[k].clone());
            let base = *first.get_or_insert(m);
            let s: colloidsim_mc::SweepStats = stats[k];
            println!(
                "{phi}\t{t}\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{mc:.4e}\t{:.3}\t{:.4}\t{:.3}\t{:.2}",
                s.acceptance(),
                warm.delta(),
                s.left_cell as f64 / s.trials as f64,
                m / base
            );
        }
    }
    Ok(())
}
