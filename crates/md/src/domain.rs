//! A run decomposed in space over ranks ([`Exchange`]): the slab of z-layers of cells each rank
//! owns, its neighbours, the buffers of its messages and the agreements every step needs. The
//! engines ([`crate::dpd`], [`crate::brownian`]) keep their particles; this is what they share.
//!
//! The ranks form a grid of `py` columns along y by `pz` slabs along z (`rank = rz py + ry`;
//! `py = 1`, slabs, for every engine but DPD). Rank `(ry, rz)` owns the layers
//! `z0 = rz nz / pz .. z1 = (rz + 1) nz / pz` of `nz` and in them the rows of cells
//! `y0 = ry ny / py .. y1 = (ry + 1) ny / py` of `ny`. The half stencil of cells
//! ([`crate::cells`]) reaches only the own and the next layer, so a rank needs one ghost layer,
//! `z1 mod nz` (the first layer of the rank above), and sends the forces its last layer exerts
//! on the ghosts (the *halo*) back to their owner. Along y the stencil reaches a row either
//! way: a rank cut along y holds one *fringe* row of ghosts on each side and computes the
//! pairs across the cut itself (the rank on the other side computes them too), so that every
//! pair of an owned particle is met in the order of one rank (module `dpd::domain`).

use colloidsim_core::exchange::Exchange;

/// What the ghosts of the fringe rows carry between sorts ([`Domain::refresh_fringe`]).
pub(crate) trait FringeState {
    /// Numbers per slot.
    const WIDTH: usize;
    /// Append slot `i`'s numbers to `out`.
    fn read(&self, i: usize, out: &mut Vec<f64>);
    /// Set slot `i` from its numbers.
    fn write(&mut self, i: usize, numbers: &[f64]);
}

/// Positions alone (Brownian dynamics).
impl FringeState for [[f64; 3]] {
    const WIDTH: usize = 3;
    fn read(&self, i: usize, out: &mut Vec<f64>) {
        out.extend_from_slice(&self[i]);
    }
    fn write(&mut self, i: usize, m: &[f64]) {
        self[i] = [m[0], m[1], m[2]];
    }
}

/// Positions and velocities (DPD).
pub(crate) struct PosVel<'a>(pub &'a mut [[f64; 3]], pub &'a mut [[f64; 3]]);

impl FringeState for PosVel<'_> {
    const WIDTH: usize = 6;
    fn read(&self, i: usize, out: &mut Vec<f64>) {
        out.extend_from_slice(&self.0[i]);
        out.extend_from_slice(&self.1[i]);
    }
    fn write(&mut self, i: usize, m: &[f64]) {
        self.0[i] = [m[0], m[1], m[2]];
        self.1[i] = [m[3], m[4], m[5]];
    }
}

/// This rank's share of a decomposed run.
pub(crate) struct Domain {
    pub comm: Box<dyn Exchange>,
    /// Layers of cells along z.
    pub nz: usize,
    /// Owned layers `z0..z1`.
    pub z0: usize,
    pub z1: usize,
    /// Rows of cells along y (1 when the grid has one column).
    pub ny: usize,
    /// Owned rows `y0..y1` of every owned layer.
    pub y0: usize,
    pub y1: usize,
    /// Ranks along y and along z (`py pz` ranks).
    pub py: usize,
    pub pz: usize,
    /// This rank and the number of ranks (kept: asking MPI costs a call, and the migration
    /// asks for every leaver).
    rank: usize,
    size: usize,
    pub send_left: Vec<f64>,
    pub send_right: Vec<f64>,
    pub recv: Vec<f64>,
    /// Particles that would have to skip a rank (an error, reported after the exchange).
    pub lost: Vec<f64>,
    /// The lowest tag of such a particle since the last agreement on it (`u32::MAX`: none);
    /// DPD agrees on it with the step's velocity check, at the step's end.
    pub lost_tag: u32,
    /// All-gather results.
    pub gathered: Vec<f64>,
    /// This rank's part of an all-gather.
    pub mine: Vec<f64>,
}

impl Domain {
    /// The domain of `comm`'s rank for `nz` layers cut into slabs; an error when there are
    /// more ranks than layers.
    pub fn new(comm: Box<dyn Exchange>, nz: usize, cell_range: f64) -> Result<Self, String> {
        let p = comm.size();
        Self::grid(comm, [1, nz], [1, p], cell_range)
    }

    /// The domain of `comm`'s rank on a grid of `py` by `pz` ranks (`[py, pz]`) over `ny` rows
    /// and `nz` layers of cells (`[ny, nz]`); an error naming the limit when the grid does not
    /// fit: a layer per slab, and with `py > 1` a row per column and two rows more than a
    /// column holds (its two fringe rows must be other rows than its own).
    pub fn grid(
        comm: Box<dyn Exchange>,
        [ny, nz]: [usize; 2],
        [py, pz]: [usize; 2],
        cell_range: f64,
    ) -> Result<Self, String> {
        let p = comm.size();
        if py * pz != p {
            return Err(format!(
                "a grid of {py} x {pz} ranks (y x z) for {p} ranks: the product must be the \
                 number of ranks"
            ));
        }
        if nz < pz && py == 1 {
            return Err(format!(
                "{p} ranks for {nz} layers of cells along z (cells at least {cell_range:.3} \
                 wide): each rank needs a layer; use at most {nz} ranks or a longer box"
            ));
        }
        if nz < pz {
            return Err(format!(
                "{pz} ranks along z for {nz} layers of cells (cells at least {cell_range:.3} \
                 wide): each rank needs a layer; use at most {nz} ranks along z or a longer box"
            ));
        }
        if py > 1 && (py > ny || ny.div_ceil(py) + 2 > ny) {
            return Err(format!(
                "{py} ranks along y for {ny} rows of cells (cells at least {cell_range:.3} \
                 wide): a rank cut along y needs its rows and a fringe row on each side; use \
                 fewer ranks along y or a wider box"
            ));
        }
        let r = comm.rank();
        let (ry, rz) = (r % py, r / py);
        Ok(Self {
            z0: rz * nz / pz,
            z1: (rz + 1) * nz / pz,
            nz,
            y0: ry * ny / py,
            y1: (ry + 1) * ny / py,
            ny,
            py,
            pz,
            rank: r,
            size: p,
            comm,
            send_left: Vec::new(),
            send_right: Vec::new(),
            recv: Vec::new(),
            lost: Vec::new(),
            lost_tag: u32::MAX,
            gathered: Vec::new(),
            mine: Vec::new(),
        })
    }

    /// The rank below along z (same column).
    pub fn left(&self) -> usize {
        let p = self.size;
        (self.rank + p - self.py) % p
    }

    /// The rank above along z (same column).
    pub fn right(&self) -> usize {
        (self.rank + self.py) % self.size
    }

    /// The rank of the same slab in the column before along y.
    pub fn y_left(&self) -> usize {
        let r = self.rank;
        r - r % self.py + (r % self.py + self.py - 1) % self.py
    }

    /// The rank of the same slab in the column after along y.
    pub fn y_right(&self) -> usize {
        let r = self.rank;
        r - r % self.py + (r % self.py + 1) % self.py
    }

    /// The rank of this column that owns layer `z`.
    pub fn owner(&self, z: usize) -> usize {
        let rz = (0..self.pz)
            .find(|&k| z < (k + 1) * self.nz / self.pz)
            .unwrap_or(self.pz - 1);
        rz * self.py + self.rank % self.py
    }

    /// The rank of this slab that owns row `y`.
    pub fn y_owner(&self, y: usize) -> usize {
        let ry = (0..self.py)
            .find(|&k| y < (k + 1) * self.ny / self.py)
            .unwrap_or(self.py - 1);
        self.rank - self.rank % self.py + ry
    }

    /// The layers `z0..z1` and rows `y0..y1` rank `r` owns, as `[z0, z1, y0, y1]`.
    pub fn block_of(&self, r: usize) -> [usize; 4] {
        let (ry, rz) = (r % self.py, r / self.py);
        [
            rz * self.nz / self.pz,
            (rz + 1) * self.nz / self.pz,
            ry * self.ny / self.py,
            (ry + 1) * self.ny / self.py,
        ]
    }

    /// Whether this rank holds particles of layer `z`: its own, or the ghost layer.
    pub fn holds_layer(&self, z: usize) -> bool {
        self.owns(z) || (self.pz > 1 && z == self.ghost_layer())
    }

    /// Whether this rank holds particles of row `y`: its own, or a fringe row.
    pub fn holds_row(&self, y: usize) -> bool {
        self.py == 1
            || self.owns_row(y)
            || y == self.y1 % self.ny
            || y == (self.y0 + self.ny - 1) % self.ny
    }

    /// Between sorts: the fringe rows' ghosts refreshed from their owners, who send the first
    /// and the last row of every owned layer (the same particles in the same order as at the
    /// last sort). `rows(z, y)` are the slots of row `y` of layer `z`; `state` reads and writes
    /// a slot's numbers.
    pub fn refresh_fringe<S: FringeState + ?Sized>(
        &mut self,
        rows: impl Fn(usize, usize) -> std::ops::Range<usize>,
        state: &mut S,
    ) {
        let ny = self.ny;
        let below = (self.y0 + ny - 1) % ny;
        for (send, to, recv, from) in [
            (self.y0, self.y_left(), self.y1 % ny, self.y_right()),
            (self.y1 - 1, self.y_right(), below, self.y_left()),
        ] {
            self.send_left.clear();
            let mut m = 0;
            for z in self.z0..self.z1 {
                for i in rows(z, send) {
                    state.read(i, &mut self.send_left);
                }
                m += rows(z, recv).len();
            }
            self.recv.resize(S::WIDTH * m, 0.0);
            self.comm
                .shift_exact(to, &self.send_left, from, &mut self.recv);
            let mut numbers = self.recv.chunks_exact(S::WIDTH);
            for z in self.z0..self.z1 {
                for i in rows(z, recv) {
                    state.write(i, numbers.next().expect("one row per slot"));
                }
            }
        }
    }

    /// Whether row `y` is this rank's.
    pub fn owns_row(&self, y: usize) -> bool {
        (self.y0..self.y1).contains(&y)
    }

    /// The grid `[py, pz]` for `p` ranks over `[nx, ny, nz]` cells that costs the least per
    /// rank in ghosts (ties: fewer columns), among those [`Self::grid`] accepts; `y_cuts`
    /// false: slabs only. A slab holds a ghost layer (`nx ny` cells when `pz > 1`); a column
    /// also a fringe row on each side of each of its layers, whose pairs it computes too: a
    /// fringe cell counts as four ghost-layer cells (sorted and copied, a third of a cell's
    /// step, against a whole step and that; docs/parallel.md). So slabs for a few ranks, and
    /// columns as the ranks approach or pass the number of layers.
    pub fn choose_grid(p: usize, [nx, ny, nz]: [usize; 3], y_cuts: bool) -> [usize; 2] {
        let mut best: Option<(usize, [usize; 2])> = None;
        for py in 1..=p {
            if !p.is_multiple_of(py) || (py > 1 && (!y_cuts || py > ny || ny.div_ceil(py) + 2 > ny))
            {
                continue;
            }
            let pz = p / py;
            if nz < pz {
                continue;
            }
            let slab = if pz > 1 {
                nx * (ny.div_ceil(py) + if py > 1 { 2 } else { 0 })
            } else {
                0
            };
            let fringe = if py > 1 { 2 * nx * nz.div_ceil(pz) } else { 0 };
            let cost = slab + 4 * fringe;
            if best.is_none_or(|(c, _)| cost < c) {
                best = Some((cost, [py, pz]));
            }
        }
        // None fits: slabs, refused by `grid` with the limit in the message.
        best.map_or([1, p], |(_, g)| g)
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

#[cfg(test)]
mod tests {
    use super::Domain;

    #[test]
    fn the_grid_chosen_is_slabs_where_they_fit_and_columns_beyond() {
        // The L = 30 water box: slabs up to 30 ranks.
        assert_eq!(Domain::choose_grid(4, [30, 30, 30], true), [1, 4]);
        assert_eq!(Domain::choose_grid(30, [30, 30, 30], true), [1, 30]);
        // Beyond: as few columns as the layers allow, each with two fringe rows.
        assert_eq!(Domain::choose_grid(60, [30, 30, 30], true), [2, 30]);
        assert_eq!(Domain::choose_grid(6, [5, 5, 5], true), [2, 3]);
        // Sheared runs (no y cuts), and grids that do not fit: slabs, refused by `grid`.
        assert_eq!(Domain::choose_grid(6, [5, 5, 5], false), [1, 6]);
        assert_eq!(Domain::choose_grid(13, [11, 11, 11], true), [1, 13]);
    }
}
