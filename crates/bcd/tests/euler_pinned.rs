//! Euler stays bit for bit what it was before the Leimkuhler–Matthews integrator was added: a
//! few positions of short runs of every update (ring, walls, chronological; hard and sticky)
//! pinned to the values the code of main at 4161e63 produced.

use colloidsim_bcd::engine::CHUNK;
use colloidsim_bcd::forces::{CosineForce, NoPair, PairForce, Sticky};
use colloidsim_bcd::{Bcd, BcdConfig, Boundary, Integrator, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};

fn cosine() -> CosineForce {
    CosineForce::from_field(&ExternalField {
        terms: vec![FieldTerm::Cosine {
            amplitude: 6.0,
            wavelength: 1.0,
        }],
        drive: 0.0,
    })
    .unwrap()
}

fn run<P: PairForce>(
    (boundary, update): (Boundary, Update),
    pair: P,
    (length, n): (f64, usize),
    steps: u64,
    integrator: Option<Integrator>,
) -> Vec<u64> {
    let cfg = BcdConfig {
        length,
        sigma: 0.5,
        mobility: 1.0,
        kt: 1.0,
        dt: 1e-3,
        boundary,
        seed: 5,
        update,
    };
    let x = init::random(&cfg, n, 5).unwrap();
    let mut b = Bcd::new(cfg, x, cosine(), pair).unwrap();
    if let Some(i) = integrator {
        b = b.with_integrator(i);
    }
    b.run(steps).unwrap();
    let x = b.positions();
    // FNV-1a over the bits of every position, then a few positions themselves.
    let hash = x.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
        (h ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3)
    });
    let mut pins = vec![hash];
    pins.extend([0, 1, n / 2, n - 1].map(|i| x[i].to_bits()));
    if n > CHUNK {
        pins.extend([CHUNK - 1, CHUNK].map(|i| x[i].to_bits()));
    }
    pins
}

/// The pins were printed by this file's `run` at main 4161e63, before the integrator choice
/// existed (Euler was the only scheme). They hold for the default integrator and for Euler
/// chosen explicitly; Leimkuhler–Matthews gives other positions.
#[test]
fn euler_runs_are_bitwise_those_of_main() {
    for integrator in [None, Some(Integrator::Euler)] {
        euler_pins(integrator);
    }
    let st = Sticky::new(1.0, 0.05, 3.0, 0.5, 1.0).unwrap();
    let lm = run(
        (Boundary::Periodic, Update::Premerge),
        st,
        (100.0, 80),
        2000,
        Some(Integrator::Lm),
    );
    assert_ne!(lm[0], 0x0771153c55c3882f, "LM gave Euler's positions");
}

fn euler_pins(integrator: Option<Integrator>) {
    let st = Sticky::new(1.0, 0.05, 3.0, 0.5, 1.0).unwrap();
    let ring = (Boundary::Periodic, Update::Premerge);
    let walls = (Boundary::Walls, Update::Premerge);
    let chrono = (Boundary::Periodic, Update::Chronological);
    let cases: [(&str, Vec<u64>, Vec<u64>); 7] = [
        (
            "ring",
            run(ring, NoPair, (100.0, 80), 2000, integrator),
            vec![
                0x92168eb747bfeae7,
                0x404144b48e91c617,
                0x40424c02deebba44,
                0x4056587d88e072b5,
                0x4060b4db036ead72,
            ],
        ),
        (
            "ring sticky",
            run(ring, st, (100.0, 80), 2000, integrator),
            vec![
                0x0771153c55c3882f,
                0x404144b48e91c617,
                0x4042cc02deebb9fa,
                0x405699027b71ef50,
                0x4060911410b6c5e7,
            ],
        ),
        (
            "walls",
            run(walls, NoPair, (100.0, 80), 2000, integrator),
            vec![
                0xfa61a171c2349d49,
                0x3ff89691d238c2ff,
                0x400cc02deebba42f,
                0x404c30fb11c0e56a,
                0x4058e9b606dd5ae4,
            ],
        ),
        (
            "walls sticky",
            run(walls, st, (100.0, 80), 2000, integrator),
            vec![
                0x5f13932f33a8a341,
                0x3ff89691d238c2ff,
                0x40126016f75dcfd3,
                0x404cb204f6e3dea2,
                0x4058e22817282630,
            ],
        ),
        (
            "chronological",
            run(chrono, NoPair, (100.0, 80), 500, integrator),
            vec![
                0x3225c964dc262d76,
                0x40414b65698b0c60,
                0x4042c5bec88770f8,
                0x40565921f0df217d,
                0x4060af30a4a2e7a1,
            ],
        ),
        (
            "ring, three chunks",
            run(ring, NoPair, (10000.0, 9000), 100, integrator),
            vec![
                0xbf833695c5424929,
                0x40bc937da1a56c8c,
                0x40bc9486f39f63ff,
                0x40c818c1d2f2d23f,
                0x40d0e8a6dc25d316,
                0x40c7333e2688db97,
                0x40c733b1be69570c,
            ],
        ),
        (
            "walls, three chunks",
            run(walls, NoPair, (10000.0, 9000), 100, integrator),
            vec![
                0x8a18d4b0f3142520,
                0x3fdf68affb5ae18b,
                0x4004364013965bae,
                0x40b39f0064a7e6fb,
                0x40c387cda0067e10,
                0x40b1d3df2e4e9367,
                0x40b1d46592a59605,
            ],
        ),
    ];
    for (name, got, want) in cases {
        assert_eq!(
            got, want,
            "{name}: hash of all positions, then positions 0, 1, N/2, N-1"
        );
    }
}
