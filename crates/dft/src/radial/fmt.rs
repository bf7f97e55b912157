//! Rosenfeld FMT on the radial grid (the drying-droplet paper, docs/references.md; paper Eqs. 11–21).
//!
//! The density is piecewise constant on the cells; the radial kernels are integrated exactly over
//! each cell, so the weighted densities at the centres `r_i` are
//! `n_alpha(r_i) = sum_j W_alpha[i, j] rho_j` with, for a shell `r'` (radius `a = d/2`):
//! - `n3(r) = (pi / r) int_{|r-a|}^{r+a} r' rho (a^2 - (r - r')^2) dr' + int_0^{a-r} 4 pi r'^2 rho dr'`,
//! - `n2(r) = (2 pi a / r) int_{|r-a|}^{r+a} r' rho dr'`,
//! - `nv2(r) = (pi / r^2) int_{|r-a|}^{r+a} r' rho (a^2 + r^2 - r'^2) dr'` (radial component),
//!
//! and `n0 = n2 / (4 pi a^2)`, `n1 = n2 / (4 pi a)`, `nv1 = nv2 / (4 pi a)`. Away from the centre
//! (`r > a`) these are the convolution form of Eqs. (18)–(20); for `r < a` the same cell integrals
//! are the direct quadrature of Eq. (21). The free energy is the discrete functional
//! `beta F_ex = sum_i V_i Phi(n(r_i))`, with Rosenfeld's
//! `Phi = -n0 ln(1-n3) + (n1 n2 - nv1.nv2)/(1-n3) + (n2^3 - 3 n2 nv2.nv2)/(24 pi (1-n3)^2)`,
//! and `beta mu_ex(r) = sum_alpha int d^3r' dPhi/dn_alpha(r') w_alpha(r' - r)` treats the
//! derivatives `dPhi/dn_alpha` as piecewise constant on the cells too: the scalar kernels are the
//! same, the vector one is its adjoint, `(pi / r) int_{|r-a|}^{r+a} dPhi/dnv2(r') (a^2 + r'^2 - r^2) dr'`
//! (no contribution from `r' < a - r`). This is exact for a uniform fluid at every `r`, including
//! the centre, and O(dr^2) otherwise.

use std::f64::consts::PI;

use super::{RadialError, RadialGrid};

/// Minimum number of cells per particle diameter.
pub const MIN_CELLS_PER_DIAMETER: f64 = 10.0;

/// Rosenfeld's `Phi` (paper Eq. 12) of `n3, n2, nv2` for spheres of radius `a`, with
/// `n0 = n2 / (4 pi a^2)`, `n1 = n2 / (4 pi a)`, `nv1 = nv2 / (4 pi a)` substituted; returns
/// `(Phi, dPhi/dn3, dPhi/dn2, dPhi/dnv2)` (total derivatives through the proportional densities).
#[inline]
pub fn rosenfeld_phi(n3: f64, n2: f64, nv2: f64, a: f64) -> (f64, f64, f64, f64) {
    let ca = 1.0 / (4.0 * PI * a * a);
    let cb = 1.0 / (4.0 * PI * a);
    let l = (1.0 - n3).ln();
    let q = 1.0 / (1.0 - n3);
    let q2 = q * q;
    let d2 = n2 * n2 - nv2 * nv2;
    let c3 = n2 * n2 * n2 - 3.0 * n2 * nv2 * nv2;
    let phi = -ca * n2 * l + cb * d2 * q + c3 * q2 / (24.0 * PI);
    let p3 = ca * n2 * q + cb * d2 * q2 + c3 * q2 * q / (12.0 * PI);
    let p2 = -ca * l + 2.0 * cb * n2 * q + d2 * q2 / (8.0 * PI);
    let pv = -2.0 * cb * nv2 * q - n2 * nv2 * q2 / (4.0 * PI);
    (phi, p3, p2, pv)
}

/// Refuse a `diameter` that is not positive, a grid that does not resolve it
/// (`diameter / dr < 10`, naming `dr`) or one shorter than it (naming `r_max`).
pub(crate) fn check_resolution(grid: &RadialGrid, diameter: f64) -> Result<(), RadialError> {
    colloidsim_core::param::positive("diameter", diameter)?;
    let dr = grid.dr();
    if diameter / dr < MIN_CELLS_PER_DIAMETER {
        return Err(colloidsim_core::ParamError::new(
                "dr",
                format!(
                    "grid spacing {dr} does not resolve the particle: need dr <= diameter / {MIN_CELLS_PER_DIAMETER} = {}",
                    diameter / MIN_CELLS_PER_DIAMETER
                ),
            )
            .into());
    }
    if grid.r_max() < diameter {
        return Err(colloidsim_core::ParamError::new(
            "r_max",
            format!(
                "grid extent {} is shorter than the diameter {diameter}",
                grid.r_max()
            ),
        )
        .into());
    }
    Ok(())
}

/// The exact cell integrals of the radial kernels for spheres of one diameter (module docs):
/// row `i` holds `bw` cells from `j0[i]`; `w3`, `w2`, `wv2` give `n3, n2, nv2` at centre `i`,
/// `wt` is the vector kernel's adjoint for the functional derivative.
#[derive(Debug, Clone)]
pub(crate) struct CellWeights {
    pub(crate) bw: usize,
    pub(crate) j0: Vec<usize>,
    pub(crate) w3: Vec<f64>,
    pub(crate) w2: Vec<f64>,
    pub(crate) wv2: Vec<f64>,
    pub(crate) wt: Vec<f64>,
}

impl CellWeights {
    /// Weights of spheres of `diameter` on `grid` (the caller checked the resolution).
    pub(crate) fn new(grid: &RadialGrid, diameter: f64) -> Result<Self, RadialError> {
        let dr = grid.dr();
        let a = 0.5 * diameter;
        let n = grid.len();
        let bw = (2.0 * a / dr).ceil() as usize + 2;
        // Four weight bands of n x bw, and as much again for the DDFT's kernels and scratch:
        // refused before they are allocated when the machine cannot hold them.
        colloidsim_core::resources::ensure_fits(
            "dr",
            &format!(
                "the FMT weights of {n} cells x {bw} (grid spacing {dr:.3e}; a larger --dx makes them smaller)"
            ),
            8.0 * 8.0 * n as f64 * bw as f64,
        )?;
        let faces = grid.faces();
        let mut j0 = vec![0; n];
        let mut w3 = vec![0.0; n * bw];
        let mut w2 = vec![0.0; n * bw];
        let mut wv2 = vec![0.0; n * bw];
        let mut wt = vec![0.0; n * bw];
        for (i, &r) in grid.centres().iter().enumerate() {
            let start = if r > a {
                ((r - a) / dr).floor() as usize
            } else {
                0
            };
            j0[i] = start;
            let lo_r = (r - a).abs();
            let hi_r = r + a;
            // Antiderivatives in t = r' - r of the shell kernels (without prefactors).
            let f3 =
                |t: f64| r * (a * a * t - t.powi(3) / 3.0) + a * a * t * t / 2.0 - t.powi(4) / 4.0;
            let f2 = |t: f64| r * t + t * t / 2.0;
            let fv = |t: f64| {
                r * a * a * t + (a * a - 2.0 * r * r) * t * t / 2.0
                    - r * t.powi(3)
                    - t.powi(4) / 4.0
            };
            let ft = |t: f64| a * a * t + r * t * t + t.powi(3) / 3.0;
            for k in 0..bw {
                let j = start + k;
                if j >= n {
                    break;
                }
                let (cl, ch) = (faces[j], faces[j + 1]);
                let lo = cl.max(lo_r);
                let hi = ch.min(hi_r);
                let idx = i * bw + k;
                if hi > lo {
                    let (tl, th) = (lo - r, hi - r);
                    w3[idx] += PI / r * (f3(th) - f3(tl));
                    w2[idx] += 2.0 * PI * a / r * (f2(th) - f2(tl));
                    wv2[idx] += PI / (r * r) * (fv(th) - fv(tl));
                    wt[idx] += PI / r * (ft(th) - ft(tl));
                }
                if r < a {
                    let hi = ch.min(a - r);
                    if hi > cl {
                        w3[idx] += 4.0 * PI / 3.0 * (hi.powi(3) - cl.powi(3));
                    }
                }
            }
        }
        Ok(Self {
            bw,
            j0,
            w3,
            w2,
            wv2,
            wt,
        })
    }
}

/// Rosenfeld hard-sphere functional on a [`RadialGrid`], with preallocated workspace.
#[derive(Debug, Clone)]
pub struct Rosenfeld {
    diameter: f64,
    n: usize,
    bw: usize,
    j0: Vec<usize>,
    w3: Vec<f64>,
    w2: Vec<f64>,
    wv2: Vec<f64>,
    wt: Vec<f64>,
    vol: Vec<f64>,
    n3: Vec<f64>,
    n2: Vec<f64>,
    nv2: Vec<f64>,
    s3: Vec<f64>,
    s2: Vec<f64>,
    sv2: Vec<f64>,
    mu: Vec<f64>,
}

impl Rosenfeld {
    /// Precompute the cell weights for spheres of `diameter` on `grid`.
    ///
    /// Errors if the grid does not resolve the particle (`diameter / dr < 10`) or the grid is
    /// shorter than one diameter.
    pub fn new(grid: &RadialGrid, diameter: f64) -> Result<Self, RadialError> {
        check_resolution(grid, diameter)?;
        let CellWeights {
            bw,
            j0,
            w3,
            w2,
            wv2,
            wt,
        } = CellWeights::new(grid, diameter)?;
        let n = grid.len();
        Ok(Self {
            diameter,
            n,
            bw,
            j0,
            w3,
            w2,
            wv2,
            wt,
            vol: grid.volumes().to_vec(),
            n3: vec![0.0; n],
            n2: vec![0.0; n],
            nv2: vec![0.0; n],
            s3: vec![0.0; n],
            s2: vec![0.0; n],
            sv2: vec![0.0; n],
            mu: vec![0.0; n],
        })
    }

    /// Particle diameter.
    pub fn diameter(&self) -> f64 {
        self.diameter
    }

    /// Number of grid cells.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Always false.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Number of rows a density supported on cells `0..active` influences.
    pub fn rows_touched(&self, active: usize) -> usize {
        (active + self.bw).min(self.n)
    }

    /// Weighted densities and `beta mu_ex` for `rho` (zero beyond cell `active`).
    ///
    /// Returns `beta F_ex = sum_i V_i Phi_i`. Fails where `n3 >= 1` or a weighted density is not
    /// finite (the time is left `NaN` for the caller to fill in).
    pub fn evaluate(&mut self, rho: &[f64], active: usize) -> Result<f64, RadialError> {
        let active = active.min(self.n).min(rho.len());
        let rows = self.rows_touched(active);
        let a = 0.5 * self.diameter;
        let mut fex = 0.0;
        for i in 0..rows {
            let start = self.j0[i];
            let end = (start + self.bw).min(active);
            let (mut n3, mut n2, mut nv2) = (0.0, 0.0, 0.0);
            if end > start {
                let base = i * self.bw;
                let len = end - start;
                let r = &rho[start..end];
                let w3 = &self.w3[base..base + len];
                let w2 = &self.w2[base..base + len];
                let wv = &self.wv2[base..base + len];
                for k in 0..len {
                    n3 += w3[k] * r[k];
                    n2 += w2[k] * r[k];
                    nv2 += wv[k] * r[k];
                }
            }
            self.n3[i] = n3;
            self.n2[i] = n2;
            self.nv2[i] = nv2;
            if n3.is_nan() || n3 >= 1.0 || !n2.is_finite() || !nv2.is_finite() {
                return Err(RadialError::Unphysical {
                    time: f64::NAN,
                    message: format!(
                        "local packing fraction n3 = {n3} >= 1 (or not finite) at cell {i}"
                    ),
                });
            }
            let (phi, p3, p2, pv) = rosenfeld_phi(n3, n2, nv2, a);
            fex += self.vol[i] * phi;
            self.s3[i] = p3;
            self.s2[i] = p2;
            self.sv2[i] = pv;
        }
        for i in rows..self.n {
            self.n3[i] = 0.0;
            self.n2[i] = 0.0;
            self.nv2[i] = 0.0;
        }
        // Functional derivative: the kernels applied to dPhi/dn (gathered over each row).
        let mu_end = rows.min(active + self.bw / 2 + 1).min(self.n);
        for j in 0..mu_end {
            let start = self.j0[j];
            let end = (start + self.bw).min(rows);
            let mut m = 0.0;
            if end > start {
                let base = j * self.bw;
                let len = end - start;
                let w3 = &self.w3[base..base + len];
                let w2 = &self.w2[base..base + len];
                let wt = &self.wt[base..base + len];
                let p3 = &self.s3[start..end];
                let p2 = &self.s2[start..end];
                let pv = &self.sv2[start..end];
                for k in 0..len {
                    m += w3[k] * p3[k] + w2[k] * p2[k] + wt[k] * pv[k];
                }
            }
            self.mu[j] = m;
        }
        for j in mu_end..self.n {
            self.mu[j] = 0.0;
        }
        Ok(fex)
    }

    /// Local packing fraction `n3` at the cell centres (last [`Self::evaluate`]).
    pub fn n3(&self) -> &[f64] {
        &self.n3
    }
    /// `n2` at the cell centres.
    pub fn n2(&self) -> &[f64] {
        &self.n2
    }
    /// Radial component of `nv2` at the cell centres.
    pub fn nv2(&self) -> &[f64] {
        &self.nv2
    }
    /// `beta mu_ex` at the cell centres.
    pub fn mu_ex(&self) -> &[f64] {
        &self.mu
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Largest |dF/drho_j / V_j - mu_j| over cells with 0.5 < r < 2.5 on a grid of spacing `dr`.
    fn gradient_mismatch(dr: f64) -> f64 {
        let g = RadialGrid::covering(dr, 5.0).unwrap();
        let mut f = Rosenfeld::new(&g, 1.0).unwrap();
        let rho: Vec<f64> = g
            .centres()
            .iter()
            .map(|r| 0.4 * (1.0 + 0.3 * (3.0 * r).sin()) / (1.0 + (4.0 * (r - 3.5)).exp()))
            .collect();
        f.evaluate(&rho, g.len()).unwrap();
        let mu = f.mu_ex().to_vec();
        let mut worst = 0.0f64;
        for j in (0..g.len())
            .filter(|&j| g.centres()[j] > 0.5 && g.centres()[j] < 2.5)
            .step_by(7)
        {
            let h = 1e-5;
            let mut p = rho.clone();
            p[j] += h;
            let fp = f.evaluate(&p, g.len()).unwrap();
            p[j] -= 2.0 * h;
            let fm = f.evaluate(&p, g.len()).unwrap();
            let fd = (fp - fm) / (2.0 * h) / g.volumes()[j];
            worst = worst.max((fd - mu[j]).abs());
        }
        worst
    }

    #[test]
    fn derivative_is_the_gradient_of_the_discrete_functional_to_second_order() {
        // mu_ex discretises the continuous derivative; the discrete gradient of
        // sum_i V_i Phi_i agrees with it to O(dr^2).
        let e1 = gradient_mismatch(0.05);
        let e2 = gradient_mismatch(0.025);
        assert!(e1 / e2 > 3.0, "{e1} {e2}");
        assert!(e2 < 2e-2, "{e2}");
    }

    #[test]
    fn coarse_grid_is_rejected() {
        let g = RadialGrid::new(0.2, 50).unwrap();
        let e = Rosenfeld::new(&g, 1.0).unwrap_err();
        assert!(e.to_string().starts_with("dr:"), "{e}");
    }
}
