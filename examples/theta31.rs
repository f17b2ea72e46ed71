//! The paper's Fig. 6 simulation statements at Θ = 31°: start at α = 90°, β = 270° (paper
//! convention; 90° physical, `paper_fig6_start`, as `gearbif figure fig5` and `fig6`), 90 settling
//! turns, 10 recorded; both classifications, with the exact
//! event-driven integrator and the paper's fixed-step RK4 (50 steps per period); then the same
//! with 1000 settling turns (transients) and from 8 other initial angles (multistability).
//!
//! Run: `cargo run --release --example theta31`
use gearbif::analysis::{classify_point, paper_fig6_start, ClassifyOptions, ThdDefinition};
use gearbif::integrator::{EventDriven, FixedStep};
use gearbif::model::GearParams;

fn main() -> gearbif::Result<()> {
    let opts = ClassifyOptions::paper();
    let fixed = ClassifyOptions {
        rigorous: false,
        ..ClassifyOptions::paper()
    };
    let long = ClassifyOptions {
        settle_turns: 1000,
        ..ClassifyOptions::paper()
    };
    println!("| f [Hz] | flowchart, exact (RMS_fit, THD std / printed) | printed-THD class | rigorous, exact (ρ, λ/period) | flowchart, RK4 T/50 (RMS_fit, THD) | rigorous after 1000 turns | rigorous classes from 8 other β₀ |");
    println!("|---|---|---|---|---|---|---|");
    for f in [1.00, 1.07, 1.33, 1.48, 1.63, 1.65, 1.68] {
        // the start of `gearbif figure fig5` / `fig6`: the same trajectories as those figures
        let (gear, x0) = paper_fig6_start(&GearParams::paper(), 31.0, f)?;
        let a = classify_point(&gear, x0, &EventDriven, &opts)?;
        let b = classify_point(&gear, x0, &FixedStep::default(), &fixed)?;
        let c = classify_point(&gear, x0, &EventDriven, &long)?;
        let r = a.rigorous.as_ref().expect("rigorous");
        let printed =
            gearbif::analysis::harmonic::paper_class(&a.paper.fit, ThdDefinition::Printed);
        let mut others = Vec::new();
        for k in 0..8 {
            // physical β₀ (the same set of angles as 22.5° + 45° k in the paper convention)
            let b0 = (45.0 * k as f64 + 22.5f64).to_radians();
            let o = classify_point(&gear, [b0, 0.0], &EventDriven, &opts)?;
            others.push(o.rigorous.expect("rigorous").label);
        }
        let lam = r
            .lyapunov
            .per_period
            .map(|l| format!("{l:.3}"))
            .unwrap_or("-inf".into());
        println!(
            "| {f:.2} | {} ({:.2}°, {:.3} / {:.4}) | {} | {} (ρ = {:.4}, λ = {lam}) | {} ({:.2}°, {:.3}) | {} | {} |",
            a.paper.class.label(),
            a.paper.rms_fit_deg,
            a.paper.thd,
            a.paper.thd_printed,
            printed.label(),
            r.label,
            r.rotation_number,
            b.paper.class.label(),
            b.paper.rms_fit_deg,
            b.paper.thd,
            c.rigorous.expect("rigorous").label,
            others.join(", "),
        );
    }
    Ok(())
}
