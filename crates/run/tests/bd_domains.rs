//! Brownian dynamics decomposed over ranks (issue 20): the ranks are threads talking over
//! channels ([`LocalRanks`]); the MPI ranks of the CLI run the same code. A decomposed run must
//! be bitwise the single-rank run for any number of ranks: periodic (with a body force that
//! drives particles across every domain face and the periodic seam) and in a drying droplet.

use crate::common;

use colloidsim_md::brownian::ListState;
use colloidsim_md::{BdError, BdParams, Brownian, Integrator};
use colloidsim_particles::potential::{ConstantForce, External, Pair};
use colloidsim_particles::{LennardJones, Particles, SimBox};
use common::on_ranks;
use std::f64::consts::PI;

/// `n` steps one at a time: [`Brownian::run`] runs them on a worker of the thread pool, where
/// ranks that are threads of one process would wait for each other with too few workers.
fn steps<P: Pair, E: External>(sim: &mut Brownian<P, E>, n: u64) {
    for _ in 0..n {
        sim.advance().unwrap();
    }
}

type Sedimenting = Brownian<LennardJones, ConstantForce>;

/// 1500 WCA spheres of diameters 0.8–1.2 at phi = 0.2 (11 layers of cells along z, L = 15.8),
/// pushed along (0.3, -0.2, 1) by a body force of 100 kT/d: in 1000 steps of dt = 2e-4 every
/// particle drifts about 20 d along z, across every domain face and the periodic seam.
fn sedimenting(integrator: Integrator) -> (Particles, SimBox, BdParams) {
    let n = 1500;
    let l = (n as f64 * PI / 6.0 / 0.2).cbrt();
    let sbox = SimBox::cube(l);
    let pos = colloidsim_particles::init::random_in_box(n, 1.2, &sbox, 31, 0).unwrap();
    let mut p = Particles::monodisperse(pos, 1.0);
    for (i, d) in p.diameter.iter_mut().enumerate() {
        *d = 0.8 + 0.4 * ((i * 7919) % 1000) as f64 / 1000.0;
    }
    let mut params = BdParams::new(2e-4, 77);
    params.viscosity = 1.0 / (3.0 * PI);
    params.sort_every = 50;
    params.integrator = integrator;
    (p, sbox, params)
}

fn build(
    p: &Particles,
    sbox: SimBox,
    params: BdParams,
    list: Option<&ListState>,
    step: u64,
) -> Sedimenting {
    Brownian::restart(
        p.clone(),
        sbox,
        LennardJones::wca(1.0, 1.0),
        ConstantForce([30.0, -20.0, 100.0]),
        params,
        step,
        list,
    )
    .unwrap()
}

/// What a run shows at its end.
#[derive(Debug, PartialEq)]
struct End {
    snap: Particles,
    forces: Vec<[f64; 3]>,
    list: ListState,
    builds: u64,
}

fn end<P: Pair, E: External>(sim: &Brownian<P, E>) -> End {
    End {
        snap: sim.snapshot(),
        forces: sim.forces(),
        list: sim.list_state(),
        builds: sim.neighbor_builds(),
    }
}

/// Run `steps`, recording the fewest and most particles this rank owned.
fn run_counting<E: External>(sim: &mut Brownian<LennardJones, E>, steps: u64) -> (usize, usize) {
    let mut owned = (usize::MAX, 0);
    for _ in 0..steps {
        sim.advance().unwrap();
        owned = (owned.0.min(sim.owned()), owned.1.max(sim.owned()));
    }
    owned
}

#[test]
fn sedimenting_spheres_on_2_3_4_ranks_are_the_single_rank_run() {
    let (p, sbox, params) = sedimenting(Integrator::Euler);
    let mut one = build(&p, sbox, params, None, 0);
    one.run(1000).unwrap();
    let want = end(&one);
    // Every particle crossed the periodic seam along z at least once (to the image above).
    assert!(
        want.snap.image.iter().all(|i| i[2] >= 1),
        "no seam crossing"
    );
    for ranks in [2, 3, 4] {
        let got = on_ranks(ranks, |c| {
            let mut sim = build(&p, sbox, params, None, 0).decomposed(c).unwrap();
            let owned = run_counting(&mut sim, 1000);
            (end(&sim), owned)
        });
        for (r, (e, owned)) in got.iter().enumerate() {
            assert!(
                e == &want,
                "{ranks} ranks: rank {r} differs from one process"
            );
            // Particles came and went: a rank owns between a few and all but a few.
            assert!(owned.0 < owned.1, "{ranks} ranks: rank {r} owned {owned:?}");
        }
    }
}

#[test]
fn leimkuhler_matthews_on_3_ranks_is_the_single_rank_run() {
    let (p, sbox, params) = sedimenting(Integrator::Lm);
    let mut one = build(&p, sbox, params, None, 0);
    one.run(150).unwrap();
    let want = end(&one);
    let got = on_ranks(3, |c| {
        let mut sim = build(&p, sbox, params, None, 0).decomposed(c).unwrap();
        steps(&mut sim, 150);
        end(&sim)
    });
    assert!(got.iter().all(|e| e == &want));
}

/// A checkpoint (particles and list state) at step 170 of a run on `ranks` ranks on `grid`
/// (`None`: the grid chosen) continues on 3 ranks and on one process as the uninterrupted run.
fn checkpoint_continues_on_3_and_on_1(ranks: usize, grid: Option<[usize; 2]>) {
    let (p, sbox, params) = sedimenting(Integrator::Euler);
    let mut one = build(&p, sbox, params, None, 0);
    one.run(300).unwrap();
    let want = end(&one);
    let saved = on_ranks(ranks, |c| {
        let mut sim = build(&p, sbox, params, None, 0)
            .decomposed_on(c, grid)
            .unwrap();
        steps(&mut sim, 170);
        (sim.snapshot(), sim.list_state(), sim.step)
    });
    let (snap, list, step) = &saved[0];
    assert!(saved.iter().all(|s| &s.0 == snap && &s.1 == list));
    let got = on_ranks(3, |c| {
        let mut sim = build(snap, sbox, params, Some(list), *step)
            .decomposed(c)
            .unwrap();
        steps(&mut sim, 130);
        end(&sim)
    });
    assert!(
        got.iter()
            .all(|e| e.snap == want.snap && e.forces == want.forces),
        "saved on {ranks} ranks ({grid:?}), continued on 3"
    );
    let mut back = build(snap, sbox, params, Some(list), *step);
    back.run(130).unwrap();
    assert_eq!(end(&back).snap, want.snap);
}

#[test]
fn checkpoint_of_2_ranks_continues_on_3_and_on_1() {
    checkpoint_continues_on_3_and_on_1(2, None);
}

/// A drying droplet (the `droplet-bd` engine: harmonic interface shrinking in a periodic box)
/// on 2 and 4 ranks: most layers are empty at first and the colloids gather in the middle ones.
#[test]
fn drying_droplet_on_2_and_4_ranks_is_the_single_rank_run() {
    let text = r#"
method = "droplet-bd"
seed = 5
[system]
particles = 600
phi0 = 0.1
[drying]
peclet = 10
final_volume_fraction = 0.3
"#;
    let dp = droplet_params(text);
    let n_steps = 600;
    let mut one = dp.build_replica(0).unwrap();
    one.run(n_steps).unwrap();
    let want = end(&one);
    for ranks in [2, 4] {
        let got = on_ranks(ranks, |c| {
            let mut sim = dp.build_replica(0).unwrap().decomposed(c).unwrap();
            steps(&mut sim, n_steps);
            end(&sim)
        });
        assert!(got.iter().all(|e| e == &want), "{ranks} ranks differ");
    }
    let got = on_ranks(4, |c| {
        let mut sim = dp
            .build_replica(0)
            .unwrap()
            .decomposed_on(c, Some([2, 2]))
            .unwrap();
        steps(&mut sim, n_steps);
        end(&sim)
    });
    assert!(got.iter().all(|e| e == &want), "a 2 x 2 grid differs");
}

/// A time step far too large stops every rank with the single-rank run's error.
#[test]
fn a_blow_up_stops_every_rank_with_one_error() {
    let (p, sbox, mut params) = sedimenting(Integrator::Euler);
    params.dt = 1e-3;
    let mut one = build(&p, sbox, params, None, 0);
    let want = (0..200).find_map(|_| one.advance().err()).unwrap();
    assert!(matches!(want, BdError::BlowUp { .. }), "{want}");
    let got = on_ranks(3, |c| {
        let mut sim = build(&p, sbox, params, None, 0).decomposed(c).unwrap();
        (0..200).find_map(|_| sim.advance().err())
    });
    for e in got {
        assert_eq!(e.as_ref(), Some(&want));
    }
}

#[test]
fn more_ranks_than_any_grid_fits_are_refused() {
    // 11 x 11 x 11 cells: 13 ranks (prime) fit neither as slabs nor as columns.
    let (p, sbox, params) = sedimenting(Integrator::Euler);
    let got = on_ranks(13, |c| build(&p, sbox, params, None, 0).decomposed(c).err());
    for e in got {
        let msg = e.unwrap().to_string();
        assert!(msg.contains("13 ranks for 11 layers"), "{msg}");
    }
}

/// Grids cut along y as well as z: each rank holds a fringe row of ghosts on each side of its
/// rows and sums the pairs across the cut itself; its owned slots are a run per layer, each
/// drawing its noise from where it starts in the whole system's order.
#[test]
fn sedimenting_spheres_on_grids_cut_along_y_are_the_single_rank_run() {
    let (p, sbox, params) = sedimenting(Integrator::Euler);
    let mut one = build(&p, sbox, params, None, 0);
    one.run(600).unwrap();
    let want = end(&one);
    for grid in [[2, 1], [2, 2], [3, 2]] {
        let got = on_ranks(grid[0] * grid[1], |c| {
            let mut sim = build(&p, sbox, params, None, 0)
                .decomposed_on(c, Some(grid))
                .unwrap();
            let owned = run_counting(&mut sim, 600);
            (end(&sim), owned)
        });
        for (r, (e, owned)) in got.iter().enumerate() {
            assert!(
                e == &want,
                "grid {grid:?}: rank {r} differs from one process"
            );
            assert!(owned.0 < owned.1, "grid {grid:?}: rank {r} owned {owned:?}");
        }
    }
    // More ranks than layers: the grid chosen cuts along y (12 ranks, 11 layers).
    let got = on_ranks(12, |c| {
        let mut sim = build(&p, sbox, params, None, 0).decomposed(c).unwrap();
        steps(&mut sim, 600);
        end(&sim)
    });
    assert!(got.iter().all(|e| e == &want), "12 ranks differ");
}

#[test]
fn leimkuhler_matthews_and_a_checkpoint_on_a_2_x_2_grid_are_the_single_rank_run() {
    let (p, sbox, params) = sedimenting(Integrator::Lm);
    let mut one = build(&p, sbox, params, None, 0);
    one.run(150).unwrap();
    let want = end(&one);
    let got = on_ranks(4, |c| {
        let mut sim = build(&p, sbox, params, None, 0)
            .decomposed_on(c, Some([2, 2]))
            .unwrap();
        steps(&mut sim, 150);
        end(&sim)
    });
    assert!(got.iter().all(|e| e == &want));
    // Euler: a checkpoint (particles and list state) of a 2 x 2 grid continues on slabs and on
    // one process as the uninterrupted run.
    checkpoint_continues_on_3_and_on_1(4, Some([2, 2]));
}

/// A `droplet-bd` scenario read by the run layer (its keys through their declarations).
fn droplet_params(text: &str) -> colloidsim_md::DropletParams {
    colloidsim_run::methods::droplet_bd::params::read(
        &toml::from_str(text).unwrap(),
        std::path::Path::new("."),
        None,
    )
    .unwrap()
}
