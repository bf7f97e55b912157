//! The benchmark system of `colloidsim bench mc`: hard spheres of diameter 1 in a periodic cube
//! at volume fraction `phi`, started from an FCC lattice and warmed up with move-size tuning.

use crate::engine::{HardSphereMc, McError, McParams};
use crate::geometry::Geometry;
use crate::init::fcc_in_box;
use std::f64::consts::PI;

/// Box edge of `n` spheres of diameter 1 at volume fraction `phi`: `(n pi / (6 phi))^(1/3)`.
pub fn bulk_edge(n: usize, phi: f64) -> f64 {
    (n as f64 * PI / 6.0 / phi).cbrt()
}

/// `n` hard spheres (d = 1) at volume fraction `phi` in a periodic cube, on an FCC lattice,
/// with `warmup` sweeps tuned every 100 towards acceptance 0.3 (delta then frozen).
pub fn bulk_system(n: usize, phi: f64, seed: u32, warmup: u64) -> Result<HardSphereMc, McError> {
    let edge = bulk_edge(n, phi);
    let pos = fcc_in_box(n, 1.0, edge)?;
    let params = McParams {
        diameter: 1.0,
        geometry: Geometry::Bulk { edge },
        seed,
        delta: 0.1,
        mixture: None,
    };
    let mut mc = HardSphereMc::new(&params, &pos, "system")?;
    mc.warm_up(warmup, 100, 0.3);
    Ok(mc)
}

/// The slowest density modes of a periodic cube: `cos` and `sin` of `k x_a` summed over the
/// spheres, `k = 2 pi / L`, for each axis `a` (six real series, each over `sqrt(N)`), whose
/// relaxation is the slowest of the fluid's structure (diffusive, time `~ 1 / (D k^2)`).
pub fn density_modes(mc: &HardSphereMc) -> [f64; 6] {
    let k = 2.0 * PI / mc.box_edge();
    let norm = 1.0 / (mc.len().max(1) as f64).sqrt();
    let mut out = [0.0; 6];
    for (a, xs) in mc.positions().iter().enumerate() {
        let (mut c, mut s) = (0.0, 0.0);
        for &x in xs.iter() {
            let (sn, cs) = (k * x).sin_cos();
            c += cs;
            s += sn;
        }
        out[2 * a] = c * norm;
        out[2 * a + 1] = s * norm;
    }
    out
}

/// Integrated autocorrelation time (in samples) of series of one observable's components
/// (their normalised autocorrelations averaged), `tau = 1/2 + sum_{t=1}^{W} rho(t)` with
/// Sokal's window: the smallest `W >= 6 tau(W)`; and whether the window was found within a
/// tenth of the series (else the series is too short: the estimate is a lower bound).
pub fn integrated_time(series: &[Vec<f64>]) -> (f64, bool) {
    let n = series.first().map_or(0, |s| s.len());
    if n < 4 {
        return (f64::NAN, false);
    }
    let centred: Vec<(Vec<f64>, f64)> = series
        .iter()
        .map(|s| {
            let m = s.iter().sum::<f64>() / n as f64;
            let c: Vec<f64> = s.iter().map(|x| x - m).collect();
            let var = c.iter().map(|x| x * x).sum::<f64>() / n as f64;
            (c, var)
        })
        .filter(|(_, v)| *v > 0.0)
        .collect();
    if centred.is_empty() {
        return (f64::NAN, false);
    }
    let rho = |t: usize| {
        centred
            .iter()
            .map(|(c, var)| {
                c[..n - t]
                    .iter()
                    .zip(&c[t..])
                    .map(|(a, b)| a * b)
                    .sum::<f64>()
                    / (n - t) as f64
                    / var
            })
            .sum::<f64>()
            / centred.len() as f64
    };
    let mut tau = 0.5;
    for w in 1..n / 10 {
        tau += rho(w);
        if w as f64 >= 6.0 * tau {
            return (tau.max(0.5), true);
        }
    }
    (tau.max(0.5), false)
}

#[cfg(test)]
mod tests {
    use super::integrated_time;

    /// An AR(1) series `x_t = a x_{t-1} + noise` has `tau = (1 + a) / (2 (1 - a))`.
    #[test]
    fn integrated_time_of_an_ar1_series() {
        use rand::Rng;
        let mut rng = colloidsim_core::rng::stream(1, 0, colloidsim_core::rng::Purpose::Moves, 0);
        let a: f64 = 0.9;
        let mut x = 0.0;
        let s: Vec<f64> = (0..200_000)
            .map(|_| {
                x = a * x + ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
                x
            })
            .collect();
        let (tau, ok) = integrated_time(&[s]);
        let exact = (1.0 + a) / (2.0 * (1.0 - a));
        assert!(ok && (tau / exact - 1.0).abs() < 0.1, "{tau} vs {exact}");
    }
}
