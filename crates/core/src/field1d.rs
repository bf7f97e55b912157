//! One-dimensional external potentials U(x), shared by Brownian cluster dynamics and the exact
//! 1D theory. Energies in units of the scenario's energy unit (kT = 1 by default), lengths in
//! the scenario's length unit. The force on a particle is `-dU/dx + drive`.

use crate::param::{self, ParamError};
use std::f64::consts::TAU;

/// One term of an external potential.
#[derive(Debug, Clone, PartialEq)]
pub enum FieldTerm {
    /// `U = (amplitude / 2) cos(2 pi x / wavelength)` (hard-rods paper, Sec. III C).
    Cosine {
        /// Peak-to-peak height U0.
        amplitude: f64,
        /// Period lambda.
        wavelength: f64,
    },
    /// `U = stiffness / 2 (x - centre)^2`, with the minimum-image displacement on a ring.
    Harmonic {
        /// Spring constant k.
        stiffness: f64,
        /// Trap centre.
        centre: f64,
        /// Ring length for the minimum image (None between walls).
        ring: Option<f64>,
    },
    /// `U = sum_n [cos_n cos(2 pi n x / wavelength) + sin_n sin(2 pi n x / wavelength)]`, n = 1, 2, ...
    Fourier {
        /// Period of the fundamental.
        wavelength: f64,
        /// Cosine coefficients, n = 1.. .
        cos: Vec<f64>,
        /// Sine coefficients, n = 1.. .
        sin: Vec<f64>,
    },
    /// A periodic table interpolated by a periodic cubic spline (continuous force).
    Tabulated(PeriodicSpline),
}

impl FieldTerm {
    /// U(x).
    pub fn potential(&self, x: f64) -> f64 {
        match self {
            Self::Cosine {
                amplitude,
                wavelength,
            } => 0.5 * amplitude * (TAU * x / wavelength).cos(),
            Self::Harmonic {
                stiffness,
                centre,
                ring,
            } => {
                let d = displacement(x - centre, *ring);
                0.5 * stiffness * d * d
            }
            Self::Fourier {
                wavelength,
                cos,
                sin,
            } => {
                let k = TAU / wavelength;
                let mut u = 0.0;
                for (n, (a, b)) in cos.iter().zip(sin).enumerate() {
                    let q = k * (n + 1) as f64 * x;
                    u += a * q.cos() + b * q.sin();
                }
                u
            }
            Self::Tabulated(s) => s.value(x),
        }
    }

    /// -dU/dx.
    pub fn force(&self, x: f64) -> f64 {
        match self {
            Self::Cosine {
                amplitude,
                wavelength,
            } => {
                let k = TAU / wavelength;
                0.5 * amplitude * k * (k * x).sin()
            }
            Self::Harmonic {
                stiffness,
                centre,
                ring,
            } => -stiffness * displacement(x - centre, *ring),
            Self::Fourier {
                wavelength,
                cos,
                sin,
            } => {
                let k = TAU / wavelength;
                let mut f = 0.0;
                for (n, (a, b)) in cos.iter().zip(sin).enumerate() {
                    let kn = k * (n + 1) as f64;
                    let q = kn * x;
                    f += kn * (a * q.sin() - b * q.cos());
                }
                f
            }
            Self::Tabulated(s) => -s.derivative(x),
        }
    }

    /// Period of the term, if periodic.
    pub fn period(&self) -> Option<f64> {
        match self {
            Self::Cosine { wavelength, .. } | Self::Fourier { wavelength, .. } => Some(*wavelength),
            Self::Harmonic { .. } => None,
            Self::Tabulated(s) => Some(s.period()),
        }
    }
}

fn displacement(d: f64, ring: Option<f64>) -> f64 {
    match ring {
        Some(l) => d - l * (d / l).round(),
        None => d,
    }
}

/// An external field: a sum of potential terms plus a constant drive force.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExternalField {
    /// Potential terms.
    pub terms: Vec<FieldTerm>,
    /// Constant force (tilted washboard), in energy / length.
    pub drive: f64,
}

impl ExternalField {
    /// U(x) without the drive (the drive has no periodic potential).
    pub fn potential(&self, x: f64) -> f64 {
        self.terms.iter().map(|t| t.potential(x)).sum()
    }

    /// Total external force `-dU/dx + drive`.
    pub fn force(&self, x: f64) -> f64 {
        self.drive + self.terms.iter().map(|t| t.force(x)).sum::<f64>()
    }

    /// True when the field exerts no force anywhere.
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty() && self.drive == 0.0
    }

    /// Common period of all terms (the largest, if the others divide it), or None.
    /// A field without terms has no period.
    pub fn period(&self) -> Option<f64> {
        let mut p: Option<f64> = None;
        for t in &self.terms {
            let q = t.period()?;
            p = Some(match p {
                None => q,
                Some(p) => {
                    let (big, small) = if p >= q { (p, q) } else { (q, p) };
                    let r = big / small;
                    if (r - r.round()).abs() > 1e-9 * r {
                        return None;
                    }
                    big
                }
            });
        }
        p
    }
}

/// A periodic cubic spline through `(x_i, y_i)`, `i = 0..n`, with `y_n = y_0`: continuous value,
/// slope and curvature across the period.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicSpline {
    x: Vec<f64>,
    y: Vec<f64>,
    /// Second derivatives at the knots (periodic: m[n] = m[0]).
    m: Vec<f64>,
}

impl PeriodicSpline {
    /// Build from a table covering exactly one period: strictly increasing `x`, at least 4
    /// rows, and the last value equal to the first (to `1e-9` of the table's range).
    /// `key` names the scenario key in error messages.
    pub fn new(key: &str, x: Vec<f64>, y: Vec<f64>) -> Result<Self, ParamError> {
        if x.len() != y.len() || x.len() < 4 {
            return Err(ParamError::new(
                key,
                format!(
                    "a tabulated potential needs at least 4 rows of (x, U), got {} x and {} U values",
                    x.len(),
                    y.len()
                ),
            ));
        }
        for (i, v) in x.iter().chain(&y).enumerate() {
            param::finite(key, *v).map_err(|_| {
                ParamError::new(key, format!("value #{i} of the table is not finite"))
            })?;
        }
        if let Some(i) = x.windows(2).position(|w| w[1] <= w[0]) {
            return Err(ParamError::new(
                key,
                format!(
                    "x must increase strictly; row {} (x = {}) does not exceed row {} (x = {})",
                    i + 1,
                    x[i + 1],
                    i,
                    x[i]
                ),
            ));
        }
        let n = x.len() - 1;
        let span = y.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - y.iter().cloned().fold(f64::INFINITY, f64::min);
        if (y[n] - y[0]).abs() > 1e-9 * span.max(1.0) {
            return Err(ParamError::new(
                key,
                format!(
                    "the table is not periodic: U(first x = {}) = {} but U(last x = {}) = {}; the last row must repeat the first value one period later",
                    x[0], y[0], x[n], y[n]
                ),
            ));
        }
        let m = periodic_second_derivatives(&x, &y);
        Ok(Self { x, y, m })
    }

    /// The period (table span).
    pub fn period(&self) -> f64 {
        self.x[self.x.len() - 1] - self.x[0]
    }

    fn locate(&self, x: f64) -> (usize, f64, f64) {
        let p = self.period();
        let x0 = self.x[0];
        let u = x0 + (x - x0).rem_euclid(p);
        let i = (self.x.partition_point(|&xi| xi <= u).max(1) - 1).min(self.x.len() - 2);
        let h = self.x[i + 1] - self.x[i];
        (i, (u - self.x[i]) / h, h)
    }

    /// Interpolated value.
    pub fn value(&self, x: f64) -> f64 {
        let (i, t, h) = self.locate(x);
        let (a, b) = (1.0 - t, t);
        a * self.y[i]
            + b * self.y[i + 1]
            + h * h / 6.0 * ((a * a * a - a) * self.m[i] + (b * b * b - b) * self.m[i + 1])
    }

    /// Interpolated derivative dU/dx.
    pub fn derivative(&self, x: f64) -> f64 {
        let (i, t, h) = self.locate(x);
        let (a, b) = (1.0 - t, t);
        (self.y[i + 1] - self.y[i]) / h
            + h / 6.0 * (-(3.0 * a * a - 1.0) * self.m[i] + (3.0 * b * b - 1.0) * self.m[i + 1])
    }
}

/// Second derivatives of the periodic cubic spline: the cyclic tridiagonal system
/// `h_{i-1} M_{i-1} + 2 (h_{i-1} + h_i) M_i + h_i M_{i+1} = 6 (s_i - s_{i-1})`,
/// solved by the Thomas algorithm with a Sherman–Morrison correction for the corners.
fn periodic_second_derivatives(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len() - 1; // unknowns M_0..M_{n-1}, M_n = M_0
    let h: Vec<f64> = (0..n).map(|i| x[i + 1] - x[i]).collect();
    let s: Vec<f64> = (0..n).map(|i| (y[i + 1] - y[i]) / h[i]).collect();
    let hm = |i: usize| h[(i + n - 1) % n];
    let sm = |i: usize| s[(i + n - 1) % n];
    let a: Vec<f64> = (0..n).map(hm).collect(); // sub-diagonal (a[0] is the corner)
    let c: Vec<f64> = (0..n).map(|i| h[i]).collect(); // super-diagonal (c[n-1] is the corner)
    let b: Vec<f64> = (0..n).map(|i| 2.0 * (hm(i) + h[i])).collect();
    let d: Vec<f64> = (0..n).map(|i| 6.0 * (s[i] - sm(i))).collect();
    // Sherman–Morrison: A = T + u v^T with u = (gamma, 0.., c_{n-1}), v = (1, 0.., a_0 / gamma).
    let gamma = -b[0];
    let mut bb = b.clone();
    bb[0] -= gamma;
    bb[n - 1] -= c[n - 1] * a[0] / gamma;
    let solve = |rhs: &[f64]| -> Vec<f64> {
        let mut cp = vec![0.0; n];
        let mut dp = vec![0.0; n];
        cp[0] = c[0] / bb[0];
        dp[0] = rhs[0] / bb[0];
        for i in 1..n {
            let den = bb[i] - a[i] * cp[i - 1];
            cp[i] = c[i] / den;
            dp[i] = (rhs[i] - a[i] * dp[i - 1]) / den;
        }
        let mut z = vec![0.0; n];
        z[n - 1] = dp[n - 1];
        for i in (0..n - 1).rev() {
            z[i] = dp[i] - cp[i] * z[i + 1];
        }
        z
    };
    let yv = solve(&d);
    let mut u = vec![0.0; n];
    u[0] = gamma;
    u[n - 1] = c[n - 1];
    let q = solve(&u);
    let vy = yv[0] + a[0] / gamma * yv[n - 1];
    let vq = q[0] + a[0] / gamma * q[n - 1];
    let mut m: Vec<f64> = (0..n).map(|i| yv[i] - vy / (1.0 + vq) * q[i]).collect();
    m.push(m[0]);
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cosine_force_is_minus_gradient() {
        let f = ExternalField {
            terms: vec![
                FieldTerm::Cosine {
                    amplitude: 6.0,
                    wavelength: 1.0,
                },
                FieldTerm::Fourier {
                    wavelength: 2.0,
                    cos: vec![0.3, 0.1],
                    sin: vec![0.2, -0.4],
                },
            ],
            drive: 0.5,
        };
        for i in 0..50 {
            let x = -1.3 + 0.17 * i as f64;
            let h = 1e-5;
            let fd = -(f.potential(x + h) - f.potential(x - h)) / (2.0 * h) + 0.5;
            assert!((f.force(x) - fd).abs() < 1e-6, "x={x}");
        }
        assert_eq!(f.period(), Some(2.0));
    }

    #[test]
    fn periodic_spline_reproduces_a_smooth_periodic_function() {
        let n = 200;
        let x: Vec<f64> = (0..=n).map(|i| 0.5 + 2.0 * i as f64 / n as f64).collect();
        let u = |x: f64| (TAU * x / 2.0).cos() + 0.3 * (2.0 * TAU * x / 2.0).sin();
        let mut y: Vec<f64> = x.iter().map(|&x| u(x)).collect();
        y[n] = y[0];
        let s = PeriodicSpline::new("potential.table", x, y).unwrap();
        for i in 0..97 {
            let x = -3.0 + 0.0731 * i as f64;
            assert!((s.value(x) - u(x)).abs() < 1e-6);
            let h = 1e-6;
            let du = (u(x + h) - u(x - h)) / (2.0 * h);
            assert!((s.derivative(x) - du).abs() < 1e-4);
        }
        // slope is continuous across the period
        let p = s.period();
        assert!((s.derivative(0.5 - 1e-12) - s.derivative(0.5 + p - 1e-12)).abs() < 1e-9);
    }

    #[test]
    fn non_periodic_table_is_refused() {
        let e = PeriodicSpline::new(
            "potential.table",
            vec![0., 1., 2., 3.],
            vec![0., 1., 2., 3.],
        )
        .unwrap_err();
        assert!(e.message.contains("not periodic"), "{e}");
        assert!(PeriodicSpline::new("k", vec![0., 1., 1., 3.], vec![0., 1., 2., 0.]).is_err());
    }
}
