//! Speed and memory of the bulk SRD solvent (a development benchmark, not a test):
//! `srd_speed [L] [STEPS]` (defaults 60 and 50) streams and collides the standard solvent
//! (density 5, 130 degrees, tau 0.1, cell thermostat; `NOTHERMO=1` turns the thermostat off,
//! `SORT=k` sets the storage-sort period) in a periodic cube of `L` cells after 5 warm-up
//! steps, on `RAYON_NUM_THREADS` threads, and prints particle-updates per second, the time
//! per particle of each part of a step, the CPU time of the timed steps (per CPU-second, and
//! as a percentage of the wall time: 200 % is two busy threads), and the resident memory (VmRSS after the run, and
//! VmHWM, the peak, which includes the start-up arrays). Build with `--release`.
use colloidsim_md::SimBox;
use colloidsim_md::mpcd::{Acceleration, Confinement, Srd, SrdParams};
use std::time::Instant;

/// A line of /proc/self/status in bytes (kB there), or NaN off Linux.
fn status_bytes(key: &str) -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|v| v.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb * 1024.0)
}

/// CPU seconds used so far by this process (user + system, from /proc/self/stat), or NaN.
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // Fields after the command name (which is in parentheses): utime is the 12th, stime
            // the 13th, in clock ticks of 1/100 s.
            let rest = s.rsplit_once(')')?.1;
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some((f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?) / 100.0)
        })
        .unwrap_or(f64::NAN)
}

fn main() {
    let mut args = std::env::args().skip(1);
    let l: f64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(60.0);
    let steps: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(50);
    let mut p = SrdParams::standard(1);
    p.thermostat = std::env::var("NOTHERMO").is_err();
    let conf = Confinement::None;
    let mut srd = Srd::new(p, SimBox::cube(l), &conf, 0.0).expect("valid solvent");
    if let Some(k) = std::env::var("SORT").ok().and_then(|s| s.parse().ok()) {
        srd.set_sort_every(k);
    }
    let n = srd.len();
    let step = |srd: &mut Srd| {
        let t = (srd.step() + 1) as f64 * p.tau;
        srd.stream(t, &conf, &Acceleration::None).expect("finite");
        srd.collide(t, &conf, None);
    };
    for _ in 0..5 {
        step(&mut srd);
    }
    srd.timers = [0.0; 4];
    let (t0, c0) = (Instant::now(), cpu_seconds());
    for _ in 0..steps {
        step(&mut srd);
    }
    let secs = t0.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - c0;
    let updates = n as f64 * steps as f64;
    let ns = |x: f64| x / updates * 1e9;
    println!(
        "threads {} N {n} steps {steps} thermostat {}: {:.4e} particle-updates/s ({:.4e} per CPU-second, CPU use {:.0} %); per particle: stream {:.1} ns, bin {:.1} ns, sort {:.1} ns, cells {:.1} ns; T = {:.4}",
        rayon::current_num_threads(),
        p.thermostat,
        updates / secs,
        updates / cpu,
        100.0 * cpu / secs,
        ns(srd.timers[0]),
        ns(srd.timers[1]),
        ns(srd.timers[2]),
        ns(srd.timers[3]),
        srd.temperature()
    );
    println!(
        "memory: VmRSS {:.1} MB = {:.1} B per particle, VmHWM {:.1} MB; arrays {} B per particle + {} B per cell",
        status_bytes("VmRSS:") / 1e6,
        status_bytes("VmRSS:") / n as f64,
        status_bytes("VmHWM:") / 1e6,
        Srd::bytes_per_particle(),
        Srd::bytes_per_cell()
    );
}
