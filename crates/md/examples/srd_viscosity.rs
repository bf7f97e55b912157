//! Development aid: SRD viscosity from a periodic Poiseuille flow against Kikuchi's formula.
//! `srd_viscosity L STEPS G0 DENSITY ANGLE_DEG TAU [thermostat 0/1]`
use colloidsim_md::SimBox;
use colloidsim_md::mpcd::measure::PoiseuilleProbe;
use colloidsim_md::mpcd::{Acceleration, Confinement, Srd, SrdParams, theory};

fn main() {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    let get = |i: usize, d: f64| a.get(i).copied().unwrap_or(d);
    let (l, steps, g0) = (get(0, 16.0), get(1, 6000.0) as u64, get(2, 0.05));
    let mut p = SrdParams::standard(7);
    p.density = get(3, 5.0);
    p.angle = get(4, 130.0).to_radians();
    p.tau = get(5, 0.1);
    p.thermostat = get(6, 1.0) == 1.0;
    let global = get(6, 1.0) == 2.0;
    let th = theory::viscosity(&p);
    let k = 2.0 * std::f64::consts::PI / l;
    let rho = p.density * p.mass;
    let relax = rho / (th.total() * k * k);
    let equil = ((5.0 * relax / p.tau).ceil() as u64).min(steps / 2);
    let mut srd = Srd::new(p, SimBox::cube(l), &Confinement::None, 0.0).unwrap();
    let acc = Acceleration::CosineX {
        amplitude: g0,
        wavenumber: k,
    };
    let mut probe = PoiseuilleProbe::new(g0, k, rho, ((steps - equil) / 20).max(1));
    for s in 0..steps {
        let t = (s + 1) as f64 * p.tau;
        srd.stream(t, &Confinement::None, &acc).unwrap();
        srd.collide(t, &Confinement::None, None);
        if global {
            let amp = PoiseuilleProbe::amplitude_of(&srd, k);
            srd.rescale_about(|x| [amp * (k * x[2]).cos(), 0.0, 0.0]);
        }
        if s >= equil {
            probe.sample(&srd);
        }
    }
    let (eta, se) = probe.viscosity();
    println!(
        "L {l} M {} alpha {} tau {} thermostat {}: eta = {eta:.4} +- {se:.4}; theory {:.4} (kin {:.4} col {:.4}); ratio {:.4} +- {:.4}; T = {:.4}, A = {:.4}",
        p.density,
        p.angle.to_degrees(),
        p.tau,
        p.thermostat,
        th.total(),
        th.kinetic,
        th.collisional,
        eta / th.total(),
        se / th.total(),
        srd.temperature(),
        probe.flow.mean()
    );
}
