//! A BCD run's observables do not depend on the number of threads: the density and the
//! clusters are taken in the step's own parallel pass (`Bcd::step_observed`), per chunk, and
//! must come out the same on one thread as on two, on a ring of several chunks.

use colloidsim_run::{Control, RunOptions, Scenario};
use std::path::Path;

/// 9,000 dense rods (three chunks of the ring step) in a cosine field, every observer every
/// step, 120 steps with 20 of equilibration.
const RODS: &str = "method = \"bcd\"\nseed = 4\n[system]\nlength = 9000.0\nparticles = 9000\n\
     diameter = 0.99\n[potential]\ncosine = { amplitude = 6.0, wavelength = 1.0 }\n\
     [run]\ndt = 1e-3\nequilibrate = 0.02\ntime = 0.1\n\
     [observe]\nevery = 1\ndensity = { bins = 40 }\nmsd = { points = 6 }\nclusters = true\n\
     contact_density = { bins = 20, window = 0.05 }\ncurrent = true\n";

fn run_on(threads: usize, sc: &Scenario, out: &Path) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let opts = RunOptions {
        out: Some(out.to_path_buf()),
        seed: None,
        force: false,
    };
    pool.install(|| colloidsim_run::run(sc, &opts, &Control::default()))
        .unwrap();
}

#[test]
fn bcd_observables_are_the_same_on_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let sc = Scenario::from_toml(RODS, dir.path()).unwrap();
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    run_on(1, &sc, &one);
    run_on(2, &sc, &two);
    for file in [
        "density.csv",
        "clusters.csv",
        "msd.csv",
        "contact_density.csv",
        "current.csv",
        "final_configuration.csv",
    ] {
        let a = std::fs::read(one.join(file)).unwrap();
        let b = std::fs::read(two.join(file)).unwrap();
        assert!(!a.is_empty(), "{file} is empty");
        assert!(a == b, "{file} differs between one and two threads");
    }
}
