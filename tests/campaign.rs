//! The campaign generator's correctness (against the crate's event-driven integrator; the Filippov
//! stick rule) and a CI-sized campaign whose rates are asserted with binomial bounds that follow
//! from the stated goals and the campaign size.

use gearbif::campaign::cases::{build_case, effect};
use gearbif::campaign::generator::SetSize;
use gearbif::campaign::metrics::{max_consistent_failures, Rate, Summary, CURVE_COVERAGE};
use gearbif::campaign::rk4::Rk4Filippov;
use gearbif::campaign::runner::{run_campaign, CampaignDoc, CampaignSpec};
use gearbif::campaign::truth::{Drive, Stribeck, StribeckShape, TruthModel};
use gearbif::integrator::{EventDriven, FlowMethod, FlowOptions};
use gearbif::model::Gear;
use std::collections::HashMap;
use std::f64::consts::TAU;
use std::sync::{Mutex, OnceLock};

/// The first two stages of the diagnosis of `set` (cleaning and ring-downs, the base model with
/// its judging windows) and the `opts.folds` folds, for the tests that refit a chosen model on
/// those windows.
fn prepared_base(
    set: &gearbif::io::recordings::RecordingSet,
    opts: &gearbif::identification::diagnose::DiagnoseOptions,
) -> (
    gearbif::identification::diagnose::Prepared,
    gearbif::identification::diagnose::BaseModel,
    gearbif::identification::judge::Folds,
) {
    use gearbif::identification::diagnose::{fit_base, prepare};
    let prep = prepare(set, opts, &gearbif::progress::Silent).unwrap();
    let folds = gearbif::identification::judge::Folds::new(&prep.runs, opts.folds);
    let base = fit_base(&prep, set, opts, &folds, &gearbif::progress::Silent).unwrap();
    (prep, base, folds)
}

/// `f` called with the selection's context and the base model's state on a set of the campaign
/// generator (effect `id` at size `level`, seed `seed`, `ci` size; the default options), for the
/// tests that judge chosen candidates by hand.
fn on_base_model<R>(
    id: &str,
    level: f64,
    seed: u64,
    f: impl FnOnce(
        gearbif::identification::select::SelectCtx,
        &gearbif::identification::select::ModelState,
    ) -> R,
) -> R {
    use gearbif::identification::diagnose::{propose_ctx, select_ctx, DiagnoseOptions};
    let opts = DiagnoseOptions::default();
    let (prep, base, folds) = cached_base(id, level, seed);
    let b = base.state.clone().expect("the base refit");
    let pctx = propose_ctx(&prep.runs, base, &opts);
    f(select_ctx(&pctx, base, folds, &opts), &b)
}

/// The first two stages of a diagnosis and its folds ([`prepared_base`]).
type Based = (
    gearbif::identification::diagnose::Prepared,
    gearbif::identification::diagnose::BaseModel,
    gearbif::identification::judge::Folds,
);

/// The cleaned runs, base model and folds of [`on_base_model`]'s set (effect `id` at `level`,
/// seed `seed`, `ci` size, the default options), computed once for all the tests that judge
/// candidates on the same set (`static_torque_2h` at level 2: seeds 1 and 2 serve two tests each).
fn cached_base(id: &str, level: f64, seed: u64) -> &'static Based {
    type Cells = Mutex<HashMap<(String, u64, u64), &'static OnceLock<Based>>>;
    static CELLS: OnceLock<Cells> = OnceLock::new();
    let cell: &'static OnceLock<Based> = CELLS
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .entry((id.to_string(), level.to_bits(), seed))
        .or_insert_with(|| Box::leak(Box::new(OnceLock::new())));
    cell.get_or_init(|| {
        let spec = effect(id).unwrap();
        let g = build_case(spec, level, seed, &SetSize::ci(), &Rk4Filippov::default()).unwrap();
        let opts = gearbif::identification::diagnose::DiagnoseOptions::default();
        prepared_base(&g.set, &opts)
    })
}

/// Camera noise of the documented sets, rad (0.5°).
const CAMERA_NOISE: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// Fixed-step RK4 with bisected events against the adaptive event-driven DP5 (tolerance 1e-11)
/// on the base model: driven runs with slipping and with stick–slip motion. At the default step
/// (0.25 ms) the two agree to 1e-7 rad (measured: 1.4e-10, 8.1e-8, 1.6e-11 rad); asserted below
/// 1e-6 rad, about 1e-4 of the camera noise.
#[test]
fn generator_integrator_matches_event_driven_integrator() {
    // (g, Δ, ζ, η, f): the paper's gear at 31°, slow and fast; Δ = 1 with strong friction, which
    // sticks for part of every turn
    let cases: [(f64, f64, f64, f64, f64); 3] = [
        (298.0, 0.2042, 1.1, 23.1, 0.5),
        (298.0, 0.2042, 1.1, 23.1, 2.5),
        (298.0, 1.0, 1.1, 150.0, 0.3),
    ];
    for (k, &(g, delta, zeta, eta, f)) in cases.iter().enumerate() {
        let theta = ((1.0 - delta) / 3.0).sqrt().asin(); // parallel shafts: Δ = 1 − 3 sin²Θ
        let truth = TruthModel::base(g, theta, theta, zeta, eta);
        assert!((truth.delta() - delta).abs() < 1e-12);
        let times: Vec<f64> = (1..=800).map(|i| i as f64 * 0.01).collect();
        let x0 = [1.0, 0.0];
        let drive = Drive {
            alpha0: 0.0,
            rate: TAU * f,
            ripple: 0.0,
        };
        let (ours, stats) = Rk4Filippov::default()
            .sample(&truth, drive, 0.0, x0, &times)
            .unwrap();
        let gear = Gear::new(g, delta, zeta, eta, f).unwrap();
        let opts = FlowOptions::with_tol(1e-11).samples(times.clone());
        let flow = EventDriven.flow(&gear, 0.0, x0, 8.0, &opts).unwrap();
        let err = ours
            .iter()
            .zip(&flow.samples)
            .map(|(a, s)| (a - s.beta).abs())
            .fold(0.0, f64::max);
        assert!(
            err < 1e-6,
            "case {k}: max |Δβ| = {err:.2e} rad ({:.1e} of the camera noise)",
            err / CAMERA_NOISE
        );
        if k == 2 {
            assert!(stats.sticks > 0 && stats.releases > 0, "{stats:?}");
        }
    }
}

/// The stick rule |smooth part| ≤ R(α, β, 0): at rest with the coupling torque between the
/// sliding friction η and the breakaway bound η + Δη_s, the output stays stuck; with no breakaway
/// excess it slips at once; a ring-down ends at rest inside the stick band and stays there.
#[test]
fn stick_rule_uses_the_static_friction_bound() {
    let times: Vec<f64> = (1..=200).map(|i| i as f64 * 0.005).collect();
    let drive = Drive {
        alpha0: 0.0,
        rate: 0.0,
        ripple: 0.0,
    };
    // Δ = 1: the smooth part at rest is g sin(β − α0); at β = 0.1 it is 29.9 s⁻²
    let mut m = TruthModel::base(300.0, 0.0, 0.0, 1.0, 20.0);
    let a = 300.0 * 0.1f64.sin();
    assert!(a > 20.0 && a < 30.0);
    let (slip, _) = Rk4Filippov::default()
        .sample(&m, drive, 0.0, [0.1, 0.0], &times)
        .unwrap();
    assert!((slip[0] - 0.1).abs() > 1e-6, "must slip at once");
    m.stribeck = Some(Stribeck {
        excess: 10.0,
        width: 0.5,
        shape: StribeckShape::Gaussian,
    });
    let (stuck, _) = Rk4Filippov::default()
        .sample(&m, drive, 0.0, [0.1, 0.0], &times)
        .unwrap();
    assert!(stuck.iter().all(|&b| b == 0.1), "must stay stuck");
    // ring-down from far away: comes to rest where |g sin(β − α0)| ≤ η and stays
    let m = TruthModel::base(300.0, 0.0, 0.0, 1.1, 23.1);
    let d = Drive {
        alpha0: 0.3,
        rate: 0.0,
        ripple: 0.0,
    };
    let times: Vec<f64> = (0..=400).map(|i| i as f64 * 0.01).collect();
    let (beta, stats) = Rk4Filippov::default()
        .sample(&m, d, 0.0, [1.5, 0.0], &times)
        .unwrap();
    assert!(stats.sticks >= 1);
    let last = *beta.last().unwrap();
    assert!((300.0 * (last - 0.3).sin()).abs() <= 23.1 + 1e-9);
    assert!(beta[300..].iter().all(|&b| b == last));
}

/// Every effect generates a set in the documented format that the reader accepts back.
#[test]
fn every_effect_generates_a_readable_set() {
    let size = SetSize {
        ringdowns: 2,
        driven: 1,
        turns: 2.0,
        ringdown_s: 0.5,
        ..SetSize::ci()
    };
    let dir = std::env::temp_dir().join(format!("gearbif-campaign-sets-{}", std::process::id()));
    for e in gearbif::campaign::cases::EFFECTS {
        let c = build_case(e, 1.0, 3, &size, &Rk4Filippov::default()).unwrap();
        let d = dir.join(e.id);
        gearbif::io::recordings::write_set(&c.set, &d, true).unwrap();
        let back = gearbif::io::recordings::read_set(&d).unwrap();
        assert_eq!(back.runs.len(), 3, "{}", e.id);
        assert_eq!(back.gear.theta_deg, 31.0);
    }
    std::fs::remove_dir_all(&dir).ok();
    assert!(effect("no_such_effect").is_err());
}

/// A campaign on the CI's tiny sets (4 ring-downs of 2 s and 2 driven runs of 8 turns, else as
/// `ci`) at level `level`, the diagnosis's default options; the folder (named by `tag`) is
/// removed afterwards.
fn tiny_campaign(
    tag: &str,
    effects: &[&str],
    level: f64,
    seeds: u64,
    null_seeds: u64,
) -> CampaignDoc {
    let set = SetSize {
        name: "test".into(),
        ringdowns: 4,
        driven: 2,
        turns: 8.0,
        ringdown_s: 2.0,
        ..SetSize::ci()
    };
    let out = std::env::temp_dir().join(format!("gearbif-campaign-{tag}-{}", std::process::id()));
    let spec = CampaignSpec {
        effects: effects.iter().map(|s| s.to_string()).collect(),
        levels: vec![level],
        seeds: (1..=seeds).collect(),
        null_seeds: (1..=null_seeds).collect(),
        set,
        rk4_step_s: 2.5e-4,
        keep_sets: false,
        tol: gearbif::identification::diagnose::DiagnoseOptions::default().tol,
        profile_shapes: false,
    };
    let doc = run_campaign(&spec, &out, &gearbif::progress::Silent).unwrap();
    std::fs::remove_dir_all(&out).ok();
    doc
}

/// The CI campaign, run once for the tests below: tiny sets (4 ring-downs of 2 s, 2 driven runs of
/// 8 turns); 20 seeds of the plain control; 8 seeds each of a static torque with a sin 2β part
/// (A₁ = 12 s⁻², twice its reference size) and of a sensor latency (12 ms, twice its reference),
/// the two headline sizes whose σ coverage the tests assert (docs/diagnosis.md, "Campaigns",
/// gives the cost).
fn ci_campaign() -> &'static CampaignDoc {
    static DOC: OnceLock<CampaignDoc> = OnceLock::new();
    DOC.get_or_init(|| tiny_campaign("ci", &["none", "static_torque_2h", "latency"], 2.0, 8, 20))
}

fn summary() -> &'static Summary {
    &ci_campaign().summary
}

/// Goal: false-positive rate ≤ 5 %. With n controls, more than `max_consistent_failures(n, 0.05,
/// 0.01)` false positives (4 of 20) refute the goal at the 1 % level.
#[test]
fn ci_campaign_false_positive_rate() {
    let fp = summary().false_positive;
    assert_eq!(fp.n, 20);
    let bound = max_consistent_failures(fp.n, 0.05, 0.01);
    assert!(
        fp.k <= bound,
        "{} false positives of {} (bound {bound})",
        fp.k,
        fp.n
    );
}

/// The share of controls with a remainder above noise (`remaining_above_noise`) is that of the
/// z ≥ 3 test, P(z ≥ 3) = 0.00135, for the campaign's cases `cases` of the controls `ids`: more
/// than `max_consistent_failures(n, 0.00135, 0.01)` refute it at the 1 % level.
fn assert_remainder_rate(cases: &[gearbif::campaign::metrics::CaseResult], ids: &[&str]) {
    let ctl: Vec<_> = cases
        .iter()
        .filter(|c| ids.contains(&c.effect.as_str()))
        .collect();
    assert!(ctl.iter().all(|c| c.remaining_above_noise.is_some()));
    let above: Vec<String> = ctl
        .iter()
        .filter(|c| c.remaining_above_noise == Some(true))
        .map(|c| format!("{} seed {} z = {:?}", c.effect, c.seed, c.remaining_z))
        .collect();
    let bound = max_consistent_failures(ctl.len(), 0.00135, 0.01);
    assert!(
        above.len() <= bound,
        "remainder above noise in {} of {} controls (bound {bound}): {above:?}",
        above.len(),
        ctl.len()
    );
}

/// The remainder's noise floor on the 20 white-noise controls of the CI campaign: a remainder
/// above noise at most `max_consistent_failures(20, 0.00135, 0.01)` = 1 times.
#[test]
fn ci_campaign_remainder_rate_on_white_noise() {
    assert_remainder_rate(&ci_campaign().cases, &["none"]);
}

/// The remainder's dependence test on the 20 white-noise controls of the CI campaign: its
/// threshold keeps the family-wise rate of a significant dependence at 1 % (eight variables
/// tested, [`gearbif::identification::judge::z_threshold`]); more than
/// `max_consistent_failures(20, 0.01, 0.01)` controls with one refute that at the 1 % level.
#[test]
fn ci_campaign_dependence_rate_on_white_noise() {
    let ctl: Vec<_> = ci_campaign()
        .cases
        .iter()
        .filter(|c| c.effect == "none")
        .collect();
    assert_eq!(ctl.len(), 20);
    let found: Vec<String> = ctl
        .iter()
        .filter_map(|c| {
            Some(format!(
                "seed {}: {}",
                c.seed,
                c.remaining_depends_on.as_ref()?
            ))
        })
        .collect();
    let bound = max_consistent_failures(ctl.len(), 0.01, 0.01);
    assert!(
        found.len() <= bound,
        "a significant dependence on {} of {} controls (bound {bound}): {found:?}",
        found.len(),
        ctl.len()
    );
}

/// The remainder's noise floor under coloured camera noise (docs/diagnosis.md, "What remains and
/// where"): AR(1) between frames with ρ = 0.7 and 0.9 (controls `none_ar1`, `none_ar1_strong`; 5
/// seeds each on the CI campaign's tiny sets). The floor of an earlier version (white noise at the
/// cleaning's σ, which the cleaning's high-pass prediction errors underestimate 3.9 and 13 times
/// in variance) called a remainder above noise in every such control; at most
/// `max_consistent_failures(10, 0.00135, 0.01)` = 1 is consistent with the nominal rate. The
/// verdicts must be `none`.
#[test]
fn remainder_floor_holds_under_coloured_noise() {
    assert_controls_clean("ar1", &["none_ar1", "none_ar1_strong"], 5);
}

/// The controls `ids` on the CI campaign's tiny sets, seeds 1 to `seeds` each: every verdict
/// `none`, and the remainder at the noise ([`assert_remainder_rate`]).
fn assert_controls_clean(tag: &str, ids: &[&str], seeds: u64) {
    let doc = tiny_campaign(tag, ids, 1.0, 1, seeds);
    assert_eq!(doc.cases.len(), ids.len() * seeds as usize);
    for c in &doc.cases {
        assert_eq!(c.verdict, "none", "{} seed {}", c.effect, c.seed);
    }
    assert_remainder_rate(&doc.cases, ids);
}

/// The remainder's noise floor under a timing jitter of the frames (control `none_jitter`, 0.5 ms,
/// 5 seeds on the CI campaign's tiny sets): β̇·δt is a white noise that grows with the speed and
/// is absent at rest; a floor measured only at rest called a remainder above noise in 20 of 20
/// `ci` sets (docs/diagnosis.md, "What remains and where"). The floor's speed part measures it in
/// motion: at most `max_consistent_failures(5, 0.00135, 0.01)` = 0 above noise, verdicts `none`
/// (without the speed part seed 2 is above noise, z = 3.94).
#[test]
fn remainder_floor_holds_under_timing_jitter() {
    assert_controls_clean("jitter", &["none_jitter"], 5);
}

/// A drive whose speed ripples once per input turn (control `none_drive_ripple`: α = Ωt +
/// 0.15 sin Ωt, recorded as it is; 5 seeds on the CI campaign's tiny sets). The prediction
/// windows follow the recorded input (`predict::window_input`): the verdicts are `none` and the
/// remainder is at the noise, at most `max_consistent_failures(5, 0.00135, 0.01)` = 0 above it.
/// With each window's input the line at the stated rate through its first recorded α, the
/// remainder was above noise in all 5 (docs/diagnosis.md, "Pipeline").
#[test]
fn the_windows_follow_a_drive_whose_speed_ripples() {
    assert_controls_clean("ripple", &["none_drive_ripple"], 5);
}

/// Goal: effects of a clear size are named right in ≥ 90 % of the sets. Misses beyond
/// `max_consistent_failures(8, 0.10, 0.01)` (= 3 of 8) refute it at the 1 % level.
#[test]
fn ci_campaign_detects_clear_effects() {
    for p in &summary().power {
        let r = p.points[0].named_right;
        assert_eq!(r.n, 8);
        let bound = max_consistent_failures(r.n, 0.10, 0.01);
        assert!(
            r.n - r.k <= bound,
            "{}: named right {} of {} (at most {bound} misses allowed)",
            p.effect,
            r.k,
            r.n
        );
    }
}

/// Goal: the truth lies within ±2σ of the reported headline size in ≥ 90 % of the detections,
/// for each effect (static torque, sensor latency) and pooled. Every detection must report its
/// size; misses beyond `max_consistent_failures(n, 0.10, 0.01)` refute the goal at the 1 % level.
/// (Ignored while the sizes were attenuated by the judging windows' masks: 4 of 8 static-torque
/// sizes within ±2σ then; docs/diagnosis.md, "Sizes".)
#[test]
fn ci_campaign_sigma_coverage() {
    let c = &summary().coverage;
    assert_eq!(c.missing_size, 0, "detections without a headline size");
    assert_eq!(c.other_unit, 0, "headline sizes in an unexpected unit");
    assert!(c.pooled.n >= 12, "only {} comparable sizes", c.pooled.n);
    for effect in ["static_torque", "sensor_latency"] {
        let r = c.per_effect.get(effect).copied().unwrap_or(Rate::new(0, 0));
        assert!(r.n >= 5, "{effect}: only {} comparable sizes", r.n);
    }
    for (name, r) in c
        .per_effect
        .iter()
        .map(|(e, r)| (e.as_str(), r))
        .chain([("pooled", &c.pooled)])
    {
        let bound = max_consistent_failures(r.n, 0.10, 0.01);
        assert!(
            r.n - r.k <= bound,
            "{name}: truth within ±2σ in {} of {} (at most {bound} misses allowed)",
            r.k,
            r.n
        );
    }
}

/// The refit by simulation is unbiased where its σ is small: a set from the campaign generator
/// (not the catalog's) at a tenth of the documented camera noise (0.05°, outlier frames of 10–40°
/// kept), with a two-harmonic static torque (12 and 6 s⁻²) and a 6 ms latency, refitted with the
/// true model's terms from the weak-form start (latency 4 ms) on the judging windows. Every size
/// must lie within 3 of its σ (about 0.1 % here). The masks of an earlier version (every frame
/// beyond 5σ of the weak-form base model masked, windows with more than a fifth masked dropped)
/// dropped most windows at this noise and gave the amplitude 4 % low; the windows left out at
/// a start short of the latency and never tried again biased it low.
#[test]
fn refit_sizes_are_unbiased_at_low_noise() {
    use gearbif::campaign::cases::draw_lab;
    use gearbif::campaign::generator::{generate, Measurement};
    use gearbif::campaign::rng::Rng;
    use gearbif::identification::diagnose::DiagnoseOptions;
    use gearbif::identification::regression::{fit, Term, BASE_TERMS};
    use gearbif::identification::shooting::{refit, Reselect, ShootingOptions, SimModel};
    let mut rng = Rng::new(5, 77);
    let (mut truth, stated, _) = draw_lab(&mut rng);
    let (a1, a2, tau) = (12.0, 6.0, 0.006);
    truth.harmonics = vec![(1, a1, 0.8), (2, a2, 2.1)];
    let meas = Measurement {
        noise_deg: 0.05,
        latency_s: tau,
        ..Measurement::default()
    };
    let size = SetSize {
        ringdowns: 4,
        driven: 2,
        turns: 8.0,
        ringdown_s: 2.0,
        ..SetSize::ci()
    };
    let set = generate(
        &truth,
        &meas,
        &size,
        stated,
        &Rk4Filippov::default(),
        &mut rng,
    )
    .unwrap();
    let opts = DiagnoseOptions::default();
    let (prep, base, _) = prepared_base(&set, &opts);
    let extra = [Term::SinB, Term::CosB, Term::Sin(0, 2), Term::Cos(0, 2)];
    let mut terms = BASE_TERMS.to_vec();
    terms.extend(extra);
    let mut cols = vec![0, 1, 2, 3];
    cols.extend(extra.iter().map(|&t| base.design.col(t).unwrap()));
    let mut theta0 = fit(&base.design, &cols).unwrap().coef;
    theta0.push(0.004);
    let model = SimModel {
        runs: &prep.runs,
        geo: base.geo,
        terms,
        latency: 0.004,
        fit_latency: true,
        eta_static_excess: 0.0,
        tol: opts.tol,
        held_shapes: Vec::new(),
        roughness: 0.0,
        session: Default::default(),
    };
    let sopts = ShootingOptions {
        patience: 4,
        reselect: Reselect::Always,
        ..ShootingOptions::default()
    };
    let f = refit(&model, &theta0, &base.wins, &sopts).unwrap();
    let amp = |i: usize| {
        let (a, b) = (f.theta[i], f.theta[i + 1]);
        let r = a.hypot(b);
        let v = (a * a * f.cov[(i, i)]
            + 2.0 * a * b * f.cov[(i, i + 1)]
            + b * b * f.cov[(i + 1, i + 1)])
            / (r * r);
        (r, v.sqrt())
    };
    let got = [amp(4), amp(6), (f.theta[8], f.err[8])];
    for ((name, truth), (v, s)) in [("A1", a1), ("A2", a2), ("latency", tau)]
        .into_iter()
        .zip(got)
    {
        assert!(
            (v - truth).abs() <= 3.0 * s && s < 0.01 * truth,
            "{name} = {v} ± {s} (truth {truth}); windows {} of {}",
            f.used.len(),
            base.wins.len()
        );
    }
}

fn gearbif(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_gearbif"))
        .args(args)
        .output()
        .unwrap()
}

/// Bad input: exit code 2 with a message that names the problem, and no output written.
#[test]
fn cli_campaign_rejects_bad_input() {
    let out = std::env::temp_dir().join(format!("gearbif-campaign-bad-{}", std::process::id()));
    let o = out.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["--effects", "warp_drive"],
            "unknown effect `warp_drive`",
        ),
        (vec!["--sizes", "-1"], "level -1"),
        (vec!["--set", "huge"], "unknown set size `huge`"),
        (vec!["--seeds", "0"], "--seeds"),
        (vec!["--step", "0.5"], "RK4 step"),
    ] {
        let mut all = vec!["campaign", "--out", o];
        all.extend(args.iter());
        let r = gearbif(&all);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!out.join("campaign.json").exists());
    }
    let help = String::from_utf8_lossy(&gearbif(&["campaign", "--help"]).stdout).to_string();
    for unit in ["s^-2", "deg", "ms", "Hz", "frames/s"] {
        assert!(help.contains(unit), "--help lacks `{unit}`");
    }
}

/// A one-set campaign through the CLI writes campaign.json (schema `gearbif.campaign/1`), the
/// Markdown tables, the figure and the completion marker; a second run resumes without
/// diagnosing again.
#[test]
fn cli_campaign_writes_its_outputs_and_resumes() {
    let out = std::env::temp_dir().join(format!("gearbif-campaign-cli-{}", std::process::id()));
    let o = out.to_str().unwrap();
    let args = [
        "campaign",
        "--out",
        o,
        "--effects",
        "none",
        "--null-seeds",
        "1",
        "--set",
        "ci",
        "--ringdowns",
        "2",
        "--driven",
        "1",
        "--turns",
        "4",
    ];
    let r = gearbif(&args);
    assert_eq!(
        r.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("campaign.json")).unwrap()).unwrap();
    assert_eq!(doc["schema"], "gearbif.campaign/1");
    assert_eq!(doc["summary"]["false_positive"]["n"], 1);
    assert!(std::fs::read_to_string(out.join("campaign.md"))
        .unwrap()
        .contains("False positives"));
    assert!(out.join("campaign.svg").exists() && out.join("campaign.png").exists());
    // the completion marker, written last, names the result files
    let done: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("complete.json")).unwrap()).unwrap();
    assert_eq!(done["schema"], "gearbif.complete/1");
    assert_eq!(done["files"].as_array().map(Vec::len), Some(4));
    let again = gearbif(&args);
    assert!(String::from_utf8_lossy(&again.stderr).contains("1 already done, 0 to run"));
    std::fs::remove_dir_all(&out).ok();
}

/// What remains and where (report key `remaining`): on a set whose friction law lies outside
/// every family (a Lorentzian Stribeck decay 1/(1 + (β̇/w)²), `lorentz_stribeck` at level 4,
/// seed 1, the CI set of `gearbif campaign --set ci --ringdowns 4 --driven 2 --turns 8`; the
/// Stribeck member of `static_friction` is named and explains part of it) the report finds a
/// held-out mismatch above the camera noise (z = 3.77 with the code of 2026-11-26) and locates it
/// in bins; on a control it says nothing is left. The set was a tilted set-up's bearing load
/// (`tilted_load_friction`, level 2) until the load family fitted the weight's direction: the
/// family now predicts it within noise (z = 1.52, was 3.44).
#[test]
fn remainder_is_located_out_of_family_and_absent_on_a_control() {
    let size = SetSize {
        ringdowns: 4,
        driven: 2,
        turns: 8.0,
        ..SetSize::ci()
    };
    let dir = std::env::temp_dir().join(format!("gearbif-remainder-{}", std::process::id()));
    for (id, level, left) in [("lorentz_stribeck", 4.0, true), ("none", 1.0, false)] {
        let c = build_case(
            effect(id).unwrap(),
            level,
            1,
            &size,
            &Rk4Filippov::default(),
        )
        .unwrap();
        let d = dir.join(id);
        gearbif::io::recordings::write_set(&c.set, &d, true).unwrap();
        let set = gearbif::io::recordings::read_set(&d).unwrap();
        let opts = gearbif::identification::diagnose::DiagnoseOptions::default();
        let rep =
            gearbif::identification::diagnose::diagnose(&set, &opts, &gearbif::progress::Silent)
                .unwrap()
                .report;
        let r = rep.remaining.clone().expect("a remainder in the report");
        let z = r.excess_chi2_per_dof / r.excess_sigma;
        assert_eq!(!r.within_noise, left, "{id}: E/σ = {z:.2}, {:?}", r.located);
        if left {
            assert!(z >= 3.0 && !r.located.is_empty(), "{id}: {r:?}");
            for b in &r.located {
                assert!(b.excess_chi2_per_dof >= 3.0 * b.excess_sigma, "{b:?}");
            }
        } else {
            assert!(r.located.is_empty(), "{id}: {r:?}");
            let md = gearbif::identification::report::markdown(&rep, id);
            assert!(md.contains("Nothing left above noise"), "{md}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A campaign of one effect at level 2 on `ci` sets (6 ring-downs of 3 s, 3 driven runs of 12
/// turns), seeds 1..=`seeds`, no controls, the diagnosis's default options. The folder is
/// removed afterwards.
fn level2_ci_campaign(effect: &str, seeds: u64) -> CampaignDoc {
    level2_ci_seeds(effect, (1..=seeds).collect())
}

/// [`level2_ci_campaign`] on the seeds `seeds`.
fn level2_ci_seeds(effect: &str, seeds: Vec<u64>) -> CampaignDoc {
    ci_seeds(effect, 2.0, seeds)
}

/// A campaign of one effect at `level` on `ci` sets, the seeds `seeds`, no controls, the
/// diagnosis's default options. The folder is removed afterwards.
fn ci_seeds(effect: &str, level: f64, seeds: Vec<u64>) -> CampaignDoc {
    let out = std::env::temp_dir().join(format!(
        "gearbif-campaign-{effect}-{level}-{}-{}",
        seeds.first().copied().unwrap_or(0),
        std::process::id()
    ));
    let spec = CampaignSpec {
        effects: vec![effect.into()],
        levels: vec![level],
        seeds,
        null_seeds: Vec::new(),
        set: SetSize::ci(),
        tol: gearbif::identification::diagnose::DiagnoseOptions::default().tol,
        profile_shapes: false,
        rk4_step_s: 2.5e-4,
        keep_sets: false,
    };
    let doc = run_campaign(&spec, &out, &gearbif::progress::Silent).unwrap();
    std::fs::remove_dir_all(&out).ok();
    doc
}

/// The backward check drops an accepted effect the recordings do not need and keeps the one they
/// do. On sets with a two-harmonic static torque and nothing else (the campaign generator's
/// `static_torque_2h`, level 1, `ci` size, seeds 1–3), the torque member with two harmonics and
/// then a corotating drag (absent from the recordings) are accepted by hand, each refitted by
/// simulation on top of the model before it (`select::evaluate`, as the rounds do), and
/// `backward::backward` runs on the model with both at the threshold of a round of the actual
/// size: the drag is dropped in every seed (its Wald z in the final model is below the
/// threshold and the model without it does not predict the held-out runs significantly worse),
/// the torque is kept, and the final model has no drag term. (A drag that absorbed part of the
/// torque would keep a Wald z above the threshold, or predict better, and fail this.)
#[test]
fn the_backward_check_drops_an_effect_the_recordings_do_not_need() {
    use gearbif::identification::backward::backward;
    use gearbif::identification::catalog::catalog;
    use gearbif::identification::judge::z_threshold;
    use gearbif::identification::propose::{propose, Candidate};
    use gearbif::identification::regression::Term;
    use gearbif::identification::select::{evaluate, ModelState, Tried};
    use gearbif::progress::Silent;
    for seed in 1..=3u64 {
        on_base_model("static_torque_2h", 1.0, seed, |sctx, b| {
            // the candidates of a round on `cur` and the round's threshold
            let round = |cur: &ModelState| {
                let lat = cur.fit_latency.then(|| cur.latency());
                let cands = propose(sctx.propose, &cur.terms, lat, &cur.effects);
                let z_crit = z_threshold(cands.len());
                (cands, z_crit)
            };
            let pick = |cur: &ModelState, id: &str, n: usize| {
                let (cands, z_crit) = round(cur);
                let c = cands
                    .into_iter()
                    .find(|c| c.effect.id == id && c.terms.len() == n)
                    .unwrap_or_else(|| panic!("seed {seed}: no {id} candidate with {n} terms"));
                (c, z_crit)
            };
            let (torque, z1) = pick(b, "static_torque", 4);
            let with_torque = evaluate(&sctx, b, &torque).expect("the torque's refit");
            // the drag is not proposed on these sets (the weak form does not see it): its candidate
            // starts nested, at the current θ with a zero drag
            let (_, z2) = round(&with_torque);
            let nt = with_torque.terms.len();
            let drag = Candidate {
                effect: catalog()
                    .into_iter()
                    .find(|e| e.id == "corotating_drag")
                    .unwrap(),
                terms: vec![Term::Corot],
                weak_coef: with_torque.fit.theta[..nt]
                    .iter()
                    .copied()
                    .chain([0.0])
                    .collect(),
                weak_coef_current: with_torque.fit.theta[..nt].to_vec(),
                latency: None,
                weak_dbic: 0.0,
            };
            let with_both = evaluate(&sctx, &with_torque, &drag).expect("the drag's refit");
            let accepted = |round, candidate, z_crit, state| Tried {
                round,
                candidate,
                cmp: None,
                screen: None,
                screen_fit: None,
                screen_beaten: None,
                z_crit,
                accepted: true,
                state: Some(state),
                added_z: None,
                member: None,
                dropped: None,
                forked: false,
                joined: false,
                on_top_of: None,
            };
            let mut tried = vec![
                accepted(1, torque, z1, with_torque),
                accepted(2, drag, z2, with_both.clone()),
            ];
            let fin = backward(&sctx, with_both, &mut tried, &Silent);
            // the numbers of docs/diagnosis.md ("Pipeline", after step 8), shown with --nocapture
            eprintln!(
                "seed {seed}: drag {:?} (threshold {z2:.2})",
                tried[1].dropped
            );
            assert!(
                !tried[1].accepted && tried[1].dropped.is_some(),
                "seed {seed}: the drag was kept: {:?}",
                tried[1].dropped
            );
            assert!(
                tried[0].accepted && tried[0].dropped.is_none(),
                "seed {seed}"
            );
            assert!(
                !fin.terms.contains(&Term::Corot),
                "seed {seed}: {:?}",
                fin.terms
            );
            assert_eq!(fin.effects.len(), 1, "seed {seed}");
        });
    }
}

/// The order of two close rivals does not decide what is named. A static torque of 12 s⁻²
/// (6 s⁻² at 2β) and a 12 ms latency together (the campaign generator's `torque_and_latency` at
/// level 2). Seed 3: in round 1 a corotating drag and the latency reach the threshold with
/// nearly equal held-out gains, and the drag does not predict the held-out windows
/// significantly better than the latency. The greedy rule accepted the drag, which absorbed the
/// latency, and the set was named `corotating_drag`. The selection now forks there
/// (`beam::select`): the drag's branch ends with drag + torque, the latency's with latency +
/// torque, and the latter's final model predicts the held-out windows better and is kept. Since
/// the settling drifts, the drag's round-1 rival is a settling `parameter_drift` member, whose
/// branch goes on to accept the latency and the torque and drops the drift in the backward
/// check (the same verdict, findings and sizes); the drag's branch now takes the latency and the
/// torque too, but keeps the drag, and predicts the held-out windows significantly worse (z 10.2
/// for the kept branch). Seed 2:
/// with the greedy rule one candidate of a round-1 tie (`drive_steps` when the significance was
/// tested on the raw χ² gains, docs/diagnosis.md) was accepted and neither true effect after it;
/// the branch of its rival goes on to accept the latency and the torque, and what they make
/// superfluous is dropped by the backward check at the end. On both sets: exactly one fork, in
/// round 1, between two candidates of which neither predicts significantly better (|z| < 3);
/// the kept branch holds both true effects (on seed 2 only it; on seed 3 the other holds the
/// drag besides), and its final model predicts significantly better than the other branch's
/// (z ≥ 3, also when the other branch was left early); the
/// verdict names the two true effects and nothing else, their sizes within ±2σ on seed 3 and
/// within ±3σ on seed 2 (the torque 11.75 ± 0.08 s⁻² for 12, 3.0σ; the latency within ±2σ).
#[test]
fn close_rivals_are_told_apart_by_their_branches() {
    let doc = level2_ci_seeds("torque_and_latency", vec![2, 3]);
    let truth = ["sensor_latency".to_string(), "static_torque".to_string()];
    for c in &doc.cases {
        let lines = format!(
            "seed {}: verdict {}, findings {:?}, coverage {:?}, forks {:?}",
            c.seed, c.verdict, c.findings, c.coverage, c.forks
        );
        assert!(c.named_right, "{lines}");
        assert!(
            c.findings
                .iter()
                .all(|f| f.effect == "static_torque" || f.effect == "sensor_latency"),
            "{lines}"
        );
        assert_eq!(c.coverage.len(), 2, "{lines}");
        let k = if c.seed == 2 { 3.0 } else { 2.0 };
        assert!(
            c.coverage.iter().all(|e| e
                .reported
                .is_some_and(|(v, s)| (v - e.truth).abs() <= k * s)),
            "{lines}"
        );
        assert_eq!(c.forks.len(), 1, "{lines}");
        let f = &c.forks[0];
        assert_eq!(f.round, 1, "{lines}");
        assert!(f.round_z.abs() < 3.0, "{lines}");
        assert!(f.final_z >= 3.0, "{lines}");
        let holds_both = |effects: &[String]| truth.iter().all(|t| effects.contains(t));
        assert!(holds_both(&f.kept_effects), "{lines}");
        if c.seed == 2 {
            assert!(!holds_both(&f.other_effects), "{lines}");
        } else {
            // the drag's branch is the one left, and it keeps the drag that is not in the truth
            assert_eq!(f.other.as_str(), "corotating_drag", "{lines}");
            assert!(
                f.other_effects.iter().any(|e| e == "corotating_drag"),
                "{lines}"
            );
        }
    }
}

/// Close rivals each significant on top of the other are accepted together (`beam`, the joint
/// check). On a set with a static torque and a sensor latency (`torque_and_latency`, level 1:
/// 6 s⁻² and 6 ms, `ci` size, seed 1; the set the campaign runner diagnoses, written and read
/// back) the two tie in round 1; each refitted on top of the other is significant, so both are
/// accepted in round 1 without a fork. On this set the order matters: the torque's member chosen
/// on the base model, with the latency on top, left a mismatch that an input compliance then
/// took (torque 6.67 ± 0.18 s⁻²); the torque's member chosen on top of the latency predicts
/// better (z 7.2) and is kept. Asserted: the report's one joint (the pair, round 1, the
/// tie below the round's threshold and both z above it), no fork, the findings the two effects
/// and both sizes within 3σ of the truth; the second finding says it was judged on top of the
/// first and names no member of it as a rival; the rival's round-1 entry is listed with the
/// joint's reason. On sets with the torque alone the check refuses a pair (below). The refusal
/// inside the selection is `close_rivals_are_told_apart_by_their_branches`, whose sets fork.
#[test]
fn close_rivals_each_significant_on_top_of_the_other_are_accepted_together() {
    use gearbif::campaign::metrics::{coverage_entries, FoundEffect};
    use gearbif::identification::diagnose::{diagnose, DiagnoseOptions};
    use gearbif::io::recordings::{read_set, write_set};
    let spec = effect("torque_and_latency").unwrap();
    let g = build_case(spec, 1.0, 1, &SetSize::ci(), &Rk4Filippov::default()).unwrap();
    let dir = std::env::temp_dir().join(format!("gearbif-joint-{}", std::process::id()));
    write_set(&g.set, &dir, true).unwrap();
    let set = read_set(&dir).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let d = diagnose(
        &set,
        &DiagnoseOptions::default(),
        &gearbif::progress::Silent,
    )
    .unwrap();
    let r = &d.report;
    let joints = r.selection_joints();
    let found: Vec<FoundEffect> = r
        .findings
        .iter()
        .map(|f| FoundEffect {
            effect: f.effect.clone(),
            size: f.size.clone(),
        })
        .collect();
    let coverage = coverage_entries(&g.truths, &found);
    let lines = format!(
        "verdict {}, findings {:?}, coverage {coverage:?}, forks {:?}, joints {joints:?}",
        r.verdict,
        found.iter().map(|f| &f.effect).collect::<Vec<_>>(),
        r.selection_forks()
    );
    assert!(r.selection_forks().is_empty(), "{lines}");
    assert_eq!(joints.len(), 1, "{lines}");
    let j = &joints[0];
    let mut pair = [j.first.as_str(), j.second.as_str()];
    pair.sort();
    assert_eq!(pair, ["sensor_latency", "static_torque"], "{lines}");
    assert_eq!(j.round, 1, "{lines}");
    assert!(j.round_z < j.z_crit, "{lines}");
    assert!(
        j.second_on_first.0 >= j.z_crit && j.first_on_second.0 >= j.z_crit,
        "{lines}"
    );
    let mut ids: Vec<&str> = found.iter().map(|f| f.effect.as_str()).collect();
    ids.sort();
    assert_eq!(ids, ["sensor_latency", "static_torque"], "{lines}");
    assert_eq!(coverage.len(), 2, "{lines}");
    assert!(
        coverage.iter().all(|e| e
            .reported
            .is_some_and(|(v, s)| (v - e.truth).abs() <= 3.0 * s)),
        "{lines}"
    );
    let second = r
        .findings
        .iter()
        .find(|f| f.effect == j.second)
        .expect("the second's finding");
    assert_eq!(
        second.evidence["accepted_together_with"]["effect"], j.first,
        "{lines}"
    );
    let rivals = second
        .evidence
        .get("significant_rivals")
        .map(|v| v.to_string())
        .unwrap_or_default();
    assert!(!rivals.contains(&j.first), "{lines}: {rivals}");
    let rejected = r.fits.as_ref().expect("fits")["rejected_candidates"]
        .as_array()
        .expect("a list")
        .clone();
    assert!(
        rejected.iter().any(|c| c["round"] == 1
            && c["effect"] == j.second.as_str()
            && c["reason"]
                .as_str()
                .is_some_and(|s| s.contains("accepted with it in the same round"))),
        "{lines}"
    );
    refused_on_sets_with_the_torque_alone();
}

/// The negative half of the test above: the joint check refuses the pair of the torque and the
/// Stribeck member where the recordings hold the torque alone (the Stribeck member is not
/// significant on top of the torque, while the torque is on top of the Stribeck member).
fn refused_on_sets_with_the_torque_alone() {
    use gearbif::identification::beam::{on_top_of_each_other, OnTop};
    use gearbif::identification::judge::z_threshold;
    use gearbif::identification::propose::propose;
    use gearbif::identification::select::{converge, evaluate};
    for seed in [1u64, 2] {
        on_base_model("static_torque_2h", 2.0, seed, |sctx, b| {
            let cands = propose(sctx.propose, &b.terms, None, &b.effects);
            let z_crit = z_threshold(cands.len());
            let pick = |id: &str, n: usize| {
                cands
                    .iter()
                    .find(|c| c.effect.id == id && c.terms.len() == n)
                    .unwrap_or_else(|| panic!("seed {seed}: no {id} with {n} terms"))
            };
            let (torque, stribeck) = (pick("static_torque", 4), pick("static_friction", 3));
            let on = |c| converge(&sctx, &evaluate(&sctx, b, c).expect("the refit"));
            let [stribeck_on_torque, torque_on_stribeck] = on_top_of_each_other(
                &sctx,
                (torque, &on(torque)),
                (stribeck, &on(stribeck)),
                (1, z_crit),
            );
            let z = |t: &OnTop| {
                t.tried
                    .iter()
                    .map(|t| (t.cmp.map(|c| c.z), t.added_z))
                    .collect::<Vec<_>>()
            };
            let lines = format!(
            "static_torque_2h seed {seed}: the Stribeck member on the torque (held-out z, Wald \
             z): {:?}; the torque's members on it: {:?} (threshold {z_crit:.2})",
            z(&stribeck_on_torque),
            z(&torque_on_stribeck)
        );
            eprintln!("{lines}");
            assert!(!stribeck_on_torque.tried.is_empty(), "{lines}");
            assert_eq!(stribeck_on_torque.chosen, None, "{lines}");
            // the other direction: the torque the sets hold is significant on top of the Stribeck
            // member's model (held-out z 7.9–13.2; −12.6 to −10.4 while the leave-fold-out step
            // moved the Stribeck excess that model's windows do not determine by 10²⁸³)
            assert!(torque_on_stribeck.chosen.is_some(), "{lines}");
        });
    }
}

/// The judge's one-step leave-fold-out refits against exact ones (each fold's model refitted to
/// convergence without the fold's windows, then the fold's windows predicted), on the set where
/// the one-step refit used to move an undetermined parameter (docs/diagnosis.md, Known
/// weaknesses): `static_torque_2h` level 2 seed 2 (`ci` set), the torque's members on top of the
/// Stribeck member's model, against that model. The held-out z of the two must agree to 0.5
/// (the one-step refit is first order in what a fold changes; measured 7.70 against 7.64 and
/// 13.19 against 12.99; the one-step refit that moved the Stribeck excess gave −7.37 for the
/// first). About 5 s: `cargo test --release --test campaign -- --nocapture one_step_held_out`.
#[test]
fn one_step_held_out_agrees_with_exact_leave_fold_out_refits() {
    use gearbif::identification::judge::{compare, HeldOut};
    use gearbif::identification::propose::propose;
    use gearbif::identification::select::{
        converge, evaluate, proposed_on, refit_to_convergence, ModelState, SelectCtx,
    };
    use gearbif::identification::shooting::{Reselect, ShootingOptions};
    let exact = |ctx: &SelectCtx, st: &ModelState| -> HeldOut {
        let model = st.model(ctx.runs, ctx.geo, ctx.tol);
        let (chi2_fit, warm) = st.fit.window_chi2(&model, ctx.wins);
        let opts = ShootingOptions {
            reselect: Reselect::Never,
            ..*ctx.shooting
        };
        let mut chi2 = vec![None; ctx.wins.len()];
        for f in 0..ctx.folds.k {
            let out = |w: &gearbif::identification::shooting::Win| ctx.folds.of_run[w.run] == f;
            let train: Vec<_> = ctx.wins.iter().filter(|w| !out(w)).cloned().collect();
            let th = refit_to_convergence(&model, &st.fit.theta, &train, &opts)
                .map_or(st.fit.theta.clone(), |fit| fit.theta);
            for (k, w) in ctx.wins.iter().enumerate().filter(|(_, w)| out(w)) {
                chi2[k] = model.window_chi2_from(&th, w, warm[k]);
            }
        }
        HeldOut { chi2, chi2_fit }
    };
    on_base_model("static_torque_2h", 2.0, 2, |sctx, b| {
        let cands = propose(sctx.propose, &b.terms, None, &b.effects);
        let find = |id: &str| cands.iter().find(|c| c.effect.id == id).unwrap();
        let stribeck = cands
            .iter()
            .find(|c| c.effect.id == "static_friction" && c.terms.len() == 3)
            .unwrap();
        let s = converge(&sctx, &evaluate(&sctx, b, stribeck).unwrap());
        let s_exact = exact(&sctx, &s);
        let members = proposed_on(&sctx, &s, find("static_torque"));
        for c in members.iter().take(2) {
            let t = converge(&sctx, &evaluate(&sctx, &s, c).unwrap());
            let one_step = compare(&s.held, &t.held, sctx.wins, sctx.runs);
            let exact_z = compare(&s_exact, &exact(&sctx, &t), sctx.wins, sctx.runs);
            let sum = |h: &HeldOut| h.chi2.iter().flatten().sum::<f64>();
            eprintln!(
            "torque with {} terms on the Stribeck model: one-step z {:.2} (held-out Σχ² {:.4e}), \
             exact z {:.2}; in sample Σχ² {:.4e}",
            c.terms.len(),
            one_step.z,
            sum(&t.held),
            exact_z.z,
            t.held.chi2_fit.iter().flatten().sum::<f64>()
        );
            assert!(
                (one_step.z - exact_z.z).abs() < 0.5,
                "{one_step:?} vs {exact_z:?}"
            );
        }
    });
}

/// A 12 ms camera latency (the campaign generator's `latency` at level 2, seed 4: its own
/// equation, integrator and noise) that the base model cannot follow on the driven runs (it
/// follows 2 of their 97 judging windows): named `sensor_latency`, with the truth within ±2σ of
/// the reported latency. The judge's refit of the latency candidate used to keep only the windows
/// its weak-form start followed (25, none of them driven), left the latency undetermined (Wald z
/// 0) and named a `condition_dependence` of ζ instead (docs/diagnosis.md, Known weaknesses). One
/// diagnosis: 72 s wall in the release build at load ≈ 5 (95 s CPU for the same set by `gearbif
/// diagnose`).
#[test]
fn a_large_latency_is_judged_on_the_driven_windows_it_explains() {
    let doc = level2_ci_seeds("latency", vec![4]);
    let c = &doc.cases[0];
    assert!(c.named_right, "{}: {:?}", c.verdict, c.findings);
    let cov: Vec<_> = c.coverage.iter().map(|k| k.within_2sigma).collect();
    assert_eq!(cov, vec![Some(true)], "{:?}", c.findings);
}

/// A viscous damping that depends on the drive frequency, from the campaign generator (not the
/// catalog's form: ζ(1 + k(f − 1 Hz)) in the driven runs, the ring-downs at ζ, k = 0.6/Hz; CI
/// sets of 6 ring-downs of 3 s and 3 driven runs of 12 turns at 0.5, 1.5, 2.5 Hz), over 4 seeds:
/// named a `condition_dependence` *of ζ* (headline `zeta_change`) in ≥ 90 % of the sets (more
/// misses than `max_consistent_failures(4, 0.10, 0.01)` refute it), and never a per-run
/// parameter other than ζ. The condition law of an earlier version put the ring-downs at f = 0
/// and named g instead (the Python generator's `freq_zeta`).
#[test]
fn frequency_dependent_damping_is_a_condition_dependence_of_zeta() {
    let doc = level2_ci_campaign("frequency_damping", 4);
    assert_per_run_effect_of(&doc, "zeta_change");
}

/// The cases of `doc` (4 seeds) whose first finding is a per-run parameter effect headlined by
/// `headline` (e.g. `zeta_change`) and named right: in ≥ 90 % of the sets (more misses than
/// `max_consistent_failures(4, 0.10, 0.01)` refute it), and no per-run finding
/// (`condition_dependence`, `parameter_drift`) of another parameter in any set.
fn assert_per_run_effect_of<'a>(
    doc: &'a CampaignDoc,
    headline: &str,
) -> Vec<&'a gearbif::campaign::metrics::CaseResult> {
    assert_eq!(doc.cases.len(), 4);
    let per_run = |f: &&gearbif::campaign::metrics::FoundEffect| {
        f.effect == "condition_dependence" || f.effect == "parameter_drift"
    };
    let of_param = |f: &gearbif::campaign::metrics::FoundEffect| {
        f.size.as_ref().is_some_and(|s| s.name == headline)
    };
    let right: Vec<_> = doc
        .cases
        .iter()
        .filter(|c| c.named_right && c.findings.first().is_some_and(of_param))
        .collect();
    let bound = max_consistent_failures(4, 0.10, 0.01);
    let seen: Vec<_> = doc
        .cases
        .iter()
        .map(|c| (&c.verdict, &c.findings))
        .collect();
    assert!(
        4 - right.len() <= bound,
        "{} of 4 right: {seen:#?}",
        right.len()
    );
    for c in &doc.cases {
        for f in c.findings.iter().filter(per_run) {
            assert!(of_param(f), "seed {}: {:?}", c.seed, c.findings);
        }
    }
    right
}

/// A friction that falls as the bearings warm up, from the campaign generator (not the catalog's
/// form: η(1 − a tanh(u/0.2)) of each run at its session position u, a = 0.4; the catalog's
/// drifts are linear or exponential; CI sets of 6 ring-downs of 3 s and 3 driven runs of 12 turns
/// in order of frequency, so a frequency dependence competes), over 4 seeds: named a
/// `parameter_drift` *of η* (headline `eta_change`) in ≥ 90 % of the sets (more misses than
/// `max_consistent_failures(4, 0.10, 0.01)` refute it), never a per-run parameter other than η,
/// and the change from the first run to the last within ±2σ in ≥ 90 % of the detections
/// (the same bound). Before the settling clocks the catalog had linear drifts only.
#[test]
fn a_friction_warm_up_is_a_parameter_drift_of_eta() {
    let doc = level2_ci_campaign("warming_friction", 4);
    let right = assert_per_run_effect_of(&doc, "eta_change");
    let covered = right
        .iter()
        .filter(|c| c.coverage.iter().all(|k| k.within_2sigma == Some(true)))
        .count();
    assert!(
        right.len() - covered <= max_consistent_failures(right.len(), 0.10, 0.01),
        "{covered} of {} cover the truth: {:#?}",
        right.len(),
        doc.cases
    );
}

/// The Stribeck family's size from recordings of the campaign generator (its own equation,
/// integrator and noise; truth inside the family: a Gaussian decay, w = 0.5 rad/s, excess
/// Δη_s = η), refitted by simulation from a start off the truth (the exponential grid member at
/// w = 1.2 rad/s with half the excess) to convergence, as the final refit of the diagnosis does
/// (`select::refit_to_convergence`): the truth within ±2σ of the relative excess Δη_s/η and of
/// w in at least 2 of 3 seeds (a rate of ≥ 90 % fails at most once in 3 at the 3 % level), and no
/// seed off by more than 4σ. A fit stopped on its evaluation budget part-way along the
/// width–excess valley gave the excess 13 % low with σ 0.2 % on a Python-generated set.
///
/// Ignored: it fails today. Measured 2026-11-25 with the variable-projection Jacobian (15 s wall
/// for the 3 refits, release build): seeds 1 and 3 cover the truth (Δη_s/η 0.953 ± 0.027 and
/// 1.009 ± 0.045, w 0.525 ± 0.066 and 0.467 ± 0.052), seed 2 stops with δ at the end of its range
/// (4 ± 0.11 with the column one-sided there; σ infinite before) and Δη_s/η 1.096 ± 0.015, w
/// 0.352 ± 0.011: 6σ and 14σ off. This is one start; the diagnosis refits the member from two
/// (`breakaway::final_member`, tested end to end below). Before that
/// Jacobian, seed 1 stopped at its start and seeds 2 and 3 left δ near 1 with σ(δ) ≤ 0.015 (0 of
/// 3 covered). See docs/diagnosis.md, Known weaknesses.
#[test]
#[ignore = "fails today: one seed of three stops with the Stribeck shape at its range's end (docs/diagnosis.md)"]
fn stribeck_size_covers_the_truth_on_generated_sets() {
    use gearbif::campaign::cases::draw_lab;
    use gearbif::campaign::generator::{generate, Measurement};
    use gearbif::campaign::rng::Rng;
    use gearbif::identification::diagnose::DiagnoseOptions;
    use gearbif::identification::model::Shape;
    use gearbif::identification::regression::{Term, BASE_TERMS};
    use gearbif::identification::select::refit_to_convergence;
    use gearbif::identification::shooting::{Reselect, ShootingOptions, SimModel};
    let (mut covered, mut worst) = (0, 0.0_f64);
    let mut lines = Vec::new();
    for seed in 1..=3u64 {
        let mut rng = Rng::new(seed, 91);
        let (mut truth, stated, _) = draw_lab(&mut rng);
        let (excess, width) = (truth.eta, 0.5);
        truth.stribeck = Some(Stribeck {
            excess,
            width,
            shape: StribeckShape::Gaussian,
        });
        let set = generate(
            &truth,
            &Measurement::default(),
            &SetSize::ci(),
            stated,
            &Rk4Filippov::default(),
            &mut rng,
        )
        .unwrap();
        let opts = DiagnoseOptions::default();
        let (prep, base, _) = prepared_base(&set, &opts);
        let st = base.state.as_ref().unwrap();
        let mut terms = BASE_TERMS.to_vec();
        terms.extend([
            Term::StaticExcess,
            Term::Shape(Shape::StribeckWidth),
            Term::Shape(Shape::StribeckPower),
        ]);
        let mut theta0 = st.fit.theta[..4].to_vec();
        theta0.extend([0.5 * excess, 1.2, 1.0]);
        let model = SimModel {
            runs: &prep.runs,
            geo: base.geo,
            tol: opts.tol,
            terms,
            latency: 0.0,
            fit_latency: false,
            eta_static_excess: 0.0,
            held_shapes: Vec::new(),
            roughness: 0.0,
            session: Default::default(),
        };
        let sopts = ShootingOptions {
            patience: 4,
            reselect: Reselect::Always,
            ..ShootingOptions::default()
        };
        let f = refit_to_convergence(&model, &theta0, &base.wins, &sopts).unwrap();
        // the report's headline: Δη_s/η with σ(Δη_s)/η
        let (eta, s, s_err) = (f.theta[1], f.theta[4] / f.theta[1], f.err[4] / f.theta[1]);
        let pulls = [
            (s - excess / truth.eta) / s_err,
            (f.theta[5] - width) / f.err[5],
        ];
        if pulls.iter().all(|p| p.abs() <= 2.0) {
            covered += 1;
        }
        worst = pulls.iter().fold(worst, |m, p| m.max(p.abs()));
        lines.push(format!(
            "seed {seed}: excess {s:.4} ± {s_err:.4} (truth {:.4}), w {:.4} ± {:.4} (0.5), δ {:.3} \
             ± {:.3} (2), η {eta:.3} ({:.3}), converged {}, windows {} of {}",
            excess / truth.eta,
            f.theta[5],
            f.err[5],
            f.theta[6],
            f.err[6],
            truth.eta,
            f.converged,
            f.used.len(),
            base.wins.len()
        ));
    }
    assert!(covered >= 2 && worst <= 4.0, "{}", lines.join("\n"));
    eprintln!("{}", lines.join("\n"));
}

/// The Stribeck excess, diagnosed end to end on recordings of the campaign generator (friction
/// η + Δη_s exp(−(β̇/w)²), Δη_s = η, w = 0.5 rad/s: level 2 of `stribeck`, `ci` sets of 6
/// ring-downs of 3 s and 3 driven runs of 12 turns) over 3 seeds with the diagnosis's default
/// options: every set is named `static_friction` (or `partly_explained` with the static friction
/// leading, where the final model leaves a significant remainder) with a size (not a lower bound)
/// within 20 % of the truth Δη_s/η = 1. The weak form does not propose the Stribeck member on these sets; the
/// stick-phase profile at rest does, and the member with a width is then refitted by simulation
/// (`breakaway::width_member`). Before, the finding was the profile at rest (the member's w → 0
/// limit), which reads the braking of slow sliding as a larger excess at rest: 1.5 ± 0.0001–0.009
/// on these seeds, the end of its range (docs/diagnosis.md, "Static friction"). The 20 % is the
/// accuracy measured on the campaign (0.79–1.04 on 5 seeds). The truth lies within ±2σ in ≥ 90 %
/// of the sets — more misses than `max_consistent_failures(3, 0.10, 0.01)` refute that at the 1 %
/// level; with the final refit's second minimum in the σ (`findings::second_minimum_size`), seed
/// 2's 0.841 carries σ 0.121 instead of 0.052 (docs/diagnosis.md).
#[test]
fn stribeck_member_sizes_the_excess_on_generated_sets() {
    let doc = level2_ci_campaign("stribeck", 3);
    assert_eq!(doc.cases.len(), 3);
    let misses = doc
        .cases
        .iter()
        .flat_map(|c| &c.coverage)
        .filter(|e| e.effect == "static_friction" && e.within_2sigma != Some(true))
        .count();
    let bound = max_consistent_failures(3, 0.10, 0.01);
    assert!(misses <= bound, "{misses} of 3 outside ±2σ (bound {bound})");
    for c in &doc.cases {
        let e = c
            .coverage
            .iter()
            .find(|e| e.effect == "static_friction")
            .unwrap_or_else(|| panic!("seed {}: verdict {}", c.seed, c.verdict));
        let (v, s) = e
            .reported
            .unwrap_or_else(|| panic!("seed {}: no size ({:?})", c.seed, e.note));
        // the verdict follows the remainder (docs/verdict.md): where the final model leaves a
        // significant remainder it is `partly_explained`, with the static friction leading
        let leads = c.verdict == "partly_explained"
            && c.findings.first().map(|f| f.effect.as_str()) == Some("static_friction");
        assert!(
            (c.named_right || leads) && (v - e.truth).abs() <= 0.2 * e.truth,
            "seed {}: verdict {}, excess {v} ± {s} (truth {})",
            c.seed,
            c.verdict,
            e.truth
        );
    }
}

/// The drag family's exponent, diagnosed end to end on recordings of the campaign generator
/// (−c |β̇|^1.5 sgn β̇ with c = 0.4 rad^-0.5 s^-0.5, level 2, `ci` sets: 6 ring-downs of 3 s and 3
/// driven runs of 12 turns) over 4 seeds with the diagnosis's default options: every detection
/// reports the exponent with a σ, and the truth 1.5 lies within ±2σ of it in ≥ 90 % of the
/// detections — more misses than `max_consistent_failures(n, 0.10, 0.01)` refute that at the 1 %
/// level — with at least 3 of the 4 sets named `power_law_drag`. Before the refit's Jacobian was
/// the variable-projection one (`shooting::varpro_jacobian`), the refit crept from the quadratic
/// member and stopped at 1.88–2.00 with σ 0.01–0.06: 0 of 11 covered in the campaign of
/// docs/diagnosis.md; only the opt-in shape profile (`--profile-shapes`, 3–9 times the CPU)
/// covered the truth.
#[test]
fn drag_exponent_covers_the_truth_on_generated_sets() {
    let doc = level2_ci_campaign("power_law_drag", 4);
    let cov: Vec<_> = doc
        .cases
        .iter()
        .flat_map(|c| c.coverage.iter().map(move |e| (c.seed, e)))
        .filter(|(_, e)| e.effect == "power_law_drag")
        .collect();
    let lines: Vec<String> = cov
        .iter()
        .map(|(s, e)| format!("seed {s}: {:?} (truth {})", e.reported, e.truth))
        .collect();
    let named = doc.cases.iter().filter(|c| c.named_right).count();
    assert!(named >= 3, "named right in {named} of 4: {lines:#?}");
    assert!(
        cov.iter().all(|(_, e)| e.within_2sigma.is_some()),
        "{lines:#?}"
    );
    let n = cov.len();
    let k = cov
        .iter()
        .filter(|(_, e)| e.within_2sigma == Some(true))
        .count();
    let bound = max_consistent_failures(n, 0.10, 0.01);
    assert!(
        n - k <= bound,
        "{k} of {n} within ±2σ (bound {bound}): {lines:#?}"
    );
    eprintln!("{}", lines.join("\n"));
}

/// The refit's σ of a shape parameter means what it says. The drag exponent's Gauss–Newton σ
/// ((JᵀJ)⁻¹ of the refit's Jacobian, white-noise scale s²) is compared with the curvature of its
/// profile: the exponent held at p̂ + kσ, k = −2 … 2, every other parameter refitted to
/// convergence on the refit's windows, and a parabola fitted to the five χ²/s²; the σ it implies
/// must agree with the Gauss–Newton σ within a factor 1.5 either way (the profile is not exactly
/// quadratic along the ζ–q–p valley, and each held refit stops within a few tenths of a χ² unit of
/// its minimum; each starts from the linearisation's prediction of the other parameters). Set: the campaign's `power_law_drag` at level 2 (−0.4 |β̇|^1.5 sgn β̇), `ci`
/// size, seed 1; the refit starts at the quadratic member p = 2. Before the refit's Jacobian was
/// the variable-projection one (`shooting::varpro_jacobian`) it differenced the projected
/// residuals, each trial re-projecting the window states from the last trial's: the exponent's σ
/// came out 0.005 on this set, while its profile gives about 0.11.
#[test]
fn a_shape_sigma_matches_the_curvature_of_its_profile() {
    use gearbif::identification::diagnose::DiagnoseOptions;
    use gearbif::identification::lm::gauss_newton_cov;
    use gearbif::identification::model::Shape;
    use gearbif::identification::regression::{Term, BASE_TERMS};
    use gearbif::identification::select::refit_to_convergence;
    use gearbif::identification::shooting::{Reselect, ShootingOptions, SimModel, Win};
    let c = build_case(
        effect("power_law_drag").unwrap(),
        2.0,
        1,
        &SetSize::ci(),
        &Rk4Filippov::default(),
    )
    .unwrap();
    let opts = DiagnoseOptions::default();
    let (prep, base, _) = prepared_base(&c.set, &opts);
    let mut terms = BASE_TERMS.to_vec();
    terms.extend([Term::Quad, Term::Shape(Shape::DragExponent)]);
    let model = SimModel::of_terms(&prep.runs, base.geo, terms, opts.tol);
    let mut theta0 = base.state.as_ref().unwrap().fit.theta[..4].to_vec();
    theta0.extend([3.2, 2.0]);
    let sopts = ShootingOptions {
        patience: 4,
        reselect: Reselect::Always,
        ..ShootingOptions::default()
    };
    let f = refit_to_convergence(&model, &theta0, &base.wins, &sopts).unwrap();
    let wins: Vec<Win> = f.used.iter().map(|&(w, _)| base.wins[w].clone()).collect();
    let s2 = f.resid.iter().map(|r| r * r).sum::<f64>()
        / (f.samples - 2 * f.used.len() - f.theta.len()) as f64;
    let k = 5;
    let cov = gauss_newton_cov(&f.jac);
    let sigma = cov[(k, k)].sqrt();
    assert!(sigma.is_finite() && sigma > 0.0);
    let profile: Vec<(f64, f64)> = (-2..=2)
        .map(|i| {
            let v = f.theta[k] + i as f64 * sigma;
            let mut terms = model.terms.clone();
            terms.remove(k);
            let held = SimModel {
                terms,
                held_shapes: vec![(Shape::DragExponent, v)],
                ..model.clone()
            };
            // each held refit starts where the linearisation puts the profile's other parameters
            // (θ̂_j + C_jk/C_kk (p − p̂)): near its own minimum along the ζ–q–p valley
            let mut th: Vec<f64> = (0..f.theta.len())
                .map(|j| f.theta[j] + cov[(j, k)] / cov[(k, k)] * (v - f.theta[k]))
                .collect();
            th.remove(k);
            let g = refit_to_convergence(&held, &th, &wins, &sopts).unwrap();
            let c: f64 = g
                .window_chi2(&held, &wins)
                .0
                .iter()
                .map(|c| c.unwrap())
                .sum();
            ((v - f.theta[k]) / sigma, c / s2)
        })
        .collect();
    // least-squares parabola a u² + b u + c in u = (p − p̂)/σ: the profile's σ is σ/√a
    let x = nalgebra::DMatrix::from_fn(5, 3, |i, j| profile[i].0.powi(2 - j as i32));
    let y = nalgebra::DVector::from_iterator(5, profile.iter().map(|p| p.1));
    let abc = x.svd(true, true).solve(&y, 1e-12).unwrap();
    let ratio = 1.0 / abc[0].max(1e-12).sqrt();
    let msg = format!(
        "p = {:.4}, Gauss–Newton σ {sigma:.4}, s² {s2:.3}; profile (u, χ²/s²) {profile:?}; \
         curvature {:.3} per σ²: profile σ / Gauss–Newton σ = {ratio:.3}",
        f.theta[k], abc[0]
    );
    assert!((1.0 / 1.5..=1.5).contains(&ratio), "{msg}");
    eprintln!("{msg}");
}

/// A round's screening stops only candidates the judge rejects (docs/diagnosis.md, "Screening"):
/// a candidate whose refit fits the screening's windows significantly worse than the current
/// model has a held-out screening z below `SCREEN_Z` when predicted anyway, and a candidate the screening's
/// leader predicts significantly better there is, refitted on all judging windows, predicted
/// significantly worse than the leader there too and gains less (so it could be neither the
/// accepted candidate nor its close rival). Round 1 of two sets whose base model leaves much
/// unexplained (6 candidates stopped by the first rule, 7 by the second).
#[test]
fn the_screening_stops_only_candidates_the_judge_rejects() {
    use gearbif::identification::judge::compare;
    use gearbif::identification::select::{evaluate, judge_round, screen, SCREEN_Z};
    use gearbif::progress::Silent;
    let (mut gated, mut beaten) = (0, 0);
    for (id, level, seed) in [
        ("torque_and_latency", 2.0, 1u64),
        ("static_torque_2h", 2.0, 1),
    ] {
        on_base_model(id, level, seed, |ctx, b| {
            let round = judge_round(&ctx, b, 1, "", &Silent).expect("candidates");
            for t in &round {
                let name = format!("{id}: {} {:?}", t.candidate.effect.id, t.candidate.terms);
                if t.screen_fit.is_some() {
                    gated += 1;
                    let held_out = screen(&ctx, b, &t.candidate);
                    assert!(
                        held_out.is_none_or(|c| c.z < SCREEN_Z),
                        "{name}: {held_out:?}"
                    );
                }
                if let Some(bt) = &t.screen_beaten {
                    beaten += 1;
                    let lead = round[bt.leader].state.as_ref().expect("the leader's refit");
                    let Some(st) = evaluate(&ctx, b, &t.candidate) else {
                        continue;
                    };
                    let vs = compare(&st.held, &lead.held, ctx.wins, ctx.runs);
                    assert!(vs.improves(t.z_crit), "{name}: {vs:?}");
                    let own = compare(&b.held, &st.held, ctx.wins, ctx.runs);
                    assert!(own.gain < round[bt.leader].gain(), "{name}: {own:?}");
                }
            }
        });
    }
    assert_eq!((gated, beaten), (6, 7));
}

/// Forms the catalog does not contain (docs/diagnosis.md, "The verdict"): an off-centre output
/// magnet (the coupling modulated once per output turn), a bearing defect (a friction bump at one
/// output angle), a friction growing with the transmitted torque, a Stribeck peak far narrower than
/// the family's widths and a distortion of the angle reading, at 1 and 2 times their reference
/// size on the CI campaign's tiny sets (a lab of its own for each form and size). Wherever the report's own remainder test finds a
/// significant mismatch left, the verdict is `partly_explained` or `unexplained`, never a catalog
/// name; and the verdict is honest (no catalog effect the truth does not contain, no error) in
/// ≥ 90 % of the cases: more than `max_consistent_failures(n, 0.10, 0.01)` confident wrong names
/// refute it at the 1 % level. Every finding that is not the verdict's carries the reason.
///
/// The curve of what remains (docs/verdict.md): where the truth has a curve of the fitted kind (the
/// bearing defect's friction η(β)), the ±2σ bands hold the true curves on ≥ 90 % of their grid
/// points, pooled over those cases, and the cases whose band misses on more than 10 % of its grid
/// are no more than a rate of 90 % allows at the 1 % level; on the CI campaign's 20 controls no
/// curve stands.
#[test]
fn out_of_catalog_forms_get_honest_verdicts() {
    let forms = [
        "offcentre_coupling",
        "bearing_bump",
        "torque_friction",
        "narrow_stribeck",
        "angle_reading",
    ];
    let mut cases = Vec::new();
    for level in [1.0, 2.0] {
        cases.extend(tiny_campaign(&format!("ooc{level}"), &forms, level, 1, 0).cases);
    }
    assert_eq!(cases.len(), forms.len() * 2);
    // the controls: the CI campaign's 20 (the same tiny sets, a control is drawn at level 1)
    let controls: Vec<_> = ci_campaign()
        .cases
        .iter()
        .filter(|c| c.effect == "none")
        .collect();
    assert_eq!(controls.len(), 20);
    for c in &controls {
        assert!(
            c.curve.as_ref().is_none_or(|k| !k.stands),
            "a control with a curve that stands: {c:?}"
        );
    }
    let covered: Vec<(f64, String)> = cases
        .iter()
        .filter_map(|c| {
            Some((
                c.curve.as_ref()?.coverage?,
                format!("{} ×{}", c.effect, c.level),
            ))
        })
        .collect();
    assert!(!covered.is_empty(), "no curve with a truth of its kind");
    let pooled = covered.iter().map(|c| c.0).sum::<f64>() / covered.len() as f64;
    assert!(
        pooled >= 0.9,
        "the bands hold the true curves on {pooled:.3} of their grids: {covered:?}"
    );
    // the campaign's rate: a case's band covers when it holds the truth on ≥ 90 % of its grid;
    // more misses than a rate of 90 % allows at the 1 % level refute it
    let missed = covered.iter().filter(|c| c.0 < CURVE_COVERAGE).count();
    let bound = max_consistent_failures(covered.len(), 0.10, 0.01);
    assert!(
        missed <= bound,
        "{missed} bands of {} miss the truth on more than 10 % of their grid (bound {bound}): \
         {covered:?}",
        covered.len()
    );
    let mut lines = Vec::new();
    for c in &cases {
        lines.push(format!(
            "{} ×{} seed {}: {} (remainder z {:?}, findings {:?})",
            c.effect,
            c.level,
            c.seed,
            c.verdict,
            c.remaining_z,
            c.findings.iter().map(|f| &f.effect).collect::<Vec<_>>()
        ));
        assert!(c.error.is_none(), "{}", lines.last().unwrap());
        if c.remaining_above_noise == Some(true) {
            assert!(
                ["partly_explained", "unexplained"].contains(&c.verdict.as_str()),
                "a catalog verdict with a significant remainder: {}",
                lines.last().unwrap()
            );
        }
    }
    let wrong: Vec<&String> = cases
        .iter()
        .zip(&lines)
        .filter(|(c, _)| c.confident_wrong)
        .map(|(_, l)| l)
        .collect();
    let bound = max_consistent_failures(cases.len(), 0.10, 0.01);
    assert!(
        wrong.len() <= bound,
        "{} confident wrong names of {} (bound {bound}): {wrong:#?}\nall: {lines:#?}",
        wrong.len(),
        cases.len()
    );
    eprintln!("{lines:#?}");
}
