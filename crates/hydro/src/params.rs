//! The `[hydrodynamics]` table of a scenario: typed, validated parameters.
//!
//! ```toml
//! [hydrodynamics]
//! model = "rpy"          # "free-draining" (default) | "rpy"
//! method = "pse"         # "direct" | "pse"; default: direct up to `direct_max` particles
//! tolerance = 1e-3       # relative error of the product and of the Lanczos square root, (0, 0.1]
//! splitting = 1.0        # PSE splitting xi (1 / length), > 0; default 0.5 / a = 1 / d
//! box_factor = 2.0       # droplet with PSE: box edge / droplet diameter, [1.2, 20]
//! max_iterations = 200   # Lanczos iteration limit, [1, 1000]
//! ```

use crate::lanczos::LanczosParams;
use crate::pse::PseParams;
use colloidsim_core::ParamError;
use colloidsim_core::param::in_range;
use serde::{Deserialize, Serialize};

/// Default tolerance (the drying-droplet paper's PSE setting).
pub const DEFAULT_TOLERANCE: f64 = 1e-3;
/// Largest tolerance accepted.
pub const MAX_TOLERANCE: f64 = 0.1;
/// Default box edge of a periodic droplet, in droplet diameters (the paper's).
pub const DEFAULT_BOX_FACTOR: f64 = 2.0;
/// Default: the direct method up to this many particles, PSE above.
pub const DEFAULT_DIRECT_MAX: usize = 2000;

/// `[hydrodynamics]` as written in a scenario file.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HydrodynamicsSection {
    /// `"free-draining"` (default) or `"rpy"`.
    #[serde(default)]
    pub model: Option<String>,
    /// `"direct"` (unbounded fluid) or `"pse"` (periodic cube); default by N.
    #[serde(default)]
    pub method: Option<String>,
    /// Relative tolerance, (0, 0.1] (default 1e-3).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// PSE splitting parameter xi (1 / length), > 0 (default 0.5 / a).
    #[serde(default)]
    pub splitting: Option<f64>,
    /// Droplet with PSE: box edge as a multiple of the initial droplet diameter (default 2).
    #[serde(default)]
    pub box_factor: Option<f64>,
    /// Lanczos iteration limit (default 200).
    #[serde(default)]
    pub max_iterations: Option<usize>,
}

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

/// Tolerance and iteration limit must be in range (`hydrodynamics.tolerance`,
/// `hydrodynamics.max_iterations`).
pub fn check_lanczos(p: &LanczosParams) -> Result<(), ParamError> {
    check_tolerance(p.tolerance)?;
    if !(1..=1000).contains(&p.max_iterations) {
        return Err(ParamError::new(
            "hydrodynamics.max_iterations",
            format!("must lie in [1, 1000], got {}", p.max_iterations),
        ));
    }
    Ok(())
}

/// `hydrodynamics.tolerance` must lie in (0, 0.1].
pub fn check_tolerance(t: f64) -> Result<f64, ParamError> {
    if t.is_finite() && t > 0.0 && t <= MAX_TOLERANCE {
        Ok(t)
    } else {
        Err(ParamError::new(
            "hydrodynamics.tolerance",
            format!("must lie in (0, {MAX_TOLERANCE}], got {t}"),
        ))
    }
}

impl HydrodynamicsSection {
    /// Validate for `particles` spheres of radius `radius`. `periodic`: the system is a
    /// periodic cube (bulk), so RPY needs PSE; otherwise (droplet) both methods are allowed and
    /// the default is direct up to [`DEFAULT_DIRECT_MAX`] particles.
    pub fn validate(
        &self,
        particles: usize,
        radius: f64,
        periodic: bool,
    ) -> Result<HydroParams, ParamError> {
        let model = match self.model.as_deref().unwrap_or("free-draining") {
            "free-draining" => HydroModel::FreeDraining,
            "rpy" => HydroModel::Rpy,
            other => {
                return Err(ParamError::new(
                    "hydrodynamics.model",
                    format!("must be \"free-draining\" or \"rpy\", got \"{other}\""),
                ));
            }
        };
        let method = match (model, self.method.as_deref()) {
            (HydroModel::FreeDraining, None) => None,
            (HydroModel::FreeDraining, Some(m)) => {
                return Err(ParamError::new(
                    "hydrodynamics.method",
                    format!("\"{m}\" needs model = \"rpy\" (free draining has no method)"),
                ));
            }
            (HydroModel::Rpy, None) => Some(if periodic || particles > DEFAULT_DIRECT_MAX {
                HydroMethod::Pse
            } else {
                HydroMethod::Direct
            }),
            (HydroModel::Rpy, Some("direct")) if periodic => {
                return Err(ParamError::new(
                    "hydrodynamics.method",
                    "\"direct\" is the unbounded fluid; a periodic box needs \"pse\"",
                ));
            }
            (HydroModel::Rpy, Some("direct")) => Some(HydroMethod::Direct),
            (HydroModel::Rpy, Some("pse")) => Some(HydroMethod::Pse),
            (_, Some(other)) => {
                return Err(ParamError::new(
                    "hydrodynamics.method",
                    format!("must be \"direct\" or \"pse\", got \"{other}\""),
                ));
            }
        };
        let tolerance = check_tolerance(self.tolerance.unwrap_or(DEFAULT_TOLERANCE))?;
        let splitting = self.splitting.unwrap_or(0.5 / radius);
        if !(splitting.is_finite() && splitting > 0.0) {
            return Err(ParamError::new(
                "hydrodynamics.splitting",
                format!(
                    "must be a finite number > 0 (1 / length; paper: 0.5 / a), got {splitting}"
                ),
            ));
        }
        let box_factor = in_range(
            "hydrodynamics.box_factor",
            self.box_factor.unwrap_or(DEFAULT_BOX_FACTOR),
            1.2,
            20.0,
        )?;
        let max_iterations = self.max_iterations.unwrap_or(200);
        let p = HydroParams {
            model,
            method,
            tolerance,
            splitting,
            box_factor,
            max_iterations,
        };
        check_lanczos(&p.lanczos())?;
        for (key, given) in [
            ("hydrodynamics.splitting", self.splitting.is_some()),
            ("hydrodynamics.box_factor", self.box_factor.is_some()),
        ] {
            if given && method != Some(HydroMethod::Pse) {
                return Err(ParamError::new(key, "applies only to method = \"pse\""));
            }
        }
        Ok(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> HydrodynamicsSection {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn defaults_and_errors_name_the_key() {
        let p = parse("").validate(1000, 0.5, false).unwrap();
        assert_eq!(p.model, HydroModel::FreeDraining);
        assert_eq!(p.method, None);
        let p = parse("model = \"rpy\"").validate(1000, 0.5, false).unwrap();
        assert_eq!(p.method, Some(HydroMethod::Direct));
        assert_eq!(p.splitting, 1.0);
        let p = parse("model = \"rpy\"")
            .validate(50_000, 0.5, false)
            .unwrap();
        assert_eq!(p.method, Some(HydroMethod::Pse));
        let key = |t: &str, periodic| parse(t).validate(100, 0.5, periodic).unwrap_err().key;
        assert_eq!(key("model = \"oseen\"", false), "hydrodynamics.model");
        assert_eq!(
            key("model = \"rpy\"\ntolerance = 0.2", false),
            "hydrodynamics.tolerance"
        );
        assert_eq!(
            key("model = \"rpy\"\ntolerance = 0.0", false),
            "hydrodynamics.tolerance"
        );
        assert_eq!(
            key("model = \"rpy\"\nmethod = \"pse\"\nsplitting = -1", false),
            "hydrodynamics.splitting"
        );
        assert_eq!(
            key("model = \"rpy\"\nmethod = \"direct\"", true),
            "hydrodynamics.method"
        );
        assert_eq!(key("method = \"pse\"", false), "hydrodynamics.method");
        assert_eq!(
            key("model = \"rpy\"\nmethod = \"pse\"\nbox_factor = 1.0", false),
            "hydrodynamics.box_factor"
        );
        assert_eq!(
            key(
                "model = \"rpy\"\nmethod = \"direct\"\nsplitting = 1.0",
                false
            ),
            "hydrodynamics.splitting"
        );
        assert_eq!(
            key("model = \"rpy\"\nmax_iterations = 0", false),
            "hydrodynamics.max_iterations"
        );
        let e = parse("model = \"rpy\"\ntolerance = 0.5")
            .validate(10, 0.5, false)
            .unwrap_err();
        assert!(e.to_string().contains("(0, 0.1]"), "{e}");
        assert!(toml::from_str::<HydrodynamicsSection>("speed = 1").is_err());
    }
}
