//! Neighbour search: a cell list feeding a full Verlet list with a skin.
//!
//! The list holds, for every particle, all others within `r_cut + skin` (each pair appears
//! twice), so that forces can be summed per particle in parallel without write conflicts and in
//! an order that does not depend on the number of threads. It must be rebuilt when a particle
//! has moved more than half the skin since the last build ([`NeighborList::needs_rebuild`]).
//! The cut-off is the largest over all type pairs, which makes the list valid for mixed
//! diameters.

use crate::state::SimBox;
use rayon::prelude::*;

/// Cell list plus Verlet list, with buffers kept between builds.
#[derive(Debug, Clone)]
pub struct NeighborList {
    /// Interaction cut-off the list serves.
    pub r_cut: f64,
    /// Verlet skin.
    pub skin: f64,
    stride: usize,
    count: Vec<u32>,
    list: Vec<u32>,
    ref_pos: Vec<[f64; 3]>,
    cell_of: Vec<u32>,
    cell_start: Vec<u32>,
    cell_members: Vec<u32>,
    cell_pos: Vec<[f64; 3]>,
    cell_xyz: Vec<[usize; 3]>,
    fill: Vec<u32>,
    n_cells: [usize; 3],
    builds: u64,
}

/// The box is too small for the interaction range.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
#[error(
    "the box edge {edge} is shorter than {minimum}, the least the neighbour range {range} (cut-off + skin) needs"
)]
pub struct BoxTooSmall {
    /// The shortest edge.
    pub edge: f64,
    /// The shortest edge allowed.
    pub minimum: f64,
    /// Cut-off plus skin.
    pub range: f64,
}

impl NeighborList {
    /// An empty list for cut-off `r_cut` and skin `skin`.
    pub fn new(r_cut: f64, skin: f64) -> Self {
        Self {
            r_cut,
            skin,
            stride: 16,
            count: Vec::new(),
            list: Vec::new(),
            ref_pos: Vec::new(),
            cell_of: Vec::new(),
            cell_start: Vec::new(),
            cell_members: Vec::new(),
            cell_pos: Vec::new(),
            cell_xyz: Vec::new(),
            fill: Vec::new(),
            n_cells: [1; 3],
            builds: 0,
        }
    }

    /// Range of the list, `r_cut + skin` (0 without interactions: the list stays empty).
    pub fn range(&self) -> f64 {
        if self.r_cut > 0.0 {
            self.r_cut + self.skin
        } else {
            0.0
        }
    }

    /// Number of builds so far.
    pub fn builds(&self) -> u64 {
        self.builds
    }

    /// Neighbours of particle `i`.
    #[inline(always)]
    pub fn neighbors(&self, i: usize) -> &[u32] {
        let s = i * self.stride;
        &self.list[s..s + self.count[i] as usize]
    }

    /// Positions at the last build.
    pub fn reference_positions(&self) -> &[[f64; 3]] {
        &self.ref_pos
    }

    /// Has any particle moved more than half the skin since the last build (or was the list
    /// never built for this many particles)?
    pub fn needs_rebuild(&self, sbox: &SimBox, pos: &[[f64; 3]]) -> bool {
        if self.ref_pos.len() != pos.len() {
            return true;
        }
        let lim = 0.25 * self.skin * self.skin;
        pos.par_iter().zip(self.ref_pos.par_iter()).any(|(p, q)| {
            let d = sbox.min_image([p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
            d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > lim
        })
    }

    /// [`Self::needs_rebuild`] in a Lees–Edwards box whose offset is now `offset` and has moved
    /// by `moved` (unwrapped) since the last build: true when `2 max|displacement| + moved`
    /// exceeds the skin (the separation of a pair across the y boundary changes by the two
    /// displacements plus the change of the offset), the displacements measured with
    /// [`SimBox::min_image_sheared`].
    pub fn needs_rebuild_sheared(
        &self,
        sbox: &SimBox,
        pos: &[[f64; 3]],
        offset: f64,
        moved: f64,
    ) -> bool {
        if self.ref_pos.len() != pos.len() {
            return true;
        }
        let half = 0.5 * (self.skin - moved);
        if half <= 0.0 {
            return true;
        }
        let lim = half * half;
        pos.par_iter().zip(self.ref_pos.par_iter()).any(|(p, q)| {
            let d = sbox
                .min_image_sheared([p[0] - q[0], p[1] - q[1], p[2] - q[2]], offset)
                .0;
            d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > lim
        })
    }

    /// Squared displacement of `p` from particle `i`'s reference position.
    #[inline(always)]
    pub fn displacement2(&self, sbox: &SimBox, i: usize, p: [f64; 3]) -> f64 {
        let q = self.ref_pos[i];
        let d = sbox.min_image([p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    }

    /// Build the list for wrapped positions `pos`; each particle's neighbours are listed in
    /// increasing `key` (e.g. the particles' tags), so that sums over them have an order that
    /// does not depend on how particles are stored or when the list was built.
    pub fn build(
        &mut self,
        sbox: &SimBox,
        pos: &[[f64; 3]],
        key: &[u32],
    ) -> Result<(), BoxTooSmall> {
        self.build_with(sbox, pos, key, None)
    }

    /// [`Self::build`] in a Lees–Edwards box: the image of the box above (`y + L_y`) displaced
    /// by `offset` along x. Separations are [`SimBox::min_image_sheared`]; a row of cells
    /// across the y boundary is scanned whole (its members' images are shifted along x).
    pub fn build_sheared(
        &mut self,
        sbox: &SimBox,
        pos: &[[f64; 3]],
        key: &[u32],
        offset: f64,
    ) -> Result<(), BoxTooSmall> {
        self.build_with(sbox, pos, key, Some(offset))
    }

    fn build_with(
        &mut self,
        sbox: &SimBox,
        pos: &[[f64; 3]],
        key: &[u32],
        shear: Option<f64>,
    ) -> Result<(), BoxTooSmall> {
        let n = pos.len();
        let range = self.range();
        let edge = sbox.l.iter().cloned().fold(f64::INFINITY, f64::min);
        if range > 0.0 && edge < 2.0 * range {
            return Err(BoxTooSmall {
                edge,
                minimum: 2.0 * range,
                range,
            });
        }
        self.builds += 1;
        self.ref_pos.clear();
        self.ref_pos.extend_from_slice(pos);
        self.count.resize(n, 0);
        if range <= 0.0 {
            self.count.iter_mut().for_each(|c| *c = 0);
            self.list.resize(n * self.stride, 0);
            return Ok(());
        }

        self.bin(sbox, pos);
        let r2max = range * range;
        loop {
            let stride = self.stride;
            self.list.resize(n * stride, 0);
            let cells = &self.cell_start;
            let members = &self.cell_members;
            let cpos = &self.cell_pos;
            let cell_xyz = &self.cell_xyz;
            let [nx, ny, nz] = self.n_cells;
            let overflow = self
                .list
                .par_chunks_mut(stride)
                .zip(self.count.par_iter_mut())
                .enumerate()
                .with_min_len(256)
                .map(|(i, (slot, cnt))| {
                    let p = pos[i];
                    let [cx, cy, cz] = cell_xyz[i];
                    let mut m = 0usize;
                    if nx >= 3 && ny >= 3 && nz >= 3 && shear.is_none() {
                        // Every neighbour cell is a distinct cell next to particle i's, so the
                        // periodic image of each run is known in advance: `d = (p - q) + s`
                        // with the run's shift `s` in {-L, 0, +L} per axis, the value
                        // `min_image` gives for every pair within range.
                        let l = sbox.l;
                        let shift = |u: usize, c: usize, n: usize, l: f64| -> (usize, f64) {
                            // Neighbour index c + u - 1 (u = 0, 1, 2), wrapped.
                            if c + u == 0 {
                                (n - 1, l)
                            } else if c + u > n {
                                (0, -l)
                            } else {
                                (c + u - 1, 0.0)
                            }
                        };
                        for a in 0..3 {
                            let (z, sz) = shift(a, cz, nz, l[2]);
                            for b in 0..3 {
                                let (y, sy) = shift(b, cy, ny, l[1]);
                                let row = (z * ny + y) * nx;
                                let mut run = |first: usize, last: usize, sx: f64| {
                                    scan_run(
                                        p,
                                        i,
                                        [sx, sy, sz],
                                        &cpos[cells[first] as usize..cells[last + 1] as usize],
                                        &members[cells[first] as usize..cells[last + 1] as usize],
                                        r2max,
                                        slot,
                                        &mut m,
                                    )
                                };
                                if cx == 0 {
                                    run(row, row + 1, 0.0);
                                    run(row + nx - 1, row + nx - 1, l[0]);
                                } else if cx == nx - 1 {
                                    run(row, row, -l[0]);
                                    run(row + nx - 2, row + nx - 1, 0.0);
                                } else {
                                    run(row + cx - 1, row + cx + 1, 0.0);
                                }
                            }
                        }
                    } else {
                        // Members of cells first..=last (consecutive along x).
                        let mut scan = |first: usize, last: usize| {
                            for k in cells[first] as usize..cells[last + 1] as usize {
                                let q = cpos[k];
                                let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
                                let d = match shear {
                                    None => sbox.min_image(d),
                                    Some(offset) => sbox.min_image_sheared(d, offset).0,
                                };
                                let j = members[k];
                                let hit = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r2max)
                                    & (j as usize != i);
                                // Branch-free append; overflow is detected through `m`.
                                slot[m.min(stride - 1)] = j;
                                m += hit as usize;
                            }
                        };
                        let (z_lo, z_n) = if nz >= 3 { (cz + nz - 1, 3) } else { (0, 1) };
                        let (y_lo, y_n) = if ny >= 3 { (cy + ny - 1, 3) } else { (0, 1) };
                        for a in 0..z_n {
                            let z = wrap_index(z_lo + a, nz);
                            for b in 0..y_n {
                                let y = wrap_index(y_lo + b, ny);
                                let row = (z * ny + y) * nx;
                                // Under shear a row across the y boundary (or the only row)
                                // holds images shifted along x: all of it.
                                let across = y_n == 1 || cy + b == 0 || cy + b > ny;
                                // The 3 (or 1) cells along x as runs of consecutive cells; a
                                // run that would wrap around the boundary is split in two.
                                if nx < 3 || (shear.is_some() && across) {
                                    scan(row, row + nx - 1);
                                } else if cx == 0 {
                                    scan(row, row + 1);
                                    scan(row + nx - 1, row + nx - 1);
                                } else if cx == nx - 1 {
                                    scan(row, row);
                                    scan(row + nx - 2, row + nx - 1);
                                } else {
                                    scan(row + cx - 1, row + cx + 1);
                                }
                            }
                        }
                    }
                    *cnt = m.min(stride) as u32;
                    if m < stride {
                        slot[..m].sort_unstable_by_key(|&j| key[j as usize]);
                    }
                    m
                })
                .max()
                .unwrap_or(0);
            // Every candidate, hit or not, is written at the slot after the last hit: a row is
            // whole only with that slot to spare (a full row may have lost its last hit).
            if overflow < self.stride {
                return Ok(());
            }
            self.stride = overflow + overflow / 4 + 4;
        }
    }

    /// Sort particles into cells (of side at least `r_cut + skin`) and return the particle
    /// indices in cell order, each cell's members in increasing index. Engines reorder their
    /// particles by this permutation so that neighbours lie close in memory.
    pub fn bin(&mut self, sbox: &SimBox, pos: &[[f64; 3]]) -> &[u32] {
        let n = pos.len();
        let range = self.range().max(1e-300);
        // Cells at least `range` wide; fewer than 3 along an axis means one cell there.
        // Never more than about 4 cells per particle (larger cells stay valid).
        let cap = ((4 * n.max(1)) as f64).cbrt().ceil().max(3.0);
        let mut n_cells = [1usize; 3];
        for k in 0..3 {
            let m = (sbox.l[k] / range).floor().min(cap) as usize;
            n_cells[k] = if m >= 3 { m } else { 1 };
        }
        self.n_cells = n_cells;
        let [nx, ny, nz] = self.n_cells;
        let total = nx * ny * nz;
        let scale = [
            nx as f64 / sbox.l[0],
            ny as f64 / sbox.l[1],
            nz as f64 / sbox.l[2],
        ];
        let half = [0.5 * sbox.l[0], 0.5 * sbox.l[1], 0.5 * sbox.l[2]];
        self.cell_of.resize(n, 0);
        self.cell_xyz.resize(n, [0; 3]);
        for ((c, xyz), p) in self
            .cell_of
            .iter_mut()
            .zip(self.cell_xyz.iter_mut())
            .zip(pos)
        {
            let cx = (((p[0] + half[0]) * scale[0]).max(0.0) as usize).min(nx - 1);
            let cy = (((p[1] + half[1]) * scale[1]).max(0.0) as usize).min(ny - 1);
            let cz = (((p[2] + half[2]) * scale[2]).max(0.0) as usize).min(nz - 1);
            *xyz = [cx, cy, cz];
            *c = ((cz * ny + cy) * nx + cx) as u32;
        }
        // Counting sort: members of each cell in increasing particle index, with their
        // positions copied alongside for locality.
        self.cell_start.clear();
        self.cell_start.resize(total + 1, 0);
        for &c in &self.cell_of {
            self.cell_start[c as usize + 1] += 1;
        }
        for c in 0..total {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.cell_members.resize(n, 0);
        self.cell_pos.resize(n, [0.0; 3]);
        self.fill.clear();
        self.fill.extend_from_slice(&self.cell_start[..total]);
        for (i, &c) in self.cell_of.iter().enumerate() {
            let k = self.fill[c as usize] as usize;
            self.cell_members[k] = i as u32;
            self.cell_pos[k] = pos[i];
            self.fill[c as usize] += 1;
        }

        &self.cell_members
    }
}

/// Append to `slot` (branch-free; overflow shows in `m` exceeding its length) the members of
/// one run of cells whose shifted separation from `p`, `(p - q) + shift`, is within range.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn scan_run(
    p: [f64; 3],
    i: usize,
    shift: [f64; 3],
    cpos: &[[f64; 3]],
    members: &[u32],
    r2max: f64,
    slot: &mut [u32],
    m: &mut usize,
) {
    let last = slot.len() - 1;
    let mut k = *m;
    for (q, &j) in cpos.iter().zip(members) {
        let d = [
            (p[0] - q[0]) + shift[0],
            (p[1] - q[1]) + shift[1],
            (p[2] - q[2]) + shift[2],
        ];
        let hit = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r2max) & (j as usize != i);
        slot[k.min(last)] = j;
        k += hit as usize;
    }
    *m = k;
}

/// `i mod n` for `i < 3 n` without a division.
#[inline(always)]
fn wrap_index(mut i: usize, n: usize) -> usize {
    if i >= n {
        i -= n;
    }
    if i >= n {
        i -= n;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use colloidsim_core::rng::{Purpose, stream};
    use rand::RngExt;

    /// Spheres with exactly as many neighbours as the list's first width (16) keep all of
    /// them: the branch-free append writes every candidate, hit or not, at the slot after the
    /// last hit, so the last slot is scratch and a full row must grow the list (found as a
    /// sphere listed as its own neighbour, a NaN force, in a compressed droplet).
    #[test]
    fn a_row_filled_to_the_list_width_keeps_every_neighbour() {
        // Sphere 0 at the origin, 16 on a sphere of radius 0.5 around it (all 16 apart by at
        // most 1: each has 16 neighbours within range 1), a 17th beyond range of all, scanned
        // last (one cell: the box is under 3 ranges).
        let mut pos = vec![[0.0; 3]];
        for k in 0..16 {
            let z = -0.9 + 1.8 * k as f64 / 15.0;
            let a = 2.4 * k as f64;
            let r = (1.0 - z * z).sqrt();
            pos.push([0.5 * r * a.cos(), 0.5 * r * a.sin(), 0.5 * z]);
        }
        pos.push([1.2, 1.2, 1.2]);
        let sbox = SimBox::cube(2.5);
        let key: Vec<u32> = (0..pos.len() as u32).collect();
        let mut nl = NeighborList::new(1.0, 0.0);
        nl.build(&sbox, &pos, &key).unwrap();
        for i in 0..pos.len() {
            let want: Vec<u32> = (0..pos.len() as u32)
                .filter(|&j| {
                    let (p, q) = (pos[i], pos[j as usize]);
                    let d = sbox.min_image([p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
                    j as usize != i && d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < 1.0
                })
                .collect();
            assert_eq!(nl.neighbors(i), &want[..], "sphere {i}");
        }
        assert_eq!(nl.neighbors(0).len(), 16);
    }

    #[test]
    fn matches_brute_force_including_periodic_images() {
        // 3 x 4 x 3 cells (the shifted-run path) and 3 x 1 x 3 (one cell along y).
        for l in [[7.0, 9.5, 6.2], [7.0, 4.5, 6.2]] {
            check_against_brute_force(SimBox::new(l));
        }
    }

    fn check_against_brute_force(sbox: SimBox) {
        let mut rng = stream(5, 0, Purpose::Initial, 0);
        let pos: Vec<[f64; 3]> = (0..600)
            .map(|_| {
                let u: [f64; 3] = [rng.random(), rng.random(), rng.random()];
                [
                    (u[0] - 0.5) * sbox.l[0],
                    (u[1] - 0.5) * sbox.l[1],
                    (u[2] - 0.5) * sbox.l[2],
                ]
            })
            .collect();
        let mut nl = NeighborList::new(1.5, 0.4);
        let key: Vec<u32> = (0..pos.len() as u32).collect();
        nl.build(&sbox, &pos, &key).unwrap();
        let r2 = 1.9f64 * 1.9;
        for i in 0..pos.len() {
            let got: Vec<u32> = nl.neighbors(i).to_vec();
            let want: Vec<u32> = (0..pos.len() as u32)
                .filter(|&j| {
                    let (p, q) = (pos[i], pos[j as usize]);
                    let d = sbox.min_image([p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
                    j as usize != i && d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r2
                })
                .collect();
            assert_eq!(got, want, "particle {i}");
        }
        assert!(!nl.needs_rebuild(&sbox, &pos));
        let mut moved = pos.clone();
        moved[17][0] += 0.21;
        assert!(nl.needs_rebuild(&sbox, &moved));
        // A box shorter than twice the range is refused.
        assert!(
            NeighborList::new(1.5, 0.4)
                .build(&SimBox::cube(3.0), &pos, &key)
                .is_err()
        );
    }
}
