//! Resolved hydrodynamics parameters (model, method, PSE splitting, Lanczos tolerance and
//! iteration limit): the run layer reads a scenario's `[hydrodynamics]` into [`HydroParams`].

use crate::lanczos::LanczosParams;
use crate::pse::PseParams;
use colloidsim_core::ParamError;
use serde::Serialize;

/// Default tolerance (the drying-droplet paper's PSE setting).
pub const DEFAULT_TOLERANCE: f64 = 1e-3;
/// Largest tolerance accepted: PSE's error split (Fourier cut-off, window support) meets its
/// tolerance up to 1e-2 (tests/pse.rs); at 0.1 the Gaussian window then in use came out wider
/// than the splitting allows and the product missed the tolerance by a factor of two.
pub const MAX_TOLERANCE: f64 = 1e-2;
/// Default box edge of a periodic droplet, in droplet diameters (the paper's).
pub const DEFAULT_BOX_FACTOR: f64 = 2.0;
/// Default: the direct method up to this many particles, PSE above.
pub const DEFAULT_DIRECT_MAX: usize = 2000;

/// The mobility model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum HydroModel {
    /// `M = I / (6 pi eta a)`.
    FreeDraining,
    /// Rotne–Prager–Yamakawa.
    Rpy,
}

/// How the RPY mobility is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum HydroMethod {
    /// Free space, O(N^2) direct sums ([`crate::DirectRpy`]).
    Direct,
    /// Periodic cube, positively split Ewald ([`crate::Pse`]).
    Pse,
}

/// Resolved, validated `[hydrodynamics]`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HydroParams {
    /// Mobility model.
    pub model: HydroModel,
    /// Method (free draining: none).
    pub method: Option<HydroMethod>,
    /// Relative tolerance.
    pub tolerance: f64,
    /// PSE splitting xi (1 / length).
    pub splitting: f64,
    /// Droplet box edge / droplet diameter (PSE).
    pub box_factor: f64,
    /// Lanczos iteration limit.
    pub max_iterations: usize,
}

impl HydroParams {
    /// The Lanczos parameters.
    pub fn lanczos(&self) -> LanczosParams {
        LanczosParams {
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
        }
    }

    /// A bound checked before the PSE grid is sized: `xi L <= 1e6` for a box of edge
    /// `box_length`. PSE needs at least `2 xi L / pi` grid points per axis (its Fourier cut-off
    /// exceeds `2 xi`), so this refuses nothing PSE would accept (it takes at most 1024 per
    /// axis); it keeps absurd values (a splitting or box of 1e300) from reaching the grid
    /// arithmetic. The error names `key` (the splitting, or the box's key).
    pub fn check_pse_extent(&self, box_length: f64, key: &str) -> Result<(), ParamError> {
        let extent = self.splitting * box_length;
        if extent.is_finite() && extent <= 1e6 {
            return Ok(());
        }
        Err(ParamError::new(
            key,
            format!(
                "splitting xi = {} in a box of edge {} gives xi L = {extent:e}: the PSE grid would \
                 need far more than 1024 points per axis (about 2 xi L / pi at least)",
                colloidsim_core::param::show(self.splitting),
                colloidsim_core::param::show(box_length)
            ),
        ))
    }

    /// The PSE parameters of these settings for spheres of radius `radius` in a solvent of
    /// viscosity `viscosity`, in a periodic cube of edge `box_length`.
    pub fn pse_params(&self, radius: f64, viscosity: f64, box_length: f64) -> PseParams {
        PseParams {
            radius,
            viscosity,
            box_length,
            splitting: self.splitting,
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
        }
    }
}

/// Tolerance and iteration limit must be in range (the errors name `tolerance` and
/// `max_iterations`).
pub fn check_lanczos(p: &LanczosParams) -> Result<(), ParamError> {
    check_tolerance(p.tolerance)?;
    if !(1..=1000).contains(&p.max_iterations) {
        return Err(ParamError::new(
            "max_iterations",
            format!("must lie in [1, 1000], got {}", p.max_iterations),
        ));
    }
    Ok(())
}

/// The tolerance must lie in (0, [`MAX_TOLERANCE`]] (the error names `tolerance`).
pub fn check_tolerance(t: f64) -> Result<f64, ParamError> {
    if t.is_finite() && t > 0.0 && t <= MAX_TOLERANCE {
        Ok(t)
    } else {
        Err(ParamError::new(
            "tolerance",
            format!("must lie in (0, {MAX_TOLERANCE}], got {t}"),
        ))
    }
}
