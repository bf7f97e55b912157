//! Krylov (Lanczos) square root: `y = M^(1/2) z` from products with M alone.
//!
//! Ando, Chow, Saad & Skolnick, J. Chem. Phys. 137, 064106 (2012): after k Lanczos steps from
//! `v_1 = z / |z|`, `M V_k = V_k T_k + beta_k v_{k+1} e_k^T` with `T_k` tridiagonal, and
//! `y_k = |z| V_k T_k^(1/2) e_1` (the square root of the small `T_k` by its eigenvectors).
//! The iteration stops when the relative change `|y_k − y_(k−1)| / |y_k|` (Ando et al.'s error
//! estimate, measured on the coefficient vectors: the basis is orthonormal) has been below the
//! tolerance for two iterations in a row (one alone can undershoot the error of `y_k`; the
//! tests measure the error against exact square roots), or when the Krylov space is exhausted
//! (`beta_k = 0`: `y_k` is exact).
//! It never stops silently short: without convergence within the iteration limit it returns
//! [`LanczosError::NotConverged`] with the iterations done and the residual reached.
//!
//! The basis is stored (`k` vectors of length 3N, grown once and reused) so that the
//! operator is applied once per iteration. Dot products sum in a fixed order
//! ([`crate::noise::dot`]), so the result does not depend on the thread count.

use crate::noise::dot;
use nalgebra::{DMatrix, SymmetricEigen};
use rayon::prelude::*;

/// Entries per parallel work item of the vector updates.
const CHUNK: usize = 4096;

/// Tolerance and iteration limit of a Lanczos square root.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LanczosParams {
    /// Relative change `|y_k − y_(k−1)| / |y_k|` at which the iteration stops.
    pub tolerance: f64,
    /// Most iterations before [`LanczosError::NotConverged`].
    pub max_iterations: usize,
}

impl Default for LanczosParams {
    /// Tolerance 1e-3 (the drying-droplet paper's PSE tolerance), at most 200 iterations.
    fn default() -> Self {
        Self {
            tolerance: 1e-3,
            max_iterations: 200,
        }
    }
}

/// How a square root converged.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SqrtReport {
    /// Lanczos iterations (products with M).
    pub iterations: usize,
    /// Relative change of the last iteration (0 when the Krylov space was exhausted).
    pub residual: f64,
}

/// A Lanczos square root that did not deliver.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LanczosError {
    /// The tolerance was not reached within the iteration limit.
    #[error(
        "the Lanczos square root did not converge: relative change {residual:.3e} after {iterations} \
         iterations, tolerance {tolerance:.3e} (raise `max_iterations` or the tolerance)"
    )]
    NotConverged {
        /// Iterations done.
        iterations: usize,
        /// Relative change of the last iteration.
        residual: f64,
        /// Requested tolerance.
        tolerance: f64,
    },
    /// The operator is not positive definite (or not symmetric).
    #[error(
        "the mobility is not positive definite: the Lanczos matrix has eigenvalue {eigenvalue:.3e} \
         (largest {largest:.3e}) after {iterations} iterations"
    )]
    NotPositive {
        /// Most negative eigenvalue.
        eigenvalue: f64,
        /// Largest eigenvalue.
        largest: f64,
        /// Iterations done.
        iterations: usize,
    },
    /// A non-finite number appeared.
    #[error("the Lanczos square root met a non-finite number after {iterations} iterations")]
    NonFinite {
        /// Iterations done.
        iterations: usize,
    },
}

/// Scratch of the Lanczos square root (grown on first use, then reused).
#[derive(Debug, Clone, Default)]
pub struct Lanczos {
    basis: Vec<f64>,
    w: Vec<f64>,
    alpha: Vec<f64>,
    beta: Vec<f64>,
    coeff: Vec<f64>,
    prev: Vec<f64>,
    partials: Vec<f64>,
}

impl Lanczos {
    /// Bytes held by the stored basis and work vectors.
    pub fn bytes(&self) -> usize {
        8 * (self.basis.capacity() + self.w.capacity())
    }

    /// `out = M^(1/2) z`, with `apply(v, w)` writing `w = M v` (M symmetric positive definite).
    pub fn sqrt_times(
        &mut self,
        params: &LanczosParams,
        z: &[f64],
        mut apply: impl FnMut(&[f64], &mut [f64]),
        out: &mut [f64],
    ) -> Result<SqrtReport, LanczosError> {
        let n = z.len();
        assert_eq!(out.len(), n, "output length");
        let beta0 = dot(z, z, &mut self.partials).sqrt();
        if !beta0.is_finite() {
            return Err(LanczosError::NonFinite { iterations: 0 });
        }
        if beta0 == 0.0 {
            out.iter_mut().for_each(|x| *x = 0.0);
            return Ok(SqrtReport::default());
        }
        self.w.resize(n, 0.0);
        self.alpha.clear();
        self.beta.clear();
        self.prev.clear();
        if self.basis.len() < n {
            self.basis.resize(n, 0.0);
        }
        let inv = 1.0 / beta0;
        self.basis[..n]
            .par_chunks_mut(CHUNK)
            .zip(z.par_chunks(CHUNK))
            .for_each(|(v, z)| v.iter_mut().zip(z).for_each(|(v, z)| *v = z * inv));
        let mut residual = f64::INFINITY;
        let mut below = 0;
        for k in 0..params.max_iterations {
            let done = &self.basis[..(k + 1) * n];
            let vk = &done[k * n..];
            apply(vk, &mut self.w);
            let alpha = dot(vk, &self.w, &mut self.partials);
            let beta_prev = if k > 0 { self.beta[k - 1] } else { 0.0 };
            let vprev = if k > 0 { &done[(k - 1) * n..k * n] } else { vk };
            self.w
                .par_chunks_mut(CHUNK)
                .zip(vk.par_chunks(CHUNK))
                .zip(vprev.par_chunks(CHUNK))
                .for_each(|((w, v), u)| {
                    for i in 0..w.len() {
                        w[i] -= alpha * v[i] + beta_prev * u[i];
                    }
                });
            let beta = dot(&self.w, &self.w, &mut self.partials).sqrt();
            self.alpha.push(alpha);
            self.beta.push(beta);
            if !(alpha.is_finite() && beta.is_finite()) {
                return Err(LanczosError::NonFinite { iterations: k + 1 });
            }
            self.tridiagonal_sqrt(beta0, k + 1)?;
            // Krylov space exhausted: y_k is exact.
            let exhausted = beta <= 1e-14 * alpha.abs().max(beta_prev);
            if k > 0 || exhausted {
                let mut d2 = 0.0;
                let mut y2 = 0.0;
                for (i, c) in self.coeff.iter().enumerate() {
                    let p = self.prev.get(i).copied().unwrap_or(0.0);
                    d2 += (c - p) * (c - p);
                    y2 += c * c;
                }
                residual = if exhausted { 0.0 } else { (d2 / y2).sqrt() };
            }
            below = if residual < params.tolerance {
                below + 1
            } else {
                0
            };
            if exhausted || below == 2 {
                self.combine(k + 1, n, out);
                return Ok(SqrtReport {
                    iterations: k + 1,
                    residual,
                });
            }
            std::mem::swap(&mut self.prev, &mut self.coeff);
            // v_(k+1) = w / beta, stored after the first k+1 vectors.
            if self.basis.len() < (k + 2) * n {
                self.basis.resize((k + 2) * n, 0.0);
            }
            let inv = 1.0 / beta;
            self.basis[(k + 1) * n..(k + 2) * n]
                .par_chunks_mut(CHUNK)
                .zip(self.w.par_chunks(CHUNK))
                .for_each(|(v, w)| v.iter_mut().zip(w).for_each(|(v, w)| *v = w * inv));
        }
        Err(LanczosError::NotConverged {
            iterations: params.max_iterations,
            residual,
            tolerance: params.tolerance,
        })
    }

    /// `coeff = beta0 T_m^(1/2) e_1` from the stored `alpha`, `beta`.
    fn tridiagonal_sqrt(&mut self, beta0: f64, m: usize) -> Result<(), LanczosError> {
        let t = DMatrix::from_fn(m, m, |i, j| {
            if i == j {
                self.alpha[i]
            } else if i + 1 == j {
                self.beta[i]
            } else if j + 1 == i {
                self.beta[j]
            } else {
                0.0
            }
        });
        let eig = SymmetricEigen::new(t);
        let largest = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
        let smallest = eig
            .eigenvalues
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min);
        // Rounding may leave eigenvalues of order 1e-16 of the largest slightly negative.
        if smallest < -1e-10 * largest || largest <= 0.0 {
            return Err(LanczosError::NotPositive {
                eigenvalue: smallest,
                largest,
                iterations: m,
            });
        }
        self.coeff.clear();
        self.coeff.resize(m, 0.0);
        for j in 0..m {
            let s = eig.eigenvalues[j].max(0.0).sqrt() * eig.eigenvectors[(0, j)] * beta0;
            for i in 0..m {
                self.coeff[i] += eig.eigenvectors[(i, j)] * s;
            }
        }
        Ok(())
    }

    /// `out = sum_i coeff_i v_i` (each entry summed over the basis in order).
    fn combine(&self, m: usize, n: usize, out: &mut [f64]) {
        let (basis, coeff) = (&self.basis, &self.coeff);
        out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, o)| {
            let lo = c * CHUNK;
            o.iter_mut().for_each(|x| *x = 0.0);
            for (i, &ci) in coeff[..m].iter().enumerate() {
                let v = &basis[i * n + lo..i * n + lo + o.len()];
                for (x, v) in o.iter_mut().zip(v) {
                    *x += ci * v;
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric positive definite test matrix with known square root: `Q diag(d) Q^T`
    /// with Q a product of plane rotations.
    fn spd(n: usize, cond: f64) -> (DMatrix<f64>, DMatrix<f64>) {
        let mut q = DMatrix::<f64>::identity(n, n);
        for k in 0..3 * n {
            let (i, j) = (k % n, (7 * k + 3) % n);
            if i == j {
                continue;
            }
            let th = 0.3 + 0.1 * k as f64;
            let mut g = DMatrix::<f64>::identity(n, n);
            g[(i, i)] = th.cos();
            g[(j, j)] = th.cos();
            g[(i, j)] = th.sin();
            g[(j, i)] = -th.sin();
            q = &g * q;
        }
        let d: Vec<f64> = (0..n)
            .map(|i| cond.powf(i as f64 / (n - 1) as f64))
            .collect();
        let m =
            &q * DMatrix::from_diagonal(&nalgebra::DVector::from_vec(d.clone())) * q.transpose();
        let s =
            &q * DMatrix::from_diagonal(&nalgebra::DVector::from_vec(
                d.iter().map(|x| x.sqrt()).collect(),
            )) * q.transpose();
        (m, s)
    }

    #[test]
    fn square_root_matches_the_exact_one_to_the_tolerance() {
        let n = 60;
        let (m, s) = spd(n, 50.0);
        let z: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) / 3.0).collect();
        let want = &s * nalgebra::DVector::from_vec(z.clone());
        let mut prev_err = f64::INFINITY;
        for tol in [1e-2, 1e-4, 1e-6, 1e-8] {
            let mut l = Lanczos::default();
            let mut out = vec![0.0; n];
            let params = LanczosParams {
                tolerance: tol,
                max_iterations: 200,
            };
            let rep = l
                .sqrt_times(
                    &params,
                    &z,
                    |v, w| {
                        let y = &m * nalgebra::DVector::from_column_slice(v);
                        w.copy_from_slice(y.as_slice());
                    },
                    &mut out,
                )
                .unwrap();
            let err = (nalgebra::DVector::from_vec(out) - &want).norm() / want.norm();
            // The stopping rule estimates the error of the previous iterate; the actual error
            // is below the tolerance and falls with it.
            assert!(err < tol, "tol {tol}: error {err} after {rep:?}");
            assert!(err < prev_err);
            prev_err = err;
        }
    }

    #[test]
    fn identity_converges_in_one_step_and_limits_are_reported() {
        let n = 10;
        let z: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let mut out = vec![0.0; n];
        let mut l = Lanczos::default();
        let rep = l
            .sqrt_times(
                &LanczosParams::default(),
                &z,
                |v, w| w.iter_mut().zip(v).for_each(|(w, v)| *w = 4.0 * v),
                &mut out,
            )
            .unwrap();
        assert_eq!(rep.iterations, 1);
        for i in 0..n {
            assert!((out[i] - 2.0 * z[i]).abs() < 1e-13);
        }
        // Too few iterations: an error naming the iterations and residual.
        let (m, _) = spd(40, 1e4);
        let params = LanczosParams {
            tolerance: 1e-12,
            max_iterations: 3,
        };
        let z = vec![1.0; 40];
        let mut out = vec![0.0; 40];
        let e = l
            .sqrt_times(
                &params,
                &z,
                |v, w| {
                    let y = &m * nalgebra::DVector::from_column_slice(v);
                    w.copy_from_slice(y.as_slice());
                },
                &mut out,
            )
            .unwrap_err();
        match e {
            LanczosError::NotConverged {
                iterations,
                residual,
                ..
            } => {
                assert_eq!(iterations, 3);
                assert!(residual > 1e-12 && residual.is_finite());
            }
            other => panic!("{other}"),
        }
        assert!(e.to_string().contains("3 iterations"));
        // An indefinite operator is refused.
        let e = l
            .sqrt_times(
                &LanczosParams::default(),
                &z,
                |v, w| {
                    for i in 0..v.len() {
                        w[i] = if i % 2 == 0 { v[i] } else { -v[i] };
                    }
                },
                &mut out,
            )
            .unwrap_err();
        assert!(matches!(e, LanczosError::NotPositive { .. }), "{e}");
    }
}
