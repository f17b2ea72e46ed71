//! `gearbif bench-integrators`: a work-precision diagram of every integrator on one case.

use super::common::{count, limits, output_file, tolerance, within, GearArgs, Output};
use super::methods::{parse_x0, DriveArgs};
use crate::bench::{rhs_only_time, to_csv, work_precision, Candidate, WorkPrecisionSetup};
use crate::error::{positive, Result};
use crate::integrator::{EventDriven, EventDriven853, FixedStep, FlowMethod, Sensitivity, Taylor};
use crate::model::Gear;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `gearbif bench-integrators`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    /// Drive (input) frequency f [Hz].
    #[arg(long, default_value_t = 2.7, allow_hyphen_values = true)]
    f: f64,
    /// Initial state "BETA,OMEGA": β [deg], ω [rad/s] (default 28.6479,2 = (0.5 rad, 2 rad/s):
    /// at Θ = 25°, f = 2.7 Hz its first period crosses ω = 0).
    #[arg(
        long = "x0-deg",
        value_name = "BETA_DEG,OMEGA",
        allow_hyphen_values = true
    )]
    x0: Option<String>,
    /// Duration in drive periods [1], in (0, 1000] (1 = one stroboscopic map P_T).
    #[arg(long, default_value_t = 1.0)]
    periods: f64,
    /// Do not propagate the state Jacobian (default: P_T with its Jacobian).
    #[arg(long)]
    no_jacobian: bool,
    /// Record a sample at every whole drive period (the strobe of a simulation; with
    /// `--periods 1000 --x0-deg 180,0`: the per-period cost goals of docs/performance.md).
    #[arg(long)]
    strobe: bool,
    /// Tolerances of the event-driven DP5 [dimensionless], each in (0, 1), comma-separated (the
    /// option without a value: none, also for the other lists).
    #[arg(
        long,
        value_delimiter = ',',
        num_args = 0..,
        default_value = "1e-4,1e-6,1e-8,1e-10,1e-12"
    )]
    event_tols: Vec<f64>,
    /// Tolerances of the event-driven DOP853 [dimensionless], comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        num_args = 0..,
        default_value = "1e-4,1e-6,1e-8,1e-10,1e-12"
    )]
    dop853_tols: Vec<f64>,
    /// Tolerances of the event-driven Taylor method [dimensionless], comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        num_args = 0..,
        default_value = "1e-4,1e-6,1e-8,1e-10,1e-12"
    )]
    taylor_tols: Vec<f64>,
    /// Steps per period of the fixed-step RK4 [1], each 1 to 1000000, comma-separated (the paper
    /// uses 50).
    #[arg(
        long,
        value_delimiter = ',',
        num_args = 0..,
        default_value = "25,50,100,200,400,800,1600,3200,12800"
    )]
    fixed_steps: Vec<usize>,
    /// Tolerances of the regularised diffsol method [dimensionless], comma-separated (each is run
    /// with every --reg-eps).
    #[arg(long, value_delimiter = ',',
        num_args = 0.., default_value = "1e-6,1e-8,1e-10")]
    reg_tols: Vec<f64>,
    /// Regularisation velocities ε of the regularised method [rad/s], each in (0, 1],
    /// comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1e-2,1e-3,1e-4,1e-5")]
    reg_eps: Vec<f64>,
    /// Tolerance of the event-driven reference (DOP853) [dimensionless], in (0, 1).
    #[arg(long, default_value_t = 1e-13)]
    reference_tol: f64,
    /// Minimum wall time spent timing each point [s], in [0, 60].
    #[arg(long, default_value_t = 0.05)]
    min_time: f64,
    /// CSV file of the points (family, method, tol, error, jac_error, rhs_evals, steps, time_s, repeats).
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Figure file (.svg or .png): log10 error vs log10 wall time.
    #[arg(long, value_name = "FILE")]
    figure: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct Report {
    f_hz: f64,
    theta_deg: f64,
    delta: f64,
    x0: [f64; 2],
    periods: f64,
    strobe: bool,
    jacobian: bool,
    reference_tol: f64,
    /// The reference's final state (β, ω), for comparisons with other programs.
    reference_x: [f64; 2],
    points: Vec<crate::bench::WorkPrecisionPoint>,
    /// Time of the reference's number of RHS evaluations alone (jets if with Jacobian), s.
    rhs_only_time_s: f64,
    rhs_only_evals: usize,
}

/// Runs `gearbif bench-integrators`.
pub fn run(a: Args) -> Result<()> {
    let mut g = a.gear.clone();
    if g.theta_deg.is_none() && g.config.is_none() {
        g.theta_deg = Some(25.0);
    }
    let p = g.params()?;
    let drive = DriveArgs { f: a.f, x0: None };
    let gear: Gear = drive.gear(&g)?;
    let x0 = match &a.x0 {
        Some(s) => parse_x0(s)?,
        None => [0.5, 2.0],
    };
    check_args(&a)?;
    let files = crate::io::StagedFiles::begin(&plan(&a))?;
    let methods = Methods::new(&a);
    let cands = methods.candidates(&a);
    let setup = WorkPrecisionSetup {
        x0,
        periods: a.periods,
        strobe: a.strobe,
        sensitivity: if a.no_jacobian {
            Sensitivity::None
        } else {
            Sensitivity::State
        },
        reference_tol: a.reference_tol,
        min_time_s: a.min_time,
    };
    let points = work_precision(&gear, &setup, &cands)?;
    let refflow = crate::bench::reference(&gear, &setup)?;
    let n_rhs = refflow.stats.rhs_evals;
    let rhs_t = rhs_only_time(&gear, x0, n_rhs, !a.no_jacobian);
    let report = Report {
        f_hz: gear.f,
        theta_deg: p.theta.to_degrees(),
        delta: gear.delta,
        x0,
        periods: a.periods,
        strobe: a.strobe,
        jacobian: !a.no_jacobian,
        reference_tol: a.reference_tol,
        reference_x: refflow.x,
        points,
        rhs_only_time_s: rhs_t,
        rhs_only_evals: n_rhs,
    };
    write_files(&a, &files, &report)?;
    files.commit()?;
    Output { json: a.json }.emit_tagged("gearbif.bench_integrators/1", &report, || {
        text_table(&report)
    })
}

/// Checks the numeric options (duration, ε, tolerances, minimum time, step counts) and that the
/// `--csv` and `--figure` files can be written, before anything is timed.
fn check_args(a: &Args) -> Result<()> {
    positive("periods", a.periods)?;
    within("periods", a.periods, 0.0, 1e3, "must be in (0, 1e3]")?;
    for &e in &a.reg_eps {
        within(
            "epsilon",
            e,
            f64::MIN_POSITIVE,
            1.0,
            "must be in (0, 1] rad/s",
        )?;
    }
    tolerance("reference-tol", a.reference_tol)?;
    within("min-time", a.min_time, 0.0, 60.0, "must be in [0, 60] s")?;
    for &t in a
        .event_tols
        .iter()
        .chain(&a.reg_tols)
        .chain(&a.dop853_tols)
        .chain(&a.taylor_tols)
    {
        tolerance("tol", t)?;
    }
    for &n in &a.fixed_steps {
        count("fixed-steps", n, 1, limits::TURNS_MAX)?;
    }
    if let Some(p) = &a.csv {
        output_file("--csv", p, false)?;
    }
    if let Some(p) = &a.figure {
        output_file("--figure", p, true)?;
    }
    Ok(())
}

/// The configured methods that the candidates borrow: the fixed-step RK4 for each step count
/// and (with `diffsol-check`) the regularised method for each (ε, tolerance).
struct Methods {
    fixed: Vec<FixedStep>,
    #[cfg(feature = "diffsol-check")]
    reg: Vec<(crate::integrator::Regularised, f64)>,
}

impl Methods {
    /// The methods of the options.
    fn new(a: &Args) -> Self {
        Self {
            fixed: a
                .fixed_steps
                .iter()
                .map(|&n| FixedStep {
                    steps_per_period: n,
                })
                .collect(),
            #[cfg(feature = "diffsol-check")]
            reg: a
                .reg_eps
                .iter()
                .flat_map(|&e| {
                    a.reg_tols
                        .iter()
                        .map(move |&t| (crate::integrator::Regularised::new(e), t))
                })
                .collect(),
        }
    }

    /// The candidates in the order of the diagram: the event-driven DP5, DOP853 and Taylor at
    /// their tolerances, the fixed-step RK4, the regularised method (a note on stderr if it was
    /// asked for but not built).
    fn candidates(&self, a: &Args) -> Vec<Candidate<'_, Gear>> {
        let mut cands: Vec<Candidate<'_, Gear>> = Vec::new();
        for &t in &a.event_tols {
            cands.push(Candidate::new(&EventDriven, t, "event-driven DP5"));
        }
        for &t in &a.dop853_tols {
            cands.push(Candidate::new(&EventDriven853, t, "event-driven DOP853"));
        }
        for &t in &a.taylor_tols {
            cands.push(Candidate::new(&Taylor, t, "event-driven Taylor"));
        }
        for m in &self.fixed {
            cands.push(Candidate::new(
                m as &dyn FlowMethod<Gear>,
                0.0,
                "fixed-step RK4",
            ));
        }
        #[cfg(feature = "diffsol-check")]
        for (m, t) in &self.reg {
            cands.push(Candidate::new(
                m as &dyn FlowMethod<Gear>,
                *t,
                format!("regularised diffsol ESDIRK34, ε = {:e}", m.epsilon),
            ));
        }
        #[cfg(not(feature = "diffsol-check"))]
        if !a.reg_tols.is_empty() {
            eprintln!("note: built without `diffsol-check`: the regularised method is skipped");
        }
        cands
    }
}

/// The output files of `--csv` and `--figure`, for [`crate::io::StagedFiles::begin`].
fn plan(a: &Args) -> Vec<(&'static str, &std::path::Path, crate::io::FileKind)> {
    let mut v = Vec::new();
    if let Some(p) = &a.csv {
        v.push(("--csv", p.as_path(), crate::io::FileKind::Data));
    }
    if let Some(p) = &a.figure {
        v.push(("--figure", p.as_path(), crate::io::FileKind::Figure));
    }
    v
}

/// Writes the `--csv` points and the `--figure` (log10 error over log10 wall time), if asked,
/// into their staged files `files`.
fn write_files(a: &Args, files: &crate::io::StagedFiles, report: &Report) -> Result<()> {
    if let Some(path) = &a.csv {
        crate::io::write_atomic(files.path(path), to_csv(&report.points).as_bytes())?;
    }
    if let Some(path) = &a.figure {
        let title = format!(
            "work-precision: Θ = {:.1}°, f = {} Hz, {} period(s){}",
            report.theta_deg,
            report.f_hz,
            report.periods,
            if report.jacobian {
                " with Jacobian"
            } else {
                ""
            }
        );
        crate::plotting::save(
            &crate::bench::figure(&report.points, &title),
            files.path(path),
        )?;
    }
    Ok(())
}

/// The text output: the case, one row per point (error, Jacobian error, RHS evaluations,
/// steps, time and time per period), and the time of the right-hand side alone.
fn text_table(report: &Report) -> String {
    let x0 = report.x0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Θ = {:.2}°, f = {} Hz, x0 = ({}, {}), {} period(s), strobe: {}, Jacobian: {}, \
         reference tol {:e}",
        report.theta_deg,
        report.f_hz,
        x0[0],
        x0[1],
        report.periods,
        report.strobe,
        report.jacobian,
        report.reference_tol
    );
    let _ = writeln!(
        s,
        "{:<44} {:>9} {:>10} {:>10} {:>9} {:>8} {:>12} {:>12}",
        "method", "tol", "error", "jac_err", "rhs", "steps", "time [µs]", "µs/period"
    );
    for p in &report.points {
        let _ = writeln!(
            s,
            "{:<44} {:>9.0e} {:>10.2e} {:>10} {:>9} {:>8} {:>12.1} {:>12.2}",
            p.method.chars().take(44).collect::<String>(),
            p.tol,
            p.error,
            p.jac_error.map(|e| format!("{e:.2e}")).unwrap_or_default(),
            p.rhs_evals,
            p.steps,
            p.time_s * 1e6,
            p.time_s * 1e6 / report.periods
        );
    }
    let _ = writeln!(
        s,
        "RHS alone: {} evaluations in {:.1} µs",
        report.rhs_only_evals,
        report.rhs_only_time_s * 1e6
    );
    s
}
