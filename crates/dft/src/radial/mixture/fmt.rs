//! Fundamental-measure functionals of a hard-sphere mixture on the radial grid.
//!
//! Each species `s` (radius `a_s = d_s / 2`) has its own cell integrals of the radial kernels
//! ([`crate::radial::fmt`]), and the weighted densities are sums over species (Rosenfeld, PRL 63,
//! 980 (1989), Eqs. 3–5): `n3 = sum_s w3_s * rho_s`, `n2 = sum_s w2_s * rho_s`,
//! `nv2 = sum_s wv2_s * rho_s`, `n1 = sum_s (w2_s * rho_s) / (4 pi a_s)`,
//! `n0 = sum_s (w2_s * rho_s) / (4 pi a_s^2)`, `nv1 = sum_s (wv2_s * rho_s) / (4 pi a_s)`.
//! The free-energy density is
//! `Phi = -n0 ln(1 - n3) + (n1 n2 - nv1.nv2) / (1 - n3) + (n2^3 - 3 n2 nv2.nv2) phi3(n3)` with
//!
//! - Rosenfeld: `phi3 = 1 / (24 pi (1 - n3)^2)`; its bulk limit is the scaled-particle /
//!   Percus–Yevick compressibility equation of state of the mixture (Lebowitz 1964),
//!   [`super::bulk::py_pressure`];
//! - White Bear, mark I (Roth, Evans, Lang and Kahl, J. Phys.: Condens. Matter 14, 12063 (2002),
//!   Eq. 20; Yu and Wu, J. Chem. Phys. 117, 10156 (2002)):
//!   `phi3 = [n3 + (1 - n3)^2 ln(1 - n3)] / (36 pi n3^2 (1 - n3)^2)`; its bulk limit is the
//!   Boublík–Mansoori–Carnahan–Starling–Leland equation of state, [`super::bulk::bmcsl_pressure`]
//!   (Carnahan–Starling for one species). Below `n3 = 0.01` `phi3` and its derivative are summed
//!   from their series `36 pi phi3 = sum_k (k+1)(k+3)/(k+2) n3^k` (no cancellation).
//!
//! `beta mu_ex,s = sum_alpha (dPhi/dn_alpha) (*) w_alpha,s` applies species `s`'s kernels to the
//! derivatives: `w3_s` to `dPhi/dn3`, `w2_s` to `dPhi/dn2 + dPhi/dn1 / (4 pi a_s)
//! + dPhi/dn0 / (4 pi a_s^2)`, the adjoint vector kernel to `dPhi/dnv2 + dPhi/dnv1 / (4 pi a_s)`.
//! One species gives [`crate::radial::Rosenfeld`] to rounding (tested).

use std::f64::consts::PI;

use crate::radial::fmt::{CellWeights, check_resolution};
use crate::radial::{RadialError, RadialGrid};

/// Which fundamental-measure functional.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Functional {
    /// Rosenfeld (1989): bulk limit Percus–Yevick compressibility (scaled-particle theory).
    #[default]
    Rosenfeld,
    /// White Bear mark I (2002): bulk limit BMCSL (Carnahan–Starling for one species).
    WhiteBear,
}

impl Functional {
    /// Name used in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rosenfeld => "rosenfeld",
            Self::WhiteBear => "white-bear",
        }
    }

    /// `(phi3, dphi3/dn3)` of the module docs.
    #[inline]
    pub fn phi3(self, n3: f64) -> (f64, f64) {
        match self {
            Self::Rosenfeld => {
                let q = 1.0 / (1.0 - n3);
                (q * q / (24.0 * PI), q * q * q / (12.0 * PI))
            }
            Self::WhiteBear => {
                if n3 < 0.01 {
                    let (mut f, mut df, mut p) = (0.0, 0.0, 1.0);
                    for k in 0..14 {
                        let kf = k as f64;
                        let c = (kf + 1.0) * (kf + 3.0) / (kf + 2.0);
                        f += c * p;
                        if k + 1 < 14 {
                            let c1 = (kf + 2.0) * (kf + 4.0) / (kf + 3.0);
                            df += (kf + 1.0) * c1 * p;
                        }
                        p *= n3;
                    }
                    (f / (36.0 * PI), df / (36.0 * PI))
                } else {
                    let m = 1.0 - n3;
                    let l = m.ln();
                    let num = n3 + m * m * l;
                    let den = n3 * n3 * m * m;
                    // d num = 1 - 2 m l - m = n3 - 2 m l; d den = 2 n3 m^2 - 2 n3^2 m.
                    let dnum = n3 - 2.0 * m * l;
                    let dden = 2.0 * n3 * m * (m - n3);
                    (
                        num / den / (36.0 * PI),
                        (dnum * den - num * dden) / (den * den) / (36.0 * PI),
                    )
                }
            }
        }
    }

    /// `Phi` and its partial derivatives `[d/dn0, d/dn1, d/dn2, d/dn3, d/dnv1, d/dnv2]` at the
    /// six weighted densities `n = [n0, n1, n2, n3, nv1, nv2]` (vector ones: radial components).
    #[inline]
    pub fn phi(self, n: [f64; 6]) -> (f64, [f64; 6]) {
        let [n0, n1, n2, n3, nv1, nv2] = n;
        let l = (1.0 - n3).ln();
        let q = 1.0 / (1.0 - n3);
        let (f3, df3) = self.phi3(n3);
        let two = n1 * n2 - nv1 * nv2;
        let c3 = n2 * n2 * n2 - 3.0 * n2 * nv2 * nv2;
        let phi = -n0 * l + two * q + c3 * f3;
        let d = [
            -l,
            n2 * q,
            n1 * q + 3.0 * (n2 * n2 - nv2 * nv2) * f3,
            n0 * q + two * q * q + c3 * df3,
            -nv2 * q,
            -nv1 * q - 6.0 * n2 * nv2 * f3,
        ];
        (phi, d)
    }
}

/// A fundamental-measure functional of `species` hard-sphere species on a [`RadialGrid`].
///
/// Densities are passed species after species, `rho[s * cells + i]` (`cells` = the grid's).
#[derive(Debug, Clone)]
pub struct MixtureFmt {
    functional: Functional,
    diameters: Vec<f64>,
    weights: Vec<CellWeights>,
    n: usize,
    bw_max: usize,
    vol: Vec<f64>,
    /// `n0, n1, n2, n3, nv1, nv2` at the centres.
    wd: [Vec<f64>; 6],
    /// `n3` of each species (stride `n`).
    n3s: Vec<f64>,
    /// `dPhi/dn_alpha` at the centres.
    der: [Vec<f64>; 6],
    scalar: Vec<f64>,
    vector: Vec<f64>,
    mu: Vec<f64>,
}

impl MixtureFmt {
    /// Weights of every species (errors name `diameter` and `dr` as [`crate::radial::Rosenfeld`]).
    pub fn new(
        grid: &RadialGrid,
        diameters: &[f64],
        functional: Functional,
    ) -> Result<Self, RadialError> {
        colloidsim_core::param::at_least("species", diameters.len(), 1)?;
        let mut weights = Vec::with_capacity(diameters.len());
        for &d in diameters {
            check_resolution(grid, d)?;
            weights.push(CellWeights::new(grid, d)?);
        }
        let n = grid.len();
        let ns = diameters.len();
        Ok(Self {
            functional,
            diameters: diameters.to_vec(),
            bw_max: weights.iter().map(|w| w.bw).max().unwrap_or(0),
            weights,
            n,
            vol: grid.volumes().to_vec(),
            wd: std::array::from_fn(|_| vec![0.0; n]),
            n3s: vec![0.0; ns * n],
            der: std::array::from_fn(|_| vec![0.0; n]),
            scalar: vec![0.0; n],
            vector: vec![0.0; n],
            mu: vec![0.0; ns * n],
        })
    }

    /// The functional.
    pub fn functional(&self) -> Functional {
        self.functional
    }
    /// Species diameters.
    pub fn diameters(&self) -> &[f64] {
        &self.diameters
    }
    /// Number of species.
    pub fn species(&self) -> usize {
        self.diameters.len()
    }
    /// Number of grid cells.
    pub fn len(&self) -> usize {
        self.n
    }
    /// Always false.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Rows a density supported on cells `0..active` influences.
    pub fn rows_touched(&self, active: usize) -> usize {
        (active + self.bw_max).min(self.n)
    }

    /// Weighted densities and `beta mu_ex,s` for `rho` (species after species; zero beyond
    /// cell `active`). Returns `beta F_ex = sum_i V_i Phi_i`; fails where `n3 >= 1` or a weighted
    /// density is not finite (time `NaN` for the caller to fill in).
    pub fn evaluate(&mut self, rho: &[f64], active: usize) -> Result<f64, RadialError> {
        let n = self.n;
        assert_eq!(
            rho.len(),
            n * self.species(),
            "one density per species and cell"
        );
        let active = active.min(n);
        let rows = self.rows_touched(active);
        for v in self.wd.iter_mut() {
            v.iter_mut().for_each(|x| *x = 0.0);
        }
        for (s, w) in self.weights.iter().enumerate() {
            let a = 0.5 * self.diameters[s];
            let (c0, c1) = (1.0 / (4.0 * PI * a * a), 1.0 / (4.0 * PI * a));
            let rs = &rho[s * n..(s + 1) * n];
            let n3s = &mut self.n3s[s * n..(s + 1) * n];
            let [w0, w1, w2, w3, wv1, wv2] = &mut self.wd;
            for i in 0..rows {
                let start = w.j0[i];
                let end = (start + w.bw).min(active);
                let (mut n3, mut n2, mut nv2) = (0.0, 0.0, 0.0);
                if end > start {
                    let base = i * w.bw;
                    let len = end - start;
                    let r = &rs[start..end];
                    let k3 = &w.w3[base..base + len];
                    let k2 = &w.w2[base..base + len];
                    let kv = &w.wv2[base..base + len];
                    for k in 0..len {
                        n3 += k3[k] * r[k];
                        n2 += k2[k] * r[k];
                        nv2 += kv[k] * r[k];
                    }
                }
                n3s[i] = n3;
                w3[i] += n3;
                w2[i] += n2;
                wv2[i] += nv2;
                w0[i] += c0 * n2;
                w1[i] += c1 * n2;
                wv1[i] += c1 * nv2;
            }
            n3s[rows..].iter_mut().for_each(|x| *x = 0.0);
        }
        let mut fex = 0.0;
        for i in 0..rows {
            let nd: [f64; 6] = std::array::from_fn(|k| self.wd[k][i]);
            if nd[3].is_nan() || nd[3] >= 1.0 || nd.iter().any(|v| !v.is_finite()) {
                return Err(RadialError::Unphysical {
                    time: f64::NAN,
                    message: format!(
                        "local packing fraction n3 = {} >= 1 (or not finite) at cell {i}",
                        nd[3]
                    ),
                });
            }
            let (phi, d) = self.functional.phi(nd);
            fex += self.vol[i] * phi;
            for k in 0..6 {
                self.der[k][i] = d[k];
            }
        }
        let mu_end = rows.min(active + self.bw_max / 2 + 1).min(n);
        for (s, w) in self.weights.iter().enumerate() {
            let a = 0.5 * self.diameters[s];
            let (c0, c1) = (1.0 / (4.0 * PI * a * a), 1.0 / (4.0 * PI * a));
            for i in 0..rows {
                self.scalar[i] = self.der[2][i] + c1 * self.der[1][i] + c0 * self.der[0][i];
                self.vector[i] = self.der[5][i] + c1 * self.der[4][i];
            }
            let p3 = &self.der[3];
            let mu = &mut self.mu[s * n..(s + 1) * n];
            for j in 0..mu_end {
                let start = w.j0[j];
                let end = (start + w.bw).min(rows);
                let mut m = 0.0;
                if end > start {
                    let base = j * w.bw;
                    let len = end - start;
                    let k3 = &w.w3[base..base + len];
                    let k2 = &w.w2[base..base + len];
                    let kt = &w.wt[base..base + len];
                    let (q3, q2, qv) = (
                        &p3[start..end],
                        &self.scalar[start..end],
                        &self.vector[start..end],
                    );
                    for k in 0..len {
                        m += k3[k] * q3[k] + k2[k] * q2[k] + kt[k] * qv[k];
                    }
                }
                mu[j] = m;
            }
            mu[mu_end..].iter_mut().for_each(|x| *x = 0.0);
        }
        Ok(fex)
    }

    /// Total local packing fraction `n3` at the centres (last [`Self::evaluate`]).
    pub fn n3(&self) -> &[f64] {
        &self.wd[3]
    }
    /// The weighted densities `[n0, n1, n2, n3, nv1, nv2]` at the centres.
    pub fn weighted(&self) -> &[Vec<f64>; 6] {
        &self.wd
    }
    /// Species `s`'s share of `n3` (its local packing fraction).
    pub fn n3_of(&self, s: usize) -> &[f64] {
        &self.n3s[s * self.n..(s + 1) * self.n]
    }
    /// `beta mu_ex` of species `s` at the centres.
    pub fn mu_ex(&self, s: usize) -> &[f64] {
        &self.mu[s * self.n..(s + 1) * self.n]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// White Bear's `phi3`: the series meets the closed form at `n3 = 0.01`, starts at
    /// Rosenfeld's `1 / (24 pi)`, and its derivative is the finite difference of the function.
    #[test]
    fn white_bear_phi3_series_closed_form_and_derivative_agree() {
        let wb = Functional::WhiteBear;
        let (below, dbelow) = wb.phi3(0.01 - 1e-15);
        let (above, dabove) = wb.phi3(0.01);
        assert!((below / above - 1.0).abs() < 1e-12, "{below} {above}");
        assert!((dbelow / dabove - 1.0).abs() < 1e-9, "{dbelow} {dabove}");
        assert!((wb.phi3(0.0).0 * 24.0 * PI - 1.0).abs() < 1e-15);
        for x in [1e-3, 0.02, 0.3, 0.6] {
            for f in [Functional::Rosenfeld, Functional::WhiteBear] {
                let h = 1e-6;
                let fd = (f.phi3(x + h).0 - f.phi3(x - h).0) / (2.0 * h);
                assert!((fd / f.phi3(x).1 - 1.0).abs() < 1e-7, "{f:?} {x}");
            }
        }
    }
}
