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
//! run**, for any number of ranks. Colloids are few: their positions and velocities are
//! gathered on every rank each step, and the colloid–colloid list is built from that copy.
//!
//! Per step: the drift's largest displacement is agreed on (one all-gather; with Verlet lists
//! the ghosts' positions and velocities travel in the same exchange), particles that left
//! their rank's layers migrate to the neighbour and the ghost layer is fetched whole (at every
//! sort: every step with cells, at list rebuilds with Verlet lists), the halo forces are sent
//! right, and the step ends with one agreement on a non-finite velocity or a particle lost in
//! the migration; thermodynamic sums are gathered layer by layer and added in layer order.

use super::{COLLOID_BIT, Dpd, DpdError};
use crate::cells::CellSort;
use crate::domain::Domain;

/// Numbers per migrating particle: key, position, velocity, image.
const MIGRANT: usize = 10;
/// Numbers per ghost at a sort: key, position, velocity.
const GHOST: usize = 7;

impl Dpd {
    /// The z-layer of cells of a wrapped position, as [`CellSort::sort`] finds it.
    fn layer_of(&self, x: &[f64; 3], nz: usize) -> usize {
        CellSort::cell_coordinate(x[2], self.sbox.l[2], nz)
    }

    /// Keep the particles of this rank's layers (at construction, from the full set).
    pub(super) fn keep_own(&mut self) {
        let Some(d) = self.domain.as_ref() else {
            return;
        };
        let (z0, z1, nz) = (d.z0, d.z1, d.nz);
        let mut w = 0;
        for i in 0..self.pos.len() {
            let z = self.layer_of(&self.pos[i], nz);
            if (z0..z1).contains(&z) {
                self.move_slot(i, w);
                w += 1;
            }
        }
        self.truncate_slots(w);
        self.own = (0, w);
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

    /// Send the owned particles that left this rank's layers to the neighbours, take theirs,
    /// drop the old ghosts and fetch the new ghost layer from the right. The caller sorts.
    pub(super) fn migrate_and_fetch_ghosts(&mut self) -> Result<(), DpdError> {
        let Some(mut d) = self.domain.take() else {
            return Ok(());
        };
        let out = self.migrate(&mut d);
        self.domain = Some(d);
        out
    }

    fn migrate(&mut self, d: &mut Domain) -> Result<(), DpdError> {
        let (left, right) = (d.left(), d.right());
        d.send_left.clear();
        d.send_right.clear();
        // Drop the ghosts, which lie before or after the owned slots: move the owned slots at
        // the end into the ghosts' place (the order does not matter: a sort follows).
        let (o0, o1) = self.own;
        let n_own = o1 - o0;
        for k in 0..o0.min(n_own) {
            self.move_slot(o1 - 1 - k, k);
        }
        self.truncate_slots(n_own);
        // Leavers go to the neighbours; the last slot fills the hole.
        let mut lost = None;
        let mut n = n_own;
        let mut i = 0;
        d.layer.clear();
        while i < n {
            let z = self.layer_of(&self.pos[i], d.nz);
            if d.owns(z) {
                d.layer.push(z as u32);
                i += 1;
                continue;
            }
            let to = d.owner(z);
            let buf = if to == right {
                &mut d.send_right
            } else if to == left {
                &mut d.send_left
            } else {
                &mut d.lost
            };
            if to != right && to != left {
                lost.get_or_insert(self.key[i] & !COLLOID_BIT);
            }
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
        // With two ranks left and right are one rank, and everything went right.
        d.comm.shift(right, &d.send_right, left, &mut d.recv);
        self.take_migrants(&d.recv);
        if left != right {
            d.comm.shift(left, &d.send_left, right, &mut d.recv);
            self.take_migrants(&d.recv);
        }
        let n_own = self.pos.len();
        self.own = (0, n_own);
        for i in d.layer.len()..n_own {
            let z = self.layer_of(&self.pos[i], d.nz);
            d.layer.push(z as u32);
        }
        // Ghosts: this rank's first layer goes left (it is the left rank's ghost layer).
        d.send_left.clear();
        for (i, &z) in d.layer.iter().enumerate() {
            if z as usize == d.z0 {
                d.send_left.push(self.key[i] as f64);
                d.send_left.extend_from_slice(&self.pos[i]);
                d.send_left.extend_from_slice(&self.vel[i]);
            }
        }
        d.comm.shift(left, &d.send_left, right, &mut d.recv);
        for g in d.recv.chunks_exact(GHOST) {
            self.push_slot(
                g[0] as u32,
                [g[1], g[2], g[3]],
                [g[4], g[5], g[6]],
                [0; 3],
                0.0,
            );
        }
        // The ranks agree on whether one lost a particle at the step's end, with the velocity
        // check (one all-gather fewer; the step's time-step check makes it all but impossible:
        // a layer is wider than the half cut-off a particle may move).
        d.lost_tag = d.lost_tag.min(lost.unwrap_or(u32::MAX));
        Ok(())
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

    /// After a sort: the owned slots are the owned layers' (contiguous, as layers are stored in
    /// z order and the ghost layer is before or after them).
    pub(super) fn set_own_range(&mut self) {
        self.own = match &self.domain {
            None => (0, self.pos.len()),
            Some(d) => (self.grid.layer(d.z0).0, self.grid.layer(d.z1 - 1).1),
        };
    }

    /// [`Domain::agree_max`] of the step's `[value, tag, other, bad]`, and in the same
    /// exchange (Verlet lists: `refresh`) the ghosts' positions and velocities into the same
    /// slots, as they stand after the drift. The refreshed ghosts are not used when the
    /// agreement calls for a sort: the migration fetches the ghost layer anew.
    pub(super) fn agree_and_refresh(&mut self, row: [f64; 4], refresh: bool) -> [f64; 4] {
        let Some(d) = self.domain.as_mut() else {
            return row;
        };
        if !refresh {
            return d.agree_max(row[0], row[1], row[2], row[3]);
        }
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
    }

    /// After the forces: the last owned slab's forces on the ghost layer go right; the left
    /// rank's on the first owned layer arrive into the slab before it.
    pub(super) fn exchange_halo(&mut self) {
        let Some(d) = self.domain.as_mut() else {
            return;
        };
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
                    if k & COLLOID_BIT != 0 {
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

    /// Every rank's `record(layer)` for its owned layers, in layer order, summed element-wise
    /// in layer order into `total` (`width` numbers a layer): the same additions on any
    /// number of ranks.
    pub(super) fn sum_layers(
        &self,
        width: usize,
        record: impl Fn(usize, &mut [f64]),
        total: &mut [f64],
    ) {
        let nz = self.slabs.len();
        let (z0, z1) = self.domain.as_ref().map_or((0, nz), |d| (d.z0, d.z1));
        // Buffers kept between calls: the pressure is summed every step of a viscosity run.
        let mut guard = self.layer_sums.borrow_mut();
        let (mine, all) = &mut *guard;
        mine.clear();
        mine.resize(width * (z1 - z0), 0.0);
        for (z, r) in (z0..z1).zip(mine.chunks_exact_mut(width)) {
            record(z, r);
        }
        let rows = match &self.domain {
            None => &*mine,
            Some(d) => {
                d.comm.all_gather(mine, all);
                &*all
            }
        };
        total.iter_mut().for_each(|t| *t = 0.0);
        for r in rows.chunks_exact(width) {
            for (t, x) in total.iter_mut().zip(r) {
                *t += x;
            }
        }
    }

    /// Every rank's owned particles as `(tag, numbers)` rows of `width` numbers from `row`,
    /// on every rank (in rank order).
    pub(super) fn gather_own(&self, width: usize, row: impl Fn(usize, &mut Vec<f64>)) -> Vec<f64> {
        let mut mine = Vec::with_capacity((self.own.1 - self.own.0) * width);
        for i in self.own.0..self.own.1 {
            row(i, &mut mine);
        }
        debug_assert_eq!(mine.len(), (self.own.1 - self.own.0) * width);
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
