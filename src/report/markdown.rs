//! The report's text: each function writes one section's Markdown from its data
//! ([`super::compute`]) and the links of the figures drawn for it ([`super::figures`]). No
//! computation happens here beyond formatting.

use super::compute::{
    Advice, Bifurcations, Derived, LockBranchCheck, MapSummary, Outcome, SpecialRow,
    BIFURCATION_THETA_DEG,
};
use crate::continuation::two_param::Curve;
use crate::model::GearParams;
use crate::sweep::SweepResult;

/// A value with `prec` decimals, or "—".
pub fn fmt_opt(v: Option<f64>, prec: usize) -> String {
    match v {
        Some(x) => format!("{x:.prec$}"),
        None => "—".into(),
    }
}

/// A multiplier (re, im): real with 6 decimals, complex with 4.
pub fn fmt_mu(z: [f64; 2]) -> String {
    if z[1] == 0.0 {
        format!("{:.6}", z[0])
    } else {
        format!("{:.4}{:+.4}i", z[0], z[1])
    }
}

/// Both multipliers.
pub fn fmt_mus(m: &[[f64; 2]; 2]) -> String {
    format!("{}, {}", fmt_mu(m[0]), fmt_mu(m[1]))
}

/// Markdown image links of `figures` ((file, alt) pairs relative to the report folder).
pub fn figure_links(figures: &[(String, String)]) -> String {
    figures
        .iter()
        .map(|(f, alt)| format!("\n![{alt}]({f})\n"))
        .collect()
}

/// Section "Derived quantities".
pub fn derived(d: &Derived) -> String {
    format!(
        "| quantity | value | formula |\n|---|---|---|\n\
         | c | {:.5e} J | μ0 m1 m2 / (4π r³) |\n\
         | g | {:.3} s⁻² | c / I |\n\
         | Δ (this gear) | {:.4} | cos Θ cos Φ − 2 sin Θ sin Φ |\n\
         | f_c | {} Hz | (g − η)/(2πζ), lock loss at Δ = ±1 |\n\
         | η/g | {:.4} | static load; lock angle offset arcsin(η/g) = {:.2}° |\n\
         | cogging-free parallel shaft angles | Θ = {:.2}° (Δ = +1), {:.2}° (Δ = −1) | Δ = 1 − 3 sin²Θ |\n\
         | largest cogging (Δ = 0) | Θ = {:.2}° | sense of rotation flips |\n",
        d.coupling_j,
        d.g,
        d.delta,
        fmt_opt(d.f_c_hz, 3),
        d.eta_over_g,
        d.static_offset_deg,
        d.theta_cogging_free_deg[0],
        d.theta_cogging_free_deg[1],
        d.theta_max_cogging_deg
    )
}

/// Section "Analytic lock branch and f_c".
pub fn lock_branch(c: &LockBranchCheck) -> String {
    let mut md = String::from(
        "At Θ = 0 (Δ = 1) the locked orbit has a constant δ with sin δ = (2πfζ + η)/g; \
         stable δ = 180° − arcsin(…) (physical convention; the paper's convention adds 180°). \
         The paper's eq. `delta_lock` and its Fig. 10a give 180° + arcsin(…), i.e. α − β = \
         180° − δ(paper convention) (model.md, erratum); the figure below plots that. The branch \
         ends in a saddle-node at f_c. Simulated: the upward semi-static run of the Θ = 0 \
         hysteresis loop (mean δ over the window).\n\n\
         | f [Hz] | analytic δ (paper conv.) [°] | simulated δ_avg (paper conv.) [°] | analytic α − β (paper's eq. `delta_lock`) [°] | |μ| of P_T |\n|---|---|---|---|---|\n",
    );
    for r in &c.points {
        if (r.f_hz as usize) % 5 == 0 || r.f_hz < 1.5 {
            md += &format!(
                "| {:.1} | {:.4} | {:.4} | {:.4} | {:.4} |\n",
                r.f_hz,
                r.analytic_deg,
                r.simulated_deg,
                crate::analysis::harmonic::paper_figure_delta_deg(r.analytic_deg),
                r.multiplier
            );
        }
    }
    md += &format!(
        "\nLargest |simulated − analytic| over the {} locked points: {:.2e}°. f_c = {} Hz.\n",
        c.points.len(),
        c.max_deviation_deg,
        fmt_opt(c.f_c_hz, 3)
    );
    md
}

fn special_note(r: &SpecialRow) -> String {
    match (r.events_before, r.events_after, r.jump_multiplier) {
        (Some(b), Some(a), Some(m)) => format!(
            "(crossings, sticks) {b:?} → {a:?}, μ₁ {} → {}{}{}",
            fmt_mu(m[0]),
            fmt_mu(m[1]),
            r.crosses
                .as_ref()
                .map(|c| format!("; a multiplier jumps across the {c} value"))
                .unwrap_or_default(),
            if r.note.is_empty() {
                String::new()
            } else {
                format!("; {}", r.note)
            }
        ),
        _ => r.note.clone(),
    }
}

fn boundary_table(gear: &GearParams, curves: &[(String, Curve)]) -> String {
    let mut thetas: Vec<f64> = Vec::new();
    for (_, c) in curves {
        for (i, p) in c.points.iter().enumerate() {
            let on5 = (p.along / 5.0 - (p.along / 5.0).round()).abs() < 1e-9;
            if on5 || i + 1 == c.points.len() || i == 0 {
                thetas.push(p.along);
            }
        }
    }
    thetas.sort_by(f64::total_cmp);
    thetas.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let mut md =
        String::from("| Θ [°] | Δ | f_c, p = +1 [Hz] | f_c, p = −1 [Hz] |\n|---|---|---|---|\n");
    let exact = |c: &Curve, th: f64| {
        c.points
            .iter()
            .find(|p| (p.along - th).abs() < 1e-9)
            .map(|p| p.free)
    };
    for th in &thetas {
        let cell = |p: i32| {
            curves
                .iter()
                .find(|(_, c)| c.spec.winding == p)
                .and_then(|(_, c)| exact(c, *th))
        };
        md += &format!(
            "| {:.4} | {:+.4} | {} | {} |\n",
            th,
            gear.with_parallel_shafts_deg(*th).delta(),
            fmt_opt(cell(1), 9),
            fmt_opt(cell(-1), 9)
        );
    }
    for (label, c) in curves {
        let (a, b) = c
            .points
            .iter()
            .map(|p| p.along)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        md += &format!(
            "\n{label}: {} points over Θ = {:.3}–{:.3}°, largest Newton error estimate \
             {:.1e} Hz{}.",
            c.points.len(),
            a,
            b,
            c.points.iter().map(|p| p.precision).fold(0.0, f64::max),
            c.stopped
                .as_ref()
                .map(|s| format!("; stopped {s}"))
                .unwrap_or_default()
        );
    }
    md + "\n"
}

/// Section "Located bifurcations (continuation)"; `figures` are placed after the f_c(Θ) table,
/// `figure_errors` reported at the end.
pub fn bifurcations(
    gear: &GearParams,
    b: &Bifurcations,
    figures: &[(String, String)],
    figure_errors: &[String],
) -> String {
    let mut md = String::from(
        "Pseudo-arclength continuation of periodic orbits with located special points \
         (`gearbif::continuation`, docs/continuation.md). Frequencies are located to the stated \
         precision (half-width of the final bracket plus the corrector tolerance; integrator \
         tolerance 1e-11). Multipliers are those of the orbit's map: the half-period map G on a \
         symmetric branch (μ_G = −1 is a symmetry-breaking pitchfork of P_T), P_T on an \
         asymmetric branch.\n\n### Θ = 0: fold of the lock branch\n\n",
    );
    match &b.theta0 {
        Outcome::Done(f) => {
            md += &format!(
                "The lock branch, continued in f from {:.3} Hz ({} points, {} map evaluations), \
                 folds at **f = {:.10} ± {:.1e} Hz**; analytic f_c = (g − η)/(2πζ) = {:.10} Hz; \
                 difference {:+.2e} Hz. At the fold δ = {:.6}° (paper convention), μ_G = {}.\n",
                f.start_f_hz,
                f.points,
                f.map_evaluations,
                f.fold_f_hz,
                f.precision_hz,
                f.analytic_f_c_hz,
                f.difference_hz,
                f.delta_deg_paper,
                fmt_mus(&f.multipliers)
            )
        }
        Outcome::Failed { error } => md += &format!("**Failed:** {error}\n"),
    }
    let t = &b.theta25;
    md += &format!(
        "\n### Θ = {}°, {}–{} Hz: every special point\n\n",
        t.theta_deg, t.f_range_hz[0], t.f_range_hz[1]
    );
    match &t.symmetric {
        Outcome::Done(s) => {
            md += &format!(
                "Symmetric branch (fixed points of G, winding 1): {} points, {} map evaluations, \
                 stop {}.",
                s.points, s.map_evaluations, s.stop
            );
            if t.asymmetric.is_empty() {
                md += " No supercritical symmetry-breaking point: no asymmetric branch continued.";
            }
            for (f, a) in &t.asymmetric {
                match a {
                    Outcome::Done(a) => {
                        md += &format!(
                            " Asymmetric branch (P_T, winding {}) switched onto at the \
                             supercritical point {f:.6} Hz: {} points, {} map evaluations, stop {}.",
                            a.winding, a.points, a.map_evaluations, a.stop
                        )
                    }
                    Outcome::Failed { error } => md += &format!(" **Failed:** {error}."),
                }
            }
            md += "\n\n| branch | type | f [Hz] | precision [Hz] | multipliers | note |\n\
                   |---|---|---|---|---|---|\n";
            for r in &t.specials {
                md += &format!(
                    "| {} | {} | {:.9} | {:.1e} | {} | {} |\n",
                    r.branch,
                    r.kind,
                    r.f_hz,
                    r.precision_hz,
                    fmt_mus(&r.multipliers),
                    special_note(r)
                );
            }
        }
        Outcome::Failed { error } => md += &format!("**Failed:** {error}\n"),
    }
    md += &format!(
        "\n### Lock-loss boundary f_c(Θ)\n\nFold of the symmetric locked orbit followed in Θ \
         (parallel shafts, {}° steps, halved where Newton fails): forward lock p = +1 from Θ = 0, \
         reversed lock p = −1 from Θ = 54.7356° (Δ = −1), each started at the analytic f_c. \
         Above f_c(Θ) the lock of that sense does not exist.\n\n",
        b.boundary.step_deg
    );
    match &b.boundary.curves {
        Ok(curves) => md += &boundary_table(gear, curves),
        Err(e) => md += &format!("**Failed:** lock-loss boundary f_c(Θ): {e}\n"),
    }
    md += &figure_links(figures);
    for e in figure_errors {
        md += &format!("\n**Failed:** figures: {e}\n");
    }
    md += &format!(
        "\nComputing time: Θ = 0 fold {:.2} s, Θ = {BIFURCATION_THETA_DEG}° branches {:.2} s.\n",
        b.seconds_theta0, b.seconds_theta25
    );
    md
}

/// Section "Stability and classification map".
pub fn map(res: &SweepResult, s: &MapSummary) -> String {
    let cols = &res.spec.cols.values;
    format!(
        "Semi-static ramp-up: for each Θ the drive frequency rises through {} log-spaced values \
         from {:.2} to {:.1} Hz, carrying the state, {} settling turns per step, start α = {}°, \
         β = {}° (paper convention). {} points: {} symmetric periodic (the paper's T/2), {} \
         asymmetric periodic (T, kT), {} chaotic (λ_max > {} per period), {} quasi-periodic, {} \
         unresolved; {} points slip (|rotation number| ≠ 1). The paper's flowchart and the rigorous \
         class disagree at {} points.\n",
        cols.len(),
        cols[0],
        cols[cols.len() - 1],
        res.spec.classify.settle_turns,
        res.spec.alpha0_deg,
        res.spec.beta0_deg,
        s.points,
        s.symmetric,
        s.asymmetric,
        s.chaotic,
        res.spec.classify.lyapunov_threshold,
        s.quasi_periodic,
        s.unresolved,
        s.slipping,
        s.disagree
    )
}

fn list_deg(v: &[f64]) -> String {
    if v.is_empty() {
        "none".to_string()
    } else {
        v.iter()
            .map(|t| format!("{t:.0}°"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Section "Operating advice".
pub fn advice(a: &Advice, gear: &GearParams) -> String {
    let mut md = format!(
        "A point is a *good operating point* if the output is locked (|rotation number| = 1), \
         periodic and RMS_δ ≤ {}°. Safe frequency: the highest f of the ramp-up up to which \
         every step was good (a property of this ramp: {} steps of {:.1} % each; finer ramps keep \
         the lock longer near f_c).",
        a.smooth_rms_deg, a.ramp_steps, a.ramp_step_percent
    );
    if a.with_boundary {
        md += " Lock-loss limit: f_c(Θ) of the lock in the gear's natural sense (forward, p = +1, \
               for Δ ≥ 0; reversed, p = −1, for Δ < 0), located by continuation (section \
               *Located bifurcations*); above it that lock does not exist, so it bounds every safe \
               frequency from above. Recommended limit: the lower of the two; — where either is \
               missing (no good ramp step, or Θ outside the range of the computed f_c(Θ) curve).\n\n\
               | Θ [°] | Δ | safe up to f (ramp) [Hz] | lock-loss limit f_c(Θ) [Hz] | lock | recommended: below f [Hz] |\n\
               |---|---|---|---|---|---|\n";
        for (s, l) in a.safe_f_hz.iter().zip(&a.lock_loss_limits) {
            md += &format!(
                "| {:.0} | {:+.3} | {} | {} | {:+} | {} |\n",
                s.theta_deg,
                l.delta,
                fmt_opt(s.f_hz, 2),
                fmt_opt(l.f_c_hz, 3),
                l.winding,
                fmt_opt(l.recommended_below_hz, 2)
            );
        }
        match &a.boundary_error {
            None => {
                let above: Vec<String> = a
                    .ramp_safe_above_f_c_theta_deg
                    .iter()
                    .map(|t| format!("Θ = {t:.0}°"))
                    .collect();
                md += &format!(
                    "\nRamp-safe frequencies above the lock-loss limit: {} (a locked ramp step \
                     above f_c(Θ) would be locked in the other sense).\n",
                    if above.is_empty() {
                        "none".to_string()
                    } else {
                        above.join(", ")
                    }
                );
            }
            Some(e) => md += &format!("\nf_c(Θ) could not be computed: {e}\n"),
        }
    } else {
        md += "\n\n| Θ [°] | Δ | safe up to f [Hz] |\n|---|---|---|\n";
        for s in &a.safe_f_hz {
            md += &format!(
                "| {:.0} | {:+.3} | {} |\n",
                s.theta_deg,
                gear.with_parallel_shafts_deg(s.theta_deg).delta(),
                fmt_opt(s.f_hz, 2)
            );
        }
    }
    for r in &a.theta_ranges {
        md += &format!(
            "\nShaft angles safe up to at least {} Hz: {}.",
            r.f_min_hz,
            list_deg(&r.theta_deg)
        );
    }
    md += &format!(
        "\n\nWorst shaft angle of the grid: Θ = {}° (largest cogging at Δ = 0, Θ = 35.26°).\n\n\
         Lock loss at Θ = 0 (the loop of `gearbif figure fig10`): going up, the lock is lost at {} \
         Hz (f_c = {} Hz); coming down, the output still slips at {} Hz and is locked again at {} \
         Hz. Between these the gear is bistable: **to be safe against slip-through, operate below \
         {} Hz**, or restart from standstill after an overload. A stronger coupling g raises \
         both.\n",
        fmt_opt(a.worst_theta_deg, 0),
        fmt_opt(a.lock_lost_up_hz, 1),
        fmt_opt(a.f_c_theta0_hz, 2),
        fmt_opt(a.last_slip_down_hz, 1),
        fmt_opt(a.relock_down_hz, 1),
        fmt_opt(a.relock_down_hz, 1),
    );
    md
}
