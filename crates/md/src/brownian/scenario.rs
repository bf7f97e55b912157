//! What the Brownian-dynamics scenarios (`droplet-bd`, `bd`) share: an initial configuration
//! read from a GSD file, and the engines' parameters of a replica.

use super::hydrodynamic::HydroBdParams;
use super::{BdParams, Integrator};
use crate::gsd::{GsdFrame, read_frame};
use crate::state::Particles;
use colloidsim_particles::Mixture;
use std::path::Path;

/// The last frame of `path` (`system.initial`), which must hold `n` particles; the error
/// names the file.
pub(crate) fn read_initial(path: &Path, n: usize) -> Result<GsdFrame, String> {
    let f = read_frame(path, None).map_err(|e| e.to_string())?;
    if f.particles.len() != n {
        return Err(format!(
            "{} holds {} particles, `particles` is {n}",
            path.display(),
            f.particles.len(),
        ));
    }
    Ok(f)
}

/// The particles read from `path` must be one species (typeid 0, as a `what` holds); they all
/// get the scenario's diameter `d` (GSD stores diameters in single precision).
pub(crate) fn one_species(
    path: &Path,
    p: &mut Particles,
    what: &str,
    d: f64,
) -> Result<(), String> {
    if let Some(i) = p.typeid.iter().position(|&t| t != 0) {
        return Err(format!(
            "{}: particle {i} has typeid {}, but a {what} holds one type of particle (typeid 0)",
            path.display(),
            p.typeid[i]
        ));
    }
    p.diameter.iter_mut().for_each(|x| *x = d);
    Ok(())
}

/// The particles read from `path` hold the species of `mixture`: each particle's typeid names
/// its species, the counts match, and every particle gets its species' diameter. One species:
/// [`one_species`].
pub(crate) fn species_from_file(
    path: &Path,
    p: &mut Particles,
    what: &str,
    mixture: &Mixture,
) -> Result<(), String> {
    if mixture.is_single() {
        return one_species(path, p, what, mixture.diameters[0]);
    }
    let mut counts = vec![0usize; mixture.len()];
    for (i, &t) in p.typeid.iter().enumerate() {
        match counts.get_mut(t as usize) {
            Some(c) => *c += 1,
            None => {
                return Err(format!(
                    "{}: particle {i} has typeid {t}, but the {what} has {} species (typeids 0 to {})",
                    path.display(),
                    mixture.len(),
                    mixture.len() - 1
                ));
            }
        }
    }
    if counts != mixture.counts {
        return Err(format!(
            "{}: holds {counts:?} particles of each species, the scenario {:?}",
            path.display(),
            mixture.counts
        ));
    }
    for (d, &t) in p.diameter.iter_mut().zip(&p.typeid) {
        *d = mixture.diameters[t as usize];
    }
    p.type_names = mixture.names.clone();
    Ok(())
}

/// The free-draining engine's parameters of replica `replica` (a fresh start and a restart
/// take them from here alike): the scenario's values, the neighbour list's sorting and drift
/// fixed for both scenarios.
pub(crate) fn free_draining(
    kt: f64,
    viscosity: f64,
    dt: f64,
    seed: u32,
    replica: u32,
    skin: f64,
    integrator: Integrator,
) -> BdParams {
    BdParams {
        kt,
        viscosity,
        dt,
        seed,
        replica,
        skin,
        sort_every: 500,
        max_drift: 0.2,
        integrator,
    }
}

/// The hydrodynamic engine's parameters of replica `replica`, as [`free_draining`].
pub(crate) fn hydrodynamic(kt: f64, dt: f64, seed: u32, replica: u32, skin: f64) -> HydroBdParams {
    HydroBdParams {
        kt,
        dt,
        seed,
        replica,
        skin,
        max_drift: 0.2,
    }
}
