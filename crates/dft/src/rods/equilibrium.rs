//! Direct solution of the structure equation at fixed mean density.
//!
//! Unknown `u = ln rho` on the grid. One Picard map is
//! `G(u) = beta mu - beta U - mu_ex[e^u]`, with `beta mu` the Lagrange multiplier that gives
//! `int e^{G(u)} = N` (trapezoid rule); the residual is `r = G(u) - u`, i.e. the structure equation
//! `ln rho + mu_ex + beta U - beta mu = 0` (Eq. 35a; Percus at `gamma = 0`) in `ln rho` form.
//! Anderson mixing accelerates the map; steps that would overlap rods (a window integral of `rho`
//! reaching 1) are halved. Grid sequencing: the problem is first solved on grids coarser by powers
//! of two and the solution interpolated as the starting guess.

use super::functional::{self, Overlap, Work};
use super::grid::Grid;
use super::{BetaPotential, RodsError, RodsProblem};
use crate::anderson::{Anderson, Convention};
use colloidsim_core::param::{self, ParamError};

/// The equilibrium profile and its diagnostics.
#[derive(Debug, Clone)]
pub struct Equilibrium {
    /// Grid points (rod centres): `i dx` on `[0, period)`, or `[sigma/2, length - sigma/2]`.
    pub x: Vec<f64>,
    /// Density `rho(x)`; `int rho = N` to within the residual.
    pub rho: Vec<f64>,
    /// Two-particle density at contact `rho2(x, x + sigma^+)` (left rod at `x`): Eq. (24) for hard
    /// rods; for sticky rods the regular part just outside contact, `K(x+sigma) K_hat(x) (1 - eta(x+sigma))`.
    pub contact_density: Vec<f64>,
    /// Sticky rods only: density of bonded pairs with the left rod at `x` (weight of the
    /// `gamma delta(r - sigma)` term), `gamma` times [`Equilibrium::contact_density`].
    pub bonded_pair_density: Option<Vec<f64>>,
    /// Chemical potential `beta mu` (thermal wavelength 1).
    pub beta_mu: f64,
    /// Iterations on the finest grid.
    pub iterations: usize,
    /// Iterations on all grids (coarse ones included).
    pub total_iterations: usize,
    /// Number of grids used (1 = no grid sequencing).
    pub levels: usize,
    /// Final residual: max-norm of the structure equation in `ln rho` form.
    pub residual: f64,
    /// Tolerance that was asked for (`residual < tolerance`).
    pub tolerance: f64,
    /// Grid spacing actually used.
    pub dx: f64,
    grid: Grid,
    rho_full: Vec<f64>,
    contact_full: Vec<f64>,
    gamma: f64,
}

/// The diagnostics of an [`Equilibrium`], ready for `summary.json`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct EquilibriumSummary {
    /// Always true for a returned [`Equilibrium`] (non-convergence is an error).
    pub converged: bool,
    /// Max-norm of the structure equation in `ln rho` form at the returned profile.
    pub residual: f64,
    /// Tolerance asked for.
    pub tolerance: f64,
    /// Iterations on the finest grid.
    pub iterations: usize,
    /// Iterations on all grids.
    pub total_iterations: usize,
    /// Grids used (grid sequencing).
    pub levels: usize,
    /// Grid spacing used.
    pub dx: f64,
    /// Number of grid points carrying density.
    pub grid_points: usize,
    /// Chemical potential `beta mu` (thermal wavelength 1).
    pub beta_mu: f64,
}

/// An [`Equilibrium`] averaged over histogram bins (the same bins as a simulation's).
#[derive(Debug, Clone, PartialEq)]
pub struct BinnedProfile {
    /// Bin centres.
    pub centres: Vec<f64>,
    /// Bin averages of `rho`.
    pub rho: Vec<f64>,
    /// Bin averages of the contact density.
    pub contact_density: Vec<f64>,
    /// Bin averages of the bonded-pair density (sticky rods).
    pub bonded_pair_density: Option<Vec<f64>>,
}

impl Equilibrium {
    /// Diagnostics for `summary.json`.
    pub fn summary(&self) -> EquilibriumSummary {
        EquilibriumSummary {
            converged: self.residual < self.tolerance,
            residual: self.residual,
            tolerance: self.tolerance,
            iterations: self.iterations,
            total_iterations: self.total_iterations,
            levels: self.levels,
            dx: self.dx,
            grid_points: self.x.len(),
            beta_mu: self.beta_mu,
        }
    }

    /// Averages over `bins` equal bins covering `[0, over]` (e.g. the simulation box or one
    /// period; periodic profiles are continued periodically, profiles between walls are zero
    /// outside `[sigma/2, length - sigma/2]`). Each value is the exact average of the piecewise-linear
    /// profile over the bin, so theory and a histogram (paper Eqs. 26, 27) share a grid.
    pub fn bin_average(&self, bins: usize, over: f64) -> Result<BinnedProfile, RodsError> {
        param::at_least("bins", bins, 1)?;
        param::positive("over", over)?;
        let g = &self.grid;
        let width = over / bins as f64;
        let mut cum = vec![0.0; g.m + 1];
        let mut avg = |h: &[f64]| -> Vec<f64> {
            g.prefix(h, &mut cum);
            (0..bins)
                .map(|k| g.average(h, &cum, k as f64 * width, (k + 1) as f64 * width))
                .collect()
        };
        let rho = avg(&self.rho_full);
        let contact = avg(&self.contact_full);
        let bonded = (self.gamma > 0.0).then(|| contact.iter().map(|c| self.gamma * c).collect());
        Ok(BinnedProfile {
            centres: (0..bins).map(|k| (k as f64 + 0.5) * width).collect(),
            rho,
            contact_density: contact,
            bonded_pair_density: bonded,
        })
    }

    /// What the window estimator of the contact density (hard-rods paper Eq. 27: a rod at `x`
    /// whose right neighbour lies within `[x + sigma, x + sigma + window)`, divided by `window`)
    /// reads in exact equilibrium, averaged over the same bins as [`Self::bin_average`]; hard
    /// rods only (`None` for sticky ones).
    ///
    /// The nearest-neighbour density of hard rods in a field (grand canonical) is
    /// `n(x, y) = rho(x) a(y) exp(-int_{x+sigma}^{y} a)`, `y >= x + sigma`, with
    /// `a = rho / (1 - eta)` and `eta(y) = int_{y-sigma}^{y} rho` (the configurations left of a
    /// rod and right of the next are independent; `ln R(s)`, the weight of the rods right of `s`,
    /// falls at the rate `a(s)`). Its integral over the window is
    /// `rho(x) (1 - exp(-int_{x+sigma}^{x+sigma+window} a)) / window`, which tends to Eq. 24 as
    /// `window -> 0` and is the Tonks gas' `rho (1 - e^{-a w}) / w` without a field. Canonical
    /// runs of N rods read about `(N - 1) / N` of it (exact for the Tonks gas on a ring).
    pub fn window_contact_average(
        &self,
        bins: usize,
        over: f64,
        window: f64,
    ) -> Result<Option<Vec<f64>>, RodsError> {
        param::at_least("bins", bins, 1)?;
        param::positive("over", over)?;
        param::positive("window", window)?;
        if self.gamma > 0.0 {
            return Ok(None);
        }
        let g = &self.grid;
        let rho = &self.rho_full;
        let mut cum = vec![0.0; g.m + 1];
        let mut eta = vec![0.0; g.m];
        g.prefix(rho, &mut cum);
        g.window_backward(rho, &cum, &mut eta);
        let a: Vec<f64> = rho
            .iter()
            .zip(&eta)
            .map(|(&r, &e)| {
                if r > 0.0 {
                    r / (1.0 - e).max(f64::MIN_POSITIVE)
                } else {
                    0.0
                }
            })
            .collect();
        let mut cum_a = vec![0.0; g.m + 1];
        g.prefix(&a, &mut cum_a);
        let sigma = (g.n as f64 + g.f) * g.dx;
        let windowed: Vec<f64> = (0..g.m)
            .map(|i| {
                let start = g.x(i) + sigma;
                let integral = window * g.average(&a, &cum_a, start, start + window);
                rho[i] * (-(-integral).exp_m1()) / window
            })
            .collect();
        let width = over / bins as f64;
        let mut cum_w = vec![0.0; g.m + 1];
        g.prefix(&windowed, &mut cum_w);
        Ok(Some(
            (0..bins)
                .map(|k| g.average(&windowed, &cum_w, k as f64 * width, (k + 1) as f64 * width))
                .collect(),
        ))
    }
}

/// Solves for the equilibrium profile of `problem` (validated first). Errors: invalid parameters,
/// or [`RodsError::NotConverged`] with the residual reached; an `Ok` result always has
/// `residual < tolerance`.
pub fn equilibrium(problem: &RodsProblem) -> Result<Equilibrium, RodsError> {
    problem.validate()?;
    match solve_levels(problem) {
        Err(RodsError::NotConverged { iterations, .. })
            if problem.anderson_memory < ROBUST_MEMORY || problem.mixing > ROBUST_MIXING =>
        {
            // Strongly layered or nearly jammed states: once more with a longer history and
            // smaller mixing (slower per iteration, but converges in more of these states).
            log::debug!(
                "rods: retrying with Anderson memory {ROBUST_MEMORY}, mixing {ROBUST_MIXING}"
            );
            let mut robust = problem.clone();
            robust.anderson_memory = problem.anderson_memory.max(ROBUST_MEMORY);
            robust.mixing = problem.mixing.min(ROBUST_MIXING);
            match solve_levels(&robust) {
                Ok(mut eq) => {
                    eq.total_iterations += iterations;
                    Ok(eq)
                }
                Err(RodsError::NotConverged {
                    iterations: it2,
                    residual,
                    tolerance,
                    min_vacancy,
                }) => Err(RodsError::NotConverged {
                    iterations: iterations + it2,
                    residual,
                    tolerance,
                    min_vacancy,
                }),
                Err(e) => Err(e),
            }
        }
        other => other,
    }
}

/// Anderson settings of the second attempt.
const ROBUST_MEMORY: usize = 40;
const ROBUST_MIXING: f64 = 0.1;

/// Grid sequencing and the solve on every level.
fn solve_levels(problem: &RodsProblem) -> Result<Equilibrium, RodsError> {
    let gamma = problem.interaction.gamma();
    let fine = problem.grid(problem.dx)?;
    // Grid sequencing: coarser grids by factors of 2 while sigma/dx >= 20 and >= 1024 active points.
    let mut levels = vec![fine.clone()];
    if !matches!(problem.beta_u, BetaPotential::OnGrid(_)) {
        loop {
            let last = levels.last().expect("non-empty");
            let dx = 2.0 * last.dx;
            if problem.sigma / dx < 2.0 * super::MIN_POINTS_PER_SIGMA || last.active < 1024 {
                break;
            }
            match problem.grid(dx) {
                Ok(g) => levels.push(g),
                Err(_) => break,
            }
        }
    }
    levels.reverse();
    let n_levels = levels.len();
    let mut u_prev: Option<(Grid, Vec<f64>)> = None;
    let mut total = 0;
    for (l, grid) in levels.into_iter().enumerate() {
        let last = l + 1 == n_levels;
        let mut solver = Solver::new(problem, grid, gamma)?;
        match &u_prev {
            None => solver.uniform_start(),
            Some((g, u)) => solver.interpolate_start(g, u),
        }
        let (tol, max_it) = if last {
            (problem.tolerance, problem.max_iterations)
        } else {
            // a coarse level that struggles is abandoned early (the fine level then starts cold)
            (
                problem.tolerance.max(1e-8),
                problem.max_iterations.min(1000),
            )
        };
        let out = solver.iterate(problem, tol, max_it);
        match out {
            Ok((it, res, beta_mu)) => {
                total += it;
                if last {
                    return Ok(solver.finish(it, total, n_levels, res, beta_mu, problem.tolerance));
                }
                u_prev = Some((solver.grid.clone(), solver.u.clone()));
            }
            Err(e) => {
                // A coarse grid may fail where the fine one converges: restart the fine one cold.
                if last || !matches!(e, RodsError::NotConverged { .. }) {
                    return Err(e);
                }
                if let RodsError::NotConverged { iterations, .. } = e {
                    total += iterations;
                }
                log::debug!("rods: coarse level {l} did not converge ({e}); continuing");
                u_prev = None;
            }
        }
    }
    unreachable!("the finest level returns")
}

/// State of the iteration on one grid.
struct Solver {
    grid: Grid,
    gamma: f64,
    particles: f64,
    beta_u: Vec<f64>,
    u: Vec<f64>,
    u_ok: Vec<f64>,
    rho: Vec<f64>,
    r: Vec<f64>,
    work: Work,
}

impl Solver {
    fn new(problem: &RodsProblem, grid: Grid, gamma: f64) -> Result<Self, RodsError> {
        let m = grid.m;
        let mut beta_u = vec![0.0; m];
        problem.sample_potential(&grid, &mut beta_u)?;
        Ok(Self {
            gamma,
            particles: problem.particles(),
            beta_u,
            u: vec![0.0; m],
            u_ok: vec![0.0; m],
            rho: vec![0.0; m],
            r: vec![0.0; m],
            work: Work::new(m),
            grid,
        })
    }

    fn uniform_start(&mut self) {
        let rho0 = self.particles / (self.grid.active as f64 * self.grid.dx);
        self.u.fill(rho0.ln());
    }

    /// Start between walls when the uniform density overlaps: `k = floor(length / sigma)` (the
    /// most rods that fit) narrow peaks spread evenly over the centre range, each holding N/k < 1.
    fn peaked_start(&mut self, sigma: f64) {
        let act = self.grid.active;
        let span = (act - 1) as f64 * self.grid.dx;
        let k = ((span / sigma).floor() as usize + 1).max(1);
        let spacing = if k > 1 { span / (k - 1) as f64 } else { span };
        let w = ((spacing - sigma) / 6.0)
            .max(2.0 * self.grid.dx)
            .min(sigma / 4.0);
        let x0 = self.grid.x(0);
        let dx = self.grid.dx;
        self.rho[..act].fill(0.0);
        // each peak (half peaks at the walls included) holds N/k
        for p in 0..k {
            let c = if k > 1 {
                p as f64 * spacing
            } else {
                0.5 * span
            };
            let z = |i: usize| (self.grid.x(i) - x0 - c) / w;
            let mass: f64 = (0..act).map(|i| (-0.5 * z(i) * z(i)).exp()).sum::<f64>() * dx;
            let scale = self.particles / k as f64 / mass;
            for i in 0..act {
                self.rho[i] += scale * (-0.5 * z(i) * z(i)).exp();
            }
        }
        let floor = 1e-12 * self.particles / span.max(dx);
        for i in 0..act {
            self.u[i] = (self.rho[i] + floor).ln();
        }
    }

    /// Linear interpolation of a coarser solution (by position; clamped at walls).
    fn interpolate_start(&mut self, gc: &Grid, uc: &[f64]) {
        let periodic = gc.active == gc.m;
        for i in 0..self.grid.active {
            let s = (self.grid.x(i) - gc.x0) / gc.dx;
            let v = if periodic {
                let k = s.floor();
                let t = s - k;
                let j = (k as isize).rem_euclid(gc.m as isize) as usize;
                let j1 = (j + 1) % gc.m;
                (1.0 - t) * uc[j] + t * uc[j1]
            } else {
                let s = s.clamp(0.0, (gc.active - 1) as f64);
                let j = (s.floor() as usize).min(gc.active.saturating_sub(2));
                let t = s - j as f64;
                if gc.active == 1 {
                    uc[0]
                } else {
                    (1.0 - t) * uc[j] + t * uc[j + 1]
                }
            };
            self.u[i] = v;
        }
    }

    /// Evaluates the map at `self.u`: fills `self.r`, returns `(beta mu, max |r|)`.
    fn eval(&mut self) -> Result<(f64, f64), Overlap> {
        let act = self.grid.active;
        for i in 0..act {
            self.rho[i] = self.u[i].exp();
        }
        self.rho[act..].fill(0.0);
        functional::excess(&self.grid, self.gamma, &self.rho, &mut self.work)?;
        // v = -beta U - mu_ex, kept in r for now
        let mut vmax = f64::NEG_INFINITY;
        for i in 0..act {
            let v = -self.beta_u[i] - self.work.mu_ex[i];
            self.r[i] = v;
            vmax = vmax.max(v);
        }
        if !vmax.is_finite() {
            return Err(Overlap);
        }
        let mut sum = 0.0;
        for i in 0..act {
            sum += (self.r[i] - vmax).exp();
        }
        let beta_mu = self.particles.ln() - vmax - (sum * self.grid.dx).ln();
        let mut res: f64 = 0.0;
        for i in 0..act {
            let ri = beta_mu + self.r[i] - self.u[i];
            self.r[i] = ri;
            res = res.max(ri.abs());
        }
        self.r[act..].fill(0.0);
        if !res.is_finite() {
            return Err(Overlap);
        }
        Ok((beta_mu, res))
    }

    /// Anderson-accelerated Picard iteration from `self.u`. Returns (iterations, residual, beta mu).
    fn iterate(
        &mut self,
        problem: &RodsProblem,
        tol: f64,
        max_it: usize,
    ) -> Result<(usize, f64, f64), RodsError> {
        let mut anderson = Anderson::new(
            self.grid.m,
            problem.anderson_memory,
            problem.mixing,
            Convention::RODS,
        );
        let mut best = f64::INFINITY;
        let mut have_ok = false;
        let mut tried_peaks = false;
        let mut it = 0;
        // Mixing adapted to the state: halved after a step that overlaps rods, regrown by 10% per
        // iteration that lowers the residual.
        let mut beta = problem.mixing;
        let mut prev_res = f64::INFINITY;
        let mut overlaps_in_row = 0;
        loop {
            match self.eval() {
                Ok((beta_mu, res)) => {
                    best = best.min(res);
                    if res < tol {
                        return Ok((it, res, beta_mu));
                    }
                    if it >= max_it {
                        return Err(RodsError::NotConverged {
                            iterations: it,
                            residual: res,
                            tolerance: tol,
                            min_vacancy: self.work.g.iter().cloned().fold(1.0, f64::min),
                        });
                    }
                    self.u_ok.copy_from_slice(&self.u);
                    have_ok = true;
                    overlaps_in_row = 0;
                    if res < prev_res && beta < problem.mixing {
                        beta = (1.1 * beta).min(problem.mixing);
                        anderson.set_beta(beta);
                    }
                    prev_res = res;
                    anderson.step(&mut self.u, &self.r);
                }
                Err(Overlap) => {
                    if !have_ok && !tried_peaks && self.grid.active < self.grid.m {
                        // dense box: start from separated peaks instead of the uniform density
                        tried_peaks = true;
                        self.peaked_start(problem.sigma);
                        continue;
                    }
                    if !have_ok {
                        return Err(ParamError::new(
                            "mean_density",
                            format!(
                                "no admissible starting profile: the uniform density {} overlaps \
                                 rods of length {} in this domain (and separated peaks too); \
                                 the state is too close to jamming for this grid",
                                self.particles / (self.grid.active as f64 * self.grid.dx),
                                problem.sigma
                            ),
                        )
                        .into());
                    }
                    if it >= max_it {
                        return Err(RodsError::NotConverged {
                            iterations: it,
                            residual: best,
                            tolerance: tol,
                            min_vacancy: 0.0,
                        });
                    }
                    // Halve the step back towards the last admissible iterate and the mixing;
                    // forget the history only if that keeps failing.
                    for i in 0..self.grid.m {
                        self.u[i] = 0.5 * (self.u[i] + self.u_ok[i]);
                    }
                    beta = (0.5 * beta).max(1e-3);
                    anderson.set_beta(beta);
                    overlaps_in_row += 1;
                    if overlaps_in_row >= 3 {
                        anderson.reset();
                    }
                }
            }
            it += 1;
        }
    }

    fn finish(
        mut self,
        iterations: usize,
        total_iterations: usize,
        levels: usize,
        residual: f64,
        beta_mu: f64,
        tolerance: f64,
    ) -> Equilibrium {
        let act = self.grid.active;
        let mut contact = vec![0.0; self.grid.m];
        functional::contact(&self.rho, &self.work, &mut contact);
        contact[act..].fill(0.0);
        let rho_full = std::mem::take(&mut self.rho);
        let gamma = self.gamma;
        Equilibrium {
            x: (0..act).map(|i| self.grid.x(i)).collect(),
            rho: rho_full[..act].to_vec(),
            contact_density: contact[..act].to_vec(),
            bonded_pair_density: (gamma > 0.0)
                .then(|| contact[..act].iter().map(|c| gamma * c).collect()),
            beta_mu,
            iterations,
            total_iterations,
            levels,
            residual,
            tolerance,
            dx: self.grid.dx,
            grid: self.grid,
            rho_full,
            contact_full: contact,
            gamma,
        }
    }
}
