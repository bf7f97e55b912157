//! `colloidsim analyse TRAJ.gsd`: the observables of a run — g(r) with its standard error,
//! S(q), the mean-squared displacement, contacts, coordination numbers and clusters, radial
//! profiles about a centre — from any GSD trajectory in the HOOMD schema (HOOMD-blue's,
//! LAMMPS' `dump gsd`, colloidsim's), with the same file names, columns and pictures as a run's
//! outputs (docs/analyse.md).

use crate::Report;
use crate::output::plot::{Scale, Series, Style, line_plot, line_plot_styled, picture};
use crate::output::{PairStructure, write_pair_structure};
use anyhow::{Context, Result, bail};
use colloidsim_analysis::{
    cluster_stats, contacts, coordination_histogram, coordination_numbers,
    mean_squared_displacement, overlap_profile, pair_distribution, radial_profile,
};
use colloidsim_core::output::OutputDir;
use colloidsim_dft::oz;
use colloidsim_particles::gsd::{frame_count, read_frame};
use serde_json::json;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Most g(r) and profile bins.
const MAX_BINS: usize = 100_000;

/// Where the radial profiles are centred.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Centre {
    /// The box centre, the origin of HOOMD's boxes (default).
    Origin,
    /// Each frame's centre of mass of the unwrapped positions (a droplet that drifts).
    CentreOfMass,
    /// A fixed point.
    Point([f64; 3]),
}

impl std::str::FromStr for Centre {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "origin" => Ok(Self::Origin),
            "com" | "centre-of-mass" | "center-of-mass" => Ok(Self::CentreOfMass),
            _ => {
                let v: Vec<f64> = s
                    .split(',')
                    .map(|x| x.trim().parse::<f64>())
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|_| {
                        anyhow::anyhow!("--centre: expected origin, com or x,y,z, got '{s}'")
                    })?;
                match v[..] {
                    [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Self::Point([x, y, z])),
                    _ => bail!(
                        "--centre: expected origin, com or three finite numbers x,y,z, got '{s}'"
                    ),
                }
            }
        }
    }
}

/// Which frames: `first`, `first + stride`, ... up to `last` (inclusive; default the last).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Frames {
    /// First frame (0-based).
    pub first: u64,
    /// Last frame (default: the file's last).
    pub last: Option<u64>,
    /// Every how many frames.
    pub stride: u64,
}

impl Default for Frames {
    fn default() -> Self {
        Self {
            first: 0,
            last: None,
            stride: 1,
        }
    }
}

impl std::str::FromStr for Frames {
    type Err = anyhow::Error;
    /// `FIRST:LAST:STRIDE` as Python's slices without negatives: `10:`, `:100`, `::5`, `7`.
    fn from_str(s: &str) -> Result<Self> {
        let bad = || {
            anyhow::anyhow!(
                "--frames: expected FIRST:LAST:STRIDE (each optional, frames counted from 0), got '{s}'"
            )
        };
        let parts: Vec<&str> = s.split(':').collect();
        if s.trim().is_empty() || parts.len() > 3 {
            return Err(bad());
        }
        let num = |p: Option<&&str>| -> Result<Option<u64>> {
            match p.map(|x| x.trim()) {
                None | Some("") => Ok(None),
                Some(x) => x.parse::<u64>().map(Some).map_err(|_| bad()),
            }
        };
        let first = num(parts.first())?.unwrap_or(0);
        let last = if parts.len() == 1 {
            Some(first)
        } else {
            num(parts.get(1))?
        };
        let stride = num(parts.get(2))?.unwrap_or(1);
        if stride == 0 {
            bail!("--frames: the stride must be at least 1, got '{s}'");
        }
        Ok(Self {
            first,
            last,
            stride,
        })
    }
}

/// What `colloidsim analyse` computes, and where it writes.
#[derive(Debug, Clone, Default)]
pub struct AnalyseOptions {
    /// Output folder (default: the trajectory's name followed by `-analysis`).
    pub out: Option<PathBuf>,
    /// Write into a folder that already holds files.
    pub force: bool,
    /// Particle types analysed, by name (default: all).
    pub types: Option<Vec<String>>,
    /// Frames analysed.
    pub frames: Frames,
    /// Range of g(r) (default `0.49 L`, L the shortest box edge).
    pub r_max: Option<f64>,
    /// Bins of g(r) (default 200).
    pub bins: Option<usize>,
    /// Two spheres touch when their surface gap is below this (default 0.1 mean diameters).
    pub contact_gap: Option<f64>,
    /// Centre of the radial profiles (default the origin).
    pub centre: Option<Centre>,
    /// Bins of the radial profiles (default 50, out to half the shortest box edge).
    pub profile_bins: Option<usize>,
    /// Time per step (default: none; the MSD is then given per step only).
    pub dt: Option<f64>,
    /// Write and draw the hard-sphere Percus–Yevick g(r) at the trajectory's volume fraction
    /// beside the measured one (one diameter only).
    pub percus_yevick: bool,
}

/// The selected particles of one frame.
struct Frame {
    step: u64,
    l: [f64; 3],
    wrapped: Vec<[f64; 3]>,
    unwrapped: Vec<[f64; 3]>,
    diameter: Vec<f64>,
    typeid: Vec<u32>,
}

fn positive(name: &str, v: Option<f64>) -> Result<()> {
    if let Some(x) = v
        && !(x.is_finite() && x > 0.0)
    {
        bail!("{name}: must be a positive finite number, got {x}");
    }
    Ok(())
}

fn bins_in_range(name: &str, v: Option<usize>) -> Result<()> {
    if let Some(b) = v
        && !(1..=MAX_BINS).contains(&b)
    {
        bail!("{name}: must lie in [1, {MAX_BINS}], got {b}");
    }
    Ok(())
}

/// Read the frames `opts` selects, keeping the particles of the selected types.
fn read_frames(path: &Path, opts: &AnalyseOptions) -> Result<(Vec<Frame>, Vec<String>)> {
    let total = frame_count(path)?;
    if total == 0 {
        bail!("{}: the file holds no frames", path.display());
    }
    let f = opts.frames;
    let last = f.last.unwrap_or(total - 1);
    if f.first >= total || last >= total || last < f.first {
        bail!(
            "--frames: frames {}..={} requested, {} holds frames 0..={}",
            f.first,
            last,
            path.display(),
            total - 1
        );
    }
    let mut frames = Vec::new();
    let mut names: Vec<String> = Vec::new();
    let mut k = f.first;
    while k <= last {
        let g = read_frame(path, Some(k))?;
        let p = &g.particles;
        let keep: Vec<usize> = match &opts.types {
            None => (0..p.len()).collect(),
            Some(want) => {
                for t in want {
                    if !p.type_names.contains(t) {
                        bail!(
                            "--types: no type '{t}' in frame {k} (its types: {})",
                            p.type_names.join(", ")
                        );
                    }
                }
                (0..p.len())
                    .filter(|&i| want.contains(&p.type_names[p.typeid[i] as usize]))
                    .collect()
            }
        };
        if names.is_empty() {
            names = p.type_names.clone();
        }
        frames.push(Frame {
            step: g.step,
            l: g.sbox.l,
            wrapped: keep.iter().map(|&i| p.pos[i]).collect(),
            unwrapped: keep
                .iter()
                .map(|&i| g.sbox.unwrap(p.pos[i], p.image[i]))
                .collect(),
            diameter: keep.iter().map(|&i| p.diameter[i]).collect(),
            typeid: keep.iter().map(|&i| p.typeid[i]).collect(),
        });
        k += f.stride;
    }
    if let Some((k, fr)) = frames
        .iter()
        .enumerate()
        .find(|(_, fr)| fr.wrapped.len() < 2)
    {
        bail!(
            "{}: frame {} holds {} selected particle(s); the analysis needs at least 2",
            path.display(),
            f.first + k as u64 * f.stride,
            fr.wrapped.len()
        );
    }
    if frames
        .iter()
        .all(|fr| fr.wrapped.iter().all(|x| x[2] == 0.0))
    {
        bail!(
            "{}: every particle lies at z = 0: two-dimensional frames are not supported",
            path.display()
        );
    }
    Ok((frames, names))
}

/// Mean and standard error of the mean over samples (rows), column by column; the error is
/// not a number for one sample.
fn mean_and_error(samples: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>) {
    let m = samples.len() as f64;
    let width = samples[0].len();
    let mean: Vec<f64> = (0..width)
        .map(|b| samples.iter().map(|s| s[b]).sum::<f64>() / m)
        .collect();
    let err = (0..width)
        .map(|b| {
            if samples.len() < 2 {
                return f64::NAN;
            }
            let v = samples
                .iter()
                .map(|s| (s[b] - mean[b]).powi(2))
                .sum::<f64>()
                / (m - 1.0);
            (v / m).sqrt()
        })
        .collect();
    (mean, err)
}

/// Analyse the trajectory at `path` as `opts` say; writes the tables, pictures and
/// `summary.json` into the output folder.
pub fn analyse(path: &Path, opts: &AnalyseOptions) -> Result<Report> {
    positive("--r-max", opts.r_max)?;
    positive("--dt", opts.dt)?;
    bins_in_range("--bins", opts.bins)?;
    bins_in_range("--profile-bins", opts.profile_bins)?;
    if let Some(h) = opts.contact_gap
        && !h.is_finite()
    {
        bail!(
            "--contact-gap: must be a finite number (a negative gap counts overlaps only), got {h}"
        );
    }
    if let Some(t) = &opts.types
        && t.is_empty()
    {
        bail!("--types: name at least one type");
    }
    let (frames, type_names) =
        read_frames(path, opts).with_context(|| format!("analysing {}", path.display()))?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "trajectory".into());
    let out_path = opts
        .out
        .clone()
        .unwrap_or_else(|| format!("{stem}-analysis").into());
    let first = &frames[0];
    let n = first.wrapped.len();
    let l_min = first.l.iter().cloned().fold(f64::INFINITY, f64::min);
    let d_mean = first.diameter.iter().sum::<f64>() / n as f64;
    let monodisperse = first.diameter.iter().all(|&d| d == first.diameter[0]);
    let r_max = opts.r_max.unwrap_or(0.49 * l_min);
    let shortest = frames
        .iter()
        .flat_map(|f| f.l)
        .fold(f64::INFINITY, f64::min);
    if r_max > 0.5 * shortest {
        bail!(
            "--r-max: at most half the shortest box edge, {}, got {r_max}",
            0.5 * shortest
        );
    }
    let bins = opts.bins.unwrap_or(200);
    let gap = opts.contact_gap.unwrap_or(0.1 * d_mean);
    let profile_bins = opts.profile_bins.unwrap_or(50);
    let profile_max = 0.5 * shortest;
    let centre = opts.centre.unwrap_or(Centre::Origin);

    let volume = first.l[0] * first.l[1] * first.l[2];
    let phi: f64 = first
        .diameter
        .iter()
        .map(|d| PI / 6.0 * d.powi(3))
        .sum::<f64>()
        / volume;
    let py = if opts.percus_yevick {
        if !monodisperse {
            bail!("--percus-yevick: the trajectory's spheres have more than one diameter");
        }
        if !(phi > 0.0 && phi <= oz::ETA_MAX) {
            bail!(
                "--percus-yevick: the volume fraction {phi:.4} lies outside (0, {}]",
                oz::ETA_MAX
            );
        }
        Some(oz::solve(phi, &oz::PyOptions::default())?)
    } else {
        None
    };
    let out = OutputDir::create(&out_path, opts.force)?;
    let mut files: Vec<String> = Vec::new();
    let mut warnings: Vec<String> = Vec::new();

    // Per frame: g(r), contacts, clusters, radial profiles.
    let mut g_samples = Vec::with_capacity(frames.len());
    let mut r = Vec::new();
    let mut coordination: Vec<u64> = Vec::new();
    let mut cluster_rows: Vec<[f64; 6]> = Vec::new();
    let mut phi_samples = Vec::with_capacity(frames.len());
    let mut density_samples = Vec::with_capacity(frames.len());
    let mut shells = Vec::new();
    for f in &frames {
        let (rr, g) = pair_distribution(&f.wrapped, f.l, r_max, bins);
        r = rr;
        g_samples.push(g);
        let radius: Vec<f64> = f.diameter.iter().map(|d| 0.5 * d).collect();
        let bonds = contacts(&f.wrapped, &radius, f.l, gap);
        let z = coordination_numbers(f.wrapped.len(), &bonds);
        let h = coordination_histogram(&z);
        if coordination.len() < h.len() {
            coordination.resize(h.len(), 0);
        }
        for (a, b) in coordination.iter_mut().zip(&h) {
            *a += b;
        }
        let cs = cluster_stats(f.wrapped.len(), &bonds);
        cluster_rows.push([
            f.step as f64,
            f.wrapped.len() as f64,
            cs.n_clusters as f64,
            cs.largest as f64,
            cs.weight_average_size(),
            cs.mean_degree,
        ]);
        let c = match centre {
            Centre::Origin => [0.0; 3],
            Centre::Point(p) => p,
            Centre::CentreOfMass => {
                let m = f.unwrapped.len() as f64;
                let mut s = [0.0; 3];
                for x in &f.unwrapped {
                    for k in 0..3 {
                        s[k] += x[k] / m;
                    }
                }
                s
            }
        };
        // About a centre of mass the unwrapped positions are the droplet's; about a fixed
        // point the wrapped ones are the box's.
        let pos = if centre == Centre::CentreOfMass {
            &f.unwrapped
        } else {
            &f.wrapped
        };
        phi_samples.push(overlap_profile(
            pos,
            &f.diameter,
            c,
            profile_max,
            profile_bins,
        ));
        // Centre binning with unit particle volumes (d^3 = 6 / pi): the number density.
        let unit = vec![(6.0 / PI).cbrt(); pos.len()];
        let p = radial_profile(pos, &unit, c, profile_max, profile_bins);
        shells = p.r;
        density_samples.push(p.phi);
    }
    let m = frames.len();
    let steps: Vec<u64> = frames.iter().map(|f| f.step).collect();

    // gr.csv, gr_percus_yevick.csv, gr.png
    let (g, g_err) = mean_and_error(&g_samples);
    if m < 2 {
        out.explain("gr.csv", "err", "one frame: no standard error");
    }
    write_pair_structure(
        &out,
        &PairStructure {
            r: &r,
            g: &g,
            err: &g_err,
            diameter: d_mean,
            rho: n as f64 / volume,
            r_max,
            percus_yevick: py.as_ref(),
            label: "trajectory (bars: standard error over frames)",
            title: &format!("g(r), {n} particles, box volume fraction {phi:.3}, {m} frames"),
            xlabel: "r / d (mean diameters)",
        },
        &mut files,
        &mut warnings,
    )?;
    let rho = n as f64 / volume;

    // coordination.csv, clusters.csv
    let total: u64 = coordination.iter().sum();
    let z: Vec<f64> = (0..coordination.len()).map(|k| k as f64).collect();
    let pz: Vec<f64> = coordination
        .iter()
        .map(|&c| c as f64 / total.max(1) as f64)
        .collect();
    out.write_table("coordination.csv", &[("z", &z), ("probability", &pz)])?;
    files.push("coordination.csv".into());
    let col = |k: usize| cluster_rows.iter().map(|row| row[k]).collect::<Vec<f64>>();
    out.write_table(
        "clusters.csv",
        &[
            ("step", &col(0)),
            ("particles", &col(1)),
            ("clusters", &col(2)),
            ("largest", &col(3)),
            ("weight_average_size", &col(4)),
            ("mean_degree", &col(5)),
        ],
    )?;
    files.push("clusters.csv".into());

    // profile.csv, profile.png
    let (phi_r, phi_err) = mean_and_error(&phi_samples);
    let (dens, dens_err) = mean_and_error(&density_samples);
    if m < 2 {
        for c in ["phi_err", "number_density_err"] {
            out.explain("profile.csv", c, "one frame: no standard error");
        }
    }
    out.write_table(
        "profile.csv",
        &[
            ("r", &shells),
            ("phi", &phi_r),
            ("phi_err", &phi_err),
            ("number_density", &dens),
            ("number_density_err", &dens_err),
        ],
    )?;
    files.push("profile.csv".into());
    picture(
        line_plot_styled(
            &out.join("profile.png"),
            &format!(
                "Radial volume fraction about the {}, {m} frames",
                centre_name(centre)
            ),
            "r (length unit of the trajectory)",
            "volume fraction (sphere-shell overlap)",
            &[Series {
                label: "phi (bars: standard error over frames)",
                x: &shells,
                y: &phi_r,
                points: false,
            }],
            &[Some(phi_err.as_slice())],
            Scale::Linear,
            Style::default(),
        ),
        "profile.png",
        &mut files,
        &mut warnings,
    );

    // msd.csv, msd.png: evenly spaced frames of the same particles only.
    let spacing = (m >= 2).then(|| steps[1] - steps[0]);
    let even = spacing.is_some_and(|s| s > 0 && steps.windows(2).all(|w| w[1] - w[0] == s));
    let same = frames
        .iter()
        .all(|f| f.typeid == first.typeid && f.wrapped.len() == n);
    let mut msd_summary = serde_json::Value::Null;
    if m < 2 {
        warnings.push("msd.csv not written: one frame".into());
    } else if !even {
        warnings.push("msd.csv not written: the frames are not evenly spaced in steps".into());
    } else if !same {
        warnings.push(
            "msd.csv not written: the frames hold different particles (numbers or types)".into(),
        );
    } else {
        let s = spacing.unwrap_or(1) as f64;
        let unwrapped: Vec<Vec<[f64; 3]>> = frames.iter().map(|f| f.unwrapped.clone()).collect();
        let msd = mean_squared_displacement(&unwrapped);
        let lag_steps: Vec<f64> = (1..m).map(|k| k as f64 * s).collect();
        let mut columns: Vec<(&str, &[f64])> = vec![("lag_steps", &lag_steps)];
        let time: Vec<f64> = lag_steps
            .iter()
            .map(|l| l * opts.dt.unwrap_or(f64::NAN))
            .collect();
        if opts.dt.is_some() {
            columns.push(("time", &time));
        }
        columns.push(("msd", &msd));
        out.write_table("msd.csv", &columns)?;
        files.push("msd.csv".into());
        if m < 3 {
            warnings.push("msd.png not drawn: one lag".into());
        }
        let (x, xlabel) = if opts.dt.is_some() {
            (&time, "lag time (time unit of --dt)")
        } else {
            (&lag_steps, "lag (steps)")
        };
        let drawn = (m >= 3).then(|| {
            line_plot(
                &out.join("msd.png"),
                &format!("Mean-squared displacement, {n} particles, {m} frames"),
                xlabel,
                "mean-squared displacement (length unit squared)",
                &[Series {
                    label: "all time origins",
                    x,
                    y: &msd,
                    points: false,
                }],
                Scale::LogLog,
            )
        });
        if let Some(drawn) = drawn {
            picture(drawn, "msd.png", &mut files, &mut warnings);
        }
        msd_summary = json!({ "lags": m - 1, "lag_steps": s });
    }

    let mut summary = json!({
        "analysis": {
            "trajectory": path.display().to_string(),
            "frames": m,
            "steps": steps,
            "particles": n,
            "types": opts.types.clone().unwrap_or(type_names),
            "box": first.l,
            "volume_fraction": phi,
            "number_density": rho,
            "mean_diameter": d_mean,
            "r_max": r_max,
            "bins": bins,
            "contact_gap": gap,
            "centre": centre,
            "profile_bins": profile_bins,
            "profile_r_max": profile_max,
            "dt": opts.dt,
            "percus_yevick": opts.percus_yevick,
            "msd": msd_summary,
        },
        "files": files,
        "warnings": warnings,
    });
    let non_finite: Vec<_> = out
        .non_finite()
        .into_iter()
        .filter(|e| e.reason.is_some())
        .collect();
    if !non_finite.is_empty() {
        summary["non_finite"] = json!(non_finite);
    }
    out.write_json("summary.json", &summary)?;
    Ok(Report {
        out: out.path().to_path_buf(),
        message: format!(
            "analysed {m} frame(s) of {n} particles of {}; outputs in {}",
            path.display(),
            out.path().display()
        ),
        summary,
        files,
        warnings,
    })
}

fn centre_name(c: Centre) -> String {
    match c {
        Centre::Origin => "origin".into(),
        Centre::CentreOfMass => "centre of mass".into(),
        Centre::Point(p) => format!("point ({}, {}, {})", p[0], p[1], p[2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_parse_like_slices() {
        let f = |s: &str| s.parse::<Frames>().unwrap();
        assert_eq!(
            f("::5"),
            Frames {
                first: 0,
                last: None,
                stride: 5
            }
        );
        assert_eq!(
            f("10:"),
            Frames {
                first: 10,
                last: None,
                stride: 1
            }
        );
        assert_eq!(
            f(":20"),
            Frames {
                first: 0,
                last: Some(20),
                stride: 1
            }
        );
        assert_eq!(
            f("7"),
            Frames {
                first: 7,
                last: Some(7),
                stride: 1
            }
        );
        for bad in ["1:2:0", "a", "1:2:3:4", "-1:"] {
            assert!(bad.parse::<Frames>().is_err(), "{bad}");
        }
    }

    #[test]
    fn centres_parse() {
        assert_eq!("origin".parse::<Centre>().unwrap(), Centre::Origin);
        assert_eq!("com".parse::<Centre>().unwrap(), Centre::CentreOfMass);
        assert_eq!(
            "1,2.5,-3".parse::<Centre>().unwrap(),
            Centre::Point([1.0, 2.5, -3.0])
        );
        for bad in ["1,2", "x,y,z", "1,2,inf", ""] {
            assert!(bad.parse::<Centre>().is_err(), "{bad}");
        }
    }

    #[test]
    fn mean_and_error_of_known_samples() {
        let (m, e) = mean_and_error(&[vec![1.0, 2.0], vec![3.0, 2.0]]);
        assert_eq!(m, vec![2.0, 2.0]);
        // Sample variance 2, standard error sqrt(2 / 2) = 1.
        assert!((e[0] - 1.0).abs() < 1e-15 && e[1] == 0.0);
        let (_, e) = mean_and_error(&[vec![1.0]]);
        assert!(e[0].is_nan());
    }
}
