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
    theory_of(DROPLET, dir, name, hydro, pair)
}

/// `colloidsim theory` of the scenario `text` into `dir/name`, at dx = 0.05.
fn theory_of(
    text: &str,
    dir: &std::path::Path,
    name: &str,
    hydro: Option<&str>,
    pair: Option<&str>,
) -> anyhow::Result<colloidsim_run::Report> {
    let sc = Scenario::from_toml(text, dir).unwrap();
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

/// examples/droplet/bidisperse-bd.toml shrunk to 160 small + 20 large spheres (size ratio 2,
/// equal volumes, phi 0.05 -> 0.5, Pe_s = 10, stiffness 100 kT/d^2), dr = d_s/10: the dilute
/// mixture RPY flux ejects large spheres at mean phi ~0.19 (75 % of the drying time); with the
/// dense `g_ij` (Trokhymchuk's `h` scaled to BMCSL contact values) the run gets much further
/// (measured: mean phi 0.40, 96 % of the drying time) or completes.
#[test]
fn the_dense_mixture_flux_dries_a_bidisperse_droplet_further_than_the_dilute_one() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/droplet/bidisperse-bd.toml"),
    )
    .unwrap()
    .replace("particles = 900", "particles = 180")
    .replace("counts = [800, 100]", "counts = [160, 20]");
    assert!(
        text.contains("counts = [160, 20]"),
        "the example changed: update this test"
    );
    let dir = tempfile::tempdir().unwrap();
    let sc = Scenario::from_toml(&text, dir.path()).unwrap();
    let run = |name: &str, pair: &str| {
        let opts = TheoryOptions {
            out: Some(dir.path().join(name)),
            dx: Some(0.1),
            force: false,
            hydrodynamics: Some("rpy".into()),
            pair: Some(pair.into()),
        };
        let result = colloidsim_run::theory(&sc, &opts, &Control::default());
        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.path().join(name).join("summary.json")).unwrap(),
        )
        .unwrap();
        (result, summary)
    };
    let (dilute, sd) = run("dilute", "dilute");
    let e = dilute.unwrap_err();
    assert!(e.to_string().contains("ejected"), "{e}");
    assert_eq!(sd["status"], "unphysical");
    assert_eq!(sd["pair_correlation"], "dilute");
    let phi_dilute = sd["reached"]["mean_volume_fraction"].as_f64().unwrap();
    let (_, st) = run("dense", "trokhymchuk");
    assert_eq!(st["pair_correlation"], "trokhymchuk");
    let phi_dense = st["reached"]["mean_volume_fraction"].as_f64().unwrap();
    eprintln!(
        "reached mean phi: dilute {phi_dilute:.3}, trokhymchuk {phi_dense:.3} ({}: {})",
        st["status"], st["message"]
    );
    assert!(phi_dilute < 0.25, "{phi_dilute}");
    assert!(
        st["status"] == "ok" || phi_dense > phi_dilute + 0.15,
        "dilute {phi_dilute}, dense {phi_dense}"
    );
}

/// The DDFT is of hard spheres: a scenario with another pair interaction (or a WCA of another
/// depth) is refused naming the key, not solved as hard spheres; the default written out is
/// accepted by the same check.
#[test]
fn the_theory_refuses_a_pair_interaction_it_does_not_have() {
    let dir = tempfile::tempdir().unwrap();
    let run = |pair: &str, name: &str| {
        theory_of(
            &format!("{DROPLET}[pair]\n{pair}\n"),
            dir.path(),
            name,
            None,
            None,
        )
    };
    for (pair, key) in [
        (
            "kind = \"morse\"\ndepth = 3.0\nkappa = 10.0\nh0 = 0.0\nrange = 0.5",
            "pair.kind",
        ),
        (
            "kind = \"ao\"\ndepletant_diameter = 0.2\ndepletant_fraction = 0.1",
            "pair.kind",
        ),
        ("kind = \"wca\"\nepsilon = [5.0]", "pair.epsilon"),
    ] {
        let e = format!("{:#}", run(pair, "refused").unwrap_err());
        assert!(e.contains(key) && e.contains("hard spheres"), "{pair}: {e}");
        assert!(!dir.path().join("refused").exists(), "{pair}: wrote output");
    }
    let r = run("kind = \"wca\"\nepsilon = [1.0]", "default").unwrap();
    assert_eq!(r.summary["status"], "ok", "{}", r.summary["message"]);
}
