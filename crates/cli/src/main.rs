//! `colloidsim`: run a scenario, compute its theory, check it, list its keys, or benchmark an
//! engine. Argument parsing, a progress bar, signals (Ctrl-C, SIGTERM, SIGUSR1), the wall-time
//! budget and the exit statuses; the run path is `colloidsim-run`.

mod bench_bcd;
mod bench_bd;
mod bench_dpd_ranks;
mod bench_mc;
mod bench_mpcd;
mod common;
mod dpd_bench;
mod parallel;
mod rpy_bench;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use colloidsim_run::ensemble::{Ensemble, MemberState, parse_vary};
use colloidsim_run::{Control, Progress, RunOptions, Scenario, Stop, TheoryOptions};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The methods and where they are documented, for `--help`.
fn methods_help() -> String {
    let mut s = String::from("Methods (the `method` key of a scenario):\n");
    for m in colloidsim_run::registry::all() {
        s.push_str(&format!(
            "  {:<28} {}\n  {:<28} keys: colloidsim keys {}; docs: {}\n",
            m.names().join(", "),
            m.about(),
            "",
            m.names()[0],
            m.docs()
        ));
    }
    s.push_str(
        "\nExamples: examples/*/*.toml (each says what it shows). Every scenario key has a unit, a\n\
         default and an allowed range (colloidsim keys METHOD); unknown keys are errors.",
    );
    s
}

#[derive(Parser)]
#[command(
    name = "colloidsim",
    version,
    about = "Simulations of colloidal suspensions: Brownian cluster dynamics of rods beside the exact 1D theory, drying droplets of hard spheres beside their DDFT, DPD colloids",
    after_help = methods_help()
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// `--set key.path=value`, repeatable: override a scenario key (same validation as in the file).
#[derive(clap::Args, Clone)]
struct Overrides {
    /// Override a scenario key, e.g. `--set run.dt=1e-4 --set system.boundary=walls`
    /// (repeatable; values are TOML).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

#[derive(Subcommand)]
enum Command {
    /// Run the simulation a scenario file describes and write its outputs.
    Run {
        /// Scenario file (TOML); with --restart it may be left out (the run's own is used).
        #[arg(required_unless_present = "restart")]
        scenario: Option<PathBuf>,
        /// Output folder (default: the scenario's file name without extension).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override the scenario's seed (0 ..= 4294967295).
        #[arg(long)]
        seed: Option<u64>,
        /// Worker threads (default: all cores; at most 8 per core and 4096).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bar, no informational messages, no closing line (warnings and errors
        /// are still printed, on stderr).
        #[arg(long)]
        quiet: bool,
        /// Write into an output folder that already holds files (the files of an earlier run
        /// are removed and listed; other files are kept and listed).
        #[arg(long)]
        force: bool,
        /// Continue an interrupted run from the checkpoint in this output folder.
        #[arg(long, conflicts_with_all = ["out", "force"])]
        restart: Option<PathBuf>,
        /// Wall-time budget, HH:MM:SS (or D-HH:MM:SS, or seconds), counted from the program's
        /// start: the run stops at the last checkpoint that fits, with a safety margin, and
        /// exits with status 83 (docs/cluster.md).
        #[arg(long, value_name = "HH:MM:SS", value_parser = parse_walltime)]
        walltime: Option<WallTime>,
        #[command(flatten)]
        overrides: Overrides,
    },
    /// Compute the continuum (theory) counterpart of a scenario on the same grid and file names.
    Theory {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Output folder (default: the scenario's name followed by `-theory`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Grid spacing of the theory (default: fine enough for the scenario).
        #[arg(long)]
        dx: Option<f64>,
        /// Write into an output folder that already holds files.
        #[arg(long)]
        force: bool,
        /// Droplet DDFT only: `free-draining` (default, like the BD run) or `rpy` (adds the
        /// pairwise RPY flux with the dilute pair correlation; stops if the solution turns
        /// unphysical).
        #[arg(long)]
        hydrodynamics: Option<String>,
        /// Droplet DDFT with `--hydrodynamics rpy` only: the pair correlation in the flux's
        /// two-body density, `dilute` (default, `g = Theta(r - d)`), `trokhymchuk`
        /// (Trokhymchuk et al. 2005 at the mean local packing fraction; for a mixture scaled to
        /// each pair's BMCSL contact value) or `trokhymchuk-n3` (at the weighted `n3`).
        #[arg(long)]
        pair: Option<String>,
        #[command(flatten)]
        overrides: Overrides,
    },
    /// Analyse any GSD trajectory (HOOMD-blue's, LAMMPS' dump gsd, colloidsim's): g(r) with
    /// its standard error over frames, S(q), MSD, contacts, coordination, clusters and radial
    /// profiles, written as a run writes them (docs/analyse.md).
    #[command(visible_alias = "analyze")]
    Analyse {
        /// GSD trajectory (HOOMD schema; orthorhombic 3D boxes).
        trajectory: PathBuf,
        /// Output folder (default: the trajectory's name followed by `-analysis`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write into an output folder that already holds files.
        #[arg(long)]
        force: bool,
        /// Particle types analysed, by name, comma-separated (default: all).
        #[arg(long, value_delimiter = ',')]
        types: Option<Vec<String>>,
        /// Frames FIRST:LAST:STRIDE, counted from 0, each optional (default: all).
        #[arg(long, default_value = "::1")]
        frames: colloidsim_run::analyse::Frames,
        /// Range of g(r), in the trajectory's length unit (default: 0.49 of the shortest box
        /// edge; at most half of it).
        #[arg(long)]
        r_max: Option<f64>,
        /// Bins of g(r) (default 200; 1 to 100000).
        #[arg(long)]
        bins: Option<usize>,
        /// Two spheres touch when their surface gap is below this (default 0.1 mean diameters).
        #[arg(long, allow_negative_numbers = true)]
        contact_gap: Option<f64>,
        /// Centre of the radial profiles: origin (the box centre), com (each frame's centre of
        /// mass) or x,y,z (default: origin).
        #[arg(long, allow_hyphen_values = true)]
        centre: Option<colloidsim_run::analyse::Centre>,
        /// Bins of the radial profiles, out to half the shortest box edge (default 50).
        #[arg(long)]
        profile_bins: Option<usize>,
        /// Time per step: msd.csv gets a time column (default: lags in steps only).
        #[arg(long)]
        dt: Option<f64>,
        /// Hard spheres of one diameter: write and draw the Percus-Yevick g(r) at the
        /// trajectory's volume fraction beside the measured one.
        #[arg(long)]
        percus_yevick: bool,
        /// Worker threads (default: all cores; at most 8 per core and 4096).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Draw particles from a run's trajectory.gsd (or any GSD file): a snapshot (spheres in
    /// perspective, shaded; rods on a line as a space-time picture) or an animated GIF
    /// (docs/render.md).
    Render {
        /// A run's output folder (its trajectory.gsd) or a GSD file.
        input: PathBuf,
        /// Picture file (default: snapshot.png, or movie.gif with --animate, beside the
        /// trajectory).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replace an existing picture.
        #[arg(long)]
        force: bool,
        /// The snapshot's frame, counted from 0 (default: the last; rods: every frame).
        #[arg(long)]
        frame: Option<u64>,
        /// An animated GIF of --frames instead of one snapshot.
        #[arg(long)]
        animate: bool,
        /// Frames FIRST:LAST:STRIDE of an animation or a rods' space-time picture (default:
        /// all, thinned evenly to 400).
        #[arg(long, default_value = "::1")]
        frames: colloidsim_run::analyse::Frames,
        /// What colours the spheres: type, distance (from the centre) or diameter.
        #[arg(long, default_value = "type")]
        colour: colloidsim_run::render::Colour,
        /// Leave out the half of the spheres facing the camera (the inside of a droplet).
        #[arg(long)]
        cut: bool,
        /// Picture width in pixels (200 to 4000).
        #[arg(long, default_value_t = 800)]
        width: u32,
        /// Animation frames per second (1 to 50).
        #[arg(long, default_value_t = 10)]
        fps: u32,
    },
    /// Run a scenario at its time step and at half of it (several seeds each) and write its
    /// tables extrapolated to dt -> 0 with their errors (Richardson).
    Extrapolate {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Output folder (default: the scenario's name followed by `-extrapolated`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Seeds per time step (at least 2; the errors come from their spread).
        #[arg(long, default_value_t = 4)]
        seeds: u32,
        /// Order p of the time-step bias, A(dt) = A(0) + c dt^p: 1 for Euler's bias of
        /// averages, 2 for Leimkuhler-Matthews' force bias, 0.5 for contact densities (0.25 to 4).
        #[arg(long, default_value_t = 1.0)]
        order: f64,
        /// Write into an output folder that already holds files.
        #[arg(long)]
        force: bool,
        /// Worker threads (default: all cores; at most 8 per core and 4096).
        #[arg(long)]
        threads: Option<usize>,
        #[command(flatten)]
        overrides: Overrides,
    },
    /// Run replicas of a scenario (seeds seed, seed + 1, ...) and sweeps of its keys, each
    /// member in its own folder, and write their averages with errors; spreads the members over
    /// MPI ranks under `mpirun` (built with `--features mpi`).
    Ensemble {
        /// Scenario file (TOML); not with --restart or --collect.
        #[arg(required_unless_present_any = ["restart", "collect"])]
        scenario: Option<PathBuf>,
        /// Output folder (default: the scenario's name followed by `-ensemble`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replicas per sweep point (1 ..= 10000; the errors come from their spread).
        #[arg(long, default_value_t = 4)]
        replicas: u32,
        /// Sweep a key over a TOML array of values, e.g. `--vary system.phi=[0.1,0.2]`
        /// (repeatable: the points are all combinations).
        #[arg(long, value_name = "KEY=[V1,V2,...]")]
        vary: Vec<String>,
        /// Worker threads per rank (default: the node's cores shared among its ranks; at most 8
        /// per core and 4096).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bar, no informational messages, no closing line.
        #[arg(long)]
        quiet: bool,
        /// Write into an output folder that already holds files.
        #[arg(long)]
        force: bool,
        /// Continue the interrupted ensemble in this folder (on any number of ranks): completed
        /// members are kept, interrupted ones continue from their checkpoints.
        #[arg(long, conflicts_with_all = ["scenario", "out", "force", "vary", "replicas"])]
        restart: Option<PathBuf>,
        /// Run only member K (0-based; the folder and seed a whole ensemble gives it), e.g.
        /// one job of a job array; the ensemble's folder and plan are created by the first
        /// member to start, checked by the others. Then `--collect DIR` averages.
        #[arg(long, value_name = "K", conflicts_with = "force")]
        member: Option<usize>,
        /// Average the members of the ensemble in this folder that were run with --member, as
        /// a whole ensemble run does; refused while members are unfinished.
        #[arg(long, value_name = "DIR", conflicts_with_all = [
            "scenario", "out", "force", "vary", "replicas", "restart", "member", "walltime",
            "threads", "set",
        ])]
        collect: Option<PathBuf>,
        /// With --collect: average the members that finished, leaving out (and naming in
        /// summary.json) those that did not.
        #[arg(long, requires = "collect")]
        finished_only: bool,
        /// Wall-time budget, as for `colloidsim run --walltime` (for all the members run).
        #[arg(long, value_name = "HH:MM:SS", value_parser = parse_walltime)]
        walltime: Option<WallTime>,
        #[command(flatten)]
        overrides: Overrides,
    },
    /// Validate a scenario and print its keys with their values and units (defaults marked).
    Check {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Print instead the resolved parameters as JSON (summary.json's `parameters`).
        #[arg(long)]
        json: bool,
        /// Skip the estimate of run time and memory (which starts the run and times its first
        /// steps for about half a second).
        #[arg(long)]
        no_estimate: bool,
        /// Worker threads the estimate is measured with (default: all cores, as a run).
        #[arg(long)]
        threads: Option<usize>,
        #[command(flatten)]
        overrides: Overrides,
    },
    /// List every scenario key of a method with its unit, default and allowed range.
    Keys {
        /// Method (bcd, droplet-bd, dpd, ...).
        method: String,
        /// Output format.
        #[arg(long, value_enum, default_value_t = KeyFormat::Text)]
        format: KeyFormat,
    },
    /// Benchmark an engine and print a table.
    Bench {
        /// Which benchmark.
        #[command(subcommand)]
        which: BenchKind,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum KeyFormat {
    /// Aligned columns.
    Text,
    /// The reference page of docs/keys/METHOD.md (a Markdown table under a heading).
    Markdown,
    /// JSON.
    Json,
}

#[derive(Subcommand)]
enum BenchKind {
    /// Fast BCD scaling case of fast-bcd Fig. 6 (sigma = 0.99, U0 = 6, density 1, dt = 1e-3).
    Bcd(bench_bcd::BenchArgs),
    /// WCA Brownian dynamics, 25,000 particles at phi = 0.1 in a periodic box, beside LAMMPS.
    Bd(bench_bd::BenchArgs),
    /// Hard-sphere Monte Carlo, 10,976 spheres at phi = 0.3 and 0.5, trial moves per second.
    Mc(bench_mc::BenchArgs),
    /// Pure DPD water, 81,000 beads at density 3 (L = 30, dt = 0.04), beside LAMMPS.
    Dpd(dpd_bench::BenchArgs),
    /// RPY mobility: direct product beside pystokes, PSE from 10^3 to 10^5, BD+RPY step.
    Rpy(rpy_bench::BenchArgs),
    /// SRD solvent, 1.08e6 particles at density 5 (L = 60 cells), beside LAMMPS fix srd.
    Mpcd(bench_mpcd::BenchArgs),
}

/// The progress bar: appears only on a terminal, only when not quiet, and only once the run
/// has lasted a second (short runs print nothing but their result).
struct Bar {
    quiet: bool,
    bar: Mutex<Option<ProgressBar>>,
}

impl Bar {
    fn new(quiet: bool) -> Self {
        Self {
            quiet,
            bar: Mutex::new(None),
        }
    }

    fn with(&self, f: impl FnOnce(&ProgressBar)) {
        if let Some(pb) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).as_ref() {
            f(pb);
        }
    }
}

impl Progress for Bar {
    fn begin(&self, label: &str, total: u64, done: u64) {
        if self.quiet || !std::io::stderr().is_terminal() {
            return;
        }
        let pb =
            ProgressBar::with_draw_target(Some(total), indicatif::ProgressDrawTarget::hidden());
        pb.set_style(
            ProgressStyle::with_template(&format!(
                "{label} {{bar:30}} {{percent:>3}}% {{elapsed_precise}} eta {{eta}} {{msg}}"
            ))
            .expect("static template"),
        );
        pb.set_position(done);
        pb.enable_steady_tick(Duration::from_millis(500));
        let reveal = pb.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_secs(1));
            if !reveal.is_finished() {
                reveal.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            }
        });
        *self.bar.lock().unwrap_or_else(|e| e.into_inner()) = Some(pb);
    }

    fn advance(&self, done: u64) {
        self.with(|pb| pb.set_position(done));
    }

    fn status(&self, text: &str) {
        self.with(|pb| pb.set_message(text.to_string()));
    }

    fn message(&self, text: &str) {
        if self.quiet {
            return;
        }
        self.print(text);
    }

    fn warning(&self, text: &str) {
        self.print(&format!("warning: {text}"));
    }

    fn end(&self) {
        if let Some(pb) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            pb.finish_and_clear();
        }
    }
}

impl Bar {
    /// A line on stderr, above the progress bar when one is shown.
    fn print(&self, text: &str) {
        let mut shown = false;
        self.with(|pb| {
            pb.suspend(|| eprintln!("{text}"));
            shown = true;
        });
        if !shown {
            eprintln!("{text}");
        }
    }
}

/// Which signals ask a command to stop at its next checkpoint.
#[derive(Clone, Copy, PartialEq)]
enum Signals {
    /// Ctrl-C only (commands that do not write checkpoints: SIGTERM still ends them at once).
    CtrlC,
    /// Ctrl-C, SIGTERM and SIGUSR1 (runs and ensembles).
    All,
}

/// A control that the first Ctrl-C (and, with [`Signals::All`], SIGTERM or SIGUSR1) stops at
/// the next checkpoint, with the signal as its cause; a second signal ends the program at
/// once, without a checkpoint, with status 128 + the signal's number (130 for Ctrl-C). With a
/// budget, the run stops by itself at the last checkpoint that fits in it.
fn control(quiet: bool, signals: Signals, walltime: Option<&WallTime>) -> Control {
    let mut ctl = Control::new(Arc::new(Bar::new(quiet)));
    if let Some(w) = walltime {
        ctl = ctl.with_walltime(w.seconds, started());
    }
    watch_signals(&ctl, signals);
    ctl
}

#[cfg(unix)]
fn watch_signals(ctl: &Control, which: Signals) {
    use signal_hook::consts::{SIGINT, SIGTERM, SIGUSR1};
    let list: &[i32] = match which {
        Signals::CtrlC => &[SIGINT],
        Signals::All => &[SIGINT, SIGTERM, SIGUSR1],
    };
    let Ok(mut signals) = signal_hook::iterator::Signals::new(list) else {
        return;
    };
    let ctl = ctl.clone();
    std::thread::spawn(move || {
        let mut seen = false;
        for sig in signals.forever() {
            let (cause, name) = match sig {
                SIGTERM => (Stop::Terminate, "SIGTERM"),
                SIGUSR1 => (Stop::User1, "SIGUSR1"),
                _ => (Stop::Interrupt, "Ctrl-C"),
            };
            if seen {
                eprintln!(
                    "\nsecond {name}: stopping at once, without a checkpoint (the last one written remains)"
                );
                std::process::exit(128 + sig);
            }
            seen = true;
            ctl.stop(cause);
        }
    });
}

#[cfg(not(unix))]
fn watch_signals(ctl: &Control, _which: Signals) {
    let ctl = ctl.clone();
    let seen = std::sync::atomic::AtomicBool::new(false);
    let _ = ctrlc::set_handler(move || {
        if seen.swap(true, std::sync::atomic::Ordering::SeqCst) {
            eprintln!(
                "\nsecond Ctrl-C: stopping at once, without a checkpoint (the last one written remains)"
            );
            std::process::exit(130);
        }
        ctl.stop(Stop::Interrupt);
    });
}

/// When the program started (the wall-time budget counts from it).
fn started() -> Instant {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    *START.get_or_init(Instant::now)
}

/// `--walltime`: the budget as given (repeated in the command that continues) and in seconds.
#[derive(Clone, Debug)]
struct WallTime {
    text: String,
    seconds: f64,
}

/// Parse `--walltime`: `HH:MM:SS` (hours may exceed 23), `D-HH:MM:SS` (Slurm's form), or
/// seconds; more than 0 s and at most 366 days.
fn parse_walltime(text: &str) -> std::result::Result<WallTime, String> {
    let t = text.trim();
    let form = "expected HH:MM:SS (e.g. 23:50:00), D-HH:MM:SS or a number of seconds";
    let number = |s: &str| -> std::result::Result<f64, String> {
        if s.is_empty() || !s.chars().all(|c| c.is_ascii_digit() || c == '.') {
            return Err(format!("{form}, got '{text}'"));
        }
        s.parse::<f64>()
            .map_err(|_| format!("{form}, got '{text}'"))
    };
    let (days, clock) = match t.split_once('-') {
        Some((d, rest)) => (number(d)?, rest),
        None => (0.0, t),
    };
    let parts: Vec<&str> = clock.split(':').collect();
    let seconds = match parts[..] {
        [s] if days == 0.0 && !t.contains('-') => number(s)?,
        [h, m, s] => {
            let (h, m, s) = (number(h)?, number(m)?, number(s)?);
            if m >= 60.0 || s >= 60.0 {
                return Err(format!(
                    "minutes and seconds must be below 60, got '{text}'"
                ));
            }
            ((days * 24.0 + h) * 60.0 + m) * 60.0 + s
        }
        _ => return Err(format!("{form}, got '{text}'")),
    };
    if !(seconds > 0.0 && seconds <= 366.0 * 86400.0) {
        return Err(format!(
            "must be more than 0 s and at most 366 days, got '{text}'"
        ));
    }
    Ok(WallTime {
        text: t.to_string(),
        seconds,
    })
}

/// The exit status of a run stopped with its checkpoint written, per cause (docs/cluster.md).
fn stop_status(cause: Stop) -> u8 {
    match cause {
        Stop::Interrupt => 80,
        Stop::Terminate => 81,
        Stop::User1 => 82,
        Stop::WallTime => 83,
    }
}

/// A command stopped on request, its checkpoints written: the program exits with `status`
/// after printing `message` (none when another rank printed it already).
#[derive(Debug)]
struct Stopped {
    status: u8,
    message: Option<String>,
}

impl std::fmt::Display for Stopped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(
            self.message
                .as_deref()
                .unwrap_or("stopped (see the message above)"),
        )
    }
}

impl std::error::Error for Stopped {}

/// [`parallel::Ranks::agree`] that keeps a stop's exit status on every rank.
fn agree_stopped<T>(ranks: &parallel::Ranks, local: Result<T>) -> Result<T> {
    let status = local
        .as_ref()
        .err()
        .and_then(|e| e.downcast_ref::<Stopped>())
        .map(|s| s.status);
    ranks.agree(local).map_err(|e| match status {
        Some(status) if e.downcast_ref::<parallel::Reported>().is_some() => Stopped {
            status,
            message: None,
        }
        .into(),
        _ => e,
    })
}

fn scenario(path: &Path, overrides: &Overrides) -> Result<Scenario> {
    Scenario::from_path(path)?.with_overrides(&overrides.set)
}

fn main() -> std::process::ExitCode {
    started();
    quiet_on_closed_pipe();
    match run_cli() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            if let Some(s) = e.downcast_ref::<Stopped>() {
                if let Some(m) = &s.message {
                    eprintln!("error: {m}");
                }
                return std::process::ExitCode::from(s.status);
            }
            if e.downcast_ref::<parallel::Reported>().is_none() {
                report(&e);
            }
            std::process::ExitCode::FAILURE
        }
    }
}

/// `error: ` and the error's chain on stderr.
fn report(e: &anyhow::Error) {
    eprintln!("error: {}", error_chain(e));
}

/// The most worker threads `--threads` may ask for: 8 per core this process may use
/// (`available_parallelism`, which follows CPU affinity and cgroup quotas), and never more than
/// 4096. More threads than that only share the same cores, while each costs a stack and the
/// per-thread buffers of the engines (a histogram or a force array per thread).
fn max_threads() -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    (8 * cores).min(4096)
}

/// `--threads N`: the global pool of N workers (default: all cores); refused above
/// [`max_threads`] before any thread starts.
fn thread_pool(threads: Option<usize>) -> Result<()> {
    if let Some(n) = threads {
        if n == 0 {
            bail!("--threads must be at least 1");
        }
        let limit = max_threads();
        if n > limit {
            bail!(
                "--threads {n}: at most {limit} (8 per available core, {} here, and at most 4096): more threads only share the same cores",
                std::thread::available_parallelism().map_or(1, |c| c.get())
            );
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("cannot start the thread pool")?;
    }
    Ok(())
}

/// The error and its causes, `a: b: c`, each cause once (an error whose message already ends
/// with its source's is not followed by it again).
fn error_chain(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        if msg.ends_with(&c) {
            continue;
        }
        if !msg.is_empty() {
            msg.push_str(": ");
        }
        msg.push_str(&c);
    }
    msg
}

/// `colloidsim check ... | head`: output into a closed pipe ends the program quietly with the
/// status of SIGPIPE, as a command-line tool should (`println!` panics on it).
fn quiet_on_closed_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let msg = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.contains("Broken pipe") {
            std::process::exit(141);
        }
        default(info);
    }));
}

/// The error of an interrupted run, with the command that continues it (`--walltime` again
/// when one was given) and the exit status of its cause. A budget that ran out before a step
/// could be made is an error (status 1), so that a loop of restarts does not go on forever.
fn continue_hint(e: anyhow::Error, launcher: &str, walltime: Option<&WallTime>) -> anyhow::Error {
    let Some(i) = e.downcast_ref::<colloidsim_run::Interrupted>() else {
        return e;
    };
    let again = walltime.map_or(String::new(), |w| {
        format!(" --walltime {}", shell_word(&w.text))
    });
    let command = format!(
        "{launcher}colloidsim run --restart {}{again}",
        shell_word(&i.out.display().to_string())
    );
    if i.cause == Stop::WallTime && i.checkpoint == i.started {
        return budget_too_short(
            &format!("{i}: "),
            "a step could be made",
            walltime,
            &format!(
                "{launcher}colloidsim run --restart {}",
                shell_word(&i.out.display().to_string())
            ),
        );
    }
    Stopped {
        status: stop_status(i.cause),
        message: Some(format!("{i}. Continue with: {command}")),
    }
    .into()
}

/// A wall-time budget spent before `what`: an error (status 1), not a stop to continue from,
/// so that a loop of restarts with the same budget does not go on forever; `command` continues
/// with a longer one.
fn budget_too_short(
    prefix: &str,
    what: &str,
    walltime: Option<&WallTime>,
    command: &str,
) -> anyhow::Error {
    anyhow::anyhow!(
        "{prefix}the wall-time budget (--walltime {}) ran out before {what}; \
         continue with a longer one: {command} --walltime ...",
        walltime.map_or("?", |w| &w.text),
    )
}

/// `s` quoted for a POSIX shell when it needs it.
fn shell_word(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=+,:@%".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

fn run_cli() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Run {
            scenario: path,
            out,
            seed,
            threads,
            quiet,
            force,
            restart,
            walltime,
            overrides,
        } => {
            let ranks = parallel::Ranks::init()?;
            if ranks.size() > 1 {
                let opts = RunOptions { out, seed, force };
                let sc = path.as_deref().map(|p| (p, &overrides));
                return run_on_ranks(&ranks, sc, opts, restart, threads, quiet, walltime);
            }
            thread_pool(threads)?;
            let sc = path
                .as_deref()
                .map(|p| scenario(p, &overrides))
                .transpose()?;
            if sc.is_none() && !overrides.set.is_empty() {
                bail!(
                    "--set needs the scenario file: colloidsim run SCENARIO --set ... --restart DIR"
                );
            }
            let ctl = control(quiet, Signals::All, walltime.as_ref());
            let report = match (&restart, &sc) {
                (Some(dir), _) => colloidsim_run::resume(dir, sc.as_ref(), seed, &ctl),
                (None, Some(sc)) => colloidsim_run::run(sc, &RunOptions { out, seed, force }, &ctl),
                (None, None) => unreachable!("clap requires a scenario without --restart"),
            }
            .map_err(|e| continue_hint(e, "", walltime.as_ref()))?;
            if !quiet {
                println!("{}", report.message);
            }
            Ok(())
        }
        Command::Theory {
            scenario: path,
            out,
            dx,
            force,
            hydrodynamics,
            pair,
            overrides,
        } => {
            let sc = scenario(&path, &overrides)?;
            let report = colloidsim_run::theory(
                &sc,
                &TheoryOptions {
                    out,
                    dx,
                    force,
                    hydrodynamics,
                    pair,
                },
                &control(false, Signals::CtrlC, None),
            )?;
            println!("{}", report.message);
            Ok(())
        }
        Command::Analyse {
            trajectory,
            out,
            force,
            types,
            frames,
            r_max,
            bins,
            contact_gap,
            centre,
            profile_bins,
            dt,
            percus_yevick,
            threads,
        } => {
            thread_pool(threads)?;
            let report = colloidsim_run::analyse(
                &trajectory,
                &colloidsim_run::AnalyseOptions {
                    out,
                    force,
                    types,
                    frames,
                    r_max,
                    bins,
                    contact_gap,
                    centre,
                    profile_bins,
                    dt,
                    percus_yevick,
                },
            )?;
            for w in &report.warnings {
                eprintln!("warning: {w}");
            }
            println!("{}", report.message);
            Ok(())
        }
        Command::Render {
            input,
            out,
            force,
            frame,
            animate,
            frames,
            colour,
            cut,
            width,
            fps,
        } => {
            let path = colloidsim_run::render(
                &input,
                &colloidsim_run::RenderOptions {
                    out,
                    force,
                    frame,
                    animate,
                    frames,
                    colour,
                    cut,
                    width,
                    fps,
                },
            )?;
            println!("drew {}", path.display());
            Ok(())
        }
        Command::Extrapolate {
            scenario: path,
            out,
            seeds,
            order,
            force,
            threads,
            overrides,
        } => {
            thread_pool(threads)?;
            let sc = scenario(&path, &overrides)?;
            let opts = colloidsim_run::ExtrapolateOptions {
                out,
                seeds,
                order,
                force,
            };
            let report =
                colloidsim_run::extrapolate(&sc, &opts, &control(true, Signals::CtrlC, None))?;
            println!("{}", report.message);
            Ok(())
        }
        Command::Ensemble {
            scenario: path,
            out,
            replicas,
            vary,
            threads,
            quiet,
            force,
            restart,
            member,
            collect,
            finished_only,
            walltime,
            overrides,
        } => {
            if let Some(dir) = collect {
                return collect_ensemble(&dir, finished_only);
            }
            let create = restart.is_none();
            let plan = move || match (&restart, &path) {
                (Some(dir), _) if overrides.set.is_empty() => Ensemble::reopen(dir),
                (Some(_), _) => bail!("--set cannot change an ensemble that is continued"),
                (None, Some(path)) => Ensemble::plan(
                    &scenario(path, &overrides)?,
                    &colloidsim_run::EnsembleOptions {
                        out,
                        replicas,
                        vary: vary.iter().map(|v| parse_vary(v)).collect::<Result<_>>()?,
                        force,
                    },
                ),
                (None, None) => unreachable!("clap requires a scenario without --restart"),
            };
            let how = Launch {
                create,
                threads,
                quiet,
                walltime,
            };
            match member {
                Some(k) => ensemble_member(plan, k, &how),
                None => ensemble(plan, &how),
            }
        }
        Command::Check {
            scenario: path,
            json,
            no_estimate,
            threads,
            overrides,
        } => {
            thread_pool(threads)?;
            let sc = scenario(&path, &overrides)?;
            let checked = colloidsim_run::check(&sc)?;
            for w in &checked.warnings {
                eprintln!("warning: {w}");
            }
            if json {
                println!("{}", serde_json::to_string_pretty(&checked.resolved)?);
            } else {
                let keys = colloidsim_run::keys(&sc.method()?)?;
                print!("{}", colloidsim_run::keys::values(&sc.table()?, &keys));
            }
            println!("scenario {} is valid", path.display());
            if !json && !no_estimate {
                let e = colloidsim_run::estimate::estimate(&sc, Duration::from_millis(500))
                    .context("estimating the run's cost (skip with --no-estimate)")?;
                println!("{}", e.line());
                if let Some(why) = &e.stopped {
                    eprintln!("warning: the run stopped while it was timed: {why}");
                }
                if let Some(w) = e.warning() {
                    eprintln!("warning: {w}");
                }
            }
            Ok(())
        }
        Command::Keys { method, format } => {
            let keys = colloidsim_run::keys(&method)?;
            match format {
                KeyFormat::Json => println!("{}", serde_json::to_string_pretty(&keys)?),
                KeyFormat::Markdown => print!("{}", colloidsim_run::keys_page(&method)?),
                KeyFormat::Text => print!("{}", colloidsim_run::keys::text(&keys)),
            }
            Ok(())
        }
        Command::Bench { which } => match which {
            BenchKind::Bcd(args) => bench_bcd::bench(&args),
            BenchKind::Bd(args) => bench_bd::bench(&args),
            BenchKind::Dpd(args) => dpd_bench::bench(&args),
            BenchKind::Mc(args) => bench_mc::bench(&args),
            BenchKind::Rpy(args) => rpy_bench::bench(&args),
            BenchKind::Mpcd(args) => bench_mpcd::bench(&args),
        },
    }
}

/// `colloidsim run` under `mpirun -n N`: one run decomposed in space over the ranks (DPD,
/// free-draining BD and the MPCD solvent so far; docs/parallel.md). Every rank reads the scenario and builds its
/// share; rank 0 writes the folder a single-rank run writes.
fn run_on_ranks(
    ranks: &parallel::Ranks,
    scenario_path: Option<(&Path, &Overrides)>,
    opts: RunOptions,
    restart: Option<PathBuf>,
    threads: Option<usize>,
    quiet: bool,
    walltime: Option<WallTime>,
) -> Result<()> {
    let (rank, size) = (ranks.rank(), ranks.size());
    ranks.agree(thread_pool(threads.or(ranks.default_threads())))?;
    let sc = ranks.agree(scenario_path.map(|(p, o)| scenario(p, o)).transpose())?;
    ranks.agree(match (&sc, scenario_path) {
        (None, Some((_, o))) if !o.set.is_empty() => Err(anyhow::anyhow!(
            "--set needs the scenario file: colloidsim run SCENARIO --set ... --restart DIR"
        )),
        _ => Ok(()),
    })?;
    let ctl = control(quiet || rank != 0, Signals::All, walltime.as_ref());
    let comm = ranks.agree(ranks.exchange())?;
    let report = match (&restart, &sc) {
        (Some(dir), _) => {
            colloidsim_run::resume_decomposed(dir, sc.as_ref(), opts.seed, &ctl, comm)
        }
        (None, Some(sc)) => colloidsim_run::run_decomposed(sc, &opts, &ctl, comm),
        (None, None) => unreachable!("clap requires a scenario without --restart"),
    }
    .map_err(|e| continue_hint(e, "mpirun -n N ", walltime.as_ref()));
    let report = agree_stopped(ranks, report)?;
    if rank == 0 && !quiet {
        println!("{} ({size} MPI ranks)", report.message);
    }
    Ok(())
}

/// How `colloidsim ensemble` runs: whether it creates the folder (not when continued), the
/// threads, quiet, the wall-time budget.
struct Launch {
    create: bool,
    threads: Option<usize>,
    quiet: bool,
    walltime: Option<WallTime>,
}

/// `--walltime X` as repeated in a command that continues, or nothing.
fn walltime_again(w: Option<&WallTime>) -> String {
    w.map_or(String::new(), |w| {
        format!(" --walltime {}", shell_word(&w.text))
    })
}

/// `colloidsim ensemble ... --member K`: member `k` alone, in one process, into the folder a
/// whole ensemble gives it (the folder and its plan created if absent, checked otherwise).
fn ensemble_member(plan: impl FnOnce() -> Result<Ensemble>, k: usize, how: &Launch) -> Result<()> {
    let ranks = parallel::Ranks::init()?;
    if ranks.size() > 1 {
        bail!(
            "--member runs one member in one process; under mpirun, leave it out (the ranks share \
             the members) or start one process per member"
        );
    }
    thread_pool(how.threads)?;
    let plan = plan()?;
    let n = plan.members().len();
    if k >= n {
        bail!(
            "--member: must lie in 0 ..= {} (this ensemble has {n} member(s)), got {k}",
            n - 1
        );
    }
    if how.create {
        plan.join()?;
    }
    let dir = plan.out().join(&plan.members()[k].folder);
    let out = shell_word(&plan.out().display().to_string());
    let collect =
        format!("once every member is, average them: colloidsim ensemble --collect {out}");
    if plan.member_state(k) == MemberState::Complete {
        if !how.quiet {
            println!("member {k} is complete in {}; {collect}", dir.display());
        }
        return Ok(());
    }
    let ctl = control(how.quiet, Signals::All, how.walltime.as_ref());
    if let Err(e) = plan.run_member(k, &ctl) {
        if let Some(i) = e.downcast_ref::<colloidsim_run::Interrupted>() {
            if i.cause == Stop::WallTime && i.checkpoint == i.started {
                return Err(budget_too_short(
                    &format!("member {k}: "),
                    "a step could be made",
                    how.walltime.as_ref(),
                    &format!("colloidsim ensemble --restart {out} --member {k}"),
                ));
            }
            return Err(Stopped {
                status: stop_status(i.cause),
                message: Some(format!(
                    "member {k}: {i}. Continue with: colloidsim ensemble --restart {out} --member {k}{}",
                    walltime_again(how.walltime.as_ref())
                )),
            }
            .into());
        }
        return Err(e);
    }
    if !how.quiet {
        println!("member {k} completed in {}; {collect}", dir.display());
    }
    Ok(())
}

/// `colloidsim ensemble --collect DIR`: average the members run with --member.
fn collect_ensemble(dir: &Path, finished_only: bool) -> Result<()> {
    let ranks = parallel::Ranks::init()?;
    if ranks.size() > 1 {
        bail!("--collect runs in one process, not under mpirun");
    }
    let report = Ensemble::load(dir, "--collect")?.collect(finished_only)?;
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    println!("{}", report.message);
    Ok(())
}

/// `colloidsim ensemble`: every rank plans the same ensemble (and stops alike on bad input),
/// rank 0 creates the folder (unless the ensemble is continued), member `k` runs on rank
/// `k mod size`, and rank 0 combines. A stop (a signal, the budget) on any rank stops every
/// rank after its running member, with the status of the largest cause seen.
fn ensemble(plan: impl FnOnce() -> Result<Ensemble>, how: &Launch) -> Result<()> {
    let start = std::time::Instant::now();
    let ranks = parallel::Ranks::init()?;
    let (rank, size) = (ranks.rank(), ranks.size());
    ranks.agree(thread_pool(how.threads.or(ranks.default_threads())))?;
    let plan = ranks.agree(plan())?;
    ranks.agree(if rank == 0 && how.create {
        plan.create()
    } else {
        Ok(())
    })?;
    let quiet = how.quiet;
    let ctl = control(quiet || rank != 0, Signals::All, how.walltime.as_ref());
    let (failed, progressed) = plan.run_share(rank, size, &ctl);
    let mine: serde_json::Map<String, serde_json::Value> = failed
        .into_iter()
        .map(|(k, e)| (k.to_string(), e.into()))
        .collect();
    let progressed = ranks
        .all_gather(&u8::from(progressed).to_string())
        .iter()
        .any(|p| p == "1");
    let code = ranks
        .all_gather(&ctl.stop_cause().map_or(0, Stop::code).to_string())
        .iter()
        .filter_map(|c| c.parse::<u8>().ok())
        .max()
        .and_then(Stop::from_code);
    let out = shell_word(&plan.out().display().to_string());
    agree_stopped(
        &ranks,
        match code {
            // As for `run`: a budget too short for any step is an error, so that a loop of
            // restarts does not go on forever.
            Some(Stop::WallTime) if !progressed => Err(budget_too_short(
                "",
                "any member could make a step",
                how.walltime.as_ref(),
                &format!(
                    "{}colloidsim ensemble --restart {out}",
                    if size > 1 { "mpirun -n N " } else { "" }
                ),
            )),
            Some(cause) => Err(Stopped {
                status: stop_status(cause),
                message: Some(format!(
                    "{}; continue with: {}colloidsim ensemble --restart {out}{}",
                    cause.what(),
                    if size > 1 { "mpirun -n N " } else { "" },
                    walltime_again(how.walltime.as_ref())
                )),
            }
            .into()),
            None => Ok(()),
        },
    )?;
    let mut errors = vec![None; plan.members().len()];
    for text in ranks.all_gather(&serde_json::Value::Object(mine).to_string()) {
        let failed: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&text)?;
        for (k, e) in failed {
            errors[k.parse::<usize>()?] = Some(e.as_str().unwrap_or("?").to_string());
        }
    }
    let report = ranks.agree(if rank == 0 {
        plan.finish(&errors, start.elapsed().as_secs_f64())
            .map(Some)
    } else {
        Ok(None)
    })?;
    if let Some(report) = report.filter(|_| !quiet) {
        for w in &report.warnings {
            eprintln!("warning: {w}");
        }
        println!(
            "{}{}",
            report.message,
            if size > 1 {
                format!(" ({size} MPI ranks)")
            } else {
                String::new()
            }
        );
    }
    Ok(())
}
