//! Bulk hard-sphere pair correlation `g(r; eta)` for the DDFT's two-body density (paper Eq. 17).
//!
//! - [`Trokhymchuk`]: the analytical `g(r)` of Trokhymchuk, Nezbeda, Jirsák and Henderson,
//!   J. Chem. Phys. 123, 024501 (2005), with `mu` and `gamma` as corrected in the erratum,
//!   J. Chem. Phys. 124, 149902 (2006). In units of the diameter (`x = r / d`):
//!   - depletion part, `1 <= x <= x*`:
//!     `g = (A / x) exp(mu (x - 1)) + (B / x) cos(beta (x - 1) + gamma) exp(alpha (x - 1))`;
//!   - structural part, `x > x*`: `g = 1 + (C / x) cos(omega x + delta) exp(-kappa x)`;
//!   - `x*` and `g(x*) = g_m` (the first minimum), `omega`, `kappa`, `alpha`, `beta` are the
//!     paper's fits in `eta`; `mu` and `gamma` come from the Percus–Yevick poles (Wertheim);
//!     the contact value is `g(1+) = (Z - 1) / (4 eta)` with Kolafa's `Z`; `A`, `B`, `C` and
//!     `delta` make `g` continuous at contact and at `x*` and put the minimum of the structural
//!     part at `x*`.
//!
//!   The fits were made for `0.2 <= rho d^3 <= 0.9` (`0.105 <= eta <= 0.471`).
//! - [`total_correlation`]: `h = g - 1` for every `eta` in `[0, 0.6]`, as the DDFT uses it:
//!   Trokhymchuk's form in its range and above it up to 0.6 (the paper clipped the mean density
//!   there too); below it, the exact low-density limit `h = 8 eta (1 - 3x/4 + x^3/16)` for
//!   `1 < x < 2` (the overlap volume of two exclusion spheres) blended into the fit so that `h`
//!   is continuous in `eta`:
//!   `h = h_vir(eta) + (eta / eta_min)^2 [h_T(eta_min) - h_vir(eta_min)]`.

use std::f64::consts::PI;

use colloidsim_core::ParamError;

/// Lowest packing fraction of Trokhymchuk's fits (`rho d^3 = 0.2`).
pub const ETA_FIT_MIN: f64 = PI * 0.2 / 6.0;
/// Highest packing fraction of Trokhymchuk's fits (`rho d^3 = 0.9`).
pub const ETA_FIT_MAX: f64 = PI * 0.9 / 6.0;
/// Largest packing fraction [`total_correlation`] accepts (the paper's clip of the mean density).
pub const ETA_CLIP: f64 = 0.6;

/// Trokhymchuk's analytical hard-sphere `g(r)` at one packing fraction (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trokhymchuk {
    /// Packing fraction.
    pub eta: f64,
    /// Contact value `g(1+)`.
    pub contact: f64,
    /// Position `x*` of the first minimum, where the two parts meet.
    pub x_min: f64,
    /// `g(x*)`.
    pub g_min: f64,
    mu: f64,
    alpha: f64,
    beta: f64,
    gamma: f64,
    omega: f64,
    kappa: f64,
    delta: f64,
    a: f64,
    b: f64,
    c: f64,
}

impl Trokhymchuk {
    /// The parameters at packing fraction `eta`, `0 < eta <= ETA_CLIP` (outside the fitted
    /// range `[ETA_FIT_MIN, ETA_FIT_MAX]` the fits are extrapolated; [`total_correlation`] uses
    /// them only above it).
    pub fn new(eta: f64) -> Result<Self, ParamError> {
        if !(eta.is_finite() && eta > 0.0 && eta <= ETA_CLIP) {
            return Err(ParamError::new(
                "pair.eta",
                format!("packing fraction must be in (0, {ETA_CLIP}], got {eta}"),
            ));
        }
        let e = eta;
        // Percus–Yevick poles (Wertheim): mu real, alpha0 +- i beta0 complex (erratum Eq. 29).
        let root = (3.0 * (e.powi(4) - 2.0 * e.powi(3) + e * e + 6.0 * e + 3.0)).sqrt();
        let dw = (2.0 * e * (e * e - 3.0 * e - 3.0 + root)).cbrt();
        let s = 2.0 * e / (1.0 - e);
        let mu = s * (-1.0 - dw / (2.0 * e) + e / dw);
        let alpha0 = s * (-1.0 + dw / (4.0 * e) - e / (2.0 * dw));
        let beta0 = s * 3f64.sqrt() * (-dw / (4.0 * e) - e / (2.0 * dw));
        // Erratum Eq. 30.
        let (a2, b2) = (alpha0 * alpha0, beta0 * beta0);
        let num = (alpha0 * (a2 + b2) - mu * (a2 - b2)) * (1.0 + 0.5 * e)
            + (a2 + b2 - mu * alpha0) * (1.0 + 2.0 * e);
        let den = (a2 + b2 - 2.0 * mu * alpha0) * (1.0 + 0.5 * e) - mu * (1.0 + 2.0 * e);
        let gamma = (-num / (beta0 * den)).atan();
        // Fits (Eqs. 27, 28, 33, 34 and the minimum).
        let omega = -0.682 * (-24.697 * e).exp() + 4.720 + 4.450 * e;
        let kappa = 4.674 * (-3.935 * e).exp() + 3.536 * (-56.270 * e).exp();
        let alpha = 44.554 + 79.868 * e + 116.432 * e * e - 44.652 * (2.0 * e).exp();
        let beta = -5.022 + 5.857 * e + 5.089 * (-4.0 * e).exp();
        let x_min = 2.0116 - 1.0647 * e + 0.0538 * e * e;
        let g_min = 1.0286 - 0.6095 * e + 3.5781 * e.powi(2) - 21.3651 * e.powi(3)
            + 42.6344 * e.powi(4)
            - 33.8485 * e.powi(5);
        // Kolafa's equation of state for the contact value.
        let z =
            (1.0 + e + e * e - 2.0 / 3.0 * e.powi(3) - 2.0 / 3.0 * e.powi(4)) / (1.0 - e).powi(3);
        let contact = (z - 1.0) / (4.0 * e);
        // Continuity at contact and at x*, minimum of the structural part at x*.
        let sm = x_min - 1.0;
        let b = x_min * (g_min - contact / x_min * (mu * sm).exp())
            / ((beta * sm + gamma).cos() * (alpha * sm).exp() - gamma.cos() * (mu * sm).exp());
        let a = contact - b * gamma.cos();
        let delta = -omega * x_min - ((kappa * x_min + 1.0) / (omega * x_min)).atan();
        let c = x_min * (g_min - 1.0) * (kappa * x_min).exp() / (omega * x_min + delta).cos();
        let t = Self {
            eta,
            contact,
            x_min,
            g_min,
            mu,
            alpha,
            beta,
            gamma,
            omega,
            kappa,
            delta,
            a,
            b,
            c,
        };
        if [a, b, c, delta, mu, gamma].iter().any(|v| !v.is_finite()) {
            return Err(ParamError::new(
                "pair.eta",
                format!("Trokhymchuk's g(r) has no finite parameters at eta = {eta}"),
            ));
        }
        Ok(t)
    }

    /// `g(x)` at `x = r / d` (0 inside the core).
    pub fn g(&self, x: f64) -> f64 {
        if x < 1.0 {
            0.0
        } else if x <= self.x_min {
            self.depletion(x)
        } else {
            self.structural(x)
        }
    }

    fn depletion(&self, x: f64) -> f64 {
        let s = x - 1.0;
        (self.a * (self.mu * s).exp()
            + self.b * (self.beta * s + self.gamma).cos() * (self.alpha * s).exp())
            / x
    }

    fn structural(&self, x: f64) -> f64 {
        1.0 + self.c / x * (self.omega * x + self.delta).cos() * (-self.kappa * x).exp()
    }

    /// A bound on `|h(x)|` for `x >= x*`: `|C| exp(-kappa x) / x`.
    pub fn tail_bound(&self, x: f64) -> f64 {
        self.c.abs() * (-self.kappa * x).exp() / x
    }
}

/// Exact low-density `h(x)` to first order in `eta` (`x > 1`): `8 eta (1 - 3x/4 + x^3/16)` for
/// `x < 2`, else 0.
pub fn virial_total_correlation(x: f64, eta: f64) -> f64 {
    if x < 1.0 {
        -1.0
    } else if x < 2.0 {
        8.0 * eta * (1.0 - 0.75 * x + x * x * x / 16.0)
    } else {
        0.0
    }
}

/// The total correlation `h = g - 1` of a bulk hard-sphere fluid at packing fraction `eta` in
/// `[0, ETA_CLIP]`, at `x = r / d` (module docs); `-1` inside the core.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TotalCorrelation {
    eta: f64,
    fit: Option<Trokhymchuk>,
    blend: Option<(f64, Trokhymchuk)>,
}

impl TotalCorrelation {
    /// `h(x; eta)` for `0 <= eta <= ETA_CLIP`.
    pub fn new(eta: f64) -> Result<Self, ParamError> {
        if !(eta.is_finite() && (0.0..=ETA_CLIP).contains(&eta)) {
            return Err(ParamError::new(
                "pair.eta",
                format!("packing fraction must be in [0, {ETA_CLIP}], got {eta}"),
            ));
        }
        if eta >= ETA_FIT_MIN {
            Ok(Self {
                eta,
                fit: Some(Trokhymchuk::new(eta)?),
                blend: None,
            })
        } else {
            let w = (eta / ETA_FIT_MIN).powi(2);
            Ok(Self {
                eta,
                fit: None,
                blend: Some((w, Trokhymchuk::new(ETA_FIT_MIN)?)),
            })
        }
    }

    /// Packing fraction.
    pub fn eta(&self) -> f64 {
        self.eta
    }

    /// `h(x)`.
    pub fn h(&self, x: f64) -> f64 {
        if x < 1.0 {
            return -1.0;
        }
        match (&self.fit, &self.blend) {
            (Some(t), _) => t.g(x) - 1.0,
            (None, Some((w, t))) => {
                let vir = virial_total_correlation(x, self.eta);
                vir + w * (t.g(x) - 1.0 - virial_total_correlation(x, ETA_FIT_MIN))
            }
            (None, None) => unreachable!("constructed with one of the two"),
        }
    }

    /// A distance beyond which `|h| < tol` (in units of `d`).
    pub fn range(&self, tol: f64) -> f64 {
        let t = match (&self.fit, &self.blend) {
            (Some(t), _) => t,
            (None, Some((_, t))) => t,
            (None, None) => unreachable!("constructed with one of the two"),
        };
        let w = self.blend.map_or(1.0, |(w, _)| w);
        let mut x = t.x_min.max(2.0);
        while w * t.tail_bound(x) >= tol {
            x += 0.05;
        }
        x
    }
}

/// `int_1^range x h(x; eta) dx` (midpoint rule on 100,000 points): the part of the bulk
/// sedimentation coefficient beyond contact, [`bulk_sedimentation`] `= 1 - 5 eta + 12 eta` times it.
pub fn first_moment(eta: f64, range: f64) -> Result<f64, ParamError> {
    let h = TotalCorrelation::new(eta)?;
    let n = 100_000;
    let dx = (range - 1.0) / n as f64;
    Ok((0..n)
        .map(|k| {
            let x = 1.0 + (k as f64 + 0.5) * dx;
            x * h.h(x) * dx
        })
        .sum())
}

/// Bulk sedimentation coefficient of the pairwise far-field RPY flux with this pair correlation
/// kept to `range` diameters: `K = 1 - 5 eta + 12 eta int_1^range x h(x) dx` (the angular mean of
/// the RPY pair tensor along the force is `1 / (6 pi eta_s r)`; `1 - 5 eta` is the excluded core).
pub fn bulk_sedimentation(eta: f64, range: f64) -> Result<f64, ParamError> {
    Ok(1.0 - 5.0 * eta + 12.0 * eta * first_moment(eta, range)?)
}

/// `h(x; eta)` (see [`TotalCorrelation`]).
pub fn total_correlation(x: f64, eta: f64) -> Result<f64, ParamError> {
    Ok(TotalCorrelation::new(eta)?.h(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Kolafa's compressibility factor.
    fn kolafa(e: f64) -> f64 {
        (1.0 + e + e * e - 2.0 / 3.0 * e.powi(3) - 2.0 / 3.0 * e.powi(4)) / (1.0 - e).powi(3)
    }

    #[test]
    fn contact_value_continuity_and_minimum_at_the_join() {
        for eta in [0.12, 0.2, 0.3, 0.4, 0.45, 0.5, 0.6] {
            let t = Trokhymchuk::new(eta).unwrap();
            assert!((t.g(1.0) - (kolafa(eta) - 1.0) / (4.0 * eta)).abs() < 1e-12);
            let (lo, hi) = (t.g(t.x_min - 1e-9), t.g(t.x_min + 1e-9));
            assert!(
                (lo - t.g_min).abs() < 1e-7 && (hi - t.g_min).abs() < 1e-7,
                "{eta}"
            );
            // The structural part has its minimum at x*.
            let h = 1e-5;
            let slope = (t.structural(t.x_min + h) - t.structural(t.x_min - h)) / (2.0 * h);
            assert!(slope.abs() < 1e-7, "{eta}: slope {slope}");
            assert!((t.g(40.0) - 1.0).abs() < 1e-6, "{eta}");
        }
    }

    /// Compressibility route: `S(0) = 1 + 24 eta int_0^inf x^2 h dx` against Carnahan–Starling's
    /// `(1 - eta)^4 / (1 + 4 eta + 4 eta^2 - 4 eta^3 + eta^4)` (measured within 1.3 % up to the
    /// top of the fits; above them, at 0.5, it is off by a factor 2).
    #[test]
    fn compressibility_sum_rule_agrees_with_carnahan_starling_in_the_fitted_range() {
        let s0 = |eta: f64| {
            let t = TotalCorrelation::new(eta).unwrap();
            let (n, xm) = (100_000, 30.0);
            let dx = (xm - 1.0) / n as f64;
            let tail: f64 = (0..n)
                .map(|k| {
                    let x = 1.0 + (k as f64 + 0.5) * dx;
                    x * x * t.h(x) * dx
                })
                .sum();
            1.0 + 24.0 * eta * (tail - 1.0 / 3.0)
        };
        let cs = |e: f64| {
            (1.0 - e).powi(4) / (1.0 + 4.0 * e + 4.0 * e * e - 4.0 * e.powi(3) + e.powi(4))
        };
        for eta in [0.02, 0.05, ETA_FIT_MIN, 0.2, 0.3, 0.4, 0.45] {
            let (s, c) = (s0(eta), cs(eta));
            assert!((s / c - 1.0).abs() < 0.02, "eta {eta}: S(0) {s} vs CS {c}");
        }
    }

    #[test]
    fn total_correlation_is_continuous_in_eta_and_exact_at_low_density() {
        let lo = TotalCorrelation::new(ETA_FIT_MIN * (1.0 - 1e-9)).unwrap();
        let hi = TotalCorrelation::new(ETA_FIT_MIN).unwrap();
        for x in [1.0, 1.2, 1.6, 2.3, 3.0] {
            assert!((lo.h(x) - hi.h(x)).abs() < 1e-7, "x = {x}");
        }
        let e = 1e-4;
        let t = TotalCorrelation::new(e).unwrap();
        for x in [1.0, 1.5, 1.9, 2.5] {
            let exact = virial_total_correlation(x, e);
            assert!(
                (t.h(x) - exact).abs() < 1e-7,
                "x = {x}: {} vs {exact}",
                t.h(x)
            );
        }
        assert_eq!(TotalCorrelation::new(0.0).unwrap().h(1.5), 0.0);
        assert_eq!(TotalCorrelation::new(0.3).unwrap().h(0.99), -1.0);
    }

    #[test]
    fn bad_packing_fractions_are_refused_with_the_key() {
        for e in [-0.1, 0.61, f64::NAN] {
            let err = TotalCorrelation::new(e).unwrap_err();
            assert!(err.to_string().contains("pair.eta"), "{err}");
        }
    }
}
