//! Analysis of a GSD trajectory written by the engine: unwrapping with the image counts and the
//! MSD of free Brownian particles (6 D t).

use colloidsim_analysis::{mean_squared_displacement, read_trajectory};
use colloidsim_md::gsd::GsdWriter;
use colloidsim_md::init::random_in_box;
use colloidsim_md::{BdParams, Brownian, NoExternal, NoPair, Particles, SimBox};
use std::f64::consts::PI;

#[test]
fn msd_from_a_gsd_trajectory_is_6_d_t() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("free.gsd");
    let n = 3000;
    let sbox = SimBox::cube(6.0); // small: positions wrap many times
    let pos = random_in_box(n, 0.0, &sbox, 1, 0).unwrap();
    let params = BdParams::new(0.01, 4);
    let mut sim = Brownian::new(
        Particles::monodisperse(pos, 1.0),
        sbox,
        NoPair,
        NoExternal,
        params,
        0,
    )
    .unwrap();
    let mut w = GsdWriter::create_new(&path).unwrap();
    for _ in 0..6 {
        w.write_frame(sim.step, &sim.sbox, &sim.snapshot(), true, &[])
            .unwrap();
        sim.run(50).unwrap();
    }
    drop(w);
    let frames = read_trajectory(&path).unwrap();
    assert_eq!(frames.len(), 6);
    let x: Vec<Vec<[f64; 3]>> = frames.iter().map(|f| f.unwrapped.clone()).collect();
    let msd = mean_squared_displacement(&x);
    let d0 = 1.0 / (3.0 * PI);
    for (k, m) in msd.iter().enumerate() {
        let t = (k + 1) as f64 * 50.0 * 0.01;
        let want = 6.0 * d0 * t;
        // The lag-1 average over 5 origins of N particles: relative error well below
        // sqrt(2/3) / sqrt(N) = 1.5 %; 5 sigma (lags share origins, so this is generous).
        let tol = 5.0 * (2.0 / 3.0f64).sqrt() / (n as f64).sqrt();
        assert!((m / want - 1.0).abs() < tol, "lag {}: {m} vs {want}", k + 1);
    }
    // Wrapped positions alone would not give it: the box is smaller than the displacements.
    let w: Vec<Vec<[f64; 3]>> = frames.iter().map(|f| f.wrapped.clone()).collect();
    let wrong = mean_squared_displacement(&w);
    assert!((wrong[4] / (6.0 * d0 * 2.5) - 1.0).abs() > 0.1);
}
