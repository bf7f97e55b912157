//! Static structure factor S(q) from a tabulated pair distribution function g(r).

use rayon::prelude::*;
use std::f64::consts::PI;

/// Window applied to `g(r) - 1` before the Fourier transform in [`structure_factor_windowed`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Window {
    /// No window: the plain truncated transform, `W(r) = 1`.
    #[default]
    None,
    /// Lorch's window `W(r) = sin(pi r / R) / (pi r / R)` with `R` the outer edge of the last
    /// bin. It goes smoothly to zero at `R` and so damps the ripples that the truncation of
    /// `g(r)` at `R` causes in S(q), at the price of a resolution of about `2 pi / R` in q.
    Lorch,
}

/// `sin(x) / x`, with its limit 1 at `x = 0`.
#[inline]
fn sinc(x: f64) -> f64 {
    if x == 0.0 { 1.0 } else { x.sin() / x }
}

/// Static structure factor of an isotropic fluid of number density `rho` from its pair
/// distribution function, by the midpoint rule on the bins of `g`:
///
/// ```text
/// S(q) = 1 + 4 pi rho \int r^2 (g(r) - 1) sin(q r) / (q r) dr
///      ~ 1 + 4 pi rho dr \sum_b r_b^2 (g_b - 1) sin(q r_b) / (q r_b)
/// ```
///
/// `r` are the bin midpoints (uniform, width `dr = r[1] - r[0]`, as returned by
/// `pair_distribution`), `g` the values there, `rho` in particles per length^3 and `q` in
/// 1/length (the unit of `r`); `S(0)` is the `q -> 0` limit of the same sum. The integral ends at
/// the outer edge of the last bin, so `g` should have reached 1 there; see
/// [`structure_factor_windowed`] to damp the ripples of a truncation.
///
/// Panics if `r` and `g` differ in length, if there are fewer than two bins or if the bins are
/// not uniform (to 1e-6 dr).
pub fn structure_factor(r: &[f64], g: &[f64], rho: f64, q: &[f64]) -> Vec<f64> {
    structure_factor_windowed(r, g, rho, q, Window::None)
}

/// [`structure_factor`] with a window `W(r)` multiplying `g(r) - 1`:
///
/// ```text
/// S(q) = 1 + 4 pi rho dr \sum_b r_b^2 (g_b - 1) W(r_b) sin(q r_b) / (q r_b)
/// ```
///
/// with `W = 1` for [`Window::None`] and `W(r) = sin(pi r / R) / (pi r / R)`, `R = r_last +
/// dr / 2` for [`Window::Lorch`]. Same units and panics as [`structure_factor`].
pub fn structure_factor_windowed(
    r: &[f64],
    g: &[f64],
    rho: f64,
    q: &[f64],
    window: Window,
) -> Vec<f64> {
    assert_eq!(r.len(), g.len(), "r and g must have the same length");
    assert!(r.len() >= 2, "g(r) needs at least two bins");
    let dr = r[1] - r[0];
    assert!(dr > 0.0, "the bin midpoints must increase");
    assert!(
        r.windows(2)
            .all(|w| ((w[1] - w[0]) - dr).abs() <= 1e-6 * dr),
        "the bins of g(r) must be uniform"
    );
    let r_edge = r[r.len() - 1] + 0.5 * dr;
    // Weights 4 pi rho dr r^2 (g - 1) W(r), computed once for all q.
    let w: Vec<f64> = r
        .iter()
        .zip(g)
        .map(|(&ri, &gi)| {
            let win = match window {
                Window::None => 1.0,
                Window::Lorch => sinc(PI * ri / r_edge),
            };
            4.0 * PI * rho * dr * ri * ri * (gi - 1.0) * win
        })
        .collect();
    q.par_iter()
        .map(|&qk| {
            1.0 + r
                .iter()
                .zip(&w)
                .map(|(&ri, &wi)| wi * sinc(qk * ri))
                .sum::<f64>()
        })
        .collect()
}

/// A q grid for [`structure_factor`] matched to a g(r) with `bins` bins up to `r_max`:
/// `q_k = k pi / r_max` for `k = 2, ..., bins`, i.e. from `2 pi / r_max` (the longest wavelength
/// the sampled range resolves) up to `pi / dr` with `dr = r_max / bins`, in steps of
/// `pi / r_max` (`bins - 1` points, 1/length).
///
/// Panics unless `r_max > 0` and `bins >= 2`.
pub fn default_q_grid(r_max: f64, bins: usize) -> Vec<f64> {
    assert!(
        r_max > 0.0 && bins >= 2,
        "need r_max > 0 and at least two bins"
    );
    (2..=bins).map(|k| k as f64 * PI / r_max).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn q_grid_ends() {
        let q = default_q_grid(5.0, 100);
        assert_eq!(q.len(), 99);
        assert!((q[0] - 2.0 * PI / 5.0).abs() < 1e-12);
        assert!((q[98] - PI / 0.05).abs() < 1e-9);
    }

    #[test]
    #[should_panic(expected = "uniform")]
    fn non_uniform_bins_panic() {
        structure_factor(&[0.5, 1.5, 3.0], &[1.0; 3], 1.0, &[1.0]);
    }
}
