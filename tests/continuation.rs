//! Continuation and located special points, each confirmed by an independent answer: the analytic
//! lock branch and f_c, the augmented-system Newton (a second locating method), convergence in the
//! integrator tolerance, and quasi-static sweeps of the simulation (no Newton, no Jacobians).

use approx::assert_relative_eq;
use gearbif::continuation::two_param::{follow, locate_augmented};
use gearbif::continuation::*;
use gearbif::model::{Gear, GearParam, Parameter, Parametrised};
use gearbif::orbits::{quasi_static_sweep, OrbitSpec, ShootingOptions};
use gearbif::Error;
use std::f64::consts::{FRAC_PI_2, TAU};
use std::sync::OnceLock;

fn lock_branch_theta0() -> Branch {
    let gear = Gear::paper(0.0, 5.0).unwrap();
    let lock = gear.lock_branch().unwrap().stable;
    let opts = ContinuationOptions {
        ds: 0.5,
        ds_max: 5.0,
        param_min: 0.5,
        param_max: 60.0,
        max_multiplier: 1e3,
        ..Default::default()
    };
    Continuation::new(
        gear,
        GearParam::F,
        OrbitSpec::symmetric(1),
        lock.state,
        opts,
    )
    .unwrap()
    .run(None)
    .unwrap()
}

fn sym_branch_theta25(tol: f64) -> Branch {
    sym_branch_theta25_with(gearbif::integrator::DEFAULT_METHOD, tol)
}

/// The symmetric T-orbit branch at Θ = 25° from 1.5 Hz to 3 Hz, continued by `method`.
fn sym_branch_theta25_with<M: gearbif::integrator::FlowMethod<Gear>>(
    method: M,
    tol: f64,
) -> Branch {
    let gear = Gear::paper(25.0, 1.5).unwrap();
    let opts = ContinuationOptions {
        ds: 0.02,
        ds_max: 0.05,
        param_min: 1.5,
        param_max: 3.0,
        shooting: ShootingOptions {
            tol,
            ..Default::default()
        },
        ..Default::default()
    };
    Continuation::with_method(
        method,
        gear,
        GearParam::F,
        OrbitSpec::symmetric(1),
        [2.98, 0.6],
        opts,
    )
    .unwrap()
    .run(None)
    .unwrap()
}

#[test]
fn theta0_lock_branch_equals_analytic_and_folds_at_fc() {
    let b = lock_branch_theta0();
    let fc = Gear::paper(0.0, 1.0)
        .unwrap()
        .lock_loss_frequency()
        .unwrap();
    // every point is on the analytic branch: δ = β(0) with sin δ = (2πfζ + η)/g, ω = 2πf
    let mut n_stable = 0;
    let mut n_unstable = 0;
    for p in &b.points {
        let g = Gear::paper(0.0, p.param).unwrap();
        let lb = g.lock_branch().unwrap();
        let lp = if p.x[0] > FRAC_PI_2 {
            lb.stable
        } else {
            lb.unstable
        };
        assert_relative_eq!(p.x[0], lp.state[0], epsilon = 1e-7);
        assert_relative_eq!(p.x[1], TAU * p.param, epsilon = 1e-6);
        assert_eq!(p.stable, lp.stable, "at f = {}", p.param);
        if p.stable {
            n_stable += 1
        } else {
            n_unstable += 1
        }
        // G-multipliers squared are the analytic P_T multipliers
        let mut ana: Vec<f64> = lp.multipliers.iter().map(|z| z.norm()).collect();
        let mut num: Vec<f64> = p
            .floquet
            .multipliers
            .iter()
            .map(|z| z[0].hypot(z[1]).powi(2))
            .collect();
        ana.sort_by(f64::total_cmp);
        num.sort_by(f64::total_cmp);
        for (a, n) in ana.iter().zip(&num) {
            assert_relative_eq!(a, n, max_relative = 1e-5);
        }
    }
    assert!(n_stable > 5 && n_unstable > 5);
    let folds: Vec<_> = b.specials_of(SpecialKind::Fold).collect();
    assert_eq!(folds.len(), 1, "{:?}", b.specials);
    let fold = folds[0];
    assert!(fold.precision < 1e-6);
    assert!((fold.param - fc).abs() < 1e-6, "{} vs {fc}", fold.param);
    assert_relative_eq!(fold.x[0], FRAC_PI_2, epsilon = 1e-3);
    assert!(fold.stability_change);
    // the unstable part stops where single shooting is no longer trustworthy, with the reason
    assert!(matches!(b.stop, StopReason::MultiplierLimit(m) if m > 1e3));
    // second method: Newton on the augmented system
    let g = Gear::paper(0.0, fold.param).unwrap();
    let aug = locate_augmented(
        &g,
        &OrbitSpec::symmetric(1),
        SpecialKind::Fold,
        GearParam::F,
        [fold.x[0] + 0.01, fold.x[1]],
        fold.param - 0.1,
        &ShootingOptions::default(),
    )
    .unwrap();
    assert!((aug.free - fc).abs() < 1e-7, "{}", aug.free);
}

#[test]
fn theta0_lock_loss_confirmed_by_quasi_static_sweep() {
    // upward sweep through f_c in small steps (the basin of the lock shrinks to nothing at the fold:
    // with coarse steps a sweep loses the lock early, as the paper notes for its 1 Hz steps)
    let vals = [
        39.80, 39.81, 39.82, 39.83, 39.835, 39.839, 39.8405, 39.845, 39.85,
    ];
    let g0 = Gear::paper(0.0, 39.8).unwrap();
    let x0 = g0.lock_branch().unwrap().stable.state;
    let sw = quasi_static_sweep(|f| Gear::paper(0.0, f), &vals, x0, 300, 1e-9).unwrap();
    for p in &sw {
        // near the fold the approach is slow (a multiplier near 1): accept a closing of 1e-3
        let locked = p.winding == 1 && p.closing < 1e-3;
        if p.param <= 39.835 {
            assert!(locked, "{p:?}");
        } else if p.param >= 39.845 {
            assert!(!locked, "{p:?}");
        }
    }
}

#[test]
fn theta25_symmetry_breaking_points_located_and_converged() {
    let b = sym_branch_theta25(1e-11);
    let sb: Vec<_> = b.specials_of(SpecialKind::SymmetryBreaking).collect();
    assert_eq!(sb.len(), 2, "{:?}", b.specials);
    assert!(b.specials_of(SpecialKind::Fold).next().is_none());
    assert!((sb[0].param - 2.0777402).abs() < 1e-5, "{}", sb[0].param);
    assert!((sb[1].param - 2.5013844).abs() < 1e-5, "{}", sb[1].param);
    for s in &sb {
        assert!(s.precision < 1e-7, "{s:?}");
        assert!((s.floquet.multipliers[0][0] + 1.0).abs() < 1e-6);
        assert!(s.eigenvector.is_some());
        // second method (augmented Newton) and a tighter integrator tolerance agree
        let g = Gear::paper(25.0, s.param).unwrap();
        let tight = ShootingOptions {
            tol: 1e-12,
            ..Default::default()
        };
        let aug = locate_augmented(
            &g,
            &OrbitSpec::symmetric(1),
            SpecialKind::SymmetryBreaking,
            GearParam::F,
            s.x,
            s.param + 1e-3,
            &tight,
        )
        .unwrap();
        assert!(
            (aug.free - s.param).abs() < 1e-7,
            "{} vs {}",
            aug.free,
            s.param
        );
    }
    // convergence in tolerance of the branch location
    let loose = sym_branch_theta25(1e-9);
    let sl: Vec<_> = loose.specials_of(SpecialKind::SymmetryBreaking).collect();
    for (a, c) in sb.iter().zip(&sl) {
        assert!(
            (a.param - c.param).abs() < 1e-6,
            "{} vs {}",
            a.param,
            c.param
        );
    }
}

#[test]
fn theta25_transitions_confirmed_by_up_and_down_sweeps() {
    let mk = |f| Gear::paper(25.0, f);
    let sym = |a: f64| a < 1e-6;
    // up through the subcritical SB at 2.0777: symmetric until it, asymmetric right after
    let up = [2.05, 2.07, 2.085, 2.1];
    let s = quasi_static_sweep(mk, &up, [2.98, 8.0], 300, 1e-9).unwrap();
    assert!(sym(s[0].asymmetry) && sym(s[1].asymmetry));
    assert!(!sym(s[2].asymmetry) && !sym(s[3].asymmetry), "{s:?}");
    // on, through the supercritical SB at 2.5014: asymmetric below, symmetric above
    let up2 = [2.3, 2.45, 2.49, 2.515, 2.53];
    let s2 = quasi_static_sweep(mk, &up2, s[3].x, 300, 1e-9).unwrap();
    assert!(s2[..3].iter().all(|p| !sym(p.asymmetry)), "{s2:?}");
    assert!(s2[3..].iter().all(|p| p.asymmetry < 1e-4), "{s2:?}");
    // down: asymmetric again below 2.5014 (supercritical: no hysteresis), and it stays asymmetric
    // down to the flip of the asymmetric branch at 1.8549 (hysteresis between 1.855 and 2.078)
    let dn = [2.45, 2.2, 2.0, 1.9, 1.87, 1.86];
    let s3 = quasi_static_sweep(mk, &dn, s2[4].x, 300, 1e-9).unwrap();
    assert!(
        s3.iter().all(|p| !sym(p.asymmetry) && p.closing < 1e-6),
        "{s3:?}"
    );
    // below the flip the period-1 asymmetric orbit is gone; by 1.80 it is symmetric again
    let dn2 = [1.84, 1.82, 1.8];
    let s4 = quasi_static_sweep(mk, &dn2, s3[5].x, 300, 1e-9).unwrap();
    assert!(s4[0].closing > 1e-3, "{s4:?}");
    assert!(sym(s4[2].asymmetry) && s4[2].closing < 1e-6, "{s4:?}");
}

#[test]
fn theta25_switch_to_asymmetric_branch_and_find_its_flip() {
    let a = default_asymmetric_branch();
    check_theta25_asymmetric_branch(a, "default method");
    let flips: Vec<_> = a.specials_of(SpecialKind::Flip).collect();
    // the branch passes stick onset and end: nonsmooth points with (crossings, sticks) changes
    let ns: Vec<_> = a.specials_of(SpecialKind::Nonsmooth).collect();
    assert!(!ns.is_empty());
    for s in &ns {
        let j = s.jump.as_ref().unwrap();
        assert_ne!(j.events_before.signature(), j.events_after.signature());
        assert!(s.precision < 1e-7);
    }
    // period doubling: switch at the flip onto P_T², a period-2 orbit
    let pd = switch_branch(a, flips[0], -1e-3, &ShootingOptions::default()).unwrap();
    assert_eq!(pd.spec, OrbitSpec::stroboscopic(2, 2));
    // it is not a fixed point of P_T
    let (r1, _) = gearbif::orbits::residual(
        &pd.system,
        &OrbitSpec::stroboscopic(1, 1),
        pd.orbit.x,
        &ShootingOptions::default(),
        false,
    )
    .unwrap();
    assert!(r1[0].hypot(r1[1]) > 1e-4);
}

/// The asymmetric P_T branch of `theta25_switch_to_asymmetric_branch_and_find_its_flip` (switched
/// from the symmetric branch continued by `method`) continued by `method2`.
fn theta25_asymmetric_branch<M, M2>(method: M, method2: M2) -> Branch
where
    M: gearbif::integrator::FlowMethod<Gear> + Clone,
    M2: gearbif::integrator::FlowMethod<Gear>,
{
    let b = sym_branch_theta25_with(method.clone(), 1e-11);
    let sb = b
        .specials_of(SpecialKind::SymmetryBreaking)
        .find(|s| s.param > 2.4)
        .unwrap()
        .clone();
    let sw = switch_branch_with(&method, &b, &sb, -1e-3, &ShootingOptions::default()).unwrap();
    assert_eq!(sw.spec, OrbitSpec::stroboscopic(1, 1));
    assert!(sw.separation > 1e-3);
    assert!(sw.orbit.floquet.stable);
    let opts = ContinuationOptions {
        ds: -0.005,
        ds_max: 0.02,
        param_min: 1.8,
        param_max: 3.0,
        max_steps: 400,
        ..Default::default()
    };
    Continuation::with_method(
        method2,
        sw.system,
        GearParam::F,
        sw.orbit.spec,
        sw.orbit.x,
        opts,
    )
    .unwrap()
    .run(None)
    .unwrap()
}

/// [`theta25_asymmetric_branch`] with the default method (the DOP853), computed once for the two
/// tests that use it.
fn default_asymmetric_branch() -> &'static Branch {
    static A: OnceLock<Branch> = OnceLock::new();
    A.get_or_init(|| {
        use gearbif::integrator::DEFAULT_METHOD;
        theta25_asymmetric_branch(DEFAULT_METHOD, DEFAULT_METHOD)
    })
}

/// The checks of `theta25_switch_to_asymmetric_branch_and_find_its_flip` on that branch.
fn check_theta25_asymmetric_branch(a: &Branch, label: &str) {
    for s in &a.specials {
        eprintln!("{label}: {:?} at {} ± {:e}", s.kind, s.param, s.precision);
    }
    assert_eq!(a.stop, StopReason::ParameterBound(1.8), "{:?}", a.stop);
    let flips: Vec<_> = a.specials_of(SpecialKind::Flip).collect();
    assert_eq!(flips.len(), 1, "{:?}", a.specials);
    assert!((flips[0].param - 1.8549349).abs() < 1e-5);
    assert!(flips[0].precision < 1e-7);
    for s in a.specials_of(SpecialKind::Nonsmooth) {
        assert!(s.precision < 1e-7, "{} ± {:e}", s.param, s.precision);
    }
}

#[test]
fn theta25_asymmetric_branch_with_the_dp5_finds_the_same_points() {
    // The whole chain (symmetric branch, switch, asymmetric branch) with the default DOP853 (shared
    // with the test above) and with the DP5 as a second method: the orbit first sticks at F ≈ 2.37033877 (ω = 0 touched where static friction holds,
    // a corner of the branch). With a sign test at 16 points per step the DOP853 bracketed a
    // nonsmooth point only to ≥ 1e-7; an exact search of the whole step found spurious re-sticks
    // right after tangential releases (15 nonsmooth points, two bracketed to 5.7e-5 and 2.8e-3).
    // With the exact search from 1/16 of a step that starts on Σ on, both methods find the same
    // three nonsmooth points and flip within their brackets (measured, DOP853 / DP5:
    // 2.3703387830 / 2.3703387657, 2.3641732853 / 2.3641732821, 2.3429963756 / 2.3429963706,
    // flip 1.8549348707 / 1.8549348727).
    use gearbif::integrator::EventDriven;
    let a = default_asymmetric_branch();
    let b = theta25_asymmetric_branch(EventDriven, EventDriven);
    check_theta25_asymmetric_branch(&b, "DP5");
    let pa: Vec<_> = a
        .specials
        .iter()
        .map(|s| (s.kind, s.param, s.precision))
        .collect();
    let pb: Vec<_> = b
        .specials
        .iter()
        .map(|s| (s.kind, s.param, s.precision))
        .collect();
    assert_eq!(pa.len(), pb.len(), "{pa:?} vs {pb:?}");
    for ((ka, xa, ea), (kb, xb, eb)) in pa.iter().zip(&pb) {
        assert_eq!(ka, kb);
        // both located to their brackets; the two integrators' orbits differ by their errors
        // (measured: the stick onset 1.73e-8 apart with brackets 4.3e-9 + 9.8e-9, the others
        // within their brackets)
        assert!(
            (xa - xb).abs() < ea + eb + 1e-8,
            "{ka:?}: {xa} ± {ea:e} vs {xb} ± {eb:e}"
        );
    }
}

#[test]
fn fc_boundary_in_theta_hits_analytic_endpoints() {
    let opts = ShootingOptions::default();
    let fc = Gear::paper(0.0, 1.0)
        .unwrap()
        .lock_loss_frequency()
        .unwrap();
    let vals: Vec<f64> = (0..=10).map(|i| 2.5 * i as f64).collect();
    let g0 = Gear::paper(0.0, fc).unwrap();
    let c = follow(
        &g0,
        &OrbitSpec::symmetric(1),
        SpecialKind::Fold,
        GearParam::F,
        GearParam::ThetaDeg,
        [FRAC_PI_2, TAU * fc],
        fc - 0.05,
        &vals,
        &opts,
    )
    .unwrap();
    assert!(c.stopped.is_none());
    assert!((c.points[0].free - fc).abs() < 1e-7);
    assert!(c.points.windows(2).all(|w| w[1].free < w[0].free));
    // Θ = 25°: cross-check with the fold located by one-parameter continuation in f
    let p25 = c.points.iter().find(|p| p.along == 25.0).unwrap();
    let start = Gear::paper(25.0, 20.0).unwrap();
    let o = gearbif::orbits::orbit_from_simulation(&start, [2.5, TAU * 20.0], 400, 2, true, &opts)
        .unwrap();
    let br = Continuation::from_orbit(
        start,
        GearParam::F,
        &o,
        ContinuationOptions {
            ds: 1.0,
            ds_max: 2.0,
            param_min: 10.0,
            param_max: 40.0,
            max_steps: 60,
            ..Default::default()
        },
    )
    .unwrap()
    .run(None)
    .unwrap();
    let f25 = br.specials_of(SpecialKind::Fold).next().unwrap();
    assert!(
        (f25.param - p25.free).abs() < 1e-6,
        "{} vs {}",
        f25.param,
        p25.free
    );
    // Θ = 54.74° (Δ = −1): the reversed lock, winding −1, folds at the same analytic f_c
    let th = (2.0f64 / 3.0).sqrt().asin().to_degrees();
    let g1 = g0.with_param(GearParam::ThetaDeg, th).unwrap();
    let p = locate_augmented(
        &g1,
        &OrbitSpec::symmetric(-1),
        SpecialKind::Fold,
        GearParam::F,
        [FRAC_PI_2, -TAU * fc],
        fc - 0.1,
        &opts,
    )
    .unwrap();
    assert!((p.free - fc).abs() < 1e-6, "{}", p.free);
}

#[test]
fn bad_options_are_errors_not_panics() {
    let gear = Gear::paper(0.0, 5.0).unwrap();
    let x = gear.lock_branch().unwrap().stable.state;
    let spec = OrbitSpec::symmetric(1);
    let bad = ContinuationOptions {
        ds: 0.0,
        ..Default::default()
    };
    assert!(matches!(
        Continuation::new(gear, GearParam::F, spec, x, bad),
        Err(Error::InvalidParameter { name: "ds", .. })
    ));
    let out = ContinuationOptions {
        param_min: 10.0,
        param_max: 20.0,
        ..Default::default()
    };
    assert!(matches!(
        Continuation::new(gear, GearParam::F, spec, x, out),
        Err(gearbif::Error::InvalidParameter { name: "f", .. })
    ));
    assert!(matches!(
        GearParam::from_name("nope"),
        Err(Error::UnknownParameter { .. })
    ));
    // switching at a fold is refused with a reason
    let b = lock_branch_theta0();
    let f = b.specials_of(SpecialKind::Fold).next().unwrap();
    assert!(matches!(
        switch_branch(&b, f, 1e-3, &ShootingOptions::default()),
        Err(Error::UnsupportedPoint { kind: "fold", .. })
    ));
}

#[cfg(feature = "cli")]
#[test]
fn cli_continue_writes_branch_json_and_plots() {
    use clap::Parser;
    let dir = std::env::temp_dir().join(format!("gearbif-cont-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("lock.json");
    let svg = dir.join("lock.svg");
    let cli = gearbif::cli::Cli::try_parse_from([
        "gearbif",
        "continue",
        "--f",
        "5",
        "--lock",
        "stable",
        "--range",
        "0.5:60",
        "--ds",
        "0.5",
        "--ds-max",
        "5",
        "--max-multiplier",
        "1e3",
        "--out",
        out.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ])
    .unwrap();
    gearbif::cli::run(cli).unwrap();
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(doc["schema"], "gearbif.branches/1");
    let v: Vec<Branch> = serde_json::from_value(doc["branches"].clone()).unwrap();
    let fc = Gear::paper(0.0, 1.0)
        .unwrap()
        .lock_loss_frequency()
        .unwrap();
    let fold = v[0].specials_of(SpecialKind::Fold).next().unwrap();
    assert!((fold.param - fc).abs() < 1e-6);
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    // bad input is an error, not a panic
    let bad =
        gearbif::cli::Cli::try_parse_from(["gearbif", "continue", "--f", "5", "--range", "3:1"])
            .unwrap();
    assert!(gearbif::cli::run(bad).is_err());
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn theta25_nonsmooth_fold_and_narrow_stable_window_confirmed_by_simulation() {
    let b = sym_branch_theta25(1e-11);
    let sb = b
        .specials_of(SpecialKind::SymmetryBreaking)
        .next()
        .unwrap()
        .clone();
    let sw = switch_branch(&b, &sb, -1e-3, &ShootingOptions::default()).unwrap();
    let opts = ContinuationOptions {
        ds: -0.005,
        ds_max: 0.02,
        param_min: 1.9,
        param_max: 3.0,
        max_steps: 300,
        ..Default::default()
    };
    let a = Continuation::from_orbit(sw.system, GearParam::F, &sw.orbit, opts)
        .unwrap()
        .run(None)
        .unwrap();
    // stick onset where a multiplier jumps across +1 (2.31 → 0.51): a nonsmooth fold
    let nf = a
        .specials
        .iter()
        .find(|s| {
            s.kind == SpecialKind::Nonsmooth
                && s.jump.as_ref().unwrap().crosses.as_deref() == Some("fold")
        })
        .expect("nonsmooth fold");
    assert!((nf.param - 1.9278115).abs() < 1e-5, "{}", nf.param);
    assert!(nf.precision < 1e-7 && nf.stability_change);
    let j = nf.jump.as_ref().unwrap();
    assert_eq!(j.events_after.sticks, 1);
    assert_eq!(j.floquet_after.multipliers[1], [0.0, 0.0]);
    let fold = a
        .specials_of(SpecialKind::Fold)
        .next()
        .expect("smooth fold");
    assert!((fold.param - 1.9579023).abs() < 1e-5, "{}", fold.param);
    // independent: the stable orbit between them is an attractor of the simulation, and a sweep
    // loses it above the fold
    let p = a
        .points
        .iter()
        .find(|p| p.stable && p.param > 1.935 && p.param < 1.955)
        .expect("stable point in the window");
    let mk = |f| Gear::paper(25.0, f);
    let x0 = [p.x[0] + 1e-3, p.x[1] + 1e-2];
    let s = quasi_static_sweep(mk, &[p.param, 1.956, 1.962], x0, 300, 1e-9).unwrap();
    let d0 = (s[0].x[0] - p.x[0].rem_euclid(TAU)).hypot(s[0].x[1] - p.x[1]);
    assert!(d0 < 1e-5, "relaxed back onto the orbit: {d0}");
    assert!(s[0].asymmetry > 1e-3 && s[1].asymmetry > 1e-3 && s[1].closing < 1e-5);
    // above the fold the narrow T-state is gone: the sweep lands elsewhere
    let d2 = (s[2].x[0] - s[1].x[0]).hypot(s[2].x[1] - s[1].x[1]);
    assert!(d2 > 0.1 || s[2].closing > 1e-3, "{s:?}");
}

#[test]
fn continuation_in_theta_uses_the_chain_rule_and_meets_the_fc_curve() {
    // ∂F/∂Θ from the Δ column times dΔ/dΘ against central differences
    let sh = ShootingOptions::default();
    let g = Gear::paper(20.0, 10.0).unwrap();
    let spec = OrbitSpec::symmetric(1);
    let x = [2.0, 60.0];
    let (_, img) = gearbif::orbits::residual(&g, &spec, x, &sh, false).unwrap();
    let d = gearbif::model::param_derivative(&g, GearParam::ThetaDeg, img.jac_p.as_ref().unwrap())
        .unwrap();
    let h = 1e-5;
    let r = |th: f64| {
        let gg = g.with_param(GearParam::ThetaDeg, th).unwrap();
        gearbif::orbits::residual(&gg, &spec, x, &sh, false)
            .unwrap()
            .0
    };
    let (rp, rm) = (r(20.0 + h), r(20.0 - h));
    for i in 0..2 {
        assert_relative_eq!(d[i], (rp[i] - rm[i]) / (2.0 * h), max_relative = 1e-5);
    }
    assert_relative_eq!(g.param(GearParam::ThetaDeg), 20.0, epsilon = 1e-10);
    // at f = f_c(25°) from the boundary, the lock branch continued in Θ folds at Θ = 25°
    let f25 = 28.2708171273;
    let g10 = Gear::paper(10.0, f25).unwrap();
    let o = gearbif::orbits::shoot(&g10, &spec, [2.4, TAU * f25], &sh).unwrap();
    assert!(o.floquet.stable);
    let b = Continuation::from_orbit(
        g10,
        GearParam::ThetaDeg,
        &o,
        ContinuationOptions {
            ds: 1.0,
            ds_max: 2.0,
            param_min: 0.0,
            param_max: 40.0,
            max_steps: 60,
            ..Default::default()
        },
    )
    .unwrap()
    .run(None)
    .unwrap();
    let fold = b.specials_of(SpecialKind::Fold).next().unwrap();
    assert!((fold.param - 25.0).abs() < 1e-5, "{}", fold.param);
}
