//! Event-chain Monte Carlo (ECMC) for hard spheres: a move type beside the local moves of
//! [`HardSphereMc::sweep`] (`mc.move = "event-chain"`).
//!
//! # Algorithm (straight event chains)
//!
//! Bernard, Krauth & Wilson, Phys. Rev. E 80, 056704 (2009); in 3D Isobe & Krauth, J. Chem.
//! Phys. 143, 084509 (2015). A chain picks a sphere `i` uniformly and a direction `e` (bulk: one
//! of `+x, +y, +z` uniformly; droplets: one of the six `±x, ±y, ±z`) and a displacement budget
//! `l` (`mc.chain_length`). The active sphere moves along `e` until it touches a sphere `j`
//! (centre distance `(d_i + d_j) / 2`); then `j` becomes the active sphere (a *lift*) and moves on
//! along `e` with what is left of the budget; the chain ends when the budget is spent. No move is
//! ever rejected. In a droplet the active sphere also meets the container:
//!
//! - **hard wall** (and the interface's outer cut): the direction is *reversed*, `e -> -e`,
//!   and the same sphere goes on (see "Walls" below);
//! - **the interface** (a soft one-body potential `beta V(|r|)`): the factorised Metropolis
//!   rule in its event-driven form (Michel, Kapfer & Krauth, J. Chem. Phys. 140, 054116 (2014);
//!   Peters & de With, Phys. Rev. E 85, 026703 (2012)): along the path the event comes where
//!   the *increase* of `beta V` since the last event (decreases not counted) reaches `-ln u`,
//!   `u` uniform; then, as at the hard wall, the direction is reversed. `V` depends on `|r|`
//!   alone and grows with it, and `|r + s e|` is convex in `s`, so along a straight path `V`
//!   first falls (to `s* = -r.e`), then grows: the event solves
//!   `beta V(s) = beta V(max(0, s*)) + |ln u|` on the growing part, by bisection. A sphere that has not entered the interface's
//!   range needs no draw until it does (the event rate is zero before).
//!
//! **Global balance.** The lifted chain lives on (configuration `x`, active sphere `i`,
//! direction `e`) with the stationary density `pi(x) / (N n_e)`, `n_e` the number of
//! directions. Moving `i` along `e` transports this density without change (it is flat on the
//! allowed configurations), so only where the transport starts or stops must flow be redirected:
//! a state in which `i` touches `j` ahead of it loses its flow and the state in which `j` touches
//! `i` behind it (same `x`, active `j`, same `e`) lacks inflow, at the same rate
//! (`e . n` times the density): the lift `i -> j` carries one to the other. At a wall, the state
//! with `i` touching the wall ahead (rate `e . n`) loses its flow and the state at the same `x`
//! with `i` active and direction `-e` lacks exactly that inflow (`(-e) . (-n) = e . n`): the
//! reversal carries one to the other, which needs `-e` among the directions with the same weight
//! as `e` (hence the six directions in droplets). For the interface, the reversal at rate
//! `(e . grad beta V)^+` balances the density change `-(e . grad beta V) pi` of the transport in
//! sectors `e` and `-e` together (the one-particle "zig-zag" balance). A chain of fixed length
//! started from a uniform sphere and direction therefore preserves `pi(x)`.
//! **Why not end the chain at the wall** (and start a new one): that stops the chain at a
//! random displacement that depends on the configuration (a stopping time), and leaves the
//! sphere exactly at the wall: every such stop adds probability to a set of configurations of
//! measure zero (a delta at the wall in the density profile). Specular reflection with
//! continuous directions would also balance, but leaves the axis directions the cell search
//! relies on; reversal is the reflection that keeps them.
//!
//! # The pressure
//!
//! In bulk, `beta P / rho = 1 + < sum_lifts (x_j - x_i) . e > / l` over chains (Michel, Kapfer &
//! Krauth 2014, the event-chain pressure; the "excess chain displacement"): a sphere moving a
//! distance `s` along `e` through the others meets, per unit distance, the `(N - 1) / V`
//! others with density `g(d+)` at contact over the forward half of its contact sphere, at a rate
//! `(N - 1)/V g d^2 int (n . e)^+ dOmega = pi d^2 g (N - 1)/V`; each lift jumps the chain ahead by
//! `(x_j - x_i) . e = d (n . e)`, `2 d / 3` on the average weighted by that rate: so
//! `<sum (x_j - x_i) . e> / l = (2 pi / 3) d^3 g(d+) (N - 1)/V = 4 phi (1 - 1/N) g(d+)`, the virial
//! `Z - 1` of N hard spheres exactly (the form the contact-value estimator uses). Additive
//! mixtures: the same with `d_ij` per pair. Because the lifted chain is stationary at every point
//! of its length, the estimator is unbiased chain by chain.
//!
//! # Cells and numbers
//!
//! The next collision is found in a cell list of its own (side `>= d_max`, at most `8 N`
//! cells), kept up to date as the active sphere crosses cell faces (the step is capped at the
//! face, so only the own cell and the next one along `e`, with their eight neighbours across,
//! are scanned); nothing is allocated per event. Contacts and walls stop a hair short, at
//! `(d_i + d_j) / 2 + margin` and `R_c - margin` with `margin = 64 eps L` (`L` the box edge;
//! about 3e-13 d in the examples): positions written and read back, or re-expressed relative to
//! the cells, never overlap (the restart's check has no tolerance). Each chain draws from the
//! stream `(seed, sweep, Moves, 2^40 + k)` for its index `k` in the sweep, so a run is a pure
//! function of its seed and restarts from a checkpoint bitwise.
//!
//! **A sweep** of event chains is `chains_per_sweep` chains (fixed per run; the run layer takes
//! `max(1, round(N lambda / l))`, `lambda = d / (6 phi g_CS(phi))` the Carnahan–Starling free
//! path between lifts, so that a sweep makes about N lifts, as a local sweep makes N trial
//! moves). Its number must not depend on the configuration: a number of chains chosen by what
//! happened (say, until N events) would be a stopping time and bias the samples.

use super::{HardSphereMc, SweepStats, below, unit};
use crate::geometry::Geometry;
use colloidsim_core::ParamError;
use colloidsim_core::param::show;
use colloidsim_core::rng::{Purpose, stream};
use rand::Rng;
use serde::{Deserialize, Serialize};

/// First stream index of the chains of a sweep (the local moves use indices up to the number of
/// cell layers plus one).
pub const CHAIN_STREAM: u64 = 1 << 40;

/// Settings of the event chains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventChain {
    /// Displacement budget `l` of a chain (length).
    pub length: f64,
    /// Chains per sweep (at least 1).
    pub chains_per_sweep: u64,
}

/// Carnahan–Starling free path between lifts of a sphere moving through hard spheres of
/// diameter `d` at volume fraction `phi`: `1 / (pi d^2 rho g(d+)) = d / (6 phi g_CS)`.
pub fn free_path(phi: f64, d: f64) -> f64 {
    let g = (1.0 - 0.5 * phi) / (1.0 - phi).powi(3);
    d / (6.0 * phi * g)
}

/// Counts and sums of one or more sweeps of event chains.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ChainStats {
    /// Chains run.
    pub chains: u64,
    /// Lifts (sphere-sphere events).
    pub lifts: u64,
    /// Reversals at a wall or an interface event.
    pub reversals: u64,
    /// Total displacement of the chains (their lengths summed).
    pub length: f64,
    /// Sum over lifts of `(x_target - x_active) . e` at contact.
    pub lift_sum: f64,
}

impl ChainStats {
    /// `beta P / rho = 1 + lift_sum / length` (bulk; NaN without chains).
    pub fn compressibility(&self) -> f64 {
        if self.length > 0.0 {
            1.0 + self.lift_sum / self.length
        } else {
            f64::NAN
        }
    }
}

impl std::ops::AddAssign for ChainStats {
    fn add_assign(&mut self, o: Self) {
        self.chains += o.chains;
        self.lifts += o.lifts;
        self.reversals += o.reversals;
        self.length += o.length;
        self.lift_sum += o.lift_sum;
    }
}

/// The cell list of the chains (kept between sweeps only as allocated scratch).
#[derive(Debug, Clone, Default)]
pub(crate) struct ChainCells {
    nc: usize,
    side: f64,
    cap: usize,
    /// Particle indices per cell (`cap` slots each, the first `count` used).
    members: Vec<u32>,
    count: Vec<u32>,
    /// Per particle: its slot within its cell, its cell's grid coordinates.
    slot: Vec<u32>,
    coord: Vec<[u32; 3]>,
}

impl ChainCells {
    #[inline(always)]
    fn id(&self, c: [u32; 3]) -> usize {
        (c[2] as usize * self.nc + c[1] as usize) * self.nc + c[0] as usize
    }

    /// Bin `pos` (coordinates in `[-L/2, L/2)`) into `nc^3` cells.
    fn build(&mut self, pos: &[Vec<f64>; 3], edge: f64, nc: usize) {
        let n = pos[0].len();
        self.nc = nc;
        self.side = edge / nc as f64;
        let cells = nc * nc * nc;
        self.count.clear();
        self.count.resize(cells, 0);
        self.coord.resize(n, [0; 3]);
        self.slot.resize(n, 0);
        let inv = 1.0 / self.side;
        for i in 0..n {
            let c: [u32; 3] = std::array::from_fn(|a| {
                (((pos[a][i] + 0.5 * edge) * inv).max(0.0) as usize).min(nc - 1) as u32
            });
            self.coord[i] = c;
            let id = self.id(c);
            self.slot[i] = self.count[id];
            self.count[id] += 1;
        }
        let fullest = self.count.iter().copied().max().unwrap_or(0) as usize;
        self.cap = (fullest + 4).max(self.cap);
        self.members.clear();
        self.members.resize(cells * self.cap, 0);
        for i in 0..n {
            let id = self.id(self.coord[i]);
            self.members[id * self.cap + self.slot[i] as usize] = i as u32;
        }
    }

    /// Twice the slots per cell (a cell overflowed).
    fn grow(&mut self) {
        let (old, cap) = (self.cap, 2 * self.cap);
        let cells = self.count.len();
        let mut members = vec![0; cells * cap];
        for c in 0..cells {
            let k = self.count[c] as usize;
            members[c * cap..c * cap + k].copy_from_slice(&self.members[c * old..c * old + k]);
        }
        self.members = members;
        self.cap = cap;
    }

    /// Move particle `i` into the cell at `c`.
    fn transfer(&mut self, i: usize, c: [u32; 3]) {
        let from = self.id(self.coord[i]);
        let s = self.slot[i] as usize;
        let last = self.count[from] as usize - 1;
        let moved = self.members[from * self.cap + last];
        self.members[from * self.cap + s] = moved;
        self.slot[moved as usize] = s as u32;
        self.count[from] -= 1;
        let to = self.id(c);
        if self.count[to] as usize == self.cap {
            self.grow();
        }
        let k = self.count[to] as usize;
        self.members[to * self.cap + k] = i as u32;
        self.slot[i] = k as u32;
        self.count[to] += 1;
        self.coord[i] = c;
    }
}

/// What stops the active sphere besides a collision.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Stop {
    /// Nothing within reach.
    None,
    /// The sphere enters the interface's range: draw its event there.
    EnterSoft,
    /// An event of the interface: reverse.
    Soft,
    /// The hard wall (or the interface's outer cut): reverse.
    Hard,
}

/// Distance along `sg e_a` from `x` to the sphere `|r| = radius` (from inside; 0 if outside).
#[inline]
fn exit_distance(x: [f64; 3], a: usize, sg: f64, radius: f64) -> f64 {
    let p = sg * x[a];
    let q = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - x[a] * x[a];
    let disc = radius * radius - q;
    if disc <= 0.0 {
        return 0.0;
    }
    (disc.sqrt() - p).max(0.0)
}

impl HardSphereMc {
    /// Run event chains instead of local moves (`None`: local moves). Errors (key `move`) for
    /// the tabulated potential, which need not grow with the distance (the event search relies
    /// on that), and (key `chain_length`) for a length that is not positive and finite.
    pub fn set_event_chain(&mut self, chain: Option<EventChain>) -> Result<(), ParamError> {
        if let Some(c) = chain {
            if !(c.length.is_finite() && c.length > 0.0) {
                return Err(ParamError::new(
                    "chain_length",
                    format!("must be positive and finite, got {}", show(c.length)),
                ));
            }
            if self.pair.is_some() {
                return Err(ParamError::new(
                    "move",
                    "event chains here are for hard spheres: with a pair interaction use local moves",
                ));
            }
            if matches!(self.geometry, Geometry::Tabulated { .. }) {
                return Err(ParamError::new(
                    "move",
                    "event chains need a container potential that grows with the distance from the centre; the tabulated one need not: use local moves",
                ));
            }
        }
        self.chain = chain;
        Ok(())
    }

    /// The event-chain settings (`None`: local moves).
    pub fn event_chain(&self) -> Option<EventChain> {
        self.chain
    }

    /// Counts of the last sweep's event chains (zero after a local sweep).
    pub fn last_chains(&self) -> ChainStats {
        self.last_chain
    }

    /// Cells per edge of the chains' cell list: sides `>= d_max`, at most `8 N` cells, or 1
    /// (every sphere scanned) when fewer than 3 fit.
    fn chain_cells_per_edge(&self) -> usize {
        let d = (self.scale * self.d_max).max(f64::MIN_POSITIVE);
        let fit = (self.edge / d).floor().max(1.0) as usize;
        let most = ((8 * self.len().max(1)) as f64).cbrt().floor() as usize;
        let nc = fit.min(most.max(1));
        if nc < 3 { 1 } else { nc }
    }

    /// One sweep of event chains (see the module documentation).
    pub(super) fn chain_sweep(&mut self, chain: EventChain) -> SweepStats {
        let nc = self.chain_cells_per_edge();
        let mut cells = std::mem::take(&mut self.chain_cells);
        cells.build(&self.pos, self.edge, nc);
        let mut total = ChainStats::default();
        if !self.is_empty() {
            for k in 0..chain.chains_per_sweep {
                let mut rng = stream(self.seed, self.sweep, Purpose::Moves, CHAIN_STREAM + k);
                total += self.run_chain(&mut cells, chain.length, &mut rng);
            }
        }
        self.chain_cells = cells;
        self.last_chain = total;
        // The cells of the local moves and the pair observers are binned when next needed.
        self.binned = false;
        self.sweep += 1;
        SweepStats::default()
    }

    /// Largest centre distance of sphere `i` (infinite in bulk).
    #[inline]
    fn chain_confine(&self, i: usize) -> f64 {
        self.confinement_of_sphere(i).unwrap_or(f64::INFINITY)
    }

    /// The next stop of the active sphere `i` moving along `sg e_a` from its position, drawing
    /// an interface event from `rng` where needed (`entered`: the sphere has just reached the
    /// interface's range, whatever rounding says): (distance, kind).
    fn next_stop(
        &self,
        i: usize,
        a: usize,
        sg: f64,
        margin: f64,
        entered: bool,
        rng: &mut impl Rng,
    ) -> (f64, Stop) {
        let x = self.position(i);
        match self.geometry {
            Geometry::Bulk { .. } | Geometry::Tabulated { .. } => (f64::INFINITY, Stop::None),
            Geometry::HardWall { .. } => (
                exit_distance(x, a, sg, self.chain_confine(i) - margin),
                Stop::Hard,
            ),
            Geometry::Interface { interface, .. } => {
                let h = self.radius[i] - 0.5 * self.diameter;
                let cut = exit_distance(x, a, sg, self.chain_confine(i) - margin);
                let soft = interface.radius.r0 + interface.offset - h;
                let r2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
                if r2 < soft * soft && !entered {
                    let s = exit_distance(x, a, sg, soft);
                    return if s < cut {
                        (s, Stop::EnterSoft)
                    } else {
                        (cut, Stop::Hard)
                    };
                }
                // In the interface's range: the event where the growth of beta V since the
                // lowest point ahead (s* = -r.e, or here) reaches -ln u.
                let at = |s: f64| {
                    let mut r = x;
                    r[a] += sg * s;
                    self.geometry.beta_energy_of(r, h)
                };
                let base = (-sg * x[a]).clamp(0.0, cut);
                let target = at(base) - (1.0 - unit(rng.next_u64())).ln();
                if at(cut) < target {
                    return (cut, Stop::Hard);
                }
                let (mut lo, mut hi) = (base, cut);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    if at(mid) >= target {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                (hi, Stop::Soft)
            }
        }
    }

    /// The first sphere that `i`, moving along `sg e_a`, touches within `limit`: (distance,
    /// sphere, `(x_j - x_i) . e` at contact), or `(limit, None, 0)`.
    #[inline]
    fn next_collision(
        &self,
        cells: &ChainCells,
        i: usize,
        a: usize,
        sg: f64,
        limit: f64,
        margin: f64,
    ) -> (f64, Option<usize>, f64) {
        let l = self.edge;
        let periodic = matches!(self.geometry, Geometry::Bulk { .. });
        let xi = self.position(i);
        let ri = self.radius[i];
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let mut best = (limit, None, 0.0);
        let visit = |j: usize, best: &mut (f64, Option<usize>, f64)| {
            if j == i {
                return;
            }
            let mut f = sg * (self.pos[a][j] - xi[a]);
            if f < 0.0 {
                if !periodic {
                    return;
                }
                f += l;
            }
            let image = |mut v: f64| {
                if v > 0.5 * l {
                    v -= l;
                } else if v < -0.5 * l {
                    v += l;
                }
                v
            };
            let (u, w) = (image(self.pos[b][j] - xi[b]), image(self.pos[c][j] - xi[c]));
            let perp2 = u * u + w * w;
            let contact = ri + self.radius[j] + margin;
            let c2 = contact * contact;
            if perp2 >= c2 {
                return;
            }
            let along = (c2 - perp2).sqrt();
            let t = (f - along).max(0.0);
            if t < best.0 {
                *best = (t, Some(j), along);
            }
        };
        let nc = cells.nc;
        if nc == 1 {
            for j in 0..self.len() {
                visit(j, &mut best);
            }
            return best;
        }
        let own = cells.coord[i];
        // The cells below, at and above along an axis, wrapped (nc >= 3: all distinct).
        let around = |k: u32| {
            let top = nc as u32 - 1;
            [
                if k == 0 { top } else { k - 1 },
                k,
                if k == top { 0 } else { k + 1 },
            ]
        };
        let (na, nb, ncc) = (around(own[a]), around(own[b]), around(own[c]));
        let ahead = if sg > 0.0 { na[2] } else { na[0] };
        for ka in [own[a], ahead] {
            for &kb in &nb {
                for &kc in &ncc {
                    let mut cc = own;
                    cc[a] = ka;
                    cc[b] = kb;
                    cc[c] = kc;
                    let id = cells.id(cc);
                    let first = id * cells.cap;
                    for &j in &cells.members[first..first + cells.count[id] as usize] {
                        visit(j as usize, &mut best);
                    }
                }
            }
        }
        best
    }

    /// One chain of length `length` (see the module documentation).
    fn run_chain(&mut self, cells: &mut ChainCells, length: f64, rng: &mut impl Rng) -> ChainStats {
        let mut stats = ChainStats {
            chains: 1,
            length,
            ..Default::default()
        };
        let bulk = matches!(self.geometry, Geometry::Bulk { .. });
        let l = self.edge;
        let margin = 64.0 * f64::EPSILON * l;
        let mut i = below(rng.next_u64(), self.len());
        let (a, mut sg) = if bulk {
            (below(rng.next_u64(), 3), 1.0)
        } else {
            let k = below(rng.next_u64(), 6);
            (k % 3, if k < 3 { 1.0 } else { -1.0 })
        };
        let mut left = length;
        let (mut stop_at, mut stop) = self.next_stop(i, a, sg, margin, false, rng);
        let mut idle = 0usize;
        while left > 0.0 {
            // Distance to the face of the active sphere's cell ahead.
            let face = if cells.nc == 1 {
                f64::INFINITY
            } else {
                let start = cells.coord[i][a] as f64 * cells.side - 0.5 * l;
                let mut u = self.pos[a][i] - start;
                if u > 0.5 * l {
                    u -= l;
                } else if u < -0.5 * l {
                    u += l;
                }
                if sg > 0.0 {
                    (cells.side - u).max(0.0)
                } else {
                    u.max(0.0)
                }
            };
            // What limits this step: the end of the chain (0), the container (1) or the face (2).
            let (limit, which) = if left <= stop_at && left <= face {
                (left, 0)
            } else if stop_at <= face {
                (stop_at, 1)
            } else {
                (face, 2)
            };
            let (t, hit, along) = self.next_collision(cells, i, a, sg, limit, margin);
            // A chain that cannot advance: more steps no longer than the margin in a row than
            // spheres could stand in a touching row, which happens only in a row of touching
            // spheres jammed between two points of a wall (the droplets' FCC start has them,
            // equilibrium has not): ended there.
            if t <= margin {
                idle += 1;
                if idle > self.len() + 64 {
                    break;
                }
            } else {
                idle = 0;
            }
            let x = &mut self.pos[a][i];
            *x += sg * t;
            if *x >= 0.5 * l {
                *x -= l;
            } else if *x < -0.5 * l {
                *x += l;
            }
            if let Some(j) = hit {
                left -= t;
                stats.lifts += 1;
                stats.lift_sum += along;
                i = j;
                (stop_at, stop) = self.next_stop(i, a, sg, margin, false, rng);
                continue;
            }
            match which {
                0 => break,
                1 => {
                    left -= t;
                    if matches!(stop, Stop::Soft | Stop::Hard) {
                        sg = -sg;
                        stats.reversals += 1;
                    }
                    let entered = stop == Stop::EnterSoft;
                    (stop_at, stop) = self.next_stop(i, a, sg, margin, entered, rng);
                }
                _ => {
                    left -= t;
                    stop_at -= t;
                    // Into the next cell along the direction.
                    let mut c = cells.coord[i];
                    let nc = cells.nc as i64;
                    c[a] = (c[a] as i64 + if sg > 0.0 { 1 } else { -1 }).rem_euclid(nc) as u32;
                    cells.transfer(i, c);
                }
            }
        }
        stats
    }
}
