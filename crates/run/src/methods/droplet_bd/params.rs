//! A `droplet-bd` scenario read through its key declarations ([`super::keys`]) into the
//! engine's parameters ([`DropletParams`]), with every check that relates several keys, each
//! error naming the key and the allowed range.

use super::keys::*;
use crate::keys::shared::{
    self, DRYING_PECLET, HYDRO_MAX_ITERATIONS, HYDRO_SPLITTING, HYDRO_TOLERANCE, HYDRODYNAMICS,
    INTERFACE_OFFSET, INTERFACE_RANGE, INTERFACE_STIFFNESS, RUN_DT, RUN_SKIN, Spheres,
    TRAJECTORY_EVERY,
};
use crate::keys::{Reader, SEED_KEY, Spec, rekey};
use anyhow::{Result, bail};
use colloidsim_core::ParamError;
use colloidsim_core::param::show;
use colloidsim_md::DropletParams;
use colloidsim_md::brownian::droplet::{HOLD_KT, MAX_PHI_FINAL, MAX_PHI0, MIN_DRYING_STEPS};
use colloidsim_md::hydro::HydroModel;
use std::f64::consts::PI;
use std::path::Path;

/// The engine's names of its parameters, and the keys that set them.
const ENGINE_NAMES: &[(&str, &Spec)] = &[
    ("box_factor", &HYDRO_BOX_FACTOR),
    ("box_length", &HYDRO_BOX_FACTOR),
    ("splitting", &HYDRO_SPLITTING),
    // The PSE engine's sphere radius: half the diameter.
    ("radius", &shared::DIAMETER),
    ("tolerance", &HYDRO_TOLERANCE),
    ("max_iterations", &HYDRO_MAX_ITERATIONS),
    ("method", &HYDRO_METHOD),
    ("hydrodynamics", &HYDRODYNAMICS),
];

/// An engine's error about one of its parameters, naming the scenario key instead.
pub(crate) fn keyed(e: ParamError) -> ParamError {
    rekey(e, ENGINE_NAMES)
}

/// A scenario's table checked against [`KEYS`] and resolved (with `seed` replacing the
/// scenario's); `system.initial` is taken relative to `base`.
pub fn read(table: &toml::Table, base: &Path, seed: Option<u64>) -> Result<DropletParams> {
    let r = Reader::new(table, KEYS)?;
    resolve(&r, base, seed)
}

/// `key` must lie in `[lo, hi]`.
fn within(key: &Spec, x: f64, lo: f64, hi: f64) -> Result<f64, ParamError> {
    colloidsim_core::param::in_range(key.path, x, lo, hi)
}

/// Every key read and checked against the others, in the order the checks were always made.
fn resolve(r: &Reader, base: &Path, seed: Option<u64>) -> Result<DropletParams> {
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
    let pair = crate::keys::species::pair(r, &species, kt, base)?;
    let initial = r.file(&SYSTEM_INITIAL).map(|f| base.join(f));
    // Spheres of diameter d with the colloids' volume (N for one species).
    let n = species.equivalent_number(d);
    // Random insertion packs to MAX_PHI0; a configuration read from a file may be denser.
    let max_phi0 = if initial.is_some() {
        MAX_PHI_FINAL
    } else {
        MAX_PHI0
    };
    let (phi0, r0) = match (r.opt_number(&SYSTEM_PHI0)?, r.opt_number(&SYSTEM_RADIUS)?) {
        (Some(phi), None) => {
            if phi > max_phi0 {
                bail!(ParamError::new(
                    SYSTEM_PHI0.path,
                    format!(
                        "an initial volume fraction of {phi} cannot be packed by random insertion \
                         of hard spheres (at most {max_phi0}); start from a GSD file (system.initial) \
                         or lower phi0"
                    ),
                ));
            }
            (phi, d * (n / (8.0 * phi)).cbrt())
        }
        (None, Some(radius)) => {
            let phi = n * d.powi(3) / (8.0 * radius.powi(3));
            if phi > max_phi0 {
                bail!(ParamError::new(
                    SYSTEM_RADIUS.path,
                    format!(
                        "{particles} particles (diameter {d}) in radius {radius} give phi0 = {phi:.4}, \
                         which cannot be packed (at most {max_phi0}); \
                         the radius must be at least {:.4}",
                        d * (n / (8.0 * max_phi0)).cbrt()
                    ),
                ));
            }
            (phi, radius)
        }
        (Some(_), Some(_)) => bail!(ParamError::new(
            SYSTEM_PHI0.path,
            "give either system.phi0 or system.radius, not both",
        )),
        (None, None) => bail!(ParamError::new(
            SYSTEM_PHI0.path,
            "missing: give system.phi0 (initial volume fraction, (0, 0.3]) or system.radius",
        )),
    };
    if r0 < d {
        bail!(ParamError::new(
            SYSTEM_PARTICLES.path,
            format!("the initial droplet radius {r0:.4} is smaller than a diameter {d}"),
        ));
    }

    // The drying law: alpha = 8 pi Pe D0 (Pe = R |dR/dt| / D0), from peclet or alpha.
    let (peclet, alpha) = shared::drying_rate(r, d0)?;
    let duration = r.opt_number(&DRYING_DURATION)?;
    let final_given = r.has(&DRYING_FINAL_VOLUME_FRACTION);
    if alpha == 0.0 && duration.is_none() {
        let key = if final_given {
            &DRYING_FINAL_VOLUME_FRACTION
        } else {
            &DRYING_DURATION
        };
        bail!(ParamError::new(
            key.path,
            "a static droplet (drying.peclet = 0) keeps its volume fraction: give drying.duration \
             (the time to run) instead of drying.final_volume_fraction",
        ));
    }
    // R(t)^2 = R0^2 - alpha t / (4 pi).
    let t_dry = 4.0 * PI * r0 * r0 / alpha; // time at which R^2 = 0
    let (t_end, r_end) = match (final_given, duration) {
        (true, Some(_)) => bail!(ParamError::new(
            DRYING_FINAL_VOLUME_FRACTION.path,
            "give either drying.final_volume_fraction or drying.duration, not both",
        )),
        (false, Some(t)) => {
            if t >= t_dry {
                bail!(ParamError::new(
                    DRYING_DURATION.path,
                    format!(
                        "a drying time of {t} would need R^2 = {:.4} < 0 (the droplet vanishes at t = {t_dry:.6}); \
                         use a shorter duration or drying.final_volume_fraction",
                        r0 * r0 - alpha * t / (4.0 * PI)
                    ),
                ));
            }
            (t, (r0 * r0 - alpha * t / (4.0 * PI)).sqrt())
        }
        (_, None) => {
            let phi_f = r.number(&DRYING_FINAL_VOLUME_FRACTION)?;
            if !(phi_f > phi0 && phi_f <= MAX_PHI_FINAL) {
                bail!(ParamError::new(
                    DRYING_FINAL_VOLUME_FRACTION.path,
                    format!(
                        "must lie in (phi0 = {phi0:.4}, {MAX_PHI_FINAL}], got {phi_f}: \
                         the drying would end before it starts"
                    ),
                ));
            }
            let r_end = r0 * (phi0 / phi_f).cbrt();
            ((r0 * r0 - r_end * r_end) * 4.0 * PI / alpha, r_end)
        }
    };
    let phi_end = n * d.powi(3) / (8.0 * r_end.powi(3));
    if phi_end > MAX_PHI_FINAL {
        bail!(ParamError::new(
            DRYING_DURATION.path,
            format!(
                "the mean volume fraction would reach {phi_end:.4} > {MAX_PHI_FINAL} (random close packing)"
            ),
        ));
    }

    let it = shared::interface(r, d, kt, Some(&INTERFACE_HARD))?;
    let (stiffness, range, hard_interface) = (it.stiffness, it.range, it.hard);
    if range > r0 {
        bail!(ParamError::new(
            INTERFACE_RANGE.path,
            format!(
                "{} is more than the initial droplet radius R0 = {r0:.4}: the harmonic part of the interface must be thinner than the droplet",
                show(range)
            ),
        ));
    }
    let offset = within(&INTERFACE_OFFSET, it.offset, -r0, r0)?;
    // The interface must hold the colloids: V = k s^2 / 2 up to the range, then linear with
    // force k * range; the distance beyond the wall where V reaches HOLD_KT kT must be smaller
    // than the droplet (else the colloids leave it, and the continuum theory's domain grows
    // without bound).
    let hold = HOLD_KT * kt;
    let reach = if hold <= 0.5 * stiffness * range * range {
        (2.0 * hold / stiffness).sqrt()
    } else {
        range + (hold - 0.5 * stiffness * range * range) / (stiffness * range)
    };
    if !hard_interface && reach > r0 {
        bail!(ParamError::new(
            INTERFACE_STIFFNESS.path,
            format!(
                "{} (with interface.range = {}) does not hold the colloids: the interface \
                 potential reaches {HOLD_KT} kT only {reach:.3} beyond the wall, more than \
                 the droplet radius R0 = {r0:.4}; use at least stiffness * range = {:.3} \
                 (the default is 50 kT/d^2 with range d/2)",
                show(stiffness),
                show(range),
                hold / (r0 - 0.5 * range)
            ),
        ));
    }
    if r_end + offset <= 0.0 {
        bail!(ParamError::new(
            INTERFACE_OFFSET.path,
            format!(
                "the wall R(t) + offset would reach {:.4} <= 0",
                r_end + offset
            ),
        ));
    }

    let dt = r.number(&RUN_DT)?;
    let steps = (t_end / dt).ceil();
    if steps > 1e12 {
        bail!(ParamError::new(
            RUN_DT.path,
            format!("{steps:e} steps: dt = {dt} is far too small for a drying time {t_end}"),
        ));
    }
    let steps = (steps as u64).max(1);
    // The drying must be resolved in time, and its last step must still have a droplet.
    if steps < MIN_DRYING_STEPS {
        bail!(ParamError::new(
            if r.has(&DRYING_PECLET) {
                DRYING_PECLET.path
            } else {
                RUN_DT.path
            },
            format!(
                "the droplet would dry in {steps} steps of run.dt = {dt:.3e} (at least {MIN_DRYING_STEPS} are needed to follow it); lower drying.peclet or run.dt"
            ),
        ));
    }
    // A step must not overshoot the interface's harmonic well: (D0 / kT) k dt < 1.
    let kappa = d0 / kt * stiffness * dt;
    if kappa >= 1.0 {
        bail!(ParamError::new(
            if r.has(&INTERFACE_STIFFNESS) {
                INTERFACE_STIFFNESS.path
            } else {
                RUN_DT.path
            },
            format!(
                "an interface of stiffness {} is too stiff for run.dt = {}: D0 k dt / kT = \
                 {kappa:.3e} >= 1, so a step overshoots the interface's well; use run.dt < \
                 {:.3e} or a softer interface",
                show(stiffness),
                show(dt),
                kt / (d0 * stiffness)
            ),
        ));
    }
    let r_last_sq = r0 * r0 - alpha * (steps as f64 * dt) / (4.0 * PI);
    if r_last_sq.is_nan() || r_last_sq <= 0.0 {
        bail!(ParamError::new(
            RUN_DT.path,
            format!(
                "the last step ends at t = {:.4e}, after the droplet has vanished (t = {t_dry:.4e}); use a smaller run.dt",
                steps as f64 * dt
            ),
        ));
    }
    let skin = within(&RUN_SKIN, r.number(&RUN_SKIN)?, 1e-3 * d, 5.0 * d)?;

    let hydrodynamics = shared::hydrodynamics(
        r,
        &HYDRO_METHOD,
        Some(&HYDRO_BOX_FACTOR),
        particles,
        0.5 * d,
        false,
    )?;
    let integrator = shared::integrator(
        r,
        hydrodynamics
            .as_ref()
            .is_some_and(|h| h.model == HydroModel::Rpy),
    )?;
    let bins = r.count(&OBSERVE_PROFILE_BINS)? as usize;
    let fractions = r.numbers(&OBSERVE_PROFILE_FRACTIONS)?;
    if fractions.is_empty() {
        bail!(ParamError::new(
            OBSERVE_PROFILE_FRACTIONS.path,
            "must list at least one fraction in [0, 1]",
        ));
    }
    let profile_steps = fractions
        .iter()
        .map(|f| (f * steps as f64).round() as u64)
        .collect();
    let width = r.opt_number(&OBSERVE_CROSS_SECTION_WIDTH)?;
    let cross_section = r
        .has(&OBSERVE_CROSS_SECTION)
        .then(|| {
            within(
                &OBSERVE_CROSS_SECTION_WIDTH,
                width.unwrap_or(d),
                1e-3 * d,
                2.0 * r0,
            )
        })
        .transpose()?;

    let mut params = DropletParams {
        seed,
        replicas,
        particles,
        diameter: d,
        species,
        pair,
        kt,
        viscosity: eta,
        friction,
        d0,
        phi0,
        r0,
        peclet,
        alpha,
        t_end,
        r_end,
        phi_end,
        stiffness,
        range,
        offset,
        hard_interface,
        dt,
        integrator,
        steps,
        skin,
        bins,
        fractions,
        profile_steps,
        trajectory_every: r.count(&TRAJECTORY_EVERY)?,
        initial,
        hydrodynamics,
        pse: None,
        cross_section,
    };
    // Memory before anything is allocated: about 400 B per particle (state, lists,
    // copies), 24 B per neighbour cell of the box, the profile sums.
    let cells = (params.box_edge() / (2f64.powf(1.0 / 6.0) * d + skin)).powi(3);
    let bytes =
        400.0 * particles as f64 + 24.0 * cells + 8.0 * (bins * params.fractions.len()) as f64;
    colloidsim_core::resources::ensure_fits(
        SYSTEM_PARTICLES.path,
        &format!("{particles} colloids in a box of {cells:.3e} neighbour cells"),
        bytes,
    )?;
    // PSE's radii are the species' when there are several.
    params.pse = params.check_hydrodynamics().map_err(|e| {
        if e.key == "radius" && !params.species.is_single() {
            rekey(e, &[("radius", &crate::keys::species::SPECIES_DIAMETERS)])
        } else {
            keyed(e)
        }
    })?;
    Ok(params)
}

#[cfg(test)]
mod tests {
    use super::*;
    use colloidsim_md::Integrator;
    use colloidsim_md::hydro::HydroMethod;

    const PAPER: &str = r#"
method = "droplet-bd"
seed = 3
replicas = 4
[system]
particles = 6250
phi0 = 0.05
[drying]
peclet = 10
final_volume_fraction = 0.5
"#;

    /// A scenario with every table, so that every key is read.
    const FULL: &str = r#"
method = "droplet-bd"
[system]
particles = 300
phi0 = 0.05
initial = "start.gsd"
[drying]
peclet = 10
[interface]
stiffness = 50.0
[run]
skin = 0.5
[observe.profile]
bins = 20
[observe.trajectory]
every = 100
[observe.cross_section]
width = 2.0
[hydrodynamics]
model = "rpy"
method = "pse"
"#;

    fn parse(text: &str) -> Result<DropletParams> {
        read(&toml::from_str(text).unwrap(), Path::new("."), None)
    }

    fn err_key(text: &str) -> String {
        match parse(text).unwrap_err().downcast::<ParamError>() {
            Ok(e) => e.key,
            Err(e) => format!("parse: {e}"),
        }
    }

    #[test]
    fn every_declared_key_is_read() {
        let t: toml::Table = toml::from_str(FULL).unwrap();
        let r = Reader::new(&t, KEYS).unwrap();
        resolve(&r, Path::new("."), None).unwrap();
        // The species and pair keys are read by kind (one scenario cannot give them all):
        // tests/species.rs reads each.
        let unread: Vec<&str> = r
            .unread()
            .into_iter()
            .filter(|k| !k.starts_with("pair.") && !k.starts_with("system.species."))
            .collect();
        assert_eq!(unread, Vec::<&str>::new());
    }

    #[test]
    fn derived_defaults_are_computed_from_the_keys_they_name() {
        let p = parse(PAPER).unwrap();
        assert_eq!(p.dt, 2e-4 * p.diameter * p.diameter / p.d0);
        assert_eq!(p.skin, 0.6 * p.diameter);
        let wide = PAPER.replace(
            "phi0 = 0.05",
            "phi0 = 0.05\ndiameter = 2.0\nviscosity = 3.0",
        );
        let p = parse(&wide).unwrap();
        assert_eq!(p.d0, 1.0 / (3.0 * PI * 3.0 * 2.0));
        assert_eq!(p.dt, 2e-4 * 4.0 / p.d0);
        assert_eq!((p.skin, p.range, p.offset), (1.2, 1.0, -1.0));
    }

    #[test]
    fn paper_case_resolves_to_r0_25_and_alpha_8_pi_pe_d0() {
        let p = parse(PAPER).unwrap();
        assert!((p.r0 - 25.0).abs() < 1e-12, "R0 {}", p.r0);
        let d0 = 1.0 / (3.0 * PI);
        assert!((p.d0 - d0).abs() < 1e-15);
        assert!((p.alpha - 8.0 * PI * 10.0 * d0).abs() < 1e-12);
        // Pe = R |dR/dt| / D0 = alpha / (8 pi D0) at every time.
        let t = 0.3 * p.t_end;
        let h = 1e-6 * p.t_end;
        let drdt = (p.radius_at(t + h) - p.radius_at(t - h)) / (2.0 * h);
        assert!((p.radius_at(t) * drdt.abs() / p.d0 - 10.0).abs() < 1e-5);
        assert!((p.volume_fraction_at_radius(p.radius_at(p.t_end)) - 0.5).abs() < 1e-9);
        assert_eq!(p.profile_steps.len(), 5);
        assert_eq!(*p.profile_steps.last().unwrap(), p.steps);
    }

    #[test]
    fn bad_input_names_the_key() {
        let e = err_key(&PAPER.replace("peclet = 10", "peclet = 10\nspeed = 3"));
        assert!(e.starts_with("parse") && e.contains("speed"), "{e}");
        assert_eq!(
            err_key(&PAPER.replace("phi0 = 0.05", "phi0 = 0.45")),
            "system.phi0"
        );
        assert_eq!(
            err_key(&PAPER.replace("phi0 = 0.05", "radius = 10.0")),
            "system.radius"
        );
        assert_eq!(
            err_key(&PAPER.replace(
                "final_volume_fraction = 0.5",
                "final_volume_fraction = 0.04"
            )),
            "drying.final_volume_fraction"
        );
        assert_eq!(
            err_key(&PAPER.replace("final_volume_fraction = 0.5", "duration = 1e6")),
            "drying.duration"
        );
        assert_eq!(
            err_key(&PAPER.replace("peclet = 10", "peclet = 10\nalpha = 1.0")),
            "drying.peclet"
        );
    }

    #[test]
    fn a_static_droplet_keeps_its_radius_and_needs_a_duration() {
        let text = PAPER.replace(
            "peclet = 10\nfinal_volume_fraction = 0.5",
            "peclet = 0\nduration = 50.0",
        );
        let p = parse(&text).unwrap();
        assert!(p.is_static() && p.alpha == 0.0);
        assert_eq!(p.radius_at(p.t_end), p.r0);
        assert_eq!((p.r_end, p.phi_end), (p.r0, p.phi0));
        assert_eq!(p.steps, (50.0 / p.dt).ceil() as u64);
        assert_eq!(
            err_key(&PAPER.replace("peclet = 10", "peclet = 0")),
            "drying.final_volume_fraction"
        );
        assert_eq!(
            err_key(&PAPER.replace("peclet = 10\nfinal_volume_fraction = 0.5", "peclet = 0")),
            "drying.duration"
        );
    }

    #[test]
    fn the_integrator_is_euler_or_lm_and_lm_is_free_draining_only() {
        let with = |run: &str, h: &str| format!("{PAPER}[run]\n{run}\n{h}");
        let integrator = |text: &str| parse(text).map(|p| p.integrator).ok();
        assert_eq!(integrator(PAPER), Some(Integrator::Euler));
        assert_eq!(
            integrator(&with("integrator = \"lm\"", "")),
            Some(Integrator::Lm)
        );
        let free = "[hydrodynamics]\nmodel = \"free-draining\"";
        assert_eq!(
            integrator(&with("integrator = \"lm\"", free)),
            Some(Integrator::Lm)
        );
        let rpy = "[hydrodynamics]\nmodel = \"rpy\"";
        let text = with("integrator = \"lm\"", rpy);
        assert_eq!(err_key(&text), "run.integrator");
        assert!(format!("{}", parse(&text).unwrap_err()).contains("rpy"));
        assert!(integrator(&with("integrator = \"euler\"", rpy)).is_some());
    }

    #[test]
    fn hydrodynamics_are_checked_against_the_droplet_naming_the_key() {
        let with = |h: &str| format!("{PAPER}[hydrodynamics]\n{h}\n");
        let p = parse(&with("model = \"rpy\"")).unwrap();
        // 6250 particles: PSE by default, in a box of two droplet diameters.
        assert_eq!(
            p.hydrodynamics.as_ref().unwrap().method,
            Some(HydroMethod::Pse)
        );
        assert!(p.has_hydrodynamics());
        let g = p.pse.unwrap();
        assert!((g.spacing * g.grid as f64 - 4.0 * p.r0).abs() < 1e-9);
        let p = parse(&with("model = \"free-draining\"")).unwrap();
        assert!(!p.has_hydrodynamics() && p.pse.is_none());
        for (h, key) in [
            (
                "model = \"rpy\"\nmethod = \"pse\"\nsplitting = 0.02",
                "hydrodynamics.splitting",
            ),
            (
                "model = \"rpy\"\nmethod = \"pse\"\nsplitting = 1e300",
                "hydrodynamics.splitting",
            ),
            (
                "model = \"rpy\"\nmethod = \"direct\"\nsplitting = 1.0",
                "hydrodynamics.splitting",
            ),
            ("method = \"pse\"", "hydrodynamics.method"),
        ] {
            assert_eq!(err_key(&with(h)), key, "{h}");
        }
        assert_eq!(
            err_key(
                &with("model = \"rpy\"\nmethod = \"pse\"\nbox_factor = 1.2").replace("6250", "300")
            ),
            "hydrodynamics.box_factor"
        );
        // Too many particles for the direct method: the engine's refusal names the key.
        let big = with("model = \"rpy\"\nmethod = \"direct\"").replace("6250", "30000");
        let e = parse(&big).unwrap_err().downcast::<ParamError>().unwrap();
        assert_eq!(e.key, "hydrodynamics.method");
        let m = e.to_string();
        assert!(
            m.contains("at most 20000") && m.contains("\"pse\"") && m.contains("GiB"),
            "{m}"
        );
    }
}
