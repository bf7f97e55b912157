//! `colloidsim run|check` for DPD colloids in explicit solvent (`method = "dpd"`).

use crate::common::{RunOptions, progress, seed32};
use crate::plot::{Scale, Series, line_plot};
use anyhow::{Context, Result, bail};
use colloidsim_analysis::{
    Window, cluster_stats, contacts, coordination_histogram, coordination_numbers, default_q_grid,
    pair_distribution, structure_factor_windowed,
};
use colloidsim_core::output::OutputDir;
use colloidsim_md::dpd::scenario::{DpdScenario, DpdSetup, TemperatureMonitor};
use colloidsim_md::dpd::{Dpd, Thermo};
use colloidsim_md::gsd::GsdWriter;
use serde_json::json;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Parse and validate a scenario, with the seed from the command line if given.
pub fn resolve(path: &Path, text: &str, seed: Option<u64>) -> Result<(DpdScenario, DpdSetup)> {
    let mut sc =
        DpdScenario::from_toml(text).with_context(|| format!("scenario {}", path.display()))?;
    if let Some(s) = seed {
        seed32(s)?;
        sc.seed = s;
    }
    let setup = sc
        .validate()
        .with_context(|| format!("scenario {}", path.display()))?;
    Ok((sc, setup))
}

fn describe(s: &DpdSetup) -> serde_json::Value {
    let p = &s.params;
    let c = &p.colloid;
    json!({
        "box": s.sbox.l,
        "colloids": s.colloids,
        "solvent_beads": s.solvent,
        "colloid_radius": s.radius,
        "radius_distribution": format!("{:?}", s.distribution),
        "density": s.density,
        "solvent_mass": s.solvent_mass,
        "kT": p.kt,
        "gamma": p.gamma,
        "rc": p.rc,
        "repulsion_solvent_solvent": p.repulsion * p.kt / p.rc,
        "colloid_solvent_surface_cutoff": colloidsim_md::dpd::colloid_solvent_cutoff(p.rc, s.radius),
        "colloid_solvent_centre_cutoff": s.radius + colloidsim_md::dpd::colloid_solvent_cutoff(p.rc, s.radius),
        "repulsion_colloid_solvent": p.repulsion_cs * p.kt / colloidsim_md::dpd::colloid_solvent_cutoff(p.rc, s.radius),
        "colloid_colloid_surface_cutoff": p.colloid_cutoff,
        "contact_modulus": c.contact,
        "contact_range": c.contact_range,
        "morse_depth": c.morse_depth,
        "morse_kappa": c.morse_kappa,
        "morse_r0": c.morse_r0,
        "eta0_lubrication": c.eta0,
        "lubrication_gap": c.lubrication_gap,
        "lubrication_noise": format!("{:?}", p.lubrication_noise).to_lowercase(),
        "dt": p.dt,
        "skin": p.skin,
        "steps": s.steps,
        "stokes_einstein_diffusion_D0": s.d0,
        "diffusion_time_tau": s.tau,
        "steps_per_tau": s.tau / p.dt,
        "contact_gap": s.contact_gap,
    })
}

/// `colloidsim check`.
pub fn check(path: &Path, text: &str) -> Result<()> {
    let (_, s) = resolve(path, text, None)?;
    println!("{}", serde_json::to_string_pretty(&describe(&s))?);
    for w in &s.warnings {
        println!("warning: {w}");
    }
    println!("scenario {} is valid", path.display());
    Ok(())
}

/// What a run accumulates.
#[derive(Default)]
struct Observed {
    thermo: Vec<(f64, Thermo)>,
    msd_steps: Vec<u64>,
    colloid_frames: Vec<Vec<[f64; 3]>>,
    solvent_frames: Vec<Vec<[f64; 3]>>,
    gr_sum: Vec<f64>,
    gr_r: Vec<f64>,
    gr_samples: usize,
    coordination: Vec<u64>,
    clusters: Vec<[f64; 5]>,
}

/// MSD at lags of whole frames, averaged over at most ~200 time origins per lag.
fn msd(frames: &[Vec<[f64; 3]>]) -> Vec<f64> {
    let f = frames.len();
    let stride = (f / 200).max(1);
    (1..f)
        .map(|lag| {
            let mut s = 0.0;
            let mut c = 0usize;
            for t0 in (0..f - lag).step_by(stride) {
                for (a, b) in frames[t0].iter().zip(&frames[t0 + lag]) {
                    s += (0..3).map(|k| (b[k] - a[k]).powi(2)).sum::<f64>();
                }
                c += frames[t0].len();
            }
            if c > 0 { s / c as f64 } else { f64::NAN }
        })
        .collect()
}

/// `colloidsim run` for a `dpd` scenario.
pub fn run(path: &Path, text: &str, opts: &RunOptions) -> Result<()> {
    if opts.restart.is_some() {
        bail!(
            "--restart is not supported for dpd runs yet (their GSD trajectory holds the last configuration with velocities; start a new run from it)"
        );
    }
    let (_, s) = resolve(path, text, opts.seed)?;
    for w in &s.warnings {
        eprintln!("warning: {w}");
    }
    let out = OutputDir::create(&opts.out, opts.force)?;
    let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
    let start = Instant::now();
    let mut sim = s.build()?;
    let o = &s.observe;
    let p = sim.snapshot();
    let colloid_tags: Vec<u32> = (0..p.len() as u32)
        .filter(|&t| p.typeid[t as usize] == DpdSetup::COLLOID_TYPE)
        .collect();
    let solvent_tags: Vec<u32> = (0..p.len() as u32)
        .filter(|&t| p.typeid[t as usize] != DpdSetup::COLLOID_TYPE)
        .take(o.msd_solvent_beads)
        .collect();
    let radii: Vec<f64> = colloid_tags
        .iter()
        .map(|&t| 0.5 * p.diameter[t as usize])
        .collect();
    drop(p);
    let mut gsd = if o.trajectory_every > 0 {
        Some(GsdWriter::create_new(&out.join("trajectory.gsd"))?.with_velocities())
    } else {
        None
    };
    let mut obs = Observed::default();
    let mut monitor =
        TemperatureMonitor::new(s.params.kt, s.max_temperature_drift, s.temperature_window);
    let dt = s.params.dt;
    let tau = s.tau;
    let record = |sim: &Dpd, obs: &mut Observed, gsd: &mut Option<GsdWriter>| -> Result<()> {
        let step = sim.step;
        if o.msd_every > 0 && step.is_multiple_of(o.msd_every) {
            let mut a = Vec::new();
            sim.unwrapped(&colloid_tags, &mut a);
            let mut b = Vec::new();
            sim.unwrapped(&solvent_tags, &mut b);
            obs.msd_steps.push(step);
            obs.colloid_frames.push(a);
            obs.solvent_frames.push(b);
        }
        if o.structure_every > 0 && step.is_multiple_of(o.structure_every) && radii.len() >= 2 {
            let snap = sim.snapshot();
            let pos: Vec<[f64; 3]> = colloid_tags.iter().map(|&t| snap.pos[t as usize]).collect();
            let (r, g) = pair_distribution(&pos, sim.sbox.l, s.gr_max, o.gr_bins);
            if obs.gr_sum.is_empty() {
                obs.gr_sum = vec![0.0; g.len()];
                obs.gr_r = r;
            }
            for (a, b) in obs.gr_sum.iter_mut().zip(&g) {
                *a += b;
            }
            obs.gr_samples += 1;
            let bonds = contacts(&pos, &radii, sim.sbox.l, s.contact_gap);
            let z = coordination_numbers(pos.len(), &bonds);
            let h = coordination_histogram(&z);
            if obs.coordination.len() < h.len() {
                obs.coordination.resize(h.len(), 0);
            }
            for (a, b) in obs.coordination.iter_mut().zip(&h) {
                *a += b;
            }
            let cs = cluster_stats(pos.len(), &bonds);
            obs.clusters.push([
                step as f64,
                step as f64 * dt / tau,
                cs.n_clusters as f64,
                cs.largest as f64,
                cs.mean_degree,
            ]);
        }
        if let Some(w) = gsd.as_mut()
            && step.is_multiple_of(o.trajectory_every)
        {
            let snap = sim.snapshot();
            w.write_frame(
                step,
                &sim.sbox,
                &snap,
                false,
                &[("time_tau", step as f64 * dt / tau)],
            )?;
        }
        Ok(())
    };
    record(&sim, &mut obs, &mut gsd)?;
    let pb = progress(s.steps, opts.quiet, "dpd");
    let mut failure: Option<String> = None;
    let check_every = if o.thermo_every > 0 {
        o.thermo_every
    } else {
        100
    };
    while sim.step < s.steps {
        if INTERRUPTED.load(Ordering::SeqCst) {
            failure = Some(format!("interrupted at step {}", sim.step));
            break;
        }
        let next = sim.step + 1;
        let result = if o.thermo_every > 0 && next.is_multiple_of(o.thermo_every) {
            sim.advance_with_thermo().map(|th| {
                obs.thermo.push((next as f64 * dt, th));
            })
        } else {
            sim.advance()
        };
        if let Err(e) = result {
            failure = Some(e.to_string());
            break;
        }
        if next.is_multiple_of(check_every) {
            let t = obs
                .thermo
                .last()
                .filter(|(_, th)| th.step == next)
                .map(|(_, th)| th.temperature)
                .unwrap_or_else(|| sim.thermo().temperature);
            if let Err(e) = monitor.push(next, t) {
                failure = Some(e);
                break;
            }
        }
        record(&sim, &mut obs, &mut gsd)?;
        if next.is_multiple_of(100) {
            pb.set_position(next);
        }
    }
    pb.finish_and_clear();
    if let Some(w) = gsd.as_mut() {
        w.sync()?;
    }
    let wall = start.elapsed().as_secs_f64();
    let files = write_outputs(&out, &s, &sim, &obs, wall, failure.as_deref())?;
    if let Some(f) = failure {
        bail!(
            "{f}\nthe outputs up to step {} are in {} (summary.json says completed = false)",
            sim.step,
            out.path().display()
        );
    }
    if !opts.quiet {
        println!(
            "dpd: {} colloids + {} solvent beads, {} steps ({:.3} tau_D) in {:.1} s -> {}",
            s.colloids,
            s.solvent,
            s.steps,
            s.steps as f64 * dt / tau,
            wall,
            out.path().display()
        );
        println!("wrote {}", files.join(", "));
    }
    Ok(())
}

fn write_outputs(
    out: &OutputDir,
    s: &DpdSetup,
    sim: &Dpd,
    obs: &Observed,
    wall: f64,
    failure: Option<&str>,
) -> Result<Vec<String>> {
    let dt = s.params.dt;
    let tau = s.tau;
    let mut files = Vec::new();
    let vol = sim.sbox.volume();
    // thermo.csv
    if !obs.thermo.is_empty() {
        let rows = &obs.thermo;
        let col = |f: &dyn Fn(&Thermo) -> f64| rows.iter().map(|(_, t)| f(t)).collect::<Vec<_>>();
        let tr = |v: &[f64; 6]| (v[0] + v[1] + v[2]) / (3.0 * vol);
        let step = col(&|t| t.step as f64);
        let time: Vec<f64> = rows.iter().map(|(t, _)| *t).collect();
        let time_tau: Vec<f64> = time.iter().map(|t| t / tau).collect();
        let tt = col(&|t| t.temperature);
        let ts = col(&|t| t.temperature_by_type[0]);
        let tc = col(&|t| t.temperature_by_type.get(1).copied().unwrap_or(f64::NAN));
        let pk: Vec<Vec<f64>> = (0..6).map(|k| col(&|t| t.pressure[k])).collect();
        let p = col(&|t| (t.pressure[0] + t.pressure[1] + t.pressure[2]) / 3.0);
        let pkin = col(&|t| (t.kinetic[0] + t.kinetic[1] + t.kinetic[2]) / 3.0);
        let pc = col(&|t| tr(&t.virial.conservative));
        let pd = col(&|t| tr(&t.virial.dissipative));
        let pr = col(&|t| tr(&t.virial.random));
        let pcon = col(&|t| tr(&t.virial.contact));
        let pm = col(&|t| tr(&t.virial.morse));
        let pl = col(&|t| tr(&t.virial.lubrication));
        let ec = col(&|t| t.virial.energy_conservative);
        let econ = col(&|t| t.virial.energy_contact);
        let em = col(&|t| t.virial.energy_morse);
        let ep = col(&|t| t.potential_energy);
        out.write_table(
            "thermo.csv",
            &[
                ("step", &step),
                ("time", &time),
                ("time_tau", &time_tau),
                ("T", &tt),
                ("T_solvent", &ts),
                ("T_colloid", &tc),
                ("p", &p),
                ("pxx", &pk[0]),
                ("pyy", &pk[1]),
                ("pzz", &pk[2]),
                ("pxy", &pk[3]),
                ("pxz", &pk[4]),
                ("pyz", &pk[5]),
                ("p_kinetic", &pkin),
                ("p_conservative", &pc),
                ("p_dissipative", &pd),
                ("p_random", &pr),
                ("p_contact", &pcon),
                ("p_morse", &pm),
                ("p_lubrication", &pl),
                ("energy_conservative", &ec),
                ("energy_contact", &econ),
                ("energy_morse", &em),
                ("energy_potential", &ep),
            ],
        )?;
        files.push("thermo.csv".to_string());
    }
    // msd.csv
    let mut diffusion = None;
    if obs.msd_steps.len() >= 2 {
        let mc = msd(&obs.colloid_frames);
        let ms = msd(&obs.solvent_frames);
        let lag_steps: Vec<f64> = (1..obs.msd_steps.len())
            .map(|k| (obs.msd_steps[k] - obs.msd_steps[0]) as f64)
            .collect();
        let time: Vec<f64> = lag_steps.iter().map(|l| l * dt).collect();
        let time_tau: Vec<f64> = time.iter().map(|t| t / tau).collect();
        out.write_table(
            "msd.csv",
            &[
                ("lag_steps", &lag_steps),
                ("time", &time),
                ("time_tau", &time_tau),
                ("msd_colloid", &mc),
                ("msd_solvent", &ms),
            ],
        )?;
        files.push("msd.csv".into());
        // Long-time colloid diffusion: slope of the MSD over the second half of the lags
        // (least squares), D = slope / 6.
        let n = mc.len();
        if s.colloids > 0 && n >= 4 {
            let (a, b) = (n / 2, n);
            let xs = &time[a..b];
            let ys = &mc[a..b];
            let mx = xs.iter().sum::<f64>() / xs.len() as f64;
            let my = ys.iter().sum::<f64>() / ys.len() as f64;
            let sxy: f64 = xs.iter().zip(ys).map(|(x, y)| (x - mx) * (y - my)).sum();
            let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
            if sxx > 0.0 {
                diffusion = Some(sxy / sxx / 6.0);
            }
        }
        let series = [
            Series {
                label: "colloids",
                x: &time_tau,
                y: &mc,
                points: false,
            },
            Series {
                label: "solvent beads",
                x: &time_tau,
                y: &ms,
                points: false,
            },
        ];
        let n_series = if s.colloids > 0 { 2 } else { 1 };
        line_plot(
            &out.join("msd.png"),
            &format!(
                "MSD, DPD colloids (phi = {:.3}, {} colloids)",
                s.colloids as f64 * 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3) / vol,
                s.colloids
            ),
            "t / tau_D",
            "mean-squared displacement [rc^2]",
            &series[2 - n_series..],
            Scale::LogLog,
        )?;
        files.push("msd.png".into());
    }
    // g(r), S(q), coordination, clusters
    if obs.gr_samples > 0 {
        let g: Vec<f64> = obs
            .gr_sum
            .iter()
            .map(|x| x / obs.gr_samples as f64)
            .collect();
        let r = &obs.gr_r;
        let r_over_d: Vec<f64> = r.iter().map(|x| x / (2.0 * s.radius)).collect();
        out.write_table(
            "gr.csv",
            &[("r", r), ("r_over_diameter", &r_over_d), ("g", &g)],
        )?;
        files.push("gr.csv".into());
        let rho = s.colloids as f64 / vol;
        let q = default_q_grid(s.gr_max, g.len());
        let sq = structure_factor_windowed(r, &g, rho, &q, Window::Lorch);
        let q_d: Vec<f64> = q.iter().map(|x| x * 2.0 * s.radius).collect();
        out.write_table("sq.csv", &[("q", &q), ("q_diameter", &q_d), ("S", &sq)])?;
        files.push("sq.csv".into());
        line_plot(
            &out.join("gr.png"),
            &format!("Colloid g(r), {} samples", obs.gr_samples),
            "r / (2 R_c)",
            "g(r)",
            &[Series {
                label: "colloids",
                x: &r_over_d,
                y: &g,
                points: false,
            }],
            Scale::Linear,
        )?;
        files.push("gr.png".into());
        let total: u64 = obs.coordination.iter().sum();
        let z: Vec<f64> = (0..obs.coordination.len()).map(|k| k as f64).collect();
        let pz: Vec<f64> = obs
            .coordination
            .iter()
            .map(|&c| c as f64 / total.max(1) as f64)
            .collect();
        out.write_table("coordination.csv", &[("z", &z), ("probability", &pz)])?;
        files.push("coordination.csv".into());
        let col = |k: usize| obs.clusters.iter().map(|r| r[k]).collect::<Vec<f64>>();
        out.write_table(
            "clusters.csv",
            &[
                ("step", &col(0)),
                ("time_tau", &col(1)),
                ("clusters", &col(2)),
                ("largest", &col(3)),
                ("mean_degree", &col(4)),
            ],
        )?;
        files.push("clusters.csv".into());
    }
    if s.observe.trajectory_every > 0 {
        files.push("trajectory.gsd".into());
    }
    let last = obs.thermo.last().map(|(_, t)| t.clone());
    let n = (s.colloids + s.solvent) as f64;
    let summary = json!({
        "software": format!("colloidsim {}", env!("CARGO_PKG_VERSION")),
        "method": "dpd",
        "seed": s.params.seed,
        "parameters": describe(s),
        "completed": failure.is_none(),
        "error": failure,
        "steps": sim.step,
        "time": sim.step as f64 * dt,
        "time_tau": sim.step as f64 * dt / tau,
        "wall_seconds": wall,
        "particle_steps_per_second": n * sim.step as f64 / wall,
        "threads": rayon::current_num_threads(),
        "neighbor_builds": sim.neighbor_builds(),
        "final_temperature": last.as_ref().map(|t| t.temperature),
        "final_temperature_by_type": last.as_ref().map(|t| t.temperature_by_type.clone()),
        "mean_temperature_second_half": mean_second_half(&obs.thermo, |t| t.temperature),
        "mean_colloid_temperature_second_half": mean_second_half(&obs.thermo, |t| t.temperature_by_type.get(1).copied().unwrap_or(f64::NAN)),
        "mean_pressure_second_half": mean_second_half(&obs.thermo, |t| (t.pressure[0] + t.pressure[1] + t.pressure[2]) / 3.0),
        "colloid_diffusion_long_time": diffusion,
        "colloid_diffusion_over_stokes_einstein": diffusion.map(|d| d / s.d0),
        "files": files,
    });
    out.write_json("summary.json", &summary)?;
    files.push("summary.json".into());
    Ok(files)
}

fn mean_second_half(rows: &[(f64, Thermo)], f: impl Fn(&Thermo) -> f64) -> Option<f64> {
    let h = &rows[rows.len() / 2..];
    if h.is_empty() {
        None
    } else {
        Some(h.iter().map(|(_, t)| f(t)).sum::<f64>() / h.len() as f64)
    }
}
