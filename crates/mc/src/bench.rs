//! The benchmark system of `colloidsim bench mc`: hard spheres of diameter 1 in a periodic cube
//! at volume fraction `phi`, started from an FCC lattice and warmed up with move-size tuning.

use crate::engine::{HardSphereMc, McError, McParams};
use crate::geometry::Geometry;
use crate::init::fcc_in_box;
use std::f64::consts::PI;

/// Box edge of `n` spheres of diameter 1 at volume fraction `phi`: `(n pi / (6 phi))^(1/3)`.
pub fn bulk_edge(n: usize, phi: f64) -> f64 {
    (n as f64 * PI / 6.0 / phi).cbrt()
}

/// `n` hard spheres (d = 1) at volume fraction `phi` in a periodic cube, on an FCC lattice,
/// with `warmup` sweeps tuned every 100 towards acceptance 0.3 (delta then frozen).
pub fn bulk_system(n: usize, phi: f64, seed: u32, warmup: u64) -> Result<HardSphereMc, McError> {
    let edge = bulk_edge(n, phi);
    let pos = fcc_in_box(n, 1.0, edge)?;
    let params = McParams {
        diameter: 1.0,
        geometry: Geometry::Bulk { edge },
        seed,
        delta: 0.1,
        mixture: None,
    };
    let mut mc = HardSphereMc::new(&params, &pos, "system")?;
    mc.warm_up(warmup, 100, 0.3);
    Ok(mc)
}
