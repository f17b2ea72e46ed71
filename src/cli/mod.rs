//! The command-line interface (feature `cli`). Each command is a thin layer over library calls:
//! one file per command group, each with an `Args` struct (clap) and a `run` function.
//!
//! Conventions shared by all commands: gear parameters by flags or a TOML file (`--config`), in SI
//! units with angles in degrees; `--json` prints machine-readable output on stdout; errors go to
//! stderr with exit code 2; output files are written atomically.

mod basins;
mod bench;
mod boundary;
mod campaign;
mod classify;
mod common;
mod continue_;
mod diagnose;
mod diagram;
mod figure;
mod fit;
mod info;
mod locate;
mod map;
mod methods;
mod model_arg;
mod report;
mod simulate;
mod sweep;
mod sweep_model;
mod synth;

pub use common::{parse_config, GearArgs, GearConfig, Output};

use clap::{Parser, Subcommand};

/// gearbif: exact dynamics, periodic orbits and bifurcations of periodically driven oscillators
/// with dry friction — the dipole magnetic gear of Hartung & Rehberg (2020) built in.
#[derive(Debug, Parser)]
#[command(
    name = "gearbif",
    version,
    about,
    long_about = None,
    propagate_version = true,
    after_help = "Every command works on the dipole gear: the paper's (the default), one given by \
                  the gear flags or --config, or a recorded gear's model.json with --model \
                  (simulate, map, locate, classify, continue, diagram, boundary, sweep, report, \
                  figure orbit/lyapunov). fit, diagnose, synth and campaign read or make \
                  recordings of the gear. Any other driven oscillator with dry friction goes \
                  through the library (the DrivenOscillator trait) or Python (gearbif.UserSystem)."
)]
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
    /// Pseudo-arclength continuation of a periodic orbit in one parameter, with special points
    /// (event-driven DOP853).
    Continue(continue_::Args),
    /// Refine one special point (fold, flip, symmetry-breaking, Neimark–Sacker) by Newton
    /// (event-driven DOP853; --dp5 for the DP5).
    Locate(locate::Args),
    /// The whole bifurcation diagram over a parameter range, automatically: seeds from simulations
    /// and analytic branches, switching at every flip and symmetry-breaking point (event-driven
    /// DOP853).
    Diagram(diagram::Args),
    /// A two-parameter curve of special points, by default the lock-loss boundary f_c(Θ)
    /// (event-driven DOP853).
    Boundary(boundary::Args),
    /// Integrate the driven gear: trajectory CSV (t, alpha, beta, omega, delta) and events on ω = 0.
    Simulate(simulate::Args),
    /// Poincaré map P_T (or half-period map G) of a state, its Jacobians and multipliers.
    Map(map::Args),
    /// Work-precision diagram of the integrators (error, RHS evaluations, wall time) on one case
    /// (default Θ = 25°, f = 2.7 Hz, one P_T with its Jacobian).
    BenchIntegrators(bench::Args),
    /// Fit a recording set: ring-downs (eq. `model`), κ(α0) → g, |Δ|, I, and the base model.
    Fit(fit::Args),
    /// Diagnose a recording set: locate the mismatch and name the missing physics (report.json).
    Diagnose(diagnose::Args),
    /// Make a synthetic recording set with a chosen effect at a chosen size.
    Synth(synth::Args),
    /// Measure the diagnosis on sets from an independent generator: false positives, power per
    /// effect against size, confusion matrix, σ coverage (campaign.json, campaign.md, figure).
    Campaign(campaign::Args),
    /// Classify one point: the paper's flowchart (harmonic fit, RMS, THD) and the rigorous class
    /// (event-driven DOP853; --dp5 for the DP5).
    Classify(classify::Args),
    /// Two-parameter atlas (Θ × f, …), parallel, resumable; CSV/JSON and an RMS_δ map
    /// (event-driven DOP853; --dp5, --rk4).
    Sweep(sweep::Args),
    /// The report of a gear: derived quantities, lock branch, classification map, operating advice
    /// (sweeps and continuation with the event-driven DOP853).
    Report(report::Args),
    /// The paper's figures (fig5 … fig10), orbit diagram, Lyapunov exponent: SVG and PNG (fig7 …
    /// fig10 with the event-driven DOP853; fig5, fig6, orbit and lyapunov with the DP5).
    Figure(figure::Args),
    /// The attractors of P_T at one (Θ, f), their basin map (figure), basin fractions with
    /// binomial σ and the minimal fatal kick (event-driven DOP853).
    Basins(basins::Args),
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> crate::Result<()> {
    match cli.command {
        Command::Info(a) => info::run(a),
        Command::Continue(a) => continue_::run(a),
        Command::Locate(a) => locate::run(a),
        Command::Diagram(a) => diagram::run(a),
        Command::Boundary(a) => boundary::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Map(a) => map::run(a),
        Command::BenchIntegrators(a) => bench::run(a),
        Command::Fit(a) => fit::run(a),
        Command::Diagnose(a) => diagnose::run(a),
        Command::Synth(a) => synth::run(a),
        Command::Campaign(a) => campaign::run(a),
        Command::Classify(a) => classify::run(a),
        Command::Sweep(a) => sweep::run(a),
        Command::Report(a) => report::run(a),
        Command::Figure(a) => figure::run(a),
        Command::Basins(a) => basins::run(a),
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
