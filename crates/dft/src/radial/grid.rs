//! Cell-centred radial grid: cells `[i dr, (i+1) dr]`, `i = 0..n`, density at the cell centres.

use colloidsim_core::param;

use super::RadialError;

/// Uniform radial finite-volume grid on `[0, n dr]`.
#[derive(Debug, Clone, PartialEq)]
pub struct RadialGrid {
    dr: f64,
    centres: Vec<f64>,
    faces: Vec<f64>,
    volumes: Vec<f64>,
    areas: Vec<f64>,
}

impl RadialGrid {
    /// `n` cells of width `dr` (errors name `dr` and `cells`).
    pub fn new(dr: f64, n: usize) -> Result<Self, RadialError> {
        param::positive("dr", dr)?;
        param::at_least("cells", n, 2)?;
        Self::ensure_fits(dr, n as f64)?;
        let faces: Vec<f64> = (0..=n).map(|i| i as f64 * dr).collect();
        let centres = (0..n).map(|i| (i as f64 + 0.5) * dr).collect();
        let volumes = (0..n)
            .map(|i| 4.0 * std::f64::consts::PI / 3.0 * (faces[i + 1].powi(3) - faces[i].powi(3)))
            .collect();
        let areas = faces
            .iter()
            .map(|f| 4.0 * std::f64::consts::PI * f * f)
            .collect();
        Ok(Self {
            dr,
            centres,
            faces,
            volumes,
            areas,
        })
    }

    /// The smallest grid of spacing `dr` that covers `[0, r_max]`.
    pub fn covering(dr: f64, r_max: f64) -> Result<Self, RadialError> {
        param::positive("dr", dr)?;
        param::positive("r_max", r_max)?;
        let cells = (r_max / dr).ceil().max(2.0);
        // Before the count becomes an integer: 1e301 cells would saturate it.
        Self::ensure_fits(dr, cells)?;
        Self::new(dr, cells as usize)
    }

    /// Refuse a grid of `cells` cells whose four arrays (and as much again for a solver's
    /// fields on it) the machine cannot hold, naming the spacing.
    fn ensure_fits(dr: f64, cells: f64) -> Result<(), RadialError> {
        colloidsim_core::resources::ensure_fits(
            "dr",
            &format!(
                "a radial grid of {cells:.3e} cells of width {dr:.3e} (a larger --dx makes it smaller)"
            ),
            64.0 * cells,
        )?;
        Ok(())
    }

    /// Cell width.
    pub fn dr(&self) -> f64 {
        self.dr
    }
    /// Number of cells.
    pub fn len(&self) -> usize {
        self.centres.len()
    }
    /// Always false (a grid has at least two cells).
    pub fn is_empty(&self) -> bool {
        self.centres.is_empty()
    }
    /// Outer radius `n dr`.
    pub fn r_max(&self) -> f64 {
        self.faces[self.faces.len() - 1]
    }
    /// Cell centres `(i + 1/2) dr`.
    pub fn centres(&self) -> &[f64] {
        &self.centres
    }
    /// Cell faces `i dr`, `i = 0..=n`.
    pub fn faces(&self) -> &[f64] {
        &self.faces
    }
    /// Shell volumes `4 pi (r_{i+1}^3 - r_i^3) / 3`.
    pub fn volumes(&self) -> &[f64] {
        &self.volumes
    }
    /// Face areas `4 pi r_f^2`.
    pub fn areas(&self) -> &[f64] {
        &self.areas
    }
    /// Number of particles `sum_i V_i rho_i`.
    pub fn integrate(&self, rho: &[f64]) -> f64 {
        self.volumes.iter().zip(rho).map(|(v, r)| v * r).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volumes_sum_to_sphere() {
        let g = RadialGrid::new(0.1, 50).unwrap();
        let v: f64 = g.volumes().iter().sum();
        assert!((v - 4.0 * std::f64::consts::PI / 3.0 * 125.0).abs() < 1e-9);
        assert!(RadialGrid::new(0.0, 5).is_err());
        assert!(RadialGrid::new(0.1, 1).is_err());
    }

    /// A spacing of 1e-300 over 15 diameters asked for 1.5e301 cells ("capacity overflow").
    #[test]
    fn grids_beyond_the_memory_are_refused_naming_the_spacing() {
        let e = RadialGrid::covering(1e-300, 15.0).unwrap_err().to_string();
        assert!(e.contains("dr:") && e.contains("radial grid"), "{e}");
        assert!(RadialGrid::new(1e-3, usize::MAX).is_err());
    }
}
