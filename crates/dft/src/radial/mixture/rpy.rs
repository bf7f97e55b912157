//! Pairwise RPY flux of a hard-sphere mixture in spherical symmetry, dilute or dense pair
//! correlations.
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

//!
//! **Dense pair correlations** ([`PairCorrelation::Trokhymchuk`], `TrokhymchukWeighted`): the
//! one-size cure of [`crate::radial::rpy`] generalised by scaling (our choice, not from a paper):
//! `h_ij(r) = A_ij h_1(r / sigma_ij; eta)` for `r > sigma_ij` (`-1` inside), with `h_1` the
//! one-size total correlation [`crate::radial::pair::TotalCorrelation`] at the total packing
//! fraction `eta = xi3` and the amplitude
//! `A_ij = [g_ij^BMCSL(sigma_ij) - 1] / [g_CS(eta) - 1]`, the Boublík–Mansoori–Carnahan–
//! Starling–Leland partial contact value (Boublík 1970; Mansoori et al. 1971)
//! `g_ij = 1/(1-xi3) + 3 xi2 D_ij/(1-xi3)^2 + 2 xi2^2 D_ij^2/(1-xi3)^3`, `D_ij = d_i d_j/(d_i+d_j)`,
//! `xi_n = (pi/6) sum_k rho_k d_k^n`, over its one-size limit, Carnahan–Starling's
//! `g_CS = (1 - eta/2)/(1-eta)^3`. With `q_ij = xi2 D_ij / xi3`,
//! `A_ij = [(1-eta)^2 + 3 q_ij (1-eta) + 2 eta q_ij^2] / (5/2 - 3 eta + eta^2)` (no 0/0 at
//! `eta -> 0`); one size has `q = 1/2` and `A = 1` exactly, so the one-size kernel is recovered
//! to rounding. Trokhymchuk's contact value is Kolafa's, not Carnahan–Starling's; dividing by
//! `g_CS - 1` (not Kolafa's) is what makes one size exact, and the mixture's contact values are
//! BMCSL's times the one-size ratio `h_1(1; eta) / (g_CS - 1)` (Kolafa over Carnahan–Starling:
//! within 0.6 % of 1 for `0.105 <= eta <= 0.5`, 0.991 at the 0.6 clamp; both `2.5 eta` to first
//! order at low `eta`). Limits: the shape of `h_ij` beyond contact is
//! the one-size shape in units of `sigma_ij` (the oscillation period of an unequal pair and the
//! depletion well of small spheres around large ones are not modelled), and the compressibility
//! sum rules of the mixture are not imposed.
//!
//! The far-field tensor against `h_ij` over `r > sigma_ij`, in `r` (`P = x^2 + y^2`,
//! `Q = x^2 - y^2`), adds `(1 / (16 x^2)) int [(2P + s^2/3) - 3 r^2 + (2 s^2 P/3 + Q^2)/r^2
//! - s^2 Q^2/r^4] h_ij(r) dr` over `max(sigma, |x - y|) < r < x + y` to `K_ij` (the one-size
//! moment form with `2 a^2 -> s^2`; with `h = -1` inside it gives [`kernel`], tested). The
//! kernel of `h_1` is tabulated once per pair at the 11 packing fractions of [`PairTable`];
//! per face and cell, the amplitude and the packing fraction are those of the mean of the two
//! points' `xi2`, `xi3` (as the one-size code takes the mean `eta`), so the cost per flux is
//! the one-size dense flux's per pair. Bulk limit: [`bulk_coupling`].

use std::f64::consts::PI;

use colloidsim_core::ParamError;
use rayon::prelude::*;

use crate::radial::pair::{TotalCorrelation, first_moment};
use crate::radial::rpy::{PAIR_NODES, PairCorrelation, PairTable, TailMoments};
use crate::radial::{RadialError, RadialGrid};

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

/// The extra kernel of a total correlation `h` beyond contact `sigma` (moments `m` of `h` from
/// `sigma`), units `kT / eta` (module docs).
fn tail_kernel(x: f64, y: f64, sigma: f64, s2: f64, m: &TailMoments) -> f64 {
    let lo = (x - y).abs().max(sigma);
    let hi = x + y;
    if hi <= lo {
        return 0.0;
    }
    let (p, q) = (x * x + y * y, x * x - y * y);
    let (ml, mh) = (m.at(lo), m.at(hi));
    let c = [
        2.0 * p + s2 / 3.0,
        -3.0,
        2.0 * s2 * p / 3.0 + q * q,
        -s2 * q * q,
    ];
    let s: f64 = (0..4).map(|k| c[k] * (mh[k] - ml[k])).sum();
    s / (16.0 * x * x)
}

/// BMCSL contact value `g_ij(sigma_ij)` of species of diameters `di`, `dj` in a mixture with
/// `xi2`, `xi3` (module docs).
pub fn bmcsl_contact(xi2: f64, xi3: f64, di: f64, dj: f64) -> f64 {
    let dd = di * dj / (di + dj);
    let v = 1.0 - xi3;
    1.0 / v + 3.0 * xi2 * dd / (v * v) + 2.0 * (xi2 * dd).powi(2) / (v * v * v)
}

/// Carnahan–Starling contact value `(1 - eta/2) / (1 - eta)^3`.
pub fn carnahan_starling_contact(eta: f64) -> f64 {
    (1.0 - 0.5 * eta) / (1.0 - eta).powi(3)
}

/// `A = [g_ij^BMCSL - 1] / [g_CS(eta) - 1]` from `eta = xi3` and `q = xi2 D_ij / xi3`
/// (module docs); 1 for one size (`q = 1/2`).
#[inline]
pub fn amplitude(eta: f64, q: f64) -> f64 {
    let v = 1.0 - eta;
    (v * v + 3.0 * q * v + 2.0 * eta * q * q) / (2.5 - 3.0 * eta + eta * eta)
}

/// Banded cell integrals for one unordered pair of species: row `f` (face `f`) holds `rows`
/// rows of `bw` cells from `start[f]` (`weights[(f * rows + row) * bw + k]`): the dilute
/// kernel, then (dense `g`) the kernel of `h_1` at each packing-fraction node.
#[derive(Debug, Clone)]
struct Band {
    bw: usize,
    rows: usize,
    start: Vec<usize>,
    weights: Vec<f64>,
}

/// The cell-integrated kernels of every pair of species on a grid.
#[derive(Debug, Clone)]
pub struct MixtureRpy {
    species: usize,
    radii: Vec<f64>,
    /// Band of the pair `(i, j)` at `band_of[i * species + j]` (`K_ij = K_ji`).
    band_of: Vec<usize>,
    bands: Vec<Band>,
    /// `D_ij = d_i d_j / (d_i + d_j)` per band.
    reduced: Vec<f64>,
    /// Packing-fraction nodes (1: dilute).
    nodes: usize,
    d_eta: f64,
    eta_max: f64,
}

/// Per-cell `xi2`, `xi3` of the densities `rho` (species after species, `cells` each) on cells
/// `0..active`: `(pi/6) sum_s rho_s d_s^n`.
pub fn point_packing(
    diameters: &[f64],
    rho: &[f64],
    cells: usize,
    active: usize,
    xi2: &mut [f64],
    xi3: &mut [f64],
) {
    xi2[..active].iter_mut().for_each(|v| *v = 0.0);
    xi3[..active].iter_mut().for_each(|v| *v = 0.0);
    for (s, &d) in diameters.iter().enumerate() {
        let (c2, c3) = (PI / 6.0 * d * d, PI / 6.0 * d * d * d);
        for c in 0..active {
            let r = rho[s * cells + c];
            xi2[c] += c2 * r;
            xi3[c] += c3 * r;
        }
    }
}

impl MixtureRpy {
    /// Kernels for spheres of `diameters` on `grid`, dilute pair correlations: each cell piece
    /// between the kernel's breakpoints integrated by 3-point Gauss–Legendre (exact: a quartic
    /// in `y`).
    pub fn new(grid: &RadialGrid, diameters: &[f64]) -> Self {
        Self::with_pair(
            grid,
            diameters,
            PairCorrelation::Dilute,
            PairTable::default(),
        )
        .expect("the dilute kernel has no parameters to refuse")
    }

    /// The bytes [`Self::with_pair`] will hold.
    pub fn memory_bytes(
        grid: &RadialGrid,
        diameters: &[f64],
        pair: PairCorrelation,
        table: PairTable,
    ) -> usize {
        let ns = diameters.len();
        let mut total = 0;
        for i in 0..ns {
            for j in i..ns {
                let (bw, rows) =
                    Self::shape(grid.dr(), 0.5 * (diameters[i] + diameters[j]), pair, table);
                total += (grid.len() + 1) * bw * rows;
            }
        }
        total * std::mem::size_of::<f64>()
    }

    fn shape(dr: f64, sigma: f64, pair: PairCorrelation, table: PairTable) -> (usize, usize) {
        match pair {
            PairCorrelation::Dilute => ((2.0 * sigma / dr).ceil() as usize + 3, 1),
            PairCorrelation::Trokhymchuk | PairCorrelation::TrokhymchukWeighted => (
                (2.0 * table.range * sigma / dr).ceil() as usize + 3,
                1 + PAIR_NODES,
            ),
        }
    }

    /// Kernels with pair correlation `pair` (module docs; `table.range` in units of each pair's
    /// `sigma_ij`). The dilute part as [`Self::new`]; the dense part by 3-point Gauss–Legendre
    /// on the same cell pieces. Refused naming `dr` when the tables do not fit in memory.
    pub fn with_pair(
        grid: &RadialGrid,
        diameters: &[f64],
        pair: PairCorrelation,
        table: PairTable,
    ) -> Result<Self, RadialError> {
        table.validate()?;
        let ns = diameters.len();
        let radii: Vec<f64> = diameters.iter().map(|d| 0.5 * d).collect();
        let dr = grid.dr();
        let faces = grid.faces();
        let nf = faces.len();
        let n = grid.len();
        let dense = pair != PairCorrelation::Dilute;
        let nodes = if dense { PAIR_NODES } else { 1 };
        let d_eta = table.eta_max / (PAIR_NODES - 1) as f64;
        if dense {
            let bytes = Self::memory_bytes(grid, diameters, pair, table);
            colloidsim_core::resources::ensure_fits(
                "dr",
                &format!(
                    "the mixture RPY kernel tables of {nf} faces x {} packing fractions for {} pairs of species (grid spacing {dr:.3e}; a larger --dx makes them smaller)",
                    PAIR_NODES,
                    ns * (ns + 1) / 2
                ),
                bytes as f64,
            )?;
        }
        let gl = [
            (-(0.6f64).sqrt(), 5.0 / 9.0),
            (0.0, 8.0 / 9.0),
            ((0.6f64).sqrt(), 5.0 / 9.0),
        ];
        let mut band_of = vec![0; ns * ns];
        let mut bands = Vec::with_capacity(ns * (ns + 1) / 2);
        let mut reduced = Vec::with_capacity(ns * (ns + 1) / 2);
        for i in 0..ns {
            for j in i..ns {
                band_of[i * ns + j] = bands.len();
                band_of[j * ns + i] = bands.len();
                let (ai, aj) = (radii[i], radii[j]);
                let sigma = ai + aj;
                let s2 = ai * ai + aj * aj;
                reduced.push(diameters[i] * diameters[j] / (diameters[i] + diameters[j]));
                let (bw, rows) = Self::shape(dr, sigma, pair, table);
                let reach = if dense { table.range * sigma } else { sigma };
                let tails: Vec<Option<TailMoments>> = (0..nodes)
                    .map(|k| {
                        if k == 0 {
                            return Ok(None);
                        }
                        let h = TotalCorrelation::new(k as f64 * d_eta)?;
                        Ok(Some(TailMoments::new(
                            |r| h.h(r / sigma),
                            sigma,
                            reach,
                            sigma,
                        )))
                    })
                    .collect::<Result<_, ParamError>>()?;
                let mut start = vec![0; nf];
                for (f, st) in start
                    .iter_mut()
                    .enumerate()
                    .take(nf.saturating_sub(1))
                    .skip(1)
                {
                    *st = ((faces[f] - reach).max(0.0) / dr).floor() as usize;
                }
                let mut weights = vec![0.0; nf * rows * bw];
                // Faces in parallel; each face's sums are serial (thread-count independent).
                weights
                    .par_chunks_mut(rows * bw)
                    .enumerate()
                    .filter(|(f, _)| *f >= 1 && *f + 1 < nf)
                    .for_each(|(f, block)| {
                        let x = faces[f];
                        let lo_y = (x - reach).max(0.0);
                        let hi_y = x + reach;
                        let s = start[f];
                        let mut cuts = Vec::with_capacity(6);
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
                                let (m, h) =
                                    (0.5 * (piece[0] + piece[1]), 0.5 * (piece[1] - piece[0]));
                                for (t, w) in gl {
                                    let y = m + h * t;
                                    block[k] += w * h * kernel(x, y, ai, aj);
                                    for (node, tail) in tails.iter().enumerate() {
                                        if let Some(mt) = tail {
                                            block[(1 + node) * bw + k] +=
                                                w * h * tail_kernel(x, y, sigma, s2, mt);
                                        }
                                    }
                                }
                            }
                        }
                    });
                bands.push(Band {
                    bw,
                    rows,
                    start,
                    weights,
                });
            }
        }
        Ok(Self {
            species: ns,
            radii,
            band_of,
            bands,
            reduced,
            nodes,
            d_eta,
            eta_max: table.eta_max,
        })
    }

    /// Does the kernel read the local packing (`xi2`, `xi3`)?
    pub fn is_dense(&self) -> bool {
        self.nodes > 1
    }

    /// Drift velocities `u_i / D0_i` of species `i` at the interior faces `1..active` into
    /// `out`, from `g_j = rho_j d(beta mu_j)` at the cell centres (`g[j * cells + c]`), for
    /// Stokes mobilities (`kT / eta = 6 pi a_i D0_i`). `xi2`, `xi3`: the local packing of the
    /// cells (`point_packing`, or the weighted `sum_s n3_s / d_s`, `n3`), read by the dense
    /// pair correlations only (the dilute kernel takes empty slices).
    #[allow(clippy::too_many_arguments)]
    pub fn velocities(
        &self,
        i: usize,
        g: &[f64],
        xi2: &[f64],
        xi3: &[f64],
        cells: usize,
        active: usize,
        out: &mut [f64],
    ) {
        out[0] = 0.0;
        out[active] = 0.0;
        if self.nodes == 1 {
            for f in 1..active {
                out[f] = self.face_velocity(i, f, g, xi2, xi3, cells, active);
            }
        } else {
            out[1..active]
                .par_iter_mut()
                .with_min_len(32)
                .enumerate()
                .for_each(|(k, o)| *o = self.face_velocity(i, k + 1, g, xi2, xi3, cells, active));
        }
    }

    /// `u_i / D0_i` at one interior face.
    #[allow(clippy::too_many_arguments)]
    fn face_velocity(
        &self,
        i: usize,
        f: usize,
        g: &[f64],
        xi2: &[f64],
        xi3: &[f64],
        cells: usize,
        active: usize,
    ) -> f64 {
        let mut acc = 0.0;
        let (f2, f3) = if self.nodes > 1 {
            (0.5 * (xi2[f - 1] + xi2[f]), 0.5 * (xi3[f - 1] + xi3[f]))
        } else {
            (0.0, 0.0)
        };
        let top = (self.nodes - 1) as f64;
        for j in 0..self.species {
            let p = self.band_of[i * self.species + j];
            let b = &self.bands[p];
            let s = b.start[f];
            let e = (s + b.bw).min(active);
            if e <= s {
                continue;
            }
            let block = &b.weights[f * b.rows * b.bw..(f + 1) * b.rows * b.bw];
            let gj = &g[j * cells + s..j * cells + e];
            if b.rows == 1 {
                for (w, x) in block[..e - s].iter().zip(gj) {
                    acc += w * x;
                }
                continue;
            }
            let (dilute, tails) = block.split_at(b.bw);
            let dd = self.reduced[p];
            let inv = 1.0 / self.d_eta;
            for (k, gk) in gj.iter().enumerate() {
                let c = s + k;
                let e3 = 0.5 * (f3 + xi3[c]);
                let t = (e3 * inv).clamp(0.0, top);
                let node = (t as usize).min(self.nodes - 2);
                let frac = t - node as f64;
                let (lo, hi) = (tails[node * b.bw + k], tails[(node + 1) * b.bw + k]);
                let tail = lo + frac * (hi - lo);
                // `amplitude(e, q)` with `q = e2 dd / e3`, numerator and denominator times
                // `e3^2`: one division per cell.
                let amp = if e3 > 0.0 {
                    let e = e3.min(self.eta_max);
                    let (v, w) = (1.0 - e, 0.5 * (f2 + xi2[c]) * dd);
                    (v * e3 * (v * e3 + 3.0 * w) + 2.0 * e * w * w)
                        / (e3 * e3 * (2.5 - 3.0 * e + e * e))
                } else {
                    1.0
                };
                acc += (dilute[k] + amp * tail) * gk;
            }
        }
        -6.0 * PI * self.radii[i] * acc
    }
}

/// Bulk limit of the mixture RPY flux (uniform densities `rho`, a uniform force `F_j` on each
/// particle of species `j`, Stokes mobilities): `u_i / D0_i = beta F_i + sum_j C_ij beta F_j`,
/// returned as `C` (`C[i * n + j]`), with
/// `C_ij = 6 pi a_i rho_j [-(sigma_ij^2/3 - s_ij^2/9) + (2 sigma_ij^2 / 3) A_ij int_1^range x h_1(x; eta) dx]`
/// (the angular mean of the tensor along the force is `1/(6 pi eta r)`, whatever `s_ij`), `eta =
/// min(xi3, table.eta_max)`; the dilute pair correlation drops the last term. For one size
/// `1 + sum_j C_ij` is [`crate::radial::pair::bulk_sedimentation`] (tested).
pub fn bulk_coupling(
    diameters: &[f64],
    rho: &[f64],
    pair: PairCorrelation,
    table: PairTable,
) -> Result<Vec<f64>, RadialError> {
    table.validate()?;
    let ns = diameters.len();
    let xi = |p: i32| -> f64 {
        (0..ns)
            .map(|s| PI / 6.0 * rho[s] * diameters[s].powi(p))
            .sum()
    };
    let (xi2, xi3) = (xi(2), xi(3));
    let eta = xi3.min(table.eta_max);
    let moment = if pair == PairCorrelation::Dilute {
        0.0
    } else {
        first_moment(eta, table.range)?
    };
    let mut c = vec![0.0; ns * ns];
    for i in 0..ns {
        for j in 0..ns {
            let (ai, aj) = (0.5 * diameters[i], 0.5 * diameters[j]);
            let (sg, s2) = (ai + aj, ai * ai + aj * aj);
            let dd = diameters[i] * diameters[j] / (diameters[i] + diameters[j]);
            let a = if xi3 > 0.0 {
                amplitude(eta, xi2 * dd / xi3)
            } else {
                1.0
            };
            c[i * ns + j] = 6.0
                * PI
                * ai
                * rho[j]
                * (-(sg * sg / 3.0 - s2 / 9.0) + 2.0 * sg * sg / 3.0 * a * moment);
        }
    }
    Ok(c)
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

    #[test]
    fn moment_form_with_h_minus_one_inside_contact_is_the_closed_form() {
        for (ai, aj) in [(0.5, 1.0), (0.5, 0.5), (1.0, 1.0)] {
            let sigma = ai + aj;
            let from = 0.05;
            let m = TailMoments::new(|_| -1.0, from, sigma, sigma);
            for (x, y) in [(3.0, 3.4), (3.0, 2.2), (0.7, 0.5), (0.3, 1.4), (5.0, 6.3)] {
                let k = kernel(x, y, ai, aj);
                let t = tail_kernel(x, y, from, ai * ai + aj * aj, &m);
                assert!(
                    (k - t).abs() < 1e-8 * (1.0 + k.abs()),
                    "({ai},{aj}) ({x},{y}): {k} vs {t}"
                );
            }
        }
    }

    /// BMCSL partial contact values at `xi2 = 0.2`, `xi3 = 0.3` (`pi rho_s / 6 = 0.1`,
    /// `pi rho_l / 6 = 0.025`, `d = 1, 2`) by hand in fractions:
    /// `g_ss = 10/7 + (3/5)(100/49)(1/2) + (2/25)(1000/343)(1/4) = 720/343`,
    /// `g_sl = 10/7 + (60/49)(2/3) + (80/343)(4/9) = 7250/3087`, `g_ll = 990/343`; one size: the
    /// Carnahan–Starling contact value, and the amplitude 1.
    #[test]
    fn bmcsl_contact_values_and_their_one_size_limit() {
        let (xi2, xi3) = (0.2, 0.3);
        for ((di, dj), hand) in [
            ((1.0, 1.0), 720.0 / 343.0),
            ((1.0, 2.0), 7250.0 / 3087.0),
            ((2.0, 1.0), 7250.0 / 3087.0),
            ((2.0, 2.0), 990.0 / 343.0),
        ] {
            let g = bmcsl_contact(xi2, xi3, di, dj);
            assert!((g - hand).abs() < 1e-14, "({di},{dj}): {g} vs {hand}");
            // The amplitude is the ratio of the excess contact values.
            let a = amplitude(xi3, xi2 * di * dj / (di + dj) / xi3);
            let ratio = (g - 1.0) / (carnahan_starling_contact(xi3) - 1.0);
            assert!((a - ratio).abs() < 1e-13, "({di},{dj}): {a} vs {ratio}");
        }
        for eta in [1e-6, 0.01, 0.1, 0.3, 0.45, 0.6] {
            for d in [0.5, 1.0, 3.0] {
                let (xi2, xi3) = (eta / d, eta);
                let g = bmcsl_contact(xi2, xi3, d, d);
                let cs = carnahan_starling_contact(eta);
                assert!(
                    (g / cs - 1.0).abs() < 1e-14,
                    "eta {eta}, d {d}: {g} vs {cs}"
                );
                let a = amplitude(eta, xi2 * 0.5 * d / xi3);
                assert!((a - 1.0).abs() < 1e-14, "eta {eta}, d {d}: A = {a}");
            }
        }
    }

    /// Two species of equal diameter on the same (non-uniform) profile: each species' velocity
    /// is the one-size dense kernel's on the summed `g` and density.
    #[test]
    fn equal_diameters_give_the_one_size_dense_flux() {
        let grid = RadialGrid::covering(0.05, 7.0).unwrap();
        let n = grid.len();
        let d = 1.0;
        let table = PairTable::default();
        let r = grid.centres();
        let rho_a: Vec<f64> = r.iter().map(|x| 0.4 + 0.3 * (1.3 * x).sin()).collect();
        let rho_b: Vec<f64> = r.iter().map(|x| 0.3 + 0.2 * (0.7 * x).cos()).collect();
        let g_a: Vec<f64> = r.iter().map(|x| (0.9 * x).sin() * x).collect();
        let g_b: Vec<f64> = r.iter().map(|x| 0.5 - (0.4 * x).cos()).collect();
        let rho: Vec<f64> = rho_a.iter().zip(&rho_b).map(|(a, b)| a + b).collect();
        let g_sum: Vec<f64> = g_a.iter().zip(&g_b).map(|(a, b)| a + b).collect();
        let mut rho_ab = rho_a.clone();
        rho_ab.extend(&rho_b);
        let mut g_ab = g_a.clone();
        g_ab.extend(&g_b);
        for pair in [
            PairCorrelation::Dilute,
            PairCorrelation::Trokhymchuk,
            PairCorrelation::TrokhymchukWeighted,
        ] {
            let one = crate::radial::RpyKernel::with_pair(&grid, d, pair, table).unwrap();
            let mix = MixtureRpy::with_pair(&grid, &[d, d], pair, table).unwrap();
            // The one-size kernel reads eta = pi rho / 6 (point) or n3 (weighted; here a
            // made-up profile in the same range): the mixture gets the same as xi3 and xi2 = xi3/d.
            let local: Vec<f64> = if pair.reads_n3() {
                r.iter().map(|x| 0.25 + 0.2 * (0.5 * x).sin()).collect()
            } else {
                rho.clone()
            };
            let (mut xi2, mut xi3) = (vec![0.0; n], vec![0.0; n]);
            if pair.reads_n3() {
                xi3.copy_from_slice(&local);
                xi2.iter_mut().zip(&local).for_each(|(a, b)| *a = b / d);
            } else {
                point_packing(&[d, d], &rho_ab, n, n, &mut xi2, &mut xi3);
            }
            let mut u1 = vec![0.0; n + 1];
            one.velocities(&g_sum, &local, n, &mut u1);
            let scale = u1.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(scale > 1.0, "{pair:?}: a flux to compare ({scale})");
            for i in 0..2 {
                let mut u = vec![0.0; n + 1];
                mix.velocities(i, &g_ab, &xi2, &xi3, n, n, &mut u);
                let diff = u
                    .iter()
                    .zip(&u1)
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                eprintln!(
                    "{pair:?} species {i}: max |u_mix - u_one| / max |u| = {:.2e}",
                    diff / scale
                );
                assert!(
                    diff < 1e-12 * scale,
                    "{pair:?} species {i}: {}",
                    diff / scale
                );
            }
        }
    }

    /// Bulk limit: one size gives `pair::bulk_sedimentation`; two sizes at `eta -> 0` tend to
    /// the dilute coupling (the dense part is `O(eta)` relative to it).
    #[test]
    fn bulk_coupling_limits() {
        let table = PairTable::default();
        for eta in [0.05, 0.2, 0.35, 0.45] {
            for d in [1.0, 2.0] {
                let rho = eta / (PI / 6.0 * d * d * d);
                let c = bulk_coupling(&[d], &[rho], PairCorrelation::Trokhymchuk, table).unwrap();
                let k = crate::radial::pair::bulk_sedimentation(eta, table.range).unwrap();
                assert!(
                    (1.0 + c[0] - k).abs() < 1e-12,
                    "eta {eta}, d {d}: {} vs {k}",
                    1.0 + c[0]
                );
                let cd = bulk_coupling(&[d], &[rho], PairCorrelation::Dilute, table).unwrap();
                assert!((1.0 + cd[0] - (1.0 - 5.0 * eta)).abs() < 1e-12);
            }
        }
        let d = [1.0, 2.0];
        let mut last = f64::INFINITY;
        for eta in [1e-2, 1e-3, 1e-4] {
            // Equal volumes of the two sizes.
            let rho = [0.5 * eta / (PI / 6.0), 0.5 * eta / (PI / 6.0 * 8.0)];
            let dense = bulk_coupling(&d, &rho, PairCorrelation::Trokhymchuk, table).unwrap();
            let dilute = bulk_coupling(&d, &rho, PairCorrelation::Dilute, table).unwrap();
            let worst = dense
                .iter()
                .zip(&dilute)
                .fold(0.0f64, |m, (a, b)| m.max((a / b - 1.0).abs()));
            eprintln!("eta {eta}: dense / dilute - 1 up to {worst:.3e}");
            assert!(worst < 5.0 * eta && worst < last, "eta {eta}: {worst}");
            last = worst;
        }
    }

    /// The bulk collective mobility matrix `Lambda_ij = rho_i D0_i (delta_ij + C_ij)` (symmetric:
    /// `D0_i C_ij rho_i` is symmetric in `i, j`) of a size-ratio-2 mixture: positive definite at
    /// every composition and `xi3 <= 0.6` with the dense `g_ij` (so uniform bulk states are
    /// stable, as `K > 0` for one size), while the dilute one has a negative eigenvalue from
    /// `xi3 = 0.2` on (the mixture form of `1 - 5 phi < 0`).
    #[test]
    fn dense_bulk_mobility_matrix_is_positive_definite_where_the_dilute_one_is_not() {
        let d = [1.0, 2.0];
        let table = PairTable::default();
        let smallest = |pair: PairCorrelation, eta: f64, fs: f64| {
            let rho = [fs * eta / (PI / 6.0), (1.0 - fs) * eta / (PI / 6.0 * 8.0)];
            let c = bulk_coupling(&d, &rho, pair, table).unwrap();
            let l = |i: usize, j: usize| {
                rho[i] / d[i] * (if i == j { 1.0 } else { 0.0 } + c[i * 2 + j])
            };
            assert!((l(0, 1) - l(1, 0)).abs() < 1e-14, "symmetry");
            let (tr, det) = (l(0, 0) + l(1, 1), l(0, 0) * l(1, 1) - l(0, 1) * l(1, 0));
            // The smaller eigenvalue over the larger (scale-free).
            let disc = (0.25 * tr * tr - det).max(0.0).sqrt();
            (0.5 * tr - disc) / (0.5 * tr + disc)
        };
        for eta in [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6] {
            for fs in [0.1, 0.3, 0.5, 0.7, 0.9] {
                let dense = smallest(PairCorrelation::Trokhymchuk, eta, fs);
                assert!(dense > 1e-3, "eta {eta}, small fraction {fs}: {dense}");
                let dilute = smallest(PairCorrelation::Dilute, eta, fs);
                if eta >= 0.3 {
                    assert!(dilute < 0.0, "eta {eta}, small fraction {fs}: {dilute}");
                }
            }
        }
    }
}
