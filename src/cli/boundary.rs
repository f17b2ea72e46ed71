//! `gearbif boundary`: a two-parameter curve of special points, by default the lock-loss boundary
//! f_c(Θ) of the locked orbit over Θ ∈ [0°, 54.74°] (both senses of rotation).

use super::common::{limits, output_file, tolerance, GearArgs, Output};
use super::continue_::{check_winding, parse_range, parse_section, parse_state};
use super::locate::parse_kind;
use super::model_arg::ModelArgs;
use crate::analysis::uncertainty::{located_sigma, LocatedSigma};
use crate::continuation::palc2::{continue_curve, lock_loss_curves, CurveOptions};
use crate::continuation::two_param::{follow, grid, Curve};
use crate::continuation::SpecialKind;
use crate::error::{Error, Result};
use crate::integrator::DEFAULT_METHOD;
use crate::io::{FileKind, StagedFiles};
use crate::maps::Section;
use crate::model::recorded::file::ModelFile;
use crate::model::recorded::RecordedParam;
use crate::model::{GearParam, Parameter, Parametrised};
use crate::orbits::{OrbitSpec, ShootingOptions};

/// Arguments of `gearbif boundary`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    #[command(flatten)]
    model: ModelArgs,
    /// Type of the special point followed: fold, flip, sb or ns.
    #[arg(long, default_value = "fold")]
    kind: String,
    /// The parameter solved for.
    #[arg(long, default_value = "f")]
    free: String,
    /// The parameter stepped (theta for parallel shafts; with --model a parameter of the
    /// recorded gear, whose set-up fixes Θ).
    #[arg(long, default_value = "theta")]
    along: String,
    /// Range `lo:hi` of the stepped parameter (finite, lo < hi; default 0:54.7356 for theta).
    #[arg(long, allow_hyphen_values = true)]
    range: Option<String>,
    /// Step of the stepped parameter (finite, > 0, at most 100000 steps over the range).
    #[arg(long, default_value_t = 1.0)]
    step: f64,
    /// Start: free-parameter value, state and winding at the first value of the range (default: the
    /// analytic lock fold at Θ = 0 and at 54.74°, i.e. the lock-loss boundary).
    #[arg(long)]
    start_free: Option<f64>,
    /// Start state "BETA,OMEGA": β [rad], ω [rad/s] (physical convention; |β| <= 2π, |ω| <= 1e6).
    #[arg(
        long = "start-state-rad",
        value_name = "BETA_RAD,OMEGA",
        allow_hyphen_values = true
    )]
    start_state: Option<String>,
    /// Step the range downwards (from hi to lo); the start is then at hi.
    #[arg(long)]
    reverse: bool,
    /// Winding of the orbit, |p| <= 1000.
    #[arg(long, allow_hyphen_values = true, default_value_t = 1)]
    winding: i32,
    /// Orbit problem: sym or strob.
    #[arg(long, default_value = "sym")]
    section: String,
    /// Integrator tolerance, in (0, 1).
    #[arg(long, default_value_t = 1e-11)]
    tol: f64,
    /// Write the curves (JSON).
    #[arg(long)]
    out: Option<std::path::PathBuf>,
    /// Plot (.svg or .png).
    #[arg(long)]
    plot: Option<std::path::PathBuf>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
    /// Continuation method: palc (pseudo-arclength in both parameters, passes turning points and
    /// locates codimension-two points; `--step` is the largest arclength step) or natural (steps of
    /// `--step` in the stepped parameter, stops at turning points).
    #[arg(long, default_value = "palc")]
    method: String,
}

/// Runs `gearbif boundary`.
pub fn run(a: Args) -> Result<()> {
    if let Some(file) = a.model.file(&a.gear)? {
        return run_recorded(&a, &file);
    }
    let params = a.gear.params()?;
    let base = params.driven(1.0)?;
    let kind = parse_kind(&a.kind)?;
    let free = GearParam::from_name(&a.free)?;
    let along = GearParam::from_name(&a.along)?;
    check_args(&a)?;
    let files = output_plan(&a)?;
    let copts = curve_options(&a, free == GearParam::F)?;
    let curves = if a.start_state.is_none()
        && kind == SpecialKind::Fold
        && along == GearParam::ThetaDeg
        && free == GearParam::F
    {
        if a.method == "palc" {
            lock_loss_curves(&base, &copts)?
        } else {
            crate::continuation::two_param::lock_loss_boundary(&base, a.step, &copts.shooting)?
        }
    } else {
        vec![started_curve(&a, &base, kind, (free, along), &copts)?]
    };
    let mut marks = Vec::new();
    if let Some(fc) = base.lock_loss_frequency() {
        marks.push(("analytic f_c at Δ = ±1".to_string(), 0.0, fc));
        marks.push((
            "analytic f_c at Δ = ±1".to_string(),
            crate::model::gear::cogging_free_parallel_angles()
                .2
                .to_degrees(),
            fc,
        ));
    }
    emit(&a, files, kind, &curves, marks, (None, &[]))
}

/// `boundary --model`: the curve from --start-state-rad and --start-free on the recorded gear,
/// each point with its σ from the file's covariance.
fn run_recorded(a: &Args, file: &ModelFile) -> Result<()> {
    let kind = parse_kind(&a.kind)?;
    let free = RecordedParam::from_name(&a.free)?;
    let along = RecordedParam::from_name(&a.along)?;
    check_args(a)?;
    let files = output_plan(a)?;
    let base = file.model(1.0)?.with_column(along)?.with_column(free)?;
    let copts = curve_options(a, free == RecordedParam::F)?;
    let curve = started_curve(a, &base, kind, (free, along), &copts)?;
    let sigma = curve
        .1
        .points
        .iter()
        .map(|p| {
            located_sigma(
                &DEFAULT_METHOD,
                &base,
                &file.covariance,
                &curve.1.spec,
                kind,
                (free, Some(along)),
                p,
                &copts.shooting,
            )
        })
        .collect::<Result<Vec<_>>>()?;
    let notes = outside_notes(file, (free, along), &curve.1.points);
    emit(a, files, kind, &[curve], Vec::new(), (Some(&sigma), &notes))
}

/// The sentence for the point of `points` farthest outside the file's recorded drive
/// frequencies (when f is the free or the stepped parameter and some point lies far outside),
/// with how many points do.
fn outside_notes(
    file: &ModelFile,
    (free, along): (RecordedParam, RecordedParam),
    points: &[crate::continuation::two_param::CurvePoint],
) -> Vec<String> {
    let Some(r) = file.recorded else {
        return Vec::new();
    };
    let f_of = |p: &crate::continuation::two_param::CurvePoint| {
        if free == RecordedParam::F {
            Some(p.free)
        } else if along == RecordedParam::F {
            Some(p.along)
        } else {
            None
        }
    };
    let far: Vec<f64> = points
        .iter()
        .filter_map(f_of)
        .filter(|&f| r.far_outside(f))
        .collect();
    let [lo, hi] = r.drive_hz;
    let dist = |f: f64| (f / hi).max(lo / f);
    far.iter()
        .copied()
        .max_by(|a, b| dist(*a).total_cmp(&dist(*b)))
        .and_then(|f| r.statement("f", f, file.has_drag()))
        .map(|s| {
            format!(
                "{s} ({} of {} points of the curve lie that far out)",
                far.len(),
                points.len()
            )
        })
        .into_iter()
        .collect()
}

/// The output files (--out, --plot), checked and staged before any curve is computed.
fn output_plan(a: &Args) -> Result<StagedFiles> {
    let mut plan = Vec::new();
    if let Some(p) = &a.out {
        plan.push(("--out", p.as_path(), FileKind::Data));
    }
    if let Some(p) = &a.plot {
        plan.push(("--plot", p.as_path(), FileKind::Figure));
    }
    StagedFiles::begin(&plan)
}

/// The options of the curve's continuation (`free_is_f`: the free parameter is a frequency, kept
/// above 1e-3 Hz).
fn curve_options(a: &Args, free_is_f: bool) -> Result<CurveOptions> {
    let (lo, hi) = parse_range(a.range.as_deref().unwrap_or("0:54.7356103"))?;
    Ok(CurveOptions {
        ds: 0.5 * a.step,
        ds_max: a.step,
        max_steps: 2000,
        along_range: (lo, hi),
        free_range: if free_is_f {
            (1e-3, f64::INFINITY)
        } else {
            (f64::NEG_INFINITY, f64::INFINITY)
        },
        shooting: ShootingOptions {
            tol: a.tol,
            ..Default::default()
        },
        ..Default::default()
    })
}

/// The curve of `kind` in (free, along) of `base` from --start-state-rad and --start-free.
fn started_curve<S: Parametrised>(
    a: &Args,
    base: &S,
    kind: SpecialKind,
    (free, along): (S::Param, S::Param),
    copts: &CurveOptions,
) -> Result<(String, Curve<S>)> {
    let x = parse_state(a.start_state.as_deref().ok_or_else(|| {
        Error::inconsistent(
            "--kind, --free, --along, --start-state-rad",
            "--start-state-rad is needed for this curve (only the lock-loss fold of the paper's \
             gear has a built-in start)",
        )
    })?)?;
    let f0 = a.start_free.ok_or_else(|| {
        Error::inconsistent(
            "--start-state-rad, --start-free",
            "--start-free is needed with --start-state-rad",
        )
    })?;
    let spec = match parse_section(&a.section)? {
        Section::HalfPeriod => OrbitSpec::symmetric(a.winding),
        Section::Stroboscopic => OrbitSpec::stroboscopic(1, a.winding),
    };
    let (lo, hi) = copts.along_range;
    let vals = grid(lo, hi, a.step, a.reverse);
    let g = base.with_param(free, f0)?.with_param(along, vals[0])?;
    let c: Curve<S> = if a.method == "palc" {
        let o = CurveOptions {
            ds: if a.reverse { -copts.ds } else { copts.ds },
            ..*copts
        };
        continue_curve(&DEFAULT_METHOD, &g, &spec, kind, free, along, x, f0, &o)?
    } else {
        follow(&g, &spec, kind, free, along, x, f0, &vals, &copts.shooting)?
    };
    Ok((format!("{} curve", kind.label()), c))
}

/// Writes --out and --plot and prints the curves (with the σ of each point of the first curve,
/// if given).
fn emit<S: Parametrised + serde::Serialize>(
    a: &Args,
    files: StagedFiles,
    kind: SpecialKind,
    curves: &[(String, Curve<S>)],
    mut marks: Vec<(String, f64, f64)>,
    (sigma, notes): (Option<&[LocatedSigma]>, &[String]),
) -> Result<()> {
    // one document for --out and --json: {"schema": "gearbif.curves/1", "curves": [[label, curve],
    // ...]} and, with --model, "sigma": the σ of each point of the curve
    let mut tagged = match sigma {
        Some(sg) => {
            serde_json::json!({ "schema": "gearbif.curves/1", "curves": curves, "sigma": sg })
        }
        None => serde_json::json!({ "schema": "gearbif.curves/1", "curves": curves }),
    };
    if !notes.is_empty() {
        tagged["outside_recorded"] = serde_json::json!(notes);
    }
    if let Some(p) = &a.out {
        crate::io::write_json_atomic(files.path(p), &tagged)?;
    }
    if let Some(p) = &a.plot {
        for (_, c) in curves {
            for q in &c.codim2 {
                marks.push((q.kind.label().to_string(), q.along, q.free));
            }
        }
        let fig = crate::plotting::branch::BoundaryPlot {
            title: match kind {
                SpecialKind::Fold => "lock-loss boundary f_c(Θ): fold of the locked orbit".into(),
                k => format!("{} curve", k.label()),
            },
            curves: curves.to_vec(),
            marks,
            ..Default::default()
        };
        crate::plotting::save(&fig, files.path(p))?;
    }
    files.commit()?;
    Output { json: a.json }.emit(&tagged, || {
        let mut s = curves_text(curves, sigma);
        for n in notes {
            s += &format!("{n}\n");
        }
        s
    })
}

/// The curves as text, with "σ …" after each point when `sigma` is given.
fn curves_text<S: Parametrised>(
    curves: &[(String, Curve<S>)],
    sigma: Option<&[LocatedSigma]>,
) -> String {
    let mut s = String::new();
    for (label, c) in curves {
        s.push_str(&format!(
            "{label}: {} points{}\n",
            c.points.len(),
            c.stopped
                .as_ref()
                .map(|r| format!(" (stopped {r})"))
                .unwrap_or_default()
        ));
        for (i, p) in c.points.iter().enumerate() {
            let sg = sigma
                .and_then(|v| v.get(i))
                .map(|v| format!("   σ {:.3e}", v.sigma))
                .unwrap_or_default();
            s.push_str(&format!(
                "  {} = {:9.4}   {} = {:.9} ± {:.1e}   x = ({:.6}, {:.4}){sg}\n",
                c.along.name(),
                p.along,
                c.free.name(),
                p.free,
                p.precision,
                p.x[0],
                p.x[1]
            ));
        }
        for q in &c.codim2 {
            s.push_str(&format!(
                "  {}: {} = {:.7}, {} = {:.9} ± {:.1e}\n",
                q.kind.label(),
                c.along.name(),
                q.along,
                c.free.name(),
                q.free,
                q.precision
            ));
        }
    }
    s
}

/// The domain checks of `boundary`, all before any curve is computed.
fn check_args(a: &Args) -> Result<()> {
    tolerance("tol", a.tol)?;
    if a.method != "palc" && a.method != "natural" {
        return Err(Error::unknown_name(
            "--method",
            a.method.as_str(),
            ["palc", "natural"],
        ));
    }
    check_winding(a.winding)?;
    parse_section(&a.section)?;
    let (lo, hi) = parse_range(a.range.as_deref().unwrap_or("0:54.7356103"))?;
    if !(a.step.is_finite() && a.step > 0.0) || (hi - lo) / a.step > limits::GRID_MAX as f64 {
        return Err(Error::option(
            "--step",
            format!(
                "{} must be finite and > 0 with at most {} steps over {lo}:{hi}",
                a.step,
                limits::GRID_MAX
            ),
        ));
    }
    if let Some(s) = &a.start_state {
        parse_state(s)?;
    }
    if let Some(f) = a.start_free {
        crate::error::finite("start-free", f)?;
    }
    if let Some(p) = &a.out {
        output_file("--out", p, false)?;
    }
    if let Some(p) = &a.plot {
        output_file("--plot", p, true)?;
    }
    Ok(())
}
