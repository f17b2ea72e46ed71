//! The boundaries of the paper's Fig. 9 regimes over the whole range of parallel shaft angles, by
//! pseudo-arclength continuation of the minimally augmented systems in (Θ, f): the lock-loss fold
//! curves f_c(Θ) of both senses of rotation, and the symmetry-breaking curve that bounds the window of
//! T-periodic response inside the T/2 regime, with the codimension-two and turning points located on
//! them; compared with the paper's values at Θ = 25° and the analytic f_c at Δ = ±1.
//!
//! Run: `cargo run --release --example fig9_boundaries docs/figures/continuation` (writes
//! `fig9_boundaries.png`, `fig9_boundaries_zoom.png`, their SVGs and `fig9_boundaries.json`).

use gearbif::continuation::minaug::grazing_margin;
use gearbif::continuation::palc2::{continue_curve, lock_loss_curves, CurveOptions};
use gearbif::continuation::two_param::Curve;
use gearbif::continuation::SpecialKind;
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
    let full = BoundaryPlot {
        title: "Fig. 9 regimes over Θ: lock-loss folds and the T-window boundary".into(),
        curves: curves.clone(),
        marks: marks.clone(),
    };
    gearbif::plotting::save(&full, dir.join("fig9_boundaries.png"))?;
    gearbif::plotting::save(&full, dir.join("fig9_boundaries.svg"))?;
    let zoom = BoundaryPlot {
        title: "f ≤ 3 Hz: T window (between the SB curve's branches) and fold ends".into(),
        curves: below(&curves, 3.0),
        marks: marks.into_iter().filter(|m| m.2 <= 3.0).collect(),
    };
    gearbif::plotting::save(&zoom, dir.join("fig9_boundaries_zoom.png"))?;
    gearbif::plotting::save(&zoom, dir.join("fig9_boundaries_zoom.svg"))?;
    println!("total {:.2?}", t0.elapsed());
    Ok(())
}
