//! A `droplet-mpcd` scenario read through its key declarations ([`super::keys`]) into the
//! engine's parameters, with every check that relates several keys: the drying droplet of
//! `droplet-bd` (the radius law `R(t) = sqrt(R0^2 - alpha t / (4 pi))`) filled with the SRD
//! solvent, in MPCD units.

use super::keys::*;
use crate::keys::{Reader, Spec, shared};
use crate::methods::mpcd::common::{
    SolventParams, box_edge, ensure_colloids_fit, ensure_solvent_fits, run_seed, solvent_bytes,
    thermo_every,
};
use anyhow::Result;
use colloidsim_core::ParamError;
use colloidsim_core::param::show;
use colloidsim_md::mpcd::ColloidParams;
use colloidsim_md::mpcd::colloid::{Geometry, MAX_BOND_STRAIN, MAX_FREQUENCY};
use colloidsim_particles::Mixture;
use colloidsim_particles::potential::{HarmonicInterface, SpeciesInterface, SphereAreaLaw};
use serde::Serialize;
use std::f64::consts::PI;

/// The solvent's boundary at the droplet's sphere.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Boundary {
    /// The solvent fills the periodic box and ignores the interface.
    None,
    /// Bounce-back reversing the normal part of the velocity relative to the wall.
    Slip,
    /// Bounce-back reversing the whole velocity relative to the wall.
    NoSlip,
}

/// The colloid profiles: bins and the fractions of the run at which they are taken.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Profile {
    /// Radial bins between 0 and R(t).
    pub bins: usize,
    /// Fractions of the drying time.
    pub fractions: Vec<f64>,
}

/// A resolved drying droplet of MPCD solvent (`parameters` of `summary.json`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DropletRun {
    /// Seed.
    pub seed: u32,
    /// Boundary at the sphere.
    pub boundary: Boundary,
    /// The solvent.
    pub solvent: SolventParams,
    /// Colloids.
    pub particles: usize,
    /// Colloid diameter d (the smallest species').
    pub diameter: f64,
    /// The species (written only when there are several).
    #[serde(skip_serializing_if = "Mixture::is_single")]
    pub species: Mixture,
    /// Stokes–Einstein diffusivity `kT / (3 pi eta d)` with the theory's viscosity (the
    /// paper's estimate at infinite dilution).
    pub d0: f64,
    /// Initial radius R0.
    pub r0: f64,
    /// Initial colloid volume fraction.
    pub phi0: f64,
    /// Box edge.
    pub box_edge: f64,
    /// Peclet number `R |dR/dt| / D0`.
    pub peclet: f64,
    /// Rate of loss of surface area.
    pub alpha: f64,
    /// Drying time (end of the run).
    pub t_end: f64,
    /// Radius at the end.
    pub r_end: f64,
    /// Mean colloid volume fraction `N d^3 / (8 R^3)` at the end.
    pub phi_end: f64,
    /// The colloid model (also resolved without colloids).
    pub colloid: ColloidParams,
    /// Interface spring constant, range and offset (`s = r - (R(t) + offset)`).
    pub interface: [f64; 3],
    /// A hard wall at `R(t) + offset` instead of the spring (`interface.hard`; stiffness and
    /// range 0).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub hard_interface: bool,
    /// Collisions `ceil(t_end / tau)`.
    pub collisions: u64,
    /// Solvent particles at the start.
    pub solvent_particles: usize,
    /// Colloid-profile bins and fractions of the run at which profiles are taken.
    pub profile: Profile,
    /// Collisions at which the profiles are taken (`round(fraction * collisions)`).
    pub profile_collisions: Vec<u64>,
    /// Solvent-profile bins.
    pub solvent_bins: usize,
    /// Collisions each solvent profile averages.
    pub solvent_window: u64,
    /// `thermo.csv` period.
    pub thermo_every: u64,
    /// GSD frame period (0: none).
    pub trajectory_every: u64,
    /// Frames hold the solvent.
    pub trajectory_solvent: bool,
}

impl DropletRun {
    /// The harmonic interface on the colloid centres.
    pub fn harmonic(&self) -> HarmonicInterface {
        HarmonicInterface {
            centre: [0.0; 3],
            radius: self.law(),
            stiffness: self.interface[0],
            range: self.interface[1],
            offset: self.interface[2],
        }
    }

    /// The interface as each species meets it: placed for the smallest colloids, a colloid
    /// of diameter `d_s` meets it `(d_s - d) / 2` further in (its surface, not its centre, at
    /// the same place).
    pub fn species_interface(&self) -> SpeciesInterface {
        SpeciesInterface {
            interface: self.harmonic(),
            reference_diameter: self.diameter,
            hard: self.hard_interface,
        }
    }

    /// The radius law.
    pub fn law(&self) -> SphereAreaLaw {
        SphereAreaLaw {
            r0: self.r0,
            alpha: self.alpha,
        }
    }
}

fn refuse(k: &Spec, message: impl Into<String>) -> anyhow::Error {
    ParamError::new(k.path, message).into()
}

/// The shells of the species beside the smallest ([`Geometry::frequency_for`]): each must be
/// supported (at most [`MAX_FREQUENCY`]), held in shape and resolved by the Verlet step like
/// the smallest (`shared::colloid`); the highest bond frequency of them all.
fn shells(
    species: &Mixture,
    colloid: &ColloidParams,
    kt: f64,
    tau: f64,
    colloids: bool,
) -> Result<f64> {
    let mut omega = colloid.highest_bond_frequency();
    if species.is_single() || !colloids {
        return Ok(omega);
    }
    let d = colloid.diameter;
    let dt = tau / colloid.md_steps as f64;
    for (name, &ds) in species.names.iter().zip(&species.diameters) {
        let f = Geometry::frequency_for(ds, d);
        if f > MAX_FREQUENCY {
            return Err(refuse(
                &SPECIES_DIAMETERS,
                format!(
                    "species {name} of diameter {} is {:.4} times the smallest ({}): its shell would need {} vertices \
                     (frequency {f}), at most {} (frequency {MAX_FREQUENCY}): a size ratio of at most {}",
                    show(ds),
                    ds / d,
                    show(d),
                    Geometry::vertex_count(f.min(1000)),
                    Geometry::vertex_count(MAX_FREQUENCY),
                    (MAX_FREQUENCY as f64 + 0.5) / 2.0
                ),
            ));
        }
        let strain = colloid.thermal_bond_strain_of(kt, ds, f);
        if strain > MAX_BOND_STRAIN || strain.is_nan() {
            return Err(refuse(
                &SPECIES_DIAMETERS,
                format!(
                    "the shell of species {name} (diameter {}, {} vertices) is not held in shape: its bonds stretch by {strain:.3e} of the shortest (at most {MAX_BOND_STRAIN}); stiffer colloid.bond_k",
                    show(ds),
                    Geometry::vertex_count(f)
                ),
            ));
        }
        let w = colloid.highest_bond_frequency_of(f);
        if w * dt > 1.0 {
            return Err(refuse(
                &SPECIES_DIAMETERS,
                format!(
                    "the shell of species {name} ({} vertices) vibrates at omega = {w:.4e}: omega dt = {:.4e} with dt = solvent.tau / colloid.md_steps, at most 1; more colloid.md_steps",
                    Geometry::vertex_count(f),
                    w * dt
                ),
            ));
        }
        omega = omega.max(w);
    }
    Ok(omega)
}

/// Read `table` (a `droplet-mpcd` scenario) through [`KEYS`]; `seed` overrides the scenario's.
pub fn read(table: &toml::Table, seed: Option<u64>) -> Result<DropletRun> {
    let r = Reader::new(table, KEYS)?;
    resolve(&r, seed)
}

/// Every key read and every check that relates several keys.
pub fn resolve(r: &Reader, seed: Option<u64>) -> Result<DropletRun> {
    r.word(&METHOD)?;
    let seed = run_seed(r, seed)?;
    let boundary = match r.opt_word(&BOUNDARY)?.as_deref() {
        Some("none") => Boundary::None,
        Some("no-slip") => Boundary::NoSlip,
        _ => Boundary::Slip,
    };
    let srd = shared::solvent(r, seed)?;
    let solvent = SolventParams::of(srd);
    let a = srd.cell;
    let particles = r.count(&SYSTEM_PARTICLES)? as usize;
    let d = r.number(&SYSTEM_DIAMETER)?;
    let kt = srd.kt;
    let colloid = shared::colloid(r, &SYSTEM_DIAMETER, d, particles > 0)?;
    let species = crate::keys::species::species(r, particles, d, &SYSTEM_DIAMETER)?;
    // The shells' highest bond frequency (the smallest's when alone).
    let omega_bonds = shells(&species, &colloid, kt, srd.tau, particles > 0)?;
    // Spheres of diameter d with the colloids' volume (N for one species).
    let n = species.equivalent_number(d);
    // system.radius is required unless system.phi0 gives it.
    let radius = match r.has(&SYSTEM_RADIUS) {
        true => Some(r.number(&SYSTEM_RADIUS)?),
        false => None,
    };
    let (r0, phi0) = match (radius, r.opt_number(&SYSTEM_PHI0)?) {
        (Some(_), Some(_)) => {
            return Err(refuse(
                &SYSTEM_PHI0,
                "give either system.phi0 or system.radius, not both",
            ));
        }
        (Some(radius), None) => {
            let phi = n * d.powi(3) / (8.0 * radius.powi(3));
            if phi > 0.3 {
                return Err(refuse(
                    &SYSTEM_RADIUS,
                    format!(
                        "{particles} colloids of diameter {} in radius {} give phi0 = {phi:.4}, more than random insertion packs (0.3): the radius must be at least {:.4}",
                        show(d),
                        show(radius),
                        d * (n / 2.4).cbrt()
                    ),
                ));
            }
            (radius, phi)
        }
        (None, Some(phi)) => {
            if particles == 0 {
                return Err(refuse(
                    &SYSTEM_PHI0,
                    "a pure-solvent droplet (system.particles = 0) has no volume fraction: give system.radius",
                ));
            }
            (d * (n / (8.0 * phi)).cbrt(), phi)
        }
        (None, None) => {
            return Err(refuse(
                &SYSTEM_RADIUS,
                "missing: give system.radius (the initial droplet radius, in cells) or system.phi0",
            ));
        }
    };
    if r0 < 2.0 * a {
        return Err(refuse(
            &SYSTEM_RADIUS,
            format!(
                "the initial droplet radius {} must be at least two cells ({})",
                show(r0),
                show(2.0 * a)
            ),
        ));
    }
    if r0 < species.d_max() && particles > 0 {
        return Err(refuse(
            &SYSTEM_RADIUS,
            format!(
                "the initial droplet radius {} is smaller than a colloid diameter {}",
                show(r0),
                show(species.d_max())
            ),
        ));
    }
    let it = shared::interface(r, d, kt, Some(&INTERFACE_HARD))?;
    // The interface's spring on each centre adds at most stiffness / m_centre to the bonds'
    // omega^2 (Weyl): velocity Verlet must still resolve it (as the bonds, `shared::colloid`).
    let dt = srd.tau / colloid.md_steps as f64;
    let omega = (omega_bonds.powi(2) + it.stiffness / colloid.centre_mass).sqrt();
    if particles > 0 && omega * dt > 1.0 {
        return Err(refuse(
            &INTERFACE_STIFFNESS,
            format!(
                "{} on colloid centres of mass {} with their bonds vibrates at up to omega = {omega:.4e} per time: \
                 omega dt = {:.4e} with dt = solvent.tau / colloid.md_steps = {}, at most 1 (velocity Verlet \
                 diverges above 2); at most {:.4e}",
                show(it.stiffness),
                show(colloid.centre_mass),
                omega * dt,
                show(dt),
                (dt.powi(-2) - omega_bonds.powi(2)) * colloid.centre_mass,
            ),
        ));
    }
    if it.range > r0 {
        return Err(refuse(
            &INTERFACE_RANGE,
            format!(
                "{} is more than the initial droplet radius R0 = {r0:.4}",
                show(it.range)
            ),
        ));
    }
    if it.offset.abs() > r0 {
        return Err(refuse(
            &INTERFACE_OFFSET,
            format!(
                "must lie in [-R0, R0] = [{:.4}, {r0:.4}], got {}",
                -r0,
                show(it.offset)
            ),
        ));
    }
    let min_box = 2.0 * r0 + 4.0 * a;
    let l = match r.opt_number(&SYSTEM_BOX)? {
        Some(l) => {
            let l = box_edge(&SYSTEM_BOX, l, a, 2)?;
            if l < min_box {
                return Err(refuse(
                    &SYSTEM_BOX,
                    format!(
                        "{} cannot hold the droplet: at least 2 R0 + 4 cells = {}",
                        show(l),
                        show(min_box)
                    ),
                ));
            }
            l
        }
        None => box_edge(&SYSTEM_BOX, (min_box / a).ceil() * a, a, 2)?,
    };
    // The WCA between the largest centres must not reach round the box.
    let cut = 2f64.powf(1.0 / 6.0) * species.d_max();
    if particles > 0 && l <= 2.0 * cut {
        return Err(refuse(
            &SYSTEM_BOX,
            format!(
                "{} must exceed twice the WCA cut-off 2^(1/6) d_max = {cut:.4} of the largest colloids",
                show(l)
            ),
        ));
    }
    let d0 = srd.kt / (3.0 * PI * solvent.viscosity_theory * d);
    let (peclet, alpha) = shared::drying_rate(r, d0)?;
    let final_fraction = r.if_given(&DRYING_FINAL_VOLUME_FRACTION, Reader::number)?;
    let t_end = match (final_fraction, r.opt_number(&DRYING_DURATION)?) {
        (Some(_), _) if particles == 0 => {
            return Err(refuse(
                &DRYING_FINAL_VOLUME_FRACTION,
                "a pure-solvent droplet (system.particles = 0) has no volume fraction: give drying.duration",
            ));
        }
        (Some(_), Some(_)) => {
            return Err(refuse(
                &DRYING_FINAL_VOLUME_FRACTION,
                "give either drying.final_volume_fraction or drying.duration, not both",
            ));
        }
        (_, Some(t)) => t,
        (phi_f, None) => {
            if particles == 0 {
                return Err(refuse(
                    &DRYING_DURATION,
                    "missing: a pure-solvent droplet needs drying.duration (the time to run)",
                ));
            }
            let phi_f = match phi_f {
                Some(phi_f) => phi_f,
                // The shared declaration's default (this method's says when it applies).
                None => r.number(&shared::DRYING_FINAL_VOLUME_FRACTION)?,
            };
            if phi_f <= phi0 {
                return Err(refuse(
                    &DRYING_FINAL_VOLUME_FRACTION,
                    format!("must lie in (phi0 = {phi0:.4}, 0.64], got {}", show(phi_f)),
                ));
            }
            if alpha == 0.0 {
                return Err(refuse(
                    &DRYING_FINAL_VOLUME_FRACTION,
                    "a static droplet (drying.peclet = 0) keeps its volume fraction: give drying.duration",
                ));
            }
            let r_end = r0 * (phi0 / phi_f).cbrt();
            (r0 * r0 - r_end * r_end) * 4.0 * PI / alpha
        }
    };
    let r_end2 = r0 * r0 - alpha * t_end / (4.0 * PI);
    if r_end2 < 4.0 * a * a {
        return Err(refuse(
            &DRYING_DURATION,
            format!(
                "the droplet would shrink below two cells (R^2 = {:.4} at t = {}): a shorter drying.duration or a smaller drying.peclet",
                r_end2,
                show(t_end)
            ),
        ));
    }
    let r_end = r_end2.sqrt();
    let phi_end = n * d.powi(3) / (8.0 * r_end.powi(3));
    if phi_end > 0.64 {
        return Err(refuse(
            &DRYING_DURATION,
            format!(
                "the mean volume fraction would reach {phi_end:.4} > 0.64 (random close packing)"
            ),
        ));
    }
    let collisions = (t_end / srd.tau).ceil();
    if collisions > (1u64 << 40) as f64 {
        return Err(refuse(
            &DRYING_DURATION,
            format!("{collisions:e} collisions: at most 2^40"),
        ));
    }
    let collisions = (collisions as u64).max(1);
    let volume = match boundary {
        Boundary::None => l.powi(3),
        _ => 4.0 / 3.0 * PI * r0.powi(3),
    };
    let solvent_particles = (srd.density / a.powi(3) * volume).round();
    if solvent_particles >= (1u64 << 31) as f64 {
        return Err(refuse(
            &SYSTEM_BOX,
            format!("{solvent_particles:e} solvent particles: at most 2^31 - 1"),
        ));
    }
    ensure_solvent_fits(&SYSTEM_BOX, solvent_particles, (l / a).powi(3))?;
    ensure_colloids_fit(
        &SYSTEM_PARTICLES,
        particles,
        species
            .diameters
            .iter()
            .zip(&species.counts)
            .map(|(&ds, &c)| c * (1 + Geometry::vertex_count(Geometry::frequency_for(ds, d))))
            .sum(),
        solvent_bytes(solvent_particles, (l / a).powi(3)),
    )?;
    let profile = Profile {
        bins: r.count(&OBSERVE_PROFILE_BINS)? as usize,
        fractions: r.numbers(&OBSERVE_PROFILE_FRACTIONS)?,
    };
    if profile.fractions.is_empty() {
        return Err(refuse(
            &OBSERVE_PROFILE_FRACTIONS,
            "must be a non-empty list of numbers in [0, 1] (fractions of the drying time)",
        ));
    }
    let mut profile_collisions: Vec<u64> = profile
        .fractions
        .iter()
        .map(|f| (f * collisions as f64).round() as u64)
        .collect();
    profile_collisions.dedup();
    if profile_collisions.windows(2).any(|w| w[1] <= w[0]) {
        return Err(refuse(
            &OBSERVE_PROFILE_FRACTIONS,
            "must increase and name distinct collisions",
        ));
    }
    let solvent_bins = r.count(&OBSERVE_SOLVENT_BINS)? as usize;
    let solvent_window = r
        .opt_count(&OBSERVE_SOLVENT_WINDOW)?
        .unwrap_or((collisions / 10).max(1));
    if solvent_window > collisions {
        return Err(refuse(
            &OBSERVE_SOLVENT_WINDOW,
            format!("must be an integer in [1, collisions = {collisions}], got {solvent_window}"),
        ));
    }
    let trajectory_every = r.count(&OBSERVE_TRAJECTORY_EVERY)?;
    let trajectory_solvent = r.flag(&OBSERVE_TRAJECTORY_SOLVENT)?;
    if trajectory_every > 0 && !trajectory_solvent && particles == 0 {
        return Err(refuse(
            &OBSERVE_TRAJECTORY_SOLVENT,
            "a pure-solvent droplet has no colloids: a trajectory needs observe.trajectory.solvent = true",
        ));
    }
    Ok(DropletRun {
        seed,
        boundary,
        solvent,
        particles,
        diameter: d,
        species,
        d0,
        r0,
        phi0,
        box_edge: l,
        peclet,
        alpha,
        t_end,
        r_end,
        phi_end,
        colloid,
        interface: [it.stiffness, it.range, it.offset],
        hard_interface: it.hard,
        collisions,
        solvent_particles: solvent_particles as usize,
        profile,
        profile_collisions,
        solvent_bins,
        solvent_window,
        thermo_every: thermo_every(r, &OBSERVE_EVERY, collisions)?,
        trajectory_every,
        trajectory_solvent,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: &str = "method = \"droplet-mpcd\"\nseed = 3\nboundary = \"no-slip\"\n\
        [solvent]\ndensity = 5\nangle = 130\ntau = 0.1\nkT = 1\nmass = 1\ncell = 1\nthermostat = true\n\
        [system]\nparticles = 10\ndiameter = 2\nradius = 6\nbox = 16\n\
        [drying]\nalpha = 0.5\nfinal_volume_fraction = 0.1\n\
        [interface]\nstiffness = 12.5\nrange = 1\noffset = -1\n\
        [colloid]\nvertex_mass = 5\ncentre_mass = 5\nbond_k = 5000\nmd_steps = 50\n\
        [observe]\nevery = 10\n\
        [observe.profile]\nbins = 50\nfractions = [0.0, 0.5, 1.0]\n\
        [observe.solvent]\nbins = 20\nwindow = 10\n\
        [observe.trajectory]\nevery = 0\nsolvent = false\n";

    fn droplet(extra: &str) -> Result<DropletRun> {
        let text = format!(
            "method = \"droplet-mpcd\"\n[system]\nradius = 6\n[drying]\nduration = 20\n{extra}"
        );
        read(&toml::from_str(&text).unwrap(), None)
    }

    #[test]
    fn every_declared_key_is_read() {
        let table: toml::Table = toml::from_str(FULL).unwrap();
        let r = Reader::new(&table, KEYS).unwrap();
        resolve(&r, None).unwrap();
        // system.phi0 is read (and refused beside system.radius) but absent here; the species
        // keys are read by `species_keys_are_read` (counts and volume_fractions exclude each other).
        let unread: Vec<&str> = r
            .unread()
            .into_iter()
            .filter(|k| !k.starts_with("system.species."))
            .collect();
        assert_eq!(unread, Vec::<&str>::new());
    }

    #[test]
    fn species_keys_are_read() {
        for share in ["counts = [48, 6]", "volume_fractions = [0.5, 0.5]"] {
            let text = format!(
                "method = \"droplet-mpcd\"\n[system]\nparticles = 54\nradius = 10\n\
                 [system.species]\ndiameters = [2.0, 4.0]\n{share}\n[drying]\nduration = 20\n"
            );
            let r = match read(&toml::from_str(&text).unwrap(), None) {
                Ok(r) => r,
                Err(e) => panic!("{share}: {e:#}"),
            };
            // The smallest is system.diameter; phi0 from sum N d^3.
            assert_eq!(r.species.counts, vec![48, 6], "{share}");
            assert_eq!(r.diameter, 2.0);
            let phi = (48.0 * 8.0 + 6.0 * 64.0) / (8.0 * 1000.0);
            assert!((r.phi0 - phi).abs() < 1e-12, "{} vs {phi}", r.phi0);
        }
    }

    #[test]
    fn droplet_defaults_resolve_and_bad_keys_name_themselves() {
        let r = droplet("").unwrap();
        assert_eq!(r.boundary, Boundary::Slip);
        assert_eq!(r.box_edge, 16.0);
        assert_eq!(r.collisions, 200);
        assert_eq!(
            r.solvent_particles,
            (5.0 * 4.0 / 3.0 * PI * 216.0f64).round() as usize
        );
        // Pe = R |dR/dt| / D0 = alpha / (8 pi D0).
        assert!((r.alpha / (8.0 * PI * r.d0) - 10.0).abs() < 1e-12);
        // system.diameter: 4 cells; [interface]: from d and kT.
        assert_eq!(r.diameter, 4.0);
        assert_eq!(r.interface, [50.0 / 16.0, 2.0, -2.0]);
        let fail = |text: &str| {
            let e = read(&toml::from_str(text).unwrap(), None).unwrap_err();
            format!("{e:#}")
        };
        let base = "method = \"droplet-mpcd\"\n[system]\nradius = 6\n";
        for (extra, key) in [
            (
                "[solvent]\nangle = 0\n[drying]\nduration = 20",
                "solvent.angle:",
            ),
            (
                "[solvent]\nangle = 181\n[drying]\nduration = 20",
                "solvent.angle:",
            ),
            (
                "[solvent]\ndensity = -1\n[drying]\nduration = 20",
                "solvent.density:",
            ),
            (
                "[solvent]\ntau = 0\n[drying]\nduration = 20",
                "solvent.tau:",
            ),
            ("[drying]\nduration = 1e9", "drying.duration:"),
            (
                "[drying]\nduration = 20\npeclet = 1\nalpha = 1",
                "drying.peclet:",
            ),
            (
                "[drying]\nfinal_volume_fraction = 0.5",
                "drying.final_volume_fraction:",
            ),
            (
                "[drying]\nduration = 20\n[interface]\nrange = 7",
                "interface.range:",
            ),
            (
                "particles = 2\n[drying]\nduration = 20\n[interface]\nstiffness = 1e300",
                "interface.stiffness: 1e300 on colloid centres",
            ),
            (
                "box = 12\n[drying]\nduration = 20",
                "system.box: 12 cannot hold the droplet",
            ),
            (
                "box = 16.5\n[drying]\nduration = 20",
                "system.box: 16.5 is not a whole number of cells",
            ),
        ] {
            let e = fail(&format!("{base}{extra}"));
            assert!(e.starts_with(key), "{extra}: {e}");
        }
        let e = fail("method = \"droplet-mpcd\"\n[system]\nparticles = 10\n");
        assert!(e.starts_with("system.radius: missing"), "{e}");
    }

    /// `interface.hard`: no spring (stiffness and range 0, the offset kept), the centres
    /// reflected at the wall (`SpeciesInterface::hard`); a spring beside it refused naming its
    /// key.
    #[test]
    fn a_hard_interface_has_no_spring() {
        let r = droplet("[interface]\nhard = true\noffset = -1.5\n").unwrap();
        assert!(r.hard_interface && r.species_interface().hard);
        assert_eq!(r.interface, [0.0, 0.0, -1.5]);
        assert!(!droplet("").unwrap().species_interface().hard);
        for key in ["stiffness = 10", "range = 1"] {
            let e = droplet(&format!("[interface]\nhard = true\n{key}\n")).unwrap_err();
            let want = format!("interface.{}:", key.split(' ').next().unwrap());
            assert!(format!("{e:#}").starts_with(&want), "{e:#}");
            assert!(format!("{e:#}").contains("no spring"), "{e:#}");
        }
    }

    #[test]
    fn colloids_that_do_not_fit_name_the_radius() {
        let e = read(
            &toml::from_str("method = \"droplet-mpcd\"\n[system]\nparticles = 1000\nradius = 6\n")
                .unwrap(),
            None,
        )
        .unwrap_err();
        assert!(format!("{e:#}").starts_with("system.radius:"), "{e:#}");
    }
}
