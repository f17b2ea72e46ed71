use super::*;
use crate::campaign::rng::Rng;
use crate::continuation::two_param::locate_augmented_with;
use crate::integrator::DEFAULT_METHOD;
use crate::model::recorded::{RecordedModel, RecordedParam};
use crate::model::Parameter;
use std::f64::consts::TAU;

use RecordedParam::{DragP, DragQ, Eta, StaticA, StaticB, Zeta, F, G};

/// The paper's gear as a recorded model (Δ = 1, Θ = 0) at `f` Hz.
fn paper(f: f64) -> RecordedModel {
    RecordedModel::base(298.452035046191, 1.0, 1.1, 23.1, f).unwrap()
}

/// The paper's gear with a static torque A sin β + B cos β (no half-period symmetry) and a
/// power-law drag q (|β̇|/V)^p (7.8 s⁻² at the lock's 250 rad/s), columns f, A, B, g, ζ, η, q, p.
fn bench_gear(f: f64) -> RecordedModel {
    [(StaticA, 3.0), (StaticB, -1.5), (DragQ, 2e-3), (DragP, 2.0)]
        .into_iter()
        .fold(paper(f), |m, (p, v)| m.with_param(p, v).unwrap())
        .with_columns(&[F, StaticA, StaticB, G, Zeta, Eta, DragQ, DragP])
        .unwrap()
}

/// A lock-loss fold in f: (model, orbit problem, point) located from the guess of
/// docs/recorded_gear.md.
struct Case {
    model: RecordedModel,
    spec: OrbitSpec,
    point: CurvePoint,
}

fn locate(m: &RecordedModel, spec: &OrbitSpec, x: [f64; 2], f: f64) -> Result<CurvePoint> {
    let opts = ShootingOptions::default();
    locate_augmented_with(&DEFAULT_METHOD, m, spec, SpecialKind::Fold, F, x, f, &opts)
}

fn case(model: RecordedModel, spec: OrbitSpec) -> Case {
    let point = locate(&model, &spec, [1.5808, 250.3], 39.7).unwrap();
    Case { model, spec, point }
}

fn gradient(c: &Case, params: &[RecordedParam]) -> Vec<f64> {
    point_gradient(
        &DEFAULT_METHOD,
        &c.model,
        &c.spec,
        SpecialKind::Fold,
        F,
        &c.point,
        params,
        &ShootingOptions::default(),
    )
    .unwrap()
}

/// The lock-loss fold of the paper's gear is f_c = (g − η)/(2πζ) (model.md): its gradient in
/// (g, ζ, η) by the implicit-function theorem is the closed form's, to 1e-5 relative.
#[test]
fn gradient_of_the_lock_loss_fold_is_the_closed_forms() {
    let c = case(paper(39.7), OrbitSpec::symmetric(1));
    let (g, zeta, eta) = (298.452035046191, 1.1, 23.1);
    let fc = (g - eta) / (TAU * zeta);
    assert!((c.point.free - fc).abs() < 1e-8, "{} {fc}", c.point.free);
    let got = gradient(&c, &[G, Zeta, Eta]);
    let want = [1.0 / (TAU * zeta), -fc / zeta, -1.0 / (TAU * zeta)];
    for (a, b) in got.iter().zip(want) {
        assert!((a - b).abs() < 1e-5 * b.abs(), "{got:?} {want:?}");
    }
}

/// With a static torque and a drag (no closed form, stroboscopic section) the gradient matches central
/// differences of the fold re-located at p ± h, to 1e-4 relative (or 1e-6 absolute).
#[test]
fn gradient_matches_relocated_differences() {
    let c = case(bench_gear(39.5), OrbitSpec::stroboscopic(1, 1));
    let params = [StaticA, StaticB, G, Zeta, Eta, DragQ, DragP];
    let got = gradient(&c, &params);
    for (&p, d) in params.iter().zip(&got) {
        let v = c.model.param(p);
        let h = 1e-3 * if v == 0.0 { 1.0 } else { v.abs() };
        let at = |v: f64| {
            let m = c.model.with_param(p, v).unwrap();
            locate(&m, &c.spec, c.point.x, c.point.free).unwrap().free
        };
        let fd = (at(v + h) - at(v - h)) / (2.0 * h);
        assert!(
            (d - fd).abs() < 1e-4 * fd.abs() + 1e-6,
            "{}: IFT {d} differences {fd}",
            p.name()
        );
    }
}

/// Draws from N(mean, cov) (symmetric square root, so a singular covariance works).
fn draws(mean: &[f64], cov: &DMatrix<f64>, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let e = cov.clone().symmetric_eigen();
    let root = &e.eigenvectors
        * DMatrix::from_diagonal(&e.eigenvalues.map(|v| v.max(0.0).sqrt()))
        * e.eigenvectors.transpose();
    let mut rng = Rng::new(seed, 0);
    (0..n)
        .map(|_| {
            let z = nalgebra::DVector::from_fn(mean.len(), |_, _| rng.normal());
            let d = &root * z;
            mean.iter().zip(d.iter()).map(|(m, d)| m + d).collect()
        })
        .collect()
}

/// Monte Carlo over the covariance: the standard deviation of the fold re-located at 200 draws of
/// (g, ζ, η[, q, p]) agrees with σ = √(gᵀCg) of the implicit-function gradient to 20 %, on the
/// paper's gear (symmetric section) and on the gear with a static torque and a drag
/// (stroboscopic).
#[test]
fn sigma_agrees_with_monte_carlo() {
    let cases = [
        (
            case(paper(39.7), OrbitSpec::symmetric(1)),
            vec![G, Zeta, Eta],
        ),
        (
            case(bench_gear(39.5), OrbitSpec::stroboscopic(1, 1)),
            vec![G, Zeta, Eta, DragQ, DragP],
        ),
    ];
    for (c, params) in &cases {
        let n = params.len();
        let sd = [2.0, 0.02, 1.0, 2e-4, 0.05];
        // g and η correlated (ρ = 0.5), as a fit of g and η from the same lock limit makes them
        let cov = DMatrix::from_fn(n, n, |i, j| {
            let r = if i == j {
                1.0
            } else if (i, j) == (0, 2) || (i, j) == (2, 0) {
                0.5
            } else {
                0.0
            };
            r * sd[i] * sd[j]
        });
        let sigma = linear_sigma(&gradient(c, params), &cov).unwrap();
        let mean: Vec<f64> = params.iter().map(|&p| c.model.param(p)).collect();
        let lams: Vec<f64> = draws(&mean, &cov, 200, 7)
            .iter()
            .map(|v| {
                let m = params
                    .iter()
                    .zip(v)
                    .fold(c.model.clone(), |m, (&p, &x)| m.with_param(p, x).unwrap());
                locate(&m, &c.spec, c.point.x, c.point.free).unwrap().free
            })
            .collect();
        let avg = lams.iter().sum::<f64>() / lams.len() as f64;
        let var = lams.iter().map(|l| (l - avg).powi(2)).sum::<f64>() / (lams.len() - 1) as f64;
        let mc = var.sqrt();
        assert!(
            (mc / sigma - 1.0).abs() < 0.2,
            "σ = {sigma}, Monte Carlo {mc}"
        );
    }
}

/// The gradient of the paper's gear's flip point at Θ = 25° (stroboscopic branch, tutorial.md) and
/// of its symmetry-breaking point (half-period section) in ζ, η, g matches central differences of
/// the re-located point, to 1e-4 relative: a second system and two more kinds of point.
#[test]
fn flip_and_symmetry_breaking_gradients_match_differences() {
    use crate::model::{Gear, GearParam};
    let gear = Gear::paper(25.0, 1.85).unwrap();
    let opts = ShootingOptions::default();
    let cases = [
        (
            SpecialKind::Flip,
            OrbitSpec::stroboscopic(1, 1),
            [2.041556, -7.257868],
            1.854934870,
        ),
        (
            SpecialKind::SymmetryBreaking,
            OrbitSpec::symmetric(1),
            [2.984640, 8.795335],
            2.077740215,
        ),
    ];
    let params = [GearParam::Zeta, GearParam::Eta, GearParam::G];
    for (kind, spec, x, f) in cases {
        let loc = |g: &Gear, x: [f64; 2], f: f64| {
            locate_augmented_with(&DEFAULT_METHOD, g, &spec, kind, GearParam::F, x, f, &opts)
                .unwrap()
        };
        let point = loc(&gear, x, f);
        assert!((point.free - f).abs() < 1e-7, "{kind:?} at {}", point.free);
        let got = point_gradient(
            &DEFAULT_METHOD,
            &gear,
            &spec,
            kind,
            GearParam::F,
            &point,
            &params,
            &opts,
        )
        .unwrap();
        for (&p, d) in params.iter().zip(&got) {
            let v = gear.param(p);
            let h = 1e-3 * v.abs();
            let at = |w: f64| loc(&gear.with_param(p, w).unwrap(), point.x, point.free).free;
            let fd = (at(v + h) - at(v - h)) / (2.0 * h);
            assert!(
                (d - fd).abs() < 1e-4 * fd.abs(),
                "{kind:?} {}: IFT {d} differences {fd}",
                p.name()
            );
        }
    }
}

/// The singular directions reconstruct ∂ψ/∂M: Σ d_k u_k v_kᵀ = D for a full-rank D (two terms,
/// the Neimark–Sacker and stick-phase case) and for a rank-one D (one term, a located fold).
#[test]
fn directions_reconstruct_the_test_gradient() {
    let full = Matrix2::new(0.3, -1.2, 0.7, 2.0);
    let rank_one = Matrix2::new(1.0, -2.0, -0.5, 1.0);
    for (d, terms) in [(full, 2), (rank_one, 1)] {
        let dirs = directions(&d);
        assert_eq!(dirs.len(), terms, "{d}");
        let back = dirs.iter().fold(Matrix2::zeros(), |acc, (s, u, v)| {
            acc + Matrix2::new(u[0] * v[0], u[0] * v[1], u[1] * v[0], u[1] * v[1]) * *s
        });
        assert!((back - d).norm() < 1e-12 * d.norm(), "{back} {d}");
    }
}
