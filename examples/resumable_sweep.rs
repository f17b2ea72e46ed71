//! A small Θ × f atlas through the library: semi-static protocol, checkpoints in a folder, stopped
//! after two rows and resumed, then written as CSV/JSON.
//!
//! Run: `cargo run --release --example resumable_sweep -- OUTDIR`
use gearbif::sweep::{Axis, Protocol, SweepOutcome, SweepParam, SweepRunner, SweepSpec};

fn main() -> gearbif::Result<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "atlas-example".into());
    let mut spec = SweepSpec::paper_fig7(
        Axis::range(SweepParam::ThetaDeg, 0.0, 50.0, 10.0)?,
        Axis::range(SweepParam::F, 0.5, 3.0, 0.25)?,
    );
    spec.protocol = Protocol::SemiStatic;
    spec.classify.settle_turns = 200;
    let ckpt = std::path::Path::new(&out).join("checkpoint");
    // first run: "killed" after two rows
    let first = SweepRunner::new(spec.clone())
        .checkpoint(&ckpt)
        .max_new_rows(2)
        .run()?;
    println!("first run: {first:?}");
    // second run: resumes from the checkpoint
    if let SweepOutcome::Complete(res) = SweepRunner::new(spec).checkpoint(&ckpt).run()? {
        res.write(&out)?;
        for p in res.points().filter(|p| p.agree == Some(false)) {
            println!(
                "Θ = {:>4}°, f = {:.2} Hz: flowchart {:>5}, rigorous {:>5} (ρ = {:.3})",
                p.row_value,
                p.f_hz,
                p.paper_class,
                p.class,
                p.rotation_number.unwrap_or(f64::NAN)
            );
        }
        println!("wrote {out}/points.csv and {out}/sweep.json");
    }
    Ok(())
}
