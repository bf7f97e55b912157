//! Benchmark cases of `colloidsim bench rpy`: the direct product at a few thousand particles
//! (beside pystokes, run by the CLI as a Python subprocess with [`PYSTOKES_SCRIPT`]) and PSE
//! per product and per Brownian displacement from 10^3 to 10^5 particles.
//!
//! Spheres of radius 0.5 (diameter 1), viscosity 1, uniformly random positions in a cube at
//! volume fraction `phi` (overlaps allowed: the mobility does not care), random forces.

use crate::{DirectRpy, HydroError, LanczosParams, Mobility, NoiseKey, Pse, PseParams, PseTimes};
use colloidsim_core::rng::{Purpose, stream};
use rand::{Rng, RngExt};
use std::f64::consts::PI;
use std::time::Instant;

/// Sphere radius of the benchmark systems.
pub const RADIUS: f64 = 0.5;

/// Edge of the cube holding `n` spheres of radius [`RADIUS`] at volume fraction `phi`.
pub fn box_edge(n: usize, phi: f64) -> f64 {
    (n as f64 * 4.0 / 3.0 * PI * RADIUS.powi(3) / phi).cbrt()
}

/// `n` uniformly random positions in the cube of edge `l` centred on the origin, and `n`
/// forces with components uniform in [−1, 1) (stream `seed`, `Purpose::Initial`).
pub fn random_system(n: usize, l: f64, seed: u32) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let mut rng = stream(seed, 0, Purpose::Initial, 0);
    let u = |rng: &mut dyn Rng| rng.random::<f64>();
    let pos = (0..n)
        .map(|_| [0; 3].map(|_| (u(&mut rng) - 0.5) * l))
        .collect();
    let f = (0..n)
        .map(|_| [0; 3].map(|_| 2.0 * u(&mut rng) - 1.0))
        .collect();
    (pos, f)
}

/// Run `f` on a pool of `threads` workers.
pub fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
        .install(f)
}

/// Median of `v` (sorted in place).
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// Median time of the direct product.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct DirectTiming {
    /// Particles.
    pub n: usize,
    /// Worker threads.
    pub threads: usize,
    /// Median seconds per product `M F`.
    pub seconds: f64,
    /// Fastest product (the least disturbed by other load on the machine).
    pub min_seconds: f64,
    /// Nanoseconds per pair tensor (N^2 per product).
    pub ns_per_pair: f64,
}

/// Time the direct product of the benchmark system (`phi = 0.1`) with `threads` workers,
/// `repeats` times after one warm-up product. Returns the timing and the velocities.
pub fn time_direct(
    pos: &[[f64; 3]],
    f: &[[f64; 3]],
    threads: usize,
    repeats: usize,
) -> (DirectTiming, Vec<[f64; 3]>) {
    let n = pos.len();
    with_threads(threads, || {
        let mut m = DirectRpy::new(n, RADIUS, 1.0, LanczosParams::default(), usize::MAX)
            .expect("benchmark system");
        m.set_positions(pos).expect("finite positions");
        let mut u = vec![[0.0; 3]; n];
        m.apply(f, &mut u);
        let mut t: Vec<f64> = (0..repeats.max(1))
            .map(|_| {
                let s = Instant::now();
                m.apply(f, &mut u);
                s.elapsed().as_secs_f64()
            })
            .collect();
        let seconds = median(&mut t);
        (
            DirectTiming {
                n,
                threads,
                seconds,
                min_seconds: t[0],
                ns_per_pair: seconds * 1e9 / (n as f64 * n as f64),
            },
            u,
        )
    })
}

/// Median times of PSE on one system.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PseTiming {
    /// Particles.
    pub n: usize,
    /// Worker threads.
    pub threads: usize,
    /// Box edge.
    pub box_length: f64,
    /// Grid and cut-offs.
    pub geometry: crate::PseGeometry,
    /// Real-space neighbours per particle.
    pub neighbours: f64,
    /// Median seconds per product `M F` (positions fixed).
    pub product: f64,
    /// Median seconds per Brownian-dynamics displacement: new positions (lists, tensors,
    /// weights) plus `dt M F + sqrt(2 kT dt) M^(1/2) z`.
    pub step: f64,
    /// Time shares of the parts of a step, summed over the repeats.
    pub times: PseTimes,
    /// Sum of the repeats' step times (the denominator of the shares).
    pub step_total: f64,
    /// Memory held by the operator per particle (bytes).
    pub bytes_per_particle: f64,
}

/// Time PSE (paper parameters: `xi = 0.5 / a`, tolerance `tol`) on `n` spheres at volume
/// fraction `phi`: `repeats` products and `repeats` displacements after one warm-up each.
pub fn time_pse(
    n: usize,
    phi: f64,
    tol: f64,
    threads: usize,
    repeats: usize,
) -> Result<PseTiming, HydroError> {
    time_pse_radii(n, phi, tol, threads, repeats, 1.0, 0.0)
}

/// The radii of the bidisperse benchmark: a number fraction `large` of the particles, spread
/// evenly through the list, `ratio` times [`RADIUS`], the rest [`RADIUS`] (`large = 0.5`: every
/// other particle; `ratio = 1`: all [`RADIUS`]).
pub fn bidisperse_radii(n: usize, ratio: f64, large: f64) -> Vec<f64> {
    let count = |i: usize| (i as f64 * large).floor();
    (0..n)
        .map(|i| {
            if count(i + 1) > count(i) {
                ratio * RADIUS
            } else {
                RADIUS
            }
        })
        .collect()
}

/// [`time_pse`] with a number fraction `large` of the spheres `ratio` times larger
/// ([`bidisperse_radii`], [`Pse::with_radii`]) in the same box (the monodisperse system's at `phi`), with the same
/// splitting `0.5 / RADIUS` and tolerance; `ratio = 1` is [`time_pse`] ([`Pse::new`]).
pub fn time_pse_radii(
    n: usize,
    phi: f64,
    tol: f64,
    threads: usize,
    repeats: usize,
    ratio: f64,
    large: f64,
) -> Result<PseTiming, HydroError> {
    let l = box_edge(n, phi);
    let (pos, f) = random_system(n, l, 1);
    with_threads(threads, || {
        let mut p = PseParams::paper(RADIUS, 1.0, l);
        p.tolerance = tol;
        let mut m = if ratio == 1.0 {
            Pse::new(n, p)?
        } else {
            Pse::with_radii(&bidisperse_radii(n, ratio, large), p)?
        };
        m.set_positions(&pos)?;
        let mut u = vec![[0.0; 3]; n];
        m.apply(&f, &mut u);
        let mut tp: Vec<f64> = (0..repeats.max(1))
            .map(|_| {
                let s = Instant::now();
                m.apply(&f, &mut u);
                s.elapsed().as_secs_f64()
            })
            .collect();
        // Steps: positions drift a little between steps (as in Brownian dynamics).
        let mut x = pos.clone();
        let mut ts = Vec::new();
        let mut step_total = 0.0;
        for s in 0..=repeats.max(1) {
            if s == 1 {
                m.reset_times();
                step_total = 0.0;
            }
            for (xi, ui) in x.iter_mut().zip(&u) {
                for k in 0..3 {
                    xi[k] += 1e-3 * ui[k].signum();
                }
            }
            let t = Instant::now();
            m.set_positions(&x)?;
            let key = NoiseKey {
                seed: 1,
                step: s as u64,
                key0: 0,
            };
            m.displacement(&f, 1e-4, 1.0, key, &mut u)?;
            let e = t.elapsed().as_secs_f64();
            if s > 0 {
                ts.push(e);
                step_total += e;
            }
        }
        Ok(PseTiming {
            n,
            threads,
            box_length: l,
            geometry: *m.geometry(),
            neighbours: m.pairs() as f64 / n as f64,
            product: median(&mut tp),
            step: median(&mut ts),
            times: *m.times(),
            step_total,
            bytes_per_particle: m.bytes() as f64 / n as f64,
        })
    })
}

/// Python program timing pystokes' RPY products: `pystokes.unbounded.Rbm.mobilityTT` (an
/// unbounded fluid) or, for a case with `"box"`, `pystokes.periodic.Rbm.mobilityTT` (Ewald sum
/// in a periodic cube, `"nb"` real-space boxes and `"nm"` Fourier modes). Reads one JSON
/// document on standard input, `{"radius", "viscosity", "repeats", "cases": [{"n", "pos",
/// "force", "box"?, "nb"?, "nm"?, "repeats"?}]}` (positions and forces as flat
/// `[x0, y0, z0, x1, ...]`), writes `{"version", "cases": [{"n", "median_s", "min_s",
/// "velocity"}]}` (velocities in the same layout), or `{"error": message}` when pystokes
/// cannot be imported.
pub const PYSTOKES_SCRIPT: &str = r#"
import json, sys, time
try:
    import numpy as np
    import pystokes
except Exception as e:
    print(json.dumps({"error": "cannot import pystokes: %s" % e}))
    sys.exit(0)
req = json.load(sys.stdin)
out = []
for case in req["cases"]:
    n = case["n"]
    # pystokes stores all x, then all y, then all z.
    r = np.ascontiguousarray(np.array(case["pos"], dtype=np.float64).reshape(n, 3).T.ravel())
    f = np.ascontiguousarray(np.array(case["force"], dtype=np.float64).reshape(n, 3).T.ravel())
    if "box" in case:
        rbm = pystokes.periodic.Rbm(radius=req["radius"], particles=n,
                                    viscosity=req["viscosity"], boxSize=case["box"])
        product = lambda v: rbm.mobilityTT(v, r, f, case["nb"], case["nm"])
    else:
        rbm = pystokes.unbounded.Rbm(radius=req["radius"], particles=n,
                                     viscosity=req["viscosity"])
        product = lambda v: rbm.mobilityTT(v, r, f)
    v = np.zeros(3 * n)
    repeats = case.get("repeats", req["repeats"])
    if repeats > 1:
        product(v)
    times = []
    for _ in range(repeats):
        v[:] = 0.0
        t = time.perf_counter()
        product(v)
        times.append(time.perf_counter() - t)
    times.sort()
    m = len(times) // 2
    med = times[m] if len(times) % 2 else 0.5 * (times[m - 1] + times[m])
    out.append({"n": n, "median_s": med, "min_s": times[0],
                "velocity": v.reshape(3, n).T.ravel().tolist()})
version = getattr(pystokes, "__version__", "unknown")
print(json.dumps({"version": version, "cases": out}))
"#;

/// The PSE product `M F` (splitting `xi = 0.5 / a`, the given tolerance) of spheres of radius
/// [`RADIUS`] in a periodic cube of edge `l`, viscosity 1, and the seconds it took (after one
/// warm-up product).
pub fn pse_product(
    pos: &[[f64; 3]],
    f: &[[f64; 3]],
    l: f64,
    tolerance: f64,
) -> Result<(Vec<[f64; 3]>, f64), HydroError> {
    let mut p = PseParams::paper(RADIUS, 1.0, l);
    p.tolerance = tolerance;
    let mut m = Pse::new(pos.len(), p)?;
    m.set_positions(pos)?;
    let mut u = vec![[0.0; 3]; pos.len()];
    m.apply(f, &mut u);
    let s = Instant::now();
    m.apply(f, &mut u);
    Ok((u, s.elapsed().as_secs_f64()))
}

/// `|u − v| / |v|` over all components.
pub fn relative_difference(u: &[f64], v: &[f64]) -> f64 {
    let (mut d2, mut w2) = (0.0, 0.0);
    for (x, y) in u.iter().zip(v) {
        d2 += (x - y) * (x - y);
        w2 += y * y;
    }
    (d2 / w2).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn benchmark_systems_have_the_requested_density_and_run() {
        let l = box_edge(1000, 0.1);
        assert!((1000.0 * PI / 6.0 / l.powi(3) - 0.1).abs() < 1e-12);
        let (pos, f) = random_system(50, 5.0, 3);
        assert!(pos.iter().flatten().all(|x| x.abs() <= 2.5));
        assert!(f.iter().flatten().all(|x| x.abs() <= 1.0));
        let (t, u) = time_direct(&pos, &f, 1, 1);
        assert_eq!(t.n, 50);
        assert!(t.seconds > 0.0 && u.iter().flatten().all(|x| x.is_finite()));
        let p = time_pse(200, 0.1, 1e-2, 1, 1).unwrap();
        assert!(p.step > 0.0 && p.product > 0.0 && p.bytes_per_particle > 0.0);
        assert!(p.times.fft > 0.0 && p.times.fft < p.step_total);
        let b = time_pse_radii(200, 0.1, 1e-2, 1, 1, 2.0, 0.5).unwrap();
        assert!(b.step > 0.0 && b.geometry.grid == p.geometry.grid);
        assert_eq!(median(&mut [3.0, 1.0, 2.0, 10.0]), 2.5);
    }
}
