//! MPCD engines with colloids, stepped by hand (Python's `colloidsim.MPCD`): the particle
//! arrays (solvent, then colloid centres, then vertices), split stepping bit for bit, the
//! momentum of solvent and colloids conserved by the coupled step, and the forces (none on the
//! solvent; on the colloids internal ones that sum to zero in the bulk).

use colloidsim_run::{Scenario, engine};
use std::path::Path;

/// Two colloids of d = 3 in a bulk box of 8 cells (2560 solvent particles).
const BULK: &str = r#"
method = "mpcd"
seed = 5
[system]
box = 8
colloids = 2
diameter = 3
[run]
collisions = 100
equilibrate = 10
[observe]
vacf_lags = 5
"#;

/// A drying droplet of R0 = 8 cells with 6 colloids of d = 4 (no-slip).
const DROPLET: &str = r#"
method = "droplet-mpcd"
seed = 4
boundary = "no-slip"
[system]
particles = 6
diameter = 4
radius = 8
[drying]
peclet = 10
duration = 30
"#;

fn scenario(text: &str) -> Scenario {
    Scenario::from_toml(text, Path::new(".")).unwrap()
}

/// Total momentum from flattened velocities: solvent mass 1, colloid particles mass 5 (the
/// defaults of both).
fn momentum(v: &[f64], solvent: usize) -> [f64; 3] {
    let mut p = [0.0; 3];
    for (i, row) in v.chunks(3).enumerate() {
        let m = if i < solvent { 1.0 } else { 5.0 };
        for k in 0..3 {
            p[k] += m * row[k];
        }
    }
    p
}

#[test]
fn a_bulk_engine_with_colloids_steps_the_coupled_system() {
    let sc = scenario(BULK);
    let solvent = 5 * 8 * 8 * 8;
    let mut a = engine(&sc, None).unwrap();
    assert_eq!(a.particles(), solvent + 2 * 43);
    let (x0, v0) = (a.positions(), a.velocities().unwrap());
    assert_eq!(x0.len(), 3 * a.particles());
    a.step(6).unwrap();
    let mut b = engine(&sc, None).unwrap();
    b.step(2).unwrap();
    b.step(4).unwrap();
    assert_eq!(a.positions(), b.positions());
    assert_eq!(a.velocities(), b.velocities());
    let (x, v) = (a.positions(), a.velocities().unwrap());
    // The colloids moved (centres and vertices), and exchanged momentum with the solvent in
    // the collisions while the total stayed put (the cell thermostat conserves each cell's).
    assert_ne!(x[3 * solvent..], x0[3 * solvent..]);
    let (p0, p) = (momentum(&v0, solvent), momentum(&v, solvent));
    let pc = momentum(&v[3 * solvent..], 0);
    let pc0 = momentum(&v0[3 * solvent..], 0);
    assert!(
        (0..3).all(|k| (p[k] - p0[k]).abs() < 1e-9),
        "{p0:?} -> {p:?}"
    );
    assert!(
        (0..3).any(|k| (pc[k] - pc0[k]).abs() > 1e-3),
        "{pc0:?} -> {pc:?}"
    );
    // Vertices lie within d/2 (plus the bond strain) of their centre.
    for c in 0..2 {
        let centre = &x[3 * (solvent + c)..3 * (solvent + c + 1)];
        for k in 0..42 {
            let i = solvent + 2 + 42 * c + k;
            let r = (0..3)
                .map(|j| (x[3 * i + j] - centre[j]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!((r - 1.5).abs() < 0.1, "colloid {c} vertex {k} at {r}");
        }
    }
    // Forces: none on the solvent; bonds and WCA on the colloids, summing to zero.
    let f = a.forces().unwrap();
    assert_eq!(f.len(), x.len());
    assert!(f[..3 * solvent].iter().all(|&y| y == 0.0));
    let largest = f.iter().fold(0f64, |m, y| m.max(y.abs()));
    assert!(largest > 0.0 && largest.is_finite());
    let net = momentum(&f[3 * solvent..], 0).map(|s| s / 5.0);
    assert!(net.iter().all(|s| s.abs() < 1e-9 * largest), "{net:?}");
}

#[test]
fn a_droplet_engine_with_colloids_dries_with_them() {
    let sc = scenario(DROPLET);
    let mut e = engine(&sc, None).unwrap();
    let n0 = e.particles();
    e.step(20).unwrap();
    assert_eq!(e.steps(), 20);
    assert!(
        e.particles() < n0,
        "the solvent follows the shrinking volume"
    );
    let x = e.positions();
    assert!(x.iter().all(|y| y.is_finite()));
    let f = e.forces().unwrap();
    assert_eq!(f.len(), x.len());
    assert!(f.iter().all(|y| y.is_finite()));
}
