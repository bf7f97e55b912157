//! One-body excess chemical potential `mu_ex(x) = delta beta F_ex / delta rho(x)` of hard rods
//! (Percus) and sticky rods (Baxter), evaluated in O(M) with prefix sums.
//!
//! Notation (paper `bcd-hard-rods-sticky.md`, Eqs. 21b, 35a–35c), at every grid point `y`:
//! `g(y) = 1 - eta(y + sigma) = 1 - int_y^{y+sigma} rho`,
//! `s(y) = [rho(y+sigma) + rho(y)] / g(y)`, `d(y) = [rho(y+sigma) - rho(y)] / g(y)`,
//! `S(y) = sqrt(1 + 2 gamma s + gamma^2 d^2)`. `S` is the common square root of Eq. (35a) and of the
//! quadratics that define `K_hat(y)` (Eq. 35b) and `K(y + sigma) = K_hat(y) - d(y)` (Eq. 35c):
//! `K_hat(y) = 2 rho(y+sigma) / (g (1 - gamma d + S))`, `K(y+sigma) = 2 rho(y) / (g (1 + gamma d + S))`.
//! Eq. (35a) then reads `delta beta Omega / delta rho(x) = ln rho(x) + mu_ex(x) + beta U(x) - beta mu`,
//!
//! `mu_ex(x) = ln 4 - ln[T1(x) T2(x - sigma)] + int_{x-sigma}^{x} W(y) dy`,
//!
//! with `T1 = sqrt(g) (1 + gamma d + S)`, `T2 = sqrt(g) (1 - gamma d + S)` and
//! `W = (S - 1) / (2 gamma) = (s + gamma d^2 / 2) / (S + 1)`. At `gamma = 0`, `T1 = T2 = 2 sqrt(g)`
//! and `W = s / 2`: the Percus hard-rod equation (the hard-rods paper, docs/references.md), so one code path serves
//! both and the limit `gamma -> 0` is continuous. The forms used avoid cancellation: `W` as above,
//! and `1 +- gamma d + S = 4 gamma rho / (g (S - (1 +- gamma d)))` when `1 +- gamma d < 0`.

use super::grid::Grid;

/// Work arrays for one evaluation (allocated once per grid).
#[derive(Debug, Clone)]
pub(crate) struct Work {
    /// Prefix integrals (length m + 1).
    pub cum: Vec<f64>,
    /// `rho(x + sigma)`.
    pub rho_p: Vec<f64>,
    /// `g = 1 - eta(x + sigma)`.
    pub g: Vec<f64>,
    /// `T1`.
    pub t1: Vec<f64>,
    /// `T2`, then `T2(x - sigma)`.
    pub t2: Vec<f64>,
    /// Scratch.
    pub tmp: Vec<f64>,
    /// `W`.
    pub w: Vec<f64>,
    /// The result `mu_ex`.
    pub mu_ex: Vec<f64>,
}

impl Work {
    pub fn new(m: usize) -> Self {
        Self {
            cum: vec![0.0; m + 1],
            rho_p: vec![0.0; m],
            g: vec![0.0; m],
            t1: vec![0.0; m],
            t2: vec![0.0; m],
            tmp: vec![0.0; m],
            w: vec![0.0; m],
            mu_ex: vec![0.0; m],
        }
    }
}

/// A density with a window `int_x^{x+sigma} rho >= 1` somewhere: rods overlap (no admissible state).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Overlap;

/// Fills `work.mu_ex` (and the intermediate arrays) for the density `rho` (length `grid.m`).
pub(crate) fn excess(grid: &Grid, gamma: f64, rho: &[f64], work: &mut Work) -> Result<(), Overlap> {
    let m = grid.m;
    grid.prefix(rho, &mut work.cum);
    // g = 1 - int_x^{x+sigma} rho
    grid.window_forward(rho, &work.cum, &mut work.g);
    let mut ok = true;
    for g in work.g.iter_mut() {
        *g = 1.0 - *g;
        ok &= *g > 0.0; // false for NaN too
    }
    if !ok {
        return Err(Overlap);
    }
    grid.shift_forward(rho, &mut work.rho_p);
    let four_gamma = 4.0 * gamma;
    for i in 0..m {
        let g = work.g[i];
        let ig = 1.0 / g;
        let r = rho[i];
        let rp = work.rho_p[i];
        let s = (rp + r) * ig;
        let d = (rp - r) * ig;
        let gd = gamma * d;
        let big_s = (1.0 + gamma * (2.0 * s + gamma * d * d)).sqrt();
        let sg = g.sqrt();
        let a = 1.0 + gd;
        let b = 1.0 - gd;
        work.t1[i] = if a >= 0.0 {
            sg * (a + big_s)
        } else {
            four_gamma * r / (sg * (big_s - a))
        };
        work.t2[i] = if b >= 0.0 {
            sg * (b + big_s)
        } else {
            four_gamma * rp / (sg * (big_s - b))
        };
        work.w[i] = (s + 0.5 * gamma * d * d) / (big_s + 1.0);
    }
    // T2(x - sigma)
    grid.shift_backward(&work.t2, &mut work.tmp);
    // int_{x-sigma}^{x} W
    grid.prefix(&work.w, &mut work.cum);
    grid.window_backward(&work.w, &work.cum, &mut work.mu_ex);
    let ln4 = 4f64.ln();
    for i in 0..m {
        work.mu_ex[i] += ln4 - (work.t1[i] * work.tmp[i]).ln();
    }
    Ok(())
}

/// Regular part of the two-particle density at contact, `rho2(x, x + sigma^+)`, after [`excess`]
/// was evaluated for `rho`: `K(x + sigma) K_hat(x) g(x) = 4 rho(x) rho(x+sigma) / (T1 T2)`
/// (Eq. 24 at `gamma = 0`; derivation for `gamma > 0` in `docs/theory-rods.md`).
pub(crate) fn contact(rho: &[f64], work: &Work, out: &mut [f64]) {
    for i in 0..rho.len() {
        out[i] = 4.0 * rho[i] * work.rho_p[i] / (work.t1[i] * work.t2[i]);
    }
}
