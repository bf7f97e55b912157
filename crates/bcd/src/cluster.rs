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

/// Reusable work space of [`fragment`].
#[derive(Debug, Default, Clone)]
pub struct FragmentScratch {
    prefix: Vec<f64>,
    segments: Vec<(u32, u32, bool, bool)>,
}

/// Fragment one cluster of rods with velocities `u` (the free velocities `mu F_i`) into the
/// subclusters that move apart, by successive pair fragmentation at the point of largest
/// positive difference of mean velocities right minus left, leftmost on ties (fast-bcd Eqs. 7–8;
/// the paper proves this yields the exact fragmentation, Eqs. 4a/4b). A wall on either side acts
/// as a member of infinite mass. Fragments are emitted left to right as
/// `(first, len, velocity, wall)` with `first` relative to `u`.
pub fn fragment(
    u: &[f64],
    left_wall: bool,
    right_wall: bool,
    scratch: &mut FragmentScratch,
    mut emit: impl FnMut(usize, usize, f64, Wall),
) {
    let n = u.len();
    if n == 0 {
        return;
    }
    if n == 1 && !left_wall && !right_wall {
        emit(0, 1, u[0], Wall::None);
        return;
    }
    let p = &mut scratch.prefix;
    p.clear();
    p.push(0.0);
    let mut s = 0.0;
    for &x in u {
        s += x;
        p.push(s);
    }
    let segs = &mut scratch.segments;
    segs.clear();
    segs.push((0, n as u32, left_wall, right_wall));
    // Each segment carries whether it is stuck to a wall: a split at its very end detaches it.
    while let Some((a, b, lw, rw)) = segs.pop() {
        let (a, b) = (a as usize, b as usize);
        let lo = if lw { a } else { a + 1 };
        let hi = if rw { b } else { b - 1 };
        let mut best = 0.0;
        let mut split = usize::MAX;
        for j in lo..=hi {
            let vl = if lw || j == a {
                0.0
            } else {
                (p[j] - p[a]) / (j - a) as f64
            };
            let vr = if rw || j == b {
                0.0
            } else {
                (p[b] - p[j]) / (b - j) as f64
            };
            let d = vr - vl;
            if d > best {
                best = d;
                split = j;
            }
        }
        if split != usize::MAX {
            if split < b {
                segs.push((split as u32, b as u32, false, rw));
            }
            if split > a {
                segs.push((a as u32, split as u32, lw, false));
            }
        } else if lw {
            emit(a, b - a, 0.0, Wall::Left);
        } else if rw {
            emit(a, b - a, 0.0, Wall::Right);
        } else {
            emit(a, b - a, (p[b] - p[a]) / (b - a) as f64, Wall::None);
        }
    }
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
