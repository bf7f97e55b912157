//! Species and pair interactions of the Brownian-dynamics scenarios (docs/species.md): one
//! species declared in `[system.species]` is today's monodisperse run bit for bit, a mixture
//! keeps every pair at its contact distance and every surface inside the interface, and bad
//! input is refused naming its key.

use colloidsim_md::DropletParams;
use colloidsim_particles::Pair;

const BASE: &str = r#"
method = "droplet-bd"
seed = 5
[system]
particles = 300
phi0 = 0.05
[drying]
peclet = 10
final_volume_fraction = 0.2
"#;

fn read(text: &str) -> anyhow::Result<DropletParams> {
    colloidsim_run::methods::droplet_bd::params::read(
        &toml::from_str(text).unwrap(),
        std::path::Path::new("."),
        None,
    )
}

/// The message a scenario is refused with (`key: what`).
fn refused(text: &str) -> String {
    match read(text) {
        Ok(_) => panic!("accepted: {text}"),
        Err(e) => e.to_string(),
    }
}

/// `BASE` with these lines added to `[system]` and these tables at the end.
fn with(system: &str, tables: &str) -> String {
    BASE.replace("phi0 = 0.05\n", &format!("phi0 = 0.05\n{system}\n")) + tables
}

#[test]
fn one_declared_species_is_the_monodisperse_run_bit_for_bit() {
    let plain = read(BASE).unwrap();
    let one = read(&with(
        "",
        "[system.species]\ndiameters = [1.0]\ncounts = [300]\n",
    ))
    .unwrap();
    let (mut a, mut b) = (
        plain.build_replica(0).unwrap(),
        one.build_replica(0).unwrap(),
    );
    a.run(200).unwrap();
    b.run(200).unwrap();
    assert_eq!(a.snapshot(), b.snapshot());
    // And the declared WCA of eps = kT is the default's.
    let wca = read(&with("", "[pair]\nkind = \"wca\"\nepsilon = [1.0]\n")).unwrap();
    let mut c = wca.build_replica(0).unwrap();
    c.run(200).unwrap();
    assert_eq!(a.snapshot(), c.snapshot());
}

#[test]
fn a_mixture_keeps_its_pairs_apart_and_its_surfaces_inside() {
    let p = read(&with(
        "",
        "[system.species]\ndiameters = [1.0, 2.0]\nvolume_fractions = [0.5, 0.5]\n",
    ))
    .unwrap();
    assert_eq!(p.species.counts, vec![267, 33]);
    assert_eq!(p.diameter, 1.0);
    let mut sim = p.build_replica(0).unwrap();
    sim.run(500).unwrap();
    let snap = sim.snapshot();
    let wall = p.radius_at(sim.time()) + p.offset;
    let pair = p.interaction().unwrap();
    let (mut closest, mut beyond) = (f64::INFINITY, 0usize);
    for i in 0..snap.len() {
        let x = snap.pos[i];
        let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        // A sphere's wall is (d - d_min) / 2 further in; a range of k s^2/2 ~ a few kT.
        if r - (wall - 0.5 * (snap.diameter[i] - 1.0)) > 0.5 {
            beyond += 1;
        }
        for j in 0..i {
            let y = snap.pos[j];
            let d = ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt();
            closest = closest.min(d / (0.5 * (snap.diameter[i] + snap.diameter[j])));
        }
    }
    // WCA at kT: pairs closer than 0.85 contact distances cost > 10 kT (Boltzmann 4e-5).
    assert!(
        closest > 0.85,
        "closest pair at {closest} contact distances"
    );
    assert_eq!(beyond, 0);
    // The large-large cut-off is 2^(1/6) * 2.
    assert!((pair.r_cut_max() - 2.0 * 2f64.powf(1.0 / 6.0)).abs() < 1e-12);
}

#[test]
fn bad_species_and_pairs_are_refused_naming_the_key() {
    let sp = |body: &str| with("", &format!("[system.species]\n{body}\n"));
    for (text, key, says) in [
        (
            sp("diameters = [1.0, 0.0]\ncounts = [200, 100]"),
            "system.species.diameters",
            "> 0",
        ),
        (
            sp("diameters = [1.0, -2.0]\ncounts = [200, 100]"),
            "system.species.diameters",
            "",
        ),
        (
            sp("diameters = [1.0, 2.0]\ncounts = [200, 50]"),
            "system.species.counts",
            "sum to 250",
        ),
        (
            sp("diameters = [1.0, 2.0]\ncounts = [200.5, 99.5]"),
            "system.species.counts",
            "whole",
        ),
        (
            sp("diameters = [1.0, 2.0]\nvolume_fractions = [0.5, 0.4]"),
            "system.species.volume_fractions",
            "summing to 1",
        ),
        (
            sp("diameters = [1.0, 2.0]"),
            "system.species.counts",
            "either",
        ),
        (
            sp("diameters = [1.0, 2.0]\ncounts = [300, 0]"),
            "system.species.counts",
            "no particles",
        ),
        (
            sp("diameters = [1.0, 500.0]\ncounts = [200, 100]"),
            "system.species.diameters",
            "size ratio",
        ),
        (
            with(
                "diameter = 1.0",
                "[system.species]\ndiameters = [1.0, 2.0]\ncounts = [200, 100]\n",
            ),
            "system.diameter",
            "not system.diameter",
        ),
        (
            sp("diameters = [1.0, 20.0]\ncounts = [299, 1]")
                + "[hydrodynamics]\nmodel = \"rpy\"\nmethod = \"pse\"\nbox_factor = 4\n",
            "system.species.diameters",
            "16",
        ),
        (
            with(
                "",
                "[pair]\nkind = \"yukawa\"\nbjerrum_length = 0.7\ndebye_length = 1.0\n",
            ),
            "pair.charges",
            "required",
        ),
        (
            with(
                "",
                "[pair]\nkind = \"yukawa\"\ncharges = [1.0, 2.0]\nbjerrum_length = 0.7\ndebye_length = 1.0\n",
            ),
            "pair.charges",
            "per species",
        ),
        (
            with("", "[pair]\nkind = \"morse\"\ndepth = 3.0\n"),
            "pair.kappa",
            "required",
        ),
        (
            with("", "[pair]\nkind = \"lj\"\nepsilon = [1.0, 2.0]\n"),
            "pair.epsilon",
            "unordered species pair",
        ),
        (
            with("", "[pair]\nkind = \"ao\"\ndepletant_diameter = 0.2\n"),
            "pair.depletant_fraction",
            "required",
        ),
        (
            with(
                "",
                "[pair]\nkind = \"table\"\ntable = \"no-such-file.csv\"\n",
            ),
            "pair.table",
            "no-such-file",
        ),
    ] {
        let e = refused(&text);
        assert!(e.starts_with(&format!("{key}: ")), "{text}\n-> {e}");
        assert!(e.contains(says), "{text}\n-> {e}");
    }
}

/// A `pair.table` file at `path` of harmonic soft spheres, `U = k (sigma - r)^2` and its force
/// `2 k (sigma - r)` below `sigma` (zero beyond), on `points` values of r from `r_first` in
/// steps of `dr`.
pub(crate) fn harmonic_table(
    path: &std::path::Path,
    k: f64,
    sigma: f64,
    r_first: f64,
    dr: f64,
    points: usize,
) {
    let mut csv = String::from("r,U_AA,F_AA\n");
    for i in 0..points {
        let r = r_first + dr * i as f64;
        let h = (sigma - r).max(0.0);
        csv += &format!("{r},{},{}\n", k * h.powi(2), 2.0 * k * h);
    }
    std::fs::write(path, csv).unwrap();
}

#[test]
fn each_pair_kind_runs_a_static_droplet() {
    let dir = tempfile::tempdir().unwrap();
    let table = dir.path().join("soft.csv");
    harmonic_table(&table, 10.0, 1.4, 0.9, 0.005, 101);
    for pair in [
        "kind = \"lj\"\nepsilon = [0.5]\ncutoff = 2.5".to_string(),
        "kind = \"yukawa\"\ncharges = [20.0]\nbjerrum_length = 0.01\ndebye_length = 0.2".into(),
        "kind = \"morse\"\ndepth = 2.0\nkappa = 10.0".into(),
        "kind = \"ao\"\ndepletant_diameter = 0.2\ndepletant_fraction = 0.1".into(),
        format!("kind = \"table\"\ntable = \"{}\"", table.display()),
    ] {
        let p = read(&format!("{BASE}[pair]\n{pair}\n")).unwrap_or_else(|e| panic!("{pair}: {e}"));
        let mut sim = p.build_replica(0).unwrap();
        sim.run(100).unwrap_or_else(|e| panic!("{pair}: {e}"));
        assert!(sim.snapshot().pos.iter().flatten().all(|x| x.is_finite()));
    }
}

#[test]
fn a_mixture_drifts_with_pse_at_each_species_stokes_mobility() {
    let p = read(&with(
        "",
        "[system.species]\ndiameters = [1.0, 2.0]\ncounts = [280, 20]\n\
         [hydrodynamics]\nmodel = \"rpy\"\nmethod = \"pse\"\ntolerance = 1e-3\n",
    ))
    .unwrap();
    let hydro = p.hydrodynamics.clone().unwrap();
    let mut sim = p.build_hydro_replica(0, &hydro).unwrap();
    use colloidsim_md::hydro::Mobility;
    let eta = p.viscosity;
    for (i, d) in sim.particles().diameter.iter().enumerate() {
        let want = 1.0 / (3.0 * std::f64::consts::PI * eta * d);
        let got = sim.mobility().stokes_mobility(i);
        assert!(
            (got / want - 1.0).abs() < 1e-12,
            "particle {i}: {got} vs {want}"
        );
    }
    sim.run(20).unwrap();
    let pos = sim.particles().pos.clone();
    assert!(pos.iter().flatten().all(|x| x.is_finite()));
    // Reproducible: the same replica again is the same run.
    let mut again = p.build_hydro_replica(0, &hydro).unwrap();
    again.run(20).unwrap();
    assert_eq!(again.particles().pos, pos);
}
