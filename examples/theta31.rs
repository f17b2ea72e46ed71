//! The paper's Fig. 6 simulation statements at Θ = 31°: start at α = 90°, β = 270° (paper
//! convention; 90° physical), 90 settling turns, 10 recorded; both classifications, with the exact
//! event-driven integrator and the paper's fixed-step RK4 (50 steps per period).
//!
//! Run: `cargo run --release --example theta31`
use gearbif::analysis::{classify_point, ClassifyOptions};
use gearbif::integrator::{EventDriven, FixedStep};
use gearbif::model::Gear;

fn main() -> gearbif::Result<()> {
    let opts = ClassifyOptions::paper();
    let fixed = ClassifyOptions {
        rigorous: false,
        ..ClassifyOptions::paper()
    };
    let x0 = [90f64.to_radians(), 0.0];
    println!("f [Hz]  | event-driven: paper class (RMS_fit, THD) / rigorous (λ per period) | RK4 T/50: paper class (RMS_fit, THD)");
    for f in [1.00, 1.07, 1.33, 1.48, 1.63, 1.65, 1.68] {
        let gear = Gear::paper(31.0, f)?.with_alpha0(90f64.to_radians())?;
        let t = std::time::Instant::now();
        let a = classify_point(&gear, x0, &EventDriven, &opts)?;
        let dt = t.elapsed().as_secs_f64();
        let b = classify_point(&gear, x0, &FixedStep::default(), &fixed)?;
        let r = a.rigorous.as_ref().expect("rigorous");
        println!(
            "{f:.2}    | {} ({:.2}°, {:.3}, printed {:.4}) / {} (λ = {:?}, ρ = {:.4}) [{dt:.2} s] | {} ({:.2}°, {:.3})",
            a.paper.class.label(),
            a.paper.rms_fit_deg,
            a.paper.thd,
            a.paper.thd_printed,
            r.label,
            r.lyapunov.per_period,
            r.rotation_number,
            b.paper.class.label(),
            b.paper.rms_fit_deg,
            b.paper.thd,
        );
    }
    Ok(())
}
