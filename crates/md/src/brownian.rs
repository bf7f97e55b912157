//! Free-draining Brownian dynamics (Euler–Maruyama).
//!
//! `x(t + dt) = x + F / gamma_i dt + sqrt(2 kT dt / gamma_i) xi`, with Stokes friction
//! `gamma_i = 3 pi eta d_i` from each particle's diameter.
//!
//! Particles are stored in cell order so that neighbours lie close in memory: they are
//! re-sorted every [`BdParams::sort_every`] steps (a fixed schedule) and the storage order is
//! part of the state ([`Brownian::order`], saved in checkpoints). The noise of the particle in
//! storage slot `k` at step `n` comes from the counter-based stream keyed by
//! (seed, n, replica, k / BLOCK), one keyed stream per block of [`BLOCK`] slots. A run is
//! therefore a pure function of its inputs: identical for any number of threads, and a restart
//! from a checkpoint (positions, images, box and storage order in double precision) continues
//! bitwise identically. Forces are summed over each particle's neighbours in the order of their
//! input index, so sums do not depend on when the neighbour list was rebuilt.
//! [`Brownian::snapshot`] returns the particles in input order.
//!
//! One step is a single parallel pass over chunks of particles: each chunk sums its particles'
//! forces from the neighbour list (reading the old positions), draws its noise and writes the
//! new positions into a second buffer; the buffers are then swapped. Nothing is allocated per
//! step.

use crate::neighbor::{BoxTooSmall, NeighborList, near_image};
use crate::potential::{External, Pair};
use crate::state::{Particles, SimBox};
use colloidsim_core::rng::{BLOCK, Purpose, stream};
use rand::RngExt;
use rand_distr::StandardNormal;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Particles per parallel work item (a multiple of the noise block).
const CHUNK: usize = 4 * BLOCK;

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
    /// Re-sort particles into cell order every this many steps (0: never after the start).
    pub sort_every: u64,
    /// A step whose deterministic displacement `|F| dt / gamma` exceeds this fraction of the
    /// particle's diameter stops the run (the time step is too large for the potential).
    pub max_drift: f64,
}

impl BdParams {
    /// Defaults: kT = 1, eta = 1, skin 0.3, sort every 500 steps, max_drift 0.2.
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
        }
    }
}

/// Why a run stopped.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum BdError {
    /// The time step is too large for the forces.
    #[error(
        "blow-up at step {step} (t = {time}): particle {particle} at ({:.4}, {:.4}, {:.4}) would move {drift:.4} \
         (diameter {diameter}) in one step under a force {force:.4e}; the time step is too large for the WCA core — reduce run.dt",
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
    nlist: NeighborList,
    new_pos: Vec<[f64; 3]>,
    new_image: Vec<[i32; 3]>,
    mobility: Vec<f64>,
    noise_amp: Vec<f64>,
    drift_limit2: Vec<f64>,
    scratch_f64: Vec<f64>,
    scratch_u32: Vec<u32>,
    perm: Vec<u32>,
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

/// Borrowed view of everything a force evaluation reads.
struct ForceCtx<'a, P, E> {
    pos: &'a [[f64; 3]],
    typeid: &'a [u32],
    diameter: &'a [f64],
    nlist: &'a NeighborList,
    sbox: SimBox,
    pair: &'a P,
    external: &'a E,
}

impl<P: Pair, E: External> ForceCtx<'_, P, E> {
    #[inline(always)]
    fn force_on(&self, i: usize, t: f64) -> [f64; 3] {
        let p = self.pos[i];
        let mut f = self.external.force(p, t);
        let (ti, di) = (self.typeid[i], self.diameter[i]);
        for &j in self.nlist.neighbors(i) {
            let j = j as usize;
            let q = self.pos[j];
            let d = near_image(&self.sbox, [p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let fr = self
                .pair
                .force_over_r(r2, ti, self.typeid[j], di, self.diameter[j]);
            f[0] += fr * d[0];
            f[1] += fr * d[1];
            f[2] += fr * d[2];
        }
        f
    }
}

fn permute<T: Copy + Send + Sync>(v: &mut Vec<T>, perm: &[u32], scratch: &mut Vec<T>) {
    scratch.clear();
    scratch.extend(perm.iter().map(|&k| v[k as usize]));
    std::mem::swap(v, scratch);
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

    /// Continue from a checkpoint: `particles` in input order at `step`, stored in `order`
    /// (input indices in storage order, as [`Self::order`] returned) when given, so that the run
    /// continues bitwise identically.
    pub fn restart(
        particles: Particles,
        sbox: SimBox,
        pair: P,
        external: E,
        params: BdParams,
        step: u64,
        order: Option<&[u32]>,
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
        let mut particles = particles;
        for (p, img) in particles.pos.iter_mut().zip(particles.image.iter_mut()) {
            sbox.wrap(p, img);
        }
        let n = particles.len();
        let nlist = NeighborList::new(pair.r_cut_max(), params.skin);
        let mut s = Self {
            particles,
            tag: (0..n as u32).collect(),
            sbox,
            pair,
            external,
            params,
            step,
            nlist,
            new_pos: vec![[0.0; 3]; n],
            new_image: vec![[0; 3]; n],
            mobility: Vec::new(),
            noise_amp: Vec::new(),
            drift_limit2: Vec::new(),
            scratch_f64: Vec::new(),
            scratch_u32: Vec::new(),
            perm: Vec::new(),
        };
        s.set_dt(params.dt);
        match order {
            None => s.sort_and_rebuild()?,
            Some(order) => {
                let mut seen = vec![false; n];
                for &k in order {
                    if (k as usize) >= n || std::mem::replace(&mut seen[k as usize], true) {
                        return Err(BdError::Invalid(
                            "the stored particle order is not a permutation of the particles"
                                .into(),
                        ));
                    }
                }
                if order.len() != n {
                    return Err(BdError::Invalid(format!(
                        "the stored particle order has {} entries for {n} particles",
                        order.len()
                    )));
                }
                s.perm.clear();
                s.perm.extend_from_slice(order);
                s.apply_perm();
                s.nlist.build(&s.sbox, &s.particles.pos, &s.tag)?;
            }
        }
        Ok(s)
    }

    /// Change the time step (the time origin stays at `step * dt`).
    pub fn set_dt(&mut self, dt: f64) {
        self.params.dt = dt;
        let p = self.params;
        self.mobility = self
            .particles
            .diameter
            .iter()
            .map(|d| 1.0 / (3.0 * PI * p.viscosity * d))
            .collect();
        self.noise_amp = self
            .mobility
            .iter()
            .map(|m| (2.0 * p.kt * dt * m).sqrt())
            .collect();
        self.drift_limit2 = self
            .particles
            .diameter
            .iter()
            .map(|d| (p.max_drift * d).powi(2))
            .collect();
    }

    /// Integrator parameters.
    pub fn params(&self) -> &BdParams {
        &self.params
    }

    /// Particles in the engine's internal (cell) order; see [`Self::tags`].
    pub fn particles(&self) -> &Particles {
        &self.particles
    }

    /// Input index of each internally stored particle (the storage order; save it with a
    /// checkpoint and pass it to [`Self::restart`]).
    pub fn order(&self) -> &[u32] {
        &self.tag
    }

    /// The particles in input order (allocates; for output and analysis).
    pub fn snapshot(&self) -> Particles {
        let n = self.particles.len();
        let mut inv = vec![0u32; n];
        for (k, &t) in self.tag.iter().enumerate() {
            inv[t as usize] = k as u32;
        }
        let p = &self.particles;
        let pick = |k: &u32| *k as usize;
        Particles {
            pos: inv.iter().map(|k| p.pos[pick(k)]).collect(),
            image: inv.iter().map(|k| p.image[pick(k)]).collect(),
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

    /// Number of neighbour-list builds so far.
    pub fn neighbor_builds(&self) -> u64 {
        self.nlist.builds()
    }

    fn ctx(&self) -> ForceCtx<'_, P, E> {
        ForceCtx {
            pos: &self.particles.pos,
            typeid: &self.particles.typeid,
            diameter: &self.particles.diameter,
            nlist: &self.nlist,
            sbox: self.sbox,
            pair: &self.pair,
            external: &self.external,
        }
    }

    /// Forces on the particles in input order at the current positions and time.
    pub fn forces(&self) -> Vec<[f64; 3]> {
        let t = self.time();
        let ctx = self.ctx();
        let internal: Vec<[f64; 3]> = (0..self.particles.len())
            .into_par_iter()
            .map(|i| ctx.force_on(i, t))
            .collect();
        let mut out = vec![[0.0; 3]; internal.len()];
        for (k, f) in internal.into_iter().enumerate() {
            out[self.tag[k] as usize] = f;
        }
        out
    }

    /// Reorder the particles by cell (when there is a pair potential) and rebuild the list.
    fn sort_and_rebuild(&mut self) -> Result<(), BdError> {
        if self.nlist.range() > 0.0 {
            let order = self.nlist.bin(&self.sbox, &self.particles.pos);
            self.perm.clear();
            self.perm.extend_from_slice(order);
            self.apply_perm();
        }
        self.nlist
            .build(&self.sbox, &self.particles.pos, &self.tag)?;
        Ok(())
    }

    /// Apply `self.perm` (new slot k takes old slot perm[k]) to every per-particle array.
    fn apply_perm(&mut self) {
        {
            let perm = &self.perm;
            let p = &mut self.particles;
            permute(&mut p.pos, perm, &mut self.new_pos);
            permute(&mut p.vel, perm, &mut self.new_pos);
            permute(&mut p.image, perm, &mut self.new_image);
            permute(&mut p.typeid, perm, &mut self.scratch_u32);
            permute(&mut self.tag, perm, &mut self.scratch_u32);
            permute(&mut p.diameter, perm, &mut self.scratch_f64);
            permute(&mut p.mass, perm, &mut self.scratch_f64);
            permute(&mut self.mobility, perm, &mut self.scratch_f64);
            permute(&mut self.noise_amp, perm, &mut self.scratch_f64);
            permute(&mut self.drift_limit2, perm, &mut self.scratch_f64);
        }
    }

    /// Advance `n` steps.
    pub fn run(&mut self, n: u64) -> Result<(), BdError> {
        for _ in 0..n {
            self.advance()?;
        }
        Ok(())
    }

    /// Advance one step.
    pub fn advance(&mut self) -> Result<(), BdError> {
        let t = self.time();
        let step = self.step;
        let seed = self.params.seed;
        let key0 = (self.params.replica as u64) << 32;
        let dt = self.params.dt;
        let n = self.particles.len();
        let mut new_pos = std::mem::take(&mut self.new_pos);
        let mut new_image = std::mem::take(&mut self.new_image);
        new_pos.resize(n, [0.0; 3]);
        new_image.resize(n, [0; 3]);
        let old_image = &self.particles.image;
        let ctx = self.ctx();
        let (mobility, noise_amp, drift_limit2, tag) = (
            &self.mobility,
            &self.noise_amp,
            &self.drift_limit2,
            &self.tag,
        );
        let report = new_pos
            .par_chunks_mut(CHUNK)
            .zip(new_image.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(b, (out, images))| {
                let mut rep = ChunkReport::EMPTY;
                let block0 = (b * CHUNK / BLOCK) as u64;
                let mut rng = stream(seed, step, Purpose::Noise, key0 | block0);
                for (k, (np, img)) in out.iter_mut().zip(images.iter_mut()).enumerate() {
                    let i = b * CHUNK + k;
                    let f = ctx.force_on(i, t);
                    let m = mobility[i] * dt;
                    let drift = [f[0] * m, f[1] * m, f[2] * m];
                    let drift2 = drift[0] * drift[0] + drift[1] * drift[1] + drift[2] * drift[2];
                    // NaN forces fail the comparison and count as a blow-up too.
                    let ok = drift2 <= drift_limit2[i];
                    if !ok && rep.blow_up.is_none_or(|b| tag[i] < b.3) {
                        rep.blow_up = Some((
                            i,
                            (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt(),
                            drift2.sqrt(),
                            tag[i],
                        ));
                    }
                    if k > 0 && k % BLOCK == 0 {
                        rng = stream(
                            seed,
                            step,
                            Purpose::Noise,
                            key0 | (block0 + (k / BLOCK) as u64),
                        );
                    }
                    let xi: [f64; 3] = [
                        rng.sample(StandardNormal),
                        rng.sample(StandardNormal),
                        rng.sample(StandardNormal),
                    ];
                    let a = noise_amp[i];
                    let p = ctx.pos[i];
                    let mut q = [
                        p[0] + drift[0] + a * xi[0],
                        p[1] + drift[1] + a * xi[1],
                        p[2] + drift[2] + a * xi[2],
                    ];
                    rep.max_disp2 = rep.max_disp2.max(ctx.nlist.displacement2(&ctx.sbox, i, q));
                    *img = old_image[i];
                    ctx.sbox.wrap(&mut q, img);
                    *np = q;
                }
                rep
            })
            .reduce(|| ChunkReport::EMPTY, ChunkReport::merge);
        if let Some((i, force, drift, _)) = report.blow_up {
            self.new_pos = new_pos;
            self.new_image = new_image;
            return Err(BdError::BlowUp {
                step,
                time: t,
                particle: self.tag[i] as usize,
                position: self.particles.pos[i],
                force,
                drift,
                diameter: self.particles.diameter[i],
            });
        }
        std::mem::swap(&mut self.particles.pos, &mut new_pos);
        std::mem::swap(&mut self.particles.image, &mut new_image);
        self.new_pos = new_pos;
        self.new_image = new_image;
        self.step += 1;
        if self.nlist.range() > 0.0 {
            let every = self.params.sort_every;
            if every > 0 && self.step.is_multiple_of(every) {
                self.sort_and_rebuild()?;
            } else if report.max_disp2 > 0.25 * self.nlist.skin * self.nlist.skin {
                self.nlist
                    .build(&self.sbox, &self.particles.pos, &self.tag)?;
            }
        }
        Ok(())
    }
}
