//! A `dpd` scenario read through its key declarations ([`super::keys`]) into the engine's
//! setup ([`DpdSetup`]) and the run's settings, with every check that relates several keys.
//!
//! Units: lengths in the solvent cut-off `rc`, energies as noted (kT multiples), masses in
//! solvent-bead masses, times in DPD time.

use super::keys::*;
use crate::keys::Reader;
use colloidsim_core::ParamError;
use colloidsim_core::param::in_range;
use colloidsim_md::dpd::setup::{DpdSetup, RadiusDistribution};
use colloidsim_md::dpd::{
    ColloidForces, DpdParams, LubricationNoise, NeighborMode, colloid_solvent_cutoff,
};
use colloidsim_particles::SimBox;
use std::f64::consts::PI;

/// The shortest DPD time step (DPD times `rc sqrt(m / kT)`).
const MIN_DT: f64 = 1e-6;

/// Most sample intervals in the stress autocorrelation (`observe.viscosity_time`): each sample
/// costs that many products of six components.
pub const MAX_VISCOSITY_LAGS: usize = 100_000;

/// A DPD scenario as given, every key read through its declaration (defaults included).
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// `dpd`.
    pub method: String,
    /// Seed of all random streams.
    pub seed: u64,
    /// Box, densities, temperature, colloid sizes.
    pub system: System,
    /// DPD solvent forces.
    pub dpd: Solvent,
    /// Colloid–colloid forces.
    pub colloids: Colloids,
    /// Time stepping.
    pub run: Run,
    /// Observables.
    pub observe: Observe,
}

/// `[system]`.
#[derive(Debug, Clone, PartialEq)]
pub struct System {
    /// Cube edge, if given.
    pub box_length: Option<f64>,
    /// Box edges `[Lx, Ly, Lz]`, if given.
    pub box_edges: Option<Vec<f64>>,
    /// Solvent beads per volume the colloids leave free.
    pub density: f64,
    /// Colloid volume fraction.
    pub phi: f64,
    /// Thermal energy.
    pub kt: f64,
    /// Mean colloid radius `R_c`.
    pub colloid_radius: f64,
    /// `monodisperse`, `gaussian`, `lognormal` or `uniform`.
    pub radius_distribution: String,
    /// Relative spread of the radii.
    pub radius_spread: f64,
    /// Mass of a solvent bead.
    pub solvent_mass: f64,
}

/// `[dpd]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Solvent {
    /// Solvent–solvent cut-off `rc`.
    pub cutoff: f64,
    /// Solvent–solvent repulsion `a` (kT / rc).
    pub repulsion: f64,
    /// Colloid–solvent repulsion (kT / rc').
    pub repulsion_colloid_solvent: f64,
    /// Dissipation `gamma`.
    pub gamma: f64,
}

/// `[colloids]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Colloids {
    /// Colloid–colloid surface cut-off.
    pub cutoff: f64,
    /// Contact modulus (kT / rc).
    pub contact: f64,
    /// Contact range `Delta`.
    pub contact_range: f64,
    /// Morse depth (kT).
    pub morse_depth: f64,
    /// Morse `kappa`.
    pub morse_kappa: f64,
    /// Morse `r0`.
    pub morse_r0: f64,
    /// Background viscosity `eta0`.
    pub eta0: f64,
    /// Squeeze lubrication on or off.
    pub lubrication: bool,
    /// Smallest lubrication gap.
    pub lubrication_gap: f64,
    /// Noise of the lubrication pair.
    pub lubrication_noise: LubricationNoise,
}

/// `[run]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Time step.
    pub dt: f64,
    /// Steps to run.
    pub steps: u64,
    /// Neighbour-list skin.
    pub skin: f64,
    /// Choose the skin and the neighbour search from measured step times.
    pub tune_skin: bool,
    /// Largest relative drift of the window-averaged kinetic temperature.
    pub max_temperature_drift: f64,
    /// Window of that check (steps).
    pub temperature_window: u64,
    /// How solvent pairs are found.
    pub neighbors: NeighborMode,
    /// Lees–Edwards shear rate.
    pub shear_rate: f64,
    /// Grid of MPI ranks `[py, pz]`, if given (as written: checked in [`Scenario::resolve`]).
    pub rank_grid: Option<Vec<f64>>,
}

/// `[observe]` (periods in steps; 0 switches an output off).
#[derive(Debug, Clone, PartialEq)]
pub struct Observe {
    /// `thermo.csv` period.
    pub thermo_every: u64,
    /// GSD trajectory period.
    pub trajectory_every: u64,
    /// Period of the positions kept for the MSD.
    pub msd_every: u64,
    /// Solvent beads followed for the solvent MSD (the first tags).
    pub msd_solvent_beads: usize,
    /// Period of the structure samples (g(r), S(q), contacts, clusters).
    pub structure_every: u64,
    /// Bins of the colloid g(r).
    pub gr_bins: usize,
    /// Steps averaged into one stress sample of the Green–Kubo viscosity (0: off).
    pub viscosity_every: u64,
    /// Longest lag of the stress autocorrelation (DPD time).
    pub viscosity_time: f64,
    /// Bins along y of the velocity profile of a shear run.
    pub profile_bins: usize,
}

/// A resolved scenario: the engine's setup and the run's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Resolved {
    /// What the engine is built from.
    pub setup: DpdSetup,
    /// Steps.
    pub steps: u64,
    /// `run.tune_skin`: choose `setup.params.skin` and `.neighbors` before the run.
    pub tune_skin: bool,
    /// The tuning that chose them, once made.
    pub skin_tuning: Option<colloidsim_md::tune::SkinTuning>,
    /// Temperature-drift limit (relative).
    pub max_temperature_drift: f64,
    /// Temperature window (steps).
    pub temperature_window: u64,
    /// Observables.
    pub observe: Observe,
    /// Contact gap of the coordination number.
    pub contact_gap: f64,
    /// g(r) range.
    pub gr_max: f64,
    /// Lags of the stress autocorrelation (`observe.viscosity_time / (viscosity_every dt)`
    /// + 1; 0 when the viscosity is not observed).
    pub viscosity_lags: usize,
    /// Warnings to show the user (valid but questionable settings).
    pub warnings: Vec<String>,
}

impl Scenario {
    /// The scenario read through the declarations of [`super::keys`] (which have checked every
    /// key's type and range).
    pub fn read(r: &Reader) -> anyhow::Result<Self> {
        let count = |k| -> anyhow::Result<usize> { Ok(r.count(k)? as usize) };
        Ok(Self {
            method: r.word(&METHOD)?,
            seed: r.count(&SEED)?,
            system: System {
                box_length: r.opt_number(&SYSTEM_BOX_LENGTH)?,
                box_edges: r
                    .given(&SYSTEM_BOX_EDGES)
                    .map(|_| r.numbers(&SYSTEM_BOX_EDGES))
                    .transpose()?,
                density: r.number(&SYSTEM_DENSITY)?,
                phi: r.number(&SYSTEM_PHI)?,
                kt: r.number(&SYSTEM_KT)?,
                colloid_radius: r.number(&SYSTEM_COLLOID_RADIUS)?,
                radius_distribution: r.word(&SYSTEM_RADIUS_DISTRIBUTION)?,
                radius_spread: r.number(&SYSTEM_RADIUS_SPREAD)?,
                solvent_mass: r.number(&SYSTEM_SOLVENT_MASS)?,
            },
            dpd: Solvent {
                cutoff: r.number(&DPD_CUTOFF)?,
                repulsion: r.number(&DPD_REPULSION)?,
                repulsion_colloid_solvent: r.number(&DPD_REPULSION_COLLOID_SOLVENT)?,
                gamma: r.number(&DPD_GAMMA)?,
            },
            colloids: Colloids {
                cutoff: r.number(&COLLOIDS_CUTOFF)?,
                contact: r.number(&COLLOIDS_CONTACT)?,
                contact_range: r.number(&COLLOIDS_CONTACT_RANGE)?,
                morse_depth: r.number(&COLLOIDS_MORSE_DEPTH)?,
                morse_kappa: r.number(&COLLOIDS_MORSE_KAPPA)?,
                morse_r0: r.number(&COLLOIDS_MORSE_R0)?,
                eta0: r.number(&COLLOIDS_ETA0)?,
                lubrication: r.flag(&COLLOIDS_LUBRICATION)?,
                lubrication_gap: r.number(&COLLOIDS_LUBRICATION_GAP)?,
                lubrication_noise: match r.word(&COLLOIDS_LUBRICATION_NOISE)?.as_str() {
                    "authors" => LubricationNoise::Authors,
                    _ => LubricationNoise::Exact,
                },
            },
            run: Run {
                dt: r.number(&RUN_DT)?,
                steps: r.count(&RUN_STEPS)?,
                skin: r.number(&RUN_SKIN)?,
                tune_skin: r.flag(&RUN_TUNE_SKIN)?,
                max_temperature_drift: r.number(&RUN_MAX_TEMPERATURE_DRIFT)?,
                temperature_window: r.count(&RUN_TEMPERATURE_WINDOW)?,
                neighbors: match r.word(&RUN_NEIGHBORS)?.as_str() {
                    "verlet" => NeighborMode::Verlet,
                    "cells" => NeighborMode::Cells,
                    _ => NeighborMode::Auto,
                },
                shear_rate: r.number(&RUN_SHEAR_RATE)?,
                rank_grid: r
                    .given(&RUN_RANK_GRID)
                    .map(|_| r.numbers(&RUN_RANK_GRID))
                    .transpose()?,
            },
            observe: Observe {
                thermo_every: r.count(&OBSERVE_THERMO_EVERY)?,
                trajectory_every: r.count(&OBSERVE_TRAJECTORY_EVERY)?,
                msd_every: r.count(&OBSERVE_MSD_EVERY)?,
                msd_solvent_beads: count(&OBSERVE_MSD_SOLVENT_BEADS)?,
                structure_every: r.count(&OBSERVE_STRUCTURE_EVERY)?,
                gr_bins: count(&OBSERVE_GR_BINS)?,
                viscosity_every: r.count(&OBSERVE_VISCOSITY_EVERY)?,
                viscosity_time: r.number(&OBSERVE_VISCOSITY_TIME)?,
                profile_bins: count(&OBSERVE_PROFILE_BINS)?,
            },
        })
    }

    /// Check what relates several keys and resolve the setup (with `seed` replacing the
    /// scenario's); `r` gives the derived defaults.
    pub fn resolve(&self, r: &Reader, seed: Option<u64>) -> anyhow::Result<Resolved> {
        let seed = match seed {
            Some(s) => crate::seed32(s)?,
            None => self.seed as u32,
        };
        self.resolve_seeded(r, seed)
    }

    fn resolve_seeded(&self, r: &Reader, seed: u32) -> anyhow::Result<Resolved> {
        let key =
            |k: &crate::keys::Spec, m: String| anyhow::Error::from(ParamError::new(k.path, m));
        let mut warnings = Vec::new();
        let s = &self.system;
        let l = match (s.box_length, &s.box_edges) {
            (Some(l), None) => [l; 3],
            (None, Some(e)) => {
                if let Some(x) = e.iter().find(|&&x| x <= 0.0) {
                    return Err(key(
                        &SYSTEM_BOX_EDGES,
                        format!("must be a finite number > 0, got {x}"),
                    ));
                }
                [e[0], e[1], e[2]]
            }
            (None, None) => {
                return Err(key(
                    &SYSTEM_BOX_LENGTH,
                    "give the box as box_length (cube) or box_edges = [Lx, Ly, Lz]".into(),
                ));
            }
            (Some(_), Some(_)) => {
                return Err(key(
                    &SYSTEM_BOX_EDGES,
                    "give either box_length or box_edges, not both".into(),
                ));
            }
        };
        let (density, phi, kt, radius) = (s.density, s.phi, s.kt, s.colloid_radius);
        let spread = s.radius_spread;
        let distribution = match s.radius_distribution.as_str() {
            "gaussian" => RadiusDistribution::Gaussian(spread),
            "lognormal" => RadiusDistribution::LogNormal(spread),
            "uniform" => RadiusDistribution::Uniform(spread),
            _ => RadiusDistribution::Monodisperse,
        };
        if spread > 0.0 && distribution == RadiusDistribution::Monodisperse {
            return Err(key(
                &SYSTEM_RADIUS_SPREAD,
                "a spread needs radius_distribution = \"gaussian\", \"lognormal\" or \"uniform\""
                    .into(),
            ));
        }
        let d = &self.dpd;
        let (rc, gamma) = (d.cutoff, d.gamma);
        if gamma < 4.5 {
            warnings.push(format!(
                "dpd.gamma = {gamma} is below 4.5: too little dissipation to hold the temperature (notes: 4.5 <= gamma <= 200)"
            ));
        }
        let c = &self.colloids;
        let (cc_cut, delta, kappa) = (c.cutoff, c.contact_range, c.morse_kappa);
        if cc_cut <= delta {
            return Err(key(
                &COLLOIDS_CUTOFF,
                format!(
                    "the colloid cut-off {cc_cut} must exceed the contact range colloids.contact_range = {delta}"
                ),
            ));
        }
        let r0 = in_range(COLLOIDS_MORSE_R0.path, c.morse_r0, 0.0, cc_cut)?;
        if c.lubrication_gap >= cc_cut {
            return Err(key(
                &COLLOIDS_LUBRICATION_GAP,
                format!(
                    "must be smaller than colloids.cutoff = {cc_cut}, got {}",
                    c.lubrication_gap
                ),
            ));
        }
        let morse_depth = c.morse_depth * kt;
        if morse_depth > 0.0 && (kappa * cc_cut) < 5.0 {
            warnings.push(format!(
                "the Morse force at the cut-off is exp(-{:.1}) of its range: raise colloids.cutoff or colloids.morse_kappa",
                kappa * cc_cut
            ));
        }
        let run = &self.run;
        let (dt, skin, shear_rate) = (run.dt, run.skin, run.shear_rate);
        if dt < MIN_DT {
            // The random force's amplitude grows as 1 / sqrt(dt): its pressure and stress
            // samples become noise that no run averages out.
            return Err(key(
                &RUN_DT,
                format!(
                    "{dt:e} is below {MIN_DT:e} DPD times: the random force scales as 1/sqrt(dt), so its pressure and stress samples would be {:.0e} times the thermal scale and the run would cover no time (the usual step: 0.01 to 0.04)",
                    dt.sqrt().recip()
                ),
            ));
        }
        let rank_grid = match run.rank_grid.as_deref() {
            Some(&[py, pz]) => {
                if py.fract() != 0.0 || pz.fract() != 0.0 {
                    return Err(key(
                        &RUN_RANK_GRID,
                        format!("[{py}, {pz}]: ranks along y and along z, whole numbers"),
                    ));
                }
                if py > 1.0 && shear_rate > 0.0 {
                    return Err(key(
                        &RUN_RANK_GRID,
                        format!("[{py}, {pz}]: a sheared run is cut along z only (py = 1)"),
                    ));
                }
                Some([py as usize, pz as usize])
            }
            _ => None,
        };
        let o = &self.observe;
        let shortest = l.iter().cloned().fold(f64::INFINITY, f64::min);
        // Left out: just under half the box (freud's RDF, and any AABB query, refuses L/2).
        let gr_max = r.number(&OBSERVE_GR_MAX)?;
        if r.has(&OBSERVE_GR_MAX) {
            in_range(OBSERVE_GR_MAX.path, gr_max, 1e-6, 0.5 * shortest)?;
        }
        let contact_gap = r.number(&OBSERVE_CONTACT_GAP)?;
        let viscosity_time = o.viscosity_time;
        let viscosity_lags = if o.viscosity_every > 0 {
            let delta = o.viscosity_every as f64 * dt;
            let intervals = (viscosity_time / delta).round();
            if intervals < 1.0 {
                return Err(key(
                    &OBSERVE_VISCOSITY_TIME,
                    format!(
                        "must be at least one sample interval, viscosity_every x dt = {delta}, got {viscosity_time}"
                    ),
                ));
            }
            if intervals > MAX_VISCOSITY_LAGS as f64 {
                return Err(key(
                    &OBSERVE_VISCOSITY_TIME,
                    format!(
                        "spans {intervals} sample intervals of {delta}; at most {MAX_VISCOSITY_LAGS} (raise observe.viscosity_every)"
                    ),
                ));
            }
            intervals as usize + 1
        } else {
            0
        };
        let sbox = SimBox::new(l);
        let vc = 4.0 / 3.0 * PI * radius.powi(3);
        // Memory before the counts become integers (a cast saturates) and anything is
        // allocated: about 600 B per bead (state, forces, Verlet lists at density 3, copies).
        let beads = sbox.volume() * (phi / vc + density * (1.0 - phi));
        colloidsim_core::resources::ensure_fits(
            SYSTEM_BOX_LENGTH.path,
            &format!("{beads:.3e} beads (density x box volume)"),
            600.0 * beads,
        )?;
        let colloids = (phi * sbox.volume() / vc).round() as usize;
        if phi > 0.0 && vc > sbox.volume() {
            return Err(key(
                &SYSTEM_COLLOID_RADIUS,
                format!(
                    "one colloid of radius {radius} (volume {vc:.4}) does not fit in the box (volume {:.4}) at phi = {phi}; use a larger box or smaller colloids, or phi = 0 for the solvent alone",
                    sbox.volume()
                ),
            ));
        }
        if phi > 0.0 && colloids == 0 {
            // The requested volume fraction would be dropped without notice.
            return Err(key(
                &SYSTEM_PHI,
                format!(
                    "{phi} of a box of volume {:.4} is {:.3} colloids of radius {radius} (volume {vc:.4} each), which rounds to none; use a larger box or smaller colloids (at least half a colloid: phi >= {:.3}), or phi = 0 for the solvent alone",
                    sbox.volume(),
                    phi * sbox.volume() / vc,
                    0.5 * vc / sbox.volume()
                ),
            ));
        }
        let free = sbox.volume() * (1.0 - phi);
        let solvent = (density * free).round() as usize;
        if colloids + solvent < 2 {
            return Err(key(
                &SYSTEM_DENSITY,
                "the box holds fewer than 2 particles".into(),
            ));
        }
        // The MSD keeps every sample's unwrapped positions of the colloids and the followed
        // solvent beads (24 B each) to the end of the run.
        if let Some(samples) = run.steps.checked_div(self.observe.msd_every) {
            let frames = samples as f64 + 1.0;
            let followed = colloids + self.observe.msd_solvent_beads.min(solvent);
            colloidsim_core::resources::ensure_fits(
                OBSERVE_MSD_EVERY.path,
                &format!(
                    "{frames:.3e} MSD samples of {followed} particles (run.steps / observe.msd_every)"
                ),
                600.0 * beads + 24.0 * frames * followed as f64,
            )?;
        }
        // Box must hold 3 cells of the fluid range and twice the colloid range.
        let rmax = match distribution {
            RadiusDistribution::Monodisperse => radius,
            RadiusDistribution::Gaussian(s) => radius * (1.0 + 3.0 * s),
            RadiusDistribution::LogNormal(s) => radius * (1.0 + 6.0 * s),
            RadiusDistribution::Uniform(s) => radius * (1.0 + s),
        };
        let fluid = rc.max(if colloids > 0 {
            rmax + colloid_solvent_cutoff(rc, rmax)
        } else {
            0.0
        }) + skin;
        let need = (3.0 * fluid).max(if colloids > 0 {
            2.0 * (cc_cut + 2.0 * rmax + skin)
        } else {
            0.0
        });
        if shortest < need {
            return Err(key(
                &SYSTEM_BOX_LENGTH,
                format!(
                    "the shortest box edge {shortest} is below {need:.3} (three neighbour cells of rc' + skin and twice the colloid range)"
                ),
            ));
        }
        let eta0 = c.eta0;
        let d0 = kt / (6.0 * PI * eta0 * radius);
        let params = DpdParams {
            kt,
            gamma,
            rc,
            repulsion: d.repulsion,
            repulsion_cs: d.repulsion_colloid_solvent,
            colloid_cutoff: cc_cut,
            colloid: ColloidForces {
                contact: c.contact * kt / rc,
                contact_range: delta,
                morse_depth,
                morse_kappa: kappa,
                morse_r0: r0,
                eta0: if c.lubrication { eta0 } else { 0.0 },
                lubrication_gap: c.lubrication_gap,
            },
            lubrication_noise: c.lubrication_noise,
            dt,
            skin,
            neighbors: run.neighbors,
            seed,
            shear_rate,
            rank_grid,
        };
        Ok(Resolved {
            setup: DpdSetup {
                params,
                sbox,
                colloids,
                solvent,
                radius,
                distribution,
                density,
                solvent_mass: s.solvent_mass,
                d0,
                tau: radius * radius / d0,
            },
            steps: run.steps,
            tune_skin: run.tune_skin,
            skin_tuning: None,
            max_temperature_drift: run.max_temperature_drift,
            temperature_window: run.temperature_window,
            observe: o.clone(),
            contact_gap,
            gr_max,
            viscosity_lags,
            warnings,
        })
    }
}

/// A scenario's table checked against [`KEYS`], read, and resolved (with `seed` replacing the
/// scenario's).
pub fn read(table: &toml::Table, seed: Option<u64>) -> anyhow::Result<(Scenario, Resolved)> {
    let r = Reader::new(table, KEYS)?;
    let sc = Scenario::read(&r)?;
    let resolved = sc.resolve(&r, seed)?;
    Ok((sc, resolved))
}

/// The engine's setup of a scenario's text (tests and benchmarks).
pub fn setup(text: &str) -> anyhow::Result<DpdSetup> {
    Ok(read(&toml::from_str(text)?, None)?.1.setup)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> toml::Table {
        toml::from_str(text).expect("scenario syntax")
    }

    fn refused(text: &str) -> String {
        format!("{:#}", read(&table(text), None).unwrap_err())
    }

    /// A scenario that gives every key (the box as edges; `box_length` is read first).
    const FULL: &str = r#"
method = "dpd"
seed = 3
[system]
box_edges = [10.0, 11.0, 12.0]
density = 3.0
phi = 0.1
kT = 0.1
colloid_radius = 1.0
radius_distribution = "uniform"
radius_spread = 0.1
solvent_mass = 1.0
[dpd]
cutoff = 1.0
repulsion = 25.0
repulsion_colloid_solvent = 25.0
gamma = 4.5
[colloids]
cutoff = 1.0
contact = 10000.0
contact_range = 0.001
morse_depth = 12.0
morse_kappa = 30.0
morse_r0 = 0.0
eta0 = 0.3
lubrication = true
lubrication_gap = 0.001
lubrication_noise = "authors"
[run]
dt = 0.001
steps = 100
skin = 0.4
max_temperature_drift = 0.1
temperature_window = 100
neighbors = "cells"
shear_rate = 0.0
rank_grid = [1, 2]
[observe]
thermo_every = 10
trajectory_every = 0
msd_every = 10
msd_solvent_beads = 10
structure_every = 50
gr_bins = 100
gr_max = 4.0
contact_gap = 0.1
viscosity_every = 5
viscosity_time = 0.05
profile_bins = 8
"#;

    #[test]
    fn every_declared_key_is_read() {
        let t = table(FULL);
        let r = Reader::new(&t, KEYS).unwrap();
        let sc = Scenario::read(&r).unwrap();
        let resolved = sc.resolve(&r, None).unwrap();
        assert_eq!(r.unread(), Vec::<&str>::new());
        let p = &resolved.setup.params;
        assert_eq!(p.lubrication_noise, LubricationNoise::Authors);
        assert_eq!(p.neighbors, NeighborMode::Cells);
        assert_eq!(p.rank_grid, Some([1, 2]));
        assert_eq!(p.seed, 3);
        assert_eq!(resolved.setup.sbox.l, [10.0, 11.0, 12.0]);
        assert_eq!(resolved.viscosity_lags, 11);
        assert_eq!((resolved.gr_max, resolved.contact_gap), (4.0, 0.1));
    }

    #[test]
    fn derived_defaults_are_computed_from_the_keys_they_name() {
        let text = "method = \"dpd\"\n[system]\nbox_edges = [9.0, 8.0, 10.0]\n\
                    [colloids]\nmorse_kappa = 20.0\n";
        let (_, r) = read(&table(text), None).unwrap();
        // observe.gr_max: 0.49 L of the shortest edge; observe.contact_gap: 3 / morse_kappa.
        assert_eq!(r.gr_max, 0.49 * 8.0);
        assert_eq!(r.contact_gap, 3.0 / 20.0);
        let (_, cube) = read(
            &table("method = \"dpd\"\n[system]\nbox_length = 7.0\n"),
            None,
        )
        .unwrap();
        assert_eq!(cube.gr_max, 0.49 * 7.0);
        // Literal defaults come from the declarations.
        assert_eq!(cube.setup.params.kt, 0.1);
        assert_eq!(cube.steps, 10_000);
    }

    #[test]
    fn checks_across_keys_name_the_key() {
        let base = "method = \"dpd\"\n[system]\nbox_length = 10.0\nphi = 0.1\n";
        for (extra, says) in [
            ("", "system.box_length: give the box"),
            (
                "box_edges = [10.0, 10.0, 10.0]\n",
                "system.box_edges: give either",
            ),
            (
                "radius_spread = 0.1\n",
                "system.radius_spread: a spread needs",
            ),
            (
                "[colloids]\nlubrication_gap = 2.0\n",
                "colloids.lubrication_gap: must be smaller than colloids.cutoff",
            ),
            ("[colloids]\nmorse_r0 = 1.5\n", "colloids.morse_r0"),
            ("[observe]\ngr_max = 6.0\n", "observe.gr_max"),
            (
                "[observe]\nviscosity_every = 10\nviscosity_time = 0.001\n",
                "observe.viscosity_time: must be at least one sample interval",
            ),
            ("[run]\nrank_grid = [1.5, 2]\n", "run.rank_grid: [1.5, 2]"),
        ] {
            let text = if extra.is_empty() {
                "method = \"dpd\"\n[system]\nphi = 0.1\n".to_string()
            } else if extra.starts_with('[') {
                format!("{base}{extra}")
            } else {
                format!("method = \"dpd\"\n[system]\nbox_length = 10.0\n{extra}")
            };
            let e = refused(&text);
            assert!(e.contains(says), "{extra}: {e}");
        }
        let e = refused("method = \"dpd\"\n[system]\nbox_length = 3.0\nphi = 0.1\n");
        assert!(
            e.contains("system.box_length: the shortest box edge 3"),
            "{e}"
        );
        let e = refused("method = \"dpd\"\n[system]\nbox_edges = [10.0, 0.0, 10.0]\n");
        assert!(e.contains("system.box_edges: must be"), "{e}");
    }

    #[test]
    fn a_seed_beyond_the_random_streams_names_the_key() {
        // The counter-based streams take 32 bits: a --seed beyond them names `seed`.
        let t = table("method = \"dpd\"\n[system]\nbox_length = 8.0\n");
        let e = read(&t, Some(1 << 40)).unwrap_err().to_string();
        assert!(e.starts_with("seed: "), "{e}");
    }
}
