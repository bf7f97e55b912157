//! Species of colloids: a name, a diameter and a number of particles each.
//!
//! Particles are stored species by species (all of species 0, then all of species 1, ...), so a
//! particle's species is its `typeid` and its diameter is its species' diameter. One species
//! is the monodisperse case, not a second code path.

use crate::state::Particles;
use std::f64::consts::PI;

/// The species of a run and how many particles of each.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Mixture {
    /// Names (GSD type names): `A`, `B`, ... in the order given.
    pub names: Vec<String>,
    /// Diameter of each species.
    pub diameters: Vec<f64>,
    /// Particles of each species.
    pub counts: Vec<usize>,
}

impl Mixture {
    /// One species `A` of `n` particles of diameter `d`.
    pub fn one(d: f64, n: usize) -> Self {
        Self::new(vec![d], vec![n])
    }

    /// Species named `A`, `B`, ... with these diameters and counts (same length, at least
    /// one species, at most 26).
    pub fn new(diameters: Vec<f64>, counts: Vec<usize>) -> Self {
        assert!(
            !diameters.is_empty() && diameters.len() == counts.len() && diameters.len() <= 26,
            "one count per species, 1 to 26 species"
        );
        let names = (0..diameters.len())
            .map(|s| char::from(b'A' + s as u8).to_string())
            .collect();
        Self {
            names,
            diameters,
            counts,
        }
    }

    /// Number of species.
    pub fn len(&self) -> usize {
        self.diameters.len()
    }

    /// No species? (Never, for a mixture built by [`Mixture::new`].)
    pub fn is_empty(&self) -> bool {
        self.diameters.is_empty()
    }

    /// One species (the monodisperse case)?
    pub fn is_single(&self) -> bool {
        self.len() == 1
    }

    /// `sum_s N_s d_s^3` (the mean volume fraction in a sphere of radius R is this over `8 R^3`).
    pub fn sum_n_d3(&self) -> f64 {
        self.diameters
            .iter()
            .zip(&self.counts)
            .map(|(d, &n)| n as f64 * d.powi(3))
            .sum()
    }

    /// Number of spheres of diameter `d` with the volume of all particles,
    /// `sum_s N_s (d_s / d)^3` (exactly `N` for one species of diameter `d`).
    pub fn equivalent_number(&self, d: f64) -> f64 {
        self.diameters
            .iter()
            .zip(&self.counts)
            .map(|(ds, &n)| n as f64 * (ds / d).powi(3))
            .sum()
    }

    /// Total number of particles.
    pub fn total(&self) -> usize {
        self.counts.iter().sum()
    }

    /// Smallest diameter (the reference length of the defaults).
    pub fn d_min(&self) -> f64 {
        self.diameters.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Largest diameter.
    pub fn d_max(&self) -> f64 {
        self.diameters.iter().copied().fold(0.0, f64::max)
    }

    /// Particle volume of all particles, `sum_s N_s pi d_s^3 / 6`.
    pub fn particle_volume(&self) -> f64 {
        self.diameters
            .iter()
            .zip(&self.counts)
            .map(|(d, &n)| n as f64 * PI * d.powi(3) / 6.0)
            .sum()
    }

    /// Each particle's species, species by species.
    pub fn typeids(&self) -> Vec<u32> {
        self.counts
            .iter()
            .enumerate()
            .flat_map(|(s, &n)| std::iter::repeat_n(s as u32, n))
            .collect()
    }

    /// Each particle's diameter, species by species.
    pub fn particle_diameters(&self) -> Vec<f64> {
        self.typeids()
            .into_iter()
            .map(|t| self.diameters[t as usize])
            .collect()
    }

    /// Particles at `pos` (species by species), unit mass, at rest.
    pub fn particles(&self, pos: Vec<[f64; 3]>) -> Particles {
        assert_eq!(pos.len(), self.total(), "one position per particle");
        let mut p = Particles::monodisperse(pos, self.diameters[0]);
        p.typeid = self.typeids();
        p.diameter = self.particle_diameters();
        p.type_names = self.names.clone();
        p
    }

    /// Counts of `n` particles whose species take the shares `shares` (sum 1) of the particle
    /// volume: `N_s` proportional to `share_s / d_s^3`, rounded by largest remainder so that
    /// they sum to `n`.
    pub fn counts_from_volume_shares(n: usize, diameters: &[f64], shares: &[f64]) -> Vec<usize> {
        let w: Vec<f64> = diameters
            .iter()
            .zip(shares)
            .map(|(d, x)| x / d.powi(3))
            .collect();
        let total: f64 = w.iter().sum();
        let exact: Vec<f64> = w.iter().map(|x| n as f64 * x / total).collect();
        let mut counts: Vec<usize> = exact.iter().map(|x| x.floor() as usize).collect();
        let mut order: Vec<usize> = (0..exact.len()).collect();
        order.sort_by(|&a, &b| {
            (exact[b] - exact[b].floor())
                .total_cmp(&(exact[a] - exact[a].floor()))
                .then(a.cmp(&b))
        });
        let missing = n - counts.iter().sum::<usize>();
        for &s in order.iter().take(missing) {
            counts[s] += 1;
        }
        counts
    }

    /// Index of the unordered species pair `(a, b)` in the order (0,0), (0,1), ..., (1,1), ...
    pub fn pair_index(&self, a: usize, b: usize) -> usize {
        let (a, b) = (a.min(b), a.max(b));
        a * self.len() - a * (a + 1) / 2 + b
    }

    /// Number of unordered species pairs `n (n + 1) / 2`.
    pub fn pairs(&self) -> usize {
        self.len() * (self.len() + 1) / 2
    }

    /// Name of the unordered pair `(a, b)`, e.g. `AB`.
    pub fn pair_name(&self, a: usize, b: usize) -> String {
        format!("{}{}", self.names[a.min(b)], self.names[a.max(b)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_from_volume_shares_sum_to_n_and_follow_the_shares() {
        // Equal volume shares, size ratio 2: eight small per large.
        let c = Mixture::counts_from_volume_shares(900, &[1.0, 2.0], &[0.5, 0.5]);
        assert_eq!(c, vec![800, 100]);
        let c = Mixture::counts_from_volume_shares(1001, &[1.0, 2.0, 3.0], &[0.2, 0.3, 0.5]);
        assert_eq!(c.iter().sum::<usize>(), 1001);
        assert_eq!(
            Mixture::counts_from_volume_shares(7, &[1.5], &[1.0]),
            vec![7]
        );
    }

    #[test]
    fn particles_are_stored_species_by_species() {
        let m = Mixture::new(vec![1.0, 2.0], vec![2, 1]);
        let p = m.particles(vec![[0.0; 3]; 3]);
        assert_eq!(p.typeid, vec![0, 0, 1]);
        assert_eq!(p.diameter, vec![1.0, 1.0, 2.0]);
        assert_eq!(p.type_names, vec!["A", "B"]);
        assert_eq!(
            (m.pair_index(0, 1), m.pair_index(1, 1), m.pairs()),
            (1, 2, 3)
        );
        assert_eq!(m.pair_name(1, 0), "AB");
        let one = Mixture::one(1.5, 4);
        assert_eq!(
            one.particles(vec![[0.0; 3]; 4]),
            Particles::monodisperse(vec![[0.0; 3]; 4], 1.5)
        );
    }
}
