//! S(q) from g(r) against closed-form transforms: the ideal gas, the low-density hard-sphere
//! step and the Ornstein–Zernike tail (for the Lorch window).

use colloidsim_analysis::{Window, default_q_grid, structure_factor, structure_factor_windowed};
use std::f64::consts::PI;

/// Bin midpoints of `bins` uniform bins on [0, r_max].
fn midpoints(r_max: f64, bins: usize) -> Vec<f64> {
    let dr = r_max / bins as f64;
    (0..bins).map(|b| (b as f64 + 0.5) * dr).collect()
}

#[test]
fn ideal_gas_has_s_equal_to_one_exactly() {
    let r = midpoints(5.0, 200);
    let g = vec![1.0; r.len()];
    let mut q = default_q_grid(5.0, 200);
    q.insert(0, 0.0);
    for w in [Window::None, Window::Lorch] {
        let s = structure_factor_windowed(&r, &g, 0.8, &q, w);
        assert_eq!(s.len(), q.len());
        assert!(s.iter().all(|&s| s == 1.0), "{w:?}: {s:?}");
    }
}

/// Low-density hard spheres: g = 0 for r < sigma, 1 beyond, so
/// S(q) = 1 - 4 pi rho (sin(q s) - q s cos(q s)) / q^3, S(0) = 1 - 4 pi rho s^3 / 3.
fn step_s(q: f64, rho: f64, sigma: f64) -> f64 {
    let x = q * sigma;
    1.0 - 4.0 * PI * rho * (x.sin() - x * x.cos()) / q.powi(3)
}

#[test]
fn step_g_matches_the_analytic_transform_within_the_midpoint_error() {
    let (rho, sigma, r_max, bins) = (0.3, 1.0, 5.0, 500);
    let dr = r_max / bins as f64; // sigma = 100 dr lies on a bin edge
    let r = midpoints(r_max, bins);
    let g: Vec<f64> = r
        .iter()
        .map(|&r| if r < sigma { 0.0 } else { 1.0 })
        .collect();
    let q = default_q_grid(r_max, bins); // 2 pi / r_max .. pi / dr
    let s = structure_factor(&r, &g, rho, &q);
    // Midpoint rule on [0, sigma] for f(r) = r sin(q r) / q: |error| <= sigma dr^2 / 24 max|f''|,
    // f'' = 2 cos(q r) - q r sin(q r), so max|f''| <= 2 + q sigma.
    let tol = |q: f64| 4.0 * PI * rho * sigma * dr * dr / 24.0 * (2.0 + q * sigma) + 1e-12;
    let mut worst: f64 = 0.0;
    for (&qk, &sk) in q.iter().zip(&s) {
        let err = (sk - step_s(qk, rho, sigma)).abs();
        assert!(
            err <= tol(qk),
            "q = {qk}: S = {sk}, exact {}",
            step_s(qk, rho, sigma)
        );
        worst = worst.max(err / tol(qk));
    }
    println!("step g: largest error / bound = {worst:.3}");
    // q = 0: the limit 1 - 4 pi rho sigma^3 / 3.
    let s0 = structure_factor(&r, &g, rho, &[0.0])[0];
    assert!((s0 - (1.0 - 4.0 * PI * rho / 3.0)).abs() <= tol(0.0));
    // The same comparison with sigma 5% off in the formula must fail, by far.
    let wrong = q
        .iter()
        .zip(&s)
        .map(|(&qk, &sk)| (sk - step_s(qk, rho, 1.05 * sigma)).abs() / tol(qk))
        .fold(0.0, f64::max);
    println!("step g with sigma x 1.05: largest error / bound = {wrong:.1}");
    assert!(wrong > 100.0, "sigma 5% off is not rejected: {wrong}");
}

/// Ornstein–Zernike tail h(r) = g(r) - 1 = A exp(-r / xi) / r:
/// S(q) = 1 + 4 pi rho A xi^2 / (1 + q^2 xi^2).
fn oz(r_max: f64, bins: usize, q: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let (rho, a, xi) = (0.5, 0.3, 1.0);
    let r = midpoints(r_max, bins);
    let g = r.iter().map(|&r| 1.0 + a * (-r / xi).exp() / r).collect();
    let exact = q
        .iter()
        .map(|&q| 1.0 + 4.0 * PI * rho * a * xi * xi / (1.0 + q * q * xi * xi))
        .collect();
    (r, g, exact)
}

fn max_err(s: &[f64], exact: &[f64]) -> f64 {
    s.iter()
        .zip(exact)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

#[test]
fn lorch_window_damps_truncation_ripples() {
    // g(r) cut at R = 3 xi, where h(R) = 0.015: the plain transform rings as cos(q R) / q^2, the
    // windowed one (integrand zero at R) decays faster.
    let q: Vec<f64> = (0..=200).map(|k| 10.0 + 0.1 * k as f64).collect();
    let (r, g, exact) = oz(3.0, 300, &q);
    let plain = max_err(&structure_factor(&r, &g, 0.5, &q), &exact);
    let lorch = max_err(
        &structure_factor_windowed(&r, &g, 0.5, &q, Window::Lorch),
        &exact,
    );
    println!("q in [10, 30], R = 3: ripple plain {plain:.2e}, Lorch {lorch:.2e}");
    assert!(lorch < 0.25 * plain, "plain {plain:.2e}, Lorch {lorch:.2e}");
}

#[test]
fn lorch_window_bias_at_q_zero_is_the_leading_order_one() {
    // W(r) = 1 - (pi r / R)^2 / 6 + O(R^-4) changes S(0) - 1 = 4 pi rho A \int r e^{-r/xi} W dr
    // by -4 pi rho A pi^2 xi^4 / R^2 (plus O(R^-4)); the unwindowed transform is exact there up
    // to the e^{-R/xi} tail and the midpoint error.
    let (rho, a, xi, r_max) = (0.5, 0.3, 1.0f64, 40.0f64);
    let (r, g, exact) = oz(r_max, 4000, &[0.0]);
    let plain = structure_factor(&r, &g, rho, &[0.0])[0];
    let lorch = structure_factor_windowed(&r, &g, rho, &[0.0], Window::Lorch)[0];
    assert!((plain - exact[0]).abs() < 1e-5, "{plain} vs {}", exact[0]);
    let bias = -4.0 * PI * rho * a * PI * PI * xi.powi(4) / (r_max * r_max);
    // Next order: +4 pi rho A (pi / R)^4 / 120 * 120 xi^6 = 7e-5 here.
    let next = 4.0 * PI * rho * a * PI.powi(4) * xi.powi(6) / r_max.powi(4);
    println!(
        "Lorch S(0) bias {:.4e}, leading order {bias:.4e}, next {next:.1e}",
        lorch - exact[0]
    );
    assert!((lorch - exact[0] - bias).abs() < 2.0 * next);
}
