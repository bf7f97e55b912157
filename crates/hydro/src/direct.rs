//! The direct method: the RPY mobility in an unbounded fluid by O(N^2) matrix-free products,
//! and free draining.
//!
//! A product `U_i = sum_j M_ij F_j` is one row per particle, rows in parallel (rayon). A row
//! sums its pairs in a fixed order: positions and forces are kept as structure of arrays, and
//! the pairs go through [`LANES`] independent accumulators (consecutive `j` in consecutive
//! lanes, the vectorised inner loop: both branches of the tensor computed and selected, no
//! branch), added in a fixed order at the end. So each row — and the product — is the same
//! for any number of threads. The self term is the `r = 0` limit of the overlapping branch
//! (`mu0 I`), so no pair is skipped. Nothing is allocated per product.
//!
//! The Brownian displacement is `scale M^(1/2) z` by the Lanczos square root
//! ([`crate::lanczos`]), one product per iteration.

use crate::lanczos::{Lanczos, LanczosParams, SqrtReport};
use crate::noise::{NoiseKey, fill_particle_noise};
use crate::{HydroError, Mobility};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Independent accumulators of a row (two AVX2 registers of f64).
pub const LANES: usize = 8;
/// Rows per parallel work item.
const ROWS: usize = 8;

/// Default largest N of the direct method.
pub const DEFAULT_MAX_DIRECT: usize = 20_000;

/// Radii of the spheres.
#[derive(Debug, Clone, PartialEq)]
enum Radii {
    /// All spheres have this radius.
    Equal(f64),
    /// Per sphere.
    Each(Vec<f64>),
}

/// Positions and radii as structure of arrays, and the force components of a product.
#[derive(Debug, Clone)]
struct Kernel {
    eta: f64,
    radii: Radii,
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    fx: Vec<f64>,
    fy: Vec<f64>,
    fz: Vec<f64>,
}

impl Kernel {
    /// Radius of sphere `i`.
    fn radius(&self, i: usize) -> f64 {
        match &self.radii {
            Radii::Equal(a) => *a,
            Radii::Each(r) => r[i],
        }
    }
}

/// One lane of the monodisperse pair kernel, in units of `mu0`: `(A, B / r^2)` of
/// `M = A I + B r̂r̂` for the separation with squared length `r2` (both branches; `r2 = 0`
/// gives the self term `(1, 0)`).
#[inline(always)]
fn mono_lane(r2: f64, a: f64, inv_a: f64, four_a2: f64) -> (f64, f64) {
    let inv_r = if r2 > 0.0 { 1.0 / r2.sqrt() } else { 0.0 };
    let r = r2 * inv_r;
    // r >= 2a: A = (3/4) s (1 + 2 s^2 / 3), B = (3/4) s (1 - 2 s^2), s = a / r.
    let s = a * inv_r;
    let s2 = s * s;
    let far_a = s * (0.75 + 0.5 * s2);
    let far_b = s * (0.75 - 1.5 * s2) * (inv_r * inv_r);
    // r < 2a: A = 1 - 9 r / (32 a), B = 3 r / (32 a).
    let near_a = 1.0 - (9.0 / 32.0) * r * inv_a;
    let near_b = (3.0 / 32.0) * inv_a * inv_r;
    if r2 < four_a2 {
        (near_a, near_b)
    } else {
        (far_a, far_b)
    }
}

/// One lane of the unequal-radius kernel (Zuk et al. 2014), in units of `1 / (8 pi eta)`.
#[inline(always)]
fn zuk_lane(r2: f64, ai: f64, aj: f64) -> (f64, f64) {
    let inv_r = if r2 > 0.0 { 1.0 / r2.sqrt() } else { 0.0 };
    let r = r2 * inv_r;
    let inv_r2 = inv_r * inv_r;
    let inv_r3 = inv_r2 * inv_r;
    let (sum, diff) = (ai + aj, (ai - aj).abs());
    let sq = ai * ai + aj * aj;
    let far_a = inv_r * (1.0 + sq * inv_r2 * (1.0 / 3.0));
    let far_b = inv_r3 * (1.0 - sq * inv_r2);
    // 8 pi eta / (6 pi eta ai aj 32 r^3) = 1 / (24 ai aj r^3).
    let c = inv_r3 / (24.0 * ai * aj);
    let d2 = diff * diff;
    let q = d2 + 3.0 * r2;
    let p = d2 - r2;
    let mid_a = c * (16.0 * r2 * r * sum - q * q);
    let mid_b = c * 3.0 * p * p * inv_r2;
    let in_a = (4.0 / 3.0) / ai.max(aj);
    if r > sum {
        (far_a, far_b)
    } else if r > diff {
        (mid_a, mid_b)
    } else {
        (in_a, 0.0)
    }
}

impl Kernel {
    fn len(&self) -> usize {
        self.x.len()
    }

    /// `U_i` of particle `i` from the forces in `fx, fy, fz` (physical units).
    #[inline(always)]
    fn row(&self, i: usize) -> [f64; 3] {
        let p = [self.x[i], self.y[i], self.z[i]];
        match &self.radii {
            Radii::Equal(a) => {
                let (a, inv_a, four_a2) = (*a, 1.0 / *a, 4.0 * a * a);
                let mu0 = 1.0 / (6.0 * PI * self.eta * a);
                // The radii slice is not read by this lane function: pass any of length N.
                let u = self.row_sum(p, &self.x, |r2, _| mono_lane(r2, a, inv_a, four_a2));
                u.map(|c| c * mu0)
            }
            Radii::Each(r) => {
                let ai = r[i];
                let u = self.row_sum(p, r, |r2, aj| zuk_lane(r2, ai, aj));
                u.map(|c| c / (8.0 * PI * self.eta))
            }
        }
    }

    /// `sum_j (A_j F_j + B_j d_j (d_j . F_j))` over all j, `(A, B) = lane(r2, a_j)`, in
    /// [`LANES`] accumulators: consecutive j in consecutive lanes, fixed-length chunks of the
    /// structure of arrays (the loop LLVM vectorises), the last partial chunk in the first
    /// lanes, and the lanes added in a fixed order.
    #[inline(always)]
    fn row_sum(
        &self,
        p: [f64; 3],
        radii: &[f64],
        lane: impl Fn(f64, f64) -> (f64, f64),
    ) -> [f64; 3] {
        const L: usize = LANES;
        let mut acc = [[0.0f64; L]; 3];
        let pair = |acc: &mut [[f64; L]; 3], l: usize, x: [f64; 3], f: [f64; 3], aj: f64| {
            let d = [p[0] - x[0], p[1] - x[1], p[2] - x[2]];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let (a, b) = lane(r2, aj);
            let df = b * (d[0] * f[0] + d[1] * f[1] + d[2] * f[2]);
            acc[0][l] += a * f[0] + df * d[0];
            acc[1][l] += a * f[1] + df * d[1];
            acc[2][l] += a * f[2] + df * d[2];
        };
        let chunks = self
            .x
            .chunks_exact(L)
            .zip(self.y.chunks_exact(L))
            .zip(self.z.chunks_exact(L))
            .zip(self.fx.chunks_exact(L))
            .zip(self.fy.chunks_exact(L))
            .zip(self.fz.chunks_exact(L))
            .zip(radii.chunks_exact(L));
        for ((((((x, y), z), fx), fy), fz), r) in chunks {
            for l in 0..L {
                pair(&mut acc, l, [x[l], y[l], z[l]], [fx[l], fy[l], fz[l]], r[l]);
            }
        }
        let full = self.len() / L * L;
        for j in full..self.len() {
            pair(
                &mut acc,
                j - full,
                [self.x[j], self.y[j], self.z[j]],
                [self.fx[j], self.fy[j], self.fz[j]],
                radii[j],
            );
        }
        acc.map(|c| {
            let mut s = [0.0; L / 2];
            for l in 0..L / 2 {
                s[l] = c[l] + c[l + L / 2];
            }
            (s[0] + s[2]) + (s[1] + s[3])
        })
    }

    /// `out = M f` (`f` already in `fx, fy, fz`).
    fn product(&self, out: &mut [[f64; 3]]) {
        out.par_chunks_mut(ROWS).enumerate().for_each(|(c, o)| {
            for (k, u) in o.iter_mut().enumerate() {
                *u = self.row(c * ROWS + k);
            }
        });
    }

    fn load_forces(&mut self, f: &[[f64; 3]]) {
        for (i, v) in f.iter().enumerate() {
            self.fx[i] = v[0];
            self.fy[i] = v[1];
            self.fz[i] = v[2];
        }
    }
}

/// The RPY mobility of spheres in an unbounded fluid, by direct summation.
#[derive(Debug, Clone)]
pub struct DirectRpy {
    kernel: Kernel,
    lanczos: Lanczos,
    params: LanczosParams,
    noise: Vec<[f64; 3]>,
    scratch: Vec<[f64; 3]>,
}

impl DirectRpy {
    /// `n` spheres of radius `radius` in a fluid of viscosity `eta`; at most `max_particles`.
    pub fn new(
        n: usize,
        radius: f64,
        eta: f64,
        lanczos: LanczosParams,
        max_particles: usize,
    ) -> Result<Self, HydroError> {
        Self::build(n, Radii::Equal(radius), eta, lanczos, max_particles)
    }

    /// Spheres of radii `radii` (unequal radii: Zuk et al. 2014).
    pub fn with_radii(
        radii: &[f64],
        eta: f64,
        lanczos: LanczosParams,
        max_particles: usize,
    ) -> Result<Self, HydroError> {
        let r = match radii.first() {
            Some(&a) if radii.iter().all(|&b| b == a) => Radii::Equal(a),
            _ => Radii::Each(radii.to_vec()),
        };
        Self::build(radii.len(), r, eta, lanczos, max_particles)
    }

    fn build(
        n: usize,
        radii: Radii,
        eta: f64,
        params: LanczosParams,
        max_particles: usize,
    ) -> Result<Self, HydroError> {
        if n > max_particles {
            let nf = n as f64;
            return Err(HydroError::TooManyParticles {
                particles: n,
                max: max_particles,
                pairs: nf * nf,
                matrix_gib: 9.0 * nf * nf * 8.0 / (1u64 << 30) as f64,
            });
        }
        let bad = match &radii {
            Radii::Equal(a) => !(a.is_finite() && *a > 0.0),
            Radii::Each(r) => r.iter().any(|a| !(a.is_finite() && *a > 0.0)),
        };
        if bad || !(eta.is_finite() && eta > 0.0) {
            return Err(HydroError::Invalid(format!(
                "radii and viscosity must be finite and > 0 (viscosity {eta})"
            )));
        }
        crate::params::check_lanczos(&params)?;
        let zeros = vec![0.0; n];
        Ok(Self {
            kernel: Kernel {
                eta,
                radii,
                x: zeros.clone(),
                y: zeros.clone(),
                z: zeros.clone(),
                fx: zeros.clone(),
                fy: zeros.clone(),
                fz: zeros,
            },
            lanczos: Lanczos::default(),
            params,
            noise: vec![[0.0; 3]; n],
            scratch: vec![[0.0; 3]; n],
        })
    }

    /// The Lanczos parameters.
    pub fn lanczos_params(&self) -> &LanczosParams {
        &self.params
    }
}

impl Mobility for DirectRpy {
    fn len(&self) -> usize {
        self.kernel.len()
    }

    fn set_positions(&mut self, pos: &[[f64; 3]]) -> Result<(), HydroError> {
        if pos.len() != self.len() {
            return Err(HydroError::Invalid(format!(
                "{} positions for {} particles",
                pos.len(),
                self.len()
            )));
        }
        if let Some(i) = pos.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            return Err(HydroError::Invalid(format!(
                "particle {i} has a non-finite position"
            )));
        }
        let k = &mut self.kernel;
        for (i, p) in pos.iter().enumerate() {
            k.x[i] = p[0];
            k.y[i] = p[1];
            k.z[i] = p[2];
        }
        Ok(())
    }

    fn apply(&mut self, f: &[[f64; 3]], out: &mut [[f64; 3]]) {
        self.kernel.load_forces(f);
        self.kernel.product(out);
    }

    fn brownian(
        &mut self,
        key: NoiseKey,
        scale: f64,
        out: &mut [[f64; 3]],
    ) -> Result<SqrtReport, HydroError> {
        fill_particle_noise(key, &mut self.noise);
        let kernel = &mut self.kernel;
        let rep = self
            .lanczos
            .sqrt_times(
                &self.params,
                self.noise.as_flattened(),
                |v, w| {
                    for (i, c) in v.chunks_exact(3).enumerate() {
                        kernel.fx[i] = c[0];
                        kernel.fy[i] = c[1];
                        kernel.fz[i] = c[2];
                    }
                    let (w3, _) = w.as_chunks_mut::<3>();
                    kernel.product(w3);
                },
                out.as_flattened_mut(),
            )
            .map_err(|source| HydroError::Lanczos {
                step: key.step,
                source,
            })?;
        out.iter_mut().flatten().for_each(|x| *x *= scale);
        Ok(rep)
    }

    // `displacement`: the trait's provided method (Lanczos noise, then the product).
    fn displacement_scratch(&mut self) -> Option<&mut Vec<[f64; 3]>> {
        Some(&mut self.scratch)
    }

    fn stokes_mobility(&self, i: usize) -> f64 {
        1.0 / (6.0 * PI * self.kernel.eta * self.kernel.radius(i))
    }

    fn pair_block(&self, i: usize, j: usize) -> ([f64; 3], crate::rpy::PairTensor) {
        let k = &self.kernel;
        let d = [k.x[i] - k.x[j], k.y[i] - k.y[j], k.z[i] - k.z[j]];
        crate::rpy::pair_block(d, k.radius(i), k.radius(j), k.eta)
    }

    fn bytes(&self) -> usize {
        let n = self.len();
        let radii = match &self.kernel.radii {
            Radii::Equal(_) => 0,
            Radii::Each(r) => 8 * r.len(),
        };
        6 * 8 * n + 2 * 24 * n + radii + self.lanczos.bytes()
    }
}

/// Free draining: `M_ij = delta_ij I / (6 pi eta a_i)` (no hydrodynamic coupling).
#[derive(Debug, Clone)]
pub struct FreeDraining {
    mobility: Vec<f64>,
    noise: Vec<[f64; 3]>,
}

impl FreeDraining {
    /// Spheres of radii `radii` in a fluid of viscosity `eta`.
    pub fn new(radii: &[f64], eta: f64) -> Result<Self, HydroError> {
        if radii.iter().any(|a| !(a.is_finite() && *a > 0.0)) || !(eta.is_finite() && eta > 0.0) {
            return Err(HydroError::Invalid(format!(
                "radii and viscosity must be finite and > 0 (viscosity {eta})"
            )));
        }
        Ok(Self {
            mobility: radii.iter().map(|a| 1.0 / (6.0 * PI * eta * a)).collect(),
            noise: vec![[0.0; 3]; radii.len()],
        })
    }
}

impl Mobility for FreeDraining {
    fn len(&self) -> usize {
        self.mobility.len()
    }

    fn set_positions(&mut self, pos: &[[f64; 3]]) -> Result<(), HydroError> {
        if pos.len() != self.len() {
            return Err(HydroError::Invalid(format!(
                "{} positions for {} particles",
                pos.len(),
                self.len()
            )));
        }
        Ok(())
    }

    fn apply(&mut self, f: &[[f64; 3]], out: &mut [[f64; 3]]) {
        for ((o, f), m) in out.iter_mut().zip(f).zip(&self.mobility) {
            *o = f.map(|c| c * m);
        }
    }

    fn brownian(
        &mut self,
        key: NoiseKey,
        scale: f64,
        out: &mut [[f64; 3]],
    ) -> Result<SqrtReport, HydroError> {
        fill_particle_noise(key, &mut self.noise);
        for ((o, z), m) in out.iter_mut().zip(&self.noise).zip(&self.mobility) {
            let s = scale * m.sqrt();
            *o = z.map(|c| c * s);
        }
        Ok(SqrtReport {
            iterations: 0,
            residual: 0.0,
        })
    }

    /// Kept rather than the provided method: this adds `(dt m_i) f`, the provided one would add
    /// `dt (f m_i)` (through [`Mobility::apply`]), which rounds differently; and it needs no
    /// buffer.
    fn displacement(
        &mut self,
        f: &[[f64; 3]],
        dt: f64,
        kt: f64,
        key: NoiseKey,
        out: &mut [[f64; 3]],
    ) -> Result<SqrtReport, HydroError> {
        let rep = self.brownian(key, (2.0 * kt * dt).sqrt(), out)?;
        for ((o, f), m) in out.iter_mut().zip(f).zip(&self.mobility) {
            for k in 0..3 {
                o[k] += dt * m * f[k];
            }
        }
        Ok(rep)
    }

    fn stokes_mobility(&self, i: usize) -> f64 {
        self.mobility[i]
    }

    fn bytes(&self) -> usize {
        8 * self.mobility.len() + 24 * self.noise.len()
    }
}

/// The dense 3N x 3N matrix of a mobility, column by column from products with unit forces
/// (for tests and small references; row-major, entry `(3 i + p, 3 j + q)`).
pub fn dense_matrix(m: &mut dyn Mobility) -> Vec<f64> {
    let n = m.len();
    let mut out = vec![0.0; 9 * n * n];
    let mut f = vec![[0.0; 3]; n];
    let mut u = vec![[0.0; 3]; n];
    for j in 0..n {
        for q in 0..3 {
            f[j][q] = 1.0;
            m.apply(&f, &mut u);
            f[j][q] = 0.0;
            for i in 0..n {
                for p in 0..3 {
                    out[(3 * i + p) * 3 * n + 3 * j + q] = u[i][p];
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rpy::{rpy, rpy_unequal};

    /// `pair_block(i, j)` is the block of the operator: a force on `j` alone moves `i` by it,
    /// for spheres of unequal radii apart and overlapping; free draining's is zero.
    #[test]
    fn pair_blocks_are_the_operators_blocks() {
        let radii = [0.5, 1.0, 0.5];
        let pos = [[0.0, 0.0, 0.0], [1.0, 0.6, -0.3], [0.3, -2.5, 1.1]];
        let mut m = DirectRpy::with_radii(&radii, 0.7, LanczosParams::default(), 10).unwrap();
        m.set_positions(&pos).unwrap();
        for (i, j) in [(0, 1), (1, 0), (0, 2), (2, 1)] {
            let (e, t) = m.pair_block(i, j);
            for k in 0..3 {
                let mut f = [[0.0; 3]; 3];
                f[j][k] = 1.0;
                let mut u = [[0.0; 3]; 3];
                m.apply(&f, &mut u);
                for c in 0..3 {
                    let want = t.a * (c == k) as u8 as f64 + t.b * e[c] * e[k];
                    assert!(
                        (u[i][c] - want).abs() < 1e-12,
                        "({i}, {j}) [{c}][{k}]: {} vs {want}",
                        u[i][c]
                    );
                }
            }
        }
        let fd = FreeDraining::new(&radii, 0.7).unwrap();
        assert_eq!(fd.pair_block(0, 1).1.a, 0.0);
    }

    fn config(n: usize, l: f64, seed: u64) -> Vec<[f64; 3]> {
        // A deterministic scatter (golden-ratio sequences).
        (0..n)
            .map(|i| {
                let t = (i as u64 + seed) as f64;
                [
                    ((t * 0.618_033_988_7).fract() - 0.5) * l,
                    ((t * 0.754_877_666_2).fract() - 0.5) * l,
                    ((t * 0.569_840_290_9).fract() - 0.5) * l,
                ]
            })
            .collect()
    }

    /// The dense matrix from the pair formulas of [`crate::rpy`].
    fn reference(pos: &[[f64; 3]], radii: &[f64], eta: f64) -> Vec<f64> {
        let n = pos.len();
        let mut m = vec![0.0; 9 * n * n];
        for i in 0..n {
            for j in 0..n {
                let d = [
                    pos[i][0] - pos[j][0],
                    pos[i][1] - pos[j][1],
                    pos[i][2] - pos[j][2],
                ];
                let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let t = if radii[i] == radii[j] {
                    rpy(r, radii[i], eta)
                } else {
                    rpy_unequal(r, radii[i], radii[j], eta)
                };
                let b = t.matrix(d);
                for p in 0..3 {
                    for q in 0..3 {
                        m[(3 * i + p) * 3 * n + 3 * j + q] = b[p][q];
                    }
                }
            }
        }
        m
    }

    #[test]
    fn product_equals_the_pair_formulas_mono_and_unequal() {
        // 29 particles (not a multiple of the lanes) and 150, dense enough for overlaps.
        for (n, l) in [(29, 4.0), (150, 6.9)] {
            product_matches_reference(n, l);
        }
    }

    fn product_matches_reference(n: usize, l: f64) {
        let pos = config(n, l, 3);
        let eta = 0.8;
        for radii in [
            vec![0.5; n],
            (0..n).map(|i| 0.3 + 0.4 * i as f64 / n as f64).collect(),
        ] {
            let mut m = DirectRpy::with_radii(&radii, eta, LanczosParams::default(), 200).unwrap();
            m.set_positions(&pos).unwrap();
            let got = dense_matrix(&mut m);
            let want = reference(&pos, &radii, eta);
            let scale = 1.0 / (6.0 * PI * eta * 0.3);
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() < 1e-14 * scale, "{g} vs {w}");
            }
            // Symmetric.
            let n3 = 3 * n;
            for r in 0..n3 {
                for c in 0..n3 {
                    assert!((got[r * n3 + c] - got[c * n3 + r]).abs() < 1e-15 * scale);
                }
            }
        }
    }

    #[test]
    fn too_many_particles_is_refused_with_the_memory() {
        let e = DirectRpy::new(30_000, 0.5, 1.0, LanczosParams::default(), 20_000).unwrap_err();
        let s = e.to_string();
        assert!(s.starts_with("method:") && s.contains("pse") && s.contains("GiB"));
    }

    #[test]
    fn products_and_noise_do_not_depend_on_the_thread_count() {
        let pos = config(300, 8.0, 1);
        let f: Vec<[f64; 3]> = config(300, 2.0, 9);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let mut m =
                        DirectRpy::new(300, 0.5, 1.0, LanczosParams::default(), 1000).unwrap();
                    m.set_positions(&pos).unwrap();
                    let mut u = vec![[0.0; 3]; 300];
                    let key = NoiseKey {
                        seed: 4,
                        step: 2,
                        key0: 0,
                    };
                    m.displacement(&f, 0.01, 1.0, key, &mut u).unwrap();
                    u
                })
        };
        assert_eq!(run(1), run(3));
    }

    #[test]
    fn displacements_keep_their_bits() {
        // Expected bits from DirectRpy's and FreeDraining's own displacement() at commit 705c480,
        // before DirectRpy moved to the trait's provided method.
        let (pos, f) = (config(4, 3.0, 1), config(4, 2.0, 5));
        let key = NoiseKey {
            seed: 3,
            step: 11,
            key0: 0,
        };
        let bits = |m: &mut dyn Mobility| {
            m.set_positions(&pos).unwrap();
            let mut u = vec![[0.0; 3]; 4];
            m.displacement(&f, 0.02, 1.1, key, &mut u).unwrap();
            u.as_flattened()
                .iter()
                .map(|v| v.to_bits())
                .collect::<Vec<_>>()
        };
        let mut direct = DirectRpy::new(4, 0.5, 0.9, LanczosParams::default(), 100).unwrap();
        assert_eq!(
            bits(&mut direct),
            [
                0xbf93011d99953ced,
                0x3f9d1c19c12f304f,
                0xbf907a7f26c66782,
                0x3f67ec7b8c6b3404,
                0xbfa0638a91260782,
                0xbfb2b6cdf4b942f7,
                0xbfa8e48cfe81adec,
                0x3f950b774509dcdb,
                0xbfb1f0ce5511064d,
                0x3fab79c2f0220ff8,
                0xbfb120d497369254,
                0xbfaf3b4eff97686d,
            ]
        );
        let mut free = FreeDraining::new(&[0.3, 0.4, 0.5, 0.6], 0.9).unwrap();
        assert_eq!(
            bits(&mut free),
            [
                0xbf9041eca1ba224b,
                0x3fa81d5bba60bd7a,
                0x3f824313be7b4870,
                0xbf54207bb8573e53,
                0xbf9bea14434fb22b,
                0xbfb304aeebfc5c27,
                0xbfa9f03de468bf95,
                0x3f96ad8326887614,
                0xbfaecffa8382ee20,
                0x3fad570a7038aaab,
                0xbfb076089f5f7a33,
                0xbfa5e5f029f35d6e,
            ]
        );
    }
}
