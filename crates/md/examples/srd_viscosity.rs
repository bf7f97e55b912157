//! Development aid: the SRD viscosity from a periodic Poiseuille flow against Kikuchi's formula.
//! `srd_viscosity L STEPS G0 DENSITY ANGLE_DEG TAU` (defaults 16 6000 0.05 5 130 0.1).
use colloidsim_md::SimBox;
use colloidsim_md::mpcd::measure::poiseuille_viscosity;
use colloidsim_md::mpcd::{Confinement, Srd, SrdParams, theory};

fn main() {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("numbers"))
        .collect();
    let get = |i: usize, d: f64| a.get(i).copied().unwrap_or(d);
    let (l, steps, g0) = (get(0, 16.0), get(1, 6000.0) as u64, get(2, 0.05));
    let mut p = SrdParams::standard(7);
    p.density = get(3, 5.0);
    p.angle = get(4, 130.0).to_radians();
    p.tau = get(5, 0.1);
    let th = theory::viscosity(&p);
    let k = 2.0 * std::f64::consts::PI / l;
    let relax = p.density * p.mass / (th.total() * k * k) / p.tau;
    let mut srd = Srd::new(p, SimBox::cube(l), &Confinement::None, 0.0).unwrap();
    let r = poiseuille_viscosity(&mut srd, g0, (6.0 * relax).ceil() as u64, steps, 1, 10);
    println!(
        "L {l} M {} alpha {} tau {}: eta = {:.4} +- {:.4}; theory {:.4} (kin {:.4} col {:.4}); ratio {:.4} +- {:.4}; T = {:.4}, A = {:.4}",
        p.density,
        p.angle.to_degrees(),
        p.tau,
        r.eta,
        r.standard_error,
        th.total(),
        th.kinetic,
        th.collisional,
        r.eta / th.total(),
        r.standard_error / th.total(),
        r.temperature,
        r.flow_amplitude
    );
}
