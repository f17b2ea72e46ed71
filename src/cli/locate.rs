//! `gearbif locate`: refine one special point by Newton on the augmented system, with an error
//! estimate from a second solve at a tenfold tighter integrator tolerance.

use super::common::{check_frequency, count, tolerance, GearArgs, Output};
use super::continue_::{check_winding, parse_section, parse_state};
use super::model_arg::ModelArgs;
use crate::analysis::uncertainty::{located_sigma, LocatedSigma};
use crate::continuation::two_param::{locate_augmented_with, CurvePoint};
use crate::continuation::SpecialKind;
use crate::error::{Error, Result};
use crate::integrator::{EventDriven, FlowMethod, DEFAULT_METHOD};
use crate::maps::Section;
use crate::model::recorded::RecordedParam;
use crate::model::{GearParam, Parameter, Parametrised};
use crate::orbits::{OrbitSpec, ShootingOptions};
use serde::Serialize;

/// Arguments of `gearbif locate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    #[command(flatten)]
    model: ModelArgs,
    /// Drive frequency f [Hz], in [1e-3, 1e4] (the guess when --param f).
    #[arg(long)]
    f: f64,
    /// Type: fold, flip, sb (symmetry-breaking) or ns (Neimark–Sacker).
    #[arg(long)]
    kind: String,
    /// The parameter solved for (f, theta, delta, zeta, eta, g; with --model any parameter of
    /// the recorded gear with a column, docs/recorded_gear.md).
    #[arg(long, default_value = "f")]
    param: String,
    /// Guess of the state "BETA,OMEGA": β [rad], ω [rad/s] (physical convention; |β| <= 2π,
    /// |ω| <= 1e6).
    #[arg(
        long = "state-rad",
        value_name = "BETA_RAD,OMEGA",
        allow_hyphen_values = true
    )]
    state: String,
    /// Orbit problem: sym (G) or strob (P_T^k).
    #[arg(long, default_value = "sym")]
    section: String,
    /// Winding, |p| <= 1000.
    #[arg(long, allow_hyphen_values = true, default_value_t = 1)]
    winding: i32,
    /// Period k (strob), 1 to 1000.
    #[arg(long, default_value_t = 1)]
    period: usize,
    /// Integrator tolerance, in (0, 1).
    #[arg(long, default_value_t = 1e-11)]
    tol: f64,
    /// Use the event-driven DP5 instead of the default event-driven DOP853.
    #[arg(long)]
    dp5: bool,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct Located {
    kind: SpecialKind,
    param: &'static str,
    point: CurvePoint,
    /// |λ(tol) − λ(tol/10)|: the error estimate from the integrator tolerance.
    tolerance_error: f64,
    /// Total error estimate: Newton's last correction plus the tolerance error.
    error_estimate: f64,
    /// Wall time of the two solves, s.
    wall_time_s: f64,
    /// σ of the located parameter from the model file's covariance (--model only).
    #[serde(skip_serializing_if = "Option::is_none")]
    sigma: Option<Sigma>,
    /// The sentence when a located frequency lies far outside the model file's recorded drive
    /// frequencies (--model only).
    #[serde(skip_serializing_if = "Option::is_none")]
    outside_recorded: Option<String>,
}

/// [`LocatedSigma`] and the wall time it took.
#[derive(Debug, Serialize)]
struct Sigma {
    #[serde(flatten)]
    value: LocatedSigma,
    /// Wall time of σ (three linearisations of the map per group of parameters), s.
    wall_time_s: f64,
}

pub(crate) fn parse_kind(s: &str) -> Result<SpecialKind> {
    Ok(match s {
        "fold" => SpecialKind::Fold,
        "flip" => SpecialKind::Flip,
        "sb" | "symmetry-breaking" => SpecialKind::SymmetryBreaking,
        "ns" => SpecialKind::NeimarkSacker,
        _ => return Err(Error::unknown_name("kind", s, ["fold", "flip", "sb", "ns"])),
    })
}

/// The point located at tolerance `tol` from `start` (state, parameter), then refined at `tol`/10
/// from there (so both solves refine the same point), with `method`.
fn locate_twice<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    gear: &S,
    spec: &OrbitSpec,
    kind: SpecialKind,
    param: S::Param,
    start: ([f64; 2], f64),
    tol: f64,
) -> Result<(CurvePoint, CurvePoint)> {
    let o1 = ShootingOptions {
        tol,
        ..Default::default()
    };
    let o2 = ShootingOptions {
        tol: tol * 0.1,
        ..Default::default()
    };
    let p1 = locate_augmented_with(method, gear, spec, kind, param, start.0, start.1, &o1)?;
    let p2 = locate_augmented_with(method, gear, spec, kind, param, p1.x, p1.free, &o2)?;
    Ok((p1, p2))
}

/// Runs `gearbif locate`.
pub fn run(a: Args) -> Result<()> {
    check_frequency(a.f)?;
    tolerance("tol", a.tol)?;
    check_winding(a.winding)?;
    count("period", a.period, 1, 1000)?;
    let kind = parse_kind(&a.kind)?;
    let spec = match parse_section(&a.section)? {
        Section::HalfPeriod => OrbitSpec::symmetric(a.winding),
        Section::Stroboscopic => OrbitSpec::stroboscopic(a.period, a.winding),
    };
    let x = parse_state(&a.state)?;
    if let Some(file) = a.model.file(&a.gear)? {
        let param = RecordedParam::from_name(&a.param)?;
        let m = file.model(a.f)?.with_column(param)?;
        let mut out = locate(&a, &m, &spec, kind, param, x)?;
        let clock = std::time::Instant::now();
        let opts = ShootingOptions {
            tol: a.tol,
            ..Default::default()
        };
        let cov = &file.covariance;
        let value = if a.dp5 {
            located_sigma(
                &EventDriven,
                &m,
                cov,
                &spec,
                kind,
                (param, None),
                &out.point,
                &opts,
            )
        } else {
            located_sigma(
                &DEFAULT_METHOD,
                &m,
                cov,
                &spec,
                kind,
                (param, None),
                &out.point,
                &opts,
            )
        }?;
        out.sigma = Some(Sigma {
            value,
            wall_time_s: clock.elapsed().as_secs_f64(),
        });
        let f = if param == RecordedParam::F {
            out.point.free
        } else {
            a.f
        };
        out.outside_recorded = file
            .recorded
            .and_then(|r| r.statement("f", f, file.has_drag()));
        return emit(&a, &out, param.unit());
    }
    let gear = a.gear.params()?.driven(a.f)?;
    let param = GearParam::from_name(&a.param)?;
    let out = locate(&a, &gear, &spec, kind, param, x)?;
    emit(&a, &out, param.unit())
}

/// Locates the point on `sys` from the guess `x` (and the current value of `param`).
fn locate<S: Parametrised>(
    a: &Args,
    sys: &S,
    spec: &OrbitSpec,
    kind: SpecialKind,
    param: S::Param,
    x: [f64; 2],
) -> Result<Located>
where
    EventDriven: FlowMethod<S>,
{
    let clock = std::time::Instant::now();
    let lam0 = sys.param(param);
    let (p1, p2) = if a.dp5 {
        locate_twice(&EventDriven, sys, spec, kind, param, (x, lam0), a.tol)?
    } else {
        locate_twice(&DEFAULT_METHOD, sys, spec, kind, param, (x, lam0), a.tol)?
    };
    let te = (p1.free - p2.free).abs();
    Ok(Located {
        kind,
        param: param.name(),
        error_estimate: te + p2.precision,
        tolerance_error: te,
        point: p2,
        wall_time_s: clock.elapsed().as_secs_f64(),
        sigma: None,
        outside_recorded: None,
    })
}

/// Prints the located point (`unit`: the parameter's).
fn emit(a: &Args, out: &Located, unit: &str) -> Result<()> {
    Output { json: a.json }.emit_tagged("gearbif.locate/1", out, || {
        let p = &out.point;
        let mut s = format!(
            "{} at {} = {:.10} (error estimate {:.1e}: tolerance {:.1e}, Newton {:.1e})\n  x = ({:.9}, {:.9})  μ = {}  events: {}\n",
            out.kind.label(),
            out.param,
            p.free,
            out.error_estimate,
            out.tolerance_error,
            p.precision,
            p.x[0],
            p.x[1],
            multipliers_text(&p.floquet.multipliers),
            p.events
        );
        if let Some(sg) = &out.sigma {
            s.push_str(&sigma_text(out.param, unit, &sg.value));
        }
        if let Some(w) = &out.outside_recorded {
            s.push_str(&format!("  {w}\n"));
        }
        s
    })
}

/// "σ(λ) = … from the covariance of …" with the largest contributions.
fn sigma_text(param: &str, unit: &str, v: &LocatedSigma) -> String {
    let names: Vec<&str> = v.gradient.iter().map(|d| d.name).collect();
    let mut s = format!(
        "  σ({param}) = {:.4e} {unit} (first order, from the model file's covariance of {})\n",
        v.sigma,
        if names.is_empty() {
            "no parameter".to_string()
        } else {
            names.join(", ")
        }
    );
    for d in &v.gradient {
        s.push_str(&format!(
            "    d{param}/d{} = {:.6e}\n",
            d.name, d.derivative
        ));
    }
    if !v.omitted.is_empty() {
        s.push_str(&format!("    not in σ: {}\n", v.omitted.join(", ")));
    }
    s
}

/// Floquet multipliers [[re, im], [re, im]] as "a, b" or "a ± b i" for a complex pair.
fn multipliers_text(mu: &[[f64; 2]; 2]) -> String {
    let one = |m: &[f64; 2]| {
        if m[1] == 0.0 {
            format!("{:.6}", m[0])
        } else {
            format!(
                "{:.6} {} {:.6}i",
                m[0],
                if m[1] < 0.0 { "−" } else { "+" },
                m[1].abs()
            )
        }
    };
    format!("{}, {}", one(&mu[0]), one(&mu[1]))
}
