//! Quick timing of the SRD solvent (development aid; the benchmark is `colloidsim bench mpcd`).
use colloidsim_md::SimBox;
use colloidsim_md::mpcd::{Acceleration, Confinement, Srd, SrdParams};
use std::time::Instant;

fn main() {
    let l: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(60.0);
    let steps: u64 = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(50);
    let mut p = SrdParams::standard(1);
    p.thermostat = std::env::var("NOTHERMO").is_err();
    let mut srd = Srd::new(p, SimBox::cube(l), &Confinement::None, 0.0).unwrap();
    let n = srd.len();
    let conf = Confinement::None;
    if let Ok(k) = std::env::var("SORT") {
        srd.set_sort_every(k.parse().unwrap());
    }
    for _ in 0..5 {
        let t = (srd.step() + 1) as f64 * 0.1;
        srd.stream(t, &conf, &Acceleration::None).unwrap();
        srd.collide(t, &conf, None);
    }
    srd.timers = [0.0; 4];
    let t0 = Instant::now();
    let (mut ts, mut tc) = (0.0, 0.0);
    for _ in 0..steps {
        let t = (srd.step() + 1) as f64 * 0.1;
        let a = Instant::now();
        srd.stream(t, &conf, &Acceleration::None).unwrap();
        ts += a.elapsed().as_secs_f64();
        let a = Instant::now();
        srd.collide(t, &conf, None);
        tc += a.elapsed().as_secs_f64();
    }
    let secs = t0.elapsed().as_secs_f64();
    let per = |x: f64| x / (n as f64 * steps as f64) * 1e9;
    println!(
        "bin {:.1} ns, sort {:.1} ns, cells {:.1} ns",
        per(srd.timers[1]),
        per(srd.timers[2]),
        per(srd.timers[3])
    );
    println!(
        "N = {n}, {steps} steps in {secs:.3} s: {:.3e} particle-steps/s (stream {:.1} ns, collide {:.1} ns per particle); T = {:.4}",
        n as f64 * steps as f64 / secs,
        ts / (n as f64 * steps as f64) * 1e9,
        tc / (n as f64 * steps as f64) * 1e9,
        srd.temperature()
    );
}
