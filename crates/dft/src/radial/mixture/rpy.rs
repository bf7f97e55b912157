//! Pairwise RPY flux of a hard-sphere mixture in spherical symmetry, dilute pair correlations.
//!
//! The generalisation of [`crate::radial::rpy`] (the drying-droplet paper's Eqs. 16, 24–27) to
//! unequal radii: the velocity of species `i` at `x` is
//! `u_i(x) = -(kT / eta) sum_j int dy K_ij(x, y) rho_j(y) d_y(beta mu_j(y))`, with the far-field
//! unequal-radius RPY pair tensor (Zuk, Wajnryb, Mizerski and Szymczak, J. Fluid Mech. 741, R5
//! (2014), Eq. 2.4; `crates/hydro/src/rpy.rs`)
//! `Omega_ij = 1/(8 pi eta r) [(1 + s_ij^2/(3 r^2)) I + (1 - s_ij^2/r^2) r̂r̂]`, `s_ij^2 = a_i^2 + a_j^2`,
//! and the dilute pair correlation `g_ij = Theta(r - sigma_ij)`, `sigma_ij = a_i + a_j`
//! (additive hard spheres never overlap, so only the far-field branch enters). As in the
//! one-size kernel, the far-field tensor integrated over a full shell `|y| = y` vanishes, so only
//! the excluded orientations `|x - y| < sigma_ij` contribute, with the opposite sign:
//! `K_ij(x, y) = (3 sigma^2 - s^2) / (48 x^2 sigma^3) [sigma^2 - (x - y)^2] [sigma^2 - (x + y)^2]`
//! for `|x - y| < sigma < x + y` (else 0), in units of `kT / eta = 6 pi a_i D0_i` (the same for
//! every species when `D0_i` is Stokes', `D0 proportional to 1/d`). For `a_i = a_j = a`,
//! `6 pi a D0 K = (5 pi D0 / (32 x^2)) [d^2 - (x-y)^2][d^2 - (x+y)^2]`, the one-size kernel (tested).
//!
//! Bulk limit (uniform densities, a uniform force `F_j` on each particle of species `j`):
//! `u_i = beta D0_i F_i - sum_j rho_j F_j (sigma_ij^2 / 3 - s_ij^2 / 9) / eta`; for one size
//! `K = 1 - 5 phi` (tested). This is the dilute limit of the RPY level of description: Batchelor's
//! polydisperse sedimentation coefficients (J. Fluid Mech. 119, 379 (1982)) add the near-field
//! two-sphere mobility functions (for one size `1 - 6.55 phi` instead of `1 - 5 phi`).

use std::f64::consts::PI;

use crate::radial::RadialGrid;

/// `K_ij(x, y)` of the module docs (units `kT / eta`), for radii `ai`, `aj`.
#[inline]
pub fn kernel(x: f64, y: f64, ai: f64, aj: f64) -> f64 {
    let sigma = ai + aj;
    if (x - y).abs() >= sigma || x + y <= sigma {
        return 0.0;
    }
    let s2 = ai * ai + aj * aj;
    let sg2 = sigma * sigma;
    (3.0 * sg2 - s2) / (48.0 * x * x * sg2 * sigma)
        * (sg2 - (x - y).powi(2))
        * (sg2 - (x + y).powi(2))
}

/// Banded cell integrals of `K_ij` for one pair of species: row `f` (face `f`) holds `bw` cells
/// from `start[f]`.
#[derive(Debug, Clone)]
struct Band {
    bw: usize,
    start: Vec<usize>,
    weights: Vec<f64>,
}

/// The cell-integrated kernels of every ordered pair of species on a grid.
#[derive(Debug, Clone)]
pub struct MixtureRpy {
    species: usize,
    radii: Vec<f64>,
    bands: Vec<Band>,
}

impl MixtureRpy {
    /// Kernels for spheres of `diameters` on `grid`: each cell piece between the kernel's
    /// breakpoints integrated by 3-point Gauss–Legendre (exact: a quartic in `y`).
    pub fn new(grid: &RadialGrid, diameters: &[f64]) -> Self {
        let ns = diameters.len();
        let radii: Vec<f64> = diameters.iter().map(|d| 0.5 * d).collect();
        let dr = grid.dr();
        let faces = grid.faces();
        let nf = faces.len();
        let n = grid.len();
        let gl = [
            (-(0.6f64).sqrt(), 5.0 / 9.0),
            (0.0, 8.0 / 9.0),
            ((0.6f64).sqrt(), 5.0 / 9.0),
        ];
        let mut bands = Vec::with_capacity(ns * ns);
        for i in 0..ns {
            for j in 0..ns {
                let (ai, aj) = (radii[i], radii[j]);
                let sigma = ai + aj;
                let bw = (2.0 * sigma / dr).ceil() as usize + 3;
                let mut start = vec![0; nf];
                let mut weights = vec![0.0; nf * bw];
                let mut cuts = Vec::with_capacity(6);
                for f in 1..nf.saturating_sub(1) {
                    let x = faces[f];
                    let lo_y = (x - sigma).max(0.0);
                    let hi_y = x + sigma;
                    let s = (lo_y / dr).floor() as usize;
                    start[f] = s;
                    for k in 0..bw {
                        let c = s + k;
                        if c >= n {
                            break;
                        }
                        let lo = faces[c].max(lo_y);
                        let hi = faces[c + 1].min(hi_y);
                        if hi <= lo {
                            continue;
                        }
                        cuts.clear();
                        cuts.push(lo);
                        for b in [x - sigma, x + sigma, sigma - x] {
                            if b > lo && b < hi {
                                cuts.push(b);
                            }
                        }
                        cuts.push(hi);
                        cuts.sort_by(f64::total_cmp);
                        for piece in cuts.windows(2) {
                            let (m, h) = (0.5 * (piece[0] + piece[1]), 0.5 * (piece[1] - piece[0]));
                            for (t, w) in gl {
                                weights[f * bw + k] += w * h * kernel(x, m + h * t, ai, aj);
                            }
                        }
                    }
                }
                bands.push(Band { bw, start, weights });
            }
        }
        Self {
            species: ns,
            radii,
            bands,
        }
    }

    /// Drift velocities `u_i / D0_i` of species `i` at the interior faces `1..active` into
    /// `out`, from `g_j = rho_j d(beta mu_j)` at the cell centres (`g[j * cells + c]`), for
    /// Stokes mobilities (`kT / eta = 6 pi a_i D0_i`).
    pub fn velocities(&self, i: usize, g: &[f64], cells: usize, active: usize, out: &mut [f64]) {
        out[0] = 0.0;
        out[active] = 0.0;
        let scale = 6.0 * PI * self.radii[i];
        for (f, o) in out.iter_mut().enumerate().take(active).skip(1) {
            let mut acc = 0.0;
            for j in 0..self.species {
                let b = &self.bands[i * self.species + j];
                let s = b.start[f];
                let e = (s + b.bw).min(active);
                if e <= s {
                    continue;
                }
                let row = &b.weights[f * b.bw..f * b.bw + (e - s)];
                let gj = &g[j * cells + s..j * cells + e];
                for (w, x) in row.iter().zip(gj) {
                    acc += w * x;
                }
            }
            *o = -scale * acc;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `K_ij` by direct quadrature of the far-field tensor over the allowed orientations
    /// (`eta = kT = 1`).
    fn direct(x: f64, y: f64, ai: f64, aj: f64) -> f64 {
        let sigma = ai + aj;
        let s2 = ai * ai + aj * aj;
        let c_max = ((x * x + y * y - sigma * sigma) / (2.0 * x * y)).min(1.0);
        if c_max <= -1.0 {
            return 0.0;
        }
        let m = 200_000;
        let h = (c_max + 1.0) / m as f64;
        let mut acc = 0.0;
        for k in 0..m {
            let c = -1.0 + (k as f64 + 0.5) * h;
            let r2 = x * x + y * y - 2.0 * x * y * c;
            let r = r2.sqrt();
            let proj = (x - y * c) * (x * c - y) / r2;
            acc += h / (8.0 * PI * r) * ((1.0 + s2 / (3.0 * r2)) * c + (1.0 - s2 / r2) * proj);
        }
        2.0 * PI * y * y * acc
    }

    #[test]
    fn unequal_kernel_matches_angular_quadrature_and_the_one_size_kernel() {
        for (ai, aj) in [(0.5, 1.0), (1.0, 0.5), (0.5, 0.5)] {
            for (x, y) in [(3.0, 3.4), (3.0, 2.2), (0.7, 0.5), (0.3, 1.4), (5.0, 6.3)] {
                let k = kernel(x, y, ai, aj);
                let q = direct(x, y, ai, aj);
                assert!(
                    (k - q).abs() < 1e-6 * (1.0 + q.abs()),
                    "({x},{y}) {k} vs {q}"
                );
            }
        }
        // One size: 6 pi a D0 K = M of the one-size kernel (D0 = 1).
        for (x, y) in [(3.0, 3.4), (0.7, 0.5)] {
            let one = crate::radial::rpy::kernel(x, y, 1.0);
            let here = 6.0 * PI * 0.5 * kernel(x, y, 0.5, 0.5);
            assert!((one - here).abs() < 1e-13 * one.abs(), "{one} {here}");
        }
    }
}
