//! What a droplet of two or more species adds to the outputs: per-species profiles with their
//! errors (`species_profile_<fraction>.csv`, `species_profiles.png`: [`write_species_profile`],
//! [`draw_species_profiles`], shared with hs-mc, whose errors are over blocks) and, for a
//! drying run (`droplet-bd`, `droplet-mpcd`, errors over the replicas: [`SpeciesAccum`]), the
//! stratification measures of [`colloidsim_analysis::stratification`] at every profile time
//! (`stratification.csv`, `stratification.png`, `stratification` in summary.json).

use crate::output::plot::{Scale, Series, line_plot_with_errors, picture};
use crate::output::profile_name;
use anyhow::Result;
use colloidsim_analysis::stratification;
use colloidsim_core::output::OutputDir;
use colloidsim_particles::Mixture;
use serde::{Deserialize, Serialize};
use serde_json::json;

/// Why an error over the replicas is missing (droplet-bd).
pub const ONE_REPLICA: &str =
    "one replica: no spread to estimate an error from (set replicas >= 2)";

/// What the species outputs need to know of a drying run.
#[derive(Debug, Clone)]
pub struct SpeciesRun<'a> {
    /// The species.
    pub mixture: &'a Mixture,
    /// Radial bins of the profiles.
    pub bins: usize,
    /// Fractions of the drying time at which profiles are taken.
    pub fractions: &'a [f64],
    /// Time of each profile.
    pub times: Vec<f64>,
    /// Droplet radius at each of those times.
    pub radii: Vec<f64>,
    /// Replicas of the run.
    pub replicas: usize,
    /// Why an error over the replicas is missing with one (the method's advice).
    pub one_replica: &'static str,
}
/// Why a shell enrichment is missing.
const EMPTY_SHELL: &str =
    "no centre in the outer shell R - d_large < r, or no small sphere in the droplet";

/// Why the error of a shell enrichment is missing.
const FEW_SHELLS: &str =
    "fewer than two replicas with a centre in the outer shell (set replicas >= 2)";

/// Per profile fraction, what the replicas that reached it gave (saved in checkpoints).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct SpeciesAccum {
    /// `[fraction][species][bin]`: sum over replicas of the species' volume fraction.
    sums: Vec<Vec<Vec<f64>>>,
    /// The same, of its square.
    squares: Vec<Vec<Vec<f64>>>,
    /// `[fraction][replica]`: mean radius of each species over R, then the radius
    /// difference, the shell enrichment and the small-layer thickness.
    measures: Vec<Vec<Vec<f64>>>,
}

impl SpeciesAccum {
    /// Record the spheres at `pos` (diameters `diameter`, species `typeid`) at profile `j`
    /// (radius `radius`).
    pub fn record(
        &mut self,
        p: &SpeciesRun,
        j: usize,
        pos: &[[f64; 3]],
        diameter: &[f64],
        typeid: &[u32],
        radius: f64,
    ) {
        let n = p.mixture.len();
        if n < 2 {
            return;
        }
        let k = p.fractions.len();
        if self.sums.len() != k {
            self.sums = vec![vec![vec![0.0; p.bins]; n]; k];
            self.squares = self.sums.clone();
            self.measures = vec![Vec::new(); k];
        }
        let s = stratification(pos, diameter, typeid, &p.mixture.diameters, radius, p.bins);
        for (sp, phi) in s.phi.iter().enumerate() {
            for (b, x) in phi.iter().enumerate() {
                self.sums[j][sp][b] += x;
                self.squares[j][sp][b] += x * x;
            }
        }
        let mut m = s.mean_radius.clone();
        m.extend([
            s.radius_difference,
            s.shell_enrichment,
            s.small_layer_thickness,
        ]);
        self.measures[j].push(m);
    }

    /// Write the files of the profiles `drawn` (indices of fractions reached by `counts[j]`
    /// replicas, at droplet radii `radii`, on shells `r_axes`); the final stratification for
    /// summary.json (`Null` with one species).
    pub fn write(
        &self,
        out: &OutputDir,
        p: &SpeciesRun,
        drawn: &[usize],
        counts: &[u64],
        radii: &[f64],
        r_axes: &[Vec<f64>],
        files: &mut Vec<String>,
        warnings: &mut Vec<String>,
    ) -> Result<serde_json::Value> {
        if p.mixture.len() < 2 || self.sums.is_empty() || drawn.is_empty() {
            return Ok(serde_json::Value::Null);
        }
        let names = &p.mixture.names;
        let mean_err = |sum: f64, sq: f64, m: f64| {
            let mean = sum / m;
            let var = (sq / m - mean * mean).max(0.0) * m / (m - 1.0);
            (mean, (var / m).sqrt())
        };
        let mut shown: Vec<(String, Vec<f64>, Vec<f64>)> = Vec::new();
        for &j in drawn {
            let m = counts[j] as f64;
            let name = format!("species_{}", profile_name(p.fractions[j]));
            let (mut phi, mut err) = (Vec::new(), Vec::new());
            for (sp, sname) in names.iter().enumerate() {
                let (mean, e): (Vec<f64>, Vec<f64>) = self.sums[j][sp]
                    .iter()
                    .zip(&self.squares[j][sp])
                    .map(|(s, q)| mean_err(*s, *q, m))
                    .unzip();
                if j == drawn[0] || j == drawn[drawn.len() - 1] {
                    let x: Vec<f64> = r_axes[j].iter().map(|r| r / radii[j]).collect();
                    shown.push((
                        format!("{sname}, t = {:.0} %", p.fractions[j] * 100.0),
                        x,
                        mean.clone(),
                    ));
                }
                phi.push(mean);
                err.push(e);
            }
            let no_error = (m < 2.0).then_some(p.one_replica);
            write_species_profile(out, &name, &r_axes[j], names, &phi, &err, no_error, files)?;
        }
        // The measures: mean and standard error over the replicas (those that are finite).
        let n = names.len();
        let mut header: Vec<String> = vec!["fraction".into(), "t".into(), "R".into()];
        for sname in names {
            header.push(format!("mean_radius_{sname}"));
            header.push(format!("mean_radius_{sname}_err"));
        }
        for what in [
            "radius_difference",
            "shell_enrichment",
            "small_layer_thickness",
        ] {
            header.push(what.into());
            header.push(format!("{what}_err"));
        }
        let mut rows = Vec::new();
        let mut last = Vec::new();
        for &j in drawn {
            let mut row = vec![p.fractions[j], p.times[j], p.radii[j]];
            last.clear();
            for k in 0..n + 3 {
                let v: Vec<f64> = self.measures[j]
                    .iter()
                    .map(|m| m[k])
                    .filter(|x| x.is_finite())
                    .collect();
                let m = v.len() as f64;
                let mean = if v.is_empty() {
                    f64::NAN
                } else {
                    v.iter().sum::<f64>() / m
                };
                let err = if v.len() < 2 {
                    f64::NAN
                } else {
                    (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (m - 1.0) / m).sqrt()
                };
                row.extend([mean, err]);
                last.push((mean, err));
            }
            rows.push(row);
        }
        let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
        out.write_rows("stratification.csv", &hdr, &rows)?;
        for (k, h) in header.iter().enumerate().skip(3) {
            if rows.iter().any(|r| !r[k].is_finite()) {
                let why = match (h.starts_with("shell_enrichment"), h.ends_with("_err")) {
                    (true, false) => EMPTY_SHELL,
                    (true, true) => FEW_SHELLS,
                    _ => p.one_replica,
                };
                out.explain("stratification.csv", h, why);
            }
        }
        files.push("stratification.csv".into());
        // Pictures: the species' profiles at the first and last times, the measures in time.
        draw_species_profiles(
            out,
            &format!(
                "Species profiles: {} (diameters {:?}), {} replica(s)",
                names.join(", "),
                p.mixture.diameters,
                p.replicas
            ),
            "r / R(t)",
            &shown,
            &[],
            files,
            warnings,
        );
        let x: Vec<f64> = drawn.iter().map(|&j| p.fractions[j]).collect();
        let col =
            |k: usize| -> (Vec<f64>, Vec<f64>) { rows.iter().map(|r| (r[k], r[k + 1])).unzip() };
        let (dr, dr_err) = col(3 + 2 * n);
        let (en, en_err) = col(5 + 2 * n);
        let en1: Vec<f64> = en.iter().map(|e| e - 1.0).collect();
        let labels = ["(<r>_small - <r>_large) / R", "shell enrichment - 1"];
        let series = [
            Series {
                label: labels[0],
                x: &x,
                y: &dr,
                points: true,
            },
            Series {
                label: labels[1],
                x: &x,
                y: &en1,
                points: true,
            },
        ];
        picture(
            line_plot_with_errors(
                &out.join("stratification.png"),
                "Stratification (above 0: small-on-top)",
                "fraction of the drying time",
                "measure",
                &series,
                &[Some(&dr_err), Some(&en_err)],
                Scale::Linear,
            ),
            "stratification.png",
            files,
            warnings,
        );
        let entry = |k: usize| json!({"mean": last[k].0, "err": last[k].1});
        let mut mean_radius = serde_json::Map::new();
        for (k, sname) in names.iter().enumerate() {
            mean_radius.insert(sname.clone(), entry(k));
        }
        Ok(json!({
            "fraction": x.last(),
            "mean_radius": mean_radius,
            "radius_difference": entry(n),
            "shell_enrichment": entry(n + 1),
            "small_layer_thickness": entry(n + 2),
        }))
    }
}

/// One species profile table: `r`, then `rho_v_<name>` (the centre density times the sphere
/// volume, not a volume fraction) and `err_<name>` of each species (`phi[s]`, `err[s]` on the
/// bins `r`); with `no_error`, every error column is explained with
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
        cols.push((format!("rho_v_{name}"), &phi[s]));
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
