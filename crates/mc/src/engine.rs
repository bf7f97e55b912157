//! The hard-sphere NVT Monte Carlo engine: single-particle displacement moves on a grid of
//! cells, updated layer by layer in parallel.
//!
//! # Algorithm
//!
//! The periodic box (the bulk cube, or a cube around the droplet with [`Geometry::box_edge`]'s
//! margin) is tiled by `nc^3` cubic cells of side `s = L / nc >= d` (`d` the largest diameter
//! of a mixture), `nc` a multiple of 4 (or 2 in short boxes).
//! A sweep is:
//!
//! 1. draw a random grid offset uniform in `[0, s)^3` and a random order of the two parities of
//!    the z layers (even `iz`, odd `iz`) from the stream `(seed, sweep, Moves, 0)`;
//! 2. bin every particle into the shifted grid (a parallel counting sort that keeps particle
//!    order within each cell), storing its position relative to its cell's corner;
//! 3. for each parity in turn, every layer of that parity (concurrently, with rayon, one task per
//!    layer) visits its `nc^2` cells in storage order, and each cell makes `nselect` (default 1)
//!    times as many trial moves as it holds particles: pick one of its particles uniformly,
//!    displace it uniformly in the cube `[-delta, delta)^3`, reject the move if the new centre
//!    leaves the cell, leaves the container, or overlaps any sphere (a centre distance below
//!    the pair's mean diameter), and (interface geometry) accept it with the Metropolis
//!    probability `min(1, exp(-beta dV))`. Layers of one parity
//!    are a layer apart, `s >= d`, so a sphere moving in one can touch only spheres of its own
//!    layer (updated in turn by the same task) and of the two layers beside it, which have the
//!    other parity and stay fixed during the pass;
//! 4. write the positions back in particle order.
//!
//! This is a domain form of the checkerboard scheme of Anderson, Jankowski, Grubb, Engel,
//! Glotzer, J. Comput. Phys. 254, 27 (2013) (HOOMD-blue HPMC): two colours of whole layers
//! instead of eight colours of cells, so a sweep has two parallel passes instead of eight, and
//! a task's work is a whole layer. Each elementary move keeps detailed balance with respect to
//! the hard-sphere Boltzmann distribution: with the grid fixed, the number of particles in a
//! cell does not change during the sweep, so the pick is symmetric; the displacement is
//! symmetric; moves out of the cell are rejected in both directions. The sweep is a composition
//! of such moves (balance holds), and the random offset and parity order make it ergodic. A
//! sweep makes exactly `nselect N` trial moves (HOOMD-blue's `nselect`, default 1 here): more
//! moves per binning share its cost (the binning and write-back are a third of a sweep at
//! `nselect = 1` and scale worse than the moves); the offset is drawn anew every sweep.
//!
//! Random numbers: layer `k` of parity `p` draws from the stream `(seed, sweep, Moves,
//! 1 + p nc/2 + k)`, so a run is a pure function of its seed and the result does not depend on
//! the number of threads.
//!
//! Memory: positions live twice, in particle order (`pos`, structure of arrays) and in the cell
//! slots (`slot`, fixed capacity per cell, the even layers stored before the odd ones so that a
//! parity's layers are one contiguous mutable range while the other parity is read-only). Per
//! particle the binning keeps only its cell and slot. Nothing is allocated per move or per
//! sweep (only when a cell overflows its capacity, which grows).

pub mod chain;
pub mod pair;

use crate::geometry::Geometry;
use colloidsim_core::ParamError;
use colloidsim_core::param::{positive, show};
use colloidsim_core::resources::ensure_fits;
use colloidsim_core::rng::{Purpose, stream};
pub use colloidsim_particles::Mixture;
use colloidsim_particles::PairSpec;
use pair::{SoftPair, SoftPass};
use rand::Rng;
use rayon::prelude::*;
use thiserror::Error;

/// Errors of the Monte Carlo engine.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum McError {
    /// A parameter is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// Two spheres of the initial configuration overlap.
    #[error(
        "{key}: spheres {i} and {j} overlap (centre distance {distance:.6} < diameter {diameter}); a hard-sphere configuration needs every centre distance >= d (the pair's mean diameter in a mixture)"
    )]
    Overlap {
        /// Scenario key of the configuration.
        key: String,
        /// First sphere.
        i: usize,
        /// Second sphere.
        j: usize,
        /// Their centre distance.
        distance: f64,
        /// Their contact distance: the diameter, or the pair's mean diameter `(d_i + d_j) / 2`.
        diameter: f64,
    },
    /// A sphere of the initial configuration lies outside its container.
    #[error(
        "{key}: sphere {i} has its centre at distance {r:.6} from the droplet centre, beyond the allowed {max:.6} (hard wall: radius - d/2)"
    )]
    OutsideWall {
        /// Scenario key of the configuration.
        key: String,
        /// The sphere.
        i: usize,
        /// Its centre distance.
        r: f64,
        /// The largest allowed centre distance.
        max: f64,
    },
}

/// Settings of [`HardSphereMc`].
#[derive(Debug, Clone, PartialEq)]
pub struct McParams {
    /// Sphere diameter d (length unit): the diameter of every sphere when `mixture` is `None`;
    /// with a mixture, the reference diameter the geometry's lengths were given for (the
    /// interface's `offset`, see [`Geometry::confinement_of`]).
    pub diameter: f64,
    /// Container.
    pub geometry: Geometry,
    /// Seed of the random streams.
    pub seed: u32,
    /// Initial half-width of the trial displacement cube.
    pub delta: f64,
    /// The species of an additive mixture (`None`: one species, every sphere of `diameter`):
    /// spheres `i` and `j` overlap when their centre distance is below `(d_ti + d_tj) / 2`; the
    /// positions are species by species (the first `counts[0]` of species 0, and so on).
    pub mixture: Option<Mixture>,
}

/// Counts of one or more sweeps.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SweepStats {
    /// Trial moves (N per sweep).
    pub trials: u64,
    /// Accepted moves.
    pub accepted: u64,
    /// Moves rejected because the new centre left its cell.
    pub left_cell: u64,
}

impl SweepStats {
    /// Accepted / trials (0 for no trials).
    pub fn acceptance(&self) -> f64 {
        if self.trials == 0 {
            0.0
        } else {
            self.accepted as f64 / self.trials as f64
        }
    }
}

impl std::ops::AddAssign for SweepStats {
    fn add_assign(&mut self, o: Self) {
        self.trials += o.trials;
        self.accepted += o.accepted;
        self.left_cell += o.left_cell;
    }
}

/// What the moves of a cell, a layer or a sweep did: moves accepted, moves rejected for
/// leaving their cell, and the sum of the accepted moves' `beta dU` of the pair interaction.
#[derive(Debug, Clone, Copy, Default)]
struct Tally {
    accepted: u64,
    left: u64,
    beta_pair_du: f64,
}

impl std::ops::AddAssign for Tally {
    fn add_assign(&mut self, o: Self) {
        self.accepted += o.accepted;
        self.left += o.left;
        self.beta_pair_du += o.beta_pair_du;
    }
}

/// Which neighbour cells a colour pass reads: the slots below and above the colour's range.
#[derive(Clone, Copy)]
struct Frozen<'a> {
    below: [&'a [f64]; 3],
    above: [&'a [f64]; 3],
    /// First and one-past-last slot of the active colour.
    lo: usize,
    hi: usize,
}

impl<'a> Frozen<'a> {
    /// Coordinates of the `n` particles of the (inactive) cell whose slots start at `base`.
    #[inline(always)]
    fn cell(&self, base: usize, n: usize) -> [&'a [f64]; 3] {
        if base < self.lo {
            self.below.map(|s| &s[base..base + n])
        } else {
            let b = base - self.hi;
            self.above.map(|s| &s[b..b + n])
        }
    }
}

/// Everything a cell's pass needs apart from the slots (copied into each task).
#[derive(Clone, Copy)]
struct Pass {
    /// Largest sphere radius (half the largest diameter, times the growth scale).
    r_max: f64,
    /// Reference radius (half [`McParams::diameter`]): a sphere of another radius `r` sees the
    /// container's confinement and energy shifted by `r - r_ref` ([`Geometry::confinement_of`]).
    r_ref: f64,
    side: f64,
    edge: f64,
    nc: usize,
    half: usize,
    cap: usize,
    /// Trial moves per sphere per sweep.
    nselect: usize,
    delta: f64,
    seed: u32,
    sweep: u64,
    offset: [f64; 3],
    /// Distance of the box's lower face from the shifted grid's origin, per axis
    /// (`L/2 - offset`), and `1/s`.
    shift: [f64; 3],
    inv_side: f64,
    geometry: Geometry,
    /// Largest centre distance from the droplet centre of a sphere of radius `r_ref` (infinite
    /// in bulk).
    confine: f64,
    /// Whether the confinement shrinks by `r - r_ref` for a sphere of radius `r`.
    shrinks: bool,
}

/// A uniform deviate in [0, 1) from 53 bits.
#[inline(always)]
fn unit(bits: u64) -> f64 {
    (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniform integer in `0..n` from 64 bits (multiply-shift; bias below n / 2^64).
#[inline(always)]
fn below(bits: u64, n: usize) -> usize {
    ((bits as u128 * n as u128) >> 64) as usize
}

impl Pass {
    /// Grid coordinates of the cell with storage index `id` (see [`Self::id`]).
    #[inline(always)]
    fn coords(&self, id: usize) -> [usize; 3] {
        let (nc, h) = (self.nc, self.half);
        let layer = id / (nc * nc);
        [id % nc, (id / nc) % nc, 2 * (layer % h) + layer / h]
    }

    /// Storage index of the cell at grid coordinates `c`: layer by layer along z, the even
    /// layers first, each layer row by row (`(parity h + iz / 2) nc^2 + iy nc + ix`).
    #[inline(always)]
    fn id(&self, c: [usize; 3]) -> usize {
        let (nc, h) = (self.nc, self.half);
        ((c[2] & 1) * h + (c[2] >> 1)) * nc * nc + c[1] * nc + c[0]
    }

    /// The shifted grid's cell index along axis `a` of the coordinate `x` (relative to the box
    /// centre, in `[-L/2, L/2)`), the position relative to that cell's lower face (in
    /// `[0, s]`), and the face's coordinate. The binning and the write-back both call it on the
    /// same inputs, so they agree to the bit.
    #[inline(always)]
    fn locate(&self, x: f64, a: usize) -> (usize, f64, f64) {
        let mut t = x + self.shift[a];
        if t < 0.0 {
            t += self.edge;
        }
        let j = ((t * self.inv_side) as usize).min(self.nc - 1);
        let face = j as f64 * self.side;
        (j, (t - face).clamp(0.0, self.side), face - self.shift[a])
    }

    /// The cell (storage index) of the point `(x, y, z)` and its position relative to the
    /// cell's corner.
    #[inline(always)]
    fn bin(&self, x: f64, y: f64, z: f64) -> (usize, [f64; 3]) {
        let (jx, ux, _) = self.locate(x, 0);
        let (jy, uy, _) = self.locate(y, 1);
        let (jz, uz, _) = self.locate(z, 2);
        (self.id([jx, jy, jz]), [ux, uy, uz])
    }

    /// Position of the centre of the cell at grid coordinates `c` relative to the box centre
    /// (minimum image).
    #[inline(always)]
    fn cell_centre(&self, c: [usize; 3]) -> [f64; 3] {
        std::array::from_fn(|a| {
            let mut x = -0.5 * self.edge + self.offset[a] + (c[a] as f64 + 0.5) * self.side;
            if x >= 0.5 * self.edge {
                x -= self.edge;
            }
            x
        })
    }

    /// The first slot (global index) and the slots to scan of the 27 cells around (index
    /// `9 dz + 3 dy + dx`, the own cell at 13; `around`: the grid coordinates below, at and
    /// above along each axis): the slots up to the count rounded up to whole vectors of eight.
    #[inline(always)]
    fn stencil(&self, around: [&[usize; 3]; 3], counts: &[u32]) -> ([usize; 27], [usize; 27]) {
        let mut base = [0usize; 27];
        let mut len = [0usize; 27];
        for (dz, &jz) in around[2].iter().enumerate() {
            for (dy, &jy) in around[1].iter().enumerate() {
                for (dx, &jx) in around[0].iter().enumerate() {
                    let j = self.id([jx, jy, jz]);
                    base[9 * dz + 3 * dy + dx] = j * self.cap;
                    len[9 * dz + 3 * dy + dx] = (counts[j] as usize).next_multiple_of(8);
                }
            }
        }
        (base, len)
    }

    /// The trial moves of one active layer: the `k`-th layer of parity `parity` (grid layer
    /// `iz = 2 k + parity`), whose `nc^2` cells' slots are `layer`, cell after cell in storage
    /// order; one random stream per layer, `(seed, sweep, Moves, 1 + parity h + k)`. Returns
    /// (accepted, left their cell).
    fn layer_moves(
        &self,
        parity: usize,
        k: usize,
        layer: [&mut [f64]; 3],
        radii: &[f64],
        counts: &[u32],
        frozen: &Frozen<'_>,
        soft: Option<&SoftPass<'_>>,
    ) -> Tally {
        let (h, nc, cap) = (self.half, self.nc, self.cap);
        let first = (parity * h + k) * nc * nc;
        if counts[first..first + nc * nc].iter().all(|&c| c == 0) {
            return Tally::default();
        }
        let around = |i: usize| {
            [
                if i == 0 { nc - 1 } else { i - 1 },
                i,
                if i + 1 == nc { 0 } else { i + 1 },
            ]
        };
        let zs = around(2 * k + parity);
        let mut rng = stream(
            self.seed,
            self.sweep,
            Purpose::Moves,
            1 + (parity * h + k) as u64,
        );
        let [mut lx, mut ly, mut lz] = layer;
        let mut tally = Tally::default();
        for iy in 0..nc {
            let ys = around(iy);
            for ix in 0..nc {
                let n = counts[first + iy * nc + ix] as usize;
                if n == 0 {
                    continue;
                }
                let xs = around(ix);
                tally += self.cell_moves(
                    [&xs, &ys, &zs],
                    [&mut lx, &mut ly, &mut lz],
                    radii,
                    first * cap,
                    n,
                    counts,
                    frozen,
                    soft,
                    &mut rng,
                );
            }
        }
        tally
    }

    /// The trial moves of one active cell (`around`: the grid coordinates below, at and above
    /// it along each axis, wrapped): `nselect` times as many as it holds particles. `layer`
    /// holds the slots of its layer, whose first slot has global index `layer_base`: the cell's
    /// own `cap` slots (positions relative to its corner, the `n` occupied ones first and
    /// [`EMPTY`] beyond) and those of its eight neighbours in the layer, which the same task
    /// updates in turn; the neighbours above and below are read from `frozen`; `radii` holds
    /// every slot's sphere radius (global slot index; fixed during the sweep). Returns
    /// (accepted, left the cell).
    ///
    /// A sphere of radius `r_p` moved to `u` can touch only the neighbour cells within
    /// `r_p + r_max` of `u`: along each axis the lower one when `u < r_p + r_max`, the upper one
    /// when `u > s - r_p - r_max` (one species, `s >= 2 d`: about 7 of the 27 cells). Each is scanned over all its slots (empty ones hold [`EMPTY`], far from
    /// everything), a fixed-length loop that vectorises and never mispredicts its end.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn cell_moves(
        &self,
        around: [&[usize; 3]; 3],
        layer: [&mut [f64]; 3],
        radii: &[f64],
        layer_base: usize,
        n: usize,
        counts: &[u32],
        frozen: &Frozen<'_>,
        pair: Option<&SoftPass<'_>>,
        rng: &mut impl Rng,
    ) -> Tally {
        let [lx, ly, lz] = layer;
        let (s, cap) = (self.side, self.cap);
        let c = [around[0][1], around[1][1], around[2][1]];
        let own = self.id(c) * cap - layer_base;
        let (base, len) = self.stencil(around, counts);
        let centre = self.cell_centre(c);
        let half_side = 0.5 * s;
        let at =
            |u: [f64; 3]| -> [f64; 3] { std::array::from_fn(|a| centre[a] + u[a] - half_side) };
        let soft_wall = self.geometry.is_soft();
        let mut tally = Tally::default();
        let own_radii = &radii[layer_base..];
        for _ in 0..n * self.nselect {
            let p = own + below(rng.next_u64(), n);
            let rp = own_radii[p];
            // One species: rp + r_max = d and h = 0, exactly.
            let reach = rp + self.r_max;
            let h = rp - self.r_ref;
            let range = |u: f64| (usize::from(u >= reach), 1 + usize::from(u > s - reach));
            let step = |b: u64| self.delta * (2.0 * unit(b) - 1.0);
            let new = [
                lx[p] + step(rng.next_u64()),
                ly[p] + step(rng.next_u64()),
                lz[p] + step(rng.next_u64()),
            ];
            if !new.iter().all(|&u| (0.0..s).contains(&u)) {
                tally.left += 1;
                continue;
            }
            let r = at(new);
            let confine = if self.shrinks {
                self.confine - h
            } else {
                self.confine
            };
            if r[0] * r[0] + r[1] * r[1] + r[2] * r[2] > confine * confine {
                continue;
            }
            // Hard spheres: an overlap is a rejection; a pair interaction: its energy change.
            let mut beta_du = 0.0;
            if let Some(pair) = pair {
                let old = [lx[p], ly[p], lz[p]];
                let layer = [&*lx, &*ly, &*lz];
                beta_du = self.pair_energy_change(
                    pair,
                    (p, old, new),
                    own,
                    &base,
                    layer,
                    layer_base,
                    radii,
                    counts,
                    frozen,
                );
            } else {
                // The own cell, without p itself.
                let mut hit = false;
                for q in own..own + len[13] {
                    let (a, b, cc) = (new[0] - lx[q], new[1] - ly[q], new[2] - lz[q]);
                    let contact = rp + own_radii[q];
                    hit |= (a * a + b * b + cc * cc < contact * contact) & (q != p);
                }
                let (xr, yr, zr) = (range(new[0]), range(new[1]), range(new[2]));
                'scan: for dz in zr.0..=zr.1 {
                    for dy in yr.0..=yr.1 {
                        for dx in xr.0..=xr.1 {
                            let k = 9 * dz + 3 * dy + dx;
                            if hit {
                                break 'scan;
                            }
                            if k == 13 || len[k] == 0 {
                                continue;
                            }
                            let [x, y, z] = if dz == 1 {
                                let b = base[k] - layer_base..base[k] - layer_base + len[k];
                                [&lx[b.clone()], &ly[b.clone()], &lz[b]]
                            } else {
                                frozen.cell(base[k], len[k])
                            };
                            // The sphere's position relative to our corner is its own plus the
                            // offset of its cell; move the offset to the trial position instead.
                            let q = [
                                new[0] - (dx as f64 - 1.0) * s,
                                new[1] - (dy as f64 - 1.0) * s,
                                new[2] - (dz as f64 - 1.0) * s,
                            ];
                            let rq = &radii[base[k]..base[k] + len[k]];
                            hit = any_within(x, y, z, rq, q, rp);
                        }
                    }
                }
                if hit {
                    continue;
                }
            }
            let pair_du = beta_du;
            if soft_wall {
                beta_du += self.geometry.beta_energy_of(r, h)
                    - self.geometry.beta_energy_of(at([lx[p], ly[p], lz[p]]), h);
            }
            // Metropolis (NaN, infinite energies on both sides, is a rejection too).
            if (pair.is_some() || soft_wall)
                && !(beta_du <= 0.0 || unit(rng.next_u64()) < (-beta_du).exp())
            {
                continue;
            }
            lx[p] = new[0];
            ly[p] = new[1];
            lz[p] = new[2];
            tally.accepted += 1;
            tally.beta_pair_du += pair_du;
        }
        tally
    }
}

/// Coordinate of an empty slot: far from every position, so that fixed-length scans over all
/// the slots of a cell never see it as a neighbour (its squared distances stay finite).
pub(crate) const EMPTY: f64 = 1e30;

/// Whether any of the spheres at `(x, y, z)` of radii `r` (a cell's slots, a multiple of
/// eight) overlaps a sphere of radius `rp` at `p` (centre distance below `rp + r`): a
/// fixed-length, branch-free loop that vectorises.
#[inline(always)]
fn any_within(x: &[f64], y: &[f64], z: &[f64], r: &[f64], p: [f64; 3], rp: f64) -> bool {
    let mut hit = false;
    for (((x, y), z), r) in x.iter().zip(y).zip(z).zip(r) {
        let (a, b, c) = (p[0] - x, p[1] - y, p[2] - z);
        let contact = rp + r;
        hit |= a * a + b * b + c * c < contact * contact;
    }
    hit
}

/// Hard spheres in a [`Geometry`], moved by checkerboard Monte Carlo sweeps.
#[derive(Debug, Clone)]
pub struct HardSphereMc {
    /// Reference diameter ([`McParams::diameter`]).
    diameter: f64,
    /// Diameter of each species.
    diameters: Vec<f64>,
    /// Species of each sphere.
    types: Vec<u32>,
    /// Radius of each sphere: half its species' diameter, times `scale`.
    radius: Vec<f64>,
    /// Factor on every diameter: 1 except while [`Self::grow`] inflates a compressed start.
    scale: f64,
    /// Largest species diameter.
    d_max: f64,
    geometry: Geometry,
    seed: u32,
    delta: f64,
    /// Trial moves per sphere per sweep (HOOMD-blue's `nselect`).
    nselect: usize,
    sweep: u64,
    edge: f64,
    nc: usize,
    side: f64,
    /// Positions in particle order, relative to the box (droplet) centre, in [-L/2, L/2).
    pos: [Vec<f64>; 3],
    /// Slots per cell.
    cap: usize,
    /// Particles per cell (storage order).
    count: Vec<u32>,
    /// Position relative to the cell's corner, per slot.
    slot: [Vec<f64>; 3],
    /// Particle index per slot.
    tag: Vec<u32>,
    /// Sphere radius per slot (0 in empty slots).
    slot_r: Vec<f64>,
    /// Grid offset of the current binning.
    offset: [f64; 3],
    /// Per particle: its cell and its slot (scratch of the binning, kept to avoid allocating
    /// per sweep).
    cell_of: Vec<u32>,
    slot_of: Vec<u32>,
    /// Scratch of the parallel binning: per part and cell, the part's count and its running
    /// count; per cell, the running count of the cell's filler.
    part_count: Vec<u32>,
    part_seen: Vec<u32>,
    cell_seen: Vec<u32>,
    /// Per part, its particles grouped by the range of cells they fall in, and where each
    /// range's group ends.
    bucket: Vec<u32>,
    bucket_end: Vec<u32>,
    /// Event chains instead of local moves ([`chain`]).
    chain: Option<chain::EventChain>,
    /// The chains' cell list (scratch).
    chain_cells: chain::ChainCells,
    /// Counts of the last sweep's chains.
    last_chain: chain::ChainStats,
    /// The cells' slots hold the current positions (false after event chains, which move
    /// `pos` alone: [`Self::bin`] brings them up to date).
    binned: bool,
    /// A pair interaction in place of the hard cores ([`Self::with_pair`]).
    pair: Option<SoftPair>,
    /// The pair energy change of the last sweep's accepted moves (with a pair interaction).
    last_pair_energy_change: Option<f64>,
}

/// Half of `diameter` times `scale` (exactly `diameter / 2` at scale 1).
fn radius_of(diameter: f64, scale: f64) -> f64 {
    if scale == 1.0 {
        0.5 * diameter
    } else {
        0.5 * diameter * scale
    }
}

/// Fewest particles per part of the parallel binning.
const REBIN_PART_MIN: usize = 1024;

/// Smallest cell side, in diameters (see [`HardSphereMc::new`]).
const CELL_MIN: f64 = 2.0;

/// Cells per box edge: the largest multiple of 4 whose cells have side `>= CELL_MIN d` (fewer,
/// fuller cells: fewer moves leave their cell, and the gathered neighbours amortise over more
/// moves), or 2 in boxes too short for 4 such cells (then `s >= d`, the edge being `>= 2 d`).
/// A multiple of 4 gives each parity an even number of layers, which two threads share
/// equally (an odd number of 5 layers capped 2 threads at 5/3 = 1.67x; docs/reports/mc-validation.md, "Speed").
/// A function of the geometry alone, so a run does not depend on the thread count.
fn cells_per_edge(edge: f64, d: f64) -> usize {
    let fit = (edge / (CELL_MIN * d)).floor() as usize;
    (fit - fit % 4).max(2)
}

/// Refuse a container whose grid of cells (side >= `d`) is far larger than its `n` spheres
/// need: a sweep visits every cell, so the run would spend its time (and the slots' memory) on
/// empty cells. Checked before the spheres are placed (placing them on a lattice is as costly).
pub(crate) fn check_cell_count(edge: f64, d: f64, n: usize) -> Result<(), McError> {
    let nc = cells_per_edge(edge, d);
    let cells = (nc as f64).powi(3);
    let most = (CELLS_PER_SPHERE * n as f64).max(MIN_CELL_BOUND);
    if cells > most {
        return Err(ParamError::new(
            "system",
            format!(
                "{nc}^3 = {cells:.3e} cells of side >= d for {n} spheres (a volume fraction of \
                 {:.1e}): each sweep visits every cell, so the run would spend its time on \
                 empty cells; at most {most:.3e} cells (volume fraction about 1e-4): use a \
                 smaller container or more spheres",
                n as f64 * std::f64::consts::PI / 6.0 * d.powi(3) / edge.powi(3)
            ),
        )
        .into());
    }
    Ok(())
}

/// Cells of the grid per sphere at most (a volume fraction of about 1e-4), above
/// [`MIN_CELL_BOUND`].
const CELLS_PER_SPHERE: f64 = 4096.0;

/// Cells any container may have whatever its spheres (64^3).
const MIN_CELL_BOUND: f64 = 262_144.0;

/// Largest delta the tuner may choose, in cell sides (a larger cube always leaves the cell).
const MAX_DELTA_PER_SIDE: f64 = 0.5;

impl HardSphereMc {
    /// Spheres at `positions` (relative to the box centre, or the droplet centre), of the
    /// species of `params.mixture` (or all of `params.diameter`). Errors: parameters out of
    /// range, overlaps (centre distance below the pair's mean diameter), centres outside the
    /// container, a cell grid larger than the memory (`key` names where the positions came from
    /// in messages; other errors name the parameter: `diameter`, `diameters`, `counts`, `delta`,
    /// `radius`, `box`).
    pub fn new(params: &McParams, positions: &[[f64; 3]], key: &str) -> Result<Self, McError> {
        Self::new_scaled(params, positions, key, 1.0, None)
    }

    /// Spheres at `positions` as [`Self::new`], interacting by the pair interaction `pair` at
    /// thermal energy `kt` in place of the hard cores (the container stays as it is; module
    /// [`pair`]): the cells are at least the interaction's range. Errors as `new`, and: the
    /// range beyond half the box (key `box`) or, in a droplet, beyond eight largest diameters
    /// (`pair_range`); a pair of the positions at infinite energy (`key`); the interaction's own
    /// parameters (named as in [`PairSpec::build`]).
    pub fn with_pair(
        params: &McParams,
        positions: &[[f64; 3]],
        key: &str,
        pair: &PairSpec,
        kt: f64,
    ) -> Result<Self, McError> {
        Self::new_scaled(params, positions, key, 1.0, Some((pair, kt)))
    }

    /// [`Self::new`] with every diameter times `scale` (in (0, 1]): the compressed start that
    /// [`Self::grow`] inflates. The cells and the box are those of the full diameters.
    pub(crate) fn new_scaled(
        params: &McParams,
        positions: &[[f64; 3]],
        key: &str,
        scale: f64,
        pair: Option<(&PairSpec, f64)>,
    ) -> Result<Self, McError> {
        let d = positive("diameter", params.diameter)?;
        positive("delta", params.delta)?;
        let n = positions.len();
        let (diameters, types) = match &params.mixture {
            None => (vec![d], vec![0u32; n]),
            Some(m) => {
                if m.diameters.is_empty() {
                    return Err(ParamError::new("diameters", "needs at least one species").into());
                }
                for (s, &ds) in m.diameters.iter().enumerate() {
                    if !(ds.is_finite() && ds > 0.0) {
                        return Err(ParamError::new(
                            "diameters",
                            format!(
                                "species {s}: the diameter must be positive and finite, got {}",
                                show(ds)
                            ),
                        )
                        .into());
                    }
                }
                let total: usize = m.counts.iter().sum();
                if m.counts.len() != m.diameters.len() || total != n {
                    return Err(ParamError::new(
                        "counts",
                        format!(
                            "{} counts summing to {total} for {} species and {n} spheres",
                            m.counts.len(),
                            m.diameters.len()
                        ),
                    )
                    .into());
                }
                (m.diameters.clone(), m.typeids())
            }
        };
        let d_max = diameters.iter().fold(0.0f64, |a, &b| a.max(b));
        let edge = params.geometry.box_edge_of(d, &diameters);
        positive("box", edge)?;
        if let Geometry::HardWall { radius } = params.geometry
            && radius <= 0.5 * d_max
        {
            return Err(ParamError::new(
                "radius",
                format!(
                    "must exceed d/2 = {} (no room for a centre)",
                    show(0.5 * d_max)
                ),
            )
            .into());
        }
        for &ds in &diameters {
            if let Some(c) = params.geometry.confinement_of(ds, d)
                && c <= 0.0
            {
                return Err(ParamError::new(
                    "diameters",
                    format!(
                        "a sphere of diameter {} has no room for its centre in the container",
                        show(ds)
                    ),
                )
                .into());
            }
        }
        if edge < 2.0 * d_max {
            return Err(ParamError::new(
                "box",
                format!(
                    "the periodic box edge must be at least 2 d = {}, got {}",
                    show(2.0 * d_max),
                    show(edge)
                ),
            )
            .into());
        }
        let pair = pair
            .map(|(spec, kt)| SoftPair::new(spec, &diameters, kt))
            .transpose()?;
        // Cells at least the pair's range (CELL_MIN reaches apart, as for the diameters).
        let reach = pair
            .as_ref()
            .map_or(d_max, |p| d_max.max(p.r_cut / CELL_MIN));
        let nc = cells_per_edge(edge, reach);
        if let Some(p) = &pair {
            p.check_range(&params.geometry, edge, edge / nc as f64, d_max)?;
        }
        let cells = (nc as f64).powi(3);
        check_cell_count(edge, reach, n)?;
        // Slots (3 coordinates, a radius, a tag) at the initial capacity, counts, particle
        // arrays.
        let cap0 = 8usize;
        let bytes = cells * (cap0 as f64 * 36.0 + 4.0) + n as f64 * 100.0;
        ensure_fits(
            "system",
            &format!("a grid of {nc}^3 Monte Carlo cells"),
            bytes,
        )?;
        let nc_cells = nc * nc * nc;
        let radius = types
            .iter()
            .map(|&t| radius_of(diameters[t as usize], scale))
            .collect();
        let mut mc = Self {
            diameter: d,
            diameters,
            types,
            radius,
            scale,
            d_max,
            geometry: params.geometry,
            seed: params.seed,
            delta: params.delta,
            nselect: 1,
            sweep: 0,
            edge,
            nc,
            side: edge / nc as f64,
            pos: std::array::from_fn(|_| Vec::with_capacity(n)),
            cap: cap0,
            count: vec![0; nc_cells],
            slot: std::array::from_fn(|_| vec![0.0; nc_cells * cap0]),
            tag: vec![0; nc_cells * cap0],
            slot_r: vec![0.0; nc_cells * cap0],
            offset: [0.0; 3],
            cell_of: vec![0; n],
            slot_of: vec![0; n],
            part_count: Vec::new(),
            part_seen: Vec::new(),
            cell_seen: vec![0; nc_cells],
            bucket: Vec::new(),
            bucket_end: Vec::new(),
            chain: None,
            chain_cells: Default::default(),
            binned: false,
            last_chain: Default::default(),
            pair,
            last_pair_energy_change: None,
        };
        mc.delta = mc.delta.min(mc.max_delta());
        for (i, p) in positions.iter().enumerate() {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(
                    ParamError::new(key, format!("sphere {i} has a non-finite position")).into(),
                );
            }
            let mut q = *p;
            if let Some(max) = mc.confinement_of_sphere(i) {
                let r = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
                if r > max {
                    return Err(McError::OutsideWall {
                        key: key.into(),
                        i,
                        r,
                        max,
                    });
                }
            } else {
                for x in &mut q {
                    *x -= edge * (*x / edge + 0.5).floor();
                    if *x >= 0.5 * edge {
                        *x -= edge;
                    }
                }
            }
            for a in 0..3 {
                mc.pos[a].push(q[a]);
            }
        }
        mc.rebin([0.0; 3]);
        if let Some((i, j, r)) = mc.first_infinite_energy() {
            return Err(ParamError::new(
                key,
                format!(
                    "spheres {i} and {j} at distance {r:.6} have an infinite or undefined pair energy"
                ),
            )
            .into());
        }
        if mc.pair.is_none()
            && let Some((i, j, r)) = mc.first_overlap(0.0)
        {
            return Err(McError::Overlap {
                key: key.into(),
                i,
                j,
                distance: r,
                diameter: mc.radius[i] + mc.radius[j],
            });
        }
        Ok(mc)
    }

    /// Largest centre distance from the droplet centre of sphere `i` at its current radius
    /// (`None` in bulk): [`Geometry::confinement_of`] as the moves apply it.
    fn confinement_of_sphere(&self, i: usize) -> Option<f64> {
        let c = self.geometry.confinement(self.diameter)?;
        Some(if self.geometry.shrinks() {
            c - (self.radius[i] - 0.5 * self.diameter)
        } else {
            c
        })
    }

    /// Inflate a compressed start ([`Self::new_scaled`]) to the full diameters: sweeps (with
    /// the move size tuned towards acceptance 0.3 every 10), after each of which every diameter
    /// grows to the largest factor (at most 1) that the closest pair (relative to its contact
    /// distance) and the walls allow, less a relative 1e-9. The sweeps draw from streams far
    /// beyond any run's (sweep numbers from 2^62), and afterwards the sweep count is 0 again
    /// and delta is `delta`, so the run starts as from any other configuration. Error (key
    /// `system.volume_fraction`) when `max_sweeps` sweeps do not reach the full diameters.
    pub fn grow(&mut self, max_sweeps: u64, delta: f64) -> Result<u64, McError> {
        const FIRST: u64 = 1 << 62;
        let (sweep0, delta0) = (self.sweep, self.delta);
        self.sweep = FIRST;
        let mut window = SweepStats::default();
        let mut done = 0;
        while self.scale < 1.0 {
            if done == max_sweeps {
                return Err(ParamError::new(
                    "n",
                    format!(
                        "{max_sweeps} Monte Carlo sweeps grew the mixture from its lattice to only {:.4} of its diameters: pack it less densely",
                        self.scale
                    ),
                )
                .into());
            }
            window += self.sweep();
            done += 1;
            if done % 10 == 0 {
                self.tune(window.acceptance(), 0.3);
                window = SweepStats::default();
            }
            let grown = (self.largest_scale() * (1.0 - 1e-9)).min(1.0);
            if grown > self.scale {
                self.set_scale(grown);
            }
        }
        self.sweep = sweep0;
        self.delta = delta0;
        self.set_delta(delta);
        Ok(done)
    }

    /// The largest diameter factor the current positions allow: over pairs `r / d_ij`, over
    /// spheres in a shrinking container `(c_ref + r_ref - |x|) / r_i` (`r_i`, `r_ref`: full
    /// radii); at least the current scale.
    fn largest_scale(&self) -> f64 {
        let full: Vec<f64> = self
            .types
            .iter()
            .map(|&t| 0.5 * self.diameters[t as usize])
            .collect();
        let mut best = f64::INFINITY;
        self.for_each_pair(self.d_max, |i, j, r2| {
            best = best.min(r2.sqrt() / (full[i] + full[j]));
        });
        if self.geometry.shrinks()
            && let Some(c) = self.geometry.confinement(self.diameter)
        {
            let top = c + 0.5 * self.diameter;
            for (i, &ri) in full.iter().enumerate() {
                let p = self.position(i);
                let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                best = best.min((top - r) / ri);
            }
        }
        best.max(self.scale)
    }

    /// Set the diameter factor (1: the full diameters, exactly).
    fn set_scale(&mut self, scale: f64) {
        self.scale = scale;
        for (r, &t) in self.radius.iter_mut().zip(&self.types) {
            *r = radius_of(self.diameters[t as usize], scale);
        }
        self.rebin(self.offset);
    }

    /// Number of spheres.
    pub fn len(&self) -> usize {
        self.pos[0].len()
    }

    /// Whether there are no spheres.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sphere diameter (one species), or the reference diameter of a mixture
    /// ([`McParams::diameter`]).
    pub fn diameter(&self) -> f64 {
        self.diameter
    }

    /// Diameter of each species (one species: `[diameter]`).
    pub fn diameters(&self) -> &[f64] {
        &self.diameters
    }

    /// Species of each sphere (one species: all 0).
    pub fn types(&self) -> &[u32] {
        &self.types
    }

    /// Number of species.
    pub fn species(&self) -> usize {
        self.diameters.len()
    }

    /// Spheres of each species.
    pub fn species_counts(&self) -> Vec<usize> {
        let mut c = vec![0; self.diameters.len()];
        for &t in &self.types {
            c[t as usize] += 1;
        }
        c
    }

    /// Largest species diameter (the cells are sized by it).
    pub fn max_diameter(&self) -> f64 {
        self.d_max
    }

    /// The container.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// Edge of the periodic box the cells tile.
    pub fn box_edge(&self) -> f64 {
        self.edge
    }

    /// Cell side s.
    pub fn cell_side(&self) -> f64 {
        self.side
    }

    /// Cells per box edge.
    pub fn cells_per_edge(&self) -> usize {
        self.nc
    }

    /// Current half-width of the trial displacement cube.
    pub fn delta(&self) -> f64 {
        self.delta
    }

    /// Largest delta allowed (half a cell side).
    pub fn max_delta(&self) -> f64 {
        MAX_DELTA_PER_SIDE * self.side
    }

    /// Set the displacement half-width (clamped to `(0, max_delta]`).
    pub fn set_delta(&mut self, delta: f64) {
        self.delta = delta.clamp(1e-12 * self.diameter, self.max_delta());
    }

    /// Trial moves per sphere per sweep (1 unless set).
    pub fn nselect(&self) -> usize {
        self.nselect
    }

    /// Make `nselect` trial moves per sphere per sweep (HOOMD-blue's `nselect`; at least 1):
    /// each cell of a layer makes `nselect` times as many moves as it holds spheres, all on
    /// one binning, so the binning and write-back are shared by `nselect N` moves.
    pub fn set_nselect(&mut self, nselect: usize) {
        self.nselect = nselect.max(1);
    }

    /// Sweeps done.
    pub fn sweeps(&self) -> u64 {
        self.sweep
    }

    /// Seed of the random streams.
    pub fn seed(&self) -> u32 {
        self.seed
    }

    /// Positions in particle order, relative to the box centre: `[x, y, z]`.
    pub fn positions(&self) -> [&[f64]; 3] {
        [&self.pos[0], &self.pos[1], &self.pos[2]]
    }

    /// Position of sphere `i`.
    pub fn position(&self, i: usize) -> [f64; 3] {
        [self.pos[0][i], self.pos[1][i], self.pos[2][i]]
    }

    /// Restore a saved state: positions (as returned by [`Self::positions`]), sweeps done and
    /// delta; the next sweep continues bitwise as the saved run would have.
    pub fn restore(&mut self, pos: [Vec<f64>; 3], sweeps: u64, delta: f64) {
        assert!(pos.iter().all(|p| p.len() == self.len()));
        self.pos = pos;
        self.sweep = sweeps;
        self.delta = delta;
        self.rebin([0.0; 3]);
    }

    fn pass(&self) -> Pass {
        let confine = self.geometry.confinement(self.diameter);
        Pass {
            r_max: 0.5 * self.scale * self.d_max,
            r_ref: 0.5 * self.diameter,
            side: self.side,
            edge: self.edge,
            nc: self.nc,
            half: self.nc / 2,
            cap: self.cap,
            nselect: self.nselect,
            delta: self.delta,
            seed: self.seed,
            sweep: self.sweep,
            offset: self.offset,
            shift: self.offset.map(|o| 0.5 * self.edge - o),
            inv_side: 1.0 / self.side,
            geometry: self.geometry,
            confine: confine.unwrap_or(f64::INFINITY),
            shrinks: self.geometry.shrinks(),
        }
    }

    /// Bin every particle into the grid shifted by `offset`, growing the cell capacity when a
    /// cell overflows. A parallel counting sort that keeps particle order within each cell, so
    /// the slots do not depend on the number of threads:
    ///
    /// 1. parts of the particle range (one per thread), in parallel: each particle's cell, the
    ///    part's count per cell, and the part's particles grouped by the range of cells (one
    ///    range per part) they fall in;
    /// 2. serially, per cell: the total over parts (`count`), the capacity check;
    /// 3. in parallel, two jobs side by side: each part writes its particles' slot indices
    ///    (the cell's first slot, plus the counts of the earlier parts in that cell, plus its own
    ///    running count), while each range of cells fills its own slots from its group of every
    ///    part in turn (so in particle order), binning each particle again for its position in
    ///    the cell, and pads each cell to a whole vector with [`EMPTY`].
    ///
    /// Per particle only its cell and slot are stored; the write-back ([`Self::scatter`])
    /// finds the cell's corner again from the position it binned.
    fn rebin(&mut self, offset: [f64; 3]) {
        self.offset = offset;
        self.binned = true;
        let pass = self.pass();
        let n = self.len();
        let cells = self.count.len();
        if n == 0 {
            self.count.fill(0);
            return;
        }
        let parts = rayon::current_num_threads().min(n.div_ceil(REBIN_PART_MIN));
        let part_len = n.div_ceil(parts.max(1));
        // Exactly as many parts as chunks of `part_len`.
        let parts = n.div_ceil(part_len);
        self.part_count.resize(parts * cells, 0);
        self.part_seen.resize(parts * cells, 0);
        // Ranges of cells, one filler each.
        let range = cells.div_ceil(parts);
        let ranges = cells.div_ceil(range);
        self.bucket.resize(n, 0);
        // Each part's `ranges + 1` ends on cache lines of their own (the parts count into them
        // concurrently).
        let stride = (ranges + 1).next_multiple_of(16);
        self.bucket_end.resize(parts * stride, 0);
        // 1. Per part: cells, counts per cell, and the part's particles grouped by range.
        {
            let [px, py, pz] = &self.pos;
            self.cell_of
                .par_chunks_mut(part_len)
                .zip(self.part_count.par_chunks_mut(cells))
                .zip(self.bucket.par_chunks_mut(part_len))
                .zip(self.bucket_end.par_chunks_mut(stride))
                .enumerate()
                .for_each(|(k, (((cell, counts), bucket), end))| {
                    counts.fill(0);
                    end.fill(0);
                    let first = k * part_len;
                    for (j, out) in cell.iter_mut().enumerate() {
                        let i = first + j;
                        let (id, _) = pass.bin(px[i], py[i], pz[i]);
                        *out = id as u32;
                        counts[id] += 1;
                    }
                    // Where each range's group ends, from the counts per cell.
                    for (r, c) in counts.chunks(range).enumerate() {
                        end[r + 1] = end[r] + c.iter().sum::<u32>();
                    }
                    // Counting sort by range: afterwards end[r] is where range r ends.
                    for (j, &id) in cell.iter().enumerate() {
                        let r = id as usize / range;
                        bucket[end[r] as usize] = (first + j) as u32;
                        end[r] += 1;
                    }
                });
        }
        // 2. Totals per cell and the capacity.
        let mut fullest = 0;
        for (c, total) in self.count.iter_mut().enumerate() {
            *total = (0..parts).map(|k| self.part_count[k * cells + c]).sum();
            fullest = fullest.max(*total as usize);
        }
        while fullest > self.cap {
            self.grow_slots();
        }
        let part_count = &self.part_count[..parts * cells];
        // 3. Slot indices per part, and the slots per range of cells.
        let cap = self.cap;
        let cell_of = &self.cell_of;
        let [px, py, pz] = &self.pos;
        let (bucket, bucket_end) = (&self.bucket, &self.bucket_end);
        let [sx, sy, sz] = &mut self.slot;
        let (tag, cell_seen) = (&mut self.tag, &mut self.cell_seen);
        let (radius, slot_r) = (&self.radius, &mut self.slot_r);
        rayon::join(
            || {
                self.slot_of
                    .par_chunks_mut(part_len)
                    .zip(self.part_seen.par_chunks_mut(cells))
                    .enumerate()
                    .for_each(|(k, (slot_of, seen))| {
                        seen.fill(0);
                        for (j, out) in slot_of.iter_mut().enumerate() {
                            let id = cell_of[k * part_len + j] as usize;
                            let before: u32 = (0..k).map(|q| part_count[q * cells + id]).sum();
                            *out = (id * cap) as u32 + before + seen[id];
                            seen[id] += 1;
                        }
                    })
            },
            || {
                sx.par_chunks_mut(range * cap)
                    .zip(sy.par_chunks_mut(range * cap))
                    .zip(sz.par_chunks_mut(range * cap))
                    .zip(tag.par_chunks_mut(range * cap))
                    .zip(slot_r.par_chunks_mut(range * cap))
                    .zip(cell_seen.par_chunks_mut(range))
                    .enumerate()
                    .for_each(|(k, (((((x, y), z), tag), rad), seen))| {
                        let first = k * range;
                        seen.fill(0);
                        // This range's particles, part after part: particle order.
                        let mine = (0..parts).flat_map(|q| {
                            let end = &bucket_end[q * stride..q * stride + ranges + 1];
                            let begin = if k == 0 { 0 } else { end[k - 1] as usize };
                            &bucket[q * part_len + begin..q * part_len + end[k] as usize]
                        });
                        for &i in mine {
                            let i = i as usize;
                            let c = cell_of[i] as usize - first;
                            let slot = c * cap + seen[c] as usize;
                            seen[c] += 1;
                            let (_, u) = pass.bin(px[i], py[i], pz[i]);
                            (x[slot], y[slot], z[slot]) = (u[0], u[1], u[2]);
                            tag[slot] = i as u32;
                            rad[slot] = radius[i];
                        }
                        // Pad each cell to a whole vector of eight (the scans read that far).
                        for (c, &m) in seen.iter().enumerate() {
                            let pad =
                                c * cap + m as usize..c * cap + (m as usize).next_multiple_of(8);
                            x[pad.clone()].fill(EMPTY);
                            y[pad.clone()].fill(EMPTY);
                            z[pad.clone()].fill(EMPTY);
                            rad[pad].fill(0.0);
                        }
                    })
            },
        );
    }

    /// Eight more slots per cell (a multiple of eight keeps the scans in whole vectors).
    fn grow_slots(&mut self) {
        self.cap += 8;
        let total = self.count.len() * self.cap;
        for s in &mut self.slot {
            s.resize(total, 0.0);
        }
        self.tag.resize(total, 0);
        self.slot_r.resize(total, 0.0);
    }

    /// Write the slots back into the particle-order positions (in parallel): each particle's
    /// new position is its cell's corner (found again from the position it was binned at) plus
    /// its slot, wrapped into the box.
    fn scatter(&mut self) {
        let pass = self.pass();
        let l = self.edge;
        let (slot_of, slot) = (&self.slot_of, &self.slot);
        let [px, py, pz] = &mut self.pos;
        px.par_iter_mut()
            .zip(py.par_iter_mut())
            .zip(pz.par_iter_mut())
            .enumerate()
            .with_min_len(1024)
            .for_each(|(i, ((x, y), z))| {
                let k = slot_of[i] as usize;
                let back = |a: usize, old: f64| {
                    let v = pass.locate(old, a).2 + slot[a][k];
                    if v >= 0.5 * l { v - l } else { v }
                };
                (*x, *y, *z) = (back(0, *x), back(1, *y), back(2, *z));
            });
    }

    /// One sweep: `nselect N` trial moves (see the module documentation), or with
    /// [`Self::set_event_chain`] a sweep of event chains ([`chain`]; its counts in
    /// [`Self::last_chains`], the returned counts zero).
    pub fn sweep(&mut self) -> SweepStats {
        if let Some(c) = self.chain {
            return self.chain_sweep(c);
        }
        self.last_chain = Default::default();
        let mut rng = stream(self.seed, self.sweep, Purpose::Moves, 0);
        let s = self.side;
        let offset = [
            s * unit(rng.next_u64()),
            s * unit(rng.next_u64()),
            s * unit(rng.next_u64()),
        ];
        // The two parities of the z layers, in random order.
        let parities = if rng.next_u64() >> 63 == 0 {
            [0usize, 1]
        } else {
            [1, 0]
        };
        self.rebin(offset);
        let pass = self.pass();
        let layer = pass.nc * pass.nc * self.cap;
        let span = pass.half * layer;
        let mut tally = Tally::default();
        let (counts, radii) = (&self.count, &self.slot_r);
        let soft = self.pair.as_ref().map(|pair| SoftPass {
            pair,
            tag: &self.tag,
            types: &self.types,
        });
        for parity in parities {
            let (lo, hi) = (parity * span, (parity + 1) * span);
            let [sx, sy, sz] = &mut self.slot;
            let (xb, rest) = sx.split_at_mut(lo);
            let (xc, xa) = rest.split_at_mut(span);
            let (yb, rest) = sy.split_at_mut(lo);
            let (yc, ya) = rest.split_at_mut(span);
            let (zb, rest) = sz.split_at_mut(lo);
            let (zc, za) = rest.split_at_mut(span);
            let frozen = Frozen {
                below: [xb, yb, zb],
                above: [xa, ya, za],
                lo,
                hi,
            };
            tally += xc
                .par_chunks_mut(layer)
                .zip(yc.par_chunks_mut(layer))
                .zip(zc.par_chunks_mut(layer))
                .enumerate()
                .map(|(k, ((x, y), z))| {
                    pass.layer_moves(parity, k, [x, y, z], radii, counts, &frozen, soft.as_ref())
                })
                .reduce(Tally::default, |mut p, q| {
                    p += q;
                    p
                });
        }
        self.scatter();
        self.sweep += 1;
        self.last_pair_energy_change = self.pair.as_ref().map(|p| tally.beta_pair_du / p.beta);
        SweepStats {
            trials: (self.len() * self.nselect) as u64,
            accepted: tally.accepted,
            left_cell: tally.left,
        }
    }

    /// `sweeps` sweeps, with their summed counts.
    pub fn run(&mut self, sweeps: u64) -> SweepStats {
        let mut total = SweepStats::default();
        for _ in 0..sweeps {
            total += self.sweep();
        }
        total
    }

    /// Scale delta by `acceptance / target` (the factor clamped to [1/2, 2], delta to
    /// `(0, max_delta]`): the warm-up's move-size tuning.
    pub fn tune(&mut self, acceptance: f64, target: f64) {
        let factor = (acceptance / target).clamp(0.5, 2.0);
        self.set_delta(self.delta * factor);
    }

    /// Warm up for `sweeps` sweeps, tuning delta towards acceptance `target` every `every`
    /// sweeps; returns the counts of the last tuning window. Delta is frozen afterwards (the
    /// sampling sweeps keep detailed balance only with a fixed delta).
    pub fn warm_up(&mut self, sweeps: u64, every: u64, target: f64) -> SweepStats {
        let every = every.max(1);
        let mut window = SweepStats::default();
        for k in 1..=sweeps {
            window += self.sweep();
            if k % every == 0 {
                self.tune(window.acceptance(), target);
                if k < sweeps {
                    window = SweepStats::default();
                }
            }
        }
        window
    }

    /// Bring the cells up to date with the positions after event chains (which move the
    /// positions alone; the cells serve [`Self::for_each_pair`]). Binning at the last offset
    /// gives the same cells as binning after every sweep would: observables do not depend on
    /// how often this is called.
    pub fn bin(&mut self) {
        if !self.binned {
            self.rebin(self.offset);
        }
    }

    /// Visit every unordered pair with centre distance `r < rcut` once: `f(i, j, r^2)`.
    /// `rcut` is clamped so that the cell stencil fits the box (at most `L/2`). After event
    /// chains without [`Self::bin`] the pairs are found by visiting all `N^2 / 2` (correct,
    /// slow): call `bin` first.
    pub fn for_each_pair(&self, rcut: f64, mut f: impl FnMut(usize, usize, f64)) {
        if !self.binned {
            return self.for_each_pair_direct(rcut, f);
        }
        let pass = self.pass();
        let (nc, s, cap) = (self.nc, self.side, self.cap);
        let rcut = rcut.min(0.5 * self.edge);
        let reach = ((rcut / s).ceil() as isize).max(1);
        let rc2 = rcut * rcut;
        for a in 0..self.count.len() {
            let ca = pass.coords(a);
            let na = self.count[a] as usize;
            if na == 0 {
                continue;
            }
            for dz in -reach..=reach {
                for dy in -reach..=reach {
                    for dx in -reach..=reach {
                        let w = |c: usize, o: isize| (c as isize + o).rem_euclid(nc as isize);
                        let b = pass.id([
                            w(ca[0], dx) as usize,
                            w(ca[1], dy) as usize,
                            w(ca[2], dz) as usize,
                        ]);
                        if b < a {
                            continue;
                        }
                        let sh = [dx as f64 * s, dy as f64 * s, dz as f64 * s];
                        for p in a * cap..a * cap + na {
                            let first = if a == b { p + 1 } else { b * cap };
                            for q in first..b * cap + self.count[b] as usize {
                                let r2 = (0..3)
                                    .map(|k| {
                                        let v = self.slot[k][p] - self.slot[k][q] - sh[k];
                                        v * v
                                    })
                                    .sum::<f64>();
                                if r2 < rc2 {
                                    f(self.tag[p] as usize, self.tag[q] as usize, r2);
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    /// [`Self::for_each_pair`] over all pairs (the minimum image in bulk).
    fn for_each_pair_direct(&self, rcut: f64, mut f: impl FnMut(usize, usize, f64)) {
        let rcut = rcut.min(0.5 * self.edge);
        let rc2 = rcut * rcut;
        let l = self.edge;
        let periodic = matches!(self.geometry, Geometry::Bulk { .. });
        for i in 0..self.len() {
            for j in i + 1..self.len() {
                let r2 = (0..3)
                    .map(|k| {
                        let mut v = self.pos[k][i] - self.pos[k][j];
                        if periodic {
                            v -= l * (v / l).round();
                        }
                        v * v
                    })
                    .sum::<f64>();
                if r2 < rc2 {
                    f(i, j, r2);
                }
            }
        }
    }

    /// The first pair closer than its contact distance `(d_i + d_j) / 2` times
    /// `1 - tolerance` (particle indices and distance), if any. Positions are re-expressed
    /// relative to a new cell each sweep, so distances carry a rounding error of a few ulp of
    /// the box edge; the checks of the tests allow 1e-12.
    pub fn first_overlap(&self, tolerance: f64) -> Option<(usize, usize, f64)> {
        let mut found = None;
        let r = &self.radius;
        self.for_each_pair(self.scale * self.d_max, |i, j, r2| {
            let lim = (r[i] + r[j]) * (1.0 - tolerance);
            if found.is_none() && r2 < lim * lim {
                found = Some((i.min(j), i.max(j), r2.sqrt()));
            }
        });
        found
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid: `nc` a multiple of 4 with cells of side `>= 2 d`, the largest such, or 2 with
    /// cells `>= d` in short boxes; the benchmark's boxes (N = 10,976 at phi 0.5: 8 cells).
    #[test]
    fn cells_per_edge_gives_each_parity_an_even_number_of_layers() {
        for k in 0..20_000 {
            let edge = 2.0 + k as f64 * 0.01;
            let nc = cells_per_edge(edge, 1.0);
            let side = edge / nc as f64;
            assert!(side >= 1.0, "{edge}: {nc}");
            if nc == 2 {
                assert!(edge < 4.0 * CELL_MIN, "{edge}");
            } else {
                assert_eq!(nc % 4, 0, "{edge}");
                assert!(side >= CELL_MIN, "{edge}: {nc}");
                assert!(
                    edge / ((nc + 4) as f64) < CELL_MIN,
                    "{edge}: {nc} is not the largest"
                );
            }
        }
        let bench = |n: f64, phi: f64| (n * std::f64::consts::PI / 6.0 / phi).cbrt();
        assert_eq!(cells_per_edge(bench(10_976.0, 0.5), 1.0), 8);
        assert_eq!(cells_per_edge(bench(10_976.0, 0.3), 1.0), 12);
        assert_eq!(cells_per_edge(bench(87_808.0, 0.5), 1.0), 20);
        assert_eq!(cells_per_edge(4.0, 0.5), 4);
        assert_eq!(cells_per_edge(3.99, 0.5), 2);
    }
}
