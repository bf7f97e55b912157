//! DDFT of a hard-sphere mixture on spherical shells: per species
//! `d rho_s / dt = -(1/r^2) d/dr (r^2 J_s)`, free-draining
//! `J_s = -D0_s (d rho_s/dr + rho_s dw_s/dr)`, `w_s = beta mu_ex,s[rho] + beta V_s(r, t)`,
//! optionally plus the pairwise RPY flux `rho_s u_s` of [`super::rpy`] (dilute or dense pair
//! correlations, [`DdftOptions::pair`]).
//!
//! Numerics as [`crate::radial::Ddft`], species by species: Scharfetter–Gummel face fluxes
//! (`D = w_s,i+1 - w_s,i - u_s dr / D0_s`), implicit Euler, each step the fixed point of "freeze
//! every `w_s` (and `u_s`) at the iterate, solve one tridiagonal implicit step per species",
//! accelerated by Anderson mixing over all species; the accepted densities are the last
//! tridiagonal solutions, so each `N_s` is conserved to rounding. The step residual is the largest
//! over species of `max |G(rho_s) - rho_s| / max rho_s`.

use super::fmt::MixtureFmt;
use super::rpy::{MixtureRpy, point_packing};
use crate::anderson::{Anderson, Convention};
use crate::radial::{
    DdftOptions, DryingSchedule, HarmonicInterface, Hydrodynamics, RadialError, RadialGrid,
    StepReport,
};

/// `B(z) = z / (e^z - 1)`.
#[inline]
fn bernoulli(z: f64) -> f64 {
    if z.abs() < 1e-5 {
        1.0 - 0.5 * z + z * z / 12.0
    } else {
        z / z.exp_m1()
    }
}

/// Implicit-Euler DDFT of a mixture (state and workspace).
#[derive(Debug, Clone)]
pub struct MixtureDdft {
    grid: RadialGrid,
    fmt: MixtureFmt,
    d0: Vec<f64>,
    walls: Vec<HarmonicInterface>,
    schedule: DryingSchedule,
    opts: DdftOptions,
    rpy: Option<MixtureRpy>,
    t: f64,
    dt: f64,
    dt_last: f64,
    active: usize,
    particles: Vec<f64>,
    steps: usize,
    iterations: usize,
    rho: Vec<f64>,
    rho_prev: Vec<f64>,
    x: Vec<f64>,
    g: Vec<f64>,
    vext: Vec<f64>,
    delta: Vec<f64>,
    gcell: Vec<f64>,
    xi2: Vec<f64>,
    xi3: Vec<f64>,
    u: Vec<f64>,
    lower: Vec<f64>,
    diag: Vec<f64>,
    upper: Vec<f64>,
    cp: Vec<f64>,
    acc: Anderson,
}

impl MixtureDdft {
    /// Start from `rho0` (species after species, cell values on `grid`) at `t = 0`. `d0[s]` and
    /// `walls[s]` are species `s`'s bare diffusion coefficient and interface; `opts.d0` is not
    /// used; `opts.pair` and `opts.pair_table` choose the RPY flux's pair correlations
    /// ([`super::rpy`]: `TrokhymchukWeighted` reads `xi3 = n3`, `xi2 = sum_s n3_s / d_s`).
    pub fn new(
        grid: RadialGrid,
        fmt: MixtureFmt,
        d0: &[f64],
        walls: &[HarmonicInterface],
        schedule: DryingSchedule,
        rho0: &[f64],
        opts: DdftOptions,
    ) -> Result<Self, RadialError> {
        let mut o = opts;
        o.d0 = d0.iter().cloned().fold(f64::INFINITY, f64::min);
        o.validate()?;
        let ns = fmt.species();
        let n = grid.len();
        if d0.len() != ns || walls.len() != ns {
            return Err(colloidsim_core::ParamError::new(
                "species",
                format!(
                    "{ns} species need {ns} diffusion coefficients and interfaces (got {}, {})",
                    d0.len(),
                    walls.len()
                ),
            )
            .into());
        }
        for (s, &v) in d0.iter().enumerate() {
            colloidsim_core::param::positive(&format!("d0[{s}]"), v)?;
        }
        if rho0.len() != ns * n || rho0.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(colloidsim_core::ParamError::new(
                "initial",
                format!("initial densities need {} finite values >= 0", ns * n),
            )
            .into());
        }
        let rpy = match opts.hydrodynamics {
            Hydrodynamics::FreeDraining => None,
            Hydrodynamics::Rpy => {
                check_stokes(fmt.diameters(), d0, |s| format!("d0[{s}]"))?;
                Some(MixtureRpy::with_pair(
                    &grid,
                    fmt.diameters(),
                    opts.pair,
                    opts.pair_table,
                )?)
            }
        };
        let particles = (0..ns)
            .map(|s| grid.integrate(&rho0[s * n..(s + 1) * n]))
            .collect();
        let mut me = Self {
            fmt,
            d0: d0.to_vec(),
            walls: walls.to_vec(),
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
            x: vec![0.0; ns * n],
            g: vec![0.0; ns * n],
            vext: vec![0.0; ns * n],
            delta: vec![0.0; n + 1],
            gcell: vec![0.0; ns * n],
            xi2: vec![0.0; n],
            xi3: vec![0.0; n],
            u: vec![0.0; n + 1],
            lower: vec![0.0; n],
            diag: vec![0.0; n],
            upper: vec![0.0; n],
            cp: vec![0.0; n],
            acc: Anderson::new(ns * n, opts.depth, 1.0, Convention::RADIAL),
            grid,
        };
        let r = me.schedule.radius(0.0)?;
        me.set_active(r);
        Ok(me)
    }

    /// Current time.
    pub fn time(&self) -> f64 {
        self.t
    }
    /// Densities at the cell centres, species after species.
    pub fn rho(&self) -> &[f64] {
        &self.rho
    }
    /// Density of species `s`.
    pub fn rho_of(&self, s: usize) -> &[f64] {
        let n = self.grid.len();
        &self.rho[s * n..(s + 1) * n]
    }
    /// The grid.
    pub fn grid(&self) -> &RadialGrid {
        &self.grid
    }
    /// Particle numbers at the start.
    pub fn initial_particles(&self) -> &[f64] {
        &self.particles
    }
    /// Accepted steps so far.
    pub fn steps(&self) -> usize {
        self.steps
    }
    /// Fixed-point iterations so far.
    pub fn iterations(&self) -> usize {
        self.iterations
    }
    /// Droplet radius at the current time.
    pub fn radius(&self) -> Result<f64, RadialError> {
        self.schedule.radius(self.t)
    }

    /// The functional evaluated at the current densities (its `n3`, `n3_of`, `mu_ex`).
    pub fn functional_now(&mut self) -> Result<&MixtureFmt, RadialError> {
        let (t, active) = (self.t, self.active);
        self.fmt
            .evaluate(&self.rho, active)
            .map_err(|e| at_time(e, t))?;
        Ok(&self.fmt)
    }

    fn set_active(&mut self, radius: f64) {
        let cutoff = self.opts.potential_cutoff;
        let edge = self
            .walls
            .iter()
            .map(|w| radius + w.offset + w.reach(cutoff))
            .fold(0.0, f64::max);
        let n = self.grid.len();
        let new = ((edge / self.grid.dr()).ceil() as usize + 1).clamp(2, n);
        if new < self.active {
            let vol = self.grid.volumes();
            for s in 0..self.fmt.species() {
                let r = &mut self.rho[s * n..(s + 1) * n];
                let moved: f64 = (new..self.active).map(|i| vol[i] * r[i]).sum();
                r[new - 1] += moved / vol[new - 1];
                for i in new..self.active {
                    r[i] = 0.0;
                    self.rho_prev[s * n + i] = 0.0;
                }
            }
        }
        self.active = new;
    }

    /// Advance to exactly `t_end`; `on_step` sees every accepted step.
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

    /// One accepted step of at most `dt` (halved on failure).
    pub fn step(&mut self, dt: f64) -> Result<StepReport, RadialError> {
        let mut dt = dt;
        loop {
            match self.attempt(dt) {
                Ok((iters, res)) => {
                    std::mem::swap(&mut self.rho, &mut self.rho_prev);
                    self.rho.copy_from_slice(&self.g);
                    self.t += dt;
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
                                    "mixture implicit Euler step at t = {} (step fell below dt_min = {})",
                                    self.t, self.opts.dt_min
                                ),
                                iterations,
                                residual,
                                tolerance,
                            },
                            other => at_time(other, self.t),
                        });
                    }
                }
            }
        }
    }

    fn attempt(&mut self, dt: f64) -> Result<(usize, f64), RadialError> {
        let n = self.grid.len();
        let ns = self.fmt.species();
        let radius = self.schedule.radius(self.t + dt)?;
        let m = self.active;
        for s in 0..ns {
            self.walls[s].fill(
                &self.grid.centres()[..m],
                radius,
                &mut self.vext[s * n..s * n + m],
            );
        }
        let f = if self.steps > 0 && self.dt_last > 0.0 {
            dt / self.dt_last
        } else {
            0.0
        };
        for i in 0..ns * n {
            self.x[i] = (self.rho[i] + f * (self.rho[i] - self.rho_prev[i])).max(0.0);
        }
        self.acc.reset();
        let mut res = f64::INFINITY;
        for it in 1..=self.opts.max_iterations {
            self.picard_image(dt)?;
            res = 0.0f64;
            for s in 0..ns {
                let (xs, gs) = (&self.x[s * n..s * n + m], &self.g[s * n..s * n + m]);
                let scale = gs.iter().cloned().fold(0.0, f64::max).max(1e-300);
                let d = xs
                    .iter()
                    .zip(gs)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                res = res.max(d / scale);
            }
            self.iterations += 1;
            if !res.is_finite() {
                break;
            }
            if res < self.opts.tolerance {
                return Ok((it, res));
            }
            self.acc.step_map(&mut self.x, &self.g);
            for v in &mut self.x {
                if *v < 0.0 {
                    *v = 0.0;
                }
            }
        }
        Err(RadialError::NotConverged {
            what: "mixture implicit Euler step".into(),
            iterations: self.opts.max_iterations,
            residual: res,
            tolerance: self.opts.tolerance,
        })
    }

    /// `g = G(x)`: freeze `w_s[x]` (and `u_s[x]`), solve each species' linear implicit step.
    fn picard_image(&mut self, dt: f64) -> Result<(), RadialError> {
        let n = self.grid.len();
        let ns = self.fmt.species();
        let m = self.active;
        let dr = self.grid.dr();
        self.fmt.evaluate(&self.x, m)?;
        if self.rpy.is_some() {
            // g_s = rho_s d(beta mu_s) = -J_free,s / D0_s on the cells (face mean).
            for s in 0..ns {
                let mu = self.fmt.mu_ex(s);
                let (xs, vs) = (&self.x[s * n..], &self.vext[s * n..]);
                let mut prev = 0.0;
                for c in 0..m {
                    let next = if c + 1 < m {
                        let z = (mu[c + 1] + vs[c + 1]) - (mu[c] + vs[c]);
                        let b = bernoulli(z);
                        (b * xs[c] - (z + b) * xs[c + 1]) / dr
                    } else {
                        0.0
                    };
                    self.gcell[s * n + c] = -0.5 * (prev + next);
                    prev = next;
                }
            }
            let dense = self.rpy.as_ref().is_some_and(|k| k.is_dense());
            if dense && self.opts.pair.reads_n3() {
                self.xi2[..m].iter_mut().for_each(|v| *v = 0.0);
                for (s, d) in self.fmt.diameters().iter().enumerate() {
                    for (x, n3) in self.xi2[..m].iter_mut().zip(self.fmt.n3_of(s)) {
                        *x += n3 / d;
                    }
                }
                self.xi3[..m].copy_from_slice(&self.fmt.n3()[..m]);
            } else if dense {
                point_packing(
                    self.fmt.diameters(),
                    &self.x,
                    n,
                    m,
                    &mut self.xi2,
                    &mut self.xi3,
                );
            }
        }
        let vol = self.grid.volumes();
        let area = self.grid.areas();
        for s in 0..ns {
            let mu = self.fmt.mu_ex(s);
            let vs = &self.vext[s * n..];
            self.delta[0] = 0.0;
            self.delta[m] = 0.0;
            for f in 1..m {
                self.delta[f] = (mu[f] + vs[f]) - (mu[f - 1] + vs[f - 1]);
            }
            if let Some(k) = &self.rpy {
                k.velocities(s, &self.gcell, &self.xi2, &self.xi3, n, m, &mut self.u);
                for f in 1..m {
                    self.delta[f] -= self.u[f] * dr;
                }
            }
            let c = self.d0[s] / dr;
            for i in 0..m {
                self.diag[i] = vol[i] / dt;
                self.lower[i] = 0.0;
                self.upper[i] = 0.0;
            }
            for f in 1..m {
                let z = self.delta[f];
                let b = bernoulli(z);
                let bm = z + b;
                let a = area[f] * c;
                self.diag[f - 1] += a * b;
                self.upper[f - 1] = -a * bm;
                self.diag[f] += a * bm;
                self.lower[f] = -a * b;
            }
            let rho = &self.rho[s * n..];
            let g = &mut self.g[s * n..(s + 1) * n];
            let mut beta = self.diag[0];
            g[0] = vol[0] / dt * rho[0] / beta;
            for i in 1..m {
                self.cp[i - 1] = self.upper[i - 1] / beta;
                beta = self.diag[i] - self.lower[i] * self.cp[i - 1];
                g[i] = (vol[i] / dt * rho[i] - self.lower[i] * g[i - 1]) / beta;
            }
            for i in (0..m - 1).rev() {
                g[i] -= self.cp[i] * g[i + 1];
            }
            g[m..].iter_mut().for_each(|v| *v = 0.0);
        }
        Ok(())
    }

    /// Fraction of species `s` where its interface potential exceeds `potential` (kT).
    pub fn fraction_beyond(&self, s: usize, potential: f64) -> Result<f64, RadialError> {
        let radius = self.schedule.radius(self.t)?;
        let w = &self.walls[s];
        let edge = radius + w.offset + w.reach(potential);
        let vol = self.grid.volumes();
        let r = self.rho_of(s);
        let outside: f64 = (0..self.active)
            .filter(|&i| self.grid.centres()[i] > edge)
            .map(|i| r[i] * vol[i])
            .sum();
        Ok(outside / self.particles[s])
    }

    fn check_physical(&self) -> Result<(), RadialError> {
        let n = self.grid.len();
        for s in 0..self.fmt.species() {
            let r = &self.rho[s * n..s * n + self.active];
            if let Some(i) = r.iter().position(|v| v.is_nan() || *v < 0.0) {
                return Err(RadialError::Unphysical {
                    time: self.t,
                    message: format!(
                        "negative or undefined density {} of species {s} at r = {}",
                        r[i],
                        self.grid.centres()[i]
                    ),
                });
            }
            let frac = self.fraction_beyond(s, self.opts.eject_potential)?;
            if frac > self.opts.eject_tolerance {
                return Err(RadialError::Unphysical {
                    time: self.t,
                    message: format!(
                        "particles of species {s} ejected from the droplet: a fraction {frac:.3e} lies where its interface potential exceeds {} kT (R(t) = {:.4}); tolerance {:.1e}",
                        self.opts.eject_potential,
                        self.schedule.radius(self.t)?,
                        self.opts.eject_tolerance
                    ),
                });
            }
        }
        Ok(())
    }
}

fn at_time(e: RadialError, t: f64) -> RadialError {
    match e {
        RadialError::Unphysical { message, .. } => RadialError::Unphysical { time: t, message },
        other => other,
    }
}

/// Refuse RPY hydrodynamics when the diffusion coefficients are not Stokes' for one viscosity
/// (`D0_s d_s` equal to 1e-9), naming `key(s)`.
pub fn check_stokes(
    diameters: &[f64],
    d0: &[f64],
    key: impl Fn(usize) -> String,
) -> Result<(), RadialError> {
    let c0 = d0[0] * diameters[0];
    for s in 1..d0.len() {
        let c = d0[s] * diameters[s];
        if ((c - c0) / c0).abs() > 1e-9 {
            return Err(colloidsim_core::ParamError::new(
                key(s),
                format!(
                    "the RPY flux needs Stokes mobilities of one viscosity, D0 proportional to 1/d: D0 d = {c} differs from species 0's {c0}"
                ),
            )
            .into());
        }
    }
    Ok(())
}
