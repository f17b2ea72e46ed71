//! Two-parameter curves by pseudo-arclength on the minimally augmented systems, and the
//! codimension-two points located on them, each checked by an independent computation.

use gearbif::continuation::codim2::{Codim2Kind, Codim2Point};
use gearbif::continuation::palc2::{continue_curve, lock_loss_curves, CurveOptions};
use gearbif::continuation::two_param::{follow, locate_augmented, Curve};
use gearbif::continuation::{Continuation, ContinuationOptions, SpecialKind};
use gearbif::integrator::EventDriven;
use gearbif::model::{ForcedPendulum, Gear, GearParam, Parametrised, PendulumParam};
use gearbif::orbits::{OrbitSpec, ShootingOptions};

fn codim2<S: Parametrised>(c: &Curve<S>, kind: Codim2Kind) -> Vec<&Codim2Point> {
    c.codim2.iter().filter(|q| q.kind == kind).collect()
}

fn delta(theta_deg: f64) -> f64 {
    1.0 - 3.0 * theta_deg.to_radians().sin().powi(2)
}

/// The fold curve of the forward lock passes its turning point in Θ (the steep part of f_c(Θ) near
/// 49.4°) and continues on the lower side; points on both sides agree with the fold located at fixed
/// Θ by the determinant-based augmented system; the turning point agrees with the maximum of Θ(f)
/// from natural continuation in f, and with the reversed lock's turning point mapped by the exact
/// symmetry Δ → −Δ (which the two curves, computed separately, must respect).
#[test]
fn fc_curve_by_arclength_passes_its_theta_turning_point() {
    let base = Gear::paper(0.0, 1.0).unwrap();
    let opts = CurveOptions {
        free_range: (0.05, 100.0),
        ..Default::default()
    };
    let curves = lock_loss_curves(&base, &opts).unwrap();
    let (fwd, rev) = (&curves[0].1, &curves[1].1);
    // the first turning point in Θ (the curve ends further on, see docs/continuation.md)
    let t = codim2(fwd, Codim2Kind::TurningAlong)[0];
    assert!(t.along > 49.3 && t.along < 49.5, "{t:?}");
    // the curve went on past the turn: points below Θ* after it
    let after: Vec<_> = fwd.points.iter().skip(t.after_point + 1).collect();
    assert!(after
        .iter()
        .any(|p| p.along < t.along - 0.05 && p.free < t.free));
    // both sides against the fold located at fixed Θ (another test function, 1 − tr + det)
    let sh = ShootingOptions::default();
    let mut checked = [0, 0];
    for (i, p) in fwd.points.iter().enumerate() {
        // away from the turn and from the end of the curve near 49.29° (see docs/continuation.md)
        if p.along < 45.0 || (p.along - t.along).abs() < 0.03 || p.along < 49.3 && i > t.after_point
        {
            continue;
        }
        let g = base.with_param(GearParam::ThetaDeg, p.along).unwrap();
        let q = locate_augmented(
            &g,
            &fwd.spec,
            SpecialKind::Fold,
            GearParam::F,
            [p.x[0] + 1e-4, p.x[1] * (1.0 + 1e-5)],
            p.free * (1.0 + 1e-5),
            &sh,
        )
        .unwrap();
        assert!(
            (q.free - p.free).abs() < 1e-8,
            "Θ = {}: {} vs {}",
            p.along,
            q.free,
            p.free
        );
        checked[usize::from(i > t.after_point)] += 1;
    }
    assert!(checked[0] >= 3 && checked[1] >= 2, "{checked:?}");
    // the turning point against natural continuation in f solving for Θ: vertex of Θ(f)
    let h = 0.01;
    let g = base
        .with_param(GearParam::ThetaDeg, t.along)
        .unwrap()
        .with_param(GearParam::F, t.free - h)
        .unwrap();
    let nat = follow(
        &g,
        &fwd.spec,
        SpecialKind::Fold,
        GearParam::ThetaDeg,
        GearParam::F,
        t.x,
        t.along,
        &[t.free - h, t.free, t.free + h],
        &sh,
    )
    .unwrap();
    assert_eq!(nat.points.len(), 3, "{:?}", nat.stopped);
    let y: Vec<f64> = nat.points.iter().map(|p| p.free).collect();
    let (a2, a1) = (
        (y[2] - 2.0 * y[1] + y[0]) / (2.0 * h * h),
        (y[2] - y[0]) / (2.0 * h),
    );
    let (f_vertex, th_vertex) = (t.free - a1 / (2.0 * a2), y[1] - a1 * a1 / (4.0 * a2));
    println!(
        "turning point Θ* = {:.9}°, f = {:.9} Hz; natural-continuation vertex Θ = {th_vertex:.9}°, \
         f = {f_vertex:.9} Hz",
        t.along, t.free
    );
    assert!(
        (th_vertex - t.along).abs() < 1e-6,
        "{th_vertex} vs {}",
        t.along
    );
    assert!((f_vertex - t.free).abs() < 1e-3, "{f_vertex} vs {}", t.free);
    // the reversed lock: the same turning point with Δ → −Δ
    let r = codim2(rev, Codim2Kind::TurningAlong);
    println!(
        "reversed lock: Θ* = {:.9}°, f = {:.9} Hz",
        r[0].along, r[0].free
    );
    assert!((r[0].free - t.free).abs() < 1e-8);
    assert!((delta(r[0].along) + delta(t.along)).abs() < 1e-8);
}

fn pendulum(amplitude: f64) -> ForcedPendulum {
    ForcedPendulum::new(std::f64::consts::TAU, 0.3, 0.0, amplitude, 0.5).unwrap()
}

/// The two folds of the resonance curve of the forced pendulum at amplitude `a`, by one-parameter
/// continuation in f (determinant test functions, located on the branch).
fn pendulum_folds(a: f64) -> Vec<(f64, [f64; 2])> {
    let opts = ContinuationOptions {
        ds: 0.02,
        ds_max: 0.02,
        param_min: 0.5,
        param_max: 1.1,
        ..Default::default()
    };
    let x0 = [a / (std::f64::consts::TAU.powi(2) - 9.87), 0.0];
    let sys = pendulum(a);
    let b = Continuation::new(sys, PendulumParam::F, OrbitSpec::symmetric(0), x0, opts)
        .unwrap()
        .run(None)
        .unwrap();
    b.specials_of(SpecialKind::Fold)
        .map(|s| (s.param, s.x))
        .collect()
}

/// A generic system through the parameter lens: the fold curve of the softening resonance of the
/// forced pendulum in (A, f) passes its cusp, where the cusp test ⟨∇ₓg, v⟩ and both tangent
/// components dA/ds, df/ds vanish together. Independent check: the distance of the two folds found
/// by one-parameter continuation at A > A_c scales like (A − A_c)^{3/2}; A_c extrapolated from three
/// amplitudes agrees with the located cusp.
#[test]
fn pendulum_fold_curve_passes_a_cusp_confirmed_by_the_fold_pair() {
    let folds = pendulum_folds(3.0);
    assert_eq!(folds.len(), 2, "{folds:?}");
    let (f0, x0) = folds
        .iter()
        .copied()
        .fold((0.0, [0.0; 2]), |a, b| if b.0 > a.0 { b } else { a });
    let sys = pendulum(3.0).with_param(PendulumParam::F, f0).unwrap();
    let opts = CurveOptions {
        ds: -0.2,
        ds_max: 0.2,
        max_steps: 20,
        along_range: (1.0, 3.0),
        ..Default::default()
    };
    let c = continue_curve(
        &EventDriven,
        &sys,
        &OrbitSpec::symmetric(0),
        SpecialKind::Fold,
        PendulumParam::F,
        PendulumParam::Amplitude,
        x0,
        f0,
        &opts,
    )
    .unwrap();
    let cusp = codim2(&c, Codim2Kind::Cusp);
    assert_eq!(cusp.len(), 1, "{:?}", c.codim2);
    let k = cusp[0];
    // the two tangent components vanish at the same point (located separately)
    for kind in [Codim2Kind::TurningAlong, Codim2Kind::TurningFree] {
        let q = codim2(&c, kind);
        let q = q
            .iter()
            .find(|q| q.after_point == k.after_point)
            .expect("turning point");
        assert!(
            (q.along - k.along).abs() < 1e-9 && (q.free - k.free).abs() < 1e-9,
            "{q:?}"
        );
    }
    // the fold pair at A_c + δ: (Δf)^{2/3} is linear in δ to leading order; quadratic through three
    let ds = [0.02, 0.04, 0.08];
    let w: Vec<f64> = ds
        .iter()
        .map(|d| {
            let f = pendulum_folds(k.along + d);
            assert_eq!(f.len(), 2, "{f:?}");
            (f[0].0 - f[1].0).abs().powf(2.0 / 3.0)
        })
        .collect();
    // fit w = a (δ − δ₀) + b (δ − δ₀)², δ₀ = A_c(extrapolated) − A_c(located)
    let (d1, d2, d3) = (ds[0], ds[1], ds[2]);
    let b = ((w[2] - w[1]) / (d3 - d2) - (w[1] - w[0]) / (d2 - d1)) / (d3 - d1);
    let a = (w[1] - w[0]) / (d2 - d1) - b * (d1 + d2);
    let c0 = w[0] - a * d1 - b * d1 * d1;
    let delta0 = (-a + (a * a - 4.0 * b * c0).sqrt()) / (2.0 * b);
    println!(
        "cusp A = {:.10}, f = {:.10} Hz; fold-pair extrapolation A_c = {:.10} (difference {:.1e})",
        k.along,
        k.free,
        k.along + delta0,
        delta0
    );
    assert!(delta0.abs() < 2e-3, "{delta0}");
}

/// The two symmetry-breaking curves of the T window are one curve by pseudo-arclength, turning in Θ
/// where they meet. Independent check: at fixed Θ = Θ* + δ the two symmetry-breaking points located
/// by the determinant-based augmented Newton are Δf apart with Δf² linear in δ to leading order; the
/// meeting angle extrapolated from three δ agrees with the located turning point.
#[test]
fn symmetry_breaking_curves_meet_at_a_located_turning_point_in_theta() {
    let (f0, x0) = (2.0777402, [2.98464, 8.79534]);
    let g = Gear::paper(25.0, f0).unwrap();
    let opts = CurveOptions {
        ds: -0.2,
        ds_max: 0.5,
        along_range: (10.0, 25.0),
        ..Default::default()
    };
    let spec = OrbitSpec::symmetric(1);
    let c = continue_curve(
        &EventDriven,
        &g,
        &spec,
        SpecialKind::SymmetryBreaking,
        GearParam::F,
        GearParam::ThetaDeg,
        x0,
        f0,
        &opts,
    )
    .unwrap();
    let t = codim2(&c, Codim2Kind::TurningAlong)[0];
    assert!((t.along - 16.3).abs() < 0.1, "{t:?}");
    // back at Θ = 25° on the other branch: the supercritical point 2.5013844 Hz (docs/continuation.md)
    let end = c.points.last().unwrap();
    assert!(
        (end.along - 25.0).abs() < 1e-12 && (end.free - 2.501384436).abs() < 1e-7,
        "{end:?}"
    );
    let sh = ShootingOptions::default();
    let ds = [0.02, 0.04, 0.08];
    let w: Vec<f64> = ds
        .iter()
        .map(|d| {
            let th = t.along + d;
            let gt = base_at(th);
            let pair: Vec<f64> = [-1.0, 1.0]
                .iter()
                .map(|s| {
                    let guess = t.free + s * 0.02 * (d / 0.02f64).sqrt();
                    locate_augmented(
                        &gt.with_param(GearParam::F, guess).unwrap(),
                        &spec,
                        SpecialKind::SymmetryBreaking,
                        GearParam::F,
                        t.x,
                        guess,
                        &sh,
                    )
                    .unwrap()
                    .free
                })
                .collect();
            assert!((pair[1] - pair[0]).abs() > 1e-4, "Θ = {th}: {pair:?}");
            (pair[1] - pair[0]).powi(2)
        })
        .collect();
    let (d1, d2, d3) = (ds[0], ds[1], ds[2]);
    let b = ((w[2] - w[1]) / (d3 - d2) - (w[1] - w[0]) / (d2 - d1)) / (d3 - d1);
    let a = (w[1] - w[0]) / (d2 - d1) - b * (d1 + d2);
    let c0 = w[0] - a * d1 - b * d1 * d1;
    let delta0 = if b.abs() > 1e-12 {
        (-a + (a * a - 4.0 * b * c0).sqrt()) / (2.0 * b)
    } else {
        -c0 / a
    };
    println!(
        "SB curves meet at Θ = {:.9}°, f = {:.9} Hz; pair extrapolation Θ* = {:.9}° ({delta0:.1e})",
        t.along,
        t.free,
        t.along + delta0
    );
    assert!(delta0.abs() < 1e-5, "{delta0}");
}

fn base_at(theta_deg: f64) -> Gear {
    Gear::paper(theta_deg, 2.5).unwrap()
}
