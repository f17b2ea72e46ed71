//! `gearbif diagram`: the whole bifurcation diagram over a parameter range, automatically (seeds
//! from simulations and analytic branches, continuation, switching at every flip and
//! symmetry-breaking point, branches recognised modulo symmetry, lift and map).

use super::common::{check_frequency, count, frequency, limits, Output};
use super::continue_::BranchArgs;
use crate::continuation::diagram::{diagram, lock_seeds, AnalyticSeed, Diagram, DiagramOptions};
use crate::continuation::multiple_shooting::MultipleShootingOptions;
use crate::continuation::ContinuationOptions;
use crate::error::{Error, Result};
use crate::model::recorded::RecordedParam;
use crate::model::{GearParam, Parameter, Parametrised};
use crate::orbits::ShootingOptions;

/// Arguments of `gearbif diagram`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    common: BranchArgs,
    /// Drive frequency [Hz] when the parameter is not f.
    #[arg(long, default_value_t = 2.0)]
    f: f64,
    /// Number of parameter values where attractors are sought by simulation.
    #[arg(long, default_value_t = 6)]
    grid: usize,
    /// Largest period (in drive periods) followed through period doublings.
    #[arg(long, default_value_t = 16)]
    max_period: usize,
    /// Drive periods of relaxation of each simulation seed.
    #[arg(long, default_value_t = 300)]
    relax: usize,
    /// Initial arclength step.
    #[arg(long, default_value_t = 0.01)]
    ds: f64,
    /// Largest arclength step.
    #[arg(long, default_value_t = 0.05)]
    ds_max: f64,
    /// Largest number of steps per continuation run.
    #[arg(long, default_value_t = 600)]
    max_steps: usize,
}

fn summary<S: Parametrised>(d: &Diagram<S>) -> String {
    let mut s = format!(
        "diagram in {} ∈ [{}, {}]: {} continuation runs, {} map evaluations\n",
        d.param.name(),
        d.range.0,
        d.range.1,
        d.branches.len(),
        d.map_evaluations
    );
    let mut pts: Vec<_> = d
        .special_points
        .iter()
        .enumerate()
        .filter(|(_, p)| p.same_as.is_none())
        .collect();
    pts.sort_by(|a, b| a.1.point.param.total_cmp(&b.1.point.param));
    s.push_str("special points (distinct):\n");
    for (i, p) in pts {
        let b = &d.branches[p.branch].branch;
        let extra = match (&p.criticality, &p.point.jump) {
            (Some(c), _) => format!(" {c}"),
            (None, Some(j)) => format!(
                " {:?} → {:?}{}",
                j.events_before.signature(),
                j.events_after.signature(),
                j.crosses
                    .as_ref()
                    .map(|c| format!(", multiplier jumps across ({c})"))
                    .unwrap_or_default()
            ),
            _ => String::new(),
        };
        s.push_str(&format!(
            "  [{i:>2}] {:<18} {} = {:.9} ± {:.1e}  on {} k = {} p = {:+}{extra}\n",
            p.point.kind.label(),
            d.param.name(),
            p.point.param,
            p.point.precision,
            b.spec.section,
            b.spec.iterations,
            b.spec.winding,
        ));
    }
    s.push_str("runs:\n");
    for (i, b) in d.branches.iter().enumerate() {
        let (lo, hi) = b.branch.param_range().unwrap_or((f64::NAN, f64::NAN));
        s.push_str(&format!(
            "  [{i:>2}] {} k = {} p = {:+} {} points, {} ∈ [{lo:.6}, {hi:.6}], from {}, stop: {}\n",
            b.branch.spec.section,
            b.branch.spec.iterations,
            b.branch.spec.winding,
            b.branch.points.len(),
            d.param.name(),
            b.origin,
            b.branch.stop
        ));
    }
    s
}

/// The domain checks of `diagram`, all before any orbit is computed.
fn check_args(a: &Args) -> Result<()> {
    BranchArgs::check_steps(a.ds, a.ds_max, a.max_steps)?;
    if a.ds < 0.0 {
        return Err(Error::option(
            "--ds",
            format!("{} must be > 0 (the diagram continues both ways)", a.ds),
        ));
    }
    count("grid", a.grid, 1, 1000)?;
    count("max-period", a.max_period, 1, 64)?;
    count("relax", a.relax, 1, limits::TURNS_MAX)?;
    Ok(())
}

/// Runs `gearbif diagram`.
pub fn run(a: Args) -> Result<()> {
    if a.common.model.model.is_some() {
        // the frequency first, as without --model: f is the range's midpoint when it is the
        // parameter
        let is_f = a.common.param == RecordedParam::F.name();
        let f = if is_f {
            let (lo, hi) = super::continue_::parse_range(&a.common.range)?;
            frequency("f", lo)?;
            frequency("f", hi)?;
            0.5 * (lo + hi)
        } else {
            a.f
        };
        check_frequency(f)?;
        let m = a
            .common
            .model
            .recorded(&a.common.gear, f)?
            .ok_or_else(|| Error::option("--model", "missing"))?;
        let (m, param, range) = a.common.parse_recorded(m)?;
        check_args(&a)?;
        let files = crate::io::StagedFiles::begin(&a.common.plan())?;
        // no analytic seeds: the lock branch in closed form is the paper's gear's
        return draw(&a, files, &m, param, range, Vec::new());
    }
    let (param, (lo, hi)) = a.common.parse()?;
    let f = if param == GearParam::F {
        frequency("f", lo)?;
        frequency("f", hi)?;
        0.5 * (lo + hi)
    } else {
        a.f
    };
    check_frequency(f)?;
    check_args(&a)?;
    let files = crate::io::StagedFiles::begin(&a.common.plan())?;
    let gear = a.common.gear.params()?.driven(f)?;
    let seeds = lock_seeds(&gear, &shooting(&a));
    draw(&a, files, &gear, param, (lo, hi), seeds)
}

fn shooting(a: &Args) -> ShootingOptions {
    ShootingOptions {
        tol: a.common.tol,
        ..Default::default()
    }
}

/// The diagram of `sys` in `param` over `lo..hi` from the simulations and the `seeds`: written,
/// drawn and printed.
fn draw<S: Parametrised + serde::Serialize>(
    a: &Args,
    files: crate::io::StagedFiles,
    sys: &S,
    param: S::Param,
    (lo, hi): (f64, f64),
    seeds: Vec<AnalyticSeed<S>>,
) -> Result<()> {
    let opts = DiagramOptions {
        grid: a.grid,
        max_period: a.max_period,
        relax_periods: a.relax,
        continuation: ContinuationOptions {
            ds: a.ds,
            ds_max: a.ds_max,
            max_steps: a.max_steps,
            shooting: shooting(a),
            ..Default::default()
        },
        multiple_shooting: Some(MultipleShootingOptions::default()),
        ..DiagramOptions::new(param, (lo, hi))
    };
    opts.continuation.validate()?;
    let d = diagram(sys, &opts, seeds)?;
    if let Some(p) = &a.common.out {
        crate::io::write_json_atomic(
            files.path(p),
            &crate::io::with_schema("gearbif.diagram/1", &d),
        )?;
    }
    let branches: Vec<_> = d.branches.iter().map(|b| b.branch.clone()).collect();
    a.common.save_plot(
        &files,
        format!(
            "bifurcation diagram in {} (automatic, {} runs)",
            param.name(),
            d.branches.len()
        ),
        &branches,
    )?;
    files.commit()?;
    Output {
        json: a.common.json,
    }
    .emit_tagged("gearbif.diagram/1", &d, || summary(&d))
}
