//! Metropolis Monte Carlo of sticky rods on a ring in `U = (U0 / 2) cos(2 pi x)`: the density
//! profile without a time step, as an independent check of BCD and of the exact theory for
//! strongly sticky dense rods (hard-rods paper Fig. 6). The pair weight is the finite-range
//! Baxter well that BCD simulates (hard-rods paper Eq. 33 ff.):
//! `exp(-V(r)/kT) = 1 + gamma (p + 1) (eps - g)^p / eps^(p + 1)` for a gap `g = r - sigma` in
//! `[0, eps)`, 1 beyond, 0 on overlap (p = 3).
//!
//! Moves: one rod displaced, and a whole bound chain (consecutive rods with gaps below eps)
//! displaced rigidly, rejected if the chain would gain or lose a member (so that the reverse
//! move picks the same chain: detailed balance); the chain move lets chains cross the wells,
//! which single-rod moves at 6.7 kT per bond (gamma = 10) hardly do.
//!
//! `cargo run --release -p colloidsim-bcd --example sticky_profile_mc -- N L U0 SIGMA GAMMA EPS SWEEPS SEED BINS [FINAL]`
//! prints `x,rho,err` on BINS (default 50) bins over one period (errors from 20 blocks), after
//! SWEEPS / 4 sweeps of equilibration (a sweep: N single-rod moves and N / 4 + 1 chain moves).
//! `scripts/sticky_profiles_mc.py` runs it for the panels of Fig. 6. With FINAL, the last
//! configuration is written there as a CSV column `x` (a BCD scenario's `initial.file`).

use rand::{RngExt, SeedableRng, rngs::StdRng};

struct Ring {
    x: Vec<f64>,
    length: f64,
    sigma: f64,
    gamma: f64,
    eps: f64,
    u0: f64,
}

impl Ring {
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

    fn single(&mut self, rng: &mut StdRng, step: f64) {
        let n = self.n() as isize;
        let i = rng.random_range(0..n as i64) as isize;
        let d = step * (2.0 * rng.random::<f64>() - 1.0);
        let (l, r, xi) = (self.at(i - 1), self.at(i + 1), self.at(i));
        let new = xi + d;
        let before = self.pair_weight(xi - l - self.sigma) * self.pair_weight(r - xi - self.sigma);
        let after = self.pair_weight(new - l - self.sigma) * self.pair_weight(r - new - self.sigma);
        if after == 0.0 {
            return;
        }
        let ratio = after / before * (-(self.u(new) - self.u(xi))).exp();
        if ratio >= 1.0 || rng.random::<f64>() < ratio {
            self.x[i as usize] = new;
        }
    }

    /// Rigid move of the bound chain through a random rod.
    fn chain(&mut self, rng: &mut StdRng, step: f64) {
        let n = self.n() as isize;
        let i = rng.random_range(0..n as i64) as isize;
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
        let d = step * (2.0 * rng.random::<f64>() - 1.0);
        let gl = self.at(a) + d - self.at(a - 1) - self.sigma;
        let gr = self.at(b + 1) - self.at(b) - d - self.sigma;
        // Stay a chain of the same members: no overlap and no new bond at either end.
        if gl < self.eps || gr < self.eps {
            return;
        }
        let du: f64 = (a..=b)
            .map(|k| self.u(self.at(k) + d) - self.u(self.at(k)))
            .sum();
        if du <= 0.0 || rng.random::<f64>() < (-du).exp() {
            for k in a..=b {
                let j = k.rem_euclid(n) as usize;
                self.x[j] += d;
            }
        }
    }

    fn sweep(&mut self, rng: &mut StdRng) {
        for _ in 0..self.n() {
            self.single(rng, 0.1);
        }
        for _ in 0..self.n() / 4 + 1 {
            self.chain(rng, 0.3);
        }
    }
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: f64| a.get(i).map_or(d, |s| s.parse().unwrap());
    let n = arg(1, 80.0) as usize;
    let length = arg(2, 100.0);
    let u0 = arg(3, 6.0);
    let sigma = arg(4, 0.8);
    let gamma = arg(5, 10.0);
    let eps = arg(6, 0.05);
    let sweeps = arg(7, 1e6) as u64;
    let seed = arg(8, 1.0) as u64;
    let bins = arg(9, 50.0) as usize;
    let mut rng = StdRng::seed_from_u64(seed);
    let mut ring = Ring {
        x: (0..n)
            .map(|i| (i as f64 + 0.5) * length / n as f64)
            .collect(),
        length,
        sigma,
        gamma,
        eps,
        u0,
    };
    for _ in 0..sweeps / 4 {
        ring.sweep(&mut rng);
    }
    let blocks = 20u64;
    let per_block = sweeps / blocks;
    let mut profiles = vec![vec![0.0; bins]; blocks as usize];
    for p in profiles.iter_mut() {
        for _ in 0..per_block {
            ring.sweep(&mut rng);
            for &x in &ring.x {
                let b = ((x.rem_euclid(1.0)) * bins as f64) as usize;
                p[b.min(bins - 1)] += 1.0;
            }
        }
        let norm = per_block as f64 * length / bins as f64;
        p.iter_mut().for_each(|v| *v /= norm);
    }
    if let Some(path) = a.get(10) {
        let mut text = String::from("x\n");
        for x in &ring.x {
            text.push_str(&format!("{}\n", x.rem_euclid(length)));
        }
        std::fs::write(path, text).expect("final configuration");
    }
    println!("x,rho,err");
    for b in 0..bins {
        let v: Vec<f64> = profiles.iter().map(|p| p[b]).collect();
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
        println!(
            "{},{m},{}",
            (b as f64 + 0.5) / bins as f64,
            (var / v.len() as f64).sqrt()
        );
    }
}
