//! Spatial domain decomposition of a DPD run over ranks ([`Exchange`]).
//!
//! The box is cut into slabs of whole z-layers of the force cells: rank `r` of `P` owns layers
//! `z0 = r nz / P .. z1 = (r + 1) nz / P` and the particles in them. The half stencil of cells
//! reaches only the own and the next layer ([`crate::cells`]), so a rank needs one ghost layer,
//! `z1 mod nz` (the first layer of the rank on its right), and the forces its last layer's pairs
//! exert on that ghost layer (the last slab's *halo*) go back to that rank, which adds them
//! exactly where a single process adds the previous slab's halo. Every rank sorts its particles
//! and ghosts into the same global cells (ties by tag), so each pair is met in the same order
//! and summed in the same place as on one rank: **a decomposed run is bitwise the single-rank
//! run**, for any number of ranks. On a grid cut along y as well ([`crate::domain`]) a rank
//! also holds a fringe row of ghosts on each side of its rows and computes the pairs across
//! the y cut itself (no forces go back along y), so every pair of an owned particle is still
//! met in the single-rank order. Colloids are few: their positions and velocities are
//! gathered on every rank each step, and the colloid–colloid list is built from that copy.
//!
//! Per step: the drift's largest displacement is agreed on (one all-gather; with Verlet lists
//! the ghosts' positions and velocities travel in the same exchange), particles that left
//! their rank's cells migrate to the neighbour (along z, then along y) and the ghosts are
//! fetched whole (the fringe rows, then the ghost layer; at every sort: every step with cells,
//! at list rebuilds with Verlet lists), the halo forces are sent up, and the step ends with one
//! agreement on a non-finite velocity or a particle lost in the migration; thermodynamic sums
//! are gathered row of cells by row and added in the global order of the rows.

use super::{COLLOID_BIT, Dpd, DpdError, PairVirial};
use crate::cells::CellSort;
use crate::domain::{Domain, PosVel};

/// Numbers per migrating particle: key, position, velocity, image.
const MIGRANT: usize = 10;
/// Numbers per ghost at a sort: key, position, velocity.
const GHOST: usize = 7;

/// The axis a migration stage crosses.
#[derive(Clone, Copy, PartialEq)]
enum Axis {
    Y,
    Z,
}

impl Dpd {
    /// The row (along y) and layer (along z) of cells of a wrapped position, as
    /// [`CellSort::sort`] finds them.
    fn row_layer_of(&self, x: &[f64; 3], d: &Domain) -> (usize, usize) {
        (
            CellSort::cell_coordinate(x[1], self.sbox.l[1], d.ny),
            CellSort::cell_coordinate(x[2], self.sbox.l[2], d.nz),
        )
    }

    /// Keep the particles of this rank's cells (at construction, from the full set).
    pub(super) fn keep_own(&mut self) {
        let Some(d) = self.domain.take() else {
            return;
        };
        let mut w = 0;
        for i in 0..self.pos.len() {
            let (y, z) = self.row_layer_of(&self.pos[i], &d);
            if d.owns(z) && d.owns_row(y) {
                self.move_slot(i, w);
                w += 1;
            }
        }
        self.truncate_slots(w);
        self.own = (0, w);
        self.ghost.clear();
        self.domain = Some(d);
    }

    fn move_slot(&mut self, from: usize, to: usize) {
        self.pos[to] = self.pos[from];
        self.vel[to] = self.vel[from];
        self.image[to] = self.image[from];
        self.key[to] = self.key[from];
        self.inv_mass[to] = self.inv_mass[from];
    }

    fn truncate_slots(&mut self, n: usize) {
        self.pos.truncate(n);
        self.vel.truncate(n);
        self.image.truncate(n);
        self.key.truncate(n);
        self.inv_mass.truncate(n);
    }

    fn push_slot(&mut self, key: u32, x: [f64; 3], v: [f64; 3], image: [i32; 3], inv_mass: f64) {
        self.pos.push(x);
        self.vel.push(v);
        self.image.push(image);
        self.key.push(key);
        self.inv_mass.push(inv_mass);
    }

    /// Send the owned particles that left this rank's cells to the neighbours, take theirs,
    /// drop the old ghosts and fetch the new ones (the fringe rows, then the ghost layer with
    /// its fringe rows). The caller sorts.
    pub(super) fn migrate_and_fetch_ghosts(&mut self) -> Result<(), DpdError> {
        let Some(mut d) = self.domain.take() else {
            return Ok(());
        };
        let out = self.migrate(&mut d);
        self.domain = Some(d);
        out
    }

    fn migrate(&mut self, d: &mut Domain) -> Result<(), DpdError> {
        // Drop the ghosts: the last owned slots fill their places (the order does not matter:
        // a sort follows), so a ghost layer after the owned slots costs no move at all.
        let is_ghost = |g: &[bool], i: usize| g.get(i).copied().unwrap_or(false);
        let mut end = self.pos.len();
        let mut i = 0;
        while i < end {
            if !is_ghost(&self.ghost, i) {
                i += 1;
                continue;
            }
            end -= 1;
            while end > i && is_ghost(&self.ghost, end) {
                end -= 1;
            }
            if end > i {
                self.move_slot(end, i);
                i += 1;
            }
        }
        self.truncate_slots(end);
        self.ghost.clear();
        // Leavers go to the neighbours: along z, then along y (a particle crossing a corner
        // takes both steps).
        let mut lost = None;
        if d.pz > 1 {
            self.send_leavers(d, Axis::Z, &mut lost);
        }
        if d.py > 1 {
            self.send_leavers(d, Axis::Y, &mut lost);
        }
        let n_own = self.pos.len();
        self.own = (0, n_own);
        // Fringe rows: this rank's first row goes to the column before (it is that column's
        // upper fringe), its last row to the column after.
        if d.py > 1 {
            for (row, to, from) in [
                (d.y0, d.y_left(), d.y_right()),
                (d.y1 - 1, d.y_right(), d.y_left()),
            ] {
                d.send_left.clear();
                let rows = CellSort::range(self.sbox.l[1], d.ny, row, row + 1);
                for i in 0..n_own {
                    if rows.contains(self.pos[i][1]) {
                        self.push_ghost_row(i, &mut d.send_left);
                    }
                }
                d.comm.shift(to, &d.send_left, from, &mut d.recv);
                self.take_ghosts(&d.recv);
            }
        }
        // The ghost layer: this rank's first layer, fringe rows included, goes to the rank
        // below (it is that rank's ghost layer).
        if d.pz > 1 {
            d.send_left.clear();
            let first = CellSort::range(self.sbox.l[2], d.nz, d.z0, d.z0 + 1);
            for i in 0..self.pos.len() {
                if first.contains(self.pos[i][2]) {
                    self.push_ghost_row(i, &mut d.send_left);
                }
            }
            d.comm.shift(d.left(), &d.send_left, d.right(), &mut d.recv);
            self.take_ghosts(&d.recv);
        }
        // The ranks agree on whether one lost a particle at the step's end, with the velocity
        // check (one all-gather fewer; the step's time-step check makes it all but impossible:
        // a cell is wider than the half cut-off a particle may move).
        d.lost_tag = d.lost_tag.min(lost.unwrap_or(u32::MAX));
        Ok(())
    }

    /// Send the owned particles outside this rank's layers (`Axis::Z`) or rows (`Axis::Y`) to
    /// the neighbour along that axis and take the neighbours' (the last slot fills a hole).
    fn send_leavers(&mut self, d: &mut Domain, axis: Axis, lost: &mut Option<u32>) {
        let (left, right) = match axis {
            Axis::Z => (d.left(), d.right()),
            Axis::Y => (d.y_left(), d.y_right()),
        };
        d.send_left.clear();
        d.send_right.clear();
        let (k, cells, mine) = match axis {
            Axis::Z => (2, d.nz, CellSort::range(self.sbox.l[2], d.nz, d.z0, d.z1)),
            Axis::Y => (1, d.ny, CellSort::range(self.sbox.l[1], d.ny, d.y0, d.y1)),
        };
        let mut n = self.pos.len();
        let mut i = 0;
        while i < n {
            if mine.contains(self.pos[i][k]) {
                i += 1;
                continue;
            }
            let c = CellSort::cell_coordinate(self.pos[i][k], self.sbox.l[k], cells);
            let to = match axis {
                Axis::Z => d.owner(c),
                Axis::Y => d.y_owner(c),
            };
            let buf = if to == right {
                &mut d.send_right
            } else if to == left {
                &mut d.send_left
            } else {
                lost.get_or_insert(self.key[i] & !COLLOID_BIT);
                &mut d.lost
            };
            let (x, v, im) = (self.pos[i], self.vel[i], self.image[i]);
            buf.push(self.key[i] as f64);
            buf.extend_from_slice(&x);
            buf.extend_from_slice(&v);
            buf.extend(im.iter().map(|&k| k as f64));
            n -= 1;
            self.move_slot(n, i);
        }
        self.truncate_slots(n);
        d.lost.clear();
        // With two ranks along the axis left and right are one rank, and everything went right.
        d.comm.shift(right, &d.send_right, left, &mut d.recv);
        self.take_migrants(&d.recv);
        if left != right {
            d.comm.shift(left, &d.send_left, right, &mut d.recv);
            self.take_migrants(&d.recv);
        }
    }

    fn push_ghost_row(&self, i: usize, buf: &mut Vec<f64>) {
        buf.push(self.key[i] as f64);
        buf.extend_from_slice(&self.pos[i]);
        buf.extend_from_slice(&self.vel[i]);
    }

    fn take_ghosts(&mut self, recv: &[f64]) {
        for g in recv.chunks_exact(GHOST) {
            self.push_slot(
                g[0] as u32,
                [g[1], g[2], g[3]],
                [g[4], g[5], g[6]],
                [0; 3],
                0.0,
            );
        }
    }

    fn take_migrants(&mut self, recv: &[f64]) {
        for m in recv.chunks_exact(MIGRANT) {
            let key = m[0] as u32;
            let inv_mass = 1.0 / self.props[(key & !COLLOID_BIT) as usize].mass;
            self.push_slot(
                key,
                [m[1], m[2], m[3]],
                [m[4], m[5], m[6]],
                [m[7] as i32, m[8] as i32, m[9] as i32],
                inv_mass,
            );
        }
    }

    /// The storage slots of row `y` of layer `z` (after a sort).
    fn row_slots(&self, z: usize, y: usize) -> (usize, usize) {
        let [nx, ny, _] = self.grid.n_cells;
        let c = (z * ny + y) * nx;
        (
            self.grid.cell_start[c] as usize,
            self.grid.cell_start[c + nx] as usize,
        )
    }

    /// After a sort: the slots of the owned layers (contiguous, as layers are stored in z
    /// order and the ghost layer is before or after them), and which of them are ghosts (the
    /// fringe rows, when the run is cut along y).
    pub(super) fn set_own_range(&mut self) {
        let n = self.pos.len();
        self.ghost.clear();
        let Some(d) = &self.domain else {
            self.own = (0, n);
            self.ghost.resize(n, false);
            return;
        };
        self.own = (self.grid.layer(d.z0).0, self.grid.layer(d.z1 - 1).1);
        self.ghost.resize(n, true);
        for z in d.z0..d.z1 {
            let (a, _) = self.row_slots(z, d.y0);
            let (_, b) = self.row_slots(z, d.y1 - 1);
            self.ghost[a..b].iter_mut().for_each(|g| *g = false);
        }
    }

    /// [`Domain::agree_max`] of the step's `[value, tag, other, bad]`, and in the same
    /// exchange (Verlet lists: `refresh`) the ghosts' positions and velocities into the same
    /// slots, as they stand after the drift (the fringe rows first, then the ghost layer with
    /// its fringe rows). The refreshed ghosts are not used when the agreement calls for a
    /// sort: the migration fetches the ghosts anew.
    pub(super) fn agree_and_refresh(&mut self, row: [f64; 4], refresh: bool) -> [f64; 4] {
        let Some(mut d) = self.domain.take() else {
            return row;
        };
        if refresh && d.py > 1 {
            let [nx, ny, _] = self.grid.n_cells;
            let cell_start = &self.grid.cell_start;
            let rows = |z: usize, y: usize| {
                let c = (z * ny + y) * nx;
                cell_start[c] as usize..cell_start[c + nx] as usize
            };
            d.refresh_fringe(rows, &mut PosVel(&mut self.pos, &mut self.vel));
        }
        let out = if !refresh || d.pz == 1 {
            d.agree_max(row[0], row[1], row[2], row[3])
        } else {
            let (a, b) = (self.slabs[d.z0].start, self.slabs[d.z0].end);
            d.send_left.clear();
            for i in a..b {
                d.send_left.extend_from_slice(&self.pos[i]);
                d.send_left.extend_from_slice(&self.vel[i]);
            }
            let g = &self.slabs[d.ghost_layer()];
            d.recv.resize(6 * (g.end - g.start), 0.0);
            d.mine.clear();
            d.mine.extend_from_slice(&row);
            d.agree_and_fetch_ghosts();
            for (k, m) in d.recv.chunks_exact(6).enumerate() {
                self.pos[g.start + k] = [m[0], m[1], m[2]];
                self.vel[g.start + k] = [m[3], m[4], m[5]];
            }
            d.reduce_max()
        };
        self.domain = Some(d);
        out
    }

    /// After the forces: the last owned slab's forces on the ghost layer go to the rank
    /// above; the rank below's on the first owned layer arrive into the slab before it (with
    /// one slab along z the halo stays on the rank).
    pub(super) fn exchange_halo(&mut self) {
        let Some(d) = self.domain.as_mut() else {
            return;
        };
        if d.pz == 1 {
            return;
        }
        d.send_right.clear();
        for f in &self.slabs[d.z1 - 1].halo {
            d.send_right.extend_from_slice(f);
        }
        let (left, right) = (d.left(), d.right());
        let h = &mut self.slabs[d.before_layer()].halo;
        d.recv.resize(3 * h.len(), 0.0);
        d.comm.shift_exact(right, &d.send_right, left, &mut d.recv);
        for (f, m) in h.iter_mut().zip(d.recv.chunks_exact(3)) {
            *f = [m[0], m[1], m[2]];
        }
    }

    /// Positions and velocities of every colloid, by slot, on every rank.
    pub(super) fn gather_colloids(&mut self) {
        let nc = self.cc_tag.len();
        self.cc_pos.resize(nc, [0.0; 3]);
        self.cc_vel.resize(nc, [0.0; 3]);
        match self.domain.as_mut() {
            None => {
                for (s, &t) in self.cc_tag.iter().enumerate() {
                    let i = self.by_tag[t as usize] as usize;
                    self.cc_pos[s] = self.pos[i];
                    self.cc_vel[s] = self.vel[i];
                }
            }
            Some(d) => {
                d.mine.clear();
                for i in self.own.0..self.own.1 {
                    let k = self.key[i];
                    if k & COLLOID_BIT != 0 && !self.ghost[i] {
                        d.mine.push((k & !COLLOID_BIT) as f64);
                        d.mine.extend_from_slice(&self.pos[i]);
                        d.mine.extend_from_slice(&self.vel[i]);
                    }
                }
                d.comm.all_gather(&d.mine, &mut d.gathered);
                for m in d.gathered.chunks_exact(7) {
                    let s = self.cc_slot[m[0] as usize] as usize;
                    self.cc_pos[s] = [m[1], m[2], m[3]];
                    self.cc_vel[s] = [m[4], m[5], m[6]];
                }
            }
        }
    }

    /// Every rank's `record((start, end, virial), numbers)` for each of its rows of cells
    /// (the slots `start..end` of a row of a layer, the virial of the pairs met from it), the
    /// rows summed element-wise in the global order of the rows (layer by layer, row by row)
    /// into `total` (`width` numbers a row): the same additions on any number of ranks.
    pub(super) fn sum_rows(
        &self,
        width: usize,
        record: impl Fn((usize, usize, &PairVirial), &mut [f64]),
        total: &mut [f64],
    ) {
        let [_, ny, nz] = self.grid.n_cells;
        let [z0, z1, y0, y1] = self
            .domain
            .as_ref()
            .map_or([0, nz, 0, ny], |d| d.block_of(d.comm.rank()));
        // Buffers kept between calls: the pressure is summed every step of a viscosity run.
        let mut guard = self.layer_sums.borrow_mut();
        let (mine, all, at) = &mut *guard;
        mine.clear();
        mine.resize(width * (z1 - z0) * (y1 - y0), 0.0);
        let mut rows = mine.chunks_exact_mut(width);
        for z in z0..z1 {
            for y in y0..y1 {
                let (a, b) = self.row_slots(z, y);
                record((a, b, &self.slabs[z].row_virial[y]), rows.next().unwrap());
            }
        }
        total.iter_mut().for_each(|t| *t = 0.0);
        let mut add = |r: &[f64]| {
            for (t, x) in total.iter_mut().zip(r) {
                *t += x;
            }
        };
        match &self.domain {
            None => mine.chunks_exact(width).for_each(&mut add),
            Some(d) => {
                d.comm.all_gather(mine, all);
                // Where each row lies among the ranks' blocks (in rank order).
                at.clear();
                at.resize(nz * ny, 0);
                let mut k = 0;
                for r in 0..d.comm.size() {
                    let [z0, z1, y0, y1] = d.block_of(r);
                    for z in z0..z1 {
                        for y in y0..y1 {
                            at[z * ny + y] = k;
                            k += 1;
                        }
                    }
                }
                for &k in at.iter() {
                    add(&all[k * width..(k + 1) * width]);
                }
            }
        }
    }

    /// Every rank's owned particles as `(tag, numbers)` rows of `width` numbers from `row`,
    /// on every rank (in rank order).
    pub(super) fn gather_own(&self, width: usize, row: impl Fn(usize, &mut Vec<f64>)) -> Vec<f64> {
        let mut mine = Vec::with_capacity((self.own.1 - self.own.0) * width);
        for i in self.own.0..self.own.1 {
            if !self.ghost[i] {
                row(i, &mut mine);
            }
        }
        debug_assert_eq!(mine.len(), self.owned() * width);
        match &self.domain {
            None => mine,
            Some(d) => {
                let mut all = Vec::new();
                d.comm.all_gather(&mine, &mut all);
                all
            }
        }
    }
}
