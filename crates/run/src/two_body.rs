//! The two-body density the DDFT assumes (paper Eq. 17) on the Monte Carlo's `g2` grid of a
//! droplet: `rho2(x1, x2) = rho(r1) rho(r2) g(|x1 - x2|; rho_bar)` with the bulk `g` at the mean
//! of the two local densities, `rho_bar = (rho(r1) + rho(r2)) / 2`, so
//! `g2 = g(s; eta_bar)`, `s^2 = r1^2 + r2^2 - 2 r1 r2 cos theta`, `eta_bar = pi d^3 rho_bar / 6`
//! (clipped at 0.6, as the paper did). Two bulk `g`: the dilute `Theta(s - d)` and Trokhymchuk
//! et al.'s ([`colloidsim_dft::radial::pair`]).
//!
//! Each cell `(r1, r2, cos theta)` of the grid (radial bins of equal width over `[0, r_max]`,
//! `cos theta` bins over `[-1, 1]`, index `(a r_bins + b) cos_bins + c`) gets the average of `g`
//! over the cell with the weight `r1^2 r2^2` of its pairs (midpoints of `SUB^3` sub-cells), which is
//! what a histogram of the pairs measures when the density is constant across a radial bin.

use anyhow::Result;
use colloidsim_dft::radial::pair::{ETA_CLIP, TotalCorrelation};
use std::f64::consts::PI;

/// Sub-cells per axis of a grid cell.
const SUB: usize = 6;

/// `g2` of Eq. 17 on a grid, cell by cell.
#[derive(Debug, Clone, PartialEq)]
pub struct Eq17 {
    /// With the dilute `g = Theta(s - d)`.
    pub dilute: Vec<f64>,
    /// With Trokhymchuk's `g(s; eta_bar)`.
    pub trokhymchuk: Vec<f64>,
}

/// Eq. 17's `g2` on the grid of `r_bins` radial bins over `[0, r_max]` and `cos_bins` bins of
/// `cos theta`, for spheres of `diameter` and the local density `rho` of each radial bin.
pub fn eq17(
    r_max: f64,
    r_bins: usize,
    cos_bins: usize,
    diameter: f64,
    rho: &[f64],
) -> Result<Eq17> {
    anyhow::ensure!(
        rho.len() == r_bins,
        "eq17: {} densities for {r_bins} radial bins",
        rho.len()
    );
    let (wr, wc) = (r_max / r_bins as f64, 2.0 / cos_bins as f64);
    let cells = r_bins * r_bins * cos_bins;
    let mut dilute = vec![0.0; cells];
    let mut trokhymchuk = vec![0.0; cells];
    let sub = |lo: f64, w: f64, k: usize| lo + (k as f64 + 0.5) * w / SUB as f64;
    for a in 0..r_bins {
        for b in 0..r_bins {
            let eta = (PI * diameter.powi(3) / 12.0 * (rho[a] + rho[b])).clamp(0.0, ETA_CLIP);
            let h = TotalCorrelation::new(eta)?;
            for c in 0..cos_bins {
                let (mut wsum, mut dil, mut tro) = (0.0, 0.0, 0.0);
                for i in 0..SUB {
                    let r1 = sub(a as f64 * wr, wr, i);
                    for j in 0..SUB {
                        let r2 = sub(b as f64 * wr, wr, j);
                        let w = r1 * r1 * r2 * r2;
                        for k in 0..SUB {
                            let cos = sub(-1.0 + c as f64 * wc, wc, k);
                            let s = (r1 * r1 + r2 * r2 - 2.0 * r1 * r2 * cos).max(0.0).sqrt();
                            let x = s / diameter;
                            wsum += w;
                            if x >= 1.0 {
                                dil += w;
                            }
                            tro += w * (1.0 + h.h(x));
                        }
                    }
                }
                let k = (a * r_bins + b) * cos_bins + c;
                dilute[k] = dil / wsum;
                trokhymchuk[k] = tro / wsum;
            }
        }
    }
    Ok(Eq17 {
        dilute,
        trokhymchuk,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilute_cells_are_zero_inside_the_core_and_one_beyond_and_symmetric() {
        // R = 10 d, 20 bins of 0.5 d, 400 cos bins; an empty droplet (rho = 0) makes
        // Trokhymchuk's g the dilute one.
        let (nr, nc) = (20, 400);
        let e = eq17(10.0, nr, nc, 1.0, &vec![0.0; nr]).unwrap();
        let at = |v: &[f64], a: usize, b: usize, c: usize| v[(a * nr + b) * nc + c];
        // Same shell at r = 8-8.5 d, cos theta > 0.995: s < 0.9 d, inside the core.
        assert_eq!(at(&e.dilute, 16, 16, nc - 1), 0.0);
        // Opposite sides: s ~ 16 d.
        assert_eq!(at(&e.dilute, 16, 16, 0), 1.0);
        for (a, b, c) in [(3, 7, 2), (16, 15, 399), (0, 19, 5)] {
            assert!((at(&e.dilute, a, b, c) - at(&e.dilute, b, a, c)).abs() < 1e-12);
            assert!((at(&e.trokhymchuk, a, b, c) - at(&e.dilute, a, b, c)).abs() < 1e-12);
        }
    }

    #[test]
    fn trokhymchuk_cells_show_the_contact_peak_and_tend_to_one() {
        let (nr, nc) = (32, 400);
        let rho = vec![6.0 * 0.3 / PI; nr];
        let e = eq17(8.0, nr, nc, 1.0, &rho).unwrap();
        let at = |a: usize, b: usize, c: usize| e.trokhymchuk[(a * nr + b) * nc + c];
        // Same shell at r = 6-6.25 d: the largest g2 over cos theta is the contact peak, at a
        // pair distance just above d (cos theta = 1 - s^2 / (2 r^2)).
        let (c_max, g_max) = (0..nc)
            .map(|c| (c, at(24, 24, c)))
            .fold((0, 0.0), |m, v| if v.1 > m.1 { v } else { m });
        let cos = -1.0 + (c_max as f64 + 0.5) * 2.0 / nc as f64;
        let s = 6.125 * (2.0 * (1.0 - cos)).sqrt();
        assert!(
            g_max > 1.5 && (1.0..1.3).contains(&s),
            "peak {g_max} at s = {s}"
        );
        // Opposite sides: s ~ 12 d.
        assert!((at(24, 24, 0) - 1.0).abs() < 1e-3);
        // A wrong number of densities is refused.
        assert!(eq17(8.0, nr, nc, 1.0, &rho[1..]).is_err());
    }
}
