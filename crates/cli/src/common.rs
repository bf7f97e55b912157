//! What the benchmarks share: CPU time, load, medians, and LAMMPS input and output.

use std::path::Path;

/// CPU time (user + system, all threads) of this process in seconds, from /proc (Linux; `None`
/// elsewhere). For benchmarks: a rate per CPU second is less sensitive to other work on the
/// machine than one per wall second.
pub fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// The 1-, 5- and 15-minute load averages, from /proc/loadavg (Linux; `None` elsewhere).
pub fn load_average() -> Option<[f64; 3]> {
    let s = std::fs::read_to_string("/proc/loadavg").ok()?;
    let mut w = s.split_whitespace().map(|x| x.parse::<f64>().ok());
    Some([w.next()??, w.next()??, w.next()??])
}

/// Median, min and max of `v` (not empty).
pub fn median(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    // An even count: the mean of the two middle values.
    let m = if n.is_multiple_of(2) {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    } else {
        v[n / 2]
    };
    (m, v[0], v[n - 1])
}

/// The timed loop of a LAMMPS screen output: the last "Loop time of T on P procs for S steps
/// with N atoms" line and the "X% CPU use ..." line after it.
pub struct LammpsLoop {
    /// Wall seconds of the loop.
    pub secs: f64,
    /// Steps of the loop.
    pub steps: f64,
    /// CPU use in percent of wall time (NaN when not printed).
    pub cpu_percent: f64,
    /// Index of the "Loop time" line.
    pub line: usize,
}

/// Parse the timed loop of a LAMMPS screen output.
pub fn lammps_loop_time(text: &str) -> anyhow::Result<LammpsLoop> {
    use anyhow::Context;
    let lines: Vec<&str> = text.lines().collect();
    let at = lines
        .iter()
        .rposition(|l| l.starts_with("Loop time of"))
        .context("LAMMPS printed no loop time")?;
    let w: Vec<&str> = lines[at].split_whitespace().collect();
    let secs: f64 = w.get(3).context("loop time line")?.parse()?;
    let steps: f64 = w.get(8).context("loop time line")?.parse()?;
    let cpu_percent = lines[at..]
        .iter()
        .find_map(|l| {
            l.split_once("% CPU use")
                .and_then(|(p, _)| p.trim().parse::<f64>().ok())
        })
        .unwrap_or(f64::NAN);
    Ok(LammpsLoop {
        secs,
        steps,
        cpu_percent,
        line: at,
    })
}

/// A LAMMPS data file (`atom_style atomic`, one atom type of mass 1) of `p` in input order
/// (LAMMPS id = index + 1), box centred on the origin like colloidsim's; with `velocities`, a
/// Velocities section too. Positions are written with `f64`'s shortest exact representation.
pub fn write_lammps_data(
    path: &Path,
    title: &str,
    p: &colloidsim_particles::Particles,
    sbox: &colloidsim_particles::SimBox,
    velocities: bool,
) -> anyhow::Result<()> {
    use anyhow::Context;
    use std::fmt::Write as _;
    let l = sbox.l;
    let mut s = String::with_capacity(p.len() * 120);
    writeln!(
        s,
        "{title}\n\n{} atoms\n1 atom types\n\n{} {} xlo xhi\n{} {} ylo yhi\n{} {} zlo zhi\n\nMasses\n\n1 1.0\n\nAtoms # atomic\n",
        p.len(),
        -0.5 * l[0],
        0.5 * l[0],
        -0.5 * l[1],
        0.5 * l[1],
        -0.5 * l[2],
        0.5 * l[2]
    )?;
    for (i, x) in p.pos.iter().enumerate() {
        writeln!(s, "{} 1 {} {} {}", i + 1, x[0], x[1], x[2])?;
    }
    if velocities {
        writeln!(s, "\nVelocities\n")?;
        for (i, v) in p.vel.iter().enumerate() {
            writeln!(s, "{} {} {} {}", i + 1, v[0], v[1], v[2])?;
        }
    }
    std::fs::write(path, s).with_context(|| format!("{}", path.display()))
}

#[cfg(test)]
mod median_tests {
    #[test]
    fn the_median_of_an_even_count_is_the_mean_of_the_middle_two() {
        assert_eq!(super::median(vec![3.0, 1.0, 2.0]), (2.0, 1.0, 3.0));
        assert_eq!(super::median(vec![4.0, 1.0, 3.0, 2.0]), (2.5, 1.0, 4.0));
        assert_eq!(super::median(vec![5.0]), (5.0, 5.0, 5.0));
    }
}
