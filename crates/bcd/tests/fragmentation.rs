//! The pair-fragmentation procedure yields the exact fragmentation: the unique composition that
//! satisfies the non-splitting conditions (fast-bcd Eq. 4a) and the splitting conditions (4b),
//! checked by enumerating all 2^(n-1) compositions of small clusters.

use colloidsim_bcd::cluster::{FragmentScratch, fragment};
use proptest::prelude::*;

fn mean(f: &[f64]) -> f64 {
    f.iter().sum::<f64>() / f.len() as f64
}

/// Does the composition (cut after the indices in `cuts`) satisfy Eqs. (4a) and (4b)?
fn satisfies(f: &[f64], parts: &[(usize, usize)]) -> bool {
    for &(a, b) in parts {
        for l in a + 1..b {
            // (4a): left part of a subcluster does not move slower than its right part.
            if mean(&f[a..l]) < mean(&f[l..b]) {
                return false;
            }
        }
    }
    // (4b): consecutive subclusters separate.
    parts
        .windows(2)
        .all(|w| mean(&f[w[0].0..w[0].1]) < mean(&f[w[1].0..w[1].1]))
}

/// The paper's successive pair fragmentation (fast-bcd Sec. III, Eqs. 7–8): split where the
/// mean velocity right minus left is largest and positive (leftmost on ties), recurse.
fn greedy(f: &[f64], a: usize, b: usize, out: &mut Vec<(usize, usize)>) {
    let mut best = 0.0;
    let mut split = None;
    for j in a + 1..b {
        let d = mean(&f[j..b]) - mean(&f[a..j]);
        if d > best {
            best = d;
            split = Some(j);
        }
    }
    match split {
        Some(j) => {
            greedy(f, a, j, out);
            greedy(f, j, b, out);
        }
        None => out.push((a, b)),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]
    /// The O(n) hull construction equals the paper's successive pair fragmentation, also for
    /// large clusters.
    #[test]
    fn hull_equals_successive_pair_fragmentation(
        f in prop::collection::vec(-10.0f64..10.0, 1..300)
    ) {
        let mut ours = Vec::new();
        fragment(&f, false, false, &mut FragmentScratch::default(), |a, len, _, _| {
            ours.push((a, a + len))
        });
        let mut paper = Vec::new();
        greedy(&f, 0, f.len(), &mut paper);
        prop_assert_eq!(ours, paper);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    #[test]
    fn pair_fragmentation_is_the_unique_exact_fragmentation(
        f in prop::collection::vec(-10.0f64..10.0, 1..10)
    ) {
        let n = f.len();
        let mut ours = Vec::new();
        fragment(&f, false, false, &mut FragmentScratch::default(), |a, len, v, _| {
            ours.push((a, a + len, v))
        });
        let our_parts: Vec<(usize, usize)> = ours.iter().map(|p| (p.0, p.1)).collect();
        prop_assert!(satisfies(&f, &our_parts), "ours violates Eq. 4: {our_parts:?}");
        for (a, b, v) in &ours {
            prop_assert!((v - mean(&f[*a..*b])).abs() < 1e-12);
        }
        let mut valid = 0;
        for mask in 0u32..(1 << (n - 1)) {
            let mut parts = Vec::new();
            let mut a = 0;
            for j in 1..n {
                if mask & (1 << (j - 1)) != 0 {
                    parts.push((a, j));
                    a = j;
                }
            }
            parts.push((a, n));
            if satisfies(&f, &parts) {
                valid += 1;
                prop_assert_eq!(&parts, &our_parts);
            }
        }
        prop_assert_eq!(valid, 1);
    }
}
