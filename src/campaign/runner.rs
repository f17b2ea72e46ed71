//! The campaign runner: every case (effect × level × seed) is generated, written in the documented
//! recording format, read back, diagnosed with the default options (but the spec's tolerance),
//! and scored; each result is written atomically to its own file as soon as it is known, so an
//! interrupted campaign resumes where it stopped. Cases run in parallel with rayon (feature `parallel`).

use super::cases::{build_case, effect, EffectSpec};
use super::generator::SetSize;
use super::metrics::{
    confident_wrong, coverage_entries, named_right, summarize, CaseResult, CurveResult,
    FoundEffect, Summary,
};
use super::rk4::Rk4Filippov;
use crate::error::{Error, Result};
use crate::identification::diagnose::{diagnose, DiagnoseOptions};
use crate::io::recordings::{read_set, write_set};
use crate::io::write_json_atomic;
use crate::progress::{stage, Observer};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Schema identifier of campaign.json.
pub const SCHEMA: &str = "gearbif.campaign/1";

/// What to run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignSpec {
    /// Effect ids (see [`super::cases::EFFECTS`]).
    pub effects: Vec<String>,
    /// Levels: multiples of each effect's reference size (controls run at level 1 only).
    pub levels: Vec<f64>,
    /// Seeds of the swept effects (one lab and one noise realisation each).
    pub seeds: Vec<u64>,
    /// Seeds of the controls (expected `none`).
    pub null_seeds: Vec<u64>,
    /// Size of each recording set.
    pub set: SetSize,
    /// Step of the generator's RK4 integrator, s.
    pub rk4_step_s: f64,
    /// Keep the generated sets (under `sets/`).
    #[serde(default)]
    pub keep_sets: bool,
    /// Relative tolerance of the diagnosis' simulations ([`DiagnoseOptions::tol`]); a spec.json
    /// written before this field existed reads as the default.
    #[serde(default = "default_tol")]
    pub tol: f64,
    /// Profile the final models' shape parameters ([`DiagnoseOptions::profile_shapes`]); a
    /// spec.json written before this field existed reads as `false`.
    #[serde(default)]
    pub profile_shapes: bool,
}

/// [`DiagnoseOptions::tol`] of the default options.
fn default_tol() -> f64 {
    DiagnoseOptions::default().tol
}

impl CampaignSpec {
    /// Checks ids, levels, seeds and the set size.
    pub fn validate(&self) -> Result<()> {
        if self.effects.is_empty() || self.levels.is_empty() {
            return Err(Error::inconsistent(
                "effects, levels",
                "a campaign needs at least one effect and one level",
            ));
        }
        for e in &self.effects {
            let spec = effect(e)?;
            let seeds = if spec.is_null() {
                &self.null_seeds
            } else {
                &self.seeds
            };
            if seeds.is_empty() {
                return Err(Error::option(
                    format!("seeds of effect `{e}`"),
                    "none given",
                ));
            }
        }
        for &l in &self.levels {
            if !(l.is_finite() && l > 0.0) {
                return Err(Error::option(
                    format!("level {l}"),
                    "must be finite and > 0",
                ));
            }
        }
        if !(self.rk4_step_s.is_finite() && self.rk4_step_s > 0.0 && self.rk4_step_s <= 0.01) {
            return Err(Error::InvalidParameter {
                name: "rk4_step_s",
                value: self.rk4_step_s,
                reason: "the RK4 step must be in (0, 0.01] s",
            });
        }
        crate::error::relative_tolerance("tol", self.tol)?;
        self.set.validate()
    }
}

/// One case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Case {
    /// The effect.
    pub effect: &'static EffectSpec,
    /// Its level.
    pub level: f64,
    /// The seed.
    pub seed: u64,
}

impl Case {
    /// File-name key `effect__L<level>__s<seed>`.
    pub fn key(&self) -> String {
        format!("{}__L{}__s{}", self.effect.id, self.level, self.seed)
    }
}

/// The cases of a campaign: controls once per null seed, swept effects at every level and seed.
pub fn plan(spec: &CampaignSpec) -> Result<Vec<Case>> {
    spec.validate()?;
    let mut out = Vec::new();
    for id in &spec.effects {
        let e = effect(id)?;
        let (levels, seeds) = if e.is_null() {
            (vec![1.0], &spec.null_seeds)
        } else {
            (spec.levels.clone(), &spec.seeds)
        };
        for &level in &levels {
            for &seed in seeds {
                out.push(Case {
                    effect: e,
                    level,
                    seed,
                });
            }
        }
    }
    Ok(out)
}

/// The message of a caught panic (its `&str` or `String` payload).
fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(no message)".to_string())
}

/// Generates, writes, reads back, diagnoses and scores one case. `sets_dir` receives the set (and
/// loses it again unless `keep`).
pub fn run_case(
    case: &Case,
    spec: &CampaignSpec,
    sets_dir: &Path,
    keep: bool,
) -> Result<CaseResult> {
    let rk4 = Rk4Filippov {
        step: spec.rk4_step_s,
    };
    let g = build_case(case.effect, case.level, case.seed, &spec.set, &rk4)?;
    let dir = sets_dir.join(case.key());
    write_set(&g.set, &dir, true)?;
    let set = read_set(&dir)?;
    let t0 = Instant::now();
    let opts = DiagnoseOptions {
        tol: spec.tol,
        profile_shapes: spec.profile_shapes,
        ..DiagnoseOptions::default()
    };
    // a diagnosis that panics (a bug) is recorded as that case's error, and the campaign goes on
    let diag = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        diagnose(&set, &opts, &crate::progress::Silent)
    }))
    .map_err(|p| format!("the diagnosis panicked: {}", panic_message(&*p)))
    .and_then(|d| d.map_err(|e| e.to_string()));
    let seconds = t0.elapsed().as_secs_f64();
    if !keep {
        let _ = std::fs::remove_dir_all(&dir);
    }
    let expected: Vec<String> = case.effect.expected.iter().map(|s| s.to_string()).collect();
    let remaining_above_noise = diag
        .as_ref()
        .ok()
        .and_then(|d| d.report.remaining.as_ref())
        .map(|r| !r.within_noise);
    let rem = diag.as_ref().ok().and_then(|d| d.report.remaining.as_ref());
    let remaining_z = rem.map(|r| r.excess_chi2_per_dof / r.excess_sigma);
    let remaining_depends_on = rem.and_then(|r| {
        r.dependence
            .iter()
            .find(|d| d.significant)
            .map(|d| d.variable.clone())
    });
    let noise_at_rest = rem
        .and_then(|r| r.noise.as_ref())
        .filter(|n| n.method == "rest" && !n.correlation.is_empty())
        .map(|n| [n.sigma_rad, n.correlation[0]]);
    let timing_jitter = rem
        .and_then(|r| r.noise.as_ref())
        .and_then(|n| n.speed_noise.as_ref())
        .map(|s| [s.timing_var_s2, s.timing_var_sigma_s2]);
    let curve = diag
        .as_ref()
        .ok()
        .and_then(|d| d.report.curve.as_ref())
        .map(|c| CurveResult {
            kind: c.kind.clone(),
            stands: c.stands,
            z: c.z,
            coverage: g
                .truth
                .curve(&c.kind, 0.0)
                .map(|_| c.coverage(|b| g.truth.curve(&c.kind, b).unwrap_or(f64::NAN))),
            worst: g
                .truth
                .curve(&c.kind, 0.0)
                .map(|_| c.worst(|b| g.truth.curve(&c.kind, b).unwrap_or(f64::NAN))),
        });
    let (forks, joints) = diag
        .as_ref()
        .map(|d| (d.report.selection_forks(), d.report.selection_joints()))
        .unwrap_or_default();
    let (verdict, findings, error) = match diag {
        Ok(d) => (
            d.report.verdict.clone(),
            d.report
                .findings
                .iter()
                .map(|f| FoundEffect {
                    effect: f.effect.clone(),
                    size: f.size.clone(),
                })
                .collect(),
            None,
        ),
        Err(e) => ("error".to_string(), Vec::new(), Some(e)),
    };
    Ok(CaseResult {
        effect: case.effect.id.to_string(),
        level: case.level,
        size: g.size,
        unit: case.effect.unit.to_string(),
        seed: case.seed,
        named_right: error.is_none() && named_right(&expected, &verdict, &findings),
        confident_wrong: confident_wrong(&expected, &verdict),
        coverage: coverage_entries(&g.truths, &findings),
        expected,
        verdict,
        findings,
        truths: g.truths,
        seconds,
        remaining_above_noise,
        remaining_z,
        remaining_depends_on,
        noise_at_rest,
        timing_jitter,
        forks,
        joints,
        curve,
        error,
    })
}

/// campaign.json.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignDoc {
    /// Always [`SCHEMA`].
    pub schema: String,
    /// What was run.
    pub spec: CampaignSpec,
    /// The metrics.
    pub summary: Summary,
    /// Every case.
    pub cases: Vec<CaseResult>,
}

fn cases_dir(out: &Path) -> PathBuf {
    out.join("cases")
}

/// Runs (or resumes) a campaign in `out`: results of finished cases in `out/cases/` are reused,
/// the others computed (in parallel with feature `parallel`). `progress` gets one line per case.
pub fn run_campaign(
    spec: &CampaignSpec,
    out: &Path,
    progress: &dyn Observer,
) -> Result<CampaignDoc> {
    let cases = plan(spec)?;
    let spec_path = out.join("spec.json");
    if let Ok(text) = std::fs::read_to_string(&spec_path) {
        let old: CampaignSpec = serde_json::from_str(&text).map_err(|e| Error::Recording {
            file: spec_path.display().to_string(),
            line: (e.line() > 0).then_some(e.line()),
            what: format!("not a campaign spec ({e})"),
        })?;
        if old.set != spec.set
            || old.rk4_step_s != spec.rk4_step_s
            || old.tol != spec.tol
            || old.profile_shapes != spec.profile_shapes
        {
            return Err(Error::checkpoint(
                out,
                "the folder holds a campaign with another set size, step, tolerance or shape \
                 profiling; choose another --out",
            ));
        }
    }
    write_json_atomic(&spec_path, spec)?;
    let cdir = cases_dir(out);
    let load = |c: &Case| -> Option<CaseResult> {
        let text = std::fs::read_to_string(cdir.join(format!("{}.json", c.key()))).ok()?;
        serde_json::from_str(&text).ok()
    };
    let pending: Vec<&Case> = cases.iter().filter(|c| load(c).is_none()).collect();
    let total = cases.len();
    let done = AtomicUsize::new(total - pending.len());
    stage(
        progress,
        &format!(
            "{total} cases, {} already done, {} to run",
            total - pending.len(),
            pending.len()
        ),
    );
    let sets_dir = out.join("sets");
    let run_one = |c: &&Case| -> Result<()> {
        let r = run_case(c, spec, &sets_dir, spec.keep_sets)?;
        write_json_atomic(cdir.join(format!("{}.json", c.key())), &r)?;
        let k = done.fetch_add(1, Ordering::SeqCst) + 1;
        stage(
            progress,
            &format!(
                "[{k}/{total}] {}: verdict {} ({}, {:.1} s)",
                c.key(),
                r.verdict,
                if r.named_right { "right" } else { "wrong" },
                r.seconds
            ),
        );
        Ok(())
    };
    #[cfg(feature = "parallel")]
    let outcomes: Vec<Result<()>> = {
        use rayon::prelude::*;
        pending.par_iter().map(run_one).collect()
    };
    #[cfg(not(feature = "parallel"))]
    let outcomes: Vec<Result<()>> = pending.iter().map(run_one).collect();
    outcomes.into_iter().collect::<Result<Vec<()>>>()?;
    if !spec.keep_sets {
        let _ = std::fs::remove_dir(&sets_dir);
    }
    let results: Vec<CaseResult> = cases
        .iter()
        .map(|c| {
            load(c).ok_or_else(|| {
                Error::checkpoint(out, format!("the result of case {} is missing", c.key()))
            })
        })
        .collect::<Result<_>>()?;
    Ok(CampaignDoc {
        schema: SCHEMA.to_string(),
        spec: spec.clone(),
        summary: summarize(&results),
        cases: results,
    })
}
