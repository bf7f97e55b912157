//! Forces on rods: external fields and pair interactions beyond the hard core.
//!
//! Any continuous force field plugs into the engine through [`ExternalForce`] and any continuous
//! pair force through [`PairForce`]; the engine is generic over both, so the innermost loop has
//! no dynamic dispatch.

use colloidsim_core::ParamError;
use colloidsim_core::field1d::ExternalField;

/// 0, 1, ..., 63 as floats: rod indices `i0 + IOTA[k]` without a per-rod integer conversion
/// (exact below 2^53).
const IOTA: [f64; 64] = {
    let mut a = [0.0; 64];
    let mut k = 0;
    while k < 64 {
        a[k] = k as f64;
        k += 1;
    }
    a
};

/// A one-body force f(x) (energy/length). Implemented for closures `Fn(f64) -> f64`.
pub trait ExternalForce: Send + Sync {
    /// Force at position `x` (unwrapped coordinates).
    fn force(&self, x: f64) -> f64;

    /// `out[k] = force(x[k] + offset)` for a run of rods (the engine's inner loop; fields with
    /// a cheaper batched form override it).
    #[inline]
    fn force_block(&self, x: &[f64], offset: f64, out: &mut [f64]) {
        for (o, &xk) in out.iter_mut().zip(x) {
            *o = self.force(xk + offset);
        }
    }

    /// `out[k] = force(y[k] + (first + k) sigma)`: the forces on rods `first, first + 1, ...`
    /// from their reduced positions `y_i = x_i - i sigma` (the ring update's inner loop). The
    /// default forms the positions and calls [`force_block`](Self::force_block).
    #[inline]
    fn force_block_reduced(&self, y: &[f64], first: usize, sigma: f64, out: &mut [f64]) {
        let mut x = [0.0f64; 64];
        for (c, (ys, os)) in y.chunks(64).zip(out.chunks_mut(64)).enumerate() {
            let x = &mut x[..ys.len()];
            let i0 = (first + 64 * c) as f64;
            for ((xk, &yk), &i) in x.iter_mut().zip(ys).zip(&IOTA) {
                *xk = yk + (i0 + i) * sigma;
            }
            self.force_block(x, 0.0, os);
        }
    }
}

impl<F: Fn(f64) -> f64 + Send + Sync> ExternalForce for F {
    #[inline]
    fn force(&self, x: f64) -> f64 {
        self(x)
    }
}

/// No external force.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoField;

impl ExternalForce for NoField {
    #[inline]
    fn force(&self, _x: f64) -> f64 {
        0.0
    }
}

/// A periodic external force tabulated with cubic Hermite interpolation of the exact values and
/// slopes on `cells` cells per period: one table look-up instead of transcendental functions.
/// The interpolation error is O(h^4); [`ForceTable::from_field`] chooses `cells` so that the
/// largest error (checked at every cell midpoint) stays below `1e-9` of the largest force.
///
/// Cell `i` covers `[(i - 1/2) h, (i + 1/2) h)`, so the look-up is a rounding to the nearest
/// knot, done branch-free by adding `1.5 * 2^52` (the sum's low bits are the rounded integer).
#[derive(Debug, Clone)]
pub struct ForceTable {
    inv_h: f64,
    h: f64,
    /// Cells per period (a power of two, so the periodic wrap is a bit mask).
    cells: usize,
    /// Per cell, the cubic `c0 + c1 t + c2 t^2 + c3 t^3` in the centred cell coordinate
    /// `t = x / h - i` in [-1/2, 1/2], with the drive included in `c0`.
    cubic: Vec<[f64; 4]>,
    /// Largest interpolation error found at the cell midpoints.
    pub max_error: f64,
}

/// `1.5 * 2^52`: for |s| < 2^51, `s + ROUND` rounds `s` to an integer held in the low bits.
const ROUND: f64 = 6_755_399_441_055_744.0;

/// `2^50`: the rounding trick serves `|x / h| < NEAR`, larger (and non-finite) arguments take
/// the far path.
const NEAR: f64 = (1u64 << 50) as f64;

impl ForceTable {
    /// Tabulate a periodic `field` (its drive is added exactly). Returns `None` when the field
    /// has no period.
    pub fn from_field(field: &ExternalField) -> Option<Self> {
        let period = field.period()?;
        let exact = |x: f64| field.force(x) - field.drive;
        let fmax = (0..1024)
            .map(|i| exact(period * i as f64 / 1024.0).abs())
            .fold(0.0, f64::max)
            .max(1e-300);
        let mut cells = 1024;
        loop {
            let t = Self::build(period, cells, &exact, field.drive);
            if t.max_error <= 1e-9 * fmax || cells >= 1 << 22 {
                return Some(t);
            }
            cells *= 4;
        }
    }

    fn build(period: f64, cells: usize, f: &dyn Fn(f64) -> f64, drive: f64) -> Self {
        let h = period / cells as f64;
        let d = 1e-4 * h;
        // Knots at the cell edges (i - 1/2) h, i = 0..=cells.
        let knots: Vec<[f64; 2]> = (0..=cells)
            .map(|i| {
                let x = (i as f64 - 0.5) * h;
                // Slope by a fourth-order central difference: exact to ~1e-12 relative.
                let slope = (-f(x + 2.0 * d) + 8.0 * f(x + d) - 8.0 * f(x - d) + f(x - 2.0 * d))
                    / (12.0 * d);
                [f(x), slope * h]
            })
            .collect();
        // Hermite data (f, h f') at the two ends of each cell as a cubic in tau = t + 1/2 in
        // [0, 1], re-expanded about the cell centre (tau = 1/2).
        let cubic = knots
            .windows(2)
            .map(|k| {
                let ([f0, m0], [f1, m1]) = (k[0], k[1]);
                let (a0, a1, a2, a3) = (
                    f0,
                    m0,
                    3.0 * (f1 - f0) - 2.0 * m0 - m1,
                    2.0 * (f0 - f1) + m0 + m1,
                );
                [
                    drive + a0 + 0.5 * a1 + 0.25 * a2 + 0.125 * a3,
                    a1 + a2 + 0.75 * a3,
                    a2 + 1.5 * a3,
                    a3,
                ]
            })
            .collect();
        let mut t = Self {
            inv_h: 1.0 / h,
            h,
            cells,
            cubic,
            max_error: 0.0,
        };
        t.max_error = (0..cells)
            .map(|i| {
                let x = i as f64 * h;
                (t.force(x) - drive - f(x)).abs()
            })
            .fold(0.0, f64::max);
        t
    }

    /// Table spacing.
    pub fn spacing(&self) -> f64 {
        self.h
    }

    /// The look-up for |x / h| >= 2^50 (and non-finite x), with an explicit floor.
    #[cold]
    fn force_far(&self, s: f64) -> f64 {
        if !s.is_finite() {
            return f64::NAN;
        }
        let r = s.round();
        let t = s - r;
        let i = (r.rem_euclid(self.cells as f64)) as usize;
        let [c0, c1, c2, c3] = self.cubic[i];
        c0 + t * (c1 + t * (c2 + t * c3))
    }
}

impl ExternalForce for ForceTable {
    /// The batched look-up, one branch-free pass that LLVM vectorises: the values of every rod
    /// and, alongside, whether any `|x / h|` is not below 2^50 (or NaN); only then is the run
    /// redone rod by rod with [`ExternalForce::force`]. Bitwise equal to `force(x + offset)`.
    #[inline]
    fn force_block(&self, x: &[f64], offset: f64, out: &mut [f64]) {
        /// Rods per step of the vectorised loop.
        const R: usize = 4;
        let (inv_h, cubic) = (self.inv_h, &self.cubic[..]);
        // `cells` is a power of two, so the index is in bounds without a check.
        let mask = cubic.len() - 1;
        let n = out.len().min(x.len());
        let (out, x) = (&mut out[..n], &x[..n]);
        let mut far = [false; R];
        let (head, tail) = out.split_at_mut(n / R * R);
        for (o, xs) in head.chunks_exact_mut(R).zip(x.chunks_exact(R)) {
            let s: [f64; R] = std::array::from_fn(|j| (xs[j] + offset) * inv_h);
            let big = s.map(|s| s + ROUND);
            let c: [[f64; 4]; R] =
                std::array::from_fn(|j| cubic[(big[j].to_bits() as usize) & mask]);
            for j in 0..R {
                // NaN fails the comparison and counts as far.
                let near = s[j].abs() < NEAR;
                far[j] |= !near;
                let t = s[j] - (big[j] - ROUND);
                let [c0, c1, c2, c3] = c[j];
                o[j] = c0 + t * (c1 + t * (c2 + t * c3));
            }
        }
        for (o, &xk) in tail.iter_mut().zip(&x[n / R * R..]) {
            let s = (xk + offset) * inv_h;
            let near = s.abs() < NEAR;
            far[0] |= !near;
            let big = s + ROUND;
            let t = s - (big - ROUND);
            let [c0, c1, c2, c3] = cubic[(big.to_bits() as usize) & mask];
            *o = c0 + t * (c1 + t * (c2 + t * c3));
        }
        if far.iter().any(|&f| f) {
            for (o, &xk) in out.iter_mut().zip(x) {
                *o = self.force(xk + offset);
            }
        }
    }

    #[inline]
    fn force(&self, x: f64) -> f64 {
        let s = x * self.inv_h;
        // NaN fails the comparison and takes the far path too.
        let near = s.abs() < NEAR;
        if !near {
            return self.force_far(s);
        }
        let big = s + ROUND;
        let t = s - (big - ROUND);
        let i = (big.to_bits() as usize) & (self.cells - 1);
        let [c0, c1, c2, c3] = self.cubic[i];
        c0 + t * (c1 + t * (c2 + t * c3))
    }
}

/// The force of a sum of cosine potentials `U = sum_k (A_k / 2) cos(2 pi x / lambda_k)` plus a
/// drive `F0`: `F(x) = F0 + sum_k (A_k / 2) (2 pi / lambda_k) sin(2 pi x / lambda_k)`
/// (hard-rods paper Sec. III C), evaluated exactly (to ~1e-15 of the amplitude) by a branch-free
/// sine that the compiler vectorises: no table, no look-up.
///
/// The sine: `u = x / lambda` is reduced to `v = 2 (u - round(u))` in [-1, 1], folded into
/// [-1/2, 1/2] by `sin(pi v) = sin(pi (1 - v)) = sin(pi (-1 - v))`, and `sin(w)`, `|w| <= pi/2`,
/// is its Taylor series to `w^19` (truncation below 3e-16).
#[derive(Debug, Clone, PartialEq)]
pub struct CosineForce {
    /// Per term: `[1 / lambda, A pi / lambda]` (the force amplitude).
    terms: Vec<[f64; 2]>,
    drive: f64,
}

/// Taylor coefficients of `sin(w) / w` in powers of `w^2`: `(-1)^n / (2n + 1)!`.
const SIN_TAYLOR: [f64; 10] = {
    let mut c = [0.0; 10];
    let mut n = 0;
    let mut f = 1.0; // (2n + 1)!
    while n < 10 {
        c[n] = if n % 2 == 0 { 1.0 / f } else { -1.0 / f };
        f *= ((2 * n + 2) * (2 * n + 3)) as f64;
        n += 1;
    }
    c
};

/// Is `u` within reach of the branch-free reduction (`|u| < 2^50`; false for NaN)?
#[inline(always)]
fn reducible(u: f64) -> bool {
    u.abs() < (1u64 << 50) as f64
}

/// The reduced sine argument `w = pi v` in [-pi/2, pi/2] with `sin(w) = sin(2 pi u)`, for
/// `|u| < 2^50` (branch-free; see [`CosineForce`]).
#[inline(always)]
fn sin_turns_arg(u: f64) -> f64 {
    let r = u - ((u + ROUND) - ROUND);
    let v = 2.0 * r;
    // min(v, 1 - v) then max(., -1 - v), written as selects: `f64::min`/`max` would also
    // handle NaN, which costs two more instructions per vector and cannot occur here.
    let (a, b) = (1.0 - v, -1.0 - v);
    let m = if v < a { v } else { a };
    std::f64::consts::PI * if m > b { m } else { b }
}

/// `sin(w)` for `|w| <= pi/2`: the series summed by Estrin's scheme with fused multiply-adds
/// (short dependency chains; `mul_add` rounds once, the same on every CPU).
#[inline(always)]
fn sin_reduced(w: f64) -> f64 {
    let c = &SIN_TAYLOR;
    let w2 = w * w;
    let w4 = w2 * w2;
    let w8 = w4 * w4;
    let w16 = w8 * w8;
    let a0 = c[1].mul_add(w2, c[0]);
    let a1 = c[3].mul_add(w2, c[2]);
    let a2 = c[5].mul_add(w2, c[4]);
    let a3 = c[7].mul_add(w2, c[6]);
    let a4 = c[9].mul_add(w2, c[8]);
    let b0 = a1.mul_add(w4, a0);
    let b1 = a3.mul_add(w4, a2);
    w * a4.mul_add(w16, b1.mul_add(w8, b0))
}

impl CosineForce {
    /// The field as cosine terms and a drive, or None when it has other terms.
    pub fn from_field(field: &ExternalField) -> Option<Self> {
        use colloidsim_core::field1d::FieldTerm;
        let terms = field
            .terms
            .iter()
            .map(|t| match t {
                FieldTerm::Cosine {
                    amplitude,
                    wavelength,
                } => Some([
                    1.0 / wavelength,
                    amplitude * std::f64::consts::PI / wavelength,
                ]),
                _ => None,
            })
            .collect::<Option<Vec<_>>>()?;
        (!terms.is_empty()).then_some(Self {
            terms,
            drive: field.drive,
        })
    }

    /// The exact force, for positions too far out for the branch-free reduction.
    #[cold]
    fn force_far(&self, x: f64) -> f64 {
        let tau = std::f64::consts::TAU;
        self.drive
            + self
                .terms
                .iter()
                .map(|&[k, a]| a * (tau * (x * k).fract()).sin())
                .sum::<f64>()
    }
}

impl ExternalForce for CosineForce {
    #[inline]
    fn force(&self, x: f64) -> f64 {
        let mut f = self.drive;
        for &[k, a] in &self.terms {
            let u = x * k;
            if !reducible(u) {
                return self.force_far(x);
            }
            f += a * sin_reduced(sin_turns_arg(u));
        }
        f
    }

    fn force_block(&self, x: &[f64], offset: f64, out: &mut [f64]) {
        self.forces_at(x, 0, out, |xk, _| xk + offset);
    }

    fn force_block_reduced(&self, y: &[f64], first: usize, sigma: f64, out: &mut [f64]) {
        // (i0 + i) in `forces_at` is exact: the same index as (first + 64 c + i) as f64.
        self.forces_at(y, first, out, |yk, i| yk + i * sigma);
    }
}

impl CosineForce {
    /// `out[k]` = the force at `pos(v[k], first + k)` (the index as a float). Two simple passes
    /// per run of up to 64 rods (reduction, then the series), so that the compiler can overlap
    /// neighbouring rods' long dependency chains.
    #[inline(always)]
    fn forces_at(&self, v: &[f64], first: usize, out: &mut [f64], pos: impl Fn(f64, f64) -> f64) {
        let mut w = [0.0f64; 64];
        let mut far = false;
        for (c, (vs, os)) in v.chunks(64).zip(out.chunks_mut(64)).enumerate() {
            os.fill(self.drive);
            let w = &mut w[..os.len()];
            let i0 = (first + 64 * c) as f64;
            for &[k, a] in &self.terms {
                for ((wk, &vk), &i) in w.iter_mut().zip(vs).zip(&IOTA) {
                    let u = pos(vk, i0 + i) * k;
                    far |= !reducible(u);
                    *wk = sin_turns_arg(u);
                }
                add_sines(os, w, a);
            }
        }
        if far {
            for (i, (o, &vk)) in out.iter_mut().zip(v).enumerate() {
                *o = self.force(pos(vk, (first + i) as f64));
            }
        }
    }
}

/// `out[k] += a sin(w[k])` for reduced arguments `w` (see [`sin_reduced`]).
#[inline(always)]
fn add_sines(out: &mut [f64], w: &[f64], a: f64) {
    for (o, &wk) in out.iter_mut().zip(w) {
        *o += a * sin_reduced(wk);
    }
}

/// An external field evaluated exactly (for non-periodic fields such as a harmonic trap).
impl ExternalForce for ExternalField {
    #[inline]
    fn force(&self, x: f64) -> f64 {
        ExternalField::force(self, x)
    }
}

/// A central pair force between rods at centre distance `r >= sigma`, positive when repulsive.
pub trait PairForce: Send + Sync {
    /// Distance beyond which the force vanishes (0 for none).
    fn range(&self) -> f64;
    /// Force magnitude at distance `r` (positive pushes the rods apart).
    fn force(&self, r: f64) -> f64;
}

/// No pair force beyond the hard core.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoPair;

impl PairForce for NoPair {
    #[inline]
    fn range(&self) -> f64 {
        0.0
    }
    #[inline]
    fn force(&self, _r: f64) -> f64 {
        0.0
    }
}

/// Baxter's sticky contact represented by the power law of order `p` on `[sigma, sigma + eps]`
/// (hard-rods paper Eq. 33):
/// `f(r) = -kT gamma p (eps + sigma - r)^(p-1) / (eps^(p+1)/(p+1) + gamma (eps + sigma - r)^p)`.
#[derive(Debug, Clone, Copy)]
pub struct Sticky {
    /// Strength gamma of the delta-function adhesion.
    pub gamma: f64,
    /// Virtual range eps.
    pub eps: f64,
    /// Order p > 1.
    pub order: f64,
    /// Rod length sigma.
    pub sigma: f64,
    /// Thermal energy kT.
    pub kt: f64,
}

impl Sticky {
    /// Validate the sticky parameters; errors name the parameter (`gamma`, `eps`, `order`, `kt`).
    pub fn new(gamma: f64, eps: f64, order: f64, sigma: f64, kt: f64) -> Result<Self, ParamError> {
        colloidsim_core::param::positive("gamma", gamma)?;
        colloidsim_core::param::positive("eps", eps)?;
        if !(order > 1.0 && order.is_finite()) {
            return Err(ParamError::new(
                "order",
                format!("must be a finite number > 1 for a continuous force (Eq. 32), got {order}"),
            ));
        }
        if eps >= sigma {
            return Err(ParamError::new(
                "eps",
                format!("must be much smaller than the rod length {sigma}, got {eps}"),
            ));
        }
        if kt <= 0.0 {
            return Err(ParamError::new(
                "kt",
                "sticky rods are defined by a Boltzmann factor and need kT > 0",
            ));
        }
        Ok(Self {
            gamma,
            eps,
            order,
            sigma,
            kt,
        })
    }

    /// Largest |f| over the range (for the time-step criterion Eq. 34), in closed form: with
    /// `u = eps + sigma - r` and `A = eps^(p+1) / (p+1)`, `|f| = kT gamma p u^(p-1) / (A + gamma u^p)`
    /// is largest where `gamma u^p = (p - 1) A`, with the value `kT gamma u^(p-1) / A`, or at the
    /// contact `u = eps` when that point lies beyond it. The hard-rods paper's Fig. 5(b): at
    /// `eps = 0.05`, `gamma = 1` it is smallest for `p = 2.95`.
    pub fn max_force(&self) -> f64 {
        let (p, eps) = (self.order, self.eps);
        let a = eps.powf(p + 1.0) / (p + 1.0);
        let u = ((p - 1.0) * a / self.gamma).powf(1.0 / p).min(eps);
        self.kt * self.gamma * p * u.powf(p - 1.0) / (a + self.gamma * u.powf(p))
    }
}

impl PairForce for Sticky {
    #[inline]
    fn range(&self) -> f64 {
        self.sigma + self.eps
    }
    #[inline]
    fn force(&self, r: f64) -> f64 {
        let s = self.eps + self.sigma - r.max(self.sigma);
        if s <= 0.0 {
            return 0.0;
        }
        let p = self.order;
        let spm1 = s.powf(p - 1.0);
        -self.kt * self.gamma * p * spm1
            / (self.eps.powf(p + 1.0) / (p + 1.0) + self.gamma * spm1 * s)
    }
}

/// Screened-Coulomb (Yukawa) repulsion between rod surfaces, truncated and force-shifted at
/// `cutoff`: `U(r) = strength exp(-(r - sigma)/screening)` for `sigma <= r < cutoff`.
#[derive(Debug, Clone, Copy)]
pub struct Yukawa {
    /// Contact energy (energy units; negative for attraction).
    pub strength: f64,
    /// Screening length.
    pub screening: f64,
    /// Cutoff distance (centre to centre).
    pub cutoff: f64,
    /// Rod length.
    pub sigma: f64,
    shift: f64,
}

impl Yukawa {
    /// Validate; errors name the parameter (`strength`, `screening`, `cutoff`).
    pub fn new(strength: f64, screening: f64, cutoff: f64, sigma: f64) -> Result<Self, ParamError> {
        colloidsim_core::param::finite("strength", strength)?;
        colloidsim_core::param::positive("screening", screening)?;
        if !(cutoff > sigma && cutoff.is_finite()) {
            return Err(ParamError::new(
                "cutoff",
                format!("must exceed the rod length {sigma}, got {cutoff}"),
            ));
        }
        let raw = |r: f64| strength / screening * (-(r - sigma) / screening).exp();
        Ok(Self {
            strength,
            screening,
            cutoff,
            sigma,
            shift: raw(cutoff),
        })
    }
}

impl PairForce for Yukawa {
    #[inline]
    fn range(&self) -> f64 {
        self.cutoff
    }
    #[inline]
    fn force(&self, r: f64) -> f64 {
        if r >= self.cutoff {
            return 0.0;
        }
        self.strength / self.screening * (-(r - self.sigma) / self.screening).exp() - self.shift
    }
}

/// A pair force tabulated as `(r, f)` rows, linearly interpolated (continuous), zero beyond
/// the last row; the last force value must be 0 so the force is continuous there.
#[derive(Debug, Clone)]
pub struct TabulatedPair {
    r: Vec<f64>,
    f: Vec<f64>,
}

impl TabulatedPair {
    /// Validate a table (errors name the parameter `table`): at least 2 rows, strictly increasing r starting
    /// at or below sigma, finite values, last force 0.
    pub fn new(r: Vec<f64>, f: Vec<f64>, sigma: f64) -> Result<Self, ParamError> {
        let key = "table";
        if r.len() < 2 || r.len() != f.len() {
            return Err(ParamError::new(key, "needs at least 2 rows of (r, f)"));
        }
        if r.iter().chain(&f).any(|v| !v.is_finite()) {
            return Err(ParamError::new(key, "contains a non-finite value"));
        }
        if let Some(i) = r.windows(2).position(|w| w[1] <= w[0]) {
            return Err(ParamError::new(
                key,
                format!("r must increase strictly (row {})", i + 1),
            ));
        }
        if r[0] > sigma {
            return Err(ParamError::new(
                key,
                format!("must start at r <= sigma = {sigma}, starts at {}", r[0]),
            ));
        }
        if f[f.len() - 1] != 0.0 {
            return Err(ParamError::new(
                key,
                "the force in the last row must be 0 (a continuous cut-off)",
            ));
        }
        Ok(Self { r, f })
    }
}

impl PairForce for TabulatedPair {
    #[inline]
    fn range(&self) -> f64 {
        self.r[self.r.len() - 1]
    }
    #[inline]
    fn force(&self, r: f64) -> f64 {
        let n = self.r.len();
        if r >= self.r[n - 1] {
            return 0.0;
        }
        let i = self.r.partition_point(|&x| x <= r).clamp(1, n - 1) - 1;
        let t = (r - self.r[i]) / (self.r[i + 1] - self.r[i]);
        self.f[i] + t * (self.f[i + 1] - self.f[i])
    }
}

/// A sum of two pair forces.
#[derive(Debug, Clone)]
pub struct PairSum<A, B>(pub A, pub B);

impl<A: PairForce, B: PairForce> PairForce for PairSum<A, B> {
    #[inline]
    fn range(&self) -> f64 {
        self.0.range().max(self.1.range())
    }
    #[inline]
    fn force(&self, r: f64) -> f64 {
        self.0.force(r) + self.1.force(r)
    }
}

/// External force as the engine sees it.
#[derive(Debug, Clone)]
pub enum Field {
    /// No field.
    None,
    /// Cosine potentials (and a drive), evaluated exactly.
    Cosine(CosineForce),
    /// Periodic field from a table (exact to 1e-9).
    Table(ForceTable),
    /// Non-periodic field evaluated exactly.
    Exact(ExternalField),
}

impl Field {
    /// The fastest exact form of `field`: none, cosines evaluated directly, other periodic
    /// fields from a table, the rest evaluated term by term.
    pub fn new(field: &ExternalField) -> Self {
        if field.is_zero() {
            Field::None
        } else if let Some(c) = CosineForce::from_field(field) {
            Field::Cosine(c)
        } else if let Some(t) = ForceTable::from_field(field) {
            Field::Table(t)
        } else {
            Field::Exact(field.clone())
        }
    }
}

impl ExternalForce for Field {
    #[inline]
    fn force(&self, x: f64) -> f64 {
        match self {
            Field::None => 0.0,
            Field::Cosine(c) => c.force(x),
            Field::Table(t) => t.force(x),
            Field::Exact(f) => f.force(x),
        }
    }

    /// One dispatch per run of rods, then the field's own batched loop.
    #[inline]
    fn force_block(&self, x: &[f64], offset: f64, out: &mut [f64]) {
        match self {
            Field::None => out.fill(0.0),
            Field::Cosine(c) => c.force_block(x, offset, out),
            Field::Table(t) => t.force_block(x, offset, out),
            Field::Exact(f) => f.force_block(x, offset, out),
        }
    }

    #[inline]
    fn force_block_reduced(&self, y: &[f64], first: usize, sigma: f64, out: &mut [f64]) {
        match self {
            Field::None => out.fill(0.0),
            Field::Cosine(c) => c.force_block_reduced(y, first, sigma, out),
            Field::Table(t) => t.force_block_reduced(y, first, sigma, out),
            Field::Exact(f) => f.force_block_reduced(y, first, sigma, out),
        }
    }
}

/// Pair force as the engine sees it: any combination of the specified terms.
#[derive(Debug, Clone, Default)]
pub struct Pair {
    /// Sticky contact.
    pub sticky: Option<Sticky>,
    /// Yukawa.
    pub yukawa: Option<Yukawa>,
    /// Tabulated.
    pub table: Option<TabulatedPair>,
    range: f64,
}

impl Pair {
    /// The sum of the terms given; its range is the longest of theirs.
    pub fn new(
        sticky: Option<Sticky>,
        yukawa: Option<Yukawa>,
        table: Option<TabulatedPair>,
    ) -> Self {
        let range = [
            sticky.as_ref().map(|s| s.range()),
            yukawa.as_ref().map(|y| y.range()),
            table.as_ref().map(|t| t.range()),
        ]
        .into_iter()
        .flatten()
        .fold(0.0, f64::max);
        Self {
            sticky,
            yukawa,
            table,
            range,
        }
    }
}

impl PairForce for Pair {
    #[inline]
    fn range(&self) -> f64 {
        self.range
    }
    #[inline]
    fn force(&self, r: f64) -> f64 {
        let mut f = 0.0;
        if let Some(s) = &self.sticky {
            f += s.force(r);
        }
        if let Some(y) = &self.yukawa {
            f += y.force(r);
        }
        if let Some(t) = &self.table {
            f += t.force(r);
        }
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use colloidsim_core::field1d::FieldTerm;

    /// The closed-form maximum of the sticky force equals a fine scan of Eq. 33, and (the
    /// hard-rods paper's Fig. 5b) over the order p it is smallest at p = 2.95 for eps = 0.05,
    /// gamma = 1, at 136.78 kT per unit length; at eps = 0.1 the best order is 2.46 instead.
    #[test]
    fn sticky_force_maximum_is_smallest_at_p_2_95() {
        let sticky = |p: f64, eps: f64| Sticky::new(1.0, eps, p, 0.2, 1.0).unwrap();
        for (p, eps) in [(1.5, 0.05), (2.95, 0.05), (6.0, 0.05), (3.0, 0.1)] {
            let st = sticky(p, eps);
            let scan = (0..=200_000)
                .map(|i| st.force(0.2 + eps * i as f64 / 200_000.0).abs())
                .fold(0.0, f64::max);
            let exact = st.max_force();
            assert!(
                exact >= scan && exact - scan < 1e-6 * exact,
                "p {p}: {exact} vs {scan}"
            );
        }
        // Golden-section search for the order with the smallest maximum.
        let best = |eps: f64| {
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let (mut a, mut b) = (1.1, 10.0);
            for _ in 0..100 {
                let (c, d) = (b - g * (b - a), a + g * (b - a));
                if sticky(c, eps).max_force() < sticky(d, eps).max_force() {
                    b = d;
                } else {
                    a = c;
                }
            }
            0.5 * (a + b)
        };
        let p = best(0.05);
        assert!((p - 2.95).abs() < 0.01, "best order {p}");
        assert!((sticky(p, 0.05).max_force() - 136.78).abs() < 0.01);
        assert!((best(0.1) - 2.46).abs() < 0.01, "eps 0.1: {}", best(0.1));
    }

    #[test]
    fn table_matches_exact_cosine_force() {
        let field = ExternalField {
            terms: vec![FieldTerm::Cosine {
                amplitude: 6.0,
                wavelength: 1.0,
            }],
            drive: 0.3,
        };
        let t = ForceTable::from_field(&field).unwrap();
        for i in 0..10_000 {
            let x = -7.3 + 0.001_37 * i as f64;
            assert!((t.force(x) - field.force(x)).abs() < 1e-8 * 18.85, "x={x}");
        }
        // Far from the origin (beyond the rounding trick) and non-finite positions.
        // (Whole periods: the table must give the force at 0.3 and 0.)
        for (x, x0) in [
            (2f64.powi(60), 0.0),
            (-13.0 * 2f64.powi(53), 0.0),
            (1e6 + 0.3, 0.3),
        ] {
            assert!((t.force(x) - field.force(x0)).abs() < 1e-6 * 18.85, "x={x}");
        }
        assert!(t.force(f64::NAN).is_nan() && t.force(f64::INFINITY).is_nan());
    }

    #[test]
    fn table_force_block_is_bitwise_the_force() {
        let field = ExternalField {
            terms: vec![
                FieldTerm::Cosine {
                    amplitude: 6.0,
                    wavelength: 1.7,
                },
                FieldTerm::Cosine {
                    amplitude: 1.0,
                    wavelength: 0.85,
                },
            ],
            drive: -0.3,
        };
        let fine = ForceTable::from_field(&field).unwrap();
        // A coarse table too, where every term of the cubic matters in the last bit.
        let exact = |x: f64| field.force(x) - field.drive;
        let coarse = ForceTable::build(1.7, 4, &exact, field.drive);
        for t in [fine, coarse] {
            check_force_block(&t);
        }
    }

    fn check_force_block(t: &ForceTable) {
        let h = t.spacing();
        let limit = 2f64.powi(50) * h;
        // Random positions over many periods, cell edges and centres, and the edge cases of
        // the rounding trick and of the far path.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut xs: Vec<f64> = (0..3000).map(|_| 2000.0 * uniform() - 1000.0).collect();
        xs.extend((-40..40).flat_map(|i| [(i as f64 + 0.5) * h, i as f64 * h]));
        let edges = [
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            -5e-324,
            1e-300,
            limit,
            -limit,
            limit * (1.0 - f64::EPSILON),
            -limit * (1.0 - f64::EPSILON),
            2f64.powi(52) * h,
            2f64.powi(60),
            -13.0 * 2f64.powi(53),
            1e300,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            -f64::NAN,
        ];
        for (i, &e) in edges.iter().enumerate() {
            // Each edge case alone in an otherwise near block, and at different positions.
            let mut block = xs[i * 37..i * 37 + 67].to_vec();
            block[i % 67] = e;
            xs.extend(block);
        }
        let check = |x: &[f64], offset: f64| {
            let mut out = vec![1.0; x.len()];
            t.force_block(x, offset, &mut out);
            for (k, (&xk, &o)) in x.iter().zip(&out).enumerate() {
                let r = t.force(xk + offset);
                assert_eq!(
                    o.to_bits(),
                    r.to_bits(),
                    "x[{k}] = {xk}, offset {offset}: {o} vs {r}"
                );
            }
        };
        for offset in [0.0, -1000.0, 3.5 * h, 1e6, f64::NAN] {
            for len in [0, 1, 3, 4, 5, 7, 8, 255, 256, 257] {
                for start in (0..xs.len().saturating_sub(len)).step_by(97) {
                    check(&xs[start..start + len], offset);
                }
            }
            for &e in &edges {
                // In the vectorised part and in the remainder of a block.
                check(&[0.1, 0.2, e, 0.3, 0.4], offset);
                check(&[0.1, 0.2, 0.3, 0.4, e], offset);
                check(&[e], offset);
            }
        }
        // The whole mixed run at once (it has far rods).
        check(&xs, 0.0);
    }

    #[test]
    fn sticky_force_is_minus_derivative_of_eq31_potential() {
        // V(r) = -kT ln(1 + gamma delta_eps(r - sigma)) with delta_eps of Eq. 32.
        let s = Sticky::new(1.0, 0.05, 3.0, 0.5, 1.0).unwrap();
        let v = |r: f64| {
            let d = s.eps + s.sigma - r;
            let de = (s.order + 1.0) / s.eps.powf(s.order + 1.0) * d.powf(s.order);
            -(1.0 + s.gamma * de).ln()
        };
        for i in 1..50 {
            let r = s.sigma + s.eps * i as f64 / 50.0;
            let h = 1e-7;
            let fd = -(v(r + h) - v(r - h)) / (2.0 * h);
            assert!((s.force(r) - fd).abs() < 1e-5 * (1.0 + fd.abs()), "r={r}");
        }
        assert_eq!(s.force(s.sigma + s.eps + 1e-9), 0.0);
        assert!(Sticky::new(1.0, 0.05, 1.0, 0.5, 1.0).is_err());
    }

    #[test]
    fn tabulated_pair_interpolates() {
        let t = TabulatedPair::new(vec![0.5, 1.0, 1.5], vec![2.0, 1.0, 0.0], 0.5).unwrap();
        assert!((t.force(0.75) - 1.5).abs() < 1e-15);
        assert_eq!(t.force(2.0), 0.0);
        assert!(TabulatedPair::new(vec![0.5, 1.0], vec![1.0, 1.0], 0.5).is_err());
    }

    #[test]
    fn cosine_force_is_the_exact_field_force() {
        use colloidsim_core::field1d::FieldTerm;
        let field = ExternalField {
            terms: vec![
                FieldTerm::Cosine {
                    amplitude: 6.0,
                    wavelength: 1.0,
                },
                FieldTerm::Cosine {
                    amplitude: -2.5,
                    wavelength: 3.7,
                },
            ],
            drive: 0.3,
        };
        let c = CosineForce::from_field(&field).unwrap();
        let xs: Vec<f64> = (0..5000)
            .map(|i| -1e6 + 2e6 * ((i as f64 * 0.618_033_988_75).fract()))
            .chain((0..4000).map(|i| -10.0 + i as f64 * 0.005))
            .chain([0.0, 0.25, 0.5, 0.75, 1.0, -0.25, 1e15, -3e16, f64::NAN])
            .collect();
        let mut out = vec![0.0; xs.len()];
        c.force_block(&xs, 0.0, &mut out);
        let fmax = 6.0 * std::f64::consts::PI + 2.5 * std::f64::consts::PI / 3.7;
        for (&x, &f) in xs.iter().zip(&out) {
            let exact = field.force(x);
            // Both reduce x / lambda in double precision: allow for its rounding near 1e6.
            let tol = 1e-14 * fmax * (1.0 + x.abs());
            assert!(
                (f - exact).abs() <= tol || (f.is_nan() && exact.is_nan()),
                "x = {x}: {f} vs {exact}"
            );
            assert_eq!(
                f.to_bits(),
                c.force(x).to_bits(),
                "block and single differ at {x}"
            );
        }
        // From reduced positions: the force at y_k + (first + k) sigma, bit for bit, for the
        // cosine field and for the default implementation (the table).
        let (first, sigma) = (999_937, 0.99);
        let y: Vec<f64> = (0..300).map(|k| -9.9e3 + 0.37 * (k as f64).sin()).collect();
        let one = ExternalField {
            terms: field.terms[..1].to_vec(),
            drive: 0.3,
        };
        let table = ForceTable::from_field(&one).unwrap();
        let mut tout = vec![0.0; y.len()];
        c.force_block_reduced(&y, first, sigma, &mut out[..y.len()]);
        table.force_block_reduced(&y, first, sigma, &mut tout);
        for (k, &yk) in y.iter().enumerate() {
            let x = yk + (first + k) as f64 * sigma;
            assert_eq!(out[k].to_bits(), c.force(x).to_bits(), "cosine, rod {k}");
            assert_eq!(
                tout[k].to_bits(),
                table.force(x).to_bits(),
                "table, rod {k}"
            );
        }
        // A field with other terms is not a cosine field.
        let mut other = field.clone();
        other.terms.push(FieldTerm::Harmonic {
            stiffness: 1.0,
            centre: 0.0,
            ring: None,
        });
        assert!(CosineForce::from_field(&other).is_none());
    }
}
