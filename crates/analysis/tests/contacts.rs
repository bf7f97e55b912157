//! The cell-list contact search against a brute-force double loop on random configurations:
//! monodisperse, polydisperse, orthorhombic, small boxes (edges without cell division) and
//! particles exactly on the box edges or in other periodic images.

use colloidsim_analysis::{contacts, coordination_numbers};
use colloidsim_core::rng::{Purpose, stream};
use rand::RngExt;

/// Every pair i < j with minimum-image gap below h_max, by the definition.
fn brute_force(pos: &[[f64; 3]], a: &[f64], l: [f64; 3], h_max: f64) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for i in 0..pos.len() {
        for j in (i + 1)..pos.len() {
            let mut d2 = 0.0;
            for k in 0..3 {
                let d = pos[i][k] - pos[j][k];
                let d = d - l[k] * (d / l[k]).round();
                d2 += d * d;
            }
            if d2.sqrt() - (a[i] + a[j]) < h_max {
                out.push((i as u32, j as u32));
            }
        }
    }
    out
}

/// `n` uniform positions in [lo, lo + L) per axis and radii uniform in [a_min, a_max].
fn random_config(
    n: usize,
    l: [f64; 3],
    lo: f64,
    a_min: f64,
    a_max: f64,
    seed: u32,
) -> (Vec<[f64; 3]>, Vec<f64>) {
    let mut rng = stream(seed, 0, Purpose::Initial, 0);
    let pos = (0..n)
        .map(|_| std::array::from_fn(|k| lo + rng.random::<f64>() * l[k]))
        .collect();
    let a = (0..n)
        .map(|_| a_min + (a_max - a_min) * rng.random::<f64>())
        .collect();
    (pos, a)
}

fn check(pos: &[[f64; 3]], a: &[f64], l: [f64; 3], h_max: f64, what: &str) -> usize {
    let fast = contacts(pos, a, l, h_max);
    let slow = brute_force(pos, a, l, h_max);
    assert_eq!(fast, slow, "{what}");
    fast.len()
}

#[test]
fn monodisperse_random_configurations_match_brute_force() {
    for seed in 0..2 {
        let l = [20.0; 3];
        let (pos, a) = random_config(2000, l, 0.0, 0.5, 0.5, seed);
        let m = check(&pos, &a, l, 0.1, "monodisperse");
        assert!(m > 100, "too few contacts to test anything: {m}");
    }
}

#[test]
fn polydisperse_orthorhombic_configurations_match_brute_force() {
    // Radii from 0.05 to 1.2: the cell size is set by the largest pair; the centred box
    // [-L/2, L/2) tests the wrapping of negative coordinates.
    let l = [14.0, 18.0, 23.0];
    for (seed, h_max) in [(10, 0.0), (11, 0.3), (12, -0.2)] {
        let (pos, a) = random_config(2000, l, -0.5 * l[0], 0.05, 1.2, seed);
        let m = check(&pos, &a, l, h_max, "polydisperse");
        assert!(m > 100, "{m}");
    }
}

#[test]
fn small_and_thin_boxes_match_brute_force() {
    // rc = 2 * 0.8 + 0.25 = 1.85: a 4.5 cube has 2 cells per edge (not divided: O(N^2)); the
    // slabs have one or two undivided edges beside divided ones.
    for (l, seed) in [
        ([4.5, 4.5, 4.5], 20),
        ([3.0, 20.0, 20.0], 21),
        ([20.0, 5.0, 3.9], 22),
        ([1.0, 1.0, 30.0], 23),
    ] {
        let (pos, a) = random_config(600, l, 0.0, 0.3, 0.8, seed);
        check(&pos, &a, l, 0.25, &format!("box {l:?}"));
    }
}

#[test]
fn particles_on_box_edges_and_in_other_images() {
    // A simple cubic lattice touching exactly (spacing 2a) with sites on x = 0 and neighbours
    // across the periodic boundary; every other particle shifted by whole box lengths.
    let (nside, s) = (6usize, 1.0);
    let l = [nside as f64 * s; 3];
    let mut pos = Vec::new();
    for i in 0..nside {
        for j in 0..nside {
            for k in 0..nside {
                let shift = |m: usize| {
                    if (i + j + k + m).is_multiple_of(2) {
                        0.0
                    } else {
                        -l[0]
                    }
                };
                pos.push([
                    i as f64 * s + shift(0),
                    j as f64 * s + 2.0 * shift(1),
                    k as f64 * s - shift(2),
                ]);
            }
        }
    }
    let a = vec![0.5 * s; pos.len()];
    let bonds = contacts(&pos, &a, l, 1e-9);
    assert_eq!(bonds, brute_force(&pos, &a, l, 1e-9));
    let z = coordination_numbers(pos.len(), &bonds);
    assert!(z.iter().all(|&z| z == 6), "{z:?}");
    // A touching lattice with h_max = -1e-9 has no contacts.
    assert!(contacts(&pos, &a, l, -1e-9).is_empty());

    // Random particles with coordinates snapped to -L/2, 0, L/2, L (the same planes of the
    // periodic box), or just below L.
    let l = [12.0, 13.0, 14.0];
    for seed in 30..32 {
        let mut rng = stream(seed, 0, Purpose::Initial, 1);
        let (mut pos, a) = random_config(1500, l, 0.0, 0.2, 0.6, seed);
        for x in pos.iter_mut() {
            for k in 0..3 {
                x[k] = match rng.random_range(0..6) {
                    0 => -0.5 * l[k],
                    1 => 0.0,
                    2 => 0.5 * l[k],
                    3 => l[k],
                    4 => l[k] * (1.0 - f64::EPSILON),
                    _ => x[k],
                };
            }
        }
        let m = check(&pos, &a, l, 0.1, "edges");
        assert!(m > 100, "{m}");
    }
}

#[test]
fn degenerate_inputs() {
    assert!(contacts(&[], &[], [5.0; 3], 1.0).is_empty());
    assert!(contacts(&[[0.0; 3]], &[1.0], [5.0; 3], 1.0).is_empty());
    // 2 a_max + h_max <= 0: nothing can be in contact.
    assert!(contacts(&[[0.0; 3], [0.0; 3]], &[0.5, 0.5], [5.0; 3], -1.0).is_empty());
    // Point particles (a = 0) within h_max.
    assert_eq!(
        contacts(&[[0.0; 3], [4.9, 0.0, 0.0]], &[0.0, 0.0], [5.0; 3], 0.2),
        vec![(0, 1)]
    );
}
