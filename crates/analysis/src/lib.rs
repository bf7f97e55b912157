//! colloidsim-analysis: observables of particle configurations and trajectories — radial
//! volume-fraction profiles, the pair distribution function g(r) and the mean-squared
//! displacement, the static structure factor S(q), contacts between spheres and the clusters,
//! coordination numbers and bond lifetimes of the contact network — working on plain arrays,
//! so on any GSD trajectory ([`read_trajectory`]) as well as on a running engine.

mod contacts;
mod network;
mod stratification;
mod structure;

pub use contacts::contacts;
pub use network::{
    BondTracker, ClusterStats, cluster_labels, cluster_stats, coordination_histogram,
    coordination_numbers,
};
pub use stratification::{Stratification, stratification};
pub use structure::{Window, default_q_grid, structure_factor, structure_factor_windowed};

use colloidsim_particles::gsd::{GsdError, frame_count, read_frame};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::path::Path;

/// A radial volume-fraction profile on `bins` shells of equal width between 0 and `r_max`.
#[derive(Debug, Clone, PartialEq)]
pub struct RadialProfile {
    /// Shell mid-points.
    pub r: Vec<f64>,
    /// Volume fraction of each shell: particle volumes `pi d^3 / 6` of the centres in the shell
    /// divided by the shell's volume.
    pub phi: Vec<f64>,
    /// Centres at `|x - centre| >= r_max`, not counted in any shell.
    pub outside: usize,
}

/// Radial volume-fraction profile around `centre` by centre binning.
pub fn radial_profile(
    pos: &[[f64; 3]],
    diameter: &[f64],
    centre: [f64; 3],
    r_max: f64,
    bins: usize,
) -> RadialProfile {
    assert!(bins > 0 && r_max > 0.0 && pos.len() == diameter.len());
    let dr = r_max / bins as f64;
    let mut vol = vec![0.0; bins];
    let mut outside = 0;
    for (x, d) in pos.iter().zip(diameter) {
        let v = [x[0] - centre[0], x[1] - centre[1], x[2] - centre[2]];
        let r = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let b = (r / dr) as usize;
        if b < bins {
            vol[b] += PI / 6.0 * d * d * d;
        } else {
            outside += 1;
        }
    }
    let r = (0..bins).map(|b| (b as f64 + 0.5) * dr).collect();
    let phi = vol
        .iter()
        .enumerate()
        .map(|(b, v)| {
            let (lo, hi) = (b as f64 * dr, (b + 1) as f64 * dr);
            v / (4.0 / 3.0 * PI * (hi.powi(3) - lo.powi(3)))
        })
        .collect();
    RadialProfile { r, phi, outside }
}

/// Volume of the part of a sphere of radius `a`, centred at distance `rho` from the origin,
/// that lies inside the ball of radius `big_r` about the origin: the whole sphere when
/// `rho + a <= R`, the ball when `rho + R <= a`, nothing when `rho >= R + a`, else the lens of
/// the two spheres (e.g. Weisstein, "Sphere-Sphere Intersection", MathWorld),
/// `V = pi (R + a - rho)^2 (rho^2 + 2 rho a - 3 a^2 + 2 rho R + 6 a R - 3 R^2) / (12 rho)`.
pub fn sphere_ball_overlap(big_r: f64, rho: f64, a: f64) -> f64 {
    let rho = rho.abs();
    if big_r <= 0.0 || a <= 0.0 || rho >= big_r + a {
        0.0
    } else if rho + a <= big_r {
        4.0 / 3.0 * PI * a.powi(3)
    } else if rho + big_r <= a {
        4.0 / 3.0 * PI * big_r.powi(3)
    } else {
        let r = big_r;
        PI * (r + a - rho).powi(2)
            * (rho * rho + 2.0 * rho * a - 3.0 * a * a + 2.0 * rho * r + 6.0 * a * r - 3.0 * r * r)
            / (12.0 * rho)
    }
}

/// Radial volume-fraction profile around `centre` by sphere–shell overlap: each sphere's
/// volume is shared among the shells `[b dr, (b + 1) dr)` it cuts, by the exact volume of
/// their intersection ([`sphere_ball_overlap`] of the outer minus the inner ball), and each
/// shell's fraction is that volume over the shell's. Unlike centre binning (the centre density
/// times the particle volume, [`radial_profile`]) it is a true local volume fraction, at most 1
/// and smooth where centres are few; the volume beyond `r_max` is not counted.
pub fn overlap_profile(
    pos: &[[f64; 3]],
    diameter: &[f64],
    centre: [f64; 3],
    r_max: f64,
    bins: usize,
) -> Vec<f64> {
    assert!(bins > 0 && r_max > 0.0 && pos.len() == diameter.len());
    let dr = r_max / bins as f64;
    let mut vol = vec![0.0; bins];
    for (x, d) in pos.iter().zip(diameter) {
        let v = [x[0] - centre[0], x[1] - centre[1], x[2] - centre[2]];
        let rho = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let a = 0.5 * d;
        let first = (((rho - a) / dr).floor().max(0.0) as usize).min(bins);
        let last = (((rho + a) / dr).ceil().max(0.0) as usize).min(bins);
        let mut inner = sphere_ball_overlap(first as f64 * dr, rho, a);
        for (b, slot) in vol.iter_mut().enumerate().take(last).skip(first) {
            let outer = sphere_ball_overlap((b + 1) as f64 * dr, rho, a);
            *slot += outer - inner;
            inner = outer;
        }
    }
    vol.iter()
        .enumerate()
        .map(|(b, v)| {
            let (lo, hi) = (b as f64 * dr, (b + 1) as f64 * dr);
            v / (4.0 / 3.0 * PI * (hi.powi(3) - lo.powi(3)))
        })
        .collect()
}

/// Pair distribution function g(r) of a periodic orthorhombic box with edges `l`, on `bins`
/// shells up to `r_max` (at most half the shortest edge). O(N^2), parallel over particles.
pub fn pair_distribution(
    pos: &[[f64; 3]],
    l: [f64; 3],
    r_max: f64,
    bins: usize,
) -> (Vec<f64>, Vec<f64>) {
    let n = pos.len();
    assert!(n >= 2 && bins > 0);
    assert!(
        r_max <= 0.5 * l.iter().cloned().fold(f64::INFINITY, f64::min),
        "r_max must not exceed half the shortest box edge"
    );
    let dr = r_max / bins as f64;
    let hist = (0..n)
        .into_par_iter()
        .fold(
            || vec![0u64; bins],
            |mut h, i| {
                for j in (i + 1)..n {
                    let mut d = [0.0; 3];
                    for k in 0..3 {
                        let x = pos[i][k] - pos[j][k];
                        d[k] = x - l[k] * (x / l[k]).round();
                    }
                    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    let b = (r / dr) as usize;
                    if b < bins {
                        h[b] += 2;
                    }
                }
                h
            },
        )
        .reduce(
            || vec![0u64; bins],
            |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect(),
        );
    let rho = n as f64 / (l[0] * l[1] * l[2]);
    let r = (0..bins).map(|b| (b as f64 + 0.5) * dr).collect();
    let g = hist
        .iter()
        .enumerate()
        .map(|(b, &c)| {
            let (lo, hi) = (b as f64 * dr, (b + 1) as f64 * dr);
            c as f64 / (n as f64 * rho * 4.0 / 3.0 * PI * (hi.powi(3) - lo.powi(3)))
        })
        .collect();
    (r, g)
}

/// Mean-squared displacement at lags `1 .. frames - 1` (in frames), averaged over all time
/// origins and particles, from unwrapped positions.
pub fn mean_squared_displacement(frames: &[Vec<[f64; 3]>]) -> Vec<f64> {
    let f = frames.len();
    (1..f)
        .into_par_iter()
        .map(|lag| {
            let mut s = 0.0;
            let mut c = 0usize;
            for t0 in 0..f - lag {
                let (a, b) = (&frames[t0], &frames[t0 + lag]);
                assert_eq!(
                    a.len(),
                    b.len(),
                    "frames hold different numbers of particles"
                );
                for (x, y) in a.iter().zip(b) {
                    s += (0..3).map(|k| (y[k] - x[k]).powi(2)).sum::<f64>();
                }
                c += a.len();
            }
            s / c as f64
        })
        .collect()
}

/// One frame of a trajectory: step, box edges, unwrapped positions, diameters.
#[derive(Debug, Clone)]
pub struct TrajectoryFrame {
    /// `configuration/step`.
    pub step: u64,
    /// Box edges.
    pub l: [f64; 3],
    /// Unwrapped positions (`position + image * L`).
    pub unwrapped: Vec<[f64; 3]>,
    /// Wrapped positions.
    pub wrapped: Vec<[f64; 3]>,
    /// Diameters.
    pub diameter: Vec<f64>,
}

/// Read every frame of a GSD trajectory (HOOMD schema).
pub fn read_trajectory(path: &Path) -> Result<Vec<TrajectoryFrame>, GsdError> {
    let n = frame_count(path)?;
    (0..n)
        .map(|k| {
            let f = read_frame(path, Some(k))?;
            let p = f.particles;
            Ok(TrajectoryFrame {
                step: f.step,
                l: f.sbox.l,
                unwrapped: p
                    .pos
                    .iter()
                    .zip(&p.image)
                    .map(|(x, i)| f.sbox.unwrap(*x, *i))
                    .collect(),
                wrapped: p.pos,
                diameter: p.diameter,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{overlap_profile, sphere_ball_overlap};

    /// The exact overlap against a quadrature of the sphere's radial density: a shell of radius
    /// r about the origin lies inside the sphere over the fraction (1 - c) / 2 of its area,
    /// c = (r^2 + rho^2 - a^2) / (2 r rho) clipped to [-1, 1].
    #[test]
    fn sphere_ball_overlap_is_the_integral_of_the_radial_density() {
        let numeric = |big_r: f64, rho: f64, a: f64| {
            let n = 20_000;
            let h = big_r / n as f64;
            let f = |r: f64| {
                if r == 0.0 {
                    return 0.0;
                }
                let c = ((r * r + rho * rho - a * a) / (2.0 * r * rho)).clamp(-1.0, 1.0);
                4.0 * std::f64::consts::PI * r * r * 0.5 * (1.0 - c)
            };
            // Composite Simpson.
            (0..=n)
                .map(|i| {
                    let w = if i == 0 || i == n {
                        1.0
                    } else if i % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    };
                    w * f(i as f64 * h)
                })
                .sum::<f64>()
                * h
                / 3.0
        };
        let a = 0.5;
        for (big_r, rho) in [
            (3.0, 2.8),
            (3.0, 3.2),
            (3.0, 2.5),
            (3.0, 3.49),
            (0.3, 0.1),
            (0.3, 0.5),
            (1.0, 0.6),
            (2.0, 0.2),
        ] {
            let exact = sphere_ball_overlap(big_r, rho, a);
            let quad = numeric(big_r, rho, a);
            assert!(
                (exact - quad).abs() < 1e-6 * std::f64::consts::PI / 6.0,
                "R {big_r}, rho {rho}: {exact} vs {quad}"
            );
        }
        let v = std::f64::consts::PI / 6.0;
        assert_eq!(sphere_ball_overlap(3.0, 1.0, a), v);
        assert_eq!(sphere_ball_overlap(3.0, 3.5, a), 0.0);
    }

    /// The overlap profile shares each sphere's whole volume among the shells it cuts, and a
    /// sphere at the centre fills the innermost shell completely (centre binning would read
    /// a volume fraction of (d / 2 dr)^3 there).
    #[test]
    fn overlap_profile_keeps_the_volume_and_stays_below_one() {
        let pos = [
            [0.0, 0.0, 0.0],
            [1.3, 0.4, -0.2],
            [-2.0, 1.1, 0.7],
            [0.0, 0.0, 2.95],
        ];
        let d = [1.0; 4];
        let (r_max, bins) = (4.0, 40);
        let phi = overlap_profile(&pos, &d, [0.0; 3], r_max, bins);
        let dr = r_max / bins as f64;
        let total: f64 = phi
            .iter()
            .enumerate()
            .map(|(b, p)| {
                let (lo, hi) = (b as f64 * dr, (b + 1) as f64 * dr);
                p * 4.0 / 3.0 * std::f64::consts::PI * (hi.powi(3) - lo.powi(3))
            })
            .sum();
        assert!(
            (total - 4.0 * std::f64::consts::PI / 6.0).abs() < 1e-12,
            "{total}"
        );
        assert!((phi[0] - 1.0).abs() < 1e-12, "{}", phi[0]);
        assert!(
            phi.iter().all(|&p| (0.0..=1.0 + 1e-12).contains(&p)),
            "{phi:?}"
        );
    }

    use super::*;
    use colloidsim_core::rng::{Purpose, stream};
    use rand::RngExt;

    fn uniform_cube(n: usize, l: f64, seed: u32) -> Vec<[f64; 3]> {
        let mut rng = stream(seed, 0, Purpose::Initial, 0);
        (0..n)
            .map(|_| {
                [
                    (rng.random::<f64>() - 0.5) * l,
                    (rng.random::<f64>() - 0.5) * l,
                    (rng.random::<f64>() - 0.5) * l,
                ]
            })
            .collect()
    }

    #[test]
    fn uniform_sphere_gives_a_flat_profile() {
        // Points uniform in a cube of side 20, profile up to r = 10: phi = N v / L^3.
        let n = 200_000;
        let pos = uniform_cube(n, 20.0, 1);
        let d = vec![1.0; n];
        let p = radial_profile(&pos, &d, [0.0; 3], 10.0, 10);
        let want = n as f64 * PI / 6.0 / 8000.0;
        for (b, phi) in p.phi.iter().enumerate().skip(1) {
            // Poisson: relative error 1 / sqrt(expected count).
            let count = want / (PI / 6.0) * 4.0 / 3.0 * PI * ((b + 1) as f64).powi(3)
                - want / (PI / 6.0) * 4.0 / 3.0 * PI * (b as f64).powi(3);
            assert!(
                (phi / want - 1.0).abs() < 5.0 / count.sqrt(),
                "bin {b}: {phi} vs {want}"
            );
        }
        assert!(p.outside > 0);
        assert!((p.r[0] - 0.5).abs() < 1e-12);
    }

    #[test]
    fn ideal_gas_g_is_one_and_msd_of_uniform_motion() {
        let n = 3000;
        let pos = uniform_cube(n, 15.0, 2);
        let (r, g) = pair_distribution(&pos, [15.0; 3], 7.5, 15);
        for (ri, gi) in r.iter().zip(&g).skip(2) {
            // Pair counts in a shell: n^2 / 2 * shell / V; relative error 1/sqrt.
            let shell = 4.0 * PI * ri * ri * 0.5;
            let pairs = (n * n) as f64 / 2.0 * shell / 15f64.powi(3);
            assert!((gi - 1.0).abs() < 5.0 / pairs.sqrt(), "g({ri}) = {gi}");
        }
        let frames: Vec<Vec<[f64; 3]>> = (0..5)
            .map(|t| vec![[t as f64, 2.0 * t as f64, 0.0]; 3])
            .collect();
        let msd = mean_squared_displacement(&frames);
        for (k, m) in msd.iter().enumerate() {
            let lag = (k + 1) as f64;
            assert!((m - 5.0 * lag * lag).abs() < 1e-12);
        }
    }
}
