//! The droplet's liquid–vapour interface and its shrinking radius (the drying-droplet paper, docs/references.md; paper
//! Eqs. 1–2).

use std::f64::consts::PI;

use colloidsim_core::{ParamError, param};

use super::RadialError;

/// Harmonic interface: with `s = r - (R + offset)`, `beta V = 0` for `s < 0`,
/// `beta V = k s^2 / 2` for `0 <= s < Delta`, and the linear continuation
/// `beta V = k Delta^2 / 2 + k Delta (s - Delta)` beyond (`k` in `kT / length^2`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicInterface {
    /// Spring constant `beta k` (1 / length^2).
    pub stiffness: f64,
    /// Range `Delta` of the harmonic part (length).
    pub range: f64,
    /// Wall position relative to `R(t)` (length; `-d/2` puts the colloid surface at `R`).
    pub offset: f64,
}

impl HarmonicInterface {
    /// Validated interface (errors name `stiffness`, `range`, `offset`).
    pub fn new(stiffness: f64, range: f64, offset: f64) -> Result<Self, RadialError> {
        param::positive("stiffness", stiffness)?;
        param::positive("range", range)?;
        param::finite("offset", offset)?;
        Ok(Self {
            stiffness,
            range,
            offset,
        })
    }

    /// `beta V` at distance `r` from the centre for droplet radius `radius`.
    #[inline]
    pub fn potential(&self, r: f64, radius: f64) -> f64 {
        let s = r - (radius + self.offset);
        if s <= 0.0 {
            0.0
        } else if s < self.range {
            0.5 * self.stiffness * s * s
        } else {
            self.stiffness * self.range * (0.5 * self.range + (s - self.range))
        }
    }

    /// `beta V` at every point of `r` into `out`.
    pub fn fill(&self, r: &[f64], radius: f64, out: &mut [f64]) {
        for (o, &x) in out.iter_mut().zip(r) {
            *o = self.potential(x, radius);
        }
    }

    /// Distance beyond `R + offset` at which `beta V` reaches `v`.
    pub fn reach(&self, v: f64) -> f64 {
        let k = self.stiffness;
        let d = self.range;
        if v <= 0.5 * k * d * d {
            (2.0 * v / k).sqrt()
        } else {
            d + (v - 0.5 * k * d * d) / (k * d)
        }
    }
}

/// Drying law `R(t) = sqrt(R0^2 - alpha t / (4 pi))` (Eq. 1; surface area falls linearly).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DryingSchedule {
    /// Initial radius `R0`.
    pub r0: f64,
    /// Rate of loss of surface area `alpha` (length^2 / time); 0 for a static droplet.
    pub alpha: f64,
}

impl DryingSchedule {
    /// Validated schedule (errors name `r0`, `alpha`).
    pub fn new(r0: f64, alpha: f64) -> Result<Self, RadialError> {
        param::positive("r0", r0)?;
        param::non_negative("alpha", alpha)?;
        Ok(Self { r0, alpha })
    }

    /// Schedule of Peclet number `Pe = R |dR/dt| / D0`, i.e. `alpha = 8 pi Pe D0`.
    pub fn from_peclet(r0: f64, peclet: f64, d0: f64) -> Result<Self, RadialError> {
        param::non_negative("peclet", peclet)?;
        param::positive("d0", d0)?;
        Self::new(r0, 8.0 * PI * peclet * d0)
    }

    /// Time at which `R` would reach zero (infinite for a static droplet).
    pub fn collapse_time(&self) -> f64 {
        if self.alpha > 0.0 {
            4.0 * PI * self.r0 * self.r0 / self.alpha
        } else {
            f64::INFINITY
        }
    }

    /// `R(t)`; errors once the schedule passes `R = 0`.
    pub fn radius(&self, t: f64) -> Result<f64, RadialError> {
        let r2 = self.r0 * self.r0 - self.alpha * t / (4.0 * PI);
        if r2 > 0.0 {
            Ok(r2.sqrt())
        } else {
            Err(ParamError::new(
                "t_end",
                format!(
                    "the drying schedule passes R = 0 at t = {} (asked for t = {t})",
                    self.collapse_time()
                ),
            )
            .into())
        }
    }

    /// Time at which the radius is `radius` (< `R0`).
    pub fn time_at_radius(&self, radius: f64) -> f64 {
        4.0 * PI * (self.r0 * self.r0 - radius * radius) / self.alpha
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn potential_is_continuous_and_reach_inverts_it() {
        let w = HarmonicInterface::new(100.0, 0.5, -0.5).unwrap();
        let r = 10.0;
        let edge = r - 0.5 + 0.5;
        assert!((w.potential(edge - 1e-12, r) - w.potential(edge + 1e-12, r)).abs() < 1e-9);
        assert_eq!(w.potential(9.4, r), 0.0);
        for v in [1.0, 12.5, 60.0] {
            assert!((w.potential(r - 0.5 + w.reach(v), r) - v).abs() < 1e-9);
        }
    }

    #[test]
    fn schedule_has_constant_peclet_and_rejects_collapse() {
        let d0 = 0.3;
        let s = DryingSchedule::from_peclet(25.0, 10.0, d0).unwrap();
        for t in [0.0, 10.0, 100.0] {
            let h = 1e-4;
            let r = s.radius(t).unwrap();
            let v = (s.radius(t + h).unwrap() - s.radius(t - h).unwrap()) / (2.0 * h);
            assert!((r * v.abs() / d0 - 10.0).abs() < 1e-5);
        }
        assert!(s.radius(s.collapse_time() * 1.01).is_err());
        assert!((s.time_at_radius(s.radius(50.0).unwrap()) - 50.0).abs() < 1e-9);
    }
}
