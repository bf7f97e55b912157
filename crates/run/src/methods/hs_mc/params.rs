//! An `hs-mc` scenario read through its key declarations ([`super::keys`]) into the run the
//! engine takes ([`McRun`]), with every check that relates several keys, each error naming the
//! key and the allowed range.

use super::keys::*;
use crate::keys::shared::{
    self, INTERFACE, INTERFACE_OFFSET, INTERFACE_RANGE, INTERFACE_STIFFNESS,
};
use crate::keys::species::{SPECIES, SPECIES_COUNTS, SPECIES_DIAMETERS};
use crate::keys::{Reader, SEED_KEY, rekey};
use anyhow::{Result, bail};
use colloidsim_core::ParamError;
use colloidsim_core::param::show;
use colloidsim_core::resources::ensure_fits;
use colloidsim_mc::geometry::Geometry;
use colloidsim_mc::params::{MAX_PHI, McRun};
use colloidsim_particles::Mixture;
use std::f64::consts::PI;
use std::path::Path;

/// The most cells of the two-body density rho2(r1, r2, cos theta): g2.csv writes a row of nine
/// numbers each (some 150 MB of text at this bound; 100 x 100 radial x 100 angular bins).
const MAX_RHO2_CELLS: usize = 1_000_000;

/// The engine's names of its parameters, and the keys that set them.
const ENGINE_NAMES: &[(&str, &crate::keys::Spec)] = &[
    ("diameter", &SYSTEM_DIAMETER),
    ("delta", &MC_DELTA),
    ("radius", &SYSTEM_RADIUS),
    ("stiffness", &INTERFACE_STIFFNESS),
    ("range", &INTERFACE_RANGE),
    ("offset", &INTERFACE_OFFSET),
    ("n", &SYSTEM_VOLUME_FRACTION),
    ("diameters", &SPECIES_DIAMETERS),
    ("counts", &SPECIES_COUNTS),
    ("chain_length", &MC_CHAIN_LENGTH),
    ("move", &MC_MOVE),
    ("box", &SYSTEM_BOX),
    ("pair_range", &crate::keys::species::PAIR_RANGE),
];

/// An engine's error about one of its parameters, naming the scenario key instead.
pub(super) fn keyed(e: ParamError) -> ParamError {
    rekey(e, ENGINE_NAMES)
}

/// Longest event chain, in diameters (`mc.chain_length`): far beyond any useful length, and
/// short enough that a sweep's chain count and displacement stay exact in f64.
const MAX_CHAIN_LENGTH: f64 = 1e6;

/// A scenario's table checked against [`KEYS`] and resolved (with `seed` replacing the
/// scenario's); `system.initial` is taken relative to `base`.
pub fn read(table: &toml::Table, base: &Path, seed: Option<u64>) -> Result<McRun> {
    let r = Reader::new(table, KEYS)?;
    resolve(&r, base, seed)
}

/// Every key read and checked against the others.
fn resolve(r: &Reader, base: &Path, seed: Option<u64>) -> Result<McRun> {
    let seed = colloidsim_core::param::seed(SEED_KEY.path, seed.unwrap_or(r.count(&SEED_KEY)?))?;
    let d = r.number(&SYSTEM_DIAMETER)?;
    let kt = r.number(&SYSTEM_KT)?;
    let geometry = r.word(&SYSTEM_GEOMETRY)?;
    let bulk = geometry == "bulk";
    let (size_key, other_key) = if bulk {
        (&SYSTEM_BOX, &SYSTEM_RADIUS)
    } else {
        (&SYSTEM_RADIUS, &SYSTEM_BOX)
    };
    let size = r.opt_number(size_key)?;
    if r.has(other_key) {
        bail!(ParamError::new(
            other_key.path,
            format!(
                "does not apply to system.geometry = \"{geometry}\" (give {})",
                size_key.path
            ),
        ));
    }
    let particles = r.opt_count(&SYSTEM_PARTICLES)?.map(|n| n as usize);
    if bulk && particles == Some(1) {
        bail!(ParamError::new(
            SYSTEM_PARTICLES.path,
            "must be at least 2 in bulk, got 1"
        ));
    }
    // The species (one of diameter d without [system.species]); a mixture needs N given.
    let species = match particles {
        Some(n) => Some(crate::keys::species::species(r, n, d, &SYSTEM_DIAMETER)?),
        None if r.has(&SPECIES) => bail!(ParamError::new(
            SYSTEM_PARTICLES.path,
            "required with [system.species] (the counts or volume fractions share it out)",
        )),
        None => None,
    };
    // Spheres of diameter d with the volume of all spheres (N for one species).
    let n_eq = |n: usize| {
        species
            .as_ref()
            .map_or(n as f64, |m| m.equivalent_number(d))
    };
    let d_max = species.as_ref().map_or(d, |m| m.d_max());
    let volume_fraction = r.opt_number(&SYSTEM_VOLUME_FRACTION)?;
    // phi of N spheres in a size, and its inverses.
    let unit = if bulk { PI / 6.0 } else { 1.0 / 8.0 };
    let (particles, size) = match (particles, volume_fraction, size) {
        (Some(n), None, Some(l)) => (n, l),
        (Some(n), Some(phi), None) => (n, (n_eq(n) * unit * d.powi(3) / phi).cbrt()),
        (None, Some(phi), Some(l)) => {
            let n = (phi * l.powi(3) / (unit * d.powi(3))).round();
            if !(1.0..=1e8).contains(&n) {
                bail!(ParamError::new(
                    SYSTEM_VOLUME_FRACTION.path,
                    format!(
                        "gives {} spheres in {} = {}; between 1 and 1e8 are allowed",
                        show(n),
                        size_key.path,
                        show(l)
                    ),
                ));
            }
            (n as usize, l)
        }
        _ => bail!(ParamError::new(
            SYSTEM.path,
            format!(
                "give exactly two of system.particles, system.volume_fraction and {}",
                size_key.path
            ),
        )),
    };
    let phi = n_eq(particles) * unit * d.powi(3) / size.powi(3);
    if phi > MAX_PHI {
        bail!(ParamError::new(
            SYSTEM_VOLUME_FRACTION.path,
            format!(
                "{particles} spheres in {} = {} pack to {:.4}, above random close packing {MAX_PHI}",
                size_key.path,
                show(size),
                phi
            ),
        ));
    }
    let interface = if geometry == "interface" {
        let i = shared::interface(r, d, kt, None)?;
        Some([i.stiffness, i.range, i.offset])
    } else {
        if r.has(&INTERFACE) {
            bail!(ParamError::new(
                INTERFACE.path,
                format!("applies to system.geometry = \"interface\" only, not \"{geometry}\""),
            ));
        }
        None
    };
    let shape = if bulk {
        Geometry::Bulk { edge: size }
    } else if let Some([k, range, offset]) = interface {
        Geometry::interface(size, k, range, offset, kt).map_err(keyed)?
    } else {
        if size <= 0.5 * d_max {
            bail!(ParamError::new(
                SYSTEM_RADIUS.path,
                format!(
                    "must exceed d/2 = {} (the largest diameter), got {}",
                    show(0.5 * d_max),
                    show(size)
                ),
            ));
        }
        Geometry::HardWall { radius: size }
    };
    let diameters = species.as_ref().map_or(vec![d], |m| m.diameters.clone());
    let box_edge = shape.box_edge_of(d, &diameters);
    if bulk && box_edge < 2.0 * d_max {
        bail!(ParamError::new(
            SYSTEM_BOX.path,
            format!(
                "must be at least 2 d = {} (the cells need two per edge; d the largest diameter), got {}",
                show(2.0 * d_max),
                show(box_edge)
            ),
        ));
    }
    // The engine's cell grid over the box (cells of at least 2 d, as HardSphereMc::new makes
    // it): a radius or box of 1e18 diameters is refused here, before check or run go on.
    let cells = (box_edge / (2.0 * d)).floor().max(2.0).powi(3);
    ensure_fits(
        size_key.path,
        &format!(
            "a grid of {cells:.3e} Monte Carlo cells over a box of edge {}",
            show(box_edge)
        ),
        cells * 228.0,
    )?;
    let sweeps = r.count(&MC_SWEEPS)?;
    let target_acceptance = r.number(&MC_TARGET_ACCEPTANCE)?;
    if !(target_acceptance > 0.0 && target_acceptance < 1.0) {
        bail!(ParamError::new(
            MC_TARGET_ACCEPTANCE.path,
            format!(
                "must lie strictly between 0 and 1, got {}",
                show(target_acceptance)
            ),
        ));
    }
    let sample_every = r.count(&MC_SAMPLE_EVERY)?;
    let blocks = r.count(&MC_BLOCKS)? as usize;
    let samples = sweeps.div_ceil(sample_every);
    if blocks as u64 > samples {
        bail!(ParamError::new(
            MC_BLOCKS.path,
            format!(
                "must be at most the number of samples, mc.sweeps / mc.sample_every = {samples}, got {blocks}"
            ),
        ));
    }
    let chain_length = match r.word(&MC_MOVE)?.as_str() {
        "event-chain" => {
            if r.has(&MC_NSELECT) {
                bail!(ParamError::new(
                    MC_NSELECT.path,
                    "applies to mc.move = \"local\" only (a sweep of event chains makes about N lifts; set its chains' length with mc.chain_length)",
                ));
            }
            let l = r
                .opt_number(&MC_CHAIN_LENGTH)?
                .unwrap_or(0.5 * d * (particles as f64).cbrt());
            if !(l > 0.0 && l <= MAX_CHAIN_LENGTH * d) {
                bail!(ParamError::new(
                    MC_CHAIN_LENGTH.path,
                    format!(
                        "must lie in (0, {MAX_CHAIN_LENGTH:e} d = {}], got {}",
                        show(MAX_CHAIN_LENGTH * d),
                        show(l)
                    ),
                ));
            }
            Some(l)
        }
        _ => {
            if r.has(&MC_CHAIN_LENGTH) {
                bail!(ParamError::new(
                    MC_CHAIN_LENGTH.path,
                    "applies to mc.move = \"event-chain\" only",
                ));
            }
            None
        }
    };
    let profile_bins = r.count(&OUTPUT_PROFILE_BINS)? as usize;
    let gr_bins = r.count(&OUTPUT_GR_BINS)? as usize;
    let half = 0.5 * box_edge;
    // Just under half the box: freud's RDF (and any AABB query) refuses exactly L/2.
    let gr_max = r.opt_number(&OUTPUT_GR_MAX)?.unwrap_or(0.98 * half);
    if gr_max > half * (1.0 + 1e-12) {
        bail!(ParamError::new(
            OUTPUT_GR_MAX.path,
            format!(
                "must lie in (0, L/2 = {}], got {}",
                show(half),
                show(gr_max)
            ),
        ));
    }
    if gr_max <= d {
        bail!(ParamError::new(
            OUTPUT_GR_MAX.path,
            format!(
                "{} is not beyond the diameter {}: hard spheres never come closer, so g(r) would hold no pair (and its shells' volumes underflow as gr_max goes to 0); use gr_max > d, e.g. 3 d to 5 d",
                show(gr_max),
                show(d)
            ),
        ));
    }
    let rho2_r_bins = r.count(&OUTPUT_RHO2_R_BINS)? as usize;
    let rho2_bins = (rho2_r_bins > 0)
        .then(|| -> Result<_> { Ok((rho2_r_bins, r.count(&OUTPUT_RHO2_COS_BINS)? as usize)) })
        .transpose()?;
    r.count(&OUTPUT_RHO2_COS_BINS)?;
    // g2.csv has a row per cell of (r1, r2, cos theta).
    if let Some((nr, nc)) = rho2_bins
        && nr * nr * nc > MAX_RHO2_CELLS
    {
        bail!(ParamError::new(
            OUTPUT_RHO2_R_BINS.path,
            format!(
                "{nr}^2 radial x {nc} angular bins (output.rho2_cos_bins) are {} cells of rho2 and rows of g2.csv: at most {MAX_RHO2_CELLS}",
                nr * nr * nc
            ),
        ));
    }
    if bulk && rho2_bins.is_some() {
        bail!(ParamError::new(
            OUTPUT_RHO2_R_BINS.path,
            "applies to the droplet geometries only (give 0 or leave it out in bulk)",
        ));
    }
    // The pair interaction, built for the species (one of the final diameter without a
    // mixture) to check it; event chains are for hard spheres.
    let one = Mixture::one(diameters[0], particles);
    let pair = crate::keys::species::pair(r, species.as_ref().unwrap_or(&one), kt, base)?;
    if pair.is_some() && chain_length.is_some() {
        bail!(ParamError::new(
            MC_MOVE.path,
            "event chains are for hard spheres: with [pair] use mc.move = \"local\"",
        ));
    }
    let species = species.filter(|m| !m.is_single());
    if let Some(m) = &species
        && rho2_bins.is_some()
    {
        bail!(ParamError::new(
            OUTPUT_RHO2_R_BINS.path,
            format!(
                "the two-body density and g2 have no support for mixtures yet ({} species in system.species): give 0 or leave it out",
                m.len()
            ),
        ));
    }
    let rho2_cells = rho2_bins.map_or(0.0, |(r, c)| (r * r * c) as f64);
    // Positions (particle order, scratch and slots), histograms of every block.
    let kinds = species.as_ref().map_or(1, |m| m.len());
    let bytes = particles as f64 * 200.0
        + blocks as f64
            * 8.0
            * (((kinds + 1) * profile_bins + gr_bins + 100 * kinds * kinds) as f64 + rho2_cells);
    ensure_fits(
        SYSTEM_PARTICLES.path,
        &format!("{particles} spheres"),
        bytes,
    )?;
    Ok(McRun {
        seed,
        particles,
        // One species declared is the plain run: its diameter, no mixture.
        diameter: if species.is_none() { diameters[0] } else { d },
        mixture: species,
        geometry,
        volume_fraction: phi,
        radius: (!bulk).then_some(size),
        box_edge,
        kt,
        interface,
        sweeps,
        nselect: r.count(&MC_NSELECT)? as usize,
        chain_length,
        warmup_sweeps: r.count(&MC_WARMUP_SWEEPS)?,
        target_acceptance,
        tune_every: r.count(&MC_TUNE_EVERY)?,
        sample_every,
        delta: r.number(&MC_DELTA)?,
        blocks,
        profile_bins,
        gr_bins,
        gr_max,
        trajectory_every: r.count(&OUTPUT_TRAJECTORY_EVERY)?,
        rho2_bins,
        initial: r.file(&SYSTEM_INITIAL).map(|f| base.join(f)),
        pair,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scenario with every table, so that every key is read.
    const FULL: &str = r#"
method = "hs-mc"
[system]
geometry = "interface"
particles = 100
radius = 5.0
initial = "start.gsd"
[interface]
stiffness = 50.0
[mc]
sweeps = 1000
[output]
rho2_r_bins = 4
"#;

    fn table(text: &str) -> toml::Table {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn every_declared_key_is_read() {
        let t = table(FULL);
        let r = Reader::new(&t, KEYS).unwrap();
        resolve(&r, Path::new("."), None).unwrap();
        // The species keys are read by kind (counts or volume fractions) and the pair keys by
        // pair.kind: tests/hs_mc_species.rs and tests/species.rs read each.
        let unread: Vec<&str> = r
            .unread()
            .into_iter()
            .filter(|k| !k.starts_with("system.species.") && !k.starts_with("pair"))
            .collect();
        assert_eq!(unread, Vec::<&str>::new());
    }

    #[test]
    fn derived_defaults_are_computed_from_the_keys_they_name() {
        let run = read(&table(FULL), Path::new("."), None).unwrap();
        assert_eq!(run.delta, 0.1 * run.diameter);
        let [k, range, offset] = run.interface.unwrap();
        assert_eq!((k, range, offset), (50.0, 0.5, -0.5));
        let wide = FULL.replace("radius = 5.0", "radius = 5.0\ndiameter = 2.0\nkT = 3.0");
        let wide = wide.replace("particles = 100", "particles = 10");
        let run = read(&table(&wide), Path::new("."), None).unwrap();
        assert_eq!(run.delta, 0.2);
        assert_eq!(run.interface.unwrap()[1..], [1.0, -1.0]);
    }

    #[test]
    fn the_engine_s_checks_name_the_scenario_key() {
        let bad = FULL.replace("stiffness = 50.0", "stiffness = 50.0\noffset = -9.0");
        let e = format!(
            "{:#}",
            read(&table(&bad), Path::new("."), None).unwrap_err()
        );
        assert!(e.starts_with("interface.offset:"), "{e}");
        let both = FULL.replace("radius = 5.0", "radius = 5.0\nbox = 3.0");
        let e = format!(
            "{:#}",
            read(&table(&both), Path::new("."), None).unwrap_err()
        );
        assert!(e.starts_with("system.box: does not apply"), "{e}");
    }

    /// rho2's cells, each a row of g2.csv, are bounded (a fuzzed 3202 radial bins took 31 s
    /// and wrote 2e8 rows); the bound itself is accepted.
    #[test]
    fn too_many_rho2_cells_are_refused_naming_the_key() {
        let at = |r: usize, c: usize| {
            let t = FULL.replace(
                "rho2_r_bins = 4",
                &format!("rho2_r_bins = {r}\nrho2_cos_bins = {c}"),
            );
            read(&table(&t), Path::new("."), None).map(|_| ())
        };
        at(100, 100).unwrap();
        let e = format!("{:#}", at(100, 101).unwrap_err());
        assert!(
            e.starts_with("output.rho2_r_bins: 100^2 radial x 101"),
            "{e}"
        );
    }
}
