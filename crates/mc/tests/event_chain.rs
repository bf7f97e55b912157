//! Event-chain Monte Carlo (`colloidsim_mc::engine::chain`): hard constraints kept, restarts
//! bitwise, the event-chain pressure against Carnahan–Starling, the equilibrium of droplets
//! against local moves (tolerances from the runs' own block errors; docs/reports/mc-validation.md lists the numbers).

use colloidsim_mc::engine::chain::free_path;
use colloidsim_mc::engine::{HardSphereMc, McParams};
use colloidsim_mc::geometry::Geometry;
use colloidsim_mc::init::{fcc_in_box, fcc_in_sphere};
use colloidsim_mc::observe::{carnahan_starling, mean_and_error};
use colloidsim_mc::{ChainStats, EventChain};
use std::f64::consts::PI;

/// `n` unit spheres at `phi` in a periodic cube, FCC start.
fn bulk(n: usize, phi: f64, seed: u32) -> HardSphereMc {
    let edge = (n as f64 * PI / 6.0 / phi).cbrt();
    let pos = fcc_in_box(n, 1.0, edge).unwrap();
    let p = McParams {
        diameter: 1.0,
        geometry: Geometry::Bulk { edge },
        seed,
        delta: 0.1,
        mixture: None,
    };
    HardSphereMc::new(&p, &pos, "test").unwrap()
}

/// `n` unit spheres in `geometry` (centres within `rc` at the start).
fn droplet(n: usize, geometry: Geometry, rc: f64, seed: u32) -> HardSphereMc {
    let pos = fcc_in_sphere(n, 1.0, rc).unwrap();
    let p = McParams {
        diameter: 1.0,
        geometry,
        seed,
        delta: 0.1,
        mixture: None,
    };
    HardSphereMc::new(&p, &pos, "test").unwrap()
}

/// Chains of `length` at `chains` per sweep.
fn chains(mc: &mut HardSphereMc, length: f64, chains: u64) {
    mc.set_event_chain(Some(EventChain {
        length,
        chains_per_sweep: chains,
    }))
    .unwrap();
}

/// Block estimates of `beta P / rho` from the lifts.
fn z_blocks(mc: &mut HardSphereMc, blocks: usize, sweeps: u64) -> Vec<f64> {
    (0..blocks)
        .map(|_| {
            let mut s = ChainStats::default();
            for _ in 0..sweeps {
                mc.sweep();
                s += mc.last_chains();
            }
            s.compressibility()
        })
        .collect()
}

/// (Z, standard error) at `phi` with N spheres, chains of about N^(1/3) ... (see docs).
fn event_chain_z(n: usize, phi: f64, length: f64, blocks: usize, sweeps: u64) -> (f64, f64) {
    let mut mc = bulk(n, phi, 11);
    let per_sweep = ((n as f64 * free_path(phi, 1.0) / length).round() as u64).max(1);
    chains(&mut mc, length, per_sweep);
    mc.run(200);
    let z = z_blocks(&mut mc, blocks, sweeps);
    let (m, e) = mean_and_error(&z);
    eprintln!(
        "phi {phi}: event-chain Z = {m:.4} +- {e:.4}, CS {:.4} ({per_sweep} chains/sweep)",
        carnahan_starling(phi)
    );
    (m, e)
}

/// The virial series of hard spheres through `B12` (`Z = 1 + sum_n B_n eta^(n-1)`, reduced
/// coefficients; to B10 those of Clisby & McCoy 2006, B11 and B12 estimates whose terms are
/// 3e-5 and 1e-5 at eta = 0.3): at phi = 0.3 the truncation is below 1e-4, and the sum,
/// 3.9838, lies 0.25 % above Carnahan–Starling (whose B4 is 18 instead of 18.365).
fn virial_series(eta: f64) -> f64 {
    let b = [
        1.0, 4.0, 10.0, 18.3647684, 28.224512, 39.81514, 53.3444, 68.538, 85.813, 105.78, 127.9,
        152.7,
    ];
    b.iter()
        .enumerate()
        .map(|(k, b)| b * eta.powi(k as i32))
        .sum()
}

/// The exact event-chain pressure: within 1 % of Carnahan–Starling at phi 0.3 and 0.45, and
/// within 4 of its standard errors of the virial series at 0.3 (measured 3.9857 +- 0.0044
/// against 3.9838; CS 3.9738) and of CS at 0.45 (9.3922 +- 0.0164 against 9.3847). Lifts
/// counted 1 % short: 3.9558 at phi 0.3, fails.
#[test]
fn event_chain_pressure_matches_carnahan_starling() {
    for phi in [0.3, 0.45] {
        let (z, e) = event_chain_z(500, phi, 5.0, 20, 100);
        let cs = carnahan_starling(phi);
        let exact = if phi < 0.4 { virial_series(phi) } else { cs };
        assert!(e > 0.0 && e < 0.003 * cs, "phi {phi}: error {e}");
        assert!((z - cs).abs() < 0.01 * cs, "phi {phi}: Z {z} vs CS {cs}");
        assert!(
            (z - exact).abs() < 4.0 * e,
            "phi {phi}: Z {z} +- {e} vs {exact}"
        );
    }
}

/// The three geometries of the event-chain tests: bulk at phi 0.5, a hard wall (R = 5) and
/// the BD interface (R = 5, k = 50 kT/d^2), 300 spheres in each droplet (mean phi 0.3).
fn cases(seed: u32) -> Vec<(HardSphereMc, &'static str)> {
    vec![
        (bulk(256, 0.5, seed), "bulk 0.5"),
        (
            droplet(300, Geometry::HardWall { radius: 5.0 }, 4.5, seed),
            "hard wall",
        ),
        (
            droplet(
                300,
                Geometry::interface(5.0, 50.0, 0.5, -0.5, 1.0).unwrap(),
                4.5,
                seed,
            ),
            "interface",
        ),
    ]
}

/// No overlap at all (the restart's check, without tolerance), every centre inside its
/// container, and the chains move the spheres (lifts, and reversals in droplets).
#[test]
fn event_chains_keep_every_hard_constraint() {
    for (mut mc, name) in cases(3) {
        chains(&mut mc, 3.0, 40);
        let max = mc.geometry().confinement(1.0);
        let start: Vec<[f64; 3]> = (0..mc.len()).map(|i| mc.position(i)).collect();
        let mut total = ChainStats::default();
        for k in 0..200 {
            mc.sweep();
            total += mc.last_chains();
            assert_eq!(
                mc.first_overlap(0.0),
                None,
                "{name}: overlap after sweep {k}"
            );
            if let Some(max) = max {
                for i in 0..mc.len() {
                    let p = mc.position(i);
                    let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                    assert!(r <= max, "{name}: sphere {i} at {r} > {max}");
                }
            }
        }
        eprintln!("{name}: {total:?}");
        assert_eq!(total.chains, 200 * 40);
        assert!(total.lifts > 10 * total.chains, "{name}: {total:?}");
        assert_eq!(total.reversals > 0, max.is_some(), "{name}: {total:?}");
        let moved = (0..mc.len())
            .filter(|&i| mc.position(i) != start[i])
            .count();
        assert!(
            moved > mc.len() * 9 / 10,
            "{name}: only {moved} spheres moved"
        );
    }
}

/// Chains move the positions alone and leave the cells to [`HardSphereMc::bin`]: the pairs
/// that `for_each_pair` finds before it and after it are those of the current positions
/// (every pair computed here), at the same distances to rounding; local moves after chains
/// start from binned cells. (Cells left as they were before the chains fail.)
#[test]
fn pairs_after_event_chains_are_those_of_the_positions() {
    for (mut mc, name) in cases(4) {
        chains(&mut mc, 3.0, 40);
        mc.run(20);
        let rc = 2.5;
        let l = mc.box_edge();
        let bulk = matches!(mc.geometry(), Geometry::Bulk { .. });
        let mut want = Vec::new();
        for i in 0..mc.len() {
            for j in i + 1..mc.len() {
                let (p, q) = (mc.position(i), mc.position(j));
                let r2: f64 = (0..3)
                    .map(|k| {
                        let v = p[k] - q[k];
                        let v = if bulk { v - l * (v / l).round() } else { v };
                        v * v
                    })
                    .sum();
                if r2 < rc * rc {
                    want.push((i, j, r2));
                }
            }
        }
        assert!(want.len() > 5 * mc.len(), "{name}: {} pairs", want.len());
        for stage in ["before bin", "after bin"] {
            if stage == "after bin" {
                mc.bin();
            }
            let mut got = Vec::new();
            mc.for_each_pair(rc, |i, j, r2| got.push((i.min(j), i.max(j), r2)));
            got.sort_by_key(|a| (a.0, a.1));
            assert_eq!(got.len(), want.len(), "{name}, {stage}");
            for (a, b) in got.iter().zip(&want) {
                assert_eq!((a.0, a.1), (b.0, b.1), "{name}, {stage}");
                assert!(
                    (a.2 - b.2).abs() < 1e-12,
                    "{name}, {stage}: {a:?} against {b:?}"
                );
            }
        }
        mc.set_event_chain(None).unwrap();
        mc.run(5);
        assert_eq!(mc.first_overlap(0.0), None, "{name}");
    }
}

/// A run continued from its positions and sweep count (what a checkpoint holds) is bitwise
/// the uninterrupted run; the positions pass the strict overlap check of a restart.
#[test]
fn event_chain_restarts_are_bitwise() {
    for ((mut a, name), (b, _)) in cases(5).into_iter().zip(cases(5)) {
        chains(&mut a, 3.0, 20);
        a.run(30);
        let saved = a.positions().map(|p| p.to_vec());
        let rows: Vec<[f64; 3]> = (0..a.len()).map(|i| a.position(i)).collect();
        let params = McParams {
            diameter: 1.0,
            geometry: *b.geometry(),
            seed: 5,
            delta: 0.1,
            mixture: None,
        };
        let mut c = HardSphereMc::new(&params, &rows, "checkpoint").unwrap();
        c.restore(saved, a.sweeps(), a.delta());
        chains(&mut c, 3.0, 20);
        a.run(20);
        c.run(20);
        assert_eq!(a.positions(), c.positions(), "{name}");
        assert_eq!(a.last_chains(), c.last_chains(), "{name}");
    }
}

/// Per block: the radial density on `bins` bins of `[0, r_max]`, then the two-body density
/// `rho2` on `(r_bins, r_bins, cos_bins)` cells (zero cells dropped later by their errors).
fn droplet_blocks(
    mc: &mut HardSphereMc,
    r_max: f64,
    (bins, r_bins, cos_bins): (usize, usize, usize),
    blocks: usize,
    sweeps: u64,
    every: u64,
) -> Vec<Vec<f64>> {
    use colloidsim_mc::observe::{PairDensity, RadialHistogram};
    (0..blocks)
        .map(|_| {
            let mut rho = RadialHistogram::new(0.0, r_max, bins);
            let mut rho2 = PairDensity::new(r_max, r_bins, cos_bins);
            for s in 0..sweeps {
                mc.sweep();
                if s % every == 0 {
                    rho.sample(mc);
                    rho2.sample(mc);
                }
            }
            let mut v = rho.density();
            v.extend(rho2.rho2());
            v
        })
        .collect()
}

/// `sum (a - b)^2 / (e_a^2 + e_b^2)` over the bins where either has an error, and their
/// number: the per-bin means and standard errors of two block lists.
fn chi_square(a: &[Vec<f64>], b: &[Vec<f64>]) -> (f64, usize) {
    let (mut chi2, mut bins) = (0.0, 0);
    for k in 0..a[0].len() {
        let col = |x: &[Vec<f64>]| mean_and_error(&x.iter().map(|v| v[k]).collect::<Vec<_>>());
        let ((ma, ea), (mb, eb)) = (col(a), col(b));
        let var = ea * ea + eb * eb;
        if var > 0.0 {
            chi2 += (ma - mb).powi(2) / var;
            bins += 1;
        }
    }
    (chi2, bins)
}

/// Chi-square limit for `bins` terms: the mean plus five standard deviations.
fn limit(bins: usize) -> f64 {
    bins as f64 + 5.0 * (2.0 * bins as f64).sqrt()
}

/// Global balance on a small system: 4 spheres in a hard spherical wall of radius 1.6 d
/// (centres within 1.1 d, crowded: every pair meets often), the radial density (10 bins) and
/// the two-body density (4 x 4 x 4 cells) of event chains against a long run of local moves.
#[test]
fn event_chains_sample_a_small_droplet_like_local_moves() {
    let geometry = Geometry::HardWall { radius: 1.6 };
    let shape = (10, 4, 4);
    let mut local = droplet(4, geometry, 1.1, 21);
    local.warm_up(2000, 100, 0.4);
    let want = droplet_blocks(&mut local, 1.1, shape, 20, 20_000, 2);
    let mut ecmc = droplet(4, geometry, 1.1, 22);
    chains(&mut ecmc, 1.0, 2);
    ecmc.run(1000);
    let got = droplet_blocks(&mut ecmc, 1.1, shape, 20, 20_000, 2);
    let (chi2, bins) = chi_square(&want, &got);
    eprintln!(
        "small droplet: chi2 {chi2:.1} for {bins} bins (limit {:.1})",
        limit(bins)
    );
    assert!(bins > 30, "{bins} bins");
    assert!(chi2 < limit(bins), "chi2 {chi2} for {bins} bins");
}

/// The droplet's profile and two-body density (12 radial bins; rho2 on 6 x 6 x 6 cells) of
/// event chains equal local moves' within their block errors: hard wall (R = 4, 154 spheres,
/// mean phi 0.3) and the BD interface (R = 4, k = 50 kT/d^2, 154 spheres).
#[test]
fn event_chains_sample_droplets_like_local_moves() {
    let shape = (12, 4, 4);
    for (geometry, name) in [
        (Geometry::HardWall { radius: 4.0 }, "hard wall"),
        (
            Geometry::interface(4.0, 50.0, 0.5, -0.5, 1.0).unwrap(),
            "interface",
        ),
    ] {
        let r_max = 4.0;
        let mut local = droplet(154, geometry, 3.5, 31);
        local.warm_up(2000, 100, 0.3);
        local.set_nselect(4);
        let want = droplet_blocks(&mut local, r_max, shape, 20, 500, 5);
        let mut ecmc = droplet(154, geometry, 3.5, 32);
        chains(&mut ecmc, 3.0, 20);
        ecmc.run(1000);
        let got = droplet_blocks(&mut ecmc, r_max, shape, 20, 1000, 5);
        let (chi2, bins) = chi_square(&want, &got);
        eprintln!(
            "{name}: chi2 {chi2:.1} for {bins} bins (limit {:.1})",
            limit(bins)
        );
        assert!(bins > 60, "{name}: {bins} bins");
        assert!(chi2 < limit(bins), "{name}: chi2 {chi2} for {bins} bins");
    }
}
