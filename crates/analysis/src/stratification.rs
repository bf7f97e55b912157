//! Stratification of a droplet of two or more colloid species: per-species radial profiles and
//! the measures the drying literature uses to say whether the small spheres gather at the
//! surface ("small-on-top", Fortini et al., PRL 116, 118301 (2016); Howard, Nikoubashman &
//! Panagiotopoulos, Langmuir 33, 3685 (2017); Tang, Grest & Cheng, Langmuir 34, 7161 (2018)).
//!
//! With `s` the smallest and `l` the largest species, at droplet radius `R`:
//!
//! - `mean_radius[k] = <|r_i|>_k / R`, the mean centre distance of species k;
//! - `radius_difference = mean_radius[s] - mean_radius[l]`: positive when the small spheres sit
//!   further out;
//! - `shell_enrichment = x_s(shell) / x_s`: the number fraction of small spheres among the
//!   centres in the outer shell `R - d_l < |r|` over their fraction in the whole droplet
//!   (1: mixed; above 1: small-on-top; NaN when the shell is empty);
//! - `small_layer_thickness`: the depth below `R` of the outer region where the small spheres
//!   hold more volume than the large, scanning the per-species profiles inwards from the
//!   outermost shell a large centre can reach (the outermost occupied shell less
//!   `(d_l - d_s) / 2`: closer to the wall only small centres fit, whatever the structure);
//!   0 when the large spheres dominate there.

use crate::radial_profile;

/// Profiles and stratification of one configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Stratification {
    /// Volume-fraction profile of each species on `bins` equal shells of `[0, R]`.
    pub phi: Vec<Vec<f64>>,
    /// Mean centre distance of each species over R.
    pub mean_radius: Vec<f64>,
    /// `mean_radius[small] - mean_radius[large]`.
    pub radius_difference: f64,
    /// Small-sphere number fraction in the outer shell over that in the droplet.
    pub shell_enrichment: f64,
    /// Thickness of the small-rich outer layer.
    pub small_layer_thickness: f64,
}

/// The stratification of spheres at `pos` (diameters `diameter`, species `typeid` among
/// `species` diameters) in a droplet of radius `radius` centred at the origin.
pub fn stratification(
    pos: &[[f64; 3]],
    diameter: &[f64],
    typeid: &[u32],
    species: &[f64],
    radius: f64,
    bins: usize,
) -> Stratification {
    let n = species.len();
    let small = (0..n).fold(0, |a, k| if species[k] < species[a] { k } else { a });
    let large = (0..n).fold(0, |a, k| if species[k] > species[a] { k } else { a });
    let mut phi = Vec::with_capacity(n);
    let mut mean_radius = Vec::with_capacity(n);
    let dist = |x: &[f64; 3]| (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    for k in 0..n {
        let (p, d): (Vec<[f64; 3]>, Vec<f64>) = pos
            .iter()
            .zip(diameter)
            .zip(typeid)
            .filter(|(_, t)| **t as usize == k)
            .map(|((x, d), _)| (*x, *d))
            .unzip();
        phi.push(radial_profile(&p, &d, [0.0; 3], radius, bins).phi);
        mean_radius.push(p.iter().map(dist).sum::<f64>() / (p.len() as f64 * radius));
    }
    let shell = radius - species[large];
    let (mut in_shell, mut small_in_shell, mut small_all) = (0usize, 0usize, 0usize);
    for (x, &t) in pos.iter().zip(typeid) {
        let is_small = t as usize == small;
        small_all += is_small as usize;
        if dist(x) > shell {
            in_shell += 1;
            small_in_shell += is_small as usize;
        }
    }
    let shell_enrichment = if in_shell == 0 || small_all == 0 {
        f64::NAN
    } else {
        (small_in_shell as f64 / in_shell as f64) / (small_all as f64 / pos.len() as f64)
    };
    let dr = radius / bins as f64;
    let occupied = (0..bins)
        .rev()
        .find(|&b| phi[small][b] + phi[large][b] > 0.0);
    let small_layer_thickness = match occupied {
        Some(top) => {
            // Shells below `start` lie wholly where a large centre can be.
            let reach = (top + 1) as f64 * dr - 0.5 * (species[large] - species[small]);
            let start = ((reach / dr).floor().max(0.0) as usize).min(top + 1);
            let mut b = start;
            while b > 0 && phi[small][b - 1] > phi[large][b - 1] {
                b -= 1;
            }
            if b == start {
                0.0
            } else {
                radius - b as f64 * dr
            }
        }
        None => 0.0,
    };
    Stratification {
        radius_difference: mean_radius[small] - mean_radius[large],
        phi,
        mean_radius,
        shell_enrichment,
        small_layer_thickness,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_shell_around_a_large_core() {
        // Large spheres (d = 2) near the centre, small ones (d = 1) at radius 9.7 of R = 10.
        let mut pos = Vec::new();
        let (mut d, mut t) = (Vec::new(), Vec::new());
        for k in 0..20 {
            let a = k as f64 * 0.3;
            pos.push([2.0 * a.cos(), 2.0 * a.sin(), 0.0]);
            d.push(2.0);
            t.push(1);
            pos.push([9.7 * a.cos(), 0.0, 9.7 * a.sin()]);
            d.push(1.0);
            t.push(0);
        }
        let s = stratification(&pos, &d, &t, &[1.0, 2.0], 10.0, 20);
        assert!((s.mean_radius[0] - 0.97).abs() < 1e-12 && (s.mean_radius[1] - 0.2).abs() < 1e-12);
        assert!((s.radius_difference - 0.77).abs() < 1e-12);
        // Every centre beyond R - d_l = 8 is small: x_s(shell) = 1, x_s = 1/2.
        assert!((s.shell_enrichment - 2.0).abs() < 1e-12);
        // The small spheres fill the bin [9.5, 10), where no large centre fits ((2 - 1) / 2 =
        // 0.5 below the outermost shell's top): no layer is counted from it alone.
        assert_eq!(s.small_layer_thickness, 0.0);
        // Small spheres also at 9.2 (a shell a large centre could reach): a layer down to 9.
        let mut pos3 = pos.clone();
        let (mut d3, mut t3) = (d.clone(), t.clone());
        for k in 0..40 {
            let a = k as f64 * 0.15;
            pos3.push([9.2 * a.cos(), 9.2 * a.sin(), 0.0]);
            d3.push(1.0);
            t3.push(0);
        }
        let s = stratification(&pos3, &d3, &t3, &[1.0, 2.0], 10.0, 20);
        assert!(
            (s.small_layer_thickness - 1.0).abs() < 1e-12,
            "{}",
            s.small_layer_thickness
        );
        // Swap the species' roles: large-on-top, no small layer, enrichment 0.
        let t2: Vec<u32> = t.iter().map(|x| 1 - x).collect();
        let d2: Vec<f64> = d.iter().map(|x| 3.0 - x).collect();
        let s = stratification(&pos, &d2, &t2, &[1.0, 2.0], 10.0, 20);
        assert!(s.radius_difference < 0.0 && s.shell_enrichment == 0.0);
        assert_eq!(s.small_layer_thickness, 0.0);
    }
}
