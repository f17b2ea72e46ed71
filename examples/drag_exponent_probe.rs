//! The drag family (`power_law_drag`: base terms, q and the exponent p) refitted to convergence on
//! a recording set's judging windows from given starts of p, then (unless the last argument is 0)
//! profiled over p: the probe behind docs/diagnosis.md, "Shape parameters".
//!
//! ```sh
//! gearbif campaign --effects power_law_drag --sizes 2 --seeds 1 --first-seed 1 --set ci \
//!     --keep-sets --out drag
//! cargo run --release --example drag_exponent_probe -- \
//!     drag/sets/power_law_drag__L2__s1 3.2 1.5,2 1
//! ```
//!
//! Arguments: the set, the start of q (s⁻², the drag at 4 rad/s), the starts of p
//! (comma-separated), and 1 (profile) or 0.
use gearbif::identification::diagnose::{fit_base, prepare, DiagnoseOptions};
use gearbif::identification::judge::Folds;
use gearbif::identification::model::Shape;
use gearbif::identification::profile::{delta_chi2, profile_shape};
use gearbif::identification::regression::{Term, BASE_TERMS};
use gearbif::identification::select::refit_to_convergence;
use gearbif::identification::shooting::{
    Reselect, ShootingOptions, SimModel, Win, CONVERGED_PATIENCE,
};
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 4 {
        eprintln!("usage: drag_exponent_probe SET Q0 P0[,P0...] [1|0]");
        std::process::exit(2);
    }
    let dir = &a[1];
    let q0: f64 = a[2].parse().unwrap();
    let starts: Vec<f64> = a[3].split(',').map(|x| x.parse().unwrap()).collect();
    let do_profile = a.get(4).map(|s| s == "1").unwrap_or(true);
    let set = gearbif::io::recordings::read_set(dir).unwrap();
    let opts = DiagnoseOptions::default();
    let prep = prepare(&set, &opts, &gearbif::progress::Silent).unwrap();
    let folds = Folds::new(&prep.runs, 4);
    let base = fit_base(&prep, &set, &opts, &folds, &gearbif::progress::Silent).unwrap();
    let st = base.state.as_ref().unwrap();
    let mut terms = BASE_TERMS.to_vec();
    terms.extend([Term::Quad, Term::Shape(Shape::DragExponent)]);
    let model = SimModel::of_terms(&prep.runs, base.geo, terms, opts.tol);
    let sopts = ShootingOptions {
        patience: CONVERGED_PATIENCE,
        reselect: Reselect::Always,
        ..ShootingOptions::default()
    };
    println!("base theta {:?}", &st.fit.theta);
    let mut last = None;
    for &p0 in &starts {
        let mut theta0: Vec<f64> = st.fit.theta[..4].to_vec();
        theta0.extend([q0, p0]);
        let t0 = Instant::now();
        let f = refit_to_convergence(&model, &theta0, &base.wins, &sopts).unwrap();
        let chi_used: f64 = f.resid.iter().map(|r| r * r).sum();
        let (all, _) = f.window_chi2(&model, &base.wins);
        let chi_all: f64 = all.iter().flatten().sum();
        println!(
            "start p = {p0}: theta {:?}\n  err {:?}\n  used {} of {}, chi2 used {:.2}, chi2 all {:.2} ({} windows), converged {}, inflation {:.3}, {:.1} s",
            f.theta,
            f.err,
            f.used.len(),
            base.wins.len(),
            chi_used,
            chi_all,
            all.iter().flatten().count(),
            f.converged,
            f.inflation,
            t0.elapsed().as_secs_f64()
        );
        last = Some(f);
    }
    if !do_profile {
        return;
    }
    let f = last.unwrap();
    let wins: Vec<Win> = f.used.iter().map(|&(w, _)| base.wins[w].clone()).collect();
    let popts = ShootingOptions {
        reselect: Reselect::Never,
        ..sopts
    };
    let fit = |m: &SimModel, th: &[f64]| -> Option<(f64, Vec<f64>)> {
        let g = refit_to_convergence(m, th, &wins, &popts)?;
        let c: f64 = g
            .window_chi2(m, &wins)
            .0
            .iter()
            .map(|c| c.unwrap_or(f64::INFINITY))
            .sum();
        Some((c, g.theta))
    };
    let k = 5;
    let d = delta_chi2(&f, k);
    let t0 = Instant::now();
    let pr = profile_shape(&model, &f.theta, k, d, &fit).unwrap();
    println!(
        "profile from the last fit: p = {:.4}, interval {:?}, open {:?}, delta {:.3}, chi2 min {:.2}, {:.1} s",
        pr.value,
        pr.interval,
        pr.open,
        pr.delta,
        pr.chi2_min,
        t0.elapsed().as_secs_f64()
    );
    for (v, c) in &pr.points {
        println!("  {v:.4} {c:.3}");
    }
    println!("best theta {:?}", pr.best);
}
