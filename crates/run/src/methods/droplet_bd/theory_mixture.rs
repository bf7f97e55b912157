//! `colloidsim theory` for a `droplet-bd` scenario of two or more species: the radial mixture
//! FMT DDFT (White Bear mark I, whose bulk limit is BMCSL; `colloidsim_dft::radial::mixture`),
//! free-draining or with the pairwise unequal-radius RPY flux (`--hydrodynamics rpy`, dilute
//! pair correlation), on the BD run's bins and output times.
//!
//! Each species gets its Stokes diffusivity `kT / (3 pi eta d_s)` and the interface as the BD
//! run's spheres meet it: the same stiffness and range, the wall `(d_s - d) / 2` further in
//! than that of the smallest spheres. Writes `species_profile_<fraction>.csv` (`r`, then
//! `phi_<name>` per species: bin averages of `pi d_s^3 rho_s / 6` on `observe.profile.bins`
//! equal bins of `[0, R(t)]`, as the BD run), `species_profiles.png` and `summary.json` with
//! the mean radius of each species over R(t) and their difference at every output time.

use std::f64::consts::PI;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use colloidsim_core::output::OutputDir;
use colloidsim_dft::radial::mixture::{Functional, MixtureSetup, Species, run_mixture_droplet};
use colloidsim_dft::radial::{EquilibriumOptions, HarmonicInterface, Hydrodynamics, bin_average};
use colloidsim_md::DropletParams;
use serde_json::json;

use crate::control::Control;
use crate::output::plot::{self, Scale, Series};
use crate::output::profile_name;
use crate::{Report, Scenario as Source, TheoryOptions};

/// The mixture DDFT of the validated scenario `p` (grid spacing `dr`, fluxes `hydro`).
pub(super) fn theory(
    src: &Source,
    topts: &TheoryOptions,
    ctl: &Control,
    p: &DropletParams,
    hydro: Hydrodynamics,
    dr: f64,
) -> Result<Report> {
    if topts.pair.as_deref().is_some_and(|x| x != "dilute") {
        bail!("--pair: the mixture DDFT has the dilute pair correlation only");
    }
    let m = &p.species;
    let species = (0..m.len())
        .map(|s| {
            let d = m.diameters[s];
            let wall = HarmonicInterface::new(
                p.stiffness / p.kt,
                p.range,
                p.offset - 0.5 * (d - p.diameter),
            )?;
            Species::stokes(d, m.counts[s] as f64, p.kt, p.viscosity, wall)
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| anyhow!("{}: {e}", src.label()))?;
    let mut order: Vec<usize> = (0..p.fractions.len()).collect();
    let time_of = |k: usize| p.profile_steps[k] as f64 * p.dt;
    order.sort_by(|&a, &b| time_of(a).total_cmp(&time_of(b)));
    let times: Vec<f64> = order.iter().map(|&k| time_of(k)).collect();
    let setup = MixtureSetup {
        species,
        r0: p.r0,
        alpha: p.alpha,
        t_end: times.last().copied().unwrap_or(0.0).max(p.t_end),
        dr,
        functional: Functional::WhiteBear,
        hydrodynamics: hydro,
    };
    setup
        .validate()
        .map_err(|e| anyhow!("{}: {e}", src.label()))?;
    let out = topts
        .out
        .clone()
        .unwrap_or_else(|| format!("{}-theory", src.name()).into());
    let dir = OutputDir::create(&out, topts.force)
        .with_context(|| format!("cannot use output folder {}", out.display()))?;
    let pb = ctl.progress();
    pb.begin("theory", 1000, 0);
    let mut files = Vec::new();
    let mut write_err: Option<anyhow::Error> = None;
    let mut snapshots = Vec::new();
    let mut shown: Vec<(String, Vec<f64>, Vec<f64>)> = Vec::new();
    let mut next = 0usize;
    let start = Instant::now();
    let result = run_mixture_droplet(
        &setup,
        &times,
        &setup.ddft_options(),
        &EquilibriumOptions::default(),
        |grid, s| {
            let fraction = p.fractions[order[next]];
            let last = next + 1 == times.len();
            next += 1;
            let width = s.radius / p.bins as f64;
            let edges: Vec<f64> = (0..=p.bins).map(|k| k as f64 * width).collect();
            let r: Vec<f64> = (0..p.bins).map(|k| (k as f64 + 0.5) * width).collect();
            let mut cols: Vec<(String, Vec<f64>)> = Vec::new();
            for (k, name) in m.names.iter().enumerate() {
                let vp = PI * m.diameters[k].powi(3) / 6.0;
                let phi: Vec<f64> = bin_average(grid, &s.rho[k], &edges)
                    .iter()
                    .map(|x| x * vp)
                    .collect();
                if next == 1 || last {
                    let x = r.iter().map(|x| x / s.radius).collect();
                    let label = format!("{name}, t = {:.0} %", fraction * 100.0);
                    shown.push((label, x, phi.clone()));
                }
                cols.push((format!("phi_{name}"), phi));
            }
            let mut refs: Vec<(&str, &[f64])> = vec![("r", &r)];
            refs.extend(cols.iter().map(|(n, v)| (n.as_str(), v.as_slice())));
            let name = format!("species_{}", profile_name(fraction));
            match dir.write_table(&name, &refs) {
                Ok(_) => files.push(name),
                Err(e) => {
                    write_err.get_or_insert(e.into());
                }
            }
            let mean: Vec<f64> = s.mean_radius.iter().map(|x| x / s.radius).collect();
            let (small, large) = (argmin(&m.diameters), argmax(&m.diameters));
            snapshots.push(json!({
                "fraction": fraction,
                "time": s.time,
                "radius": s.radius,
                "mean_radius": mean,
                "radius_difference": mean[small] - mean[large],
            }));
        },
        |rep| pb.advance((1000.0 * rep.time / p.t_end.max(1e-300)) as u64),
    );
    pb.end();
    let wall = start.elapsed().as_secs_f64();
    if let Some(e) = write_err {
        return Err(e);
    }
    let (status, message) = match &result {
        Ok(_) => ("ok", String::new()),
        Err(e) => ("failed", e.to_string()),
    };
    let summary = json!({
        "method": "droplet-bd",
        "engine": "theory: radial mixture FMT DDFT (White Bear mark I), implicit Euler",
        "hydrodynamics": match hydro {
            Hydrodynamics::FreeDraining => "free-draining",
            Hydrodynamics::Rpy => "rpy (pairwise unequal-radius RPY flux, dilute pair correlation)",
        },
        "software": crate::software(),
        "status": status,
        "message": message,
        "parameters": p,
        "theory": { "dr": dr },
        "stratification": snapshots,
        "particle_number_drift": result.as_ref().ok().map(|o| o.particle_drift.clone()),
        "wall_seconds": wall,
    });
    dir.write_json("summary.json", &summary)?;
    let mut warnings = Vec::new();
    let series: Vec<Series> = shown
        .iter()
        .map(|(label, x, y)| Series {
            label,
            x,
            y,
            points: false,
        })
        .collect();
    if !series.is_empty() {
        plot::picture(
            plot::line_plot_with_errors(
                &dir.join("species_profiles.png"),
                &format!(
                    "Mixture DDFT: species {} (diameters {:?})",
                    m.names.join(", "),
                    m.diameters
                ),
                "r / R(t)",
                "volume fraction phi_k(r)",
                &series,
                &[],
                Scale::Linear,
            ),
            "species_profiles.png",
            &mut files,
            &mut warnings,
        );
    }
    match result {
        Ok(_) => Ok(Report {
            out: dir.path().to_path_buf(),
            summary,
            files,
            warnings,
            message: format!(
                "theory: {} species profiles in {} ({wall:.1} s)",
                snapshots.len(),
                dir.path().display()
            ),
        }),
        Err(e) => Err(anyhow!(
            "{}: {e}; the profiles up to then are in {}",
            src.label(),
            dir.path().display()
        )),
    }
}

fn argmin(v: &[f64]) -> usize {
    (0..v.len()).fold(0, |a, k| if v[k] < v[a] { k } else { a })
}

fn argmax(v: &[f64]) -> usize {
    (0..v.len()).fold(0, |a, k| if v[k] > v[a] { k } else { a })
}
