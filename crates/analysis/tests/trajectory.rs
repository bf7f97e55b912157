//! Analysis of a GSD trajectory: unwrapping with the image counts and the MSD of free Brownian
//! particles (6 D t). The frames are a free random walk written with the shared GSD writer (the
//! engine's own MSD is tested in `colloidsim-md`), in a box smaller than the displacements.

use colloidsim_analysis::{mean_squared_displacement, read_trajectory};
use colloidsim_core::rng::fill_normals;
use colloidsim_particles::gsd::GsdWriter;
use colloidsim_particles::init::random_in_box;
use colloidsim_particles::{Particles, SimBox};
use std::f64::consts::PI;

#[test]
fn msd_from_a_gsd_trajectory_is_6_d_t() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("free.gsd");
    let n = 3000;
    let sbox = SimBox::cube(6.0); // small: positions wrap many times
    let d0 = 1.0 / (3.0 * PI);
    let interval = 50.0 * 0.01; // time between frames
    let start = random_in_box(n, 0.0, &sbox, 1, 0).unwrap();
    let mut truth = start.clone();
    let mut p = Particles::monodisperse(start, 1.0);
    let mut w = GsdWriter::create_new(&path).unwrap();
    let mut xi = vec![0.0; 3 * n];
    let mut history = Vec::new();
    for frame in 0..6u64 {
        w.write_frame(frame * 50, &sbox, &p, true, &[]).unwrap();
        history.push(truth.clone());
        fill_normals(1, frame, &mut xi);
        let s = (2.0 * d0 * interval).sqrt();
        for i in 0..n {
            for k in 0..3 {
                truth[i][k] += s * xi[3 * i + k];
                p.pos[i][k] += s * xi[3 * i + k];
            }
            sbox.wrap(&mut p.pos[i], &mut p.image[i]);
        }
    }
    drop(w);
    let frames = read_trajectory(&path).unwrap();
    assert_eq!(frames.len(), 6);
    // The image counts restore the walk.
    for (f, want) in frames.iter().zip(&history) {
        for (u, x) in f.unwrapped.iter().zip(want) {
            for k in 0..3 {
                assert!((u[k] - x[k]).abs() < 1e-9, "{u:?} vs {x:?}");
            }
        }
    }
    let x: Vec<Vec<[f64; 3]>> = frames.iter().map(|f| f.unwrapped.clone()).collect();
    let msd = mean_squared_displacement(&x);
    for (k, m) in msd.iter().enumerate() {
        let t = (k + 1) as f64 * interval;
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
