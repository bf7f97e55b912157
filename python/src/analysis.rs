//! `_colloidsim.analysis_*`: the observables of `colloidsim-analysis` on arrays, for
//! `colloidsim.analysis` (which checks shapes and values and names the argument at fault;
//! the checks here repeat the ones the analysis functions would otherwise panic on).
//!
//! Vectors cross the boundary as little-endian `f64` bytes, 3 numbers per particle, as in
//! `hydro.rs`; the work runs without the GIL.

use crate::ColloidsimError;
use colloidsim_analysis as an;
use pyo3::prelude::*;

fn err(m: String) -> PyErr {
    ColloidsimError::new_err(m)
}

/// Little-endian `f64` bytes as 3-vectors, each finite; `what` names the argument.
fn points(bytes: &[u8], what: &str) -> PyResult<Vec<[f64; 3]>> {
    if !bytes.len().is_multiple_of(24) {
        return Err(err(format!("{what}: expected 3 numbers per particle")));
    }
    let v: Vec<[f64; 3]> = bytes
        .chunks_exact(24)
        .map(|c| {
            let x = |k: usize| f64::from_le_bytes(c[8 * k..8 * k + 8].try_into().expect("8 bytes"));
            [x(0), x(1), x(2)]
        })
        .collect();
    if let Some(i) = v.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
        return Err(err(format!(
            "{what}: particle {i} has a coordinate that is not finite"
        )));
    }
    Ok(v)
}

fn check_box(l: [f64; 3]) -> PyResult<()> {
    if l.iter().all(|x| x.is_finite() && *x > 0.0) {
        Ok(())
    } else {
        Err(err(format!(
            "box: edges must be positive and finite, got {l:?}"
        )))
    }
}

fn check_radii(radius: &[f64], n: usize) -> PyResult<()> {
    if radius.len() != n {
        return Err(err(format!(
            "diameters: {} values for {n} particles",
            radius.len()
        )));
    }
    if let Some(i) = radius.iter().position(|a| !(a.is_finite() && *a >= 0.0)) {
        return Err(err(format!(
            "diameters: particle {i} has {} (need >= 0, finite)",
            2.0 * radius[i]
        )));
    }
    Ok(())
}

/// g(r) of one frame: `(r, g)` (normalised by `N^2 / V`, as freud's default).
#[pyfunction]
pub fn analysis_rdf(
    py: Python<'_>,
    positions: &[u8],
    box_l: [f64; 3],
    r_max: f64,
    bins: usize,
) -> PyResult<(Vec<f64>, Vec<f64>)> {
    let pos = points(positions, "positions")?;
    check_box(box_l)?;
    if pos.len() < 2 {
        return Err(err(format!(
            "positions: g(r) needs at least 2 particles, got {}",
            pos.len()
        )));
    }
    let half = 0.5 * box_l.iter().cloned().fold(f64::INFINITY, f64::min);
    if !(r_max.is_finite() && r_max > 0.0 && r_max <= half) {
        return Err(err(format!(
            "r_max: must lie in (0, {half}] (half the shortest box edge), got {r_max}"
        )));
    }
    if bins == 0 {
        return Err(err("bins: must be at least 1".into()));
    }
    Ok(py.detach(|| an::pair_distribution(&pos, box_l, r_max, bins)))
}

/// Mean-squared displacement at lags 1 .. F-1 from F frames of unwrapped positions (each
/// `n` particles, concatenated).
#[pyfunction]
pub fn analysis_msd(py: Python<'_>, unwrapped: &[u8], n: usize) -> PyResult<Vec<f64>> {
    let all = points(unwrapped, "positions")?;
    if n == 0 || !all.len().is_multiple_of(n) || all.len() / n < 2 {
        return Err(err(format!(
            "positions: need at least 2 frames of {n} particles, got {} positions",
            all.len()
        )));
    }
    let frames: Vec<Vec<[f64; 3]>> = all.chunks(n).map(|c| c.to_vec()).collect();
    Ok(py.detach(|| an::mean_squared_displacement(&frames)))
}

/// Contacts `(i, j)`, `i < j`, flattened: surface gap below `gap` under the minimum image.
#[pyfunction]
pub fn analysis_contacts(
    py: Python<'_>,
    positions: &[u8],
    radius: Vec<f64>,
    box_l: [f64; 3],
    gap: f64,
) -> PyResult<Vec<u32>> {
    let pos = points(positions, "positions")?;
    check_box(box_l)?;
    check_radii(&radius, pos.len())?;
    if !gap.is_finite() {
        return Err(err(format!("gap: must be finite, got {gap}")));
    }
    if pos.len() > u32::MAX as usize {
        return Err(err("positions: at most 2^32 - 1 particles".into()));
    }
    let bonds = py.detach(|| an::contacts(&pos, &radius, box_l, gap));
    Ok(bonds.into_iter().flat_map(|(i, j)| [i, j]).collect())
}

/// Cluster labels of `n` particles joined by `bonds` (flattened pairs).
#[pyfunction]
pub fn analysis_cluster_labels(n: usize, bonds: Vec<u32>) -> PyResult<Vec<u32>> {
    if !bonds.len().is_multiple_of(2) {
        return Err(err("bonds: pairs (i, j) expected".into()));
    }
    if let Some(b) = bonds.iter().find(|&&b| b as usize >= n) {
        return Err(err(format!("bonds: index {b} for {n} particles")));
    }
    let pairs: Vec<(u32, u32)> = bonds.chunks_exact(2).map(|c| (c[0], c[1])).collect();
    Ok(an::cluster_labels(n, &pairs))
}

/// Radial profiles about `centre`: `(r, volume fraction by sphere-shell overlap, number density)`.
#[pyfunction]
pub fn analysis_radial_profile(
    py: Python<'_>,
    positions: &[u8],
    diameters: Vec<f64>,
    centre: [f64; 3],
    r_max: f64,
    bins: usize,
) -> PyResult<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    let pos = points(positions, "positions")?;
    let radius: Vec<f64> = diameters.iter().map(|d| 0.5 * d).collect();
    check_radii(&radius, pos.len())?;
    if centre.iter().any(|c| !c.is_finite()) {
        return Err(err(format!("centre: must be finite, got {centre:?}")));
    }
    if !(r_max.is_finite() && r_max > 0.0) {
        return Err(err(format!(
            "r_max: must be positive and finite, got {r_max}"
        )));
    }
    if bins == 0 {
        return Err(err("bins: must be at least 1".into()));
    }
    Ok(py.detach(|| {
        let phi = an::overlap_profile(&pos, &diameters, centre, r_max, bins);
        // Centre binning with unit particle volumes (d^3 = 6 / pi): the number density.
        let unit = vec![(6.0 / std::f64::consts::PI).cbrt(); pos.len()];
        let p = an::radial_profile(&pos, &unit, centre, r_max, bins);
        (p.r, phi, p.phi)
    }))
}

/// S(q) from g(r) on evenly spaced bins `r` at number density `rho` (Lorch window).
#[pyfunction]
pub fn analysis_structure_factor(
    r: Vec<f64>,
    g: Vec<f64>,
    rho: f64,
    q: Vec<f64>,
) -> PyResult<Vec<f64>> {
    if r.len() != g.len() || r.len() < 2 {
        return Err(err(format!(
            "r, g: need the same length, at least 2, got {} and {}",
            r.len(),
            g.len()
        )));
    }
    let dr = r[1] - r[0];
    let even = dr > 0.0
        && r.windows(2)
            .all(|w| ((w[1] - w[0]) - dr).abs() <= 1e-6 * dr)
        && r.iter().chain(&g).all(|x| x.is_finite());
    if !even {
        return Err(err(
            "r: bin midpoints must be finite, increasing and evenly spaced (g finite)".into(),
        ));
    }
    if !(rho.is_finite() && rho > 0.0) {
        return Err(err(format!("rho: must be positive and finite, got {rho}")));
    }
    if q.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return Err(err("q: wave numbers must be positive and finite".into()));
    }
    Ok(an::structure_factor_windowed(
        &r,
        &g,
        rho,
        &q,
        an::Window::Lorch,
    ))
}
