//! Fig. 10 of Hartung & Rehberg (2020) by continuation: Θ = 0, the lock branch and its fold at
//! f_c = (g − η)/(2πζ), compared with the analytic `LockBranch`; then the slip-through state and the
//! frequency where a downward quasi-static sweep re-locks.
//!
//! Run: `cargo run --release --example fig10_continuation [OUTDIR]` (figures and JSON go to OUTDIR,
//! default `target/fig10`).

use gearbif::continuation::{Continuation, ContinuationOptions, SpecialKind};
use gearbif::integrator::{EventDriven, FlowOptions};
use gearbif::maps::{poincare_map, Section};
use gearbif::model::{Gear, GearParam};
use gearbif::orbits::OrbitSpec;
use std::f64::consts::{FRAC_PI_2, TAU};

fn main() -> gearbif::Result<()> {
    let dir = std::path::PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "target/fig10".into()),
    );
    let gear = Gear::paper(0.0, 5.0)?;
    let fc = gear.lock_loss_frequency().unwrap_or(f64::NAN);
    let t0 = std::time::Instant::now();
    let opts = ContinuationOptions {
        ds: 0.5,
        ds_max: 5.0,
        param_min: 0.5,
        param_max: 60.0,
        max_multiplier: 1e3,
        ..Default::default()
    };
    let start = gear.lock_branch()?.stable.state;
    let b =
        Continuation::new(gear, GearParam::F, OrbitSpec::symmetric(1), start, opts)?.run(None)?;
    println!(
        "lock branch: {} points, {} map evaluations, {:?}, stop {:?}",
        b.points.len(),
        b.map_evaluations,
        t0.elapsed(),
        b.stop
    );
    let mut worst: f64 = 0.0;
    for p in &b.points {
        let lb = Gear::paper(0.0, p.param)?.lock_branch()?;
        let lp = if p.x[0] > FRAC_PI_2 {
            lb.stable
        } else {
            lb.unstable
        };
        worst = worst.max((p.x[0] - lp.state[0]).abs());
    }
    println!("largest |δ − δ_analytic| over the branch: {worst:.2e} rad");
    for s in b.specials_of(SpecialKind::Fold) {
        println!(
            "fold: f = {:.10} ± {:.1e} Hz; analytic f_c = {fc:.10} Hz; difference {:.1e}; δ = {:.6}°; μ_G = {:?}",
            s.param,
            s.precision,
            (s.param - fc).abs(),
            s.x[0].to_degrees(),
            s.floquet.multipliers
        );
    }
    // slip-through state and re-locking: downward quasi-static sweep from above f_c
    let o = FlowOptions::with_tol(1e-9);
    let mut x = [FRAC_PI_2, TAU * 42.0];
    let mut relock = None;
    println!("downward sweep (net output rotation per drive period after relaxation):");
    let mut f = 42.0;
    while f > 1.0 {
        let g = Gear::paper(0.0, f)?;
        x = poincare_map(&EventDriven, &g, Section::Stroboscopic, x, 200, &o)?.x;
        let y = poincare_map(&EventDriven, &g, Section::Stroboscopic, x, 100, &o)?.x;
        let rate = (y[0] - x[0]) / (TAU * 100.0);
        x = y;
        if (f - f.round()).abs() < 1e-9 && (f as i64) % 4 == 2 {
            println!("  f = {f:5.1} Hz: {rate:.4}");
        }
        if relock.is_none() && (rate - 1.0).abs() < 1e-6 {
            relock = Some(f);
            break;
        }
        f -= 0.5;
    }
    match relock {
        Some(f) => println!(
            "  re-locked at f = {f:.1} Hz (between {f:.1} and {:.1} Hz)",
            f + 0.5
        ),
        None => println!("  no re-locking above 1 Hz"),
    }
    std::fs::create_dir_all(&dir).map_err(|e| gearbif::Error::Io(e.to_string()))?;
    gearbif::io::write_json_atomic(dir.join("lock_branch.json"), &b)?;
    #[cfg(feature = "plot")]
    {
        use gearbif::plotting::branch::{BranchDiagram, MultiplierPlot};
        let fig = BranchDiagram {
            title: "Θ = 0: lock branch (β − α at α = 0), fold at f_c".into(),
            branches: vec![b.clone()],
            ..Default::default()
        };
        gearbif::plotting::save(&fig, dir.join("fig10_lock_branch.svg"))?;
        gearbif::plotting::save(&fig, dir.join("fig10_lock_branch.png"))?;
        let m = MultiplierPlot {
            title: "Θ = 0: multipliers of G along the lock branch".into(),
            branch: Some(b),
        };
        gearbif::plotting::save(&m, dir.join("fig10_multipliers.svg"))?;
    }
    Ok(())
}
