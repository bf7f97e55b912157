//! What every `run` shares: options, output folders, progress bars, summaries.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Options of `colloidsim run` common to all methods.
pub struct RunOptions {
    /// Output folder.
    pub out: PathBuf,
    /// Seed overriding the scenario's.
    pub seed: Option<u64>,
    /// No progress bar.
    pub quiet: bool,
    /// Overwrite a non-empty output folder.
    pub force: bool,
    /// Continue from the checkpoint in this folder.
    pub restart: Option<PathBuf>,
}

/// Default output folder: the scenario's file stem plus `suffix`, in the current folder.
pub fn default_out(scenario: &Path, out: Option<PathBuf>, suffix: &str) -> PathBuf {
    out.unwrap_or_else(|| {
        let stem = scenario
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "colloidsim".into());
        PathBuf::from(format!("{stem}{suffix}"))
    })
}

/// A progress bar over `total` units that appears only on a terminal, only when not quiet, and
/// only once the run has lasted a second (short runs print nothing but their result).
pub fn progress(total: u64, quiet: bool, what: &str) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::with_draw_target(Some(total), indicatif::ProgressDrawTarget::hidden());
    pb.set_style(
        ProgressStyle::with_template(&format!(
            "{what} {{bar:40}} {{percent:>3}}% {{elapsed_precise}} eta {{eta}} {{msg}}"
        ))
        .expect("static template"),
    );
    pb.enable_steady_tick(Duration::from_millis(500));
    let reveal = pb.clone();
    std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(1));
        if !reveal.is_finished() {
            reveal.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
    });
    pb
}

/// Validate a seed from the scenario or the command line: the counter-based streams take 32 bits.
pub fn seed32(seed: u64) -> anyhow::Result<u32> {
    u32::try_from(seed)
        .map_err(|_| anyhow::anyhow!("seed: must lie in [0, 4294967295], got {seed}"))
}

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
    (v[v.len() / 2], v[0], v[v.len() - 1])
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
    p: &colloidsim_md::Particles,
    sbox: &colloidsim_md::SimBox,
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

/// Checkpoint format: bumped whenever a checkpoint's layout, or the random streams that a
/// continuation draws, change, so that a restart across such a change is refused instead of
/// silently continuing a different run. 2: the 1024-strip ziggurat (session 5); checkpoints
/// written before carry no format.
pub const CHECKPOINT_FORMAT: u32 = 2;

/// The version string that leads every checkpoint: the package version and the format.
pub fn checkpoint_version() -> String {
    format!(
        "{}+checkpoint{CHECKPOINT_FORMAT}",
        env!("CARGO_PKG_VERSION")
    )
}

/// Refuse checkpoint bytes that were written by another format, naming both versions (read
/// from the leading version string, before the rest is decoded).
pub fn check_checkpoint_version(bytes: &[u8], path: &Path) -> anyhow::Result<()> {
    let version: String = bincode::deserialize(bytes)
        .map_err(|e| anyhow::anyhow!("{}: unreadable checkpoint ({e})", path.display()))?;
    let ours = checkpoint_version();
    if version != ours {
        anyhow::bail!(
            "{}: written by colloidsim {version}, this build writes {ours}; the state layout or the random streams differ, so the run cannot be continued bitwise. Start it again, or continue it with the build that wrote it",
            path.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod checkpoint_tests {
    use super::*;

    #[test]
    fn checkpoints_of_another_format_are_refused_by_name() {
        let path = Path::new("run/checkpoint.bin");
        let ours = bincode::serialize(&(checkpoint_version(), 7u64, "rest")).unwrap();
        assert!(check_checkpoint_version(&ours, path).is_ok());
        let old = bincode::serialize(&("0.1.0".to_string(), 7u64, "rest")).unwrap();
        let e = check_checkpoint_version(&old, path)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("colloidsim 0.1.0") && e.contains(&checkpoint_version()),
            "{e}"
        );
        assert!(check_checkpoint_version(&[1, 2], path).is_err());
    }
}
