//! `observe.figure_format`: every picture of a run as PNG, SVG or both, through the shared
//! plotting module, for every method alike; a value not allowed is refused naming the key.

use colloidsim_run::{Control, RunOptions, Scenario};
use std::path::Path;

const RODS: &str = "method = \"bcd\"\nseed = 3\n[system]\nlength = 10.0\nparticles = 5\n\
                    diameter = 0.5\n[run]\ndt = 1e-4\ntime = 0.05\n\
                    [observe]\ndensity = { bins = 20 }\n";

const SPHERES: &str = "method = \"hs-mc\"\nseed = 1\n[system]\ngeometry = \"bulk\"\n\
                       particles = 64\nvolume_fraction = 0.2\n[mc]\nsweeps = 40\n\
                       warmup_sweeps = 10\nsample_every = 2\nblocks = 4\n\
                       [output]\ngr_bins = 40\n[observe]\n";

fn run(text: &str, format: &str, out: &Path, force: bool) {
    // Both scenarios end in their [observe] table.
    let text = format!("{text}figure_format = \"{format}\"\n");
    let sc = Scenario::from_toml(&text, out.parent().unwrap()).unwrap();
    let opts = RunOptions {
        out: Some(out.to_path_buf()),
        seed: None,
        force,
    };
    colloidsim_run::run(&sc, &opts, &Control::default()).unwrap();
}

/// The names in `dir` ending in `.ext`.
fn with_ext(dir: &Path, ext: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(&format!(".{ext}")))
        .collect();
    v.sort();
    v
}

/// The files summary.json lists, each of which exists.
fn listed(dir: &Path) -> Vec<String> {
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    let files: Vec<String> = s["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .collect();
    for f in &files {
        assert!(dir.join(f).is_file(), "{f} listed but not written");
    }
    files
}

fn is_svg(path: &Path) -> bool {
    let text = std::fs::read_to_string(path).unwrap();
    let head = text.trim_start();
    (head.starts_with("<svg") || head.starts_with("<?xml")) && text.trim_end().ends_with("</svg>")
}

#[test]
fn pictures_are_written_as_svg_png_or_both() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in [("rods", RODS), ("spheres", SPHERES)] {
        let out = dir.path().join(name);
        run(text, "svg", &out, false);
        let svg = with_ext(&out, "svg");
        assert!(!svg.is_empty(), "{name}: no svg");
        assert_eq!(with_ext(&out, "png"), Vec::<String>::new(), "{name}");
        for f in &svg {
            assert!(is_svg(&out.join(f)), "{name}/{f} is not SVG");
        }
        let files = listed(&out);
        assert!(svg.iter().all(|f| files.contains(f)), "{files:?}");
        // Both: each picture twice, under the same stem; a --force rerun in the folder replaces
        // the earlier run's SVG files (they are the run's own).
        run(text, "both", &out, true);
        let png = with_ext(&out, "png");
        let stems = |v: &[String]| -> Vec<String> {
            v.iter()
                .map(|f| f.rsplit_once('.').unwrap().0.to_string())
                .collect()
        };
        assert_eq!(stems(&png), stems(&with_ext(&out, "svg")), "{name}");
        assert!(!png.is_empty());
        listed(&out);
        // PNG (the default): the SVG files are gone.
        run(text, "png", &out, true);
        assert_eq!(with_ext(&out, "svg"), Vec::<String>::new(), "{name}");
        assert_eq!(with_ext(&out, "png"), png, "{name}");
        listed(&out);
    }
}

/// `colloidsim theory` draws its pictures in the scenario's format too, and names them.
#[test]
fn theory_pictures_follow_the_figure_format() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!("{RODS}figure_format = \"svg\"\n");
    let sc = Scenario::from_toml(&text, dir.path()).unwrap();
    let out = dir.path().join("theory");
    let opts = colloidsim_run::TheoryOptions {
        out: Some(out.clone()),
        ..Default::default()
    };
    let r = colloidsim_run::theory(&sc, &opts, &Control::default()).unwrap();
    let svg = with_ext(&out, "svg");
    assert!(!svg.is_empty(), "no svg in {:?}", r.files);
    assert_eq!(with_ext(&out, "png"), Vec::<String>::new());
    for f in &svg {
        assert!(is_svg(&out.join(f)), "{f}");
        assert!(r.files.contains(f), "{f} not in {:?}", r.files);
    }
    for f in &r.files {
        assert!(out.join(f).is_file(), "{f} listed, not written");
    }
}

#[test]
fn a_figure_format_not_allowed_is_refused_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    for text in [RODS, SPHERES] {
        let text = format!("{text}figure_format = \"pdf\"\n");
        let sc = Scenario::from_toml(&text, dir.path()).unwrap();
        let e = colloidsim_run::check(&sc).unwrap_err();
        let m = format!("{e:#}");
        assert!(
            m.contains("observe.figure_format") && m.contains("\"svg\""),
            "{m}"
        );
        let out = dir.path().join("bad");
        let opts = RunOptions {
            out: Some(out.clone()),
            seed: None,
            force: false,
        };
        let e = colloidsim_run::run(&sc, &opts, &Control::default()).unwrap_err();
        assert!(format!("{e:#}").contains("observe.figure_format"), "{e:#}");
        assert!(!out.exists());
    }
}

/// The droplet example (examples/droplet/drying-bd.toml, smaller): the centre density of the
/// innermost shells reads far above 1 (one centre in a shell smaller than a sphere), the
/// volume fraction by sphere-shell overlap beside it stays below 0.80 everywhere.
#[test]
fn droplet_volume_fractions_by_overlap_stay_below_close_packing() {
    let dir = tempfile::tempdir().unwrap();
    let example =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/droplet/drying-bd.toml");
    let out = dir.path().join("droplet");
    run_example(&example, &["system.particles=300", "replicas=2"], &out);
    let mut centre_max: f64 = 0.0;
    for f in ["0.00", "0.25", "0.50", "0.75", "1.00"] {
        let text = std::fs::read_to_string(out.join(format!("profile_{f}.csv"))).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("r,rho_v,phi_overlap,phi_overlap_err"));
        let mut error_max: f64 = 0.0;
        for l in lines {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            centre_max = centre_max.max(v[1]);
            assert!((0.0..0.80).contains(&v[2]), "profile_{f}.csv: {l}");
            // The replicas' error: none where no sphere reaches, below the value it bars.
            assert!(
                v[3] >= 0.0 && v[3] <= v[2].max(1e-300),
                "profile_{f}.csv: {l}"
            );
            error_max = error_max.max(v[3]);
        }
        assert!(
            error_max > 0.0,
            "profile_{f}.csv: no error over the replicas"
        );
    }
    // The centre density is not a volume fraction: in a shell thinner than a sphere it can
    // exceed 1 (the case of the issue, 3.38 in the full example).
    assert!(centre_max > 0.80, "{centre_max}");
}

/// Run the scenario file `path` with `overrides` (`key=value`) into the new folder `out`.
fn run_example(path: &Path, overrides: &[&str], out: &Path) {
    let overrides: Vec<String> = overrides.iter().map(|o| o.to_string()).collect();
    let sc = Scenario::from_path(path)
        .unwrap()
        .with_overrides(&overrides)
        .unwrap();
    let opts = RunOptions {
        out: Some(out.to_path_buf()),
        seed: None,
        force: false,
    };
    colloidsim_run::run(&sc, &opts, &Control::default()).unwrap();
}

/// The columns of a CSV file by name.
fn columns(path: &Path) -> std::collections::BTreeMap<String, Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let names: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let mut cols = vec![Vec::new(); names.len()];
    for l in lines {
        for (c, x) in cols.iter_mut().zip(l.split(',')) {
            c.push(x.parse().unwrap());
        }
    }
    names.into_iter().zip(cols).collect()
}

/// Monte Carlo in a hard-walled droplet and a drying MPCD droplet (their examples, smaller)
/// write the volume fraction by overlap beside the centre density, as droplet-bd does: below
/// close packing everywhere, where the centre density of the wall's contact layer is not.
#[test]
fn monte_carlo_and_mpcd_droplets_write_volume_fractions_by_overlap() {
    let dir = tempfile::tempdir().unwrap();
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    for (file, overrides, csv) in [
        (
            "mc/droplet-static.toml",
            vec![
                "mc.sweeps=400",
                "mc.warmup_sweeps=100",
                "mc.blocks=4",
                "output.rho2_r_bins=0",
            ],
            vec!["profile_mean.csv"],
        ),
        (
            "droplet/drying-mpcd.toml",
            vec!["drying.peclet=1000", "observe.solvent.window=10"],
            vec!["profile_0.00.csv", "profile_1.00.csv"],
        ),
    ] {
        let out = dir.path().join(file.replace('/', "-"));
        run_example(&examples.join(file), &overrides, &out);
        let mut centre_max: f64 = 0.0;
        for name in csv {
            let c = columns(&out.join(name));
            assert_eq!(c["phi_overlap"].len(), c["rho_v"].len(), "{file}: {name}");
            // Every column named as a volume fraction stays below close packing.
            for (col, v) in c
                .iter()
                .filter(|(k, _)| k.starts_with("phi") && !k.ends_with("_err"))
            {
                assert!(
                    v.iter().all(|v| (0.0..0.80).contains(v)),
                    "{file}: {name}: {col}: {v:?}"
                );
            }
            centre_max = centre_max.max(c["rho_v"].iter().cloned().fold(0.0, f64::max));
        }
        if file.starts_with("mc") {
            assert!(centre_max > 0.80, "{file}: {centre_max}");
        }
    }
}
