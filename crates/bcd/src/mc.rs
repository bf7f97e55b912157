//! Metropolis Monte Carlo of hard or sticky rods on a ring in a cosine potential: the exact
//! equilibrium of what BCD simulates, with no time step, for validation (hard-rods paper Figs. 4
//! and 6; docs/figures.md).
//!
//! The pair weight is the finite-range Baxter well of [`crate::forces::Sticky`] with p = 3
//! (hard-rods paper Eq. 33 ff.): `exp(-V(r)/kT) = 1 + gamma (p + 1) (eps - g)^p / eps^(p + 1)`
//! for a gap `g = r - sigma` in `[0, eps)`, 1 beyond, 0 on overlap; `gamma = 0` is hard rods.
//! A sweep is N single-rod moves and N / 4 + 1 rigid moves of a chain (consecutive rods with
//! gaps below eps, bound or merely close), rejected if the chain would gain or lose a member, so that the reverse
//! move picks the same chain (detailed balance); chain moves let chains cross the wells, which
//! single-rod moves at 6.7 kT per bond (gamma = 10) hardly do.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

/// Rods on a ring of length `length` in `U = (u0 / 2) cos(2 pi x)` (kT = 1, wavelength 1).
pub struct StickyRing {
    /// Positions, in ring order (not wrapped).
    pub x: Vec<f64>,
    length: f64,
    sigma: f64,
    gamma: f64,
    eps: f64,
    u0: f64,
    rng: StdRng,
}

impl StickyRing {
    /// `n` rods evenly spaced; `gamma = 0` for hard rods (then `eps` only sets which rods the
    /// chain moves carry together).
    pub fn new(
        n: usize,
        length: f64,
        u0: f64,
        sigma: f64,
        gamma: f64,
        eps: f64,
        seed: u64,
    ) -> Self {
        assert!(n >= 2 && n as f64 * sigma < length && eps > 0.0 && gamma >= 0.0);
        Self {
            x: (0..n)
                .map(|i| (i as f64 + 0.5) * length / n as f64)
                .collect(),
            length,
            sigma,
            gamma,
            eps,
            u0,
            rng: StdRng::seed_from_u64(seed),
        }
    }

    /// One sweep: `N` single-rod moves (up to 0.1) and `N / 4 + 1` chain moves (up to 0.3).
    pub fn sweep(&mut self) {
        for _ in 0..self.n() {
            self.single(0.1);
        }
        for _ in 0..self.n() / 4 + 1 {
            self.chain(0.3);
        }
    }

    /// Add the rods' positions, folded into one period, to the histogram `counts` (bins over
    /// `[0, 1)`).
    pub fn histogram(&self, counts: &mut [f64]) {
        let bins = counts.len();
        for &x in &self.x {
            let b = (x.rem_euclid(1.0) * bins as f64) as usize;
            counts[b.min(bins - 1)] += 1.0;
        }
    }

    /// Pairs of neighbours closer than `sigma + w` (with `w = eps`: the bound pairs).
    pub fn pairs_within(&self, w: f64) -> usize {
        let n = self.n() as isize;
        (0..n)
            .filter(|&i| self.at(i + 1) - self.at(i) - self.sigma < w)
            .count()
    }

    fn n(&self) -> usize {
        self.x.len()
    }

    /// Position of rod `i` for any integer `i` (periodic images).
    fn at(&self, i: isize) -> f64 {
        let n = self.n() as isize;
        let k = i.div_euclid(n);
        self.x[i.rem_euclid(n) as usize] + k as f64 * self.length
    }

    fn u(&self, x: f64) -> f64 {
        0.5 * self.u0 * (std::f64::consts::TAU * x).cos()
    }

    /// Boltzmann weight of a pair at gap `g` (0 on overlap).
    fn pair_weight(&self, g: f64) -> f64 {
        if g < 0.0 {
            0.0
        } else if g < self.eps {
            1.0 + self.gamma * 4.0 * (self.eps - g).powi(3) / self.eps.powi(4)
        } else {
            1.0
        }
    }

    fn bound(&self, left: isize) -> bool {
        self.at(left + 1) - self.at(left) - self.sigma < self.eps
    }

    fn single(&mut self, step: f64) {
        let n = self.n() as isize;
        let i = self.rng.random_range(0..n as i64) as isize;
        let d = step * (2.0 * self.rng.random::<f64>() - 1.0);
        let (l, r, xi) = (self.at(i - 1), self.at(i + 1), self.at(i));
        let new = xi + d;
        let before = self.pair_weight(xi - l - self.sigma) * self.pair_weight(r - xi - self.sigma);
        let after = self.pair_weight(new - l - self.sigma) * self.pair_weight(r - new - self.sigma);
        if after == 0.0 {
            return;
        }
        let ratio = after / before * (-(self.u(new) - self.u(xi))).exp();
        if ratio >= 1.0 || self.rng.random::<f64>() < ratio {
            self.x[i as usize] = new;
        }
    }

    /// Rigid move of the bound chain through a random rod.
    fn chain(&mut self, step: f64) {
        let n = self.n() as isize;
        let i = self.rng.random_range(0..n as i64) as isize;
        let (mut a, mut b) = (i, i);
        while a > i - n + 1 && self.bound(a - 1) {
            a -= 1;
        }
        while b < a + n - 1 && self.bound(b) {
            b += 1;
        }
        if b - a + 1 >= n {
            return; // one chain round the ring
        }
        let d = step * (2.0 * self.rng.random::<f64>() - 1.0);
        let gl = self.at(a) + d - self.at(a - 1) - self.sigma;
        let gr = self.at(b + 1) - self.at(b) - d - self.sigma;
        // Stay a chain of the same members: no overlap and no new bond at either end.
        if gl < self.eps || gr < self.eps {
            return;
        }
        let du: f64 = (a..=b)
            .map(|k| self.u(self.at(k) + d) - self.u(self.at(k)))
            .sum();
        if du <= 0.0 || self.rng.random::<f64>() < (-du).exp() {
            for k in a..=b {
                let j = k.rem_euclid(n) as usize;
                self.x[j] += d;
            }
        }
    }
}
