//! Gauss–Legendre quadrature, shared by the methods that integrate smooth functions on an
//! interval (the PSE's real-space tables, the PY compressibility route, the 1D rods' bulk).

use std::f64::consts::PI;

/// Nodes and weights of `n`-point Gauss–Legendre quadrature on `[-1, 1]`: the roots `x_i` of
/// the Legendre polynomial `P_n` by Newton's method on its three-term recurrence, from the
/// estimate `cos(pi (i + 3/4) / (n + 1/2))`, and `w_i = 2 / ((1 - x_i^2) P_n'(x_i)^2)`
/// (Abramowitz and Stegun 25.4.29). Exact for polynomials of degree up to `2 n - 1`.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut x, mut w) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n {
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                (p0, p1) = (p1, p2);
            }
            let dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            x[i] = z;
            w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
            if dz.abs() < 1e-15 {
                break;
            }
        }
    }
    (x, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact for every monomial up to degree 2n - 1, not for degree 2n (few nodes); symmetric
    /// nodes and weights.
    #[test]
    fn integrates_polynomials_of_degree_2n_minus_1_exactly() {
        for n in [2, 8, 16, 64] {
            let (x, w) = gauss_legendre(n);
            let integral = |p: i32| x.iter().zip(&w).map(|(x, w)| w * x.powi(p)).sum::<f64>();
            for p in 0..2 * n as i32 {
                let exact = if p % 2 == 0 {
                    2.0 / (p + 1) as f64
                } else {
                    0.0
                };
                assert!((integral(p) - exact).abs() < 1e-13, "n {n} degree {p}");
            }
            // The error at degree 2n falls as 4^-n: seen for few nodes only.
            let p = 2 * n as i32;
            if n <= 8 {
                assert!((integral(p) - 2.0 / (p + 1) as f64).abs() > 1e-9, "n {n}");
            }
            for i in 0..n {
                assert!((x[i] + x[n - 1 - i]).abs() < 1e-14 && (w[i] - w[n - 1 - i]).abs() < 1e-13);
            }
        }
    }
}
