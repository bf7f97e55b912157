//! Equilibrium density at fixed particle number in a static droplet.
//!
//! Minimises `beta Omega = beta F_id + beta F_ex + int rho beta V - beta mu N` with the chemical
//! potential as the Lagrange multiplier of `N`. Euler–Lagrange equation (discrete):
//! `ln rho_i = beta mu - beta mu_ex,i[rho] - beta V_i`, `beta mu` fixed by `sum_i V_i rho_i = N`.
//! Solved as a fixed point in `x = ln rho` (Picard) accelerated by Anderson mixing.

use colloidsim_core::param;

use super::{RadialError, RadialGrid, Rosenfeld};
use crate::anderson::{Anderson, Convention};

/// Settings of the equilibrium solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EquilibriumOptions {
    /// Stop when `max_i |ln rho_i^new - ln rho_i| < tolerance`.
    pub tolerance: f64,
    /// Iteration limit; exceeding it is an error that reports the residual.
    pub max_iterations: usize,
    /// Anderson depth (0: damped Picard; at most 32).
    pub depth: usize,
    /// Anderson damping in (0, 1].
    pub mixing: f64,
}

impl Default for EquilibriumOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 3000,
            depth: 8,
            mixing: 0.1,
        }
    }
}

/// Converged equilibrium profile.
#[derive(Debug, Clone, PartialEq)]
pub struct Equilibrium {
    /// Density at the cell centres.
    pub rho: Vec<f64>,
    /// Local packing fraction `n3` at the cell centres.
    pub n3: Vec<f64>,
    /// Chemical potential `beta mu` (with `Lambda = 1`).
    pub beta_mu: f64,
    /// Final residual `max |Delta ln rho|`.
    pub residual: f64,
    /// Iterations used.
    pub iterations: usize,
}

/// Equilibrium of `particles` hard spheres in the external potential `beta_v` (at the centres).
///
/// `initial` (optional) is a starting density; otherwise the ideal-gas profile. Errors: bad
/// options, `particles <= 0`, or no convergence within `max_iterations` (with the residual).
pub fn solve_equilibrium(
    grid: &RadialGrid,
    fmt: &mut Rosenfeld,
    beta_v: &[f64],
    particles: f64,
    initial: Option<&[f64]>,
    opts: &EquilibriumOptions,
) -> Result<Equilibrium, RadialError> {
    param::positive("particles", particles)?;
    param::positive("tolerance", opts.tolerance)?;
    param::in_range("mixing", opts.mixing, 1e-6, 1.0)?;
    let n = grid.len();
    assert_eq!(beta_v.len(), n, "potential must be given at every cell");
    let vol = grid.volumes();
    let ln_n = particles.ln();
    let mut x = vec![0.0; n];
    let mut g = vec![0.0; n];
    let mut rho = vec![0.0; n];
    let mut w = vec![0.0; n];
    // G(x): the Picard map, normalised to N.
    let normalise = |w: &[f64], out: &mut [f64]| {
        let wmin = w.iter().cloned().fold(f64::INFINITY, f64::min);
        let z: f64 = w
            .iter()
            .zip(vol)
            .map(|(wi, v)| v * (-(wi - wmin)).exp())
            .sum();
        let c = ln_n - z.ln() + wmin;
        for (o, wi) in out.iter_mut().zip(w) {
            *o = c - wi;
        }
        c
    };
    match initial {
        Some(r0) => {
            let s = particles / grid.integrate(r0);
            for i in 0..n {
                x[i] = (r0[i] * s).max(1e-300).ln();
            }
        }
        None => {
            normalise(beta_v, &mut x);
        }
    }
    let mut acc = Anderson::new(n, opts.depth, opts.mixing, Convention::RADIAL);
    let mut residual = f64::INFINITY;
    let mut beta_mu = 0.0;
    let mut x_good = x.clone();
    let mut g_good = x.clone();
    let mut damp = 1.0;
    for it in 0..opts.max_iterations {
        for i in 0..n {
            rho[i] = x[i].exp();
        }
        match fmt.evaluate(&rho, n) {
            Ok(_) => {}
            Err(RadialError::Unphysical { .. }) if it > 0 => {
                // Overshoot into n3 >= 1: restart mixing from a damped step of the last good state.
                damp *= 0.5;
                if damp < 1e-6 {
                    break;
                }
                acc.reset();
                for i in 0..n {
                    x[i] = x_good[i] + damp * (g_good[i] - x_good[i]);
                }
                continue;
            }
            Err(e) => return Err(e),
        }
        for i in 0..n {
            w[i] = fmt.mu_ex()[i] + beta_v[i];
        }
        beta_mu = normalise(&w, &mut g);
        x_good.copy_from_slice(&x);
        g_good.copy_from_slice(&g);
        residual = acc.step_map(&mut x, &g);
        if !residual.is_finite() {
            break;
        }
        if residual < opts.tolerance {
            // Return the last Picard image: exactly normalised.
            let rho: Vec<f64> = g_good.iter().map(|v| v.exp()).collect();
            fmt.evaluate(&rho, n)?;
            log::debug!("equilibrium converged in {} iterations", it + 1);
            return Ok(Equilibrium {
                n3: fmt.n3().to_vec(),
                rho,
                beta_mu,
                residual,
                iterations: it + 1,
            });
        }
        damp = (damp * 2.0).min(1.0);
    }
    let _ = beta_mu;
    Err(RadialError::NotConverged {
        what: "equilibrium (Picard + Anderson)".into(),
        iterations: opts.max_iterations,
        residual,
        tolerance: opts.tolerance,
    })
}
