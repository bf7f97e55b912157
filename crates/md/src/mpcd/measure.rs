//! Measurements on the MPCD solvent: the shear viscosity from a periodic Poiseuille flow, and
//! block averages with their standard errors.
//!
//! **Viscosity.** A body force per unit mass `g_x(z) = g0 cos(k z)` (`k = 2 pi / L_z`) drives
//! the flow `v_x(z) = A cos(k z)` whose steady amplitude balances the viscous stress,
//! `eta k^2 A = rho g0` with the mass density `rho = n m` (Backer, Lowe, Hoefsloot & Iedema,
//! J. Chem. Phys. 122, 154503 (2005), the periodic Poiseuille method for particle fluids). The
//! amplitude is sampled after every collision as `A = (2 / N) sum_i v_x,i cos(k z_i)` once the
//! flow has built up (relaxation time `rho / (eta k^2)`), and its standard error comes from
//! block averages, so that `eta = rho g0 / (k^2 <A>)` with the standard error
//! `eta SE(A) / <A>`. The drive is weak (`g0` such that the flow stays well below the thermal
//! speed) and the cell thermostat removes the viscous heat.

use serde::{Deserialize, Serialize};

/// A time series reduced to the means of consecutive blocks of `len` samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlockAverage {
    /// Samples per block.
    pub len: u64,
    /// Means of the completed blocks.
    pub blocks: Vec<f64>,
    /// Sum and count of the block under way.
    partial: (f64, u64),
}

impl BlockAverage {
    /// Blocks of `len >= 1` samples.
    pub fn new(len: u64) -> Self {
        Self {
            len: len.max(1),
            blocks: Vec::new(),
            partial: (0.0, 0),
        }
    }

    /// Add a sample.
    pub fn push(&mut self, x: f64) {
        self.partial.0 += x;
        self.partial.1 += 1;
        if self.partial.1 == self.len {
            self.blocks.push(self.partial.0 / self.len as f64);
            self.partial = (0.0, 0);
        }
    }

    /// Mean of the completed blocks (NaN without any).
    pub fn mean(&self) -> f64 {
        if self.blocks.is_empty() {
            return f64::NAN;
        }
        self.blocks.iter().sum::<f64>() / self.blocks.len() as f64
    }

    /// Standard error of the mean from the scatter of the block means (NaN with fewer than two
    /// blocks).
    pub fn standard_error(&self) -> f64 {
        let b = self.blocks.len();
        if b < 2 {
            return f64::NAN;
        }
        let m = self.mean();
        let var = self.blocks.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (b - 1) as f64;
        (var / b as f64).sqrt()
    }
}

/// The flow amplitude `A = (2 / N) sum v_x cos(k z)` and the viscosity it gives.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoiseuilleProbe {
    /// Drive amplitude `g0` (force per unit mass).
    pub amplitude: f64,
    /// Wave number `k`.
    pub wavenumber: f64,
    /// Mass density `n m`.
    pub mass_density: f64,
    /// Samples of the flow amplitude.
    pub flow: BlockAverage,
}

impl PoiseuilleProbe {
    /// A probe for the drive `g0 cos(k z)` in a fluid of mass density `rho`, with blocks of
    /// `block` samples.
    pub fn new(amplitude: f64, wavenumber: f64, mass_density: f64, block: u64) -> Self {
        Self {
            amplitude,
            wavenumber,
            mass_density,
            flow: BlockAverage::new(block),
        }
    }

    /// The flow amplitude of the solvent now.
    pub fn amplitude_of(srd: &super::Srd, wavenumber: f64) -> f64 {
        let n = srd.len() as f64;
        2.0 / n * srd.sum(|x, v| [v[0] * (wavenumber * x[2]).cos()])[0]
    }

    /// Sample the flow of `srd`.
    pub fn sample(&mut self, srd: &super::Srd) {
        self.flow.push(Self::amplitude_of(srd, self.wavenumber));
    }

    /// `(eta, standard error)` from the blocks so far.
    pub fn viscosity(&self) -> (f64, f64) {
        let a = self.flow.mean();
        let eta = self.mass_density * self.amplitude / (self.wavenumber.powi(2) * a);
        (eta, eta * self.flow.standard_error() / a.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_averages_of_independent_samples_have_the_textbook_error() {
        use rand::RngExt;
        let mut b = BlockAverage::new(10);
        // Uniform deviates: mean 0.5, variance 1/12.
        let mut rng = colloidsim_core::rng::stream(1, 0, colloidsim_core::rng::Purpose::Moves, 0);
        for _ in 0..100_000 {
            b.push(rng.random::<f64>());
        }
        assert_eq!(b.blocks.len(), 10_000);
        assert!((b.mean() - 0.5).abs() < 0.01);
        let expect = (1.0f64 / 12.0 / 100_000.0).sqrt();
        let se = b.standard_error();
        assert!((se / expect - 1.0).abs() < 0.1, "{se} vs {expect}");
        assert!(BlockAverage::new(5).standard_error().is_nan());
    }
}
