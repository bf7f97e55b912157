//! Uniform periodic grid with O(M) window integrals and shifts by a rod length `sigma` that need
//! not be a multiple of the spacing.
//!
//! Fields are represented by their piecewise-linear interpolant through the grid values, so that a
//! window integral `int_{x_i - sigma}^{x_i} h` is the exact integral of the interpolant (trapezoid
//! rule with fractional end cells) and `h(x_i +- sigma)` is the interpolated value. Both are
//! second-order accurate for smooth `h` and exact for constants, so the homogeneous fluid is
//! reproduced to rounding. Between hard walls the grid is a periodic one with an empty gap longer
//! than `sigma` (see [`super::Domain::Walls`]).

/// Periodic grid `x_i = x0 + i dx`, `i = 0..m`, with `sigma = (n + f) dx`, `0 <= f < 1`.
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    /// Number of grid points in one period.
    pub m: usize,
    /// Grid spacing.
    pub dx: f64,
    /// Position of point 0.
    pub x0: f64,
    /// Integer part of `sigma / dx`.
    pub n: usize,
    /// Fractional part of `sigma / dx`.
    pub f: f64,
    /// Number of points carrying density (`0..active`); the rest is the empty gap between walls.
    pub active: usize,
}

impl Grid {
    /// Position of point `i`.
    #[inline]
    pub fn x(&self, i: usize) -> f64 {
        self.x0 + i as f64 * self.dx
    }

    /// `dst[i] = h(x_i + k dx + theta dx)` (linear interpolation, periodic), `0 <= theta < 1`.
    fn shift(&self, h: &[f64], k: isize, theta: f64, dst: &mut [f64]) {
        let m = self.m as isize;
        let mut j = k.rem_euclid(m) as usize;
        let mut j1 = if j + 1 == self.m { 0 } else { j + 1 };
        let (a, b) = (1.0 - theta, theta);
        for d in dst.iter_mut().take(self.m) {
            *d = a * h[j] + b * h[j1];
            j = j1;
            j1 = if j1 + 1 == self.m { 0 } else { j1 + 1 };
        }
    }

    /// `dst[i] = h(x_i + sigma)`.
    pub fn shift_forward(&self, h: &[f64], dst: &mut [f64]) {
        self.shift(h, self.n as isize, self.f, dst);
    }

    /// `dst[i] = h(x_i - sigma)`.
    pub fn shift_backward(&self, h: &[f64], dst: &mut [f64]) {
        let (k, theta) = self.back_offset();
        self.shift(h, k, theta, dst);
    }

    /// `x_i - sigma = x_{i+k} + theta dx` with `0 <= theta < 1`.
    fn back_offset(&self) -> (isize, f64) {
        if self.f > 0.0 {
            (-(self.n as isize) - 1, 1.0 - self.f)
        } else {
            (-(self.n as isize), 0.0)
        }
    }

    /// Prefix integrals of the interpolant: `cum[j] = int_{x_0}^{x_j} h`, `j = 0..=m`
    /// (`cum[m]` is the integral over one period). Returns that total.
    pub fn prefix(&self, h: &[f64], cum: &mut [f64]) -> f64 {
        let half = 0.5 * self.dx;
        let mut s = 0.0;
        cum[0] = 0.0;
        for j in 0..self.m - 1 {
            s += half * (h[j] + h[j + 1]);
            cum[j + 1] = s;
        }
        s += half * (h[self.m - 1] + h[0]);
        cum[self.m] = s;
        s
    }

    /// `dst[i] = C(x_i + k dx + theta dx) - sign...`: the helper behind both windows.
    /// Writes `C(x_i + k dx + theta dx)` where `C` is the periodic continuation of the prefix
    /// integral (`C(t + period) = C(t) + total`).
    fn cum_at(&self, h: &[f64], cum: &[f64], k: isize, theta: f64, dst: &mut [f64]) {
        let m = self.m as isize;
        let total = cum[self.m];
        let mut q = k.div_euclid(m) as f64 * total;
        let mut j = k.rem_euclid(m) as usize;
        let c1 = self.dx * theta;
        let c2 = 0.5 * self.dx * theta * theta;
        for d in dst.iter_mut().take(self.m) {
            let j1 = if j + 1 == self.m { 0 } else { j + 1 };
            *d = q + cum[j] + c1 * h[j] + c2 * (h[j1] - h[j]);
            j = j1;
            if j == 0 {
                q += total;
            }
        }
    }

    /// `dst[i] = int_{x_i - sigma}^{x_i} h` given `cum` from [`Grid::prefix`].
    pub fn window_backward(&self, h: &[f64], cum: &[f64], dst: &mut [f64]) {
        let (k, theta) = self.back_offset();
        self.cum_at(h, cum, k, theta, dst);
        for (d, c) in dst.iter_mut().zip(cum.iter()).take(self.m) {
            *d = c - *d;
        }
    }

    /// `dst[i] = int_{x_i}^{x_i + sigma} h` given `cum` from [`Grid::prefix`].
    pub fn window_forward(&self, h: &[f64], cum: &[f64], dst: &mut [f64]) {
        self.cum_at(h, cum, self.n as isize, self.f, dst);
        for (d, c) in dst.iter_mut().zip(cum.iter()).take(self.m) {
            *d -= c;
        }
    }

    /// Average of the interpolant of `h` over `[lo, hi]` (any real positions, periodic).
    pub fn average(&self, h: &[f64], cum: &[f64], lo: f64, hi: f64) -> f64 {
        (self.cum_point(h, cum, hi) - self.cum_point(h, cum, lo)) / (hi - lo)
    }

    /// `C(t)` at one position.
    fn cum_point(&self, h: &[f64], cum: &[f64], t: f64) -> f64 {
        let s = (t - self.x0) / self.dx;
        let mut k = s.floor();
        let mut theta = s - k;
        if theta >= 1.0 {
            k += 1.0;
            theta = 0.0;
        }
        let k = k as isize;
        let m = self.m as isize;
        let total = cum[self.m];
        let q = k.div_euclid(m) as f64 * total;
        let j = k.rem_euclid(m) as usize;
        let j1 = if j + 1 == self.m { 0 } else { j + 1 };
        q + cum[j] + self.dx * (theta * h[j] + 0.5 * theta * theta * (h[j1] - h[j]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(m: usize, dx: f64, sigma: f64) -> Grid {
        let r = sigma / dx;
        let n = (r + 1e-9).floor();
        let f = (r - n).max(0.0);
        Grid {
            m,
            dx,
            x0: 0.0,
            n: n as usize,
            f: if f < 1e-9 { 0.0 } else { f },
            active: m,
        }
    }

    #[test]
    fn windows_and_shifts_are_exact_for_linear_pieces_and_accurate_for_smooth_fields() {
        // h = 2 + sin(2 pi x) on a period 1; sigma fractional and larger than the period.
        for &sigma in &[0.3, 0.3137, 1.2571] {
            let m = 400;
            let g = grid(m, 1.0 / m as f64, sigma);
            let tau = std::f64::consts::TAU;
            let h: Vec<f64> = (0..m).map(|i| 2.0 + (tau * g.x(i)).sin()).collect();
            let prim = |x: f64| 2.0 * x - (tau * x).cos() / tau;
            let mut cum = vec![0.0; m + 1];
            let total = g.prefix(&h, &mut cum);
            assert!((total - 2.0).abs() < 1e-12);
            let mut w = vec![0.0; m];
            g.window_backward(&h, &cum, &mut w);
            let mut wf = vec![0.0; m];
            g.window_forward(&h, &cum, &mut wf);
            let mut sf = vec![0.0; m];
            g.shift_forward(&h, &mut sf);
            let mut sb = vec![0.0; m];
            g.shift_backward(&h, &mut sb);
            // Trapezoid / linear interpolation error bound: dx^2 / 8 * max|h''| = dx^2 tau^2 / 8.
            let tol = (g.dx * g.dx) * tau * tau / 8.0 * 1.01;
            for i in 0..m {
                let x = g.x(i);
                assert!((w[i] - (prim(x) - prim(x - sigma))).abs() < tol * sigma.max(1.0));
                assert!((wf[i] - (prim(x + sigma) - prim(x))).abs() < tol * sigma.max(1.0));
                assert!((sf[i] - (2.0 + (tau * (x + sigma)).sin())).abs() < tol);
                assert!((sb[i] - (2.0 + (tau * (x - sigma)).sin())).abs() < tol);
            }
            let avg = g.average(&h, &cum, 0.1, 0.35);
            let exact = (prim(0.35) - prim(0.1)) / 0.25;
            assert!((avg - exact).abs() < tol);
        }
    }
}
