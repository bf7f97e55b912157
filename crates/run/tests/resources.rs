//! Sizes a key or flag sets (grids, bins, terms, colloids, lags, seeds) are estimated before
//! anything starts: what no machine can hold, or no check could finish, is refused with a
//! message naming the key; sizes that only looked large are handled at a bounded cost (issue
//! 42: a panic, an abort and hangs). Each test is a `check` (or a refusal) of a tiny scenario.

use colloidsim_run::{Control, ExtrapolateOptions, Scenario, TheoryOptions};

/// The error of `check` on `text`, with its causes.
fn refusal(text: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let sc = Scenario::from_toml(text, dir.path()).unwrap();
    match colloidsim_run::check(&sc) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => format!("{e:#}"),
    }
}

const DROPLET: &str = r#"
method = "droplet-bd"
seed = 1
[system]
particles = 50
diameter = 1.0
phi0 = 0.05
[drying]
peclet = 10
final_volume_fraction = 0.2
[run]
dt = 2e-3
"#;

/// `colloidsim theory --dx 1e-300` on a droplet: a grid of 1e301 cells was allocated (a
/// "capacity overflow" panic); now refused naming the spacing, before any output.
#[test]
fn a_theory_grid_beyond_the_memory_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sc = Scenario::from_toml(DROPLET, dir.path()).unwrap();
    let opts = TheoryOptions {
        out: Some(dir.path().join("t")),
        dx: Some(1e-300),
        force: false,
        hydrodynamics: None,
        pair: None,
    };
    let e = colloidsim_run::theory(&sc, &opts, &Control::default()).unwrap_err();
    let e = format!("{e:#}");
    assert!(
        e.contains("theory.dr") && e.contains("radial grid") && e.contains("--dx"),
        "{e}"
    );
}

const MPCD: &str = r#"
method = "mpcd"
seed = 1
[system]
box = 10
colloids = 1
diameter = 4
[run]
collisions = 1000
equilibrate = 0
"#;

/// One MPCD colloid of diameter 1e-300 in a box of 10: its placement grid had 1024^3 cells
/// (24 GiB, an abort); the grid now holds no more cells than the colloids need (the engine's
/// `grids_over_the_colloids_stay_small_for_any_diameter`), and `check` refuses such a colloid,
/// whose bonds cannot hold its shape (it went non-finite at its first step).
#[test]
fn a_tiny_mpcd_colloid_is_refused_by_check() {
    let e = refusal(&MPCD.replace("diameter = 4", "diameter = 1e-300"));
    assert!(
        e.contains("system.diameter: a colloid of diameter 1e-300")
            && e.contains("not held in shape"),
        "{e}"
    );
}

/// The colloids' velocity autocorrelation holds `lags + 1` velocity sets: 1e15 lags are
/// refused by check, naming the key (they were allocated when the run began).
#[test]
fn mpcd_autocorrelation_lags_beyond_the_memory_are_refused() {
    let text = MPCD
        .replace("collisions = 1000", "collisions = 4000000000000000")
        .replace(
            "equilibrate = 0",
            "equilibrate = 0\n[observe]\nvacf_lags = 1000000000000000",
        );
    let e = refusal(&text);
    assert!(
        e.contains("observe.vacf_lags") && e.contains("more than this machine can give"),
        "{e}"
    );
}

const HS_MC: &str = r#"
method = "hs-mc"
seed = 1
[system]
geometry = "interface"
particles = 20
radius = 4.0
diameter = 1.0
[interface]
stiffness = 50.0
range = 0.5
offset = -0.5
[mc]
sweeps = 20
warmup_sweeps = 0
sample_every = 10
blocks = 2
"#;

/// hs-mc's search for the interface's cut-off never left the wall when `wall + range` rounds
/// to `wall` (a radius or offset of 2^63, a range of 1e-300): check hung. Now refused naming
/// the range, with the radius and offset it was compared with.
#[test]
fn an_interface_range_unresolved_at_the_wall_is_refused() {
    for (from, to) in [
        ("radius = 4.0", "radius = 9223372036854775807"),
        ("range = 0.5", "range = 1e-300"),
        ("offset = -0.5", "offset = 9223372036854775807"),
    ] {
        let e = refusal(&HS_MC.replace(from, to));
        assert!(
            e.contains("interface.range") && e.contains("not resolved at the wall"),
            "{to}: {e}"
        );
    }
}

/// A droplet of radius 1e15 diameters behind a hard wall: its Monte Carlo cell grid (1e45
/// cells) is refused by check, naming the radius.
#[test]
fn an_hs_mc_cell_grid_beyond_the_memory_is_refused() {
    let text = HS_MC
        .replace("\"interface\"", "\"hard-wall\"")
        .replace("radius = 4.0", "radius = 1e15")
        .replace(
            "[interface]\nstiffness = 50.0\nrange = 0.5\noffset = -0.5\n",
            "",
        );
    let e = refusal(&text);
    assert!(
        e.contains("system.radius") && e.contains("Monte Carlo cells"),
        "{e}"
    );
}

/// `potential.fourier` with more terms than [`MAX_FOURIER_TERMS`]: check tabulated the force
/// from every term at up to 2^22 points (2e5 terms: hours); now refused naming the list.
#[test]
fn fourier_series_beyond_the_term_bound_are_refused() {
    for (list, n) in [("cos", 257), ("sin", 200_000)] {
        let terms = vec!["1e-6"; n].join(", ");
        let text = format!(
            "method = \"bcd\"\n[system]\nlength = 20.0\nparticles = 10\ndiameter = 0.5\n\
             [run]\ndt = 1e-4\nequilibrate = 0.1\ntime = 1.0\n\
             [potential]\nfourier = {{ wavelength = 2.0, {list} = [{terms}] }}\n"
        );
        let e = refusal(&text);
        assert!(
            e.contains(&format!("potential.fourier.{list}"))
                && e.contains(&format!("{n} terms: at most 256")),
            "{e}"
        );
    }
}

/// DPD's S(q) cost wave numbers x bins with as many wave numbers as bins: 1e5 bins never
/// finished. The wave numbers are now at most 1000 and the bins at most 1e5.
#[test]
fn dpd_gr_bins_beyond_the_bound_are_refused() {
    let text =
        "method = \"dpd\"\n[system]\nbox_length = 8.0\nphi = 0.1\n[observe]\ngr_bins = 100001\n";
    let e = refusal(text);
    assert!(
        e.contains("observe.gr_bins") && e.contains("[2, 100000]"),
        "{e}"
    );
}

/// DPD keeps every MSD sample to the end of the run: 1e15 steps sampled every step are refused
/// by check, naming the sampling interval (they grew until the machine ran out of memory).
#[test]
fn dpd_msd_samples_beyond_the_memory_are_refused() {
    let text = "method = \"dpd\"\n[system]\nbox_length = 8.0\nphi = 0.1\n\
                [run]\nsteps = 1000000000000000\n[observe]\nmsd_every = 1\n";
    let e = refusal(text);
    assert!(
        e.contains("observe.msd_every") && e.contains("MSD samples"),
        "{e}"
    );
}

/// BD with PSE hydrodynamics and a diameter far below 1 / splitting: the real-space table of
/// the wave-space functions (1e302 points at d = 1e-300, which overflowed its count, a panic in
/// check; 4e8 at d = 1e-6, which hung check) is refused naming the diameter. (A diameter of
/// 1e-300 is now refused before, by the scales it makes: `finite_cli`.)
#[test]
fn a_pse_table_beyond_the_bound_is_refused_naming_the_diameter() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/bd/hasimoto.toml"
    );
    let text = std::fs::read_to_string(path)
        .unwrap()
        .replace("[system]", "[system]\ndiameter = 1e-6");
    let e = refusal(&text);
    assert!(
        e.contains("system.diameter") && e.contains("wave-space table"),
        "{e}"
    );
}

/// `extrapolate --seeds 100000` started 200,000 runs one after the other; now refused before
/// the output folder is made.
#[test]
fn extrapolation_seeds_beyond_the_bound_are_refused_before_any_output() {
    let dir = tempfile::tempdir().unwrap();
    let text = "method = \"bcd\"\nseed = 1\n[system]\nlength = 20.0\nparticles = 10\n\
                diameter = 0.5\n[run]\ndt = 1e-3\nequilibrate = 0.1\ntime = 1.0\n";
    let sc = Scenario::from_toml(text, dir.path()).unwrap();
    let out = dir.path().join("x");
    let opts = ExtrapolateOptions {
        out: Some(out.clone()),
        seeds: 100_000,
        ..Default::default()
    };
    let e = colloidsim_run::extrapolate(&sc, &opts, &Control::default()).unwrap_err();
    let e = format!("{e:#}");
    assert!(e.contains("--seeds 100000: at most 1000"), "{e}");
    assert!(!out.exists());
    // The seeds seed .. seed + seeds - 1 must be valid seeds, checked before any run too.
    let sc =
        Scenario::from_toml(&text.replace("seed = 1", "seed = 4294967295"), dir.path()).unwrap();
    let opts = ExtrapolateOptions { seeds: 2, ..opts };
    let e = format!(
        "{:#}",
        colloidsim_run::extrapolate(&sc, &opts, &Control::default()).unwrap_err()
    );
    assert!(e.contains("--seeds") && e.contains("2^32"), "{e}");
    assert!(!out.exists());
}

/// hs-mc with 20 spheres in a hard-wall droplet of radius 304 d: 3e7 cells, each visited every
/// sweep, and `check` spent 26 s (5.8 GB) building them and two minutes placing 20 spheres on a
/// lattice counted over 1e8 sites; refused before either (found by the key-by-key fuzz).
#[test]
fn a_cell_grid_far_larger_than_its_spheres_need_is_refused() {
    let text = "method = \"hs-mc\"\n[system]\ngeometry = \"hard-wall\"\nparticles = 20\n\
                radius = 304.5\n[mc]\nsweeps = 20\nwarmup_sweeps = 10\nblocks = 2\n";
    let e = refusal(text);
    assert!(
        e.contains("system") && e.contains("each sweep visits every cell"),
        "{e}"
    );
    // The same spheres in a droplet the grid bound allows are accepted.
    let near = text.replace("radius = 304.5", "radius = 30.0");
    let sc = colloidsim_run::Scenario::from_toml(&near, std::path::Path::new(".")).unwrap();
    colloidsim_run::check(&sc).unwrap();
}
