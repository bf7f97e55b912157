//! `colloidsim bench rpy`: the RPY mobility's direct product beside pystokes, PSE per product
//! and per Brownian displacement, and a Brownian-dynamics step with PSE against a free-draining
//! step of the `bench bd` system. The cases live in `colloidsim_hydro::bench`.

use anyhow::{Context, Result};
use clap::Args;
use colloidsim_md::hydro::bench::{
    PYSTOKES_SCRIPT, RADIUS, box_edge, median, pse_product, random_system, relative_difference,
    time_direct, time_pse, time_pse_radii,
};
use std::io::Write;
use std::process::{Command, Stdio};
use std::time::Instant;

/// Arguments of `colloidsim bench rpy`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Particle numbers of the direct product (and pystokes).
    #[arg(long, value_delimiter = ',', default_value = "1000,2000,5000")]
    pub sizes: Vec<usize>,
    /// Particle numbers of PSE.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1000,3000,10000,30000,100000"
    )]
    pub pse_sizes: Vec<usize>,
    /// Thread counts to measure.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// Repetitions; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Volume fraction of the random systems.
    #[arg(long, default_value_t = 0.1)]
    pub phi: f64,
    /// PSE tolerance.
    #[arg(long, default_value_t = 1e-3)]
    pub tolerance: f64,
    /// Particles of the Brownian-dynamics step comparison (the `bench bd` system).
    #[arg(long, default_value_t = 25_000)]
    pub bd_n: usize,
    /// Python interpreter that can import pystokes.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// Do not run pystokes.
    #[arg(long)]
    pub no_pystokes: bool,
    /// Particle numbers of PSE's accuracy against pystokes' periodic Ewald sum.
    #[arg(long, value_delimiter = ',', default_value = "200,500")]
    pub periodic_sizes: Vec<usize>,
    /// Particle numbers of the bidisperse PSE comparison.
    #[arg(long, value_delimiter = ',', default_value = "10000,30000")]
    pub bidisperse_sizes: Vec<usize>,
    /// Radius ratio of the bidisperse PSE comparison.
    #[arg(long, default_value_t = 2.0)]
    pub ratio: f64,
    /// Number fraction of the larger spheres in the bidisperse PSE comparison (0.5: half;
    /// 1 / (1 + ratio^3): equal volumes of the two sizes, the droplet study's mixture).
    #[arg(long, default_value_t = 0.5)]
    pub large_fraction: f64,
    /// Parts to run: direct, pse, bidisperse (PSE with two radii against one), periodic (PSE's
    /// accuracy against pystokes.periodic), bd.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "direct,pse,bidisperse,periodic,bd"
    )]
    pub parts: Vec<String>,
}

/// Positions and forces of one benchmark system.
type System = (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// Run pystokes on the same systems (in a periodic cube of that edge where `boxes` gives one);
/// `None` (with the reason printed) when it cannot run.
fn pystokes(a: &BenchArgs, systems: &[System], boxes: Option<&[f64]>) -> Option<serde_json::Value> {
    let cases: Vec<serde_json::Value> = systems
        .iter()
        .enumerate()
        .map(|(k, (p, f))| {
            let mut c = serde_json::json!({"n": p.len(), "pos": p.as_flattened(), "force": f.as_flattened()});
            if let Some(l) = boxes {
                // Ewald sum converged to about 3e-11 (against 8 boxes and modes); slow, so once.
                c["box"] = l[k].into();
                c["nb"] = 6.into();
                c["nm"] = 6.into();
                c["repeats"] = 1.into();
            }
            c
        })
        .collect();
    let req = serde_json::json!({
        "radius": RADIUS, "viscosity": 1.0, "repeats": a.repeats.max(1), "cases": cases
    });
    let child = Command::new(&a.python)
        .args(["-c", PYSTOKES_SCRIPT])
        .env("OMP_NUM_THREADS", "1")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(c) => c,
        Err(e) => {
            println!("# pystokes: cannot start {} ({e}); not compared", a.python);
            return None;
        }
    };
    if let Some(mut stdin) = child.stdin.take() {
        let _ = stdin.write_all(req.to_string().as_bytes());
    }
    let out = match child.wait_with_output() {
        Ok(o) => o,
        Err(e) => {
            println!("# pystokes: {e}; not compared");
            return None;
        }
    };
    let v: serde_json::Value = match serde_json::from_slice(&out.stdout) {
        Ok(v) => v,
        Err(_) => {
            println!(
                "# pystokes: the Python run failed ({}); not compared",
                String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .last()
                    .unwrap_or("no output")
            );
            return None;
        }
    };
    if let Some(e) = v.get("error") {
        println!("# pystokes: {e} (pip install pystokes); not compared");
        return None;
    }
    Some(v)
}

/// `colloidsim bench rpy`.
pub fn bench(a: &BenchArgs) -> Result<()> {
    let reps = a.repeats.max(1);
    println!(
        "# colloidsim bench rpy: spheres of radius {RADIUS}, viscosity 1, random positions at phi = {}, random forces; median of {reps}",
        a.phi
    );
    let part = |p: &str| a.parts.iter().any(|x| x == p);
    if part("direct") {
        direct(a, reps)?;
    }
    if part("pse") {
        pse(a, reps)?;
    }
    if part("bidisperse") {
        bidisperse(a, reps)?;
    }
    if part("periodic") && !a.no_pystokes {
        periodic(a)?;
    }
    if part("bd") {
        bd_step(a, reps)?;
    }
    Ok(())
}

/// The direct product beside pystokes.
fn direct(a: &BenchArgs, reps: usize) -> Result<()> {
    println!(
        "## direct RPY product M F (free space, non-overlapping spheres), beside pystokes.unbounded.Rbm.mobilityTT (OMP_NUM_THREADS=1); speed-ups of medians (and of minima)"
    );
    // Non-overlapping spheres (pystokes has only the r >= 2a branch of the tensor).
    let (systems, _) = hard_systems(&a.sizes, a.phi)?;
    let mut ours = Vec::new();
    for (p, f) in &systems {
        for &t in &a.threads {
            let (timing, u) = time_direct(p, f, t, reps);
            ours.push((timing, u));
        }
    }
    let peer = if a.no_pystokes {
        None
    } else {
        pystokes(a, &systems, None)
    };
    println!(
        "code\tN\tthreads\tseconds\tmin_seconds\tns_per_pair\tspeed-up_vs_pystokes\tof_minima\trel_diff_vs_pystokes"
    );
    for (timing, u) in &ours {
        let case = peer.as_ref().and_then(|v| {
            v["cases"]
                .as_array()?
                .iter()
                .find(|c| c["n"].as_u64() == Some(timing.n as u64))
                .cloned()
        });
        let (speed, speed_min, diff) = match &case {
            Some(c) => {
                let s = c["median_s"].as_f64().unwrap_or(f64::NAN);
                let smin = c["min_s"].as_f64().unwrap_or(f64::NAN);
                let v: Vec<f64> = c["velocity"]
                    .as_array()
                    .map(|a| a.iter().filter_map(|x| x.as_f64()).collect())
                    .unwrap_or_default();
                (
                    format!("{:.2}", s / timing.seconds),
                    format!("{:.2}", smin / timing.min_seconds),
                    format!("{:.2e}", relative_difference(u.as_flattened(), &v)),
                )
            }
            None => ("-".into(), "-".into(), "-".into()),
        };
        println!(
            "colloidsim\t{}\t{}\t{:.4e}\t{:.4e}\t{:.3}\t{speed}\t{speed_min}\t{diff}",
            timing.n, timing.threads, timing.seconds, timing.min_seconds, timing.ns_per_pair
        );
    }
    if let Some(v) = &peer {
        for c in v["cases"].as_array().into_iter().flatten() {
            println!(
                "pystokes-{}\t{}\t1\t{:.4e}\t{:.4e}\t{:.3}\t1.00\t1.00\t0",
                v["version"].as_str().unwrap_or("?"),
                c["n"],
                c["median_s"].as_f64().unwrap_or(f64::NAN),
                c["min_s"].as_f64().unwrap_or(f64::NAN),
                c["median_s"].as_f64().unwrap_or(f64::NAN) * 1e9
                    / (c["n"].as_f64().unwrap_or(1.0)).powi(2)
            );
        }
    }
    Ok(())
}

/// Non-overlapping random spheres at the benchmark's volume fraction, with random forces, and
/// the edges of their cubes.
fn hard_systems(sizes: &[usize], phi: f64) -> Result<(Vec<System>, Vec<f64>)> {
    let mut systems = Vec::new();
    let mut edges = Vec::new();
    for &n in sizes {
        let l = box_edge(n, phi);
        let sbox = colloidsim_particles::SimBox::cube(l);
        let pos = colloidsim_particles::init::random_in_box(n, 2.0 * RADIUS, &sbox, 1, 0)?;
        systems.push((pos, random_system(n, l, 1).1));
        edges.push(l);
    }
    Ok((systems, edges))
}

/// PSE's product against pystokes' periodic Ewald sum (an independent second reference
/// besides the Beenakker sum of the tests), at several tolerances.
fn periodic(a: &BenchArgs) -> Result<()> {
    println!(
        "## PSE (xi = 0.5/a) against pystokes.periodic.Rbm.mobilityTT (Ewald sum, 6 boxes and 6 modes, one product; non-overlapping spheres): relative difference of M F"
    );
    let (systems, edges) = hard_systems(&a.periodic_sizes, a.phi)?;
    let Some(peer) = pystokes(a, &systems, Some(&edges)) else {
        return Ok(());
    };
    println!("N\tL\ttolerance\trel_diff_vs_pystokes_periodic\tpse_product_s\tpystokes_periodic_s");
    let cases = peer["cases"].as_array().cloned().unwrap_or_default();
    for ((p, f), (&l, c)) in systems.iter().zip(edges.iter().zip(&cases)) {
        let v: Vec<f64> = c["velocity"]
            .as_array()
            .map(|a| a.iter().filter_map(|x| x.as_f64()).collect())
            .unwrap_or_default();
        for tol in [1e-2, 1e-3, 1e-4, 1e-5] {
            let (u, secs) = pse_product(p, f, l, tol)?;
            println!(
                "{}\t{l:.2}\t{tol:.0e}\t{:.2e}\t{secs:.3e}\t{:.3e}",
                p.len(),
                relative_difference(u.as_flattened(), &v),
                c["median_s"].as_f64().unwrap_or(f64::NAN)
            );
        }
    }
    Ok(())
}

/// PSE per product and per displacement.
fn pse(a: &BenchArgs, reps: usize) -> Result<()> {
    println!(
        "## PSE (xi = 0.5/a, tolerance {}) per product and per Brownian displacement (new positions + dt M F + sqrt(2 kT dt) M^1/2 z); shares of the displacement",
        a.tolerance
    );
    println!(
        "N\tthreads\tL\tgrid\tsupport\tr_cut\tneighbours\tproduct_s\tstep_s\tfft\tspread\tkernel_noise\tinterp\treal+lanczos\tsetup\tlanczos_iters\tbytes_per_particle"
    );
    for &n in &a.pse_sizes {
        for &t in &a.threads {
            let p = time_pse(n, a.phi, a.tolerance, t, reps)
                .with_context(|| format!("PSE at N = {n}"))?;
            let shares: Vec<String> = (p.times.parts().iter())
                .map(|x| format!("{:.1}%", 100.0 * x / p.step_total))
                .collect();
            println!(
                "{n}\t{t}\t{:.2}\t{}\t{}\t{:.3}\t{:.1}\t{:.4e}\t{:.4e}\t{}\t{:.1}\t{:.0}",
                p.box_length,
                p.geometry.grid,
                p.geometry.support,
                p.geometry.r_cut,
                p.neighbours,
                p.product,
                p.step,
                shares.join("\t"),
                p.times.lanczos_iterations as f64 / reps as f64,
                p.bytes_per_particle
            );
        }
    }
    Ok(())
}

/// PSE's displacement with two radii against one, at the same N, box, splitting and
/// tolerance: the runs alternate (one monodisperse, one bidisperse, `reps` rounds, each the
/// median of 3 steps).
fn bidisperse(a: &BenchArgs, reps: usize) -> Result<()> {
    if !(a.large_fraction > 0.0 && a.large_fraction <= 1.0) {
        anyhow::bail!(
            "--large-fraction must be in (0, 1], got {}",
            a.large_fraction
        );
    }
    println!(
        "## bidisperse PSE: a fraction {} of the spheres of radius {}, the rest {RADIUS} (same N, box as phi = {} of radius {RADIUS}, xi = 0.5/{RADIUS}, tolerance {}); step = new positions + displacement; the two alternate, {reps} rounds of 3 steps each",
        a.large_fraction,
        a.ratio * RADIUS,
        a.phi,
        a.tolerance
    );
    println!(
        "N\tthreads\tmono_step_s\tbi_step_s\tratio_of_medians\tmedian_of_round_ratios\tmono_neighbours\tbi_neighbours\tmono_lanczos_iters\tbi_lanczos_iters\tbi_fft_share"
    );
    let mut parts = Vec::new();
    for &n in &a.bidisperse_sizes {
        for &t in &a.threads {
            let (mut mono, mut bi, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
            let mut last = None;
            for _ in 0..reps {
                let m = time_pse_radii(n, a.phi, a.tolerance, t, 3, 1.0, 0.0)
                    .with_context(|| format!("PSE at N = {n}"))?;
                let b = time_pse_radii(n, a.phi, a.tolerance, t, 3, a.ratio, a.large_fraction)
                    .with_context(|| format!("bidisperse PSE at N = {n}, ratio {}", a.ratio))?;
                mono.push(m.step);
                bi.push(b.step);
                ratios.push(b.step / m.step);
                last = Some((m, b));
            }
            let Some((m, b)) = last else { continue };
            let (mm, mb) = (median(&mut mono), median(&mut bi));
            println!(
                "{n}\t{t}\t{mm:.4e}\t{mb:.4e}\t{:.2}\t{:.2}\t{:.1}\t{:.1}\t{:.1}\t{:.1}\t{:.1}%",
                mb / mm,
                median(&mut ratios),
                m.neighbours,
                b.neighbours,
                m.times.lanczos_iterations as f64 / 3.0,
                b.times.lanczos_iterations as f64 / 3.0,
                100.0 * b.times.fft / b.step_total
            );
            parts.push((n, t, m, b));
        }
    }
    println!(
        "# per part, milliseconds per step (last round): fft, spread, kernel and noise, interpolation, real space and Lanczos, set-up (of it the window weights and spreading order)"
    );
    println!(
        "N\tthreads\tsystem\tfft_ms\tspread_ms\tkernel_ms\tinterp_ms\treal_ms\tsetup_ms\tof_it_weights_ms\tstep_ms"
    );
    for (n, t, m, b) in parts {
        for (name, p) in [("mono", m), ("bi", b)] {
            let ms: Vec<String> = (p.times.parts().iter())
                .chain([&p.times.setup_spreading, &p.step_total])
                .map(|x| format!("{:.2}", 1e3 * x / 3.0))
                .collect();
            println!("{n}\t{t}\t{name}\t{}", ms.join("\t"));
        }
    }
    Ok(())
}

/// A BD+RPY step against a free-draining step of the `bench bd` system.
fn bd_step(a: &BenchArgs, reps: usize) -> Result<()> {
    println!(
        "## Brownian dynamics step, N = {}, phi = {} (the bench bd system: WCA, friction 1, dt = 1e-4): free draining vs RPY by PSE",
        a.bd_n, a.phi
    );
    println!(
        "# the two engines alternate (one free-draining run of 200 steps, then one RPY step, {reps} times); minima are the least disturbed by other load"
    );
    println!(
        "# shares of the RPY steps' time: FFTs, spreading, wave-space kernel and noise, interpolation, real space and Lanczos, set-up (lists, pair tensors, window weights), the rest (integrator, forces)"
    );
    println!(
        "threads\tfree_draining_s\tfd_min_s\trpy_pse_s\trpy_min_s\tratio_of_medians\tratio_of_minima\tfft\tspread\tkernel_noise\tinterp\treal+lanczos\tsetup\tother"
    );
    for &t in &a.threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .context("thread pool")?;
        let row = pool.install(|| -> Result<([f64; 4], [f64; 7])> {
            let mut fd = colloidsim_md::bench::wca_periodic(a.bd_n, a.phi, 1e-4, 1)?;
            let mut hi =
                colloidsim_md::bench::wca_periodic_rpy(a.bd_n, a.phi, 1e-4, 1, a.tolerance)?;
            fd.run(100)?;
            hi.run(2)?;
            if let Some(p) = hi.mobility_mut().pse_mut() {
                p.reset_times();
            }
            let (mut tf, mut th) = (Vec::new(), Vec::new());
            for _ in 0..reps {
                let s = Instant::now();
                fd.run(200)?;
                tf.push(s.elapsed().as_secs_f64() / 200.0);
                let s = Instant::now();
                hi.run(1)?;
                th.push(s.elapsed().as_secs_f64());
            }
            let total: f64 = th.iter().sum();
            let p = hi
                .mobility()
                .pse()
                .map_or_else(Default::default, |p| *p.times());
            let parts = p.parts();
            let other = total - parts.iter().sum::<f64>();
            let mut shares = [0.0; 7];
            for (s, x) in shares.iter_mut().zip(parts.iter().chain([&other])) {
                *s = 100.0 * x / total;
            }
            let (mf, mh) = (median(&mut tf), median(&mut th));
            Ok(([mf, tf[0], mh, th[0]], shares))
        })?;
        let ([mf, f0, mh, h0], shares) = row;
        let shares: Vec<String> = shares.iter().map(|s| format!("{s:.1}%")).collect();
        println!(
            "{t}\t{mf:.4e}\t{f0:.4e}\t{mh:.4e}\t{h0:.4e}\t{:.1}\t{:.1}\t{}",
            mh / mf,
            h0 / f0,
            shares.join("\t")
        );
    }
    Ok(())
}
