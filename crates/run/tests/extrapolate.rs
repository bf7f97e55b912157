//! Richardson extrapolation in dt removes Euler's first-order bias of the BCD density.

use colloidsim_core::output::read_table;
use colloidsim_run::{Control, ExtrapolateOptions, Scenario};

/// The hard-rods paper's Fig. 3 case sigma = rho = 0.5 (50 rods on L = 100, U0 = 6 kT) at
/// dt = 1e-3 and 5e-4, eight seeds each: Euler's density L1 error against the exact theory is
/// about 3.4 % at dt = 1e-3 and half that at 5e-4; the extrapolation to dt -> 0 must take at
/// least half of the finer run's error away (its statistical floor, about 0.25 %, is well
/// below that). Extrapolating the wrong way (the steps swapped) must fail the same check.
#[test]
fn extrapolated_density_is_closer_to_the_exact_theory_than_either_run() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"
method = "bcd"
seed = 300
[system]
length = 100.0
particles = 50
diameter = 0.5
[potential]
cosine = { amplitude = 6.0, wavelength = 1.0 }
[run]
dt = 1e-3
equilibrate = 20.0
time = 60.0
[observe]
density = { bins = 50 }
"#;
    let sc = Scenario::from_toml(text, dir.path()).unwrap();
    let opts = ExtrapolateOptions {
        out: Some(dir.path().join("x")),
        seeds: 8,
        ..Default::default()
    };
    let r = colloidsim_run::extrapolate(&sc, &opts, &Control::default()).unwrap();
    assert!(
        r.files.contains(&"density.csv".to_string()),
        "{:?}",
        r.files
    );
    let col = |path: &std::path::Path, name: &str| {
        let (h, c) = read_table(path).unwrap();
        c[h.iter().position(|x| x == name).unwrap()].clone()
    };
    let exact = col(
        &dir.path().join("x/runs/dt-seed-0/density_theory.csv"),
        "rho",
    );
    let l1 = |rho: &[f64]| {
        rho.iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).abs())
            .sum::<f64>()
            / exact.iter().sum::<f64>()
    };
    let coarse = col(&dir.path().join("x/dt/density.csv"), "rho");
    let fine = col(&dir.path().join("x/half-dt/density.csv"), "rho");
    let extrapolated = col(&dir.path().join("x/density.csv"), "rho");
    let err = col(&dir.path().join("x/density.csv"), "rho_err");
    let floor = err.iter().sum::<f64>() / exact.iter().sum::<f64>();
    let wrong: Vec<f64> = coarse.iter().zip(&fine).map(|(c, f)| 2.0 * c - f).collect();
    eprintln!(
        "density L1 error: dt {:.2e}, dt/2 {:.2e}, extrapolated {:.2e} (noise floor {floor:.1e}), swapped {:.2e}",
        l1(&coarse),
        l1(&fine),
        l1(&extrapolated),
        l1(&wrong)
    );
    assert!(l1(&coarse) > 0.02, "Euler's O(dt) bias is missing");
    assert!(
        l1(&fine) < 0.7 * l1(&coarse),
        "the bias does not fall with dt"
    );
    assert!(floor < 0.3 * l1(&fine), "too noisy to judge: floor {floor}");
    assert!(l1(&extrapolated) < 0.5 * l1(&fine));
    assert!(l1(&wrong) > l1(&fine));
}

#[test]
fn bad_extrapolation_options_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let sc = Scenario::from_toml(
        "method = \"bcd\"\n[system]\nlength = 10.0\nparticles = 5\ndiameter = 0.5\n[run]\ndt = 1e-3\ntime = 0.01\n",
        dir.path(),
    )
    .unwrap();
    for (seeds, order, key) in [
        (1, 1.0, "--seeds"),
        (4, 0.0, "--order"),
        (4, f64::NAN, "--order"),
    ] {
        let o = ExtrapolateOptions {
            out: Some(dir.path().join("o")),
            seeds,
            order,
            force: false,
        };
        let e = colloidsim_run::extrapolate(&sc, &o, &Control::default()).unwrap_err();
        assert!(e.to_string().contains(key), "{e}");
    }
}
