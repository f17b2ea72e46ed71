//! Campaign metrics: false-positive rate on the controls, detection power per effect against its
//! size, the confusion matrix of verdicts, and the coverage of the reported σ; with exact binomial
//! (Clopper–Pearson) intervals, and the binomial bounds the tests assert.

use super::cases::{effect, TruthSize};
use crate::identification::report::EffectSize;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What a diagnosis said about a finding, as far as the campaign scores it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FoundEffect {
    /// Effect identifier.
    pub effect: String,
    /// Headline size with its σ, when the diagnosis reports one.
    pub size: Option<EffectSize>,
}

/// A σ-coverage check of one headline size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoverageEntry {
    /// Effect.
    pub effect: String,
    /// True value.
    pub truth: f64,
    /// Reported value and σ (None: no size reported, or in another unit).
    pub reported: Option<(f64, f64)>,
    /// |reported − truth| ≤ 2σ (None when not comparable).
    pub within_2sigma: Option<bool>,
    /// Why not comparable, if so.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// The result of one case, as appended to the campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    /// Effect id.
    pub effect: String,
    /// Level (multiple of the effect's reference size).
    pub level: f64,
    /// Effect size, in `unit`.
    pub size: f64,
    /// Unit of the size.
    pub unit: String,
    /// Seed of the lab and the noise.
    pub seed: u64,
    /// The findings a correct diagnosis names.
    pub expected: Vec<String>,
    /// The report's verdict (`error` if the diagnosis failed).
    pub verdict: String,
    /// The findings, in report order.
    pub findings: Vec<FoundEffect>,
    /// The verdict is right (see [`named_right`]).
    pub named_right: bool,
    /// The verdict names a catalog effect the truth does not contain (see [`confident_wrong`]).
    #[serde(default)]
    pub confident_wrong: bool,
    /// Headline truths.
    pub truths: Vec<TruthSize>,
    /// σ coverage of the headline sizes of detected effects.
    pub coverage: Vec<CoverageEntry>,
    /// Wall time of the diagnosis, s.
    pub seconds: f64,
    /// Whether the report says a held-out mismatch above the camera noise remains after the
    /// findings (report key `remaining`; `None` when it has none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub remaining_above_noise: Option<bool>,
    /// The variable the remainder depends on significantly, the largest z first (report key
    /// `remaining.dependence`; `None` when none does).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub remaining_depends_on: Option<String>,
    /// z = E/σ_E of that remainder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub remaining_z: Option<f64>,
    /// The camera noise behind its floor: σ (rad) and the lag-1 correlation measured at rest
    /// (report key `remaining.noise`; absent when the floor is white noise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise_at_rest: Option<[f64; 2]>,
    /// The speed-dependent noise measured in motion: σ_t² (s², a timing jitter's variance) and
    /// its σ (report key `remaining.noise.speed_noise`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timing_jitter: Option<[f64; 2]>,
    /// The selection's forks (report key `fits.selection_forks`): rounds whose two best named
    /// candidates the held-out windows did not tell apart.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub forks: Vec<crate::identification::beam::Fork>,
    /// Its close rivals accepted together (report key `fits.selection_joints`): rounds whose two
    /// best named candidates were each significant on top of the other.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub joints: Vec<crate::identification::beam::Joint>,
    /// The curve of what remains (report key `curve`; `None` when none was fitted).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curve: Option<CurveResult>,
    /// The error, if the diagnosis failed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// A case's curve of what remains, scored against the truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CurveResult {
    /// `friction` or `torque`.
    pub kind: String,
    /// Whether it predicts the held-out runs significantly better than the final model.
    pub stands: bool,
    /// The judge's z.
    pub z: f64,
    /// The fraction of its grid where its band holds the true curve of its kind
    /// ([`super::truth::TruthModel::curve`]); `None` when the truth has no such curve.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverage: Option<f64>,
    /// The largest |curve − truth|/σ on the grid and where (β in degrees); `None` without a
    /// truth of its kind.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub worst: Option<[f64; 2]>,
}

/// The fraction of the grid a band must cover for a case's curve to count as covering
/// ([`Summary::curve_coverage`]).
pub const CURVE_COVERAGE: f64 = 0.9;

/// A confident wrong name: the verdict is a catalog effect (not `none`, `unexplained`,
/// `partly_explained` or `error`) that is not among the `expected` ones. A control's verdict other
/// than `none` is a false positive instead (counted there).
pub fn confident_wrong(expected: &[String], verdict: &str) -> bool {
    use crate::identification::verdict::{NONE, PARTLY_EXPLAINED, UNEXPLAINED};
    expected != [NONE]
        && ![NONE, UNEXPLAINED, PARTLY_EXPLAINED, "error"].contains(&verdict)
        && !expected.iter().any(|e| e == verdict)
}

/// Right when: `none` expected and the verdict is `none`; `unexplained` expected (a form the catalog
/// does not contain) and the verdict `unexplained` or `partly_explained`; one effect expected and
/// the verdict is it; several expected and all are among the findings with the verdict one of them.
pub fn named_right(expected: &[String], verdict: &str, findings: &[FoundEffect]) -> bool {
    use crate::identification::verdict::{PARTLY_EXPLAINED, UNEXPLAINED};
    match expected {
        // a form the catalog does not contain: part of it may be explained by catalog terms
        [one] if one == UNEXPLAINED => verdict == UNEXPLAINED || verdict == PARTLY_EXPLAINED,
        [one] => verdict == one,
        many => {
            many.iter().any(|e| e == verdict)
                && many.iter().all(|e| findings.iter().any(|f| &f.effect == e))
        }
    }
}

/// Checks each truth against the first finding of its effect (skipped when not detected).
pub fn coverage_entries(truths: &[TruthSize], findings: &[FoundEffect]) -> Vec<CoverageEntry> {
    let mut out = Vec::new();
    for t in truths {
        let Some(f) = findings.iter().find(|f| f.effect == t.effect) else {
            continue;
        };
        let mut e = CoverageEntry {
            effect: t.effect.clone(),
            truth: t.value,
            reported: None,
            within_2sigma: None,
            note: None,
        };
        match &f.size {
            None => e.note = Some("no size reported".into()),
            Some(s) if s.unit != t.unit => {
                e.note = Some(format!("unit `{}`, truth in `{}`", s.unit, t.unit))
            }
            Some(s) if !(s.sigma.is_finite() && s.sigma >= 0.0 && s.value.is_finite()) => {
                e.reported = Some((s.value, s.sigma));
                e.within_2sigma = Some(false);
                e.note = Some("non-finite value or σ".into());
            }
            Some(s) => {
                e.reported = Some((s.value, s.sigma));
                e.within_2sigma = Some((s.value - t.value).abs() <= 2.0 * s.sigma);
            }
        }
        out.push(e);
    }
    out
}

/// A count out of n with its 95 % Clopper–Pearson interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Rate {
    /// Count.
    pub k: usize,
    /// Trials.
    pub n: usize,
    /// k/n (NaN when n = 0, serialised as null).
    pub rate: Option<f64>,
    /// 95 % interval, lower end.
    pub lo95: f64,
    /// 95 % interval, upper end.
    pub hi95: f64,
}

impl Rate {
    /// k out of n.
    pub fn new(k: usize, n: usize) -> Self {
        let (lo95, hi95) = clopper_pearson(k, n, 0.95);
        Self {
            k,
            n,
            rate: (n > 0).then(|| k as f64 / n as f64),
            lo95,
            hi95,
        }
    }
}

fn ln_choose(n: usize, k: usize) -> f64 {
    let mut s = 0.0;
    for i in 0..k {
        s += ((n - i) as f64).ln() - ((i + 1) as f64).ln();
    }
    s
}

/// P(X ≥ k) for X ~ Binomial(n, p).
pub fn binomial_tail_ge(n: usize, k: usize, p: f64) -> f64 {
    if k == 0 {
        return 1.0;
    }
    if k > n {
        return 0.0;
    }
    if p <= 0.0 {
        return 0.0;
    }
    if p >= 1.0 {
        return 1.0;
    }
    (k..=n)
        .map(|j| (ln_choose(n, j) + j as f64 * p.ln() + (n - j) as f64 * (1.0 - p).ln()).exp())
        .sum::<f64>()
        .min(1.0)
}

/// The exact (Clopper–Pearson) interval of a binomial rate at confidence `conf`.
pub fn clopper_pearson(k: usize, n: usize, conf: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let a = 0.5 * (1.0 - conf);
    // lower: P(X ≥ k | p) = a; upper: P(X ≤ k | p) = a, i.e. P(X ≥ k+1 | p) = 1 − a
    let solve = |target: f64, kk: usize| {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if binomial_tail_ge(n, kk, mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let lower = if k == 0 { 0.0 } else { solve(a, k) };
    let upper = if k == n { 1.0 } else { solve(1.0 - a, k + 1) };
    (lower, upper)
}

/// The largest count of failures among n that is still consistent, at significance `alpha`,
/// with a failure rate of at most `p`: the largest k with P(X ≥ k | n, p) ≥ alpha. A campaign
/// with more failures refutes the goal "rate ≤ p" at level alpha.
pub fn max_consistent_failures(n: usize, p: f64, alpha: f64) -> usize {
    (0..=n)
        .take_while(|&k| binomial_tail_ge(n, k, p) >= alpha)
        .last()
        .unwrap_or(0)
}

/// Detection power of one effect at one level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PowerPoint {
    /// Level.
    pub level: f64,
    /// Size, in the effect's unit.
    pub size: f64,
    /// Named right, out of the seeds.
    pub named_right: Rate,
}

/// Detection power of one effect against its size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectPower {
    /// Effect id.
    pub effect: String,
    /// Expected verdict label.
    pub expected: String,
    /// Unit of the size.
    pub unit: String,
    /// By level, ascending.
    pub points: Vec<PowerPoint>,
    /// Smallest swept size from which on every larger swept size is named right in ≥ 90 % of the
    /// seeds (None: not reached in the sweep).
    pub size_90: Option<f64>,
}

/// Rows: the expected label; columns: verdicts; counts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Confusion {
    /// Expected labels.
    pub rows: Vec<String>,
    /// Verdicts seen.
    pub cols: Vec<String>,
    /// counts[row][col].
    pub counts: Vec<Vec<usize>>,
}

/// σ coverage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoverageSummary {
    /// Truth within ±2σ, per effect, among the comparable headline sizes.
    pub per_effect: BTreeMap<String, Rate>,
    /// Pooled.
    pub pooled: Rate,
    /// Detections without a reported size.
    pub missing_size: usize,
    /// Detections whose size is in another unit.
    pub other_unit: usize,
}

/// Everything the campaign measures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Any finding on a control, pooled over the controls.
    pub false_positive: Rate,
    /// Per control.
    pub false_positive_per_control: BTreeMap<String, Rate>,
    /// Per swept effect.
    pub power: Vec<EffectPower>,
    /// The confusion matrix.
    pub confusion: Confusion,
    /// The σ coverage.
    pub coverage: CoverageSummary,
    /// Verdicts that name a catalog effect the truth does not contain, over the cases that are not
    /// controls ([`confident_wrong`]).
    pub confident_wrong: Rate,
    /// Honest verdicts on the out-of-catalog effects ([`super::cases::OUT_OF_CATALOG`]): neither
    /// a confident wrong name nor an error.
    pub out_of_catalog_honest: Rate,
    /// Curves whose band holds the true curve on at least [`CURVE_COVERAGE`] of their grid, over
    /// the cases with a curve and a truth of its kind ([`CurveResult::coverage`]), whether the
    /// curve stands or not.
    #[serde(default = "no_cases")]
    pub curve_coverage: Rate,
    /// Controls with a curve that stands, over the controls.
    #[serde(default = "no_cases")]
    pub curve_false_positive: Rate,
    /// Diagnoses that failed with an error (counted as wrong).
    pub errors: usize,
    /// Median wall time of a diagnosis, s.
    pub median_seconds: f64,
}

/// Summarises case results.
pub fn summarize(results: &[CaseResult]) -> Summary {
    let nulls: Vec<&CaseResult> = results.iter().filter(|r| r.expected == ["none"]).collect();
    let fp_k = nulls.iter().filter(|r| r.verdict != "none").count();
    let mut per_control: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    for r in &nulls {
        let e = per_control.entry(r.effect.clone()).or_default();
        e.1 += 1;
        if r.verdict != "none" {
            e.0 += 1;
        }
    }
    let mut power = Vec::new();
    let mut ids: Vec<&str> = Vec::new();
    for r in results.iter().filter(|r| r.expected != ["none"]) {
        if !ids.contains(&r.effect.as_str()) {
            ids.push(&r.effect);
        }
    }
    for id in ids {
        let rs: Vec<&CaseResult> = results.iter().filter(|r| r.effect == id).collect();
        let mut levels: Vec<f64> = rs.iter().map(|r| r.level).collect();
        levels.sort_by(|a, b| a.total_cmp(b));
        levels.dedup();
        let points: Vec<PowerPoint> = levels
            .iter()
            .map(|&l| {
                let at: Vec<&&CaseResult> = rs.iter().filter(|r| r.level == l).collect();
                PowerPoint {
                    level: l,
                    size: at[0].size,
                    named_right: Rate::new(at.iter().filter(|r| r.named_right).count(), at.len()),
                }
            })
            .collect();
        let mut size_90 = None;
        for p in points.iter().rev() {
            if p.named_right.rate.is_some_and(|x| x >= 0.9) {
                size_90 = Some(p.size);
            } else {
                break;
            }
        }
        power.push(EffectPower {
            effect: id.to_string(),
            expected: rs[0].expected.join("+"),
            unit: rs[0].unit.clone(),
            points,
            size_90,
        });
    }
    let effects = results.iter().filter(|r| r.expected != ["none"]);
    let wrong = effects.clone().filter(|r| r.confident_wrong).count();
    let ooc: Vec<&CaseResult> = results
        .iter()
        .filter(|r| super::cases::OUT_OF_CATALOG.contains(&r.effect.as_str()))
        .collect();
    let honest = ooc
        .iter()
        .filter(|r| !r.confident_wrong && r.error.is_none())
        .count();
    let mut secs: Vec<f64> = results.iter().map(|r| r.seconds).collect();
    secs.sort_by(|a, b| a.total_cmp(b));
    Summary {
        false_positive: Rate::new(fp_k, nulls.len()),
        false_positive_per_control: per_control
            .into_iter()
            .map(|(k, (f, n))| (k, Rate::new(f, n)))
            .collect(),
        power,
        confusion: confusion(results),
        coverage: coverage(results),
        confident_wrong: Rate::new(wrong, effects.count()),
        out_of_catalog_honest: Rate::new(honest, ooc.len()),
        curve_coverage: curve_coverage(results),
        curve_false_positive: Rate::new(
            nulls
                .iter()
                .filter(|r| r.curve.as_ref().is_some_and(|c| c.stands))
                .count(),
            nulls.len(),
        ),
        errors: results.iter().filter(|r| r.error.is_some()).count(),
        median_seconds: secs.get(secs.len() / 2).copied().unwrap_or(0.0),
    }
}

/// A rate over no cases (the curve's rates in campaign files written without them).
fn no_cases() -> Rate {
    Rate::new(0, 0)
}

/// [`Summary::curve_coverage`].
fn curve_coverage(results: &[CaseResult]) -> Rate {
    let scored: Vec<f64> = results
        .iter()
        .filter_map(|r| r.curve.as_ref()?.coverage)
        .collect();
    Rate::new(
        scored.iter().filter(|&&c| c >= CURVE_COVERAGE).count(),
        scored.len(),
    )
}

fn confusion(results: &[CaseResult]) -> Confusion {
    let mut rows: Vec<String> = Vec::new();
    for r in results {
        let l = r.expected.join("+");
        if !rows.contains(&l) {
            rows.push(l);
        }
    }
    // rows in the order of the effect table where possible
    rows.sort_by_key(|l| {
        results
            .iter()
            .find(|r| &r.expected.join("+") == l)
            .and_then(|r| effect(&r.effect).ok())
            .map(|e| super::cases::EFFECTS.iter().position(|x| x.id == e.id))
    });
    let mut cols: Vec<String> = rows
        .iter()
        .flat_map(|r| r.split('+'))
        .map(String::from)
        .collect();
    for r in results {
        if !cols.contains(&r.verdict) {
            cols.push(r.verdict.clone());
        }
    }
    let mut seen = Vec::new();
    cols.retain(|c| {
        let keep = !seen.contains(c);
        seen.push(c.clone());
        keep
    });
    let mut counts = vec![vec![0usize; cols.len()]; rows.len()];
    for r in results {
        let i = rows.iter().position(|x| *x == r.expected.join("+"));
        let j = cols.iter().position(|x| *x == r.verdict);
        if let (Some(i), Some(j)) = (i, j) {
            counts[i][j] += 1;
        }
    }
    Confusion { rows, cols, counts }
}

fn coverage(results: &[CaseResult]) -> CoverageSummary {
    let mut per: BTreeMap<String, (usize, usize)> = BTreeMap::new();
    let (mut k, mut n, mut missing, mut other) = (0, 0, 0, 0);
    for e in results.iter().flat_map(|r| r.coverage.iter()) {
        match e.within_2sigma {
            Some(w) => {
                let p = per.entry(e.effect.clone()).or_default();
                p.1 += 1;
                n += 1;
                if w {
                    p.0 += 1;
                    k += 1;
                }
            }
            None if e.reported.is_none() && e.note.as_deref() == Some("no size reported") => {
                missing += 1
            }
            None => other += 1,
        }
    }
    CoverageSummary {
        per_effect: per
            .into_iter()
            .map(|(e, (k, n))| (e, Rate::new(k, n)))
            .collect(),
        pooled: Rate::new(k, n),
        missing_size: missing,
        other_unit: other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binomial_tail_matches_direct_sums() {
        // n = 20, p = 0.05: P(X ≥ 0) = 1, P(X ≥ 1) = 1 − 0.95^20
        assert!((binomial_tail_ge(20, 1, 0.05) - (1.0 - 0.95f64.powi(20))).abs() < 1e-14);
        // P(X ≥ 20) = p^20
        assert!((binomial_tail_ge(20, 20, 0.3) - 0.3f64.powi(20)).abs() < 1e-20);
        // symmetry at p = 1/2: P(X ≥ 6 | 10) = P(X ≤ 4 | 10) = 1 − P(X ≥ 5)
        let a = binomial_tail_ge(10, 6, 0.5);
        let b = 1.0 - binomial_tail_ge(10, 5, 0.5);
        assert!((a - b).abs() < 1e-14);
    }

    #[test]
    fn clopper_pearson_known_values() {
        // k = 0 of n: upper end 1 − (a/2)^(1/n) with a = 0.05
        let (lo, hi) = clopper_pearson(0, 20, 0.95);
        assert_eq!(lo, 0.0);
        assert!((hi - (1.0 - 0.025f64.powf(1.0 / 20.0))).abs() < 1e-9);
        // k = n mirrors it
        let (lo, hi) = clopper_pearson(20, 20, 0.95);
        assert!((lo - 0.025f64.powf(1.0 / 20.0)).abs() < 1e-9);
        assert_eq!(hi, 1.0);
    }

    #[test]
    fn consistent_failures_at_five_percent_of_twenty() {
        // P(X ≥ 4 | 20, 0.05) = 0.0159 ≥ 0.01 and P(X ≥ 5) = 0.0026 < 0.01
        assert_eq!(max_consistent_failures(20, 0.05, 0.01), 4);
    }
}
