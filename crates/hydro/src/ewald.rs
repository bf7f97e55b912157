//! Reference: Beenakker's Ewald sum of the RPY tensor in a periodic cube (C. W. J. Beenakker,
//! J. Chem. Phys. 85, 1581 (1986)), as a dense 3N x 3N matrix for small N.
//!
//! With `mu0 = 1 / (6 pi eta a)`, Ewald parameter `xi` (any value > 0: the sum does not depend
//! on it, which the tests check to rounding) and box volume V:
//!
//! - real space, per image `r = x_i − x_j + n L`: `M1(r) = mu0 (A1 I + B1 r̂r̂)` with
//!   `A1 = erfc(xi r) (3a/(4r) + a^3/(2r^3)) + exp(−xi^2 r^2)/sqrt(pi) (4 xi^7 a^3 r^4 + 3 xi^3 a r^2
//!   − 20 xi^5 a^3 r^2 − 9/2 xi a + 14 xi^3 a^3 + xi a^3 / r^2)`,
//!   `B1 = erfc(xi r) (3a/(4r) − 3a^3/(2r^3)) + exp(−xi^2 r^2)/sqrt(pi) (−4 xi^7 a^3 r^4
//!   − 3 xi^3 a r^2 + 16 xi^5 a^3 r^2 + 3/2 xi a − 2 xi^3 a^3 − 3 xi a^3 / r^2)`;
//! - wave space, `k = 2 pi m / L`, `m != 0`: `M2(k) = mu0 (a − a^3 k^2/3) (1 + k^2/(4 xi^2)
//!   + k^4/(8 xi^4)) 6 pi / (k^2 V) exp(−k^2/(4 xi^2)) (I − k̂k̂) cos(k . (x_i − x_j))`;
//! - self (the `n = 0` image of `i = j`): `mu0 (1 − 6 xi a / sqrt(pi) + 40/3 xi^3 a^3 / sqrt(pi)) I`.
//!
//! The sum is that of the far-field (`r >= 2a`) tensor over all images, with zero mean flow
//! (the `k = 0` term left out, as in every periodic Stokes sum). Overlapping pairs
//! (`r < 2a`, nearest image; the box is at least `4a`) get the difference between the
//! overlapping and the far branch added ([`crate::rpy`]).

use crate::rpy::{rpy, rpy_far};
use std::f64::consts::PI;

/// Dense periodic RPY matrix (row-major, entry `(3 i + p, 3 j + q)`) of spheres of radius `a`
/// at `pos` in a cube of edge `l`, viscosity `eta`, by Beenakker's Ewald sum with parameter
/// `xi` (real and wave sums each converged to about 1e-16 relative).
pub fn beenakker_matrix(pos: &[[f64; 3]], a: f64, eta: f64, l: f64, xi: f64) -> Vec<f64> {
    assert!(l >= 4.0 * a, "the reference needs a box of at least 4a");
    let n = pos.len();
    let mu0 = 1.0 / (6.0 * PI * eta * a);
    let sp = PI.sqrt();
    let vol = l * l * l;
    // exp(-x^2) and erfc(x) below 1e-17 beyond x = 6.2.
    let r_cut = 6.2 / xi;
    let n_img = (r_cut / l).ceil() as i32 + 1;
    let k_cut = 2.0 * xi * 6.2;
    let m_max = (k_cut * l / (2.0 * PI)).ceil() as i32;
    let real = |r: f64| -> (f64, f64) {
        let (x2, e, c) = (
            xi * xi * r * r,
            (-(xi * xi * r * r)).exp() / sp,
            libm::erfc(xi * r),
        );
        let (a3, r2) = (a * a * a, r * r);
        let x = xi;
        let a1 = c * (0.75 * a / r + 0.5 * a3 / (r2 * r))
            + e * (4.0 * x.powi(7) * a3 * r2 * r2 + 3.0 * x.powi(3) * a * r2
                - 20.0 * x.powi(5) * a3 * r2
                - 4.5 * x * a
                + 14.0 * x.powi(3) * a3
                + x * a3 / r2);
        let b1 = c * (0.75 * a / r - 1.5 * a3 / (r2 * r))
            + e * (-4.0 * x.powi(7) * a3 * r2 * r2 - 3.0 * x.powi(3) * a * r2
                + 16.0 * x.powi(5) * a3 * r2
                + 1.5 * x * a
                - 2.0 * x.powi(3) * a3
                - 3.0 * x * a3 / r2);
        let _ = x2;
        (a1, b1)
    };
    // Wave vectors and their scalar factors.
    let mut waves = Vec::new();
    for mx in -m_max..=m_max {
        for my in -m_max..=m_max {
            for mz in -m_max..=m_max {
                if mx == 0 && my == 0 && mz == 0 {
                    continue;
                }
                let k = [mx, my, mz].map(|m| 2.0 * PI * m as f64 / l);
                let k2 = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
                if k2 > k_cut * k_cut {
                    continue;
                }
                let q = k2 / (4.0 * xi * xi);
                let s = (a - a * a * a * k2 / 3.0) * (1.0 + q + 2.0 * q * q) * 6.0 * PI
                    / (k2 * vol)
                    * (-q).exp();
                waves.push((k, k2, s));
            }
        }
    }
    let self_term = 1.0 - 6.0 * xi * a / sp + 40.0 / 3.0 * xi.powi(3) * a.powi(3) / sp;
    let mut m = vec![0.0; 9 * n * n];
    for i in 0..n {
        for j in 0..n {
            let mut b = [[0.0f64; 3]; 3];
            let d0 = [0, 1, 2].map(|k| pos[i][k] - pos[j][k]);
            // Nearest image for the overlap correction and the wave sum.
            let dm = d0.map(|x| x - l * (x / l).round());
            for nx in -n_img..=n_img {
                for ny in -n_img..=n_img {
                    for nz in -n_img..=n_img {
                        let d = [
                            dm[0] + nx as f64 * l,
                            dm[1] + ny as f64 * l,
                            dm[2] + nz as f64 * l,
                        ];
                        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                        if r2 > r_cut * r_cut {
                            continue;
                        }
                        if r2 == 0.0 {
                            for p in 0..3 {
                                b[p][p] += self_term;
                            }
                            continue;
                        }
                        let r = r2.sqrt();
                        let (a1, b1) = real(r);
                        for p in 0..3 {
                            for q in 0..3 {
                                b[p][q] += if p == q { a1 } else { 0.0 } + b1 * d[p] * d[q] / r2;
                            }
                        }
                    }
                }
            }
            for &(k, k2, s) in &waves {
                let c = s * (k[0] * dm[0] + k[1] * dm[1] + k[2] * dm[2]).cos();
                for p in 0..3 {
                    for q in 0..3 {
                        b[p][q] += c * (if p == q { 1.0 } else { 0.0 } - k[p] * k[q] / k2);
                    }
                }
            }
            let r = (dm[0] * dm[0] + dm[1] * dm[1] + dm[2] * dm[2]).sqrt();
            for p in 0..3 {
                for q in 0..3 {
                    m[(3 * i + p) * 3 * n + 3 * j + q] = mu0 * b[p][q];
                }
            }
            if i != j && r < 2.0 * a {
                let (near, far) = (rpy(r, a, eta).matrix(dm), rpy_far(r, a, eta).matrix(dm));
                for p in 0..3 {
                    for q in 0..3 {
                        m[(3 * i + p) * 3 * n + 3 * j + q] += near[p][q] - far[p][q];
                    }
                }
            }
        }
    }
    m
}

/// Hasimoto's self-mobility of a sphere of radius `a` in a periodic cube of edge `l`
/// (H. Hasimoto, J. Fluid Mech. 5, 317 (1959)), relative to `mu0`:
/// `1 − 2.837297 (a/L) + (4 pi / 3) (a/L)^3 − 27.4 (a/L)^6`. The RPY tensor reproduces the
/// first three terms exactly; the last is the rigid sphere's finite-size correction beyond RPY.
pub fn hasimoto(a: f64, l: f64) -> f64 {
    let x = a / l;
    1.0 - 2.837297 * x + 4.0 * PI / 3.0 * x.powi(3) - 27.4 * x.powi(6)
}

/// The first three terms of [`hasimoto`]: the exact periodic RPY self-mobility.
pub fn hasimoto_rpy(a: f64, l: f64) -> f64 {
    let x = a / l;
    1.0 - 2.837297 * x + 4.0 * PI / 3.0 * x.powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scatter(n: usize, l: f64) -> Vec<[f64; 3]> {
        (0..n)
            .map(|i| {
                let t = i as f64 + 1.0;
                [
                    ((t * 0.618_033_988_7).fract() - 0.5) * l,
                    ((t * 0.754_877_666_2).fract() - 0.5) * l,
                    ((t * 0.569_840_290_9).fract() - 0.5) * l,
                ]
            })
            .collect()
    }

    #[test]
    fn sum_does_not_depend_on_the_ewald_parameter() {
        let (a, eta, l) = (0.5, 1.0, 6.0);
        let pos = scatter(6, l);
        let x0 = PI.sqrt() / l;
        let m1 = beenakker_matrix(&pos, a, eta, l, x0);
        let mu0 = 1.0 / (6.0 * PI * eta * a);
        for f in [0.5, 2.0, 3.0] {
            let m2 = beenakker_matrix(&pos, a, eta, l, f * x0);
            let err = m1
                .iter()
                .zip(&m2)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-12 * mu0, "xi factor {f}: {err}");
        }
    }

    #[test]
    fn single_sphere_gives_hasimoto() {
        let (a, eta) = (1.0, 1.0);
        let mu0 = 1.0 / (6.0 * PI * eta * a);
        for l in [4.0, 5.0, 8.0, 16.0, 40.0] {
            let m = beenakker_matrix(&[[0.1, 0.2, -0.3]], a, eta, l, PI.sqrt() / l);
            for p in 0..3 {
                assert!(
                    (m[4 * p] / mu0 - hasimoto_rpy(a, l)).abs() < 1e-6,
                    "L = {l}: {}",
                    m[4 * p] / mu0
                );
            }
        }
    }
}
