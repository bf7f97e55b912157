//! `_colloidsim.HydroOperator`: the mobility operators of `colloidsim-hydro` on arrays, for
//! `colloidsim.hydro` (the libMobility-shaped Python classes wrap it).
//!
//! Vectors cross the boundary as little-endian `f64` bytes, 3 numbers per particle (numpy
//! reads and writes them without a copy); the products run without the GIL. The noise is the
//! engines' own: particle `p`'s deviates at noise step `s` are those of
//! `NoiseKey { seed, step: s, key0 }` (`crates/hydro/src/noise.rs`), so a product or a
//! displacement here equals the engine's at the same positions, seed and step bit for bit.

use crate::ColloidsimError;
use colloidsim_hydro::{
    AnyMobility, DirectRpy, FreeDraining, HydroError, LanczosParams, Mobility, NoiseKey, Pse,
    PseParams, SqrtReport,
};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// A `HydroError` as `ColloidsimError`, a parameter's key renamed to the Python argument
/// (`names`: pairs of engine key and argument name).
fn hydro_err(e: HydroError, names: &[(&str, &str)]) -> PyErr {
    if let HydroError::Param(p) = &e {
        let key = names
            .iter()
            .find(|(k, _)| *k == p.key)
            .map_or(p.key.as_str(), |(_, a)| a);
        return ColloidsimError::new_err(format!("{key}: {}", p.message));
    }
    ColloidsimError::new_err(e.to_string())
}

/// The engine's parameter keys and the libMobility arguments that set them.
const NAMES: &[(&str, &str)] = &[
    ("radius", "hydrodynamicRadius"),
    ("viscosity", "viscosity"),
    ("tolerance", "tolerance"),
    ("max_iterations", "maxIterations"),
    ("splitting", "psi"),
    ("box_length", "Lx"),
];

/// `bytes` (little-endian f64) as 3-vectors; `what` names the argument in errors.
fn vectors(bytes: &[u8], n: usize, what: &str) -> PyResult<Vec<[f64; 3]>> {
    if bytes.len() != 24 * n {
        return Err(ColloidsimError::new_err(format!(
            "{what}: {} numbers for {n} particles, need {}",
            bytes.len() / 8,
            3 * n
        )));
    }
    Ok(bytes
        .chunks_exact(24)
        .map(|c| {
            let x = |k: usize| f64::from_le_bytes(c[8 * k..8 * k + 8].try_into().expect("8 bytes"));
            [x(0), x(1), x(2)]
        })
        .collect())
}

fn to_bytes<'py>(py: Python<'py>, v: &[[f64; 3]]) -> Bound<'py, PyBytes> {
    let mut out = Vec::with_capacity(24 * v.len());
    for x in v.iter().flatten() {
        out.extend_from_slice(&x.to_le_bytes());
    }
    PyBytes::new(py, &out)
}

/// A mobility operator of N spheres: free draining, direct free-space RPY or PSE.
#[pyclass(module = "colloidsim._colloidsim")]
pub struct HydroOperator {
    op: AnyMobility,
    seed: u32,
    key0: u64,
    positioned: bool,
    last: SqrtReport,
}

#[pymethods]
impl HydroOperator {
    /// `method`: "self" (free draining), "direct" (RPY, unbounded fluid) or "pse" (RPY,
    /// periodic cube of edge `box_length`, splitting `splitting`); one radius per particle.
    #[new]
    #[pyo3(signature = (method, radii, viscosity, tolerance, max_iterations, seed, key0=0, box_length=None, splitting=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        method: &str,
        radii: Vec<f64>,
        viscosity: f64,
        tolerance: f64,
        max_iterations: usize,
        seed: u32,
        key0: u64,
        box_length: Option<f64>,
        splitting: Option<f64>,
    ) -> PyResult<Self> {
        if radii.is_empty() {
            return Err(ColloidsimError::new_err(
                "positions: no particles (give at least one)",
            ));
        }
        if let Some(i) = radii.iter().position(|a| !(a.is_finite() && *a > 0.0)) {
            return Err(ColloidsimError::new_err(format!(
                "hydrodynamicRadius: must be finite and > 0, got {} (particle {i})",
                radii[i]
            )));
        }
        if !(viscosity.is_finite() && viscosity > 0.0) {
            return Err(ColloidsimError::new_err(format!(
                "viscosity: must be finite and > 0, got {viscosity}"
            )));
        }
        let lanczos = LanczosParams {
            tolerance,
            max_iterations,
        };
        colloidsim_hydro::params::check_lanczos(&lanczos)
            .map_err(|e| hydro_err(e.into(), NAMES))?;
        let op = match method {
            "self" => AnyMobility::FreeDraining(
                FreeDraining::new(&radii, viscosity).map_err(|e| hydro_err(e, NAMES))?,
            ),
            "direct" => AnyMobility::Direct(Box::new(
                DirectRpy::with_radii(&radii, viscosity, lanczos, usize::MAX)
                    .map_err(|e| hydro_err(e, NAMES))?,
            )),
            "pse" => {
                let (Some(l), Some(xi)) = (box_length, splitting) else {
                    return Err(ColloidsimError::new_err(
                        "setParameters: PSE needs psi and the box (Lx, Ly, Lz)",
                    ));
                };
                let p = PseParams {
                    radius: radii[0],
                    viscosity,
                    box_length: l,
                    splitting: xi,
                    tolerance,
                    max_iterations,
                };
                AnyMobility::Pse(Box::new(
                    Pse::with_radii(&radii, p).map_err(|e| hydro_err(e, NAMES))?,
                ))
            }
            m => {
                return Err(ColloidsimError::new_err(format!(
                    "method: \"self\", \"direct\" or \"pse\", got {m:?}"
                )));
            }
        };
        Ok(Self {
            op,
            seed,
            key0,
            positioned: false,
            last: SqrtReport::default(),
        })
    }

    /// Number of particles.
    #[getter]
    fn particles(&self) -> usize {
        self.op.len()
    }

    /// Take positions (3N little-endian f64).
    fn set_positions(&mut self, py: Python<'_>, positions: &[u8]) -> PyResult<()> {
        let pos = vectors(positions, self.op.len(), "positions")?;
        let op = &mut self.op;
        py.detach(|| op.set_positions(&pos))
            .map_err(|e| hydro_err(e, NAMES))?;
        self.positioned = true;
        Ok(())
    }

    /// `M f`.
    fn mdot<'py>(&mut self, py: Python<'py>, forces: &[u8]) -> PyResult<Bound<'py, PyBytes>> {
        self.ready()?;
        let f = vectors(forces, self.op.len(), "forces")?;
        let mut out = vec![[0.0; 3]; f.len()];
        let op = &mut self.op;
        py.detach(|| op.apply(&f, &mut out));
        Ok(to_bytes(py, &out))
    }

    /// `scale M^(1/2) z`, `z` the noise of step `step`.
    fn sqrt_mdot_w<'py>(
        &mut self,
        py: Python<'py>,
        step: u64,
        scale: f64,
    ) -> PyResult<Bound<'py, PyBytes>> {
        self.ready()?;
        let key = self.key(step);
        let mut out = vec![[0.0; 3]; self.op.len()];
        let op = &mut self.op;
        self.last = py
            .detach(|| op.brownian(key, scale, &mut out))
            .map_err(|e| hydro_err(e, NAMES))?;
        Ok(to_bytes(py, &out))
    }

    /// The engines' Brownian step `dt M f + sqrt(2 kT dt) M^(1/2) z` (noise of step `step`).
    fn displacement<'py>(
        &mut self,
        py: Python<'py>,
        forces: &[u8],
        dt: f64,
        kt: f64,
        step: u64,
    ) -> PyResult<Bound<'py, PyBytes>> {
        self.ready()?;
        let f = vectors(forces, self.op.len(), "forces")?;
        let key = self.key(step);
        let mut out = vec![[0.0; 3]; f.len()];
        let op = &mut self.op;
        self.last = py
            .detach(|| op.displacement(&f, dt, kt, key, &mut out))
            .map_err(|e| hydro_err(e, NAMES))?;
        Ok(to_bytes(py, &out))
    }

    /// (iterations, relative change) of the last Lanczos square root.
    #[getter]
    fn last_lanczos(&self) -> (usize, f64) {
        (self.last.iterations, self.last.residual)
    }

    /// `1 / (6 pi eta a_i)`.
    fn stokes_mobility(&self, i: usize) -> PyResult<f64> {
        if i >= self.op.len() {
            return Err(ColloidsimError::new_err(format!(
                "particle: {i} is not below {}",
                self.op.len()
            )));
        }
        Ok(self.op.stokes_mobility(i))
    }

    /// The PSE grid, window and cut-offs as (grid, spacing, k_cut, support, beta, half_width,
    /// r_cut); None for the other methods.
    #[allow(clippy::type_complexity)]
    fn pse_geometry(&self) -> Option<(usize, f64, f64, usize, f64, f64, f64)> {
        self.op.pse().map(|p| {
            let g = p.geometry();
            (
                g.grid,
                g.spacing,
                g.k_cut,
                g.support,
                g.beta,
                g.half_width,
                g.r_cut,
            )
        })
    }

    /// Bytes the operator holds.
    fn bytes(&self) -> usize {
        self.op.bytes()
    }
}

impl HydroOperator {
    fn ready(&self) -> PyResult<()> {
        if self.positioned {
            Ok(())
        } else {
            Err(ColloidsimError::new_err(
                "positions: not set; call setPositions first",
            ))
        }
    }

    fn key(&self, step: u64) -> NoiseKey {
        NoiseKey {
            seed: self.seed,
            step,
            key0: self.key0,
        }
    }
}
