//! DDFT of the drying droplet on spherical shells (the drying-droplet paper, docs/references.md; paper Eqs. 7–8, 16, 24).
//!
//! `d rho / dt = -(1/r^2) d/dr (r^2 J)`, free-draining flux `J = -D0 rho d/dr(beta delta F/delta rho)`
//! `= -D0 (d rho/dr + rho dw/dr)` with `w = beta mu_ex[rho] + beta V(r, t)`, optionally plus the
//! pairwise RPY flux `J_HI = rho u` ([`super::rpy`]).
//!
//! Numerics: finite volumes on the shells of a [`RadialGrid`], no flux through `r = 0` and the
//! outer face; Scharfetter–Gummel face flux
//! `J_{i+1/2} = (D0/dr) [B(D) rho_i - B(-D) rho_{i+1}]`, `B(z) = z / (e^z - 1)`,
//! `D = w_{i+1} - w_i - u_{i+1/2} dr / D0` (exact for a Boltzmann profile, keeps `rho >= 0`);
//! implicit Euler in time. The nonlinear step is solved as the fixed point of "freeze `w` and `u`
//! at the iterate, solve the linear tridiagonal implicit step", accelerated by Anderson mixing;
//! the accepted density is the last tridiagonal solution, so `N` is conserved to rounding.
//! Steps adapt to the iteration count; `R(t)` enters through `V` at the new time.

use colloidsim_core::param;

use super::rpy::{PairCorrelation, PairTable, RpyKernel};
use super::{DryingSchedule, HarmonicInterface, RadialError, RadialGrid, Rosenfeld};
use crate::anderson::{Anderson, Convention};

/// Hydrodynamic approximation of the flux.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Hydrodynamics {
    /// `M_ij = delta_ij / (6 pi eta a)`.
    FreeDraining,
    /// Free-draining plus the pairwise RPY flux (pair correlation: [`DdftOptions::pair`]).
    Rpy,
}

/// Settings of the DDFT integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DdftOptions {
    /// Bare diffusion coefficient `D0 = kT / (3 pi eta d)`.
    pub d0: f64,
    /// First time step.
    pub dt: f64,
    /// Largest time step (accuracy of implicit Euler is first order in it).
    pub dt_max: f64,
    /// Smallest time step before the run is declared failed.
    pub dt_min: f64,
    /// Per-step tolerance on `max |G(rho) - rho| / max rho`.
    pub tolerance: f64,
    /// Iterations per step attempt before the step is halved.
    pub max_iterations: usize,
    /// Anderson depth (at most 32).
    pub depth: usize,
    /// Hydrodynamic approximation.
    pub hydrodynamics: Hydrodynamics,
    /// Pair correlation in the RPY flux's two-body density (Eq. 17); unused when free-draining.
    pub pair: PairCorrelation,
    /// Tabulation of the Trokhymchuk kernel (range, clamp).
    pub pair_table: PairTable,
    /// Particles where the interface potential exceeds `eject_potential` (kT) count as ejected:
    /// no physical pressure of the compressed suspension reaches that far into the interface.
    pub eject_potential: f64,
    /// Largest allowed ejected fraction of `N` before the solution is declared unphysical.
    pub eject_tolerance: f64,
    /// Cells beyond the point where `beta V` exceeds this are dropped from the computation.
    pub potential_cutoff: f64,
}

impl DdftOptions {
    /// Defaults for a given `D0` and diameter `d`: `dt_max = 0.01 d^2 / D0`.
    pub fn new(d0: f64, diameter: f64) -> Self {
        let tau = diameter * diameter / d0;
        Self {
            d0,
            dt: 1e-4 * tau,
            dt_max: 0.01 * tau,
            dt_min: 1e-10 * tau,
            tolerance: 1e-9,
            max_iterations: 40,
            depth: 6,
            hydrodynamics: Hydrodynamics::FreeDraining,
            pair: PairCorrelation::Dilute,
            pair_table: PairTable::default(),
            eject_potential: 40.0,
            eject_tolerance: 1e-6,
            potential_cutoff: 100.0,
        }
    }

    pub(crate) fn validate(&self) -> Result<(), RadialError> {
        param::positive("d0", self.d0)?;
        param::positive("dt", self.dt)?;
        param::positive("dt_max", self.dt_max)?;
        param::positive("dt_min", self.dt_min)?;
        param::positive("tolerance", self.tolerance)?;
        param::at_least("max_iterations", self.max_iterations, 2)?;
        param::positive("eject_potential", self.eject_potential)?;
        param::positive("eject_tolerance", self.eject_tolerance)?;
        param::positive("potential_cutoff", self.potential_cutoff)?;
        if self.potential_cutoff < self.eject_potential + 20.0 {
            return Err(colloidsim_core::ParamError::new(
                "potential_cutoff",
                format!(
                    "must exceed eject_potential + 20 kT = {} so that ejected particles stay on the grid",
                    self.eject_potential + 20.0
                ),
            )
            .into());
        }
        Ok(())
    }
}

/// What one accepted step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Time after the step.
    pub time: f64,
    /// Step size used.
    pub dt: f64,
    /// Fixed-point iterations of the accepted attempt.
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
}

/// The effective force of the paper's Eq. 16 on a particle at distance `r` from the centre,
/// radial component: `beta F_eff(r) = -d/dr [ln rho + beta mu_ex[rho] + beta V(r, t)]`, the
/// gradient of the local chemical potential, whose free-draining flux is `J = D0 rho F_eff`
/// and which the RPY flux propagates. Zero at equilibrium (constant `beta mu`).
///
/// Discretised as the difference of `ln rho + w` between neighbouring cells over `dr`, at the
/// faces between them (`r`), where the Scharfetter–Gummel flux of [`Ddft`] vanishes exactly
/// when it does; `rho` is the mean of the two cells' densities. Faces run from the first inner
/// face outwards while both cells hold particles and their interface potential stays at most
/// [`DdftOptions::eject_potential`] (beyond, the density is below `e^-40` of the interior and
/// the last kept cell carries the mass of the cells dropped from the computation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EffectiveForce {
    /// Face radii (length).
    pub r: Vec<f64>,
    /// `beta F_eff` at the faces (1 / length; times the diameter: kT / d).
    pub force: Vec<f64>,
    /// Mean density of the two cells of each face (1 / length^3).
    pub rho: Vec<f64>,
}

impl EffectiveForce {
    /// Particle-weighted mean `int rho F dV / int rho dV` over the faces (1 / length). For
    /// free draining it is `(d<r>/dt) / D0`, the drift of the particles' mean distance from
    /// the centre.
    pub fn mean(&self) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for k in 0..self.r.len() {
            let w = self.rho[k] * self.r[k] * self.r[k];
            num += w * self.force[k];
            den += w;
        }
        if den > 0.0 { num / den } else { 0.0 }
    }

    /// Largest `|beta F_eff|` over the faces (1 / length).
    pub fn max_abs(&self) -> f64 {
        self.force.iter().fold(0.0, |m, f| m.max(f.abs()))
    }
}

/// `B(z) = z / (e^z - 1)` (Bernoulli function).
#[inline]
fn bernoulli(z: f64) -> f64 {
    if z.abs() < 1e-5 {
        1.0 - 0.5 * z + z * z / 12.0
    } else {
        z / z.exp_m1()
    }
}

/// Implicit-Euler DDFT state and workspace.
#[derive(Debug, Clone)]
pub struct Ddft {
    grid: RadialGrid,
    fmt: Rosenfeld,
    wall: HarmonicInterface,
    schedule: DryingSchedule,
    opts: DdftOptions,
    rpy: Option<RpyKernel>,
    t: f64,
    dt: f64,
    dt_last: f64,
    active: usize,
    particles: f64,
    steps: usize,
    iterations: usize,
    rho: Vec<f64>,
    rho_prev: Vec<f64>,
    x: Vec<f64>,
    g: Vec<f64>,
    w: Vec<f64>,
    vext: Vec<f64>,
    delta: Vec<f64>,
    flux: Vec<f64>,
    gcell: Vec<f64>,
    u: Vec<f64>,
    lower: Vec<f64>,
    diag: Vec<f64>,
    upper: Vec<f64>,
    cp: Vec<f64>,
    acc: Anderson,
}

impl Ddft {
    /// Start from density `rho0` (cell values on `grid`) at `t = 0`.
    pub fn new(
        grid: RadialGrid,
        diameter: f64,
        wall: HarmonicInterface,
        schedule: DryingSchedule,
        rho0: &[f64],
        opts: DdftOptions,
    ) -> Result<Self, RadialError> {
        opts.validate()?;
        let n = grid.len();
        if rho0.len() != n || rho0.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(colloidsim_core::ParamError::new(
                "initial",
                format!("initial density needs {n} finite values >= 0"),
            )
            .into());
        }
        let fmt = Rosenfeld::new(&grid, diameter)?;
        let rpy = match opts.hydrodynamics {
            Hydrodynamics::Rpy => Some(RpyKernel::with_pair(
                &grid,
                diameter,
                opts.pair,
                opts.pair_table,
            )?),
            Hydrodynamics::FreeDraining => None,
        };
        let particles = grid.integrate(rho0);
        let mut s = Self {
            fmt,
            wall,
            schedule,
            opts,
            rpy,
            t: 0.0,
            dt: opts.dt.min(opts.dt_max),
            dt_last: 0.0,
            active: n,
            particles,
            steps: 0,
            iterations: 0,
            rho: rho0.to_vec(),
            rho_prev: rho0.to_vec(),
            x: vec![0.0; n],
            g: vec![0.0; n],
            w: vec![0.0; n],
            vext: vec![0.0; n],
            delta: vec![0.0; n + 1],
            flux: vec![0.0; n + 1],
            gcell: vec![0.0; n],
            u: vec![0.0; n + 1],
            lower: vec![0.0; n],
            diag: vec![0.0; n],
            upper: vec![0.0; n],
            cp: vec![0.0; n],
            acc: Anderson::new(n, opts.depth, 1.0, Convention::RADIAL),
            grid,
        };
        let r = s.schedule.radius(0.0)?;
        s.set_active(r);
        Ok(s)
    }

    /// Current time.
    pub fn time(&self) -> f64 {
        self.t
    }
    /// Current density at the cell centres.
    pub fn rho(&self) -> &[f64] {
        &self.rho
    }
    /// The grid.
    pub fn grid(&self) -> &RadialGrid {
        &self.grid
    }
    /// Particle number at the start.
    pub fn initial_particles(&self) -> f64 {
        self.particles
    }
    /// Accepted steps so far.
    pub fn steps(&self) -> usize {
        self.steps
    }
    /// Fixed-point iterations so far (all attempts).
    pub fn iterations(&self) -> usize {
        self.iterations
    }
    /// Cells currently computed (the rest hold no particles).
    pub fn active_cells(&self) -> usize {
        self.active
    }

    /// Replace the RPY kernel (e.g. one of [`super::g2::TabulatedPair::kernel`] for the current
    /// stage of a drying run); only with [`Hydrodynamics::Rpy`] and a kernel of this grid.
    pub fn set_rpy_kernel(&mut self, kernel: RpyKernel) -> Result<(), RadialError> {
        if self.rpy.is_none() || kernel.faces() != self.grid.len() + 1 {
            return Err(colloidsim_core::ParamError::new(
                "hydrodynamics",
                format!(
                    "an RPY kernel of {} faces needs RPY hydrodynamics on a grid of {} cells",
                    kernel.faces(),
                    kernel.faces().saturating_sub(1)
                ),
            )
            .into());
        }
        self.rpy = Some(kernel);
        Ok(())
    }

    /// Droplet radius `R(t)` at the current time.
    pub fn radius(&self) -> Result<f64, RadialError> {
        self.schedule.radius(self.t)
    }

    /// `beta mu_ex[rho](r)` of the current density at the cell centres (active cells; 0 beyond).
    pub fn excess_chemical_potential(&mut self) -> Result<Vec<f64>, RadialError> {
        self.fmt
            .evaluate(&self.rho, self.active)
            .map_err(|e| self.at_time(e))?;
        let mut v = self.fmt.mu_ex().to_vec();
        v[self.active..].iter_mut().for_each(|x| *x = 0.0);
        Ok(v)
    }

    /// The effective force `beta F_eff = -d/dr [ln rho + beta mu_ex + beta V]` of the current
    /// density at the current time ([`EffectiveForce`]).
    pub fn effective_force(&mut self) -> Result<EffectiveForce, RadialError> {
        let radius = self.schedule.radius(self.t)?;
        let m = self.active;
        self.fmt
            .evaluate(&self.rho, m)
            .map_err(|e| self.at_time(e))?;
        let mu = self.fmt.mu_ex();
        let centres = self.grid.centres();
        let dr = self.grid.dr();
        let mut v = vec![0.0; m];
        self.wall.fill(&centres[..m], radius, &mut v);
        // Cells with particles, inside the reach of the eject potential (V grows outwards).
        let valid = (0..m)
            .take_while(|&i| self.rho[i] > 0.0 && v[i] <= self.opts.eject_potential)
            .count();
        let mut out = EffectiveForce::default();
        let chem = |i: usize| self.rho[i].ln() + mu[i] + v[i];
        for f in 1..valid {
            out.r.push(self.grid.faces()[f]);
            out.force.push(-(chem(f) - chem(f - 1)) / dr);
            out.rho.push(0.5 * (self.rho[f] + self.rho[f - 1]));
        }
        Ok(out)
    }

    /// Local packing fraction `n3` of the current density at the cell centres.
    pub fn packing_fraction(&mut self) -> Result<Vec<f64>, RadialError> {
        self.fmt
            .evaluate(&self.rho, self.active)
            .map_err(|e| self.at_time(e))?;
        Ok(self.fmt.n3().to_vec())
    }

    fn at_time(&self, e: RadialError) -> RadialError {
        match e {
            RadialError::Unphysical { message, .. } => RadialError::Unphysical {
                time: self.t,
                message,
            },
            other => other,
        }
    }

    /// Shrink the computed domain to where `beta V < potential_cutoff` at radius `radius`; the
    /// (negligible) particles of dropped cells go to the last kept cell, so `N` is unchanged.
    fn set_active(&mut self, radius: f64) {
        let edge = radius + self.wall.offset + self.wall.reach(self.opts.potential_cutoff);
        let n = self.grid.len();
        let new = ((edge / self.grid.dr()).ceil() as usize + 1).clamp(2, n);
        if new < self.active {
            let vol = self.grid.volumes();
            let moved: f64 = (new..self.active).map(|i| vol[i] * self.rho[i]).sum();
            self.rho[new - 1] += moved / vol[new - 1];
            for i in new..self.active {
                self.rho[i] = 0.0;
                self.rho_prev[i] = 0.0;
            }
            self.active = new;
        } else if new > self.active {
            self.active = new;
        }
    }

    /// Advance to exactly `t_end` with adaptive steps; `on_step` sees every accepted step.
    pub fn advance_to(
        &mut self,
        t_end: f64,
        mut on_step: impl FnMut(&StepReport),
    ) -> Result<(), RadialError> {
        while self.t < t_end * (1.0 - 1e-14) {
            let remaining = t_end - self.t;
            let dt = if self.dt >= remaining * (1.0 - 1e-9) {
                remaining
            } else if self.dt > 0.5 * remaining {
                0.5 * remaining
            } else {
                self.dt
            };
            let rep = self.step(dt)?;
            on_step(&rep);
        }
        Ok(())
    }

    /// One accepted step of at most `dt` (halved on failure); updates the step-size controller.
    pub fn step(&mut self, dt: f64) -> Result<StepReport, RadialError> {
        let mut dt = dt;
        loop {
            match self.attempt(dt) {
                Ok((iters, res)) => {
                    let t_new = self.t + dt;
                    std::mem::swap(&mut self.rho, &mut self.rho_prev);
                    self.rho[..self.active].copy_from_slice(&self.g[..self.active]);
                    self.t = t_new;
                    self.dt_last = dt;
                    self.steps += 1;
                    self.check_physical()?;
                    if iters <= 6 {
                        self.dt = (dt * 1.3).min(self.opts.dt_max).max(self.dt);
                    } else if iters > 15 {
                        self.dt = dt * 0.7;
                    }
                    let r = self.schedule.radius(self.t)?;
                    self.set_active(r);
                    return Ok(StepReport {
                        time: self.t,
                        dt,
                        iterations: iters,
                        residual: res,
                    });
                }
                Err(e @ RadialError::Param(_)) => return Err(e),
                Err(e) => {
                    dt *= 0.5;
                    self.dt = dt;
                    if dt < self.opts.dt_min {
                        return Err(match e {
                            RadialError::NotConverged {
                                iterations,
                                residual,
                                tolerance,
                                ..
                            } => RadialError::NotConverged {
                                what: format!(
                                    "implicit Euler step at t = {} (step fell below dt_min = {})",
                                    self.t, self.opts.dt_min
                                ),
                                iterations,
                                residual,
                                tolerance,
                            },
                            other => self.at_time(other),
                        });
                    }
                }
            }
        }
    }

    /// Solve one implicit-Euler step of size `dt` into `self.g`; returns (iterations, residual).
    fn attempt(&mut self, dt: f64) -> Result<(usize, f64), RadialError> {
        let t1 = self.t + dt;
        let radius = self.schedule.radius(t1)?;
        let m = self.active;
        self.wall
            .fill(&self.grid.centres()[..m], radius, &mut self.vext[..m]);
        // Initial guess: linear extrapolation in time.
        let f = if self.steps > 0 && self.dt_last > 0.0 {
            dt / self.dt_last
        } else {
            0.0
        };
        for i in 0..m {
            self.x[i] = (self.rho[i] + f * (self.rho[i] - self.rho_prev[i])).max(0.0);
        }
        self.acc.reset();
        let mut res = f64::INFINITY;
        for it in 1..=self.opts.max_iterations {
            self.picard_image(dt)?;
            let scale = self.g[..m].iter().cloned().fold(0.0, f64::max).max(1e-300);
            res = self.x[..m]
                .iter()
                .zip(&self.g[..m])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
                / scale;
            self.iterations += 1;
            if !res.is_finite() {
                break;
            }
            if res < self.opts.tolerance {
                return Ok((it, res));
            }
            self.acc.step_map(&mut self.x[..m], &self.g[..m]);
            for v in &mut self.x[..m] {
                if *v < 0.0 {
                    *v = 0.0;
                }
            }
        }
        Err(RadialError::NotConverged {
            what: "implicit Euler step".into(),
            iterations: self.opts.max_iterations,
            residual: res,
            tolerance: self.opts.tolerance,
        })
    }

    /// `g = G(x)`: freeze `w[x]` (and `u[x]`), solve the linear implicit step from `rho`.
    fn picard_image(&mut self, dt: f64) -> Result<(), RadialError> {
        let m = self.active;
        let d0 = self.opts.d0;
        let dr = self.grid.dr();
        self.fmt.evaluate(&self.x, m)?;
        let mu = self.fmt.mu_ex();
        for i in 0..m {
            self.w[i] = mu[i] + self.vext[i];
        }
        self.delta[0] = 0.0;
        self.delta[m] = 0.0;
        for f in 1..m {
            self.delta[f] = self.w[f] - self.w[f - 1];
        }
        if let Some(k) = &self.rpy {
            // g_j = rho d_j(beta mu) = -J_free / D0, averaged from the faces onto the cells.
            self.flux[0] = 0.0;
            self.flux[m] = 0.0;
            for f in 1..m {
                let z = self.delta[f];
                let b = bernoulli(z);
                self.flux[f] = (b * self.x[f - 1] - (z + b) * self.x[f]) / dr;
            }
            for j in 0..m {
                self.gcell[j] = -0.5 * (self.flux[j] + self.flux[j + 1]);
            }
            let local = if self.opts.pair.reads_n3() {
                self.fmt.n3()
            } else {
                &self.x[..]
            };
            k.velocities(&self.gcell, local, m, &mut self.u);
            for f in 1..m {
                self.delta[f] -= self.u[f] * dr;
            }
        }
        let vol = self.grid.volumes();
        let area = self.grid.areas();
        let c = d0 / dr;
        for i in 0..m {
            self.diag[i] = vol[i] / dt;
            self.lower[i] = 0.0;
            self.upper[i] = 0.0;
        }
        for f in 1..m {
            // Face between cells f-1 and f: J = c [B(D) rho_{f-1} - B(-D) rho_f].
            let z = self.delta[f];
            let b = bernoulli(z);
            let bm = z + b;
            let a = area[f] * c;
            self.diag[f - 1] += a * b;
            self.upper[f - 1] = -a * bm;
            self.diag[f] += a * bm;
            self.lower[f] = -a * b;
        }
        // Thomas algorithm (column diagonally dominant M-matrix: no pivoting needed).
        let mut beta = self.diag[0];
        self.g[0] = vol[0] / dt * self.rho[0] / beta;
        for i in 1..m {
            self.cp[i - 1] = self.upper[i - 1] / beta;
            beta = self.diag[i] - self.lower[i] * self.cp[i - 1];
            self.g[i] = (vol[i] / dt * self.rho[i] - self.lower[i] * self.g[i - 1]) / beta;
        }
        for i in (0..m - 1).rev() {
            self.g[i] -= self.cp[i] * self.g[i + 1];
        }
        Ok(())
    }

    /// Fraction of the particles at cells where the interface potential exceeds `potential` (kT).
    pub fn fraction_beyond(&self, potential: f64) -> Result<f64, RadialError> {
        let radius = self.schedule.radius(self.t)?;
        let edge = radius + self.wall.offset + self.wall.reach(potential);
        let vol = self.grid.volumes();
        let m = self.active;
        let outside: f64 = (0..m)
            .filter(|&i| self.grid.centres()[i] > edge)
            .map(|i| self.rho[i] * vol[i])
            .sum();
        Ok(outside / self.particles)
    }

    /// Stop on negative density or particles ejected beyond the interface.
    fn check_physical(&self) -> Result<(), RadialError> {
        let m = self.active;
        if let Some(i) = self.rho[..m].iter().position(|v| v.is_nan() || *v < 0.0) {
            return Err(RadialError::Unphysical {
                time: self.t,
                message: format!(
                    "negative or undefined density {} at r = {}",
                    self.rho[i],
                    self.grid.centres()[i]
                ),
            });
        }
        let frac = self.fraction_beyond(self.opts.eject_potential)?;
        if frac > self.opts.eject_tolerance {
            let radius = self.schedule.radius(self.t)?;
            let edge = radius + self.wall.offset + self.wall.reach(self.opts.eject_potential);
            return Err(RadialError::Unphysical {
                time: self.t,
                message: format!(
                    "particles ejected from the droplet: a fraction {frac:.3e} of N lies where the interface potential exceeds {} kT (r > {edge:.4}, R(t) = {radius:.4}); tolerance {:.1e}",
                    self.opts.eject_potential, self.opts.eject_tolerance
                ),
            });
        }
        Ok(())
    }
}
