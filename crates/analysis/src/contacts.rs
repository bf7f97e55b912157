//! Contacts between spheres of per-particle radius in a periodic orthorhombic box, by a cell list.

use rayon::prelude::*;

/// Minimum-image separation vector component `dx - L round(dx / L)`.
#[inline]
fn min_image(dx: f64, l: f64) -> f64 {
    dx - l * (dx / l).round()
}

/// Surface gap `h = |x_i - x_j| - (a_i + a_j)` under the minimum image convention.
#[inline]
fn gap(xi: &[f64; 3], xj: &[f64; 3], ai: f64, aj: f64, l: &[f64; 3]) -> f64 {
    let mut d2 = 0.0;
    for k in 0..3 {
        let d = min_image(xi[k] - xj[k], l[k]);
        d2 += d * d;
    }
    d2.sqrt() - (ai + aj)
}

/// Pairs `(i, j)`, `i < j`, of spheres whose surface gap under the minimum image convention of
/// a periodic orthorhombic box with edges `box_l` is below `h_max`:
///
/// ```text
/// h_ij = |x_i - x_j - L round((x_i - x_j) / L)| - (a_i + a_j) < h_max
/// ```
///
/// `pos` (any image; wrapped or unwrapped), `radius` (`a_i >= 0`, may differ per particle),
/// `box_l` and `h_max` share one length unit; `h_max` may be negative (overlaps deeper than
/// `-h_max`). Each pair appears once, with its nearest image, and the list is sorted.
///
/// O(N) by a cell list with cells at least `2 a_max + h_max` wide (and no more cells than
/// particles). An edge with fewer than three such cells is not divided, so a box with fewer than
/// three cells on every edge is searched pair by pair, O(N^2). Parallel over cells; the result
/// does not depend on the number of threads.
///
/// Panics if `pos` and `radius` differ in length, if there are more than `u32::MAX` particles,
/// if a radius is negative or not finite, if a box edge is not positive and finite, or if
/// `h_max` is NaN.
pub fn contacts(pos: &[[f64; 3]], radius: &[f64], box_l: [f64; 3], h_max: f64) -> Vec<(u32, u32)> {
    let n = pos.len();
    assert_eq!(n, radius.len(), "pos and radius must have the same length");
    assert!(u32::try_from(n).is_ok(), "at most u32::MAX particles");
    assert!(
        box_l.iter().all(|l| l.is_finite() && *l > 0.0),
        "box edges must be positive and finite"
    );
    assert!(
        radius.iter().all(|a| a.is_finite() && *a >= 0.0),
        "radii must be finite and non-negative"
    );
    assert!(!h_max.is_nan(), "h_max must not be NaN");
    let a_max = radius.iter().cloned().fold(0.0, f64::max);
    let rc = 2.0 * a_max + h_max;
    if n < 2 || rc <= 0.0 {
        return Vec::new();
    }
    // Cell width: at least the largest contact distance (with a margin against rounding in the
    // cell index), and large enough that there are at most about N cells.
    let volume = box_l[0] * box_l[1] * box_l[2];
    let width = (rc * (1.0 + 1e-9)).max((volume / n as f64).cbrt());
    let nc: [usize; 3] = std::array::from_fn(|k| {
        let c = (box_l[k] / width).floor();
        if c >= 3.0 { c as usize } else { 1 }
    });
    let cell_of = |x: &[f64; 3]| -> usize {
        let mut idx = [0usize; 3];
        for k in 0..3 {
            let l = box_l[k];
            // In [0, L] up to rounding; a particle a few ulps from a cell face may land in the
            // neighbouring cell, which the width margin above covers.
            let w = x[k] - l * (x[k] / l).floor();
            idx[k] = ((w / l * nc[k] as f64) as usize).min(nc[k] - 1);
        }
        (idx[2] * nc[1] + idx[1]) * nc[0] + idx[0]
    };
    // Counting sort of the particles by cell, with their positions and radii copied into cell
    // order so that the pair loop reads neighbouring cells from contiguous memory.
    let n_cells = nc[0] * nc[1] * nc[2];
    let cell: Vec<usize> = pos.iter().map(cell_of).collect();
    let mut start = vec![0usize; n_cells + 1];
    for &c in &cell {
        start[c + 1] += 1;
    }
    for c in 0..n_cells {
        start[c + 1] += start[c];
    }
    let mut fill = start.clone();
    let mut id = vec![0u32; n];
    for (i, &c) in cell.iter().enumerate() {
        id[fill[c]] = i as u32;
        fill[c] += 1;
    }
    let sp: Vec<[f64; 3]> = id.iter().map(|&i| pos[i as usize]).collect();
    let sa: Vec<f64> = id.iter().map(|&i| radius[i as usize]).collect();
    // Neighbour offsets per axis: -1, 0, 1 on a divided edge (three distinct cells), 0 on an
    // undivided one.
    let offsets = |k: usize| -> &'static [isize] { if nc[k] >= 3 { &[-1, 0, 1] } else { &[0] } };
    let mut pairs: Vec<(u32, u32)> = (0..n_cells)
        .into_par_iter()
        .flat_map_iter(|c| {
            let ci = [c % nc[0], (c / nc[0]) % nc[1], c / (nc[0] * nc[1])];
            let mut out = Vec::new();
            if start[c] == start[c + 1] {
                return out;
            }
            for &oz in offsets(2) {
                let z = (ci[2] as isize + oz).rem_euclid(nc[2] as isize) as usize;
                for &oy in offsets(1) {
                    let y = (ci[1] as isize + oy).rem_euclid(nc[1] as isize) as usize;
                    for &ox in offsets(0) {
                        let x = (ci[0] as isize + ox).rem_euclid(nc[0] as isize) as usize;
                        let cc = (z * nc[1] + y) * nc[0] + x;
                        for s in start[c]..start[c + 1] {
                            for t in start[cc]..start[cc + 1] {
                                // Each unordered pair is met twice (once from each cell, or
                                // twice within one cell); keep the visit with i < j.
                                if id[s] < id[t]
                                    && gap(&sp[s], &sp[t], sa[s], sa[t], &box_l) < h_max
                                {
                                    out.push((id[s], id[t]));
                                }
                            }
                        }
                    }
                }
            }
            out
        })
        .collect();
    pairs.sort_unstable();
    pairs
}
