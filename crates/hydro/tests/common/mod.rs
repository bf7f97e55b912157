//! Shared helpers of the validation tests.

use colloidsim_hydro::direct::dense_matrix;
use colloidsim_hydro::{Mobility, NoiseKey};

/// Sample covariance of `samples` Brownian displacements (scale `sqrt(2 kT dt)`) against
/// `2 kT dt M`: the largest deviation of an entry in units of its standard error
/// `sqrt((C_pp C_qq + C_pq^2) / S)`, and the mean squared one over the entries.
pub fn fdt_deviation(m: &mut dyn Mobility, samples: u64, kt: f64, dt: f64) -> (f64, f64) {
    let n3 = 3 * m.len();
    let dense = dense_matrix(m);
    let want: Vec<f64> = dense.iter().map(|x| 2.0 * kt * dt * x).collect();
    let mut cov = vec![0.0; n3 * n3];
    let mut out = vec![[0.0; 3]; m.len()];
    for s in 0..samples {
        let key = NoiseKey {
            seed: 3,
            step: s,
            key0: 0,
        };
        m.brownian(key, (2.0 * kt * dt).sqrt(), &mut out).unwrap();
        let x = out.as_flattened();
        for p in 0..n3 {
            for q in 0..n3 {
                cov[p * n3 + q] += x[p] * x[q];
            }
        }
    }
    let (mut worst, mut sum2, mut count) = (0.0f64, 0.0, 0);
    for p in 0..n3 {
        for q in p..n3 {
            let c = cov[p * n3 + q] / samples as f64;
            let w = want[p * n3 + q];
            let se = ((want[p * n3 + p] * want[q * n3 + q] + w * w) / samples as f64).sqrt();
            let z = (c - w) / se;
            worst = worst.max(z.abs());
            sum2 += z * z;
            count += 1;
        }
    }
    (worst, sum2 / count as f64)
}
