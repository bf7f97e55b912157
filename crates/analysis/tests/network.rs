//! Coordination numbers, clusters and bond lifetimes on hand-made graphs.

use colloidsim_analysis::{
    BondTracker, ClusterStats, cluster_labels, cluster_stats, coordination_histogram,
    coordination_numbers,
};

#[test]
fn coordination_of_a_chain_a_star_and_isolated_points() {
    // Chain 0-1-2-3, star 4-{5,6,7}, isolated 8 and 9.
    let bonds = [(0, 1), (1, 2), (2, 3), (4, 5), (4, 6), (4, 7)];
    let z = coordination_numbers(10, &bonds);
    assert_eq!(z, vec![1, 2, 2, 1, 3, 1, 1, 1, 0, 0]);
    assert_eq!(z.iter().sum::<u32>() as usize, 2 * bonds.len());
    assert_eq!(coordination_histogram(&z), vec![2, 5, 2, 1]);
    assert!(coordination_histogram(&[]).is_empty());
    assert_eq!(coordination_histogram(&[0, 0]), vec![2]);
}

#[test]
#[should_panic(expected = "itself")]
fn a_self_bond_is_rejected() {
    coordination_numbers(3, &[(1, 1)]);
}

#[test]
fn chain_is_one_cluster() {
    let bonds: Vec<(u32, u32)> = (0..9).map(|i| (i, i + 1)).collect();
    let s = cluster_stats(10, &bonds);
    assert_eq!(
        s,
        ClusterStats {
            n_clusters: 1,
            largest: 10,
            mean_degree: 1.8,
            sizes: vec![10],
        }
    );
    assert_eq!(cluster_labels(10, &bonds), vec![0; 10]);
}

#[test]
fn two_triangles_and_isolated_points() {
    // Triangles {1, 4, 7} and {2, 5, 8} (listed in mixed order, one bond reversed); 0, 3, 6
    // isolated.
    let bonds = [(4, 7), (1, 4), (7, 1), (2, 5), (5, 8), (2, 8)];
    let s = cluster_stats(9, &bonds);
    assert_eq!(s.n_clusters, 5);
    assert_eq!(s.largest, 3);
    assert_eq!(s.sizes, vec![3, 3, 1, 1, 1]);
    assert!((s.mean_degree - 12.0 / 9.0).abs() < 1e-15);
    assert_eq!(s.size_histogram(), vec![0, 3, 0, 2]);
    assert!((s.weight_average_size() - (3.0 + 2.0 * 9.0) / 9.0).abs() < 1e-15);
    // Labels in the order of each cluster's lowest particle.
    assert_eq!(cluster_labels(9, &bonds), vec![0, 1, 2, 3, 1, 2, 4, 1, 2]);
    // Joining the triangles by one bond merges them.
    let mut joined = bonds.to_vec();
    joined.push((8, 7));
    let s = cluster_stats(9, &joined);
    assert_eq!((s.n_clusters, s.largest), (4, 6));
    assert_eq!(s.sizes, vec![6, 1, 1, 1]);
}

#[test]
fn no_bonds_and_no_particles() {
    let s = cluster_stats(4, &[]);
    assert_eq!((s.n_clusters, s.largest, s.sizes), (4, 1, vec![1; 4]));
    assert_eq!(s.mean_degree, 0.0);
    let s = cluster_stats(0, &[]);
    assert_eq!((s.n_clusters, s.largest, s.mean_degree), (0, 0, 0.0));
    assert!(s.sizes.is_empty());
    assert_eq!(s.weight_average_size(), 0.0);
}

#[test]
fn long_random_chain_in_shuffled_order() {
    // A path through a permutation of 0..n with its bonds listed in a scrambled order: one
    // cluster whatever the order of the unions.
    let n = 10_000u32;
    let perm: Vec<u32> = (0..n).map(|i| (i * 7919) % n).collect(); // 7919 is prime to n
    let mut bonds: Vec<(u32, u32)> = perm.windows(2).map(|w| (w[0], w[1])).collect();
    let m = bonds.len();
    for k in 0..m {
        bonds.swap(k, (k * 104_729) % m);
    }
    let s = cluster_stats(n as usize, &bonds);
    assert_eq!((s.n_clusters, s.largest), (1, n as usize));
    let z = coordination_numbers(n as usize, &bonds);
    assert_eq!(coordination_histogram(&z), vec![0, 2, n as u64 - 2]);
}

#[test]
fn bond_lifetimes_in_frames() {
    let mut t = BondTracker::new();
    // frame:      0        1               2        3        4
    // (0,1):      x        x               x        .        .     -> censored 3
    // (0,2):      .        x               x        x        .     -> lifetime 3
    // (1,2):      .        x               .        x        x     -> lifetime 1, then alive 2
    // (3,4):      x        .               .        .        x     -> censored 1, then alive 1
    let frames: [&[(u32, u32)]; 5] = [
        &[(0, 1), (3, 4)],
        &[(0, 1), (0, 2), (1, 2)],
        &[(0, 1), (0, 2)],
        &[(0, 2), (1, 2)],
        &[(1, 2), (3, 4)],
    ];
    for f in frames {
        t.update(f);
    }
    assert_eq!(t.frames(), 5);
    assert_eq!(t.censored_lifetimes(), &[1, 3]);
    assert_eq!(t.lifetimes(), &[1, 3]);
    let alive: Vec<_> = t.alive().collect();
    assert_eq!(alive, vec![((1, 2), 2), ((3, 4), 1)]);
    // An empty frame breaks everything.
    t.update(&[]);
    assert_eq!(t.lifetimes(), &[1, 3, 2, 1]);
    assert_eq!(t.alive().count(), 0);
}

#[test]
#[should_panic(expected = "sorted")]
fn unsorted_bonds_are_rejected_by_the_tracker() {
    BondTracker::new().update(&[(1, 2), (0, 1)]);
}
