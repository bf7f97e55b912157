//! Particles sorted into cells, and the half stencil of cells: the neighbour search shared by
//! the Brownian ([`crate::brownian`]) and DPD ([`crate::dpd`]) engines.
//!
//! Cells are at least the neighbour range wide and numbered z-major (`(cz ny + cy) nx + cx`),
//! so that the particles of one z-layer of cells (a *slab*) are contiguous after sorting. The
//! half stencil reaches only the own and the next z-layer: every pair is met once, and a slab's
//! pairs touch only itself and the next slab. Engines exploit that to sum forces per slab into
//! the slab's own buffer plus a halo for the next slab, bitwise independent of the threads.

use crate::state::SimBox;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// Counting sort of particles into cells, with buffers kept between sorts.
#[derive(Debug, Default)]
pub(crate) struct CellSort {
    /// Cells per axis.
    pub n_cells: [usize; 3],
    /// Members of cell `c` are slots `cell_start[c]..cell_start[c + 1]` of the sorted order.
    pub cell_start: Vec<u32>,
    /// `perm[k]`: the old index of the particle that goes to slot `k`.
    pub perm: Vec<u32>,
    cell_key: Vec<u32>,
    cell_count: Vec<AtomicU32>,
    slot: Vec<AtomicU32>,
}

impl CellSort {
    /// Cells per axis for a neighbour range `range` (`floor(L / range)` per axis).
    pub fn cells_for(sbox: &SimBox, range: f64) -> [usize; 3] {
        let mut nc = [1usize; 3];
        for k in 0..3 {
            nc[k] = ((sbox.l[k] / range).floor() as usize).max(1);
        }
        nc
    }

    /// The cell (`0 ..< n`) of a wrapped coordinate `x` along an axis of length `l` cut into
    /// `n` cells; the one formula of every sort, so that domains of a decomposed run agree on
    /// which layer a particle is in.
    #[inline(always)]
    pub fn cell_coordinate(x: f64, l: f64, n: usize) -> usize {
        let scale = n as f64 / l;
        (((x + 0.5 * l) * scale).max(0.0) as usize).min(n - 1)
    }

    /// The cells `c0..c1` of an axis of length `l` cut into `n`, as a test on coordinates
    /// that agrees with [`Self::cell_coordinate`] (see [`CellRange::contains`]).
    pub fn range(l: f64, n: usize, c0: usize, c1: usize) -> CellRange {
        let w = l / n as f64;
        // Far above the round-off of `cell_coordinate` (1e-16 of a cell), far below a cell.
        let eps = 1e-9 * w;
        let edge = |c: usize| c as f64 * w - 0.5 * l;
        CellRange {
            lo: if c0 == 0 { f64::NEG_INFINITY } else { edge(c0) },
            hi: if c1 >= n { f64::INFINITY } else { edge(c1) },
            eps,
            l,
            n,
            c0,
            c1,
        }
    }

    /// Sort wrapped positions `pos` into cells at least `range` wide (z-major; inside a cell by
    /// increasing `tie`, so that the order is a function of the positions and ties alone, not of
    /// the threads). Fills [`Self::perm`] and [`Self::cell_start`] (in the new order).
    pub fn sort(&mut self, sbox: &SimBox, pos: &[[f64; 3]], tie: &[u32], range: f64) {
        let n = pos.len();
        let l = sbox.l;
        let nc = Self::cells_for(sbox, range);
        self.n_cells = nc;
        let [nx, ny, nz] = nc;
        let total = nx * ny * nz;
        self.cell_key.resize(n, 0);
        self.cell_key
            .par_iter_mut()
            .zip(pos.par_iter())
            .with_min_len(4096)
            .for_each(|(c, x)| {
                let cx = Self::cell_coordinate(x[0], l[0], nx);
                let cy = Self::cell_coordinate(x[1], l[1], ny);
                let cz = Self::cell_coordinate(x[2], l[2], nz);
                *c = ((cz * ny + cy) * nx + cx) as u32;
            });
        // Parallel counting sort: counts and scatter with atomics (the order inside a cell is
        // then arbitrary), then every cell ordered by `tie`.
        self.cell_count.resize_with(total, || AtomicU32::new(0));
        self.cell_count
            .par_iter()
            .with_min_len(4096)
            .for_each(|c| c.store(0, Relaxed));
        {
            let count = &self.cell_count;
            self.cell_key.par_iter().with_min_len(4096).for_each(|&c| {
                count[c as usize].fetch_add(1, Relaxed);
            });
        }
        self.cell_start.clear();
        self.cell_start.resize(total + 1, 0);
        for c in 0..total {
            self.cell_start[c + 1] = self.cell_start[c] + self.cell_count[c].load(Relaxed);
        }
        {
            let starts = &self.cell_start;
            self.cell_count
                .par_iter()
                .enumerate()
                .with_min_len(4096)
                .for_each(|(c, f)| f.store(starts[c], Relaxed));
        }
        self.slot.resize_with(n, || AtomicU32::new(0));
        {
            let fill = &self.cell_count;
            let slot = &self.slot;
            self.cell_key
                .par_iter()
                .enumerate()
                .with_min_len(4096)
                .for_each(|(i, &c)| {
                    let k = fill[c as usize].fetch_add(1, Relaxed);
                    slot[k as usize].store(i as u32, Relaxed);
                });
        }
        {
            let starts = &self.cell_start;
            let slot = &self.slot;
            (0..total).into_par_iter().with_min_len(256).for_each(|c| {
                let (a, b) = (starts[c] as usize, starts[c + 1] as usize);
                let mut local = [0u32; 32];
                if b - a <= local.len() {
                    let cell = &mut local[..b - a];
                    for (k, x) in cell.iter_mut().enumerate() {
                        *x = slot[a + k].load(Relaxed);
                    }
                    cell.sort_unstable_by_key(|&i| tie[i as usize]);
                    for (k, x) in cell.iter().enumerate() {
                        slot[a + k].store(*x, Relaxed);
                    }
                } else {
                    // A crowded cell (rare): allocate.
                    let mut cell: Vec<u32> = slot[a..b].iter().map(|x| x.load(Relaxed)).collect();
                    cell.sort_unstable_by_key(|&i| tie[i as usize]);
                    for (k, x) in cell.iter().enumerate() {
                        slot[a + k].store(*x, Relaxed);
                    }
                }
            });
        }
        self.perm.resize(n, 0);
        self.perm
            .par_iter_mut()
            .zip(self.slot.par_iter())
            .with_min_len(4096)
            .for_each(|(p, s)| *p = s.load(Relaxed));
    }

    /// Slot range `start..end` of z-layer `z` (after [`Self::sort`]).
    pub fn layer(&self, z: usize) -> (usize, usize) {
        let layer = self.n_cells[0] * self.n_cells[1];
        (
            self.cell_start[z * layer] as usize,
            self.cell_start[(z + 1) * layer] as usize,
        )
    }

    /// `slab_of[i]`: the z-layer of slot `i` (after [`Self::sort`]).
    pub fn layer_of_slots(&self, slab_of: &mut Vec<u32>) {
        let nz = self.n_cells[2];
        slab_of.resize(self.perm.len(), 0);
        // A layer's slots are one run (empty for the layers a rank does not hold): fill each.
        for z in 0..nz {
            let (a, b) = self.layer(z);
            slab_of[a..b].fill(z as u32);
        }
    }
}

/// A run of cells along one axis, tested by comparing coordinates with its edges
/// ([`CellSort::range`]); only a coordinate within round-off of an edge takes the exact
/// [`CellSort::cell_coordinate`], so the answer is always that formula's.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CellRange {
    lo: f64,
    hi: f64,
    eps: f64,
    l: f64,
    n: usize,
    c0: usize,
    c1: usize,
}

impl CellRange {
    /// Whether `cell_coordinate(x)` lies in the run.
    #[inline(always)]
    pub fn contains(&self, x: f64) -> bool {
        let inside = x > self.lo + self.eps && x < self.hi - self.eps;
        let outside = x < self.lo - self.eps || x > self.hi + self.eps;
        if inside || outside {
            inside
        } else {
            (self.c0..self.c1).contains(&CellSort::cell_coordinate(x, self.l, self.n))
        }
    }
}

/// Apply a permutation (new slot `k` takes old slot `perm[k]`) to `v`, through `scratch`.
pub(crate) fn permute<T: Copy + Send + Sync>(v: &mut Vec<T>, perm: &[u32], scratch: &mut Vec<T>) {
    if v.is_empty() {
        return;
    }
    scratch.clear();
    scratch.resize(v.len(), v[0]);
    let src = &*v;
    scratch
        .par_iter_mut()
        .zip(perm.par_iter())
        .with_min_len(4096)
        .for_each(|(d, &k)| *d = src[k as usize]);
    std::mem::swap(v, scratch);
}

/// The 13 neighbour cells of the half stencil, as offsets + 1 in x, y, z: +x; the +y row; the
/// whole +z layer. With the later members of the own cell, every pair is met once, in the own
/// z-layer (slab) or the next one.
const HALF_STENCIL: [[usize; 3]; 13] = [
    [2, 1, 1],
    [0, 2, 1],
    [1, 2, 1],
    [2, 2, 1],
    [0, 0, 2],
    [1, 0, 2],
    [2, 0, 2],
    [0, 1, 2],
    [1, 1, 2],
    [2, 1, 2],
    [0, 2, 2],
    [1, 2, 2],
    [2, 2, 2],
];

/// For every particle `i` of z-layer `cz` in storage (cell) order, call `f(i, candidates)` with
/// the pairs `(j, x_i - x_j)` (minimum image) closer than `range` among the later members of
/// `i`'s cell and all members of the 13 half-stencil cells. The stencil and its periodic
/// shifts are worked out once per cell; candidates are gathered branch-free into `buf`.
/// With fewer than 3 cells along an axis the stencil meets some cells twice, at different
/// periodic shifts; every pair is still met once provided the box edges exceed twice `range`
/// (then only one image of a pair lies within range).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn scan_layer(
    cz: usize,
    pos: &[[f64; 3]],
    cell_start: &[u32],
    n_cells: [usize; 3],
    sbox: &SimBox,
    range: f64,
    buf: &mut Vec<(u32, [f64; 3])>,
    f: impl FnMut(usize, &[(u32, [f64; 3])]),
) {
    scan_layer_sheared(cz, pos, cell_start, n_cells, sbox, range, None, buf, f)
}

/// [`scan_layer`] in a Lees–Edwards box when `shear_offset` is `Some(offset)`: the image of the
/// box above (`y + L_y`) is displaced by `offset` along x. A stencil row that crosses the y
/// boundary (the `+y` row of the top cell row, the `-y` and `+y` rows of the next z-layer at the
/// bottom and top) is replaced by the whole x row of cells across the boundary, its members
/// seen at `x_j +- offset` and `y_j +- L_y`, and their x separation reduced to the nearest image
/// (as [`SimBox::min_image_sheared`]). The stencil still reaches only the own and the next
/// z-layer, and every pair is met once (a crossing row is a whole row, not three cells, so the
/// shifted images of its members are all seen; each member once, as `L_x > 2 range`). With
/// `None` this is exactly [`scan_layer`]. Needs at least 3 cells along y (the callers' boxes
/// hold three cells along every axis).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn scan_layer_sheared(
    cz: usize,
    pos: &[[f64; 3]],
    cell_start: &[u32],
    n_cells: [usize; 3],
    sbox: &SimBox,
    range: f64,
    shear_offset: Option<f64>,
    buf: &mut Vec<(u32, [f64; 3])>,
    mut f: impl FnMut(usize, &[(u32, [f64; 3])]),
) {
    let range2 = range * range;
    let lx = sbox.l[0];
    let inv_lx = 1.0 / lx;
    let [nx, ny, nz] = n_cells;
    let l = sbox.l;
    let n = [nx, ny, nz];
    let mut lo = [0usize; 14];
    let mut hi = [0usize; 14];
    let mut shift = [[0.0f64; 3]; 14];
    // Runs across the sheared y boundary: their x separations are reduced to the nearest image.
    let mut wrap_x = [false; 14];
    for cy in 0..ny {
        for cx in 0..nx {
            let own = (cz * ny + cy) * nx + cx;
            if cell_start[own] == cell_start[own + 1] {
                continue;
            }
            let coords = [cx, cy, cz];
            // Stencil cells in order; neighbours in x that are contiguous in storage and share
            // a periodic shift merge into one run (same candidates, same order, fewer loops).
            let mut runs = 0usize;
            let mut total = 0;
            for off in std::iter::once(&[1usize, 1, 1]).chain(HALF_STENCIL.iter()) {
                let mut c = [0usize; 3];
                let mut sh = [0.0f64; 3];
                for k in 0..3 {
                    let raw = coords[k] + off[k];
                    // raw in [0, n + 1]: 0 is cell n - 1 seen at -L, n + 1 is cell 0 at +L.
                    (c[k], sh[k]) = if raw == 0 {
                        (n[k] - 1, -l[k])
                    } else if raw > n[k] {
                        (0, l[k])
                    } else {
                        (raw - 1, 0.0)
                    };
                }
                let mut wrap = false;
                let (a, b) = match shear_offset {
                    Some(offset) if sh[1] != 0.0 => {
                        // A row across the y boundary: the whole row once, at its first entry.
                        if off[0] != 0 {
                            continue;
                        }
                        wrap = true;
                        sh[0] = if sh[1] > 0.0 { offset } else { -offset };
                        let row = (c[2] * ny + c[1]) * nx;
                        (cell_start[row] as usize, cell_start[row + nx] as usize)
                    }
                    _ => {
                        let cell = (c[2] * ny + c[1]) * nx + c[0];
                        (cell_start[cell] as usize, cell_start[cell + 1] as usize)
                    }
                };
                total += b - a;
                if runs > 0
                    && hi[runs - 1] == a
                    && shift[runs - 1] == sh
                    && wrap_x[runs - 1] == wrap
                {
                    hi[runs - 1] = b;
                } else {
                    lo[runs] = a;
                    hi[runs] = b;
                    shift[runs] = sh;
                    wrap_x[runs] = wrap;
                    runs += 1;
                }
            }
            if buf.len() < total {
                buf.resize(total, (0, [0.0; 3]));
            }
            for i in cell_start[own] as usize..cell_start[own + 1] as usize {
                let xi = pos[i];
                let mut m = 0usize;
                for s in 0..runs {
                    // Run 0 starts with the own cell: only its later members.
                    let first = if s == 0 { i + 1 } else { lo[s] };
                    let y = [
                        xi[0] - shift[s][0],
                        xi[1] - shift[s][1],
                        xi[2] - shift[s][2],
                    ];
                    if wrap_x[s] {
                        for (j, q) in pos[first..hi[s]].iter().enumerate() {
                            let mut d = [y[0] - q[0], y[1] - q[1], y[2] - q[2]];
                            d[0] -= lx * (d[0] * inv_lx + 0.5).floor();
                            buf[m] = ((first + j) as u32, d);
                            m += (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < range2) as usize;
                        }
                    } else {
                        for (j, q) in pos[first..hi[s]].iter().enumerate() {
                            let d = [y[0] - q[0], y[1] - q[1], y[2] - q[2]];
                            buf[m] = ((first + j) as u32, d);
                            m += (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < range2) as usize;
                        }
                    }
                }
                f(i, &buf[..m]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `CellRange::contains` is the exact formula's answer, also a few ulps from every edge and
    /// outside the box (the clamped end cells).
    #[test]
    fn a_cell_range_agrees_with_the_cell_formula() {
        for (l, n) in [(30.0, 20), (8.0, 4), (7.3, 7), (150.0, 150)] {
            let w = l / n as f64;
            let mut xs = vec![-0.5 * l - 1.0, 0.5 * l + 1.0, f64::NAN];
            for c in 0..=n {
                let edge = c as f64 * w - 0.5 * l;
                let mut x = edge;
                for _ in 0..4 {
                    x = x.next_down();
                }
                for _ in 0..9 {
                    xs.push(x);
                    x = x.next_up();
                }
                xs.push(edge + 0.37 * w);
                xs.push(edge + 1e-9 * w);
                xs.push(edge - 1e-9 * w);
            }
            for c0 in 0..n {
                for c1 in c0 + 1..=n {
                    let r = CellSort::range(l, n, c0, c1);
                    for &x in &xs {
                        let exact = (c0..c1).contains(&CellSort::cell_coordinate(x, l, n));
                        assert_eq!(r.contains(x), exact, "x = {x:e}, cells {c0}..{c1} of {n}");
                    }
                }
            }
        }
    }
}
