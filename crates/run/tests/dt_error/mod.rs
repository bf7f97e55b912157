//! The time-step error of free-draining BD in a static droplet: the fractions of particles in
//! the contact layer at the interface, sampled in equilibrium (shared by the test
//! `tests/droplet_dt_error.rs` and the sweep `examples/droplet_dt_errors.rs`).

use colloidsim_md::brownian::droplet::DropletParams;
use colloidsim_md::{Brownian, Integrator};
use colloidsim_particles::{LennardJones, Pair};

/// A static droplet (`drying.peclet = 0`) of radius `r0` (in d) at mean volume fraction `phi`,
/// d = kT = 1, eta = 1 (D0 = 1 / (3 pi)), the default interface (k = 50 kT/d^2, range d/2,
/// wall at R - d/2), lasting `duration` (time units).
pub fn static_droplet(r0: f64, phi: f64, duration: f64) -> DropletParams {
    let n = (8.0 * phi * r0.powi(3)).round() as usize;
    let text = format!(
        "method = \"droplet-bd\"\n[system]\nparticles = {n}\nradius = {r0}\n\
         [drying]\npeclet = 0\nduration = {duration}\n[observe.profile]\nfractions = [0.0]\n"
    );
    droplet_params(&text)
}

/// Radii beyond which the layer fractions are counted: `R + offset - d/4` (the contact peak),
/// `R + offset - d` (the first layer) and `R + offset` (centres inside the soft interface).
pub fn cuts(p: &DropletParams) -> [f64; 3] {
    let edge = p.r0 + p.offset;
    [edge - 0.25 * p.diameter, edge - p.diameter, edge]
}

/// Observables: the fractions beyond the three [`cuts`], then the mean WCA pair energy per
/// particle (kT), sampled every fifth sample (an O(N^2) sum).
pub const OBSERVABLES: usize = 4;

/// WCA pair energy per particle of `pos` (no periodic images: the droplet lies well inside
/// its box).
pub fn pair_energy(p: &DropletParams, pos: &[[f64; 3]]) -> f64 {
    let wca = LennardJones::wca(p.kt, p.diameter);
    let rc2 = wca.r_cut_max().powi(2);
    let mut u = 0.0;
    for (i, a) in pos.iter().enumerate() {
        for b in &pos[i + 1..] {
            let r2 = (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2);
            if r2 < rc2 {
                u += wca.energy(r2, 0, 0, p.diameter, p.diameter);
            }
        }
    }
    u / (pos.len() as f64 * p.kt)
}

/// Means of the [`OBSERVABLES`] and their standard errors (from block means).
#[derive(Debug, Clone, Copy)]
pub struct Layer {
    pub mean: [f64; OBSERVABLES],
    pub se: [f64; OBSERVABLES],
    /// Blocks the error comes from.
    pub blocks: usize,
}

/// Sample the layer fractions of replicas `replicas` of `p`: each is inserted at random,
/// relaxed for `relax` d^2/D0 with Euler at p.dt, then run with `integrator` at `dt` (in
/// d^2/D0) for 0.5 d^2/D0 and sampled every `every` steps for `time` d^2/D0, in blocks of
/// `block` d^2/D0 (each block mean one sample of the error). A step that would move a
/// particle by more than `max_drift` d stops the run (the engine's guard, 0.2 in a scenario).
#[allow(clippy::too_many_arguments)]
pub fn layer_fractions(
    p: &DropletParams,
    integrator: Integrator,
    dt: f64,
    replicas: std::ops::Range<u32>,
    relax: f64,
    time: f64,
    block: f64,
    every: u64,
    max_drift: f64,
) -> Layer {
    let tau = p.diameter * p.diameter / p.d0;
    let steps = |t: f64| (t * tau / (dt * tau)).round() as u64;
    let c = cuts(p);
    let n = p.particles as f64;
    let mut means: Vec<[f64; OBSERVABLES]> = Vec::new();
    for r in replicas {
        let mut sim = p.build_replica(r).unwrap();
        sim.run((relax * tau / p.dt).round() as u64).unwrap();
        // Continue with `integrator` at `dt`, the blow-up guard at `max_drift` d.
        let mut params = *sim.params();
        params.dt = dt * tau;
        params.integrator = integrator;
        params.max_drift = max_drift;
        let mut sim = Brownian::restart(
            sim.snapshot(),
            sim.sbox,
            sim.pair,
            sim.external,
            params,
            sim.step,
            None,
        )
        .unwrap();
        sim.run(steps(0.5)).unwrap();
        let per_block = (steps(block) / every).max(1);
        for _ in 0..(time / block).round() as usize {
            let mut acc = [0.0; OBSERVABLES];
            let mut energies = 0.0;
            for k in 0..per_block {
                sim.run(every).unwrap();
                for x in &sim.particles().pos {
                    let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
                    for (a, c) in acc.iter_mut().zip(c) {
                        *a += (r > c) as u8 as f64;
                    }
                }
                if k % 5 == 0 {
                    acc[3] += pair_energy(p, &sim.particles().pos);
                    energies += 1.0;
                }
            }
            let mut m = acc.map(|a| a / (n * per_block as f64));
            m[3] = acc[3] / energies;
            means.push(m);
        }
    }
    let b = means.len() as f64;
    let mean = std::array::from_fn(|k| means.iter().map(|m| m[k]).sum::<f64>() / b);
    let se = std::array::from_fn(|k| {
        let var = means.iter().map(|m| (m[k] - mean[k]).powi(2)).sum::<f64>() / (b - 1.0);
        (var / b).sqrt()
    });
    Layer {
        mean,
        se,
        blocks: means.len(),
    }
}

/// A `droplet-bd` scenario read by the run layer (its keys through their declarations).
pub fn droplet_params(text: &str) -> colloidsim_md::DropletParams {
    colloidsim_run::methods::droplet_bd::params::read(
        &toml::from_str(text).unwrap(),
        std::path::Path::new("."),
        None,
    )
    .unwrap()
}
