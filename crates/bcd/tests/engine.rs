//! Engine tests: the premerged step against the chronological oracle, hard-core and wall
//! constraints, restart and thread-count identity, and bad input.

use colloidsim_bcd::forces::{NoField, NoPair, Sticky};
use colloidsim_bcd::{Bcd, BcdConfig, BcdError, Boundary, Update, init};
use proptest::prelude::*;

fn config(n_len: f64, sigma: f64, dt: f64, boundary: Boundary, update: Update) -> BcdConfig {
    BcdConfig {
        length: n_len,
        sigma,
        mobility: 1.0,
        kt: 1.0,
        dt,
        boundary,
        seed: 11,
        update,
    }
}

/// A rugged external force so that clusters fragment and collide in every step.
fn rugged(x: f64) -> f64 {
    3.0 * (2.3 * x).sin() + 1.5 * (7.1 * x + 0.3).cos()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    /// Premerging equals the chronological event-driven update to rounding (fast-bcd Sec. IV),
    /// on dense random configurations, rings and walls, with and without sticky contacts.
    #[test]
    fn premerge_equals_chronological(
        n in 2usize..40,
        fill in 0.5f64..0.97,
        dt in prop::sample::select(vec![1e-3, 1e-2, 5e-2]),
        seed in 0u32..1000,
        walls in any::<bool>(),
        sticky in any::<bool>(),
        steps in 1usize..4,
    ) {
        let sigma = 1.0;
        let length = n as f64 * sigma / fill;
        let boundary = if walls { Boundary::Walls } else { Boundary::Periodic };
        let mut a_cfg = config(length, sigma, dt, boundary, Update::Premerge);
        a_cfg.seed = seed;
        let mut b_cfg = a_cfg.clone();
        b_cfg.update = Update::Chronological;
        let x0 = init::random(&a_cfg, n, seed).unwrap();
        let st = Sticky::new(1.0, 0.05, 3.0, sigma, 1.0).unwrap();
        let (xa, xb, ba, bb) = if sticky {
            let mut a = Bcd::new(a_cfg, x0.clone(), rugged, st).unwrap();
            let mut b = Bcd::new(b_cfg, x0, rugged, st).unwrap();
            for _ in 0..steps {
                // Same starting state each step so that rounding cannot change cluster structure.
                let s = a.state().clone();
                b = Bcd::from_state(b.config().clone(), s, rugged, st).unwrap();
                a.step().unwrap();
                b.step().unwrap();
            }
            (a.positions().to_vec(), b.positions().to_vec(), a.state().bond.clone(), b.state().bond.clone())
        } else {
            let mut a = Bcd::new(a_cfg, x0.clone(), rugged, NoPair).unwrap();
            let mut b = Bcd::new(b_cfg, x0, rugged, NoPair).unwrap();
            for _ in 0..steps {
                let s = a.state().clone();
                b = Bcd::from_state(b.config().clone(), s, rugged, NoPair).unwrap();
                a.step().unwrap();
                b.step().unwrap();
            }
            prop_assert!(a.min_clearance() > -1e-9);
            (a.positions().to_vec(), b.positions().to_vec(), a.state().bond.clone(), b.state().bond.clone())
        };
        for i in 0..n {
            prop_assert!((xa[i] - xb[i]).abs() < 1e-9 * length, "rod {i}: {} vs {}", xa[i], xb[i]);
        }
        prop_assert_eq!(ba, bb);
    }
}

#[test]
fn hard_core_and_walls_hold_in_every_step() {
    for boundary in [Boundary::Periodic, Boundary::Walls] {
        let cfg = config(55.0, 1.0, 5e-3, boundary, Update::Premerge);
        let x = init::random(&cfg, 50, 5).unwrap();
        let mut bcd = Bcd::new(cfg, x, |x: f64| 4.0 * (x * 0.7).sin() + 0.5, NoPair).unwrap();
        for _ in 0..5000 {
            bcd.step().unwrap();
            let c = bcd.min_clearance();
            assert!(
                c > -1e-9,
                "{boundary:?}: clearance {c} at step {}",
                bcd.steps()
            );
        }
    }
}

#[test]
fn zero_temperature_gives_deterministic_cluster_motion() {
    // Two rods driven towards each other by opposite forces meet, then stop (mean force 0).
    let mut cfg = config(100.0, 1.0, 0.01, Boundary::Walls, Update::Premerge);
    cfg.kt = 0.0;
    let f = |x: f64| if x < 50.0 { 1.0 } else { -1.0 };
    let mut bcd = Bcd::new(cfg, vec![45.0, 55.0], f, NoPair).unwrap();
    bcd.run(1000).unwrap();
    let x = bcd.positions();
    assert!(
        (x[0] - 49.5).abs() < 1e-9 && (x[1] - 50.5).abs() < 1e-9,
        "{x:?}"
    );
    let mut sizes = vec![];
    bcd.cluster_sizes(|s| sizes.push(s));
    assert_eq!(sizes, vec![2]);
}

#[test]
fn restart_from_state_is_bitwise_identical() {
    let cfg = config(120.0, 0.9, 1e-3, Boundary::Periodic, Update::Premerge);
    let x = init::random(&cfg, 100, 2).unwrap();
    let mut a = Bcd::new(cfg.clone(), x, NoField, NoPair).unwrap();
    a.run(300).unwrap();
    let saved = a.state().clone();
    a.run(300).unwrap();
    let mut b = Bcd::from_state(cfg, saved, NoField, NoPair).unwrap();
    b.run(300).unwrap();
    assert_eq!(a.state(), b.state());
}

#[test]
fn thread_count_does_not_change_the_result() {
    let cfg = config(10_000.0, 0.95, 1e-3, Boundary::Periodic, Update::Premerge);
    let x = init::random(&cfg, 10_000, 4).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut b = Bcd::new(cfg.clone(), x.clone(), |x: f64| 3.0 * x.sin(), NoPair).unwrap();
            b.run(200).unwrap();
            b.state().clone()
        })
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn bad_input_is_refused_naming_the_parameter() {
    let cfg = config(10.0, 1.0, 1e-3, Boundary::Periodic, Update::Premerge);
    let e = Bcd::new(cfg.clone(), vec![0.0; 10], NoField, NoPair)
        .err()
        .unwrap();
    assert!(e.to_string().starts_with("n: "), "{e}");
    let e = Bcd::new(cfg.clone(), vec![1.0, 1.5], NoField, NoPair)
        .err()
        .unwrap();
    assert!(
        matches!(e, BcdError::Positions(_)) && e.to_string().contains("overlap"),
        "{e}"
    );
    let e = Bcd::new(cfg.clone(), vec![0.2, 9.5], NoField, NoPair)
        .err()
        .unwrap();
    assert!(e.to_string().contains("seam"), "{e}");
    let mut bad = cfg.clone();
    bad.dt = 0.0;
    let e = Bcd::new(bad, vec![1.0], NoField, NoPair).err().unwrap();
    assert!(e.to_string().starts_with("dt: "), "{e}");
    let mut walls = cfg;
    walls.boundary = Boundary::Walls;
    let e = Bcd::new(walls, vec![0.2, 5.0], NoField, NoPair)
        .err()
        .unwrap();
    assert!(e.to_string().contains("between walls"), "{e}");
}

#[test]
fn non_finite_forces_stop_with_step_and_rod() {
    let cfg = config(100.0, 1.0, 1e-3, Boundary::Periodic, Update::Premerge);
    let f = |x: f64| if x > 30.0 { f64::NAN } else { 0.0 };
    let mut b = Bcd::new(cfg, vec![10.0, 20.0, 40.0], f, NoPair).unwrap();
    match b.step() {
        Err(BcdError::NonFinite { step, particle, .. }) => {
            assert_eq!((step, particle), (0, 2));
        }
        other => panic!("expected NonFinite, got {other:?}"),
    }
}

/// Premerging across chunk boundaries and the periodic seam (N spans several chunks) equals
/// the chronological update.
#[test]
fn premerge_across_chunks_equals_chronological() {
    use colloidsim_bcd::engine::CHUNK;
    for (boundary, seed) in [
        (Boundary::Periodic, 1),
        (Boundary::Walls, 2),
        (Boundary::Periodic, 3),
    ] {
        let n = 3 * CHUNK + 123;
        let length = n as f64 / 0.9;
        let mut a_cfg = config(length, 1.0, 2e-2, boundary, Update::Premerge);
        a_cfg.seed = seed;
        let mut b_cfg = a_cfg.clone();
        b_cfg.update = Update::Chronological;
        let x0 = init::random(&a_cfg, n, seed).unwrap();
        let mut a = Bcd::new(a_cfg, x0, rugged, NoPair).unwrap();
        let mut merged_across = 0;
        for _ in 0..3 {
            let mut b = Bcd::from_state(b_cfg.clone(), a.state().clone(), rugged, NoPair).unwrap();
            a.step().unwrap();
            b.step().unwrap();
            for i in 0..n {
                assert!(
                    (a.positions()[i] - b.positions()[i]).abs() < 1e-9 * length,
                    "{boundary:?} rod {i}: {} vs {}",
                    a.positions()[i],
                    b.positions()[i]
                );
            }
            assert_eq!(a.state().bond, b.state().bond);
            let mut big = 0;
            a.cluster_sizes(|s| big = big.max(s));
            merged_across = merged_across.max(big);
        }
        assert!(merged_across > 1);
    }
}

/// A strong force towards the periodic seam packs the ring into clusters longer than a chunk:
/// pooling cascades across several chunk boundaries and the seam, and must still equal the
/// chronological update.
#[test]
fn clusters_longer_than_a_chunk_equal_chronological() {
    use colloidsim_bcd::engine::CHUNK;
    let n = 3 * CHUNK + 123;
    let length = n as f64 / 0.9;
    let mut a_cfg = config(length, 1.0, 2e-2, Boundary::Periodic, Update::Premerge);
    a_cfg.seed = 9;
    let mut b_cfg = a_cfg.clone();
    b_cfg.update = Update::Chronological;
    let x0 = init::random(&a_cfg, n, 9).unwrap();
    let k = 2.0 * std::f64::consts::PI / length;
    // Neighbours close faster (A k gap / 1.1 per unit time) than their gaps allow for one step
    // wherever cos(k x) > 0: half the ring collapses towards the seam within a step or two.
    let f = move |x: f64| -5e4 * (k * x).sin();
    let mut a = Bcd::new(a_cfg, x0, f, NoPair).unwrap();
    let mut biggest = 0;
    for _ in 0..5 {
        let mut b = Bcd::from_state(b_cfg.clone(), a.state().clone(), f, NoPair).unwrap();
        a.step().unwrap();
        b.step().unwrap();
        for i in 0..n {
            assert!(
                (a.positions()[i] - b.positions()[i]).abs() < 1e-9 * length,
                "rod {i}: {} vs {}",
                a.positions()[i],
                b.positions()[i]
            );
        }
        assert_eq!(a.state().bond, b.state().bond);
        assert!(a.min_clearance() > -1e-9);
        a.cluster_sizes(|s| biggest = biggest.max(s));
    }
    assert!(biggest > CHUNK + CHUNK / 2, "largest cluster {biggest}");
}

/// A checkpointed ring state whose reduced coordinates do not match its positions is refused,
/// naming the rod; one without them (an older or hand-made state) is accepted.
#[test]
fn inconsistent_reduced_positions_are_refused() {
    let cfg = config(60.0, 1.0, 1e-3, Boundary::Periodic, Update::Premerge);
    let x = init::random(&cfg, 40, 9).unwrap();
    let mut a = Bcd::new(cfg.clone(), x, NoField, NoPair).unwrap();
    a.run(20).unwrap();
    let good = a.state().clone();
    assert_eq!(good.reduced.len(), 40);
    let mut bad = good.clone();
    bad.reduced[17] += 0.3;
    match Bcd::from_state(cfg.clone(), bad, NoField, NoPair) {
        Err(BcdError::Positions(m)) => assert!(m.contains("17"), "{m}"),
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("inconsistent reduced positions accepted"),
    }
    let mut plain = good.clone();
    plain.reduced.clear();
    let b = Bcd::from_state(cfg, plain, NoField, NoPair).unwrap();
    for (p, q) in a.positions().iter().zip(b.positions()) {
        assert!((p - q).abs() < 1e-12 * 60.0, "{p} vs {q}");
    }
    assert_eq!(a.state().bond, b.state().bond);
}

#[test]
fn ring_cluster_sizes_follow_the_bonds_of_the_state() {
    // The ring update reads clusters off equal reduced positions and the seam flag; they must
    // be the clusters of the derived state's bonds, including one across the seam.
    let cfg = config(105.0, 0.99, 1e-3, Boundary::Periodic, Update::Premerge);
    let x = init::random(&cfg, 100, 3).unwrap();
    let mut a = Bcd::new(cfg, x, NoField, NoPair).unwrap();
    let mut across_seam = 0;
    for _ in 0..200 {
        a.run(1).unwrap();
        let mut sizes = vec![];
        a.cluster_sizes(|s| sizes.push(s));
        let bond = &a.state().bond;
        let n = bond.len();
        let start = (0..n).find(|&i| bond[(i + n - 1) % n] == 0).unwrap_or(0);
        let (mut want, mut size) = (vec![], 0);
        for w in start..start + n {
            size += 1;
            if bond[w % n] == 0 {
                want.push(size);
                size = 0;
            }
        }
        if size > 0 {
            want.push(size);
        }
        across_seam += usize::from(bond[n - 1] != 0);
        assert_eq!(sizes, want);
        assert_eq!(sizes.iter().sum::<usize>(), n);
    }
    assert!(across_seam > 0, "no cluster crossed the seam");
}

#[test]
fn branch_free_cluster_histogram_equals_the_cluster_walk() {
    // Dense rods (many clusters, some across the seam) on a ring and between walls.
    // The chronological update keeps the bonds in the state on a ring too.
    for (boundary, update) in [
        (Boundary::Periodic, Update::Premerge),
        (Boundary::Walls, Update::Premerge),
        (Boundary::Periodic, Update::Chronological),
    ] {
        let cfg = config(105.0, 0.99, 1e-3, boundary, update);
        let x = init::random(&cfg, 100, 5).unwrap();
        let mut a = Bcd::new(cfg, x, NoField, NoPair).unwrap();
        let mut counts = Vec::new();
        let mut want: Vec<u64> = Vec::new();
        for _ in 0..300 {
            a.run(1).unwrap();
            a.count_cluster_sizes(&mut counts);
            a.cluster_sizes(|s| {
                if want.len() <= s {
                    want.resize(s + 1, 0);
                }
                want[s] += 1;
            });
            want.resize(counts.len().max(want.len()), 0);
            assert_eq!(
                counts,
                want,
                "{boundary:?} {update:?} at step {}",
                a.steps()
            );
        }
    }
    // Several chunks of the ring update (clusters pooled across chunk boundaries and the
    // seam): the histogram from the pooled blocks equals the walk over the state, and so does
    // the one from the positions before the first step.
    let n = 3 * 4096 + 1000; // the ring update works in chunks of 4096 rods
    let cfg = config(
        1.01 * n as f64,
        0.99,
        1e-3,
        Boundary::Periodic,
        Update::Premerge,
    );
    // Pools of 1, 2 and 3 workers: the blocks are counted in parts of whole chunks.
    for workers in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(workers)
            .build()
            .unwrap();
        let x = init::random(&cfg, n, 8).unwrap();
        let mut a = Bcd::new(cfg.clone(), x, NoField, NoPair).unwrap();
        pool.install(|| {
            for step in 0..40 {
                if step > 0 {
                    a.run(1).unwrap();
                }
                let mut counts = Vec::new();
                a.count_cluster_sizes(&mut counts);
                let mut want = vec![0u64; counts.len()];
                a.cluster_sizes(|s| want[s] += 1);
                assert_eq!(counts, want, "{n} rods at step {step}, {workers} workers");
            }
        });
    }
    // One cluster of every rod round the ring (nothing ends): dense rods, long steps.
    let cfg = config(10.0, 0.99, 1.0, Boundary::Periodic, Update::Premerge);
    let x = init::random(&cfg, 10, 1).unwrap();
    let mut a = Bcd::new(cfg, x, NoField, NoPair).unwrap();
    let mut seen = false;
    for _ in 0..200 {
        a.run(1).unwrap();
        let mut walk = Vec::new();
        a.cluster_sizes(|s| walk.push(s));
        if walk == [10] {
            let mut counts = Vec::new();
            a.count_cluster_sizes(&mut counts);
            assert_eq!(counts.iter().sum::<u64>(), 1);
            assert_eq!(counts[10], 1);
            seen = true;
        }
    }
    assert!(seen, "the ring never formed one cluster");
}
