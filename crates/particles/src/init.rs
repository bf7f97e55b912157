//! Initial configurations: random non-overlapping hard spheres (random sequential insertion)
//! in a sphere or in a periodic box.

use crate::state::SimBox;
use colloidsim_core::rng::{Purpose, stream};
use rand::RngExt;

/// Random insertion failed: the volume fraction is too high to pack this way.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
#[error(
    "could place only {placed} of {wanted} non-overlapping spheres after {attempts} random attempts \
     (volume fraction {phi:.4} is too high for random insertion; at most about 0.3 is reachable)"
)]
pub struct PackingError {
    /// Spheres placed.
    pub placed: usize,
    /// Spheres wanted.
    pub wanted: usize,
    /// Attempts made.
    pub attempts: u64,
    /// Requested volume fraction.
    pub phi: f64,
}

/// Uniform grid of cells of side >= d for overlap checks.
struct Grid {
    origin: [f64; 3],
    cell: [f64; 3],
    n: [usize; 3],
    periodic: Option<SimBox>,
    members: Vec<Vec<u32>>,
}

impl Grid {
    fn new(
        origin: [f64; 3],
        extent: [f64; 3],
        d: f64,
        periodic: Option<SimBox>,
        particles: usize,
    ) -> Self {
        // Cells at least d wide, and never more than about two per particle.
        let cap = ((2 * particles.max(1)) as f64).cbrt().ceil().max(1.0);
        let mut n = [1; 3];
        let mut cell = [0.0; 3];
        for k in 0..3 {
            n[k] = ((extent[k] / d).floor().min(cap) as usize).max(1);
            cell[k] = extent[k] / n[k] as f64;
        }
        Self {
            origin,
            cell,
            n,
            periodic,
            members: vec![Vec::new(); n[0] * n[1] * n[2]],
        }
    }

    fn coords(&self, p: [f64; 3]) -> [i64; 3] {
        let mut c = [0; 3];
        for k in 0..3 {
            c[k] = (((p[k] - self.origin[k]) / self.cell[k]).floor() as i64)
                .clamp(0, self.n[k] as i64 - 1);
        }
        c
    }

    fn index(&self, c: [i64; 3]) -> Option<usize> {
        let mut w = [0usize; 3];
        for k in 0..3 {
            let n = self.n[k] as i64;
            w[k] = if self.periodic.is_some() {
                c[k].rem_euclid(n) as usize
            } else if c[k] < 0 || c[k] >= n {
                return None;
            } else {
                c[k] as usize
            };
        }
        Some((w[2] * self.n[1] + w[1]) * self.n[0] + w[0])
    }

    /// Does a sphere of diameter `dp` at `p` overlap a placed one (contact at the pair's mean
    /// diameter)?
    fn overlaps(&self, p: [f64; 3], dp: f64, pos: &[[f64; 3]], diameters: &[f64]) -> bool {
        let c = self.coords(p);
        let mut seen = [usize::MAX; 27];
        let mut ns = 0;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let Some(ci) = self.index([c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    // Small periodic grids visit a cell more than once.
                    if seen[..ns].contains(&ci) {
                        continue;
                    }
                    seen[ns] = ci;
                    ns += 1;
                    for &j in &self.members[ci] {
                        let q = pos[j as usize];
                        let contact = 0.5 * (dp + diameters[j as usize]);
                        let mut v = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
                        if let Some(b) = &self.periodic {
                            v = b.min_image(v);
                        }
                        if v[0] * v[0] + v[1] * v[1] + v[2] * v[2] < contact * contact {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }

    fn insert(&mut self, p: [f64; 3], i: u32) {
        let ci = self.index(self.coords(p)).expect("inside the grid");
        self.members[ci].push(i);
    }
}

/// Random sequential insertion of spheres of diameters `diameters` (largest first, ties in
/// index order), `propose(uniform, k)` giving a trial centre for sphere `k`; the result is in
/// index order.
fn insert_all(
    diameters: &[f64],
    phi: f64,
    mut grid: Grid,
    seed: u32,
    stream_index: u64,
    mut propose: impl FnMut(&mut dyn FnMut() -> f64, usize) -> [f64; 3],
) -> Result<Vec<[f64; 3]>, PackingError> {
    let n = diameters.len();
    let mut rng = stream(seed, 0, Purpose::Initial, stream_index);
    let mut uniform = move || rng.random::<f64>();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| diameters[b].total_cmp(&diameters[a]).then(a.cmp(&b)));
    // Placed spheres in insertion order, and their diameters.
    let mut pos: Vec<[f64; 3]> = Vec::with_capacity(n);
    let mut placed_d: Vec<f64> = Vec::with_capacity(n);
    let max_attempts = 2000 * n as u64 + 100_000;
    let mut attempts = 0;
    while pos.len() < n {
        if attempts >= max_attempts {
            return Err(PackingError {
                placed: pos.len(),
                wanted: n,
                attempts,
                phi,
            });
        }
        attempts += 1;
        let k = order[pos.len()];
        let p = propose(&mut uniform, k);
        if !grid.overlaps(p, diameters[k], &pos, &placed_d) {
            grid.insert(p, pos.len() as u32);
            pos.push(p);
            placed_d.push(diameters[k]);
        }
    }
    let mut out = vec![[0.0; 3]; n];
    for (slot, &k) in order.iter().enumerate() {
        out[k] = pos[slot];
    }
    Ok(out)
}

/// `n` non-overlapping spheres of diameter `d` with centres uniform in the ball of radius
/// `centre_radius` around `centre`. Deterministic in (`seed`, `stream_index`).
pub fn random_in_sphere(
    n: usize,
    d: f64,
    centre: [f64; 3],
    centre_radius: f64,
    seed: u32,
    stream_index: u64,
) -> Result<Vec<[f64; 3]>, PackingError> {
    random_mixture_in_sphere(&vec![d; n], centre, centre_radius, seed, stream_index)
}

/// Non-overlapping spheres of diameters `diameters` (contact at the pair's mean diameter) in a
/// sphere: the centres of the smallest lie uniformly within `centre_radius` of `centre`, those
/// of a sphere of diameter `d` within `centre_radius - (d - d_min) / 2` (every surface within
/// the same ball). Deterministic in (`seed`, `stream_index`); one size is
/// [`random_in_sphere`].
pub fn random_mixture_in_sphere(
    diameters: &[f64],
    centre: [f64; 3],
    centre_radius: f64,
    seed: u32,
    stream_index: u64,
) -> Result<Vec<[f64; 3]>, PackingError> {
    let d_min = diameters.iter().copied().fold(f64::INFINITY, f64::min);
    let d_max = diameters.iter().copied().fold(0.0, f64::max);
    let r = centre_radius;
    let phi = diameters.iter().map(|d| (d / 2.0).powi(3)).sum::<f64>() / (r + d_min / 2.0).powi(3);
    let origin = [centre[0] - r, centre[1] - r, centre[2] - r];
    let grid = Grid::new(origin, [2.0 * r; 3], d_max, None, diameters.len());
    insert_all(diameters, phi, grid, seed, stream_index, |u, k| {
        let rk = r - 0.5 * (diameters[k] - d_min);
        loop {
            let v = [2.0 * u() - 1.0, 2.0 * u() - 1.0, 2.0 * u() - 1.0];
            if v[0] * v[0] + v[1] * v[1] + v[2] * v[2] <= 1.0 {
                return [
                    centre[0] + rk * v[0],
                    centre[1] + rk * v[1],
                    centre[2] + rk * v[2],
                ];
            }
        }
    })
}

/// `n` non-overlapping spheres of diameter `d` uniform in the periodic box.
pub fn random_in_box(
    n: usize,
    d: f64,
    sbox: &SimBox,
    seed: u32,
    stream_index: u64,
) -> Result<Vec<[f64; 3]>, PackingError> {
    random_mixture_in_box(&vec![d; n], sbox, seed, stream_index)
}

/// Non-overlapping spheres of diameters `diameters` uniform in the periodic box (one size:
/// [`random_in_box`]).
pub fn random_mixture_in_box(
    diameters: &[f64],
    sbox: &SimBox,
    seed: u32,
    stream_index: u64,
) -> Result<Vec<[f64; 3]>, PackingError> {
    let phi = diameters
        .iter()
        .map(|d| std::f64::consts::PI * d.powi(3) / 6.0)
        .sum::<f64>()
        / sbox.volume();
    let d_max = diameters.iter().copied().fold(0.0, f64::max);
    let l = sbox.l;
    let grid = Grid::new(
        [-0.5 * l[0], -0.5 * l[1], -0.5 * l[2]],
        l,
        d_max,
        Some(*sbox),
        diameters.len(),
    );
    insert_all(diameters, phi, grid, seed, stream_index, |u, _| {
        [(u() - 0.5) * l[0], (u() - 0.5) * l[1], (u() - 0.5) * l[2]]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn min_distance(pos: &[[f64; 3]], sbox: Option<&SimBox>) -> f64 {
        let mut m = f64::INFINITY;
        for i in 0..pos.len() {
            for j in 0..i {
                let mut v = [
                    pos[i][0] - pos[j][0],
                    pos[i][1] - pos[j][1],
                    pos[i][2] - pos[j][2],
                ];
                if let Some(b) = sbox {
                    v = b.min_image(v);
                }
                m = m.min((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt());
            }
        }
        m
    }

    #[test]
    fn sphere_packing_to_phi_0_3_has_no_overlaps() {
        // phi0 = N d^3 / (8 R^3) = 0.3 with R = 8: N = 1229; centres within R - d/2.
        let n = 1229;
        let pos = random_in_sphere(n, 1.0, [0.0; 3], 7.5, 4, 0).unwrap();
        assert_eq!(pos.len(), n);
        assert!(min_distance(&pos, None) >= 1.0);
        assert!(
            pos.iter()
                .all(|p| p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= 7.5 * 7.5)
        );
        assert_eq!(pos, random_in_sphere(n, 1.0, [0.0; 3], 7.5, 4, 0).unwrap());
    }

    #[test]
    fn box_packing_to_phi_0_3_and_refusal_beyond_jamming() {
        let sbox = SimBox::cube(12.0);
        let n = (0.3 * 12f64.powi(3) / (std::f64::consts::PI / 6.0)) as usize;
        let pos = random_in_box(n, 1.0, &sbox, 9, 0).unwrap();
        assert!(min_distance(&pos, Some(&sbox)) >= 1.0);
        let sbox = SimBox::cube(5.0);
        let n = (0.5 * 125.0 / (std::f64::consts::PI / 6.0)) as usize;
        let e = random_in_box(n, 1.0, &sbox, 9, 0).unwrap_err();
        assert!(e.placed < n && e.to_string().contains("too high"));
    }

    #[test]
    fn mixtures_keep_every_pair_at_its_mean_diameter_and_every_surface_inside() {
        // 400 small (d = 1) and 50 large (d = 2) spheres: phi = 0.2 in a ball of radius 7.
        let mut d = vec![1.0; 400];
        d.extend(vec![2.0; 50]);
        let pos = random_mixture_in_sphere(&d, [0.0; 3], 6.5, 3, 0).unwrap();
        for i in 0..pos.len() {
            let ri = (pos[i][0].powi(2) + pos[i][1].powi(2) + pos[i][2].powi(2)).sqrt();
            assert!(ri + 0.5 * d[i] <= 7.0 + 1e-12, "sphere {i} pokes out");
            for j in 0..i {
                let r = ((pos[i][0] - pos[j][0]).powi(2)
                    + (pos[i][1] - pos[j][1]).powi(2)
                    + (pos[i][2] - pos[j][2]).powi(2))
                .sqrt();
                assert!(r >= 0.5 * (d[i] + d[j]), "{i} {j} at {r}");
            }
        }
        let sbox = SimBox::cube(12.0);
        let pos = random_mixture_in_box(&d, &sbox, 3, 0).unwrap();
        for i in 0..pos.len() {
            for j in 0..i {
                let v = sbox.min_image([
                    pos[i][0] - pos[j][0],
                    pos[i][1] - pos[j][1],
                    pos[i][2] - pos[j][2],
                ]);
                assert!((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt() >= 0.5 * (d[i] + d[j]));
            }
        }
    }
}
