//! The boundaries of the paper's Fig. 9 regimes over the whole range of parallel shaft angles, by
//! pseudo-arclength continuation of the minimally augmented systems in (Θ, f): the lock-loss fold
//! curves f_c(Θ) of both senses of rotation, and the symmetry-breaking curve that bounds the window of
//! T-periodic response inside the T/2 regime, with the codimension-two and turning points located on
//! them; compared with the paper's values at Θ = 25° and the analytic f_c at Δ = ±1. Curves of
//! nonsmooth points: the grazing (stick-onset) curves of the symmetric T/2 orbits (p = ±1) and of
//! the asymmetric T orbit, each started from a stick onset located by one-parameter continuation,
//! with fold–grazing and symmetry-breaking–grazing points located on them, and each confirmed at
//! several Θ by a one-parameter continuation in f.
//!
//! Run: `cargo run --release --example fig9_boundaries docs/figures/continuation` (writes
//! `fig9_boundaries.png`, `fig9_boundaries_zoom.png`, their SVGs and `fig9_boundaries.json`).

use gearbif::continuation::minaug::grazing_margin;
use gearbif::continuation::palc2::{
    continue_curve, continue_event_edge_curve, continue_grazing_curve, locate_grazing,
    lock_loss_curves, CurveOptions,
};
use gearbif::continuation::two_param::Curve;
use gearbif::continuation::{Branch, Continuation, ContinuationOptions, SpecialKind, SpecialPoint};
use gearbif::integrator::EventDriven;
use gearbif::model::{Gear, GearParam, Parametrised};
use gearbif::orbits::OrbitSpec;
use gearbif::plotting::branch::BoundaryPlot;

type Labelled = Vec<(String, Curve<Gear>)>;

fn report(curves: &Labelled) {
    for (label, c) in curves {
        let last = c.points.last().expect("a curve has a point");
        println!(
            "{label}: {} points, ends at Θ = {:.6}°, f = {:.9} Hz ({})",
            c.points.len(),
            last.along,
            last.free,
            c.stopped
                .as_ref()
                .map(|s| s.to_string())
                .unwrap_or_default()
        );
        for q in &c.codim2 {
            println!(
                "  {}: Θ = {:.7}°, f = {:.9} Hz ± {:.1e}, tangent (df/ds, dΘ/ds) = ({:.1e}, {:.1e})",
                q.kind.label(),
                q.along,
                q.free,
                q.precision,
                q.tangent_lambda[0],
                q.tangent_lambda[1]
            );
        }
    }
}

/// The part of a curve with f ≤ `fmax`, split where it leaves that range.
fn below(curves: &Labelled, fmax: f64) -> Labelled {
    let mut out = Vec::new();
    for (label, c) in curves {
        let mut cur: Vec<_> = Vec::new();
        for p in &c.points {
            if p.free <= fmax {
                cur.push(p.clone());
            } else if !cur.is_empty() {
                out.push((
                    label.clone(),
                    Curve {
                        points: std::mem::take(&mut cur),
                        ..c.clone()
                    },
                ));
            }
        }
        if !cur.is_empty() {
            out.push((
                label.clone(),
                Curve {
                    points: cur,
                    ..c.clone()
                },
            ));
        }
    }
    out
}

/// The first located nonsmooth point of a branch where the orbit starts to stick: one side of the
/// jump has no events at all (grazing of Σ).
fn stick_onset(b: &Branch) -> Option<SpecialPoint> {
    b.specials
        .iter()
        .find(|s| {
            s.jump.as_ref().is_some_and(|j| {
                j.events_before.signature() == (0, 0) || j.events_after.signature() == (0, 0)
            })
        })
        .cloned()
}

/// One-parameter continuation in f at Θ = `theta` across [f0 − w, f0 + w] from near `x`, and the
/// stick onset it locates.
fn onset_by_continuation(
    theta: f64,
    spec: OrbitSpec,
    x: [f64; 2],
    f0: f64,
    w: f64,
) -> gearbif::Result<SpecialPoint> {
    let b = branch_across(theta, spec, x, f0, w)?;
    stick_onset(&b).ok_or_else(|| gearbif::Error::NotFound {
        what: format!("stick onset near {f0} Hz at Θ = {theta}°"),
    })
}

/// The end of sticking, event signature (1, 1) ↔ (2, 0), located on a branch.
fn stick_end(b: &Branch) -> Option<SpecialPoint> {
    let want = [(1, 1), (2, 0)];
    b.specials
        .iter()
        .find(|s| {
            s.jump.as_ref().is_some_and(|j| {
                want.contains(&j.events_before.signature())
                    && want.contains(&j.events_after.signature())
            })
        })
        .cloned()
}

/// One-parameter continuation in f at Θ = `theta` across [f0 − w, f0 + w] from near `x`.
fn branch_across(
    theta: f64,
    spec: OrbitSpec,
    x: [f64; 2],
    f0: f64,
    w: f64,
) -> gearbif::Result<Branch> {
    Continuation::new(
        Gear::paper(theta, f0 + w)?,
        GearParam::F,
        spec,
        x,
        ContinuationOptions {
            ds: -0.2 * w,
            ds_max: 0.5 * w,
            param_min: f0 - w,
            param_max: f0 + w,
            ..Default::default()
        },
    )?
    .run(None)
}

/// The curve where the asymmetric T orbit's stick phase shrinks to nothing ((1, 1) ↔ (2, 0): the
/// arrival on Σ at the edge a = +η), from the point a continuation in f locates at 25°, both ways;
/// confirmed at three of its points by a continuation in f at that Θ.
fn stick_end_curves(opts: &CurveOptions) -> gearbif::Result<Labelled> {
    let spec = OrbitSpec::stroboscopic(1, 1);
    let b = branch_across(25.0, spec, [2.9748, 24.3248], 2.36, 0.025)?;
    let sp = stick_end(&b).ok_or_else(|| gearbif::Error::NotFound {
        what: "end of sticking at 25°".into(),
    })?;
    println!(
        "end of sticking, T orbit, Θ = 25° (continuation in f): {:.10} Hz",
        sp.param
    );
    let g = Gear::paper(25.0, sp.param)?;
    let mut out = Vec::new();
    for ds in [0.2, -0.2] {
        let o = CurveOptions {
            ds,
            ds_max: 0.5,
            max_steps: 40,
            max_multiplier: 1e3,
            ..*opts
        };
        let args = (GearParam::F, GearParam::ThetaDeg);
        let c =
            continue_event_edge_curve(&EventDriven, &g, &spec, args.0, args.1, sp.x, sp.param, &o)?;
        out.push(("end of sticking: T orbit (asymmetric)".to_string(), c));
    }
    for p in out[0].1.points.iter().skip(8).step_by(8).take(3) {
        let b = branch_across(p.along, spec, p.x, p.free, 0.004)?;
        let q = stick_end(&b).ok_or_else(|| gearbif::Error::NotFound {
            what: format!("end of sticking at Θ = {}°", p.along),
        })?;
        println!(
            "Θ = {:.6}°: end-of-sticking curve {:.10} Hz, continuation in f {:.10} ± {:.1e} Hz, \
             difference {:.1e} Hz",
            p.along,
            p.free,
            q.param,
            q.precision,
            p.free - q.param
        );
    }
    Ok(out)
}

/// A grazing curve from the stick onset `sp` located at Θ = 25° (both directions).
fn grazing_from(
    label: &str,
    spec: OrbitSpec,
    sp: &SpecialPoint,
    steps: [usize; 2],
    opts: &CurveOptions,
) -> gearbif::Result<Labelled> {
    let g = Gear::paper(25.0, sp.param)?;
    let side = if spec.winding >= 0 { 1.0 } else { -1.0 };
    let mut out = Vec::new();
    for (ds, max_steps) in [(0.2, steps[0]), (-0.2, steps[1])] {
        let o = CurveOptions {
            ds,
            max_steps,
            ..*opts
        };
        let c = continue_grazing_curve(
            &EventDriven,
            &g,
            &spec,
            side,
            GearParam::F,
            GearParam::ThetaDeg,
            sp.x,
            sp.param,
            &o,
        )?;
        out.push((label.to_string(), c));
    }
    Ok(out)
}

/// The grazing curves: of the symmetric orbit p = +1 and of the asymmetric T orbit, each from the
/// stick onset a one-parameter continuation locates at Θ = 25°; of the reversed symmetric orbit
/// (p = −1) from where its fold curve ends.
fn grazing_curves(opts: &CurveOptions, fold_rev: &Curve<Gear>) -> gearbif::Result<Labelled> {
    let o = CurveOptions {
        ds_max: 0.5,
        max_multiplier: 1e3,
        ..*opts
    };
    let sym = OrbitSpec::symmetric(1);
    let onset = onset_by_continuation(25.0, sym, [2.98, 0.6], 1.49, 0.03)?;
    println!(
        "stick onset, symmetric p = +1, Θ = 25° (continuation in f): {:.10} Hz",
        onset.param
    );
    let mut curves = grazing_from("grazing: T/2 orbit, p = +1", sym, &onset, [150, 45], &o)?;
    let asym = OrbitSpec::stroboscopic(1, 1);
    let onset = onset_by_continuation(25.0, asym, [2.9748, 24.3248], 2.38, 0.02)?;
    println!(
        "stick onset, asymmetric T orbit, Θ = 25° (continuation in f): {:.10} Hz",
        onset.param
    );
    curves.extend(grazing_from(
        "grazing: T orbit (asymmetric)",
        asym,
        &onset,
        [80, 60],
        &o,
    )?);
    let end = fold_rev.points.last().expect("a curve has a point");
    let g = Gear::paper(end.along, end.free)?;
    for ds in [0.2, -0.2] {
        let c = continue_grazing_curve(
            &EventDriven,
            &g,
            &fold_rev.spec,
            -1.0,
            GearParam::F,
            GearParam::ThetaDeg,
            end.x,
            end.free,
            &CurveOptions {
                ds,
                max_steps: 60,
                ..o
            },
        )?;
        curves.push(("grazing: T/2 orbit, p = -1".to_string(), c));
    }
    Ok(curves)
}

/// Second route: at each Θ of `thetas`, the grazing point of `curve` (Newton at that fixed Θ from
/// the nearest point of the curve's first monotone stretch) against the stick onset a
/// one-parameter continuation in f locates there; and the grazing point at two tolerances.
fn confirm(curve: &Curve<Gear>, thetas: &[f64], opts: &CurveOptions) -> gearbif::Result<()> {
    let pts = &curve.points;
    let mono = pts
        .windows(2)
        .position(|w| (w[1].along - w[0].along) * (pts[1].along - pts[0].along) < 0.0)
        .map_or(pts.len(), |i| i + 1);
    for &th in thetas {
        let near = pts[..mono]
            .iter()
            .min_by(|a, b| (a.along - th).abs().total_cmp(&(b.along - th).abs()))
            .expect("a curve has a point");
        let g = Gear::paper(th, near.free)?;
        let side = if curve.spec.winding >= 0 { 1.0 } else { -1.0 };
        let locate = |tol: f64| {
            let mut o = *opts;
            o.shooting.tol = tol;
            locate_grazing(
                &EventDriven,
                &g,
                &curve.spec,
                side,
                GearParam::F,
                GearParam::ThetaDeg,
                near.x,
                near.free,
                &o,
            )
        };
        let p = locate(1e-11)?;
        let p9 = locate(1e-9)?;
        let sp = onset_by_continuation(th, curve.spec, p.x, p.free, 0.004)?;
        println!(
            "Θ = {th}°: grazing curve {:.10} Hz, continuation in f {:.10} ± {:.1e} Hz, difference \
             {:.1e} Hz; tol 1e-9 vs 1e-11: {:.1e} Hz",
            p.free,
            sp.param,
            sp.precision,
            p.free - sp.param,
            p9.free - p.free
        );
    }
    Ok(())
}

fn main() -> gearbif::Result<()> {
    let dir = std::path::PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "target/fig9_boundaries".into()),
    );
    std::fs::create_dir_all(&dir).map_err(|e| gearbif::Error::Io(e.to_string()))?;
    let t0 = std::time::Instant::now();
    let th_rev = gearbif::model::gear::cogging_free_parallel_angles()
        .2
        .to_degrees();
    let base = Gear::paper(0.0, 1.0)?;
    let opts = CurveOptions {
        free_range: (0.05, 100.0),
        along_range: (0.0, th_rev),
        ..Default::default()
    };
    let mut curves: Labelled = lock_loss_curves(&base, &opts)?
        .into_iter()
        .map(|(l, c)| (format!("f_c: {l}"), c))
        .collect();
    // the symmetry-breaking curve from the subcritical point at 25° (docs/continuation.md), both ways
    for ds in [0.2, -0.2] {
        let g = Gear::paper(25.0, 2.0777402)?;
        let o = CurveOptions {
            ds,
            ds_max: 0.5,
            ..opts
        };
        let c = continue_curve(
            &EventDriven,
            &g,
            &OrbitSpec::symmetric(1),
            SpecialKind::SymmetryBreaking,
            GearParam::F,
            GearParam::ThetaDeg,
            [2.98464, 8.79534],
            2.0777402,
            &o,
        )?;
        curves.push(("symmetry breaking T/2 ↔ T (μ_G = −1)".into(), c));
    }
    let grazing = grazing_curves(&opts, &curves[1].1)?;
    confirm(&grazing[0].1, &[30.0, 35.0, 40.0, 45.0], &opts)?;
    confirm(&grazing[2].1, &[30.0, 40.0], &opts)?;
    curves.extend(grazing);
    curves.extend(stick_end_curves(&opts)?);
    report(&curves);
    // where the fold curves end: the orbit touches ω = 0 (grazing, onset of sticking)
    for (label, c) in curves.iter().take(2) {
        let p = c.points.last().expect("a curve has a point");
        let g = base
            .with_param(GearParam::ThetaDeg, p.along)?
            .with_param(GearParam::F, p.free)?;
        let side = p.x[1].signum();
        let m = grazing_margin(&EventDriven, &g, &c.spec, p.x, side, 1e-11)?;
        println!("{label}: min |ω| over the orbit at the end point = {m:.2e} rad/s");
    }
    println!("curves in {:.2?}", t0.elapsed());
    gearbif::io::write_json_atomic(
        dir.join("fig9_boundaries.json"),
        &serde_json::json!({ "schema": "gearbif.curves/1", "curves": &curves }),
    )?;
    let fc = base.lock_loss_frequency().unwrap_or(f64::NAN);
    // one list of marks for both figures, the analytic ones last (the zoom leaves them out)
    let mut marks = Vec::new();
    for (_, c) in &curves {
        for q in &c.codim2 {
            marks.push((format!("located: {}", q.kind.label()), q.along, q.free));
        }
    }
    for (_, c) in curves.iter().take(2) {
        let p = c.points.last().expect("a curve has a point");
        marks.push((
            "fold curve ends: orbit grazes ω = 0".into(),
            p.along,
            p.free,
        ));
    }
    for f in [2.1, 2.5] {
        marks.push(("paper, Fig. 9 (Θ = 25°): 2.1 and 2.5 Hz".into(), 25.0, f));
    }
    marks.push(("analytic f_c at Δ = ±1".into(), 0.0, fc));
    marks.push(("analytic f_c at Δ = ±1".into(), th_rev, fc));
    // f from below 1 Hz to 40 Hz: a log axis keeps the curves below 3 Hz apart
    let full = BoundaryPlot {
        title: "Fig. 9 regimes over Θ: lock-loss folds, T-window boundary, stick onset".into(),
        curves: curves.clone(),
        marks: marks.clone(),
        log_y: true,
    };
    gearbif::plotting::save(&full, dir.join("fig9_boundaries.png"))?;
    gearbif::plotting::save(&full, dir.join("fig9_boundaries.svg"))?;
    let zoom = BoundaryPlot {
        title: "f ≤ 3 Hz: T window (between the SB curve's branches), grazing curves".into(),
        curves: below(&curves, 3.0),
        marks: marks.into_iter().filter(|m| m.2 <= 3.0).collect(),
        ..Default::default()
    };
    gearbif::plotting::save(&zoom, dir.join("fig9_boundaries_zoom.png"))?;
    gearbif::plotting::save(&zoom, dir.join("fig9_boundaries_zoom.svg"))?;
    println!("total {:.2?}", t0.elapsed());
    Ok(())
}
