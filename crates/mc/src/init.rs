//! Starting configurations: face-centred cubic lattice sites, which the warm-up melts.
//!
//! A lattice reaches any volume fraction below close packing (0.74) without overlaps, where
//! random insertion stalls near 0.3.

use crate::engine::McError;
use colloidsim_core::ParamError;
use colloidsim_core::param::show;

/// The four sites of the FCC unit cell, in units of the cubic lattice constant.
const BASIS: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [0.5, 0.5, 0.0],
    [0.5, 0.0, 0.5],
    [0.0, 0.5, 0.5],
];

/// `n` spheres of diameter `d` on FCC sites filling the periodic cube of edge `edge` (centred on
/// the origin): `4 m^3` sites with `m = ceil((n/4)^(1/3))`, `n` of them taken evenly spread
/// through the site list. Error (parameter `n`) when the nearest-neighbour
/// distance `edge / (m sqrt 2)` is below `d`.
pub fn fcc_in_box(n: usize, d: f64, edge: f64) -> Result<Vec<[f64; 3]>, McError> {
    let m = ((n as f64 / 4.0).cbrt().ceil() as usize).max(1);
    let a = edge / m as f64;
    if a / 2f64.sqrt() < d {
        return Err(ParamError::new(
            "n",
            format!(
                "{n} spheres do not fit on an FCC lattice in a box of edge {} (neighbour distance {} < d = {})",
                show(edge),
                show(a / 2f64.sqrt()),
                show(d)
            ),
        )
        .into());
    }
    let sites = 4 * m * m * m;
    Ok((0..n)
        .map(|k| {
            let s = k * sites / n.max(1);
            let (b, cell) = (s % 4, s / 4);
            let c = [cell % m, (cell / m) % m, cell / (m * m)];
            std::array::from_fn(|i| (c[i] as f64 + BASIS[b][i] + 0.25) * a - 0.5 * edge)
        })
        .collect())
}

/// FCC sites of nearest-neighbour distance `spacing` within `radius` of the origin, nearest
/// first.
fn sphere_sites(spacing: f64, radius: f64) -> Vec<[f64; 3]> {
    let a = spacing * 2f64.sqrt();
    let m = (radius / a).ceil() as i64 + 1;
    let mut sites = Vec::new();
    for i in -m..=m {
        for j in -m..=m {
            for k in -m..=m {
                for b in BASIS {
                    let p = [
                        (i as f64 + b[0]) * a,
                        (j as f64 + b[1]) * a,
                        (k as f64 + b[2]) * a,
                    ];
                    if p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= radius * radius {
                        sites.push(p);
                    }
                }
            }
        }
    }
    let r2 = |p: &[f64; 3]| p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    sites.sort_by(|p, q| r2(p).total_cmp(&r2(q)));
    sites
}

/// `n` spheres of diameter `d` with centres within `radius` of the origin, on the FCC lattice
/// of the largest neighbour distance (>= d, found by bisection) that still has `n` sites in the
/// ball; the `n` innermost sites are taken. Error (key `system.volume_fraction`) when even the
/// close-packed lattice has fewer than `n` sites there.
pub fn fcc_in_sphere(n: usize, d: f64, radius: f64) -> Result<Vec<[f64; 3]>, McError> {
    let count = |b: f64| sphere_sites(b, radius).len();
    let tight = d * (1.0 + 1e-9);
    if count(tight) < n {
        return Err(ParamError::new(
            "n",
            format!(
                "{n} spheres of diameter {} do not fit on an FCC lattice with centres within {}",
                show(d),
                show(radius)
            ),
        )
        .into());
    }
    let (mut lo, mut hi) = (tight, tight.max(2.0 * radius));
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if count(mid) >= n {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let mut sites = sphere_sites(lo, radius);
    sites.truncate(n);
    Ok(sites)
}

/// `positions` in a random order (Fisher–Yates on the stream `(seed, 0, Initial, 0)`): lattice
/// sites come out sorted (by plane, or innermost first), and a particle's index would otherwise
/// remember where it started long after the lattice has melted.
pub fn shuffled(mut positions: Vec<[f64; 3]>, seed: u32) -> Vec<[f64; 3]> {
    use colloidsim_core::rng::{Purpose, stream};
    use rand::Rng;
    let mut rng = stream(seed, 0, Purpose::Initial, 0);
    for i in (1..positions.len()).rev() {
        let j = ((rng.next_u64() as u128 * (i as u128 + 1)) >> 64) as usize;
        positions.swap(i, j);
    }
    positions
}
