//! The two integrators of free-draining Brownian dynamics against exact results: the stationary
//! variance in a harmonic trap and the variance of free displacements.

use colloidsim_md::init::random_in_box;
use colloidsim_md::{BdParams, Brownian, External, Integrator, NoPair, Particles, SimBox};
use std::f64::consts::PI;

/// A harmonic trap `U = k |x|^2 / 2` about the origin.
struct Trap {
    k: f64,
}

impl External for Trap {
    fn force(&self, p: [f64; 3], _: f64) -> [f64; 3] {
        p.map(|x| -self.k * x)
    }
    fn energy(&self, p: [f64; 3], _: f64) -> f64 {
        0.5 * self.k * (p[0] * p[0] + p[1] * p[1] + p[2] * p[2])
    }
}

/// `n` ideal particles (friction 1: diameter 1, viscosity 1/(3 pi); kT = 1) in `field`.
fn ideal<E: External>(n: usize, field: E, dt: f64, integrator: Integrator) -> Brownian<NoPair, E> {
    let sbox = SimBox::cube(40.0);
    let start = SimBox::cube(4.0);
    let pos = random_in_box(n, 0.0, &start, 5, 0).unwrap();
    let mut params = BdParams::new(dt, 17);
    params.viscosity = 1.0 / (3.0 * PI);
    params.max_drift = 1e3;
    params.integrator = integrator;
    Brownian::new(
        Particles::monodisperse(pos, 1.0),
        sbox,
        NoPair,
        field,
        params,
        0,
    )
    .unwrap()
}

/// In a harmonic trap with `a = mu k dt`, Euler's stationary variance per axis is
/// `kT / k / (1 - a / 2)` and Leimkuhler–Matthews' is exactly `kT / k` at any `a < 2`
/// (`x_{n+1} = c x_n + s (xi_n + xi_{n+1}) / 2`, `c = 1 - a`, `s^2 = 2 kT dt / gamma`: with
/// `y_n = x_n - s xi_n / 2`, `y_{n+1} = c y_n + (1 + c) s xi_n / 2`, so `var x = var y + s^2/4
/// = s^2 / (2 (1 - c))`). At a = 0.5 Euler is 33 % high. 20000 particles x 3 axes x 300
/// steps (correlation time 1/a steps): relative statistical error about 1e-3; tolerance 5 sigma.
#[test]
fn the_stationary_variance_in_a_harmonic_trap_is_exact_with_lm() {
    let (n, k, a) = (20000, 1.0, 0.5);
    let dt = a / k;
    for (integrator, exact) in [
        (Integrator::Euler, 1.0 / k / (1.0 - 0.5 * a)),
        (Integrator::Lm, 1.0 / k),
    ] {
        let mut sim = ideal(n, Trap { k }, dt, integrator);
        sim.run(40).unwrap(); // relaxed to 0.5^40
        let (mut sum, mut samples) = (0.0, 0.0);
        for _ in 0..300 {
            sim.run(1).unwrap();
            let p = sim.snapshot();
            sum += p.pos.iter().flatten().map(|x| x * x).sum::<f64>();
            samples += 3.0 * n as f64;
        }
        let var = sum / samples;
        // Successive samples are correlated with c = 1 - a (c^2 for x^2): effective samples
        // samples (1 - c^2) / (1 + c^2); var of x^2 is 2 var^2.
        let c2 = (1.0 - a) * (1.0 - a);
        let sigma = exact * (2.0 * (1.0 + c2) / (1.0 - c2) / samples).sqrt();
        eprintln!("{integrator:?}: var {var:.5}, exact {exact:.5} +- {sigma:.1e}");
        assert!(
            (var - exact).abs() < 5.0 * sigma,
            "{integrator:?}: var {var} against {exact} +- {sigma}"
        );
    }
}

/// Free displacements over `m` steps: variance `2 D dt m` per axis with Euler, `2 D dt (m -
/// 1/2)` with Leimkuhler–Matthews (the noise of a step is `(xi_n + xi_{n+1}) / 2`). 20000
/// particles x 3 axes; tolerance 5 sigma (relative 5 sqrt(2 / 60000) = 2.9 %, the two differ
/// by 12.5 % at m = 4).
#[test]
fn free_displacements_have_the_variance_of_each_scheme() {
    use colloidsim_md::NoExternal;
    let (n, dt, m) = (20000, 0.01, 4u64);
    for (integrator, steps) in [
        (Integrator::Euler, m as f64),
        (Integrator::Lm, m as f64 - 0.5),
    ] {
        let mut sim = ideal(n, NoExternal, dt, integrator);
        sim.run(3).unwrap();
        let unwrap = |s: &Brownian<NoPair, NoExternal>| {
            let p = s.snapshot();
            p.pos
                .iter()
                .zip(&p.image)
                .map(|(x, i)| s.sbox.unwrap(*x, *i))
                .collect::<Vec<_>>()
        };
        let start = unwrap(&sim);
        sim.run(m).unwrap();
        let end = unwrap(&sim);
        let var = start
            .iter()
            .zip(&end)
            .map(|(a, b)| (0..3).map(|k| (b[k] - a[k]).powi(2)).sum::<f64>())
            .sum::<f64>()
            / (3.0 * n as f64);
        let exact = 2.0 * dt * steps; // D = kT / gamma = 1
        let sigma = exact * (2.0 / (3.0 * n as f64)).sqrt();
        eprintln!("{integrator:?}: var {var:.5}, exact {exact:.5} +- {sigma:.1e}");
        assert!(
            (var - exact).abs() < 5.0 * sigma,
            "{integrator:?}: var {var} against {exact} +- {sigma}"
        );
    }
}
