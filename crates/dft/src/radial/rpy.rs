//! Pairwise Rotne–Prager–Yamakawa flux in spherical symmetry, dilute pair correlation
//! (METHODS.md section 3, flyft `rpy_diffusive_flux`; paper Eqs. 16, 24–27).
//!
//! With `g(r) = Theta(r - d)`, the radial hydrodynamic flux is
//! `J_HI(x) = -rho(x) int dy M(x, y) rho(y) d_y(beta mu(y))` over `|x - d| < y < x + d`, where
//! (monodisperse, `a_i = a_j = a`, `kT / eta = 3 pi d D0`)
//! `M(x, y) = 5 a^2 kT / (24 x^2 eta d^3) (d-x-y)(d+x-y)(d-x+y)(d+x+y)
//!          = (5 pi D0 / (32 x^2)) [d^2 - (x-y)^2] [d^2 - (x+y)^2]`.
//! It is the far-field RPY pair tensor projected on the two radial directions, integrated over the
//! orientations allowed by `g` (the integral over a full shell vanishes, so only shells that can
//! overlap contribute, with the sign of the excluded part). Bulk sedimentation: `K = 1 - 5 phi`.

use std::f64::consts::PI;

use super::RadialGrid;

/// `M(x, y) / D0` of the module docs.
#[inline]
pub fn kernel(x: f64, y: f64, diameter: f64) -> f64 {
    let d2 = diameter * diameter;
    if (x - y).abs() >= diameter || x + y <= diameter {
        return 0.0;
    }
    5.0 * PI / (32.0 * x * x) * (d2 - (x - y).powi(2)) * (d2 - (x + y).powi(2))
}

/// Kernel integrated over the cells for every interior face: `u_f = -D0 sum_j K[f, j] g_j`
/// (`K` the cell integral of [`kernel`]) is the hydrodynamic drift velocity at face `f`,
/// `J_HI = rho u`, for `g_j = rho_j d_y(beta mu)` at the cell centres.
#[derive(Debug, Clone)]
pub struct RpyKernel {
    bw: usize,
    start: Vec<usize>,
    weights: Vec<f64>,
}

impl RpyKernel {
    /// Precompute for `grid` and particle `diameter` (exact 3-point Gauss–Legendre on each cell
    /// piece: the kernel is a quartic in `y`).
    pub fn new(grid: &RadialGrid, diameter: f64) -> Self {
        let dr = grid.dr();
        let faces = grid.faces();
        let nf = faces.len();
        let n = grid.len();
        let bw = (2.0 * diameter / dr).ceil() as usize + 3;
        let mut start = vec![0; nf];
        let mut weights = vec![0.0; nf * bw];
        let gl = [
            (-(0.6f64).sqrt(), 5.0 / 9.0),
            (0.0, 8.0 / 9.0),
            ((0.6f64).sqrt(), 5.0 / 9.0),
        ];
        for f in 1..nf.saturating_sub(1) {
            let x = faces[f];
            let lo_y = (x - diameter).abs();
            let hi_y = x + diameter;
            let s = (lo_y / dr).floor() as usize;
            start[f] = s;
            for k in 0..bw {
                let j = s + k;
                if j >= n {
                    break;
                }
                let lo = faces[j].max(lo_y);
                let hi = faces[j + 1].min(hi_y);
                if hi <= lo {
                    continue;
                }
                let (c, h) = (0.5 * (lo + hi), 0.5 * (hi - lo));
                weights[f * bw + k] = gl
                    .iter()
                    .map(|(t, w)| w * h * kernel(x, c + h * t, diameter))
                    .sum();
            }
        }
        Self { bw, start, weights }
    }

    /// Drift velocities `u_f / D0` at the interior faces `1..active` from `g` (cells `0..active`).
    pub fn velocities(&self, g: &[f64], active: usize, out: &mut [f64]) {
        out[0] = 0.0;
        for f in 1..active {
            let s = self.start[f];
            let e = (s + self.bw).min(active);
            let mut acc = 0.0;
            if e > s {
                let w = &self.weights[f * self.bw..f * self.bw + (e - s)];
                for (wk, gk) in w.iter().zip(&g[s..e]) {
                    acc += wk * gk;
                }
            }
            out[f] = -acc;
        }
        out[active] = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `M / D0` by direct quadrature of the far-field RPY pair tensor over allowed orientations.
    fn direct(x: f64, y: f64, d: f64) -> f64 {
        // Units kT = eta = 1: D0 = 1 / (3 pi d).
        let d0 = 1.0 / (3.0 * PI * d);
        let a = 0.5 * d;
        let c_max = ((x * x + y * y - d * d) / (2.0 * x * y)).min(1.0);
        if c_max <= -1.0 {
            return 0.0;
        }
        let m = 200_000;
        let h = (c_max + 1.0) / m as f64;
        let mut s = 0.0;
        for k in 0..m {
            let c = -1.0 + (k as f64 + 0.5) * h;
            let r2 = x * x + y * y - 2.0 * x * y * c;
            let r = r2.sqrt();
            let proj = (x - y * c) * (x * c - y) / r2;
            let om = 1.0 / (8.0 * PI * r)
                * ((1.0 + 2.0 * a * a / (3.0 * r2)) * c + (1.0 - 2.0 * a * a / r2) * proj);
            s += om * h;
        }
        2.0 * PI * y * y * s / d0
    }

    #[test]
    fn closed_form_matches_angular_quadrature() {
        let d = 1.0;
        for (x, y) in [
            (3.0, 3.4),
            (3.0, 2.2),
            (0.7, 0.5),
            (0.3, 1.1),
            (5.0, 6.5),
            (0.4, 0.3),
        ] {
            let k = kernel(x, y, d);
            let q = direct(x, y, d);
            assert!(
                (k - q).abs() < 1e-6 * (1.0 + q.abs()),
                "({x},{y}): {k} vs {q}"
            );
        }
    }

    #[test]
    fn bulk_sedimentation_coefficient() {
        // Far from the centre: rho^2 int M dy = -5 phi rho D0 (K = 1 - 5 phi).
        let d = 1.0;
        let x = 400.0;
        let m = 20000;
        let h = 2.0 * d / m as f64;
        let s: f64 = (0..m)
            .map(|k| kernel(x, x - d + (k as f64 + 0.5) * h, d) * h)
            .sum();
        let rho = 1.0;
        let phi = PI * rho / 6.0;
        assert!(
            (rho * s / (-5.0 * phi) - 1.0).abs() < 1e-2,
            "{}",
            rho * s / (-5.0 * phi)
        );
    }
}
