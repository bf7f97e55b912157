//! `colloidsim bench mc`: hard-sphere Monte Carlo trial moves per second in a periodic cube.

use crate::common::{cpu_seconds, median};
use anyhow::{Context, Result};
use std::time::Instant;

/// Arguments of `colloidsim bench mc`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Numbers of spheres (FCC lattices of 4 m^3 sites are filled evenly): a droplet-sized
    /// system, where the two parallel passes per sweep dominate, and a larger one.
    #[arg(long, value_delimiter = ',', default_value = "10976,87808")]
    pub n: Vec<usize>,
    /// Volume fractions to measure.
    #[arg(long, value_delimiter = ',', default_value = "0.3,0.5")]
    pub phi: Vec<f64>,
    /// Timed sweeps of one trial move per sphere per measurement at N = 10,976; scaled by
    /// 10,976 / (N nselect) otherwise (at least 10), so every measurement makes about the same
    /// number of moves.
    #[arg(long, default_value_t = 200)]
    pub sweeps: u64,
    /// Warm-up sweeps before timing at N = 10,976 (delta tuned every 100 towards acceptance
    /// 0.3, then frozen); scaled like `--sweeps` (at least 300).
    #[arg(long, default_value_t = 1000)]
    pub warmup: u64,
    /// Repetitions per case, alternating the thread counts; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Thread counts to measure.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// Trial moves per sphere per sweep (HOOMD-blue's nselect: moves per binning of the
    /// cells) to measure; the warm-up is at 1.
    #[arg(long, value_delimiter = ',', default_value = "1,4")]
    pub nselect: Vec<usize>,
}

/// `colloidsim bench mc`: for each volume fraction, one warmed-up system (FCC start, delta
/// tuned then frozen) is copied for every measurement, and the thread counts alternate within
/// each repetition (A/B on a shared machine); trial moves per second of wall time and of CPU
/// time, medians, and the speed-up over the first thread count.
pub fn bench(a: &BenchArgs) -> Result<()> {
    use colloidsim_mc::params::NSELECT_MAX;
    if let Some(bad) = a.nselect.iter().find(|&&k| !(1..=NSELECT_MAX).contains(&k)) {
        anyhow::bail!("--nselect must be integers in [1, {NSELECT_MAX}], got {bad}");
    }
    println!(
        "# colloidsim bench mc: hard spheres d = 1, periodic cube, cells updated in two parallel passes of z layers; {} N trial moves per run at N = 10976 (scaled by 10976/N), median (min-max) of {}",
        a.sweeps, a.repeats
    );
    println!("# cpu_rate: trial moves per second of CPU time (user + system, all threads)");
    println!(
        "n\tphi\tnselect\tthreads\tmoves_per_s\tmin\tmax\tcpu_rate\tacceptance\tdelta\tleft_cell\tspeedup"
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
    for (&n, &phi) in a.n.iter().flat_map(|n| a.phi.iter().map(move |p| (n, p))) {
        let scale = |sweeps: u64, least: u64| (sweeps * 10_976 / n.max(1) as u64).max(least);
        let warmup = scale(a.warmup, 300);
        let warmed = colloidsim_mc::bench::bulk_system(n, phi, 1, warmup)?;
        for &nselect in &a.nselect {
            let sweeps = scale(a.sweeps / nselect as u64, 10);
            let mut warm = warmed.clone();
            warm.set_nselect(nselect);
            let mut rates = vec![Vec::new(); pools.len()];
            let mut cpu_rates = vec![Vec::new(); pools.len()];
            let mut stats = vec![Default::default(); pools.len()];
            for _ in 0..a.repeats.max(1) {
                for (k, pool) in pools.iter().enumerate() {
                    let mut mc = warm.clone();
                    let c0 = cpu_seconds();
                    let start = Instant::now();
                    let s: colloidsim_mc::SweepStats = pool.install(|| mc.run(sweeps));
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
                    "{n}\t{phi}\t{nselect}\t{t}\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{mc:.4e}\t{:.3}\t{:.4}\t{:.3}\t{:.2}",
                    s.acceptance(),
                    warm.delta(),
                    s.left_cell as f64 / s.trials as f64,
                    m / base
                );
            }
        }
    }
    Ok(())
}
