//! Free-draining Brownian dynamics (Euler–Maruyama or Leimkuhler–Matthews, [`Integrator`]).
//!
//! `x(t + dt) = x + F / gamma_i dt + sqrt(2 kT dt / gamma_i) xi`, with Stokes friction
//! `gamma_i = 3 pi eta d_i` from each particle's diameter; Leimkuhler–Matthews replaces `xi_n`
//! by `(xi_n + xi_{n+1}) / 2`.
//!
//! **Neighbours.** Particles are kept sorted by cell ([`crate::cells`]; cells at least the
//! largest cut-off plus the skin wide, z-major) and every pair within that range is stored once,
//! in a half Verlet list of the particle whose cell has the other in its half stencil. The
//! lists are rebuilt, with a re-sort, whenever a particle has moved more than half the skin
//! since the last build, and at every multiple of [`BdParams::sort_every`] steps. Positions are
//! wrapped into the box only at a build: in between they move continuously (at most half the
//! skin outside the box), so that a pair's separation is `x_i - x_j` (or `x_i - s - x_j` for
//! the pairs found across the periodic seam, with the shift `s` stored in the list) without a
//! minimum-image search per pair and step. Each z-layer of
//! cells (a *slab*) sums its pairs into its own force buffer, whose tail is a halo for the next
//! slab; a particle's pair force is its slab's sum plus the previous slab's halo, added in a
//! fixed order.
//!
//! **Determinism.** The noise of the particle in storage slot `k` at step `n` comes from the
//! counter-based stream keyed by (seed, n, replica, k / BLOCK), one keyed stream per block of
//! [`BLOCK`] slots. The storage order and the lists are functions of the positions at the last
//! build (ties in a cell broken by input index), so a run is a pure function of its inputs:
//! bitwise identical for any number of threads. A checkpoint that keeps the storage order and
//! the positions of the last build ([`ListState`]) restarts bitwise identically.
//! Leimkuhler–Matthews draws its deviates by particle instead (input index `i`: the stream
//! (seed, n, replica, i / BLOCK)), so that `xi_n` of every particle is a function of (seed,
//! n, i) alone and a restart draws it again rather than storing it.
//! [`Brownian::snapshot`] returns the particles in input order.
//!
//! One step is two parallel passes and nothing is allocated: the pair forces slab by slab, then
//! chunk by chunk the external force, the noise and the new positions (into a second buffer;
//! the buffers are then swapped). Leimkuhler–Matthews draws its deviates `xi_{n+1}` in a third
//! pass, by input index, before the positions.
//!
//! Beside the engine, this folder holds Brownian dynamics with hydrodynamic interactions
//! ([`hydrodynamic`]) and the two BD scenarios: the drying droplet ([`droplet`]) and the bulk
//! periodic box ([`bulk`]).

pub mod bulk;
pub mod droplet;
pub mod hydrodynamic;
pub mod lj_eos;
mod ranks;
mod scenario;

use crate::cells::{CellSort, permute, scan_layer};
use crate::domain::Domain;
pub use crate::gsd::ListState;
use crate::neighbor::BoxTooSmall;
use crate::potential::{External, Pair};
use crate::state::{Particles, SimBox};
use colloidsim_core::ParamError;
use colloidsim_core::rng::{BLOCK, Purpose, Ziggurat, stream};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Particles per parallel work item of the integration pass (a multiple of the noise block).
const CHUNK: usize = 4 * BLOCK;

/// How a step integrates the overdamped Langevin equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Euler–Maruyama, `x_{n+1} = x_n + F(x_n) dt / gamma + sqrt(2 kT dt / gamma) xi_n`:
    /// first order in dt for the stationary distribution.
    #[default]
    Euler,
    /// Leimkuhler–Matthews, `x_{n+1} = x_n + F(x_n) dt / gamma + sqrt(2 kT dt / gamma)
    /// (xi_n + xi_{n+1}) / 2` (Leimkuhler & Matthews, Appl. Math. Res. Express 2013;
    /// Leimkuhler, Matthews & Tretyakov, Proc. R. Soc. A 470, 20140120 (2014)): second order
    /// in dt for the stationary distribution, at one deviate per particle and step as Euler
    /// (`xi_{n+1}` is kept for the next step). Free displacements over `k` steps have variance
    /// `2 D dt (k - 1/2)` per axis: the MSD is low by a constant `D dt` per axis, its slope
    /// (the diffusion coefficient) is not.
    Lm,
}
impl Integrator {
    /// This integrator for a run with (`rpy`) or without RPY hydrodynamics: Leimkuhler–Matthews
    /// is refused with RPY (the noise is correlated through the mobility, which the scheme does
    /// not cover); the error names the parameter `integrator`.
    pub fn check(self, rpy: bool) -> Result<Self, ParamError> {
        if self == Integrator::Lm && rpy {
            return Err(ParamError::new(
                "integrator",
                "\"lm\" (Leimkuhler-Matthews) is for free draining only: with the RPY mobility \
                 (model \"rpy\") the noise is correlated through the mobility, which the scheme \
                 does not cover; use \"euler\" or free draining",
            ));
        }
        Ok(self)
    }
}

/// Parameters of the Brownian integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BdParams {
    /// Thermal energy kT.
    pub kt: f64,
    /// Solvent viscosity eta (friction `3 pi eta d`).
    pub viscosity: f64,
    /// Time step.
    pub dt: f64,
    /// Seed of the noise streams.
    pub seed: u32,
    /// Independent replica of the same seed: its noise streams are keyed by
    /// `replica * 2^32 + block`.
    pub replica: u32,
    /// Verlet skin.
    pub skin: f64,
    /// Also rebuild the neighbour lists (re-sorting the particles into cells) at every
    /// multiple of this many steps (0: only when a particle has moved half the skin).
    pub sort_every: u64,
    /// A step whose deterministic displacement `|F| dt / gamma` exceeds this fraction of the
    /// particle's diameter stops the run (the time step is too large for the potential).
    pub max_drift: f64,
    /// Euler–Maruyama or Leimkuhler–Matthews.
    pub integrator: Integrator,
}

impl BdParams {
    /// Defaults: kT = 1, eta = 1, skin 0.3, lists rebuilt at least every 500 steps, max_drift 0.2,
    /// Euler–Maruyama.
    pub fn new(dt: f64, seed: u32) -> Self {
        Self {
            kt: 1.0,
            viscosity: 1.0,
            dt,
            seed,
            replica: 0,
            skin: 0.3,
            sort_every: 500,
            max_drift: 0.2,
            integrator: Integrator::Euler,
        }
    }
}

/// Why a run stopped.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum BdError {
    /// The time step is too large for the forces.
    #[error(
        "blow-up at step {step} (t = {time}): particle {particle} at ({:.4}, {:.4}, {:.4}) would move {drift:.4} \
         (diameter {diameter}) in one step under a force {force:.4e}; the time step is too large for the WCA core — reduce `dt`",
        position[0], position[1], position[2]
    )]
    BlowUp {
        /// Step at which it happened.
        step: u64,
        /// Time.
        time: f64,
        /// Lowest-index offending particle.
        particle: usize,
        /// Its position.
        position: [f64; 3],
        /// Magnitude of the force.
        force: f64,
        /// Deterministic displacement it would cause.
        drift: f64,
        /// Its diameter.
        diameter: f64,
    },
    /// Box too small for the neighbour list.
    #[error(transparent)]
    BoxTooSmall(#[from] BoxTooSmall),
    /// Inconsistent particle data.
    #[error("invalid particle data: {0}")]
    Invalid(String),
}

/// One z-layer of cells: its particles, their half neighbour lists and force buffer.
#[derive(Debug, Clone, Default)]
struct Slab {
    start: usize,
    end: usize,
    /// Half list of the pairs `(i, j)` found from this slab's particles `i` within the box, in
    /// build order (one flat loop: no short inner loops whose exits mispredict).
    pairs: Vec<[u32; 2]>,
    /// Pairs found across the periodic seam, with the shift `s` (a box vector) of `x_i`.
    shifted: Vec<([u32; 2], [f64; 3])>,
    /// Candidate pairs of one particle (scratch of the list build).
    cand: Vec<(u32, [f64; 3])>,
    /// Pair forces on this slab's particles (`end - start` entries), then on the next slab's
    /// particles (the halo).
    acc: Vec<[f64; 3]>,
    /// First slot of the next slab (slab 0 after the last; a ghost layer in a domain).
    next_start: usize,
}

/// A Brownian dynamics simulation with pair potential `P` and external field `E`.
pub struct Brownian<P: Pair, E: External> {
    particles: Particles,
    tag: Vec<u32>,
    /// Periodic box.
    pub sbox: SimBox,
    /// Pair potential.
    pub pair: P,
    /// External field.
    pub external: E,
    params: BdParams,
    /// Current step (time = step * dt).
    pub step: u64,
    /// Neighbour range: largest cut-off plus skin (0 without pair forces).
    range: f64,
    grid: CellSort,
    slabs: Vec<Slab>,
    slab_of: Vec<u32>,
    ref_pos: Vec<[f64; 3]>,
    builds: u64,
    /// Largest squared displacement from the reference positions before a rebuild: half the
    /// skin squared, or a quarter of the shortest edge squared without pair forces (then a
    /// "rebuild" only wraps the positions).
    rebuild_disp2: f64,
    new_pos: Vec<[f64; 3]>,
    scratch_img: Vec<[i32; 3]>,
    /// Per particle: `dt / gamma` (drift per unit force), `sqrt(2 kT dt / gamma)` (noise
    /// amplitude) and the largest allowed squared drift `(max_drift d)^2`.
    kinetics: Vec<[f64; 3]>,
    scratch_f64: Vec<f64>,
    scratch_u32: Vec<u32>,
    scratch3: Vec<[f64; 3]>,
    /// Leimkuhler–Matthews: the deviates `xi_n` and `xi_{n+1}` of every particle, by input
    /// index (empty for Euler), and the step `n` whose deviates `lm_now` holds (`None`: draw
    /// them from the stream before the next step).
    lm_now: Vec<[f64; 3]>,
    lm_next: Vec<[f64; 3]>,
    lm_step: Option<u64>,
    /// A run decomposed over ranks ([`Self::decomposed`]): this rank's layers and messages.
    domain: Option<Domain>,
    /// The span of the owned layers' slots (all, on one rank; the ghost layer lies before or
    /// after it, the fringe rows of a run cut along y inside it).
    own: (usize, usize),
    /// The owned slots as runs `(start, end, g)` of consecutive slots, `g` the slot of `start`
    /// in the storage order of the whole system (the noise streams are keyed by that order):
    /// one run on one rank or on slabs, a run per owned layer on a grid cut along y.
    runs: Vec<(usize, usize, usize)>,
    /// Decomposed: every particle's constants (type, diameter, mass, velocity) in input order.
    whole: Option<Box<Particles>>,
    /// Forces added to each particle's systematic force every step, by input index (empty:
    /// none; [`Self::set_extra_forces`]).
    extra: Vec<[f64; 3]>,
}

/// What one chunk reports: the largest squared displacement from the list's reference
/// positions and the blow-up of lowest tag (internal index, |F|, drift, tag).
#[derive(Clone, Copy)]
struct ChunkReport {
    max_disp2: f64,
    blow_up: Option<(usize, f64, f64, u32)>,
}

impl ChunkReport {
    const EMPTY: Self = Self {
        max_disp2: 0.0,
        blow_up: None,
    };

    fn merge(a: Self, b: Self) -> Self {
        Self {
            max_disp2: a.max_disp2.max(b.max_disp2),
            blow_up: match (a.blow_up, b.blow_up) {
                (Some(x), Some(y)) => Some(if x.3 <= y.3 { x } else { y }),
                (x, None) => x,
                (None, y) => y,
            },
        }
    }
}

/// Standard normal deviates `xi_n` of every particle at step `n` by input index, three per
/// particle in the order x, y, z: the particles of block `b` (indices `b * BLOCK ..`) from the
/// stream (seed, n, `Noise`, `replica * 2^32 + b`), blocks in parallel.
fn fill_deviates(seed: u32, step: u64, key0: u64, out: &mut [[f64; 3]]) {
    let zig = Ziggurat::get();
    out.par_chunks_mut(BLOCK)
        .enumerate()
        .with_min_len(4)
        .for_each(|(b, xi)| {
            let mut rng = stream(seed, step, Purpose::Noise, key0 | b as u64);
            for x in xi {
                *x = [
                    zig.sample(&mut rng),
                    zig.sample(&mut rng),
                    zig.sample(&mut rng),
                ];
            }
        });
}

/// `dt / gamma`, `sqrt(2 kT dt / gamma)` and `(max_drift d)^2` of a particle of diameter `d`
/// (`gamma = 3 pi eta d`).
fn kinetics_of(p: &BdParams, d: f64) -> [f64; 3] {
    let mobility = 1.0 / (3.0 * PI * p.viscosity * d);
    [
        mobility * p.dt,
        (2.0 * p.kt * p.dt * mobility).sqrt(),
        (p.max_drift * d).powi(2),
    ]
}

/// Pairs per batch of the pair-force pass.
const PAIR_BATCH: usize = 64;

/// Pair forces of one slab's half list into `acc` (its own particles first, then the next
/// slab's, which starts at slot `next_start`), from positions not wrapped since the list was
/// built. Batch by batch, the separations are computed and
/// the pairs within the largest cut-off `r_cut` kept (branch-free); only those evaluate the
/// potential (most list entries lie in the skin). Pairs beyond the cut-off would add exact
/// zeros, so the sums equal those over the whole list.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn slab_pair_forces<P: Pair>(
    slab: &Slab,
    next_start: usize,
    r_cut: f64,
    pos: &[[f64; 3]],
    typeid: &[u32],
    diameter: &[f64],
    pair: &P,
    acc: &mut [[f64; 3]],
) {
    let (start, end) = (slab.start, slab.end);
    let own = end - start;
    let rc2 = r_cut * r_cut;
    acc.iter_mut().for_each(|f| *f = [0.0; 3]);
    let mut near = [(0u32, 0u32, [0.0f64; 3], 0.0f64); PAIR_BATCH];
    // The forces of the pairs within range of a batch.
    let mut forces = |near: &[(u32, u32, [f64; 3], f64)]| {
        for &(i, j, d, r2) in near {
            let (i, j) = (i as usize, j as usize);
            let fr = pair.force_over_r(r2, typeid[i], typeid[j], diameter[i], diameter[j]);
            let fv = [fr * d[0], fr * d[1], fr * d[2]];
            let fi = &mut acc[i - start];
            fi[0] += fv[0];
            fi[1] += fv[1];
            fi[2] += fv[2];
            // Own slab, or the next one (slab 0 across the periodic seam): a select.
            let slot = if j.wrapping_sub(start) < own {
                j - start
            } else {
                own + j.wrapping_sub(next_start)
            };
            let fj = &mut acc[slot];
            fj[0] -= fv[0];
            fj[1] -= fv[1];
            fj[2] -= fv[2];
        }
    };
    for batch in slab.pairs.chunks(PAIR_BATCH) {
        let mut m = 0;
        for &[i, j] in batch {
            let (xi, xj) = (pos[i as usize], pos[j as usize]);
            let d = [xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            near[m] = (i, j, d, r2);
            m += (r2 < rc2) as usize;
        }
        forces(&near[..m]);
    }
    for batch in slab.shifted.chunks(PAIR_BATCH) {
        let mut m = 0;
        for &([i, j], sh) in batch {
            let (xi, xj) = (pos[i as usize], pos[j as usize]);
            let y = [xi[0] - sh[0], xi[1] - sh[1], xi[2] - sh[2]];
            let d = [y[0] - xj[0], y[1] - xj[1], y[2] - xj[2]];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            near[m] = (i, j, d, r2);
            m += (r2 < rc2) as usize;
        }
        forces(&near[..m]);
    }
}

/// Pair forces of every slab (of the owned ones, `slabs` being those) into its buffer, slabs
/// in parallel.
fn all_pair_forces<P: Pair>(slabs: &mut [Slab], p: &Particles, pair: &P) {
    let r_cut = pair.r_cut_max();
    slabs.par_iter_mut().for_each(|slab| {
        let mut acc = std::mem::take(&mut slab.acc);
        slab_pair_forces(
            slab,
            slab.next_start,
            r_cut,
            &p.pos,
            &p.typeid,
            &p.diameter,
            pair,
            &mut acc,
        );
        slab.acc = acc;
    });
}

/// Walks the slabs along consecutive slots: the pair force on slot `i` is its slab's own sum
/// plus the previous slab's halo.
struct PairForceCursor<'a> {
    slabs: &'a [Slab],
    /// Current slab, its first slot and end, and its particles' entries in the two buffers.
    z: usize,
    start: usize,
    end: usize,
    own: &'a [[f64; 3]],
    halo: &'a [[f64; 3]],
}

impl<'a> PairForceCursor<'a> {
    /// A cursor at slot `i` (`slab_of` maps slots to slabs; no slabs: zero forces).
    fn new(slabs: &'a [Slab], slab_of: &[u32], i: usize) -> Self {
        let mut c = Self {
            slabs,
            z: 0,
            start: 0,
            end: usize::MAX,
            own: &[],
            halo: &[],
        };
        if !slabs.is_empty() {
            c.seek(slab_of.get(i).map_or(0, |&z| z as usize));
        }
        c
    }

    fn seek(&mut self, z: usize) {
        let nz = self.slabs.len();
        let s = &self.slabs[z];
        let prev = &self.slabs[(z + nz - 1) % nz];
        self.z = z;
        self.start = s.start;
        self.end = s.end;
        self.own = &s.acc[..s.end - s.start];
        self.halo = &prev.acc[prev.end - prev.start..];
    }

    /// Pair force on slot `i` (slots visited in increasing order).
    #[inline(always)]
    fn force(&mut self, i: usize) -> [f64; 3] {
        if self.slabs.is_empty() {
            return [0.0; 3];
        }
        while i >= self.end {
            self.seek(self.z + 1);
        }
        let (a, b) = (self.own[i - self.start], self.halo[i - self.start]);
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }
}

impl<P: Pair, E: External> Brownian<P, E> {
    /// A simulation of `particles` (in input order) starting at `step`; particles are sorted
    /// into cell order first.
    pub fn new(
        particles: Particles,
        sbox: SimBox,
        pair: P,
        external: E,
        params: BdParams,
        step: u64,
    ) -> Result<Self, BdError> {
        Self::restart(particles, sbox, pair, external, params, step, None)
    }

    /// Continue from a checkpoint: `particles` in input order at `step`, with the storage order
    /// and list reference positions [`Self::list_state`] returned, so that the run continues
    /// bitwise identically (without it, the particles are sorted and the lists built afresh).
    pub fn restart(
        particles: Particles,
        sbox: SimBox,
        pair: P,
        external: E,
        params: BdParams,
        step: u64,
        list: Option<&ListState>,
    ) -> Result<Self, BdError> {
        particles.check().map_err(BdError::Invalid)?;
        if let Some(i) = particles
            .diameter
            .iter()
            .position(|d| !(d.is_finite() && *d > 0.0))
        {
            return Err(BdError::Invalid(format!(
                "particle {i} has diameter {}",
                particles.diameter[i]
            )));
        }
        if !(params.dt.is_finite() && params.dt > 0.0) {
            return Err(BdError::Invalid(format!(
                "time step {} must be > 0",
                params.dt
            )));
        }
        if !(params.skin.is_finite() && params.skin >= 0.0) {
            return Err(BdError::Invalid(format!(
                "skin {} must be >= 0",
                params.skin
            )));
        }
        let mut particles = particles;
        for (p, img) in particles.pos.iter_mut().zip(particles.image.iter_mut()) {
            sbox.wrap(p, img);
        }
        let n = particles.len();
        let r_cut = pair.r_cut_max();
        let range = if r_cut > 0.0 {
            r_cut + params.skin
        } else {
            0.0
        };
        let edge = sbox.l.iter().cloned().fold(f64::INFINITY, f64::min);
        // Shorter edges would let two images of a pair lie within range; one or two cells per
        // axis are fine otherwise (the half stencil then meets other images, which lie beyond
        // the range).
        if range > 0.0 && edge <= 2.0 * range {
            return Err(BoxTooSmall {
                edge,
                minimum: 2.0 * range,
                range,
            }
            .into());
        }
        let mut s = Self {
            particles,
            tag: (0..n as u32).collect(),
            sbox,
            pair,
            external,
            params,
            step,
            range,
            grid: CellSort::default(),
            slabs: Vec::new(),
            slab_of: Vec::new(),
            ref_pos: Vec::new(),
            builds: 0,
            rebuild_disp2: if range > 0.0 {
                0.25 * params.skin * params.skin
            } else {
                (0.25 * edge).powi(2)
            },
            new_pos: vec![[0.0; 3]; n],
            scratch_img: Vec::new(),
            kinetics: Vec::new(),
            scratch_f64: Vec::new(),
            scratch_u32: Vec::new(),
            scratch3: Vec::new(),
            lm_now: Vec::new(),
            lm_next: Vec::new(),
            lm_step: None,
            domain: None,
            own: (0, n),
            runs: vec![(0, n, 0)],
            whole: None,
            extra: Vec::new(),
        };
        if params.integrator == Integrator::Lm {
            s.lm_now = vec![[0.0; 3]; n];
            s.lm_next = vec![[0.0; 3]; n];
        }
        s.set_dt(params.dt);
        match list {
            None => s.sort_and_rebuild()?,
            Some(ls) => s.resume_lists(ls)?,
        }
        Ok(s)
    }

    /// Re-establish the storage order and the lists of a checkpoint.
    fn resume_lists(&mut self, ls: &ListState) -> Result<(), BdError> {
        let n = self.particles.len();
        let bad = |m: &str| BdError::Invalid(format!("the checkpoint's neighbour-list state: {m}"));
        if ls.order.len() != n
            || ls.reference.len() != n
            || ls.positions.len() != n
            || ls.images.len() != n
        {
            return Err(bad(&format!(
                "{} stored indices, {} reference positions, {} positions and {} images for {n} particles",
                ls.order.len(),
                ls.reference.len(),
                ls.positions.len(),
                ls.images.len()
            )));
        }
        let mut seen = vec![false; n];
        for &k in &ls.order {
            if (k as usize) >= n || std::mem::replace(&mut seen[k as usize], true) {
                return Err(bad(
                    "the stored order is not a permutation of the particles",
                ));
            }
        }
        if ls
            .reference
            .iter()
            .chain(&ls.positions)
            .flatten()
            .any(|x| !x.is_finite())
        {
            return Err(bad("a position is not finite"));
        }
        self.grid.perm.clear();
        self.grid.perm.extend_from_slice(&ls.order);
        self.apply_perm();
        // The particles' own positions are the wrapped snapshot of these.
        self.particles.pos.clone_from(&ls.positions);
        self.particles.image.clone_from(&ls.images);
        self.ref_pos.clear();
        self.ref_pos.extend_from_slice(&ls.reference);
        if self.range > 0.0 {
            // The stored order must be the cell order of the reference positions.
            self.grid
                .sort(&self.sbox, &self.ref_pos, &self.tag, self.range);
            if self
                .grid
                .perm
                .iter()
                .enumerate()
                .any(|(k, &p)| p as usize != k)
            {
                return Err(bad(
                    "the stored order is not the cell order of the reference positions",
                ));
            }
            self.build_lists();
        }
        Ok(())
    }

    /// The storage order and the positions of the last list build: what a checkpoint needs to
    /// continue bitwise ([`Self::restart`]). Collective when decomposed.
    pub fn list_state(&self) -> ListState {
        if self.domain.is_some() {
            return self.list_state_decomposed();
        }
        ListState {
            order: self.tag.clone(),
            reference: self.ref_pos.clone(),
            positions: self.particles.pos.clone(),
            images: self.particles.image.clone(),
        }
    }

    /// Integrate with `integrator` from the next step on. Leimkuhler–Matthews keeps two
    /// deviates per particle (48 bytes); they are not part of the state: the next step draws
    /// `xi_n` again from (seed, n, particle), so a restart continues bitwise.
    pub fn with_integrator(mut self, integrator: Integrator) -> Self {
        self.params.integrator = integrator;
        let n = if integrator == Integrator::Lm {
            self.n_particles()
        } else {
            0
        };
        self.lm_now = vec![[0.0; 3]; n];
        self.lm_next = vec![[0.0; 3]; n];
        self.lm_step = None;
        self
    }

    /// Change the time step (the time origin stays at `step * dt`).
    pub fn set_dt(&mut self, dt: f64) {
        self.params.dt = dt;
        let p = self.params;
        self.kinetics = self
            .particles
            .diameter
            .iter()
            .map(|&d| kinetics_of(&p, d))
            .collect();
    }

    /// Integrator parameters.
    pub fn params(&self) -> &BdParams {
        &self.params
    }

    /// Particles in the engine's internal (cell) order ([`Self::order`]), positions as stored:
    /// wrapped at the last list build, up to half the skin outside the box since (the image
    /// counts match; [`Self::snapshot`] wraps). Decomposed ([`Self::decomposed`]): this rank's
    /// owned and ghost slots only; [`Self::snapshot`] gathers the whole system.
    pub fn particles(&self) -> &Particles {
        &self.particles
    }

    /// Input index of each internally stored particle (the storage order; this rank's slots
    /// when decomposed).
    pub fn order(&self) -> &[u32] {
        &self.tag
    }

    /// The particles in input order, wrapped into the box (allocates; for output and analysis).
    /// Collective when decomposed: every rank gets the whole system.
    pub fn snapshot(&self) -> Particles {
        if self.domain.is_some() {
            return self.snapshot_decomposed();
        }
        let n = self.particles.len();
        let mut inv = vec![0u32; n];
        for (k, &t) in self.tag.iter().enumerate() {
            inv[t as usize] = k as u32;
        }
        let p = &self.particles;
        let pick = |k: &u32| *k as usize;
        let wrapped = |k: &u32| {
            let (mut x, mut img) = (p.pos[pick(k)], p.image[pick(k)]);
            self.sbox.wrap(&mut x, &mut img);
            (x, img)
        };
        Particles {
            pos: inv.iter().map(|k| wrapped(k).0).collect(),
            image: inv.iter().map(|k| wrapped(k).1).collect(),
            typeid: inv.iter().map(|k| p.typeid[pick(k)]).collect(),
            diameter: inv.iter().map(|k| p.diameter[pick(k)]).collect(),
            vel: inv.iter().map(|k| p.vel[pick(k)]).collect(),
            mass: inv.iter().map(|k| p.mass[pick(k)]).collect(),
            type_names: p.type_names.clone(),
        }
    }

    /// Current time `step * dt`.
    pub fn time(&self) -> f64 {
        self.step as f64 * self.params.dt
    }

    /// Number of neighbour-list builds so far (by this engine object).
    pub fn neighbor_builds(&self) -> u64 {
        self.builds
    }

    /// Add `forces` (input order; empty: none) to the systematic forces of every step from
    /// now on, as a further external field would be (on one process).
    pub fn set_extra_forces(&mut self, forces: &[[f64; 3]]) -> Result<(), BdError> {
        if !forces.is_empty() && (forces.len() != self.tag.len() || self.domain.is_some()) {
            return Err(BdError::Invalid(format!(
                "{} extra forces for {} particles{}",
                forces.len(),
                self.tag.len(),
                if self.domain.is_some() {
                    " decomposed over ranks (extra forces act on one process)"
                } else {
                    ""
                }
            )));
        }
        // Copied into the kept buffer: a script setting them every step allocates nothing.
        self.extra.clear();
        self.extra.extend_from_slice(forces);
        Ok(())
    }

    /// Forces on the particles in input order at the current positions and time (allocates;
    /// collective when decomposed).
    pub fn forces(&self) -> Vec<[f64; 3]> {
        if self.domain.is_some() {
            return self.forces_decomposed();
        }
        let t = self.time();
        let n = self.particles.len();
        let mut slabs = self.slabs.clone();
        let p = &self.particles;
        if !slabs.is_empty() {
            all_pair_forces(&mut slabs, p, &self.pair);
        }
        let mut out = vec![[0.0; 3]; n];
        let mut pair_force = PairForceCursor::new(&slabs, &self.slab_of, 0);
        for (k, &tag) in self.tag.iter().enumerate() {
            let mut f = pair_force.force(k);
            let mut e = self.external.force_on(p.pos[k], t, p.diameter[k]);
            if let Some(x) = self.extra.get(tag as usize) {
                e = [e[0] + x[0], e[1] + x[1], e[2] + x[2]];
            }
            for a in 0..3 {
                f[a] += e[a];
            }
            out[tag as usize] = f;
        }
        out
    }

    /// Wrap the positions, sort the particles into cells and rebuild the lists (without pair
    /// forces: only wrap). Decomposed: with the migration and the new ghosts (an error when a
    /// particle crossed more than one domain).
    fn sort_and_rebuild(&mut self) -> Result<(), BdError> {
        if self.domain.is_some() {
            return self.rebuild_decomposed();
        }
        let sbox = self.sbox;
        self.particles
            .pos
            .par_iter_mut()
            .zip(self.particles.image.par_iter_mut())
            .with_min_len(4096)
            .for_each(|(x, img)| sbox.wrap(x, img));
        if self.range > 0.0 {
            self.grid
                .sort(&self.sbox, &self.particles.pos, &self.tag, self.range);
            self.apply_perm();
        }
        self.ref_pos.clear();
        self.ref_pos.extend_from_slice(&self.particles.pos);
        if self.range > 0.0 {
            self.build_lists();
        }
        Ok(())
    }

    /// The layers of cells whose pairs this engine sums: all, or a domain's own.
    fn owned_layers(&self) -> (usize, usize) {
        self.domain
            .as_ref()
            .map_or((0, self.slabs.len()), |d| (d.z0, d.z1))
    }

    /// Slabs and half lists (of the owned layers) from the reference positions (which are in
    /// cell order).
    fn build_lists(&mut self) {
        self.builds += 1;
        let n = self.particles.len();
        let nz = self.grid.n_cells[2];
        self.slabs.resize_with(nz, Slab::default);
        for z in 0..nz {
            (self.slabs[z].start, self.slabs[z].end) = self.grid.layer(z);
        }
        for z in 0..nz {
            let next = &self.slabs[(z + 1) % nz];
            let (next_start, next_len) = (next.start, next.end - next.start);
            let s = &mut self.slabs[z];
            s.next_start = next_start;
            s.acc.resize(s.end - s.start + next_len, [0.0; 3]);
        }
        debug_assert_eq!(self.slabs.last().map_or(n, |s| s.end), n);
        self.grid.layer_of_slots(&mut self.slab_of);
        let pos = &self.ref_pos;
        let cell_start = &self.grid.cell_start;
        let n_cells = self.grid.n_cells;
        let (sbox, range) = (self.sbox, self.range);
        let (z0, z1) = self.owned_layers();
        self.slabs[z0..z1]
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, slab)| {
                let z = z0 + k;
                let Slab {
                    pairs,
                    shifted,
                    cand,
                    ..
                } = slab;
                pairs.clear();
                shifted.clear();
                let (l, h) = (sbox.l, sbox.l.map(|x| 0.5 * x));
                scan_layer(
                    z,
                    pos,
                    cell_start,
                    n_cells,
                    &sbox,
                    range,
                    cand,
                    |i, cands| {
                        let xi = pos[i];
                        for &(j, d) in cands {
                            // The periodic shift the scan applied to x_i: 0 or +-L per axis.
                            let xj = pos[j as usize];
                            let mut sh = [0.0; 3];
                            for k in 0..3 {
                                let gap = (xi[k] - xj[k]) - d[k];
                                sh[k] = if gap > h[k] {
                                    l[k]
                                } else if gap < -h[k] {
                                    -l[k]
                                } else {
                                    0.0
                                };
                            }
                            if sh == [0.0; 3] {
                                pairs.push([i as u32, j]);
                            } else {
                                shifted.push(([i as u32, j], sh));
                            }
                        }
                    },
                );
            });
    }

    /// Apply `self.grid.perm` (new slot k takes old slot perm[k]) to every per-particle array.
    fn apply_perm(&mut self) {
        let perm = &self.grid.perm;
        let p = &mut self.particles;
        permute(&mut p.pos, perm, &mut self.new_pos);
        permute(&mut p.vel, perm, &mut self.new_pos);
        permute(&mut p.image, perm, &mut self.scratch_img);
        permute(&mut p.typeid, perm, &mut self.scratch_u32);
        permute(&mut self.tag, perm, &mut self.scratch_u32);
        permute(&mut p.diameter, perm, &mut self.scratch_f64);
        permute(&mut p.mass, perm, &mut self.scratch_f64);
        permute(&mut self.kinetics, perm, &mut self.scratch3);
    }

    /// Advance `n` steps.
    ///
    /// The steps run on a worker of the thread pool, so that their parallel passes start
    /// without a hand-over from a foreign thread each (context switches that cost more than a
    /// step of a small system).
    pub fn run(&mut self, n: u64) -> Result<(), BdError> {
        rayon::scope(|_| (0..n).try_for_each(|_| self.advance()))
    }

    /// Advance one step.
    pub fn advance(&mut self) -> Result<(), BdError> {
        let t = self.time();
        let step = self.step;
        let seed = self.params.seed;
        let key0 = (self.params.replica as u64) << 32;
        let n = self.particles.len();
        if self.range > 0.0 {
            let (z0, z1) = self.owned_layers();
            all_pair_forces(&mut self.slabs[z0..z1], &self.particles, &self.pair);
            self.exchange_halo();
        }
        // Leimkuhler–Matthews: xi_n (drawn by the previous step, or afresh after a restart)
        // and xi_{n+1}, by input index.
        let lm = self.params.integrator == Integrator::Lm;
        if lm {
            if self.lm_step != Some(step) {
                fill_deviates(seed, step, key0, &mut self.lm_now);
            }
            fill_deviates(seed, step + 1, key0, &mut self.lm_next);
            self.lm_step = Some(step);
        }
        let mut new_pos = std::mem::take(&mut self.new_pos);
        new_pos.resize(n, [0.0; 3]);
        let pass = StepPass {
            pos: &self.particles.pos,
            kinetics: &self.kinetics,
            diameter: &self.particles.diameter,
            ref_pos: &self.ref_pos,
            tag: &self.tag,
            slabs: &self.slabs,
            slab_of: &self.slab_of,
            external: &self.external,
            extra: &self.extra,
            t,
            t_end: (step + 1) as f64 * self.params.dt,
            seed,
            step,
            key0,
            lm: lm.then_some((&self.lm_now[..], &self.lm_next[..])),
        };
        // The owned slots, whose noise comes from the blocks of the whole system's storage
        // order: run by run, a first, partial block when the run starts inside one, then
        // whole chunks.
        let mut report = ChunkReport::EMPTY;
        for &(a, b, g0) in &self.runs {
            let head = ((BLOCK - g0 % BLOCK) % BLOCK).min(b - a);
            let (head_out, rest) = new_pos[a..b].split_at_mut(head);
            let first = pass.integrate(a, head_out, (g0 / BLOCK) as u64, g0 % BLOCK);
            let g1 = (g0 + head) / BLOCK;
            let run = rest
                .par_chunks_mut(CHUNK)
                .enumerate()
                .map(|(c, out)| {
                    let lo = a + head + c * CHUNK;
                    pass.integrate(lo, out, (g1 + c * CHUNK / BLOCK) as u64, 0)
                })
                .reduce(|| first, ChunkReport::merge);
            report = ChunkReport::merge(report, run);
        }
        let (max_disp2, blow_up) = self.agree_on_step(report, &mut new_pos);
        if let Some(e) = blow_up {
            self.new_pos = new_pos;
            return Err(e);
        }
        std::mem::swap(&mut self.particles.pos, &mut new_pos);
        self.new_pos = new_pos;
        self.step += 1;
        if lm {
            // xi_{n+1} is the next step's xi_n.
            std::mem::swap(&mut self.lm_now, &mut self.lm_next);
            self.lm_step = Some(self.step);
        }
        let every = self.params.sort_every;
        // NaN displacements (a run gone non-finite without a blow-up) fail every comparison:
        // the rebuild is skipped and the next step reports the blow-up.
        if max_disp2 > self.rebuild_disp2 || (every > 0 && self.step.is_multiple_of(every)) {
            self.sort_and_rebuild()?;
        }
        // Otherwise the ghosts' positions came with the agreement.
        Ok(())
    }

    /// The blow-up of a step's report as an error (one process).
    fn blow_up_error(&self, report: &ChunkReport) -> Option<BdError> {
        report
            .blow_up
            .map(|(i, force, drift, tag)| BdError::BlowUp {
                step: self.step,
                time: self.time(),
                particle: tag as usize,
                position: self.particles.pos[i],
                force,
                drift,
                diameter: self.particles.diameter[i],
            })
    }
}

/// Leimkuhler–Matthews deviates `xi_n` and `xi_{n+1}`, by input index.
type LmDeviates<'a> = (&'a [[f64; 3]], &'a [[f64; 3]]);

/// What the integration pass of a step reads.
struct StepPass<'a, E> {
    pos: &'a [[f64; 3]],
    kinetics: &'a [[f64; 3]],
    diameter: &'a [f64],
    ref_pos: &'a [[f64; 3]],
    tag: &'a [u32],
    slabs: &'a [Slab],
    slab_of: &'a [u32],
    external: &'a E,
    /// Extra forces by input index (empty: none).
    extra: &'a [[f64; 3]],
    t: f64,
    /// Time at the end of the step (where a hard wall confines the new positions).
    t_end: f64,
    seed: u32,
    step: u64,
    key0: u64,
    /// Leimkuhler–Matthews: `xi_n` and `xi_{n+1}` by input index.
    lm: Option<LmDeviates<'a>>,
}

impl<E: External> StepPass<'_, E> {
    /// New positions of slots `lo ..< lo + out.len()` into `out`. Their Euler noise comes from
    /// the streams of blocks `block, block + 1, ...` of the whole system's storage order, the
    /// first of which begins `skip` particles before slot `lo` (their deviates are drawn and
    /// dropped).
    fn integrate(&self, lo: usize, out: &mut [[f64; 3]], block: u64, skip: usize) -> ChunkReport {
        let zig = Ziggurat::get();
        let mut rep = ChunkReport::EMPTY;
        let mut pair_force = PairForceCursor::new(self.slabs, self.slab_of, lo);
        let (mut k0, mut block, mut skip) = (0, block, skip);
        while k0 < out.len() {
            let m = (BLOCK - skip).min(out.len() - k0);
            let mut rng = stream(self.seed, self.step, Purpose::Noise, self.key0 | block);
            if self.lm.is_none() {
                for _ in 0..3 * skip {
                    zig.sample(&mut rng);
                }
            }
            for k in k0..k0 + m {
                let i = lo + k;
                let [drift_per_force, amp, limit2] = self.kinetics[i];
                let x = self.pos[i];
                let fp = pair_force.force(i);
                let mut fe = self.external.force_on(x, self.t, self.diameter[i]);
                if let Some(e) = self.extra.get(self.tag[i] as usize) {
                    fe = [fe[0] + e[0], fe[1] + e[1], fe[2] + e[2]];
                }
                let f = [fp[0] + fe[0], fp[1] + fe[1], fp[2] + fe[2]];
                let drift = [
                    f[0] * drift_per_force,
                    f[1] * drift_per_force,
                    f[2] * drift_per_force,
                ];
                let drift2 = drift[0] * drift[0] + drift[1] * drift[1] + drift[2] * drift[2];
                // NaN forces fail the comparison and count as a blow-up too.
                let ok = drift2 <= limit2;
                if !ok {
                    let tag = self.tag[i];
                    if rep.blow_up.is_none_or(|b| tag < b.3) {
                        rep.blow_up = Some((
                            i,
                            (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt(),
                            drift2.sqrt(),
                            tag,
                        ));
                    }
                }
                let xi = match self.lm {
                    // (xi_n + xi_{n+1}) / 2 of this particle.
                    Some((now, next)) => {
                        let (a, b) = (now[self.tag[i] as usize], next[self.tag[i] as usize]);
                        [
                            0.5 * (a[0] + b[0]),
                            0.5 * (a[1] + b[1]),
                            0.5 * (a[2] + b[2]),
                        ]
                    }
                    None => [
                        zig.sample(&mut rng),
                        zig.sample(&mut rng),
                        zig.sample(&mut rng),
                    ],
                };
                let mut q = [
                    x[0] + drift[0] + amp * xi[0],
                    x[1] + drift[1] + amp * xi[1],
                    x[2] + drift[2] + amp * xi[2],
                ];
                // A hard wall reflects the step (free draining: along the wall's normal).
                if let Some((s, n)) = self.external.overshoot(q, self.t_end, self.diameter[i]) {
                    q = [
                        q[0] - 2.0 * s * n[0],
                        q[1] - 2.0 * s * n[1],
                        q[2] - 2.0 * s * n[2],
                    ];
                }
                let r = self.ref_pos[i];
                let d = [q[0] - r[0], q[1] - r[1], q[2] - r[2]];
                let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                // NaN compares false and is ignored here; the blow-up check reports it.
                rep.max_disp2 = if d2 > rep.max_disp2 {
                    d2
                } else {
                    rep.max_disp2
                };
                out[k] = q;
            }
            k0 += m;
            block += 1;
            skip = 0;
        }
        rep
    }
}
