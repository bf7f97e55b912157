//! Validation of the direct free-space RPY mobility: the analytic two-sphere tensor, the
//! Lanczos square root against an exact one, and fluctuation–dissipation.

use colloidsim_hydro::direct::dense_matrix;
use colloidsim_hydro::lanczos::LanczosParams;
use colloidsim_hydro::{DirectRpy, Mobility, NoiseKey};

use crate::common;
use common::fdt_deviation;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use std::f64::consts::PI;

/// The two-sphere RPY tensor written out from METHODS.md section 3, independently of the
/// crate's code: `(self, pair)` blocks for spheres of radius a at separation d.
fn two_sphere(d: [f64; 3], a: f64, eta: f64) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let e = d.map(|x| x / r);
    let mu0 = 1.0 / (6.0 * PI * eta * a);
    let mut s = [[0.0; 3]; 3];
    let mut p = [[0.0; 3]; 3];
    for i in 0..3 {
        s[i][i] = mu0;
        for j in 0..3 {
            let delta = if i == j { 1.0 } else { 0.0 };
            p[i][j] = if r >= 2.0 * a {
                1.0 / (8.0 * PI * eta * r)
                    * ((1.0 + 2.0 * a * a / (3.0 * r * r)) * delta
                        + (1.0 - 2.0 * a * a / (r * r)) * e[i] * e[j])
            } else {
                mu0 * ((1.0 - 9.0 * r / (32.0 * a)) * delta + 3.0 * r / (32.0 * a) * e[i] * e[j])
            };
        }
    }
    (s, p)
}

#[test]
fn two_spheres_match_the_analytic_tensor_in_both_branches_to_rounding() {
    let (a, eta) = (0.5, 1.7);
    let mu0 = 1.0 / (6.0 * PI * eta * a);
    let dir = [0.48, -0.6, 0.64];
    // Overlapping (r < 2a), at contact, and apart.
    for r in [0.05, 0.4, 0.77, 0.999, 1.0, 1.3, 2.5, 10.0, 1e3] {
        let d = dir.map(|x| x * r);
        let mut m = DirectRpy::new(2, a, eta, LanczosParams::default(), 10).unwrap();
        m.set_positions(&[[0.3, -0.2, 0.1], [0.3 - d[0], -0.2 - d[1], 0.1 - d[2]]])
            .unwrap();
        let got = dense_matrix(&mut m);
        let (s, p) = two_sphere(d, a, eta);
        for i in 0..3 {
            for j in 0..3 {
                for (blk, want) in [((0, 0), s), ((0, 1), p), ((1, 0), p), ((1, 1), s)] {
                    let g = got[(3 * blk.0 + i) * 6 + 3 * blk.1 + j];
                    assert!(
                        (g - want[i][j]).abs() <= 4.0 * f64::EPSILON * mu0,
                        "r = {r}, block {blk:?} ({i},{j}): {g} vs {}",
                        want[i][j]
                    );
                }
            }
        }
    }
}

/// Random positions of `n` spheres of radius `a` in a cube of edge `l`, overlaps allowed
/// (a deterministic scatter).
fn scatter(n: usize, l: f64, seed: u64) -> Vec<[f64; 3]> {
    (0..n)
        .map(|i| {
            let t = (i as u64 * 7919 + seed * 104_729) as f64;
            [
                ((t * 0.618_033_988_749_9).fract() - 0.5) * l,
                ((t * 0.754_877_666_246_7).fract() - 0.5) * l,
                ((t * 0.569_840_290_998_1).fract() - 0.5) * l,
            ]
        })
        .collect()
}

#[test]
fn lanczos_noise_matches_the_exact_square_root_and_tightens_with_the_tolerance() {
    let n = 60;
    let pos = scatter(n, 5.0, 2);
    let (a, eta) = (0.5, 1.0);
    let mut m = DirectRpy::new(n, a, eta, LanczosParams::default(), 100).unwrap();
    m.set_positions(&pos).unwrap();
    let dense = DMatrix::from_row_slice(3 * n, 3 * n, &dense_matrix(&mut m));
    let eig = SymmetricEigen::new(dense.clone());
    assert!(eig.eigenvalues.min() > 0.0, "RPY is positive definite");
    let sqrt = &eig.eigenvectors
        * DMatrix::from_diagonal(&eig.eigenvalues.map(f64::sqrt))
        * eig.eigenvectors.transpose();
    // The noise of a key, with scale 1, is M^(1/2) z for the z drawn by the key.
    let key = NoiseKey {
        seed: 11,
        step: 5,
        key0: 0,
    };
    let mut z = vec![[0.0; 3]; n];
    colloidsim_hydro::noise::fill_particle_noise(key, &mut z);
    let want = &sqrt * DVector::from_row_slice(z.as_flattened());
    let mut prev = f64::INFINITY;
    for tol in [1e-2, 1e-3, 1e-4, 1e-6] {
        let mut m = DirectRpy::new(
            n,
            a,
            eta,
            LanczosParams {
                tolerance: tol,
                max_iterations: 200,
            },
            100,
        )
        .unwrap();
        m.set_positions(&pos).unwrap();
        let mut out = vec![[0.0; 3]; n];
        let rep = m.brownian(key, 1.0, &mut out).unwrap();
        let err = (DVector::from_row_slice(out.as_flattened()) - &want).norm() / want.norm();
        assert!(err < tol, "tolerance {tol}: error {err} ({rep:?})");
        assert!(err < prev, "the error falls with the tolerance");
        prev = err;
    }
}

#[test]
fn direct_noise_covariance_is_2_kt_dt_m() {
    // Five spheres, two of them overlapping, three close: strong off-diagonal couplings.
    let pos = [
        [0.0, 0.0, 0.0],
        [0.8, 0.1, 0.0],
        [0.0, 1.2, 0.3],
        [-1.1, -0.4, 0.6],
        [0.5, 0.5, -1.3],
    ];
    let mut m = DirectRpy::new(5, 0.5, 1.0, LanczosParams::default(), 10).unwrap();
    m.set_positions(&pos).unwrap();
    let samples = 40_000;
    let (worst, mean2) = fdt_deviation(&mut m, samples, 1.3, 0.01);
    // 120 entries: the largest of 120 standard normals exceeds 4.5 with probability 1e-3;
    // the mean square is 1 within about sqrt(2 / 120) = 0.13 (entries are correlated, so
    // allow 0.5).
    assert!(worst < 4.5, "largest deviation {worst} standard errors");
    assert!((mean2 - 1.0).abs() < 0.5, "mean squared deviation {mean2}");
}
