//! The SRD solvent decomposed in space over ranks (issue 20): rank `r` of `P` owns the z-layers
//! `r nz / P .. (r + 1) nz / P` of the collision grid ([`crate::domain`]), and with them every
//! particle whose cell is in those layers *of the grid shifted for the next collision*. A step
//! streams each rank's particles (ballistic, no message), sends those whose shifted cell now
//! lies in another rank's layers to it (the left or the right neighbour; a particle that must
//! go further is passed on in another round), and collides the own cells: a cell's members are
//! then all on one rank, and nothing else is exchanged.
//!
//! A collision is a function of the set of its cell's members (exact sums,
//! [`super::srd::ExactSum`]) and of random streams keyed by (seed, step, row of cells), so a
//! decomposed run is **bitwise the single-rank run for any number of ranks**, as a set of
//! particles: the storage order differs, and [`SrdRanks::gather_state`] and
//! [`canonical_state`] put both in one canonical order to compare them.
//!
//! Not decomposed yet: walls (the droplet) and embedded colloids ([`Srd::decomposed`] refuses
//! nothing itself; the caller must not pass them, and [`SrdRanks::advance`] has no such
//! arguments).

use super::srd::{CollisionStats, Srd};
use super::{Acceleration, Confinement, MpcdError};
use crate::domain::Domain;
use colloidsim_core::exchange::Exchange;

/// Numbers per particle in a message: the position in fixed point (three integers below 2^32,
/// exact in an `f64`) and the velocity.
const PER_PARTICLE: usize = 6;

/// The part of an SRD solvent one rank owns (see the module docs).
pub struct SrdRanks {
    srd: Srd,
    domain: Domain,
    /// Slots leaving in the current migration round.
    leaving: Vec<u32>,
}

impl Srd {
    /// This rank's part of the solvent, decomposed over the ranks of `comm`: every rank passes
    /// the same whole solvent (built from the same input) and keeps the particles in its
    /// layers. An error when there are more ranks than layers of cells.
    pub fn decomposed(mut self, comm: Box<dyn Exchange>) -> Result<SrdRanks, MpcdError> {
        let grid = *self.grid();
        let domain = Domain::new(comm, grid.n[2], grid.a).map_err(MpcdError::Invalid)?;
        let s = self.fixed_shift(self.step());
        let mut leaving: Vec<u32> = (0..self.len())
            .filter(|&i| !domain.owns(self.layer_of(i, s)))
            .map(|i| i as u32)
            .collect();
        self.remove(&mut leaving);
        self.own_layers(domain.z0, domain.z1);
        Ok(SrdRanks {
            srd: self,
            domain,
            leaving,
        })
    }
}

impl SrdRanks {
    /// This rank's particles, as an engine (positions, velocities, step, parameters); its
    /// collisions are those of the own layers.
    pub fn local(&self) -> &Srd {
        &self.srd
    }

    /// The owned layers of cells along z.
    pub fn layers(&self) -> std::ops::Range<usize> {
        self.domain.z0..self.domain.z1
    }

    /// The number of ranks.
    pub fn ranks(&self) -> usize {
        self.domain.comm.size()
    }

    /// The ranks.
    pub fn exchange(&self) -> &dyn Exchange {
        &*self.domain.comm
    }

    /// This rank.
    pub fn rank(&self) -> usize {
        self.domain.comm.rank()
    }

    /// One step on every rank at once: stream for `tau` (driven by `accel`, no walls), hand the
    /// particles to the owners of their cells on the next collision's grid, collide the own
    /// cells. A non-finite velocity on any rank stops every rank with the step (and the slot on
    /// the first rank that has one). Returns this rank's collision counts.
    pub fn advance(&mut self, accel: &Acceleration) -> Result<CollisionStats, MpcdError> {
        let t = (self.srd.step() + 1) as f64 * self.srd.params().tau;
        let bad = match self.srd.stream(t, &Confinement::None, accel) {
            Ok(_) => None,
            Err(MpcdError::NonFinite { index, .. }) => Some(index),
            Err(e) => return Err(e),
        };
        self.migrate(bad)?;
        Ok(self.srd.collide(t, &Confinement::None, None))
    }

    /// Send every particle whose cell on the grid of the coming collision is not in the own
    /// layers towards its owner, by the shorter way round, in rounds until none is left.
    fn migrate(&mut self, bad: Option<usize>) -> Result<(), MpcdError> {
        let s = self.srd.fixed_shift(self.srd.step());
        let (nz, z0, z1) = (self.domain.nz, self.domain.z0, self.domain.z1);
        loop {
            let d = &mut self.domain;
            self.leaving.clear();
            d.send_left.clear();
            d.send_right.clear();
            if bad.is_none() {
                for i in 0..self.srd.len() {
                    let z = self.srd.layer_of(i, s);
                    if d.owns(z) {
                        continue;
                    }
                    let ahead = (z + nz - z1) % nz;
                    let behind = (z0 + nz - 1 - z) % nz;
                    let buf = if ahead <= behind {
                        &mut d.send_right
                    } else {
                        &mut d.send_left
                    };
                    let (x, v) = (self.srd.raw_position(i), self.srd.velocity(i));
                    buf.extend_from_slice(&[x[0] as f64, x[1] as f64, x[2] as f64]);
                    buf.extend_from_slice(&v);
                    self.leaving.push(i as u32);
                }
            }
            d.mine.clear();
            d.mine
                .extend_from_slice(&[self.leaving.len() as f64, bad.map_or(-1.0, |i| i as f64)]);
            d.comm.all_gather_same(&d.mine, &mut d.gathered);
            if let Some(g) = d.gathered.chunks_exact(2).find(|g| g[1] >= 0.0) {
                return Err(MpcdError::NonFinite {
                    step: self.srd.step(),
                    what: "solvent",
                    index: g[1] as usize,
                });
            }
            if d.gathered.chunks_exact(2).all(|g| g[0] == 0.0) {
                return Ok(());
            }
            self.srd.remove(&mut self.leaving);
            let (left, right) = (d.left(), d.right());
            d.comm.shift(right, &d.send_right, left, &mut d.recv);
            Self::arrive(&mut self.srd, &d.recv);
            d.comm.shift(left, &d.send_left, right, &mut d.recv);
            Self::arrive(&mut self.srd, &d.recv);
        }
    }

    fn arrive(srd: &mut Srd, msg: &[f64]) {
        for p in msg.chunks_exact(PER_PARTICLE) {
            srd.push([p[0] as u32, p[1] as u32, p[2] as u32], [p[3], p[4], p[5]]);
        }
    }

    /// Every rank's particles on every rank, in the canonical order of [`canonical_state`]
    /// (collective).
    pub fn gather_state(&mut self) -> (Vec<[u32; 3]>, Vec<[f64; 3]>) {
        let d = &mut self.domain;
        d.mine.clear();
        for i in 0..self.srd.len() {
            let (x, v) = (self.srd.raw_position(i), self.srd.velocity(i));
            d.mine
                .extend_from_slice(&[x[0] as f64, x[1] as f64, x[2] as f64, v[0], v[1], v[2]]);
        }
        d.comm.all_gather(&d.mine, &mut d.gathered);
        let pos: Vec<[u32; 3]> = d
            .gathered
            .chunks_exact(PER_PARTICLE)
            .map(|p| [p[0] as u32, p[1] as u32, p[2] as u32])
            .collect();
        let vel: Vec<[f64; 3]> = d
            .gathered
            .chunks_exact(PER_PARTICLE)
            .map(|p| [p[3], p[4], p[5]])
            .collect();
        canonical(pos, vel)
    }

    /// The number of particles on all ranks (collective).
    pub fn total(&mut self) -> usize {
        let d = &mut self.domain;
        d.mine.clear();
        d.mine.push(self.srd.len() as f64);
        d.comm.all_gather_same(&d.mine, &mut d.gathered);
        d.gathered.iter().sum::<f64>() as usize
    }
}

/// The state of a whole (single-rank) solvent in the canonical order: by fixed-point position
/// (z, y, x), then by the velocity's bits.
pub fn canonical_state(srd: &Srd) -> (Vec<[u32; 3]>, Vec<[f64; 3]>) {
    canonical(srd.raw_positions(), srd.velocities())
}

fn canonical(pos: Vec<[u32; 3]>, vel: Vec<[f64; 3]>) -> (Vec<[u32; 3]>, Vec<[f64; 3]>) {
    let mut all: Vec<([u32; 3], [f64; 3])> = pos.into_iter().zip(vel).collect();
    all.sort_unstable_by_key(|(x, v)| ([x[2], x[1], x[0]], v.map(f64::to_bits)));
    all.into_iter().unzip()
}
