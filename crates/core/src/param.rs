//! Validated parameters: every check names the scenario key and the allowed range.

use thiserror::Error;

/// A parameter outside its allowed range, or an inconsistent combination of parameters.
#[derive(Debug, Clone, Error, PartialEq)]
#[error("{key}: {message}")]
pub struct ParamError {
    /// Scenario key, e.g. `system.length`.
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl ParamError {
    /// A new error for `key`.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            message: message.into(),
        }
    }
}

/// A number as messages show it: as written for ordinary sizes, in exponent form when huge
/// or tiny (`1e300`, not three hundred digits).
pub fn show(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && a.is_finite() && !(1e-5..1e16).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A run's random seed: it keys 32-bit counter streams, so it must fit in a `u32`.
pub fn seed(key: &str, value: u64) -> Result<u32, ParamError> {
    u32::try_from(value)
        .map_err(|_| ParamError::new(key, format!("must lie in [0, 4294967295], got {value}")))
}

/// `value` must be finite and > 0.
pub fn positive(key: &str, value: f64) -> Result<f64, ParamError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ParamError::new(
            key,
            format!("must be a finite number > 0, got {}", show(value)),
        ))
    }
}

/// `value` must be finite and >= 0.
pub fn non_negative(key: &str, value: f64) -> Result<f64, ParamError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(ParamError::new(
            key,
            format!("must be a finite number >= 0, got {}", show(value)),
        ))
    }
}

/// `value` must be finite.
pub fn finite(key: &str, value: f64) -> Result<f64, ParamError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ParamError::new(
            key,
            format!("must be a finite number, got {}", show(value)),
        ))
    }
}

/// `value` must lie in the closed interval [`lo`, `hi`].
pub fn in_range(key: &str, value: f64, lo: f64, hi: f64) -> Result<f64, ParamError> {
    if value.is_finite() && value >= lo && value <= hi {
        Ok(value)
    } else {
        Err(ParamError::new(
            key,
            format!(
                "must lie in [{}, {}], got {}",
                show(lo),
                show(hi),
                show(value)
            ),
        ))
    }
}

/// Integer `value` must be at least `min`.
pub fn at_least(key: &str, value: usize, min: usize) -> Result<usize, ParamError> {
    if value >= min {
        Ok(value)
    } else {
        Err(ParamError::new(
            key,
            format!("must be at least {min}, got {value}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_key_and_range() {
        let e = positive("run.dt", -1.0).unwrap_err();
        assert_eq!(e.key, "run.dt");
        assert!(e.to_string().contains("run.dt") && e.to_string().contains("> 0"));
        assert!(positive("x", f64::NAN).is_err());
        assert!(non_negative("x", 0.0).is_ok());
        assert!(in_range("x", 1.5, 0.0, 1.0).is_err());
        assert!(at_least("n", 0, 1).is_err());
        assert_eq!(show(1e300), "1e300");
        assert_eq!(show(-1.0), "-1");
        assert_eq!(show(0.25), "0.25");
        assert_eq!(show(3e-9), "3e-9");
        assert!(
            positive("x", 1e300).is_ok()
                && finite("x", f64::INFINITY)
                    .unwrap_err()
                    .message
                    .ends_with("got inf")
        );
    }
}
