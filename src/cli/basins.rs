//! `gearbif basins`: the attractors of the gear's stroboscopic map at one (Θ, f), their basin map
//! on a (β, ω) grid with its figure, basin fractions from random samples with binomial σ, and the
//! minimal fatal kick of one attractor (docs/basins.md).

use super::common::{check_frequency, count, limits, output_dir, tolerance, GearArgs, Output};
use super::continue_::parse_range;
use super::sweep::Progress;
use crate::analysis::basins::{
    basin_fractions, basin_map, follow_attractors, minimal_fatal_kick, Attractor, AttractorSet,
    BasinMap, BasinOptions, FatalKick, Follow, FollowOptions, Fractions, KickNorm, KickOptions,
    Region, TrackEvent,
};
use crate::error::{Error, Result};
use crate::model::{Gear, GearParam};
use serde::Serialize;
use std::f64::consts::TAU;
use std::path::PathBuf;

/// Arguments of `gearbif basins`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    /// Drive frequency f [Hz], in [1e-3, 1e4].
    #[arg(long, allow_hyphen_values = true)]
    f: f64,
    /// Grid cells along β (β over [0, 2π) rad), 1 to 2000.
    #[arg(long, default_value_t = 200)]
    cells_beta: usize,
    /// Grid cells along ω, 1 to 2000.
    #[arg(long, default_value_t = 200)]
    cells_omega: usize,
    /// Follow the attractors and their sample fractions over f = lo, lo + step, … ≤ hi [Hz]
    /// (`lo:hi:step`, at most 1000 values) instead of one map; --f then only sets the default ω
    /// range.
    #[arg(long)]
    f_values: Option<String>,
    /// ω range lo:hi of the grid and the samples [rad/s] (default ±3 · 2πf).
    #[arg(long, allow_hyphen_values = true)]
    omega_range: Option<String>,
    /// Random samples for the basin fractions (0: none), at most 10000000.
    #[arg(long, default_value_t = 2000)]
    samples: usize,
    /// Seed of the random samples.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Minimal fatal kick of this attractor (index in the output; default: the largest basin
    /// among the periodic attractors).
    #[arg(long)]
    kick_attractor: Option<usize>,
    /// No minimal fatal kick.
    #[arg(long)]
    no_kick: bool,
    /// Norm of the kick: `velocity` (Δω in rad/s) or `state` (√(Δβ² + (Δω T/2π)²) in rad).
    #[arg(long, default_value = "velocity")]
    kick_norm: String,
    /// Largest kick tried (rad/s or rad; default 2 · 2πf for velocity, π for state).
    #[arg(long, allow_hyphen_values = true)]
    kick_max: Option<f64>,
    /// Drive phases at which the kick is applied, 1 to 64.
    #[arg(long, default_value_t = 4)]
    kick_phases: usize,
    /// Directions of a state kick, 1 to 360.
    #[arg(long, default_value_t = 16)]
    kick_directions: usize,
    /// Integrator tolerance, in (0, 1).
    #[arg(long, default_value_t = 1e-8)]
    tol: f64,
    /// Largest number of half-period maps per start, 64 to 1000000.
    #[arg(long, default_value_t = 600)]
    max_steps: usize,
    /// Output folder (basins.json, basins.svg, basins.png), written as one result.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print JSON (without the grid's labels, which go to basins.json).
    #[arg(long)]
    json: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

#[derive(Debug, Clone, Copy, Serialize)]
struct Out<'a> {
    theta_deg: f64,
    f_hz: f64,
    options: &'a BasinOptions,
    attractors: &'a [Attractor],
    cell_fractions: &'a [f64],
    #[serde(skip_serializing_if = "Option::is_none")]
    fractions: Option<&'a Fractions>,
    #[serde(skip_serializing_if = "Option::is_none")]
    kick: Option<&'a FatalKick>,
    seconds: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    map: Option<&'a BasinMap>,
}

fn owned(name: &str, is_dir: bool) -> bool {
    !is_dir
        && matches!(
            name,
            "basins.json"
                | "basins.svg"
                | "basins.png"
                | "follow.json"
                | "fractions.svg"
                | "fractions.png"
        )
}

/// Checks the arguments; the region and the kick options.
fn check(a: &Args) -> Result<(Region, Option<KickOptions>)> {
    check_frequency(a.f)?;
    tolerance("tol", a.tol)?;
    count("cells-beta", a.cells_beta, 1, 2000)?;
    count("cells-omega", a.cells_omega, 1, 2000)?;
    count("samples", a.samples, 0, 10_000_000)?;
    count("max-steps", a.max_steps, 64, limits::TURNS_MAX)?;
    count("kick-phases", a.kick_phases, 1, 64)?;
    count("kick-directions", a.kick_directions, 1, 360)?;
    let w = TAU * a.f;
    let omega = match &a.omega_range {
        Some(s) => parse_range(s)?,
        None => (-3.0 * w, 3.0 * w),
    };
    if omega.0.abs().max(omega.1.abs()) > limits::OMEGA_MAX {
        return Err(Error::option("--omega-range", "|ω| must be <= 1e6 rad/s"));
    }
    let norm = match a.kick_norm.as_str() {
        "velocity" => KickNorm::Velocity,
        "state" => KickNorm::State,
        other => {
            return Err(Error::unknown_name(
                "kick norm",
                other,
                ["velocity", "state"],
            ))
        }
    };
    let max_kick = a.kick_max.unwrap_or(match norm {
        KickNorm::Velocity => 2.0 * w,
        KickNorm::State => std::f64::consts::PI,
    });
    let kick = KickOptions {
        norm,
        directions: a.kick_directions,
        phases: a.kick_phases,
        max_kick,
        scan: 16,
        rel_tol: 1e-3,
    };
    kick.validate()?;
    let region = Region {
        beta: (0.0, TAU),
        omega,
    };
    region.validate()?;
    Ok((region, (!a.no_kick).then_some(kick)))
}

/// Runs `gearbif basins`.
pub fn run(a: Args) -> Result<()> {
    let (region, kick_opts) = check(&a)?;
    if let Some(out) = &a.out {
        output_dir("--out", out)?;
    }
    let p = a.gear.params()?;
    let gear =
        Gear::new(p.g(), p.delta(), p.zeta, p.eta, a.f)?.with_convention(a.gear.convention());
    let opts = BasinOptions {
        tol: a.tol,
        max_steps: a.max_steps,
        ..BasinOptions::default()
    };
    let staged = match &a.out {
        Some(out) => Some(crate::io::StagedDir::begin("--out", out, owned)?),
        None => None,
    };
    if let Some(v) = &a.f_values {
        let values = parse_values(v)?;
        return follow(&a, &gear, &values, region, &opts, staged);
    }
    let t = std::time::Instant::now();
    let set = AttractorSet::new(&gear);
    let progress = Progress::new(a.quiet);
    let mut map = basin_map(
        &gear,
        &set,
        region,
        a.cells_beta,
        a.cells_omega,
        &opts,
        &progress,
    )?;
    let mut fr = match a.samples {
        0 => None,
        n => Some(basin_fractions(
            &gear, &set, region, n, a.seed, &opts, &progress,
        )?),
    };
    progress.finish();
    let mut kick = match kick_opts {
        Some(k) => {
            let target = kick_target(&set, &map, a.kick_attractor)?;
            Some(minimal_fatal_kick(&gear, &set, target, &k, &opts)?)
        }
        None => None,
    };
    let (attractors, new_of) = set.finish();
    map.relabel(&new_of);
    fr.iter_mut().for_each(|f| f.relabel(&new_of));
    kick.iter_mut().for_each(|k| k.relabel(&new_of));
    let cells = map.cell_fractions(attractors.len());
    let out = Out {
        theta_deg: p.theta.to_degrees(),
        f_hz: a.f,
        options: &opts,
        cell_fractions: &cells,
        attractors: &attractors,
        fractions: fr.as_ref(),
        kick: kick.as_ref(),
        seconds: t.elapsed().as_secs_f64(),
        map: None,
    };
    if let Some(staged) = staged {
        write(&staged, &out, &map, &attractors)?;
        staged.commit()?;
    }
    Output { json: a.json }.emit_tagged("gearbif.basins/1", &out, || text(&out, &a))
}

/// The attractor kicked: the one asked for (an index of the output, i.e. after ordering), else
/// the periodic one with the most cells.
fn kick_target(set: &AttractorSet, map: &BasinMap, asked: Option<usize>) -> Result<usize> {
    let list = set.snapshot();
    match asked {
        Some(k) => set
            .order()
            .iter()
            .position(|&new| new == k)
            .ok_or_else(|| Error::shape("--kick-attractor", format!("< {}", list.len()), k)),
        None => {
            let frac = map.cell_fractions(list.len());
            (0..list.len())
                .filter(|&i| list[i].is_periodic())
                .max_by(|&i, &j| frac[i].total_cmp(&frac[j]))
                .ok_or_else(|| Error::option("kick", "no periodic attractor was found"))
        }
    }
}

fn write(
    staged: &crate::io::StagedDir,
    out: &Out<'_>,
    map: &BasinMap,
    attractors: &[Attractor],
) -> Result<()> {
    let full = Out {
        map: Some(map),
        ..*out
    };
    let json = serde_json::to_string(&crate::io::with_schema("gearbif.basins/1", &full))
        .map_err(|e| Error::format("JSON", "basins", e))?;
    crate::io::write_atomic(staged.path().join("basins.json"), json.as_bytes())?;
    let fig = crate::plotting::basins::BasinFigure {
        title: format!(
            "Basins of P_T, Θ = {:.2}°, f = {} Hz ({} × {} cells)",
            out.theta_deg, out.f_hz, map.n_beta, map.n_omega
        ),
        map,
        attractors,
    };
    crate::plotting::save(&fig, staged.path().join("basins.svg"))?;
    crate::plotting::save(&fig, staged.path().join("basins.png"))
}

fn text(out: &Out<'_>, a: &Args) -> String {
    let mut s = format!(
        "Θ = {:.3}°, f = {} Hz: {} attractors ({:.1} s)\n",
        out.theta_deg,
        out.f_hz,
        out.attractors.len(),
        out.seconds
    );
    for (i, at) in out.attractors.iter().enumerate() {
        let mu = at.spectral_radius();
        s += &format!(
            "  {}  |μ|max = {mu:.4}, cells {:.2} %",
            at.legend(i),
            100.0 * out.cell_fractions[i]
        );
        if let Some(fr) = out.fractions {
            let (p, sg) = fr.stability(i);
            s += &format!(", samples {:.2} ± {:.2} %", 100.0 * p, 100.0 * sg);
        }
        s += "\n";
    }
    if let Some(k) = out.kick {
        let unit = match k.options.norm {
            KickNorm::Velocity => "rad/s",
            KickNorm::State => "rad",
        };
        s += &match &k.worst {
            Some(w) => format!(
                "  minimal fatal kick of #{}: {:.4} {unit} at phase {:.3} T along (Δβ, Δω) = ({:.3}, {:.3}), lands on #{}\n",
                k.attractor,
                w.size.unwrap_or(f64::NAN),
                w.phase,
                w.direction[0],
                w.direction[1],
                w.lands_on.map_or("?".into(), |l| l.to_string())
            ),
            None => format!(
                "  no fatal kick of #{} up to {} {unit}\n",
                k.attractor, k.options.max_kick
            ),
        };
    }
    if let Some(o) = &a.out {
        s += &format!(
            "  wrote {}/basins.json, basins.svg, basins.png\n",
            o.display()
        );
    }
    s
}

/// `lo:hi:step` → lo, lo + step, … ≤ hi (each a valid frequency, at most 1000 values).
fn parse_values(s: &str) -> Result<Vec<f64>> {
    let bad = |why: &str| Error::option(format!("--f-values `{s}`"), why.to_string());
    let p: Vec<f64> = s
        .split(':')
        .map(|x| {
            x.trim()
                .parse::<f64>()
                .map_err(|_| bad("expected lo:hi:step"))
        })
        .collect::<Result<_>>()?;
    let [lo, hi, step] = p[..] else {
        return Err(bad("expected lo:hi:step"));
    };
    if !(lo.is_finite() && hi.is_finite() && step.is_finite() && step > 0.0 && hi >= lo) {
        return Err(bad("needs finite lo <= hi and step > 0"));
    }
    let n = ((hi - lo) / step + 1e-9).floor() + 1.0;
    if n > 1000.0 {
        return Err(bad("more than 1000 values"));
    }
    // rounded to 12 digits so that 1.5 + 14 · 0.1 prints as 2.9
    let round = |x: f64| (x * 1e12).round() / 1e12;
    let values: Vec<f64> = (0..n as usize)
        .map(|i| round(lo + i as f64 * step))
        .collect();
    for &f in &values {
        check_frequency(f)?;
    }
    Ok(values)
}

/// `--f-values`: the global continuation over f, its JSON and the figure of the fractions.
fn follow(
    a: &Args,
    gear: &Gear,
    values: &[f64],
    region: Region,
    opts: &BasinOptions,
    staged: Option<crate::io::StagedDir>,
) -> Result<()> {
    let fo = FollowOptions {
        samples: a.samples.max(1),
        seed: a.seed,
        match_distance: 0.5,
    };
    let progress = Progress::new(a.quiet);
    let fol = follow_attractors(gear, GearParam::F, values, region, &fo, opts, &progress)?;
    progress.finish();
    if let Some(staged) = staged {
        let json = serde_json::to_string(&crate::io::with_schema("gearbif.basins-follow/1", &fol))
            .map_err(|e| Error::format("JSON", "follow", e))?;
        crate::io::write_atomic(staged.path().join("follow.json"), json.as_bytes())?;
        let fig = fractions_plot(&fol);
        crate::plotting::save(&fig, staged.path().join("fractions.svg"))?;
        crate::plotting::save(&fig, staged.path().join("fractions.png"))?;
        staged.commit()?;
    }
    Output { json: a.json }.emit_tagged("gearbif.basins-follow/1", &fol, || {
        let mut s = String::new();
        for st in &fol.steps {
            s += &format!("f = {} Hz:", st.value);
            for (i, at) in st.attractors.iter().enumerate() {
                let fr = &st.fractions[i];
                s += &format!(
                    " [track {}] {} {:.1} ± {:.1} %;",
                    st.tracks[i],
                    at.label,
                    100.0 * fr.fraction,
                    100.0 * fr.sigma
                );
            }
            s += "\n";
        }
        for e in &fol.events {
            s += &match e {
                TrackEvent::Birth { track, from, to } => {
                    format!("track {track} born between {from} and {to} Hz\n")
                }
                TrackEvent::Death { track, from, to } => {
                    format!("track {track} ends between {from} and {to} Hz\n")
                }
            };
        }
        s
    })
}

/// Basin fraction against f, one marker series per track.
fn fractions_plot(fol: &Follow) -> crate::plotting::LinePlot {
    let series = (0..fol.tracks)
        .map(|t| {
            let mut label = String::new();
            let points = fol
                .steps
                .iter()
                .filter_map(|s| {
                    let i = s.tracks.iter().position(|&x| x == t)?;
                    if label.is_empty() {
                        let at = &s.attractors[i];
                        label = format!("track {t}: {}, ρ = {:.2}", at.label, at.rotation_number);
                    }
                    Some((s.value, s.fractions[i].fraction))
                })
                .collect();
            crate::plotting::Series {
                label,
                points,
                markers: true,
                color: t,
            }
        })
        .collect();
    crate::plotting::LinePlot {
        title: "Basin fractions of the attractors of P_T".into(),
        x_label: "f [Hz]".into(),
        y_label: "basin fraction (dimensionless)".into(),
        series,
        ..Default::default()
    }
}
