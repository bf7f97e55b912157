//! `colloidsim run|theory|check|bench` for Brownian cluster dynamics scenarios.

use crate::common::RunOptions;
use anyhow::{Result, bail};
use std::path::Path;

/// Arguments of `colloidsim bench bcd`.
#[derive(clap::Args)]
pub struct BenchArgs {}

pub fn run(_scenario: &Path, _text: &str, _opts: &RunOptions) -> Result<()> {
    bail!("bcd: under construction")
}
pub fn theory(_s: &Path, _t: &str, _o: &Path, _dx: Option<f64>, _f: bool) -> Result<()> {
    bail!("bcd theory: under construction")
}
pub fn check(_s: &Path, _t: &str) -> Result<()> {
    bail!("bcd check: under construction")
}
pub fn bench(_a: &BenchArgs) -> Result<()> {
    bail!("bench: under construction")
}
