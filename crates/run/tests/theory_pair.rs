//! `colloidsim theory --hydrodynamics rpy --pair ...`: the pair correlation of the RPY flux.

use colloidsim_run::{Control, Scenario, TheoryOptions};

const DROPLET: &str = r#"
method = "droplet-bd"
seed = 1
[system]
particles = 200
phi0 = 0.05
[drying]
peclet = 10
final_volume_fraction = 0.3
[run]
dt = 0.004
[observe]
profile = { bins = 10, fractions = [0, 0.5, 1.0] }
"#;

fn theory(
    dir: &std::path::Path,
    name: &str,
    hydro: Option<&str>,
    pair: Option<&str>,
) -> anyhow::Result<colloidsim_run::Report> {
    let sc = Scenario::from_toml(DROPLET, dir).unwrap();
    let opts = TheoryOptions {
        out: Some(dir.join(name)),
        dx: Some(0.05),
        force: false,
        hydrodynamics: hydro.map(str::to_string),
        pair: pair.map(str::to_string),
    };
    colloidsim_run::theory(&sc, &opts, &Control::default())
}

/// The dilute RPY flux (`K = 1 - 5 phi < 0` above phi = 0.2) ejects particles from this small
/// droplet dried from 0.05 to 0.3; with Trokhymchuk's `g` (`K > 0`), at the point densities
/// (Eq. 17) or at `n3`, it dries to the end. Each summary names its pair correlation.
#[test]
fn the_trokhymchuk_flux_dries_a_droplet_the_dilute_one_ejects_from() {
    let dir = tempfile::tempdir().unwrap();
    let e = theory(dir.path(), "dilute", Some("rpy"), Some("dilute")).unwrap_err();
    assert!(e.to_string().contains("particles ejected"), "{e}");
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("dilute/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(summary["status"], "unphysical");
    assert_eq!(summary["pair_correlation"], "dilute");
    let mut last = Vec::new();
    for pair in ["trokhymchuk", "trokhymchuk-n3"] {
        let r = theory(dir.path(), pair, Some("rpy"), Some(pair)).unwrap();
        assert_eq!(
            r.summary["status"], "ok",
            "{pair}: {}",
            r.summary["message"]
        );
        assert_eq!(r.summary["pair_correlation"], pair);
        let table = std::fs::read_to_string(r.out.join("profile_1.00.csv")).unwrap();
        let phi: Vec<f64> = table
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
            .collect();
        last.push(phi);
    }
    let diff = last[0]
        .iter()
        .zip(&last[1])
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    eprintln!("max |phi| difference at the end, trokhymchuk vs trokhymchuk-n3: {diff:.4}");
    // Free draining has no pair correlation in its summary.
    let fd = theory(dir.path(), "fd", Some("free-draining"), None).unwrap();
    assert!(fd.summary.get("pair_correlation").is_none());
}

#[test]
fn a_bad_pair_or_one_without_the_rpy_flux_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let e = theory(dir.path(), "bad", Some("rpy"), Some("percus-yevick")).unwrap_err();
    assert!(
        e.to_string()
            .contains("--pair must be dilute, trokhymchuk or trokhymchuk-n3"),
        "{e}"
    );
    let e = theory(dir.path(), "fd", Some("free-draining"), Some("trokhymchuk")).unwrap_err();
    assert!(
        e.to_string()
            .contains("--pair applies to the RPY flux only"),
        "{e}"
    );
}
