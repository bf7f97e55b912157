//! The SRD solvent decomposed in space over ranks (issue 20): rank `r` of `P` owns the z-layers
//! `r nz / P .. (r + 1) nz / P` of the collision grid ([`crate::domain`]), and with them every
//! particle whose cell is in those layers *of the grid shifted for the next collision*. A step
//! streams each rank's particles (ballistic, no message), sends those whose shifted cell now
//! lies in another rank's layers to it (the left or the right neighbour; a particle that must
//! go further is passed on in another round), and collides the own cells: a cell's members are
//! then all on one rank, and nothing else is exchanged.
//!
//! A collision is a function of the set of its cell's members (exact sums,
//! [`super::srd::ExactSum`]) and of random streams keyed by (seed, step, row of cells), and
//! sums over all particles are exact too ([`super::srd::ExactTotal`]), so a decomposed run is
//! **bitwise the single-rank run for any number of ranks**, as a set of particles: only the
//! storage order differs, and [`Srd::gathered_state`] puts either in one canonical order.
//!
//! Embedded particles (the vertices of colloids, [`super::colloid`]) are replicated on every
//! rank: each joins the collision of its cell on the rank that owns it, and the new velocities
//! are then shared with every rank, so colloids move alike everywhere. Walls (the droplet)
//! act on each particle where it streams and on the cells each rank collides; the particles a
//! drying droplet removes are chosen from every rank's reflected ones in one canonical order
//! ([`Srd::gathered_bounced`]).

use super::Confinement;
use super::MpcdError;
use super::srd::{ExactTotal, FixedPoint, Grid, Srd, SrdParams};
use crate::domain::Domain;
use crate::state::SimBox;
use colloidsim_core::exchange::Exchange;
use std::cell::RefMut;

/// Numbers per particle in a message: the position in fixed point (three integers below 2^32,
/// exact in an `f64`) and the velocity.
const PER_PARTICLE: usize = 6;
/// The canonical order of solvent particles: fixed-point position (z, y, x), then the bits
/// of the velocity.
type CanonicalKey = ([u32; 3], [u64; 3]);

/// Numbers per migrating particle: those, and whether it was reflected in the streaming step.
const MIGRANT: usize = PER_PARTICLE + 1;

impl std::fmt::Debug for Domain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Domain {{ rank {} of {}, layers {}..{} of {} }}",
            self.comm.rank(),
            self.comm.size(),
            self.z0,
            self.z1,
            self.nz
        )
    }
}

impl Srd {
    /// This rank's part of the solvent, decomposed over the ranks of `comm`: every rank passes
    /// the same whole solvent (built from the same input, at the same step) and keeps the
    /// particles in its layers. An error when there are more ranks than layers of cells.
    /// From then on [`Self::stream`], [`Self::sum`], [`Self::particles`],
    /// [`Self::gathered_state`] and the observables built on them are collective.
    pub fn decomposed(mut self, comm: Box<dyn Exchange>) -> Result<Srd, MpcdError> {
        let grid = *self.grid();
        let domain = Domain::new(comm, grid.n[2], grid.a).map_err(MpcdError::Invalid)?;
        let s = self.fixed_shift(self.step());
        let mut leaving: Vec<u32> = (0..self.len())
            .filter(|&i| !domain.owns(self.layer_of(i, s)))
            .map(|i| i as u32)
            .collect();
        self.remove(&mut leaving);
        self.own_layers(domain.z0, domain.z1);
        self.domain = Some(domain);
        Ok(self)
    }

    /// [`Self::new`] decomposed over the ranks of `comm` from the start, without any rank
    /// holding the whole solvent: each draws the whole start chunk by chunk (the same streams)
    /// and keeps its own particles, the same as `Srd::new(...).decomposed(comm)`.
    pub fn new_decomposed(
        params: SrdParams,
        sbox: SimBox,
        conf: &Confinement,
        t: f64,
        comm: Box<dyn Exchange>,
    ) -> Result<Srd, MpcdError> {
        let grid = Grid::new(&sbox, params.cell)?;
        let domain = Domain::new(comm, grid.n[2], grid.a).map_err(MpcdError::Invalid)?;
        let s = Srd::shift_of(&params, &FixedPoint::new(&sbox), 0)[2];
        let (nz, layers) = (grid.n[2] as u64, domain.z0..domain.z1);
        let own =
            |x: [u32; 3]| layers.contains(&(((x[2].wrapping_sub(s) as u64 * nz) >> 32) as usize));
        let mut srd = Srd::generate(params, sbox, conf, t, own)?;
        srd.own_layers(domain.z0, domain.z1);
        srd.domain = Some(domain);
        Ok(srd)
    }

    /// The ranks, when decomposed.
    pub fn exchange(&self) -> Option<&dyn Exchange> {
        self.domain.as_ref().map(|d| &*d.comm)
    }

    /// This rank and the number of ranks (`(0, 1)` on one process).
    pub fn rank(&self) -> (usize, usize) {
        self.exchange().map_or((0, 1), |c| (c.rank(), c.size()))
    }

    /// The owned layers of cells along z (all of them on one process).
    pub fn layers(&self) -> std::ops::Range<usize> {
        self.domain
            .as_ref()
            .map_or(0..self.grid().n[2], |d| d.z0..d.z1)
    }

    /// Every rank's numbers, that `fill` writes, on every rank: the `.1` of what is returned
    /// (collective; `None` on one process). The messages go through buffers kept by the
    /// engine, so that the collectives of a step allocate nothing; `same`: every rank sends as
    /// many numbers.
    fn gather_with(
        &self,
        same: bool,
        fill: impl FnOnce(&mut Vec<f64>),
    ) -> Option<RefMut<'_, (Vec<f64>, Vec<f64>)>> {
        let c = self.exchange()?;
        let mut buffers = self.gather_buffers.borrow_mut();
        let (mine, all) = &mut *buffers;
        mine.clear();
        fill(mine);
        if same {
            c.all_gather_same(mine, all);
        } else {
            c.all_gather(mine, all);
        }
        Some(buffers)
    }

    /// The number of particles on all ranks (collective when decomposed; [`Self::len`] is
    /// this rank's).
    pub fn particles(&self) -> usize {
        match self.gather_with(true, |m| m.push(self.len() as f64)) {
            Some(g) => g.1.iter().sum::<f64>() as usize,
            None => self.len(),
        }
    }

    /// Every rank's partial totals merged (collective; nothing on one process). Integer
    /// additions: the result does not depend on the split.
    pub(super) fn merge_over_ranks<const K: usize>(&self, acc: &mut [ExactTotal; K]) {
        let Some(g) = self.gather_with(true, |m| m.extend(acc.iter().flat_map(|t| t.words())))
        else {
            return;
        };
        *acc = [ExactTotal::default(); K];
        for part in g.1.chunks_exact(4 * K) {
            for (d, w) in part.chunks_exact(4).enumerate() {
                acc[d].merge(ExactTotal::from_words(w));
            }
        }
    }

    /// Counts summed over all ranks (collective; unchanged on one process).
    pub(super) fn add_over_ranks<const K: usize>(&self, counts: [u64; K]) -> [u64; K] {
        let Some(g) = self.gather_with(true, |m| m.extend(counts.map(|x| x as f64))) else {
            return counts;
        };
        let mut t = [0u64; K];
        for part in g.1.chunks_exact(K) {
            for (d, x) in part.iter().enumerate() {
                t[d] += *x as u64;
            }
        }
        t
    }

    /// The particles every rank reflected in the last streaming step ([`Self::bounced`]), in
    /// the canonical order of [`Self::gathered_state`], each as (rank, slot on that rank)
    /// (collective when decomposed), into `out`.
    pub fn gathered_bounced(&self, out: &mut Vec<(u32, u32)>) {
        let key = |x: [u32; 3], v: [f64; 3]| -> CanonicalKey {
            ([x[2], x[1], x[0]], v.map(f64::to_bits))
        };
        out.clear();
        let rank = self.rank().0 as f64;
        let gathered = self.gather_with(false, |m| {
            for i in self.bounced() {
                let (x, v) = (self.raw_position(i as usize), self.velocity(i as usize));
                m.extend_from_slice(&[x[0] as f64, x[1] as f64, x[2] as f64]);
                m.extend_from_slice(&v);
                m.extend_from_slice(&[rank, i as f64]);
            }
        });
        match gathered {
            Some(g) => {
                // Entry k of every rank's list, sorted by its key, then named by (rank, slot).
                let entry = |k: u32| &g.1[8 * k as usize..8 * k as usize + 8];
                out.extend((0..g.1.len() as u32 / 8).map(|k| (k, 0)));
                out.sort_unstable_by_key(|&(k, _)| {
                    let m = entry(k);
                    key([m[0] as u32, m[1] as u32, m[2] as u32], [m[3], m[4], m[5]])
                });
                for e in out.iter_mut() {
                    let m = entry(e.0);
                    *e = (m[6] as u32, m[7] as u32);
                }
            }
            None => {
                out.extend(self.bounced().map(|i| (0, i)));
                out.sort_unstable_by_key(|&(_, i)| {
                    key(self.raw_position(i as usize), self.velocity(i as usize))
                });
            }
        }
    }

    /// Sums of `f(position, velocity)` and the particle counts in the bins `bin_of(position)`
    /// gives (`None`: no bin) of `bins`, exact in any order and over all ranks (collective
    /// when decomposed).
    pub fn profile(
        &self,
        bins: usize,
        bin_of: impl Fn([f64; 3]) -> Option<usize>,
        f: impl Fn([f64; 3], [f64; 3]) -> f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let mut sums = vec![ExactTotal::default(); bins];
        let mut counts = vec![0.0; bins];
        let view = self.view();
        for i in 0..view.len() {
            let x = view.position(i);
            if let Some(b) = bin_of(x).filter(|&b| b < bins) {
                sums[b].add(f(x, view.velocity(i)));
                counts[b] += 1.0;
            }
        }
        let gathered = self.gather_with(true, |m| {
            for (t, n) in sums.iter().zip(&counts) {
                m.extend_from_slice(&t.words());
                m.push(*n);
            }
        });
        if let Some(g) = gathered {
            sums.iter_mut().for_each(|t| *t = ExactTotal::default());
            counts.iter_mut().for_each(|n| *n = 0.0);
            for part in g.1.chunks_exact(5 * bins) {
                for (b, w) in part.chunks_exact(5).enumerate() {
                    sums[b].merge(ExactTotal::from_words(&w[..4]));
                    counts[b] += w[4];
                }
            }
        }
        (sums.into_iter().map(ExactTotal::value).collect(), counts)
    }

    /// After a collision with embedded particles (replicated on every rank, each collided by
    /// the rank owning its cell): every rank's new velocities of its own embedded particles
    /// on every rank (collective; nothing on one process).
    pub(super) fn share_embedded(&self, vel: &mut [[f64; 3]]) {
        let gathered = self.gather_with(false, |m| {
            for &(_, j) in &self.emb {
                let v = vel[j as usize];
                m.extend_from_slice(&[j as f64, v[0], v[1], v[2]]);
            }
        });
        if let Some(g) = gathered {
            for m in g.1.chunks_exact(4) {
                vel[m[0] as usize] = [m[1], m[2], m[3]];
            }
        }
    }

    /// Sums of `f(position, velocity)` and the particle counts in `bins` slabs along z of the
    /// box (slab `floor((z / L_z + 1/2) bins)`), exact in any order and over all ranks
    /// (collective when decomposed).
    pub fn z_profile(
        &self,
        bins: usize,
        f: impl Fn([f64; 3], [f64; 3]) -> f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let lz = self.sbox().l[2];
        let slab = |x: [f64; 3]| Some((((x[2] / lz + 0.5) * bins as f64) as usize).min(bins - 1));
        self.profile(bins, slab, f)
    }

    /// Send every particle whose cell on the grid of the coming collision is not in the own
    /// layers towards its owner, by the shorter way round, in rounds until none is left; a
    /// non-finite velocity on any rank (`bad`: its slot) stops every rank. Whether a particle
    /// was reflected in the streaming step travels with it, so that [`Self::bounced`] lists
    /// this rank's reflected particles afterwards.
    pub(super) fn migrate(&mut self, bad: Option<usize>) -> Result<(), MpcdError> {
        let s = self.fixed_shift(self.step());
        // Per slot: reflected in the streaming step.
        let mut flags = std::mem::take(&mut self.flags);
        flags.clear();
        flags.resize(self.len(), false);
        for i in self.bounced() {
            flags[i as usize] = true;
        }
        // The first round sends the leavers the streaming step found; later rounds look only
        // at the particles that arrived in the round before (from `first_new` on).
        let mut first_round = true;
        let mut first_new = self.len();
        let outcome = loop {
            let mut d = self.domain.take().expect("migrate: a decomposed engine");
            self.leaving.clear();
            d.send_left.clear();
            d.send_right.clear();
            if bad.is_none() {
                if first_round {
                    for c in 0..self.leavers.len() {
                        for j in 0..self.leavers[c].len() {
                            let i = self.leavers[c][j] as usize;
                            self.send_if_foreign(&mut d, i, s, flags[i]);
                        }
                    }
                } else {
                    for i in first_new..self.len() {
                        self.send_if_foreign(&mut d, i, s, flags[i]);
                    }
                }
            }
            d.mine.clear();
            d.mine
                .extend_from_slice(&[self.leaving.len() as f64, bad.map_or(-1.0, |i| i as f64)]);
            d.comm.all_gather_same(&d.mine, &mut d.gathered);
            let failed = d
                .gathered
                .chunks_exact(2)
                .find(|g| g[1] >= 0.0)
                .map(|g| g[1]);
            let done = d.gathered.chunks_exact(2).all(|g| g[0] == 0.0);
            if failed.is_some() || done {
                self.domain = Some(d);
                break match failed {
                    Some(i) => Err(MpcdError::NonFinite {
                        step: self.step(),
                        what: "solvent",
                        index: i as usize,
                    }),
                    None => Ok(()),
                };
            }
            let mut leaving = std::mem::take(&mut self.leaving);
            // `remove` sorts the slots and fills each, from the highest down, with the last
            // particle: the flags follow the same moves.
            self.remove(&mut leaving);
            for &i in leaving.iter().rev() {
                flags.swap_remove(i as usize);
            }
            self.leaving = leaving;
            first_round = false;
            first_new = self.len();
            let (left, right) = (d.left(), d.right());
            d.comm.shift(right, &d.send_right, left, &mut d.recv);
            self.arrive(&d.recv, &mut flags);
            d.comm.shift(left, &d.send_left, right, &mut d.recv);
            self.arrive(&d.recv, &mut flags);
            self.domain = Some(d);
        };
        // The reflected particles' slots now, in increasing order.
        self.bounced.truncate(1);
        self.bounced.resize_with(1, Vec::new);
        self.bounced[0].clear();
        self.bounced[0].extend((0..flags.len()).filter(|&i| flags[i]).map(|i| i as u32));
        self.flags = flags;
        outcome
    }

    /// Queue slot `i` for its owner's side when its cell is not in the own layers.
    fn send_if_foreign(&mut self, d: &mut Domain, i: usize, s: [u32; 3], reflected: bool) {
        let (nz, z0, z1) = (d.nz, d.z0, d.z1);
        let z = self.layer_of(i, s);
        if d.owns(z) {
            return;
        }
        let ahead = (z + nz - z1) % nz;
        let behind = (z0 + nz - 1 - z) % nz;
        let buf = if ahead <= behind {
            &mut d.send_right
        } else {
            &mut d.send_left
        };
        let (x, v) = (self.raw_position(i), self.velocity(i));
        buf.extend_from_slice(&[x[0] as f64, x[1] as f64, x[2] as f64]);
        buf.extend_from_slice(&v);
        buf.push(reflected as u8 as f64);
        self.leaving.push(i as u32);
    }

    fn arrive(&mut self, msg: &[f64], flags: &mut Vec<bool>) {
        for p in msg.chunks_exact(MIGRANT) {
            self.push([p[0] as u32, p[1] as u32, p[2] as u32], [p[3], p[4], p[5]]);
            flags.push(p[6] != 0.0);
        }
    }

    /// The whole solvent's fixed-point positions and velocities in a canonical order (by
    /// position z, y, x, then by the velocity's bits), the same on one process and over any
    /// number of ranks (collective when decomposed: every rank gets all of it).
    pub fn gathered_state(&self) -> (Vec<[u32; 3]>, Vec<[f64; 3]>) {
        let (pos, vel) = match self.exchange() {
            None => (self.raw_positions(), self.velocities()),
            Some(c) => {
                let mut mine = Vec::with_capacity(PER_PARTICLE * self.len());
                for i in 0..self.len() {
                    let (x, v) = (self.raw_position(i), self.velocity(i));
                    mine.extend_from_slice(&[x[0] as f64, x[1] as f64, x[2] as f64]);
                    mine.extend_from_slice(&v);
                }
                let mut all = Vec::new();
                c.all_gather(&mine, &mut all);
                all.chunks_exact(PER_PARTICLE)
                    .map(|p| ([p[0] as u32, p[1] as u32, p[2] as u32], [p[3], p[4], p[5]]))
                    .unzip()
            }
        };
        let mut all: Vec<([u32; 3], [f64; 3])> = pos.into_iter().zip(vel).collect();
        all.sort_unstable_by_key(|(x, v)| ([x[2], x[1], x[0]], v.map(f64::to_bits)));
        all.into_iter().unzip()
    }
}
