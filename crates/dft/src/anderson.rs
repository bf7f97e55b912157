//! Anderson mixing (type II; Walker & Ni, SIAM J. Numer. Anal. 49, 1715 (2011)) for a
//! fixed-point problem `u = G(u)` with residual `r = G(u) - u`, shared by the rods and the radial
//! solvers.
//!
//! With the last `m` differences `du_j = u_{k-j+1} - u_{k-j}` and `dr_j = r_{k-j+1} - r_{k-j}`,
//! the coefficients `gamma` minimise `|r_k - sum_j gamma_j dr_j|` through the regularised normal
//! equations `(G + lambda I) gamma = b` with `G_jl = dr_j . dr_l`, `b_j = dr_j . r_k`, and
//!
//! `u_{k+1} = u_k + beta r_k - sum_j gamma_j (du_j + beta dr_j)`
//!
//! (`m = 0`: damped Picard `u_{k+1} = u_k + beta r_k`). The history is a ring buffer and `G` is
//! updated by one row per step: O(m M) work per step, no allocation per step.
//!
//! The two solvers used to carry their own copies, which differ in the order of the history in
//! the small system, in `lambda` and in the pivoting; [`Convention`] keeps each caller's
//! arithmetic bit for bit as it was before the merge (commit 705c480).

/// Order of the history in the small system (it fixes the order of the floating-point sums).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum HistoryOrder {
    /// Oldest difference first.
    Chronological,
    /// Ring-buffer slot order (the oldest first only until the buffer wraps).
    Storage,
}

/// Tikhonov shift `lambda` of the normal equations, relative to `tr G`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Regularisation {
    /// `lambda = 1e-12 tr G`.
    Trace,
    /// `lambda = 1e-12 tr G / m`: relative to the mean diagonal.
    MeanDiagonal,
}

/// Partial pivoting of the Gaussian elimination of the small system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Pivoting {
    /// The first row of largest `|a|` (a NaN is never chosen); singular if the pivot is 0 or
    /// not finite.
    FirstLargest,
    /// The last row of largest `|a|` in IEEE total order; singular if `|pivot| < 1e-300`.
    LastLargest,
}

/// The numerical choices of a caller.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Convention {
    pub order: HistoryOrder,
    pub regularisation: Regularisation,
    pub pivoting: Pivoting,
    /// Longest history kept (a larger requested depth is cut to this).
    pub max_depth: usize,
}

impl Convention {
    /// The rods equilibrium solver's.
    pub(crate) const RODS: Self = Self {
        order: HistoryOrder::Chronological,
        regularisation: Regularisation::MeanDiagonal,
        pivoting: Pivoting::FirstLargest,
        max_depth: usize::MAX,
    };

    /// The radial solvers' (FMT equilibrium and implicit DDFT steps).
    pub(crate) const RADIAL: Self = Self {
        order: HistoryOrder::Storage,
        regularisation: Regularisation::Trace,
        pivoting: Pivoting::LastLargest,
        max_depth: 32,
    };
}

/// Anderson mixing of depth `m` for vectors of length up to `M`, preallocated.
#[derive(Debug, Clone)]
pub(crate) struct Anderson {
    conv: Convention,
    depth: usize,
    beta: f64,
    /// `du_j`, `dr_j` by ring-buffer slot.
    du: Vec<Vec<f64>>,
    dr: Vec<Vec<f64>>,
    /// `G` by slot, `depth x depth`.
    gram: Vec<f64>,
    u_prev: Vec<f64>,
    r_prev: Vec<f64>,
    have_prev: bool,
    /// Length of the vectors in the history.
    len: usize,
    /// Differences held, and the slot the next one goes to.
    count: usize,
    head: usize,
    /// The small system in the order of [`Convention::order`]: `a gamma = b`, slots `idx`.
    a: Vec<f64>,
    b: Vec<f64>,
    idx: Vec<usize>,
    /// Residual of [`Anderson::step_map`] (allocated on its first use).
    r: Vec<f64>,
}

impl Anderson {
    /// Vectors of length up to `m_len`, history depth `depth` (0: damped Picard; cut to
    /// `conv.max_depth`), mixing `beta` in (0, 1].
    pub(crate) fn new(m_len: usize, depth: usize, beta: f64, conv: Convention) -> Self {
        let depth = depth.min(conv.max_depth);
        Self {
            conv,
            depth,
            beta,
            du: vec![vec![0.0; m_len]; depth],
            dr: vec![vec![0.0; m_len]; depth],
            gram: vec![0.0; depth * depth],
            u_prev: vec![0.0; m_len],
            r_prev: vec![0.0; m_len],
            have_prev: false,
            len: m_len,
            count: 0,
            head: 0,
            a: vec![0.0; depth * depth],
            b: vec![0.0; depth],
            idx: vec![0; depth],
            r: Vec::new(),
        }
    }

    /// Changes the mixing `beta` (the history is kept).
    pub(crate) fn set_beta(&mut self, beta: f64) {
        self.beta = beta;
    }

    /// Forgets the history (after a rejected step, or before a new problem).
    pub(crate) fn reset(&mut self) {
        self.have_prev = false;
        self.count = 0;
        self.head = 0;
    }

    /// Replaces `u` (the current iterate, residual `r = G(u) - u`) by the next iterate. A change
    /// of the vectors' length forgets the history.
    pub(crate) fn step(&mut self, u: &mut [f64], r: &[f64]) {
        let n = u.len();
        assert!(r.len() == n && n <= self.u_prev.len(), "vector lengths");
        if n != self.len {
            self.reset();
            self.len = n;
        }
        let depth = self.depth;
        if depth > 0 && self.have_prev {
            let slot = self.head;
            let (du, dr) = (&mut self.du[slot], &mut self.dr[slot]);
            for i in 0..n {
                du[i] = u[i] - self.u_prev[i];
                dr[i] = r[i] - self.r_prev[i];
            }
            self.head = (slot + 1) % depth;
            self.count = (self.count + 1).min(depth);
            // Row and column `slot` of G against the slots in use (the others are stale).
            for k in 0..self.count {
                let v = dot(&self.dr[slot][..n], &self.dr[k][..n]);
                self.gram[slot * depth + k] = v;
                self.gram[k * depth + slot] = v;
            }
        }
        if depth > 0 {
            self.u_prev[..n].copy_from_slice(u);
            self.r_prev[..n].copy_from_slice(r);
            self.have_prev = true;
        }

        let m = self.count;
        for j in 0..m {
            self.idx[j] = match self.conv.order {
                HistoryOrder::Chronological => (self.head + depth - m + j) % depth,
                HistoryOrder::Storage => j,
            };
        }
        let mut have_gamma = false;
        if m > 0 {
            let mut trace = 0.0;
            for j in 0..m {
                let sj = self.idx[j];
                self.b[j] = dot(&self.dr[sj][..n], r);
                for k in 0..m {
                    self.a[j * m + k] = self.gram[sj * depth + self.idx[k]];
                }
                trace += self.a[j * m + j];
            }
            if trace > 0.0 && trace.is_finite() {
                let lambda = match self.conv.regularisation {
                    Regularisation::Trace => 1e-12 * trace,
                    Regularisation::MeanDiagonal => 1e-12 * trace / m as f64,
                };
                for j in 0..m {
                    self.a[j * m + j] += lambda;
                }
                have_gamma = solve(
                    &mut self.a[..m * m],
                    &mut self.b[..m],
                    m,
                    self.conv.pivoting,
                );
            }
        }
        let beta = self.beta;
        for i in 0..n {
            u[i] += beta * r[i];
        }
        if have_gamma {
            for j in 0..m {
                let gamma = self.b[j];
                let (du, dr) = (&self.du[self.idx[j]], &self.dr[self.idx[j]]);
                for i in 0..n {
                    u[i] -= gamma * (du[i] + beta * dr[i]);
                }
            }
        }
    }

    /// [`Anderson::step`] given the image `g = G(x)` instead of the residual; returns
    /// `max_i |G(x)_i - x_i|`.
    pub(crate) fn step_map(&mut self, x: &mut [f64], g: &[f64]) -> f64 {
        let n = x.len();
        let mut r = std::mem::take(&mut self.r);
        if r.len() < n {
            r.resize(n, 0.0);
        }
        let mut res = 0.0f64;
        for i in 0..n {
            r[i] = g[i] - x[i];
            res = res.max(r[i].abs());
        }
        self.step(x, &r[..n]);
        self.r = r;
        res
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Gaussian elimination with partial pivoting of the `n x n` row-major system `a x = b` (`x`
/// into `b`); false if singular or not finite.
fn solve(a: &mut [f64], b: &mut [f64], n: usize, pivoting: Pivoting) -> bool {
    for c in 0..n {
        let p = match pivoting {
            Pivoting::FirstLargest => {
                let mut p = c;
                for r in c + 1..n {
                    if a[r * n + c].abs() > a[p * n + c].abs() {
                        p = r;
                    }
                }
                p
            }
            Pivoting::LastLargest => (c..n)
                .max_by(|&i, &j| a[i * n + c].abs().total_cmp(&a[j * n + c].abs()))
                .unwrap_or(c),
        };
        let pivot = a[p * n + c];
        let singular = match pivoting {
            Pivoting::FirstLargest => pivot == 0.0 || !pivot.is_finite(),
            Pivoting::LastLargest => pivot.abs() < 1e-300,
        };
        if singular {
            return false;
        }
        if p != c {
            for k in 0..n {
                a.swap(c * n + k, p * n + k);
            }
            b.swap(c, p);
        }
        for r in c + 1..n {
            let f = a[r * n + c] / a[c * n + c];
            for k in c..n {
                a[r * n + k] -= f * a[c * n + k];
            }
            b[r] -= f * b[c];
        }
    }
    for c in (0..n).rev() {
        let mut s = b[c];
        for k in c + 1..n {
            s -= a[c * n + k] * b[k];
        }
        b[c] = s / a[c * n + c];
    }
    b.iter().all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `G(x)_i = 1.7 cos x_i + 0.4 sin x_{i+1} + 0.1 i` on 5 points (periodic), not a
    /// contraction: Picard alone oscillates.
    fn image(x: &[f64], g: &mut [f64]) {
        let n = x.len();
        for i in 0..n {
            g[i] = 1.7 * x[i].cos() + 0.4 * x[(i + 1) % n].sin() + 0.1 * i as f64;
        }
    }

    fn mix_hash(hash: &mut u64, v: f64) {
        *hash = (*hash ^ v.to_bits())
            .wrapping_mul(0x100000001b3)
            .rotate_left(17);
    }

    fn bits(x: &[f64]) -> Vec<u64> {
        x.iter().map(|v| v.to_bits()).collect()
    }

    // The expected bits below came from the two separate mixers (`rods/anderson.rs`,
    // `radial/anderson.rs`) before the merge, at commit 705c480. 16 steps of depth 3: the
    // history wraps, so the order of the small system matters, then a reset.

    #[test]
    fn rods_convention_reproduces_the_rods_mixer_bit_for_bit() {
        let n = 5;
        let (mut x, mut g, mut r) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut acc = Anderson::new(n, 3, 0.6, Convention::RODS);
        let mut hash = 0;
        for step in 0..16 {
            if step == 8 {
                acc.set_beta(0.4);
            }
            if step == 11 {
                acc.reset();
            }
            image(&x, &mut g);
            for i in 0..n {
                r[i] = g[i] - x[i];
            }
            acc.step(&mut x, &r);
            x.iter().for_each(|v| mix_hash(&mut hash, *v));
        }
        let want = [
            0x3ff1d632d14c412a,
            0x3ff2818409df8c62,
            0x3ff329b657032757,
            0x3ff3cd67d653d8f2,
            0x3ff446af74a9c7ae,
        ];
        assert_eq!(bits(&x), want);
        assert_eq!(hash, 0xc67b88d5b919980c, "an intermediate iterate changed");
    }

    #[test]
    fn radial_convention_reproduces_the_radial_mixer_bit_for_bit() {
        let n = 5;
        let (mut x, mut g) = (vec![0.0; n], vec![0.0; n]);
        let mut acc = Anderson::new(n, 3, 0.6, Convention::RADIAL);
        let mut hash = 0;
        for step in 0..16 {
            if step == 11 {
                acc.reset();
            }
            image(&x, &mut g);
            let res = acc.step_map(&mut x, &g);
            mix_hash(&mut hash, res);
            x.iter().for_each(|v| mix_hash(&mut hash, *v));
        }
        let want = [
            0x3ff1d632d14c417b,
            0x3ff2818409df8c36,
            0x3ff329b65703274a,
            0x3ff3cd67d653d8e0,
            0x3ff446af74a9c75c,
        ];
        assert_eq!(bits(&x), want);
        assert_eq!(hash, 0xea353935fcf17e85, "an intermediate iterate changed");
    }

    #[test]
    fn solves_a_linear_fixed_point_faster_than_picard() {
        // x = G(x) = A x + b with a stiff contraction-violating A (eigenvalues down to -5).
        let n = 20;
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let lam: Vec<f64> = (0..n).map(|i| -5.0 + 5.5 * i as f64 / n as f64).collect();
        for conv in [Convention::RODS, Convention::RADIAL] {
            let mut x = vec![0.0; n];
            let mut g = vec![0.0; n];
            let mut acc = Anderson::new(n, 10, 0.5, conv);
            let mut it = 0;
            loop {
                for i in 0..n {
                    g[i] = lam[i] * x[i] + b[i];
                }
                let r = acc.step_map(&mut x, &g);
                it += 1;
                if r < 1e-10 || it > 200 {
                    break;
                }
            }
            assert!(it < 100, "{conv:?}: {it}");
            for i in 0..n {
                assert!((x[i] - b[i] / (1.0 - lam[i])).abs() < 1e-8);
            }
        }
    }
}
