//! The per-species files of a droplet of two or more species, shared by droplet-bd (errors
//! over replicas) and hs-mc (errors over blocks): `species_profile_<f>.csv` and
//! `species_profiles.png` (docs/species.md).

use crate::output::plot::{Scale, Series, line_plot_with_errors, picture};
use anyhow::Result;
use colloidsim_core::output::OutputDir;

/// One species profile table: `r`, then `phi_<name>` and `err_<name>` of each species
/// (`phi[s]`, `err[s]` on the bins `r`); with `no_error`, every error column is explained with
/// that reason (it could not be estimated). Adds `file` to `files`.
pub fn write_species_profile(
    out: &OutputDir,
    file: &str,
    r: &[f64],
    names: &[String],
    phi: &[Vec<f64>],
    err: &[Vec<f64>],
    no_error: Option<&str>,
    files: &mut Vec<String>,
) -> Result<()> {
    let mut cols: Vec<(String, &[f64])> = vec![("r".into(), r)];
    for (s, name) in names.iter().enumerate() {
        cols.push((format!("phi_{name}"), &phi[s]));
        cols.push((format!("err_{name}"), &err[s]));
    }
    let refs: Vec<(&str, &[f64])> = cols.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    out.write_table(file, &refs)?;
    if let Some(why) = no_error {
        for name in names {
            out.explain(file, &format!("err_{name}"), why);
        }
    }
    files.push(file.into());
    Ok(())
}

/// `species_profiles.png`: the profiles `(label, x, phi)` against `xlabel`, with error bars
/// where `errors` gives them (one entry per series, or none at all); a picture that cannot be
/// drawn is a warning.
pub fn draw_species_profiles(
    out: &OutputDir,
    title: &str,
    xlabel: &str,
    shown: &[(String, Vec<f64>, Vec<f64>)],
    errors: &[Option<&[f64]>],
    files: &mut Vec<String>,
    warnings: &mut Vec<String>,
) {
    let series: Vec<Series> = shown
        .iter()
        .map(|(label, x, y)| Series {
            label,
            x,
            y,
            points: false,
        })
        .collect();
    picture(
        line_plot_with_errors(
            &out.join("species_profiles.png"),
            title,
            xlabel,
            "volume fraction phi_k(r)",
            &series,
            errors,
            Scale::Linear,
        ),
        "species_profiles.png",
        files,
        warnings,
    );
}
