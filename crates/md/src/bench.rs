//! Benchmark systems: WCA Brownian dynamics of hard-sphere-like colloids in a periodic cube
//! (`colloidsim bench bd`) and pure DPD water (`colloidsim bench dpd`).

use crate::brownian::hydrodynamic::{HydroBdError, HydroBdParams, HydroBrownian};
use crate::brownian::{BdError, BdParams, Brownian};
use crate::dpd::{Dpd, DpdError, DpdParams};
use crate::init::random_in_box;
use crate::potential::{LennardJones, NoExternal};
use crate::state::{Particles, SimBox};
use colloidsim_core::rng::{Purpose, stream};
use colloidsim_hydro::{AnyMobility, Pse, PseParams};
use rand::RngExt;
use rand_distr::StandardNormal;
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
    wca_periodic_box(n, SimBox::cube(l), dt, seed, skin)
}

/// [`wca_periodic_skin`] of `n` particles in the periodic box `sbox` (the weak scaling of
/// `colloidsim bench bd --ranks` stretches the cube along z).
pub fn wca_periodic_box(
    n: usize,
    sbox: SimBox,
    dt: f64,
    seed: u32,
    skin: f64,
) -> Result<Brownian<LennardJones, NoExternal>, BdError> {
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

/// The system of [`wca_periodic`] (WCA, friction 1 from viscosity `1 / (3 pi)` and diameter 1,
/// skin 0.3) with RPY hydrodynamics by positively split Ewald in the same periodic cube
/// (splitting `xi = 0.5 / a`, tolerance `tolerance`): the BD+RPY case of `colloidsim bench rpy`.
pub fn wca_periodic_rpy(
    n: usize,
    phi: f64,
    dt: f64,
    seed: u32,
    tolerance: f64,
) -> Result<HydroBrownian<LennardJones, NoExternal, AnyMobility>, HydroBdError> {
    let l = (n as f64 * PI / 6.0 / phi).cbrt();
    let sbox = SimBox::cube(l);
    let pos =
        random_in_box(n, 1.0, &sbox, seed, 0).map_err(|e| HydroBdError::Invalid(e.to_string()))?;
    let mut p = PseParams::paper(0.5, 1.0 / (3.0 * PI), l);
    p.tolerance = tolerance;
    let mobility = AnyMobility::Pse(Box::new(Pse::new(n, p)?));
    HydroBrownian::new(
        Particles::monodisperse(pos, 1.0),
        sbox,
        LennardJones::wca(1.0, 1.0),
        NoExternal,
        mobility,
        HydroBdParams::new(dt, seed),
        0,
    )
}

/// Pure DPD water (`kT = 1`, `gamma = 4.5`, `rc = 1`, repulsion 25; [`DpdParams::water`]) in a
/// periodic cube of edge `l` at bead number density `density`: `round(density l^3)` beads of
/// type `"S"` (diameter 1, mass 1) at uniformly random positions (overlaps are harmless for the
/// soft DPD repulsion; the start relaxes within a few hundred steps), Maxwell–Boltzmann
/// velocities at `kT = 1` with the total momentum removed, time step `dt`, Verlet skin `skin`.
/// Positions come from stream index 0 and velocities from index 1 of
/// `stream(seed, 0, Purpose::Initial, _)`; `seed` also seeds the pair noise. The system of
/// `colloidsim bench dpd`.
pub fn dpd_water(l: f64, density: f64, dt: f64, seed: u32, skin: f64) -> Result<Dpd, DpdError> {
    dpd_water_box([l; 3], density, dt, seed, skin)
}

/// [`dpd_water`] in a box of edges `l` (the same start as the cube when the edges are equal).
pub fn dpd_water_box(
    l: [f64; 3],
    density: f64,
    dt: f64,
    seed: u32,
    skin: f64,
) -> Result<Dpd, DpdError> {
    if !(l.iter().all(|x| x.is_finite() && *x > 0.0) && density.is_finite() && density > 0.0) {
        return Err(DpdError::Invalid(format!(
            "box edges {l:?} and density {density} must be > 0"
        )));
    }
    let n = (density * l[0] * l[1] * l[2]).round() as usize;
    let mut rng = stream(seed, 0, Purpose::Initial, 0);
    let pos: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            [
                (rng.random::<f64>() - 0.5) * l[0],
                (rng.random::<f64>() - 0.5) * l[1],
                (rng.random::<f64>() - 0.5) * l[2],
            ]
        })
        .collect();
    let mut rng = stream(seed, 0, Purpose::Initial, 1);
    let kt: f64 = 1.0;
    let sd = kt.sqrt(); // sqrt(kT / m), m = 1
    let mut vel: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            [
                sd * rng.sample::<f64, _>(StandardNormal),
                sd * rng.sample::<f64, _>(StandardNormal),
                sd * rng.sample::<f64, _>(StandardNormal),
            ]
        })
        .collect();
    if n > 0 {
        let mut mean = [0.0; 3];
        for v in &vel {
            for k in 0..3 {
                mean[k] += v[k];
            }
        }
        let mean = mean.map(|m| m / n as f64);
        for v in &mut vel {
            for k in 0..3 {
                v[k] -= mean[k];
            }
        }
    }
    let mut particles = Particles::monodisperse(pos, 1.0);
    particles.vel = vel;
    particles.type_names = vec!["S".into()];
    let mut params = DpdParams::water(dt, seed);
    params.kt = kt;
    params.skin = skin;
    Dpd::new(particles, SimBox::new(l), params, vec![false], 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dpd_water_has_the_requested_beads_temperature_and_no_momentum() {
        let sim = dpd_water(6.0, 3.0, 0.04, 5, 0.4).unwrap();
        assert_eq!(sim.len(), 648);
        let p = sim.snapshot();
        assert_eq!(p.type_names, vec!["S".to_string()]);
        let mut mom = [0.0; 3];
        let mut ke = 0.0;
        for v in &p.vel {
            for k in 0..3 {
                mom[k] += v[k];
                ke += v[k] * v[k];
            }
        }
        assert!(mom.iter().all(|m| m.abs() < 1e-9), "{mom:?}");
        let t = ke / (3.0 * 648.0 - 3.0);
        // 3N - 3 = 1941 degrees of freedom: relative standard deviation sqrt(2 / 1941) = 3.2 %.
        assert!((t - 1.0).abs() < 0.15, "T = {t}");
        assert!(p.pos.iter().flatten().all(|x| x.abs() <= 3.0));
        assert!(dpd_water(0.0, 3.0, 0.04, 5, 0.4).is_err());
    }
}
