//! Fig. 10 of Hartung & Rehberg (2020) by continuation: Θ = 0, the lock branch and its fold at
//! f_c = (g − η)/(2πζ), compared with the analytic `LockBranch`. (The slip-through state and the
//! frequency where a downward run re-locks: `gearbif figure fig10`.)
//!
//! Run: `cargo run --release --example fig10_continuation [OUTDIR]` (figures and JSON go to OUTDIR,
//! default `target/fig10`).

use gearbif::continuation::{Continuation, ContinuationOptions, SpecialKind};
use gearbif::model::{Gear, GearParam};
use gearbif::orbits::OrbitSpec;
use std::f64::consts::FRAC_PI_2;

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
    // the slip-through state and where a downward run re-locks are simulated, not continued:
    // `gearbif figure fig10` (docs/atlas.md, Fig. 10)
    std::fs::create_dir_all(&dir).map_err(|e| gearbif::Error::Io(e.to_string()))?;
    gearbif::io::write_json_atomic(dir.join("lock_branch.json"), &b)?;
    #[cfg(feature = "plot")]
    {
        use gearbif::plotting::branch::{BranchDiagram, MultiplierPlot, Quantity};
        let fig = BranchDiagram {
            title: "Θ = 0: the lock branch and its fold at f_c (compare Fig. 10a)".into(),
            branches: vec![b.clone()],
            labels: vec!["lock (G, p = 1)".into()],
            quantity: Quantity::PaperFigureDelta,
            ..Default::default()
        };
        gearbif::plotting::save(&fig, dir.join("fig10_lock_branch.svg"))?;
        gearbif::plotting::save(&fig, dir.join("fig10_lock_branch.png"))?;
        let m = MultiplierPlot {
            title: "Θ = 0: multipliers of G along the lock branch".into(),
            branch: Some(b),
        };
        gearbif::plotting::save(&m, dir.join("fig10_multipliers.svg"))?;
        gearbif::plotting::save(&m, dir.join("fig10_multipliers.png"))?;
    }
    Ok(())
}
