//! Global events located by bisection with a transient rule, each checked against the rule (how far
//! the result moves when the transient is doubled and quadrupled): the return to the symmetric T/2
//! state at Θ = 25° (moves < 1e-3 Hz) and the re-locking of the slip-through state at Θ = 0 (moves
//! by ~1e-2 Hz: located only to that accuracy) on slow down-sweeps.

use gearbif::analysis::global_events::{bisect_sweep, mean_winding, relax, TransientRule, Verdict};
use gearbif::integrator::{EventDriven, FlowOptions};
use gearbif::maps::{poincare_map, Section};
use gearbif::model::{Gear, GearParam};
use std::f64::consts::{FRAC_PI_2, TAU};

const TOL: f64 = 1e-9;

fn rules() -> [TransientRule; 3] {
    [
        TransientRule {
            transient: 200,
            window: 100,
        },
        TransientRule {
            transient: 400,
            window: 100,
        },
        TransientRule {
            transient: 800,
            window: 200,
        },
    ]
}

fn spread(v: &[f64]) -> f64 {
    v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
}

#[test]
fn theta0_relock_frequency_located_with_its_transient_rule_spread() {
    let coarse = rules()[0];
    // the coarse down-sweep of the docs (0.5 Hz steps from 42 Hz, above f_c = 39.84 Hz)
    let mut x = [FRAC_PI_2, TAU * 42.0];
    let mut f = 42.0;
    let mut last_slipping = None;
    let mut first_locked = None;
    while f > 1.0 {
        let g = Gear::paper(0.0, f).unwrap();
        let (w, y) = mean_winding(&g, relax(&g, x, &coarse, TOL).unwrap(), &coarse, TOL).unwrap();
        if (w - 1.0).abs() < 1e-6 {
            first_locked = Some(f);
            break;
        }
        last_slipping = Some((f, y));
        x = y;
        f -= 0.5;
    }
    let (f_old, x_old) = last_slipping.unwrap();
    let f_new = first_locked.expect("the sweep re-locks above 1 Hz");
    assert_eq!(f_old - f_new, 0.5);
    let base = Gear::paper(0.0, f_old).unwrap();
    let mut vals = Vec::new();
    for rule in rules() {
        let judge = |g: &Gear, y: [f64; 2]| {
            let (w, s) = mean_winding(g, y, &rule, TOL)?;
            Ok(Verdict {
                is_new: (w - 1.0).abs() < 1e-3,
                state: s,
            })
        };
        let r = bisect_sweep(
            &base,
            GearParam::F,
            f_old,
            f_new,
            x_old,
            &rule,
            judge,
            1e-4,
            TOL,
        )
        .unwrap();
        println!(
            "re-lock, rule {:?}: between {:.5} (locked) and {:.5} Hz (slipping), {} trials",
            rule, r.new_side, r.old_side, r.trials
        );
        assert!(r.new_side >= f_new && r.old_side <= f_old);
        assert!((r.old_side - r.new_side).abs() <= 1e-4);
        vals.push(r.value());
    }
    println!(
        "re-lock: coarse sweep slipping at {f_old}, locked at {f_new}; spread over rules {:.2e} Hz",
        spread(&vals)
    );
    // measured: 3.6764, 3.6875, 3.6778 Hz for transients 200, 400, 800 periods — the re-lock moves
    // by ~1e-2 Hz with the transient rule (long, basin-dependent transients of the slip-through
    // state), so 1e-3 Hz is NOT reached; this asserts the spread actually found
    assert!(
        spread(&vals) < 2e-2,
        "re-lock frequency moves with the transient rule: {vals:?}"
    );
    assert!(vals.iter().all(|v| (3.6..3.7).contains(v)), "{vals:?}");
}

#[test]
fn theta25_return_to_t2_on_the_down_sweep_located() {
    // down-sweep from 2.40 Hz (where the symmetric orbit is unstable, so the sweep starts on the
    // T-state): T down to the flip at 1.8549 Hz, then not period 1, then T/2 again (docs: at 1.80)
    let coarse = rules()[0];
    let o = FlowOptions::with_tol(TOL);
    let symmetric = |g: &Gear, y: [f64; 2]| -> gearbif::Result<Verdict> {
        // on the symmetric orbit G(x) = x + (π − c) with R(β, ω) = (β + π, ω): |G(x) − x| small
        let gx = poincare_map(&EventDriven, g, Section::HalfPeriod, y, 1, &o)?.x;
        let d = ((gx[0] - y[0]).rem_euclid(TAU)).min(TAU - (gx[0] - y[0]).rem_euclid(TAU));
        Ok(Verdict {
            is_new: d.hypot(gx[1] - y[1]) < 1e-6,
            state: y,
        })
    };
    let mut x = [2.98, 15.0];
    let mut f_old = None;
    let mut f_new = None;
    let mut f: f64 = 2.40;
    while f > 1.7 {
        let g = Gear::paper(25.0, f).unwrap();
        x = relax(&g, x, &coarse, TOL).unwrap();
        if symmetric(&g, x).unwrap().is_new {
            f_new = Some(f);
            break;
        }
        f_old = Some((f, x));
        f = ((f - 0.02) * 100.0).round() / 100.0;
    }
    let (fo, xo) = f_old.unwrap();
    assert!(fo < 1.855, "the sweep left the T-state only at {fo}");
    let fn_ = f_new.expect("falls back onto the symmetric orbit");
    let base = Gear::paper(25.0, fo).unwrap();
    let mut vals = Vec::new();
    for rule in rules() {
        let r = bisect_sweep(
            &base,
            GearParam::F,
            fo,
            fn_,
            xo,
            &rule,
            symmetric,
            1e-5,
            TOL,
        )
        .unwrap();
        println!(
            "return to T/2, rule {:?}: between {:.6} (T/2) and {:.6} Hz, {} trials",
            rule, r.new_side, r.old_side, r.trials
        );
        vals.push(r.value());
    }
    println!(
        "return to T/2: coarse sweep not T/2 at {fo:.2}, T/2 at {fn_:.2}; spread {:.2e} Hz",
        spread(&vals)
    );
    // The chaotic transients near the crisis amplify last-bit changes of the arithmetic: a
    // right-hand side and step-size controller differing in the last bit moved the N = 200 value
    // by 9e-4 Hz (docs/continuation.md), so the stated error is ±1e-3 Hz and the bound 2e-3.
    assert!(spread(&vals) < 2e-3, "{vals:?}");
}
