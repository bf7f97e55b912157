//! `colloidsim bench bcd`: the fast-bcd scaling case (fast-bcd Fig. 6).

use anyhow::Result;
use colloidsim_bcd::forces::Field;
use colloidsim_bcd::forces::NoPair;
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Integrator, Update, init};
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
    /// Integrators of the premerging case (`euler`, `lm`, `reflect`), alternated within each
    /// repetition.
    #[arg(long, value_delimiter = ',', default_value = "euler")]
    pub integrators: Vec<String>,
    /// Instead: the whole run path (`colloidsim run`) at these N, with no observers and with
    /// the main example's (density of 100 bins, MSD of 30 lags and clusters, every step),
    /// beside the bare engine, alternating the three in each repetition; runs of at least
    /// 20,000 steps (the MSD's cost per step falls as 1 / steps).
    #[arg(long, value_delimiter = ',')]
    pub observers: Vec<usize>,
}

fn rss_bytes() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: f64 = s.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096.0)
}

/// `colloidsim bench bcd`: the fast-bcd scaling case (sigma = 0.99, U0 = 6 kT, density 1 per
/// wavelength, dt = 1e-3, periodic), nanoseconds per particle-step.
pub fn bench(a: &BenchArgs) -> Result<()> {
    if !a.observers.is_empty() {
        return bench_observers(a);
    }
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
    let integrators = a
        .integrators
        .iter()
        .map(|s| match s.as_str() {
            "euler" => Ok(Integrator::Euler),
            "lm" => Ok(Integrator::Lm),
            "reflect" => Ok(Integrator::Reflect),
            o => anyhow::bail!("--integrators: '{o}' is not one of euler, lm, reflect"),
        })
        .collect::<Result<Vec<_>>>()?;
    // The integrators of one N alternate within each repetition (the machine's load drifts).
    let run = |n: usize, update: Update, schemes: &[Integrator]| -> Result<()> {
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
        let mut times = vec![Vec::new(); schemes.len()];
        let mut mem = vec![f64::NAN; schemes.len()];
        let x0 = init::lattice(&cfg, n)?;
        for rep in 0..a.repeats.max(1) {
            for (k, &scheme) in schemes.iter().enumerate() {
                let before = rss_bytes();
                let mut b = Bcd::new(cfg.clone(), x0.clone(), force.clone(), NoPair)?
                    .with_integrator(scheme);
                b.run(steps.min(50))?; // warm-up: clusters form, buffers reach their size
                let t = Instant::now();
                b.run(steps)?;
                times[k].push(t.elapsed().as_secs_f64() * 1e9 / (steps as f64 * n as f64));
                if rep == 0
                    && let (Some(b0), Some(b1)) = (before, rss_bytes())
                {
                    mem[k] = (b1 - b0) / n as f64;
                }
                drop(b);
            }
        }
        for (k, &scheme) in schemes.iter().enumerate() {
            let (m, lo, hi) = med(&mut times[k]);
            let name = match (update, scheme) {
                (Update::Chronological, _) => "chronological",
                (_, Integrator::Euler) => "premerge",
                (_, Integrator::Lm) => "premerge-lm",
                (_, Integrator::Reflect) => "reflect",
            };
            println!(
                "{name}\t{n}\t{steps}\t{m:.2}\t{lo:.2}\t{hi:.2}\t{:.0}",
                mem[k]
            );
        }
        Ok(())
    };
    // A 0 in a list skips that method.
    for &n in a.n.iter().filter(|&&n| n > 0) {
        run(n, Update::Premerge, &integrators)?;
    }
    for &n in a.chronological.iter().filter(|&&n| n > 0) {
        run(n, Update::Chronological, &[Integrator::Euler])?;
    }
    Ok(())
}

/// The fast-bcd case as a scenario for `colloidsim run`, with or without the main example's
/// observers; `steps` sampled steps.
fn scenario(n: usize, steps: u64, observers: bool) -> String {
    let mut s = format!(
        "method = \"bcd\"\nseed = 1\n[system]\nlength = {n}.0\nparticles = {n}\ndiameter = 0.99\n\
         [potential]\ncosine = {{ amplitude = 6.0, wavelength = 1.0 }}\n\
         [run]\ndt = 1e-3\ntime = {}\ncheckpoint_every = {}\n",
        steps as f64 * 1e-3,
        10 * steps
    );
    if observers {
        s.push_str("[observe]\nevery = 1\ndensity = { bins = 100 }\nmsd = { points = 30 }\nclusters = true\n");
    }
    s
}

/// Least number of steps of a run in `--observers`.
const OBSERVER_STEPS: u64 = 20_000;

/// `colloidsim bench bcd --observers N,...`: nanoseconds per particle-step of the bare engine
/// (`Bcd::run`), of `colloidsim run` without observers and with the main example's, in the
/// same process, alternating; the run path's time is its step loop (`wall_seconds` of
/// summary.json: observers included, the writing of outputs and the theory after the run not;
/// no regular checkpoint, whose writing and fsync would be timed too).
fn bench_observers(a: &BenchArgs) -> Result<()> {
    use colloidsim_run::{Control, RunOptions, Scenario};
    println!(
        "# colloidsim bench bcd --observers: sigma = 0.99, U0 = 6 kT, rho = 1, dt = 1e-3, periodic, no regular checkpoint; {} threads, median (min-max) of {}",
        rayon::current_num_threads(),
        a.repeats
    );
    println!("N\tsteps\tengine_ns\trun_bare_ns\trun_observers_ns\tobservers_over_engine");
    let field = Field::new(&ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    });
    let dir = std::env::temp_dir().join(format!("colloidsim-bench-obs-{}", std::process::id()));
    for &n in &a.observers {
        // At least OBSERVER_STEPS: the MSD's cost per step is ~3000 evaluations (100 origins
        // x 30 lags) over the run's steps, 0.003 per step in the example's 10^6 steps; in a run of
        // 1000 steps it would be 3 per step and the bench would time the MSD of a run far
        // shorter than the example's.
        let steps = (a.work / n as u64).max(OBSERVER_STEPS);
        let (mut eng, mut bare, mut obs) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..a.repeats.max(1) {
            let cfg = BcdConfig {
                length: n as f64,
                sigma: 0.99,
                mobility: 1.0,
                kt: 1.0,
                dt: 1e-3,
                boundary: Boundary::Periodic,
                seed: 1,
                update: Update::Premerge,
            };
            let mut b = Bcd::new(
                cfg.clone(),
                init::random(&cfg, n, 1)?,
                field.clone(),
                NoPair,
            )?;
            let t = Instant::now();
            b.run(steps)?;
            eng.push(t.elapsed().as_secs_f64() * 1e9 / (steps as f64 * n as f64));
            for (with, out) in [(false, &mut bare), (true, &mut obs)] {
                let _ = std::fs::remove_dir_all(&dir);
                let sc = Scenario::from_toml(&scenario(n, steps, with), &dir)?;
                let opts = RunOptions {
                    out: Some(dir.clone()),
                    seed: None,
                    force: false,
                };
                let r = colloidsim_run::run(&sc, &opts, &Control::default())?;
                let wall = r.summary["wall_seconds"].as_f64().unwrap_or(f64::NAN);
                out.push(wall * 1e9 / (steps as f64 * n as f64));
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
        let (e, b, o) = (med(&mut eng), med(&mut bare), med(&mut obs));
        println!(
            "{n}\t{steps}\t{:.2} ({:.2}-{:.2})\t{:.2} ({:.2}-{:.2})\t{:.2} ({:.2}-{:.2})\t{:.2}",
            e.0,
            e.1,
            e.2,
            b.0,
            b.1,
            b.2,
            o.0,
            o.1,
            o.2,
            o.0 / e.0
        );
    }
    Ok(())
}

/// Median, min, max.
fn med(v: &mut [f64]) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0], v[v.len() - 1])
}
