//! The command-line interface (feature `cli`). Each command is a thin layer over library calls:
//! one file per command group, each with an `Args` struct (clap) and a `run` function.
//!
//! Conventions shared by all commands: gear parameters by flags or a TOML file (`--config`), in SI
//! units with angles in degrees; `--json` prints machine-readable output on stdout; errors go to
//! stderr with exit code 2; output files are written atomically.

mod classify;
mod common;
mod figure;
mod info;
mod report;
mod sweep;

pub use common::{GearArgs, Output};

use clap::{Parser, Subcommand};

/// gearbif: exact dynamics, periodic orbits and bifurcations of periodically driven oscillators
/// with dry friction — the dipole magnetic gear of Hartung & Rehberg (2020) built in.
#[derive(Debug, Parser)]
#[command(name = "gearbif", version, about, long_about = None, propagate_version = true)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Derived quantities of a gear: g, Δ, f_c, lock angles, cogging-free shaft angles.
    Info(info::Args),
    /// Classify one point: the paper's flowchart (harmonic fit, RMS, THD) and the rigorous class.
    Classify(classify::Args),
    /// Two-parameter atlas (Θ × f, …), parallel, resumable; CSV/JSON and an RMS_δ map.
    Sweep(sweep::Args),
    /// The report of a gear: derived quantities, lock branch, classification map, operating advice.
    Report(report::Args),
    /// The paper's figures (fig5 … fig10), orbit diagram, Lyapunov exponent: SVG and PNG.
    Figure(figure::Args),
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> crate::Result<()> {
    match cli.command {
        Command::Info(a) => info::run(a),
        Command::Classify(a) => classify::run(a),
        Command::Sweep(a) => sweep::run(a),
        Command::Report(a) => report::run(a),
        Command::Figure(a) => figure::run(a),
    }
}

/// Entry point of the binary: parses the arguments, runs, and maps errors to exit code 2.
pub fn main() -> i32 {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}
