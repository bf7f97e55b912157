//! Trial moves per second of local Monte Carlo with a pair interaction against hard spheres
//! (docs/mc.md, "Pair interactions"): 4000 spheres of d = 1 in a periodic cube at number
//! density `rho` (first argument, 0.1), one thread, 200 sweeps after a tuned warm-up.
//!
//! `cargo run --release -p colloidsim-mc --example pair_speed -- 0.6`

use colloidsim_mc::engine::{HardSphereMc, McParams};
use colloidsim_mc::geometry::Geometry;
use colloidsim_particles::PairSpec;

fn main() {
    let rho: f64 = std::env::args()
        .nth(1)
        .map_or(0.1, |s| s.parse().expect("a density"));
    let n = 4000;
    let l = (n as f64 / rho).cbrt();
    let pos = colloidsim_mc::init::fcc_in_box(n, 1.0, l).expect("a lattice that fits");
    let params = McParams {
        diameter: 1.0,
        geometry: Geometry::Bulk { edge: l },
        seed: 1,
        delta: 0.1,
        mixture: None,
    };
    let kinds = [
        ("hard spheres", None),
        ("wca", Some(PairSpec::wca(1.0, 1))),
        (
            "morse (range 0.5)",
            Some(PairSpec::Morse {
                depth: 0.5,
                kappa: 10.0,
                h0: 0.0,
                h_cut: 0.5,
            }),
        ),
        (
            "yukawa (range 2)",
            Some(PairSpec::Yukawa {
                charges: vec![10.0],
                bjerrum_length: 0.1,
                debye_length: 0.5,
                range: 2.0,
            }),
        ),
    ];
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .expect("one thread");
    for (name, spec) in kinds {
        let mut mc = match &spec {
            None => HardSphereMc::new(&params, &pos, "lattice"),
            Some(s) => HardSphereMc::with_pair(&params, &pos, "lattice", s, 1.0),
        }
        .expect("a valid start");
        mc.warm_up(200, 50, 0.3);
        let t = std::time::Instant::now();
        let s = mc.run(200);
        let dt = t.elapsed().as_secs_f64();
        println!(
            "{name}: rho {rho}: {:.3e} trial moves/s, acceptance {:.3}, cell side {:.3}",
            s.trials as f64 / dt,
            s.acceptance(),
            mc.cell_side()
        );
    }
}
