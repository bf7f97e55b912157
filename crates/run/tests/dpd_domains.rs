//! DPD decomposed over ranks (issue 20): the ranks are threads talking over channels
//! ([`LocalRanks`]); the MPI ranks of the CLI run the same code. A decomposed run must be
//! bitwise the single-rank run, for any number of ranks, with lists or cells, with colloids.

use crate::common;

use colloidsim_md::dpd::setup::DpdSetup;
use colloidsim_md::dpd::{Dpd, DpdError, NeighborMode, Thermo};
use colloidsim_particles::Particles;
use colloidsim_run::methods::dpd::params;
use common::on_ranks;

fn scenario(text: &str) -> DpdSetup {
    params::setup(text).unwrap()
}

/// A small polydisperse suspension with Morse attraction (as the thread test).
fn suspension(mode: NeighborMode) -> DpdSetup {
    let mut s = scenario(
        "method = \"dpd\"\nseed = 9\n[system]\nbox_length = 8.0\nphi = 0.15\nradius_distribution = \"uniform\"\nradius_spread = 0.2\n[colloids]\nmorse_depth = 12.0\n",
    );
    s.params.neighbors = mode;
    s
}

/// What a run ends with: particles, forces, the thermo of its last step, and the smallest and
/// largest number of particles a rank held along the way.
struct End {
    snap: Particles,
    forces: Vec<[f64; 3]>,
    thermo: Thermo,
    /// The pressure tensor by part after the last step.
    parts: Vec<[f64; 6]>,
    owned: (usize, usize),
}

/// DPD water (density 3, a = 25, gamma = 4.5) at dt = 0.04 in a cube of side `l`.
fn water(l: f64) -> DpdSetup {
    scenario(&format!(
        "method = \"dpd\"\nseed = 4\n[system]\nbox_length = {l}\n[run]\ndt = 0.04\n"
    ))
}

fn finish(sim: &mut Dpd, steps: u64) -> End {
    let mut owned = (usize::MAX, 0);
    for _ in 0..steps {
        sim.advance().unwrap();
        owned = (owned.0.min(sim.owned()), owned.1.max(sim.owned()));
    }
    let thermo = sim.advance_with_thermo().unwrap();
    End {
        snap: sim.snapshot(),
        forces: sim.forces(),
        thermo,
        parts: sim.pressure_parts().to_vec(),
        owned,
    }
}

fn serial(setup: &DpdSetup, steps: u64) -> End {
    finish(&mut setup.build().unwrap(), steps)
}

fn decomposed(setup: &DpdSetup, ranks: usize, steps: u64) -> Vec<End> {
    on_ranks(ranks, |c| {
        finish(&mut setup.build_decomposed(c).unwrap(), steps)
    })
}

fn assert_same(a: &End, b: &End, what: &str) {
    assert!(a.snap == b.snap, "{what}: particles differ");
    assert!(a.forces == b.forces, "{what}: forces differ");
    // Bitwise, NaN (the temperature of a type with no particles) included.
    let (ta, tb) = (format!("{:?}", a.thermo), format!("{:?}", b.thermo));
    assert_eq!(ta, tb, "{what}: thermo differs");
    assert!(a.parts == b.parts, "{what}: pressure parts differ");
}

#[test]
fn a_decomposed_suspension_is_bitwise_the_single_rank_run() {
    for mode in [NeighborMode::Verlet, NeighborMode::Cells] {
        let setup = suspension(mode);
        // 200 steps at dt 0.005: the lists are rebuilt (and particles migrate) a few times.
        let one = serial(&setup, 200);
        assert!(one.snap.typeid.iter().filter(|&&t| t == 1).count() > 5);
        for ranks in [2, 3, 4] {
            let ends = decomposed(&setup, ranks, 200);
            let n = one.snap.len();
            for (r, e) in ends.iter().enumerate() {
                assert_same(&one, e, &format!("{mode:?}, rank {r} of {ranks}"));
                assert!(e.owned.1 < n, "{mode:?}: {:?}", e.owned);
            }
        }
    }
}

#[test]
fn water_is_bitwise_the_single_rank_run_with_lists_and_with_cells() {
    // At dt 0.04 the lists are rebuilt every few steps (each rebuild migrates particles and
    // fetches new ghosts), and with cells every step sorts. The box has 5 layers of cells
    // with lists (1.4 wide) and 7 with cells: on 3 ranks some own one layer, others two.
    for mode in [NeighborMode::Verlet, NeighborMode::Cells] {
        let mut setup = water(7.0);
        setup.params.neighbors = mode;
        let one = serial(&setup, 100);
        for ranks in [2, 3] {
            for (r, e) in decomposed(&setup, ranks, 100).iter().enumerate() {
                assert_same(&one, e, &format!("water, {mode:?}, rank {r} of {ranks}"));
                assert!(e.owned.0 < e.owned.1, "{mode:?}: {:?}", e.owned);
            }
        }
    }
}

/// A checkpoint at step 100 (synchronised every 50 steps) of `setup` run on `ranks` ranks
/// continues on each of `on` ranks bitwise as the uninterrupted single-rank run to step 250.
fn checkpoint_continues(setup: &DpdSetup, ranks: usize, on: &[usize]) {
    let (snap, forces) = on_ranks(ranks, |c| {
        let mut sim = setup.build_decomposed(c).unwrap();
        sim.set_sync_every(50);
        sim.run(100).unwrap();
        (sim.snapshot(), sim.forces())
    })
    .remove(0);
    // The uninterrupted run, on one rank.
    let mut a = setup.build().unwrap();
    a.set_sync_every(50);
    a.run(250).unwrap();
    let mut params = setup.params;
    params.rank_grid = None;
    for &ranks_after in on {
        let ends = on_ranks(ranks_after, |c| {
            let mut b = Dpd::restart_on(
                snap.clone(),
                &forces,
                setup.sbox,
                params,
                DpdSetup::colloid_types(),
                100,
                50,
                Some(c),
            )
            .unwrap();
            b.run(150).unwrap();
            b.snapshot()
        });
        for b in ends {
            assert!(
                a.snapshot() == b,
                "{:?}: saved on {ranks} ranks ({:?}), continued on {ranks_after}: differs",
                setup.params.neighbors,
                setup.params.rank_grid
            );
        }
    }
}

#[test]
fn a_checkpoint_continues_bitwise_on_another_number_of_ranks() {
    for mode in [NeighborMode::Verlet, NeighborMode::Cells] {
        checkpoint_continues(&suspension(mode), 2, &[1, 3]);
    }
}

#[test]
fn every_rank_stops_with_the_same_error() {
    // A time step far too large: the first step moves a particle more than half the cut-off.
    let setup = water(7.0);
    let mut fast = setup.clone();
    fast.params.dt = 2.0;
    let one = fast.build().unwrap().run(5).unwrap_err();
    let errs = on_ranks(3, |c| fast.build_decomposed(c).unwrap().run(5).unwrap_err());
    assert!(matches!(one, DpdError::Unstable { .. }), "{one}");
    for e in errs {
        assert_eq!(e, one);
    }
    // More ranks than any grid fits (5 x 5 x 5 cells: at most 5 slabs of at most 5 columns,
    // and a column needs two rows besides its own): refused on every rank, naming the limit.
    let errs = on_ranks(30, |c| setup.build_decomposed(c).err().unwrap().to_string());
    for e in errs {
        assert!(e.contains("30 ranks for 5 layers"), "{e}");
    }
    // A grid given that does not fit, or is not the number of ranks: refused, naming it.
    for (grid, ranks, says) in [
        ([6, 1], 6, "6 ranks along y for 5 rows"),
        ([2, 2], 3, "a grid of 2 x 2 ranks (y x z) for 3 ranks"),
    ] {
        let mut s = setup.clone();
        s.params.rank_grid = Some(grid);
        for e in on_ranks(ranks, |c| s.build_decomposed(c).err().unwrap().to_string()) {
            assert!(e.contains(says), "{e}");
        }
    }
}

fn on_grid(setup: &DpdSetup, grid: [usize; 2], steps: u64) -> Vec<End> {
    let mut s = setup.clone();
    s.params.rank_grid = Some(grid);
    decomposed(&s, grid[0] * grid[1], steps)
}

#[test]
fn a_grid_cut_along_y_and_z_is_bitwise_the_single_rank_run() {
    // Columns along y hold a fringe row of ghosts on each side and compute the pairs across
    // the cut on both sides: each owned particle's pairs are met in the single-rank order.
    // The suspension's box has 4 cells a side (lists) and 5 (cells); water's 5 and 7.
    for mode in [NeighborMode::Verlet, NeighborMode::Cells] {
        let setup = suspension(mode);
        let one = serial(&setup, 200);
        for grid in [[2, 1], [2, 2], [3, 1]] {
            for (r, e) in on_grid(&setup, grid, 200).iter().enumerate() {
                assert_same(&one, e, &format!("{mode:?}, rank {r} of grid {grid:?}"));
                assert!(e.owned.1 < one.snap.len(), "{mode:?}: {:?}", e.owned);
            }
        }
        let mut setup = water(7.0);
        setup.params.neighbors = mode;
        let one = serial(&setup, 60);
        for grid in [[2, 2], [3, 2]] {
            for (r, e) in on_grid(&setup, grid, 60).iter().enumerate() {
                assert_same(
                    &one,
                    e,
                    &format!("water, {mode:?}, rank {r} of grid {grid:?}"),
                );
            }
        }
    }
    // More ranks than layers: the grid chosen cuts along y too (6 ranks, 5 layers of lists).
    let setup = water(7.0);
    let one = serial(&setup, 60);
    for (r, e) in decomposed(&setup, 6, 60).iter().enumerate() {
        assert_same(&one, e, &format!("water on 6 ranks, rank {r}"));
    }
}

#[test]
fn a_checkpoint_of_a_grid_continues_bitwise_on_slabs_and_on_one_rank() {
    let mut on_2x2 = suspension(NeighborMode::Verlet);
    on_2x2.params.rank_grid = Some([2, 2]);
    checkpoint_continues(&on_2x2, 4, &[1, 2]);
}
