//! Checks of the recorded gear's lens: every analytic column against central differences (of the
//! forces and of the map), and the base model against the paper's [`Gear`].

use super::{Coefficients, ExtraTerm, Geometry, RecordedModel, RecordedParam};
use crate::continuation::two_param::locate_augmented;
use crate::continuation::SpecialKind;
use crate::integrator::{EventDriven853, FlowMethod, FlowOptions, Sensitivity};
use crate::model::{DrivenOscillator, Gear, GearParam, Parameter, Parametrised};
use crate::orbits::{shoot, OrbitSpec, ShootingOptions};

/// A model with every term of the lens switched on (moderate sizes, the base coupling dominant).
fn everything() -> RecordedModel {
    let mut c = Coefficients::base(300.0, 0.2, 1.0, 20.0);
    c.c_cc = 7.0;
    c.c_ss = -4.0;
    c.st_a = 3.0;
    c.st_b = -2.0;
    c.st_harmonics = [(1.5, -0.7), (0.4, 0.9)];
    c.quad = 0.8;
    c.drag_exponent = Some(1.7);
    c.corot = 0.3;
    c.eta_load = 5.0;
    c.load_weight = [1.4, -0.6];
    c.eta_static_excess = 6.0;
    c.stribeck_width = 0.5;
    c.stribeck_power = Some(1.5);
    c.compliance = 2f64.to_radians() / 300.0;
    c.alpha_offset = 0.04;
    c.extra[0] = (
        ExtraTerm::FricTrig {
            k: 1,
            l: 1,
            sin: true,
        },
        1.2,
    );
    RecordedModel::new(c, Geometry::new(0.5, 0.4), 1.3).unwrap()
}

/// The parameters with a column.
fn with_columns() -> impl Iterator<Item = RecordedParam> {
    RecordedParam::ALL.iter().copied().filter(|p| {
        !matches!(
            p,
            RecordedParam::LoadWeightVertical | RecordedParam::LoadWeightSide
        )
    })
}

/// ∂a/∂p and ∂r/∂p of every parameter against central differences of the forces (step 1e-6
/// relative), at points off Σ; and ∂r_s/∂p at rest against differences of the static bound.
#[test]
fn every_force_column_matches_differences() {
    let m = everything();
    for k in 0..9 {
        let (t, b, w) = (
            0.07 * k as f64,
            0.8 * k as f64 - 3.0,
            1.9 - 0.45 * k as f64 + 0.01,
        );
        let d = m.param_forces(t, b, w, None);
        for p in with_columns() {
            let v = m.param(p);
            let h = 1e-6 * v.abs().max(1e-3);
            let (mp, mm) = (
                m.with_param(p, v + h).unwrap(),
                m.with_param(p, v - h).unwrap(),
            );
            let (fp, fm) = (mp.forces(t, b, w), mm.forces(t, b, w));
            let (da, dr) = ((fp.a - fm.a) / (2.0 * h), (fp.r - fm.r) / (2.0 * h));
            let ia = p as usize;
            assert!(
                (d.a[ia] - da).abs() < 1e-6 * (1.0 + da.abs()),
                "{p:?} a: {} {da}",
                d.a[ia]
            );
            assert!(
                (d.r[ia] - dr).abs() < 1e-6 * (1.0 + dr.abs()),
                "{p:?} r: {} {dr}",
                d.r[ia]
            );
            if matches!(
                p,
                RecordedParam::Eta | RecordedParam::LoadFriction | RecordedParam::StaticExcess
            ) {
                let rest = m.param_forces(t, b, 0.0, None).r[ia];
                let ds = (mp.static_friction(t, b) - mm.static_friction(t, b)) / (2.0 * h);
                assert!(
                    (rest - ds).abs() < 1e-6 * (1.0 + ds.abs()),
                    "{p:?} r_s: {rest} {ds}"
                );
            }
        }
    }
}

/// The map's parameter Jacobian, column by column over the whole lens (in sets of eight), against
/// central differences of the flow over a drive period (with stick phases and releases).
#[test]
fn every_map_column_matches_differences() {
    let base = everything();
    let params: Vec<RecordedParam> = with_columns().collect();
    let x0 = [0.4, 3.0];
    let t1 = base.period();
    let tight = FlowOptions::with_tol(1e-12);
    for set in params.chunks(8) {
        let m = base.clone().with_columns(set).unwrap();
        let f = EventDriven853
            .flow(
                &m,
                0.0,
                x0,
                t1,
                &tight.clone().sensitivity(Sensitivity::StateAndParams),
            )
            .unwrap();
        let jp = f.jac_p.unwrap();
        for (k, &p) in set.iter().enumerate() {
            let v = m.param(p);
            let h = 1e-5 * v.abs().max(1e-2);
            let flow = |v: f64| {
                let s = m.with_param(p, v).unwrap();
                // the period moves with f: the map's end stays at the unperturbed t1
                EventDriven853.flow(&s, 0.0, x0, t1, &tight).unwrap().x
            };
            // Richardson's extrapolation of central differences at h and 2h
            let (xp, xm) = (flow(v + h), flow(v - h));
            let (xp2, xm2) = (flow(v + 2.0 * h), flow(v - 2.0 * h));
            for i in 0..2 {
                let d1 = (xp[i] - xm[i]) / (2.0 * h);
                let d2 = (xp2[i] - xm2[i]) / (4.0 * h);
                let fd = (4.0 * d1 - d2) / 3.0;
                assert!(
                    (jp[(i, k)] - fd).abs() < 1e-5 * (1.0 + fd.abs()),
                    "{p:?} row {i}: {} vs {fd}",
                    jp[(i, k)]
                );
            }
        }
    }
}

/// With only the base terms the recorded gear is the paper's gear: the same map (to rounding),
/// the same orbit and multipliers, and the same located lock-loss fold.
#[test]
fn base_terms_are_the_papers_gear() {
    for theta in [0.0, 20.0, 50.0] {
        let g = Gear::paper(theta, 3.0).unwrap();
        let m = RecordedModel::base(g.g, g.delta, g.zeta, g.eta, g.f).unwrap();
        let opts = FlowOptions::with_tol(1e-12).sensitivity(Sensitivity::StateAndParams);
        let (a, b) = (
            EventDriven853
                .flow(&g, 0.0, [0.3, 2.0], 2.0 / g.f, &opts)
                .unwrap(),
            EventDriven853
                .flow(&m, 0.0, [0.3, 2.0], 2.0 / g.f, &opts)
                .unwrap(),
        );
        for i in 0..2 {
            assert!(
                (a.x[i] - b.x[i]).abs() < 1e-9,
                "Θ = {theta}: {:?} {:?}",
                a.x,
                b.x
            );
        }
        // the columns f, g, Δ, ζ, η of both
        let (ja, jb) = (a.jac_p.unwrap(), b.jac_p.unwrap());
        let pairs = [
            (GearParam::F, RecordedParam::F),
            (GearParam::G, RecordedParam::G),
            (GearParam::Delta, RecordedParam::Delta),
            (GearParam::Zeta, RecordedParam::Zeta),
            (GearParam::Eta, RecordedParam::Eta),
        ];
        for (gp, rp) in pairs {
            let (ca, cb) = (g.column(gp).unwrap().index, m.column(rp).unwrap().index);
            for i in 0..2 {
                let (u, v) = (ja[(i, ca)], jb[(i, cb)]);
                assert!((u - v).abs() < 1e-7 * (1.0 + u.abs()), "{gp:?}: {u} {v}");
            }
        }
        if theta > 30.0 {
            continue; // the reversed mode (Δ < 0): the map alone
        }
        let spec = OrbitSpec::symmetric(1);
        let so = ShootingOptions {
            tol: 1e-11,
            ..Default::default()
        };
        let oa = shoot(&g, &spec, [3.5, 18.8], &so).unwrap();
        let ob = shoot(&m, &spec, [3.5, 18.8], &so).unwrap();
        for i in 0..2 {
            assert!((oa.x[i] - ob.x[i]).abs() < 1e-8, "{:?} {:?}", oa.x, ob.x);
            for j in 0..2 {
                let (u, v) = (oa.floquet.multipliers[i][j], ob.floquet.multipliers[i][j]);
                assert!((u - v).abs() < 1e-7, "Θ = {theta}: μ {u} {v}");
            }
        }
    }
    // the lock-loss fold at Θ = 0, f_c = (g − η)/(2πζ)
    let g = Gear::paper(0.0, 39.7).unwrap();
    let fc = g.lock_loss_frequency().unwrap();
    let m = RecordedModel::base(g.g, g.delta, g.zeta, g.eta, g.f).unwrap();
    let x0 = [
        std::f64::consts::FRAC_PI_2 + 0.01,
        std::f64::consts::TAU * fc,
    ];
    let so = ShootingOptions::default();
    let spec = OrbitSpec::symmetric(1);
    let fa = locate_augmented(
        &g,
        &spec,
        SpecialKind::Fold,
        GearParam::F,
        x0,
        fc - 0.1,
        &so,
    )
    .unwrap();
    let fb = locate_augmented(
        &m,
        &spec,
        SpecialKind::Fold,
        RecordedParam::F,
        x0,
        fc - 0.1,
        &so,
    )
    .unwrap();
    assert!((fa.free - fc).abs() < 1e-7, "{} {fc}", fa.free);
    assert!((fb.free - fa.free).abs() < 1e-8, "{} {}", fb.free, fa.free);
}
