//! Pair interactions in place of the hard cores (issue #43 item 1): local moves sample
//! `exp(-U / kT)`. Two spheres of unlike species in a periodic box are the exact test: their
//! minimum-image separation `r < L/2` is distributed as `r^2 exp(-u_AB(r) / kT)`.

use colloidsim_mc::engine::{HardSphereMc, McParams, Mixture};
use colloidsim_mc::geometry::Geometry;
use colloidsim_mc::observe::mean_and_error;
use colloidsim_particles::PairSpec;
use colloidsim_particles::potential::Pair;

/// Species A (d = 1) and B (d = 1.5), one each, in a periodic cube of edge `l`.
fn two_species(l: f64, seed: u32) -> (McParams, Vec<[f64; 3]>) {
    let params = McParams {
        diameter: 1.0,
        geometry: Geometry::Bulk { edge: l },
        seed,
        delta: 0.3,
        mixture: Some(Mixture::new(vec![1.0, 1.5], vec![1, 1])),
    };
    (params, vec![[0.0; 3], [2.0, 0.0, 0.0]])
}

/// A Morse well of 2 kT at contact (surface distance 0), range 1/4, cut at a surface
/// distance of 1.
fn morse() -> PairSpec {
    PairSpec::Morse {
        depth: 2.0,
        kappa: 4.0,
        h0: 0.0,
        h_cut: 1.0,
    }
}

/// Minimum-image distance of the two spheres.
fn separation(mc: &HardSphereMc, l: f64) -> f64 {
    let (a, b) = (mc.position(0), mc.position(1));
    (0..3)
        .map(|k| {
            let v = a[k] - b[k];
            let v = v - l * (v / l).round();
            v * v
        })
        .sum::<f64>()
        .sqrt()
}

/// The probability of each of `bins` bins of `[0, l/2)` given `r < l/2`, for the density
/// `r^2 exp(-beta u(r))` (midpoint rule on 400 points a bin).
fn expected(u: impl Fn(f64) -> f64, l: f64, bins: usize) -> Vec<f64> {
    let w = 0.5 * l / bins as f64;
    let sub = 400;
    let p: Vec<f64> = (0..bins)
        .map(|b| {
            (0..sub)
                .map(|k| {
                    let r = (b as f64 + (k as f64 + 0.5) / sub as f64) * w;
                    r * r * (-u(r)).exp()
                })
                .sum::<f64>()
        })
        .collect();
    let total: f64 = p.iter().sum();
    p.iter().map(|x| x / total).collect()
}

/// Chi-square of the blocks' mean bin fractions against `p`, with the blocks' standard
/// errors (bins with no scatter or a tiny probability left out), and the bins counted.
fn chi2(blocks: &[Vec<f64>], p: &[f64]) -> (f64, usize) {
    let (mut chi2, mut dof) = (0.0, 0);
    for (b, &pb) in p.iter().enumerate() {
        let col: Vec<f64> = blocks.iter().map(|h| h[b]).collect();
        let (m, e) = mean_and_error(&col);
        if pb > 1e-3 && e > 0.0 {
            chi2 += ((m - pb) / e).powi(2);
            dof += 1;
        }
    }
    (chi2, dof)
}

/// The separation histogram of an A–B pair under the Morse well follows
/// `r^2 exp(-beta u_AB)` (contact at the pair's mean diameter 1.25) within the blocks' errors;
/// the same histogram is far from the distribution of another species pair's contact (the
/// engine reading the wrong species) and from the ideal gas (the interaction ignored).
#[test]
fn two_spheres_sample_the_boltzmann_weight_of_their_pair() {
    let (l, kt) = (6.0, 1.0);
    let (params, pos) = two_species(l, 11);
    let mut mc = HardSphereMc::with_pair(&params, &pos, "test", &morse(), kt).unwrap();
    assert!(mc.cell_side() >= 2.5, "cells of {}", mc.cell_side());
    mc.warm_up(2000, 100, 0.4);
    let (bins, blocks, per_block, every) = (30, 40, 2500, 4);
    let w = 0.5 * l / bins as f64;
    let mut hist = vec![vec![0.0; bins]; blocks];
    for h in hist.iter_mut() {
        let mut inside = 0;
        for _ in 0..per_block {
            mc.run(every);
            let r = separation(&mc, l);
            if r < 0.5 * l {
                h[(r / w) as usize] += 1.0;
                inside += 1;
            }
        }
        h.iter_mut().for_each(|x| *x /= inside as f64);
    }
    let u = PairSpec::build(&morse(), &[1.0, 1.5], kt).unwrap();
    let law = |ti: u32, tj: u32, di: f64, dj: f64| {
        let u = &u;
        move |r: f64| u.energy(r * r, ti, tj, di, dj) / kt
    };
    let (c, dof) = chi2(&hist, &expected(law(0, 1, 1.0, 1.5), l, bins));
    println!("A-B: chi2 {c:.1} on {dof} bins");
    // chi2 of dof bins: mean dof, standard deviation sqrt(2 dof); 5 of those above.
    let bound = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt();
    assert!(c < bound, "chi2 {c:.1} on {dof} bins (bound {bound:.1})");
    for (name, wrong) in [
        ("B-B contact", expected(law(1, 1, 1.5, 1.5), l, bins)),
        ("ideal gas", expected(|_| 0.0, l, bins)),
    ] {
        let (c, dof) = chi2(&hist, &wrong);
        println!("{name}: chi2 {c:.1} on {dof} bins");
        assert!(c > 10.0 * bound, "{name}: chi2 {c:.1} on {dof} bins");
    }
}

/// The range sets the cells; a box shorter than twice the range, a droplet reached by the
/// pair beyond its margin and event chains are refused naming what to change; coincident
/// spheres of a Lennard-Jones core are an infinite energy, refused.
#[test]
fn a_pair_the_cells_or_the_box_cannot_resolve_is_refused() {
    let long = PairSpec::Morse {
        depth: 1.0,
        kappa: 1.0,
        h0: 0.0,
        h_cut: 6.0,
    };
    let (params, pos) = two_species(16.0, 1);
    let mc = HardSphereMc::with_pair(&params, &pos, "test", &long, 1.0).unwrap();
    assert!(mc.cell_side() >= 7.5, "{}", mc.cell_side());
    // Twice the range 7.5 (B-B contact 1.5 plus 6) is the shortest box.
    let (small, pos) = two_species(15.0, 1);
    HardSphereMc::with_pair(&small, &pos, "test", &long, 1.0).unwrap();
    let short = McParams {
        geometry: Geometry::Bulk { edge: 14.9 },
        ..small.clone()
    };
    let e = HardSphereMc::with_pair(&short, &pos, "test", &long, 1.0)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("box: the periodic box edge 14"), "{e}");
    let droplet = McParams {
        geometry: Geometry::HardWall { radius: 5.0 },
        ..small.clone()
    };
    let far = PairSpec::Morse {
        depth: 1.0,
        kappa: 1.0,
        h0: 0.0,
        h_cut: 11.0,
    };
    let e = HardSphereMc::with_pair(&droplet, &pos, "test", &far, 1.0)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("pair_range: the pair interaction reaches 12.5"),
        "{e}"
    );
    let mut mc = HardSphereMc::with_pair(&droplet, &pos, "test", &long, 1.0).unwrap();
    let e = mc
        .set_event_chain(Some(colloidsim_mc::EventChain {
            length: 1.0,
            chains_per_sweep: 1,
        }))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("move: event chains"), "{e}");
    let e = HardSphereMc::with_pair(
        &small,
        &[[1.0, 1.0, 1.0], [1.0, 1.0, 1.0]],
        "system.initial",
        &PairSpec::wca(1.0, 2),
        1.0,
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("system.initial: spheres 0 and 1"), "{e}");
}

/// WCA spheres (kT = 1) of d = 1 and 1.2, `counts` of each, on an FCC lattice of neighbour
/// distance `a` in a periodic cube of edge `l`.
fn wca_mixture(l: f64, a: f64, counts: [usize; 2], seed: u32) -> HardSphereMc {
    let pos = colloidsim_mc::init::fcc_in_box(counts[0] + counts[1], a, l).unwrap();
    let params = McParams {
        diameter: 1.0,
        geometry: Geometry::Bulk { edge: l },
        seed,
        delta: 0.1,
        mixture: Some(Mixture::new(vec![1.0, 1.2], counts.to_vec())),
    };
    HardSphereMc::with_pair(&params, &pos, "test", &PairSpec::wca(1.0, 2), 1.0).unwrap()
}

/// In a dense soft-sphere mixture (WCA, sizes 1 and 1.2, four cells a side) the accepted
/// moves' energy changes add up to the change of the total pair energy, sweep by sweep: no
/// neighbour within the range of the old or the new position is missed.
#[test]
fn the_moves_energy_changes_add_up_to_the_total_energy_change() {
    let mut mc = wca_mixture(10.0, 1.1, [500, 200], 9);
    assert!(mc.cells_per_edge() >= 4, "{}", mc.cells_per_edge());
    mc.warm_up(100, 20, 0.3);
    let mut u = mc.pair_energy_and_virial().unwrap().0;
    for _ in 0..50 {
        let s = mc.sweep();
        assert!(s.accepted > 0);
        let after = mc.pair_energy_and_virial().unwrap().0;
        let du = mc.last_pair_energy_change().unwrap();
        assert!(
            (after - u - du).abs() < 1e-9 * u.abs().max(1.0),
            "sweep {}: total change {} vs the moves' {du}",
            mc.sweeps(),
            after - u
        );
        u = after;
    }
}

/// A soft-sphere fluid (WCA, a mixture) gives the same positions on one and two threads.
#[test]
fn soft_runs_do_not_depend_on_the_thread_count() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut mc = wca_mixture(8.0, 1.2, [150, 50], 3);
                let s = mc.run(50);
                assert!(s.accepted > 0 && s.accepted < s.trials, "{s:?}");
                let (u, w) = mc.pair_energy_and_virial().unwrap();
                assert!(u.is_finite() && w > 0.0, "{u} {w}");
                mc.positions().map(|p| p.to_vec())
            })
    };
    assert_eq!(run(1), run(2));
}

/// The pair forces are minus the gradient of the pair energy (central differences, across
/// the periodic boundary too), and the virial is `r F(r)` of the pair.
#[test]
fn pair_forces_are_minus_the_energy_gradient() {
    let l = 6.0;
    let (params, _) = two_species(l, 1);
    let at = |q: [f64; 3]| {
        HardSphereMc::with_pair(&params, &[[2.9, 0.0, 0.0], q], "test", &morse(), 1.0).unwrap()
    };
    // The B sphere 1.3 away across the box face at x = +-3.
    let q = [-2.0 + 0.2, 0.3, -0.4];
    let mc = at(q);
    let f = mc.pair_forces().unwrap();
    let (_, w) = mc.pair_energy_and_virial().unwrap();
    let h = 1e-6;
    for k in 0..3 {
        let (mut a, mut b) = (q, q);
        a[k] += h;
        b[k] -= h;
        let grad = (at(a).pair_energy_and_virial().unwrap().0
            - at(b).pair_energy_and_virial().unwrap().0)
            / (2.0 * h);
        assert!(
            (f[1][k] + grad).abs() < 1e-6,
            "{k}: {} vs {}",
            f[1][k],
            -grad
        );
        assert_eq!(f[0][k], -f[1][k]);
    }
    let r = [2.9 - q[0] - l, -q[1], -q[2]];
    let rf: f64 = (0..3).map(|k| r[k] * f[0][k]).sum();
    assert!((rf - w).abs() < 1e-12 * w.abs().max(1.0), "{rf} vs {w}");
    assert!(w.abs() > 0.1, "{w}");
}
