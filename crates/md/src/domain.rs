//! A run decomposed in space over ranks ([`Exchange`]): the slab of z-layers of cells each rank
//! owns, its neighbours, the buffers of its messages and the agreements every step needs. The
//! engines ([`crate::dpd`], [`crate::brownian`]) keep their particles; this is what they share.
//!
//! Rank `r` of `P` owns the layers `z0 = r nz / P .. z1 = (r + 1) nz / P` of `nz`. The half
//! stencil of cells ([`crate::cells`]) reaches only the own and the next layer, so a rank needs
//! one ghost layer, `z1 mod nz` (the right neighbour's first layer), and sends the forces its
//! last layer exerts on the ghosts (the *halo*) back to their owner.

use colloidsim_core::exchange::Exchange;

/// This rank's share of a decomposed run.
pub(crate) struct Domain {
    pub comm: Box<dyn Exchange>,
    /// Layers of cells along z.
    pub nz: usize,
    /// Owned layers `z0..z1`.
    pub z0: usize,
    pub z1: usize,
    pub send_left: Vec<f64>,
    pub send_right: Vec<f64>,
    pub recv: Vec<f64>,
    /// Particles that would have to skip a rank (an error, reported after the exchange).
    pub lost: Vec<f64>,
    /// The lowest tag of such a particle since the last agreement on it (`u32::MAX`: none);
    /// DPD agrees on it with the step's velocity check, at the step's end.
    pub lost_tag: u32,
    /// The layer of each owned slot during a migration.
    pub layer: Vec<u32>,
    /// All-gather results.
    pub gathered: Vec<f64>,
    /// This rank's part of an all-gather.
    pub mine: Vec<f64>,
}

impl Domain {
    /// The domain of `comm`'s rank for `nz` layers; an error when there are more ranks than
    /// layers.
    pub fn new(comm: Box<dyn Exchange>, nz: usize, cell_range: f64) -> Result<Self, String> {
        let p = comm.size();
        if nz < p {
            return Err(format!(
                "{p} ranks for {nz} layers of cells along z (cells at least {cell_range:.3} \
                 wide): each rank needs a layer; use at most {nz} ranks or a longer box"
            ));
        }
        let r = comm.rank();
        Ok(Self {
            z0: r * nz / p,
            z1: (r + 1) * nz / p,
            nz,
            comm,
            send_left: Vec::new(),
            send_right: Vec::new(),
            recv: Vec::new(),
            lost: Vec::new(),
            lost_tag: u32::MAX,
            layer: Vec::new(),
            gathered: Vec::new(),
            mine: Vec::new(),
        })
    }

    pub fn left(&self) -> usize {
        let p = self.comm.size();
        (self.comm.rank() + p - 1) % p
    }

    pub fn right(&self) -> usize {
        (self.comm.rank() + 1) % self.comm.size()
    }

    pub fn owner(&self, z: usize) -> usize {
        let p = self.comm.size();
        (0..p).find(|&r| z < (r + 1) * self.nz / p).unwrap_or(p - 1)
    }

    /// Whether layer `z` is this rank's.
    pub fn owns(&self, z: usize) -> bool {
        (self.z0..self.z1).contains(&z)
    }

    /// The ghost layer.
    pub fn ghost_layer(&self) -> usize {
        self.z1 % self.nz
    }

    /// The layer before the first owned one (whose halo holds forces on the first owned layer).
    pub fn before_layer(&self) -> usize {
        (self.z0 + self.nz - 1) % self.nz
    }

    /// The largest of every rank's `value` (ties: the lowest rank) with its `tag`, and the
    /// largest `other`, as `(value, tag, other)`; and the first tag of `bad` (negative: none)
    /// in rank order.
    pub fn agree_max(&mut self, value: f64, tag: f64, other: f64, bad: f64) -> [f64; 4] {
        self.mine.clear();
        self.mine.extend_from_slice(&[value, tag, other, bad]);
        self.comm.all_gather_same(&self.mine, &mut self.gathered);
        self.reduce_max()
    }

    /// The all-gather of `mine` into `gathered` and, in the same exchange, `send_left` to the
    /// left neighbour while the right one's message arrives in `recv` (sized by the caller):
    /// a step's agreement with the ghosts' refresh.
    pub fn agree_and_fetch_ghosts(&mut self) {
        let (left, right) = (self.left(), self.right());
        self.comm.all_gather_and_shift(
            (&self.mine, &mut self.gathered),
            left,
            &self.send_left,
            right,
            &mut self.recv,
        );
    }

    /// [`Self::agree_max`] of the rows `[value, tag, other, bad]` already gathered.
    pub fn reduce_max(&self) -> [f64; 4] {
        let mut out = [f64::NEG_INFINITY, -1.0, f64::NEG_INFINITY, -1.0];
        for g in self.gathered.chunks_exact(4) {
            // NaN never wins, as in the single-rank reduction; an infinity does.
            if g[0] > out[0] {
                out[0] = g[0];
                out[1] = g[1];
            }
            out[2] = out[2].max(g[2]);
            if out[3] < 0.0 && g[3] >= 0.0 {
                out[3] = g[3];
            }
        }
        if out[0] == f64::NEG_INFINITY {
            out[0] = 0.0;
        }
        if out[2] == f64::NEG_INFINITY {
            out[2] = 0.0;
        }
        out
    }

    /// The smallest of every rank's `x`, and of every rank's `y` (one all-gather).
    pub fn agree_min(&mut self, x: u32, y: u32) -> (u32, u32) {
        self.mine.clear();
        self.mine.extend_from_slice(&[x as f64, y as f64]);
        self.comm.all_gather_same(&self.mine, &mut self.gathered);
        self.gathered
            .chunks_exact(2)
            .fold((u32::MAX, u32::MAX), |(a, b), g| {
                (a.min(g[0] as u32), b.min(g[1] as u32))
            })
    }
}
