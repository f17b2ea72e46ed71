//! Θ = 0: where the slip-through state re-locks on a slow down-sweep. The slip-through state is a
//! limit cycle of the co-rotating system (δ = β − α); it ends in a homoclinic bifurcation at the
//! saddle (the unstable lock). Three routes: the homoclinic frequency by bisection on the fate of
//! the saddle's unstable manifold (two tolerances, two start offsets); the cycle's duration near it
//! against the logarithmic law τ ≈ −ln(f − f_h)/λ_u; linear down-ramps of the drive at decreasing
//! rates, extrapolated to rate 0.
//!
//! Run: `cargo run --release --example theta0_relock`.

use gearbif::analysis::relock::{homoclinic_frequency, ramp_relock, saddle, slip_cycle, SlipCycle};
use gearbif::model::Gear;

fn main() -> gearbif::Result<()> {
    let t0 = std::time::Instant::now();
    let base = Gear::paper(0.0, 3.7)?;
    // 1. the homoclinic frequency, exact up to the bracket, tolerance and offset
    let mut fh = Vec::new();
    for (eps, tol) in [(1e-6, 1e-9), (1e-7, 1e-11), (1e-8, 1e-12)] {
        let h = homoclinic_frequency(&base, 3.6, 3.7, eps, tol, 1e-11)?;
        println!(
            "homoclinic: eps {eps:.0e}, tol {tol:.0e}: f_h = {:.11} Hz (bracket {:.1e})",
            h.value(),
            h.above - h.below
        );
        fh.push(h.value());
    }
    let f_h = fh[2];
    let spread = fh.iter().map(|v| (v - f_h).abs()).fold(0.0, f64::max);
    println!("f_h = {f_h:.10} Hz, change with tolerance/offset {spread:.1e} Hz");
    // 2. the slip cycle followed down towards f_h: τ against −ln(f − f_h)/λ_u
    let d0 = -std::f64::consts::FRAC_PI_2;
    // natural continuation from the cycle at 3.78 Hz towards f_h: steps of at most a quarter of
    // the distance f − f_h, the previous cycle as the guess, halved when Newton fails; recorded at
    // f − f_h = 0.1·10^(−k/2)
    let mut cur = (
        3.78,
        slip_cycle(&base.with_f(3.78)?, d0, (-2.738, 0.390), 1e-11)?,
    );
    let mut cycles: Vec<(f64, SlipCycle)> = Vec::new();
    let mut k = 0;
    let mut df: f64 = 0.01;
    while k <= 6 && df > 1e-12 {
        let target = f_h + 0.1 * 10f64.powf(-0.5 * k as f64);
        let f = (cur.0 - df.min(0.25 * (cur.0 - f_h))).max(target);
        let guess = (cur.1.omega0, cur.1.duration);
        match slip_cycle(&base.with_f(f)?, d0, guess, 1e-11) {
            Ok(c) => {
                cur = (f, c);
                df *= 1.5;
                if f == target {
                    cycles.push(cur);
                    k += 1;
                }
            }
            Err(_) => df *= 0.5,
        }
    }
    println!("cycle followed to f − f_h = {:.1e} Hz", cur.0 - f_h);
    let lam = saddle(&base.with_f(f_h)?)?.unstable;
    println!(
        "saddle at f_h: λ_u = {lam:.6} 1/s (ln 10/(2λ_u) = {:.6} s)",
        10f64.ln() / (2.0 * lam)
    );
    let halves: Vec<_> = cycles.iter().collect();
    for w in halves.windows(2) {
        let ((f1, c1), (f2, c2)) = (w[0], w[1]);
        println!(
            "cycle at f_h + {:.1e}: τ = {:.9} s, μ = {:.3e}, winding {:.5}; Δτ per half decade {:.6} s",
            f2 - f_h,
            c2.duration,
            c2.multiplier,
            c2.winding,
            c2.duration - c1.duration
        );
        let _ = f1;
    }
    // 3. slow down-ramps from the cycle at 3.70 Hz to 3.66 Hz
    let start = slip_cycle(&base.with_f(3.70)?, d0, (-2.90, 0.485), 1e-11)?;
    let g0 = base.with_f(3.70)?;
    let x0 = [d0 + g0.alpha(0.0), start.omega0];
    let mut rows = Vec::new();
    for rate in [-1e-2, -3e-3, -1e-3, -3e-4, -1e-4, -3e-5, -1e-5] {
        let t = std::time::Instant::now();
        let r = ramp_relock(&g0, x0, rate, 3.66, 1e-10)?;
        println!(
            "ramp {rate:.0e} Hz/s: last slip at {:.7} Hz (− f_h = {:+.2e}), {} slips, |δ − δ_s| at the end {:.1e} rad, {:.1?}",
            r.last_slip,
            r.last_slip - f_h,
            r.slips,
            r.lock_offset,
            t.elapsed()
        );
        rows.push(r);
    }
    println!("total {:.1?}", t0.elapsed());
    Ok(())
}
