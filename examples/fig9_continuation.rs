//! Fig. 9 of Hartung & Rehberg (2020) by continuation: Θ = 25°, every bifurcation between 1.5 and
//! 3 Hz. The symmetric (T/2, on the half-period map G) branch and its symmetry-breaking points, the
//! asymmetric (T-periodic) branch by branch switching, its nonsmooth points and its flip, the
//! period-doubled branch after the flip, each confirmed by a quasi-static up and down sweep; and the
//! curves bounding the T/2 and T regimes in the (Θ, f) plane.
//!
//! Run: `cargo run --release --example fig9_continuation [OUTDIR]` (default `target/fig9`).

use gearbif::continuation::two_param::follow;
use gearbif::continuation::{
    switch_branch, Branch, Continuation, ContinuationOptions, SpecialKind,
};
use gearbif::model::{Gear, GearParam};
use gearbif::orbits::{quasi_static_sweep, OrbitSpec, ShootingOptions};

fn report(name: &str, b: &Branch) {
    println!(
        "{name}: {} points, {} map evaluations, stop {:?}",
        b.points.len(),
        b.map_evaluations,
        b.stop
    );
    for s in &b.specials {
        let extra = s
            .jump
            .as_ref()
            .map(|j| {
                format!(
                    " (crossings, sticks) {:?} → {:?}, μ {:?} → {:?}",
                    j.events_before.signature(),
                    j.events_after.signature(),
                    j.floquet_before.multipliers,
                    j.floquet_after.multipliers
                )
            })
            .unwrap_or_default();
        println!(
            "  {:<18} f = {:.9} ± {:.1e} Hz  μ₁ = {:.6}{}",
            s.kind.label(),
            s.param,
            s.precision,
            s.floquet.multipliers[0][0],
            extra
        );
    }
}

fn main() -> gearbif::Result<()> {
    let dir = std::path::PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "target/fig9".into()),
    );
    let t0 = std::time::Instant::now();
    let sh = ShootingOptions::default();
    let opts = ContinuationOptions {
        ds: 0.02,
        ds_max: 0.05,
        param_min: 1.5,
        param_max: 3.0,
        ..Default::default()
    };
    let gear = Gear::paper(25.0, 1.5)?;
    let sym = Continuation::new(
        gear,
        GearParam::F,
        OrbitSpec::symmetric(1),
        [2.98, 0.6],
        opts,
    )?
    .run(None)?;
    report("symmetric branch (G, winding 1)", &sym);
    let sb_hi = sym
        .specials_of(SpecialKind::SymmetryBreaking)
        .last()
        .cloned()
        .ok_or_else(|| gearbif::Error::NotFound {
            what: "symmetry-breaking point".into(),
        })?;
    let sw = switch_branch(&sym, &sb_hi, -1e-3, &sh)?;
    let asym = Continuation::from_orbit(
        sw.system,
        GearParam::F,
        &sw.orbit,
        ContinuationOptions {
            ds: -0.005,
            ds_max: 0.02,
            max_steps: 400,
            ..opts
        },
    )?
    .run(None)?;
    report(
        "asymmetric branch (P_T, from the SB point at 2.50 Hz)",
        &asym,
    );
    let sb_lo = sym
        .specials_of(SpecialKind::SymmetryBreaking)
        .next()
        .cloned()
        .ok_or_else(|| gearbif::Error::NotFound {
            what: "symmetry-breaking point".into(),
        })?;
    let sw2 = switch_branch(&sym, &sb_lo, -1e-3, &sh)?;
    let asym2 = Continuation::from_orbit(
        sw2.system,
        GearParam::F,
        &sw2.orbit,
        ContinuationOptions {
            ds: -0.005,
            ds_max: 0.02,
            max_steps: 400,
            ..opts
        },
    )?
    .run(None)?;
    report(
        "asymmetric branch (P_T, from the SB point at 2.08 Hz)",
        &asym2,
    );
    let mut labels = vec![
        "symmetric, T/2 (G, p = 1)".to_string(),
        format!("asymmetric, T, from SB at {:.4} Hz", sb_hi.param),
        format!("asymmetric, T, from SB at {:.4} Hz", sb_lo.param),
    ];
    let mut branches = vec![sym.clone(), asym.clone(), asym2];
    // period doubling cascade: switch at the flip onto P_T², then again
    let mut last = asym;
    for level in 1..=2 {
        let Some(fl) = last.specials_of(SpecialKind::Flip).next().cloned() else {
            println!("no flip on level {level}");
            break;
        };
        match switch_branch(&last, &fl, -1e-4, &sh) {
            Ok(s) => {
                let b = Continuation::from_orbit(
                    s.system,
                    GearParam::F,
                    &s.orbit,
                    ContinuationOptions {
                        ds: -0.002,
                        ds_max: 0.01,
                        max_steps: 300,
                        param_min: 1.7,
                        ..opts
                    },
                )?
                .run(None)?;
                report(&format!("period-{} branch", 2 * last.spec.iterations), &b);
                labels.push(format!(
                    "period {}T, from the flip at {:.4} Hz",
                    b.spec.iterations, fl.param
                ));
                branches.push(b.clone());
                last = b;
            }
            Err(e) => {
                println!("switching at the flip at {:.6} Hz failed: {e}", fl.param);
                break;
            }
        }
    }
    println!("continuation total: {:?}", t0.elapsed());
    // quasi-static sweeps up and down (no Newton, no Jacobians): symmetric or not, closing or not
    let up: Vec<f64> = (0..=75).map(|i| 1.5 + 0.02 * i as f64).collect();
    let dn: Vec<f64> = up.iter().rev().copied().collect();
    let mk = |f| Gear::paper(25.0, f);
    let a = quasi_static_sweep(mk, &up, [2.98, 0.6], 200, 1e-9)?;
    let last_x = a.last().map(|p| p.x).unwrap_or([2.98, 19.0]);
    let d = quasi_static_sweep(mk, &dn, last_x, 200, 1e-9)?;
    let state = |p: &gearbif::orbits::SweepPoint| {
        if p.closing > 1e-4 {
            "not period-1"
        } else if p.asymmetry < 1e-5 {
            "T/2 (symmetric)"
        } else {
            "T (asymmetric)"
        }
    };
    for (name, s) in [("up", &a), ("down", &d)] {
        let mut prev = "";
        for p in s.iter() {
            let st = state(p);
            if st != prev {
                println!("sweep {name}: from f = {:.2} Hz {st}", p.param);
                prev = st;
            }
        }
    }
    // curves bounding the T/2 and T regimes in (Θ, f): the two symmetry-breaking points in Θ
    let mut curves = Vec::new();
    for sp in [&sb_lo, &sb_hi] {
        for vals in [
            (0..=10).map(|i| 25.0 + i as f64).collect::<Vec<_>>(),
            (0..=10).map(|i| 25.0 - i as f64).collect::<Vec<_>>(),
        ] {
            let g = Gear::paper(25.0, sp.param)?;
            let c = follow(
                &g,
                &OrbitSpec::symmetric(1),
                SpecialKind::SymmetryBreaking,
                GearParam::F,
                GearParam::ThetaDeg,
                sp.x,
                sp.param,
                &vals,
                &sh,
            )?;
            for p in c.points.iter().step_by(5) {
                println!(
                    "SB curve from {:.4} Hz: Θ = {:4.1}°, f = {:.6} Hz",
                    sp.param, p.along, p.free
                );
            }
            if let Some(r) = &c.stopped {
                println!("  stopped {r}");
            }
            let which = if sp.param < sb_hi.param {
                "lower (subcritical)"
            } else {
                "upper (supercritical)"
            };
            curves.push((
                format!("{which} SB curve, from {:.4} Hz at 25°", sp.param),
                c,
            ));
        }
    }
    println!("total: {:?}", t0.elapsed());
    std::fs::create_dir_all(&dir).map_err(|e| gearbif::Error::Io(e.to_string()))?;
    gearbif::io::write_json_atomic(dir.join("theta25_branches.json"), &branches)?;
    #[cfg(feature = "plot")]
    {
        use gearbif::plotting::branch::{BoundaryPlot, BranchDiagram, MultiplierPlot};
        let m = MultiplierPlot {
            title: "Θ = 25°: multipliers μ_G of the symmetric branch, 1.5–3 Hz".into(),
            branch: Some(sym),
        };
        gearbif::plotting::save(&m, dir.join("theta25_multipliers.svg"))?;
        gearbif::plotting::save(&m, dir.join("theta25_multipliers.png"))?;
        let fig = BranchDiagram {
            title: "Θ = 25°: symmetric, asymmetric and period-doubled orbits".into(),
            branches,
            labels,
            ..Default::default()
        };
        gearbif::plotting::save(&fig, dir.join("fig9_branches.svg"))?;
        gearbif::plotting::save(&fig, dir.join("fig9_branches.png"))?;
        let bp = BoundaryPlot {
            title: "symmetry-breaking curves in (Θ, f): T/2 outside, T between".into(),
            curves,
            ..Default::default()
        };
        gearbif::plotting::save(&bp, dir.join("fig9_sb_curves.svg"))?;
        gearbif::plotting::save(&bp, dir.join("fig9_sb_curves.png"))?;
    }
    Ok(())
}
