//! Contact networks: coordination numbers, clusters (connected components) and bond lifetimes.

/// Coordination number of each of `n` particles: the number of bonds it takes part in,
///
/// ```text
/// z_i = #{ b : b = (i, j) or b = (j, i) }
/// ```
///
/// Every bond `(i, j)` adds one to `z_i` and one to `z_j`, so `sum_i z_i = 2 * bonds.len()`;
/// pass each bond once (as [`contacts`](crate::contacts) does).
///
/// Panics if an index is `>= n` or a bond joins a particle to itself.
pub fn coordination_numbers(n: usize, bonds: &[(u32, u32)]) -> Vec<u32> {
    let mut z = vec![0u32; n];
    for &(i, j) in bonds {
        assert!(i != j, "bond ({i}, {j}) joins a particle to itself");
        z[i as usize] += 1;
        z[j as usize] += 1;
    }
    z
}

/// Histogram of coordination numbers: entry `k` is the number of particles with `z = k`,
/// for `k = 0 ..= max z` (empty for no particles). Divide by `z.len()` for the distribution
/// `P(z)`.
pub fn coordination_histogram(z: &[u32]) -> Vec<u64> {
    let Some(&max) = z.iter().max() else {
        return Vec::new();
    };
    let mut h = vec![0u64; max as usize + 1];
    for &k in z {
        h[k as usize] += 1;
    }
    h
}

/// Disjoint-set forest with union by size and path halving.
struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    fn find(&mut self, mut i: u32) -> u32 {
        while self.parent[i as usize] != i {
            let p = self.parent[i as usize];
            self.parent[i as usize] = self.parent[p as usize];
            i = p;
        }
        i
    }

    fn union(&mut self, a: u32, b: u32) {
        let (mut ra, mut rb) = (self.find(a), self.find(b));
        if ra == rb {
            return;
        }
        if self.size[ra as usize] < self.size[rb as usize] {
            std::mem::swap(&mut ra, &mut rb);
        }
        self.parent[rb as usize] = ra;
        self.size[ra as usize] += self.size[rb as usize];
    }
}

/// Cluster (connected component) label of each of `n` particles joined by `bonds`: clusters are
/// numbered `0, 1, ...` in the order of their lowest-indexed particle, so particle 0 is always in
/// cluster 0. A particle without bonds is a cluster of its own.
///
/// Panics if an index is `>= n`, or if `n > u32::MAX`.
pub fn cluster_labels(n: usize, bonds: &[(u32, u32)]) -> Vec<u32> {
    assert!(u32::try_from(n).is_ok(), "at most u32::MAX particles");
    let mut uf = UnionFind::new(n);
    for &(i, j) in bonds {
        assert!(
            (i as usize) < n && (j as usize) < n,
            "bond ({i}, {j}) out of range for {n} particles"
        );
        uf.union(i, j);
    }
    let mut label_of_root = vec![u32::MAX; n];
    let mut next = 0u32;
    (0..n as u32)
        .map(|i| {
            let r = uf.find(i) as usize;
            if label_of_root[r] == u32::MAX {
                label_of_root[r] = next;
                next += 1;
            }
            label_of_root[r]
        })
        .collect()
}

/// Summary of the clusters (connected components) of a bond network; see [`cluster_stats`].
#[derive(Debug, Clone, PartialEq)]
pub struct ClusterStats {
    /// Number of clusters, isolated particles included.
    pub n_clusters: usize,
    /// Number of particles in the largest cluster (0 for no particles).
    pub largest: usize,
    /// Mean coordination number `<z> = 2 * bonds / n` (0 for no particles).
    pub mean_degree: f64,
    /// Cluster sizes (particles per cluster), largest first; they sum to `n`.
    pub sizes: Vec<usize>,
}

impl ClusterStats {
    /// Number of clusters of each size: entry `s` counts the clusters of `s` particles, for
    /// `s = 0 ..= largest` (entry 0 is always 0).
    pub fn size_histogram(&self) -> Vec<u64> {
        let mut h = vec![0u64; self.largest + 1];
        for &s in &self.sizes {
            h[s] += 1;
        }
        h
    }

    /// Weight-average cluster size `sum_s s^2 n_s / sum_s s n_s`: the mean size of the cluster a
    /// randomly chosen particle belongs to (0 for no particles).
    pub fn weight_average_size(&self) -> f64 {
        let n: usize = self.sizes.iter().sum();
        if n == 0 {
            return 0.0;
        }
        self.sizes.iter().map(|&s| (s * s) as f64).sum::<f64>() / n as f64
    }
}

/// Clusters of `n` particles joined by `bonds` (union-find, O(n + bonds)): a cluster is a set of
/// particles connected by a path of bonds; a particle without bonds is a cluster of size 1.
///
/// Panics as [`cluster_labels`].
pub fn cluster_stats(n: usize, bonds: &[(u32, u32)]) -> ClusterStats {
    let labels = cluster_labels(n, bonds);
    let n_clusters = labels.iter().max().map_or(0, |&m| m as usize + 1);
    let mut sizes = vec![0usize; n_clusters];
    for &c in &labels {
        sizes[c as usize] += 1;
    }
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    ClusterStats {
        n_clusters,
        largest: sizes.first().copied().unwrap_or(0),
        mean_degree: if n == 0 {
            0.0
        } else {
            2.0 * bonds.len() as f64 / n as f64
        },
        sizes,
    }
}

/// Lifetimes of bonds over a sequence of frames.
///
/// Feed it the bond list of each frame in turn ([`BondTracker::update`]). A bond present in
/// frames `f0, f0 + 1, ..., f1 - 1` and absent in frame `f1` broke with lifetime `f1 - f0`
/// frames (multiply by the time between frames for a time). A bond that breaks and re-forms
/// starts a new life. Bonds already present in the first frame have an unknown birth; their
/// lifetimes are lower bounds and are kept apart ([`BondTracker::censored_lifetimes`]).
#[derive(Debug, Clone, Default)]
pub struct BondTracker {
    frames: u64,
    /// Bonds of the last frame with the frame in which each was born, sorted.
    alive: Vec<((u32, u32), u64)>,
    next: Vec<((u32, u32), u64)>,
    lifetimes: Vec<u64>,
    censored: Vec<u64>,
}

impl BondTracker {
    /// An empty tracker (no frame seen yet).
    pub fn new() -> Self {
        Self::default()
    }

    /// Add the next frame's bonds, sorted and without repeats (as [`contacts`](crate::contacts)
    /// returns them). O(old + new bonds).
    ///
    /// Panics if `bonds` is not strictly increasing.
    pub fn update(&mut self, bonds: &[(u32, u32)]) {
        assert!(
            bonds.windows(2).all(|w| w[0] < w[1]),
            "bonds must be sorted and without repeats"
        );
        let f = self.frames;
        self.next.clear();
        let (mut a, mut b) = (0, 0);
        let old = &self.alive;
        while a < old.len() || b < bonds.len() {
            let take_old = b == bonds.len() || (a < old.len() && old[a].0 < bonds[b]);
            let take_new = a == old.len() || (b < bonds.len() && bonds[b] < old[a].0);
            if take_old {
                // Broke in this frame.
                let (_, born) = old[a];
                if born == 0 {
                    self.censored.push(f - born);
                } else {
                    self.lifetimes.push(f - born);
                }
                a += 1;
            } else if take_new {
                self.next.push((bonds[b], f));
                b += 1;
            } else {
                self.next.push(old[a]);
                a += 1;
                b += 1;
            }
        }
        std::mem::swap(&mut self.alive, &mut self.next);
        self.frames += 1;
    }

    /// Number of frames seen.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Lifetimes (in frames) of the bonds that formed after the first frame and have broken, in
    /// the order they broke.
    pub fn lifetimes(&self) -> &[u64] {
        &self.lifetimes
    }

    /// Lifetimes (in frames) of the broken bonds that were already present in the first frame:
    /// lower bounds of their true lifetimes.
    pub fn censored_lifetimes(&self) -> &[u64] {
        &self.censored
    }

    /// Bonds of the last frame with their age so far in frames (1 for a bond born in the last
    /// frame), sorted by bond.
    pub fn alive(&self) -> impl Iterator<Item = ((u32, u32), u64)> + '_ {
        self.alive.iter().map(|&(b, born)| (b, self.frames - born))
    }
}
