//! Anderson mixing (type II, Walker & Ni 2011) for fixed-point problems `x = G(x)`.

/// History of iterate and residual differences, preallocated for vectors of length `n`.
#[derive(Debug, Clone)]
pub(crate) struct Anderson {
    depth: usize,
    beta: f64,
    len: usize,
    dx: Vec<Vec<f64>>,
    df: Vec<Vec<f64>>,
    count: usize,
    head: usize,
    x_prev: Vec<f64>,
    f_prev: Vec<f64>,
    f: Vec<f64>,
    has_prev: bool,
    gram: Vec<f64>,
    rhs: Vec<f64>,
}

impl Anderson {
    /// Largest history kept.
    pub(crate) const MAX_DEPTH: usize = 32;

    /// Mixing of depth `depth` (0: plain damped Picard; at most [`Self::MAX_DEPTH`]) and damping
    /// `beta` in (0, 1].
    pub(crate) fn new(n: usize, depth: usize, beta: f64) -> Self {
        let depth = depth.min(Self::MAX_DEPTH);
        Self {
            depth,
            beta,
            len: n,
            dx: vec![vec![0.0; n]; depth],
            df: vec![vec![0.0; n]; depth],
            count: 0,
            head: 0,
            x_prev: vec![0.0; n],
            f_prev: vec![0.0; n],
            f: vec![0.0; n],
            has_prev: false,
            gram: vec![0.0; depth * depth],
            rhs: vec![0.0; depth],
        }
    }

    /// Forget the history; the next vectors have length `len`.
    pub(crate) fn reset(&mut self, len: usize) {
        self.count = 0;
        self.head = 0;
        self.has_prev = false;
        self.len = len.min(self.x_prev.len());
    }

    /// Replace `x` by the next iterate given `g = G(x)`; returns `max |G(x) - x|`.
    pub(crate) fn step(&mut self, x: &mut [f64], g: &[f64]) -> f64 {
        let n = self.len;
        let mut res = 0.0f64;
        for i in 0..n {
            self.f[i] = g[i] - x[i];
            res = res.max(self.f[i].abs());
        }
        if self.depth > 0 && self.has_prev {
            let h = self.head;
            for i in 0..n {
                self.dx[h][i] = x[i] - self.x_prev[i];
                self.df[h][i] = self.f[i] - self.f_prev[i];
            }
            self.head = (h + 1) % self.depth;
            self.count = (self.count + 1).min(self.depth);
        }
        if self.depth > 0 {
            self.x_prev[..n].copy_from_slice(&x[..n]);
            self.f_prev[..n].copy_from_slice(&self.f[..n]);
            self.has_prev = true;
        }
        let m = self.count;
        let mut gamma = [0.0f64; Self::MAX_DEPTH];
        if m > 0 && self.solve_gamma(m, &mut gamma) {
            for i in 0..n {
                let mut v = x[i] + self.beta * self.f[i];
                for (k, gk) in gamma.iter().take(m).enumerate() {
                    v -= gk * (self.dx[k][i] + self.beta * self.df[k][i]);
                }
                x[i] = v;
            }
        } else {
            for i in 0..n {
                x[i] += self.beta * self.f[i];
            }
        }
        res
    }

    /// Least squares `min |f - DF gamma|` by regularised normal equations; false if singular.
    fn solve_gamma(&mut self, m: usize, gamma: &mut [f64; Self::MAX_DEPTH]) -> bool {
        let n = self.len;
        for a in 0..m {
            for b in a..m {
                let s: f64 = self.df[a][..n]
                    .iter()
                    .zip(&self.df[b][..n])
                    .map(|(p, q)| p * q)
                    .sum();
                self.gram[a * m + b] = s;
                self.gram[b * m + a] = s;
            }
            self.rhs[a] = self.df[a][..n]
                .iter()
                .zip(&self.f[..n])
                .map(|(p, q)| p * q)
                .sum();
        }
        let trace: f64 = (0..m).map(|a| self.gram[a * m + a]).sum();
        if trace.is_nan() || trace <= 0.0 || !trace.is_finite() {
            return false;
        }
        for a in 0..m {
            self.gram[a * m + a] += 1e-12 * trace;
        }
        // Gaussian elimination with partial pivoting on the m x m system.
        let g = &mut self.gram;
        let r = &mut self.rhs;
        for c in 0..m {
            let p = (c..m)
                .max_by(|&i, &j| g[i * m + c].abs().total_cmp(&g[j * m + c].abs()))
                .unwrap_or(c);
            if g[p * m + c].abs() < 1e-300 {
                return false;
            }
            if p != c {
                for k in 0..m {
                    g.swap(p * m + k, c * m + k);
                }
                r.swap(p, c);
            }
            for i in c + 1..m {
                let fct = g[i * m + c] / g[c * m + c];
                for k in c..m {
                    g[i * m + k] -= fct * g[c * m + k];
                }
                r[i] -= fct * r[c];
            }
        }
        for c in (0..m).rev() {
            let mut s = r[c];
            for k in c + 1..m {
                s -= g[c * m + k] * gamma[k];
            }
            gamma[c] = s / g[c * m + c];
        }
        gamma[..m].iter().all(|v| v.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_linear_fixed_point_faster_than_picard() {
        // x = G(x) = A x + b with a stiff contraction-violating A (eigenvalues up to -5).
        let n = 20;
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let lam: Vec<f64> = (0..n).map(|i| -5.0 + 5.5 * i as f64 / n as f64).collect();
        let mut x = vec![0.0; n];
        let mut g = vec![0.0; n];
        let mut acc = Anderson::new(n, 10, 0.5);
        let mut it = 0;
        loop {
            for i in 0..n {
                g[i] = lam[i] * x[i] + b[i];
            }
            let r = acc.step(&mut x, &g);
            it += 1;
            if r < 1e-10 || it > 200 {
                break;
            }
        }
        assert!(it < 100, "{it}");
        for i in 0..n {
            assert!((x[i] - b[i] / (1.0 - lam[i])).abs() < 1e-8);
        }
    }
}
