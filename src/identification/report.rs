//! The diagnosis report, schema `gearbif.diagnosis/1` (docs/formats.md), and its
//! Markdown rendering.

use super::verdict::{Assessment, Standing, Status};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The schema identifier.
pub const SCHEMA: &str = "gearbif.diagnosis/1";

/// report.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Always [`SCHEMA`].
    pub schema: String,
    /// The base model with refitted parameters.
    pub baseline: Baseline,
    /// Where the base model fails, in words with evidence.
    pub mismatch: Vec<Mismatch>,
    /// Findings, most supported first.
    pub findings: Vec<Finding>,
    /// The first standing finding's `effect` when nothing significant is left; `partly_explained`
    /// when findings stand but a significant remainder is left; `unexplained` when no standing
    /// finding explains a significant mismatch; `none` when there is nothing to explain
    /// ([`super::verdict`]).
    pub verdict: String,
    /// Optional (added key): the fits behind the report.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fits: Option<serde_json::Value>,
    /// Optional (added key): what the final model leaves of the held-out mismatch, and where.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub remaining: Option<Remainder>,
    /// Optional (added key): why the verdict is what it is: the standing findings, what is left
    /// ([`super::verdict::decide`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub assessment: Option<Assessment>,
    /// Optional (added key): the nonparametric curve of what remains, with its band and its
    /// held-out comparison against the final model ([`super::curve`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curve: Option<super::curve::Curve>,
}

/// What the final model leaves of the held-out mismatch (report key `remaining`): the held-out
/// χ² per degree of freedom above the camera-noise floor, the fraction of the base model's excess
/// the findings removed, and where the remainder sits.
///
/// For a set W of judging windows with held-out χ²_w (camera-noise units) and d_w = frames − 2
/// (the fitted initial state), the excess is E = Σχ²_w / Σd_w − 1 (0 for a model that predicts to
/// the camera noise) with the ratio estimator's σ_E² = n/(n−1) Σ_w (χ²_w − (1 + E) d_w)² / (Σd_w)²
/// over the n windows (each window a unit, so the residual autocorrelation within a window is
/// carried). The fraction removed is 1 − R, R = Σ(χ²_fin − d)/Σ(χ²_base − d) on the windows both
/// models predicted, with the same ratio σ.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Remainder {
    /// Held-out χ²/dof − 1 of the final model on the judging windows it predicted.
    pub excess_chi2_per_dof: f64,
    /// 1σ of it.
    pub excess_sigma: f64,
    /// The same for the base model (the same windows).
    pub base_excess_chi2_per_dof: f64,
    /// 1σ of it.
    pub base_excess_sigma: f64,
    /// Fraction of the base model's excess the findings removed (`None` when the base model's
    /// excess is itself within noise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fraction_removed: Option<f64>,
    /// 1σ of it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fraction_removed_sigma: Option<f64>,
    /// Whether the remainder is within noise: E < [`super::mismatch::REMAINDER_Z`] σ_E.
    pub within_noise: bool,
    /// Windows used.
    pub windows: usize,
    /// Every bin of every grouping, with its excess.
    pub bins: Vec<RemainderBin>,
    /// The bins whose excess is above noise (E_bin ≥ [`super::mismatch::REMAINDER_Z`] σ_bin), largest share of the
    /// remaining excess χ² first: where the remainder sits.
    pub located: Vec<RemainderBin>,
    /// The camera-noise floor: the noise measured at rest (absent in reports of earlier versions,
    /// whose floor was white noise at the cleaning's σ).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<NoiseFloor>,
    /// What the remainder depends on: one test per grouping of the windows, largest z first
    /// ([`super::mismatch::dependence`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dependence: Vec<Dependence>,
}

/// Whether the remainder depends on one variable: the heterogeneity of its bins' excesses,
/// Q = Σ_b (E_b − Ē)²/σ_b² with Ē the inverse-variance mean, against χ² with bins − 1 degrees of
/// freedom (z by the Wilson–Hilferty transform).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Dependence {
    /// The grouping (as [`RemainderBin::group`]).
    pub variable: String,
    /// Bins with a σ (the test's units).
    pub bins: usize,
    /// Q.
    pub chi2: f64,
    /// bins − 1.
    pub dof: usize,
    /// Normal deviate of Q.
    pub z: f64,
    /// Whether z reaches the threshold for this many variables tested
    /// ([`super::judge::z_threshold`]).
    pub significant: bool,
    /// The bin with the largest excess.
    pub peak_bin: String,
    /// Its excess χ²/dof.
    pub peak_excess_chi2_per_dof: f64,
    /// Its 1σ.
    pub peak_excess_sigma: f64,
    /// The experiment that tells the candidates of such a dependence apart.
    pub experiment: String,
}

/// The camera noise behind the remainder's floor (`identification::mismatch::noise_floor`): its
/// autocovariance measured on frames at rest, or white noise at the cleaning's σ when the set has
/// too few frames at rest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct NoiseFloor {
    /// `rest` (measured at rest) or `white` (the cleaning's σ, no correlation).
    pub method: String,
    /// Stationary σ of the noise measured at rest, rad (for `white`: the cleaning's σ).
    pub sigma_rad: f64,
    /// Its jackknife 1σ over the stretches at rest.
    pub sigma_rad_err: f64,
    /// The cleaning's σ (median over the runs), rad: the scale of the window χ².
    pub sigma_cleaning_rad: f64,
    /// Correlation ρ(k) at the frame lags k = 1, 2, … (up to the window length − 1).
    pub correlation: Vec<f64>,
    /// Their jackknife 1σ.
    pub correlation_sigma: Vec<f64>,
    /// Largest lag measured (the correlation beyond it is taken as 0).
    pub max_lag: usize,
    /// Frames at rest used.
    pub rest_frames: usize,
    /// Stretches at rest used (the jackknife's units).
    pub rest_pieces: usize,
    /// The floor summed over the windows, over Σ(frames − 2): 1 for white noise at the
    /// cleaning's σ.
    pub floor_over_frames_minus_2: f64,
    /// Its jackknife 1σ.
    pub floor_over_frames_minus_2_sigma: f64,
    /// How the floor was obtained.
    pub note: String,
    /// The white noise that grows with the speed, measured in motion (absent in reports of
    /// earlier versions and when it cannot be measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed_noise: Option<SpeedNoiseFloor>,
}

/// A white noise of variance σ_t² β̇² measured in motion (`identification::preprocess::speed_noise`):
/// a timing jitter of σ_t, or any error growing as |β̇|; invisible at rest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct SpeedNoiseFloor {
    /// σ_t², s² (an estimate: may be negative).
    pub timing_var_s2: f64,
    /// Its jackknife 1σ over the judging windows.
    pub timing_var_sigma_s2: f64,
    /// σ_t = √max(σ_t², 0), s.
    pub timing_jitter_s: f64,
    /// Its 1σ (σ(σ_t²)/2σ_t; √σ(σ_t²) at 0).
    pub timing_jitter_s_err: f64,
    /// z = σ_t²/σ(σ_t²).
    pub z: f64,
    /// Whether it was added to the floor (z ≥ the remainder's threshold).
    pub added: bool,
    /// The part added to the floor, over the floor at rest (both summed over the windows).
    pub floor_added: f64,
    /// The speed-free white σ of the same fit, rad.
    pub white_sigma_rad: f64,
    /// Samples used.
    pub samples: usize,
    /// Windows used (the jackknife's units).
    pub windows: usize,
}

/// One bin of the remainder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RemainderBin {
    /// Grouping: `run_kind`, `drive_hz`, `beta_phase_deg`, `speed_rad_s`, `stick_slip`.
    pub group: String,
    /// The bin (e.g. `driven`, `1.50`, `[60, 120)`, `[0.8, 2.1)`, `stick`).
    pub bin: String,
    /// Windows in the bin.
    pub windows: usize,
    /// Held-out χ²/dof − 1 of the final model in the bin.
    pub excess_chi2_per_dof: f64,
    /// 1σ of it.
    pub excess_sigma: f64,
    /// Share of the whole remaining excess χ² (Σ(χ² − d)) that falls in this bin.
    pub share: f64,
}

/// The refitted base model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Baseline {
    /// g, delta, zeta, eta (and their `_err`, and inertia when known).
    pub params: BTreeMap<String, f64>,
    /// rms of the short-horizon prediction over all runs, rad.
    pub rms_rad: f64,
    /// Per run.
    pub runs: Vec<RunRms>,
}

/// rms of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRms {
    /// CSV file.
    pub file: String,
    /// rms, rad (base model fitted on all runs).
    pub rms_rad: f64,
    /// Optional: rms when the run was left out of the fit, rad.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heldout_rms_rad: Option<f64>,
    /// Optional: equation-error χ²/row of the base model in this run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chi2_per_row: Option<f64>,
}

/// One located mismatch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Mismatch {
    /// Where the model fails, in words.
    #[serde(rename = "where")]
    pub where_: String,
    /// Numbers behind it.
    pub evidence: BTreeMap<String, serde_json::Value>,
}

/// A named piece of missing physics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Finding {
    /// Effect identifier (recordings.md table).
    pub effect: String,
    /// Class of indistinguishable effects.
    pub class: String,
    /// In words.
    pub explanation: String,
    /// Fitted physical parameters (with `_err` = 1σ).
    pub params: BTreeMap<String, f64>,
    /// Physical causes that leave the same fingerprint.
    pub candidates: Vec<String>,
    /// How to tell the candidates apart.
    pub discriminating_experiment: String,
    /// Short-horizon prediction rms before adding it, rad (null if it cannot be simulated).
    pub rms_before_rad: Option<f64>,
    /// After, rad.
    pub rms_after_rad: Option<f64>,
    /// On held-out runs (leave-one-run-out), before, rad.
    pub heldout_rms_before_rad: Option<f64>,
    /// On held-out runs, after, rad.
    pub heldout_rms_after_rad: Option<f64>,
    /// ΔBIC (effective n), cross-validation scores, equation-error rms.
    pub evidence: BTreeMap<String, serde_json::Value>,
    /// Optional (added key): the effect's headline size with its 1σ, the one number a campaign
    /// compares with the truth (e.g. the static torque's first-harmonic amplitude).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<EffectSize>,
    /// Optional (added key): whether the finding stands, and the fraction of the base model's
    /// held-out excess it removed ([`super::verdict::standing`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub standing: Option<Standing>,
}

/// The headline size of a finding: one physical number with its standard error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectSize {
    /// What is measured (e.g. `amplitude`, `latency_s`, `delta`).
    pub name: String,
    /// Value, in `unit`.
    pub value: f64,
    /// 1σ, in `unit`.
    pub sigma: f64,
    /// Unit (e.g. `s^-2`, `s`, `deg`, `1`).
    pub unit: String,
}

fn f(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:.4}"),
        _ => "–".into(),
    }
}

/// Renders report.md.
pub fn markdown(r: &Report, title: &str) -> String {
    let mut s = format!(
        "# Diagnosis of `{title}`\n\n**Verdict: `{}`**\n\n",
        r.verdict
    );
    if let Some(a) = &r.assessment {
        s.push_str(&format!("{}\n\n", a.statement));
    }
    s.push_str("## Base model, refitted\n\n| parameter | value |\n|---|---|\n");
    for (k, v) in &r.baseline.params {
        s.push_str(&format!("| {k} | {v:.6} |\n"));
    }
    s.push_str(&format!(
        "\nShort-horizon prediction rms over all runs: {:.4} rad ({:.2}°)\n\n",
        r.baseline.rms_rad,
        r.baseline.rms_rad.to_degrees()
    ));
    s.push_str("| run | rms (rad) | held-out rms (rad) | eq.-error χ²/row |\n|---|---|---|---|\n");
    for run in &r.baseline.runs {
        s.push_str(&format!(
            "| {} | {:.4} | {} | {} |\n",
            run.file,
            run.rms_rad,
            f(run.heldout_rms_rad),
            f(run.chi2_per_row)
        ));
    }
    s.push_str("\n## Where the base model fails\n\n");
    if r.mismatch.is_empty() {
        s.push_str("Nowhere significant: the residuals are at the noise level.\n");
    }
    for m in &r.mismatch {
        s.push_str(&format!(
            "- {} (evidence: `{}`)\n",
            m.where_,
            serde_json::to_string(&m.evidence).unwrap_or_default()
        ));
    }
    s.push_str("\n## Findings\n\n");
    if r.findings.is_empty() {
        s.push_str("None: no catalogued or dictionary term improves held-out runs and the BIC.\n");
    }
    for (i, fi) in r.findings.iter().enumerate() {
        s.push_str(&format!(
            "### {}. `{}` (class: {})\n\n{}\n\n",
            i + 1,
            fi.effect,
            fi.class,
            fi.explanation
        ));
        if let Some(st) = &fi.standing {
            s.push_str(&standing_markdown(st));
        }
        s.push_str("| parameter | value |\n|---|---|\n");
        for (k, v) in &fi.params {
            s.push_str(&format!("| {k} | {v:.6} |\n"));
        }
        s.push_str(&format!(
            "\nrms before → after: {} → {} rad; held-out runs: {} → {} rad\n\n",
            f(fi.rms_before_rad),
            f(fi.rms_after_rad),
            f(fi.heldout_rms_before_rad),
            f(fi.heldout_rms_after_rad)
        ));
        if !fi.candidates.is_empty() {
            s.push_str(&format!(
                "Candidates (same fingerprint): {}.\n\nTo separate them: {}\n\n",
                fi.candidates.join("; "),
                fi.discriminating_experiment
            ));
        }
        s.push_str(&format!(
            "Evidence: `{}`\n\n",
            serde_json::to_string(&fi.evidence).unwrap_or_default()
        ));
    }
    s.push_str(&forks_markdown(&r.selection_forks(), &r.selection_joints()));
    if let Some(rem) = &r.remaining {
        s.push_str(&remainder_markdown(rem));
    }
    if let Some(c) = &r.curve {
        s.push_str(&curve_markdown(c));
    }
    s
}

/// The paragraph of report.md on the curve of what remains ([`super::curve`]).
fn curve_markdown(c: &super::curve::Curve) -> String {
    let what = match c.kind.as_str() {
        "friction" => {
            "the dry friction η(β) as a function of the output angle (in place of the constant η)"
        }
        _ => "a lab-fixed torque τ(β) of the output angle",
    };
    let (imax, vmax) =
        c.value.iter().enumerate().fold(
            (0, f64::NEG_INFINITY),
            |m, (i, &v)| if v > m.1 { (i, v) } else { m },
        );
    let (imin, vmin) =
        c.value.iter().enumerate().fold(
            (0, f64::INFINITY),
            |m, (i, &v)| if v < m.1 { (i, v) } else { m },
        );
    let tried: Vec<String> = c
        .tried
        .iter()
        .map(|t| {
            format!(
                "{} λ/I = {:.0e}: gain {:.1}, z = {:.2}",
                t.kind, t.lambda_relative, t.heldout_gain, t.z
            )
        })
        .collect();
    format!(
        "## The curve of what remains\n\nThe base model with {what}, a periodic cubic B-spline of \
         {} knots with the roughness weight λ = {:.3e} chosen by the held-out judge ({}), \
         {} the held-out runs significantly better than the final model ({}): held-out χ² gain {:.1} ± {:.1}, \
         z = {:.2} against the threshold {:.2} over {} windows. The curve is largest at β = {:.0}° \
         ({:.3} ± {:.3} s⁻²) and smallest at β = {:.0}° ({:.3} ± {:.3} s⁻²), at the band's \
         λ = {:.3e} chosen by generalised cross-validation on the refit linearised at its \
         solution ({}); the band of remainder_curve.svg is ± {} σ, σ(β) from the Bayesian \
         covariance floored by the window-clustered sandwich.\n\n",
        c.knots,
        c.lambda,
        tried.join("; "),
        if c.stands { "predicts" } else { "does not predict" },
        if c.against.is_empty() { "the base model".to_string() } else { format!("with {}", c.against.join(", ")) },
        c.heldout_gain,
        c.heldout_gain_sigma,
        c.z,
        c.z_crit,
        c.windows,
        c.grid_deg[imax],
        vmax,
        c.sigma[imax],
        c.grid_deg[imin],
        vmin,
        c.sigma[imin],
        c.band_lambda,
        c.band_edf.map_or("the refit's own covariance".to_string(), |e| format!(
            "{e:.1} effective parameters"
        )),
        c.band_sigmas,
    )
}

impl Report {
    /// The selection's forks (`fits.selection_forks`, [`super::beam::Fork`]); empty without.
    pub fn selection_forks(&self) -> Vec<super::beam::Fork> {
        self.fits
            .as_ref()
            .and_then(|f| serde_json::from_value(f["selection_forks"].clone()).ok())
            .unwrap_or_default()
    }
}

impl Report {
    /// The close rivals accepted together (`fits.selection_joints`, [`super::beam::Joint`]);
    /// empty without.
    pub fn selection_joints(&self) -> Vec<super::beam::Joint> {
        self.fits
            .as_ref()
            .and_then(|f| serde_json::from_value(f["selection_joints"].clone()).ok())
            .unwrap_or_default()
    }
}

/// The selection's forks and joints ([`Report::selection_forks`], [`Report::selection_joints`])
/// as a section of report.md; empty without either.
fn forks_markdown(forks: &[super::beam::Fork], joints: &[super::beam::Joint]) -> String {
    if forks.is_empty() && joints.is_empty() {
        return String::new();
    }
    let mut s = String::from("## Close rivals\n\n");
    let terms = |t: &[String]| {
        if t.is_empty() {
            String::new()
        } else {
            format!(" ({})", t.join(", "))
        }
    };
    for j in joints {
        s.push_str(&format!(
            "- Round {}: `{}`{} and `{}`{} could not be told apart by their held-out \
             predictions (z = {:.2}), but each predicts significantly better on top of the other \
             (`{}` on `{}`: z = {:.2}, χ² gain {:.1}; `{}` on `{}`: z = {:.2}, χ² gain {:.1}; \
             threshold {:.2}): both were accepted in the round, `{}` on top of `{}` (that model \
             predicts the held-out windows better than the other order's: χ² gain {:.1}, z = \
             {:.2}).\n",
            j.round,
            j.first,
            terms(&j.first_terms),
            j.second,
            terms(&j.second_terms),
            j.round_z,
            j.second,
            j.first,
            j.second_on_first.0,
            j.second_on_first.1,
            j.first,
            j.second,
            j.first_on_second.0,
            j.first_on_second.1,
            j.z_crit,
            j.second,
            j.first,
            j.order.0,
            j.order.1
        ));
    }
    for f in forks {
        let when = match f.pruned_after {
            Some(r) => format!(
                "after round {r}, when the other branch's model predicted the held-out windows \
                 significantly worse"
            ),
            None => "at the end, by the final models".to_string(),
        };
        s.push_str(&format!(
            "- Round {}: `{}` and `{}` could not be told apart by their held-out predictions \
             (z = {:.2}), so the selection went on with each. The {}, {when}: held-out χ² gain \
             {:.1}, z = {:.2}.\n",
            f.round,
            f.kept,
            f.other,
            f.round_z,
            f.outcome(),
            f.final_gain,
            f.final_z
        ));
    }
    s.push('\n');
    s
}

/// A finding's standing as one line of report.md.
fn standing_markdown(st: &Standing) -> String {
    let status = match st.status {
        Status::Stands => "Stands",
        Status::ConsistentWithZero => "Does not stand (consistent with zero)",
        Status::Unphysical => "Does not stand (unphysical)",
        Status::Unsized => "Does not stand (no size to test)",
    };
    let removed = match (st.fraction_removed, st.fraction_removed_sigma) {
        (Some(v), Some(e)) => format!(
            "; it removed {:.0} ± {:.0} % of the base model's held-out excess",
            100.0 * v,
            100.0 * e
        ),
        _ => String::new(),
    };
    format!("**{status}**: {}{removed}.\n\n", st.reason)
}

/// The remainder's dependence tests as a table of report.md (largest z first).
fn dependence_markdown(deps: &[Dependence]) -> String {
    if deps.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "What the remainder depends on (heterogeneity of its bins; significant at the \
         threshold for this many variables):\n\n| variable | z | significant | largest in | \
         χ²/dof − 1 there | experiment |\n|---|---|---|---|---|---|\n",
    );
    for d in deps {
        s.push_str(&format!(
            "| {} | {:.1} | {} | {} | {:.3} ± {:.3} | {} |\n",
            d.variable,
            d.z,
            if d.significant { "yes" } else { "no" },
            d.peak_bin,
            d.peak_excess_chi2_per_dof,
            d.peak_excess_sigma,
            if d.significant {
                d.experiment.as_str()
            } else {
                ""
            }
        ));
    }
    s.push('\n');
    s
}

/// The camera-noise floor's paragraph of report.md, with the speed-dependent noise's line.
fn noise_markdown(n: &NoiseFloor) -> String {
    let mut s = rest_noise_markdown(n);
    if let Some(sp) = &n.speed_noise {
        s.push_str(&format!(
            "Noise growing with the speed (white, variance σ_t² β̇²: a timing jitter of σ_t, or \
             any error ∝ |β̇|), measured in motion on {} windows: σ_t = {:.3} ± {:.3} ms \
             (σ_t² at z = {:.1}); {}.\n\n",
            sp.windows,
            1e3 * sp.timing_jitter_s,
            1e3 * sp.timing_jitter_s_err,
            sp.z,
            if sp.added {
                format!(
                    "added to the floor (+{:.1} % of the floor at rest)",
                    100.0 * sp.floor_added
                )
            } else {
                "not significant, not added to the floor".to_string()
            }
        ));
    }
    s
}

/// The rest part of [`noise_markdown`].
fn rest_noise_markdown(n: &NoiseFloor) -> String {
    if n.method != "rest" {
        return format!(
            "Camera-noise floor: white noise at the cleaning's σ = {:.3}° ({}).\n\n",
            n.sigma_cleaning_rad.to_degrees(),
            n.note
        );
    }
    let rho: Vec<String> = [1usize, 2, 3, 5, 10]
        .iter()
        .filter(|&&k| k <= n.correlation.len())
        .map(|&k| {
            format!(
                "ρ({k}) = {:.2} ± {:.2}",
                n.correlation[k - 1],
                n.correlation_sigma[k - 1]
            )
        })
        .collect();
    format!(
        "Camera-noise floor: the noise measured at rest has σ = {:.3} ± {:.3}° (the cleaning's \
         estimate: {:.3}°) and {}; the windows' floor is {:.2} ± {:.2} × (frames − 2) ({}).\n\n",
        n.sigma_rad.to_degrees(),
        n.sigma_rad_err.to_degrees(),
        n.sigma_cleaning_rad.to_degrees(),
        rho.join(", "),
        n.floor_over_frames_minus_2,
        n.floor_over_frames_minus_2_sigma,
        n.note
    )
}

/// The "what remains and where" section of report.md.
fn remainder_markdown(rem: &Remainder) -> String {
    let mut s = String::from("## What remains and where\n\n");
    let removed = match (rem.fraction_removed, rem.fraction_removed_sigma) {
        (Some(f), Some(e)) => format!(
            "; the findings removed {:.0} ± {:.0} % of the base model's excess",
            100.0 * f,
            100.0 * e
        ),
        _ => String::new(),
    };
    let numbers = format!(
        "held-out χ²/dof − 1 = {:.3} ± {:.3} on {} judging windows (base model: {:.3} ± {:.3}{removed})",
        rem.excess_chi2_per_dof,
        rem.excess_sigma,
        rem.windows,
        rem.base_excess_chi2_per_dof,
        rem.base_excess_sigma
    );
    let noise = rem.noise.as_ref().map(noise_markdown).unwrap_or_default();
    if rem.within_noise {
        s.push_str(&format!("Nothing left above noise: {numbers}.\n\n{noise}"));
        return s;
    }
    s.push_str(&noise);
    s.push_str(&format!(
        "The final model leaves a mismatch above the camera-noise floor: {numbers}.\n\n"
    ));
    s.push_str(&dependence_markdown(&rem.dependence));
    if rem.located.is_empty() {
        s.push_str("No single bin (run kind, drive frequency, β phase, α − β, speed, torque, stick/slip, run order) stands out: the remainder is spread.\n\n");
        return s;
    }
    s.push_str("| where | bin | windows | χ²/dof − 1 | share of the remaining excess |\n|---|---|---|---|---|\n");
    for b in &rem.located {
        s.push_str(&format!(
            "| {} | {} | {} | {:.3} ± {:.3} | {:.0} % |\n",
            b.group,
            b.bin,
            b.windows,
            b.excess_chi2_per_dof,
            b.excess_sigma,
            100.0 * b.share
        ));
    }
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(fits: Option<serde_json::Value>) -> Report {
        Report {
            schema: SCHEMA.into(),
            baseline: Baseline {
                params: BTreeMap::new(),
                rms_rad: 0.01,
                runs: Vec::new(),
            },
            mismatch: Vec::new(),
            findings: Vec::new(),
            verdict: "none".into(),
            fits,
            remaining: None,
            assessment: None,
            curve: None,
        }
    }

    #[test]
    fn the_forks_section_reads_the_forks_of_the_fits() {
        let fork = super::super::beam::Fork {
            round: 1,
            kept: "sensor_latency".into(),
            other: "corotating_drag".into(),
            round_z: 1.31,
            kept_effects: vec!["sensor_latency".into(), "static_torque".into()],
            other_effects: vec!["corotating_drag".into(), "static_torque".into()],
            final_gain: 30227.5,
            final_z: 3.16,
            pruned_after: None,
        };
        let md = markdown(
            &report(Some(serde_json::json!({ "selection_forks": [fork] }))),
            "t",
        );
        assert!(md.contains("## Close rivals"), "{md}");
        assert!(
            md.contains(
                "The branch of `sensor_latency` (sensor_latency + static_torque) was kept over \
                 that of `corotating_drag` (corotating_drag + static_torque), at the end"
            ),
            "{md}"
        );
        assert!(md.contains("z = 1.31"), "{md}");
        for fits in [
            None,
            Some(serde_json::json!({ "selection_forks": [], "selection_joints": [] })),
        ] {
            assert!(!markdown(&report(fits), "t").contains("Close rivals"));
        }
    }

    #[test]
    fn the_close_rivals_section_lists_rivals_accepted_together() {
        let joint = super::super::beam::Joint {
            round: 1,
            first: "static_torque".into(),
            second: "sensor_latency".into(),
            first_terms: vec!["sin(beta)".into(), "cos(beta)".into()],
            second_terms: Vec::new(),
            round_z: 1.08,
            z_crit: 3.28,
            second_on_first: (16.45, 29475.0),
            first_on_second: (25.02, 32789.5),
            order: (12.5, 0.4),
        };
        let r = report(Some(
            serde_json::json!({ "selection_joints": [joint.clone()] }),
        ));
        assert_eq!(r.selection_joints(), vec![joint]);
        assert!(r.selection_forks().is_empty());
        let md = markdown(&r, "t");
        assert!(md.contains("## Close rivals"), "{md}");
        assert!(
            md.contains("`static_torque` (sin(beta), cos(beta)) and `sensor_latency` could"),
            "{md}"
        );
        assert!(
            md.contains(
                "`sensor_latency` on `static_torque`: z = 16.45, χ² gain 29475.0; \
                 `static_torque` on `sensor_latency`: z = 25.02, χ² gain 32789.5; threshold \
                 3.28): both were accepted in the round, `sensor_latency` on top of \
                 `static_torque` (that model predicts the held-out windows better than the other \
                 order's: χ² gain 12.5, z = 0.40)."
            ),
            "{md}"
        );
    }
}
