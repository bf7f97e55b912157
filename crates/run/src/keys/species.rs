//! `[system.species]` and `[pair]`: the colloid species and the pair interaction of every
//! species pair, declared once for the Brownian-dynamics methods (docs/species.md). Without
//! them a run has one species of diameter `system.diameter` and WCA spheres (eps = kT).

use super::Allowed::*;
use super::Omitted::*;
use super::{Reader, Spec, key};
use anyhow::{Result, bail};
use colloidsim_core::ParamError;
use colloidsim_core::output::read_table;
use colloidsim_particles::{Mixture, PairSpec};
use std::path::Path;

/// Most species a scenario may declare (named A to Z).
pub const MAX_SPECIES: usize = 26;

/// `[system.species]`.
pub const SPECIES: Spec = key(
    "system.species",
    "-",
    Means("one species of diameter system.diameter"),
    Table,
    "several colloid species, named A, B, ... in the order given (GSD type names)",
);

/// `system.species.diameters`.
pub const SPECIES_DIAMETERS: Spec = key(
    "system.species.diameters",
    "length",
    Required,
    Numbers(0.0, f64::MAX, None),
    "diameter of each species; the smallest is the length d of the defaults (skin, dt, interface)",
)
.also("1 to 26 species, each > 0; replaces system.diameter");

/// `system.species.counts`.
pub const SPECIES_COUNTS: Spec = key(
    "system.species.counts",
    "-",
    Means("from volume_fractions"),
    Numbers(0.0, 1e8, None),
    "number of particles of each species",
)
.also("whole numbers, one per species, summing to system.particles; give this or volume_fractions");

/// `system.species.volume_fractions`.
pub const SPECIES_VOLUME_FRACTIONS: Spec = key(
    "system.species.volume_fractions",
    "-",
    Means("from counts"),
    Numbers(0.0, 1.0, None),
    "each species' share of the colloids' volume (N_s d_s^3 / sum_t N_t d_t^3); counts rounded to sum to system.particles",
)
.also("one per species, summing to 1; give this or counts");

/// `[pair]`.
pub const PAIR: Spec = key(
    "pair",
    "-",
    Means("WCA, eps = kT, at each pair's mean diameter"),
    Table,
    "the pair interaction of every species pair, at the pair's contact distance (d_i + d_j) / 2",
);

/// `pair.kind`.
pub const PAIR_KIND: Spec = key(
    "pair.kind",
    "-",
    Word("wca"),
    OneOf(&["wca", "lj", "yukawa", "morse", "ao", "table"]),
    "WCA; Lennard-Jones; WCA + DLVO screened Coulomb; Morse on the surface distance; WCA + Asakura-Oosawa depletion; a table",
);

/// `pair.epsilon`.
pub const PAIR_EPSILON: Spec = key(
    "pair.epsilon",
    "energy",
    Means("kT for every pair"),
    Numbers(0.0, f64::MAX, None),
    "wca, lj: well depth per unordered species pair (AA, AB, ..., BB, ...)",
)
.also("one value (every pair) or one per unordered pair");

/// `pair.cutoff`.
pub const PAIR_CUTOFF: Spec = key(
    "pair.cutoff",
    "contact distances",
    Means("2.5"),
    Closed(1.0, 100.0),
    "lj: cut-off (shifted to zero there), in units of the pair's contact distance",
);

/// `pair.charges`.
pub const PAIR_CHARGES: Spec = key(
    "pair.charges",
    "elementary charges",
    Means("required for yukawa"),
    Numbers(-1e9, 1e9, None),
    "yukawa: charge number Z of each species",
);

/// `pair.bjerrum_length`.
pub const PAIR_BJERRUM: Spec = key(
    "pair.bjerrum_length",
    "length",
    Means("required for yukawa"),
    Positive,
    "yukawa: Bjerrum length l_B = e^2 / (4 pi eps kT) (water at 25 C: 0.71 nm)",
)
.plausible();

/// `pair.debye_length`.
pub const PAIR_DEBYE: Spec = key(
    "pair.debye_length",
    "length",
    Means("required for yukawa"),
    Positive,
    "yukawa: Debye screening length 1 / kappa",
)
.plausible();

/// `pair.range`.
pub const PAIR_RANGE: Spec = key(
    "pair.range",
    "length",
    Means("yukawa: 5 Debye lengths; morse: h0 + 8 / kappa"),
    Positive,
    "yukawa, morse: cut-off beyond contact (surface distance), shifted to zero there",
)
.plausible();

/// `pair.depth`.
pub const PAIR_DEPTH: Spec = key(
    "pair.depth",
    "energy",
    Means("required for morse"),
    NonNegative,
    "morse: well depth D",
);

/// `pair.kappa`.
pub const PAIR_KAPPA: Spec = key(
    "pair.kappa",
    "1 / length",
    Means("required for morse"),
    Positive,
    "morse: inverse range k of U = D [exp(-2k(h - h0)) - 2 exp(-k(h - h0))]",
);

/// `pair.h0`.
pub const PAIR_H0: Spec = key(
    "pair.h0",
    "length",
    Means("0"),
    Finite,
    "morse: surface distance of the minimum",
)
.plausible();

/// `pair.depletant_diameter`.
pub const PAIR_DEPLETANT_DIAMETER: Spec = key(
    "pair.depletant_diameter",
    "length",
    Means("required for ao"),
    Positive,
    "ao: diameter sigma_p of the ideal depletant (polymer coil)",
)
.plausible();

/// `pair.depletant_fraction`.
pub const PAIR_DEPLETANT_FRACTION: Spec = key(
    "pair.depletant_fraction",
    "-",
    Means("required for ao"),
    Closed(0.0, 10.0),
    "ao: depletant reservoir volume fraction phi_p = n_p pi sigma_p^3 / 6",
);

/// `pair.table`.
pub const PAIR_TABLE: Spec = key(
    "pair.table",
    "-",
    Means("required for table"),
    Path,
    "table: CSV with columns r, U_AA, F_AA, U_AB, F_AB, ... (energy and force -dU/dr per unordered pair) on a uniform grid of r",
);

/// The keys of this module, in the order `colloidsim keys` lists them (species after
/// `system.diameter`, the pair table after the spheres).
pub const SPECIES_KEYS: [Spec; 4] = [
    SPECIES,
    SPECIES_DIAMETERS,
    SPECIES_COUNTS,
    SPECIES_VOLUME_FRACTIONS,
];

/// A method's key list (a `&[Spec]` expression) with the `[pair]` block spliced in once: the
/// keys `head`, then the table `pair` (`PAIR`, or a method's own declaration of it) and every key
/// under it, then `tail`.
macro_rules! keys_with_pair {
    ([$($head:expr),* $(,)?], $pair:expr, [$($tail:expr),* $(,)?]) => {
        &[
            $($head,)*
            $pair,
            $crate::keys::species::PAIR_KIND,
            $crate::keys::species::PAIR_EPSILON,
            $crate::keys::species::PAIR_CUTOFF,
            $crate::keys::species::PAIR_CHARGES,
            $crate::keys::species::PAIR_BJERRUM,
            $crate::keys::species::PAIR_DEBYE,
            $crate::keys::species::PAIR_RANGE,
            $crate::keys::species::PAIR_DEPTH,
            $crate::keys::species::PAIR_KAPPA,
            $crate::keys::species::PAIR_H0,
            $crate::keys::species::PAIR_DEPLETANT_DIAMETER,
            $crate::keys::species::PAIR_DEPLETANT_FRACTION,
            $crate::keys::species::PAIR_TABLE,
            $($tail),*
        ]
    };
}
pub(crate) use keys_with_pair;

/// The `[pair]` keys.
pub const PAIR_KEYS: &[Spec] = keys_with_pair!([], PAIR, []);

/// The smallest species diameter when the scenario has `[system.species]` (the derived
/// default of `system.diameter`), the diameters checked first.
pub fn smallest_diameter(r: &Reader) -> Result<Option<f64>> {
    if !r.declares(&SPECIES) || !r.has(&SPECIES) {
        return Ok(None);
    }
    Ok(diameters(r)?.into_iter().reduce(f64::min))
}

/// `system.species.diameters`, checked: 1 to 26, each finite and > 0, size ratio at most 100.
fn diameters(r: &Reader) -> Result<Vec<f64>> {
    let diameters = r.numbers(&SPECIES_DIAMETERS)?;
    let n = diameters.len();
    if !(1..=MAX_SPECIES).contains(&n) {
        bail!(ParamError::new(
            SPECIES_DIAMETERS.path,
            format!("must list 1 to {MAX_SPECIES} diameters, got {n}"),
        ));
    }
    if let Some(x) = diameters.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
        bail!(ParamError::new(
            SPECIES_DIAMETERS.path,
            format!("every diameter must be a finite number > 0, got {x}"),
        ));
    }
    let ratio = diameters.iter().copied().fold(0.0, f64::max)
        / diameters.iter().copied().fold(f64::INFINITY, f64::min);
    if ratio > 100.0 {
        bail!(ParamError::new(
            SPECIES_DIAMETERS.path,
            format!(
                "a size ratio of {ratio:.4} is more than 100: the time step of the smallest and the neighbour cells of the largest cannot both be resolved"
            ),
        ));
    }
    Ok(diameters)
}

/// The species of a run of `particles` colloids (one of diameter `d` without
/// `[system.species]`); each error names the key.
pub fn species(r: &Reader, particles: usize, d: f64, diameter_key: &Spec) -> Result<Mixture> {
    if !r.has(&SPECIES) {
        return Ok(Mixture::one(d, particles));
    }
    if r.has(diameter_key) {
        bail!(ParamError::new(
            diameter_key.path,
            "give the diameters in system.species.diameters, not system.diameter as well",
        ));
    }
    let diameters = diameters(r)?;
    let n = diameters.len();
    let counts = match (r.has(&SPECIES_COUNTS), r.has(&SPECIES_VOLUME_FRACTIONS)) {
        (true, true) | (false, false) => bail!(ParamError::new(
            SPECIES_COUNTS.path,
            "give either system.species.counts or system.species.volume_fractions (one of them)",
        )),
        (true, false) => {
            let c = r.numbers(&SPECIES_COUNTS)?;
            if c.len() != n || c.iter().any(|x| x.fract() != 0.0) {
                bail!(ParamError::new(
                    SPECIES_COUNTS.path,
                    format!("needs {n} whole numbers (one per diameter), got {c:?}"),
                ));
            }
            let c: Vec<usize> = c.iter().map(|&x| x as usize).collect();
            if c.iter().sum::<usize>() != particles {
                bail!(ParamError::new(
                    SPECIES_COUNTS.path,
                    format!(
                        "{c:?} sum to {}, not to system.particles = {particles}",
                        c.iter().sum::<usize>()
                    ),
                ));
            }
            c
        }
        (false, true) => {
            let x = r.numbers(&SPECIES_VOLUME_FRACTIONS)?;
            let sum: f64 = x.iter().sum();
            if x.len() != n || (sum - 1.0).abs() > 1e-9 {
                bail!(ParamError::new(
                    SPECIES_VOLUME_FRACTIONS.path,
                    format!(
                        "needs {n} shares (one per diameter) summing to 1, got {x:?} (sum {sum})"
                    ),
                ));
            }
            Mixture::counts_from_volume_shares(particles, &diameters, &x)
        }
    };
    if let Some(s) = counts.iter().position(|&c| c == 0) {
        bail!(ParamError::new(
            SPECIES_COUNTS.path,
            format!(
                "species {} would have no particles (counts {counts:?}); leave it out",
                (b'A' + s as u8) as char
            ),
        ));
    }
    Ok(Mixture::new(diameters, counts))
}

/// The `[pair]` table read into a [`PairSpec`] for the species of `mixture` (`None`: the WCA
/// default), built once to check it; `base` is the scenario's folder (for `pair.table`).
pub fn pair(r: &Reader, mixture: &Mixture, kt: f64, base: &Path) -> Result<Option<PairSpec>> {
    if !r.has(&PAIR) {
        return Ok(None);
    }
    let kind = r.word(&PAIR_KIND)?;
    let uses: &[&Spec] = match kind.as_str() {
        "wca" => &[&PAIR_EPSILON],
        "lj" => &[&PAIR_EPSILON, &PAIR_CUTOFF],
        "yukawa" => &[&PAIR_CHARGES, &PAIR_BJERRUM, &PAIR_DEBYE, &PAIR_RANGE],
        "morse" => &[&PAIR_DEPTH, &PAIR_KAPPA, &PAIR_H0, &PAIR_RANGE],
        "ao" => &[&PAIR_DEPLETANT_DIAMETER, &PAIR_DEPLETANT_FRACTION],
        _ => &[&PAIR_TABLE],
    };
    // Keys of other kinds are consulted and left unused (a scenario may switch kinds).
    let _unused: Vec<bool> = PAIR_KEYS[2..]
        .iter()
        .filter(|k| !uses.iter().any(|u| u.path == k.path))
        .map(|k| r.has(k))
        .collect();
    let need = |k: &Spec| -> Result<f64> {
        r.opt_number(k)?.ok_or_else(|| {
            ParamError::new(
                k.path,
                format!("required for pair.kind = \"{kind}\" ({})", k.doc),
            )
            .into()
        })
    };
    let epsilon = || -> Result<Vec<f64>> {
        Ok(match r.opt_numbers(&PAIR_EPSILON)? {
            None => vec![kt; mixture.pairs()],
            Some(v) if v.len() == 1 => vec![v[0]; mixture.pairs()],
            Some(v) => v,
        })
    };
    let spec = match kind.as_str() {
        "wca" => PairSpec::Wca {
            epsilon: epsilon()?,
        },
        "lj" => PairSpec::Lj {
            epsilon: epsilon()?,
            cutoff: r.opt_number(&PAIR_CUTOFF)?.unwrap_or(2.5),
        },
        "yukawa" => {
            let debye_length = need(&PAIR_DEBYE)?;
            PairSpec::Yukawa {
                charges: r.opt_numbers(&PAIR_CHARGES)?.ok_or_else(|| {
                    ParamError::new(
                        PAIR_CHARGES.path,
                        "required for pair.kind = \"yukawa\": one charge number per species",
                    )
                })?,
                bjerrum_length: need(&PAIR_BJERRUM)?,
                debye_length,
                range: r.opt_number(&PAIR_RANGE)?.unwrap_or(5.0 * debye_length),
            }
        }
        "morse" => {
            let (kappa, h0) = (need(&PAIR_KAPPA)?, r.opt_number(&PAIR_H0)?.unwrap_or(0.0));
            PairSpec::Morse {
                depth: need(&PAIR_DEPTH)?,
                kappa,
                h0,
                h_cut: r.opt_number(&PAIR_RANGE)?.unwrap_or(h0 + 8.0 / kappa),
            }
        }
        "ao" => PairSpec::Ao {
            depletant_diameter: need(&PAIR_DEPLETANT_DIAMETER)?,
            depletant_fraction: need(&PAIR_DEPLETANT_FRACTION)?,
        },
        _ => {
            let file = r.file(&PAIR_TABLE).ok_or_else(|| {
                ParamError::new(
                    PAIR_TABLE.path,
                    "required for pair.kind = \"table\": a CSV file of r, U_AA, F_AA, ...",
                )
            })?;
            let path = base.join(file);
            let (header, cols) =
                read_table(&path).map_err(|e| ParamError::new(PAIR_TABLE.path, e))?;
            let mut energy = Vec::new();
            let mut force = Vec::new();
            for a in 0..mixture.len() {
                for b in a..mixture.len() {
                    let name = mixture.pair_name(a, b);
                    let col = |prefix: &str| -> Result<Vec<f64>> {
                        let want = format!("{prefix}_{name}");
                        match header.iter().position(|h| *h == want) {
                            Some(k) => Ok(cols[k].clone()),
                            None => bail!(ParamError::new(
                                PAIR_TABLE.path,
                                format!(
                                    "{}: no column {want} (columns: {})",
                                    path.display(),
                                    header.join(", ")
                                ),
                            )),
                        }
                    };
                    energy.push(col("U")?);
                    force.push(col("F")?);
                }
            }
            let Some(k) = header.iter().position(|h| h == "r") else {
                bail!(ParamError::new(
                    PAIR_TABLE.path,
                    format!("{}: no column r", path.display())
                ));
            };
            PairSpec::Table {
                r: cols[k].clone(),
                energy,
                force,
            }
        }
    };
    // Built once here, so that a bad parameter is refused before any run.
    spec.build(&mixture.diameters, kt).map_err(|e| {
        let key = PAIR_KEYS
            .iter()
            .find(|k| k.path.strip_prefix("pair.") == Some(e.key.as_str()))
            .map_or(PAIR.path, |k| k.path);
        ParamError::new(key, e.message)
    })?;
    Ok(Some(spec))
}
