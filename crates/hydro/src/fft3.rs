//! Three-dimensional real FFT of a cubic grid, from one-dimensional transforms (`realfft`
//! along x, `rustfft` along y and z), planes and lines in parallel.
//!
//! Layouts (n points per axis, `nh = n / 2 + 1` stored x-frequencies):
//! real grid `[z][y][x]`; half spectrum after the x and y passes `[z][kx][ky]` (the `spec`
//! buffer); full spectrum after the z pass `[kx][ky][kz]` (the `work` buffer, where the
//! wave-space kernel is applied). Each plane is transposed once per direction (`[y][kx]` to
//! `[kx][y]`), and the z pass gathers contiguous rows. Transforms are unnormalised (forward `e^{-ikx}`, inverse
//! `e^{+ikx}`; a round trip multiplies by `n^3`). Every line's transform is independent of the
//! others, so the result does not depend on how the planes are shared among threads.

use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// Complex number type of the spectra.
pub type C64 = Complex<f64>;

/// Plans and per-plane scratch of a cubic 3D real FFT.
pub struct Fft3 {
    n: usize,
    nh: usize,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    fwd: Arc<dyn Fft<f64>>,
    inv: Arc<dyn Fft<f64>>,
    /// Scratch length of the largest of the four transforms.
    scratch_len: usize,
    /// One scratch slot per plane.
    scratch: Vec<C64>,
    /// Whether the kz line `(kx, ky)` is wanted (`[kx][ky]`; empty: all are).
    active: Vec<bool>,
}

impl std::fmt::Debug for Fft3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Fft3({}^3)", self.n)
    }
}

impl Fft3 {
    /// Plans for an `n^3` grid (`n` even).
    pub fn new(n: usize) -> Self {
        assert!(n >= 2 && n.is_multiple_of(2), "grid size {n} must be even");
        let mut rp = RealFftPlanner::<f64>::new();
        let r2c = rp.plan_fft_forward(n);
        let c2r = rp.plan_fft_inverse(n);
        let mut cp = FftPlanner::<f64>::new();
        let fwd = cp.plan_fft_forward(n);
        let inv = cp.plan_fft_inverse(n);
        let scratch_len = r2c
            .get_scratch_len()
            .max(c2r.get_scratch_len())
            .max(fwd.get_inplace_scratch_len())
            .max(inv.get_inplace_scratch_len())
            .max(1);
        Self {
            n,
            nh: n / 2 + 1,
            r2c,
            c2r,
            fwd,
            inv,
            scratch_len,
            scratch: vec![C64::default(); scratch_len * n],
            active: Vec::new(),
        }
    }

    /// Prune the kz lines: `active[kx n + ky]` false for the lines `(kx, ky)` of the full
    /// spectrum whose values nobody reads after [`Self::forward`] (left unspecified there)
    /// and which are zero before [`Self::inverse`] (their transform, zero, is skipped).
    pub fn set_active_lines(&mut self, active: Vec<bool>) {
        assert_eq!(active.len(), self.nh * self.n, "one flag per kz line");
        self.active = active;
    }

    /// Length of a half spectrum (`spec` and `work` buffers).
    pub fn spectrum_len(&self) -> usize {
        self.n * self.n * self.nh
    }

    /// Bytes of the per-plane scratch.
    pub fn bytes(&self) -> usize {
        16 * self.scratch.len()
    }

    /// Forward transform of `real` (`[z][y][x]`, overwritten) into `work` (`[kx][ky][kz]`),
    /// through `spec`.
    pub fn forward(&mut self, real: &mut [f64], spec: &mut [C64], work: &mut [C64]) {
        let (n, nh, sl) = (self.n, self.nh, self.scratch_len);
        let (r2c, fwd) = (&self.r2c, &self.fwd);
        // x: real lines to half spectra; y: per plane, transpose [y][kx] -> [kx][y] into
        // `spec` and transform its lines: `spec` is then [z][kx][ky].
        real.par_chunks_mut(n * n)
            .zip(spec.par_chunks_mut(n * nh))
            .zip(work.par_chunks_mut(n * nh))
            .zip(self.scratch.par_chunks_mut(sl))
            .for_each(|(((rp, sp), tmp), scratch)| {
                for (line, out) in rp.chunks_exact_mut(n).zip(tmp.chunks_exact_mut(nh)) {
                    r2c.process_with_scratch(line, out, scratch)
                        .expect("r2c lengths");
                }
                transpose(tmp, sp, n, nh);
                fwd.process_with_scratch(sp, &mut scratch[..fwd.get_inplace_scratch_len()]);
            });
        // z: per kx, gather [z][kx][ky] -> [kx][ky][kz] (contiguous reads; the writes stay in
        // the plane) and transform the kz lines (the active ones).
        let spec = &*spec;
        let active = &self.active;
        let fl = fwd.get_inplace_scratch_len();
        work.par_chunks_mut(n * n)
            .zip(self.scratch.par_chunks_mut(sl))
            .enumerate()
            .for_each(|(kx, (wp, scratch))| {
                for z in 0..n {
                    let row = &spec[(z * nh + kx) * n..(z * nh + kx + 1) * n];
                    for (ky, &v) in row.iter().enumerate() {
                        wp[ky * n + z] = v;
                    }
                }
                for (ky, line) in wp.chunks_exact_mut(n).enumerate() {
                    if active.is_empty() || active[kx * n + ky] {
                        fwd.process_with_scratch(line, &mut scratch[..fl]);
                    }
                }
            });
    }

    /// Inverse transform of `work` (`[kx][ky][kz]`, overwritten) into `real` (`[z][y][x]`),
    /// through `spec`. The imaginary parts that a real signal's spectrum cannot have (kx = 0
    /// and kx = n/2 after the y pass) are dropped.
    pub fn inverse(&mut self, work: &mut [C64], spec: &mut [C64], real: &mut [f64]) {
        let (n, nh, sl) = (self.n, self.nh, self.scratch_len);
        let (c2r, inv) = (&self.c2r, &self.inv);
        let active = &self.active;
        let il = inv.get_inplace_scratch_len();
        work.par_chunks_mut(n * n)
            .zip(self.scratch.par_chunks_mut(sl))
            .enumerate()
            .for_each(|(kx, (wp, scratch))| {
                for (ky, line) in wp.chunks_exact_mut(n).enumerate() {
                    // An inactive line is zero, and so is its transform.
                    if active.is_empty() || active[kx * n + ky] {
                        inv.process_with_scratch(line, &mut scratch[..il]);
                    }
                }
            });
        {
            // [kx][ky][z] -> [z][kx][ky], blocks of Z planes so that each z line is read a
            // cache line at a time.
            const Z: usize = 4;
            let work = &*work;
            spec.par_chunks_mut(Z * n * nh)
                .enumerate()
                .for_each(|(b, sp)| {
                    let z0 = b * Z;
                    let planes = sp.len() / (n * nh);
                    for i in 0..n * nh {
                        let line = &work[i * n + z0..i * n + z0 + planes];
                        for (dz, &v) in line.iter().enumerate() {
                            sp[dz * n * nh + i] = v;
                        }
                    }
                });
        }
        real.par_chunks_mut(n * n)
            .zip(spec.par_chunks_mut(n * nh))
            .zip(work.par_chunks_mut(n * nh))
            .zip(self.scratch.par_chunks_mut(sl))
            .for_each(|(((rp, sp), tmp), scratch)| {
                inv.process_with_scratch(sp, &mut scratch[..inv.get_inplace_scratch_len()]);
                transpose(sp, tmp, nh, n);
                for (line, out) in tmp.chunks_exact_mut(nh).zip(rp.chunks_exact_mut(n)) {
                    line[0].im = 0.0;
                    line[nh - 1].im = 0.0;
                    c2r.process_with_scratch(line, out, scratch)
                        .expect("c2r lengths and real end points");
                }
            });
    }
}

/// `dst[c][r] = src[r][c]` for a `rows x cols` matrix `src`.
fn transpose(src: &[C64], dst: &mut [C64], rows: usize, cols: usize) {
    const B: usize = 16;
    for r0 in (0..rows).step_by(B) {
        let r1 = (r0 + B).min(rows);
        for c0 in (0..cols).step_by(B) {
            let c1 = (c0 + B).min(cols);
            for r in r0..r1 {
                let line = &src[r * cols + c0..r * cols + c1];
                for (c, &v) in (c0..c1).zip(line) {
                    dst[c * rows + r] = v;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Pruned kz lines: the active lines of the forward transform and the whole inverse (of a
    /// spectrum zero on the inactive lines) are those of the full transforms, bit for bit.
    #[test]
    fn pruned_lines_change_nothing_else() {
        let n = 8;
        let nh = n / 2 + 1;
        let real: Vec<f64> = (0..n * n * n)
            .map(|i| ((i * 29 % 31) as f64 - 15.0) / 7.0)
            .collect();
        let active: Vec<bool> = (0..nh * n).map(|i| (i * 7) % 5 != 0).collect();
        let mut full = Fft3::new(n);
        let mut pruned = Fft3::new(n);
        pruned.set_active_lines(active.clone());
        let len = full.spectrum_len();
        let mut spec = vec![C64::default(); len];
        let (mut a, mut b) = (vec![C64::default(); len], vec![C64::default(); len]);
        full.forward(&mut real.clone(), &mut spec, &mut a);
        pruned.forward(&mut real.clone(), &mut spec, &mut b);
        for (line, (x, y)) in a.chunks_exact(n).zip(b.chunks_exact(n)).enumerate() {
            if active[line] {
                assert_eq!(x, y, "line {line}");
            }
        }
        for (line, x) in a.chunks_exact_mut(n).enumerate() {
            if !active[line] {
                x.iter_mut().for_each(|v| *v = C64::default());
            }
        }
        let mut b = a.clone();
        let (mut ra, mut rb) = (vec![0.0; n * n * n], vec![0.0; n * n * n]);
        full.inverse(&mut a, &mut spec, &mut ra);
        pruned.inverse(&mut b, &mut spec, &mut rb);
        assert_eq!(ra, rb);
        assert!(ra.iter().any(|&x| x != 0.0));
    }

    #[test]
    fn forward_matches_the_definition_and_round_trips() {
        let n = 6;
        let mut fft = Fft3::new(n);
        let real: Vec<f64> = (0..n * n * n)
            .map(|i| ((i * 37 % 23) as f64 - 11.0) / 7.0)
            .collect();
        let mut r = real.clone();
        let mut spec = vec![C64::default(); fft.spectrum_len()];
        let mut work = vec![C64::default(); fft.spectrum_len()];
        fft.forward(&mut r, &mut spec, &mut work);
        let nh = n / 2 + 1;
        for ky in 0..n {
            for kx in 0..nh {
                for kz in 0..n {
                    let mut s = C64::default();
                    for z in 0..n {
                        for y in 0..n {
                            for x in 0..n {
                                let ph = -2.0 * PI * ((kx * x + ky * y + kz * z) as f64) / n as f64;
                                s += real[(z * n + y) * n + x] * C64::new(ph.cos(), ph.sin());
                            }
                        }
                    }
                    let got = work[(kx * n + ky) * n + kz];
                    assert!((got - s).norm() < 1e-11, "({kx},{ky},{kz}): {got} vs {s}");
                }
            }
        }
        let mut back = vec![0.0; n * n * n];
        fft.inverse(&mut work, &mut spec, &mut back);
        for (b, r) in back.iter().zip(&real) {
            assert!((b / (n * n * n) as f64 - r).abs() < 1e-13);
        }
    }
}
