//! Brownian dynamics decomposed in space over ranks ([`Exchange`]), on the grid of
//! [`crate::domain`]: a rank owns the z-layers of cells `z0..z1` (and, cut along y, the rows
//! `y0..y1` of them) and the particles in them, and keeps a copy of the next rank's first layer
//! (the ghosts) and, cut along y, a fringe row of ghosts on each side of its rows, whose pairs
//! with its own it computes itself.
//!
//! - **Forces.** Every rank sums the pairs of its own slabs ([`super::all_pair_forces`]); the
//!   forces its last slab exerts on the ghosts (the halo) go to their owner, who adds them where
//!   one process adds the previous slab's halo.
//! - **Between list builds** the ghosts' positions are refreshed each step (the owner's first
//!   layer goes left) in the same exchange as the agreement on the largest displacement and
//!   any blow-up (an all-gather, overlapped with the shift under MPI).
//! - **At a list build** positions are wrapped, particles that left their rank's layers migrate
//!   to the neighbour that owns them, the ghost layer is fetched whole, and the rank sorts its
//!   particles and ghosts into the same global cells (ties by tag) as one process would.
//! - **Noise.** The Euler noise of a particle is keyed by its slot in the storage order of the
//!   whole system (blocks of [`BLOCK`](colloidsim_core::rng::BLOCK) slots,
//!   [`super::StepPass::integrate`]). The owned slots are runs of that order (one on slabs, one
//!   per layer cut along y), each starting where the counts of every rank per layer put it
//!   (agreed on at every build), so a rank draws its particles' deviates from the same streams,
//!   skipping the deviates of a block a run shares with the particles before it.
//!
//! So each pair is met in the same order and summed in the same place, and every particle gets
//! the same deviates, as on one rank: **a decomposed run is bitwise the single-rank run** for
//! any number of ranks. Every rank holds the constants (type, diameter, mass) of all particles.

use super::{BdError, Brownian, ChunkReport, ListState, PairForceCursor, all_pair_forces};
use crate::cells::{CellSort, permute};
use crate::domain::Domain;
use crate::potential::{External, Pair};
use crate::state::Particles;
use colloidsim_core::exchange::Exchange;

/// Numbers per migrating particle: tag, position, image.
const MIGRANT: usize = 7;
/// Numbers per ghost at a list build: tag, position.
const GHOST: usize = 4;
/// Numbers per rank in a step's agreement: largest squared displacement, then the blow-up of
/// lowest tag (tag, or -1 for none; position; force; drift; diameter).
const AGREE: usize = 8;

impl<P: Pair, E: External> Brownian<P, E> {
    /// This engine decomposed over the ranks of `comm`: every rank builds the same engine
    /// (the same particles, or the same checkpoint) and keeps its layers and the ghosts. One
    /// rank: the engine unchanged. An error when the run has no pair forces (no cells to cut)
    /// or more ranks than z-layers of cells.
    pub fn decomposed(self, comm: Box<dyn Exchange>) -> Result<Self, BdError> {
        self.decomposed_on(comm, None)
    }

    /// [`Self::decomposed`] on the grid `[py, pz]` of ranks (columns along y by slabs along z;
    /// `None`: the grid with the fewest ghost cells per rank, [`Domain::choose_grid`]). Cut
    /// along y, a rank also holds a fringe row of ghosts on each side of its rows and sums the
    /// pairs across the cut itself: the run is the same on any grid.
    pub fn decomposed_on(
        mut self,
        comm: Box<dyn Exchange>,
        grid: Option<[usize; 2]>,
    ) -> Result<Self, BdError> {
        if comm.size() == 1 {
            return Ok(self);
        }
        if self.range <= 0.0 {
            return Err(BdError::Invalid(
                "a run decomposed over ranks needs pair forces: its domains are layers of \
                 neighbour cells"
                    .into(),
            ));
        }
        let nc = self.grid.n_cells;
        let [nx, ny, nz] = nc;
        let g = grid.unwrap_or_else(|| Domain::choose_grid(comm.size(), nc, true));
        let d = Domain::grid(comm, [ny, nz], g, self.range).map_err(BdError::Invalid)?;
        // The constants of every particle, by tag (positions unused).
        self.whole = Some(Box::new(self.snapshot()));
        // Where each owned layer's rows start in the whole system's order.
        let starts: Vec<usize> = (d.z0..d.z1)
            .map(|z| self.grid.cell_start[(z * ny + d.y0) * nx] as usize)
            .collect();
        // Keep the cells this rank holds, in storage order (each slot moves down or stays).
        let mut keep = Vec::new();
        for z in (0..nz).filter(|&z| d.holds_layer(z)) {
            for y in (0..ny).filter(|&y| d.holds_row(y)) {
                let c = (z * ny + y) * nx;
                keep.extend(
                    self.grid.cell_start[c] as usize..self.grid.cell_start[c + nx] as usize,
                );
            }
        }
        for (to, &from) in keep.iter().enumerate() {
            self.move_slot(from, to);
            self.ref_pos[to] = self.ref_pos[from];
        }
        self.truncate_slots(keep.len());
        self.ref_pos.truncate(keep.len());
        self.domain = Some(d);
        self.sort_local(&starts);
        // The lists of the owned layers again: not a build of the run's.
        let builds = self.builds;
        self.build_lists();
        self.builds = builds;
        Ok(self)
    }

    /// The ranks of a decomposed run (`None` on one process).
    pub fn exchange(&self) -> Option<&dyn Exchange> {
        self.domain.as_ref().map(|d| &*d.comm)
    }

    /// The engine is done with: the ranks it ran on, for the next engine (`None` on one
    /// process).
    pub fn into_exchange(self) -> Option<Box<dyn Exchange>> {
        self.domain.map(|d| d.comm)
    }

    /// Particles this rank owns (all on one process).
    pub fn owned(&self) -> usize {
        self.runs.iter().map(|&(a, b, _)| b - a).sum()
    }

    /// The owned slots, in increasing order.
    fn owned_slots(&self) -> impl Iterator<Item = usize> + '_ {
        self.runs.iter().flat_map(|&(a, b, _)| a..b)
    }

    /// Particles in the whole system (on every rank).
    pub fn n_particles(&self) -> usize {
        self.whole
            .as_ref()
            .map_or(self.particles.len(), |w| w.len())
    }

    fn move_slot(&mut self, from: usize, to: usize) {
        let p = &mut self.particles;
        p.pos[to] = p.pos[from];
        p.vel[to] = p.vel[from];
        p.image[to] = p.image[from];
        p.typeid[to] = p.typeid[from];
        p.diameter[to] = p.diameter[from];
        p.mass[to] = p.mass[from];
        self.tag[to] = self.tag[from];
        self.kinetics[to] = self.kinetics[from];
    }

    fn truncate_slots(&mut self, n: usize) {
        let p = &mut self.particles;
        p.pos.truncate(n);
        p.vel.truncate(n);
        p.image.truncate(n);
        p.typeid.truncate(n);
        p.diameter.truncate(n);
        p.mass.truncate(n);
        self.tag.truncate(n);
        self.kinetics.truncate(n);
    }

    /// A slot for particle `tag` at `x` (its constants from the whole system's).
    fn push_slot(&mut self, tag: u32, x: [f64; 3], image: [i32; 3]) {
        let w = self.whole.as_ref().expect("decomposed");
        let t = tag as usize;
        let p = &mut self.particles;
        p.pos.push(x);
        p.image.push(image);
        p.vel.push(w.vel[t]);
        p.typeid.push(w.typeid[t]);
        p.diameter.push(w.diameter[t]);
        p.mass.push(w.mass[t]);
        self.tag.push(tag);
        self.kinetics
            .push(super::kinetics_of(&self.params, w.diameter[t]));
    }

    /// Sort the stored particles and ghosts into the global cells by their reference positions
    /// (ties by tag) and find the owned slots: a run per owned layer, starting at `starts[k]`
    /// in the whole system's order (merged where consecutive in both orders: one run on slabs).
    fn sort_local(&mut self, starts: &[usize]) {
        self.grid
            .sort(&self.sbox, &self.ref_pos, &self.tag, self.range);
        self.apply_perm();
        permute(&mut self.ref_pos, &self.grid.perm, &mut self.scratch3);
        let d = self.domain.as_ref().expect("decomposed");
        self.own = (self.grid.layer(d.z0).0, self.grid.layer(d.z1 - 1).1);
        let [nx, ny, _] = self.grid.n_cells;
        let slot = |z: usize, y: usize| self.grid.cell_start[(z * ny + y) * nx] as usize;
        self.runs.clear();
        for (z, &g) in (d.z0..d.z1).zip(starts) {
            let (a, b) = (slot(z, d.y0), slot(z, d.y1));
            match self.runs.last_mut() {
                Some(r) if r.1 == a && r.2 + (r.1 - r.0) == g => r.1 = b,
                _ => self.runs.push((a, b, g)),
            }
        }
    }

    /// A list build of a decomposed run: wrap, migrate, fetch the ghost layer, sort, agree on
    /// where the owned slots start in the whole system's order, build the owned layers' lists.
    pub(super) fn rebuild_decomposed(&mut self) -> Result<(), BdError> {
        let mut d = self.domain.take().expect("decomposed");
        let lost = self.migrate(&mut d);
        // Where this rank's rows of each owned layer start in the whole system's order: every
        // rank's particles per owned layer, and whether a particle was lost on any rank.
        d.mine.clear();
        d.mine.push(lost.map_or(-1.0, |t| t as f64));
        d.mine.resize(1 + d.z1 - d.z0, 0.0);
        let l = self.sbox.l[2];
        for k in self.owned_slots() {
            let z = CellSort::cell_coordinate(self.particles.pos[k][2], l, d.nz);
            d.mine[1 + z - d.z0] += 1.0;
        }
        d.comm.all_gather(&d.mine, &mut d.gathered);
        // count[z * py + ry]: the particles of layer z in column ry.
        let mut count = vec![0usize; d.nz * d.py];
        let mut lost = None::<u32>;
        let mut at = 0;
        for r in 0..d.comm.size() {
            let [z0, z1, ..] = d.block_of(r);
            let g = &d.gathered[at..at + 1 + z1 - z0];
            if g[0] >= 0.0 {
                lost = Some(lost.map_or(g[0] as u32, |t| t.min(g[0] as u32)));
            }
            for z in z0..z1 {
                count[z * d.py + r % d.py] = g[1 + z - z0] as usize;
            }
            at += 1 + z1 - z0;
        }
        let ry = d.comm.rank() % d.py;
        let before: usize = count[..d.z0 * d.py].iter().sum();
        let starts: Vec<usize> = (d.z0..d.z1)
            .scan(before, |g, z| {
                let row = &count[z * d.py..(z + 1) * d.py];
                let start = *g + row[..ry].iter().sum::<usize>();
                *g += row.iter().sum::<usize>();
                Some(start)
            })
            .collect();
        self.domain = Some(d);
        if let Some(tag) = lost {
            return Err(BdError::Invalid(format!(
                "particle {tag} crossed more than one domain in a step at step {}; reduce `dt` \
                 or use fewer ranks",
                self.step
            )));
        }
        self.ref_pos.clear();
        self.ref_pos.extend_from_slice(&self.particles.pos);
        self.sort_local(&starts);
        self.build_lists();
        Ok(())
    }

    /// Drop the ghosts, wrap, send the leavers to their neighbours (along z, then along y)
    /// and take the arrivals, fetch the fringe rows and the ghost layer. Returns the lowest tag
    /// of a particle that skipped a rank (dropped).
    fn migrate(&mut self, d: &mut Domain) -> Option<u32> {
        let mut n = 0;
        for k in 0..self.runs.len() {
            let (a, b, _) = self.runs[k];
            for i in a..b {
                self.move_slot(i, n);
                n += 1;
            }
        }
        self.truncate_slots(n);
        let sbox = self.sbox;
        let p = &mut self.particles;
        for (x, img) in p.pos.iter_mut().zip(p.image.iter_mut()) {
            sbox.wrap(x, img);
        }
        let mut lost: Option<u32> = None;
        if d.pz > 1 {
            self.send_leavers(d, true, &mut lost);
        }
        if d.py > 1 {
            self.send_leavers(d, false, &mut lost);
        }
        let n_own = self.tag.len();
        self.own = (0, n_own);
        self.runs.clear();
        self.runs.push((0, n_own, 0));
        let cell = |x: &[f64; 3], k: usize, n: usize| CellSort::cell_coordinate(x[k], sbox.l[k], n);
        // Fringe rows: the first owned row is the upper fringe of the column before, the last
        // the lower fringe of the column after.
        if d.py > 1 {
            for (row, to, from) in [
                (d.y0, d.y_left(), d.y_right()),
                (d.y1 - 1, d.y_right(), d.y_left()),
            ] {
                d.send_left.clear();
                for k in 0..n_own {
                    let x = self.particles.pos[k];
                    if cell(&x, 1, d.ny) == row {
                        d.send_left.push(self.tag[k] as f64);
                        d.send_left.extend_from_slice(&x);
                    }
                }
                d.comm.shift(to, &d.send_left, from, &mut d.recv);
                self.take_ghosts(d);
            }
        }
        // The first layer, fringe rows included, is the ghost layer of the rank below.
        if d.pz > 1 {
            d.send_left.clear();
            for k in 0..self.tag.len() {
                let x = self.particles.pos[k];
                if cell(&x, 2, d.nz) == d.z0 {
                    d.send_left.push(self.tag[k] as f64);
                    d.send_left.extend_from_slice(&x);
                }
            }
            d.comm.shift(d.left(), &d.send_left, d.right(), &mut d.recv);
            self.take_ghosts(d);
        }
        lost
    }

    /// Send the owned particles outside this rank's layers (`along_z`) or rows to the
    /// neighbour along that axis and take the neighbours' (the last slot fills a hole).
    fn send_leavers(&mut self, d: &mut Domain, along_z: bool, lost: &mut Option<u32>) {
        let sbox = self.sbox;
        let (left, right) = if along_z {
            (d.left(), d.right())
        } else {
            (d.y_left(), d.y_right())
        };
        d.send_left.clear();
        d.send_right.clear();
        let (mut i, mut n) = (0, self.tag.len());
        while i < n {
            let x = self.particles.pos[i];
            let (mine, to) = if along_z {
                let z = CellSort::cell_coordinate(x[2], sbox.l[2], d.nz);
                (d.owns(z), z)
            } else {
                let y = CellSort::cell_coordinate(x[1], sbox.l[1], d.ny);
                (d.owns_row(y), y)
            };
            if mine {
                i += 1;
                continue;
            }
            let to = if along_z { d.owner(to) } else { d.y_owner(to) };
            let tag = self.tag[i];
            // With two ranks along the axis the left and the right neighbour are one rank.
            let buf = if to == right {
                Some(&mut d.send_right)
            } else if to == left {
                Some(&mut d.send_left)
            } else {
                *lost = Some(lost.map_or(tag, |l| l.min(tag)));
                None
            };
            if let Some(buf) = buf {
                buf.push(tag as f64);
                buf.extend_from_slice(&x);
                buf.extend(self.particles.image[i].iter().map(|&k| k as f64));
            }
            n -= 1;
            self.move_slot(n, i);
        }
        self.truncate_slots(n);
        d.comm.shift(right, &d.send_right, left, &mut d.recv);
        self.take_migrants(&d.recv);
        if left != right {
            d.comm.shift(left, &d.send_left, right, &mut d.recv);
            self.take_migrants(&d.recv);
        }
    }

    /// The ghosts just received (tag, position).
    fn take_ghosts(&mut self, d: &mut Domain) {
        let recv = std::mem::take(&mut d.recv);
        for g in recv.chunks_exact(GHOST) {
            self.push_slot(g[0] as u32, [g[1], g[2], g[3]], [0; 3]);
        }
        d.recv = recv;
    }

    fn take_migrants(&mut self, recv: &[f64]) {
        for m in recv.chunks_exact(MIGRANT) {
            let image = [m[4] as i32, m[5] as i32, m[6] as i32];
            self.push_slot(m[0] as u32, [m[1], m[2], m[3]], image);
        }
    }

    /// After the pair forces: the last owned slab's forces on the ghosts go right; the left
    /// rank's on the first owned layer arrive into the halo of the slab before it.
    pub(super) fn exchange_halo(&mut self) {
        let Some(d) = self.domain.as_mut() else {
            return;
        };
        if d.pz == 1 {
            return;
        }
        let last = &self.slabs[d.z1 - 1];
        d.send_right.clear();
        for f in &last.acc[last.end - last.start..] {
            d.send_right.extend_from_slice(f);
        }
        let before = &mut self.slabs[d.before_layer()];
        let halo = &mut before.acc[before.end - before.start..];
        d.recv.resize(3 * halo.len(), 0.0);
        d.comm
            .shift_exact(d.right(), &d.send_right, d.left(), &mut d.recv);
        for (f, m) in halo.iter_mut().zip(d.recv.chunks_exact(3)) {
            *f = [m[0], m[1], m[2]];
        }
    }

    /// The step's largest squared displacement and blow-up of lowest tag, over all ranks; and,
    /// in the same exchange, the ghosts' new positions into their slots of `new_pos` (this
    /// step's positions, the right neighbour's first layer): between list builds the same
    /// slots hold the same particles, and at a build the migration fetches the ghosts anew.
    pub(super) fn agree_on_step(
        &mut self,
        report: ChunkReport,
        new_pos: &mut [[f64; 3]],
    ) -> (f64, Option<BdError>) {
        let local = self.blow_up_error(&report);
        let Some(d) = self.domain.as_mut() else {
            return (report.max_disp2, local);
        };
        d.mine.clear();
        d.mine.push(report.max_disp2);
        match local {
            Some(BdError::BlowUp {
                particle,
                position,
                force,
                drift,
                diameter,
                ..
            }) => {
                d.mine.push(particle as f64);
                d.mine.extend_from_slice(&position);
                d.mine.extend_from_slice(&[force, drift, diameter]);
            }
            _ => d.mine.extend_from_slice(&[-1.0; AGREE - 1]),
        }
        if d.py > 1 {
            // The fringe rows first: the ghost layer sent below includes them.
            let [nx, ny, _] = self.grid.n_cells;
            let rows = |z: usize, y: usize| {
                let c = (z * ny + y) * nx;
                self.grid.cell_start[c] as usize..self.grid.cell_start[c + nx] as usize
            };
            d.refresh_fringe(rows, &mut new_pos[..]);
        }
        if d.pz > 1 {
            let first = &self.slabs[d.z0];
            d.send_left.clear();
            for x in &new_pos[first.start..first.end] {
                d.send_left.extend_from_slice(x);
            }
            let g = &self.slabs[d.ghost_layer()];
            d.recv.resize(3 * (g.end - g.start), 0.0);
            d.agree_and_fetch_ghosts();
            for (x, m) in new_pos[g.start..g.end]
                .iter_mut()
                .zip(d.recv.chunks_exact(3))
            {
                *x = [m[0], m[1], m[2]];
            }
        } else {
            let mine = std::mem::take(&mut d.mine);
            d.comm.all_gather_same(&mine, &mut d.gathered);
            d.mine = mine;
        }
        // NaN never wins, as in one process's reduction.
        let max_disp2 = d
            .gathered
            .chunks_exact(AGREE)
            .fold(0.0f64, |m, g| m.max(g[0]));
        let worst = d
            .gathered
            .chunks_exact(AGREE)
            .filter(|g| g[1] >= 0.0)
            .min_by(|a, b| a[1].total_cmp(&b[1]));
        let error = worst.map(|g| BdError::BlowUp {
            step: self.step,
            time: self.step as f64 * self.params.dt,
            particle: g[1] as usize,
            position: [g[2], g[3], g[4]],
            force: g[5],
            drift: g[6],
            diameter: g[7],
        });
        (max_disp2, error)
    }

    /// [`Self::forces`] of a decomposed run (collective).
    pub(super) fn forces_decomposed(&self) -> Vec<[f64; 3]> {
        let d = self.domain.as_ref().expect("decomposed");
        let mut slabs = self.slabs.clone();
        all_pair_forces(&mut slabs[d.z0..d.z1], &self.particles, &self.pair);
        if d.pz > 1 {
            let last = &slabs[d.z1 - 1];
            let send: Vec<f64> = last.acc[last.end - last.start..]
                .iter()
                .flatten()
                .copied()
                .collect();
            let before = &mut slabs[d.before_layer()];
            let halo = &mut before.acc[before.end - before.start..];
            let mut recv = vec![0.0; 3 * halo.len()];
            d.comm.shift_exact(d.right(), &send, d.left(), &mut recv);
            for (f, m) in halo.iter_mut().zip(recv.chunks_exact(3)) {
                *f = [m[0], m[1], m[2]];
            }
        }
        let t = self.time();
        let mut cursor = PairForceCursor::new(&slabs, &self.slab_of, self.own.0);
        let mut mine = Vec::with_capacity(4 * self.owned());
        for k in self.owned_slots() {
            let fp = cursor.force(k);
            let fe = self
                .external
                .force_on(self.particles.pos[k], t, self.particles.diameter[k]);
            mine.push(self.tag[k] as f64);
            mine.extend_from_slice(&[fp[0] + fe[0], fp[1] + fe[1], fp[2] + fe[2]]);
        }
        let mut out = vec![[0.0; 3]; self.n_particles()];
        for g in self.gather(&mine).chunks_exact(4) {
            out[g[0] as usize] = [g[1], g[2], g[3]];
        }
        out
    }

    /// Every rank's `mine`, concatenated in rank order (collective).
    fn gather(&self, mine: &[f64]) -> Vec<f64> {
        let mut all = Vec::new();
        self.exchange()
            .expect("decomposed")
            .all_gather(mine, &mut all);
        all
    }

    /// [`Self::snapshot`] of a decomposed run (collective).
    pub(super) fn snapshot_decomposed(&self) -> Particles {
        let mut mine = Vec::with_capacity(7 * self.owned());
        for k in self.owned_slots() {
            let (mut x, mut img) = (self.particles.pos[k], self.particles.image[k]);
            self.sbox.wrap(&mut x, &mut img);
            mine.push(self.tag[k] as f64);
            mine.extend_from_slice(&x);
            mine.extend(img.iter().map(|&i| i as f64));
        }
        let mut p = (**self.whole.as_ref().expect("decomposed")).clone();
        for g in self.gather(&mine).chunks_exact(7) {
            let t = g[0] as usize;
            p.pos[t] = [g[1], g[2], g[3]];
            p.image[t] = [g[4] as i32, g[5] as i32, g[6] as i32];
        }
        p
    }

    /// [`Self::list_state`] of a decomposed run (collective), in the whole system's storage
    /// order (each owned slot sent with its place in it).
    pub(super) fn list_state_decomposed(&self) -> ListState {
        let mut mine = Vec::with_capacity(11 * self.owned());
        for &(a, b, g) in &self.runs {
            for k in a..b {
                mine.push((g + k - a) as f64);
                mine.push(self.tag[k] as f64);
                mine.extend_from_slice(&self.ref_pos[k]);
                mine.extend_from_slice(&self.particles.pos[k]);
                mine.extend(self.particles.image[k].iter().map(|&i| i as f64));
            }
        }
        let gathered = self.gather(&mine);
        let mut all = vec![0.0; gathered.len() / 11 * 10];
        for row in gathered.chunks_exact(11) {
            let g = row[0] as usize;
            all[10 * g..10 * g + 10].copy_from_slice(&row[1..]);
        }
        let rows = all.chunks_exact(10);
        ListState {
            order: rows.clone().map(|g| g[0] as u32).collect(),
            reference: rows.clone().map(|g| [g[1], g[2], g[3]]).collect(),
            positions: rows.clone().map(|g| [g[4], g[5], g[6]]).collect(),
            images: rows
                .map(|g| [g[7] as i32, g[8] as i32, g[9] as i32])
                .collect(),
        }
    }

    /// The unwrapped positions `x + image L` in input order into `out` (collective when
    /// decomposed; no allocation on one process once `out` has its length).
    pub fn unwrapped_into(&self, out: &mut Vec<[f64; 3]>) {
        out.resize(self.n_particles(), [0.0; 3]);
        let p = &self.particles;
        if self.domain.is_none() {
            for k in self.owned_slots() {
                out[self.tag[k] as usize] = self.sbox.unwrap(p.pos[k], p.image[k]);
            }
            return;
        }
        let mut mine = Vec::with_capacity(4 * self.owned());
        for k in self.owned_slots() {
            mine.push(self.tag[k] as f64);
            mine.extend_from_slice(&self.sbox.unwrap(p.pos[k], p.image[k]));
        }
        for g in self.gather(&mine).chunks_exact(4) {
            out[g[0] as usize] = [g[1], g[2], g[3]];
        }
    }
}
