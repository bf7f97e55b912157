//! What the Brownian-dynamics scenarios (`droplet-bd`, `bd`) share: their head (method, seed,
//! replicas), the spheres and the solvent, and an initial configuration read from a GSD file.

use crate::gsd::{GsdFrame, read_frame};
use crate::state::Particles;
use colloidsim_core::ParamError;
use colloidsim_core::param::{at_least, positive};
use std::f64::consts::PI;
use std::path::Path;

/// The validated head of a scenario: `method` (must be `name`), `seed` (32 bits), `replicas`
/// (at least 1).
pub(crate) fn resolve_head(
    method: &str,
    name: &str,
    seed: u64,
    replicas: usize,
) -> Result<(u32, usize), ParamError> {
    if method != name {
        return Err(ParamError::new(
            "method",
            format!("must be \"{name}\", got \"{method}\""),
        ));
    }
    let seed = colloidsim_core::param::seed("seed", seed)?;
    Ok((seed, at_least("replicas", replicas, 1)?))
}

/// The spheres and the solvent (`system.particles`, `system.diameter`, `system.kT`,
/// `system.viscosity`), validated, with the Stokes friction and the free diffusivity.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Spheres {
    /// N.
    pub particles: usize,
    /// Diameter d.
    pub d: f64,
    /// kT.
    pub kt: f64,
    /// Viscosity eta.
    pub eta: f64,
    /// Stokes friction `3 pi eta d`.
    pub friction: f64,
    /// `D0 = kT / (3 pi eta d)`.
    pub d0: f64,
}

impl Spheres {
    /// Validate the four keys, in this order.
    pub(crate) fn resolve(
        particles: usize,
        diameter: f64,
        kt: f64,
        viscosity: f64,
    ) -> Result<Self, ParamError> {
        let particles = at_least("system.particles", particles, 1)?;
        let d = positive("system.diameter", diameter)?;
        let kt = positive("system.kT", kt)?;
        let eta = positive("system.viscosity", viscosity)?;
        let friction = 3.0 * PI * eta * d;
        Ok(Self {
            particles,
            d,
            kt,
            eta,
            friction,
            d0: kt / friction,
        })
    }
}

/// The last frame of `path` (`system.initial`), which must hold `n` particles; the error
/// names the file.
pub(crate) fn read_initial(path: &Path, n: usize) -> Result<GsdFrame, String> {
    let f = read_frame(path, None).map_err(|e| e.to_string())?;
    if f.particles.len() != n {
        return Err(format!(
            "{} holds {} particles, system.particles is {n}",
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
