//! `colloidsim`: run a scenario, compute its theory, check it, or benchmark an engine.

mod bcd_cmd;
mod common;
mod dpd_bench;
mod dpd_cmd;
mod droplet;
mod plot;
mod rpy_bench;
mod theory_droplet;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use common::RunOptions;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "colloidsim",
    version,
    about = "Simulations of colloidal suspensions"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the simulation a scenario file describes and write its outputs.
    Run {
        /// Scenario file (TOML).
        scenario: PathBuf,
        /// Output folder (default: the scenario's file name without extension).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override the scenario's seed (0 ..= 4294967295).
        #[arg(long)]
        seed: Option<u64>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Write into an output folder that already holds files.
        #[arg(long)]
        force: bool,
        /// Continue an interrupted run from the checkpoint in this output folder.
        #[arg(long, conflicts_with_all = ["out", "force"])]
        restart: Option<PathBuf>,
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
    },
    /// Validate a scenario and print the resolved parameters.
    Check {
        /// Scenario file (TOML).
        scenario: PathBuf,
    },
    /// Benchmark an engine and print a table.
    Bench {
        /// Which benchmark.
        #[command(subcommand)]
        which: BenchKind,
    },
}

#[derive(Subcommand)]
enum BenchKind {
    /// Fast BCD scaling case of fast-bcd Fig. 6 (sigma = 0.99, U0 = 6, density 1, dt = 1e-3).
    Bcd(bcd_cmd::BenchArgs),
    /// WCA Brownian dynamics, 25,000 particles at phi = 0.1 in a periodic box, beside LAMMPS.
    Bd(droplet::BenchArgs),
    /// Pure DPD water, 81,000 beads at density 3 (L = 30, dt = 0.04), beside LAMMPS.
    Dpd(dpd_bench::BenchArgs),
    /// RPY mobility: direct product beside pystokes, PSE from 10^3 to 10^5, BD+RPY step.
    Rpy(rpy_bench::BenchArgs),
}

/// The `method` key of a scenario decides which engine reads the rest of the file.
fn method_of(doc: &toml::Table, path: &std::path::Path) -> Result<String> {
    match doc.get("method") {
        Some(toml::Value::String(s)) => Ok(s.clone()),
        Some(other) => bail!(
            "{}: key 'method' must be a string, got {}",
            path.display(),
            other.type_str()
        ),
        None => bail!(
            "{}: missing key 'method' (one of: bcd, bcd-chronological, droplet-bd, dpd)",
            path.display()
        ),
    }
}

fn read_scenario(path: &std::path::Path) -> Result<(String, String)> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read scenario {}", path.display()))?;
    let doc: toml::Table =
        toml::from_str(&text).with_context(|| format!("{} is not valid TOML", path.display()))?;
    Ok((method_of(&doc, path)?, text))
}

fn main() -> std::process::ExitCode {
    match run_cli() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run_cli() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Run {
            scenario,
            out,
            seed,
            threads,
            quiet,
            force,
            restart,
        } => {
            if let Some(n) = threads {
                if n == 0 {
                    bail!("--threads must be at least 1");
                }
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build_global()
                    .context("cannot start the thread pool")?;
            }
            let (method, text) = read_scenario(&scenario)?;
            let opts = RunOptions {
                out: common::default_out(&scenario, out, ""),
                seed,
                quiet,
                force,
                restart,
            };
            match method.as_str() {
                "bcd" | "bcd-chronological" => bcd_cmd::run(&scenario, &text, &opts),
                "droplet-bd" => droplet::run(&scenario, &text, &opts),
                "dpd" => dpd_cmd::run(&scenario, &text, &opts),
                m => bail!(
                    "{}: unknown method '{m}' (one of: bcd, bcd-chronological, droplet-bd, dpd)",
                    scenario.display()
                ),
            }
        }
        Command::Theory {
            scenario,
            out,
            dx,
            force,
            hydrodynamics,
        } => {
            let (method, text) = read_scenario(&scenario)?;
            let out = common::default_out(&scenario, out, "-theory");
            if hydrodynamics.is_some() && method != "droplet-bd" {
                bail!("--hydrodynamics applies to droplet-bd scenarios only");
            }
            match method.as_str() {
                "bcd" | "bcd-chronological" => bcd_cmd::theory(&scenario, &text, &out, dx, force),
                "droplet-bd" => theory_droplet::theory(
                    &scenario,
                    &text,
                    &out,
                    dx,
                    force,
                    hydrodynamics.as_deref(),
                ),
                m => bail!(
                    "{}: method '{m}' has no theory counterpart",
                    scenario.display()
                ),
            }
        }
        Command::Check { scenario } => {
            let (method, text) = read_scenario(&scenario)?;
            match method.as_str() {
                "bcd" | "bcd-chronological" => bcd_cmd::check(&scenario, &text),
                "droplet-bd" => droplet::check(&scenario, &text),
                "dpd" => dpd_cmd::check(&scenario, &text),
                m => bail!("{}: unknown method '{m}'", scenario.display()),
            }
        }
        Command::Bench { which } => match which {
            BenchKind::Bcd(args) => bcd_cmd::bench(&args),
            BenchKind::Bd(args) => droplet::bench(&args),
            BenchKind::Dpd(args) => dpd_bench::bench(&args),
            BenchKind::Rpy(args) => rpy_bench::bench(&args),
        },
    }
}
