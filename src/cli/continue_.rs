//! `gearbif continue`: pseudo-arclength continuation of a periodic orbit in one parameter.

use super::common::{
    check_frequency, count, limits, output_file, start_state, tolerance, within, GearArgs, Output,
};
use super::model_arg::ModelArgs;
use crate::continuation::multiple_shooting::{continue_branch, MultipleShootingOptions};
use crate::continuation::pinned::switch_at;
use crate::continuation::{Branch, Continuation, ContinuationOptions};
use crate::error::{Error, Result};
use crate::io::{FileKind, StagedFiles};
use crate::maps::Section;
use crate::model::recorded::{RecordedModel, RecordedParam};
use crate::model::{Gear, GearParam, Parameter, Parametrised};
use crate::orbits::{orbit_from_simulation, shoot, OrbitSpec, ShootingOptions};

/// The arguments `continue` and `diagram` share: the gear, the parameter and its range, the
/// integrator tolerance and the outputs.
#[derive(Debug, clap::Args)]
pub struct BranchArgs {
    #[command(flatten)]
    pub gear: GearArgs,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Continuation parameter: f [Hz], theta (parallel shafts) [deg], delta [1], zeta [1/s],
    /// eta [1/s²] or g [1/s²]; with --model any parameter of the recorded gear with a column
    /// (docs/recorded_gear.md).
    #[arg(long, default_value = "f")]
    pub param: String,
    /// Parameter range `lo:hi` in the parameter's unit (finite, lo < hi, both in the parameter's
    /// domain: f in [1e-3, 1e4] Hz, theta within ±360°, zeta, eta, g >= 0); the continuation
    /// stops on its bounds.
    #[arg(long, allow_hyphen_values = true)]
    pub range: String,
    /// Integrator tolerance, in (0, 1).
    #[arg(long, default_value_t = 1e-11)]
    pub tol: f64,
    /// Write the result (JSON) to this file.
    #[arg(long)]
    pub out: Option<std::path::PathBuf>,
    /// Branch diagram (.svg or .png).
    #[arg(long)]
    pub plot: Option<std::path::PathBuf>,
    /// Print JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

impl BranchArgs {
    /// The parameter and its range; checks the tolerance and the output files.
    pub fn parse(&self) -> Result<(GearParam, (f64, f64))> {
        let param = GearParam::from_name(&self.param)?;
        let range = parse_range(&self.range)?;
        super::common::param_value(param, range.0)?;
        super::common::param_value(param, range.1)?;
        self.check_files()?;
        Ok((param, range))
    }

    /// The parameter of the recorded gear `m` and its range (both ends in the lens's domain);
    /// checks the tolerance and the output files. Returns `m` with the parameter's column.
    pub fn parse_recorded(
        &self,
        m: RecordedModel,
    ) -> Result<(RecordedModel, RecordedParam, (f64, f64))> {
        let param = RecordedParam::from_name(&self.param)?;
        let m = m.with_column(param)?;
        let range = parse_range(&self.range)?;
        m.with_param(param, range.0)?;
        m.with_param(param, range.1)?;
        self.check_files()?;
        Ok((m, param, range))
    }

    /// Checks the tolerance and the output files.
    fn check_files(&self) -> Result<()> {
        tolerance("tol", self.tol)?;
        if let Some(p) = &self.out {
            output_file("--out", p, false)?;
        }
        if let Some(p) = &self.plot {
            output_file("--plot", p, true)?;
        }
        Ok(())
    }

    /// Checks the continuation steps: 0 < |ds| <= ds_max (finite), 1 <= max_steps.
    pub fn check_steps(ds: f64, ds_max: f64, max_steps: usize) -> Result<()> {
        within("ds-max", ds_max, f64::MIN_POSITIVE, f64::MAX, "must be > 0")?;
        if ds == 0.0 || !ds.is_finite() || ds.abs() > ds_max {
            return Err(Error::inconsistent(
                "--ds, --ds-max",
                format!("--ds = {ds} must be finite, nonzero and at most --ds-max = {ds_max}"),
            ));
        }
        count("max-steps", max_steps, 1, limits::TURNS_MAX)?;
        Ok(())
    }

    /// The output files of --out and --plot, for [`StagedFiles::begin`].
    pub fn plan(&self) -> Vec<(&'static str, &std::path::Path, FileKind)> {
        let mut v = Vec::new();
        if let Some(p) = &self.out {
            v.push(("--out", p.as_path(), FileKind::Data));
        }
        if let Some(p) = &self.plot {
            v.push(("--plot", p.as_path(), FileKind::Figure));
        }
        v
    }

    /// Draws `branches` to --plot (its staged file in `files`), if given.
    pub fn save_plot<S: Parametrised>(
        &self,
        files: &StagedFiles,
        title: String,
        branches: &[Branch<S>],
    ) -> Result<()> {
        let Some(p) = &self.plot else { return Ok(()) };
        let fig = crate::plotting::branch::BranchDiagram {
            title,
            branches: branches.to_vec(),
            paper_convention: self.gear.convention() == crate::model::Convention::Paper,
            ..Default::default()
        };
        crate::plotting::save(&fig, files.path(p))
    }
}

/// Arguments of `gearbif continue`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    common: BranchArgs,
    /// Drive frequency f [Hz] of the start orbit, in [1e-3, 1e4].
    #[arg(long)]
    f: f64,
    /// Initial direction: up or down in the parameter.
    #[arg(long, default_value = "up")]
    direction: String,
    /// Start state "BETA,OMEGA": β [rad], ω [rad/s] (physical convention; |β| <= 2π,
    /// |ω| <= 1e6), as in the `x` of the JSON outputs; default: from a simulation (relaxed, period
    /// and winding detected), or the analytic lock with --lock.
    #[arg(
        long = "state-rad",
        value_name = "BETA_RAD,OMEGA",
        allow_hyphen_values = true
    )]
    state: Option<String>,
    /// Start from the analytic lock branch (Δ = ±1 only): stable or unstable.
    #[arg(long)]
    lock: Option<String>,
    /// Orbit problem: `sym` (half-period map G, symmetric orbits) or `strob` (P_T^k).
    #[arg(long, default_value = "sym")]
    section: String,
    /// Winding p (per period for sym, over k periods for strob), |p| <= 1000; default: detected
    /// or ±1.
    #[arg(long, allow_hyphen_values = true)]
    winding: Option<i32>,
    /// Period k of the P_T^k problem, 1 to 1000.
    #[arg(long, default_value_t = 1)]
    period: usize,
    /// Initial step (arclength), finite and nonzero, |ds| <= ds-max.
    #[arg(long, default_value_t = 0.02)]
    ds: f64,
    /// Largest step, finite and > 0.
    #[arg(long, default_value_t = 0.1)]
    ds_max: f64,
    /// Largest number of steps, 1 to 1000000.
    #[arg(long, default_value_t = 2000)]
    max_steps: usize,
    /// Single shooting is trusted up to this multiplier modulus (finite, > 1); beyond it the branch
    /// is continued by multiple shooting (or stops, with --no-multiple-shooting).
    #[arg(long, default_value_t = 1e4)]
    max_multiplier: f64,
    /// Stop at --max-multiplier instead of switching to multiple shooting.
    #[arg(long)]
    no_multiple_shooting: bool,
    /// After the continuation, switch at special point number N (flip or symmetry-breaking) and
    /// continue the new branch too, on the side of the point where it exists (away from the point).
    #[arg(long)]
    switch_at: Option<usize>,
    /// Multipliers in the complex plane (.svg or .png).
    #[arg(long)]
    plot_multipliers: Option<std::path::PathBuf>,
}

/// Schema id of the branch document written by `--json` and `--out`.
pub const BRANCHES_SCHEMA: &str = "gearbif.branches/1";

/// Parses `lo:hi`.
pub(crate) fn parse_range(s: &str) -> Result<(f64, f64)> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| Error::option(format!("range `{s}`"), "expected lo:hi"))?;
    let p = |x: &str| {
        x.trim()
            .parse::<f64>()
            .map_err(|_| Error::option(format!("range `{s}`"), format!("`{x}` is not a number")))
    };
    let (lo, hi) = (p(a)?, p(b)?);
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(Error::option(
            format!("range `{s}`"),
            "must be finite numbers with lo < hi",
        ));
    }
    Ok((lo, hi))
}

/// Parses `beta,omega`.
pub(crate) fn parse_state(s: &str) -> Result<[f64; 2]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| Error::option(format!("state `{s}`"), "expected BETA_RAD,OMEGA"))?;
    if v.len() != 2 {
        return Err(Error::option(
            format!("state `{s}`"),
            "expected two numbers BETA_RAD,OMEGA",
        ));
    }
    crate::error::finite_state("state (β [rad], ω [rad/s])", &v)?;
    start_state("state", v[0], v[1], false)?;
    Ok([v[0], v[1]])
}

pub(crate) fn parse_section(s: &str) -> Result<Section> {
    match s {
        "sym" | "half" | "G" => Ok(Section::HalfPeriod),
        "strob" | "P" => Ok(Section::Stroboscopic),
        _ => Err(Error::unknown_name("section", s, ["sym", "strob"])),
    }
}

/// The analytic lock orbit of `--lock` on the paper's gear: its state and winding.
fn lock_start(a: &Args, gear: &Gear) -> Result<Option<([f64; 2], i32)>> {
    let Some(which) = &a.lock else {
        return Ok(None);
    };
    let lb = gear.lock_branch()?;
    let pt = match which.as_str() {
        "stable" => lb.stable,
        "unstable" => lb.unstable,
        l => return Err(Error::unknown_name("--lock", l, ["stable", "unstable"])),
    };
    Ok(Some((pt.state, pt.winding * a.period as i32)))
}

/// The start orbit: the lock orbit `lock` (state, winding), --state-rad, or a simulation.
fn start_orbit<S: Parametrised>(
    a: &Args,
    sys: &S,
    lock: Option<([f64; 2], i32)>,
    shooting: &ShootingOptions,
) -> Result<crate::orbits::PeriodicOrbit> {
    let section = parse_section(&a.section)?;
    let mk_spec = |p: i32| match section {
        Section::HalfPeriod => OrbitSpec::symmetric(p),
        Section::Stroboscopic => OrbitSpec::stroboscopic(a.period, p),
    };
    if let Some((x, winding)) = lock {
        return shoot(sys, &mk_spec(a.winding.unwrap_or(winding)), x, shooting);
    }
    if let Some(s) = &a.state {
        let x = parse_state(s)?;
        let p = a.winding.ok_or_else(|| {
            Error::inconsistent("--state-rad, --winding", "--state-rad needs --winding")
        })?;
        return shoot(sys, &mk_spec(p), x, shooting);
    }
    let o = orbit_from_simulation(
        sys,
        [0.0, 0.0],
        400,
        8,
        section == Section::HalfPeriod,
        shooting,
    )?;
    Ok(o)
}

fn summary<S: Parametrised>(b: &Branch<S>) -> String {
    let mut s = String::new();
    let (lo, hi) = b.param_range().unwrap_or((f64::NAN, f64::NAN));
    s.push_str(&format!(
        "branch in {} ({}, k = {}, p = {}): {} points, {} ∈ [{lo:.6}, {hi:.6}], {} map evaluations, stop: {}\n",
        b.param.name(),
        b.spec.section,
        b.spec.iterations,
        b.spec.winding,
        b.points.len(),
        b.param.name(),
        b.map_evaluations,
        b.stop
    ));
    if let Some(i) = b.multiple_shooting_from {
        s.push_str(&format!(
            "  multiple shooting from point {i} ({} = {:.6}) on\n",
            b.param.name(),
            b.points.get(i).map(|p| p.param).unwrap_or(f64::NAN)
        ));
    }
    for (i, sp) in b.specials.iter().enumerate() {
        let mu = sp.floquet.multipliers;
        s.push_str(&format!(
            "  [{i}] {:<18} {} = {:.9} ± {:.1e}   x = ({:.6}, {:.6})   μ = ({:.6}{:+.6}i, {:.6}{:+.6}i){}\n",
            sp.kind.label(),
            b.param.name(),
            sp.param,
            sp.precision,
            sp.x[0],
            sp.x[1],
            mu[0][0],
            mu[0][1],
            mu[1][0],
            mu[1][1],
            sp.jump
                .as_ref()
                .map(|j| format!(
                    "   events (crossings, sticks) {:?} → {:?}",
                    j.events_before.signature(),
                    j.events_after.signature()
                ))
                .unwrap_or_default()
        ));
    }
    s
}

/// Runs `gearbif continue`.
pub fn run(a: Args) -> Result<()> {
    check_frequency(a.f)?;
    if let Some(m) = a.common.model.recorded(&a.common.gear, a.f)? {
        let (m, param, range) = a.common.parse_recorded(m)?;
        check_args(&a)?;
        if a.lock.is_some() {
            return Err(Error::inconsistent(
                "--model, --lock",
                "the analytic lock branch is the paper's gear's: start from --state-rad with \
                 --winding, or from a simulation",
            ));
        }
        return continue_on(&a, m, param, range, None);
    }
    let params = a.common.gear.params()?;
    let gear = params.driven(a.f)?;
    let (param, range) = a.common.parse()?;
    check_args(&a)?;
    let lock = lock_start(&a, &gear)?;
    continue_on(&a, gear, param, range, lock)
}

/// Continues from the start orbit of `sys` (the lock orbit `lock`, --state-rad or a simulation)
/// in `param` over `lo..hi`, switches if asked, writes and prints the branches.
fn continue_on<S: Parametrised + serde::Serialize>(
    a: &Args,
    sys: S,
    param: S::Param,
    (lo, hi): (f64, f64),
    lock: Option<([f64; 2], i32)>,
) -> Result<()> {
    let sign = match a.direction.as_str() {
        "up" => 1.0,
        "down" => -1.0,
        d => return Err(Error::unknown_name("--direction", d, ["up", "down"])),
    };
    let mut plan = a.common.plan();
    if let Some(p) = &a.plot_multipliers {
        plan.push(("--plot-multipliers", p.as_path(), FileKind::Figure));
    }
    let files = StagedFiles::begin(&plan)?;
    let shooting = ShootingOptions {
        tol: a.common.tol,
        ..Default::default()
    };
    let orbit = start_orbit(a, &sys, lock, &shooting)?;
    let opts = ContinuationOptions {
        ds: sign * a.ds.abs(),
        ds_max: a.ds_max,
        max_steps: a.max_steps,
        param_min: lo,
        param_max: hi,
        max_multiplier: a.max_multiplier,
        shooting,
        ..Default::default()
    };
    let ms = (!a.no_multiple_shooting).then(MultipleShootingOptions::default);
    let branch = continue_branch(
        Continuation::from_orbit(sys, param, &orbit, opts)?,
        &opts,
        ms.as_ref(),
        None,
    )?;
    let mut branches = vec![branch];
    if let Some(n) = a.switch_at {
        let b1 = switch_and_continue(a, &branches[0], n, &opts, ms.as_ref())?;
        branches.push(b1);
    }
    emit(a, files, param, &branches)
}

/// Switches at special point `n` of `b0` and continues the new branch away from the point.
fn switch_and_continue<S: Parametrised>(
    a: &Args,
    b0: &Branch<S>,
    n: usize,
    opts: &ContinuationOptions,
    ms: Option<&MultipleShootingOptions>,
) -> Result<Branch<S>> {
    let sp = b0.specials.get(n).ok_or_else(|| {
        Error::shape(
            "--switch-at: index of a special point",
            format!("< {} (the special points of the branch)", b0.specials.len()),
            n,
        )
    })?;
    // pinned switching: the new orbit is found at a fixed distance from the bifurcating one,
    // with the parameter free, so it lands on the side where the new branch exists; the new
    // branch is continued away from the point
    let (sys1, orbit1) = switch_at(b0, sp, 1e-2, &opts.shooting)?;
    let side = (sys1.param(b0.param) - sp.param).signum();
    let o1 = ContinuationOptions {
        ds: side * 0.25 * a.ds.abs(),
        ..*opts
    };
    continue_branch(
        Continuation::from_orbit(sys1, b0.param, &orbit1, o1)?,
        &o1,
        ms,
        None,
    )
}

/// Writes --out, the plots, and prints the branches.
fn emit<S: Parametrised + serde::Serialize>(
    a: &Args,
    files: StagedFiles,
    param: S::Param,
    branches: &[Branch<S>],
) -> Result<()> {
    // one document for --out and --json: {"schema": "gearbif.branches/1", "branches": [...]}
    let tagged = serde_json::json!({ "schema": BRANCHES_SCHEMA, "branches": branches });
    if let Some(p) = &a.common.out {
        crate::io::write_json_atomic(files.path(p), &tagged)?;
    }
    let what = match branches {
        [one] => crate::plotting::branch::branch_label(one),
        many => format!("{} branches", many.len()),
    };
    a.common.save_plot(
        &files,
        format!("continuation in {}: {what}", param.name()),
        branches,
    )?;
    if let Some(p) = &a.plot_multipliers {
        let fig = crate::plotting::branch::MultiplierPlot {
            title: format!(
                "multipliers along the {} branch",
                crate::plotting::branch::branch_label(&branches[0])
            ),
            branch: Some(branches[0].clone()),
        };
        crate::plotting::save(&fig, files.path(p))?;
    }
    files.commit()?;
    Output {
        json: a.common.json,
    }
    .emit(&tagged, || {
        branches.iter().map(summary).collect::<Vec<_>>().join("")
    })
}

/// The domain checks of `continue`, all before any orbit is computed.
fn check_args(a: &Args) -> Result<()> {
    BranchArgs::check_steps(a.ds, a.ds_max, a.max_steps)?;
    count("period", a.period, 1, 1000)?;
    within(
        "max-multiplier",
        a.max_multiplier,
        1.0 + f64::EPSILON,
        f64::MAX,
        "must be finite and > 1",
    )?;
    if let Some(p) = a.winding {
        check_winding(p)?;
    }
    if let Some(l) = a.lock.as_deref() {
        if !matches!(l, "stable" | "unstable") {
            return Err(Error::unknown_name("--lock", l, ["stable", "unstable"]));
        }
    }
    parse_section(&a.section)?;
    if let Some(s) = &a.state {
        parse_state(s)?;
    }
    if let Some(p) = &a.plot_multipliers {
        output_file("--plot-multipliers", p, true)?;
    }
    Ok(())
}

/// Checks a winding number: |p| <= 1000.
pub(crate) fn check_winding(p: i32) -> Result<i32> {
    if p.unsigned_abs() <= 1000 {
        Ok(p)
    } else {
        Err(Error::option(
            "--winding",
            format!("{p} must be in -1000..=1000"),
        ))
    }
}
