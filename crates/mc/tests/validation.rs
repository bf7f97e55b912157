//! Validation of the hard-sphere Monte Carlo against exact and published results, with
//! tolerances from the runs' own block-average errors (docs/reports/mc-validation.md lists the numbers).

use colloidsim_mc::engine::{HardSphereMc, McError, McParams};
use colloidsim_mc::geometry::Geometry;
use colloidsim_mc::init::{fcc_in_box, fcc_in_sphere, shuffled};
use colloidsim_mc::observe::{
    CONTACT_BINS, CONTACT_WINDOW, PairHistogram, RadialHistogram, bulk_contact, carnahan_starling,
    compressibility, contact_pairs, extrapolate_log, mean_and_error, wall_contact_density,
};
use std::f64::consts::PI;

/// A bulk run: `n` spheres of diameter `d` in the box of `n` unit spheres at `phi`.
fn bulk(n: usize, phi: f64, d: f64, seed: u32) -> HardSphereMc {
    let edge = (n as f64 * PI / 6.0 / phi).cbrt();
    let pos = fcc_in_box(n, d, edge).unwrap();
    let p = McParams {
        diameter: d,
        geometry: Geometry::Bulk { edge },
        seed,
        delta: 0.1,
        mixture: None,
    };
    HardSphereMc::new(&p, &pos, "test").unwrap()
}

/// A hard-wall droplet of radius `radius` holding `n` spheres of diameter `d`.
fn droplet(n: usize, radius: f64, d: f64, seed: u32) -> HardSphereMc {
    let pos = fcc_in_sphere(n, d, radius - 0.5 * d).unwrap();
    let p = McParams {
        diameter: d,
        geometry: Geometry::HardWall { radius },
        seed,
        delta: 0.1,
        mixture: None,
    };
    HardSphereMc::new(&p, &pos, "test").unwrap()
}

/// Block estimates of Z = 1 + 4 phi g(d+) analysed with diameter 1 (whatever the run's d).
fn compressibility_blocks(
    mc: &mut HardSphereMc,
    phi: f64,
    blocks: usize,
    sweeps: u64,
    every: u64,
) -> Vec<f64> {
    let volume = mc.box_edge().powi(3);
    let mut h = PairHistogram::new(1.0, 1.0 + CONTACT_WINDOW, CONTACT_BINS);
    (0..blocks)
        .map(|_| {
            h.clear();
            for s in 0..sweeps {
                mc.sweep();
                if s % every == 0 {
                    h.sample(mc);
                }
            }
            compressibility(phi, mc.len(), bulk_contact(&h, mc.len(), volume, 1.0))
        })
        .collect()
}

/// (Z, standard error, Z_CS) at volume fraction `phi` for spheres of diameter `d` in the box
/// of unit spheres at `phi`.
fn bulk_z(n: usize, phi: f64, d: f64, blocks: usize, sweeps: u64) -> (f64, f64, f64) {
    bulk_z_nselect(n, phi, d, blocks, sweeps, 1)
}

/// [`bulk_z`] with `nselect` trial moves per sphere per sweep (after a warm-up at 1), sampling
/// every `5 / nselect` sweeps (at least 1), so the moves between samples stay about the same.
fn bulk_z_nselect(
    n: usize,
    phi: f64,
    d: f64,
    blocks: usize,
    sweeps: u64,
    nselect: usize,
) -> (f64, f64, f64) {
    let mut mc = bulk(n, phi, d, 7);
    mc.warm_up(2000, 100, 0.3);
    mc.set_nselect(nselect);
    let every = (5 / nselect as u64).max(1);
    let z = compressibility_blocks(&mut mc, phi, blocks, sweeps, every);
    let (m, e) = mean_and_error(&z);
    eprintln!(
        "phi {phi} d {d}: Z = {m:.4} +- {e:.4}, CS {:.4}, delta {:.4}",
        carnahan_starling(phi),
        mc.delta()
    );
    (m, e, carnahan_starling(phi))
}

#[test]
fn bulk_pressure_from_contact_matches_carnahan_starling_at_phi_0_3() {
    let (z, e, cs) = bulk_z(500, 0.3, 1.0, 20, 500);
    assert!(e > 0.0 && e < 0.02 * cs, "standard error {e} is estimated");
    assert!((z - cs).abs() < 4.0 * e, "Z {z} +- {e} vs CS {cs}");
}

/// Several moves per sphere on one binning of the cells (`nselect = 4`) sample the same
/// equilibrium: Z at phi = 0.3 within the run's error of Carnahan–Starling, with a quarter of
/// the sweeps (the same number of moves).
#[test]
fn bulk_pressure_matches_carnahan_starling_with_four_moves_per_binning() {
    let (z, e, cs) = bulk_z_nselect(500, 0.3, 1.0, 20, 125, 4);
    assert!(e > 0.0 && e < 0.02 * cs, "standard error {e} is estimated");
    assert!((z - cs).abs() < 4.0 * e, "Z {z} +- {e} vs CS {cs}");
}

/// The same check catches a diameter wrong by 2 %: the spheres are 0.98 while the analysis
/// (and Carnahan–Starling) assume 1.
#[test]
fn bulk_pressure_check_fails_for_a_diameter_off_by_two_percent() {
    let (z, e, cs) = bulk_z(500, 0.3, 0.98, 20, 500);
    assert!(
        (z - cs).abs() > 4.0 * e,
        "Z {z} +- {e} vs CS {cs}: not detected"
    );
}

#[test]
#[ignore = "long: about a minute at opt-level 3"]
fn bulk_pressure_matches_carnahan_starling_at_phi_0_1_and_0_45() {
    for phi in [0.1, 0.45] {
        let (z, e, cs) = bulk_z(1000, phi, 1.0, 20, 2000);
        assert!(
            (z - cs).abs() < 4.0 * e,
            "phi {phi}: Z {z} +- {e} vs CS {cs}"
        );
    }
}

#[test]
fn pair_correlation_tends_to_one_at_large_distance() {
    let mut mc = bulk(500, 0.3, 1.0, 3);
    mc.warm_up(1000, 100, 0.3);
    let half = 0.5 * mc.box_edge();
    let volume = mc.box_edge().powi(3);
    let mut h = PairHistogram::new(0.0, half, 100);
    let mut tail = Vec::new();
    for _ in 0..10 {
        h.clear();
        for s in 0..200 {
            mc.sweep();
            if s % 10 == 0 {
                h.sample(&mc);
            }
        }
        let g = h.pair_correlation(mc.len(), volume);
        let r = h.centres();
        let far: Vec<f64> = r
            .iter()
            .zip(&g)
            .filter(|(r, _)| **r > 3.0)
            .map(|(_, g)| *g)
            .collect();
        tail.push(far.iter().sum::<f64>() / far.len() as f64);
        // Inside the core there is no pair at all.
        let w = r[1] - r[0];
        assert!(
            g.iter()
                .zip(&r)
                .all(|(g, r)| *r + 0.5 * w > 1.0 || *g == 0.0)
        );
    }
    let (m, e) = mean_and_error(&tail);
    // Normalised by the n (n - 1) / 2 pairs, the canonical g tends to 1 + (1 - S(0)) / n
    // (Lebowitz–Percus), S(0) = (1 - phi)^4 / (1 + 4 phi + 4 phi^2 - 4 phi^3 + phi^4) from
    // Carnahan–Starling; the oscillations left beyond 3 d at phi = 0.3 are below 1e-3.
    let phi: f64 = 0.3;
    let s0 =
        (1.0 - phi).powi(4) / (1.0 + 4.0 * phi + 4.0 * phi * phi - 4.0 * phi.powi(3) + phi.powi(4));
    let expect = 1.0 + (1.0 - s0) / mc.len() as f64;
    eprintln!("g(r > 3) = {m:.5} +- {e:.5}, expected {expect:.5}");
    assert!(
        (m - expect).abs() < 4.0 * e + 1e-3,
        "g(r > 3) {m} +- {e} vs {expect}"
    );
}

/// Exact sum rule of hard spheres in a hard spherical cavity (centres within `Rc = R - d/2`),
/// from the virial theorem `<sum_i r_i . F_i> = -3 N kT`: the wall pushes with `kT rho(Rc)` per
/// area of the centres' sphere, so its virial is `-4 pi Rc^3 kT rho(Rc)`; a contacting pair
/// contributes `kT d` per unit of pair density at contact, `+kT d n_c`
/// (`n_c = lim (pairs with d <= r < d + e) / e`). Hence `4 pi Rc^3 rho(Rc) = 3 N + d n_c`
/// exactly, for any N and R. (Planar limit: `rho(Rc) = beta P`.)
fn wall_sum_rule_blocks(mc: &mut HardSphereMc, d: f64, rc: f64, blocks: usize) -> Vec<f64> {
    let mut pairs = PairHistogram::new(d, d * (1.0 + CONTACT_WINDOW), CONTACT_BINS);
    let mut wall = RadialHistogram::new(rc - CONTACT_WINDOW * d, rc, CONTACT_BINS);
    (0..blocks)
        .map(|_| {
            pairs.clear();
            wall.clear();
            for s in 0..500 {
                mc.sweep();
                if s % 5 == 0 {
                    pairs.sample(mc);
                    wall.sample(mc);
                }
            }
            let lhs = 4.0 * PI * rc.powi(3) * wall_contact_density(&wall, rc);
            let rhs = 3.0 * mc.len() as f64 + d * contact_pairs(&pairs, d);
            lhs / rhs - 1.0
        })
        .collect()
}

#[test]
fn hard_wall_contact_sum_rule_holds_and_catches_a_wrong_wall() {
    // R = 6 d, mean phi = N d^3 / (8 R^3) = 0.3.
    let n = 518;
    let mut mc = droplet(n, 6.0, 1.0, 5);
    mc.warm_up(2000, 100, 0.3);
    let blocks = wall_sum_rule_blocks(&mut mc, 1.0, 5.5, 16);
    let (m, e) = mean_and_error(&blocks);
    eprintln!("sum rule: lhs / rhs - 1 = {m:.4} +- {e:.4}");
    assert!(e > 0.0 && e < 0.03, "error {e} is estimated");
    assert!(m.abs() < 4.0 * e, "lhs / rhs - 1 = {m} +- {e}");
    // The same analysis with the wall placed 2 % of d too far in (Rc = 5.48) fails.
    let broken = wall_sum_rule_blocks(&mut mc, 1.0, 5.48, 16);
    let (mb, eb) = mean_and_error(&broken);
    eprintln!("wrong wall: {mb:.4} +- {eb:.4}");
    assert!(mb.abs() > 4.0 * eb, "a wrong wall position is not detected");
}

#[test]
fn no_overlaps_and_no_escape_after_any_sweep() {
    let cases: Vec<(HardSphereMc, &str)> = vec![
        (bulk(256, 0.5, 1.0, 1), "bulk 0.5"),
        (droplet(300, 5.0, 1.0, 2), "hard wall"),
        (
            {
                let geometry = Geometry::interface(5.0, 50.0, 0.5, -0.5, 1.0).unwrap();
                let pos = fcc_in_sphere(300, 1.0, 4.5).unwrap();
                let p = McParams {
                    diameter: 1.0,
                    geometry,
                    seed: 3,
                    delta: 0.1,
                    mixture: None,
                };
                HardSphereMc::new(&p, &pos, "test").unwrap()
            },
            "interface",
        ),
    ];
    for (mut mc, name) in cases {
        let max = mc.geometry().confinement(1.0);
        let mut total = 0;
        for k in 0..300 {
            let s = mc.sweep();
            total += s.accepted;
            if k % 100 == 99 {
                mc.tune(s.acceptance(), 0.3);
            }
            assert_eq!(
                mc.first_overlap(1e-12),
                None,
                "{name}: overlap after sweep {k}"
            );
            if let Some(max) = max {
                for i in 0..mc.len() {
                    let p = mc.position(i);
                    let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                    assert!(
                        r <= max * (1.0 + 1e-12),
                        "{name}: sphere {i} at {r} > {max}"
                    );
                }
            }
        }
        assert!(
            total > 300 * 300 / 10,
            "{name}: only {total} moves accepted"
        );
        // The checker itself sees an overlap when there is one.
        let mut pos: Vec<[f64; 3]> = (0..mc.len()).map(|i| mc.position(i)).collect();
        pos[1] = [pos[0][0] + 0.5, pos[0][1], pos[0][2]];
        let p = McParams {
            diameter: 1.0,
            geometry: *mc.geometry(),
            seed: 1,
            delta: 0.1,
            mixture: None,
        };
        match HardSphereMc::new(&p, &pos, "start.gsd") {
            Err(McError::Overlap { key, .. }) => assert_eq!(key, "start.gsd"),
            Err(McError::OutsideWall { .. }) => {}
            other => panic!("{name}: overlap not refused: {other:?}"),
        }
    }
}

/// `f` on a pool of `threads` workers.
fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

#[test]
fn results_do_not_depend_on_the_thread_count_and_restarts_are_bitwise() {
    let run = |threads: usize| {
        on_threads(threads, || {
            // 5000 spheres: up to five parts of the binning's counting sort (at least 1024
            // spheres per part), so 3 and 5 threads split the particles and the cells unevenly.
            let mut mc = bulk(5000, 0.4, 1.0, 11);
            mc.warm_up(100, 20, 0.3);
            mc.run(50);
            let [x, y, z] = mc.positions();
            (x.to_vec(), y.to_vec(), z.to_vec(), mc.delta())
        })
    };
    let one = run(1);
    // Four moves per sphere per binning: 4 N trials a sweep, thread-independent too.
    let four = |threads: usize| {
        on_threads(threads, || {
            let mut mc = bulk(3000, 0.4, 1.0, 12);
            mc.set_nselect(4);
            let stats = mc.run(10);
            assert_eq!(stats.trials, 4 * 3000 * 10);
            mc.positions()
                .map(|c| c.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
        })
    };
    assert_eq!(four(1), four(2), "nselect = 4: 1 vs 2 threads");
    for threads in [2, 3, 5] {
        let other = run(threads);
        assert!(
            one.0
                .iter()
                .zip(&other.0)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "{threads} threads"
        );
        assert!(one.1 == other.1 && one.2 == other.2 && one.3.to_bits() == other.3.to_bits());
    }
    // Restart: save after 30 sweeps, continue 20; a fresh engine restored from the save
    // continues identically.
    let mut mc = droplet(400, 5.5, 1.0, 4);
    mc.run(30);
    let saved = {
        let [x, y, z] = mc.positions();
        [x.to_vec(), y.to_vec(), z.to_vec()]
    };
    let (sweeps, delta) = (mc.sweeps(), mc.delta());
    mc.run(20);
    let mut again = droplet(400, 5.5, 1.0, 4);
    again.restore(saved, sweeps, delta);
    again.run(20);
    assert_eq!(mc.positions(), again.positions());
    // A different seed gives a different run.
    let mut other = droplet(400, 5.5, 1.0, 5);
    other.run(50);
    assert_ne!(mc.positions(), other.positions());
}

#[test]
fn bad_configurations_are_refused_naming_the_key() {
    let p = McParams {
        diameter: 1.0,
        geometry: Geometry::HardWall { radius: 3.0 },
        seed: 1,
        delta: 0.1,
        mixture: None,
    };
    let e = HardSphereMc::new(&p, &[[0.0; 3], [2.6, 0.0, 0.0]], "start.gsd").unwrap_err();
    assert!(
        matches!(e, McError::OutsideWall { i: 1, .. }) && e.to_string().contains("start.gsd"),
        "{e}"
    );
    let e = HardSphereMc::new(&p, &[[0.0; 3], [0.0, 0.99, 0.0]], "start.gsd").unwrap_err();
    assert!(matches!(e, McError::Overlap { i: 0, j: 1, .. }), "{e}");
    let bad = McParams {
        diameter: -1.0,
        ..p
    };
    let e = HardSphereMc::new(&bad, &[], "x").unwrap_err();
    assert!(e.to_string().starts_with("diameter: "), "{e}");
    let e = Geometry::interface(5.0, 50.0, 0.5, -6.0, 1.0).unwrap_err();
    assert_eq!(e.key, "offset");
    assert!(fcc_in_box(1000, 1.0, 5.0).is_err());
}

/// An independent reference: the plainest serial Metropolis (random particle, displacement
/// cube of fixed half-width 0.25, all-pairs minimum-image overlap test, no cells) in the same
/// box of 108 spheres at phi = 0.3; its Z must agree with the engine's within their combined
/// errors (the same finite-size system, so this tests the checkerboard algorithm itself).
#[test]
fn engine_agrees_with_a_brute_force_serial_monte_carlo() {
    use colloidsim_core::rng::{Purpose, stream};
    use rand::Rng;
    let (n, phi, blocks, sweeps) = (108usize, 0.3, 10, 1500u64);
    let mut mc = bulk(n, phi, 1.0, 21);
    mc.warm_up(1000, 100, 0.3);
    let l = mc.box_edge();
    let volume = l.powi(3);
    let mut pos: Vec<[f64; 3]> = (0..n).map(|i| mc.position(i)).collect();
    let engine = compressibility_blocks(&mut mc, phi, blocks, sweeps, 3);
    let mut rng = stream(99, 0, Purpose::Moves, 0);
    let mut unit = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let r2 = |a: &[f64; 3], b: &[f64; 3]| -> f64 {
        (0..3)
            .map(|k| {
                let x = a[k] - b[k];
                let x = x - l * (x / l).round();
                x * x
            })
            .sum()
    };
    let mut reference = Vec::new();
    for _ in 0..blocks {
        let mut counts = [0u64; CONTACT_BINS];
        let mut samples = 0;
        for s in 0..sweeps {
            for _ in 0..n {
                let i = ((unit() * n as f64) as usize).min(n - 1);
                let mut p = pos[i];
                for x in &mut p {
                    *x += 0.25 * (2.0 * unit() - 1.0);
                    *x -= l * (*x / l).round();
                }
                if (0..n).all(|j| j == i || r2(&p, &pos[j]) >= 1.0) {
                    pos[i] = p;
                }
            }
            if s % 3 == 0 {
                samples += 1;
                for i in 0..n {
                    for j in 0..i {
                        let r = r2(&pos[i], &pos[j]).sqrt();
                        let b = ((r - 1.0) / (CONTACT_WINDOW / CONTACT_BINS as f64)) as usize;
                        if r < 1.0 + CONTACT_WINDOW && b < CONTACT_BINS {
                            counts[b] += 1;
                        }
                    }
                }
            }
        }
        let w = CONTACT_WINDOW / CONTACT_BINS as f64;
        let pairs = n as f64 * (n as f64 - 1.0) / (2.0 * volume);
        let centres: Vec<f64> = (0..CONTACT_BINS)
            .map(|b| 1.0 + w * (b as f64 + 0.5))
            .collect();
        let g: Vec<f64> = (0..CONTACT_BINS)
            .map(|b| {
                let (r0, r1) = (1.0 + w * b as f64, 1.0 + w * (b + 1) as f64);
                counts[b] as f64
                    / (samples as f64 * pairs * 4.0 * PI / 3.0 * (r1.powi(3) - r0.powi(3)))
            })
            .collect();
        reference.push(compressibility(
            phi,
            n,
            extrapolate_log(&centres, &g, 2, 1.0),
        ));
    }
    let (a, ea) = mean_and_error(&engine);
    let (b, eb) = mean_and_error(&reference);
    eprintln!(
        "N = 108: engine Z = {a:.4} +- {ea:.4}, brute force {b:.4} +- {eb:.4}, CS {:.4}",
        carnahan_starling(phi)
    );
    assert!(
        (a - b).abs() < 4.0 * (ea * ea + eb * eb).sqrt(),
        "engine {a} +- {ea} vs reference {b} +- {eb}"
    );
}

/// The radial FMT equilibrium (Rosenfeld, `colloidsim_dft::radial`) of the same droplet: hard
/// wall `beta V = 60` for centres beyond `Rc` (a Boltzmann factor of 1e-26), same N, grid
/// 0.01 d. Returns the density averaged over the MC's bins (volume-weighted).
fn fmt_profile(n: usize, rc: f64, edges: &[f64]) -> Vec<f64> {
    use colloidsim_dft::radial::{EquilibriumOptions, RadialGrid, Rosenfeld, solve_equilibrium};
    let grid = RadialGrid::covering(0.01, rc + 2.0).unwrap();
    let mut fmt = Rosenfeld::new(&grid, 1.0).unwrap();
    let v: Vec<f64> = grid
        .centres()
        .iter()
        .map(|&r| if r < rc { 0.0 } else { 60.0 })
        .collect();
    let eq = solve_equilibrium(
        &grid,
        &mut fmt,
        &v,
        n as f64,
        None,
        &EquilibriumOptions::default(),
    )
    .unwrap();
    edges
        .windows(2)
        .map(|e| {
            let (mut num, mut vol) = (0.0, 0.0);
            for ((&r, &dv), &rho) in grid.centres().iter().zip(grid.volumes()).zip(&eq.rho) {
                if r >= e[0] && r < e[1] {
                    num += rho * dv;
                    vol += dv;
                }
            }
            num / vol
        })
        .collect()
}

/// Chi-square of the MC profile (block means and errors per bin) against `reference` over the
/// bins more than 1 d from the wall, its degrees of freedom, and the largest deviation over all
/// bins in units of `4 SE + 5 % of the reference`.
fn profile_misfit(
    blocks: &[Vec<f64>],
    reference: &[f64],
    edges: &[f64],
    rc: f64,
) -> (f64, usize, f64) {
    let (mut chi2, mut dof, mut worst) = (0.0, 0, 0.0f64);
    for b in 0..reference.len() {
        let col: Vec<f64> = blocks.iter().map(|v| v[b]).collect();
        let (m, e) = mean_and_error(&col);
        if edges[b + 1] <= rc - 1.0 {
            chi2 += ((m - reference[b]) / e).powi(2);
            dof += 1;
        }
        worst = worst.max((m - reference[b]).abs() / (4.0 * e + 0.05 * reference[b]));
    }
    (chi2, dof, worst)
}

/// MC against Rosenfeld FMT in the hard-wall droplet R = 6 d, N = 518 (mean phi 0.3): in the
/// interior (more than 1 d from the wall) within the MC's errors (chi-square at p ~ 1e-4);
/// next to the wall Rosenfeld's own error shows (its first minimum 5 % low, contact 1 % high,
/// docs/reports/mc-validation.md), so every bin is held to 4 SE + 5 %. An FMT with 2 % fewer particles fails.
#[test]
fn hard_wall_profile_matches_the_radial_fmt_equilibrium() {
    let (n, radius) = (518, 6.0);
    let rc = radius - 0.5;
    let bins = 22;
    let edges: Vec<f64> = (0..=bins).map(|b| rc * b as f64 / bins as f64).collect();
    let mut mc = droplet(n, radius, 1.0, 8);
    mc.warm_up(2000, 100, 0.3);
    let mut h = RadialHistogram::new(0.0, rc, bins);
    let blocks: Vec<Vec<f64>> = (0..16)
        .map(|_| {
            h.clear();
            for s in 0..500 {
                mc.sweep();
                if s % 5 == 0 {
                    h.sample(&mc);
                }
            }
            h.density()
        })
        .collect();
    let limit = |dof: usize| dof as f64 + 4.0 * (2.0 * dof as f64).sqrt();
    let (chi2, dof, worst) = profile_misfit(&blocks, &fmt_profile(n, rc, &edges), &edges, rc);
    eprintln!(
        "FMT: chi2 {chi2:.1} for {dof} bins (limit {:.1}), worst {worst:.2}",
        limit(dof)
    );
    assert!(
        chi2 < limit(dof) && worst < 1.0,
        "chi2 {chi2} / {dof}, worst {worst}"
    );
    let (chi2, dof, worst) =
        profile_misfit(&blocks, &fmt_profile(n * 98 / 100, rc, &edges), &edges, rc);
    eprintln!("FMT with 2 % fewer spheres: chi2 {chi2:.1} for {dof}, worst {worst:.2}");
    assert!(chi2 > limit(dof), "a 2 % error in N is not detected");
}

/// rho2(r1, r2, cos theta) in the hard-wall droplet: symmetric under r1 <-> r2, equal to an
/// independent count of the ordered pairs (x_i, x_j), i != j, over the same bins, and integrating
/// to N (N - 1); far apart inside the droplet g2 = rho2 / (rho(r1) rho(r2)) is 1. (A statistical
/// test of the raw index-ordered counts' symmetry was tried and dropped: labelled spheres do not
/// mix within a test's length, and the counts of one configuration are far from Poisson.)
#[test]
fn two_body_density_is_symmetric_and_normalised() {
    use colloidsim_mc::observe::PairDensity;
    let (n, radius) = (300, 4.5);
    // Lattice sites in a random order, so that the index order carries no position.
    let pos = shuffled(fcc_in_sphere(n, 1.0, radius - 0.5).unwrap(), 9);
    let p = McParams {
        diameter: 1.0,
        geometry: Geometry::HardWall { radius },
        seed: 9,
        delta: 0.1,
        mixture: None,
    };
    let mut mc = HardSphereMc::new(&p, &pos, "test").unwrap();
    mc.warm_up(500, 100, 0.3);
    let mut h = PairDensity::new(radius, 8, 6);
    for s in 0..1000 {
        mc.sweep();
        if s % 10 == 0 {
            h.sample(&mc);
        }
    }
    let rho2 = h.rho2();
    let total = h.integral(&rho2);
    let expect = (n * (n - 1)) as f64;
    assert!(
        (total / expect - 1.0).abs() < 1e-12,
        "integral {total} vs {expect}"
    );
    let idx = |a: usize, b: usize, c: usize| (a * h.r_bins() + b) * h.cos_bins() + c;
    for a in 0..h.r_bins() {
        for b in 0..h.r_bins() {
            for c in 0..h.cos_bins() {
                assert_eq!(rho2[idx(a, b, c)], rho2[idx(b, a, c)], "r1 <-> r2");
            }
        }
    }
    // The ordered pairs of the last configuration, counted directly, against one more sample.
    let mut one = PairDensity::new(radius, 8, 6);
    one.sample(&mc);
    let mut ordered = vec![0u64; 8 * 8 * 6];
    let bin = |r: f64| ((r / radius * 8.0) as usize).min(7);
    for i in 0..n {
        for j in 0..n {
            if i == j {
                continue;
            }
            let (p, q) = (mc.position(i), mc.position(j));
            let (ri, rj) = (
                p.iter().map(|v| v * v).sum::<f64>().sqrt(),
                q.iter().map(|v| v * v).sum::<f64>().sqrt(),
            );
            let cos = ((p[0] * q[0] + p[1] * q[1] + p[2] * q[2]) / (ri * rj)).clamp(-1.0, 1.0);
            let c = (((cos + 1.0) * 3.0) as usize).min(5);
            ordered[idx(bin(ri), bin(rj), c)] += 1;
        }
    }
    for a in 0..8 {
        for b in 0..8 {
            for c in 0..6 {
                assert_eq!(
                    ordered[idx(a, b, c)],
                    one.count(a, b, c) + one.count(b, a, c),
                    "bin ({a}, {b}, {c})"
                );
            }
        }
    }
    // Far apart (opposite sides of the droplet's interior) the spheres are uncorrelated:
    // g2 = rho2 / (rho(r1) rho(r2)) is 1 up to the canonical 1 - 1/N-type correction.
    let mut radial = RadialHistogram::new(0.0, radius, 8);
    for s in 0..1000 {
        mc.sweep();
        if s % 10 == 0 {
            radial.sample(&mc);
        }
    }
    let rho = radial.density();
    let (a, b, c) = (3, 3, 0); // r1, r2 in [1.69, 2.25), cos theta in [-1, -2/3)
    let g2 = rho2[(a * h.r_bins() + b) * h.cos_bins() + c] / (rho[a] * rho[b]);
    eprintln!("g2 at r1 = r2 = 2 d, opposite sides: {g2:.3}");
    assert!((g2 - 1.0).abs() < 0.1, "g2 {g2}");
}
