//! `colloidsim theory` for a `droplet-bd` scenario of two or more species: the radial mixture
//! FMT DDFT (White Bear mark I, whose bulk limit is BMCSL; `colloidsim_dft::radial::mixture`),
//! free-draining or with the pairwise unequal-radius RPY flux (`--hydrodynamics rpy`; `--pair
//! dilute`, `trokhymchuk` or `trokhymchuk-n3`: Trokhymchuk's one-size `g` scaled to each pair's
//! BMCSL contact value, `colloidsim_dft::radial::mixture::rpy`), on the BD run's bins and output
//! times. `summary.json` says how far the drying got (`reached`) and, for RPY, the pair
//! correlation; a run stopped by ejection has status `unphysical`.
//!
//! Each species gets its Stokes diffusivity `kT / (3 pi eta d_s)` and the interface as the BD
//! run's spheres meet it: the same stiffness and range, the wall `(d_s - d) / 2` further in
//! than that of the smallest spheres. Writes `species_profile_<fraction>.csv` (`r`, then
//! `phi_<name>` per species: bin averages of `pi d_s^3 rho_s / 6` on `observe.profile.bins`
//! equal bins of `[0, R(t)]`, as the BD run), `species_profiles.png` and `summary.json` with
//! the mean radius of each species over R(t) and their difference at every output time.

use std::f64::consts::PI;
use std::time::Instant;

use anyhow::{Result, anyhow};
use colloidsim_dft::radial::mixture::mixture_volume_fraction;
use colloidsim_dft::radial::mixture::{Functional, MixtureSetup, Species, run_mixture_droplet};
use colloidsim_dft::radial::{
    EquilibriumOptions, HarmonicInterface, Hydrodynamics, PairCorrelation, RadialError, bin_average,
};
use colloidsim_md::DropletParams;
use serde_json::json;

use crate::control::Control;
use crate::output::profile_name;
use crate::output::species::draw_species_profiles;
use crate::{Report, Scenario as Source, TheoryOptions};

/// The mixture DDFT of the droplet `p` up to `t_end` (grid spacing `dr`, fluxes `hydro`): each
/// species with its Stokes diffusivity and the interface as the BD spheres of its size meet
/// it (`SpeciesInterface`: the wall `(d_s - d) / 2` further in), White Bear mark I.
pub(super) fn mixture_setup(
    p: &DropletParams,
    hydro: Hydrodynamics,
    dr: f64,
    t_end: f64,
) -> Result<MixtureSetup, RadialError> {
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
        .collect::<Result<Vec<_>, _>>()?;
    Ok(MixtureSetup {
        species,
        r0: p.r0,
        alpha: p.alpha,
        t_end,
        dr,
        functional: Functional::WhiteBear,
        hydrodynamics: hydro,
        pair: Default::default(),
    })
}

/// The mixture DDFT of the validated scenario `p` (grid spacing `dr`, fluxes `hydro`, pair
/// correlation `pair` of the RPY flux).
#[allow(clippy::too_many_arguments)]
pub(super) fn theory(
    src: &Source,
    topts: &TheoryOptions,
    ctl: &Control,
    p: &DropletParams,
    hydro: Hydrodynamics,
    pair: PairCorrelation,
    dr: f64,
) -> Result<Report> {
    let m = &p.species;
    let mut order: Vec<usize> = (0..p.fractions.len()).collect();
    let time_of = |k: usize| p.profile_steps[k] as f64 * p.dt;
    order.sort_by(|&a, &b| time_of(a).total_cmp(&time_of(b)));
    let times: Vec<f64> = order.iter().map(|&k| time_of(k)).collect();
    let t_end = times.last().copied().unwrap_or(0.0).max(p.t_end);
    let mut setup =
        mixture_setup(p, hydro, dr, t_end).map_err(|e| anyhow!("{}: {e}", src.label()))?;
    setup.pair = pair;
    let schedule = setup
        .validate()
        .map_err(|e| anyhow!("{}: {e}", src.label()))?;
    let dir = crate::theory_folder(src, topts)?;
    let pb = ctl.progress();
    pb.begin("theory", 1000, 0);
    let mut files = Vec::new();
    let mut write_err: Option<anyhow::Error> = None;
    let mut snapshots = Vec::new();
    let mut shown: Vec<(String, Vec<f64>, Vec<f64>)> = Vec::new();
    let mut next = 0usize;
    let start = Instant::now();
    let mut reached = 0.0f64;
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
                cols.push((format!("rho_v_{name}"), phi));
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
        |rep| {
            reached = rep.time;
            pb.advance((1000.0 * rep.time / p.t_end.max(1e-300)) as u64)
        },
    )
    .map_err(super::theory::relabel);
    pb.end();
    let wall = start.elapsed().as_secs_f64();
    if let Some(e) = write_err {
        return Err(e);
    }
    let (status, message) = match &result {
        Ok(_) => ("ok", String::new()),
        Err(e @ RadialError::Unphysical { .. }) => ("unphysical", e.to_string()),
        Err(e) => ("failed", e.to_string()),
    };
    let radius_reached = schedule.radius(reached)?;
    let mut summary = json!({
        "method": "droplet-bd",
        "engine": "theory: radial mixture FMT DDFT (White Bear mark I), implicit Euler",
        "hydrodynamics": match hydro {
            Hydrodynamics::FreeDraining => "free-draining",
            Hydrodynamics::Rpy => match pair {
                PairCorrelation::Dilute =>
                    "rpy (pairwise unequal-radius RPY flux, dilute pair correlation)",
                PairCorrelation::Trokhymchuk =>
                    "rpy (pairwise unequal-radius RPY flux, Trokhymchuk g scaled to BMCSL contact values at the mean local packing)",
                PairCorrelation::TrokhymchukWeighted =>
                    "rpy (pairwise unequal-radius RPY flux, Trokhymchuk g scaled to BMCSL contact values at the mean weighted packing n3)",
            },
        },
        "software": crate::software(),
        "status": status,
        "message": message,
        "parameters": p,
        "theory": { "dr": dr },
        "stratification": snapshots,
        "particle_number_drift": result.as_ref().ok().map(|o| o.particle_drift.clone()),
        "reached": {
            "time": reached,
            "fraction_of_drying_time": reached / t_end.max(1e-300),
            "radius": radius_reached,
            "mean_volume_fraction": mixture_volume_fraction(&setup.species, radius_reached),
        },
        "wall_seconds": wall,
    });
    if hydro == Hydrodynamics::Rpy {
        summary["pair_correlation"] = pair.name().into();
    }
    dir.write_json("summary.json", &summary)?;
    let mut warnings = Vec::new();
    if !shown.is_empty() {
        draw_species_profiles(
            &dir,
            &format!(
                "Mixture DDFT: species {} (diameters {:?})",
                m.names.join(", "),
                m.diameters
            ),
            "r / R(t)",
            &shown,
            &[],
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

#[cfg(test)]
mod tests {
    use super::*;
    use colloidsim_dft::radial::mixture::mixture_equilibrium_at;

    /// Static bidisperse droplet (issue 43, "Checks"): BD of a binary WCA mixture (d and 2d,
    /// equal volumes, mean phi 0.2, R = 6 d: 186 + 20 spheres) against the binary White Bear
    /// equilibrium of the same numbers in the same per-size interface. 3 replicas sampled every
    /// 0.5 d^2/D0_s from t = 4 to 12 d^2/D0_s after random insertion (the large spheres'
    /// slowest relaxation, ~R^2 / (pi^2 D_coll,l), is ~3 d^2/D0_s). Per species, the fractions
    /// of its centres within d_k/4 and within d_k of its own wall; binomial error over N_k x
    /// snapshots, tolerance 4 sigma + 3e-3 (WCA against hard spheres). A theory whose large
    /// spheres meet the wall of the small ones (no (d_l - d_s)/2 shift) must fail.
    #[test]
    fn binary_equilibrium_theory_matches_brownian_dynamics_in_a_static_droplet() {
        let text = r#"
            method = "droplet-bd"
            replicas = 3
            [system]
            particles = 206
            radius = 6.0
            [system.species]
            diameters = [1.0, 2.0]
            counts = [186, 20]
            [drying]
            peclet = 1e-6
            duration = 188.5
            [observe.profile]
            fractions = [0.0]
        "#;
        let p = super::super::params::read(
            &toml::from_str(text).unwrap(),
            std::path::Path::new("."),
            None,
        )
        .unwrap();
        let m = &p.species;
        let tau = p.diameter * p.diameter / p.d0;
        // Each species' wall, and the cuts d_k/4 and d_k inside it.
        let cuts: Vec<[f64; 2]> = m
            .diameters
            .iter()
            .map(|&d| {
                let edge = p.r0 + p.offset - 0.5 * (d - p.diameter);
                [edge - 0.25 * d, edge - d]
            })
            .collect();
        let mut bd = vec![[0.0; 2]; m.len()];
        let mut samples = 0.0;
        for rep in 0..p.replicas {
            let mut sim = p.build_replica(rep as u32).unwrap();
            for snap in 0..17 {
                let t = 4.0 + 0.5 * snap as f64;
                let stop = (t * tau / p.dt).round() as u64;
                sim.run(stop - sim.step).unwrap();
                let parts = sim.particles();
                for (x, &ty) in parts.pos.iter().zip(&parts.typeid) {
                    let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
                    let k = ty as usize;
                    for (c, out) in cuts[k].iter().zip(bd[k].iter_mut()) {
                        if r > *c {
                            *out += 1.0 / m.counts[k] as f64;
                        }
                    }
                }
                samples += 1.0;
            }
        }
        bd.iter_mut().flatten().for_each(|x| *x /= samples);
        let theory = |shift: bool| {
            let mut setup = mixture_setup(&p, Hydrodynamics::FreeDraining, 0.02, 0.0).unwrap();
            if !shift {
                for s in setup.species.iter_mut() {
                    s.interface =
                        HarmonicInterface::new(p.stiffness / p.kt, p.range, p.offset).unwrap();
                }
            }
            let (g, eq) =
                mixture_equilibrium_at(&setup, p.r0, &EquilibriumOptions::default()).unwrap();
            let cells = eq.rho.len() / m.len();
            (0..m.len())
                .map(|k| {
                    let rho = &eq.rho[k * cells..(k + 1) * cells];
                    cuts[k].map(|c| {
                        let inner = bin_average(&g, rho, &[0.0, c])[0] * 4.0 * PI / 3.0 * c.powi(3);
                        1.0 - inner / m.counts[k] as f64
                    })
                })
                .collect::<Vec<_>>()
        };
        let worst = |th: &[[f64; 2]]| {
            let mut w = 0.0f64;
            for k in 0..m.len() {
                for j in 0..2 {
                    let n = m.counts[k] as f64 * samples;
                    let sigma = (th[k][j] * (1.0 - th[k][j]) / n).sqrt();
                    w = w.max((bd[k][j] - th[k][j]).abs() / (4.0 * sigma + 3e-3));
                }
            }
            w
        };
        let good = theory(true);
        let wrong = theory(false);
        eprintln!(
            "BD {bd:?}\ntheory {good:?} (worst {:.2})\nunshifted walls {wrong:?} (worst {:.2})",
            worst(&good),
            worst(&wrong)
        );
        assert!(worst(&good) < 1.0);
        assert!(worst(&wrong) > 1.0);
    }
}
