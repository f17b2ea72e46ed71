//! Classification of the attractor reached from an initial state, twice:
//!
//! - **the paper's** ([`super::harmonic`]): 7-harmonic fit of δ over α on the last 10 of 100 turns
//!   at 50 samples per turn, RMS and THD_F, flowchart;
//! - **rigorous** ([`RigorousClass`]): the period on the Poincaré section modulo the half-period
//!   symmetry (found on the trajectory, then confirmed by a Newton solve of Gᵏ(x) = x mod 2π and
//!   its multipliers), the rotation number, and the largest Lyapunov exponent from the products of
//!   the Filippov (saltation-corrected) Jacobians ([`super::lyapunov`]).
//!
//! The half-period map G = R⁻¹ ∘ P_{T/2} is the natural map (model.md, "Symmetry"): a fixed point of
//! G^k with k odd is a *symmetric* orbit (δ is kT/2-periodic; k = 1 is the paper's "T/2"), a
//! fixed point with k = 2m even and no smaller period is an asymmetric orbit of period mT.

use super::harmonic::{paper_metrics, PaperClass, PaperMetrics, ThdDefinition};
use super::lyapunov::{LyapunovAccumulator, LyapunovEstimate};
use crate::error::{Error, Result};
use crate::integrator::{EventDriven853, FlowMethod, FlowOptions, Sensitivity};
use crate::maps::{multipliers, poincare_map, Section};
use crate::model::{DrivenOscillator, Gear, HalfPeriodSymmetry};
use nalgebra::Matrix2;
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// Options of a classification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClassifyOptions {
    /// Settling turns before the recorded window (paper: 90).
    pub settle_turns: usize,
    /// Turns in the recorded window of the paper's metrics (paper: 10).
    pub record_turns: usize,
    /// Samples per turn in the window (paper: 50).
    pub samples_per_turn: usize,
    /// Compute the rigorous classification (needs the event-driven integrator).
    pub rigorous: bool,
    /// Turns after the window over which section points and Jacobians are collected for the
    /// rigorous classification (period detection and Lyapunov exponent).
    pub analysis_turns: usize,
    /// Largest period searched, in half periods (16 = 8T).
    pub max_half_periods: usize,
    /// Candidate tolerance of a period on the trajectory (rad, and ω·T/2π).
    pub period_tol: f64,
    /// |λ| per drive period below this counts as zero (quasi-periodic), above it as chaos.
    pub lyapunov_threshold: f64,
    /// Relative tolerance of the event-driven integrator.
    pub tol: f64,
    /// THD definition of the flowchart.
    pub thd: ThdDefinition,
    /// Keep the samples of the window (for figures).
    pub keep_samples: bool,
    /// Early end of the settling phase: once the turn-by-turn states repeat with a period of
    /// m ≤ 8 turns to within this distance (twice in a row), the rest of the settling is skipped
    /// and the state the full settling would reach on that cycle is used. `None` (default): always
    /// integrate every settling turn, as the paper did.
    #[serde(default)]
    pub settle_tol: Option<f64>,
    /// Settling turns of a point that follows a non-periodic point (quasi-periodic, chaotic or
    /// unresolved) on a semi-static ramp, whose start already lies on the attractor of the
    /// neighbouring parameter value; a cycle found while settling ([`Self::settle_tol`]) still
    /// ends it earlier. `None` (default): `settle_turns` for every point. Used by sweeps.
    #[serde(default)]
    pub settle_after_nonperiodic: Option<usize>,
}

impl Default for ClassifyOptions {
    fn default() -> Self {
        Self {
            settle_turns: 90,
            record_turns: 10,
            samples_per_turn: 50,
            rigorous: true,
            analysis_turns: 60,
            max_half_periods: 16,
            period_tol: 1e-3,
            lyapunov_threshold: 0.1,
            tol: 1e-9,
            thd: ThdDefinition::Standard,
            keep_samples: false,
            settle_tol: None,
            settle_after_nonperiodic: None,
        }
    }
}

impl ClassifyOptions {
    /// The paper's protocol for one point: 90 settling turns, 10 recorded, 50 samples per turn.
    pub fn paper() -> Self {
        Self::default()
    }

    /// Validates the options.
    pub fn validate(&self) -> Result<()> {
        let at_least = |name: &str, v: usize, min: usize, why: &str| {
            if v < min {
                Err(Error::option(name, format!("{v} < {min} ({why})")))
            } else {
                Ok(())
            }
        };
        at_least("record_turns", self.record_turns, 1, "nothing to record")?;
        at_least(
            "samples_per_turn",
            self.samples_per_turn,
            15,
            "7-harmonic fit",
        )?;
        if self.rigorous {
            let why = "rigorous classification";
            at_least("analysis_turns", self.analysis_turns, 2, why)?;
            at_least("max_half_periods", self.max_half_periods, 1, why)?;
        }
        crate::error::positive("tol", self.tol)?;
        crate::error::positive("period_tol", self.period_tol)?;
        crate::error::positive("lyapunov_threshold", self.lyapunov_threshold)?;
        if let Some(e) = self.settle_tol {
            crate::error::positive("settle_tol", e)?;
        }
        if self.settle_after_nonperiodic == Some(0) {
            return Err(Error::option(
                "settle_after_nonperiodic",
                "must be >= 1 turn, got 0",
            ));
        }
        Ok(())
    }

    /// The options of a point that follows a point with result `prev` on a semi-static ramp: the
    /// settling is cut to [`Self::settle_after_nonperiodic`] turns if `prev` was classified as not
    /// periodic.
    pub fn after(&self, prev: Option<&PointResult>) -> Option<Self> {
        let n = self.settle_after_nonperiodic?;
        let rig = prev?.rigorous.as_ref()?;
        if matches!(rig.dynamics, Dynamics::Periodic { .. }) || n >= self.settle_turns {
            return None;
        }
        Some(Self {
            settle_turns: n,
            ..self.clone()
        })
    }
}

/// The dynamics found by the rigorous classification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Dynamics {
    /// A stable periodic orbit, confirmed by Newton on Gᵏ (or P_T^{k/2}).
    Periodic {
        /// Minimal period in half drive periods (1 = T/2, 2 = T, 6 = 3T).
        half_periods: usize,
        /// Invariant under the half-period symmetry (k odd).
        symmetric: bool,
        /// Moduli of the multipliers of the map Gᵏ at the orbit, largest first (0 for a stick phase).
        multipliers: [f64; 2],
        /// Residual of the Newton solve.
        residual: f64,
        /// A point of the orbit on the section t ≡ 0 mod T (β on the lift, symmetry-reduced).
        orbit: [f64; 2],
    },
    /// No period up to the search limit, |λ| below the threshold.
    QuasiPeriodic,
    /// No period up to the search limit, λ above the threshold.
    Chaotic,
    /// No period found although λ is negative: a long transient or a period beyond the limit.
    Unresolved,
    /// The output stays at rest (stuck by its dry friction) over the whole analysis window: a
    /// point of a continuum of equilibria, neither periodic motion nor chaos.
    Rest,
}

/// The rigorous classification of one attractor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigorousClass {
    /// What was found.
    pub dynamics: Dynamics,
    /// Short label: "T/2", "T", "3T", "3T/2", "QP", "chaos", "?", "rest".
    pub label: String,
    /// Mean winding of β per drive period (β on the lift over the analysis window / 2π).
    pub rotation_number: f64,
    /// Output locked to the input: |rotation number| = 1 (within 1e-3).
    pub locked: bool,
    /// Largest Lyapunov exponent.
    pub lyapunov: LyapunovEstimate,
}

/// A sample of the recorded window.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WindowSample {
    /// Time, s.
    pub t: f64,
    /// Input angle α, rad (on the lift).
    pub alpha: f64,
    /// Output angle β, rad (on the lift, in the gear's convention).
    pub beta: f64,
    /// δ = β − sα in degrees (s = sense of the gear), shifted by whole turns so the window's mean
    /// lies in [0°, 360°).
    pub delta_deg: f64,
}

/// Both classifications of one point, and the state to carry on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    /// The paper's metrics and class.
    pub paper: PaperMetrics,
    /// The rigorous class (if computed).
    pub rigorous: Option<RigorousClass>,
    /// Do the two agree (paper T/2 ⇔ symmetric period T/2, T ⇔ asymmetric T, chaos ⇔ chaos or QP)?
    pub agree: Option<bool>,
    /// Net rotation frequency of the output over the window, Hz: (β_end − β_start)/(2π · duration)
    /// (Fig. 10b; equals f for a locked output with Δ > 0).
    pub net_rotation_hz: f64,
    /// State (β mod 2π, ω) at the end, at a drive phase α ≡ α₀ (for semi-static sweeps).
    pub end_state: [f64; 2],
    /// Symmetry-reduced section points z_j = R⁻ʲ x(jT/2) of the analysis (β mod 2π, ω), if
    /// samples were requested (orbit diagrams).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub section: Option<Vec<[f64; 2]>>,
    /// The recorded window, if requested.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<Vec<WindowSample>>,
}

/// The sense s of δ = β − sα: +1 for Δ ≥ 0 (the output turns with the input), −1 for Δ < 0
/// (the reversed mode beyond Θ = 35.26°). The paper defines δ = β − α only for the first.
pub fn delta_sense(gear: &Gear) -> f64 {
    gear.co_rotation()
}

/// Do a paper class and a rigorous class agree?
pub fn classes_agree(paper: PaperClass, rig: &Dynamics) -> bool {
    matches!(
        (paper, rig),
        (
            PaperClass::Chaotic,
            Dynamics::Chaotic | Dynamics::QuasiPeriodic
        ) | (
            PaperClass::HalfPeriod,
            Dynamics::Periodic {
                half_periods: 1,
                ..
            }
        ) | (
            PaperClass::Period,
            Dynamics::Periodic {
                half_periods: 2,
                ..
            }
        )
    )
}

/// Label of a period of k half drive periods: "T/2", "T", "3T/2", "3T", …
pub fn period_label(k: usize) -> String {
    match k {
        1 => "T/2".into(),
        2 => "T".into(),
        k if k % 2 == 1 => format!("{k}T/2"),
        k => format!("{}T", k / 2),
    }
}

/// The paper's start for its Θ = 31° simulations (Figs. 5–6): α₀ = 90°, β₀ = 270° in the paper's
/// convention, i.e. 90° in the physical one, at rest. Returns the driven gear (physical convention,
/// parallel shafts at `theta_deg`, drive frequency `f` Hz) and the state (β₀, ω₀). Every figure
/// and table of these points starts here, so their numbers come from the same trajectory.
pub fn paper_fig6_start(
    params: &crate::model::GearParams,
    theta_deg: f64,
    f: f64,
) -> Result<(Gear, [f64; 2])> {
    let g = params
        .with_parallel_shafts_deg(theta_deg)
        .driven(f)?
        .with_alpha0(90f64.to_radians())?;
    Ok((g, [90f64.to_radians(), 0.0]))
}

/// Classifies the attractor of `sys` reached from `x0` (β, ω at t = 0), simulating the paper's
/// window with `method` and (if `opts.rigorous`) the rigorous analysis with the exact event-driven
/// integrator. The paper's metrics fit δ = β − s·α over the drive phase α
/// ([`DrivenOscillator::drive_phase`], s = [`DrivenOscillator::co_rotation`]; δ = β for an
/// oscillator).
pub fn classify_point<S, M>(
    sys: &S,
    x0: [f64; 2],
    method: &M,
    opts: &ClassifyOptions,
) -> Result<PointResult>
where
    S: DrivenOscillator + ?Sized,
    M: FlowMethod<S> + ?Sized,
{
    opts.validate()?;
    crate::error::finite_state("initial state", &x0)?;
    let period = sys.period();
    let fopts = FlowOptions::with_tol(opts.tol);
    let t_settle = opts.settle_turns as f64 * period;
    let (settled_x, cycle) = match opts.settle_tol {
        None => (method.flow(sys, 0.0, x0, t_settle, &fopts)?.x, None),
        Some(eps) => settle_early(sys, x0, method, opts.settle_turns, &fopts, eps)?,
    };
    // the window
    let n = opts.record_turns * opts.samples_per_turn;
    let times: Vec<f64> = (0..n)
        .map(|m| (opts.settle_turns as f64 + m as f64 / opts.samples_per_turn as f64) * period)
        .collect();
    let t_end = (opts.settle_turns + opts.record_turns) as f64 * period;
    let wopts = FlowOptions::with_tol(opts.tol).samples(times);
    let win = method.flow(sys, t_settle, settled_x, t_end, &wopts)?;
    if win.samples.len() != n {
        return Err(Error::Integration {
            t: t_end,
            reason: format!("expected {n} samples, got {}", win.samples.len()),
        });
    }
    let s = sys.co_rotation();
    let alpha: Vec<f64> = win.samples.iter().map(|p| sys.drive_phase(p.t)).collect();
    let mut delta: Vec<f64> = win
        .samples
        .iter()
        .zip(&alpha)
        .map(|(p, a)| (p.beta - s * a).to_degrees())
        .collect();
    let mean = delta.iter().sum::<f64>() / n as f64;
    let shift = 360.0 * (mean / 360.0).floor();
    delta.iter_mut().for_each(|d| *d -= shift);
    let paper = paper_metrics(&alpha, &delta, opts.record_turns, opts.thd)?;
    let samples = opts.keep_samples.then(|| {
        win.samples
            .iter()
            .zip(&alpha)
            .zip(&delta)
            .map(|((p, &a), &d)| WindowSample {
                t: p.t,
                alpha: a,
                beta: p.beta,
                delta_deg: d,
            })
            .collect()
    });
    let net_rotation_hz = (win.x[0] - settled_x[0]) / (TAU * opts.record_turns as f64 * period);
    let mut end = win.x;
    let mut section = None;
    let rigorous = if opts.rigorous {
        let (rc, x_end, z) = match cycle {
            Some(m) => rigorous_classify_seeded(sys, end, m, opts)?,
            None => rigorous_classify_with_section(sys, end, opts)?,
        };
        end = x_end;
        if opts.keep_samples {
            section = Some(z.iter().map(|v| [sys.reduce_angle(v[0]), v[1]]).collect());
        }
        Some(rc)
    } else {
        None
    };
    // a flat δ (constant lock angle) is T- and T/2-periodic at once: it agrees with a symmetric
    // orbit of period T/2
    let agree = rigorous.as_ref().map(|r| {
        classes_agree(paper.class, &r.dynamics)
            || (paper.fit.is_flat()
                && matches!(
                    r.dynamics,
                    Dynamics::Periodic {
                        half_periods: 1,
                        ..
                    }
                ))
    });
    Ok(PointResult {
        paper,
        rigorous,
        agree,
        net_rotation_hz,
        end_state: [sys.reduce_angle(end[0]), end[1]],
        section,
        samples,
    })
}

/// Settles turn by turn; stops early when the states repeat with a period m ≤ 8 turns (to `eps`,
/// over two consecutive cycles) and returns the state the full settling reaches on that cycle and
/// m (`None`: no repetition, every turn integrated).
fn settle_early<S: DrivenOscillator + ?Sized, M: FlowMethod<S> + ?Sized>(
    sys: &S,
    x0: [f64; 2],
    method: &M,
    turns: usize,
    fopts: &FlowOptions,
    eps: f64,
) -> Result<([f64; 2], Option<usize>)> {
    const M_MAX: usize = 8;
    let period = sys.period();
    let mut hist: Vec<[f64; 2]> = Vec::with_capacity(turns + 1);
    hist.push(x0);
    let mut x = x0;
    // integrate in chunks of 4, 8, … 64 turns with a strobe sample at every turn (one integrator
    // start per chunk), checking after every turn c whether the last two cycles of some period
    // m ≤ 8 with 2m ≤ c repeat to eps
    let mut c0 = 0;
    let mut chunk = 4;
    while c0 < turns {
        let c1 = (c0 + chunk).min(turns);
        chunk = (2 * chunk).min(64);
        let times: Vec<f64> = (c0 + 1..=c1).map(|c| c as f64 * period).collect();
        let opts = fopts.clone().samples(times);
        let fl = method.flow(sys, c0 as f64 * period, x, c1 as f64 * period, &opts)?;
        if fl.samples.len() != c1 - c0 {
            return Err(Error::Integration {
                t: c1 as f64 * period,
                reason: format!(
                    "expected {} strobe samples, got {}",
                    c1 - c0,
                    fl.samples.len()
                ),
            });
        }
        for (j, smp) in fl.samples.iter().enumerate() {
            let c = c0 + 1 + j;
            hist.push(if c == c1 { fl.x } else { [smp.beta, smp.omega] });
            if c == turns {
                continue;
            }
            for m in 1..=M_MAX.min(c / 2) {
                if cyl_dist(hist[c], hist[c - m], period) < eps
                    && cyl_dist(hist[c - m], hist[c - 2 * m], period) < eps
                {
                    let i = c - m + (turns - c) % m;
                    return Ok((hist[i], Some(m)));
                }
            }
        }
        x = fl.x;
        c0 = c1;
    }
    Ok((x, None))
}

/// The rigorous classification seeded by a cycle of `m` turns found while settling: the analysis
/// runs over 2m turns (at least 2) instead of `analysis_turns` — enough to test every period that
/// divides 2m half periods on the trajectory and to confirm it by Newton with its multipliers. If
/// no period is confirmed there, the full analysis of [`rigorous_classify_with_section`] runs from
/// the same state, so the verdict is never weaker than without the seed.
fn rigorous_classify_seeded<S: DrivenOscillator + ?Sized>(
    sys: &S,
    x: [f64; 2],
    m: usize,
    opts: &ClassifyOptions,
) -> Result<(RigorousClass, [f64; 2], Vec<[f64; 2]>)> {
    let short = ClassifyOptions {
        analysis_turns: (2 * m).clamp(2, opts.analysis_turns.max(2)),
        ..opts.clone()
    };
    let seeded = rigorous_classify_with_section(sys, x, &short)?;
    if matches!(seeded.0.dynamics, Dynamics::Periodic { .. }) {
        return Ok(seeded);
    }
    rigorous_classify_with_section(sys, x, opts)
}

/// Distance on the cylinder: max(|Δβ mod 2π|, |Δω|·T/2π).
fn cyl_dist(a: [f64; 2], b: [f64; 2], period: f64) -> f64 {
    let db = (a[0] - b[0] + PI).rem_euclid(TAU) - PI;
    db.abs().max((a[1] - b[1]).abs() * period / TAU)
}

/// The rigorous classification of the attractor through `x` (a state at t = 0 mod T) of any
/// driven oscillator; returns the class and the state at the end of the analysis window
/// (again at t ≡ 0 mod T). Uses the half-period map when the system has the symmetry, else P_T.
pub fn rigorous_classify<S: DrivenOscillator + ?Sized>(
    sys: &S,
    x: [f64; 2],
    opts: &ClassifyOptions,
) -> Result<(RigorousClass, [f64; 2])> {
    rigorous_classify_with_section(sys, x, opts).map(|(c, e, _)| (c, e))
}

/// [`rigorous_classify`], also returning the symmetry-reduced section points z_j = R⁻ʲ x(jT/2).
pub fn rigorous_classify_with_section<S: DrivenOscillator + ?Sized>(
    sys: &S,
    x: [f64; 2],
    opts: &ClassifyOptions,
) -> Result<(RigorousClass, [f64; 2], Vec<[f64; 2]>)> {
    opts.validate()?;
    let period = sys.period();
    let sym = sys.half_period_symmetry();
    let fo = FlowOptions::with_tol(opts.tol).sensitivity(Sensitivity::State);
    let steps = 2 * opts.analysis_turns;
    // raw states at t = jT/2 and the symmetry-reduced points z_j = R^{-j} x_j
    let mut raw = Vec::with_capacity(steps + 1);
    let mut z = Vec::with_capacity(steps + 1);
    raw.push(x);
    z.push(x);
    let mut lyap = LyapunovAccumulator::new();
    let mut cur = x;
    for j in 0..steps {
        let t0 = j as f64 * 0.5 * period;
        let t1 = (j + 1) as f64 * 0.5 * period;
        let fl = EventDriven853.flow(sys, t0, cur, t1, &fo)?;
        let jac = fl.jac_x.ok_or_else(|| Error::Integration {
            t: t1,
            reason: "no Jacobian".into(),
        })?;
        lyap.push(&jac);
        cur = fl.x;
        raw.push(fl.x);
        z.push(reduce(sym, fl.x, j + 1));
    }
    let turns = opts.analysis_turns as f64;
    let rotation_number = (raw[steps][0] - raw[0][0]) / (TAU * turns);
    let lyapunov = lyap.estimate(turns, period);
    // candidate periods on the trajectory (only even k without the symmetry)
    let kmax = opts.max_half_periods.min(steps / 2);
    let mut found = at_rest(&raw).then_some(Dynamics::Rest);
    for k in (1..=kmax).filter(|_| found.is_none()) {
        if sym.is_none() && k % 2 == 1 {
            continue;
        }
        let m = (steps - k).min(2 * k.max(4));
        let res = (steps - k - m + 1..=steps - k)
            .map(|j| cyl_dist(z[j + k], z[j], period))
            .fold(0.0, f64::max);
        if res < opts.period_tol {
            if let Some(p) = confirm_period(sys, sym, z[steps], k, opts)? {
                found = Some(p);
                break;
            }
        }
    }
    // over a whole number of orbit periods the rotation number of a periodic orbit is exact
    let rotation_number = match &found {
        Some(Dynamics::Periodic { half_periods, .. }) => {
            let m = (steps / half_periods) * half_periods;
            (raw[m][0] - raw[0][0]) / (TAU * 0.5 * m as f64)
        }
        _ => rotation_number,
    };
    let locked_rn = (rotation_number.abs() - 1.0).abs() < 1e-3;
    let thr = opts.lyapunov_threshold;
    let (dynamics, label) = match found {
        Some(Dynamics::Rest) => (Dynamics::Rest, "rest".to_string()),
        Some(d) => {
            let k = match &d {
                Dynamics::Periodic { half_periods, .. } => *half_periods,
                _ => 0,
            };
            (d, period_label(k))
        }
        None => match lyapunov.per_period {
            Some(l) if l > thr => (Dynamics::Chaotic, "chaos".to_string()),
            Some(l) if l > -thr => (Dynamics::QuasiPeriodic, "QP".to_string()),
            _ => (Dynamics::Unresolved, "?".to_string()),
        },
    };
    let end = raw[steps];
    Ok((
        RigorousClass {
            dynamics,
            label,
            rotation_number,
            locked: locked_rn,
            lyapunov,
        },
        end,
        z,
    ))
}

/// The output never moved: every state at t = jT/2 has ω = 0 and the β of the first (a stick
/// phase keeps β exactly; 1e-12 relative allows for the lift's arithmetic).
fn at_rest(raw: &[[f64; 2]]) -> bool {
    let b0 = raw[0][0];
    raw.iter()
        .all(|x| x[1] == 0.0 && (x[0] - b0).abs() <= 1e-12 * (1.0 + b0.abs()))
}

fn reduce(sym: Option<HalfPeriodSymmetry>, x: [f64; 2], j: usize) -> [f64; 2] {
    // R⁻ʲ x: a shift by j·c for σ = +1 (the gear), the parity of j for σ = −1
    match sym {
        Some(r) => (0..j).fold(x, |v, _| r.invert(v)),
        None => x,
    }
}

/// A confirmed orbit lies within this distance ([`cyl_dist`]) of the candidate point.
const NEWTON_ACCEPT: f64 = 1e-2;
/// Newton gives up once an iterate is this far from the candidate point on the lift (50× the
/// acceptance distance).
const NEWTON_TRUST: f64 = 0.5;

/// Newton on Gᵏ(x) − x − (2πq, 0) = 0 (or P_T^{k/2} without the symmetry) from `x`; returns the
/// periodic orbit if Newton converges close to `x` and the orbit is stable. Candidates are tried
/// in increasing k, so the first confirmed one is the minimal period.
fn confirm_period<S: DrivenOscillator + ?Sized>(
    sys: &S,
    sym: Option<HalfPeriodSymmetry>,
    x: [f64; 2],
    k: usize,
    opts: &ClassifyOptions,
) -> Result<Option<Dynamics>> {
    let period = sys.period();
    let (section, iters) = match sym {
        Some(_) => (Section::HalfPeriod, k),
        None => (Section::Stroboscopic, k / 2),
    };
    let fo = FlowOptions::with_tol(opts.tol.min(1e-10)).sensitivity(Sensitivity::State);
    let mut xi = x;
    let mut res = f64::INFINITY;
    let mut jac = Matrix2::identity();
    for _ in 0..30 {
        let img = match poincare_map(&EventDriven853, sys, section, xi, iters, &fo) {
            Ok(i) => i,
            Err(_) => return Ok(None),
        };
        let j = img.jac_x.unwrap_or_else(Matrix2::identity);
        let q = ((img.x[0] - xi[0]) / TAU).round();
        let r = [img.x[0] - xi[0] - TAU * q, img.x[1] - xi[1]];
        res = r[0].abs().max(r[1].abs() * period / TAU);
        jac = j;
        if res < 1e-9 {
            break;
        }
        let a = j - Matrix2::identity();
        let Some(inv) = a.try_inverse() else {
            return Ok(None);
        };
        let dx = inv * nalgebra::Vector2::new(-r[0], -r[1]);
        if !(dx[0].is_finite() && dx[1].is_finite()) {
            return Ok(None);
        }
        xi = [xi[0] + dx[0], xi[1] + dx[1]];
        // a trust region: an iterate that leaves the neighbourhood of the candidate cannot end
        // within the acceptance distance below, and far from it (β of order 1e9 after a step
        // through a nearly singular G^k − I at a quasi-periodic point) every map costs thousands
        // of steps
        let lift_dist = (xi[0] - x[0])
            .abs()
            .max((xi[1] - x[1]).abs() * period / TAU);
        if lift_dist > NEWTON_TRUST {
            return Ok(None);
        }
    }
    if res >= 1e-7 || cyl_dist(xi, x, period) > NEWTON_ACCEPT {
        return Ok(None);
    }
    let mu = multipliers(&jac);
    let mods = [mu[0].norm(), mu[1].norm()];
    if mods[0] >= 1.0 {
        return Ok(None);
    }
    Ok(Some(Dynamics::Periodic {
        half_periods: k,
        symmetric: sym.is_some() && k % 2 == 1,
        multipliers: mods,
        residual: res,
        orbit: xi,
    }))
}
