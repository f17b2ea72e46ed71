//! Identification and diagnosis on concealed data. Two generators: the crate's `synth` (catalog
//! forms), and a truth model written here, outside the catalog's code (a bearing load computed as
//! the vector sum of the weight and the dipole force, friction modulated by cos 2β), simulated and
//! measured by this file. The truth is only compared with at the end; asserts are in units of the
//! reported σ.

use gearbif::identification::diagnose::{diagnose, DiagnoseOptions, Diagnosis};
use gearbif::identification::model::{AugmentedGear, Coefficients, Geometry, InputBend, Rng};
use gearbif::identification::preprocess::clean;
use gearbif::identification::ringdown::{fit_kappa, fit_ringdown};
use gearbif::identification::synth::{synthesize, SynthOptions};
use gearbif::integrator::{EventDriven, FlowMethod, FlowOptions};
use gearbif::io::recordings::{GearSetup, RecordingSet, Run, RunKind};
use gearbif::model::gear::shaft_index;
use gearbif::model::{DrivenOscillator, Forces, ForcesJet};
use std::f64::consts::{PI, TAU};

fn small(effect: &str, size: f64, seed: u64) -> SynthOptions {
    SynthOptions {
        effect: effect.into(),
        size,
        seed,
        ringdowns: 6,
        driven: 4,
        turns: 25.0,
        ..SynthOptions::default()
    }
}

/// Judging windows for the test sets (fewer than the default: faster, less power).
fn dopts() -> DiagnoseOptions {
    let mut o = DiagnoseOptions::default();
    o.shooting.max_windows = 160;
    o
}

fn run_set(set: &RecordingSet) -> Diagnosis {
    diagnose(set, &dopts(), &gearbif::progress::Silent).unwrap()
}

fn finding<'a>(d: &'a Diagnosis, effect: &str) -> &'a gearbif::identification::report::Finding {
    d.report
        .findings
        .iter()
        .find(|f| f.effect == effect)
        .unwrap_or_else(|| panic!("no {effect} in {:#?}", d.report.findings))
}

/// |estimate − truth| within `k` reported standard errors.
fn within(est: f64, err: f64, truth: f64, k: f64) {
    assert!(err.is_finite() && err > 0.0, "uncertainty {err}");
    assert!(
        (est - truth).abs() <= k * err,
        "estimate {est} ± {err}, truth {truth}: {:.1} σ",
        (est - truth).abs() / err
    );
}

/// Every judged finding improved the held-out prediction, and the rejected candidates carry
/// their numbers.
fn findings_improve_heldout(d: &Diagnosis) {
    for f in &d.report.findings {
        if let (Some(b), Some(a)) = (f.heldout_rms_before_rad, f.heldout_rms_after_rad) {
            assert!(
                a < b,
                "{} made the held-out prediction worse: {b} → {a}",
                f.effect
            );
        }
        assert!(f.size.is_some(), "{} without a size", f.effect);
    }
    let fits = d.report.fits.as_ref().unwrap();
    for c in fits["rejected_candidates"].as_array().unwrap() {
        assert!(c["reason"].is_string() && c["z_threshold"].as_f64().unwrap() >= 3.0);
    }
}

#[test]
fn null_set_with_other_shaft_angles_of_the_same_delta_gives_none() {
    // stated angles not parallel and 5° off, with the same Δ as the truth: nothing to find
    let mut o = small("none", 0.0, 21);
    o.noise_deg = 0.35;
    o.samples_per_turn = 45;
    let (mut set, t) = synthesize(&o).unwrap();
    let d_true = t.coefficients.delta();
    let th = t.geometry.theta() + 5f64.to_radians();
    // Φ with Δ(Θ, Φ) = Δ_true, by bisection near the true Φ
    let (mut lo, mut hi) = (t.geometry.phi() - 0.3, t.geometry.phi());
    for _ in 0..80 {
        let m = 0.5 * (lo + hi);
        if (shaft_index(th, lo) - d_true) * (shaft_index(th, m) - d_true) <= 0.0 {
            hi = m;
        } else {
            lo = m;
        }
    }
    set.gear.theta_deg = th.to_degrees();
    set.gear.phi_deg = (0.5 * (lo + hi)).to_degrees();
    assert!((shaft_index(th, 0.5 * (lo + hi)) - d_true).abs() < 1e-9);
    let d = run_set(&set);
    assert_eq!(d.report.verdict, "none", "{:#?}", d.report.findings);
    let p = &d.report.baseline.params;
    let c = t.coefficients;
    within(p["g"], p["g_err"], c.g(), 3.0);
    within(p["zeta"], p["zeta_err"], c.zeta, 3.0);
    within(p["eta"], p["eta_err"], c.eta, 3.0);
    within(p["delta"], p["delta_err"], c.delta(), 3.0);
    // short-horizon predictions at the camera noise (0.35°) within 20% (coarse 0.5 Hz runs)
    let noise = 0.35f64.to_radians();
    let j = &d.report.fits.as_ref().unwrap()["judge"];
    let held = j["base_heldout_rms_rad"].as_f64().unwrap();
    assert!(held < 1.2 * noise, "held-out rms {held}");
    assert_eq!(d.report.schema, "gearbif.diagnosis/1");
}

#[test]
fn static_torque_and_latency_together_are_both_found_and_sized() {
    let mut o = small("static_torque", 4.0, 24);
    o.noise_deg = 0.5;
    o.latency_s = 0.006;
    o.driven = 5;
    let (set, t) = synthesize(&o).unwrap();
    let d = run_set(&set);
    findings_improve_heldout(&d);
    let st = finding(&d, "static_torque");
    assert_eq!(st.class, "lab-fixed");
    assert!(st.candidates.len() >= 3 && !st.discriminating_experiment.is_empty());
    let s = st.size.as_ref().unwrap();
    assert_eq!((s.name.as_str(), s.unit.as_str()), ("amplitude", "s^-2"));
    within(s.value, s.sigma, 4.0, 3.0);
    within(
        st.params["phase_deg"],
        st.params["phase_err_deg"],
        60.0,
        3.0,
    );
    let lat = finding(&d, "sensor_latency");
    let s = lat.size.as_ref().unwrap();
    within(s.value, s.sigma, t.latency, 3.0);
    assert_eq!(d.report.findings.len(), 2, "{:#?}", d.report.findings);
}

#[test]
fn quadratic_drag_is_named_and_sized() {
    let mut o = small("quadratic_drag", 0.025, 25);
    o.noise_deg = 0.4;
    o.samples_per_turn = 55;
    let (set, _) = synthesize(&o).unwrap();
    let d = run_set(&set);
    // the drag family with its exponent fitted: the quadratic member, p = 2
    assert_eq!(
        d.report.verdict, "power_law_drag",
        "{:#?}",
        d.report.findings
    );
    findings_improve_heldout(&d);
    let f = &d.report.findings[0];
    let s = f.size.as_ref().unwrap();
    assert_eq!((s.name.as_str(), s.unit.as_str()), ("exponent", "1"));
    within(s.value, s.sigma, 2.0, 3.0);
    within(f.params["q"], f.params["q_err"], 0.025, 3.0);
}

#[test]
fn shafts_six_degrees_off_give_coupling_geometry_with_the_angles() {
    // the set was recorded with both shafts 6° away from the stated angles (parallel shafts)
    let mut o = small("none", 0.0, 27);
    o.noise_deg = 0.45;
    let (mut set, t) = synthesize(&o).unwrap();
    let true_deg = t.geometry.theta().to_degrees();
    set.gear.theta_deg = true_deg + 6.0;
    set.gear.phi_deg = true_deg + 6.0;
    let d = run_set(&set);
    assert_eq!(
        d.report.verdict, "coupling_geometry",
        "{:#?}",
        d.report.findings
    );
    let f = finding(&d, "coupling_geometry");
    let s = f.size.as_ref().unwrap();
    within(s.value, s.sigma, t.coefficients.delta(), 3.0);
    within(
        f.params["common_shift_theta_deg"],
        f.params["common_shift_err_deg"],
        true_deg,
        3.0,
    );
}

/// The bearing load as a vector: weight (along −z, the shafts horizontal in the x–y plane) plus
/// the dipole force on the output magnet, its part perpendicular to the output shaft; in units of
/// F0 = 3 μ0 m1 m2/(4π r⁴). Written here from the dipole–dipole force, not from the crate.
fn radial_load(geo: &Geometry, weight: f64, alpha: f64, beta: f64) -> f64 {
    let u1 = [
        -alpha.cos() * geo.theta().sin(),
        alpha.cos() * geo.theta().cos(),
        alpha.sin(),
    ];
    let u2 = [
        -beta.cos() * geo.phi().sin(),
        beta.cos() * geo.phi().cos(),
        beta.sin(),
    ];
    let x = [1.0, 0.0, 0.0];
    let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (m1x, m2x, m12) = (dot(&u1, &x), dot(&u2, &x), dot(&u1, &u2));
    // F = (u1·x̂)u2 + (u2·x̂)u1 + (u1·u2)x̂ − 5(u1·x̂)(u2·x̂)x̂ (force on the output dipole)
    let mut p = [0.0; 3];
    for k in 0..3 {
        p[k] = m1x * u2[k] + m2x * u1[k] + (m12 - 5.0 * m1x * m2x) * x[k];
    }
    p[2] -= weight;
    let axis = [geo.phi().cos(), geo.phi().sin(), 0.0];
    let along = dot(&p, &axis);
    let perp: f64 = (0..3).map(|k| (p[k] - along * axis[k]).powi(2)).sum();
    perp.sqrt()
}

/// A truth model outside the catalog: the smooth forces of the base gear and a dry friction
/// `friction(α, β)`.
struct TruthGear<F: Fn(f64, f64) -> f64 + Send + Sync> {
    base: AugmentedGear,
    friction: F,
}

impl<F: Fn(f64, f64) -> f64 + Send + Sync> DrivenOscillator for TruthGear<F> {
    fn period(&self) -> f64 {
        self.base.period()
    }
    fn forces(&self, t: f64, beta: f64, omega: f64) -> Forces {
        Forces {
            a: self.base.forces(t, beta, omega).a,
            r: (self.friction)(self.base.alpha(t), beta),
        }
    }
    fn forces_jet(&self, t: f64, beta: f64, omega: f64, params: bool) -> ForcesJet {
        let mut j = self.base.forces_jet(t, beta, omega, params);
        let al = self.base.alpha(t);
        j.r = (self.friction)(al, beta);
        let h = 1e-6;
        j.r_beta = ((self.friction)(al, beta + h) - (self.friction)(al, beta - h)) / (2.0 * h);
        j
    }
}

/// A recording set of the truth `make(α0, α̇)`: 6 ring-downs and 4 driven runs (0.6–2.2 Hz, 25
/// turns, 50 samples per turn), camera noise `noise_deg`, no outliers.
fn truth_set<S: DrivenOscillator>(
    make: impl Fn(f64, f64) -> S,
    c: &Coefficients,
    noise_deg: f64,
    seed: u64,
) -> RecordingSet {
    let mut rng = Rng::new(seed);
    let noise = noise_deg.to_radians();
    let mut runs = Vec::new();
    let mut record = |kind: RunKind,
                      file: String,
                      sys: &S,
                      x0: [f64; 2],
                      times: Vec<f64>,
                      alpha: Vec<f64>,
                      rng: &mut Rng| {
        let opts = FlowOptions::with_tol(1e-9).samples(times.clone());
        let f = EventDriven
            .flow(sys, 0.0, x0, *times.last().unwrap(), &opts)
            .unwrap();
        let beta = f
            .samples
            .iter()
            .map(|s| s.beta + noise * rng.normal())
            .collect();
        runs.push(Run {
            kind,
            file,
            t: times,
            alpha,
            beta,
        });
    };
    for k in 0..6 {
        let alpha0 = TAU * (k as f64 + 0.37) / 6.0;
        let sys = make(alpha0, 0.0);
        let psi = (c.c_sc * alpha0.sin()).atan2(-(c.c_cs * alpha0.cos()));
        let side = if k % 2 == 0 { 1.0 } else { -1.0 };
        let b0 = psi + side * (0.5 * PI - 0.1 + 0.2 * rng.uniform());
        let times: Vec<f64> = (0..300).map(|i| i as f64 / 100.0).collect();
        record(
            RunKind::Ringdown { alpha0 },
            format!("ringdown_{k}.csv"),
            &sys,
            [b0, 0.0],
            times,
            vec![alpha0; 300],
            &mut rng,
        );
    }
    for k in 0..4 {
        let f = 0.6 + 0.5 * k as f64;
        let sys = make(0.0, TAU * f);
        let dt = 1.0 / (50.0 * f);
        let times: Vec<f64> = (0..1250).map(|i| i as f64 * dt).collect();
        let alpha = times.iter().map(|t| TAU * f * t).collect();
        let b0 = TAU * rng.uniform();
        record(
            RunKind::Driven { f_hz: f },
            format!("driven_{k}.csv"),
            &sys,
            [b0, 0.0],
            times,
            alpha,
            &mut rng,
        );
    }
    let mut gear = GearSetup::paper();
    gear.inertia = None;
    RecordingSet {
        dir: std::path::PathBuf::new(),
        gear,
        runs,
    }
}

fn paper_truth() -> (Coefficients, Geometry) {
    let geo = Geometry::new(31f64.to_radians(), 31f64.to_radians());
    let g = GearSetup::paper().coupling() / 6.45e-5;
    let c = Coefficients::base(g, shaft_index(geo.theta(), geo.phi()), 1.1, 0.0);
    (c, geo)
}

#[test]
fn vector_load_friction_is_not_named_a_drag() {
    // all of the Coulomb friction proportional to |weight + dipole force| (radial part), the
    // weight 2.2 F0, written here from the dipole–dipole force (not from the crate)
    let (c, geo) = paper_truth();
    let weight = 2.2;
    // friction 23 s⁻² at the mean load (≈ weight)
    let mu = 23.0 / weight;
    let make = |alpha0: f64, rate: f64| TruthGear {
        base: AugmentedGear {
            c,
            geo,
            alpha0,
            alpha_rate: rate,
            bend: InputBend::default(),
        },
        friction: move |al: f64, b: f64| mu * radial_load(&geo, weight, al, b),
    };
    let set = truth_set(make, &c, 0.45, 61);
    let d = run_set(&set);
    findings_improve_heldout(&d);
    assert_ne!(
        d.report.verdict, "power_law_drag",
        "{:#?}",
        d.report.findings
    );
    assert!(
        d.report.findings.iter().all(|f| !f.effect.contains("drag")),
        "{:#?}",
        d.report.findings
    );
}

#[test]
fn ringdown_fits_recover_kappa_and_g() {
    let mut o = small("none", 0.0, 30);
    o.driven = 0;
    o.ringdowns = 8;
    o.noise_deg = 0.4;
    let (set, t) = synthesize(&o).unwrap();
    let c = t.coefficients;
    let mut fits = Vec::new();
    for r in &set.runs {
        let RunKind::Ringdown { alpha0 } = r.kind else {
            unreachable!()
        };
        let cr = clean(r, None);
        let f = fit_ringdown(
            &cr,
            &r.file,
            alpha0,
            1.1,
            23.1,
            DiagnoseOptions::default().ringdown_tol(),
        )
        .expect("fit");
        let kappa_true = gearbif::model::gear::kappa(c.g(), c.delta(), alpha0);
        if f.rms_rad < 2.0 * cr.sigma_beta {
            within(f.kappa, f.kappa_err, kappa_true, 4.0);
        }
        fits.push(f);
    }
    assert!(fits.iter().filter(|f| f.rms_rad < 0.02).count() >= 6);
    let k = fit_kappa(&fits, &set.gear).unwrap();
    within(k.g, k.g_err, c.g(), 3.5);
    within(k.delta_abs, k.delta_err, c.delta().abs(), 3.5);
    assert!((k.inertia - set.gear.coupling() / k.g).abs() <= 1e-12 * k.inertia);
    assert!(k.inertia_err / k.inertia >= set.gear.coupling_rel_tol());
}

#[test]
fn friction_modulated_by_cos_2beta_is_unexplained_and_named_by_its_term() {
    // out of the catalog: dry friction η(1 + 0.3 cos 2β)
    let (mut c, geo) = paper_truth();
    c.zeta = 1.0;
    let eta = 22.0;
    let make = |alpha0: f64, rate: f64| TruthGear {
        base: AugmentedGear {
            c,
            geo,
            alpha0,
            alpha_rate: rate,
            bend: InputBend::default(),
        },
        friction: move |_al: f64, b: f64| eta * (1.0 + 0.3 * (2.0 * b).cos()),
    };
    let set = truth_set(make, &c, 0.4, 62);
    let d = run_set(&set);
    findings_improve_heldout(&d);
    assert_eq!(d.report.verdict, "unexplained", "{:#?}", d.report.findings);
    let f = &d.report.findings[0];
    let name = "-sgn(dbeta)cos(0alpha+2beta)";
    within(
        f.params[name],
        f.params[&format!("{name}_err")],
        0.3 * eta,
        3.0,
    );
    assert!(!f.discriminating_experiment.is_empty());
    assert_eq!(f.size.as_ref().unwrap().name, name);
}

/// The tolerance set on the options reaches the integrator: the ring-down fits of the diagnosis
/// (`prepare`) and the window predictions change measurably when it is loosened and converge as
/// it is tightened (the default within a tenth of the loose one's distance from a 100 times
/// tighter run); invalid tolerances are typed errors before any work.
#[test]
fn diagnosis_tolerance_reaches_the_integrator() {
    use gearbif::identification::diagnose::prepare;
    use gearbif::identification::predict::predict;
    let mut o = small("none", 0.0, 31);
    o.ringdowns = 2;
    o.driven = 1;
    o.turns = 6.0;
    let (set, truth) = synthesize(&o).unwrap();
    let at = |tol: f64| DiagnoseOptions {
        tol,
        ..DiagnoseOptions::default()
    };
    let default_tol = DiagnoseOptions::default().tol;
    let (loose, tight) = (1e-4, 1e-2 * default_tol);
    // ring-downs: κ of each fit at the three tolerances
    let kappa = |tol: f64| -> Vec<f64> {
        let p = prepare(&set, &at(tol), &gearbif::progress::Silent).unwrap();
        assert_eq!(p.ringdowns.len(), 2, "a ring-down fit failed at tol {tol}");
        p.ringdowns.iter().map(|f| f.kappa).collect()
    };
    let (kl, kd, kt) = (kappa(loose), kappa(default_tol), kappa(tight));
    for k in 0..2 {
        let (dl, dd) = ((kl[k] - kt[k]).abs(), (kd[k] - kt[k]).abs());
        println!(
            "ring-down {k}: kappa {}; |loose - tight| {dl:e}, |default - tight| {dd:e}",
            kt[k]
        );
        assert!(
            dl > 10.0 * dd && dl > 0.0,
            "ring-down {k}: {dl:e} vs {dd:e}"
        );
    }
    // window predictions of the driven run with the true model
    let run = set
        .runs
        .iter()
        .find(|r| !matches!(r.kind, RunKind::Ringdown { .. }))
        .unwrap();
    let cr = clean(run, None);
    let rms = |tol: f64| predict(&cr, &truth.coefficients, &truth.geometry, 0.0, tol).rms;
    let (rl, rd, rt) = (rms(loose), rms(default_tol), rms(tight));
    let (dl, dd) = ((rl - rt).abs(), (rd - rt).abs());
    println!("predictions: rms {rt} rad; |loose - tight| {dl:e}, |default - tight| {dd:e}");
    assert!(dl > 10.0 * dd && dl > 0.0, "predictions: {dl:e} vs {dd:e}");
    // invalid tolerances: the variant names the field
    for (tol, ratio, name) in [
        (0.0, 0.1, "tol"),
        (1.0, 0.1, "tol"),
        (f64::NAN, 0.1, "tol"),
        (-1e-8, 0.1, "tol"),
        (1e-8, 0.0, "ringdown_tol_ratio"),
        (1e-8, 1.5, "ringdown_tol_ratio"),
    ] {
        let opts = DiagnoseOptions {
            tol,
            ringdown_tol_ratio: ratio,
            ..DiagnoseOptions::default()
        };
        match diagnose(&set, &opts, &gearbif::progress::Silent) {
            Err(gearbif::Error::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!(
                "tol {tol}, ratio {ratio}: {:?}",
                other.map(|d| d.report.verdict)
            ),
        }
    }
}
