//! The SRD solvent: point particles of mass m that stream ballistically for a collision time
//! `tau` and then exchange momentum in cubic cells of edge `a` by stochastic rotation dynamics
//! (Malevanets & Kapral, J. Chem. Phys. 110, 8605 (1999); Ihle & Kroll, Phys. Rev. E 63,
//! 020201 (2001)):
//!
//! `v_i' = u + lambda R(n, alpha) (v_i - u)`,
//!
//! with `u` the mass-weighted mean velocity of the cell's members (solvent, embedded colloid
//! vertices and virtual wall particles), `R(n, alpha) w = w cos(alpha) + (n x w) sin(alpha) +
//! n (n.w) (1 - cos(alpha))` a rotation by the fixed angle `alpha` about an axis `n` uniform
//! on the sphere, drawn per cell (no angular-momentum conservation, as in the paper), and the
//! grid shifted by a vector uniform in `[-a/2, a/2)^3` before every collision (Galilean
//! invariance). The cell-level Maxwell–Boltzmann thermostat (Huang, Chatterji, Sutmann,
//! Gompper & Winkler, J. Comput. Phys. 229, 168 (2010)) scales the relative velocities by
//! `lambda = sqrt(E'/E)`, where `E = sum m |v_i - u|^2 / 2` and `E'` is drawn from the
//! Gamma distribution of shape `3 (N_c - 1) / 2` and scale `kT` (the relative kinetic energy
//! of `N_c` particles in equilibrium); without it `lambda = 1` and the collision conserves
//! momentum and energy exactly.
//!
//! **Layout and determinism.** Every per-particle quantity is one array per component
//! (structure of arrays). Positions are 32-bit fixed-point fractions of the box edges
//! (resolution `L / 2^32`, 1.4e-8 `a` in a box of 60 cells), so that periodic wrapping is exact
//! integer arithmetic and a position takes 12 bytes; velocities are `f64`s (24 bytes). Each
//! collision sorts the particles into the shifted cells by a counting sort (a rank within the
//! cell, 2 bytes, then a list of slots cell by cell, 4 bytes). A cell's sums (its momentum
//! and, for the thermostat, its relative kinetic energy) are added exactly in fixed point
//! ([`ExactSum`]), so a collision does not depend on the order of the cell's members, and
//! every random number of a collision is drawn from a counter-based stream keyed by (seed,
//! step, row of cells along x), consumed cell by cell along the row: a step is a function of
//! the set of particles alone, bitwise the same on any number of threads, in any storage
//! order, and on any number of ranks ([`super::ranks`], each owning whole layers of cells).
//! The collision writes the velocities of each cell's members through the cell list, from many
//! threads at once (rayon over chunks of cells): velocities are therefore stored as the bits of
//! `f64`s in `AtomicU64`s ([`SharedVectors`]), whose relaxed loads and stores are plain moves;
//! every slot belongs to one cell, so no two threads touch it. Every `sort_every` collisions
//! the arrays are permuted into cell order, one component at a time through a scratch array
//! (4 + 8 bytes), in parallel. In all 54 bytes per particle ([`Srd::bytes_per_particle`])
//! and 8 per cell, 55.6 bytes per particle at density 5; nothing is allocated per step (except for cells with more
//! than [`CELL_CAPACITY`] members, which are rare).

use super::boundary::Confinement;
use super::{Draw, MpcdError, draw};
use crate::state::SimBox;
use colloidsim_core::rng::Ziggurat;
use rand::{Rng, RngExt};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

/// Members of a cell handled on the stack; larger cells (rare) allocate.
pub const CELL_CAPACITY: usize = 64;
/// Particles per streaming chunk (fixed, so that the bounce lists do not depend on the threads).
const STREAM_CHUNK: usize = 4096;
/// Cells per collision task, at least (whole rows of cells are taken).
const CELL_CHUNK: usize = 256;

/// A sum of `f64`s that does not depend on their order. Each term `x` (|x| < 2^19) is split
/// into `x` rounded to a multiple of 2^-32 and the rest rounded to a multiple of 2^-64 (by
/// adding and subtracting 1.5 2^20 and 1.5 2^-12), and the two parts are summed separately:
/// while the sums stay below 2^20 every partial sum is a float exactly, so the result, the two
/// parts added once at the end, is the same in any order (and within 2^-64 per term of the
/// true sum).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ExactSum {
    hi: f64,
    lo: f64,
}

impl ExactSum {
    const HI: f64 = 1572864.0; // 1.5 2^20: its ulp is 2^-32
    const LO: f64 = 1.5 / 4096.0; // 1.5 2^-12: its ulp is 2^-64

    /// Add `x`.
    #[inline(always)]
    pub fn add(&mut self, x: f64) {
        let h = (x + Self::HI) - Self::HI;
        let l = ((x - h) + Self::LO) - Self::LO;
        self.hi += h;
        self.lo += l;
    }

    /// The sum, rounded once to the nearest `f64`.
    #[inline]
    pub fn value(self) -> f64 {
        self.hi + self.lo
    }
}

/// Parameters of the SRD solvent (MPCD units: lengths in `a`, masses in `m`, energies in `kT`
/// unless chosen otherwise).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SrdParams {
    /// Cell edge `a`.
    pub cell: f64,
    /// Mean number of solvent particles per cell, `M = n a^3`.
    pub density: f64,
    /// Rotation angle `alpha` (radians).
    pub angle: f64,
    /// Collision time `tau` (time between collisions; the streaming step).
    pub tau: f64,
    /// Thermal energy `kT`.
    pub kt: f64,
    /// Mass `m` of a solvent particle.
    pub mass: f64,
    /// Cell-level Maxwell–Boltzmann thermostat.
    pub thermostat: bool,
    /// Seed of every random stream.
    pub seed: u32,
}

impl SrdParams {
    /// The usual values (the drying-droplet paper, docs/references.md): `a = 1`, density 5, 130 degrees, `tau = 0.1`,
    /// `m = kT = 1`, thermostat on.
    pub fn standard(seed: u32) -> Self {
        Self {
            cell: 1.0,
            density: 5.0,
            angle: 130f64.to_radians(),
            tau: 0.1,
            kt: 1.0,
            mass: 1.0,
            thermostat: true,
            seed,
        }
    }
}

/// A body force per unit mass on the solvent, integrated exactly over each free flight: the
/// velocity change `dv` of the flight is applied half before and half after streaming, so the
/// position moves by `(v + dv/2) tau` (exact for the uniform force; for the cosine force, which
/// acts along `x` and varies along `z` only, the velocity change is exact and the displacement
/// along `x` is off by a term of relative order `(k v_z tau)^2`; a reflection within the flight
/// makes both approximate).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Acceleration {
    /// None.
    #[default]
    None,
    /// The same everywhere.
    Uniform([f64; 3]),
    /// `g_x = amplitude cos(wavenumber z)` (periodic Poiseuille flow, for the viscosity).
    CosineX {
        /// Amplitude.
        amplitude: f64,
        /// Wave number `2 pi / L_z`.
        wavenumber: f64,
    },
}

impl Acceleration {
    /// The velocity change over a free flight of duration `tau` from `x` with velocity `v`:
    /// `g tau`, or for the cosine drive `int_0^tau g0 cos(k (z + v_z s)) ds =
    /// g0 tau cos(k z + theta) sin(theta) / theta` with `theta = k v_z tau / 2`.
    #[inline(always)]
    pub fn kick(&self, x: [f64; 3], v: [f64; 3], tau: f64) -> [f64; 3] {
        match *self {
            Acceleration::None => [0.0; 3],
            Acceleration::Uniform(g) => [g[0] * tau, g[1] * tau, g[2] * tau],
            Acceleration::CosineX {
                amplitude,
                wavenumber,
            } => {
                let theta = 0.5 * wavenumber * v[2] * tau;
                let sinc = if theta.abs() < 1e-4 {
                    1.0 - theta * theta / 6.0
                } else {
                    theta.sin() / theta
                };
                [
                    amplitude * tau * (wavenumber * x[2] + theta).cos() * sinc,
                    0.0,
                    0.0,
                ]
            }
        }
    }
}

/// A sum over many terms that does not depend on their order: each term `x` (|x| < 2^30) as
/// the integer `x 2^64` (truncated below 2^-64), summed in a 128-bit integer (no overflow for
/// any count of such terms below 2^33), the total rounded once; a non-finite term makes the
/// total NaN. Sums over all particles ([`Srd::sum`]) use it, so that they are the same bits
/// in any storage order and over any number of ranks (partial totals merge exactly).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ExactTotal {
    total: i128,
    non_finite: bool,
}

impl ExactTotal {
    const SCALE: f64 = 4294967296.0;

    /// Add `x`.
    #[inline(always)]
    pub fn add(&mut self, x: f64) {
        if !x.is_finite() {
            self.non_finite = true;
            return;
        }
        let a = x * Self::SCALE;
        let h = a as i64;
        // a - h is exact (the fraction of a float), and so is its scaling by 2^32.
        let l = ((a - h as f64) * Self::SCALE) as i64;
        self.total = self
            .total
            .wrapping_add(((h as i128) << 32).wrapping_add(l as i128));
    }

    /// Add another total.
    pub fn merge(&mut self, o: ExactTotal) {
        self.total = self.total.wrapping_add(o.total);
        self.non_finite |= o.non_finite;
    }

    /// The total, rounded once to the nearest `f64` (NaN after a non-finite term).
    pub fn value(self) -> f64 {
        if self.non_finite {
            return f64::NAN;
        }
        self.total as f64 / (Self::SCALE * Self::SCALE)
    }

    /// As four numbers exact in `f64`s (32-bit pieces, the top one signed; NaNs for a
    /// non-finite total), for a message.
    pub fn words(self) -> [f64; 4] {
        if self.non_finite {
            return [f64::NAN; 4];
        }
        let t = self.total;
        [
            (t >> 96) as i32 as f64,
            ((t >> 64) as u32) as f64,
            ((t >> 32) as u32) as f64,
            (t as u32) as f64,
        ]
    }

    /// From [`Self::words`].
    pub fn from_words(w: &[f64]) -> Self {
        if w[..4].iter().any(|x| x.is_nan()) {
            return Self {
                total: 0,
                non_finite: true,
            };
        }
        let total = ((w[0] as i32 as i128) << 96)
            | ((w[1] as u32 as i128) << 64)
            | ((w[2] as u32 as i128) << 32)
            | (w[3] as u32 as i128);
        Self {
            total,
            non_finite: false,
        }
    }
}

/// Vectors of `f64` stored as bits in `AtomicU64`s, one array per component, so that the
/// collision pass can write the members of each cell through the cell list from several
/// threads (see the module docs).
#[derive(Debug, Default)]
pub struct SharedVectors([Vec<AtomicU64>; 3]);

impl SharedVectors {
    /// From plain vectors.
    pub fn from_slice(v: &[[f64; 3]]) -> Self {
        Self(std::array::from_fn(|k| {
            v.iter().map(|x| AtomicU64::new(x[k].to_bits())).collect()
        }))
    }

    /// Number of vectors.
    pub fn len(&self) -> usize {
        self.0[0].len()
    }

    /// None?
    pub fn is_empty(&self) -> bool {
        self.0[0].is_empty()
    }

    /// Vector `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> [f64; 3] {
        [
            f64::from_bits(self.0[0][i].load(Relaxed)),
            f64::from_bits(self.0[1][i].load(Relaxed)),
            f64::from_bits(self.0[2][i].load(Relaxed)),
        ]
    }

    /// Set vector `i`.
    #[inline(always)]
    pub fn set(&self, i: usize, v: [f64; 3]) {
        self.0[0][i].store(v[0].to_bits(), Relaxed);
        self.0[1][i].store(v[1].to_bits(), Relaxed);
        self.0[2][i].store(v[2].to_bits(), Relaxed);
    }

    /// Copies as plain vectors.
    pub fn to_vec(&self) -> Vec<[f64; 3]> {
        (0..self.len()).map(|i| self.get(i)).collect()
    }

    /// Replace the contents by `v`, reusing the storage.
    pub fn assign(&mut self, v: &[[f64; 3]]) {
        for k in 0..3 {
            let c = &mut self.0[k];
            c.truncate(v.len());
            for (a, x) in c.iter_mut().zip(v) {
                *a.get_mut() = x[k].to_bits();
            }
            let have = c.len();
            c.extend(v[have..].iter().map(|x| AtomicU64::new(x[k].to_bits())));
        }
    }

    fn swap_remove(&mut self, i: usize) {
        for c in &mut self.0 {
            c.swap_remove(i);
        }
    }
}

/// Particles of other kinds that join the collisions (the colloids' vertices): positions
/// (any periodic image), velocities (updated) and masses.
pub struct Embedded<'a> {
    /// Positions.
    pub pos: &'a [[f64; 3]],
    /// Velocities, replaced by their post-collision values.
    pub vel: &'a mut [[f64; 3]],
    /// Masses.
    pub mass: &'a [f64],
}

/// What one streaming step did at the walls.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StreamStats {
    /// Particles that were reflected at least once.
    pub bounced: u64,
    /// Reflections.
    pub reflections: u64,
    /// Particles still outside after the most reflections and placed back by hand.
    pub stuck: u64,
}

/// What one collision did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CollisionStats {
    /// Cells with at least one member.
    pub occupied_cells: u64,
    /// Virtual particles added in cells cut by a wall.
    pub virtual_particles: u64,
}

/// Fixed-point coordinates: `x = k L / 2^32 - L/2` for the integer `k` in `[0, 2^32)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixedPoint {
    /// Box edges.
    pub l: [f64; 3],
    /// `2^32 / L` per axis.
    scale: [f64; 3],
    /// `L / 2^32` per axis.
    unit: [f64; 3],
}

const TWO32: f64 = 4_294_967_296.0;

impl FixedPoint {
    /// Coordinates of the box `sbox`.
    pub fn new(sbox: &SimBox) -> Self {
        let l = sbox.l;
        Self {
            l,
            scale: l.map(|x| TWO32 / x),
            unit: l.map(|x| x / TWO32),
        }
    }

    /// The fixed-point form of `x` (any periodic image: wrapped exactly).
    #[inline(always)]
    pub fn encode(&self, x: [f64; 3]) -> [u32; 3] {
        std::array::from_fn(|k| ((x[k] + 0.5 * self.l[k]) * self.scale[k]).round() as i64 as u32)
    }

    /// The position of `x` in `[-L/2, L/2)`.
    #[inline(always)]
    pub fn decode(&self, x: [u32; 3]) -> [f64; 3] {
        std::array::from_fn(|k| x[k] as f64 * self.unit[k] - 0.5 * self.l[k])
    }

    /// A displacement `d` (any size) in fixed-point units (two's complement).
    #[inline(always)]
    pub fn displacement(&self, d: [f64; 3]) -> [u32; 3] {
        std::array::from_fn(|k| (d[k] * self.scale[k]).round() as i64 as u32)
    }
}

/// The cells of the (shifted) collision grid: `n` per axis, z-major numbering
/// `(cz ny + cy) nx + cx`. With the shift `s` (fixed point), cell `i` along an axis holds the
/// positions `k` with `floor(((k - s) mod 2^32) n / 2^32) = i`, i.e. `[-L/2 + s + i a,
/// -L/2 + s + (i+1) a)` (periodically).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// Cells per axis.
    pub n: [usize; 3],
    /// Cell edge.
    pub a: f64,
    /// Box edges (`n a`).
    pub l: [f64; 3],
}

impl Grid {
    /// The grid of cells of edge `a` in `sbox`; every box edge must be a whole number of cells.
    pub fn new(sbox: &SimBox, a: f64) -> Result<Self, MpcdError> {
        let mut n = [0usize; 3];
        for k in 0..3 {
            let q = sbox.l[k] / a;
            let r = q.round();
            if !(r >= 1.0 && (q - r).abs() <= 1e-9 * q.max(1.0)) || r > 1e6 {
                return Err(MpcdError::Invalid(format!(
                    "box edge {} must be a whole number (1 to 10^6) of solvent cells of edge {a} (edge / cell = {q})",
                    sbox.l[k]
                )));
            }
            n[k] = r as usize;
        }
        Ok(Self { n, a, l: sbox.l })
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    /// Cell of the fixed-point position `x` on the grid shifted by `s` (fixed point).
    #[inline(always)]
    pub fn cell(&self, x: [u32; 3], s: [u32; 3]) -> usize {
        let c = |k: usize| ((x[k].wrapping_sub(s[k]) as u64 * self.n[k] as u64) >> 32) as usize;
        (c(2) * self.n[1] + c(1)) * self.n[0] + c(0)
    }

    /// Lower corner of cell `c` on the grid shifted by `s` (the shift as a position offset in
    /// `[-a/2, a/2]`; unwrapped: it may lie up to `a` outside the box).
    #[inline(always)]
    pub fn corner(&self, c: usize, s: [f64; 3]) -> [f64; 3] {
        let cx = c % self.n[0];
        let cy = (c / self.n[0]) % self.n[1];
        let cz = c / (self.n[0] * self.n[1]);
        [
            -0.5 * self.l[0] + s[0] + cx as f64 * self.a,
            -0.5 * self.l[1] + s[1] + cy as f64 * self.a,
            -0.5 * self.l[2] + s[2] + cz as f64 * self.a,
        ]
    }
}

/// Is the cell `[lo, lo + a]^3` cut by the wall of `conf` at time `t`?
fn cut(conf: &Confinement, lo: [f64; 3], a: f64, t: f64) -> bool {
    match *conf {
        Confinement::None => false,
        Confinement::Sphere { law, .. } => {
            let r = law.radius(t);
            let (mut near, mut far) = (0.0, 0.0);
            for k in 0..3 {
                let (l, h) = (lo[k], lo[k] + a);
                let d = if l > 0.0 {
                    l
                } else if h < 0.0 {
                    -h
                } else {
                    0.0
                };
                near += d * d;
                far += l.abs().max(h.abs()).powi(2);
            }
            near < r * r && far > r * r
        }
        Confinement::Slab { half_width: h, .. } => {
            let (l, u) = (lo[2], lo[2] + a);
            (l < h && u > h) || (l < -h && u > -h)
        }
    }
}

/// The wall velocity of `conf` at a point `x` beyond the wall at time `t`.
#[inline]
fn wall_velocity(conf: &Confinement, x: [f64; 3], t: f64) -> [f64; 3] {
    match *conf {
        Confinement::Sphere { law, .. } => {
            // dR/dt = -alpha / (8 pi R).
            let r = law.radius(t);
            let speed = if r > 0.0 {
                -law.alpha / (8.0 * std::f64::consts::PI * r)
            } else {
                0.0
            };
            let d = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
            if d > 0.0 {
                [speed * x[0] / d, speed * x[1] / d, speed * x[2] / d]
            } else {
                [0.0; 3]
            }
        }
        _ => [0.0; 3],
    }
}

/// Marsaglia–Tsang constants `(d, c) = (k - 1/3, 1 / sqrt(9 d))` of the Gamma distribution of
/// shape `k = 3 (N - 1) / 2`, for `N = 0 ..= CELL_CAPACITY` (entries below 2 unused).
fn gamma_table() -> [[f64; 2]; CELL_CAPACITY + 1] {
    std::array::from_fn(|n| {
        let k = 1.5 * (n.max(2) - 1) as f64;
        let d = k - 1.0 / 3.0;
        [d, 1.0 / (9.0 * d).sqrt()]
    })
}

/// A Gamma deviate of shape `d + 1/3 >= 1` and unit scale (Marsaglia & Tsang, ACM Trans. Math.
/// Softw. 26, 363 (2000)), with the normal deviates of the inlined ziggurat.
#[inline]
fn gamma(d: f64, c: f64, zig: &Ziggurat, rng: &mut impl Rng) -> f64 {
    loop {
        let x = zig.sample(rng);
        let v = 1.0 + c * x;
        if v <= 0.0 {
            continue;
        }
        let v = v * v * v;
        let u: f64 = rng.random();
        let x2 = x * x;
        if u < 1.0 - 0.0331 * x2 * x2 || u.ln() < 0.5 * x2 + d * (1.0 - v + v.ln()) {
            return d * v;
        }
    }
}

/// A unit vector uniform on the sphere (Marsaglia, Ann. Math. Statist. 43, 645 (1972)).
#[inline]
fn unit_vector(rng: &mut impl Rng) -> [f64; 3] {
    loop {
        let a = 2.0 * rng.random::<f64>() - 1.0;
        let b = 2.0 * rng.random::<f64>() - 1.0;
        let s = a * a + b * b;
        if s < 1.0 {
            let f = 2.0 * (1.0 - s).sqrt();
            return [a * f, b * f, 1.0 - 2.0 * s];
        }
    }
}

/// The particle arrays of an [`Srd`], shareable between threads (the engine itself is not
/// `Sync` when it holds the ranks of a decomposed run).
#[derive(Clone, Copy)]
pub struct View<'a> {
    pos: &'a [Vec<u32>; 3],
    vel: &'a SharedVectors,
    fixed: FixedPoint,
}

impl View<'_> {
    /// Number of particles (this rank's).
    pub fn len(&self) -> usize {
        self.pos[0].len()
    }

    /// None?
    pub fn is_empty(&self) -> bool {
        self.pos[0].is_empty()
    }

    /// Position of slot `i`, in `[-L/2, L/2)`.
    #[inline(always)]
    pub fn position(&self, i: usize) -> [f64; 3] {
        self.fixed
            .decode([self.pos[0][i], self.pos[1][i], self.pos[2][i]])
    }

    /// Velocity of slot `i`.
    #[inline(always)]
    pub fn velocity(&self, i: usize) -> [f64; 3] {
        self.vel.get(i)
    }
}

/// The constants of a collision.
struct Rule {
    cos: f64,
    sin: f64,
    kt: f64,
    mass: f64,
    density: f64,
    a: f64,
    thermostat: bool,
    gamma: [[f64; 2]; CELL_CAPACITY + 1],
}

/// The SRD solvent engine (see the module docs).
#[derive(Debug)]
pub struct Srd {
    params: SrdParams,
    sbox: SimBox,
    grid: Grid,
    fixed: FixedPoint,
    /// Positions in fixed point, one array per axis.
    pos: [Vec<u32>; 3],
    vel: SharedVectors,
    /// Collisions done.
    step: u64,
    /// Permute the arrays into cell order every this many collisions (0: never).
    sort_every: u64,
    /// The cells whose collisions this engine does (all, or the layers of a rank's domain):
    /// the per-cell arrays below are indexed by `c - owned.start`.
    owned: std::ops::Range<usize>,
    /// Per cell: members counted.
    count: Vec<AtomicU32>,
    /// Members of cell `c` are `order[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    /// Per particle: its rank among the members of its cell as they were counted.
    rank: Vec<u16>,
    /// Slots of the solvent particles, cell by cell.
    order: Vec<AtomicU32>,
    /// Scratch of the storage sort (one component at a time).
    scratch_pos: Vec<u32>,
    scratch_vel: Vec<AtomicU64>,
    /// Embedded particles of the current collision in the own cells: (cell, index), sorted.
    pub(super) emb: Vec<(u32, u32)>,
    emb_vel: SharedVectors,
    emb_mass: Vec<f64>,
    /// Per streaming chunk: slots of the particles reflected in the last streaming step.
    pub(super) bounced: Vec<Vec<u32>>,
    /// Per slot, during a migration: reflected in the streaming step (decomposed runs).
    pub(super) flags: Vec<bool>,
    /// The messages of the collective sums and counts (this rank's numbers, every rank's),
    /// kept between calls (decomposed runs).
    pub(super) gather_buffers: std::cell::RefCell<(Vec<f64>, Vec<f64>)>,
    /// Seconds spent in the parts of a step: streaming, binning, storage sorts, cell
    /// collisions.
    pub timers: [f64; 4],
    /// The ranks and this rank's layers, when decomposed ([`super::ranks`]).
    pub(super) domain: Option<crate::domain::Domain>,
    /// Slots leaving in the current migration round (decomposed runs).
    pub(super) leaving: Vec<u32>,
    /// Per streaming chunk: slots that left the own layers of the next collision's grid in the
    /// last streaming step (decomposed runs).
    pub(super) leavers: Vec<Vec<u32>>,
}

impl Srd {
    /// A solvent of `round(density / a^3 * V)` particles placed uniformly in the fluid region
    /// of `conf` at time `t` (volume `V`) with Maxwell–Boltzmann velocities at `kT` (their
    /// mean removed), from streams keyed by (seed, block of 64 particles).
    pub fn new(
        params: SrdParams,
        sbox: SimBox,
        conf: &Confinement,
        t: f64,
    ) -> Result<Self, MpcdError> {
        Self::generate(params, sbox, conf, t, |_| true)
    }

    /// The particles of [`Self::new`] for which `keep(position)` holds (all of them for `new`),
    /// in the same order, with the mean velocity of *all* of them removed: the whole start is
    /// drawn chunk by chunk, so only the kept particles are held (a rank's share of a
    /// decomposed start, [`Self::new_decomposed`]).
    pub(super) fn generate(
        params: SrdParams,
        sbox: SimBox,
        conf: &Confinement,
        t: f64,
        keep: impl Fn([u32; 3]) -> bool,
    ) -> Result<Self, MpcdError> {
        check_params(&params)?;
        Grid::new(&sbox, params.cell)?;
        let volume = conf.volume(t, sbox.l);
        let n = (params.density / params.cell.powi(3) * volume).round();
        if n >= (1u64 << 31) as f64 {
            return Err(MpcdError::Invalid(format!(
                "{n:e} solvent particles: at most 2^31 - 1 are supported"
            )));
        }
        let n = n as usize;
        let l = sbox.l;
        let sd = (params.kt / params.mass).sqrt();
        let zig = Ziggurat::get();
        let fixed = FixedPoint::new(&sbox);
        // Chunks of 1024 blocks of 64 particles, each block from its own stream.
        const CHUNK: usize = 1 << 16;
        let mut pos = vec![[0.0; 3]; CHUNK.min(n)];
        let mut vel = vec![[0.0; 3]; CHUNK.min(n)];
        let (mut kept_pos, mut kept_vel) = (Vec::new(), Vec::new());
        let mut sum = [0.0; 3];
        for c0 in (0..n).step_by(CHUNK) {
            let len = CHUNK.min(n - c0);
            pos[..len]
                .par_chunks_mut(64)
                .zip(vel[..len].par_chunks_mut(64))
                .enumerate()
                .for_each(|(b, (pc, vc))| {
                    let block = (c0 / 64 + b) as u64;
                    let mut rng = draw(params.seed, 0, Draw::Solvent, block);
                    for (x, v) in pc.iter_mut().zip(vc.iter_mut()) {
                        loop {
                            let u: [f64; 3] = [rng.random(), rng.random(), rng.random()];
                            *x = [
                                (u[0] - 0.5) * l[0],
                                (u[1] - 0.5) * l[1],
                                (u[2] - 0.5) * l[2],
                            ];
                            if conf.inside(*x, t) {
                                break;
                            }
                        }
                        for c in v.iter_mut() {
                            *c = sd * zig.sample(&mut rng);
                        }
                    }
                });
            // The mean in the order of the whole start, as one sum.
            for v in &vel[..len] {
                for k in 0..3 {
                    sum[k] += v[k] / n as f64;
                }
            }
            for (x, v) in pos[..len].iter().zip(&vel[..len]) {
                let raw = fixed.encode(*x);
                if keep(raw) {
                    kept_pos.push(raw);
                    kept_vel.push(*v);
                }
            }
        }
        for v in &mut kept_vel {
            for k in 0..3 {
                v[k] -= sum[k];
            }
        }
        Self::from_raw(params, sbox, &kept_pos, &kept_vel, 0)
    }

    /// A solvent in a given state, `step` collisions done: positions in fixed point
    /// ([`FixedPoint`], as [`Self::raw_positions`] gives them) and velocities, in storage order.
    /// Continues bitwise as the engine that had this state.
    pub fn from_raw(
        params: SrdParams,
        sbox: SimBox,
        pos: &[[u32; 3]],
        vel: &[[f64; 3]],
        step: u64,
    ) -> Result<Self, MpcdError> {
        check_params(&params)?;
        let grid = Grid::new(&sbox, params.cell)?;
        if pos.len() != vel.len() {
            return Err(MpcdError::Invalid(format!(
                "{} positions but {} velocities",
                pos.len(),
                vel.len()
            )));
        }
        if pos.len() >= 1 << 31 {
            return Err(MpcdError::Invalid(
                "at most 2^31 - 1 solvent particles are supported".into(),
            ));
        }
        if let Some(i) = vel.iter().position(|v| v.iter().any(|c| !c.is_finite())) {
            return Err(MpcdError::NonFinite {
                step,
                what: "solvent",
                index: i,
            });
        }
        let cells = grid.cells();
        let n = pos.len();
        Ok(Self {
            params,
            sbox,
            grid,
            fixed: FixedPoint::new(&sbox),
            pos: std::array::from_fn(|k| pos.iter().map(|x| x[k]).collect()),
            vel: SharedVectors::from_slice(vel),
            step,
            sort_every: 10,
            owned: 0..cells,
            count: (0..cells).map(|_| AtomicU32::new(0)).collect(),
            start: vec![0; cells + 1],
            rank: vec![0; n],
            order: (0..n as u32).map(AtomicU32::new).collect(),
            scratch_pos: Vec::new(),
            scratch_vel: Vec::new(),
            emb: Vec::new(),
            emb_vel: SharedVectors::default(),
            emb_mass: Vec::new(),
            bounced: Vec::new(),
            timers: [0.0; 4],
            domain: None,
            leaving: Vec::new(),
            leavers: Vec::new(),
            flags: Vec::new(),
            gather_buffers: Default::default(),
        })
    }

    /// A solvent from positions (any periodic image) and velocities, `step` collisions done.
    pub fn from_state(
        params: SrdParams,
        sbox: SimBox,
        pos: &[[f64; 3]],
        vel: &[[f64; 3]],
        step: u64,
    ) -> Result<Self, MpcdError> {
        if let Some(i) = pos.iter().position(|x| x.iter().any(|c| !c.is_finite())) {
            return Err(MpcdError::NonFinite {
                step,
                what: "solvent",
                index: i,
            });
        }
        let fixed = FixedPoint::new(&sbox);
        let raw: Vec<[u32; 3]> = pos.iter().map(|x| fixed.encode(*x)).collect();
        Self::from_raw(params, sbox, &raw, vel, step)
    }

    /// The particle arrays, for work on many threads.
    pub fn view(&self) -> View<'_> {
        View {
            pos: &self.pos,
            vel: &self.vel,
            fixed: self.fixed,
        }
    }

    /// Parameters.
    pub fn params(&self) -> &SrdParams {
        &self.params
    }

    /// The periodic box.
    pub fn sbox(&self) -> &SimBox {
        &self.sbox
    }

    /// The collision grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The fixed-point coordinates of the positions.
    pub fn fixed_point(&self) -> &FixedPoint {
        &self.fixed
    }

    /// Collisions done.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// Number of solvent particles.
    pub fn len(&self) -> usize {
        self.pos[0].len()
    }

    /// No solvent?
    pub fn is_empty(&self) -> bool {
        self.pos[0].is_empty()
    }

    /// Position of slot `i` in fixed point.
    #[inline(always)]
    pub fn raw_position(&self, i: usize) -> [u32; 3] {
        [self.pos[0][i], self.pos[1][i], self.pos[2][i]]
    }

    /// Positions in fixed point, in storage order (the exact state, for checkpoints).
    pub fn raw_positions(&self) -> Vec<[u32; 3]> {
        (0..self.len()).map(|i| self.raw_position(i)).collect()
    }

    /// Position of the particle in slot `i`, in `[-L/2, L/2)`.
    #[inline]
    pub fn position(&self, i: usize) -> [f64; 3] {
        self.fixed.decode(self.raw_position(i))
    }

    /// Positions in `[-L/2, L/2)`, in storage order.
    pub fn positions(&self) -> Vec<[f64; 3]> {
        (0..self.len()).map(|i| self.position(i)).collect()
    }

    /// Velocity of the particle in slot `i`.
    #[inline]
    pub fn velocity(&self, i: usize) -> [f64; 3] {
        self.vel.get(i)
    }

    /// Velocities in storage order.
    pub fn velocities(&self) -> Vec<[f64; 3]> {
        self.vel.to_vec()
    }

    /// Permute the arrays into cell order every `every` collisions (0: never). Part of the
    /// state's history: a continuation must use the same period.
    pub fn set_sort_every(&mut self, every: u64) {
        self.sort_every = every;
    }

    /// The storage-sort period.
    pub fn sort_every(&self) -> u64 {
        self.sort_every
    }

    /// Bytes held per solvent particle by the per-particle arrays: positions (12), velocities
    /// (24), rank (2), cell list (4) and the storage sort's scratch (one component: 4 + 8).
    /// The cells add [`Self::bytes_per_cell`] each (1.6 bytes per particle at density 5).
    pub fn bytes_per_particle() -> usize {
        3 * std::mem::size_of::<u32>()
            + 3 * std::mem::size_of::<AtomicU64>()
            + std::mem::size_of::<u16>()
            + std::mem::size_of::<AtomicU32>()
            + std::mem::size_of::<u32>()
            + std::mem::size_of::<AtomicU64>()
    }

    /// Bytes held per collision cell (member counts and starts).
    pub fn bytes_per_cell() -> usize {
        std::mem::size_of::<AtomicU32>() + std::mem::size_of::<u32>()
    }

    /// The grid shift of collision `step`, uniform in `[-a/2, a/2)^3`, as a position offset
    /// (rounded to the fixed-point grid, so that it names the same cells as [`Self::cell_of`]).
    pub fn shift(&self, step: u64) -> [f64; 3] {
        let d = self.raw_shift(step);
        std::array::from_fn(|k| d[k] as i32 as f64 * self.fixed.unit[k])
    }

    fn raw_shift(&self, step: u64) -> [u32; 3] {
        Self::shift_of(&self.params, &self.fixed, step)
    }

    /// The grid shift of collision `step` in fixed point.
    pub(super) fn shift_of(params: &SrdParams, fixed: &FixedPoint, step: u64) -> [u32; 3] {
        let mut rng = draw(params.seed, step, Draw::Shift, 0);
        let a = params.cell;
        let u: [f64; 3] = [rng.random(), rng.random(), rng.random()];
        fixed.displacement([(u[0] - 0.5) * a, (u[1] - 0.5) * a, (u[2] - 0.5) * a])
    }

    /// The collision cell of position `x` (any image) at collision `step`.
    pub fn cell_of(&self, x: [f64; 3], step: u64) -> usize {
        self.grid.cell(self.fixed.encode(x), self.raw_shift(step))
    }

    /// Stream every particle for `tau` up to time `t1` (driven by `accel`), reflecting at
    /// the walls of `conf`, and wrap into the box. The slots of the reflected particles are
    /// kept for [`Self::bounced`].
    ///
    /// Decomposed ([`super::ranks`]), the particles then go to the ranks that own their cells
    /// on the next collision's grid, a non-finite velocity on any rank stops every rank, and
    /// the counts returned are those of all ranks (collective); [`Self::bounced`] stays this
    /// rank's.
    pub fn stream(
        &mut self,
        t1: f64,
        conf: &Confinement,
        accel: &Acceleration,
    ) -> Result<StreamStats, MpcdError> {
        if self.domain.is_none() {
            return self.stream_own(t1, conf, accel);
        }
        let streamed = self.stream_own(t1, conf, accel);
        let bad = match &streamed {
            Err(MpcdError::NonFinite { index, .. }) => Some(*index),
            _ => None,
        };
        self.migrate(bad)?;
        let st = streamed?;
        let t = self.add_over_ranks([st.bounced, st.reflections, st.stuck]);
        Ok(StreamStats {
            bounced: t[0],
            reflections: t[1],
            stuck: t[2],
        })
    }

    /// [`Self::stream`] of this engine's (this rank's) particles.
    fn stream_own(
        &mut self,
        t1: f64,
        conf: &Confinement,
        accel: &Acceleration,
    ) -> Result<StreamStats, MpcdError> {
        let clock = std::time::Instant::now();
        let tau = self.params.tau;
        let n = self.len();
        let chunks = n.div_ceil(STREAM_CHUNK);
        self.bounced.resize_with(chunks, Vec::new);
        self.leavers.resize_with(chunks, Vec::new);
        // Decomposed: which particles leave the own layers of the next collision's grid, found
        // chunk by chunk while the positions are in cache.
        let own = self.domain.as_ref().map(|d| {
            let s = self.raw_shift(self.step)[2];
            (s, self.grid.n[2] as u64, d.z0..d.z1)
        });
        let (vel, fixed) = (&self.vel, self.fixed);
        let (accel, conf) = (*accel, *conf);
        let free = matches!(conf, Confinement::None) && matches!(accel, Acceleration::None);
        let [px, py, pz] = &mut self.pos;
        let stats: Vec<(u64, u64, u64, Option<usize>)> = px
            .par_chunks_mut(STREAM_CHUNK)
            .zip(py.par_chunks_mut(STREAM_CHUNK))
            .zip(pz.par_chunks_mut(STREAM_CHUNK))
            .zip(self.bounced.par_iter_mut().zip(self.leavers.par_iter_mut()))
            .enumerate()
            .map(|(ci, (((xs, ys), zs), (list, leavers)))| {
                list.clear();
                leavers.clear();
                let (mut bounced, mut refl, mut stuck) = (0u64, 0u64, 0u64);
                let mut bad = None;
                for k in 0..xs.len() {
                    let i = ci * STREAM_CHUNK + k;
                    let mut v = vel.get(i);
                    if !(v[0].is_finite() && v[1].is_finite() && v[2].is_finite()) {
                        bad.get_or_insert(i);
                        continue;
                    }
                    if free {
                        let d = fixed.displacement([v[0] * tau, v[1] * tau, v[2] * tau]);
                        xs[k] = xs[k].wrapping_add(d[0]);
                        ys[k] = ys[k].wrapping_add(d[1]);
                        zs[k] = zs[k].wrapping_add(d[2]);
                        continue;
                    }
                    let mut x = fixed.decode([xs[k], ys[k], zs[k]]);
                    let dv = accel.kick(x, v, tau);
                    for c in 0..3 {
                        v[c] += 0.5 * dv[c];
                    }
                    let b = conf.stream(&mut x, &mut v, t1, tau);
                    for c in 0..3 {
                        v[c] += 0.5 * dv[c];
                    }
                    if b.count > 0 {
                        bounced += 1;
                        refl += b.count as u64;
                        stuck += b.stuck as u64;
                        list.push(i as u32);
                    }
                    if !(v[0].is_finite() && v[1].is_finite() && v[2].is_finite()) {
                        bad.get_or_insert(i);
                    }
                    vel.set(i, v);
                    [xs[k], ys[k], zs[k]] = fixed.encode(x);
                }
                if let Some((s, nz, layers)) = &own {
                    for (k, &z) in zs.iter().enumerate() {
                        let layer = ((z.wrapping_sub(*s) as u64 * nz) >> 32) as usize;
                        if !layers.contains(&layer) {
                            leavers.push((ci * STREAM_CHUNK + k) as u32);
                        }
                    }
                }
                (bounced, refl, stuck, bad)
            })
            .collect();
        let mut s = StreamStats::default();
        for (b, r, st, bad) in stats {
            if let Some(i) = bad {
                return Err(MpcdError::NonFinite {
                    step: self.step,
                    what: "solvent",
                    index: i,
                });
            }
            s.bounced += b;
            s.reflections += r;
            s.stuck += st;
        }
        self.timers[0] += clock.elapsed().as_secs_f64();
        Ok(s)
    }

    /// Collide only the cells of layers `z0..z1` along z (a rank's domain, [`super::ranks`]);
    /// every particle must then lie in those layers of the shifted grid when it collides.
    pub(crate) fn own_layers(&mut self, z0: usize, z1: usize) {
        let layer = self.grid.n[0] * self.grid.n[1];
        self.owned = z0 * layer..z1 * layer;
        self.count = (0..self.owned.len()).map(|_| AtomicU32::new(0)).collect();
        self.start = vec![0; self.owned.len() + 1];
    }

    /// The layer along z of slot `i` on the grid shifted by `s` (fixed point).
    #[inline]
    pub(crate) fn layer_of(&self, i: usize, s: [u32; 3]) -> usize {
        ((self.pos[2][i].wrapping_sub(s[2]) as u64 * self.grid.n[2] as u64) >> 32) as usize
    }

    /// The grid shift of collision `step` in fixed point.
    pub(crate) fn fixed_shift(&self, step: u64) -> [u32; 3] {
        self.raw_shift(step)
    }

    /// Append a particle (fixed-point position, velocity).
    pub(crate) fn push(&mut self, x: [u32; 3], v: [f64; 3]) {
        for (k, c) in self.pos.iter_mut().enumerate() {
            c.push(x[k]);
        }
        for (k, c) in self.vel.0.iter_mut().enumerate() {
            c.push(AtomicU64::new(v[k].to_bits()));
        }
        self.order.push(AtomicU32::new(0));
        self.rank.push(0);
    }

    /// Slots of the particles reflected in the last streaming step, in increasing order.
    pub fn bounced(&self) -> impl Iterator<Item = u32> + '_ {
        self.bounced.iter().flatten().copied()
    }

    /// Remove the particles in `slots` (distinct; any order): from the highest slot down, each
    /// is replaced by the last particle of the arrays (a deterministic rule; the storage order
    /// is part of the state).
    pub fn remove(&mut self, slots: &mut [u32]) {
        slots.sort_unstable();
        for &s in slots.iter().rev() {
            let s = s as usize;
            for c in &mut self.pos {
                c.swap_remove(s);
            }
            self.vel.swap_remove(s);
        }
        let n = self.len();
        self.order.truncate(n);
        self.rank.truncate(n);
        for b in &mut self.bounced {
            b.clear();
        }
    }

    /// Sort the solvent and the embedded particles into the cells of the grid shifted by `s`:
    /// count the members of each cell (each particle keeps its rank in the count), then write
    /// the slots cell by cell.
    fn bin(&mut self, s: [u32; 3], emb_pos: &[[f64; 3]]) {
        let grid = self.grid;
        let c0 = self.owned.start;
        let cells = self.owned.len();
        let n = self.len();
        let [px, py, pz] = &self.pos;
        let count = &self.count;
        count
            .par_iter()
            .with_min_len(4096)
            .for_each(|c| c.store(0, Relaxed));
        let crowded = AtomicU32::new(0);
        self.rank
            .par_iter_mut()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(i, r)| {
                let c = grid.cell([px[i], py[i], pz[i]], s) - c0;
                let k = count[c].fetch_add(1, Relaxed);
                *r = k as u16;
                if k > u16::MAX as u32 {
                    crowded.store(1, Relaxed);
                }
            });
        self.start[0] = 0;
        for c in 0..cells {
            self.start[c + 1] = self.start[c] + self.count[c].load(Relaxed);
        }
        let (start, rank, order) = (&self.start, &self.rank, &self.order);
        if crowded.load(Relaxed) == 0 {
            (0..n).into_par_iter().with_min_len(4096).for_each(|i| {
                let c = grid.cell([px[i], py[i], pz[i]], s) - c0;
                order[(start[c] + rank[i] as u32) as usize].store(i as u32, Relaxed);
            });
        } else {
            // A cell with more than 65536 members: ranks do not fit, fill by cursors.
            count
                .par_iter()
                .enumerate()
                .for_each(|(c, f)| f.store(start[c], Relaxed));
            (0..n).into_par_iter().with_min_len(4096).for_each(|i| {
                let c = grid.cell([px[i], py[i], pz[i]], s) - c0;
                let slot = count[c].fetch_add(1, Relaxed);
                order[slot as usize].store(i as u32, Relaxed);
            });
        }
        let fixed = self.fixed;
        self.emb.clear();
        let owned = self.owned.clone();
        self.emb.extend(
            emb_pos
                .iter()
                .enumerate()
                .map(|(j, x)| (grid.cell(fixed.encode(*x), s) as u32, j as u32))
                .filter(|&(c, _)| owned.contains(&(c as usize))),
        );
        self.emb.sort_unstable();
    }

    /// Permute positions and velocities into cell order, members of a cell by increasing slot
    /// (the cell list then becomes the identity): one component at a time, gathered through the
    /// cell list into the scratch array, which then takes its place.
    fn sort_storage(&mut self) {
        let n = self.len();
        let (start, order) = (&self.start, &self.order);
        // The members of each cell in increasing slot order (the fill order is the threads').
        (0..self.owned.len())
            .into_par_iter()
            .with_min_len(1024)
            .for_each(|c| {
                let cell = &order[start[c] as usize..start[c + 1] as usize];
                for i in 1..cell.len() {
                    let x = cell[i].load(Relaxed);
                    let mut j = i;
                    while j > 0 && cell[j - 1].load(Relaxed) > x {
                        cell[j].store(cell[j - 1].load(Relaxed), Relaxed);
                        j -= 1;
                    }
                    cell[j].store(x, Relaxed);
                }
            });
        self.scratch_pos.resize(n, 0);
        for k in 0..3 {
            let src = &self.pos[k];
            self.scratch_pos
                .par_iter_mut()
                .zip(order.par_iter())
                .with_min_len(4096)
                .for_each(|(d, o)| *d = src[o.load(Relaxed) as usize]);
            std::mem::swap(&mut self.pos[k], &mut self.scratch_pos);
        }
        self.scratch_vel.resize_with(n, || AtomicU64::new(0));
        self.scratch_vel.truncate(n);
        for k in 0..3 {
            let src = &self.vel.0[k];
            self.scratch_vel
                .par_iter_mut()
                .zip(order.par_iter())
                .with_min_len(4096)
                .for_each(|(d, o)| *d.get_mut() = src[o.load(Relaxed) as usize].load(Relaxed));
            std::mem::swap(&mut self.vel.0[k], &mut self.scratch_vel);
        }
        self.order
            .par_iter_mut()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(k, o)| *o.get_mut() = k as u32);
    }

    /// One collision at time `t` (the end of the last streaming step) on the grid shifted for
    /// this step, with the embedded particles `emb` and, in the cells cut by the walls of
    /// `conf`, virtual particles. Advances the step counter.
    pub fn collide(
        &mut self,
        t: f64,
        conf: &Confinement,
        emb: Option<Embedded<'_>>,
    ) -> CollisionStats {
        let s = self.raw_shift(self.step);
        let shift = self.shift(self.step);
        let no_pos: [[f64; 3]; 0] = [];
        let emb_pos: &[[f64; 3]] = emb.as_ref().map_or(&no_pos, |e| e.pos);
        let clock = std::time::Instant::now();
        self.bin(s, emb_pos);
        self.timers[1] += clock.elapsed().as_secs_f64();
        if self.sort_every > 0 && self.step.is_multiple_of(self.sort_every) {
            let clock = std::time::Instant::now();
            self.sort_storage();
            self.timers[2] += clock.elapsed().as_secs_f64();
        }
        let clock = std::time::Instant::now();
        if let Some(e) = &emb {
            self.emb_vel.assign(e.vel);
            self.emb_mass.clear();
            self.emb_mass.extend_from_slice(e.mass);
        } else {
            self.emb_vel.assign(&[]);
            self.emb_mass.clear();
        }
        let p = &self.params;
        let rule = Rule {
            cos: p.angle.cos(),
            sin: p.angle.sin(),
            kt: p.kt,
            mass: p.mass,
            density: p.density,
            a: p.cell,
            thermostat: p.thermostat,
            gamma: gamma_table(),
        };
        let (seed, step) = (p.seed, self.step);
        let grid = self.grid;
        // Whole rows of cells along x: one random stream each, several per task.
        let row = grid.n[0];
        let (first_row, rows) = (self.owned.start / row, self.owned.len() / row);
        let rows_per_task = CELL_CHUNK.div_ceil(row);
        let (start, order, vel) = (&self.start, &self.order, &self.vel);
        let (emb_list, emb_vel, emb_mass) = (&self.emb, &self.emb_vel, &self.emb_mass);
        let conf = *conf;
        let walls = !matches!(conf, Confinement::None);
        let totals: Vec<(u64, u64)> = (0..rows.div_ceil(rows_per_task))
            .into_par_iter()
            .map(|task| {
                let r0 = first_row + task * rows_per_task;
                let r1 = (r0 + rows_per_task).min(first_row + rows);
                let mut e = emb_list.partition_point(|&(c, _)| (c as usize) < r0 * row);
                let (mut occupied, mut virt) = (0u64, 0u64);
                let zig = Ziggurat::get();
                let mut buf = Buffers::new();
                for r in r0..r1 {
                    let mut rng = draw(seed, step, Draw::Cell, r as u64);
                    for c in r * row..(r + 1) * row {
                        let l = c - first_row * row;
                        let (a, b) = (start[l] as usize, start[l + 1] as usize);
                        let e0 = e;
                        while e < emb_list.len() && emb_list[e].0 as usize == c {
                            e += 1;
                        }
                        if a == b && e0 == e {
                            continue;
                        }
                        occupied += 1;
                        let members = Members {
                            solvent: &order[a..b],
                            embedded: &emb_list[e0..e],
                        };
                        let lo = grid.corner(c, shift);
                        let cut_corner = (walls && cut(&conf, lo, grid.a, t)).then_some(lo);
                        virt += collide_cell(
                            &members, vel, emb_vel, emb_mass, &rule, &conf, cut_corner, t, zig,
                            &mut rng, &mut buf,
                        ) as u64;
                    }
                }
                (occupied, virt)
            })
            .collect();
        if let Some(e) = emb {
            for (j, v) in e.vel.iter_mut().enumerate() {
                *v = self.emb_vel.get(j);
            }
            // Decomposed: each embedded particle collided on the rank that owns its cell;
            // every rank takes the new velocities from there.
            self.share_embedded(e.vel);
        }
        self.timers[3] += clock.elapsed().as_secs_f64();
        self.step += 1;
        let mut st = CollisionStats::default();
        for (o, v) in totals {
            st.occupied_cells += o;
            st.virtual_particles += v;
        }
        // Decomposed: the counts of all ranks (collective).
        let t = self.add_over_ranks([st.occupied_cells, st.virtual_particles]);
        st.occupied_cells = t[0];
        st.virtual_particles = t[1];
        st
    }

    /// Sums over all particles of `f(position, velocity)`, exact in any order ([`ExactTotal`]):
    /// the same bits on any number of threads and, decomposed, over all ranks (collective).
    pub fn sum<const K: usize>(
        &self,
        f: impl Fn([f64; 3], [f64; 3]) -> [f64; K] + Sync,
    ) -> [f64; K] {
        let view = self.view();
        let parts: Vec<[ExactTotal; K]> = (0..view.len().div_ceil(STREAM_CHUNK))
            .into_par_iter()
            .map(|ci| {
                let mut acc = [ExactTotal::default(); K];
                let end = ((ci + 1) * STREAM_CHUNK).min(view.len());
                for i in ci * STREAM_CHUNK..end {
                    let r = f(view.position(i), view.velocity(i));
                    for d in 0..K {
                        acc[d].add(r[d]);
                    }
                }
                acc
            })
            .collect();
        let mut acc = [ExactTotal::default(); K];
        for p in parts {
            for d in 0..K {
                acc[d].merge(p[d]);
            }
        }
        self.merge_over_ranks(&mut acc);
        acc.map(ExactTotal::value)
    }

    /// Rescale the velocities relative to the flow field `flow(x)` by one factor so that their
    /// kinetic temperature `sum m |v - flow(x)|^2 / (3 (N - 1))` becomes `kT` (a global,
    /// profile-unbiased thermostat, for measurements without the cell thermostat: it removes
    /// the viscous heat of a driven flow without acting on the cells' relative velocities).
    pub fn rescale_about(&mut self, flow: impl Fn([f64; 3]) -> [f64; 3] + Sync) {
        let n = self.particles();
        if n < 2 {
            return;
        }
        let m = self.params.mass;
        let twice = self.sum(|x, v| {
            let f = flow(x);
            let w = [v[0] - f[0], v[1] - f[1], v[2] - f[2]];
            [m * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2])]
        })[0];
        if twice <= 0.0 {
            return;
        }
        let scale = (3.0 * (n - 1) as f64 * self.params.kt / twice).sqrt();
        let view = self.view();
        (0..view.len())
            .into_par_iter()
            .with_min_len(4096)
            .for_each(|i| {
                let (x, v) = (view.position(i), view.velocity(i));
                let f = flow(x);
                view.vel
                    .set(i, std::array::from_fn(|k| f[k] + scale * (v[k] - f[k])));
            });
    }

    /// Total momentum of the solvent.
    pub fn momentum(&self) -> [f64; 3] {
        let m = self.params.mass;
        self.sum(|_, v| [m * v[0], m * v[1], m * v[2]])
    }

    /// Kinetic energy of the solvent.
    pub fn kinetic_energy(&self) -> f64 {
        let m = self.params.mass;
        self.sum(|_, v| [0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])])[0]
    }

    /// Kinetic temperature `sum m |v - V|^2 / (3 (N - 1))` relative to the mean velocity `V`.
    pub fn temperature(&self) -> f64 {
        let n = self.particles() as f64;
        if n < 2.0 {
            return f64::NAN;
        }
        let p = self.momentum();
        let m = self.params.mass;
        let ke = self.kinetic_energy();
        let pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        (2.0 * ke - pp / (n * m)) / (3.0 * (n - 1.0))
    }
}

/// Per-task buffers of the cell collisions (zeroed once per task, not per cell).
struct Buffers {
    slots: [u32; CELL_CAPACITY],
    v: [[f64; 3]; CELL_CAPACITY],
    m: [f64; CELL_CAPACITY],
}

impl Buffers {
    fn new() -> Self {
        Self {
            slots: [0; CELL_CAPACITY],
            v: [[0.0; 3]; CELL_CAPACITY],
            m: [0.0; CELL_CAPACITY],
        }
    }
}

/// Every parameter at its edge; the message names the key and its allowed range.
fn check_params(p: &SrdParams) -> Result<(), MpcdError> {
    for (key, v) in [
        ("cell", p.cell),
        ("density", p.density),
        ("tau", p.tau),
        ("kT", p.kt),
        ("mass", p.mass),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(MpcdError::Invalid(format!(
                "solvent {key} = {v} must be a finite number > 0"
            )));
        }
    }
    if !(p.angle > 0.0 && p.angle <= std::f64::consts::PI) {
        return Err(MpcdError::Invalid(format!(
            "solvent angle = {} degrees must lie in (0, 180]",
            p.angle.to_degrees()
        )));
    }
    Ok(())
}

/// The members of one cell: solvent slots (from the cell list, any order) and embedded
/// particles ((cell, index), sorted).
struct Members<'a> {
    solvent: &'a [AtomicU32],
    embedded: &'a [(u32, u32)],
}

/// Collide the members of one cell (plus virtual particles when `cut_corner` is the lower
/// corner of a cell cut by a wall); returns the number of virtual particles.
#[allow(clippy::too_many_arguments)]
#[inline]
fn collide_cell(
    members: &Members<'_>,
    vel: &SharedVectors,
    emb_vel: &SharedVectors,
    emb_mass: &[f64],
    rule: &Rule,
    conf: &Confinement,
    cut_corner: Option<[f64; 3]>,
    t: f64,
    zig: &Ziggurat,
    rng: &mut impl Rng,
    buf: &mut Buffers,
) -> usize {
    let ns = members.solvent.len();
    let ne = members.embedded.len();
    let nv_max = if cut_corner.is_some() {
        rule.density.ceil() as usize + 1
    } else {
        0
    };
    let total = ns + ne + nv_max;
    if total <= CELL_CAPACITY {
        collide_in(
            members,
            vel,
            emb_vel,
            emb_mass,
            rule,
            conf,
            cut_corner,
            t,
            zig,
            rng,
            &mut buf.slots,
            &mut buf.v,
            &mut buf.m,
        )
    } else {
        let mut slots = vec![0u32; total];
        let mut v = vec![[0.0f64; 3]; total];
        let mut m = vec![0.0f64; total];
        collide_in(
            members, vel, emb_vel, emb_mass, rule, conf, cut_corner, t, zig, rng, &mut slots,
            &mut v, &mut m,
        )
    }
}

/// [`collide_cell`] with buffers of at least the members' size.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn collide_in(
    members: &Members<'_>,
    vel: &SharedVectors,
    emb_vel: &SharedVectors,
    emb_mass: &[f64],
    rule: &Rule,
    conf: &Confinement,
    cut_corner: Option<[f64; 3]>,
    t: f64,
    zig: &Ziggurat,
    rng: &mut impl Rng,
    slots: &mut [u32],
    v: &mut [[f64; 3]],
    m: &mut [f64],
) -> usize {
    let ns = members.solvent.len();
    let ne = members.embedded.len();
    // The solvent members in the order the threads filled the cell list: their sums are exact,
    // so the order does not matter.
    for (s, o) in slots.iter_mut().zip(members.solvent) {
        *s = o.load(Relaxed);
    }
    let slots = &slots[..ns];
    let mut sum_v = [ExactSum::default(); 3];
    for (k, &s) in slots.iter().enumerate() {
        let x = vel.get(s as usize);
        v[k] = x;
        m[k] = rule.mass;
        for d in 0..3 {
            sum_v[d].add(x[d]);
        }
    }
    let mut mass = rule.mass * ns as f64;
    let mut p = sum_v.map(|x| rule.mass * x.value());
    for (k, &(_, j)) in members.embedded.iter().enumerate() {
        let x = emb_vel.get(j as usize);
        let mj = emb_mass[j as usize];
        v[ns + k] = x;
        m[ns + k] = mj;
        mass += mj;
        for d in 0..3 {
            p[d] += mj * x[d];
        }
    }
    let keep = ns + ne;
    let mut n = keep;
    // Virtual particles fill the part of a cut cell beyond the wall at the solvent density:
    // floor(M) or floor(M) + 1 candidates (mean M) uniform in the cell, those beyond the wall
    // kept, with Maxwell–Boltzmann velocities at kT about the wall velocity, for slip and
    // no-slip alike: a bath at rest relative to the wall. (Drawing them about the real
    // members' mean velocity instead copies that mean's fluctuation into the fill, heats the
    // cut cells and pushes the solvent away from the wall: next to a static wall 5 % below the
    // mean density with the cell thermostat, 18 % without; docs/mpcd.md.)
    let mut nv = 0;
    if let Some(lo) = cut_corner {
        let whole = rule.density.floor();
        let extra: f64 = rng.random();
        let candidates = whole as usize + (extra < rule.density - whole) as usize;
        let sd = (rule.kt / rule.mass).sqrt();
        for _ in 0..candidates {
            let u: [f64; 3] = [rng.random(), rng.random(), rng.random()];
            let x = [
                lo[0] + u[0] * rule.a,
                lo[1] + u[1] * rule.a,
                lo[2] + u[2] * rule.a,
            ];
            if conf.inside(x, t) {
                continue;
            }
            let mean = wall_velocity(conf, x, t);
            let mut w = [0.0; 3];
            for d in 0..3 {
                w[d] = mean[d] + sd * zig.sample(rng);
                p[d] += rule.mass * w[d];
            }
            v[n] = w;
            m[n] = rule.mass;
            mass += rule.mass;
            n += 1;
            nv += 1;
        }
    }
    if n < 2 {
        return nv;
    }
    let u = [p[0] / mass, p[1] / mass, p[2] / mass];
    let rot = rotation(unit_vector(rng), rule.cos, rule.sin);
    let mut scale = 1.0;
    if rule.thermostat {
        // The solvent's part exactly (order-free), then the embedded and virtual members'.
        let mut solvent = ExactSum::default();
        for w in &v[..ns] {
            let w = [w[0] - u[0], w[1] - u[1], w[2] - u[2]];
            solvent.add(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        }
        let mut twice_e = rule.mass * solvent.value();
        for k in ns..n {
            let w = [v[k][0] - u[0], v[k][1] - u[1], v[k][2] - u[2]];
            twice_e += m[k] * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        }
        if twice_e > 0.0 {
            // E' ~ Gamma(3 (n - 1) / 2, kT).
            let [d, c] = if n <= CELL_CAPACITY {
                rule.gamma[n]
            } else {
                let d = 1.5 * (n - 1) as f64 - 1.0 / 3.0;
                [d, 1.0 / (9.0 * d).sqrt()]
            };
            let target = rule.kt * gamma(d, c, zig, rng);
            scale = (2.0 * target / twice_e).sqrt();
        }
    }
    for k in 0..keep {
        let w = [v[k][0] - u[0], v[k][1] - u[1], v[k][2] - u[2]];
        let r = [
            rot[0][0] * w[0] + rot[0][1] * w[1] + rot[0][2] * w[2],
            rot[1][0] * w[0] + rot[1][1] * w[1] + rot[1][2] * w[2],
            rot[2][0] * w[0] + rot[2][1] * w[1] + rot[2][2] * w[2],
        ];
        let out = [
            u[0] + scale * r[0],
            u[1] + scale * r[1],
            u[2] + scale * r[2],
        ];
        if k < ns {
            vel.set(slots[k] as usize, out);
        } else {
            emb_vel.set(members.embedded[k - ns].1 as usize, out);
        }
    }
    nv
}

/// The rotation by angle `alpha` (given by its cosine and sine) about the unit axis `n`:
/// `R = cos I + sin [n]_x + (1 - cos) n n^T` (Rodrigues).
#[inline(always)]
pub fn rotation(n: [f64; 3], cos: f64, sin: f64) -> [[f64; 3]; 3] {
    let c1 = 1.0 - cos;
    [
        [
            cos + c1 * n[0] * n[0],
            c1 * n[0] * n[1] - sin * n[2],
            c1 * n[0] * n[2] + sin * n[1],
        ],
        [
            c1 * n[1] * n[0] + sin * n[2],
            cos + c1 * n[1] * n[1],
            c1 * n[1] * n[2] - sin * n[0],
        ],
        [
            c1 * n[2] * n[0] - sin * n[1],
            c1 * n[2] * n[1] + sin * n[0],
            cos + c1 * n[2] * n[2],
        ],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mpcd::WallKind;
    use crate::potential::SphereAreaLaw;

    /// `steps` streaming steps and collisions of `srd` (no walls unless `conf`).
    fn run(srd: &mut Srd, steps: u64, conf: &Confinement, accel: &Acceleration) {
        for _ in 0..steps {
            let t = (srd.step() + 1) as f64 * srd.params().tau;
            srd.stream(t, conf, accel).unwrap();
            srd.collide(t, conf, None);
        }
    }

    /// Velocities uniform in `[-c, c)` per component plus `drift` (not Maxwell–Boltzmann:
    /// kurtosis 9/5), positions uniform.
    fn uniform_solvent(p: SrdParams, l: f64, c: f64, drift: [f64; 3]) -> Srd {
        let n = (p.density * l * l * l) as usize;
        let mut rng = draw(p.seed, 0, Draw::Solvent, 1 << 40);
        let pos: Vec<[f64; 3]> = (0..n)
            .map(|_| std::array::from_fn(|_| (rng.random::<f64>() - 0.5) * l))
            .collect();
        let mut vel: Vec<[f64; 3]> = (0..n)
            .map(|_| std::array::from_fn(|_| c * (2.0 * rng.random::<f64>() - 1.0)))
            .collect();
        // Remove the sample mean, then add the drift.
        let mean: [f64; 3] =
            std::array::from_fn(|k| vel.iter().map(|v| v[k]).sum::<f64>() / n as f64);
        for v in &mut vel {
            for k in 0..3 {
                v[k] += drift[k] - mean[k];
            }
        }
        Srd::from_state(p, SimBox::cube(l), &pos, &vel, 0).unwrap()
    }

    /// Mean, variance and kurtosis of the velocity components about their means.
    fn moments(srd: &Srd) -> ([f64; 3], f64, f64) {
        let v = srd.velocities();
        let n = v.len() as f64;
        let mean: [f64; 3] = std::array::from_fn(|k| v.iter().map(|x| x[k]).sum::<f64>() / n);
        let (mut m2, mut m4) = (0.0, 0.0);
        for x in &v {
            for k in 0..3 {
                let d = x[k] - mean[k];
                m2 += d * d;
                m4 += d * d * d * d;
            }
        }
        let (m2, m4) = (m2 / (3.0 * n), m4 / (3.0 * n));
        (mean, m2, m4 / (m2 * m2))
    }

    #[test]
    fn parameters_out_of_range_are_rejected_naming_the_key_and_range() {
        let ok = SrdParams::standard(1);
        let sbox = SimBox::cube(4.0);
        let bad = |f: &dyn Fn(&mut SrdParams)| {
            let mut p = ok;
            f(&mut p);
            Srd::new(p, sbox, &Confinement::None, 0.0)
                .unwrap_err()
                .to_string()
        };
        for (key, set) in [
            (
                "density",
                &(|p: &mut SrdParams| p.density = 0.0) as &dyn Fn(&mut SrdParams),
            ),
            ("density", &|p: &mut SrdParams| p.density = -5.0),
            ("density", &|p: &mut SrdParams| p.density = f64::NAN),
            ("tau", &|p: &mut SrdParams| p.tau = 0.0),
            ("tau", &|p: &mut SrdParams| p.tau = f64::INFINITY),
            ("kT", &|p: &mut SrdParams| p.kt = -1.0),
            ("mass", &|p: &mut SrdParams| p.mass = 0.0),
            ("cell", &|p: &mut SrdParams| p.cell = f64::NAN),
        ] {
            let msg = bad(set);
            assert!(
                msg.contains(&format!("solvent {key} = ")) && msg.contains("> 0"),
                "{msg}"
            );
        }
        for angle in [0.0, -10.0, 180.001, f64::NAN] {
            let msg = bad(&|p: &mut SrdParams| p.angle = angle.to_radians());
            assert!(
                msg.contains("solvent angle = ") && msg.contains("(0, 180]"),
                "{msg}"
            );
        }
        // The edges of the range are accepted.
        let mut p = ok;
        p.angle = std::f64::consts::PI;
        assert!(Srd::new(p, sbox, &Confinement::None, 0.0).is_ok());
        p.angle = 1e-6;
        assert!(Srd::new(p, sbox, &Confinement::None, 0.0).is_ok());
        // A box that is not a whole number of cells.
        let msg = Srd::new(ok, SimBox::cube(4.5), &Confinement::None, 0.0)
            .unwrap_err()
            .to_string();
        assert!(msg.contains("whole number") && msg.contains("4.5"), "{msg}");
    }

    /// Every position lies in the shifted cell that `cell_of` names, and the shifts of
    /// successive collisions cover `[-a/2, a/2)` uniformly.
    #[test]
    fn the_shifted_grid_puts_each_particle_in_its_cell() {
        let mut p = SrdParams::standard(3);
        p.cell = 0.5;
        let srd = Srd::new(p, SimBox::new([4.0, 3.0, 5.0]), &Confinement::None, 0.0).unwrap();
        let grid = *srd.grid();
        assert_eq!(grid.n, [8, 6, 10]);
        let mut mean = [0.0; 3];
        let steps = 2000;
        for step in 0..steps {
            let s = srd.shift(step);
            for k in 0..3 {
                assert!(s[k] >= -0.25 && s[k] < 0.25, "{s:?}");
                mean[k] += s[k] / steps as f64;
            }
            if step < 20 {
                for i in 0..srd.len() {
                    let x = srd.position(i);
                    let lo = grid.corner(srd.cell_of(x, step), s);
                    for k in 0..3 {
                        // The offset from the corner, wrapped into [0, L).
                        let d = (x[k] - lo[k]).rem_euclid(grid.l[k]);
                        assert!(d < p.cell * (1.0 + 1e-9), "{x:?} {lo:?} {k}");
                    }
                }
            }
        }
        // Uniform on [-a/2, a/2): mean 0 with standard error a / sqrt(12 steps) = 3.2e-3.
        for m in mean {
            assert!(m.abs() < 0.013, "{mean:?}");
        }
    }

    /// Without the thermostat a collision conserves momentum and energy exactly: after many
    /// steps both agree with the start to round-off, while the velocities have decorrelated.
    #[test]
    fn collisions_conserve_momentum_and_energy_without_the_thermostat() {
        let mut p = SrdParams::standard(11);
        p.thermostat = false;
        let mut srd = uniform_solvent(p, 8.0, 1.7, [0.3, -0.2, 0.1]);
        let v0 = srd.velocities();
        let (p0, e0) = (srd.momentum(), srd.kinetic_energy());
        run(&mut srd, 45, &Confinement::None, &Acceleration::None);
        let (p1, e1) = (srd.momentum(), srd.kinetic_energy());
        for k in 0..3 {
            // |P| ~ 800; round-off ~1e-16 per particle and collision.
            assert!((p1[k] - p0[k]).abs() < 1e-10, "{p0:?} {p1:?}");
        }
        assert!((e1 / e0 - 1.0).abs() < 1e-12, "{e0} {e1}");
        // The collisions did act: the velocity of a particle has forgotten its start (the
        // storage sorts permute the slots, so compare the distributions' kurtosis instead of
        // slot by slot): uniform 1.8 relaxes to Gaussian 3.
        let k0 = {
            let s = Srd::from_state(p, *srd.sbox(), &srd.positions(), &v0, 0).unwrap();
            moments(&s).2
        };
        let (_, _, k1) = moments(&srd);
        assert!((k0 - 1.8).abs() < 0.05, "{k0}");
        // Standard error of the kurtosis of 3 N Gaussian samples: sqrt(24 / 3N) = 0.032.
        assert!((k1 - 3.0).abs() < 0.15, "{k1}");
    }

    /// The cell thermostat brings velocities that start uniform at kT = 2 to the
    /// Maxwell–Boltzmann distribution at kT = 1: the temperature within its statistical error,
    /// the kurtosis 3, and a chi-square test of the histogram of the components against the
    /// normal distribution.
    #[test]
    fn the_thermostat_gives_maxwell_boltzmann_velocities_at_kt() {
        let mut p = SrdParams::standard(5);
        p.kt = 1.0;
        // Uniform in [-c, c): variance c^2 / 3 = 2.
        let mut srd = uniform_solvent(p, 12.0, 6f64.sqrt(), [0.0; 3]);
        run(&mut srd, 30, &Confinement::None, &Acceleration::None);
        let n = srd.len() as f64;
        let t = srd.temperature();
        // Standard error of the kinetic temperature of N particles: kT sqrt(2 / (3 N)) = 0.0088.
        let se = (2.0 / (3.0 * n)).sqrt();
        assert!((t - 1.0).abs() < 4.0 * se, "T = {t} (se {se})");
        let (mean, var, kurt) = moments(&srd);
        assert!((var - 1.0).abs() < 4.0 * se, "{var}");
        for m in mean {
            // The start has no mean velocity and the thermostat keeps the cells' momenta.
            assert!(m.abs() < 1e-10, "{mean:?}");
        }
        assert!((kurt - 3.0).abs() < 0.12, "kurtosis {kurt}");
        // 24 bins equally probable under N(0, kT/m), chi-square with 23 degrees of freedom:
        // 49.7 is its 0.1 % point.
        let bins = 24;
        let edges: Vec<f64> = (1..bins)
            .map(|j| inverse_normal_cdf(j as f64 / bins as f64))
            .collect();
        let mut counts = vec![0f64; bins];
        for v in srd.velocities() {
            for c in v {
                counts[edges.partition_point(|&e| e < c)] += 1.0;
            }
        }
        let expect = 3.0 * n / bins as f64;
        let chi2: f64 = counts.iter().map(|c| (c - expect).powi(2) / expect).sum();
        assert!(chi2 < 49.7, "chi2 = {chi2}, {counts:?}");
    }

    /// The standard normal quantile by bisection on `erfc` (tests only).
    fn inverse_normal_cdf(q: f64) -> f64 {
        let cdf = |x: f64| 0.5 * erfc(-x / std::f64::consts::SQRT_2);
        let (mut lo, mut hi) = (-10.0, 10.0);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if cdf(mid) < q { lo = mid } else { hi = mid }
        }
        0.5 * (lo + hi)
    }

    /// `erfc` to 1.2e-7 (Numerical Recipes' Chebyshev fit; tests only).
    fn erfc(x: f64) -> f64 {
        let z = x.abs();
        let t = 1.0 / (1.0 + 0.5 * z);
        let r = t
            * (-z * z - 1.26551223
                + t * (1.00002368
                    + t * (0.37409196
                        + t * (0.09678418
                            + t * (-0.18628806
                                + t * (0.27886807
                                    + t * (-1.13520398
                                        + t * (1.48851587
                                            + t * (-0.82215223 + t * 0.17087277)))))))))
                .exp();
        if x >= 0.0 { r } else { 2.0 - r }
    }

    /// The same run on 1 and on 2 threads gives the same bits: bulk with the cosine drive and
    /// storage sorts, and between no-slip walls with embedded particles and virtual particles.
    #[test]
    fn exact_totals_travel_as_words_and_do_not_depend_on_the_order() {
        let terms = [1.5e6, -3.25, 7.0e-9, -1.0e6, 2.0f64.powi(29), -0.1, 0.3];
        let mut a = ExactTotal::default();
        for x in terms {
            a.add(x);
        }
        let mut b = ExactTotal::default();
        for x in terms.iter().rev() {
            b.add(*x);
        }
        assert_eq!(a, b);
        for t in [a, ExactTotal::default()] {
            assert_eq!(ExactTotal::from_words(&t.words()), t);
        }
        let mut neg = ExactTotal::default();
        neg.add(-5.0e8);
        neg.add(-5.0e8);
        assert_eq!(ExactTotal::from_words(&neg.words()), neg);
        assert_eq!(neg.value(), -1.0e9);
        // Two halves merge to the whole, in either order.
        let (mut h1, mut h2) = (ExactTotal::default(), ExactTotal::default());
        terms[..3].iter().for_each(|x| h1.add(*x));
        terms[3..].iter().for_each(|x| h2.add(*x));
        h2.merge(h1);
        assert_eq!(h2, a);
        a.add(f64::NAN);
        assert!(a.value().is_nan() && ExactTotal::from_words(&a.words()).value().is_nan());
    }

    #[test]
    fn results_do_not_depend_on_the_thread_count() {
        let l = 16.0;
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let p = SrdParams::standard(21);
                    let mut bulk = Srd::new(p, SimBox::cube(l), &Confinement::None, 0.0).unwrap();
                    bulk.set_sort_every(4);
                    let accel = Acceleration::CosineX {
                        amplitude: 0.1,
                        wavenumber: 2.0 * std::f64::consts::PI / l,
                    };
                    run(&mut bulk, 9, &Confinement::None, &accel);
                    let slab = Confinement::Slab {
                        half_width: 6.3,
                        kind: WallKind::NoSlip,
                    };
                    let mut walled = Srd::new(p, SimBox::cube(l), &slab, 0.0).unwrap();
                    let emb_pos: Vec<[f64; 3]> = (0..50)
                        .map(|j| [0.3 * j as f64, -0.2 * j as f64, 0.1 * j as f64 - 2.5])
                        .collect();
                    let mut emb_vel = vec![[0.5, 0.0, -0.5]; 50];
                    let emb_mass = vec![5.0; 50];
                    let mut virt = 0;
                    for _ in 0..7 {
                        let t = (walled.step() + 1) as f64 * p.tau;
                        walled
                            .stream(t, &slab, &Acceleration::Uniform([0.1, 0.0, 0.0]))
                            .unwrap();
                        let emb = Embedded {
                            pos: &emb_pos,
                            vel: &mut emb_vel,
                            mass: &emb_mass,
                        };
                        virt += walled.collide(t, &slab, Some(emb)).virtual_particles;
                    }
                    assert!(virt > 0);
                    (
                        bulk.raw_positions(),
                        bulk.velocities(),
                        walled.raw_positions(),
                        walled.velocities(),
                        emb_vel,
                    )
                })
        };
        let (a, b) = (on(1), on(2));
        let bits =
            |v: &[[f64; 3]]| -> Vec<[u64; 3]> { v.iter().map(|x| x.map(f64::to_bits)).collect() };
        assert_eq!(a.0, b.0);
        assert_eq!(bits(&a.1), bits(&b.1));
        assert_eq!(a.2, b.2);
        assert_eq!(bits(&a.3), bits(&b.3));
        assert_eq!(bits(&a.4), bits(&b.4));
        // The collisions did change the embedded particles' velocities.
        assert_ne!(bits(&a.4), bits(&[[0.5, 0.0, -0.5]; 50]));
    }

    /// The solvent of a droplet fills the sphere only, at the density.
    #[test]
    fn a_droplet_solvent_fills_the_sphere() {
        let law = SphereAreaLaw {
            r0: 5.0,
            alpha: 0.0,
        };
        let conf = Confinement::Sphere {
            law,
            kind: WallKind::Slip,
        };
        let srd = Srd::new(SrdParams::standard(2), SimBox::cube(12.0), &conf, 0.0).unwrap();
        let expect = 5.0 * 4.0 / 3.0 * std::f64::consts::PI * 125.0;
        assert_eq!(srd.len(), expect.round() as usize);
        assert!(srd.positions().iter().all(|x| conf.inside(*x, 0.0)));
    }
}
