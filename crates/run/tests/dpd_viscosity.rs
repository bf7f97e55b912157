//! Green–Kubo viscosity of the DPD solvent (issue 19): the standard DPD fluid of Groot & Warren
//! (a = 25 kT/rc, gamma = 4.5, density 3, kT = 1, rc = 1) against the kinetic theory of Marsh,
//! Backx & Ernst and against the long run recorded in docs/reports/dpd-validation.md.

use colloidsim_md::dpd::setup::DpdSetup;
use colloidsim_md::dpd::viscosity::Estimate;
use colloidsim_md::dpd::{Dpd, StressAcf};
use colloidsim_run::methods::dpd::params;
use std::f64::consts::PI;

fn scenario(text: &str) -> DpdSetup {
    params::setup(text).unwrap()
}

/// The DPD solvent with the engine's defaults (repulsion 25 kT/rc, gamma = 4.5, density 3,
/// rc = 1, m = 1) at temperature `kt` in a cube of side `l`: `kt = 1` is the standard fluid of
/// Groot & Warren, `kt = 0.1` the notes' colloid solvent.
fn fluid(l: f64, kt: f64, dt: f64, seed: u64) -> Dpd {
    scenario(&format!(
        "method = \"dpd\"\nseed = {seed}\n[system]\nbox_length = {l}\nkT = {kt}\n[run]\ndt = {dt}\n"
    ))
    .build()
    .unwrap()
}

/// Marsh, Backx & Ernst (1997) for `w_D = (1 - r)^2`, m = rc = kT = 1: the kinetic part
/// `45 / (4 pi gamma)` and the dissipative part `2 pi gamma rho^2 / 1575`.
fn marsh(gamma: f64, rho: f64) -> (f64, f64) {
    (
        45.0 / (4.0 * PI * gamma),
        2.0 * PI * gamma * rho * rho / 1575.0,
    )
}

/// Run `skip` steps, then `steps` steps feeding every pressure tensor to one correlator per
/// `(every, t_max)`: samples of `every` steps, lags up to `t_max`.
fn green_kubo(sim: &mut Dpd, skip: u64, steps: u64, cfg: &[(u64, f64)]) -> Vec<Estimate> {
    sim.run(skip).unwrap();
    let dt = sim.params().dt;
    let mut accs: Vec<StressAcf> = cfg
        .iter()
        .map(|&(every, t_max)| {
            let lags = (t_max / (every as f64 * dt)).round() as usize + 1;
            StressAcf::new(every, lags, dt, sim.sbox.volume(), sim.params().kt)
        })
        .collect();
    for _ in 0..steps {
        let p = sim.advance_with_pressure().unwrap();
        for a in &mut accs {
            a.push(&p);
        }
    }
    accs.iter()
        .map(|a| {
            let v = a.viscosity();
            v.all.unwrap_or_else(|| panic!("{}", v.note))
        })
        .collect()
}

#[test]
fn marsh_numbers_for_the_standard_fluid() {
    // gamma = 4.5, rho = 3: 0.79577 + 0.16157 = 0.95735 (docs/references.md).
    let (k, d) = marsh(4.5, 3.0);
    assert!((k - 0.795_774_7).abs() < 1e-6, "{k}");
    assert!((d - 0.161_567_6).abs() < 1e-6, "{d}");
}

#[test]
fn the_pressure_step_changes_nothing_and_gives_the_thermo_pressure() {
    // Accumulating the virial does not change the dynamics: the same run with plain steps,
    // pressure steps and thermo steps ends bitwise in the same state, and the pressure tensor
    // equals the one of Thermo.
    let mut a = fluid(6.0, 1.0, 0.02, 7);
    let mut b = fluid(6.0, 1.0, 0.02, 7);
    let mut c = fluid(6.0, 1.0, 0.02, 7);
    for _ in 0..50 {
        a.advance().unwrap();
        let p = b.advance_with_pressure().unwrap();
        let th = c.advance_with_thermo().unwrap();
        for k in 0..6 {
            assert!(
                (p[k] - th.pressure[k]).abs() <= 1e-12 * th.pressure[0].abs(),
                "component {k}: {} vs {}",
                p[k],
                th.pressure[k]
            );
        }
    }
    assert!(a.snapshot() == b.snapshot() && b.snapshot() == c.snapshot());
}

/// The long runs recorded in docs/reports/dpd-validation.md
/// (`long_green_kubo_viscosity_of_the_solvent`):
/// viscosity and block standard error at kT = 1 (t_max = 1) and kT = 0.1 (t_max = 2).
const LONG_KT1: (f64, f64) = (0.8013, 0.0095);
const LONG_KT01: (f64, f64) = (0.3203, 0.0063);

/// `|x - y| < 4 sqrt(ex^2 + ey^2)`.
fn agree(x: Estimate, y: (f64, f64)) -> bool {
    (x.value - y.0).abs() < 4.0 * (x.error.powi(2) + y.1.powi(2)).sqrt()
}

#[test]
fn green_kubo_viscosity_of_the_standard_fluid() {
    // Groot & Warren's fluid (kT = 1), 1536 beads, 400 DPD times. The same pressure tensors go
    // to samples of 1 step and of 10 steps: by the Einstein–Helfand argument (module
    // viscosity) both give the same integral, while sampling single steps every 10 would count
    // the random stress ten times (+ 9 eta_D = +1.45).
    let e = green_kubo(
        &mut fluid(8.0, 1.0, 0.01, 21),
        300,
        40_000,
        &[(1, 1.0), (10, 1.0)],
    );
    let (k, d) = marsh(4.5, 3.0);
    eprintln!(
        "kT = 1: eta = {:.4} +- {:.4} (samples of 1 step), {:.4} +- {:.4} (10 steps); long run {:?}; Marsh {:.4}",
        e[0].value,
        e[0].error,
        e[1].value,
        e[1].error,
        LONG_KT1,
        k + d
    );
    assert!(e[0].error < 0.06 * e[0].value, "error {:?}", e[0]);
    assert!((e[0].value - e[1].value).abs() < 0.5 * e[0].error, "{e:?}");
    assert!(
        agree(e[0], LONG_KT1),
        "{:?} vs the long run {LONG_KT1:?}",
        e[0]
    );
    // Marsh's kinetic theory neglects the conservative force: 0.957 is 15-20 % above the
    // measured value (docs/reports/dpd-validation.md); more than 35 % off would be a different
    // fluid.
    assert!((e[0].value / (k + d) - 1.0).abs() < 0.35, "{:?}", e[0]);
}

#[test]
fn green_kubo_viscosity_of_the_notes_solvent() {
    // The notes' colloid solvent (kT = 0.1, gamma = 4.5): "eta0 = 0.3" (one digit). 1536
    // beads, 400 DPD times, samples of 5 steps, t_max = 2.
    let e = green_kubo(&mut fluid(8.0, 0.1, 0.01, 22), 300, 40_000, &[(5, 2.0)])[0];
    let (k, d) = marsh(4.5, 3.0);
    eprintln!(
        "kT = 0.1: eta = {:.4} +- {:.4}; long run {:?}; notes 0.3; Marsh {:.4}",
        e.value,
        e.error,
        LONG_KT01,
        0.1 * k + d
    );
    assert!(e.error < 0.08 * e.value, "error {e:?}");
    assert!(agree(e, LONG_KT01), "{e:?} vs the long run {LONG_KT01:?}");
    assert!(
        (e.value - 0.3).abs() < 0.05 + 4.0 * e.error,
        "{e:?} vs the notes' 0.3"
    );
}

#[test]
#[ignore = "long validation (~10 min on 2 cores); results in docs/reports/dpd-validation.md"]
fn long_green_kubo_viscosity_of_the_solvent() {
    // Ten times the CI runs, other seeds.
    let a = green_kubo(
        &mut fluid(8.0, 1.0, 0.01, 31),
        300,
        400_000,
        &[(1, 1.0), (5, 2.0)],
    );
    let b = green_kubo(
        &mut fluid(8.0, 0.1, 0.01, 32),
        300,
        400_000,
        &[(5, 2.0), (5, 4.0)],
    );
    eprintln!(
        "kT = 1: {:.4} +- {:.4} (t_max 1), {:.4} +- {:.4} (t_max 2); kT = 0.1: {:.4} +- {:.4} (t_max 2), {:.4} +- {:.4} (t_max 4)",
        a[0].value,
        a[0].error,
        a[1].value,
        a[1].error,
        b[0].value,
        b[0].error,
        b[1].value,
        b[1].error
    );
    // The runs are deterministic (fixed seeds; bitwise for any number of threads): the numbers
    // recorded above and in docs/reports/dpd-validation.md come back to their last digit.
    for (x, y) in [(a[0], LONG_KT1), (b[0], LONG_KT01)] {
        assert!(
            (x.value - y.0).abs() < 1e-4 && (x.error - y.1).abs() < 1e-4,
            "{x:?} vs {y:?}"
        );
    }
}
