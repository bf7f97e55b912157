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

//!
//! **Unequal radii** ([`beenakker_matrix_radii`]). The far branch of the Zuk et al. tensor,
//! `1/(8 pi eta r) [(1 + (a_i^2 + a_j^2)/(3 r^2)) I + (1 − (a_i^2 + a_j^2)/r^2) r̂r̂]`, is the
//! Oseen tensor plus `(a_i^2 + a_j^2)/6` times its Laplacian, the monodisperse far tensor with
//! `a^2` replaced by `s = (a_i^2 + a_j^2)/2`. Beenakker's terms are of two kinds, `mu0 a` (the
//! Oseen part, `1/(6 pi eta)`) and `mu0 a^3` (the Laplacian part, `a^2/(6 pi eta)`), so the
//! pair's sum follows with `mu0 a -> 1/(6 pi eta)` and `mu0 a^3 -> s/(6 pi eta)`; the self term
//! is Beenakker's with the sphere's own radius, and overlapping pairs
//! (`r <= a_i + a_j`, nearest image; the box is at least 4 radii of the largest sphere) get
//! the difference between Zuk et al.'s overlapping (or inner) branch and the far branch.
//! Independent of PSE: no splitting of the sinc factors, no grid, no tabulated functions.

use crate::rpy::{PairTensor, rpy, rpy_far, rpy_unequal};
use std::f64::consts::PI;

/// The wave vectors `k = 2 pi m / l` (m != 0) of a cube of edge `l` with `|k| <= k_cut`, each
/// with `k^2` and Beenakker's factor `g(k) = 6 pi (1 + q + 2 q^2) e^-q / (k^2 V)`,
/// `q = k^2 / (4 xi^2)`, which the RPY wave sum multiplies by `1 - s k^2 / 3` (`s` the pair's).
fn ewald_waves(l: f64, xi: f64, k_cut: f64) -> Vec<([f64; 3], f64, f64)> {
    let vol = l * l * l;
    let m_max = (k_cut * l / (2.0 * PI)).ceil() as i32;
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
                waves.push((
                    k,
                    k2,
                    (1.0 + q + 2.0 * q * q) * 6.0 * PI / (k2 * vol) * (-q).exp(),
                ));
            }
        }
    }
    waves
}

/// Dense periodic RPY matrix (row-major, entry `(3 i + p, 3 j + q)`) of spheres of radius `a`
/// at `pos` in a cube of edge `l`, viscosity `eta`, by Beenakker's Ewald sum with parameter
/// `xi` (real and wave sums each converged to about 1e-16 relative).
pub fn beenakker_matrix(pos: &[[f64; 3]], a: f64, eta: f64, l: f64, xi: f64) -> Vec<f64> {
    assert!(l >= 4.0 * a, "the reference needs a box of at least 4a");
    let n = pos.len();
    let mu0 = 1.0 / (6.0 * PI * eta * a);
    let sp = PI.sqrt();
    // exp(-x^2) and erfc(x) below 1e-17 beyond x = 6.2.
    let r_cut = 6.2 / xi;
    let n_img = (r_cut / l).ceil() as i32 + 1;
    let k_cut = 2.0 * xi * 6.2;
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
    // Wave vectors and their scalar factors (a - a^3 k^2 / 3) g(k).
    let waves: Vec<_> = ewald_waves(l, xi, k_cut)
        .into_iter()
        .map(|(k, k2, g)| (k, k2, (a - a * a * a * k2 / 3.0) * g))
        .collect();
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

/// The far branch of the unequal-radius RPY tensor (the `r > a_i + a_j` formula at any
/// `r > 0`).
fn rpy_far_unequal(r: f64, ai: f64, aj: f64, eta: f64) -> PairTensor {
    let c = 1.0 / (8.0 * PI * eta * r);
    let s2 = (ai * ai + aj * aj) / (r * r);
    PairTensor {
        a: c * (1.0 + s2 / 3.0),
        b: c * (1.0 - s2),
    }
}

/// Dense periodic RPY matrix of spheres of radii `radii` at `pos` in a cube of edge `l`,
/// viscosity `eta`: Beenakker's Ewald sum generalised to unequal radii (module docs), Ewald
/// parameter `xi`. Equal radii give [`beenakker_matrix`] to rounding.
pub fn beenakker_matrix_radii(
    pos: &[[f64; 3]],
    radii: &[f64],
    eta: f64,
    l: f64,
    xi: f64,
) -> Vec<f64> {
    let n = pos.len();
    assert_eq!(radii.len(), n, "one radius per particle");
    let a_max = radii.iter().copied().fold(0.0, f64::max);
    assert!(
        l >= 4.0 * a_max,
        "the reference needs a box of at least 4 radii"
    );
    let c6 = 1.0 / (6.0 * PI * eta);
    let sp = PI.sqrt();
    let r_cut = 6.2 / xi;
    let n_img = (r_cut / l).ceil() as i32 + 1;
    let k_cut = 2.0 * xi * 6.2;
    // Real-space functions of a pair with s = (a_i^2 + a_j^2)/2, in units of 1/(6 pi eta).
    let real = |r: f64, s: f64| -> (f64, f64) {
        let (e, c) = ((-(xi * xi * r * r)).exp() / sp, libm::erfc(xi * r));
        let (r2, x) = (r * r, xi);
        let a1 = c * (0.75 / r + 0.5 * s / (r2 * r))
            + e * (4.0 * x.powi(7) * s * r2 * r2 + 3.0 * x.powi(3) * r2
                - 20.0 * x.powi(5) * s * r2
                - 4.5 * x
                + 14.0 * x.powi(3) * s
                + x * s / r2);
        let b1 = c * (0.75 / r - 1.5 * s / (r2 * r))
            + e * (-4.0 * x.powi(7) * s * r2 * r2 - 3.0 * x.powi(3) * r2
                + 16.0 * x.powi(5) * s * r2
                + 1.5 * x
                - 2.0 * x.powi(3) * s
                - 3.0 * x * s / r2);
        (a1, b1)
    };
    // Wave vectors, k^2 and the factor g(k) of (1 − s k^2 / 3) g(k).
    let waves = ewald_waves(l, xi, k_cut);
    let mut m = vec![0.0; 9 * n * n];
    for i in 0..n {
        for j in 0..n {
            let (ai, aj) = (radii[i], radii[j]);
            let s = 0.5 * (ai * ai + aj * aj);
            let mut b = [[0.0f64; 3]; 3];
            let d0 = [0, 1, 2].map(|k| pos[i][k] - pos[j][k]);
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
                            // i = j, or two spheres at one point: the limit r -> 0 of the
                            // real-space term plus the inner branch 1/(6 pi eta a_max) (for
                            // i = j Beenakker's self term), in units of 1/(6 pi eta).
                            let t =
                                1.0 / ai.max(aj) - 6.0 * xi / sp + 40.0 / 3.0 * xi.powi(3) * s / sp;
                            for p in 0..3 {
                                b[p][p] += t;
                            }
                            continue;
                        }
                        let r = r2.sqrt();
                        let (a1, b1) = real(r, s);
                        for p in 0..3 {
                            for q in 0..3 {
                                b[p][q] += if p == q { a1 } else { 0.0 } + b1 * d[p] * d[q] / r2;
                            }
                        }
                    }
                }
            }
            for &(k, k2, g) in &waves {
                let c =
                    (1.0 - s * k2 / 3.0) * g * (k[0] * dm[0] + k[1] * dm[1] + k[2] * dm[2]).cos();
                for p in 0..3 {
                    for q in 0..3 {
                        b[p][q] += c * (if p == q { 1.0 } else { 0.0 } - k[p] * k[q] / k2);
                    }
                }
            }
            let r = (dm[0] * dm[0] + dm[1] * dm[1] + dm[2] * dm[2]).sqrt();
            for p in 0..3 {
                for q in 0..3 {
                    m[(3 * i + p) * 3 * n + 3 * j + q] = c6 * b[p][q];
                }
            }
            if i != j && r <= ai + aj && r > 0.0 {
                let near = rpy_unequal(r, ai, aj, eta).matrix(dm);
                let far = rpy_far_unequal(r, ai, aj, eta).matrix(dm);
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

    /// Three sizes (ratio 4), with an overlapping pair of unequal spheres and a small sphere
    /// inside a large one.
    fn mixture() -> (Vec<[f64; 3]>, Vec<f64>) {
        let pos = vec![
            [0.1, 0.2, -0.3],
            [1.0, 0.4, 0.1],
            [-1.9, 1.4, 0.9],
            [1.7, -2.2, 2.4],
            [-1.5, 1.0, 1.2],
            [2.6, 2.1, -1.8],
        ];
        let radii = vec![1.0, 0.5, 0.25, 1.0, 0.25, 0.5];
        (pos, radii)
    }

    fn max_diff(x: &[f64], y: &[f64]) -> f64 {
        x.iter()
            .zip(y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn unequal_radii_sum_does_not_depend_on_the_ewald_parameter() {
        let (eta, l) = (1.0, 7.0);
        let (pos, radii) = mixture();
        let x0 = PI.sqrt() / l;
        let m1 = beenakker_matrix_radii(&pos, &radii, eta, l, x0);
        let mu = 1.0 / (6.0 * PI * eta * 1.0);
        for f in [0.5, 2.0, 3.0] {
            let m2 = beenakker_matrix_radii(&pos, &radii, eta, l, f * x0);
            let err = max_diff(&m1, &m2);
            assert!(err < 1e-12 * mu, "xi factor {f}: {err}");
        }
        // Symmetric.
        let n3 = 3 * pos.len();
        for r in 0..n3 {
            for c in 0..n3 {
                assert!((m1[r * n3 + c] - m1[c * n3 + r]).abs() < 1e-14 * mu);
            }
        }
    }

    #[test]
    fn unequal_radii_sum_reduces_to_beenakker_for_equal_radii() {
        let (a, eta, l) = (0.5, 1.0, 6.0);
        let pos = scatter(8, l);
        let xi = 1.3 * PI.sqrt() / l;
        let want = beenakker_matrix(&pos, a, eta, l, xi);
        let got = beenakker_matrix_radii(&pos, &[a; 8], eta, l, xi);
        let mu0 = 1.0 / (6.0 * PI * eta * a);
        assert!(max_diff(&got, &want) < 1e-14 * mu0);
    }

    #[test]
    fn unequal_radii_single_spheres_give_hasimoto() {
        let eta = 1.0;
        for a in [0.25, 0.5, 1.0, 2.0] {
            let mu0 = 1.0 / (6.0 * PI * eta * a);
            for l in [8.0, 20.0] {
                let m = beenakker_matrix_radii(&[[0.3, -0.2, 0.1]], &[a], eta, l, PI.sqrt() / l);
                for p in 0..3 {
                    let mu = m[4 * p] / mu0;
                    assert!((mu - hasimoto_rpy(a, l)).abs() < 1e-6, "a {a}, L {l}: {mu}");
                }
            }
        }
    }

    #[test]
    fn unequal_radii_sum_tends_to_free_space_as_the_box_grows() {
        // M_per − M_free = −2.837297 / (6 pi eta L) I + O(r^2 / L^3) for every block (the
        // self blocks: Hasimoto's series): once the O(1/L) term is taken out, the rest falls
        // as 1 / L^3.
        use crate::{DirectRpy, LanczosParams, Mobility};
        let eta = 1.0;
        let (pos, radii) = mixture();
        let n = pos.len();
        let mut d = DirectRpy::with_radii(&radii, eta, LanczosParams::default(), 100).unwrap();
        d.set_positions(&pos).unwrap();
        let free = crate::direct::dense_matrix(&mut d);
        let mut prev = f64::INFINITY;
        for l in [20.0, 40.0, 80.0] {
            let per = beenakker_matrix_radii(&pos, &radii, eta, l, PI.sqrt() / l);
            let c = 2.837297 / (6.0 * PI * eta * l);
            let mut worst = 0.0f64;
            for r in 0..3 * n {
                for col in 0..3 * n {
                    let hasimoto = if r % 3 == col % 3 { -c } else { 0.0 };
                    let k = r * 3 * n + col;
                    worst = worst.max((per[k] - free[k] - hasimoto).abs());
                }
            }
            // Relative to the O(1/L) term itself: a few (r / L)^2 at most.
            let rel = worst / c;
            assert!(rel < 40.0 / (l * l), "L {l}: residual {rel}");
            assert!(worst < prev / 6.0, "L {l}: {worst} after {prev}");
            prev = worst;
        }
    }
}
