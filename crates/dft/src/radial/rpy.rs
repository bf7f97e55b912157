//! Pairwise Rotne–Prager–Yamakawa flux in spherical symmetry, dilute pair correlation
//! (the drying-droplet paper, docs/references.md, flyft `rpy_diffusive_flux`; paper Eqs. 16, 24–27).
//!
//! With `g(r) = Theta(r - d)`, the radial hydrodynamic flux is
//! `J_HI(x) = -rho(x) int dy M(x, y) rho(y) d_y(beta mu(y))` over `|x - d| < y < x + d`, where
//! (monodisperse, `a_i = a_j = a`, `kT / eta = 3 pi d D0`)
//! `M(x, y) = 5 a^2 kT / (24 x^2 eta d^3) (d-x-y)(d+x-y)(d-x+y)(d+x+y)
//!          = (5 pi D0 / (32 x^2)) [d^2 - (x-y)^2] [d^2 - (x+y)^2]`.
//! It is the far-field RPY pair tensor projected on the two radial directions, integrated over the
//! orientations allowed by `g` (the integral over a full shell vanishes, so only shells that can
//! overlap contribute, with the sign of the excluded part). Bulk sedimentation: `K = 1 - 5 phi`.

use std::f64::consts::PI;

use colloidsim_core::ParamError;
use rayon::prelude::*;

use super::RadialGrid;

/// `M(x, y) / D0` of the module docs.
#[inline]
pub fn kernel(x: f64, y: f64, diameter: f64) -> f64 {
    let d2 = diameter * diameter;
    if (x - y).abs() >= diameter || x + y <= diameter {
        return 0.0;
    }
    5.0 * PI / (32.0 * x * x) * (d2 - (x - y).powi(2)) * (d2 - (x + y).powi(2))
}

/// The bulk pair correlation `g` in the two-body density of the hydrodynamic flux (Eq. 17).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PairCorrelation {
    /// `g = Theta(r - d)` (the paper's first approximation; closed-form kernel).
    #[default]
    Dilute,
    /// Trokhymchuk et al.'s `g(r; eta)` at the mean of the two local packing fractions
    /// `pi d^3 rho / 6` (Eq. 17; [`super::pair`]), clamped to [`PairTable::eta_max`].
    Trokhymchuk,
    /// Trokhymchuk's `g` at the mean of the two *weighted* packing fractions `n3` (the FMT
    /// density averaged over a particle's volume) instead of the point densities: a
    /// weighted-density variant of Eq. 17 (not in the paper).
    TrokhymchukWeighted,
}

impl PairCorrelation {
    /// The name used on the command line and in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Self::Dilute => "dilute",
            Self::Trokhymchuk => "trokhymchuk",
            Self::TrokhymchukWeighted => "trokhymchuk-n3",
        }
    }

    /// Does the kernel read the weighted packing fraction `n3` (else the density)?
    pub fn reads_n3(self) -> bool {
        self == Self::TrokhymchukWeighted
    }
}

/// Packing-fraction nodes of the tabulated Trokhymchuk kernel: `eta_n = n * eta_max / 10`.
pub(in crate::radial) const PAIR_NODES: usize = 11;
/// Default [`PairTable::range`]: the tail of `h` beyond 8 d changes the bulk sedimentation
/// coefficient `12 eta int x h dx` by less than 2.1e-3 at every `eta <= 0.471`.
pub const PAIR_RANGE: f64 = 8.0;

/// How the Trokhymchuk kernel is tabulated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairTable {
    /// `h` is dropped beyond this distance, in diameters (`2..=30`; default 8).
    pub range: f64,
    /// Mean packing fractions above this are clamped to it (`0.2..=0.6`; default 0.6 as the
    /// paper's clip; above 0.471 the fits are extrapolated).
    pub eta_max: f64,
}

impl Default for PairTable {
    fn default() -> Self {
        Self {
            range: PAIR_RANGE,
            eta_max: super::pair::ETA_CLIP,
        }
    }
}

impl PairTable {
    pub(in crate::radial) fn validate(&self) -> Result<(), ParamError> {
        if !(self.range.is_finite() && (2.0..=30.0).contains(&self.range)) {
            return Err(ParamError::new(
                "pair_range",
                format!("must be in [2, 30] diameters, got {}", self.range),
            ));
        }
        if !(self.eta_max.is_finite() && (0.2..=super::pair::ETA_CLIP).contains(&self.eta_max)) {
            return Err(ParamError::new(
                "pair_eta_max",
                format!(
                    "must be in [0.2, {}], got {}",
                    super::pair::ETA_CLIP,
                    self.eta_max
                ),
            ));
        }
        Ok(())
    }
}

/// `int_from^R r^p h(r) dr` for `p = 0, 2, -2, -4` on a fine grid of `R` (cumulative Simpson,
/// step at most `d / 2000`, ending at `to`), read back by cubic Hermite interpolation (the derivative `R^p h(R)` is known).
pub(in crate::radial) struct TailMoments {
    from: f64,
    step: f64,
    integrals: Vec<[f64; 4]>,
    integrands: Vec<[f64; 4]>,
}

impl TailMoments {
    const POWERS: [i32; 4] = [0, 2, -2, -4];

    /// Moments of `h(r)` (`r` in lengths) on `[from, to]`.
    pub(in crate::radial) fn new(h: impl Fn(f64) -> f64, from: f64, to: f64, d: f64) -> Self {
        let n = ((to - from) / (d / 2000.0)).ceil().max(1.0) as usize;
        let step = (to - from) / n as f64;
        let f = |r: f64| -> [f64; 4] {
            let v = h(r);
            Self::POWERS.map(|p| r.powi(p) * v)
        };
        let mut integrands = Vec::with_capacity(n + 1);
        let mut integrals = Vec::with_capacity(n + 1);
        let mut acc = [0.0; 4];
        let mut f0 = f(from);
        integrands.push(f0);
        integrals.push(acc);
        for k in 0..n {
            let r0 = from + k as f64 * step;
            let fm = f(r0 + 0.5 * step);
            let f1 = f(r0 + step);
            for p in 0..4 {
                acc[p] += step / 6.0 * (f0[p] + 4.0 * fm[p] + f1[p]);
            }
            integrands.push(f1);
            integrals.push(acc);
            f0 = f1;
        }
        Self {
            from,
            step,
            integrals,
            integrands,
        }
    }

    /// The four moments from `from` to `r` (`from <= r`; beyond the table the last value).
    pub(in crate::radial) fn at(&self, r: f64) -> [f64; 4] {
        let t = (r - self.from) / self.step;
        let last = self.integrals.len() - 1;
        if t >= last as f64 {
            return self.integrals[last];
        }
        let k = (t.max(0.0) as usize).min(last - 1);
        let s = t - k as f64;
        let (s2, s3) = (s * s, s * s * s);
        let (h00, h10, h01, h11) = (
            2.0 * s3 - 3.0 * s2 + 1.0,
            s3 - 2.0 * s2 + s,
            -2.0 * s3 + 3.0 * s2,
            s3 - s2,
        );
        let (i0, i1) = (&self.integrals[k], &self.integrals[k + 1]);
        let (f0, f1) = (&self.integrands[k], &self.integrands[k + 1]);
        std::array::from_fn(|p| {
            h00 * i0[p] + h10 * self.step * f0[p] + h01 * i1[p] + h11 * self.step * f1[p]
        })
    }
}

/// `M(x, y) / D0` of the pairs at distance `r > m.from` (`d` in use), for a total correlation
/// `h` (moments `m`):
/// the far-field RPY pair tensor projected on both radial directions and integrated over the
/// orientations, written in `r` (`c = (x^2 + y^2 - r^2) / (2 x y)`):
/// `(3 pi a / (8 x^2)) int [(2P + 2a^2/3) - 3 r^2 + (4 a^2 P / 3 + Q^2) / r^2 - 2 a^2 Q^2 / r^4]
/// h(r) dr` over `max(from, |x - y|) < r < x + y`, with `P = x^2 + y^2`, `Q = x^2 - y^2`.
/// With `h = -1` over `r < d` the same integral gives [`kernel`] (tested).
fn tail_kernel(x: f64, y: f64, diameter: f64, m: &TailMoments) -> f64 {
    let lo = (x - y).abs().max(m.from);
    let hi = x + y;
    if hi <= lo {
        return 0.0;
    }
    let a = 0.5 * diameter;
    let (p, q) = (x * x + y * y, x * x - y * y);
    let (ml, mh) = (m.at(lo), m.at(hi));
    let c = [
        2.0 * p + 2.0 * a * a / 3.0,
        -3.0,
        4.0 * a * a * p / 3.0 + q * q,
        -2.0 * a * a * q * q,
    ];
    let s: f64 = (0..4).map(|k| c[k] * (mh[k] - ml[k])).sum();
    3.0 * PI * a / (8.0 * x * x) * s
}

/// Kernel integrated over the cells for every interior face: `u_f = -D0 sum_j K[f, j] g_j`
/// (`K` the cell integral of the kernel) is the hydrodynamic drift velocity at face `f`,
/// `J_HI = rho u`, for `g_j = rho_j d_y(beta mu)` at the cell centres.
///
/// With the Trokhymchuk pair correlation `K` is tabulated at 11 packing fractions from 0 (the
/// dilute kernel) to [`PairTable::eta_max`] and interpolated linearly at the mean
/// `(eta(x_f) + eta(y_j)) / 2` of the local packing fractions `pi d^3 rho / 6` (face values
/// are the mean of the two cells).
#[derive(Debug, Clone)]
pub struct RpyKernel {
    bw: usize,
    nodes: usize,
    /// `pi d^3 / 6` over the node spacing: node coordinate of a density.
    rho_to_node: f64,
    start: Vec<usize>,
    weights: Vec<f64>,
}

impl RpyKernel {
    /// Precompute for `grid`, particle `diameter` and the dilute pair correlation.
    pub fn new(grid: &RadialGrid, diameter: f64) -> Self {
        Self::with_pair(
            grid,
            diameter,
            PairCorrelation::Dilute,
            PairTable::default(),
        )
        .expect("the dilute kernel has no parameters to refuse")
    }

    /// A kernel given as banded weights: row `f` (face `f`) holds `bw` cell integrals starting at
    /// cell `start[f]` (`weights[f * bw + k]`, the dilute layout), as built by
    /// [`super::g2::TabulatedPair::kernel`].
    pub(super) fn from_banded(bw: usize, start: Vec<usize>, weights: Vec<f64>) -> Self {
        debug_assert_eq!(start.len() * bw, weights.len());
        Self {
            bw,
            nodes: 1,
            rho_to_node: 0.0,
            start,
            weights,
        }
    }

    /// Number of faces the kernel was built for (cells + 1).
    pub fn faces(&self) -> usize {
        self.start.len()
    }

    /// The bytes [`Self::with_pair`] will hold.
    pub fn memory_bytes(
        grid: &RadialGrid,
        diameter: f64,
        pair: PairCorrelation,
        table: PairTable,
    ) -> usize {
        let (bw, nodes) = Self::shape(grid.dr(), diameter, pair, table);
        (grid.len() + 1) * bw * nodes * std::mem::size_of::<f64>()
    }

    fn shape(dr: f64, diameter: f64, pair: PairCorrelation, table: PairTable) -> (usize, usize) {
        match pair {
            PairCorrelation::Dilute => ((2.0 * diameter / dr).ceil() as usize + 3, 1),
            PairCorrelation::Trokhymchuk | PairCorrelation::TrokhymchukWeighted => (
                (2.0 * table.range * diameter / dr).ceil() as usize + 3,
                PAIR_NODES,
            ),
        }
    }

    /// Precompute for `grid`, particle `diameter` and pair correlation `pair`. The dilute
    /// kernel is integrated exactly over each cell piece (3-point Gauss–Legendre on a quartic);
    /// the tail by 3-point Gauss–Legendre on pieces split where `|x - y| = d` and `x + y = d`.
    pub fn with_pair(
        grid: &RadialGrid,
        diameter: f64,
        pair: PairCorrelation,
        table: PairTable,
    ) -> Result<Self, super::RadialError> {
        table.validate()?;
        let dr = grid.dr();
        let faces = grid.faces();
        let nf = faces.len();
        let n = grid.len();
        let (bw, nodes) = Self::shape(dr, diameter, pair, table);
        let reach = match pair {
            PairCorrelation::Dilute => diameter,
            PairCorrelation::Trokhymchuk | PairCorrelation::TrokhymchukWeighted => {
                table.range * diameter
            }
        };
        let d_eta = table.eta_max / (PAIR_NODES - 1) as f64;
        if nodes > 1 {
            colloidsim_core::resources::ensure_fits(
                "dr",
                &format!(
                    "the RPY kernel tables of {nf} faces x {bw} cells x {nodes} packing fractions (grid spacing {dr:.3e}; a larger --dx makes them smaller)"
                ),
                (nf * bw * nodes * std::mem::size_of::<f64>()) as f64,
            )?;
        }
        let tails: Vec<Option<TailMoments>> = (0..nodes)
            .map(|k| {
                if pair == PairCorrelation::Dilute || k == 0 {
                    return Ok(None);
                }
                let h = super::pair::TotalCorrelation::new(k as f64 * d_eta)?;
                Ok(Some(TailMoments::new(
                    |r| h.h(r / diameter),
                    diameter,
                    reach,
                    diameter,
                )))
            })
            .collect::<Result<_, ParamError>>()?;
        let mut start = vec![0; nf];
        let mut weights = vec![0.0; nf * bw * nodes];
        let gl = [
            (-(0.6f64).sqrt(), 5.0 / 9.0),
            (0.0, 8.0 / 9.0),
            ((0.6f64).sqrt(), 5.0 / 9.0),
        ];
        let mut cuts = Vec::with_capacity(6);
        for f in 1..nf.saturating_sub(1) {
            let x = faces[f];
            let lo_y = (x - reach).max(0.0);
            let hi_y = x + reach;
            let s = (lo_y / dr).floor() as usize;
            start[f] = s;
            for k in 0..bw {
                let j = s + k;
                if j >= n {
                    break;
                }
                let lo = faces[j].max(lo_y);
                let hi = faces[j + 1].min(hi_y);
                if hi <= lo {
                    continue;
                }
                cuts.clear();
                cuts.push(lo);
                for c in [x - diameter, x + diameter, diameter - x] {
                    if c > lo && c < hi {
                        cuts.push(c);
                    }
                }
                cuts.push(hi);
                cuts.sort_by(f64::total_cmp);
                // Layout [face][node][cell]: a face's rows for two neighbouring nodes are read
                // together in `velocities`.
                let block = &mut weights[f * nodes * bw..(f + 1) * nodes * bw];
                for piece in cuts.windows(2) {
                    let (c, h) = (0.5 * (piece[0] + piece[1]), 0.5 * (piece[1] - piece[0]));
                    for (t, w) in gl {
                        let y = c + h * t;
                        let dilute = kernel(x, y, diameter);
                        for (node, tail) in tails.iter().enumerate() {
                            let extra = tail
                                .as_ref()
                                .map_or(0.0, |m| tail_kernel(x, y, diameter, m));
                            block[node * bw + k] += w * h * (dilute + extra);
                        }
                    }
                }
            }
        }
        Ok(Self {
            bw,
            nodes,
            rho_to_node: if pair.reads_n3() {
                1.0 / d_eta
            } else {
                PI * diameter.powi(3) / 6.0 / d_eta
            },
            start,
            weights,
        })
    }

    /// Drift velocities `u_f / D0` at the interior faces `1..active` from `g` (cells
    /// `0..active`); `rho` (the density of the cells, or their `n3` when
    /// [`PairCorrelation::reads_n3`]) sets the pair correlation's packing fraction (unused by
    /// the dilute kernel).
    pub fn velocities(&self, g: &[f64], rho: &[f64], active: usize, out: &mut [f64]) {
        out[0] = 0.0;
        out[active] = 0.0;
        if self.nodes == 1 && self.bw * active < 100_000 {
            for f in 1..active {
                out[f] = self.face_velocity(f, g, rho, active);
            }
        } else {
            // Each face's sum is serial, so the result does not depend on the thread count.
            out[1..active]
                .par_iter_mut()
                .with_min_len(32)
                .enumerate()
                .for_each(|(k, o)| *o = self.face_velocity(k + 1, g, rho, active));
        }
    }

    /// `u_f / D0` at one interior face.
    fn face_velocity(&self, f: usize, g: &[f64], rho: &[f64], active: usize) -> f64 {
        let s = self.start[f];
        let e = (s + self.bw).min(active);
        if e <= s {
            return 0.0;
        }
        let block = &self.weights[f * self.nodes * self.bw..(f + 1) * self.nodes * self.bw];
        let mut acc = 0.0;
        if self.nodes == 1 {
            for (wk, gk) in block[..e - s].iter().zip(&g[s..e]) {
                acc += wk * gk;
            }
        } else {
            let top = (self.nodes - 1) as f64;
            let face = 0.5 * (rho[f - 1] + rho[f]) * self.rho_to_node;
            for (k, (gk, rk)) in g[s..e].iter().zip(&rho[s..e]).enumerate() {
                let t = (0.5 * (face + rk * self.rho_to_node)).clamp(0.0, top);
                let i = (t as usize).min(self.nodes - 2);
                let frac = t - i as f64;
                let (lo, hi) = (block[i * self.bw + k], block[(i + 1) * self.bw + k]);
                acc += (lo + frac * (hi - lo)) * gk;
            }
        }
        -acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `M / D0` by direct quadrature of the far-field RPY pair tensor over allowed orientations.
    fn direct(x: f64, y: f64, d: f64) -> f64 {
        // Units kT = eta = 1: D0 = 1 / (3 pi d).
        let d0 = 1.0 / (3.0 * PI * d);
        let a = 0.5 * d;
        let c_max = ((x * x + y * y - d * d) / (2.0 * x * y)).min(1.0);
        if c_max <= -1.0 {
            return 0.0;
        }
        let m = 200_000;
        let h = (c_max + 1.0) / m as f64;
        let mut s = 0.0;
        for k in 0..m {
            let c = -1.0 + (k as f64 + 0.5) * h;
            let r2 = x * x + y * y - 2.0 * x * y * c;
            let r = r2.sqrt();
            let proj = (x - y * c) * (x * c - y) / r2;
            let om = 1.0 / (8.0 * PI * r)
                * ((1.0 + 2.0 * a * a / (3.0 * r2)) * c + (1.0 - 2.0 * a * a / r2) * proj);
            s += om * h;
        }
        2.0 * PI * y * y * s / d0
    }

    #[test]
    fn closed_form_matches_angular_quadrature() {
        let d = 1.0;
        for (x, y) in [
            (3.0, 3.4),
            (3.0, 2.2),
            (0.7, 0.5),
            (0.3, 1.1),
            (5.0, 6.5),
            (0.4, 0.3),
        ] {
            let k = kernel(x, y, d);
            let q = direct(x, y, d);
            assert!(
                (k - q).abs() < 1e-6 * (1.0 + q.abs()),
                "({x},{y}): {k} vs {q}"
            );
        }
    }

    #[test]
    fn moment_form_with_h_minus_one_inside_the_core_is_the_closed_form() {
        let d = 1.0;
        let from = 0.05;
        let m = TailMoments::new(|_| -1.0, from, d, d);
        for (x, y) in [
            (3.0, 3.4),
            (3.0, 2.2),
            (0.7, 0.5),
            (0.3, 1.1),
            (5.0, 6.5),
            (4.0, 4.06),
        ] {
            let k = kernel(x, y, d);
            let t = tail_kernel(x, y, d, &m);
            assert!(
                (k - t).abs() < 1e-8 * (1.0 + k.abs()),
                "({x},{y}): {k} vs {t}"
            );
        }
    }

    #[test]
    fn bulk_sedimentation_coefficient() {
        // Far from the centre: rho^2 int M dy = -5 phi rho D0 (K = 1 - 5 phi).
        let d = 1.0;
        let x = 400.0;
        let m = 20000;
        let h = 2.0 * d / m as f64;
        let s: f64 = (0..m)
            .map(|k| kernel(x, x - d + (k as f64 + 0.5) * h, d) * h)
            .sum();
        let rho = 1.0;
        let phi = PI * rho / 6.0;
        assert!(
            (rho * s / (-5.0 * phi) - 1.0).abs() < 1e-2,
            "{}",
            rho * s / (-5.0 * phi)
        );
    }
}
