//! Brownian dynamics with hydrodynamic interactions (Ermak & McCammon 1978):
//!
//! `x(t + dt) = x + M F dt + sqrt(2 kT dt) M^(1/2) xi`,
//!
//! with the mobility M of `colloidsim_hydro` (free draining, RPY by direct free-space sums, or
//! RPY by positively split Ewald in the periodic box). No drift term `kT div M dt`: these
//! mobilities are divergence-free. The forces are those of the free-draining engine
//! ([`super::Brownian`]): a pair potential on a full Verlet list ([`NeighborList`]) plus an
//! external field.
//!
//! **Determinism and restarts.** Particles stay in input order; the noise of particle `i` at
//! step `n` is keyed by (seed, n, replica, i) ([`colloidsim_hydro::noise`]); each particle's
//! pair forces are summed over its neighbours in increasing index, and pairs beyond the
//! cut-off add exact zeros, so the force does not depend on when the list was built. A step is
//! therefore a pure function of the positions (with their image counts) and the step number:
//! a checkpoint of those restarts bitwise, for any number of threads. The mobility sees the
//! unwrapped positions `x + image L` (the free-space method needs them; PSE wraps them itself).

use crate::neighbor::{BoxTooSmall, NeighborList};
use crate::potential::{External, Pair};
use crate::state::{Particles, SimBox};
use colloidsim_hydro::{HydroError, Mobility, NoiseKey};
use rayon::prelude::*;

/// Parameters of the hydrodynamic Brownian integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HydroBdParams {
    /// Thermal energy kT.
    pub kt: f64,
    /// Time step.
    pub dt: f64,
    /// Seed of the noise streams.
    pub seed: u32,
    /// Independent replica of the same seed (noise keys `replica * 2^32 + particle block`).
    pub replica: u32,
    /// Verlet skin of the pair-force list.
    pub skin: f64,
    /// A step whose deterministic displacement `|F| dt / (6 pi eta a)` exceeds this fraction of
    /// the particle's diameter stops the run (the time step is too large for the potential).
    pub max_drift: f64,
}

impl HydroBdParams {
    /// Defaults: kT = 1, skin 0.3, max_drift 0.2, replica 0.
    pub fn new(dt: f64, seed: u32) -> Self {
        Self {
            kt: 1.0,
            dt,
            seed,
            replica: 0,
            skin: 0.3,
            max_drift: 0.2,
        }
    }
}

/// Why a hydrodynamic Brownian run stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HydroBdError {
    /// The time step is too large for the forces.
    #[error(
        "blow-up at step {step} (t = {time}): particle {particle} would move {drift:.4} (diameter {diameter}) \
         in one step under a force {force:.4e}; the time step is too large for the WCA core — reduce `dt`"
    )]
    BlowUp {
        /// Step.
        step: u64,
        /// Time.
        time: f64,
        /// Lowest-index offending particle.
        particle: usize,
        /// Magnitude of its force.
        force: f64,
        /// Its free-draining deterministic displacement.
        drift: f64,
        /// Its diameter.
        diameter: f64,
    },
    /// The mobility failed (e.g. a Lanczos square root that did not converge; names the step).
    #[error("hydrodynamics: {0}")]
    Hydro(#[from] HydroError),
    /// Box too small for the neighbour list.
    #[error(transparent)]
    BoxTooSmall(#[from] BoxTooSmall),
    /// Inconsistent input.
    #[error("invalid particle data: {0}")]
    Invalid(String),
}

/// A Brownian dynamics simulation with pair potential `P`, external field `E` and mobility `M`.
pub struct HydroBrownian<P: Pair, E: External, M: Mobility> {
    particles: Particles,
    /// Periodic box.
    pub sbox: SimBox,
    /// Pair potential.
    pub pair: P,
    /// External field.
    pub external: E,
    mobility: M,
    params: HydroBdParams,
    /// Current step (time = step * dt).
    pub step: u64,
    nlist: NeighborList,
    key: Vec<u32>,
    forces: Vec<[f64; 3]>,
    unwrapped: Vec<[f64; 3]>,
    disp: Vec<[f64; 3]>,
    /// A hard wall's reflection ([`Self::reflect_at_walls`]): the spheres beyond it, the
    /// matrix of their couplings and its solution, the forces and their displacements.
    crossers: Vec<(usize, f64, [f64; 3])>,
    wall_matrix: Vec<f64>,
    wall_lambda: Vec<f64>,
    wall_force: Vec<[f64; 3]>,
    wall_disp: Vec<[f64; 3]>,
    last_iterations: usize,
    /// Forces added to each particle's systematic force every step, in input order (empty:
    /// none).
    extra: Vec<[f64; 3]>,
}

impl<P: Pair, E: External, M: Mobility> HydroBrownian<P, E, M> {
    /// A simulation of `particles` at `step` with the mobility `mobility` (for as many
    /// particles). A checkpoint is the particles (positions and image counts) and the step.
    pub fn new(
        particles: Particles,
        sbox: SimBox,
        pair: P,
        external: E,
        mobility: M,
        params: HydroBdParams,
        step: u64,
    ) -> Result<Self, HydroBdError> {
        particles.check().map_err(HydroBdError::Invalid)?;
        let n = particles.len();
        if mobility.len() != n {
            return Err(HydroBdError::Invalid(format!(
                "a mobility for {} particles given {n} particles",
                mobility.len()
            )));
        }
        if !(params.dt.is_finite() && params.dt > 0.0) {
            return Err(HydroBdError::Invalid(format!(
                "time step {} must be > 0",
                params.dt
            )));
        }
        if !(params.skin.is_finite() && params.skin >= 0.0) {
            return Err(HydroBdError::Invalid(format!(
                "skin {} must be >= 0",
                params.skin
            )));
        }
        let mut particles = particles;
        for (p, img) in particles.pos.iter_mut().zip(particles.image.iter_mut()) {
            sbox.wrap(p, img);
        }
        let mut s = Self {
            nlist: NeighborList::new(pair.r_cut_max(), params.skin),
            particles,
            sbox,
            pair,
            external,
            mobility,
            params,
            step,
            key: (0..n as u32).collect(),
            forces: vec![[0.0; 3]; n],
            unwrapped: vec![[0.0; 3]; n],
            disp: vec![[0.0; 3]; n],
            crossers: Vec::new(),
            wall_matrix: Vec::new(),
            wall_lambda: Vec::new(),
            wall_force: vec![[0.0; 3]; n],
            wall_disp: vec![[0.0; 3]; n],
            last_iterations: 0,
            extra: Vec::new(),
        };
        s.nlist.build(&s.sbox, &s.particles.pos, &s.key)?;
        Ok(s)
    }

    /// Particles in input order (positions wrapped, image counts kept).
    pub fn particles(&self) -> &Particles {
        &self.particles
    }

    /// The mobility.
    pub fn mobility(&self) -> &M {
        &self.mobility
    }

    /// The mobility (mutable: e.g. to read and reset timers).
    pub fn mobility_mut(&mut self) -> &mut M {
        &mut self.mobility
    }

    /// The mobility, giving up the engine (e.g. to hand it to a restarted engine).
    pub fn into_mobility(self) -> M {
        self.mobility
    }

    /// Integrator parameters.
    pub fn params(&self) -> &HydroBdParams {
        &self.params
    }

    /// Current time `step * dt`.
    pub fn time(&self) -> f64 {
        self.step as f64 * self.params.dt
    }

    /// Lanczos iterations of the last step's square root.
    pub fn last_lanczos_iterations(&self) -> usize {
        self.last_iterations
    }

    /// Neighbour-list builds so far.
    pub fn neighbor_builds(&self) -> u64 {
        self.nlist.builds()
    }

    /// Add `forces` (input order; empty: none) to the systematic forces of every step from
    /// now on, as a further external field would be.
    pub fn set_extra_forces(&mut self, forces: &[[f64; 3]]) -> Result<(), HydroBdError> {
        if !forces.is_empty() && forces.len() != self.particles.len() {
            return Err(HydroBdError::Invalid(format!(
                "{} extra forces for {} particles",
                forces.len(),
                self.particles.len()
            )));
        }
        self.extra.clear();
        self.extra.extend_from_slice(forces);
        Ok(())
    }

    /// Forces on the particles at the current positions and time (into the engine's buffer).
    fn compute_forces(&mut self) {
        let mut f = std::mem::take(&mut self.forces);
        self.forces_into(&mut f);
        self.forces = f;
    }

    /// The systematic (pair and external) forces at the current positions and time, in input
    /// order, without touching the engine's buffers.
    pub fn systematic_forces(&self) -> Vec<[f64; 3]> {
        let mut f = vec![[0.0; 3]; self.particles.len()];
        self.forces_into(&mut f);
        f
    }

    fn forces_into(&self, out: &mut [[f64; 3]]) {
        let t = self.time();
        let p = &self.particles;
        let (pair, external, sbox, nlist) = (&self.pair, &self.external, &self.sbox, &self.nlist);
        let extra = &self.extra;
        out.par_iter_mut()
            .enumerate()
            .with_min_len(256)
            .for_each(|(i, f)| {
                let xi = p.pos[i];
                let mut s = external.force_on(xi, t, p.diameter[i]);
                if let Some(e) = extra.get(i) {
                    s = [s[0] + e[0], s[1] + e[1], s[2] + e[2]];
                }
                for &j in nlist.neighbors(i) {
                    let j = j as usize;
                    let xj = p.pos[j];
                    let d = sbox.min_image([xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]]);
                    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    let fr = pair.force_over_r(
                        r2,
                        p.typeid[i],
                        p.typeid[j],
                        p.diameter[i],
                        p.diameter[j],
                    );
                    for k in 0..3 {
                        s[k] += fr * d[k];
                    }
                }
                *f = s;
            });
    }

    /// Forces on the particles at the current positions and time, in input order.
    pub fn forces(&mut self) -> &[[f64; 3]] {
        self.compute_forces();
        &self.forces
    }

    /// Advance `n` steps (on a worker of the thread pool, as the free-draining engine).
    pub fn run(&mut self, n: u64) -> Result<(), HydroBdError> {
        rayon::scope(|_| (0..n).try_for_each(|_| self.advance()))
    }

    /// Advance one step.
    pub fn advance(&mut self) -> Result<(), HydroBdError> {
        let step = self.step;
        let p = self.params;
        if self.nlist.needs_rebuild(&self.sbox, &self.particles.pos) {
            self.nlist
                .build(&self.sbox, &self.particles.pos, &self.key)?;
        }
        self.compute_forces();
        // The time step must resolve the forces (free-draining drift as the yardstick).
        let (forces, mobility, diameter) = (&self.forces, &self.mobility, &self.particles.diameter);
        let bad = forces
            .par_iter()
            .enumerate()
            .with_min_len(1024)
            .find_first(|(i, f)| {
                let f2 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
                let drift = f2.sqrt() * mobility.stokes_mobility(*i) * p.dt;
                // NaN forces count as a blow-up too.
                drift.is_nan() || drift > p.max_drift * diameter[*i]
            });
        if let Some((i, f)) = bad {
            let force = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
            return Err(HydroBdError::BlowUp {
                step,
                time: self.time(),
                particle: i,
                force,
                drift: force * self.mobility.stokes_mobility(i) * p.dt,
                diameter: self.particles.diameter[i],
            });
        }
        for ((u, x), img) in self
            .unwrapped
            .iter_mut()
            .zip(&self.particles.pos)
            .zip(&self.particles.image)
        {
            *u = self.sbox.unwrap(*x, *img);
        }
        self.mobility.set_positions(&self.unwrapped)?;
        let key = NoiseKey {
            seed: p.seed,
            step,
            key0: (p.replica as u64) << 32,
        };
        let rep = self
            .mobility
            .displacement(&self.forces, p.dt, p.kt, key, &mut self.disp)?;
        self.last_iterations = rep.iterations;
        self.reflect_at_walls((step + 1) as f64 * p.dt);
        let sbox = self.sbox;
        self.particles
            .pos
            .par_iter_mut()
            .zip(self.particles.image.par_iter_mut())
            .zip(self.disp.par_iter())
            .with_min_len(1024)
            .for_each(|((x, img), d)| {
                for k in 0..3 {
                    x[k] += d[k];
                }
                sbox.wrap(x, img);
            });
        self.step += 1;
        Ok(())
    }

    /// Reflect the step's displacements at a hard wall of the external field
    /// ([`External::overshoot`]) along the mobility: the spheres `i` that would end `s_i`
    /// beyond the wall (outward normals `n_i`) get the forces `-lambda_i n_i` whose
    /// displacement `M F` moves each of them `2 s_i` back along its normal, and their
    /// neighbours with them: `sum_j n_i.M_ij n_j lambda_j = 2 s_i`, `lambda >= 0` (the blocks
    /// from [`Mobility::pair_block`]; [`Self::wall_forces`]). For one sphere that is the
    /// mirror image of the step in the metric of `M^-1`, in which the step's noise is isotropic
    /// (reflection along `M n`, the co-normal): it keeps the equilibrium of a mobility that
    /// couples the spheres, where the reflection along `n` alone presses pairs at the wall
    /// together. A sweep can push a neighbour out: repeated while spheres are beyond, at most
    /// [`WALL_SWEEPS`] times, then those still beyond are reflected along `n`.
    fn reflect_at_walls(&mut self, t_end: f64) {
        for sweep in 0..=WALL_SWEEPS {
            self.crossers.clear();
            let p = &self.particles;
            for i in 0..p.len() {
                let (x, d) = (p.pos[i], &mut self.disp[i]);
                let y = [x[0] + d[0], x[1] + d[1], x[2] + d[2]];
                if let Some((s, n)) = self.external.overshoot(y, t_end, p.diameter[i]) {
                    if sweep == WALL_SWEEPS {
                        *d = [
                            d[0] - 2.0 * s * n[0],
                            d[1] - 2.0 * s * n[1],
                            d[2] - 2.0 * s * n[2],
                        ];
                    } else {
                        self.crossers.push((i, s, n));
                    }
                }
            }
            if self.crossers.is_empty() {
                return;
            }
            self.wall_forces();
            self.wall_force.iter_mut().for_each(|f| *f = [0.0; 3]);
            for (&(i, _, n), l) in self.crossers.iter().zip(self.wall_lambda.iter()) {
                self.wall_force[i] = [-l * n[0], -l * n[1], -l * n[2]];
            }
            self.mobility.apply(&self.wall_force, &mut self.wall_disp);
            for (d, w) in self.disp.iter_mut().zip(&self.wall_disp) {
                *d = [d[0] + w[0], d[1] + w[1], d[2] + w[2]];
            }
        }
    }

    /// The `lambda` of [`Self::reflect_at_walls`] for the spheres `(i, s_i, n_i)` beyond the
    /// wall, into `wall_lambda`: `A lambda = 2 s` with `A_ij = n_i.M_ij n_j` (`A_ii` the
    /// Stokes mobility) and `lambda >= 0` (the wall pushes, never pulls), by projected
    /// Gauss–Seidel (the linear complementarity problem of contact mechanics: where the
    /// unconstrained solution is non-negative, it is that solution). Without the bound, two
    /// nearly coincident spheres beyond the wall (`A` near singular) would get huge opposite
    /// forces.
    fn wall_forces(&mut self) {
        let (c, mobility) = (&self.crossers, &self.mobility);
        let m = c.len();
        let dot = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        let a = &mut self.wall_matrix;
        a.clear();
        a.resize(m * m, 0.0);
        for (r, &(i, _, ni)) in c.iter().enumerate() {
            a[r * m + r] = mobility.stokes_mobility(i);
            for (k, &(j, _, nj)) in c.iter().enumerate().take(r) {
                let (e, t) = mobility.pair_block(i, j);
                let v = t.a * dot(ni, nj) + t.b * dot(ni, e) * dot(nj, e);
                (a[r * m + k], a[k * m + r]) = (v, v);
            }
        }
        let lambda = &mut self.wall_lambda;
        lambda.clear();
        lambda.resize(m, 0.0);
        for _ in 0..WALL_SOLVE_SWEEPS {
            let mut change: f64 = 0.0;
            for (r, &(_, s, _)) in c.iter().enumerate() {
                let row = &a[r * m..(r + 1) * m];
                let off: f64 = row
                    .iter()
                    .zip(lambda.iter())
                    .map(|(x, l)| x * l)
                    .sum::<f64>()
                    - row[r] * lambda[r];
                let new = ((2.0 * s - off) / row[r]).max(0.0);
                change = change.max((new - lambda[r]).abs() * row[r] / s.max(f64::MIN_POSITIVE));
                lambda[r] = new;
            }
            if change < WALL_SOLVE_TOLERANCE {
                break;
            }
        }
    }
}

/// Projected Gauss–Seidel sweeps of [`HydroBrownian::wall_forces`] at most, and the relative
/// change of a sphere's push (in units of its overshoot) at which they stop.
const WALL_SOLVE_SWEEPS: usize = 100;
const WALL_SOLVE_TOLERANCE: f64 = 1e-10;

/// Sweeps of [`HydroBrownian::reflect_at_walls`] along the mobility before the spheres still
/// beyond a hard wall are reflected along its normal.
pub const WALL_SWEEPS: usize = 4;
