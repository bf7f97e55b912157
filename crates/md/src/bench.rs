//! The WCA Brownian-dynamics benchmark system: hard-sphere-like colloids in a periodic cube.

use crate::brownian::{BdError, BdParams, Brownian};
use crate::init::random_in_box;
use crate::potential::{LennardJones, NoExternal};
use crate::state::{Particles, SimBox};
use std::f64::consts::PI;

/// WCA (`epsilon = kT = 1`, `sigma = d = 1`) Brownian dynamics of `n` particles at volume
/// fraction `phi` in a periodic cube, friction 1 (`viscosity = 1 / (3 pi)`), time step `dt`,
/// skin 0.3: the system of `colloidsim bench bd` and of the LAMMPS input it is compared with.
pub fn wca_periodic(
    n: usize,
    phi: f64,
    dt: f64,
    seed: u32,
) -> Result<Brownian<LennardJones, NoExternal>, BdError> {
    wca_periodic_skin(n, phi, dt, seed, 0.3)
}

/// [`wca_periodic`] with a chosen Verlet skin.
pub fn wca_periodic_skin(
    n: usize,
    phi: f64,
    dt: f64,
    seed: u32,
    skin: f64,
) -> Result<Brownian<LennardJones, NoExternal>, BdError> {
    let l = (n as f64 * PI / 6.0 / phi).cbrt();
    let sbox = SimBox::cube(l);
    let pos = random_in_box(n, 1.0, &sbox, seed, 0).map_err(|e| BdError::Invalid(e.to_string()))?;
    let mut params = BdParams::new(dt, seed);
    params.viscosity = 1.0 / (3.0 * PI);
    params.skin = skin;
    Brownian::new(
        Particles::monodisperse(pos, 1.0),
        sbox,
        LennardJones::wca(1.0, 1.0),
        NoExternal,
        params,
        0,
    )
}
