//! A prototype, not an engine feature: how much of BCD's collision bias comes from resolving
//! collisions inelastically (clusters end the step in contact), measured against a reflecting
//! rule (issue #21, follow-up).
//!
//! BCD pools the free end-of-step reduced positions `z_i = y_i + u_i dt` (`y_i = x_i - i sigma`)
//! of colliding rods at their mean, so colliding pairs end a step exactly in contact: the gap is
//! a random walk stopped at zero, whose stationary law carries a boundary layer of width
//! `0.58 sqrt(4 D dt)` (Siegmund; docs/bcd.md). Reflecting instead of stopping is the
//! symmetrized Euler scheme of reflected diffusions (Bossy, Gobet & Talay, J. Appl. Probab. 41,
//! 877 (2004): weak order 1 instead of 1/2). For hard rods in reduced coordinates a reflection at
//! the face `y_i = y_{i+1}` exchanges the two values, and folding a point back into the ordered
//! set is sorting: the rods take the sorted free end positions (elastic collisions: velocities
//! exchanged). Without forces this is exact at any dt.
//!
//! This example steps a ring of hard rods in `U = (U0/2) cos(2 pi x)` with that rule (a plain
//! sequential stepper: forces rod by rod, the engine's noise keys, Euler or Leimkuhler–Matthews)
//! and prints the density error against the exact theory and the Tonks gas's contact density,
//! beside the engine (pooling) on the same cases and seeds:
//!
//! ```text
//! nice -n 10 cargo run --release -p colloidsim-bcd --example collision_rule -- [SEEDS] [TIME]
//! ```
//!
//! Kept as an example so that the numbers quoted in docs/bcd.md can be reproduced.

use colloidsim_bcd::forces::{CosineForce, ExternalForce, NoField, NoPair};
use colloidsim_bcd::observe::{ContactDensity, DensityProfile};
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Integrator, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};
use colloidsim_core::rng::fill_normal_wide;
use colloidsim_dft::rods::{self, BetaPotential, Domain, RodsProblem};
use rayon::prelude::*;

/// How the reflecting stepper integrates the free motion.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Scheme {
    Euler,
    /// Leimkuhler–Matthews as the engine has it: `y' = fold(y + dt F(y) + sqrt(dt/2) (R_n +
    /// R_{n+1}))`.
    Lm,
    /// Leimkuhler–Matthews in its Markov form (the "BAOAB limit"): the chain
    /// `Y_{n+1} = fold(Y_n + dt F(y_n) + sqrt(2 dt) R_n)` carries full Brownian increments (so
    /// that reflection is exact for free rods), and the configuration sampled and used for the
    /// forces is `y_n = fold(Y_n + sqrt(dt/2) R_n)`. Without collisions it is the same sequence
    /// `y_n` as `Lm`.
    LmMarkov,
}

/// A ring of hard rods stepped with the reflecting rule.
struct Reflecting<F> {
    /// Reduced positions: the sampled configuration (`LmMarkov`: the chain `Y`).
    y: Vec<f64>,
    z: Vec<f64>,
    kept: Vec<f64>,
    xi: Vec<f64>,
    x: Vec<f64>,
    /// `LmMarkov`: the kicked, folded configuration `y_n` and which slot each rod's kicked
    /// point landed in.
    kicked: Vec<(f64, usize)>,
    cfg: BcdConfig,
    force: F,
    scheme: Scheme,
    /// Resolve collisions by pooling (BCD's inelastic rule) instead of reflecting.
    pool: bool,
    step: u64,
}

impl<F: ExternalForce> Reflecting<F> {
    fn new(cfg: BcdConfig, x0: &[f64], force: F, scheme: Scheme, pool: bool) -> Self {
        let lm = scheme != Scheme::Euler;
        let n = x0.len();
        let y = x0
            .iter()
            .enumerate()
            .map(|(i, x)| x - i as f64 * cfg.sigma)
            .collect();
        let mut kept = vec![0.0; if lm { n } else { 0 }];
        fill(&cfg, 0, &mut kept);
        Self {
            y,
            z: vec![0.0; n],
            kept,
            xi: vec![0.0; n],
            x: vec![0.0; n],
            kicked: vec![(0.0, 0); n],
            cfg,
            force,
            scheme,
            pool,
            step: 0,
        }
    }

    /// `LmMarkov`: `y_n = fold(Y_n + sqrt(dt/2) R_n)`, with the slot of each rod's kicked point.
    fn kick(&mut self) {
        let (n, c) = (self.y.len(), &self.cfg);
        let h = (0.5 * c.diffusion() * c.dt).sqrt();
        for i in 0..n {
            self.kicked[i] = (self.y[i] + h * self.kept[i], i);
        }
        let lred = c.length - n as f64 * c.sigma;
        if self.pool {
            let mut v: Vec<f64> = self.kicked.iter().map(|k| k.0).collect();
            pool_fold(&mut v, lred);
            for (k, vi) in self.kicked.iter_mut().zip(v) {
                k.0 = vi;
            }
        } else {
            fold_pairs(&mut self.kicked, lred);
        }
    }

    fn step(&mut self) {
        if self.scheme == Scheme::LmMarkov {
            return self.step_markov();
        }
        let (n, c) = (self.y.len(), &self.cfg);
        let amp = (2.0 * c.diffusion() / c.dt).sqrt();
        let lm = self.scheme == Scheme::Lm;
        if lm {
            fill(c, self.step + 1, &mut self.xi);
        } else {
            fill(c, self.step, &mut self.xi);
        }
        for i in 0..n {
            let f = self.force.force(self.y[i] + i as f64 * c.sigma);
            let noise = if lm {
                let g = 0.5 * amp * (self.kept[i] + self.xi[i]);
                self.kept[i] = self.xi[i];
                g
            } else {
                amp * self.xi[i]
            };
            self.z[i] = self.y[i] + (c.mobility * f + noise) * c.dt;
        }
        self.resolve();
        std::mem::swap(&mut self.y, &mut self.z);
        self.step += 1;
    }

    /// Resolve the collisions of the free end positions `z`.
    fn resolve(&mut self) {
        let lred = self.cfg.length - self.y.len() as f64 * self.cfg.sigma;
        if self.pool {
            pool_fold(&mut self.z, lred);
        } else {
            fold(&mut self.z, lred);
        }
    }

    /// `LmMarkov`: the chain takes the forces at the kicked configuration (each rod the force
    /// of the slot its kicked point landed in) and a full increment `sqrt(2 D dt) R_n`.
    fn step_markov(&mut self) {
        let (n, c) = (self.y.len(), self.cfg.clone());
        if self.step == 0 {
            self.kick();
        }
        let full = (2.0 * c.diffusion() * c.dt).sqrt();
        let mut slot_force = vec![0.0; n];
        for (k, &(yk, _)) in self.kicked.iter().enumerate() {
            slot_force[k] = self.force.force(yk + k as f64 * c.sigma);
        }
        let mut landed = vec![0usize; n];
        for (k, &(_, rod)) in self.kicked.iter().enumerate() {
            landed[rod] = k;
        }
        for i in 0..n {
            self.z[i] = self.y[i] + c.mobility * slot_force[landed[i]] * c.dt + full * self.kept[i];
        }
        self.resolve();
        std::mem::swap(&mut self.y, &mut self.z);
        self.step += 1;
        fill(&c, self.step, &mut self.kept);
        self.kick();
    }

    fn positions(&mut self) -> &[f64] {
        let s = self.cfg.sigma;
        let markov = self.scheme == Scheme::LmMarkov;
        for (i, x) in self.x.iter_mut().enumerate() {
            let y = if markov { self.kicked[i].0 } else { self.y[i] };
            *x = y + i as f64 * s;
        }
        &self.x
    }
}

/// Fold reduced positions back into the ordered ring: insertion sort (the input is nearly
/// sorted), and exchanges across the seam, where rod N - 1 meets rod 0 a reduced period `lred`
/// further on.
fn fold(z: &mut [f64], lred: f64) {
    let n = z.len();
    loop {
        for i in 1..n {
            let mut k = i;
            while k > 0 && z[k - 1] > z[k] {
                z.swap(k - 1, k);
                k -= 1;
            }
        }
        if n > 1 && z[n - 1] > z[0] + lred {
            let (a, b) = (z[0], z[n - 1]);
            z[0] = b - lred;
            z[n - 1] = a + lred;
        } else {
            break;
        }
    }
}

/// BCD's rule on the ring (for the prototype's own pooled variants): pool adjacent violators of
/// `z` at their mean (ties pool), also across the seam, where the first block meets the last
/// one a reduced period `lred` further on.
fn pool_fold(z: &mut [f64], lred: f64) {
    let n = z.len();
    // Blocks [sum, rods, first rod]; rods of a block wrapped across the seam carry + lred.
    let mut blocks: Vec<(f64, usize, usize)> = Vec::new();
    let meet =
        |a: &(f64, usize, usize), b: &(f64, usize, usize)| a.0 / a.1 as f64 >= b.0 / b.1 as f64;
    for (i, &v) in z.iter().enumerate() {
        blocks.push((v, 1, i));
        while blocks.len() >= 2 && meet(&blocks[blocks.len() - 2], &blocks[blocks.len() - 1]) {
            let b = blocks.pop().expect("two blocks");
            let a = blocks.last_mut().expect("two blocks");
            a.0 += b.0;
            a.1 += b.1;
        }
    }
    // The seam: the last block meets the first one shifted by lred.
    let mut head = 0;
    while blocks.len() - head >= 2 {
        let first = blocks[head];
        let shifted = (first.0 + first.1 as f64 * lred, first.1, first.2);
        let last = blocks.len() - 1;
        if !meet(&blocks[last], &shifted) {
            break;
        }
        blocks[last].0 += shifted.0;
        blocks[last].1 += shifted.1;
        head += 1;
        while blocks.len() - head >= 2 {
            let l = blocks.len() - 1;
            if meet(&blocks[l - 1], &blocks[l]) {
                let b = blocks.pop().expect("two blocks");
                blocks[l - 1].0 += b.0;
                blocks[l - 1].1 += b.1;
            } else {
                break;
            }
        }
    }
    for b in &blocks[head..] {
        let mean = b.0 / b.1 as f64;
        for k in 0..b.1 {
            let w = b.2 + k;
            if w < n {
                z[w] = mean;
            } else {
                z[w - n] = mean - lred;
            }
        }
    }
}

/// [`fold`] of `(value, rod)` pairs, carrying the rods along.
fn fold_pairs(z: &mut [(f64, usize)], lred: f64) {
    let n = z.len();
    loop {
        for i in 1..n {
            let mut k = i;
            while k > 0 && z[k - 1].0 > z[k].0 {
                z.swap(k - 1, k);
                k -= 1;
            }
        }
        if n > 1 && z[n - 1].0 > z[0].0 + lred {
            let (a, b) = (z[0], z[n - 1]);
            z[0] = (b.0 - lred, b.1);
            z[n - 1] = (a.0 + lred, a.1);
        } else {
            break;
        }
    }
}

/// Who steps the rods.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Rule {
    /// The BCD engine (pooling).
    Engine,
    /// This example's stepper with BCD's pooling rule.
    Pool,
    /// This example's stepper with the reflecting rule.
    Reflect,
}

/// The engine's deviates of `step` for all rods (segments of 256 rods).
fn fill(cfg: &BcdConfig, step: u64, out: &mut [f64]) {
    for (seg, o) in out.chunks_mut(256).enumerate() {
        fill_normal_wide(cfg.seed, step, seg as u64, o);
    }
}

/// Density and contact densities of one seed, with either rule.
fn run(
    (n, sigma, u0): (usize, f64, f64),
    dt: f64,
    scheme: Scheme,
    rule: Rule,
    seed: u32,
    time: f64,
    windows: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let length = 100.0;
    let cfg = BcdConfig {
        length,
        sigma,
        mobility: 1.0,
        kt: 1.0,
        dt,
        boundary: Boundary::Periodic,
        seed,
        update: Update::Premerge,
    };
    let x0 = init::random(&cfg, n, seed).expect("initial configuration");
    let field = ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: u0.max(1e-300),
            wavelength: 1.0,
        }],
        drive: 0.0,
    };
    let cosine = CosineForce::from_field(&field).expect("cosine");
    let bins = 50;
    let mut d = DensityProfile::new(bins, 1.0, length);
    let mut c: Vec<ContactDensity> = windows
        .iter()
        .map(|&w| ContactDensity::new(1, w, 1.0, sigma, length, Boundary::Periodic))
        .collect();
    let relax = (20.0 / dt).round() as u64;
    let steps = (time / dt).round() as u64;
    let every = ((1e-3 / dt).round() as u64).max(1);
    let mut sample = |x: &[f64], k: u64| {
        if k >= relax && k.is_multiple_of(every) {
            d.sample(x);
            for ci in &mut c {
                ci.sample(x);
            }
        }
    };
    if rule != Rule::Engine {
        let mut r = Reflecting::new(cfg, &x0, cosine, scheme, rule == Rule::Pool);
        for k in 0..relax + steps {
            r.step();
            sample(r.positions(), k);
        }
    } else if u0 > 0.0 {
        let integrator = if scheme == Scheme::Euler {
            Integrator::Euler
        } else {
            Integrator::Lm
        };
        let mut b = Bcd::new(cfg, x0, cosine, NoPair)
            .expect("engine")
            .with_integrator(integrator);
        for k in 0..relax + steps {
            b.step().expect("step");
            sample(b.positions(), k);
        }
    } else {
        let integrator = if scheme == Scheme::Euler {
            Integrator::Euler
        } else {
            Integrator::Lm
        };
        let mut b = Bcd::new(cfg, x0, NoField, NoPair)
            .expect("engine")
            .with_integrator(integrator);
        for k in 0..relax + steps {
            b.step().expect("step");
            sample(b.positions(), k);
        }
    }
    (
        d.profile().1,
        c.iter().map(|ci| ci.profile().1[0]).collect(),
    )
}

fn mean_and_error(v: &[f64]) -> (f64, f64) {
    let k = v.len() as f64;
    let m = v.iter().sum::<f64>() / k;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k - 1.0);
    (m, (var / k).sqrt())
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let seeds: u32 = a.get(1).map_or(8, |s| s.parse().expect("SEEDS"));
    let time: f64 = a.get(2).map_or(200.0, |s| s.parse().expect("TIME"));
    let rules = [
        ("engine (pool)", Scheme::Euler, Rule::Engine),
        ("engine (pool)", Scheme::Lm, Rule::Engine),
        ("pool", Scheme::Euler, Rule::Pool),
        ("pool", Scheme::LmMarkov, Rule::Pool),
        ("reflect", Scheme::Euler, Rule::Reflect),
        ("reflect", Scheme::Lm, Rule::Reflect),
        ("reflect", Scheme::LmMarkov, Rule::Reflect),
    ];
    let scheme = |s: Scheme| format!("{s:?}");

    // Tonks gas (sigma = rho = 0.5): contact density in windows w against rho (1 - e^{-a w}) / w.
    let windows = [1e-1, 1e-2, 1e-3];
    let (rho, sigma) = (0.5, 0.5);
    let a_rate = rho / (1.0 - rho * sigma);
    println!("Tonks gas, sigma = rho = 0.5: relative error of the contact density in a window w");
    println!("| rule | scheme | dt | w = 0.1 | w = 0.01 | w = 0.001 |");
    println!("|---|---|---|---|---|---|");
    for dt in [1e-2, 1e-3, 1e-4] {
        for &(name, sch, rule) in &rules {
            let runs: Vec<_> = (1..=seeds)
                .into_par_iter()
                .map(|s| run((50, sigma, 0.0), dt, sch, rule, s, time, &windows))
                .collect();
            print!("| {name} | {} | {dt:e} |", scheme(sch));
            for (k, &w) in windows.iter().enumerate() {
                let exact = rho * (1.0 - (-a_rate * w).exp()) / w;
                let (m, e) = mean_and_error(&runs.iter().map(|r| r.1[k]).collect::<Vec<_>>());
                print!(" {:+.3} ± {:.3} |", m / exact - 1.0, e / exact);
            }
            println!();
        }
    }

    // The density in the cosine potential (U0 = 6 kT) against the exact theory.
    println!();
    println!("cosine U0 = 6 kT, L = 100: density L1 error and peak error against the exact theory");
    println!("| case | rule | scheme | dt | L1 | peak |");
    println!("|---|---|---|---|---|---|");
    for (sigma, rho) in [(0.5, 0.5), (0.2, 0.8), (0.8, 0.8)] {
        let p = RodsProblem::new(sigma, rho, Domain::Periodic { period: 1.0 })
            .with_dx(1e-3_f64.min(sigma / 50.0))
            .with_potential(BetaPotential::from_fn(1.0, |x| {
                3.0 * (std::f64::consts::TAU * x).cos()
            }));
        let exact = rods::equilibrium(&p)
            .expect("theory")
            .bin_average(50, 1.0)
            .expect("bins")
            .rho;
        let top = (0..50)
            .max_by(|&i, &j| exact[i].total_cmp(&exact[j]))
            .expect("bins");
        let norm: f64 = exact.iter().sum();
        for dt in [1e-3, 1e-4] {
            for &(name, sch, rule) in &rules {
                let n = (100.0 * rho) as usize;
                let runs: Vec<_> = (1..=seeds)
                    .into_par_iter()
                    .map(|s| run((n, sigma, 6.0), dt, sch, rule, s, time, &[]))
                    .collect();
                let col =
                    |i: usize| mean_and_error(&runs.iter().map(|r| r.0[i]).collect::<Vec<_>>());
                let l1: f64 = (0..50).map(|i| (col(i).0 - exact[i]).abs()).sum::<f64>() / norm;
                let floor: f64 = (0..50).map(|i| col(i).1).sum::<f64>() / norm * 0.798;
                let (pk, pe) = col(top);
                println!(
                    "| sigma {sigma} rho {rho} | {name} | {} | {dt:e} | {l1:.2e} (floor {floor:.1e}) | {:+.2e} ± {:.1e} |",
                    scheme(sch),
                    pk / exact[top] - 1.0,
                    pe / exact[top]
                );
            }
        }
    }
}
