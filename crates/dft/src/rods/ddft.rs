//! 1D dynamical density functional theory of hard and sticky rods.
//!
//! `d rho/dt = -dJ/dx`, `J = -D [d rho/dx + rho d psi/dx - beta f rho]`, with
//! `psi = mu_ex[rho] + beta U` (`mu_ex = delta beta F_ex / delta rho`, the exact functional of
//! [`super::equilibrium()`]) and a constant drive force `f` (`D beta f` is the free drift velocity,
//! `mu f` with mobility `mu = D / kT`).
//!
//! Finite volumes on the solver grid (control volume `dx` around each point, the same trapezoid
//! weights as the equilibrium normalisation), Scharfetter–Gummel fluxes
//! `J_{i+1/2} = (D/dx) [B(Delta_i) rho_i - B(-Delta_i) rho_{i+1}]`, `B(z) = z / (e^z - 1)`,
//! `Delta_i = psi_{i+1} - psi_i - beta f dx`, and a linearly implicit Euler step (`psi` frozen at the
//! old density, the fluxes implicit in `rho`): one cyclic tridiagonal M-matrix solve per step.
//! The update is in flux form, so the particle number is conserved to rounding; the density stays
//! positive; a stationary state without drive satisfies `ln rho + psi = const` at every grid
//! point, i.e. exactly the discrete structure equation solved by [`super::equilibrium()`].
//! Stability: `psi` is explicit. For hard rods it has only window integrals (smooth), and steps of
//! `10^4 dx^2 / D` are stable. For sticky rods it also depends pointwise on `rho(x)` and
//! `rho(x +- sigma)` (stiffness `c = max D rho (|k0| + |k+| + |k-|)`, `k ~ gamma / (g S)`), which would
//! limit explicit steps to `dx^2 / (2 c)`; the scheme therefore adds the stabilising term
//! `A d^2/dx^2 (rho_new - rho_old)` with `A = max(c, (c^2 - D^2) / (2 D))` (implicit minus explicit:
//! it vanishes in a stationary state, so steady states are unchanged, and it keeps particle
//! conservation; it slows transients on length scales below `sqrt(A dt)`). A step that would
//! make the density negative is split in halves. With [`DdftProblem::step_tolerance`] set, steps
//! are controlled by step doubling (one step of `h` against two of `h/2`; the local error in
//! max-norm relative to `max rho` must stay below the tolerance; the two-half-step result is kept).

use super::functional::{self, Work};
use super::grid::Grid;
use super::{RodsError, RodsProblem};
use colloidsim_core::param::{self, ParamError};

/// Initial density of a DDFT run.
#[derive(Debug, Clone, PartialEq)]
pub enum InitialProfile {
    /// Uniform at the problem's mean density.
    Uniform,
    /// Ideal-gas Boltzmann profile `rho ~ exp(-beta U)` at the problem's mean density.
    Boltzmann,
    /// Values on the grid points ([`RodsProblem::grid_points`]); the particle number is theirs.
    Given(Vec<f64>),
}

/// A DDFT run.
#[derive(Debug, Clone)]
pub struct DdftProblem {
    /// Rods, potential, domain, grid (its `tolerance` and iteration settings are not used).
    pub rods: RodsProblem,
    /// Diffusion coefficient `D` > 0.
    pub diffusion: f64,
    /// Drive `beta f` (constant force over kT, per length); 0 for relaxation to equilibrium.
    pub beta_drive: f64,
    /// Time step (fixed), or the first and largest step when `step_tolerance` is set.
    pub dt: f64,
    /// Adaptive steps by step doubling with this local error tolerance (relative to `max rho`);
    /// `None`: fixed steps of `dt`.
    pub step_tolerance: Option<f64>,
    /// Times at which the density is reported (ascending, >= 0).
    pub output_times: Vec<f64>,
    /// Initial density.
    pub initial: InitialProfile,
}

/// One reported state.
#[derive(Debug, Clone, Copy)]
pub struct DdftFrame<'a> {
    /// Time.
    pub time: f64,
    /// Grid points.
    pub x: &'a [f64],
    /// Density at the grid points.
    pub rho: &'a [f64],
    /// Particle number `sum rho dx`.
    pub particles: f64,
    /// Mean particle current `(1/L) int J dx` (periodic: mean density times mean velocity).
    pub mean_current: f64,
    /// Max-norm over grid points of `ln rho + psi - <ln rho + psi>` (0 in equilibrium; for
    /// driven systems it measures the distance from a Boltzmann-like profile only).
    pub stationarity: f64,
}

/// Summary of a DDFT run.
#[derive(Debug, Clone, PartialEq)]
pub struct DdftSummary {
    /// Time steps done (accepted).
    pub steps: usize,
    /// Steps rejected by the step-size control.
    pub rejected_steps: usize,
    /// Smallest accepted step (excluding steps shortened to hit an output time).
    pub min_step: f64,
    /// Grid spacing used.
    pub dx: f64,
    /// Particle number at t = 0.
    pub particles_initial: f64,
    /// Largest `|N(t) / N(0) - 1|` over all steps.
    pub max_relative_mass_change: f64,
    /// Largest stabilising diffusion coefficient `A` used (0 for hard rods); see the module docs.
    pub max_stabilization: f64,
    /// Mean current at the last time.
    pub final_mean_current: f64,
}

/// Exact stationary current of ideal Brownian particles (no rods' interaction) in the tilted
/// washboard `beta V(x) = (beta_u0 / 2) cos(2 pi x) - beta_f x` of period 1, with diffusion
/// coefficient `diffusion` and mean density `rho` (Risken, *The Fokker–Planck Equation*, Sec. 11.3):
/// `J = rho D (1 - e^{-beta f}) / int_0^1 dx e^{-beta V(x)} int_x^{x+1} e^{beta V(y)} dy`, the
/// double integral by the midpoint rule on 2000 x 2000 points. The limit of short rods' DDFT
/// current; a reference for tests.
pub fn ideal_washboard_current(beta_u0: f64, beta_f: f64, rho: f64, diffusion: f64) -> f64 {
    let n = 2000;
    let h = 1.0 / n as f64;
    let v = |x: f64| 0.5 * beta_u0 * (std::f64::consts::TAU * x).cos() - beta_f * x;
    let mut denom = 0.0;
    for i in 0..n {
        let x = (i as f64 + 0.5) * h;
        let inner: f64 = (0..n)
            .map(|j| (v(x + (j as f64 + 0.5) * h) - v(x)).exp())
            .sum();
        denom += inner * h * h;
    }
    rho * diffusion * (1.0 - (-beta_f).exp()) / denom
}

/// Runs the DDFT of `problem`, calling `on_output` at every requested time.
pub fn ddft(
    problem: &DdftProblem,
    mut on_output: impl FnMut(&DdftFrame<'_>),
) -> Result<DdftSummary, RodsError> {
    let rods = &problem.rods;
    rods.validate()?;
    param::positive("diffusion", problem.diffusion)?;
    param::finite("beta_drive", problem.beta_drive)?;
    param::positive("dt", problem.dt)?;
    if let Some(tol) = problem.step_tolerance {
        param::positive("step_tolerance", tol)?;
    }
    let mut prev = 0.0;
    for (k, &t) in problem.output_times.iter().enumerate() {
        if !(t.is_finite() && t >= prev) {
            return Err(ParamError::new(
                "output_times",
                format!("must be finite, >= 0 and ascending; entry {k} is {t} after {prev}"),
            )
            .into());
        }
        prev = t;
    }
    let grid = rods.grid(rods.dx)?;
    let mut st = Stepper::new(problem, grid)?;
    let n0 = st.particles();
    let mut max_dm: f64 = 0.0;
    let mut t = 0.0;
    let mut steps = 0usize;
    let mut current = 0.0;
    let mut rejected = 0usize;
    let mut h = problem.dt;
    let mut min_step = f64::INFINITY;
    for &t_out in &problem.output_times {
        while t < t_out {
            let remaining = t_out - t;
            let last = remaining <= h * (1.0 + 1e-9);
            let try_h = if last { remaining } else { h };
            let (done, next_h, rej) = match problem.step_tolerance {
                None => (try_h, h, 0),
                Some(tol) => {
                    let r = st.adaptive_step(try_h, tol, problem.dt)?;
                    (r.0, r.1, r.2)
                }
            };
            if problem.step_tolerance.is_none() {
                current = st.step_split(done, 0)?;
            } else {
                current = st.current;
            }
            rejected += rej;
            t = if last && done == try_h {
                t_out
            } else {
                t + done
            };
            if !(last && done == try_h) {
                min_step = min_step.min(done);
            }
            // a step shortened to land on an output time does not shrink the next one
            h = if last && done == try_h {
                h.max(next_h)
            } else {
                next_h
            };
            steps += 1;
            max_dm = max_dm.max((st.particles() / n0 - 1.0).abs());
        }
        let stationarity = st.stationarity()?;
        let act = st.grid.active;
        on_output(&DdftFrame {
            time: t,
            x: &st.x,
            rho: &st.rho[..act],
            particles: st.particles(),
            mean_current: current,
            stationarity,
        });
    }
    Ok(DdftSummary {
        steps,
        rejected_steps: rejected,
        min_step,
        dx: st.grid.dx,
        particles_initial: n0,
        max_relative_mass_change: max_dm,
        max_stabilization: st.max_stab,
        final_mean_current: current,
    })
}

/// Preallocated state of the time stepper.
struct Stepper {
    grid: Grid,
    gamma: f64,
    diffusion: f64,
    beta_drive: f64,
    x: Vec<f64>,
    beta_u: Vec<f64>,
    rho: Vec<f64>,
    work: Work,
    // edge coefficients J_{i+1/2} = a_i rho_i - b_i rho_{i+1}
    ea: Vec<f64>,
    eb: Vec<f64>,
    // cyclic tridiagonal system
    lower: Vec<f64>,
    diag: Vec<f64>,
    upper: Vec<f64>,
    rhs: Vec<f64>,
    z: Vec<f64>,
    cp: Vec<f64>,
    bb: Vec<f64>,
    // step doubling
    save: Vec<f64>,
    full: Vec<f64>,
    current: f64,
    last_current: f64,
    max_stab: f64,
}

impl Stepper {
    fn new(problem: &DdftProblem, grid: Grid) -> Result<Self, RodsError> {
        let rods = &problem.rods;
        let m = grid.m;
        let act = grid.active;
        let mut beta_u = vec![0.0; m];
        rods.sample_potential(&grid, &mut beta_u)?;
        let mut rho = vec![0.0; m];
        let n = rods.particles();
        match &problem.initial {
            InitialProfile::Uniform => {
                rho[..act].fill(n / (act as f64 * grid.dx));
            }
            InitialProfile::Boltzmann => {
                let umin = beta_u[..act].iter().cloned().fold(f64::INFINITY, f64::min);
                for i in 0..act {
                    rho[i] = (umin - beta_u[i]).exp();
                }
                let s: f64 = rho.iter().sum::<f64>() * grid.dx;
                for r in rho.iter_mut() {
                    *r *= n / s;
                }
            }
            InitialProfile::Given(v) => {
                if v.len() != act || v.iter().any(|r| !(r.is_finite() && *r >= 0.0)) {
                    return Err(ParamError::new(
                        "initial",
                        format!(
                            "must give {act} finite values >= 0 (one per grid point), got {} values",
                            v.len()
                        ),
                    )
                    .into());
                }
                rho[..act].copy_from_slice(v);
            }
        }
        let mut work = Work::new(m);
        if functional::excess(&grid, rods.interaction.gamma(), &rho, &mut work).is_err() {
            return Err(ParamError::new(
                "initial",
                "the initial profile overlaps rods (a window of length sigma holds >= 1 rod); \
                 start from a smoother profile, e.g. uniform",
            )
            .into());
        }
        Ok(Self {
            x: (0..act).map(|i| grid.x(i)).collect(),
            gamma: rods.interaction.gamma(),
            diffusion: problem.diffusion,
            beta_drive: problem.beta_drive,
            beta_u,
            rho,
            work,
            ea: vec![0.0; m],
            eb: vec![0.0; m],
            lower: vec![0.0; m],
            diag: vec![0.0; m],
            upper: vec![0.0; m],
            rhs: vec![0.0; m],
            z: vec![0.0; m],
            cp: vec![0.0; m],
            bb: vec![0.0; m],
            save: vec![0.0; m],
            full: vec![0.0; m],
            current: 0.0,
            last_current: 0.0,
            max_stab: 0.0,
            grid,
        })
    }

    fn particles(&self) -> f64 {
        self.rho.iter().sum::<f64>() * self.grid.dx
    }

    fn psi(&mut self) -> Result<(), RodsError> {
        functional::excess(&self.grid, self.gamma, &self.rho, &mut self.work).map_err(|_| {
            RodsError::Ddft(
                "a window of length sigma reached close packing; reduce dt or dx".to_string(),
            )
        })
    }

    /// Stiffness of the explicit pointwise terms of `psi`: `max_x D rho (|k0| + |k+| + |k-|)`,
    /// with `k0, k+-` the derivatives of the pointwise terms of `psi(x)` with respect to `rho(x)`,
    /// `rho(x +- sigma)` at fixed `g` (`~ gamma / (g S)`); 0 for hard rods, whose `psi` has
    /// only window integrals. Explicit steps would need `dt < dx^2 / (2 c)`.
    fn stiffness(&self) -> f64 {
        if self.gamma == 0.0 {
            return 0.0;
        }
        let m = self.grid.m;
        let n = self.grid.n + usize::from(self.grid.f >= 0.5);
        let gamma = self.gamma;
        let w = &self.work;
        // per point y: q = gamma/(g S), r1 = (S - a2)/(a1 + S), r2 = (S - a1)/(a2 + S)
        let pt = |i: usize| -> (f64, f64, f64) {
            let g = w.g[i];
            let (r, rp) = (self.rho[i], w.rho_p[i]);
            let s = (rp + r) / g;
            let d = (rp - r) / g;
            let big_s = (1.0 + gamma * (2.0 * s + gamma * d * d)).sqrt();
            let sg = g.sqrt();
            let (a1s, a2s) = (w.t1[i] / sg, w.t2[i] / sg);
            let q = gamma / (g * big_s);
            (
                q,
                (big_s - (1.0 - gamma * d)) / a1s,
                (big_s - (1.0 + gamma * d)) / a2s,
            )
        };
        let mut cmax: f64 = 0.0;
        for i in 0..self.grid.active {
            let j = (i + m - n % m) % m;
            let (q, r1, _) = pt(i);
            let (qm, _, r2m) = pt(j);
            let k0 = q * r1.abs() + qm * r2m.abs();
            cmax = cmax.max(self.diffusion * self.rho[i] * (k0 + q + qm));
        }
        cmax
    }

    /// `max |ln rho + psi - mean|` over active points.
    fn stationarity(&mut self) -> Result<f64, RodsError> {
        self.psi()?;
        let act = self.grid.active;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 0..act {
            let v = self.rho[i].ln() + self.work.mu_ex[i] + self.beta_u[i];
            lo = lo.min(v);
            hi = hi.max(v);
        }
        Ok(0.5 * (hi - lo))
    }

    /// Step doubling from the current state, trying `h` first. Returns (step done, suggested
    /// next step, rejections); the state advances by the step done.
    fn adaptive_step(
        &mut self,
        mut h: f64,
        tol: f64,
        h_max: f64,
    ) -> Result<(f64, f64, usize), RodsError> {
        let mut rejected = 0;
        self.save.copy_from_slice(&self.rho);
        loop {
            let trial = (|| -> Result<f64, RodsError> {
                self.step(h)?;
                self.full.copy_from_slice(&self.rho);
                self.rho.copy_from_slice(&self.save);
                self.step(0.5 * h)?;
                self.step(0.5 * h)?;
                let scale = self.rho.iter().cloned().fold(0.0, f64::max);
                let mut err: f64 = 0.0;
                for i in 0..self.grid.m {
                    err = err.max((self.rho[i] - self.full[i]).abs());
                }
                Ok(err / scale)
            })();
            match trial {
                Ok(err) if err <= tol => {
                    // first-order scheme: local error ~ h^2
                    let grow = if err > 0.0 {
                        (0.9 * (tol / err).sqrt()).clamp(0.2, 2.0)
                    } else {
                        2.0
                    };
                    self.current = self.last_current;
                    return Ok((h, (h * grow).min(h_max), rejected));
                }
                Ok(err) => {
                    rejected += 1;
                    h *= (0.9 * (tol / err).sqrt()).clamp(0.1, 0.5);
                }
                Err(_) => {
                    rejected += 1;
                    h *= 0.25;
                }
            }
            self.rho.copy_from_slice(&self.save);
            if h < 1e-14 * h_max.max(1.0) {
                return Err(RodsError::Ddft(format!(
                    "step size control failed: step fell to {h:e} (step_tolerance {tol:e})"
                )));
            }
        }
    }

    /// A fixed step of `h`, split into halves (recursively) where a step fails.
    fn step_split(&mut self, h: f64, depth: u32) -> Result<f64, RodsError> {
        self.save.copy_from_slice(&self.rho);
        match self.step(h) {
            Ok(c) => Ok(c),
            Err(e) if depth >= 30 => Err(e),
            Err(_) => {
                self.rho.copy_from_slice(&self.save);
                self.step_split(0.5 * h, depth + 1)?;
                self.step_split(0.5 * h, depth + 1)
            }
        }
    }

    /// One linearly implicit step of length `h`; returns the mean current of the new state.
    fn step(&mut self, h: f64) -> Result<f64, RodsError> {
        self.psi()?;
        // Stabilisation A d^2/dx^2 (rho_new - rho_old) against the explicit pointwise terms
        let stab = {
            let c = self.stiffness();
            let d = self.diffusion;
            if c > 0.0 {
                c.max((c * c - d * d) / (2.0 * d))
            } else {
                0.0
            }
        };
        self.max_stab = self.max_stab.max(stab);
        let m = self.grid.m;
        let act = self.grid.active;
        let dx = self.grid.dx;
        let k = self.diffusion / dx;
        let drift = self.beta_drive * dx;
        for i in 0..m {
            let j = if i + 1 == m { 0 } else { i + 1 };
            // between walls: no flux into or inside the empty gap
            if i + 1 >= act && act < m {
                self.ea[i] = 0.0;
                self.eb[i] = 0.0;
                continue;
            }
            let d = (self.work.mu_ex[j] + self.beta_u[j])
                - (self.work.mu_ex[i] + self.beta_u[i])
                - drift;
            self.ea[i] = k * bernoulli(d);
            self.eb[i] = k * bernoulli(-d);
        }
        let w = dx / h;
        let ks = stab / dx;
        for i in 0..m {
            let im = if i == 0 { m - 1 } else { i - 1 };
            let ip = if i + 1 == m { 0 } else { i + 1 };
            // Laplacian edges share the SG mask (no edges into the gap between walls)
            let sp = if self.ea[i] != 0.0 || self.eb[i] != 0.0 {
                ks
            } else {
                0.0
            };
            let sm = if self.ea[im] != 0.0 || self.eb[im] != 0.0 {
                ks
            } else {
                0.0
            };
            self.lower[i] = -self.ea[im] - sm;
            self.upper[i] = -self.eb[i] - sp;
            self.diag[i] = w + self.ea[i] + self.eb[im] + sp + sm;
            self.rhs[i] = w * self.rho[i]
                - (sp * (self.rho[ip] - self.rho[i]) - sm * (self.rho[i] - self.rho[im]));
        }
        solve_cyclic(
            &self.lower,
            &self.diag,
            &self.upper,
            &mut self.rhs,
            &mut self.z,
            &mut self.cp,
            &mut self.bb,
        );
        let mut lowest: f64 = 0.0;
        let mut highest: f64 = 0.0;
        for i in 0..m {
            lowest = lowest.min(self.rhs[i]);
            highest = highest.max(self.rhs[i]);
        }
        if lowest < -1e-12 * highest || !highest.is_finite() {
            return Err(RodsError::Ddft(format!(
                "the step {h:e} produced a negative density ({lowest:e}); reduce dt"
            )));
        }
        for i in 0..m {
            // M-matrix solve: non-negative up to rounding
            self.rho[i] = self.rhs[i].max(0.0);
        }
        let mut jsum = 0.0;
        for i in 0..m {
            let j = if i + 1 == m { 0 } else { i + 1 };
            jsum += self.ea[i] * self.rho[i] - self.eb[i] * self.rho[j];
        }
        self.last_current = jsum / m as f64;
        Ok(self.last_current)
    }
}

/// `B(z) = z / (e^z - 1)`, `B(0) = 1`.
fn bernoulli(z: f64) -> f64 {
    if z.abs() < 1e-8 {
        1.0 - 0.5 * z
    } else {
        z / z.exp_m1()
    }
}

/// Solves the cyclic tridiagonal system (row i: `lower[i] x[i-1] + diag[i] x[i] + upper[i] x[i+1]`,
/// indices mod n) by Sherman–Morrison; `x` holds the right-hand side on entry, the solution on exit.
fn solve_cyclic(
    lower: &[f64],
    diag: &[f64],
    upper: &[f64],
    x: &mut [f64],
    z: &mut [f64],
    cp: &mut [f64],
    bb: &mut [f64],
) {
    let n = diag.len();
    if n == 1 {
        x[0] /= diag[0] + lower[0] + upper[0];
        return;
    }
    let alpha = lower[0]; // A[0][n-1]
    let beta = upper[n - 1]; // A[n-1][0]
    let gamma = -diag[0];
    bb.copy_from_slice(diag);
    bb[0] = diag[0] - gamma;
    bb[n - 1] = diag[n - 1] - alpha * beta / gamma;
    thomas(lower, bb, upper, x, cp);
    z.fill(0.0);
    z[0] = gamma;
    z[n - 1] = beta;
    thomas(lower, bb, upper, z, cp);
    let fact = (x[0] + alpha * x[n - 1] / gamma) / (1.0 + z[0] + alpha * z[n - 1] / gamma);
    for i in 0..n {
        x[i] -= fact * z[i];
    }
}

/// Thomas algorithm, ignoring `lower[0]` and `upper[n-1]`; `d` is overwritten by the solution.
fn thomas(lower: &[f64], diag: &[f64], upper: &[f64], d: &mut [f64], cp: &mut [f64]) {
    let n = diag.len();
    cp[0] = upper[0] / diag[0];
    d[0] /= diag[0];
    for i in 1..n {
        let den = diag[i] - lower[i] * cp[i - 1];
        cp[i] = upper[i] / den;
        d[i] = (d[i] - lower[i] * d[i - 1]) / den;
    }
    for i in (0..n - 1).rev() {
        d[i] -= cp[i] * d[i + 1];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cyclic_solver_matches_dense_product() {
        let n = 7;
        let lower: Vec<f64> = (0..n).map(|i| -0.3 - 0.01 * i as f64).collect();
        let upper: Vec<f64> = (0..n).map(|i| -0.5 + 0.02 * i as f64).collect();
        let diag: Vec<f64> = (0..n).map(|i| 2.0 + 0.1 * i as f64).collect();
        let xs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() + 1.5).collect();
        let mut b = vec![0.0; n];
        for i in 0..n {
            b[i] = lower[i] * xs[(i + n - 1) % n] + diag[i] * xs[i] + upper[i] * xs[(i + 1) % n];
        }
        let (mut z, mut cp, mut bb) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        solve_cyclic(&lower, &diag, &upper, &mut b, &mut z, &mut cp, &mut bb);
        for i in 0..n {
            assert!((b[i] - xs[i]).abs() < 1e-13, "{i}: {} vs {}", b[i], xs[i]);
        }
    }

    #[test]
    fn bernoulli_is_smooth_through_zero() {
        for &z in &[-1e-6f64, -1e-9, 0.0, 1e-9, 1e-6] {
            let exact = if z == 0.0 { 1.0 } else { z / z.exp_m1() };
            assert!((bernoulli(z) - exact).abs() < 1e-12);
        }
        assert!(bernoulli(800.0) == 0.0 && (bernoulli(-50.0) - 50.0).abs() < 1e-12);
    }
}
