//! An `mpcd` scenario read through its key declarations ([`super::keys`]) into the engine's
//! parameters, with every check that relates several keys. MPCD units: lengths in the cell
//! edge `a`, masses in the solvent mass `m`, energies in `kT`, times in `a sqrt(m / kT)`.

use super::common::{
    SolventParams, box_edge, colloid_bytes, ensure_colloids_fit, ensure_solvent_fits, run_seed,
    solvent_bytes, thermo_every,
};
use super::keys::*;
use crate::keys::{Reader, Spec, shared};
use anyhow::Result;
use colloidsim_core::ParamError;
use colloidsim_core::param::show;
use colloidsim_md::mpcd::ColloidParams;
use colloidsim_md::mpcd::colloid::VERTICES;
use serde::Serialize;
use std::f64::consts::PI;

/// Target flow amplitude of the default viscosity drive, in thermal speeds `sqrt(kT / m)`
/// (the drive heats the fluid by an amount quadratic in the amplitude; docs/mpcd.md).
pub const DEFAULT_FLOW: f64 = 0.25;

/// Relaxation times `rho / (eta k^2)` of the Poiseuille flow before sampling starts.
pub const RELAXATION_TIMES: f64 = 6.0;

/// A resolved bulk run (`parameters` of `summary.json`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct BulkRun {
    /// Seed.
    pub seed: u32,
    /// The solvent.
    pub solvent: SolventParams,
    /// Box edge.
    pub box_edge: f64,
    /// Solvent particles `round(M (L / a)^3)`.
    pub particles: usize,
    /// Collisions in all.
    pub collisions: u64,
    /// Collisions before sampling.
    pub equilibrate: u64,
    /// The viscosity drive `g0` (absent: no measurement).
    pub drive: Option<f64>,
    /// Flow amplitude the drive gives by the theory's viscosity.
    pub expected_flow: Option<f64>,
    /// Blocks of the standard errors.
    pub blocks: u64,
    /// `thermo.csv` period.
    pub thermo_every: u64,
    /// GSD frame period (0: none).
    pub trajectory_every: u64,
    /// Frames hold the solvent.
    pub trajectory_solvent: bool,
    /// Colloids.
    pub colloids: usize,
    /// The colloid model.
    pub colloid: ColloidParams,
    /// Lags of the Green–Kubo sum of the colloids' centre-of-mass velocity autocorrelation.
    pub vacf_lags: u64,
    /// Stokes–Einstein–Hasimoto diffusivity `kT / (3 pi eta d) (1 - 2.837297 a/L)` of a sphere
    /// of radius `a = d/2` with the theory's viscosity (Hasimoto's leading finite-size term, as
    /// Dünweg & Kremer; docs/mpcd.md, "Colloids: diffusion").
    pub stokes_einstein_hasimoto: f64,
}

fn refuse(k: &Spec, message: impl Into<String>) -> anyhow::Error {
    ParamError::new(k.path, message).into()
}

/// The default drive `g0`: the flow amplitude [`DEFAULT_FLOW`] thermal speeds by Kikuchi's
/// viscosity in the box of `system.box`.
pub(super) fn default_drive(r: &Reader) -> Result<f64> {
    let srd = shared::solvent(r, 0)?;
    let s = SolventParams::of(srd);
    let l = box_edge(&SYSTEM_BOX, r.number(&SYSTEM_BOX)?, srd.cell, 2)?;
    let k = 2.0 * PI / l;
    Ok(DEFAULT_FLOW * (srd.kt / srd.mass).sqrt() * s.viscosity_theory * k * k / s.mass_density)
}

/// Read `table` (an `mpcd` scenario) through [`KEYS`]; `seed` overrides the scenario's.
pub fn read(table: &toml::Table, seed: Option<u64>) -> Result<BulkRun> {
    let r = Reader::new(table, KEYS)?;
    resolve(&r, seed)
}

/// Every key read and every check that relates several keys.
pub fn resolve(r: &Reader, seed: Option<u64>) -> Result<BulkRun> {
    r.word(&METHOD)?;
    let seed = run_seed(r, seed)?;
    let srd = shared::solvent(r, seed)?;
    let solvent = SolventParams::of(srd);
    let l = box_edge(&SYSTEM_BOX, r.number(&SYSTEM_BOX)?, srd.cell, 2)?;
    let particles = (srd.density * (l / srd.cell).powi(3)).round();
    if particles >= (1u64 << 31) as f64 {
        return Err(refuse(
            &SYSTEM_BOX,
            format!(
                "{particles:e} solvent particles: at most 2^31 - 1 are supported (a smaller box or density)"
            ),
        ));
    }
    ensure_solvent_fits(&SYSTEM_BOX, particles, (l / srd.cell).powi(3))?;
    let collisions = r.count(&RUN_COLLISIONS)?;
    let eta = solvent.viscosity_theory;
    let k = 2.0 * PI / l;
    let rho = solvent.mass_density;
    let thermal = (srd.kt / srd.mass).sqrt();
    let viscosity = r.has(&VISCOSITY);
    let (drive, expected_flow, relax) = if viscosity {
        let g0 = r.number(&VISCOSITY_DRIVE)?;
        let flow = rho * g0 / (eta * k * k);
        if flow > 0.6 * thermal {
            return Err(refuse(
                &VISCOSITY_DRIVE,
                format!(
                    "{} drives a flow of amplitude {flow:.3} (by the theory's viscosity), more than 0.6 thermal speeds \
                     ({:.3}): the measurement would be dominated by viscous heating; at most {:.4}",
                    show(g0),
                    0.6 * thermal,
                    0.6 * thermal * eta * k * k / rho
                ),
            ));
        }
        let relax = (RELAXATION_TIMES * rho / (eta * k * k) / srd.tau).ceil() as u64;
        (Some(g0), Some(flow), relax)
    } else {
        (None, None, 100)
    };
    let equilibrate = r
        .opt_count(&RUN_EQUILIBRATE)?
        .unwrap_or(relax.min(collisions / 2));
    if equilibrate >= collisions {
        return Err(refuse(
            &RUN_EQUILIBRATE,
            format!("must be below run.collisions = {collisions}, got {equilibrate}"),
        ));
    }
    let blocks = if viscosity {
        r.count(&VISCOSITY_BLOCKS)?
    } else {
        10
    };
    if blocks > collisions - equilibrate {
        return Err(refuse(
            &VISCOSITY_BLOCKS,
            format!(
                "must be an integer in [2, min(10000, sampling collisions = {})], got {blocks}",
                collisions - equilibrate
            ),
        ));
    }
    let trajectory_every = r.count(&OBSERVE_TRAJECTORY_EVERY)?;
    let trajectory_solvent = r.flag(&OBSERVE_TRAJECTORY_SOLVENT)?;
    let nc = r.count(&SYSTEM_COLLOIDS)? as usize;
    if trajectory_every > 0 && !trajectory_solvent && nc == 0 {
        return Err(refuse(
            &OBSERVE_TRAJECTORY_SOLVENT,
            "a bulk solvent without colloids: a trajectory (observe.trajectory.every > 0) needs observe.trajectory.solvent = true",
        ));
    }
    if nc > 0 && viscosity {
        return Err(refuse(
            &VISCOSITY,
            "the Poiseuille drive acts on the solvent alone: with colloids it would measure neither the solvent nor the suspension; measure the solvent without colloids (system.colloids = 0)",
        ));
    }
    let d = r.number(&SYSTEM_DIAMETER)?;
    if nc > 0 && 2.0 * 2f64.powf(1.0 / 6.0) * d >= l {
        return Err(refuse(
            &SYSTEM_BOX,
            format!(
                "{} must exceed twice the colloids' WCA cut-off 2^(1/6) d = {:.4}",
                show(l),
                2f64.powf(1.0 / 6.0) * d
            ),
        ));
    }
    let colloid = shared::colloid(r, &SYSTEM_DIAMETER, d, nc > 0)?;
    let nu = eta / rho;
    let slowest = l * l / (4.0 * PI * PI * nu);
    let vacf_lags = r
        .opt_count(&OBSERVE_VACF_LAGS)?
        .unwrap_or((5.0 * slowest / srd.tau).round().max(1.0) as u64);
    let sampling = collisions - equilibrate;
    if nc > 0 && !(1..=sampling / 2).contains(&vacf_lags) {
        return Err(refuse(
            &OBSERVE_VACF_LAGS,
            format!(
                "must be an integer in [1, half the sampling collisions = {}], got {vacf_lags}: run longer",
                sampling / 2
            ),
        ));
    }
    if nc > 0 {
        let solvent = solvent_bytes(particles, (l / srd.cell).powi(3));
        ensure_colloids_fit(&SYSTEM_COLLOIDS, nc, nc * (1 + VERTICES), solvent)?;
        // The autocorrelation's ring of lags + 1 velocity sets and its sums per block.
        let vacf = (vacf_lags as f64 + 1.0) * (24.0 * nc as f64 + 40.0 + 16.0 * blocks as f64);
        colloidsim_core::resources::ensure_fits(
            OBSERVE_VACF_LAGS.path,
            &format!("the velocity autocorrelation of {nc} colloids over {vacf_lags} lags"),
            solvent + colloid_bytes(nc as f64) + vacf,
        )?;
    }
    let x = 0.5 * d / l;
    let stokes_einstein_hasimoto = srd.kt / (3.0 * PI * eta * d) * (1.0 - 2.837297 * x);
    Ok(BulkRun {
        seed,
        solvent,
        box_edge: l,
        particles: particles as usize,
        collisions,
        equilibrate,
        drive,
        expected_flow,
        blocks,
        thermo_every: thermo_every(r, &OBSERVE_EVERY, collisions)?,
        trajectory_every,
        trajectory_solvent,
        colloids: nc,
        colloid,
        vacf_lags,
        stokes_einstein_hasimoto,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: &str = "method = \"mpcd\"\nseed = 3\n\
        [solvent]\ndensity = 5\nangle = 130\ntau = 0.1\nkT = 1\nmass = 1\ncell = 1\nthermostat = true\n\
        [system]\nbox = 16\ncolloids = 0\ndiameter = 4\n\
        [colloid]\nvertex_mass = 5\ncentre_mass = 5\nbond_k = 5000\nmd_steps = 50\n\
        [run]\ncollisions = 2000\nequilibrate = 100\n\
        [viscosity]\ndrive = 0.001\nblocks = 10\n\
        [observe]\nevery = 10\nvacf_lags = 100\n\
        [observe.trajectory]\nevery = 0\nsolvent = false\n";

    fn bulk(text: &str) -> Result<BulkRun> {
        read(&toml::from_str(text).unwrap(), None)
    }

    #[test]
    fn every_declared_key_is_read() {
        let table: toml::Table = toml::from_str(FULL).unwrap();
        let r = Reader::new(&table, KEYS).unwrap();
        resolve(&r, None).unwrap();
        assert_eq!(r.unread(), Vec::<&str>::new());
    }

    #[test]
    fn bulk_default_drive_gives_the_target_flow() {
        let b =
            bulk("method = \"mpcd\"\n[system]\nbox = 16\n[run]\ncollisions = 2000\n[viscosity]\n")
                .unwrap();
        assert!((b.expected_flow.unwrap() - DEFAULT_FLOW).abs() < 1e-12);
        assert_eq!(b.particles, 5 * 4096);
        // Six relaxation times rho / (eta k^2) of collision time 0.1.
        let k = 2.0 * PI / 16.0;
        let relax = 6.0 * 5.0 / (b.solvent.viscosity_theory * k * k) / 0.1;
        assert_eq!(b.equilibrate, relax.ceil() as u64);
        let e = bulk(
            "method = \"mpcd\"\n[system]\nbox = 16\n[run]\ncollisions = 2000\n[viscosity]\ndrive = 1",
        )
        .unwrap_err();
        assert!(format!("{e:#}").starts_with("viscosity.drive:"), "{e:#}");
    }

    #[test]
    fn derived_defaults_follow_the_keys_they_name() {
        // system.diameter: 4 cells; colloid.bond_k: 5000 kT.
        let b = bulk("method = \"mpcd\"\n[solvent]\ncell = 2\nkT = 0.5\n[system]\nbox = 32\n[run]\ncollisions = 100\n")
            .unwrap();
        assert_eq!(b.colloid.diameter, 8.0);
        assert_eq!(b.colloid.bond_k, 2500.0);
        assert_eq!(b.colloid.wca_epsilon, 0.5);
    }

    #[test]
    fn errors_name_their_keys() {
        for (text, key) in [
            (
                "[system]\nbox = 16.5\n[run]\ncollisions = 100",
                "system.box: 16.5 is not a whole number",
            ),
            (
                "[system]\nbox = 16\n[run]\ncollisions = 100\nequilibrate = 100",
                "run.equilibrate:",
            ),
            (
                "[system]\nbox = 16\ncolloids = 2\n[run]\ncollisions = 100\n[viscosity]",
                "viscosity:",
            ),
            (
                "[system]\nbox = 8\ncolloids = 1\n[run]\ncollisions = 100",
                "system.box: 8 must exceed",
            ),
            (
                "[system]\nbox = 16\ncolloids = 1\n[run]\ncollisions = 100",
                "observe.vacf_lags:",
            ),
            (
                "[solvent]\nangle = 181\n[system]\nbox = 16\n[run]\ncollisions = 100",
                "solvent.angle:",
            ),
            (
                "[system]\nbox = 16\n[run]\ncollisions = 100\n[observe.trajectory]\nevery = 1",
                "observe.trajectory.solvent:",
            ),
        ] {
            let e = bulk(&format!("method = \"mpcd\"\n{text}")).unwrap_err();
            assert!(format!("{e:#}").starts_with(key), "{text}: {e:#}");
        }
    }

    /// A colloid far below the cell (here 1e-300, which went non-finite at its first step) is
    /// not held in shape by its bonds: refused before the run, naming the key that was given;
    /// the limit at the default `k = 5000 kT` is d = 0.5175 cells.
    #[test]
    fn colloids_must_keep_their_shape_and_their_verlet_step_resolve_their_bonds() {
        let run = |system: &str, colloid: &str| {
            bulk(&format!(
                "method = \"mpcd\"\n[system]\nbox = 10\ncolloids = 1\n{system}\n[colloid]\n{colloid}\n\
                 [run]\ncollisions = 100\n[observe]\nvacf_lags = 10"
            ))
        };
        for d in ["1e-300", "0.5"] {
            let e = run(&format!("diameter = {d}"), "").unwrap_err();
            let e = format!("{e:#}");
            assert!(
                e.starts_with("system.diameter: a colloid of diameter"),
                "{e}"
            );
            assert!(e.contains("at least 0.5175"), "{e}");
        }
        assert!(run("diameter = 0.52", "").is_ok());
        let e = run("", "bond_k = 1").unwrap_err();
        assert!(format!("{e:#}").starts_with("colloid.bond_k:"), "{e:#}");
        // Velocity Verlet over the bonds (omega = 122.7 at k = 5000 kT, masses 5): these went
        // non-finite at their first step; refused naming the key given.
        for (solvent, colloid, key) in [
            ("tau = 3.5", "", "solvent.tau:"),
            ("", "bond_k = 1e6", "colloid.bond_k:"),
            ("", "md_steps = 5", "colloid.md_steps:"),
            ("", "centre_mass = 1e-3", "colloid.centre_mass:"),
        ] {
            let e = bulk(&format!(
                "method = \"mpcd\"\n[solvent]\n{solvent}\n[system]\nbox = 10\ncolloids = 1\n\
                 [colloid]\n{colloid}\n[run]\ncollisions = 100\n[observe]\nvacf_lags = 10"
            ))
            .unwrap_err();
            let e = format!("{e:#}");
            assert!(e.starts_with(key) && e.contains("omega dt"), "{e}");
        }
        assert!(run("", "md_steps = 13").is_ok());
        assert!(run("", "md_steps = 12").is_err());
        // Without colloids the model is not used, and not checked.
        assert!(
            bulk(
                "method = \"mpcd\"\n[system]\nbox = 10\ndiameter = 1e-300\n[run]\ncollisions = 100"
            )
            .is_ok()
        );
    }
}
