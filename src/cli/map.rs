//! `gearbif map`: the stroboscopic map P_T (or the half-period map G) of a state, with its Jacobians
//! in the state and the parameters, and the multipliers.

use super::common::{count, limits, GearArgs, Output};
use super::methods::{DriveArgs, MethodArgs};
use super::model_arg::{start, ModelArgs, SystemInfo};
use crate::error::{Error, Result};
use crate::integrator::{FlowMethod, FlowOptions, Mode, Sensitivity, Stats};
use crate::maps::{multipliers, poincare_map, Section};
use crate::model::{Convention, DrivenOscillator};
use serde::Serialize;
use std::fmt::Write as _;

/// `--section` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum SectionArg {
    /// The stroboscopic map P_T over one drive period.
    #[default]
    Strobe,
    /// The half-period map G = R⁻¹ ∘ P_{T/2}, R(β, ω) = (β + π, ω) (symmetric orbits).
    Half,
}

/// Arguments of `gearbif map`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    drive: DriveArgs,
    #[command(flatten)]
    method: MethodArgs,
    /// Which Poincaré map.
    #[arg(long, value_enum, default_value_t = SectionArg::Strobe)]
    section: SectionArg,
    /// Number of applications k of the map [1], 1 to 1000000 (the result is P^k).
    #[arg(long, default_value_t = 1)]
    iterations: usize,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct Multiplier {
    re: f64,
    im: f64,
    abs: f64,
}

#[derive(Debug, Serialize)]
struct MapReport {
    method: String,
    section: &'static str,
    iterations: usize,
    convention: Convention,
    f_hz: f64,
    g: f64,
    delta: f64,
    zeta: f64,
    eta: f64,
    /// State (β [rad], ω [rad/s]) the map is applied to.
    x: [f64; 2],
    /// Its image (β on the lift).
    image: [f64; 2],
    /// β winding of the image: (β_image − β)/(2π).
    winding: f64,
    mode: Mode,
    /// ∂(image)/∂(β, ω), row-major.
    jac_x: [[f64; 2]; 2],
    /// Parameter names of the columns of `jac_p`.
    param_names: Vec<&'static str>,
    /// ∂(image)/∂p, rows (β, ω), one column per parameter (total derivative of the map).
    jac_p: [Vec<f64>; 2],
    trace: f64,
    det: f64,
    multipliers: [Multiplier; 2],
    events: usize,
    stats: Stats,
    /// The model file (--model), if the gear is a recorded one.
    #[serde(skip_serializing_if = "Option::is_none")]
    model: Option<String>,
}

/// Runs `gearbif map`.
pub fn run(a: Args) -> Result<()> {
    super::common::check_frequency(a.drive.f)?;
    if let Some(m) = a.model.recorded(&a.gear, a.drive.f)? {
        let x = start(&m, &a.drive.x0)?;
        let method = super::model_arg::method(&a.method)?;
        let info = SystemInfo::of_model(&m, &a.model);
        return map(&m, &*method, x, &info, &a);
    }
    let gear = a.drive.gear(&a.gear)?;
    let x = a.drive.x0(&gear)?;
    let method = a.method.method()?;
    map(&gear, &*method, x, &SystemInfo::of_gear(&gear), &a)
}

/// The map of `sys` at `x` with `method`, printed as `a` asks.
fn map<S: DrivenOscillator>(
    gear: &S,
    method: &dyn FlowMethod<S>,
    x: [f64; 2],
    info: &SystemInfo,
    a: &Args,
) -> Result<()> {
    count("iterations", a.iterations, 1, limits::TURNS_MAX)?;
    let section = match a.section {
        SectionArg::Strobe => Section::Stroboscopic,
        SectionArg::Half => Section::HalfPeriod,
    };
    let opts = FlowOptions::with_tol(a.method.tol).sensitivity(Sensitivity::StateAndParams);
    let img = poincare_map(method, gear, section, x, a.iterations, &opts)?;
    let jx = img.jac_x.ok_or(Error::MissingJacobian { what: "state" })?;
    let jp = img
        .jac_p
        .ok_or(Error::MissingJacobian { what: "parameter" })?;
    let mu = multipliers(&jx);
    let np = gear.n_params();
    let report = MapReport {
        method: method.name(),
        section: match a.section {
            SectionArg::Strobe => "strobe",
            SectionArg::Half => "half",
        },
        iterations: a.iterations,
        convention: info.convention,
        f_hz: info.f,
        g: info.base[0],
        delta: info.base[1],
        zeta: info.base[2],
        eta: info.base[3],
        x,
        image: img.x,
        winding: (img.x[0] - x[0]) / std::f64::consts::TAU,
        mode: img.mode,
        jac_x: [[jx[(0, 0)], jx[(0, 1)]], [jx[(1, 0)], jx[(1, 1)]]],
        param_names: (0..np).map(|k| gear.param_name(k)).collect(),
        jac_p: [
            (0..np).map(|c| jp[(0, c)]).collect(),
            (0..np).map(|c| jp[(1, c)]).collect(),
        ],
        trace: jx.trace(),
        det: jx.determinant(),
        multipliers: mu.map(|m| Multiplier {
            re: m.re,
            im: m.im,
            abs: m.norm(),
        }),
        events: img.stats.events,
        stats: img.stats,
        model: info.model.clone(),
    };
    Output { json: a.json }.emit_tagged("gearbif.map/1", &report, || {
        let r = &report;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} map ×{} at f = {} Hz ({}), {}",
            r.section, r.iterations, r.f_hz, r.method, r.convention
        );
        let _ = writeln!(s, "x     = ({:.12}, {:.12})   [rad, rad/s]", r.x[0], r.x[1]);
        let _ = writeln!(
            s,
            "image = ({:.12}, {:.12})   winding {:.6}, mode {}",
            r.image[0], r.image[1], r.winding, r.mode
        );
        let _ = writeln!(
            s,
            "∂image/∂x = [[{:.9e}, {:.9e}],",
            r.jac_x[0][0], r.jac_x[0][1]
        );
        let _ = writeln!(
            s,
            "             [{:.9e}, {:.9e}]]",
            r.jac_x[1][0], r.jac_x[1][1]
        );
        for (c, name) in r.param_names.iter().enumerate() {
            let _ = writeln!(
                s,
                "∂image/∂{name:<5} = ({:.9e}, {:.9e})",
                r.jac_p[0][c], r.jac_p[1][c]
            );
        }
        let _ = writeln!(s, "trace = {:.9e}, det = {:.9e}", r.trace, r.det);
        for m in &r.multipliers {
            let _ = writeln!(s, "μ = {:.9e} {:+.9e} i   |μ| = {:.9e}", m.re, m.im, m.abs);
        }
        let _ = writeln!(
            s,
            "{} events, {} steps, {} rhs evaluations",
            r.events, r.stats.steps, r.stats.rhs_evals
        );
        s
    })
}
