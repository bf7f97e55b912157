//! Issue 42, "silently wrong": inputs that ran to `completed = true` with outputs that were not
//! numbers or not physical are refused at their cause, naming the key and why; a number that is
//! still not finite is written as an empty field and listed in summary.json (`non_finite`) with
//! its reason; values that almost surely mean a unit mistake are warned of by `check` and `run`.

use crate::common;
use common::{cli, text};
use std::path::Path;

fn scenario(dir: &Path, name: &str, body: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, body).unwrap();
    path.to_str().unwrap().to_string()
}

const MPCD: &str = "method = \"mpcd\"\nseed = 1\n[system]\nbox = 8\ncolloids = 1\ndiameter = 2\n[run]\ncollisions = 40\nequilibrate = 10\n[observe]\nevery = 10\nvacf_lags = 5\n";
const DROPLET_MPCD: &str = "method = \"droplet-mpcd\"\nseed = 1\n[system]\nradius = 5\n[drying]\npeclet = 0\nduration = 1.0\n";
const BCD: &str = "method = \"bcd\"\nseed = 4\n[system]\nlength = 20.0\nparticles = 5\ndiameter = 0.5\n[run]\ndt = 1e-3\ntime = 0.5\n[interaction.yukawa]\nstrength = 1.0\nscreening = 1.0\ncutoff = 2.0\n[observe]\nmsd = { points = 5, max_lag = 0.2 }\n";
const DPD: &str = "method = \"dpd\"\nseed = 1\n[system]\nbox_length = 5.0\ndensity = 3.0\nphi = 0.0\n[run]\ndt = 0.01\nsteps = 20\n[observe]\nthermo_every = 10\ntrajectory_every = 0\nmsd_every = 5\nstructure_every = 0\n";
const DROPLET_BD: &str = "method = \"droplet-bd\"\nseed = 1\n[system]\nparticles = 20\nphi0 = 0.2\n[drying]\npeclet = 0\nduration = 1.0\n";
const HS_MC: &str = "method = \"hs-mc\"\nseed = 1\n[system]\ngeometry = \"bulk\"\nparticles = 32\nvolume_fraction = 0.3\ndiameter = 1.0\n[mc]\nsweeps = 40\nwarmup_sweeps = 10\nsample_every = 5\nblocks = 2\n[output]\ngr_bins = 10\n";

/// Every case of the list, on `check` (which runs the validation `run` runs first).
#[test]
fn silently_wrong_inputs_are_refused_naming_the_key_and_why() {
    let tmp = tempfile::tempdir().unwrap();
    let cases: &[(&str, &str, &str, &[&str])] = &[
        (
            "mpcd",
            MPCD,
            "solvent.kT=1e300",
            &["solvent.kT: 1e300", "mean free path"],
        ),
        (
            "mpcd",
            MPCD,
            "solvent.kT=9223372036854775807",
            &["solvent.kT:", "[0.0001, 10] cells"],
        ),
        (
            "mpcd",
            MPCD,
            "solvent.kT=1e-300",
            &["solvent.kT: 1e-300", "would not move"],
        ),
        (
            "mpcd",
            MPCD,
            "solvent.density=1e-3",
            &["solvent.density: 0.001", "minimum 3"],
        ),
        (
            "dmpcd",
            DROPLET_MPCD,
            "solvent.density=1e-3",
            &["solvent.density: 0.001", "minimum 3"],
        ),
        (
            "bcd",
            BCD,
            "interaction.yukawa.strength=1e300",
            &[
                "interaction.yukawa.strength: 1e300",
                "more than the system length",
            ],
        ),
        (
            "bcd",
            BCD,
            "interaction.yukawa.strength=-1e300",
            &["interaction.yukawa.strength: -1e300"],
        ),
        (
            "bcdw",
            BCD,
            "observe.contact_density={bins=4,window=1e-300}",
            &["observe.contact_density.window: 1e-300", "resolve"],
        ),
        ("dpd", DPD, "system.phi=0.1", &[]),
        (
            "dpdr",
            &DPD.replace("box_length = 5.0", "box_length = 7.0"),
            "system.colloid_radius=10",
            &[],
        ),
        (
            "dpd",
            DPD,
            "run.dt=1e-300",
            &["run.dt: 1e-300 is below 1e-6"],
        ),
        (
            "dbd",
            DROPLET_BD,
            "system.diameter=1e300",
            &["system.diameter = 1e300", "d^3 = inf"],
        ),
        (
            "mc",
            HS_MC,
            "output.gr_max=1e-300",
            &["output.gr_max: 1e-300 is not beyond the diameter"],
        ),
    ];
    for (name, body, set, words) in cases {
        let sc = scenario(tmp.path(), &format!("{name}.toml"), body);
        let o = cli(&["check", &sc], &[]);
        assert!(
            o.status.success(),
            "{name}: the base scenario is valid: {}",
            text(&o)
        );
        if words.is_empty() {
            continue; // a valid setting of the base, checked below with the radius
        }
        let o = cli(&["check", &sc, "--set", set], &[]);
        let t = text(&o);
        assert!(!o.status.success(), "{name} --set {set}: accepted: {t}");
        for w in *words {
            assert!(t.contains(w), "{name} --set {set}: no '{w}' in: {t}");
        }
    }
    // DPD colloids that do not fit, or whose number rounds to none at the phi asked for.
    let sc = scenario(
        tmp.path(),
        "dpdr.toml",
        &DPD.replace("box_length = 5.0", "box_length = 7.0"),
    );
    let t = text(&cli(
        &[
            "check",
            &sc,
            "--set",
            "system.phi=0.1",
            "--set",
            "system.colloid_radius=10",
        ],
        &[],
    ));
    assert!(
        t.contains("system.colloid_radius: one colloid of radius 10") && t.contains("does not fit"),
        "{t}"
    );
    let t = text(&cli(
        &[
            "check",
            &sc,
            "--set",
            "system.phi=0.001",
            "--set",
            "system.colloid_radius=1.5",
        ],
        &[],
    ));
    assert!(
        t.contains("system.phi: 0.001") && t.contains("rounds to none"),
        "{t}"
    );
}

/// `extrapolate --order`: a range with the reason, refused before anything runs or is written.
#[test]
fn extrapolate_refuses_orders_that_only_amplify_noise() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = scenario(tmp.path(), "bcd.toml", BCD);
    let out = tmp.path().join("x");
    for order in ["1e-300", "0.1", "5"] {
        let o = cli(
            &[
                "extrapolate",
                &sc,
                "--order",
                order,
                "--out",
                out.to_str().unwrap(),
            ],
            &[],
        );
        let t = text(&o);
        assert!(!o.status.success(), "--order {order}: {t}");
        assert!(t.contains("--order: must lie in [0.25, 4]"), "{t}");
        assert!(!out.exists(), "nothing is written");
    }
}

/// A quantity with nothing to average is written as an empty field and listed with its
/// reason; a kind of particle not followed has no MSD column (instead of NaN).
#[test]
fn numbers_that_are_not_finite_are_empty_fields_listed_with_their_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = scenario(tmp.path(), "dpd.toml", DPD);
    let out = tmp.path().join("o");
    let o = cli(
        &[
            "run",
            &sc,
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--threads",
            "1",
        ],
        &[],
    );
    assert!(o.status.success(), "{}", text(&o));
    for f in std::fs::read_dir(&out).unwrap() {
        let f = f.unwrap().path();
        if f.extension().is_some_and(|e| e == "csv" || e == "json") {
            let t = std::fs::read_to_string(&f).unwrap().to_lowercase();
            assert!(
                !t.contains("nan") && !t.contains("inf,") && !t.contains(",inf"),
                "{}: {t}",
                f.display()
            );
        }
    }
    let thermo = std::fs::read_to_string(out.join("thermo.csv")).unwrap();
    let header: Vec<&str> = thermo.lines().next().unwrap().split(',').collect();
    let k = header.iter().position(|&h| h == "T_colloid").unwrap();
    assert!(
        thermo
            .lines()
            .skip(1)
            .all(|l| l.split(',').nth(k) == Some("")),
        "{thermo}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let nf = &summary["non_finite"][0];
    assert_eq!(nf["file"], "thermo.csv");
    assert_eq!(nf["column"], "T_colloid");
    assert_eq!(nf["reason"], "no colloids");
    let msd = std::fs::read_to_string(out.join("msd.csv")).unwrap();
    assert_eq!(
        msd.lines().next(),
        Some("lag_steps,time,time_tau,msd_solvent")
    );
    // With neither colloids nor solvent beads followed there is no MSD at all.
    let o = cli(
        &[
            "run",
            &sc,
            "--out",
            tmp.path().join("p").to_str().unwrap(),
            "--quiet",
            "--threads",
            "1",
            "--set",
            "observe.msd_solvent_beads=0",
        ],
        &[],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(!tmp.path().join("p/msd.csv").exists());
}

/// `ensemble --replicas 1`: the errors of one replica are empty fields, not `nan`.
#[test]
fn one_replica_ensembles_write_no_nan() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = scenario(
        tmp.path(),
        "bcd.toml",
        &BCD.replace(
            "[interaction.yukawa]\nstrength = 1.0\nscreening = 1.0\ncutoff = 2.0\n",
            "",
        ),
    );
    let out = tmp.path().join("e");
    let o = cli(
        &[
            "ensemble",
            &sc,
            "--replicas",
            "1",
            "--vary",
            "system.kT=[1.0,0.0]",
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--threads",
            "1",
        ],
        &[],
    );
    assert!(o.status.success(), "{}", text(&o));
    let t = std::fs::read_to_string(out.join("observables.csv")).unwrap();
    assert!(
        !t.to_lowercase().contains("nan") && !t.contains("inf"),
        "{t}"
    );
    assert!(t.lines().skip(1).all(|l| l.ends_with(",,1")), "{t}");
}

/// Values inside their range that almost surely mean a unit mistake: `check` warns naming the
/// key and the likely intent; a droplet refused because of such a kT names kT first.
#[test]
fn unit_mistakes_are_warned_of_by_check() {
    let tmp = tempfile::tempdir().unwrap();
    let cases: &[(&str, &str, &str, &str)] = &[
        (
            "mpcd",
            "method = \"mpcd\"\n[system]\nbox = 8\n[run]\ncollisions = 100\n",
            "solvent.angle=2.27",
            "solvent.angle = 2.27: radians?",
        ),
        ("dpd", DPD, "system.kT=300", "system.kT = 300: kelvin?"),
        (
            "bcd",
            BCD,
            "system.kT=4.1e-21",
            "system.kT = 4.1e-21: joules?",
        ),
        (
            "mc",
            HS_MC,
            "system.diameter=1e-6",
            "system.diameter = 1e-6: metres?",
        ),
        (
            "dbd",
            DROPLET_BD,
            "system.viscosity=1e-3",
            "system.viscosity = 0.001: Pa s",
        ),
    ];
    for (name, body, set, words) in cases {
        let sc = scenario(tmp.path(), &format!("{name}.toml"), body);
        let t = text(&cli(&["check", &sc], &[]));
        assert!(
            !t.contains("warning: ") || !t.contains(words),
            "{name}: {t}"
        );
        let t = text(&cli(&["check", &sc, "--set", set], &[]));
        assert!(
            t.contains(words),
            "{name} --set {set}: no '{words}' in: {t}"
        );
    }
    let example = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/droplet/static-equilibrium.toml");
    let o = cli(
        &["check", example.to_str().unwrap(), "--set", "system.kT=300"],
        &[],
    );
    let t = text(&o);
    assert!(!o.status.success());
    let first = t
        .lines()
        .find(|l| l.starts_with("error"))
        .unwrap_or_default();
    assert!(first.contains("system.kT = 300: kelvin?"), "{t}");
}
