//! Positively split Ewald (PSE): the RPY mobility of spheres (one radius or several) in a periodic cube,
//! after Fiore, Balboa Usabiaga, Donev & Swan, J. Chem. Phys. 146, 124116 (2017).
//!
//! **Split.** In Fourier space the RPY tensor is `sinc^2(ka) (I − k̂k̂) / (eta k^2)` (the
//! Stokeslet averaged over two sphere surfaces; both branches of [`crate::rpy`] follow from
//! it). Hasimoto's splitting function `H(k) = (1 + k^2/(4 xi^2)) exp(−k^2/(4 xi^2))` divides it
//! into two positive definite parts, `M = M^w + M^r`:
//!
//! - wave space: `M^w` with kernel `b(k) (I − k̂k̂)`, `b(k) = sinc^2(ka) H(k) / (eta k^2)`,
//!   summed over `k = 2 pi m / L`, `m != 0` (zero mean flow), by the spectral Ewald method:
//!   forces spread to a grid with a compact window `phi` (per axis; the three axes' product),
//!   a real FFT, the kernel `b(k) / phi^(k)^2` (the two windows' transforms taken out;
//!   `phi^(k) = phi^(kx) phi^(ky) phi^(kz)`), the inverse FFT and the same window for the
//!   velocities (quadrature weight `h^3`). The Brownian part of the wave space is drawn
//!   exactly in Fourier space: `sqrt(b / phi^2) (I − k̂k̂) W` with complex Gaussian `W` of
//!   variance V per mode (Hermitian-symmetric), through the same inverse FFT and
//!   interpolation, so its covariance is `M^w` exactly (the operators are the same).
//! - real space: `M^r(r) = M^RPY(r) − M^w_free(r)` (short ranged, like `exp(−xi^2 r^2)`), where
//!   `M^w_free(r) = A_w(r) I + B_w(r) r̂r̂` is the free-space transform of the wave kernel,
//!   `A_w = 1/(2 pi^2 eta) int_0^inf sinc^2(ka) H(k) [j0(kr) − j1(kr)/(kr)] dk`,
//!   `B_w = 1/(2 pi^2 eta) int_0^inf sinc^2(ka) H(k) j2(kr) dk` (`j_n` spherical Bessel
//!   functions), tabulated once by Gauss–Legendre quadrature and interpolated (cubic) — the
//!   RPY part is evaluated exactly, so the kink at `r = 2a` needs no table. Pairs within the
//!   cut-off `r_c` are kept in neighbour lists (cells of edge `>= r_c`, nearest image); the
//!   Brownian part is the Lanczos square root of `M^r` ([`crate::lanczos`]).
//!
//! **Unequal radii** ([`Pse::with_radii`]). The coupling of spheres of radii a_i, a_j is
//! `sinc(k a_i) sinc(k a_j) (I − k̂k̂) / (eta k^2)` in Fourier space (Zuk et al. 2014): each
//! distinct radius is a species; the kernel keeps `H(k) / (eta k^2)` only, each species' forces
//! are spread and transformed on their own, multiplied by the species' `sinc(k a_s)` and summed,
//! and the velocity spectrum is multiplied by each species' `sinc` before its inverse transform
//! and the interpolation at that species' particles. The wave-space operator is then a sum of
//! squares (positive) and its Fourier noise stays exact. The real space has a table and a
//! cut-off per pair of species (the pair's near field, [`crate::rpy::rpy_unequal`]). One
//! species takes the monodisperse path (`sinc^2` in the kernel) unchanged.
//!
//! **Parameters from (xi, tolerance eps).** Fourier cut-off `K`: `(1 + x) e^(−x) = 6 eps`,
//! `x = K^2/(4 xi^2)`, the kernel zero for `|k| > K` (about half the modes of the grid's cube,
//! which neither the product nor the noise visits); grid spacing `h <= pi / K` (n points per
//! axis, the next even 2-3-5-smooth size); the window is the "exponential of semicircle" of Barnett, Magland & af Klinteberg
//! (SIAM J. Sci. Comput. 41, C479, 2019), `phi(x) = exp(beta (sqrt(1 − (x/w)^2) − 1))` for
//! `|x| < w`, zero beyond, with `P = ceil(log10(1/eps)) + 2` points per axis, half-width
//! `w = P h / 2` (the support holds the points closer than w: at most P) and `beta = 2.3 P`;
//! its transform is a quadrature ([`PseGeometry::window_transform`]) per grid wave number,
//! once per geometry. (Their rule for a grid twice as fine as the band is `P = log10(1/eps) +
//! 1`; here the grid only just resolves K, and it is `b(k)`'s fall towards K that keeps the
//! aliased copies small: one point more, and beta between 2.0 and 2.4 P, measured against
//! Beenakker's sum at 1e-2 ... 1e-5. The Gaussian window it replaced needed 8 points per axis
//! at 1e-3, this one 5, with a smaller error.) Real-space cut-off `r_c`: beyond it
//! `|A_r|, |B_r| < 0.2 eps mu0`.
//! The shares were set by measurement: against Beenakker's Ewald sum the error of the product
//! is set by the real-space cut-off and lies between 0.07 and 0.6 of the tolerance
//! (`tests/pse.rs`, docs/hydrodynamics.md). The real-space pair tensors are stored in single
//! precision for tolerances of 1e-6 and more (the sums are in double precision).
//!
//! **Determinism.** Spreading is a gather per grid plane (each plane sums the particles whose
//! support reaches it, in a fixed order), interpolation a sum per particle, the FFT lines are
//! independent, neighbour lists are in a fixed order, and the noise is keyed by (seed, step,
//! particle) and (seed, step, grid line): results do not depend on the thread count.

use crate::fft3::{C64, Fft3};
use crate::lanczos::{Lanczos, LanczosParams, SqrtReport};
use crate::noise::{GRID_KEY, NoiseKey, fill_particle_noise};
use crate::params::check_lanczos;
use crate::rpy::{rpy, rpy_unequal};
use crate::{HydroError, Mobility};
use colloidsim_core::ParamError;
use colloidsim_core::rng::{Purpose, Ziggurat, stream};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::time::Instant;

/// Threshold of the Fourier cut-off, relative to the tolerance.
const FOURIER_SHARE: f64 = 6.0;
/// Support of the spreading window: `ceil(log10(1/eps))` points per axis and this many more.
const SUPPORT_EXTRA: usize = 2;
/// Shape of the window: `beta = 2.3 P` (P the support).
const BETA_PER_POINT: f64 = 2.3;
/// Threshold of the real-space cut-off, relative to the tolerance (the real-space truncation
/// dominates the error: measured against Beenakker's sum, the error is proportional to this
/// share and nearly independent of the other two).
const REAL_SHARE: f64 = 0.2;

/// What PSE is asked for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PseParams {
    /// Sphere radius a.
    pub radius: f64,
    /// Solvent viscosity eta.
    pub viscosity: f64,
    /// Edge L of the periodic cube (centred on the origin).
    pub box_length: f64,
    /// Splitting parameter xi (1 / length; the paper: 0.5 / a).
    pub splitting: f64,
    /// Relative tolerance of the product and of the real-space Lanczos noise.
    pub tolerance: f64,
    /// Lanczos iteration limit.
    pub max_iterations: usize,
}

impl PseParams {
    /// The paper's setting: `xi = 0.5 / a`, tolerance 1e-3, 200 Lanczos iterations at most.
    pub fn paper(radius: f64, viscosity: f64, box_length: f64) -> Self {
        Self {
            radius,
            viscosity,
            box_length,
            splitting: 0.5 / radius,
            tolerance: 1e-3,
            max_iterations: 200,
        }
    }
}

/// Grid and cut-offs chosen from [`PseParams`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PseGeometry {
    /// Grid points per axis.
    pub grid: usize,
    /// Grid spacing h = L / grid.
    pub spacing: f64,
    /// Fourier cut-off K the grid resolves.
    pub k_cut: f64,
    /// Support of the spreading window: grid points per axis.
    pub support: usize,
    /// Shape parameter beta of the window `exp(beta (sqrt(1 − (x/w)^2) − 1))`.
    pub beta: f64,
    /// Half-width w of the window (`support h / 2`): the support holds the grid points closer
    /// than w to the particle, at most `support` per axis.
    pub half_width: f64,
    /// Real-space cut-off r_c.
    pub r_cut: f64,
}

/// Even 2-3-5-smooth size at least `n`.
fn fft_size(n: usize) -> usize {
    let mut m = n.max(2);
    loop {
        let mut r = m;
        for p in [2, 3, 5] {
            while r.is_multiple_of(p) {
                r /= p;
            }
        }
        if r == 1 && m.is_multiple_of(2) {
            return m;
        }
        m += 1;
    }
}

/// `x` with `(1 + x) e^(−x) = eps` (x > 1), by bisection.
fn hasimoto_cut(eps: f64) -> f64 {
    let (mut lo, mut hi) = (1.0f64, 200.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if (1.0 + mid) * (-mid).exp() > eps {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// `(j0(x) − j1(x)/x, j2(x))`, by series below x = 0.3.
fn bessel_pair(x: f64) -> (f64, f64) {
    if x < 0.3 {
        let x2 = x * x;
        let j0 = 1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0)));
        let j1x = 1.0 / 3.0 - x2 / 30.0 + x2 * x2 / 840.0 - x2 * x2 * x2 / 45360.0
            + x2 * x2 * x2 * x2 / 3991680.0;
        let j2 = x2 / 15.0 - x2 * x2 / 210.0 + x2 * x2 * x2 / 7560.0 - x2 * x2 * x2 * x2 / 498960.0;
        (j0 - j1x, j2)
    } else {
        let (s, c) = x.sin_cos();
        let j0 = s / x;
        let j1 = s / (x * x) - c / x;
        let j2 = (3.0 / (x * x) - 1.0) * s / x - 3.0 * c / (x * x);
        (j0 - j1 / x, j2)
    }
}

/// `sin(x) / x`.
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

/// `A_w(r)`, `B_w(r)` of the free-space wave-space tensor on a uniform grid in r, with
/// cubic interpolation.
#[derive(Debug, Clone)]
struct WaveTable {
    dr: f64,
    inv_dr: f64,
    a: Vec<f64>,
    /// The nodes of `B_w` (read by the tests' check of `cubics`).
    #[cfg_attr(not(test), allow(dead_code))]
    b: Vec<f64>,
    /// Per interval `i` (from node `i` to `i + 1`, `i >= 1`), the cubics through the nodes
    /// `i − 1 ... i + 2` of `a` and `b` in powers of `u = r / dr − i` (one cache line).
    cubics: Vec<Cubics>,
}

/// `[a0, a1, a2, a3, b0, b1, b2, b3]` of one interval of a [`WaveTable`].
#[derive(Debug, Clone, Copy)]
#[repr(align(64))]
struct Cubics([f64; 8]);

/// Coefficients in powers of `u` of the cubic through `(−1, y0), (0, y1), (1, y2), (2, y3)`.
fn cubic_through(y: [f64; 4]) -> [f64; 4] {
    [
        y[1],
        -y[0] / 3.0 - 0.5 * y[1] + y[2] - y[3] / 6.0,
        0.5 * y[0] - y[1] + 0.5 * y[2],
        (y[3] - y[0]) / 6.0 + 0.5 * (y[1] - y[2]),
    ]
}

impl WaveTable {
    /// The table of the pair of radii `ai`, `aj` (kernel `sinc(k a_i) sinc(k a_j) H(k)`).
    fn build(ai: f64, aj: f64, eta: f64, xi: f64, r_max: f64) -> Self {
        let dr = ai.min(aj).min(1.0 / xi) / 64.0;
        let m = (r_max / dr).ceil() as usize + 4;
        // H(k) < 1e-19 beyond k = 14 xi.
        let k_max = 14.0 * xi;
        let width = (PI / (2.0 * r_max.max(ai + aj)))
            .min(PI / (4.0 * ai.max(aj)))
            .min(xi);
        let panels = (k_max / width).ceil() as usize;
        let (gx, gw) = colloidsim_core::quadrature::gauss_legendre(16);
        let hw = 0.5 * k_max / panels as f64;
        let nodes: Vec<(f64, f64)> = (0..panels)
            .flat_map(|p| {
                let mid = (2 * p + 1) as f64 * hw;
                gx.iter()
                    .zip(&gw)
                    .map(move |(&x, &w)| (mid + hw * x, hw * w))
            })
            .map(|(k, w)| {
                let q = k * k / (4.0 * xi * xi);
                let (si, sj) = (sinc(k * ai), sinc(k * aj));
                (k, w * si * sj * (1.0 + q) * (-q).exp())
            })
            .collect();
        let pre = 1.0 / (2.0 * PI * PI * eta);
        let (a, b): (Vec<f64>, Vec<f64>) = (0..m)
            .into_par_iter()
            .map(|i| {
                let r = i as f64 * dr;
                let (mut sa, mut sb) = (0.0, 0.0);
                for &(k, w) in &nodes {
                    let (p, q) = bessel_pair(k * r);
                    sa += w * p;
                    sb += w * q;
                }
                (pre * sa, pre * sb)
            })
            .unzip();
        let cubics = (0..a.len() - 2)
            .map(|i| {
                let i = i.max(1);
                let ca = cubic_through([a[i - 1], a[i], a[i + 1], a[i + 2]]);
                let cb = cubic_through([b[i - 1], b[i], b[i + 1], b[i + 2]]);
                Cubics([ca[0], ca[1], ca[2], ca[3], cb[0], cb[1], cb[2], cb[3]])
            })
            .collect();
        Self {
            dr,
            inv_dr: 1.0 / dr,
            a,
            b,
            cubics,
        }
    }

    /// `(A_w(r), B_w(r))`, 4-point Lagrange interpolation ([`Self::eval_lagrange`]) from the
    /// cubics' coefficients: one cache line and six multiply-adds.
    #[inline(always)]
    fn eval(&self, r: f64) -> (f64, f64) {
        let t = r * self.inv_dr;
        let i = (t as usize).clamp(1, self.a.len() - 3);
        let u = t - i as f64;
        let c = &self.cubics[i].0;
        (
            c[0] + u * (c[1] + u * (c[2] + u * c[3])),
            c[4] + u * (c[5] + u * (c[6] + u * c[7])),
        )
    }

    /// `(A_w(r), B_w(r))`, 4-point Lagrange interpolation (B_w even in r, A_w too).
    #[cfg(test)]
    fn eval_lagrange(&self, r: f64) -> (f64, f64) {
        let t = r * self.inv_dr;
        let i = (t.floor() as usize).clamp(1, self.a.len() - 3);
        let u = t - i as f64;
        // Nodes i-1, i, i+1, i+2 at offsets -1, 0, 1, 2.
        let w = [
            -u * (u - 1.0) * (u - 2.0) / 6.0,
            (u + 1.0) * (u - 1.0) * (u - 2.0) / 2.0,
            -(u + 1.0) * u * (u - 2.0) / 2.0,
            (u + 1.0) * u * (u - 1.0) / 6.0,
        ];
        let idx = |k: usize| {
            // Reflect across r = 0 (both functions are even in r).
            (i + k) as isize - 1
        };
        let (mut a, mut b) = (0.0, 0.0);
        for (k, wk) in w.iter().enumerate() {
            let j = idx(k).unsigned_abs();
            a += wk * self.a[j];
            b += wk * self.b[j];
        }
        (a, b)
    }
}

/// Seconds spent in the parts of PSE since the last [`Pse::reset_times`] (for benchmarks).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct PseTimes {
    /// Forward and inverse 3D FFTs.
    pub fft: f64,
    /// Spreading forces to the grid.
    pub spread: f64,
    /// The wave-space kernel and Fourier noise.
    pub kernel: f64,
    /// Interpolating velocities from the grid.
    pub interpolate: f64,
    /// Real-space products (including those of the Lanczos iterations).
    pub real: f64,
    /// Neighbour lists, pair tensors and window weights (`set_positions`).
    pub setup: f64,
    /// Of `setup`: the window weights and the spreading order.
    pub setup_spreading: f64,
    /// Lanczos iterations.
    pub lanczos_iterations: u64,
}

impl PseTimes {
    /// The parts in the order of the benchmarks' profiles: FFTs, spreading, kernel and noise,
    /// interpolation, real space and Lanczos, set-up.
    pub fn parts(&self) -> [f64; 6] {
        [
            self.fft,
            self.spread,
            self.kernel,
            self.interpolate,
            self.real,
            self.setup,
        ]
    }
}

/// One real-space pair of a neighbour list: `M^r_ij = a I + b e e^T`, stored in `T` (`f32`
/// halves the data the Lanczos iterations stream; the sums are in `f64`).
#[derive(Debug, Clone, Copy, Default)]
struct Entry<T> {
    j: u32,
    a: T,
    b: T,
    e: [T; 3],
}

/// Storage precision of the real-space pair tensors.
trait Stored: Copy + Default + Send + Sync {
    fn store(x: f64) -> Self;
    fn load(self) -> f64;
}

impl Stored for f32 {
    #[inline(always)]
    fn store(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn load(self) -> f64 {
        self as f64
    }
}

impl Stored for f64 {
    #[inline(always)]
    fn store(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn load(self) -> f64 {
        self
    }
}

/// Tolerances from which the real-space tensors are stored in single precision: their
/// rounding (relative 6e-8, the operator stays exactly symmetric) is then at most 1/16 of the
/// tolerance. Tighter tolerances keep them in double precision.
const SINGLE_PRECISION_FROM: f64 = 1e-6;

/// The real-space pair tensors of every row, in the precision the tolerance allows.
enum Entries {
    Single(Vec<Entry<f32>>),
    Double(Vec<Entry<f64>>),
}

impl Entries {
    fn for_tolerance(tolerance: f64) -> Self {
        if tolerance >= SINGLE_PRECISION_FROM {
            Self::Single(Vec::new())
        } else {
            Self::Double(Vec::new())
        }
    }

    fn resize(&mut self, len: usize) {
        match self {
            Self::Single(v) => v.resize(len, Entry::default()),
            Self::Double(v) => v.resize(len, Entry::default()),
        }
    }

    fn bytes(&self) -> usize {
        match self {
            Self::Single(v) => v.capacity() * std::mem::size_of::<Entry<f32>>(),
            Self::Double(v) => v.capacity() * std::mem::size_of::<Entry<f64>>(),
        }
    }
}

/// Positively split Ewald RPY mobility in a periodic cube.
pub struct Pse {
    params: PseParams,
    geom: PseGeometry,
    n: usize,
    /// Radii of the species, ascending and distinct (one for monodisperse spheres).
    radii: Vec<f64>,
    /// Species of each particle (in the order of the positions).
    species: Vec<u32>,
    /// Stokes mobility `1 / (6 pi eta a_s)` of each species.
    mu0s: Vec<f64>,
    /// Real-space self term `mu0_s − A_w^ss(0)` of each species.
    self_reals: Vec<f64>,
    /// Self term of each row (cell order).
    self_rows: Vec<f64>,
    /// Wave-space functions of each pair of species ([`pair_index`]).
    tables: Vec<WaveTable>,
    /// Squared real-space cut-off of each pair of species (the largest is the geometry's).
    rc2s: Vec<f64>,
    /// Squared candidate range of each pair of species: its cut-off and the skin.
    candidate_ranges2: Vec<f64>,
    /// The general (species) wave-space path: the kernel without the sinc factors, which
    /// `filters` apply per species. Off for one species, which keeps `sinc^2` in the kernel.
    general: bool,
    /// `sinc(|k| a_s)` per mode of `work`, per species (empty unless `general`).
    filters: Vec<Vec<f64>>,
    /// A half spectrum for the species' transforms (empty unless `general`).
    tmp: Vec<C64>,
    // Positions wrapped into the box.
    pos: Vec<[f64; 3]>,
    // Cell list of the real-space part.
    n_cells: usize,
    cell_of: Vec<u32>,
    cell_start: Vec<u32>,
    cell_order: Vec<u32>,
    /// Verlet skin of the candidate lists.
    skin: f64,
    /// Positions at the last candidate build.
    reference: Vec<[f64; 3]>,
    /// Row `i` of the candidates starts at `offsets[i]`.
    offsets: Vec<usize>,
    candidates: Vec<u32>,
    /// The pairs within the cut-off, row `r` at `entry_offsets[r]..entry_offsets[r + 1]`
    /// (stored without gaps: the Lanczos iterations stream them); an entry's `j` is the
    /// neighbour's row.
    entries: Entries,
    entry_offsets: Vec<usize>,
    /// Pairs within the cut-off per row.
    counts: Vec<u32>,
    /// Particle of each row, and row of each particle (cell order at the last candidate build).
    row_particle: Vec<u32>,
    row_of: Vec<u32>,
    /// Forces and velocities of the real-space product in row order.
    f_rows: Vec<f64>,
    u_rows: Vec<f64>,
    // Spreading, in `plane_order`: first grid index per axis and P weights per axis
    // of each particle, and the forces being spread.
    base: Vec<[u32; 3]>,
    weights: Vec<f64>,
    f_sorted: Vec<[f64; 3]>,
    /// Sort key of each particle: its species, first grid plane and row of its support,
    /// `(s g + z) g + y`.
    plane_key: Vec<u32>,
    plane_start: Vec<u32>,
    /// Particles by sort key (spreading and interpolation visit them in this order, so that
    /// consecutive particles touch nearby grid rows).
    plane_order: Vec<u32>,
    /// Position of each particle in `plane_order`.
    slot_of: Vec<u32>,
    /// Interpolated velocities in `plane_order`.
    sorted: Vec<[f64; 3]>,
    // Grids: real `[z][y][x]`, one shared half spectrum, full spectra `[kx][ky][kz]`.
    fft: Fft3,
    real: [Vec<f64>; 3],
    spec: Vec<C64>,
    work: [Vec<C64>; 3],
    /// `b(k) / phi^(k)^2` per mode of `work` (0 at k = 0, at the Nyquist planes and beyond K).
    kernel: Vec<f64>,
    /// k components per index along an axis (`None`: the Nyquist index).
    kvec: Vec<Option<f64>>,
    /// Noise of the kx = 0 plane `[ky][kz]`, three complex components.
    plane_noise: Vec<[C64; 3]>,
    lanczos: Lanczos,
    noise: Vec<[f64; 3]>,
    scratch: Vec<[f64; 3]>,
    times: PseTimes,
}

impl std::fmt::Debug for Pse {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pse")
            .field("params", &self.params)
            .field("geometry", &self.geom)
            .field("n", &self.n)
            .finish()
    }
}

impl PseGeometry {
    /// Choose the grid and cut-offs for `params` (everything [`Pse::new`] checks, without
    /// allocating the grids): errors name the scenario key at fault.
    pub fn new(params: &PseParams) -> Result<Self, HydroError> {
        Ok(Self::with_tables(params, &[params.radius])?.0)
    }

    /// The geometry of spheres of the given radii ([`Pse::with_radii`]; `params.radius` is not
    /// read): the same checks as [`Pse::with_radii`], without allocating the grids.
    pub fn with_radii(params: &PseParams, radii: &[f64]) -> Result<Self, HydroError> {
        let (species, _) = species_of(radii)?;
        Ok(Self::with_tables(params, &species)?.0)
    }

    /// Bytes of the grids and spectra a [`Pse`] of this geometry holds (three real grids,
    /// four half spectra of complex numbers, the kernel), besides about 0.3 kB per particle.
    pub fn grid_bytes(&self) -> usize {
        let g = self.grid;
        let half = g * g * (g / 2 + 1);
        8 * (3 * g * g * g + half) + 16 * 4 * half
    }

    /// Bytes that `species` radii add to [`Self::grid_bytes`] ([`Pse::with_radii`]): none for
    /// one species; else a half spectrum of scratch and one filter (8 bytes per mode) per
    /// species.
    pub fn species_bytes(&self, species: usize) -> usize {
        let g = self.grid;
        let half = g * g * (g / 2 + 1);
        if species > 1 {
            (16 + 8 * species) * half
        } else {
            0
        }
    }

    /// The geometry, the tabulated wave-space functions of each pair of species
    /// ([`pair_index`]) and the real-space self term of each species, for the species radii
    /// `radii` (ascending, distinct, positive; `params.radius` is not read). The box is checked
    /// against the largest sphere, the table spacing follows the pair's smaller sphere, and each
    /// pair's cut-off is relative to its larger sphere's mobility.
    fn with_tables(params: &PseParams, radii: &[f64]) -> Result<(Self, RealTables), HydroError> {
        let (a_min, a_max) = (radii[0], radii[radii.len() - 1]);
        let p = PseParams {
            radius: a_max,
            ..*params
        };
        colloidsim_core::param::positive("radius", a_min)?;
        colloidsim_core::param::positive("viscosity", p.viscosity)?;
        colloidsim_core::param::positive("box_length", p.box_length)?;
        if !(p.splitting.is_finite() && p.splitting > 0.0) {
            return Err(ParamError::new(
                "splitting",
                format!("must be a finite number > 0, got {}", p.splitting),
            )
            .into());
        }
        check_lanczos(&LanczosParams {
            tolerance: p.tolerance,
            max_iterations: p.max_iterations,
        })?;
        let (a, xi, l, eps) = (a_max, p.splitting, p.box_length, p.tolerance);
        if l < 4.0 * a {
            return Err(ParamError::new(
                "box_length",
                format!(
                    "the periodic box {l} must be at least 4 radii ({})",
                    4.0 * a
                ),
            )
            .into());
        }
        // Fourier side.
        let k_cut = 2.0 * xi * hasimoto_cut(FOURIER_SHARE * eps).sqrt();
        let want = (k_cut * l / PI).ceil();
        if want.is_nan() || want > 1024.0 {
            // Before the count becomes an integer (1e300 would saturate it).
            return Err(ParamError::new(
                "splitting",
                format!(
                    "xi = {xi} needs a grid of {want:.3e} points per axis for a box of edge {l}, \
                     more than 1024; lower the splitting"
                ),
            )
            .into());
        }
        // The window: support and shape from the tolerance alone (module doc).
        let digits = (1.0 / eps).log10().max(0.0);
        if digits + SUPPORT_EXTRA as f64 > MAX_SUPPORT as f64 {
            // Before the count becomes an integer.
            return Err(ParamError::new(
                "tolerance",
                format!(
                    "{eps:e} needs a window support of more than {MAX_SUPPORT} grid points per \
                     axis; use a tolerance of 1e-13 or more"
                ),
            )
            .into());
        }
        let pts = (digits * (1.0 - 1e-12)).ceil() as usize + SUPPORT_EXTRA;
        let beta = BETA_PER_POINT * pts as f64;
        let grid = fft_size((want as usize).max(pts));
        let h = l / grid as f64;
        if grid > 1024 {
            return Err(ParamError::new(
                "splitting",
                format!(
                    "xi = {xi} needs a {grid}^3 grid for a box of edge {l} ({:.1} GiB); \
                     lower the splitting",
                    60.0 * (grid as f64).powi(3) / (1u64 << 30) as f64
                ),
            )
            .into());
        }
        // Real side: the table reaches where exp(-xi^2 r^2) < 1e-18. The real-space part
        // reaches at least 1 / xi at any tolerance the run accepts (<= 0.1), so a splitting
        // below 2 / L is refused here, before a table of 416 / (a xi) points is built.
        if 1.0 / xi >= 0.5 * l {
            return Err(ParamError::new(
                "splitting",
                format!(
                    "xi = {xi} gives a real-space part reaching beyond half the box ({}); raise \
                     the splitting well above {:.4} or enlarge the box",
                    0.5 * l,
                    2.0 / l
                ),
            )
            .into());
        }
        let r_max = (4.0 * a).max(6.5 / xi);
        // The table's points (spacing min(a, 1 / xi) / 64 up to r_max), each a quadrature.
        let points = r_max / (a_min.min(1.0 / xi) / 64.0);
        if points.is_nan() || points > MAX_TABLE_POINTS {
            let (key, what) = if a_min < 1.0 / xi {
                ("radius", format!("a = {a_min:e}"))
            } else {
                ("splitting", format!("xi = {xi:e}"))
            };
            return Err(ParamError::new(
                key,
                format!(
                    "{what} beside the real-space reach {r_max:.4e} needs a wave-space table of \
                     {points:.2e} points, more than {MAX_TABLE_POINTS:e}: the radius and 1 / \
                     splitting must be within a factor of about 25,000 of each other"
                ),
            )
            .into());
        }
        let mut tables = Vec::with_capacity(radii.len() * (radii.len() + 1) / 2);
        for (t, &at) in radii.iter().enumerate() {
            for &a_s in &radii[..=t] {
                tables.push(WaveTable::build(a_s, at, p.viscosity, xi, r_max));
            }
        }
        let self_reals = radii
            .iter()
            .enumerate()
            .map(|(s, &a_s)| 1.0 / (6.0 * PI * p.viscosity * a_s) - tables[pair_index(s, s)].a[0])
            .collect();
        // The cut-off of each pair of species: the distance beyond which its real-space
        // functions stay below the threshold, relative to the pair's smaller Stokes mobility
        // (the larger sphere's); the geometry's cut-off is the largest.
        let mut r_cuts = vec![0.0f64; tables.len()];
        for (t, &at) in radii.iter().enumerate() {
            let mu_pair = 1.0 / (6.0 * PI * p.viscosity * at);
            for (s, &a_s) in radii[..=t].iter().enumerate() {
                let table = &tables[pair_index(s, t)];
                for i in (0..table.a.len() - 3).rev() {
                    let r = i as f64 * table.dr;
                    let m = rpy_pair(r, a_s, at, p.viscosity);
                    let (aw, bw) = table.eval(r);
                    if (m.a - aw).abs().max((m.b - bw).abs()) > REAL_SHARE * eps * mu_pair {
                        r_cuts[pair_index(s, t)] = r + table.dr;
                        break;
                    }
                }
            }
        }
        let r_cut = r_cuts.iter().copied().fold(0.0, f64::max);
        if r_cut >= 0.5 * l {
            return Err(ParamError::new(
                "splitting",
                format!(
                    "xi = {xi} gives a real-space cut-off {r_cut:.4} beyond half the box ({}); \
                     raise the splitting to at least {:.4} or enlarge the box",
                    0.5 * l,
                    xi * r_cut / (0.49 * l)
                ),
            )
            .into());
        }
        let geom = PseGeometry {
            grid,
            spacing: h,
            k_cut,
            support: pts,
            beta,
            half_width: 0.5 * pts as f64 * h,
            r_cut,
        };
        // The deconvolution divides by the window's transform: positive up to the Nyquist
        // wave number for the shapes chosen above (k w = pi P / 2 < beta there).
        let nyquist = geom.window_transform(PI / h) / geom.window_transform(0.0);
        if nyquist.is_nan() || nyquist <= 1e-300 {
            return Err(HydroError::Invalid(format!(
                "the spreading window's transform is {nyquist:e} at the grid's Nyquist wave \
                 number (support {pts}, beta {beta})"
            )));
        }
        Ok((
            geom,
            RealTables {
                tables,
                self_reals,
                r_cuts,
            },
        ))
    }
}

impl PseGeometry {
    /// The window per axis as a function of the distance in grid spacings (zero beyond the
    /// half-width).
    fn window_fn(&self) -> impl Fn(f64) -> f64 + Sync + Send + Copy + use<> {
        let (beta, inv_w) = (self.beta, self.spacing / self.half_width);
        move |d: f64| {
            let x = d * inv_w;
            let t = 1.0 - x * x;
            if t > 0.0 {
                (beta * (t.sqrt() - 1.0)).exp()
            } else {
                0.0
            }
        }
    }

    /// The window's Fourier transform `phi^(k) = int phi(x) e^(−ikx) dx` along an axis, by
    /// Gauss–Legendre quadrature in `x = w sin(theta)`, where the integrand
    /// `2 w exp(beta (cos theta − 1)) cos(k w sin theta) cos theta` on `[0, pi/2]` is smooth.
    pub fn window_transform(&self, k: f64) -> f64 {
        let (w, beta) = (self.half_width, self.beta);
        let (gx, gw) = colloidsim_core::quadrature::gauss_legendre(16);
        // 16 panels of 16 nodes: exact to rounding for k w and beta up to about 100.
        let panels = 16;
        let hw = 0.25 * PI / panels as f64;
        let mut sum = 0.0;
        for p in 0..panels {
            let mid = (2 * p + 1) as f64 * hw;
            for (&x, &wt) in gx.iter().zip(&gw) {
                let t = mid + hw * x;
                let (s, c) = t.sin_cos();
                sum += hw * wt * (beta * (c - 1.0)).exp() * (k * w * s).cos() * c;
            }
        }
        2.0 * w * sum
    }
}

/// The real-space functions of each pair of species ([`pair_index`]), their cut-offs, and each
/// species' real-space self term.
struct RealTables {
    tables: Vec<WaveTable>,
    self_reals: Vec<f64>,
    r_cuts: Vec<f64>,
}

/// Index of the pair of species `(s, t)` in the triangular list of tables (either order).
#[inline(always)]
fn pair_index(s: usize, t: usize) -> usize {
    let (lo, hi) = if s <= t { (s, t) } else { (t, s) };
    hi * (hi + 1) / 2 + lo
}

/// The RPY pair tensor of radii `ai`, `aj`: [`rpy`] for equal radii, else [`rpy_unequal`].
fn rpy_pair(r: f64, ai: f64, aj: f64, eta: f64) -> crate::rpy::PairTensor {
    if ai == aj {
        rpy(r, ai, eta)
    } else {
        rpy_unequal(r, ai, aj, eta)
    }
}

/// Most species (distinct radii) PSE takes: each costs a forward and an inverse transform of
/// the three grids per product, and each pair of species a real-space table.
pub const MAX_SPECIES: usize = 8;

/// Largest ratio of two radii PSE takes. The error against the dense reference was measured
/// up to this ratio (tests/pse.rs); the grid does not depend on the radii (it is set by the
/// splitting and the tolerance), but the real-space cut-off grows with the largest pair and
/// the table spacing shrinks with the smallest radius.
pub const MAX_RADIUS_RATIO: f64 = 16.0;

/// The species of `radii`: their distinct values ascending, and each particle's index among
/// them. Refuses (naming `radius`) a radius that is not finite and positive, more than
/// [`MAX_SPECIES`] distinct radii, and radii further apart than [`MAX_RADIUS_RATIO`].
fn species_of(radii: &[f64]) -> Result<(Vec<f64>, Vec<u32>), HydroError> {
    if radii.is_empty() {
        return Err(HydroError::Invalid(
            "PSE needs at least one particle".into(),
        ));
    }
    for (i, &a) in radii.iter().enumerate() {
        if !(a.is_finite() && a > 0.0) {
            return Err(ParamError::new(
                "radius",
                format!("particle {i}: must be a finite number > 0, got {a}"),
            )
            .into());
        }
    }
    let mut species: Vec<f64> = radii.to_vec();
    species.sort_by(f64::total_cmp);
    species.dedup();
    if species.len() > MAX_SPECIES {
        return Err(ParamError::new(
            "radius",
            format!(
                "{} distinct radii, more than the {MAX_SPECIES} species PSE takes (one grid \
                 transform per species and product)",
                species.len()
            ),
        )
        .into());
    }
    let ratio = species[species.len() - 1] / species[0];
    if ratio > MAX_RADIUS_RATIO {
        return Err(ParamError::new(
            "radius",
            format!(
                "radii {} and {} differ by a factor {ratio:.4}, more than the {MAX_RADIUS_RATIO} \
                 PSE resolves within its tolerance",
                species[0],
                species[species.len() - 1]
            ),
        )
        .into());
    }
    let index = radii
        .iter()
        .map(|a| species.partition_point(|b| b < a) as u32)
        .collect();
    Ok((species, index))
}

impl Pse {
    /// Set up for `n` spheres: choose the grid and cut-offs ([`PseGeometry::new`]), tabulate the
    /// real-space functions, plan the FFTs. Errors name the scenario key at fault.
    pub fn new(n: usize, params: PseParams) -> Result<Self, HydroError> {
        Self::build(params, vec![params.radius], vec![0; n], false)
    }

    /// Set up for spheres of radii `radii` (one per particle, in the order of the positions
    /// that [`Mobility::set_positions`] will be given; `params.radius` is not read). Each
    /// distinct radius is a species (at most [`MAX_SPECIES`], within a factor
    /// [`MAX_RADIUS_RATIO`] of each other): its own sinc filter in wave space and a real-space
    /// table per pair of species (docs/hydrodynamics.md). Equal radii give exactly
    /// [`Pse::new`] with that radius. Errors name the key at fault (`radius` for the radii).
    pub fn with_radii(radii: &[f64], params: PseParams) -> Result<Self, HydroError> {
        let (species, index) = species_of(radii)?;
        let general = species.len() > 1;
        Self::build(
            PseParams {
                radius: species[species.len() - 1],
                ..params
            },
            species,
            index,
            general,
        )
    }

    /// New radii for the same particles, e.g. after the caller reordered them: `radii[i]` is
    /// the radius of the particle whose position will be `pos[i]` in the next
    /// [`Mobility::set_positions`] (which must follow before the next product). Each radius
    /// must be one of the radii given at construction (the species fix the tables and
    /// filters); otherwise refused naming `radius`, and nothing changes.
    pub fn set_radii(&mut self, radii: &[f64]) -> Result<(), HydroError> {
        if radii.len() != self.n {
            return Err(HydroError::Invalid(format!(
                "{} radii for {} particles",
                radii.len(),
                self.n
            )));
        }
        for (i, a) in radii.iter().enumerate() {
            if !self.radii.contains(a) {
                return Err(ParamError::new(
                    "radius",
                    format!(
                        "particle {i}: radius {a} is none of the species radii {:?} PSE was set \
                         up with",
                        self.radii
                    ),
                )
                .into());
            }
        }
        for (s, a) in self.species.iter_mut().zip(radii) {
            *s = self.radii.partition_point(|b| b < a) as u32;
        }
        // The rows' self terms follow the species: rebuild the lists at the next positions.
        self.reference.clear();
        Ok(())
    }

    /// The species radii (ascending, distinct).
    pub fn species_radii(&self) -> &[f64] {
        &self.radii
    }

    /// `general`: the species path even for one species (tests compare it with the
    /// monodisperse path).
    fn build(
        params: PseParams,
        radii: Vec<f64>,
        species: Vec<u32>,
        general: bool,
    ) -> Result<Self, HydroError> {
        let p = params;
        let n = species.len();
        let (
            geom,
            RealTables {
                tables,
                self_reals,
                r_cuts,
            },
        ) = PseGeometry::with_tables(&p, &radii)?;
        let (a, xi, l) = (p.radius, p.splitting, p.box_length);
        let mu0s: Vec<f64> = radii
            .iter()
            .map(|&a| 1.0 / (6.0 * PI * p.viscosity * a))
            .collect();
        let (grid, pts, r_cut) = (geom.grid, geom.support, geom.r_cut);
        let fft = Fft3::new(grid);
        let nh = grid / 2 + 1;
        let kvec: Vec<Option<f64>> = (0..grid)
            .map(|m| {
                let f = if m < grid / 2 {
                    m as isize
                } else {
                    m as isize - grid as isize
                };
                (2 * m != grid).then(|| 2.0 * PI * f as f64 / l)
            })
            .collect();
        // The window's transform along an axis, per index (1 at the Nyquist index, whose modes
        // the kernel leaves out).
        let hat: Vec<f64> = kvec
            .iter()
            .map(|k| k.map_or(1.0, |k| geom.window_transform(k)))
            .collect();
        // The kernel is cut at |k| = K (beyond, H < 6 eps): about half the modes of the cube,
        // which neither the product nor the noise then visits.
        let k_cut2 = geom.k_cut * geom.k_cut;
        let mut kernel = vec![0.0; nh * grid * grid];
        kernel
            .par_chunks_mut(grid * grid)
            .enumerate()
            .for_each(|(kx, plane)| {
                for ky in 0..grid {
                    for kz in 0..grid {
                        plane[ky * grid + kz] = match (kvec[kx], kvec[ky], kvec[kz]) {
                            (Some(x), Some(y), Some(z))
                                if kx + ky + kz > 0 && x * x + y * y + z * z <= k_cut2 =>
                            {
                                let k2 = x * x + y * y + z * z;
                                let q = k2 / (4.0 * xi * xi);
                                // b(k) / phi^(k)^2, the window's transform the product of
                                // the three axes'.
                                let w = hat[kx] * hat[ky] * hat[kz];
                                let b = (1.0 + q) * (-q).exp() / (p.viscosity * k2 * w * w);
                                if general {
                                    // The sinc factors are the species' filters.
                                    b
                                } else {
                                    let s = sinc(k2.sqrt() * a);
                                    s * s * b
                                }
                            }
                            _ => 0.0,
                        };
                    }
                }
            });
        // The kz lines with no mode inside the kernel's sphere are never transformed.
        let mut fft = fft;
        fft.set_active_lines(
            kernel
                .chunks_exact(grid)
                .map(|line| line.iter().any(|&b| b != 0.0))
                .collect(),
        );
        let n3 = grid * grid * grid;
        let len = fft.spectrum_len();
        let filters: Vec<Vec<f64>> = if general {
            radii
                .iter()
                .map(|&a_s| {
                    let mut f = vec![0.0; len];
                    f.par_chunks_mut(grid * grid)
                        .enumerate()
                        .for_each(|(kx, plane)| {
                            let x = kvec[kx].unwrap_or(0.0);
                            for ky in 0..grid {
                                let y = kvec[ky].unwrap_or(0.0);
                                for kz in 0..grid {
                                    let z = kvec[kz].unwrap_or(0.0);
                                    plane[ky * grid + kz] =
                                        sinc((x * x + y * y + z * z).sqrt() * a_s);
                                }
                            }
                        });
                    f
                })
                .collect()
        } else {
            Vec::new()
        };
        let n_species = radii.len();
        // Skin of the candidate lists: a tenth of the cut-off, less where the box is tight.
        let skin = (0.1 * r_cut).min(0.5 * (0.5 * l - r_cut)).max(0.0);
        let n_cells = ((l / (r_cut + skin)).floor() as usize).max(1);
        Ok(Self {
            params,
            geom,
            n,
            radii,
            species,
            mu0s,
            self_reals,
            self_rows: vec![0.0; n],
            tables,
            rc2s: r_cuts.iter().map(|r| r * r).collect(),
            candidate_ranges2: r_cuts.iter().map(|r| (r + skin) * (r + skin)).collect(),
            general,
            filters,
            tmp: if general {
                vec![C64::default(); len]
            } else {
                Vec::new()
            },
            pos: vec![[0.0; 3]; n],
            n_cells,
            cell_of: vec![0; n],
            cell_start: vec![0; n_cells.pow(3) + 1],
            cell_order: vec![0; n],
            skin,
            reference: Vec::new(),
            offsets: vec![0; n + 1],
            candidates: Vec::new(),
            entries: Entries::for_tolerance(params.tolerance),
            entry_offsets: vec![0; n + 1],
            counts: vec![0; n],
            row_particle: (0..n as u32).collect(),
            row_of: (0..n as u32).collect(),
            f_rows: vec![0.0; 3 * n],
            u_rows: vec![0.0; 3 * n],
            base: vec![[0; 3]; n],
            weights: vec![0.0; 3 * pts * n],
            f_sorted: vec![[0.0; 3]; n],
            plane_key: vec![0; n],
            plane_start: vec![0; n_species * grid * grid + 1],
            slot_of: vec![0; n],
            sorted: vec![[0.0; 3]; n],
            plane_order: vec![0; n],
            fft,
            real: [vec![0.0; n3], vec![0.0; n3], vec![0.0; n3]],
            spec: vec![C64::default(); len],
            work: [
                vec![C64::default(); len],
                vec![C64::default(); len],
                vec![C64::default(); len],
            ],
            kernel,
            kvec,
            plane_noise: vec![[C64::default(); 3]; grid * grid],
            lanczos: Lanczos::default(),
            noise: vec![[0.0; 3]; n],
            scratch: vec![[0.0; 3]; n],
            times: PseTimes::default(),
        })
    }

    /// Time spent in each part since the last reset.
    pub fn times(&self) -> &PseTimes {
        &self.times
    }

    /// Zero the timers.
    pub fn reset_times(&mut self) {
        self.times = PseTimes::default();
    }

    /// The chosen grid and cut-offs.
    pub fn geometry(&self) -> &PseGeometry {
        &self.geom
    }

    /// The parameters.
    pub fn params(&self) -> &PseParams {
        &self.params
    }

    /// Real-space neighbour pairs within the cut-off (both directions).
    pub fn pairs(&self) -> usize {
        self.entry_offsets[self.n]
    }

    /// Candidate lists: for each particle, the others within `r_cut + skin` (cell list, each
    /// row sorted by index), kept until a particle has moved more than half the skin.
    fn build_candidates(&mut self) {
        let (n, l, nc) = (self.n, self.params.box_length, self.n_cells);
        let range = self.geom.r_cut + self.skin;
        let cell = |x: f64| (((x / l + 0.5) * nc as f64) as usize).min(nc - 1);
        for (c, p) in self.cell_of.iter_mut().zip(&self.pos) {
            *c = ((cell(p[2]) * nc + cell(p[1])) * nc + cell(p[0])) as u32;
        }
        counting_sort(&self.cell_of, &mut self.cell_start, &mut self.cell_order);
        let cells = Cells {
            pos: &self.pos,
            cell_of: &self.cell_of,
            cell_start: &self.cell_start,
            cell_order: &self.cell_order,
            nc,
            l,
            rc2: range * range,
        };
        // Rows are stored in cell order (row r holds particle cell_order[r]), so that a row's
        // neighbours lie close in memory; within a row the neighbours stay in increasing
        // particle index, which fixes the order of the sums whatever the storage.
        // Each pair of species keeps the candidates within its own cut-off and the skin (the
        // cells are those of the largest).
        let perm = &self.cell_order;
        let (species, ranges2) = (&self.species, &self.candidate_ranges2);
        let near = |i: usize, j: u32, r2: f64| {
            r2 < ranges2[pair_index(species[i] as usize, species[j as usize] as usize)]
        };
        let mut off = std::mem::take(&mut self.offsets);
        off[1..].par_iter_mut().enumerate().for_each(|(r, c)| {
            let i = perm[r] as usize;
            let mut k = 0;
            cells.visit(i, &mut |j, _, r2| k += near(i, j, r2) as usize);
            *c = k;
        });
        off[0] = 0;
        for i in 0..n {
            off[i + 1] += off[i];
        }
        self.candidates.resize(off[n], 0);
        for_row_chunks(&off, &mut self.candidates, |lo, hi, out| {
            let base = off[lo];
            for r in lo..hi {
                let row = &mut out[off[r] - base..off[r + 1] - base];
                let i = perm[r] as usize;
                let mut k = 0;
                cells.visit(i, &mut |j, _, r2| {
                    if near(i, j, r2) {
                        row[k] = j;
                        k += 1;
                    }
                });
                row.sort_unstable();
            }
        });
        self.offsets = off;
        self.reference.clone_from(&self.pos);
        self.row_particle.clone_from(&self.cell_order);
        for (r, &p) in self.row_particle.iter().enumerate() {
            self.row_of[p as usize] = r as u32;
            self.self_rows[r] = self.self_reals[self.species[p as usize] as usize];
        }
    }

    /// The real-space pair tensors of the pairs within the cut-off, each row in increasing
    /// index (a function of the positions alone, whenever the candidates were built).
    fn build_real_space(&mut self) {
        let l = self.params.box_length;
        let lim = 0.25 * self.skin * self.skin;
        let (pos, reference) = (&self.pos, &self.reference);
        let moved = reference.len() != pos.len()
            || pos.par_iter().zip(reference.par_iter()).any(|(p, q)| {
                let d = [0, 1, 2].map(|k| {
                    let d = p[k] - q[k];
                    d - l * (d / l).round()
                });
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > lim
            });
        if moved {
            self.build_candidates();
        }
        let geometry = RealSpace {
            box_length: l,
            rc2s: &self.rc2s,
            radii: &self.radii,
            species: &self.species,
            viscosity: self.params.viscosity,
            tables: &self.tables,
            pos: &self.pos,
            offsets: &self.offsets,
            candidates: &self.candidates,
            row_particle: &self.row_particle,
            row_of: &self.row_of,
        };
        // The pairs within the cut-off counted, then their tensors computed in place.
        geometry.count(&mut self.counts);
        let eo = &mut self.entry_offsets;
        for (r, &c) in self.counts.iter().enumerate() {
            eo[r + 1] = eo[r] + c as usize;
        }
        self.entries.resize(eo[self.n]);
        match &mut self.entries {
            Entries::Single(e) => geometry.fill(e, eo),
            Entries::Double(e) => geometry.fill(e, eo),
        }
    }

    /// The particles' order by the first grid plane and row of their support, and their grid
    /// bases and window weights in that order (so that spreading and interpolation read them
    /// one after the other).
    fn build_spreading(&mut self) {
        let (g, pts) = (self.geom.grid, self.geom.support);
        let (h, l) = (self.geom.spacing, self.params.box_length);
        let window = self.geom.window_fn();
        // The support: the `pts` points closer than `pts h / 2` to the particle (the first
        // along an axis), and the particle's position in grid units.
        let half = 0.5 * pts as f64;
        let first = move |x: f64| {
            let s = (x + 0.5 * l) / h;
            ((s - half).floor() as isize + 1, s)
        };
        let wrap_base = |i0: isize| i0.rem_euclid(g as isize) as u32;
        self.plane_key
            .par_iter_mut()
            .zip(self.pos.par_iter())
            .zip(self.species.par_iter())
            .for_each(|((o, x), &s)| {
                *o =
                    (s * g as u32 + wrap_base(first(x[2]).0)) * g as u32 + wrap_base(first(x[1]).0);
            });
        counting_sort(
            &self.plane_key,
            &mut self.plane_start,
            &mut self.plane_order,
        );
        for (k, &j) in self.plane_order.iter().enumerate() {
            self.slot_of[j as usize] = k as u32;
        }
        let (pos, order) = (&self.pos, &self.plane_order);
        self.base
            .par_iter_mut()
            .zip(self.weights.par_chunks_mut(3 * pts))
            .zip(order.par_iter())
            .for_each(|((base, w), &j)| {
                let x = pos[j as usize];
                for k in 0..3 {
                    let (i0, s) = first(x[k]);
                    base[k] = wrap_base(i0);
                    for m in 0..pts {
                        w[k * pts + m] = window((i0 + m as isize) as f64 - s);
                    }
                }
            });
    }

    /// The forces `f` in the spreading order.
    fn sort_forces(&mut self, f: &[[f64; 3]]) {
        self.f_sorted
            .par_iter_mut()
            .zip(self.plane_order.par_iter())
            .with_min_len(1024)
            .for_each(|(o, &j)| *o = f[j as usize]);
    }

    /// Spread the sorted forces of species `s` onto the three real grids (a gather per plane).
    fn spread(&mut self, s: usize) {
        with_support!(self.geom.support, P => self.spread_p::<P>(s))
    }

    /// [`Self::spread`] with the support `P` known at compile time (`P = 0`: read at run time),
    /// so that the rows of the support vectorise.
    fn spread_p<const P: usize>(&mut self, s: usize) {
        let g = self.geom.grid;
        let pts = if P > 0 { P } else { self.geom.support };
        let (base, weights, f) = (&self.base, &self.weights, &self.f_sorted);
        // Species s's keys start at s g^2.
        let start = &self.plane_start[s * g * g..];
        let [gx, gy, gz] = &mut self.real;
        gx.par_chunks_mut(g * g)
            .zip(gy.par_chunks_mut(g * g))
            .zip(gz.par_chunks_mut(g * g))
            .enumerate()
            .for_each(|(p, ((px, py), pz))| {
                px.iter_mut().for_each(|v| *v = 0.0);
                py.iter_mut().for_each(|v| *v = 0.0);
                pz.iter_mut().for_each(|v| *v = 0.0);
                for m in 0..pts {
                    let b = wrap(p + g - m, g);
                    for j in start[b * g] as usize..start[(b + 1) * g] as usize {
                        let w = &weights[3 * pts * j..3 * pts * (j + 1)];
                        let (wx, wy, wz) = (&w[..pts], &w[pts..2 * pts], &w[2 * pts..]);
                        let fz = f[j].map(|c| c * wz[m]);
                        let [bx, by, _] = base[j];
                        let bx = bx as usize;
                        let contiguous = P > 0 && bx + P <= g;
                        for (iy, &wyv) in wy.iter().enumerate() {
                            let row = wrap(by as usize + iy, g) * g;
                            let c = fz.map(|c| c * wyv);
                            if contiguous {
                                let r = row + bx;
                                add_scaled_fixed::<P>(&mut px[r..r + P], wx, c[0]);
                                add_scaled_fixed::<P>(&mut py[r..r + P], wx, c[1]);
                                add_scaled_fixed::<P>(&mut pz[r..r + P], wx, c[2]);
                                continue;
                            }
                            for (x, w) in row_runs(bx, pts, g) {
                                let r = row + x.start..row + x.end;
                                add_scaled(&mut px[r.clone()], &wx[w.clone()], c[0]);
                                add_scaled(&mut py[r.clone()], &wx[w.clone()], c[1]);
                                add_scaled(&mut pz[r], &wx[w], c[2]);
                            }
                        }
                    }
                }
            });
    }

    /// `u_j = h^3 sum_g u(x_g) g(x_g − x_j)` from the three real grids, for the particles of
    /// species `s` (slots of the sorted order); [`Self::scatter`] takes them back.
    fn interpolate(&mut self, s: usize) {
        with_support!(self.geom.support, P => self.interpolate_p::<P>(s))
    }

    /// [`Self::interpolate`] with the support `P` known at compile time (`P = 0`: read at run
    /// time).
    fn interpolate_p<const P: usize>(&mut self, s: usize) {
        let (g, h) = (self.geom.grid, self.geom.spacing);
        let pts = if P > 0 { P } else { self.geom.support };
        let h3 = h * h * h;
        let [gx, gy, gz] = &self.real;
        let (weights, base) = (&self.weights, &self.base);
        let gg = g * g;
        let lo = self.plane_start[s * gg] as usize;
        let hi = self.plane_start[(s + 1) * gg] as usize;
        self.sorted[lo..hi]
            .par_iter_mut()
            .enumerate()
            .with_min_len(64)
            .for_each(|(j, o)| {
                let j = lo + j;
                let w = &weights[3 * pts * j..3 * pts * (j + 1)];
                let (wx, wy, wz) = (&w[..pts], &w[pts..2 * pts], &w[2 * pts..]);
                let [bx, by, bz] = base[j];
                let bx = bx as usize;
                let contiguous = P > 0 && bx + P <= g;
                // Per x column of the support, the grid summed over y and z with their
                // weights (independent lanes, so the sums vectorise), then the x weights.
                let mut t = [[0.0; MAX_SUPPORT]; 3];
                for (iz, &wzv) in wz.iter().enumerate() {
                    let plane = wrap(bz as usize + iz, g) * g * g;
                    for (iy, &wyv) in wy.iter().enumerate() {
                        let row = plane + wrap(by as usize + iy, g) * g;
                        let c = wzv * wyv;
                        if contiguous {
                            let r = row + bx;
                            add_scaled_fixed::<P>(&mut t[0], &gx[r..r + P], c);
                            add_scaled_fixed::<P>(&mut t[1], &gy[r..r + P], c);
                            add_scaled_fixed::<P>(&mut t[2], &gz[r..r + P], c);
                            continue;
                        }
                        for (x, w) in row_runs(bx, pts, g) {
                            let r = row + x.start..row + x.end;
                            add_scaled(&mut t[0][w.clone()], &gx[r.clone()], c);
                            add_scaled(&mut t[1][w.clone()], &gy[r.clone()], c);
                            add_scaled(&mut t[2][w], &gz[r], c);
                        }
                    }
                }
                *o = t.map(|tk| {
                    h3 * tk[..pts]
                        .iter()
                        .zip(wx)
                        .fold(0.0, |acc, (a, b)| acc + a * b)
                });
            });
    }

    /// `out (+)=` the interpolated velocities, from the sorted order.
    fn scatter(&mut self, out: &mut [[f64; 3]], add: bool) {
        let (sorted, slot_of) = (&self.sorted, &self.slot_of);
        out.par_iter_mut()
            .zip(slot_of.par_iter())
            .with_min_len(1024)
            .for_each(|(o, &k)| {
                let v = sorted[k as usize];
                for c in 0..3 {
                    o[c] = if add { o[c] + v[c] } else { v[c] };
                }
            });
    }

    /// The wave-space pass: `out (+)= dt M^w f + scale (M^w)^(1/2) W` (either part optional).
    fn wave(
        &mut self,
        f: Option<(&[[f64; 3]], f64)>,
        noise: Option<(NoiseKey, f64)>,
        out: &mut [[f64; 3]],
        add: bool,
    ) {
        let (g, l) = (self.geom.grid, self.params.box_length);
        let nh = g / 2 + 1;
        let vol = l * l * l;
        let h = self.geom.spacing;
        let det = if let Some((f, dt)) = f {
            self.sort_forces(f);
            // One species: its sinc^2 is in the kernel. Several: each species' transform,
            // filtered by its sinc, summed into `work`.
            for s in 0..self.radii.len() {
                let t = Instant::now();
                self.spread(s);
                let t1 = Instant::now();
                self.times.spread += (t1 - t).as_secs_f64();
                for c in 0..3 {
                    if !self.general || s == 0 {
                        self.fft
                            .forward(&mut self.real[c], &mut self.spec, &mut self.work[c]);
                        if self.general {
                            filter_into(&mut self.work[c], &self.filters[s]);
                        }
                    } else {
                        self.fft
                            .forward(&mut self.real[c], &mut self.spec, &mut self.tmp);
                        add_filtered(&mut self.work[c], &self.tmp, &self.filters[s]);
                    }
                }
                self.times.fft += t1.elapsed().as_secs_f64();
            }
            h * h * h / vol * dt
        } else {
            0.0
        };
        let (key, amp) = match noise {
            Some((key, scale)) => (Some(key), scale / vol.sqrt()),
            None => (None, 0.0),
        };
        let t0 = Instant::now();
        if let Some(key) = key {
            self.plane_noise_fill(key);
        }
        let (kernel, kvec, pn) = (&self.kernel, &self.kvec, &self.plane_noise);
        let zig = Ziggurat::get();
        let [wx, wy, wz] = &mut self.work;
        wx.par_chunks_mut(g * g)
            .zip(wy.par_chunks_mut(g * g))
            .zip(wz.par_chunks_mut(g * g))
            .enumerate()
            .for_each(|(kx, ((px, py), pz))| {
                let kxv = kvec[kx].unwrap_or(0.0);
                for ky in 0..g {
                    let kyv = kvec[ky].unwrap_or(0.0);
                    let mut rng = key.map(|key| {
                        stream(
                            key.seed,
                            key.step,
                            Purpose::Noise,
                            GRID_KEY | key.key0 | (ky * nh + kx) as u64,
                        )
                    });
                    for kz in 0..g {
                        let i = ky * g + kz;
                        let b = kernel[i + kx * g * g];
                        if b == 0.0 {
                            // No flow and no noise (nor draws) at the modes the kernel leaves
                            // out.
                            px[i] = C64::default();
                            py[i] = C64::default();
                            pz[i] = C64::default();
                            continue;
                        }
                        let kzv = kvec[kz].unwrap_or(0.0);
                        let k = [kxv, kyv, kzv];
                        let k2 = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
                        let project = |v: [C64; 3]| {
                            if k2 == 0.0 {
                                return [C64::default(); 3];
                            }
                            let kv = (v[0] * k[0] + v[1] * k[1] + v[2] * k[2]) / k2;
                            [v[0] - kv * k[0], v[1] - kv * k[1], v[2] - kv * k[2]]
                        };
                        let mut u = [C64::default(); 3];
                        if det != 0.0 {
                            let pf = project([px[i], py[i], pz[i]]);
                            let s = det * b;
                            u = pf.map(|c| c * s);
                        }
                        if let Some(rng) = rng.as_mut() {
                            let mut w = [C64::default(); 3];
                            let r = std::f64::consts::FRAC_1_SQRT_2;
                            for c in w.iter_mut() {
                                *c = C64::new(r * zig.sample(rng), r * zig.sample(rng));
                            }
                            if kx == 0 {
                                w = pn[ky * g + kz];
                            }
                            let pw = project(w);
                            let s = amp * b.sqrt();
                            for c in 0..3 {
                                u[c] += pw[c] * s;
                            }
                        }
                        px[i] = u[0];
                        py[i] = u[1];
                        pz[i] = u[2];
                    }
                }
            });
        self.times.kernel += t0.elapsed().as_secs_f64();
        if !self.general {
            let t1 = Instant::now();
            for c in 0..3 {
                self.fft
                    .inverse(&mut self.work[c], &mut self.spec, &mut self.real[c]);
            }
            let t2 = Instant::now();
            self.times.fft += (t2 - t1).as_secs_f64();
            self.interpolate(0);
            self.scatter(out, add);
            self.times.interpolate += t2.elapsed().as_secs_f64();
            return;
        }
        // Per species: the velocity spectrum filtered by its sinc, transformed back,
        // interpolated at its particles.
        for s in 0..self.radii.len() {
            let t1 = Instant::now();
            for c in 0..3 {
                filter_copy(&mut self.tmp, &self.work[c], &self.filters[s]);
                self.fft
                    .inverse(&mut self.tmp, &mut self.spec, &mut self.real[c]);
            }
            let t2 = Instant::now();
            self.times.fft += (t2 - t1).as_secs_f64();
            self.interpolate(s);
            self.times.interpolate += t2.elapsed().as_secs_f64();
        }
        let t3 = Instant::now();
        self.scatter(out, add);
        self.times.interpolate += t3.elapsed().as_secs_f64();
    }

    /// The Hermitian-symmetric noise of the kx = 0 plane: each pair `(ky, kz)`, `(−ky, −kz)`
    /// takes the draws of its first member (in storage order) and their conjugate.
    fn plane_noise_fill(&mut self, key: NoiseKey) {
        let (g, nh) = (self.geom.grid, self.geom.grid / 2 + 1);
        let zig = Ziggurat::get();
        let r = std::f64::consts::FRAC_1_SQRT_2;
        self.plane_noise
            .par_chunks_mut(g)
            .enumerate()
            .for_each(|(ky, line)| {
                let mut rng = stream(
                    key.seed,
                    key.step,
                    Purpose::Noise,
                    GRID_KEY | key.key0 | (ky * nh) as u64,
                );
                for w in line.iter_mut() {
                    for c in w.iter_mut() {
                        *c = C64::new(r * zig.sample(&mut rng), r * zig.sample(&mut rng));
                    }
                }
            });
        for ky in 0..g {
            for kz in 0..g {
                let (py, pz) = ((g - ky) % g, (g - kz) % g);
                if (py, pz) < (ky, kz) {
                    self.plane_noise[ky * g + kz] = self.plane_noise[py * g + pz].map(|c| c.conj());
                }
            }
        }
    }

    /// `out (+)= M^r f`: the forces gathered into row (cell) order, the rows summed there,
    /// the velocities gathered back.
    fn real_product(&mut self, f: &[f64], out: &mut [f64], add: bool) {
        let (offsets, s) = (&self.entry_offsets, &self.self_rows);
        let (row_particle, row_of) = (&self.row_particle, &self.row_of);
        let (f_rows, u_rows) = (&mut self.f_rows, &mut self.u_rows);
        f_rows
            .par_chunks_mut(3)
            .zip(row_particle.par_iter())
            .with_min_len(1024)
            .for_each(|(o, &p)| o.copy_from_slice(&f[3 * p as usize..3 * p as usize + 3]));
        match &self.entries {
            Entries::Single(e) => sum_rows(e, offsets, s, f_rows, u_rows),
            Entries::Double(e) => sum_rows(e, offsets, s, f_rows, u_rows),
        }
        let u_rows = &*u_rows;
        out.par_chunks_mut(3)
            .zip(row_of.par_iter())
            .with_min_len(1024)
            .for_each(|(o, &r)| {
                let u = &u_rows[3 * r as usize..3 * r as usize + 3];
                for k in 0..3 {
                    o[k] = if add { o[k] + u[k] } else { u[k] };
                }
            });
    }

    /// `out = scale (M^r)^(1/2) z(key)` by Lanczos.
    fn real_noise(
        &mut self,
        key: NoiseKey,
        scale: f64,
        out: &mut [[f64; 3]],
    ) -> Result<SqrtReport, HydroError> {
        fill_particle_noise(key, &mut self.noise);
        let mut lanczos = std::mem::take(&mut self.lanczos);
        let lp = LanczosParams {
            tolerance: self.params.tolerance,
            max_iterations: self.params.max_iterations,
        };
        let noise = std::mem::take(&mut self.noise);
        let t = Instant::now();
        let rep = lanczos.sqrt_times(
            &lp,
            noise.as_flattened(),
            |v, w| self.real_product(v, w, false),
            out.as_flattened_mut(),
        );
        self.times.real += t.elapsed().as_secs_f64();
        self.lanczos = lanczos;
        self.noise = noise;
        if let Ok(r) = &rep {
            self.times.lanczos_iterations += r.iterations as u64;
        }
        let rep = rep.map_err(|source| HydroError::Lanczos {
            step: key.step,
            source,
        })?;
        out.iter_mut().flatten().for_each(|x| *x *= scale);
        Ok(rep)
    }
}

/// What the real-space pair tensors are computed from.
struct RealSpace<'a> {
    box_length: f64,
    rc2s: &'a [f64],
    radii: &'a [f64],
    species: &'a [u32],
    viscosity: f64,
    tables: &'a [WaveTable],
    pos: &'a [[f64; 3]],
    offsets: &'a [usize],
    candidates: &'a [u32],
    row_particle: &'a [u32],
    row_of: &'a [u32],
}

impl RealSpace<'_> {
    /// The candidates of each row within their pair's cut-off.
    fn count(&self, counts: &mut [u32]) {
        let (l, off, cand, pos) = (self.box_length, self.offsets, self.candidates, self.pos);
        counts.par_iter_mut().enumerate().for_each(|(r, c)| {
            let pi = self.row_particle[r] as usize;
            let (xi, si) = (pos[pi], self.species[pi] as usize);
            *c = cand[off[r]..off[r + 1]]
                .iter()
                .filter(|&&j| {
                    let (_, r2) = nearest_image(xi, pos[j as usize], l);
                    r2 < self.rc2s[pair_index(si, self.species[j as usize] as usize)]
                })
                .count() as u32;
        });
    }

    /// The pair tensors `M^r = M^RPY − M^w_free` of the candidates within the cut-off, each
    /// row in increasing index, row `r` at `entry_offsets[r]` (from [`Self::count`]; a
    /// function of the positions alone, whenever the candidates were built).
    fn fill<T: Stored>(&self, entries: &mut [Entry<T>], entry_offsets: &[usize]) {
        let l = self.box_length;
        let (off, cand, pos) = (self.offsets, self.candidates, self.pos);
        for_row_chunks(entry_offsets, entries, |lo, hi, out| {
            let base = entry_offsets[lo];
            for r in lo..hi {
                let pi = self.row_particle[r] as usize;
                let (xi, si) = (pos[pi], self.species[pi] as usize);
                let mut k = entry_offsets[r] - base;
                for &j in &cand[off[r]..off[r + 1]] {
                    let (d, r2) = nearest_image(xi, pos[j as usize], l);
                    let sj = self.species[j as usize] as usize;
                    let pair = pair_index(si, sj);
                    if r2 < self.rc2s[pair] {
                        // One division per pair (the tensors are most of `set_positions`).
                        let inv_r = 1.0 / r2.sqrt();
                        let r = r2 * inv_r;
                        let (ai, aj) = (self.radii[si], self.radii[sj]);
                        let (ta, tb) = if ai == aj {
                            rpy_inv(r, inv_r, ai, self.viscosity)
                        } else {
                            rpy_unequal_inv(r, inv_r, ai, aj, self.viscosity)
                        };
                        let (aw, bw) = self.tables[pair].eval(r);
                        out[k] = Entry {
                            j: self.row_of[j as usize],
                            a: T::store(ta - aw),
                            b: T::store(tb - bw),
                            e: d.map(|x| T::store(x * inv_r)),
                        };
                        k += 1;
                    }
                }
                debug_assert_eq!(base + k, entry_offsets[r + 1]);
            }
        });
    }
}

/// `(A, B)` of the monodisperse RPY tensor ([`rpy`]) at distance `r = 1 / inv_r`, with
/// multiplications by `inv_r` in place of divisions.
#[inline(always)]
fn rpy_inv(r: f64, inv_r: f64, a: f64, eta: f64) -> (f64, f64) {
    if r >= 2.0 * a {
        let c = inv_r * (1.0 / (8.0 * PI * eta));
        let s2 = a * a * inv_r * inv_r;
        (c * (1.0 + 2.0 / 3.0 * s2), c * (1.0 - 2.0 * s2))
    } else {
        let mu0 = 1.0 / (6.0 * PI * eta * a);
        let x = r / (32.0 * a);
        (mu0 * (1.0 - 9.0 * x), mu0 * 3.0 * x)
    }
}

/// `(A, B)` of the unequal-radius RPY tensor ([`rpy_unequal`]) at distance `r = 1 / inv_r`,
/// the far branch with multiplications by `inv_r`.
#[inline(always)]
fn rpy_unequal_inv(r: f64, inv_r: f64, ai: f64, aj: f64, eta: f64) -> (f64, f64) {
    if r > ai + aj {
        let c = inv_r * (1.0 / (8.0 * PI * eta));
        let s2 = (ai * ai + aj * aj) * inv_r * inv_r;
        (c * (1.0 + s2 / 3.0), c * (1.0 - s2))
    } else {
        let t = rpy_unequal(r, ai, aj, eta);
        (t.a, t.b)
    }
}

/// `u_r = s_r f_r + sum_j M^r_rj f_j` for every row `r` (forces and velocities in row order,
/// `s_r` the row's self term).
fn sum_rows<T: Stored>(
    entries: &[Entry<T>],
    offsets: &[usize],
    s: &[f64],
    f_rows: &[f64],
    u_rows: &mut [f64],
) {
    u_rows
        .par_chunks_mut(3)
        .enumerate()
        .with_min_len(256)
        .for_each(|(r, o)| {
            let s = s[r];
            let mut u = [
                s * f_rows[3 * r],
                s * f_rows[3 * r + 1],
                s * f_rows[3 * r + 2],
            ];
            for e in &entries[offsets[r]..offsets[r + 1]] {
                let j = e.j as usize;
                let fj = [f_rows[3 * j], f_rows[3 * j + 1], f_rows[3 * j + 2]];
                let (a, b) = (e.a.load(), e.b.load());
                let ev = e.e.map(Stored::load);
                let ef = b * (ev[0] * fj[0] + ev[1] * fj[1] + ev[2] * fj[2]);
                for k in 0..3 {
                    u[k] += a * fj[k] + ef * ev[k];
                }
            }
            o.copy_from_slice(&u);
        });
}

/// The cell list of the real-space part.
struct Cells<'a> {
    pos: &'a [[f64; 3]],
    cell_of: &'a [u32],
    cell_start: &'a [u32],
    cell_order: &'a [u32],
    nc: usize,
    l: f64,
    rc2: f64,
}

/// `x_i - x_j` to the nearest periodic image in a cube of edge `l` (positions in
/// `[-L/2, L/2)`: one shift at most per axis) and its square length.
#[inline(always)]
fn nearest_image(xi: [f64; 3], xj: [f64; 3], l: f64) -> ([f64; 3], f64) {
    let mut d = [xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]];
    for c in d.iter_mut() {
        if *c >= 0.5 * l {
            *c -= l;
        } else if *c < -0.5 * l {
            *c += l;
        }
    }
    (d, d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
}

impl Cells<'_> {
    /// Call `f(j, x_i − x_j, r^2)` (nearest image) for the particles `j != i` within the
    /// cut-off, in a fixed order: the 27 cells around i's (all particles when there are fewer
    /// than 3 cells per axis), a cell's particles in index order.
    #[inline(always)]
    fn visit<F: FnMut(u32, [f64; 3], f64) + ?Sized>(&self, i: usize, f: &mut F) {
        let (nc, l, rc2, pos) = (self.nc, self.l, self.rc2, self.pos);
        let xi = pos[i];
        let mut pair = |j: u32| {
            let (d, r2) = nearest_image(xi, pos[j as usize], l);
            if r2 < rc2 && j as usize != i {
                f(j, d, r2);
            }
        };
        if nc < 3 {
            (0..pos.len() as u32).for_each(&mut pair);
            return;
        }
        let c = self.cell_of[i] as usize;
        let (cx, cy, cz) = (c % nc, (c / nc) % nc, c / (nc * nc));
        for dz in [nc - 1, 0, 1] {
            for dy in [nc - 1, 0, 1] {
                let row = (((cz + dz) % nc) * nc + (cy + dy) % nc) * nc;
                for dx in [nc - 1, 0, 1] {
                    let k = row + (cx + dx) % nc;
                    let (lo, hi) = (self.cell_start[k] as usize, self.cell_start[k + 1] as usize);
                    for &j in &self.cell_order[lo..hi] {
                        pair(j);
                    }
                }
            }
        }
    }
}

/// Run `f(lo, hi, rows)` in parallel over chunks of rows `lo..hi` of a CSR array `data` with
/// row offsets `off` (`rows` = the chunk's part of `data`).
fn for_row_chunks<T: Send>(
    off: &[usize],
    data: &mut [T],
    f: impl Fn(usize, usize, &mut [T]) + Sync + Send,
) {
    const CH: usize = 256;
    let n = off.len() - 1;
    let mut rest = data;
    let mut chunks = Vec::with_capacity(n.div_ceil(CH));
    for c in 0..n.div_ceil(CH) {
        let (lo, hi) = (c * CH, ((c + 1) * CH).min(n));
        let (head, tail) = rest.split_at_mut(off[hi] - off[lo]);
        chunks.push((lo, hi, head));
        rest = tail;
    }
    chunks
        .into_par_iter()
        .for_each(|(lo, hi, rows)| f(lo, hi, rows));
}

/// Largest window support (points per axis): tolerances down to 1e-30 need fewer
/// (1e-3: 5 points, 1e-6: 8); a smaller tolerance is refused.
const MAX_SUPPORT: usize = 32;

/// The most points of the real-space table of the wave-space functions (each costs a
/// quadrature over some 1000 wave numbers): 1e7, a table 25,000 times finer than its reach.
const MAX_TABLE_POINTS: f64 = 1e7;

/// The `pts` grid columns from `bx` (periodic in `g`) as at most two contiguous runs: pairs of
/// (columns of the grid row, offsets into the support); the second run is empty unless the
/// support wraps.
#[inline(always)]
fn row_runs(
    bx: usize,
    pts: usize,
    g: usize,
) -> [(std::ops::Range<usize>, std::ops::Range<usize>); 2] {
    let first = pts.min(g - bx);
    [(bx..bx + first, 0..first), (0..pts - first, first..pts)]
}

/// `i mod g` for `i < 2 g`, without an integer division (which would dominate the spreading).
#[inline(always)]
fn wrap(i: usize, g: usize) -> usize {
    if i >= g { i - g } else { i }
}

/// `y[..P] += c x[..P]` with the length known at compile time (vectorised in full).
#[inline(always)]
fn add_scaled_fixed<const P: usize>(y: &mut [f64], x: &[f64], c: f64) {
    let y: &mut [f64; P] = (&mut y[..P]).try_into().expect("P elements");
    let x: &[f64; P] = x[..P].try_into().expect("P elements");
    for k in 0..P {
        y[k] += c * x[k];
    }
}

/// Call `$body` with the const `$p` equal to the support `$pts` for the supports the usual
/// tolerances give (1e-2 to 1e-12: 4 to 14 points), else with `$p = 0` (read at run time).
macro_rules! with_support {
    ($pts:expr, $p:ident => $body:expr) => {
        with_support!(@arms $pts, $p, $body; 4 5 6 7 8 9 10 11 12 13 14)
    };
    (@arms $pts:expr, $p:ident, $body:expr; $($n:literal)*) => {
        match $pts {
            $($n => {
                const $p: usize = $n;
                $body
            })*
            _ => {
                const $p: usize = 0;
                $body
            }
        }
    };
}
use with_support;

/// `x *= w` per mode.
fn filter_into(x: &mut [C64], w: &[f64]) {
    x.par_chunks_mut(4096)
        .zip(w.par_chunks(4096))
        .for_each(|(x, w)| x.iter_mut().zip(w).for_each(|(x, &w)| *x *= w));
}

/// `y += w x` per mode.
fn add_filtered(y: &mut [C64], x: &[C64], w: &[f64]) {
    y.par_chunks_mut(4096)
        .zip(x.par_chunks(4096))
        .zip(w.par_chunks(4096))
        .for_each(|((y, x), w)| {
            for ((y, x), &w) in y.iter_mut().zip(x).zip(w) {
                *y += *x * w;
            }
        });
}

/// `y = w x` per mode.
fn filter_copy(y: &mut [C64], x: &[C64], w: &[f64]) {
    y.par_chunks_mut(4096)
        .zip(x.par_chunks(4096))
        .zip(w.par_chunks(4096))
        .for_each(|((y, x), w)| {
            for ((y, x), &w) in y.iter_mut().zip(x).zip(w) {
                *y = *x * w;
            }
        });
}

/// `y += c x` element by element.
#[inline(always)]
fn add_scaled(y: &mut [f64], x: &[f64], c: f64) {
    for (y, x) in y.iter_mut().zip(x) {
        *y += c * x;
    }
}

/// Counting sort of `keys` (values < `start.len() − 1`): `order` lists the indices by key,
/// ascending index within a key; `start[k]..start[k + 1]` is key k's range.
fn counting_sort(keys: &[u32], start: &mut [u32], order: &mut [u32]) {
    start.iter_mut().for_each(|s| *s = 0);
    for &k in keys {
        start[k as usize + 1] += 1;
    }
    for k in 1..start.len() {
        start[k] += start[k - 1];
    }
    // `start[k]` is used as the next free slot of key k, then restored.
    for (i, &k) in keys.iter().enumerate() {
        let s = &mut start[k as usize];
        order[*s as usize] = i as u32;
        *s += 1;
    }
    for k in (1..start.len()).rev() {
        start[k] = start[k - 1];
    }
    start[0] = 0;
}

impl Mobility for Pse {
    fn len(&self) -> usize {
        self.n
    }

    fn set_positions(&mut self, pos: &[[f64; 3]]) -> Result<(), HydroError> {
        if pos.len() != self.n {
            return Err(HydroError::Invalid(format!(
                "{} positions for {} particles",
                pos.len(),
                self.n
            )));
        }
        let l = self.params.box_length;
        for (i, (q, p)) in self.pos.iter_mut().zip(pos).enumerate() {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(HydroError::Invalid(format!(
                    "particle {i} has a non-finite position"
                )));
            }
            *q = p.map(|x| {
                let y = x - l * (x / l + 0.5).floor();
                // Rounding can leave y at +L/2.
                if y >= 0.5 * l { y - l } else { y }
            });
        }
        let t = Instant::now();
        self.build_real_space();
        let t1 = Instant::now();
        self.build_spreading();
        self.times.setup += t.elapsed().as_secs_f64();
        self.times.setup_spreading += t1.elapsed().as_secs_f64();
        Ok(())
    }

    fn apply(&mut self, f: &[[f64; 3]], out: &mut [[f64; 3]]) {
        self.wave(Some((f, 1.0)), None, out, false);
        let t = Instant::now();
        self.real_product(f.as_flattened(), out.as_flattened_mut(), true);
        self.times.real += t.elapsed().as_secs_f64();
    }

    fn brownian(
        &mut self,
        key: NoiseKey,
        scale: f64,
        out: &mut [[f64; 3]],
    ) -> Result<SqrtReport, HydroError> {
        let rep = self.real_noise(key, scale, out)?;
        self.wave(None, Some((key, scale)), out, true);
        Ok(rep)
    }

    /// Fused, not the provided method: the wave-space parts of `dt M f` and of the noise share
    /// one pass (one set of inverse FFTs and one interpolation instead of two, `dt` applied in
    /// wave space), then `dt M^r f` is added. The provided method sums in another order, so it
    /// would change the bits as well as cost more.
    fn displacement(
        &mut self,
        f: &[[f64; 3]],
        dt: f64,
        kt: f64,
        key: NoiseKey,
        out: &mut [[f64; 3]],
    ) -> Result<SqrtReport, HydroError> {
        let scale = (2.0 * kt * dt).sqrt();
        let rep = self.real_noise(key, scale, out)?;
        self.wave(Some((f, dt)), Some((key, scale)), out, true);
        let t = Instant::now();
        let mut u = std::mem::take(&mut self.scratch);
        self.real_product(f.as_flattened(), u.as_flattened_mut(), false);
        for (o, u) in out.iter_mut().zip(&u) {
            for k in 0..3 {
                o[k] += dt * u[k];
            }
        }
        self.scratch = u;
        self.times.real += t.elapsed().as_secs_f64();
        Ok(rep)
    }

    fn stokes_mobility(&self, i: usize) -> f64 {
        self.mu0s[self.species[i] as usize]
    }

    fn pair_block(&self, i: usize, j: usize) -> ([f64; 3], crate::rpy::PairTensor) {
        let (d, _) = nearest_image(self.pos[i], self.pos[j], self.params.box_length);
        let radius = |k: usize| self.radii[self.species[k] as usize];
        crate::rpy::pair_block(d, radius(i), radius(j), self.params.viscosity)
    }

    fn bytes(&self) -> usize {
        let n = self.n;
        8 * (3 * self.real[0].len()
            + self.kernel.len()
            + self.weights.len()
            + self.tables.iter().map(|t| 2 * t.a.len()).sum::<usize>()
            + self.filters.iter().map(Vec::len).sum::<usize>()
            + self.self_rows.len())
            + 16 * (self.spec.len() + 3 * self.work[0].len() + self.tmp.len())
            + 48 * self.plane_noise.len()
            + self.entries.bytes()
            + 8 * (self.offsets.len() + self.entry_offsets.len())
            + n * (24 + 12 + 4 * 4 + 2 * 24)
            + 4 * (self.cell_start.len() + self.plane_start.len())
            + self.fft.bytes()
            + self.lanczos.bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table's cubics are the 4-point Lagrange interpolation they replace.
    #[test]
    fn table_cubics_are_the_lagrange_interpolation() {
        let t = WaveTable::build(0.5, 0.5, 1.0, 1.0, 6.5);
        let scale = t.a[0]
            .abs()
            .max(t.b.iter().fold(0.0f64, |m, x| m.max(x.abs())));
        for k in 0..5000 {
            let r = k as f64 * 0.0013 + 1e-9;
            let (a, b) = t.eval(r);
            let (la, lb) = t.eval_lagrange(r);
            assert!(
                (a - la).abs() < 1e-13 * scale && (b - lb).abs() < 1e-13 * scale,
                "r = {r}: ({a}, {b}) vs ({la}, {lb})"
            );
        }
    }

    /// The window's transform (the deconvolution of the kernel) against a brute-force
    /// midpoint rule over the window itself, from k = 0 to the grid's Nyquist wave number,
    /// at the supports of tolerances 1e-2 to 1e-6.
    #[test]
    fn window_transform_matches_a_brute_force_quadrature() {
        for tol in [1e-2, 1e-3, 1e-4, 1e-6] {
            let mut p = PseParams::paper(0.5, 1.0, 12.0);
            p.tolerance = tol;
            let g = PseGeometry::new(&p).unwrap();
            let (w, h) = (g.half_width, g.spacing);
            let phi = g.window_fn();
            let m = 400_000;
            let dx = 2.0 * w / m as f64;
            for k in [0.0, 0.3, 1.0, 0.5 * PI / h, PI / h] {
                let brute: f64 = (0..m)
                    .map(|i| {
                        let x = -w + (i as f64 + 0.5) * dx;
                        phi(x / h) * (k * x).cos() * dx
                    })
                    .sum();
                let got = g.window_transform(k);
                assert!(
                    (got - brute).abs() < 1e-7 * brute.abs(),
                    "tolerance {tol}, support {}, k = {k}: {got} vs {brute}",
                    g.support
                );
                assert!(got > 0.0);
            }
            // Nothing of the window beyond its support: zero at the half-width.
            assert_eq!(phi(w / h), 0.0);
            assert!(phi(0.999 * w / h) > 0.0);
        }
    }

    /// The species path (sinc filters per species, the kernel without them) with one species
    /// gives the monodisperse path (sinc^2 in the kernel) to rounding. (Their wave-space
    /// noises differ in sign where sinc(ka) < 0: `sinc sqrt(b)` against `sqrt(sinc^2 b)`, two
    /// square roots of the same covariance.)
    #[test]
    fn species_path_with_one_species_is_the_monodisperse_path_to_rounding() {
        let (a, l, n) = (0.5, 9.0, 50);
        let pos: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                let t = i as f64 + 1.0;
                [0.618_033_988_7, 0.754_877_666_2, 0.569_840_290_9]
                    .map(|g| ((t * g).fract() - 0.5) * l)
            })
            .collect();
        let f: Vec<[f64; 3]> = (0..n)
            .map(|i| [(i % 3) as f64 - 1.0, 0.5, (i % 5) as f64 * 0.3 - 0.6])
            .collect();
        let run = |general: bool| {
            let p = PseParams::paper(a, 1.0, l);
            let mut m = Pse::build(p, vec![a], vec![0; n], general).unwrap();
            m.set_positions(&pos).unwrap();
            let mut u = vec![[0.0; 3]; n];
            m.apply(&f, &mut u);
            u
        };
        let (mono, general) = (run(false), run(true));
        let scale = mono.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        for (x, y) in mono.iter().flatten().zip(general.iter().flatten()) {
            assert!((x - y).abs() < 1e-12 * scale, "{x} vs {y}");
        }
    }
}
