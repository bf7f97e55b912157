//! The SRD solvent decomposed over ranks (issue 20), the ranks being threads talking over
//! channels ([`common::on_ranks`]): a decomposed run must be bitwise the single-rank run, as a
//! set of particles, for any number of ranks, including one layer of cells per rank (where a
//! fast particle crosses a whole domain in a step and is passed on).

use crate::common;

use colloidsim_md::SimBox;
use colloidsim_md::mpcd::{Acceleration, Confinement, MpcdError, Srd, SrdParams};
use common::on_ranks;

type State = (Vec<[u32; 3]>, Vec<[f64; 3]>);

/// A periodic box of 12 x 10 x 12 cells at density 5 (7200 particles), sorted every 3
/// collisions.
fn solvent(seed: u32) -> Srd {
    let mut srd = Srd::new(
        SrdParams::standard(seed),
        SimBox::new([12.0, 10.0, 12.0]),
        &Confinement::None,
        0.0,
    )
    .unwrap();
    srd.set_sort_every(3);
    srd
}

/// A body force along z and x: in 40 steps the mean flow reaches 4 cells per unit time along z
/// (8 cells travelled), so particles cross every domain face and the periodic seam both ways
/// (thermal motion and the random grid shift move them back and forth too).
const DRIVE: Acceleration = Acceleration::Uniform([0.3, 0.0, 1.0]);

/// One step of the solvent, on one process or on every rank at once.
fn step(srd: &mut Srd, accel: &Acceleration) -> Result<(), MpcdError> {
    let t = (srd.step() + 1) as f64 * srd.params().tau;
    srd.stream(t, &Confinement::None, accel)?;
    srd.collide(t, &Confinement::None, None);
    Ok(())
}

fn single(seed: u32, steps: u64, accel: Acceleration) -> State {
    let mut srd = solvent(seed);
    for _ in 0..steps {
        step(&mut srd, &accel).unwrap();
    }
    srd.gathered_state()
}

fn decomposed(ranks: usize, seed: u32, steps: u64, accel: Acceleration) -> Vec<(State, [u64; 3])> {
    on_ranks(ranks, |comm| {
        let mut part = solvent(seed).decomposed(comm).unwrap();
        for _ in 0..steps {
            // A particle outside the own layers would index past the cell arrays and panic.
            step(&mut part, &accel).unwrap();
        }
        assert_eq!(part.particles(), 7200);
        // Exact sums: the momentum is the same bits as on one process.
        (part.gathered_state(), part.momentum().map(f64::to_bits))
    })
}

fn bits(s: &State) -> (Vec<[u32; 3]>, Vec<[u64; 3]>) {
    (
        s.0.clone(),
        s.1.iter().map(|v| v.map(f64::to_bits)).collect(),
    )
}

#[test]
fn a_decomposed_solvent_is_bitwise_the_single_rank_one() {
    let want = bits(&single(5, 40, DRIVE));
    let momentum = {
        let mut srd = solvent(5);
        for _ in 0..40 {
            step(&mut srd, &DRIVE).unwrap();
        }
        srd.momentum().map(f64::to_bits)
    };
    for ranks in [1, 2, 3, 4] {
        for (r, (got, p)) in decomposed(ranks, 5, 40, DRIVE).iter().enumerate() {
            assert!(
                bits(got) == want,
                "{ranks} ranks: rank {r}'s gathered state differs from the single-rank run"
            );
            assert_eq!(*p, momentum, "{ranks} ranks: rank {r}'s momentum");
        }
    }
}

#[test]
fn one_layer_per_rank_passes_fast_particles_on() {
    // 12 ranks of one layer each, a Poiseuille-like cosine drive along x and a strong body
    // force along z: the grid shift alone moves a particle's cell by up to one layer.
    let accel = Acceleration::Uniform([0.0, 0.0, 3.0]);
    let want = bits(&single(8, 25, accel));
    for (got, _) in decomposed(12, 8, 25, accel) {
        assert!(bits(&got) == want);
    }
    let cosine = Acceleration::CosineX {
        amplitude: 0.5,
        wavenumber: 2.0 * std::f64::consts::PI / 12.0,
    };
    let want = bits(&single(9, 20, cosine));
    for (got, _) in decomposed(6, 9, 20, cosine) {
        assert!(bits(&got) == want);
    }
}

#[test]
fn a_non_finite_velocity_on_one_rank_stops_every_rank() {
    // Bad input on rank 2 alone: its drive is infinite.
    let out = on_ranks(3, |comm| {
        let mut part = solvent(3).decomposed(comm).unwrap();
        step(&mut part, &Acceleration::None).unwrap();
        let accel = if part.rank().0 == 2 {
            Acceleration::Uniform([f64::INFINITY, 0.0, 0.0])
        } else {
            Acceleration::None
        };
        step(&mut part, &accel)
    });
    for r in out {
        match r {
            Err(MpcdError::NonFinite { step, what, .. }) => {
                assert_eq!((step, what), (1, "solvent"));
            }
            other => panic!("expected a non-finite stop on every rank, got {other:?}"),
        }
    }
}

/// A drying droplet: the solvent inside a sphere of radius 5 shrinking at alpha = 4 (to 4.4 in
/// 60 collisions), no-slip walls (virtual particles in the cut cells), the excess removed
/// from the reflected particles every collision.
fn droplet_steps(srd: &mut Srd, steps: u64) -> u64 {
    use colloidsim_md::mpcd::WallKind;
    use colloidsim_md::mpcd::drying::remove_excess;
    use colloidsim_md::potential::SphereAreaLaw;
    let conf = Confinement::Sphere {
        law: SphereAreaLaw {
            r0: 5.0,
            alpha: 4.0,
        },
        kind: WallKind::NoSlip,
    };
    let tau = srd.params().tau;
    let (mut removed, mut scratch) = (0, Vec::new());
    for _ in 0..steps {
        let step = srd.step();
        let t = (step + 1) as f64 * tau;
        srd.stream(t, &conf, &Acceleration::None).unwrap();
        let expected = (srd.params().density * conf.volume(t, srd.sbox().l)).round() as usize;
        removed += remove_excess(srd, expected, step, &mut scratch).removed;
        srd.collide(t, &conf, None);
    }
    removed
}

fn droplet(seed: u32) -> Srd {
    use colloidsim_md::mpcd::WallKind;
    use colloidsim_md::potential::SphereAreaLaw;
    let conf = Confinement::Sphere {
        law: SphereAreaLaw {
            r0: 5.0,
            alpha: 4.0,
        },
        kind: WallKind::NoSlip,
    };
    Srd::new(SrdParams::standard(seed), SimBox::cube(12.0), &conf, 0.0).unwrap()
}

#[test]
fn a_drying_droplet_is_bitwise_the_same_on_any_number_of_ranks() {
    let mut one = droplet(6);
    let removed = droplet_steps(&mut one, 60);
    assert!(removed > 100, "the droplet must lose solvent: {removed}");
    let want = bits(&one.gathered_state());
    for ranks in [2, 3, 4] {
        let got = on_ranks(ranks, |comm| {
            let mut part = droplet(6).decomposed(comm).unwrap();
            let r = droplet_steps(&mut part, 60);
            (bits(&part.gathered_state()), r)
        });
        for (r, (g, n)) in got.iter().enumerate() {
            assert_eq!(*n, removed, "{ranks} ranks: rank {r} removed another count");
            assert!(*g == want, "{ranks} ranks: rank {r}'s droplet differs");
        }
    }
}

#[test]
fn more_ranks_than_layers_are_refused() {
    let out = on_ranks(13, |comm| solvent(1).decomposed(comm).err());
    for e in out {
        let msg = e
            .expect("13 ranks for 12 layers must be refused")
            .to_string();
        assert!(msg.contains("13 ranks for 12 layers"), "{msg}");
    }
}

/// Four colloids of diameter 3 (42 vertices each, joining the collisions) in a cube of 12
/// cells, driven along z so that they cross the domain faces: solvent and colloids.
fn with_colloids(seed: u32) -> colloidsim_md::mpcd::MpcdSystem {
    use colloidsim_md::mpcd::{ColloidParams, DiscreteColloids, MpcdSystem, Region};
    let p = SrdParams::standard(seed);
    let sbox = SimBox::cube(12.0);
    let srd = Srd::new(p, sbox, &Confinement::None, 0.0).unwrap();
    let c = DiscreteColloids::random(
        ColloidParams::standard(3.0, p.kt),
        sbox,
        4,
        Region::Box,
        p.kt,
        seed,
    )
    .unwrap();
    MpcdSystem::new(srd, c, Confinement::None, None).unwrap()
}

#[test]
fn colloids_replicated_on_every_rank_move_as_on_one_process() {
    let drive = Acceleration::Uniform([0.0, 0.0, 0.5]);
    let steps = 30;
    let mut one = with_colloids(4);
    for _ in 0..steps {
        one.step(&drive).unwrap();
    }
    let want = (
        bits(&one.srd.gathered_state()),
        one.colloids.state(),
        one.momentum().map(f64::to_bits),
    );
    for ranks in [2, 3] {
        let got = on_ranks(ranks, |comm| {
            let mut sys = with_colloids(4);
            sys.srd = sys.srd.decomposed(comm).unwrap();
            for _ in 0..steps {
                sys.step(&drive).unwrap();
            }
            (
                bits(&sys.srd.gathered_state()),
                sys.colloids.state(),
                sys.momentum().map(f64::to_bits),
            )
        });
        for (r, g) in got.iter().enumerate() {
            assert!(g.0 == want.0, "{ranks} ranks: rank {r}'s solvent differs");
            assert_eq!(g.1, want.1, "{ranks} ranks: rank {r}'s colloids differ");
            assert_eq!(g.2, want.2, "{ranks} ranks: rank {r}'s momentum differs");
        }
    }
}

#[test]
fn a_start_drawn_on_the_ranks_is_the_whole_start_decomposed() {
    use colloidsim_md::mpcd::WallKind;
    use colloidsim_md::potential::SphereAreaLaw;
    let conf = Confinement::Sphere {
        law: SphereAreaLaw {
            r0: 5.0,
            alpha: 4.0,
        },
        kind: WallKind::Slip,
    };
    let p = SrdParams::standard(12);
    let sbox = SimBox::new([12.0, 10.0, 12.0]);
    for (conf, n) in [(Confinement::None, 7200), (conf, 2618)] {
        let want = bits(&Srd::new(p, sbox, &conf, 0.0).unwrap().gathered_state());
        let got = on_ranks(3, |comm| {
            let part = Srd::new_decomposed(p, sbox, &conf, 0.0, comm).unwrap();
            (part.len(), bits(&part.gathered_state()), part.particles())
        });
        let held: usize = got.iter().map(|g| g.0).sum();
        assert_eq!(held, n, "each particle is held by one rank");
        for (len, state, total) in got {
            assert_eq!(total, n);
            assert!(len < n, "a rank holds only its share: {len} of {n}");
            assert!(state == want, "the drawn start differs from the whole one");
        }
    }
}
