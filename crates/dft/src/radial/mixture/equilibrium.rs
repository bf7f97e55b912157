//! Equilibrium of a hard-sphere mixture at fixed particle numbers `N_s` of each species.
//!
//! Euler–Lagrange equations (discrete): `ln rho_s,i = beta mu_s - beta mu_ex,s,i[rho] - beta V_s,i`,
//! each `beta mu_s` fixed by `sum_i V_i rho_s,i = N_s`; solved as the fixed point in
//! `x = ln rho` of all species together (Picard, Anderson mixing), as
//! [`crate::radial::solve_equilibrium`] for one species.

use colloidsim_core::param;

use super::fmt::MixtureFmt;
use crate::anderson::{Anderson, Convention};
use crate::radial::{EquilibriumOptions, RadialError, RadialGrid};

/// Converged equilibrium of a mixture.
#[derive(Debug, Clone, PartialEq)]
pub struct MixtureEquilibrium {
    /// Densities at the cell centres, species after species (`rho[s * cells + i]`).
    pub rho: Vec<f64>,
    /// Chemical potential `beta mu_s` of each species (`Lambda = 1`).
    pub beta_mu: Vec<f64>,
    /// Final residual `max |Delta ln rho|`.
    pub residual: f64,
    /// Iterations used.
    pub iterations: usize,
}

/// Equilibrium of `particles[s]` spheres of each species in the external potentials `beta_v`
/// (species after species, at the centres); `initial` (same layout) is an optional start,
/// otherwise the ideal-gas profiles. Errors: bad options, a number `<= 0` (naming
/// `particles[s]`), or no convergence (with the residual).
pub fn solve_mixture_equilibrium(
    grid: &RadialGrid,
    fmt: &mut MixtureFmt,
    beta_v: &[f64],
    particles: &[f64],
    initial: Option<&[f64]>,
    opts: &EquilibriumOptions,
) -> Result<MixtureEquilibrium, RadialError> {
    let ns = fmt.species();
    param::positive("tolerance", opts.tolerance)?;
    param::in_range("mixing", opts.mixing, 1e-6, 1.0)?;
    if particles.len() != ns {
        return Err(colloidsim_core::ParamError::new(
            "particles",
            format!(
                "needs one number per species ({ns}), got {}",
                particles.len()
            ),
        )
        .into());
    }
    for (s, &p) in particles.iter().enumerate() {
        param::positive(&format!("particles[{s}]"), p)?;
    }
    let n = grid.len();
    assert_eq!(
        beta_v.len(),
        ns * n,
        "potential of every species at every cell"
    );
    let vol = grid.volumes();
    let mut x = vec![0.0; ns * n];
    let mut g = vec![0.0; ns * n];
    let mut rho = vec![0.0; ns * n];
    let mut w = vec![0.0; n];
    let normalise = |w: &[f64], ln_n: f64, out: &mut [f64]| {
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
    for s in 0..ns {
        let xs = &mut x[s * n..(s + 1) * n];
        match initial {
            Some(r0) => {
                let r0 = &r0[s * n..(s + 1) * n];
                let scale = particles[s] / grid.integrate(r0);
                for i in 0..n {
                    xs[i] = (r0[i] * scale).max(1e-300).ln();
                }
            }
            None => {
                normalise(&beta_v[s * n..(s + 1) * n], particles[s].ln(), xs);
            }
        }
    }
    let mut acc = Anderson::new(ns * n, opts.depth, opts.mixing, Convention::RADIAL);
    let mut residual = f64::INFINITY;
    let mut beta_mu = vec![0.0; ns];
    let mut x_good = x.clone();
    let mut g_good = x.clone();
    let mut damp = 1.0;
    for it in 0..opts.max_iterations {
        for (r, v) in rho.iter_mut().zip(&x) {
            *r = v.exp();
        }
        match fmt.evaluate(&rho, n) {
            Ok(_) => {}
            Err(RadialError::Unphysical { .. }) if it > 0 => {
                damp *= 0.5;
                if damp < 1e-6 {
                    break;
                }
                acc.reset();
                for i in 0..ns * n {
                    x[i] = x_good[i] + damp * (g_good[i] - x_good[i]);
                }
                continue;
            }
            Err(e) => return Err(e),
        }
        for s in 0..ns {
            let mu = fmt.mu_ex(s);
            for i in 0..n {
                w[i] = mu[i] + beta_v[s * n + i];
            }
            beta_mu[s] = normalise(&w, particles[s].ln(), &mut g[s * n..(s + 1) * n]);
        }
        x_good.copy_from_slice(&x);
        g_good.copy_from_slice(&g);
        residual = acc.step_map(&mut x, &g);
        if !residual.is_finite() {
            break;
        }
        if residual < opts.tolerance {
            let rho: Vec<f64> = g_good.iter().map(|v| v.exp()).collect();
            fmt.evaluate(&rho, n)?;
            return Ok(MixtureEquilibrium {
                rho,
                beta_mu,
                residual,
                iterations: it + 1,
            });
        }
        damp = (damp * 2.0).min(1.0);
    }
    Err(RadialError::NotConverged {
        what: "mixture equilibrium (Picard + Anderson)".into(),
        iterations: opts.max_iterations,
        residual,
        tolerance: opts.tolerance,
    })
}
