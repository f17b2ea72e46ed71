//! `gearbif classify`: both classifications of one point (the paper's flowchart and the rigorous
//! one), optionally with the paper's fixed-step integrator beside the exact one.

use super::common::{angle_deg, check_frequency, count, limits, tolerance, GearArgs, Output};
use super::model_arg::ModelArgs;
use crate::analysis::{classify_point, ClassifyOptions, PointResult, ThdDefinition};
use crate::integrator::FlowMethod;
use crate::integrator::{EventDriven, FixedStep, DEFAULT_METHOD};
use crate::model::{DrivenOscillator, Gear};
use crate::Result;
use serde::Serialize;

/// Arguments of `gearbif classify`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    #[command(flatten)]
    model: ModelArgs,
    /// Drive frequency f [Hz], in [1e-3, 1e4].
    #[arg(long)]
    f: f64,
    /// Input angle α at t = 0 [deg], in [-360, 360] (paper Fig. 6: 90).
    #[arg(long, default_value_t = 90.0, allow_hyphen_values = true)]
    alpha0_deg: f64,
    /// Output angle β at t = 0 [deg], in [-360, 360], in the chosen --convention (paper Fig. 6: 270
    /// paper = 90 physical).
    #[arg(long, default_value_t = 90.0, allow_hyphen_values = true)]
    beta0_deg: f64,
    /// Settling turns, 0 to 1000000 (paper: 90).
    #[arg(long, default_value_t = 90)]
    settle: usize,
    /// Recorded turns, 1 to 100000 (paper: 10).
    #[arg(long, default_value_t = 10)]
    record: usize,
    /// Turns of the rigorous analysis after the window, 2 to 1000000.
    #[arg(long, default_value_t = 60)]
    analysis: usize,
    /// Integrator tolerance, in (0, 1).
    #[arg(long, default_value_t = 1e-9)]
    tol: f64,
    /// Use the THD as printed in the paper (denominator a1² + b1²) in the flowchart.
    #[arg(long)]
    thd_printed: bool,
    /// Also run the paper's fixed-step RK4 (50 steps per period).
    #[arg(long)]
    rk4: bool,
    /// Use the event-driven DP5 instead of the default event-driven DOP853.
    #[arg(long)]
    dp5: bool,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct Out {
    theta_deg: f64,
    f_hz: f64,
    event_driven: PointResult,
    #[serde(skip_serializing_if = "Option::is_none")]
    rk4_t50: Option<PointResult>,
}

/// Builds the options from the arguments.
fn options(a: &Args) -> ClassifyOptions {
    ClassifyOptions {
        settle_turns: a.settle,
        record_turns: a.record,
        analysis_turns: a.analysis,
        tol: a.tol,
        thd: if a.thd_printed {
            ThdDefinition::Printed
        } else {
            ThdDefinition::Standard
        },
        ..ClassifyOptions::default()
    }
}

fn describe(name: &str, r: &PointResult) -> String {
    let p = &r.paper;
    let mut s = format!(
        "{name}:\n  paper flowchart: {:<5}  RMS_fit = {:.3}°  THD_F = {:.4} (standard), {:.5} (printed)  RMS_δ = {:.3}°  δ_avg = {:.3}°  δ_fund = {:.3}°  net rotation = {:.4} Hz\n",
        p.class.label(),
        p.rms_fit_deg,
        p.thd,
        p.thd_printed,
        p.rms_delta_deg,
        p.delta_avg_deg,
        p.delta_fund_deg,
        r.net_rotation_hz
    );
    if let Some(rc) = &r.rigorous {
        let lyap = match rc.lyapunov.per_period {
            Some(l) => format!("{l:.4}"),
            None => "-inf".into(),
        };
        s += &format!(
            "  rigorous:        {:<5}  rotation number = {:.5}  locked = {}  λ_max = {lyap} per period\n",
            rc.label, rc.rotation_number, rc.locked
        );
        if let crate::analysis::Dynamics::Periodic {
            multipliers,
            symmetric,
            ..
        } = &rc.dynamics
        {
            s += &format!(
                "                   symmetric = {symmetric}, |multipliers| of the section map = {:.4e}, {:.4e}\n",
                multipliers[0], multipliers[1]
            );
        }
        s += &format!(
            "  agree: {}\n",
            if r.agree == Some(true) { "yes" } else { "NO" }
        );
    }
    s
}

/// Runs `gearbif classify`.
pub fn run(a: Args) -> Result<()> {
    check_frequency(a.f)?;
    angle_deg("alpha0_deg", a.alpha0_deg)?;
    angle_deg("beta0_deg", a.beta0_deg)?;
    tolerance("tol", a.tol)?;
    count("settle", a.settle, 0, limits::TURNS_MAX)?;
    count("record", a.record, 1, 100_000)?;
    count("analysis", a.analysis, 2, limits::TURNS_MAX)?;
    let x0 = [a.beta0_deg.to_radians(), 0.0];
    let opts = options(&a);
    if let Some(m) = a.model.recorded(&a.gear, a.f)? {
        let m = m.with_alpha0(a.alpha0_deg.to_radians())?;
        let (ev, rk) = both(&m, x0, &a, &opts)?;
        let geo = *m.geometry();
        return print(&a, [geo.theta(), geo.phi()], ev, rk);
    }
    let p = a.gear.params()?;
    let gear = Gear::new(p.g(), p.delta(), p.zeta, p.eta, a.f)?
        .with_convention(a.gear.convention())
        .with_alpha0(a.alpha0_deg.to_radians())?;
    let (ev, rk) = both(&gear, x0, &a, &opts)?;
    print(&a, [p.theta, p.phi], ev, rk)
}

/// The point classified with the event-driven method and, with --rk4, the paper's RK4.
fn both<S: DrivenOscillator>(
    sys: &S,
    x0: [f64; 2],
    a: &Args,
    opts: &ClassifyOptions,
) -> Result<(PointResult, Option<PointResult>)>
where
    EventDriven: FlowMethod<S>,
    FixedStep: FlowMethod<S>,
{
    let ev = if a.dp5 {
        classify_point(sys, x0, &EventDriven, opts)?
    } else {
        classify_point(sys, x0, &DEFAULT_METHOD, opts)?
    };
    let rk = if a.rk4 {
        let o = ClassifyOptions {
            rigorous: false,
            ..opts.clone()
        };
        Some(classify_point(sys, x0, &FixedStep::default(), &o)?)
    } else {
        None
    };
    Ok((ev, rk))
}

/// Prints the classification of a gear with shaft angles `shafts` = (Θ, Φ) [rad].
fn print(a: &Args, shafts: [f64; 2], ev: PointResult, rk: Option<PointResult>) -> Result<()> {
    let out = Out {
        theta_deg: shafts[0].to_degrees(),
        f_hz: a.f,
        event_driven: ev,
        rk4_t50: rk,
    };
    Output { json: a.json }.emit_tagged("gearbif.classify/1", &out, || {
        let mut s = format!(
            "Θ = {:.3}°, Φ = {:.3}°, f = {} Hz, start α = {}°, β = {}° ({}), {} + {} turns\n",
            shafts[0].to_degrees(),
            shafts[1].to_degrees(),
            a.f,
            a.alpha0_deg,
            a.beta0_deg,
            a.gear.convention(),
            a.settle,
            a.record
        );
        s += &describe("event-driven (exact)", &out.event_driven);
        if let Some(r) = &out.rk4_t50 {
            s += &describe("fixed-step RK4, T/50 (paper)", r);
        }
        s
    })
}
