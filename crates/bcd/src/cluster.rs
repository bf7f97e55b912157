//! Clusters of rods in contact: fragmentation by successive pair splitting and premerging.
//!
//! Notation (fast-bcd paper): a cluster is a run of rods in contact that moves rigidly with the
//! mean velocity of its members, Eq. (5)/(6). Hard walls are clusters of infinite mass that never
//! move: a rod stuck to a wall has velocity zero until its force pulls it away.

/// Which wall, if any, a cluster is stuck to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum Wall {
    /// Free cluster.
    #[default]
    None = 0,
    /// Packed against the left wall (velocity 0).
    Left = 1,
    /// Packed against the right wall (velocity 0).
    Right = 2,
}

/// A cluster during one time step: `n` rods starting at ring index `start` (virtual index,
/// may exceed N for clusters crossing the periodic seam), leftmost rod centre at `left`
/// (unwrapped, at the start of the step, possibly a virtual premerged position), velocity `v`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Cluster {
    /// Virtual index of the leftmost rod.
    pub start: u32,
    /// Number of rods (0 for a bare wall).
    pub n: u32,
    /// Centre of the leftmost rod.
    pub left: f64,
    /// Velocity (mean of the member velocities, Eq. 5).
    pub v: f64,
    /// Wall the cluster is stuck to.
    pub wall: Wall,
}

impl Cluster {
    /// Centre of mass for rods of length `sigma` (free clusters).
    #[inline]
    pub fn centre(&self, sigma: f64) -> f64 {
        self.left + 0.5 * (self.n as f64 - 1.0) * sigma
    }
}

/// Do clusters `a` (left) and `b` (right) collide within `dt`, neglecting all other clusters?
/// Gap `b.left - a.left - n_a sigma`, closing speed `v_a - v_b`; the collision time of
/// fast-bcd Eq. (20) must not exceed `dt`.
#[inline]
pub fn collide(a: &Cluster, b: &Cluster, sigma: f64, dt: f64) -> bool {
    let closing = a.v - b.v;
    closing > 0.0 && b.left - a.left - a.n as f64 * sigma <= closing * dt
}

/// Completely inelastic merger of `a` (left) and `b` (right), placed at their common centre of
/// mass with the mass-weighted velocity (fast-bcd Eq. 6); a wall absorbs the other cluster.
#[inline]
pub fn merge(a: &Cluster, b: &Cluster, sigma: f64) -> Cluster {
    let n = a.n + b.n;
    let start = if a.n == 0 { b.start } else { a.start };
    match (a.wall, b.wall) {
        (Wall::Left, _) => Cluster {
            start,
            n,
            left: a.left,
            v: 0.0,
            wall: Wall::Left,
        },
        (_, Wall::Right) => Cluster {
            start,
            n,
            left: b.left - a.n as f64 * sigma,
            v: 0.0,
            wall: Wall::Right,
        },
        _ => {
            let (na, nb) = (a.n as f64, b.n as f64);
            let nf = na + nb;
            let centre = (na * a.centre(sigma) + nb * b.centre(sigma)) / nf;
            Cluster {
                start,
                n,
                left: centre - 0.5 * (nf - 1.0) * sigma,
                v: (na * a.v + nb * b.v) / nf,
                wall: Wall::None,
            }
        }
    }
}

/// Push `c` onto the premerging stack and merge it with its left neighbours for as long as
/// they collide within `dt` (fast-bcd Sec. V): O(1) amortised per cluster.
#[inline]
pub fn premerge(stack: &mut Vec<Cluster>, c: Cluster, sigma: f64, dt: f64) {
    let mut top = c;
    while let Some(prev) = stack.last() {
        if collide(prev, &top, sigma, dt) {
            top = merge(prev, &top, sigma);
            stack.pop();
        } else {
            break;
        }
    }
    stack.push(top);
}

/// A run of rods moving together during fragmentation: `n` rods from virtual index `start`
/// (leftmost centre `left`), summed free velocity `sum`; wall blocks have infinite mass and
/// velocity 0.
#[derive(Debug, Clone, Copy)]
struct Block {
    start: u32,
    n: u32,
    sum: f64,
    left: f64,
    wall: Wall,
}

impl Block {
    /// Does `self` (left) keep contact with `b` (right), i.e. is its mean velocity not smaller?
    #[inline]
    fn holds(&self, b: &Block) -> bool {
        match (self.wall, b.wall) {
            (Wall::Left, _) => b.wall == Wall::Right || b.sum <= 0.0,
            (_, Wall::Right) => self.sum >= 0.0,
            _ => self.sum * b.n as f64 >= b.sum * self.n as f64,
        }
    }

    #[inline]
    fn join(&self, b: &Block) -> Block {
        let first = if self.n == 0 { b } else { self };
        Block {
            start: first.start,
            n: self.n + b.n,
            sum: self.sum + b.sum,
            left: first.left,
            wall: if self.wall != Wall::None {
                self.wall
            } else {
                b.wall
            },
        }
    }
}

/// Fragmentation of one cluster of touching rods, built rod by rod.
///
/// The exact fragmentation (fast-bcd Eqs. 4a/4b) has strictly increasing subcluster velocities
/// and, inside each subcluster, every leading part at least as fast as the rest. In terms of the
/// cumulative sums `S_k = sum_{i<k} u_i` of the free velocities this is the lower convex hull of
/// the points `(k, S_k)`: each subcluster is one hull edge, its velocity the edge slope. The hull
/// is built by pooling adjacent violators on a stack, O(1) amortised per rod, and equals the
/// paper's successive pair fragmentation (Eqs. 7–8; the tests check both against each other and
/// against all 2^(n-1) compositions). A wall on either side acts as a member of infinite mass
/// and velocity 0.
#[derive(Debug, Default, Clone)]
pub struct Hull {
    blocks: Vec<Block>,
}

/// Former name of [`Hull`], the reusable work space of [`fragment`].
pub type FragmentScratch = Hull;

impl Hull {
    /// Start a new cluster, stuck to the left wall or not.
    #[inline]
    pub fn begin(&mut self, left_wall: bool) {
        self.blocks.clear();
        if left_wall {
            self.blocks.push(Block {
                start: 0,
                n: 0,
                sum: 0.0,
                left: 0.0,
                wall: Wall::Left,
            });
        }
    }

    fn pool(&mut self, b: Block) {
        self.blocks.push(b);
        self.settle();
    }

    /// Merge the top block into the ones below for as long as they hold it.
    fn settle(&mut self) {
        while let [.., below, top] = self.blocks[..] {
            if below.holds(&top) {
                self.blocks.pop();
                *self.blocks.last_mut().expect("two blocks") = below.join(&top);
            } else {
                break;
            }
        }
    }

    /// Add the next rod (virtual index `start`, centre `left`, free velocity `u`).
    #[inline]
    pub fn push(&mut self, start: u32, left: f64, u: f64) {
        // Fast path: the rod is not faster than the free block before it, so it joins it;
        // the slowed-down block may then be caught by the one below (rare).
        if let Some(top) = self.blocks.last_mut()
            && top.wall == Wall::None
            && top.sum >= u * top.n as f64
        {
            top.sum += u;
            top.n += 1;
            if self.blocks.len() >= 2 {
                self.settle();
            }
            return;
        }
        self.pool(Block {
            start,
            n: 1,
            sum: u,
            left,
            wall: Wall::None,
        });
    }

    /// Close the cluster (stuck to the right wall or not) and emit its fragments left to right.
    #[inline]
    pub fn finish(&mut self, right_wall: bool, mut emit: impl FnMut(Cluster)) {
        if right_wall {
            self.pool(Block {
                start: 0,
                n: 0,
                sum: 0.0,
                left: 0.0,
                wall: Wall::Right,
            });
        }
        for b in self.blocks.iter().filter(|b| b.n > 0) {
            let v = if b.wall == Wall::None {
                b.sum / b.n as f64
            } else {
                0.0
            };
            emit(Cluster {
                start: b.start,
                n: b.n,
                left: b.left,
                v,
                wall: b.wall,
            });
        }
    }
}

/// Fragment one cluster of rods with free velocities `u` (`mu F_i`) into the subclusters that
/// move apart (see [`Hull`]), emitted left to right as `(first, len, velocity, wall)` with
/// `first` relative to `u`.
pub fn fragment(
    u: &[f64],
    left_wall: bool,
    right_wall: bool,
    scratch: &mut FragmentScratch,
    mut emit: impl FnMut(usize, usize, f64, Wall),
) {
    scratch.begin(left_wall);
    for (i, &ui) in u.iter().enumerate() {
        scratch.push(i as u32, 0.0, ui);
    }
    scratch.finish(right_wall, |c| {
        emit(c.start as usize, c.n as usize, c.v, c.wall)
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frags(u: &[f64]) -> Vec<(usize, usize, f64)> {
        let mut out = Vec::new();
        fragment(
            u,
            false,
            false,
            &mut FragmentScratch::default(),
            |a, n, v, _| out.push((a, n, v)),
        );
        out
    }

    #[test]
    fn paper_fig4_example() {
        // fast-bcd Fig. 4: velocities (-4, 1, 0, -10, 2, 1) fragment into 1 | 3 | 2.
        let f = frags(&[-4.0, 1.0, 0.0, -10.0, 2.0, 1.0]);
        assert_eq!(f, vec![(0, 1, -4.0), (1, 3, -3.0), (4, 2, 1.5)]);
    }

    #[test]
    fn paper_three_cluster_example_keeps_stable_contact() {
        // F1 = F3/4, F2 = 3 F3/2: two pair-splitting points but only contact 1|2 is unstable.
        let f = frags(&[0.25, 1.5, 1.0]);
        assert_eq!(f.len(), 2);
        assert_eq!((f[0].0, f[0].1), (0, 1));
        assert_eq!((f[1].0, f[1].1), (1, 2));
    }

    #[test]
    fn walls_hold_and_release() {
        let mut out = Vec::new();
        let mut s = FragmentScratch::default();
        // Pushed into the left wall: stays stuck.
        fragment(&[-1.0, -2.0], true, false, &mut s, |a, n, v, w| {
            out.push((a, n, v, w))
        });
        assert_eq!(out, vec![(0, 2, 0.0, Wall::Left)]);
        out.clear();
        // Second rod pulled away from the stuck first one.
        fragment(&[-1.0, 2.0], true, false, &mut s, |a, n, v, w| {
            out.push((a, n, v, w))
        });
        assert_eq!(out, vec![(0, 1, 0.0, Wall::Left), (1, 1, 2.0, Wall::None)]);
        out.clear();
        // Right wall: the first rod leaves, the second is pushed into the wall and stays.
        fragment(&[-1.0, 0.5], false, true, &mut s, |a, n, v, w| {
            out.push((a, n, v, w))
        });
        assert_eq!(
            out,
            vec![(0, 1, -1.0, Wall::None), (1, 1, 0.0, Wall::Right)]
        );
        out.clear();
        // Right wall: pulled away as a whole.
        fragment(&[-0.5, -1.0], false, true, &mut s, |a, n, v, w| {
            out.push((a, n, v, w))
        });
        assert_eq!(out, vec![(0, 2, -0.75, Wall::None)]);
    }

    #[test]
    fn merge_conserves_momentum_and_centre() {
        let s = 0.5;
        let a = Cluster {
            start: 0,
            n: 2,
            left: 0.0,
            v: 3.0,
            wall: Wall::None,
        };
        let b = Cluster {
            start: 2,
            n: 1,
            left: 1.2,
            v: -1.0,
            wall: Wall::None,
        };
        assert!(collide(&a, &b, s, 1.0));
        assert!(!collide(&a, &b, s, 0.049)); // gap 0.2, closing 4: collision at t = 0.05
        let m = merge(&a, &b, s);
        assert_eq!(m.n, 3);
        assert!((m.v - (2.0 * 3.0 - 1.0) / 3.0).abs() < 1e-15);
        let c0 = (2.0 * a.centre(s) + b.centre(s)) / 3.0;
        assert!((m.centre(s) - c0).abs() < 1e-15);
    }
}
