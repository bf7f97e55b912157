//! Time-step error of free-draining BD in a static droplet, Euler against Leimkuhler–Matthews:
//! the fractions of particles in the contact layer (`r > R + offset - d/4`), in the first
//! layer (`r > R + offset - d`) and in the soft interface (`r > R + offset`), and the WCA
//! pair energy per particle, as functions of dt (docs/validation.md, *Time-step error of the
//! droplet BD*).
//!
//! `cargo run --release -p colloidsim-run --example droplet_dt_errors -- euler|lm R0 PHI TIME
//! REPLICAS MAX_DRIFT DT...` (dt in d^2/D0, TIME sampled per replica in d^2/D0 at the largest
//! dt and scaled as dt^(1/2) below it, so that small steps cost less; MAX_DRIFT the blow-up
//! guard in d, 0.2 in a scenario). Prints one CSV line per dt:
//! `integrator,dt,` then the fractions beyond `R + offset - d/4` (contact), `R + offset - d`
//! (layer) and `R + offset` (interface) and the WCA pair energy per particle, each with its
//! standard error, and the number of blocks.

#[path = "../tests/dt_error/mod.rs"]
mod dt_error;

use colloidsim_md::Integrator;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 7 {
        eprintln!("usage: droplet_dt_errors euler|lm R0 PHI TIME REPLICAS MAX_DRIFT DT...");
        std::process::exit(2);
    }
    let integrator = match args[0].as_str() {
        "euler" => Integrator::Euler,
        "lm" => Integrator::Lm,
        o => panic!("integrator {o}: euler or lm"),
    };
    let num = |s: &str| s.parse::<f64>().unwrap();
    let (r0, phi, time) = (num(&args[1]), num(&args[2]), num(&args[3]));
    let replicas: u32 = args[4].parse().unwrap();
    let max_drift = num(&args[5]);
    let dts: Vec<f64> = args[6..].iter().map(|s| num(s)).collect();
    let dt_max = dts.iter().cloned().fold(0.0, f64::max);
    let p = dt_error::static_droplet(r0, phi, 1.0);
    eprintln!(
        "N = {}, R0 = {r0}, phi = {phi}, cuts {:?}",
        p.particles,
        dt_error::cuts(&p)
    );
    println!(
        "integrator,dt,f_contact,se_contact,f_layer,se_layer,f_interface,se_interface,u_pair,se_u_pair,blocks"
    );
    for dt in dts {
        let t = time * (dt / dt_max).sqrt();
        let l = dt_error::layer_fractions(
            &p,
            integrator,
            dt,
            0..replicas,
            4.0,
            t,
            t / 10.0,
            20,
            max_drift,
        );
        let cols: Vec<String> = (0..dt_error::OBSERVABLES)
            .map(|k| format!("{:.6},{:.6}", l.mean[k], l.se[k]))
            .collect();
        println!("{},{dt:e},{},{}", args[0], cols.join(","), l.blocks);
    }
}
