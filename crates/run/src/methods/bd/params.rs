//! A `bd` scenario read through its key declarations ([`super::keys`]) into the engine's
//! parameters ([`BulkParams`]), with every check that relates several keys, each error naming
//! the key and the allowed range.

use super::keys::*;
use crate::keys::shared::{
    self, HYDRO_MAX_ITERATIONS, HYDRO_SPLITTING, HYDRO_TOLERANCE, HYDRODYNAMICS, RUN_DT, RUN_SKIN,
    RUN_TUNE_SKIN, Spheres, TRAJECTORY_EVERY,
};
use crate::keys::{Reader, SEED_KEY, Spec, rekey};
use anyhow::{Result, bail};
use colloidsim_core::ParamError;
use colloidsim_core::param::show;
use colloidsim_md::brownian::bulk::{BulkParams, MAX_BODY_DRIFT, WCA_RANGE};
use colloidsim_md::brownian::droplet::{MAX_PHI_FINAL, MAX_PHI0};
use colloidsim_md::hydro::{HydroError, HydroModel, PseGeometry};
use colloidsim_particles::Pair;
use std::f64::consts::PI;
use std::path::Path;

/// The PSE engine's names of its parameters, and the keys that set them.
const ENGINE_NAMES: &[(&str, &Spec)] = &[
    ("splitting", &HYDRO_SPLITTING),
    ("tolerance", &HYDRO_TOLERANCE),
    ("max_iterations", &HYDRO_MAX_ITERATIONS),
    ("box_length", &SYSTEM_BOX_LENGTH),
    // The PSE engine's sphere radius: half the diameter.
    ("radius", &shared::DIAMETER),
    ("hydrodynamics", &HYDRODYNAMICS),
];

/// A scenario's table checked against [`KEYS`] and resolved (with `seed` replacing the
/// scenario's); `system.initial` is taken relative to `base`.
pub fn read(table: &toml::Table, base: &Path, seed: Option<u64>) -> Result<BulkParams> {
    let r = Reader::new(table, KEYS)?;
    resolve(&r, base, seed)
}

/// `key` must lie in `[lo, hi]`.
fn within(key: &Spec, x: f64, lo: f64, hi: f64) -> Result<f64, ParamError> {
    colloidsim_core::param::in_range(key.path, x, lo, hi)
}

/// Every key read and checked against the others, in the order the checks were always made.
fn resolve(r: &Reader, base: &Path, seed: Option<u64>) -> Result<BulkParams> {
    let seed = colloidsim_core::param::seed(SEED_KEY.path, seed.unwrap_or(r.count(&SEED_KEY)?))?;
    let replicas = r.count(&REPLICAS)? as usize;
    let particles = r.count(&SYSTEM_PARTICLES)? as usize;
    let Spheres {
        d,
        kt,
        eta,
        friction,
        d0,
    } = shared::spheres(r)?;
    let species = crate::keys::species::species(r, particles, d, &shared::DIAMETER)?;
    let l = r.number(&SYSTEM_BOX_LENGTH)?;
    let initial = r.file(&SYSTEM_INITIAL).map(|f| base.join(f));
    let n = particles as f64;
    // Spheres of diameter d with the particles' volume (N for one species).
    let n_equivalent = species.equivalent_number(d);
    let phi = n_equivalent * PI * d.powi(3) / (6.0 * l.powi(3));
    // Random insertion packs to MAX_PHI0; a configuration read from a file may be denser.
    let (max_phi, how) = if initial.is_some() {
        (MAX_PHI_FINAL, "random close packing")
    } else {
        (
            MAX_PHI0,
            "random insertion of hard spheres; start from a GSD file (system.initial) for more",
        )
    };
    if phi > max_phi {
        bail!(ParamError::new(
            SYSTEM_BOX_LENGTH.path,
            format!(
                "{particles} spheres of {} in a cube of edge {} give phi = {phi:.4}, \
                 above {max_phi} ({how}); the edge must be at least {:.4}",
                if species.is_single() {
                    format!("diameter {}", show(d))
                } else {
                    format!("diameters {:?}", species.diameters)
                },
                show(l),
                d * (n_equivalent * PI / (6.0 * max_phi)).cbrt()
            ),
        ));
    }

    let dt = r.number(&RUN_DT)?;
    let time = r.number(&RUN_TIME)?;
    let equilibrate = r.number(&RUN_EQUILIBRATE)?;
    let skin = within(&RUN_SKIN, r.number(&RUN_SKIN)?, 1e-3 * d, 5.0 * d)?;
    let pair = crate::keys::species::pair(r, &species, kt, base)?;
    let d_max = species.d_max();
    let r_cut = match &pair {
        Some(spec) => spec.build(&species.diameters, kt)?.r_cut_max(),
        None => WCA_RANGE * d_max,
    };
    let range = r_cut + skin;
    if l <= 2.0 * range {
        bail!(ParamError::new(
            SYSTEM_BOX_LENGTH.path,
            format!(
                "an edge of {} is too small for the neighbour range (pair cut-off + run.skin) = {range:.4}: \
                 it must exceed twice that, {:.4} (or lower run.skin)",
                show(l),
                2.0 * range
            ),
        ));
    }
    let blocks = r.count(&OBSERVE_BLOCKS)? as usize;
    let per_block = (time / dt / blocks as f64).ceil();
    let equilibrate_steps = (equilibrate / dt).round();
    if per_block * blocks as f64 + equilibrate_steps > 1e12 {
        bail!(ParamError::new(
            RUN_DT.path,
            format!(
                "{:.3e} steps per replica: run.dt = {} is far too small for run.time = {} \
                 (and run.equilibrate); at most 1e12 steps",
                per_block * blocks as f64 + equilibrate_steps,
                show(dt),
                show(time)
            ),
        ));
    }
    let block_steps = per_block as u64;
    if block_steps < 4 {
        bail!(ParamError::new(
            RUN_TIME.path,
            format!(
                "{} in {blocks} block(s) of run.dt = {} is {block_steps} step(s) per block; \
                 at least 4 are needed (a longer run.time, a smaller run.dt or fewer observe.blocks)",
                show(time),
                show(dt)
            ),
        ));
    }
    let sampled_steps = block_steps * blocks as u64;
    let equilibrate_steps = equilibrate_steps as u64;

    let given = r.numbers(&SYSTEM_BODY_FORCE)?;
    let body_force = [given[0], given[1], given[2]];
    if let Some(k) = body_force.iter().position(|f| !f.is_finite()) {
        bail!(ParamError::new(
            SYSTEM_BODY_FORCE.path,
            format!("component {k} is {}: must be finite", body_force[k]),
        ));
    }
    let force = body_force.iter().map(|f| f * f).sum::<f64>().sqrt();
    // The largest spheres move the most for their size: F (D/d)^3 dt / (3 pi eta D) against
    // 0.1 D (one species: F dt / (3 pi eta d) against 0.1 d).
    let ratio = d_max / d;
    let scale = if species.is_single() {
        1.0
    } else {
        ratio * ratio
    };
    let drift = force * scale * dt / friction;
    if drift > MAX_BODY_DRIFT * d_max {
        let (what, limit) = if species.is_single() {
            (
                "F dt / (3 pi eta d)".to_string(),
                format!("{MAX_BODY_DRIFT} d"),
            )
        } else {
            (
                format!(
                    "F (D/d)^3 dt / (3 pi eta D) for the largest spheres, D = {}",
                    show(d_max)
                ),
                format!("{MAX_BODY_DRIFT} D"),
            )
        };
        bail!(ParamError::new(
            SYSTEM_BODY_FORCE.path,
            format!(
                "a force of magnitude {} moves a sphere {} per step of run.dt = {} ({what}), \
                 more than {limit}: at most {:.4e} at this time step, or a smaller run.dt",
                show(force),
                show(drift),
                show(dt),
                MAX_BODY_DRIFT * d_max * friction / (scale * dt)
            ),
        ));
    }

    let hydrodynamics = shared::hydrodynamics(r, &HYDRO_METHOD, None, particles, 0.5 * d, true)?;
    let rpy = hydrodynamics
        .as_ref()
        .is_some_and(|h| h.model == HydroModel::Rpy);
    let integrator = shared::integrator(r, rpy)?;
    let tune_skin = r.flag(&RUN_TUNE_SKIN)?;
    if tune_skin && rpy {
        bail!(ParamError::new(
            RUN_TUNE_SKIN.path,
            "applies to free-draining runs only: with RPY hydrodynamics the mobility's cost, not \
             the neighbour list's, decides a step (set run.skin, or leave out [hydrodynamics])",
        ));
    }

    let msd_points = r.count(&OBSERVE_MSD_POINTS)? as usize;
    let msd_max_lag = match r.opt_number(&OBSERVE_MSD_MAX_LAG)? {
        None => (block_steps / 4).max(4),
        Some(t) => (t / dt).round().min(1e12) as u64,
    };
    if msd_max_lag < 4 || msd_max_lag > block_steps {
        bail!(ParamError::new(
            OBSERVE_MSD_MAX_LAG.path,
            format!(
                "{msd_max_lag} steps: must lie in [4 run.dt, one block of the sampled time] = [{}, {}] \
                 (run.time / observe.blocks; the diffusion coefficient is the slope between a \
                 quarter of it and itself)",
                show(4.0 * dt),
                show(block_steps as f64 * dt)
            ),
        ));
    }
    let msd_origin_every = (msd_max_lag / 8).max(1);

    let mut p = BulkParams {
        seed,
        replicas,
        particles,
        box_length: l,
        diameter: d,
        species,
        pair,
        kt,
        viscosity: eta,
        friction,
        d0,
        diffusion_time: d * d / d0,
        phi,
        body_force,
        force,
        peclet: force * d / kt,
        dt,
        integrator,
        skin,
        tune_skin,
        skin_tuning: None,
        equilibrate_steps,
        sampled_steps,
        steps: equilibrate_steps + sampled_steps,
        blocks,
        block_steps,
        msd_points,
        msd_max_lag,
        msd_origin_every,
        trajectory_every: r.count(&TRAJECTORY_EVERY)?,
        initial,
        hydrodynamics,
        pse: None,
    };
    if let Some(h) = p.hydrodynamics.as_ref().filter(|_| rpy) {
        let key = if r.has(&HYDRO_SPLITTING) {
            &HYDRO_SPLITTING
        } else {
            &SYSTEM_BOX_LENGTH
        };
        h.check_pse_extent(l, key.path)?;
        // PSE's radii are the species' when there are several.
        let single = p.species.is_single();
        let g =
            PseGeometry::with_radii(&p.pse_params(h), &p.species_radii()).map_err(|e| match e {
                HydroError::Param(e) if e.key == "radius" && !single => {
                    rekey(e, &[("radius", &crate::keys::species::SPECIES_DIAMETERS)])
                }
                HydroError::Param(e) => rekey(e, ENGINE_NAMES),
                other => ParamError::new(HYDRODYNAMICS.path, other.to_string()),
            })?;
        p.pse = Some(g);
    }
    // Memory before anything is allocated: about 400 B per particle (state, lists,
    // copies), 24 B per neighbour cell, the stored MSD origins, the PSE grids and lists.
    let cells = (l / range).powi(3);
    let origins = (msd_max_lag / msd_origin_every + 2) as f64;
    let pse = p.pse.map_or(0.0, |g| {
        g.grid_bytes() as f64 + g.species_bytes(p.species.len()) as f64 + 4.1e3 * n
    });
    colloidsim_core::resources::ensure_fits(
        SYSTEM_PARTICLES.path,
        &format!(
            "{particles} spheres in a box of {cells:.3e} neighbour cells with {origins} MSD origins"
        ),
        400.0 * n + 24.0 * cells + 24.0 * n * origins + pse,
    )?;
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use colloidsim_md::Integrator;
    use colloidsim_md::brownian::bulk::dilute_sedimentation;
    use colloidsim_md::hydro::ewald::hasimoto;

    const BASE: &str = r#"
method = "bd"
seed = 3
[system]
particles = 40
box_length = 8.87
body_force = [0.0, 0.0, -5.0]
[run]
dt = 0.005
time = 4.0
[hydrodynamics]
model = "rpy"
"#;

    /// A scenario with every table and every key, so that every key is read.
    const FULL: &str = r#"
method = "bd"
seed = 3
replicas = 2
[system]
particles = 40
box_length = 8.87
diameter = 1.0
kT = 1.0
viscosity = 1.0
body_force = [0.0, 0.0, -5.0]
initial = "start.gsd"
[run]
time = 4.0
dt = 0.005
equilibrate = 1.0
skin = 0.5
integrator = "euler"
[observe]
blocks = 8
[observe.msd]
points = 20
max_lag = 0.1
[observe.trajectory]
every = 100
[hydrodynamics]
model = "rpy"
method = "pse"
tolerance = 1e-3
splitting = 1.0
max_iterations = 100
"#;

    fn parse(text: &str) -> Result<BulkParams> {
        read(&toml::from_str(text).unwrap(), Path::new("/base"), None)
    }

    /// The key an error names (a [`ParamError`]'s, or the declaration check's).
    fn err_key(text: &str) -> String {
        let e = parse(text).unwrap_err();
        match e.downcast_ref::<ParamError>() {
            Some(p) => p.key.clone(),
            None => e.to_string().split(':').next().unwrap().to_string(),
        }
    }

    #[test]
    fn every_declared_key_is_read() {
        let t: toml::Table = toml::from_str(FULL).unwrap();
        let r = Reader::new(&t, KEYS).unwrap();
        let p = resolve(&r, Path::new("/base"), None).unwrap();
        // The species and pair keys are read by kind (one scenario cannot give them all):
        // tests/species.rs reads each.
        let unread: Vec<&str> = r
            .unread()
            .into_iter()
            .filter(|k| !k.starts_with("pair.") && !k.starts_with("system.species."))
            .collect();
        assert_eq!(unread, Vec::<&str>::new());
        assert_eq!(p.initial.as_deref(), Some(Path::new("/base/start.gsd")));
        assert_eq!((p.replicas, p.msd_points, p.msd_max_lag), (2, 20, 20));
        assert_eq!((p.equilibrate_steps, p.trajectory_every), (200, 100));
        assert_eq!(p.hydrodynamics.unwrap().max_iterations, 100);
    }

    #[test]
    fn derived_defaults_are_computed_from_the_keys_they_name() {
        let text = BASE.replace("dt = 0.005\n", "").replace(
            "box_length = 8.87",
            "box_length = 20.0\ndiameter = 2.0\nviscosity = 3.0",
        );
        let p = parse(&text.replace("[hydrodynamics]\nmodel = \"rpy\"\n", "")).unwrap();
        assert_eq!(p.d0, 1.0 / (3.0 * PI * 3.0 * 2.0));
        assert_eq!(p.dt, 2e-4 * 4.0 / p.d0);
        assert_eq!(p.skin, 0.6 * 2.0);
        assert_eq!(
            (p.blocks, p.msd_points, p.integrator),
            (8, 30, Integrator::Euler)
        );
        assert_eq!(p.msd_max_lag, (p.block_steps / 4).max(4));
        assert!(p.hydrodynamics.is_none() && p.pse.is_none());
    }

    #[test]
    fn a_scenario_resolves_to_blocks_lags_and_pse() {
        let p = parse(BASE).unwrap();
        assert!((p.phi - 40.0 * PI / 6.0 / 8.87f64.powi(3)).abs() < 1e-15);
        assert!((p.d0 - 1.0 / (3.0 * PI)).abs() < 1e-15);
        // 4.0 / 0.005 = 800 steps in 8 blocks of 100; lags up to 25 steps, origins every 3.
        assert_eq!((p.blocks, p.block_steps, p.sampled_steps), (8, 100, 800));
        assert_eq!((p.msd_max_lag, p.msd_origin_every), (25, 3));
        assert!(p.has_hydrodynamics());
        let g = p.pse.unwrap();
        assert!(g.r_cut < 0.5 * 8.87 && g.grid >= 8);
        assert!((p.peclet - 5.0).abs() < 1e-15);
        // K at phi' = 0.03 * 39/40 in this box.
        let k = p.dilute_sedimentation();
        assert!((k - 0.732).abs() < 2e-3, "K = {k}");
        assert_eq!(dilute_sedimentation(0.1, 1, 0.5, 1e9), hasimoto(0.5, 1e9));
        let p = parse(&BASE.replace("seed = 3", "seed = 4294967296"));
        assert!(p.is_err());
        let p = read(&toml::from_str(BASE).unwrap(), Path::new("."), Some(7)).unwrap();
        assert_eq!(p.seed, 7);
    }

    #[test]
    fn bad_input_names_the_key() {
        for (from, to, key) in [
            ("box_length = 8.87", "box_length = 4.0", "system.box_length"),
            ("box_length = 8.87", "box_length = 3.4", "system.box_length"),
            (
                "box_length = 8.87",
                "box_length = 1e300",
                "system.box_length",
            ),
            (
                "model = \"rpy\"",
                "model = \"rpy\"\nsplitting = 1e300",
                "hydrodynamics.splitting",
            ),
            (
                "[0.0, 0.0, -5.0]",
                "[0.0, 0.0, -500.0]",
                "system.body_force",
            ),
            ("time = 4.0", "time = 0.01", "run.time"),
            ("dt = 0.005", "dt = 1e-12", "run.dt"),
            (
                "model = \"rpy\"",
                "model = \"rpy\"\nmethod = \"direct\"",
                "hydrodynamics.method",
            ),
            (
                "model = \"rpy\"",
                "model = \"free-draining\"\nmethod = \"pse\"",
                "hydrodynamics.method",
            ),
            (
                "model = \"rpy\"",
                "model = \"rpy\"\ntolerance = 0.5",
                "hydrodynamics.tolerance",
            ),
            (
                "time = 4.0",
                "time = 4.0\nintegrator = \"lm\"",
                "run.integrator",
            ),
            (
                "[run]",
                "[observe.msd]\nmax_lag = 0.001\n[run]",
                "observe.msd.max_lag",
            ),
            ("[run]", "[observe]\nblocks = 0\n[run]", "observe.blocks"),
            ("time = 4.0", "time = 4.0\nskin = 6.0", "run.skin"),
            ("method = \"bd\"", "method = \"bulk\"", "method"),
            (
                "model = \"rpy\"",
                "model = \"rpy\"\nbox_factor = 2.0",
                "hydrodynamics.box_factor",
            ),
        ] {
            assert!(BASE.contains(from), "{from}");
            assert_eq!(err_key(&BASE.replace(from, to)), key, "{to}");
        }
        // Packing: the least edge is named.
        let e = parse(&BASE.replace("box_length = 8.87", "box_length = 4.0")).unwrap_err();
        assert!(e.to_string().contains("at least"), "{e}");
    }

    #[test]
    fn the_pse_engine_errors_name_the_scenario_keys() {
        // Too small a splitting: the real-space part reaches beyond half the box.
        let e = parse(&BASE.replace("model = \"rpy\"", "model = \"rpy\"\nsplitting = 0.2"))
            .unwrap_err()
            .downcast::<ParamError>()
            .unwrap();
        assert_eq!(e.key, "hydrodynamics.splitting", "{e}");
        assert!(e.message.contains("half the box"), "{e}");
        // Too fine a tolerance for the Gaussian support.
        let e = parse(&BASE.replace("model = \"rpy\"", "model = \"rpy\"\ntolerance = 1e-300"))
            .unwrap_err()
            .downcast::<ParamError>()
            .unwrap();
        assert_eq!(e.key, "hydrodynamics.tolerance", "{e}");
    }
}
