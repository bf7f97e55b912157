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
    /// Instead of moves per second: independent samples per CPU second on one thread, local
    /// moves (each `--nselect`, delta tuned to `--acceptance`) against event chains (each
    /// `--chain-length`), from the integrated autocorrelation time of the slowest density
    /// modes (`cos`, `sin` of `2 pi x_a / L`), at each `--phi` with the first `--n`.
    #[arg(long = "move", value_enum, default_value = "local")]
    pub mode: Mode,
    /// Event-chain lengths to measure (in d; 0: the default `N^(1/3) / 2`).
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub chain_length: Vec<f64>,
    /// Target acceptances of the local moves' delta (autocorrelation mode).
    #[arg(long, value_delimiter = ',', default_value = "0.3")]
    pub acceptance: Vec<f64>,
    /// CPU seconds of sampling per case (autocorrelation mode).
    #[arg(long, default_value_t = 20.0)]
    pub seconds: f64,
}

/// What `colloidsim bench mc` measures.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Mode {
    /// Trial moves per second (local moves).
    Local,
    /// Independent samples per CPU second, local moves against event chains.
    EventChain,
}

/// `colloidsim bench mc`: for each volume fraction, one warmed-up system (FCC start, delta
/// tuned then frozen) is copied for every measurement, and the thread counts alternate within
/// each repetition (A/B on a shared machine); trial moves per second of wall time and of CPU
/// time, medians, and the speed-up over the first thread count.
pub fn bench(a: &BenchArgs) -> Result<()> {
    use colloidsim_mc::params::NSELECT_MAX;
    if a.mode == Mode::EventChain {
        return rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .context("thread pool")?
            .install(|| samples_per_second(a));
    }
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

/// One case of the autocorrelation mode: `mc` (warmed up) sampled every `every` sweeps for
/// about `seconds` of CPU time of its sweeps: (tau in sweeps, whether its window was found,
/// CPU seconds per sweep, sweeps).
fn autocorrelation(
    mc: &mut colloidsim_mc::HardSphereMc,
    every: u64,
    seconds: f64,
) -> (f64, bool, f64, u64) {
    let mut series = vec![Vec::new(); 6];
    let (mut cpu, mut sweeps) = (0.0, 0u64);
    while cpu < seconds || series[0].len() < 100 {
        let c0 = cpu_seconds().unwrap_or(0.0);
        mc.run(every);
        cpu += cpu_seconds().unwrap_or(0.0) - c0;
        sweeps += every;
        for (s, v) in series
            .iter_mut()
            .zip(colloidsim_mc::bench::density_modes(mc))
        {
            s.push(v);
        }
    }
    let (tau, ok) = colloidsim_mc::bench::integrated_time(&series);
    (tau * every as f64, ok, cpu / sweeps as f64, sweeps)
}

/// `colloidsim bench mc --move event-chain`: independent samples of the slowest density modes
/// per CPU second, `1 / (2 tau cpu_per_sweep)`, on one thread.
fn samples_per_second(a: &BenchArgs) -> Result<()> {
    let n = a.n.first().copied().unwrap_or(500);
    println!(
        "# colloidsim bench mc --move event-chain: N = {n} hard spheres (d = 1) in a periodic cube, 1 thread; observable: cos/sin(2 pi x_a / L) summed (6 series); tau: integrated autocorrelation time in sweeps (Sokal window 6 tau; '>' where the run was too short for the window); {} CPU s per case",
        a.seconds
    );
    println!(
        "phi\tmove\tparameter\ttau_sweeps\tcpu_s_per_sweep\tsamples_per_cpu_s\tgain_over_best_local\tsweeps"
    );
    for &phi in &a.phi {
        let warmup = a.warmup.max(300);
        let mut best_local = 0.0f64;
        let mut rows = Vec::new();
        // The event chains start from the first local case's warmed-up fluid.
        let mut fluid = None;
        for &target in &a.acceptance {
            let edge = colloidsim_mc::bench::bulk_edge(n, phi);
            let pos = colloidsim_mc::init::fcc_in_box(n, 1.0, edge)?;
            let params = colloidsim_mc::McParams {
                diameter: 1.0,
                geometry: colloidsim_mc::Geometry::Bulk { edge },
                seed: 1,
                delta: 0.1,
                mixture: None,
            };
            let warmed = {
                let mut mc = colloidsim_mc::HardSphereMc::new(&params, &pos, "system")?;
                mc.warm_up(warmup, 100, target);
                mc
            };
            fluid.get_or_insert_with(|| warmed.clone());
            for &nselect in &a.nselect {
                let mut mc = warmed.clone();
                mc.set_nselect(nselect);
                let every = (10 / nselect as u64).max(1);
                let (tau, ok, cpu, sweeps) = autocorrelation(&mut mc, every, a.seconds);
                let rate = 1.0 / (2.0 * tau * cpu);
                best_local = best_local.max(rate);
                rows.push((
                    "local",
                    format!("nselect={nselect},acc={target},delta={:.4}", mc.delta()),
                    tau,
                    ok,
                    cpu,
                    rate,
                    sweeps,
                ));
            }
        }
        for &length in &a.chain_length {
            let length = if length > 0.0 {
                length
            } else {
                0.5 * (n as f64).cbrt()
            };
            let Some(mut mc) = fluid.clone() else {
                anyhow::bail!("--acceptance needs at least one value");
            };
            let per_sweep =
                ((n as f64 * colloidsim_mc::engine::chain::free_path(phi, 1.0) / length).round()
                    as u64)
                    .max(1);
            mc.set_event_chain(Some(colloidsim_mc::EventChain {
                length,
                chains_per_sweep: per_sweep,
            }))?;
            mc.run(warmup / 10);
            let (tau, ok, cpu, sweeps) = autocorrelation(&mut mc, 10, a.seconds);
            let rate = 1.0 / (2.0 * tau * cpu);
            rows.push((
                "event-chain",
                format!("chain_length={length:.3},chains_per_sweep={per_sweep}"),
                tau,
                ok,
                cpu,
                rate,
                sweeps,
            ));
        }
        for (kind, param, tau, ok, cpu, rate, sweeps) in rows {
            println!(
                "{phi}\t{kind}\t{param}\t{}{tau:.1}\t{cpu:.3e}\t{rate:.3}\t{:.2}\t{sweeps}",
                if ok { "" } else { ">" },
                rate / best_local
            );
        }
    }
    Ok(())
}
