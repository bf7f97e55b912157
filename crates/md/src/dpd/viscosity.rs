//! Green–Kubo shear viscosity from the autocorrelation of the pressure tensor, accumulated as
//! the run goes (no storage of the stress history beyond one correlation window, no allocation
//! per sample).
//!
//! **Estimator.** With `P` the pressure tensor (kinetic + full pair virial over `V`: conservative,
//! dissipative and random forces, as [`super::Thermo::pressure`]),
//!
//! ```text
//! eta = V / kT  int_0^t_max  C(t) dt,    C(t) = < P_xy(0) P_xy(t) >          (Green–Kubo)
//! ```
//!
//! and, using every component of an isotropic fluid (Daivis & Evans 1994),
//! `C(t) = (1/10) sum_ab < Q_ab(0) Q_ab(t) >` with `Q = P - (tr P / 3) 1` the traceless symmetric
//! part: the three off-diagonal components count twice, the three traceless diagonal ones once
//! (`< Q_xx Q_xx > = (4/3) < P_xy P_xy >` by isotropy). Both the off-diagonal-only and the
//! all-component estimates are kept.
//!
//! **Why the random stress needs block averages.** The random DPD force makes the stress a sum
//! of a smooth part and a white noise of variance `~ 1 / dt` whose correlation is a delta at lag
//! 0. Its share of the viscosity is the instantaneous dissipative viscosity
//! `gamma / V < sum_pairs w(r)^2 (x y / r)^2 >` (with g(r) = 1 the `eta_D = 2 pi gamma rho^2
//! rc^5 / 1575` of Marsh, Backx & Ernst 1997), and the discrete Green–Kubo sum counts it right
//! only if the lag-0 term has weight `Delta / 2` with `Delta` the time the sample stands for.
//! This follows
//! from the Einstein–Helfand form: the Helfand moment `H(t) = sum_i x_i p_iy` changes by
//! `V int P_xy dt` (pairwise forces, momentum conserved), and
//! `eta = lim V / (2 kT t) < [int_0^t P_xy dt']^2 >`; with samples `S_n` that are the averages of
//! `P` over consecutive blocks of `every` steps, `int P dt = Delta sum_n S_n` exactly, and
//! `< (sum S_n)^2 > / (2 T)` becomes the trapezoid sum
//! `Delta [C_0 / 2 + C_1 + C_2 + ...]`. So a sample is the average of the pressure tensor over
//! all the steps of its block (every step must be fed), never the value at one step: sampling
//! the value every `k` steps would count the random stress `k` times (tested).
//!
//! **Running scheme.** A ring buffer holds the last `lags` samples; each new sample `S_n` is
//! multiplied with all of them, adding `S_n . S_{n-k}` to the sum of lag `k`. Only samples with a
//! complete window (`n >= lags - 1`) are counted, so every lag has the same number of products,
//! the first window (the relaxation of the start) is discarded, and the estimate
//! `eta = mean_n y_n` with `y_n = V Delta / kT sum_k w_k S_n . S_{n-k}` (trapezoid weights `w_0 =
//! w_{lags-1} = 1/2`, 1 otherwise) equals the trapezoid integral of the averaged correlation
//! function exactly. The `y_n` are summed per window (`lags` samples); at the end, the windows are
//! grouped into [`BLOCKS`] consecutive blocks and the standard error is that of the block means.
//! Each block must span at least [`MIN_WINDOWS_PER_BLOCK`] windows (`y_n` are correlated over
//! about two windows), otherwise no viscosity is reported.

use serde::{Deserialize, Serialize};

/// Number of blocks of the standard error.
pub const BLOCKS: usize = 10;
/// Correlation windows each block must span for the blocks to be nearly independent.
pub const MIN_WINDOWS_PER_BLOCK: usize = 2;

/// The running stress autocorrelation of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StressAcf {
    /// Steps averaged into one sample.
    every: u64,
    /// Time a sample stands for, `every dt`.
    delta: f64,
    /// `V / kT`.
    v_over_kt: f64,
    /// Sum of the pressure tensors of the current block (xx, yy, zz, xy, xz, yz).
    block: [f64; 6],
    /// Steps in the current block.
    block_steps: u64,
    /// The last `lags` samples, traceless symmetric part (xy, xz, yz, xx, yy, zz); `ring[head]`
    /// is where the next one goes.
    ring: Vec<[f64; 6]>,
    head: usize,
    /// Samples taken.
    samples: u64,
    /// Per lag: sums of the off-diagonal products (mean of the three) and of the
    /// all-component products (Daivis–Evans weights / 10), over the counted samples.
    sum_off: Vec<f64>,
    sum_all: Vec<f64>,
    /// Samples with a complete window (counted).
    counted: u64,
    /// Sums of `y_n` (all components, off-diagonal) over the current window.
    window_y: [f64; 2],
    window_n: u64,
    /// Sums of `y_n` of each completed window.
    windows: Vec<[f64; 2]>,
}

/// One estimate with its block standard error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Viscosity (mass / (length time)).
    pub value: f64,
    /// Standard error of the mean of the block estimates.
    pub error: f64,
}

/// The viscosity of a run, or why there is none.
#[derive(Debug, Clone, PartialEq)]
pub struct Viscosity {
    /// From all five independent components of the traceless stress (Daivis–Evans).
    pub all: Option<Estimate>,
    /// From the three off-diagonal components only.
    pub off_diagonal: Option<Estimate>,
    /// How it was measured, or why it is missing.
    pub note: String,
}

/// The correlation function and its running integral, one row per lag.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct AcfTable {
    /// Lag in steps.
    pub lag_steps: Vec<f64>,
    /// Lag in time units.
    pub time: Vec<f64>,
    /// `C(t)`, all components (Daivis–Evans).
    pub acf: Vec<f64>,
    /// `V / kT int_0^t C dt'` (trapezoid).
    pub integral: Vec<f64>,
    /// `C(t)`, off-diagonal components.
    pub acf_off_diagonal: Vec<f64>,
    /// Its running integral.
    pub integral_off_diagonal: Vec<f64>,
}

impl StressAcf {
    /// A correlator averaging `every` steps of length `dt` into one sample and keeping lags
    /// `0 .. lags` (`lags >= 2`), for a box of volume `volume` at temperature `kt`.
    ///
    /// # Panics
    /// When `every == 0` or `lags < 2` (the scenario keys are validated before).
    pub fn new(every: u64, lags: usize, dt: f64, volume: f64, kt: f64) -> Self {
        assert!(every >= 1 && lags >= 2, "every {every}, lags {lags}");
        Self {
            every,
            delta: every as f64 * dt,
            v_over_kt: volume / kt,
            block: [0.0; 6],
            block_steps: 0,
            ring: vec![[0.0; 6]; lags],
            head: 0,
            samples: 0,
            sum_off: vec![0.0; lags],
            sum_all: vec![0.0; lags],
            counted: 0,
            window_y: [0.0; 2],
            window_n: 0,
            windows: Vec::new(),
        }
    }

    /// Number of lags.
    pub fn lags(&self) -> usize {
        self.ring.len()
    }

    /// Time between samples.
    pub fn delta(&self) -> f64 {
        self.delta
    }

    /// Samples with a complete correlation window (those in the estimate).
    pub fn counted(&self) -> u64 {
        self.counted
    }

    /// Feed the pressure tensor `p` (xx, yy, zz, xy, xz, yz) of one step; every step of the
    /// run must be fed (see the module documentation).
    pub fn push(&mut self, p: &[f64; 6]) {
        for (a, b) in self.block.iter_mut().zip(p) {
            *a += b;
        }
        self.block_steps += 1;
        if self.block_steps == self.every {
            let inv = 1.0 / self.every as f64;
            let s = self.block.map(|x| x * inv);
            self.block = [0.0; 6];
            self.block_steps = 0;
            self.sample(&s);
        }
    }

    /// One sample: the block average `s` of the pressure tensor.
    fn sample(&mut self, s: &[f64; 6]) {
        let tr = (s[0] + s[1] + s[2]) / 3.0;
        let q = [s[3], s[4], s[5], s[0] - tr, s[1] - tr, s[2] - tr];
        let lags = self.ring.len();
        self.ring[self.head] = q;
        self.samples += 1;
        if self.samples >= lags as u64 {
            // Lag k is at ring[head - k]: first head, head - 1, ..., 0, then lags - 1, ...,
            // head + 1.
            let (recent, older) = self.ring.split_at(self.head + 1);
            let partners = recent.iter().rev().chain(older.iter().rev());
            let (mut y_all, mut y_off) = (0.0, 0.0);
            for (k, r) in partners.enumerate() {
                let off = (q[0] * r[0] + q[1] * r[1] + q[2] * r[2]) / 3.0;
                let diag = q[3] * r[3] + q[4] * r[4] + q[5] * r[5];
                // (2 * 3 off-diagonal + diagonal) / 10.
                let all = 0.6 * off + 0.1 * diag;
                self.sum_off[k] += off;
                self.sum_all[k] += all;
                let w = if k == 0 || k == lags - 1 { 0.5 } else { 1.0 };
                y_all += w * all;
                y_off += w * off;
            }
            let scale = self.v_over_kt * self.delta;
            self.counted += 1;
            self.window_y[0] += scale * y_all;
            self.window_y[1] += scale * y_off;
            self.window_n += 1;
            if self.window_n == lags as u64 {
                self.windows.push(self.window_y);
                self.window_y = [0.0; 2];
                self.window_n = 0;
            }
        }
        self.head = (self.head + 1) % lags;
    }

    /// The averaged correlation functions and their running integrals (empty before the first
    /// counted sample).
    pub fn table(&self) -> AcfTable {
        if self.counted == 0 {
            return AcfTable::default();
        }
        let n = self.counted as f64;
        let lags = self.ring.len();
        let mut t = AcfTable::default();
        let (mut int_all, mut int_off) = (0.0, 0.0);
        for k in 0..lags {
            let (a, o) = (self.sum_all[k] / n, self.sum_off[k] / n);
            if k > 0 {
                let (pa, po) = (self.sum_all[k - 1] / n, self.sum_off[k - 1] / n);
                int_all += 0.5 * (a + pa) * self.delta * self.v_over_kt;
                int_off += 0.5 * (o + po) * self.delta * self.v_over_kt;
            }
            t.lag_steps.push((k as u64 * self.every) as f64);
            t.time.push(k as f64 * self.delta);
            t.acf.push(a);
            t.integral.push(int_all);
            t.acf_off_diagonal.push(o);
            t.integral_off_diagonal.push(int_off);
        }
        t
    }

    /// The viscosity `V / kT int_0^t_max C dt` with the block standard error, or why not.
    pub fn viscosity(&self) -> Viscosity {
        let lags = self.ring.len();
        let t_max = (lags - 1) as f64 * self.delta;
        let need_windows = BLOCKS * MIN_WINDOWS_PER_BLOCK;
        let need_samples = (need_windows + 1) * lags - 1;
        let need_steps = need_samples as u64 * self.every;
        let windows = self.windows.len();
        if windows < need_windows {
            return Viscosity {
                all: None,
                off_diagonal: None,
                note: format!(
                    "not measured: {} stress samples of {} steps with a complete correlation \
                     window of {lags} lags (t_max = {t_max}); the error over {BLOCKS} blocks of \
                     at least {MIN_WINDOWS_PER_BLOCK} windows needs {need_samples} samples, i.e. \
                     a run of at least {need_steps} steps",
                    self.counted, self.every
                ),
            };
        }
        let n = self.counted as f64;
        let mut total = [0.0; 2];
        // The estimate uses every counted sample; the blocks use whole windows.
        for w in &self.windows {
            total[0] += w[0];
            total[1] += w[1];
        }
        total[0] += self.window_y[0];
        total[1] += self.window_y[1];
        let per_block = windows / BLOCKS;
        let block_samples = (per_block * lags) as f64;
        let estimate = |c: usize| {
            let means: Vec<f64> = self.windows[..per_block * BLOCKS]
                .chunks(per_block)
                .map(|b| b.iter().map(|w| w[c]).sum::<f64>() / block_samples)
                .collect();
            let m = means.iter().sum::<f64>() / BLOCKS as f64;
            let var = means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (BLOCKS - 1) as f64;
            Estimate {
                value: total[c] / n,
                error: (var / BLOCKS as f64).sqrt(),
            }
        };
        Viscosity {
            all: Some(estimate(0)),
            off_diagonal: Some(estimate(1)),
            note: format!(
                "Green-Kubo: V/kT times the trapezoid integral of the stress autocorrelation up \
                 to t_max = {t_max} ({lags} lags of {} steps, each sample the average pressure \
                 tensor over them), {} samples; error: standard error of {BLOCKS} block means",
                self.every, self.counted
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (SplitMix64) and Gaussian numbers by Box–Muller.
    struct Rng(u64);
    impl Rng {
        fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            ((z >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
        }
        fn gauss(&mut self) -> f64 {
            let (u, v) = (self.uniform(), self.uniform());
            (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
        }
    }

    /// Feed `steps` pressure tensors whose six components are independent Ornstein–Uhlenbeck
    /// series `x_n = a x_{n-1} + sqrt(1 - a^2) s xi_n` with the same correlation `a = exp(-dt /
    /// tau)`; off-diagonal standard deviation `s`, diagonal `sqrt 2 s` (so that the traceless
    /// diagonal parts have the isotropic variance `(4/3) s^2`), plus `white` times a white noise
    /// on every component (the random stress of DPD). The diagonal carries a constant pressure
    /// 23, which the traceless part must remove.
    fn feed(acf: &mut StressAcf, steps: u64, a: f64, s: f64, white: f64, seed: u64) {
        let mut rng = Rng(seed);
        let sd = [2f64.sqrt() * s, 2f64.sqrt() * s, 2f64.sqrt() * s, s, s, s];
        let mut x: [f64; 6] = std::array::from_fn(|k| sd[k] * rng.gauss());
        let b = (1.0 - a * a).sqrt();
        for _ in 0..steps {
            let mut p = [0.0; 6];
            for k in 0..6 {
                x[k] = a * x[k] + b * sd[k] * rng.gauss();
                let base = if k < 3 { 23.0 } else { 0.0 };
                p[k] = base + x[k] + white * sd[k] / s * rng.gauss();
            }
            acf.push(&p);
        }
    }

    /// The discrete Green–Kubo integral of the series of [`feed`] sampled every step:
    /// `V / kT dt [s^2 (1/2 + sum_k>=1 a^k) + white^2 / 2]`, truncated at `lags`.
    fn exact(a: f64, s: f64, white: f64, lags: usize, dt: f64, v_over_kt: f64) -> f64 {
        let tail = (1..lags - 1).map(|k| a.powi(k as i32)).sum::<f64>();
        let ends = 0.5 + 0.5 * a.powi(lags as i32 - 1);
        v_over_kt * dt * (s * s * (ends + tail) + 0.5 * white * white)
    }

    #[test]
    fn ornstein_uhlenbeck_integral_is_recovered_within_the_block_error() {
        // tau = 20 steps, window 200 steps (10 tau): the truncated tail is e^-10.
        let (dt, tau, lags) = (0.01_f64, 0.2, 200);
        let a = (-dt / tau).exp();
        let (v, kt, s) = (512.0, 1.0, 0.05);
        let mut acf = StressAcf::new(1, lags, dt, v, kt);
        feed(&mut acf, 400_000, a, s, 0.0, 11);
        let eta = acf.viscosity();
        let (all, off) = (eta.all.unwrap(), eta.off_diagonal.unwrap());
        let want = exact(a, s, 0.0, lags, dt, v / kt);
        // Continuum value V/kT s^2 tau = 0.256; the discrete sum differs by O(dt^2 / tau^2).
        assert!((want - v * s * s * tau).abs() < 1e-3 * want);
        eprintln!(
            "OU: all {} +- {}, off-diagonal {} +- {}, exact {want}",
            all.value, all.error, off.value, off.error
        );
        for e in [all, off] {
            assert!(e.error > 0.0 && e.error < 0.05 * want, "error {}", e.error);
            assert!((e.value - want).abs() < 4.0 * e.error, "{e:?} vs {want}");
        }
        // Five independent components beat three.
        assert!(all.error < off.error);
        // The table ends at the estimate and starts at the variance.
        let t = acf.table();
        assert_eq!(t.time.len(), lags);
        assert!((t.integral[lags - 1] - all.value).abs() < 1e-9 * all.value);
        assert!((t.integral_off_diagonal[lags - 1] - off.value).abs() < 1e-9 * off.value);
        assert!(
            (t.acf[0] - s * s).abs() < 0.05 * s * s,
            "C(0) = {}",
            t.acf[0]
        );
        assert!((t.time[lags - 1] - (lags - 1) as f64 * dt).abs() < 1e-12);
    }

    #[test]
    fn the_block_error_matches_the_scatter_of_independent_runs() {
        let (dt, tau, lags) = (0.01_f64, 0.1, 100);
        let a = (-dt / tau).exp();
        let runs = 40;
        let mut values = Vec::new();
        let mut errors = Vec::new();
        for seed in 0..runs {
            let mut acf = StressAcf::new(1, lags, dt, 1.0, 1.0);
            feed(&mut acf, 40_000, a, 1.0, 0.0, 1000 + seed);
            let e = acf.viscosity().all.unwrap();
            values.push(e.value);
            errors.push(e.error);
        }
        let m = values.iter().sum::<f64>() / runs as f64;
        let sd = (values.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (runs - 1) as f64).sqrt();
        let rms_error = (errors.iter().map(|e| e * e).sum::<f64>() / runs as f64).sqrt();
        eprintln!("scatter {sd}, mean block error {rms_error}");
        // The scatter of 40 runs is known to +-11 %; the block error must match it within 30 %.
        assert!(
            (rms_error / sd - 1.0).abs() < 0.3,
            "block error {rms_error} vs scatter {sd}"
        );
        let want = exact(a, 1.0, 0.0, lags, dt, 1.0);
        assert!(
            (m - want).abs() < 4.0 * sd / (runs as f64).sqrt(),
            "{m} vs {want}"
        );
    }

    #[test]
    fn white_noise_counts_half_its_variance_whatever_the_block_length() {
        // The random stress of DPD: a white noise of variance w^2 per step contributes
        // V/kT dt w^2 / 2 (Einstein–Helfand), whether samples are single steps or averages of 4.
        let (dt, lags) = (0.01, 50);
        let a = 0.5;
        let (s, white) = (0.3, 2.0);
        let want = exact(a, s, white, lags, dt, 1.0);
        for every in [1, 4] {
            let mut acf = StressAcf::new(every, lags, dt, 1.0, 1.0);
            feed(&mut acf, 2_000_000, a, s, white, 5);
            let e = acf.viscosity().all.unwrap();
            eprintln!("every {every}: {} +- {}, exact {want}", e.value, e.error);
            // The Einstein–Helfand sum is the same for any block length (the OU part, tau =
            // 1.4 steps, included): no allowance beyond the statistics.
            let tol = 4.0 * e.error;
            assert!(
                (e.value - want).abs() < tol,
                "every {every}: {e:?} vs {want}"
            );
        }
    }

    #[test]
    fn too_short_a_run_gives_no_viscosity_and_says_why() {
        let mut acf = StressAcf::new(2, 10, 0.01, 1.0, 1.0);
        feed(&mut acf, 100, 0.5, 1.0, 0.0, 3);
        let v = acf.viscosity();
        assert!(v.all.is_none() && v.off_diagonal.is_none());
        // 21 windows of 10 samples minus 1, of 2 steps.
        assert!(v.note.contains("418 steps"), "{}", v.note);
        assert!(acf.table().acf.len() == 10);
        let mut acf = StressAcf::new(2, 10, 0.01, 1.0, 1.0);
        feed(&mut acf, 418, 0.5, 1.0, 0.0, 3);
        assert!(acf.viscosity().all.is_some());
        let mut acf = StressAcf::new(2, 10, 0.01, 1.0, 1.0);
        feed(&mut acf, 416, 0.5, 1.0, 0.0, 3);
        assert!(acf.viscosity().all.is_none());
    }
}
