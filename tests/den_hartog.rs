//! The second worked system: Den Hartog's harmonically forced oscillator with Coulomb and viscous
//! friction, continued in the forcing frequency by the generic continuation and compared with the
//! closed-form continuous-motion steady state and the frequency where stops begin.

use gearbif::continuation::{Continuation, ContinuationOptions, SpecialKind};
use gearbif::integrator::{EventDriven, FlowMethod, DEFAULT_METHOD};
use gearbif::model::den_hartog::{
    den_hartog_coulomb_amplitude, den_hartog_coulomb_stop_ratio, non_stop_orbit,
    stop_boundary_frequency,
};
use gearbif::model::{CoulombOscillator, CoulombParam};
use gearbif::orbits::{shoot, OrbitSpec, ShootingOptions};
use std::f64::consts::TAU;

/// ω₀ = 2π (f₀ = 1 Hz), ξ = 0.05, μ = 0.3, F = 1.
fn oscillator(f: f64) -> CoulombOscillator {
    CoulombOscillator::new(TAU, 0.05, 0.3, 1.0, f).unwrap()
}

#[test]
fn closed_form_reduces_to_den_hartog_coulomb_formula() {
    // ξ = 0: the boundary-value solution against Den Hartog's U, V formula (two derivations)
    for &f in &[0.6, 0.8, 1.3, 2.0, 3.5] {
        let osc = CoulombOscillator::new(TAU, 0.0, 0.3, 1.0, f).unwrap();
        let x = non_stop_orbit(&osc).unwrap().amplitude;
        let dh = den_hartog_coulomb_amplitude(&osc).unwrap();
        assert!((x - dh).abs() < 1e-12 * dh.max(1.0), "f = {f}: {x} vs {dh}");
    }
}

#[test]
fn closed_form_is_the_shooting_orbit() {
    let sh = ShootingOptions {
        tol: 1e-12,
        newton_tol: 1e-11,
        ..Default::default()
    };
    for &f in &[0.9, 1.0, 1.5, 2.5] {
        let osc = oscillator(f);
        let dh = non_stop_orbit(&osc).unwrap();
        assert!(dh.is_valid(), "f = {f}");
        let x0 = dh.state(0.0);
        let o = shoot(&osc, &OrbitSpec::symmetric(0), [x0[0] + 0.01, x0[1]], &sh).unwrap();
        assert!(
            (o.x[0] - x0[0]).abs() < 1e-9,
            "f = {f}: {:?} vs {x0:?}",
            o.x
        );
        assert!(
            (o.x[1] - x0[1]).abs() < 1e-8,
            "f = {f}: {:?} vs {x0:?}",
            o.x
        );
        assert_eq!((o.events.crossings, o.events.sticks), (1, 0));
    }
}

#[test]
fn continuation_in_f_follows_den_hartog_and_locates_the_onset_of_stops() {
    let f_start = 2.0;
    let osc = oscillator(f_start);
    let x0 = non_stop_orbit(&osc).unwrap().state(0.0);
    let opts = ContinuationOptions {
        ds: -0.05,
        ds_max: 0.1,
        param_min: 0.3,
        param_max: 2.0,
        ..Default::default()
    };
    let b = Continuation::new(osc, CoulombParam::F, OrbitSpec::symmetric(0), x0, opts)
        .unwrap()
        .run(None)
        .unwrap();
    let ns: Vec<_> = b.specials_of(SpecialKind::Nonsmooth).collect();
    assert!(!ns.is_empty(), "{:?}", b.specials);
    let onset = ns[0];
    let f_b = stop_boundary_frequency(&osc, 0.45, 2.0, 1e-13).unwrap();
    eprintln!(
        "onset of stops: continuation {} ± {:e}, closed form {f_b}, difference {:e}",
        onset.param,
        onset.precision,
        onset.param - f_b
    );
    assert!((onset.param - f_b).abs() < onset.precision + 1e-9);
    let jump = onset.jump.as_ref().unwrap();
    assert_eq!(jump.events_before.signature(), (1, 0));
    assert!(jump.events_after.sticks > 0);
    // every point on the non-stop side is Den Hartog's steady state
    let mut n = 0;
    let mut worst: f64 = 0.0;
    for p in b.points.iter().filter(|p| p.param > onset.param) {
        let dh = non_stop_orbit(&oscillator(p.param)).unwrap();
        assert!(dh.is_valid());
        let x = dh.state(0.0);
        worst = worst
            .max((p.x[0] - x[0]).abs())
            .max((p.x[1] - x[1]).abs() / TAU);
        n += 1;
    }
    eprintln!("{n} non-stop points, worst state difference {worst:e}");
    assert!(n >= 10);
    assert!(worst < 1e-8, "{worst}");
}

/// The root of an increasing `g` in [lo, hi] by plain bisection to `tol` (kept independent of
/// the crate's root finder, which the code under test uses).
fn bisect(g: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, tol: f64) -> f64 {
    assert!(
        g(lo) < 0.0 && g(hi) > 0.0,
        "not bracketed: {} {}",
        g(lo),
        g(hi)
    );
    while hi - lo > tol {
        let m = 0.5 * (lo + hi);
        if g(m) < 0.0 {
            lo = m
        } else {
            hi = m
        }
    }
    0.5 * (lo + hi)
}

/// The frequency ratio r in [lo, hi] where Den Hartog's boundary (μ/F)_stop(r) equals `ratio`
/// (the boundary rises with r on the intervals used here).
fn published_stop_ratio_root(ratio: f64, lo: f64, hi: f64) -> f64 {
    bisect(
        |r| den_hartog_coulomb_stop_ratio(r).unwrap() - ratio,
        lo,
        hi,
        1e-14,
    )
}

#[test]
fn published_boundary_limits_and_closed_form_agree() {
    // the classical resonance bound π/4 and the exact point r = 1/2 (μ/F = 1/3)
    let near = den_hartog_coulomb_stop_ratio(1.0 - 1e-7).unwrap();
    assert!((near - std::f64::consts::FRAC_PI_4).abs() < 1e-6, "{near}");
    assert!((den_hartog_coulomb_stop_ratio(0.5).unwrap() - 1.0 / 3.0).abs() < 1e-15);
    // the formula against the tangency of the boundary-value solution (the code's own derivation)
    for &ratio in &[0.3, 0.5, 0.7] {
        let r = published_stop_ratio_root(ratio, 0.45, 0.84);
        let osc = CoulombOscillator::new(TAU, 0.0, ratio, 1.0, 1.0).unwrap();
        let f_b = stop_boundary_frequency(&osc, 0.45, 0.84, 1e-13).unwrap();
        assert!((f_b - r).abs() < 1e-9, "μ/F = {ratio}: {f_b} vs {r}");
    }
}

/// ξ = 0, ω₀ = 2π (so r = f in Hz), F = 1: the first nonsmooth point of the generic continuation,
/// started on the non-stop orbit at f = 0.84 Hz and run down in f, with the default integrator.
fn continued_onset_of_stops(ratio: f64) -> (f64, f64) {
    continued_onset_of_stops_with(DEFAULT_METHOD, ratio)
}

fn continued_onset_of_stops_with<M: FlowMethod<CoulombOscillator>>(
    method: M,
    ratio: f64,
) -> (f64, f64) {
    let f_start = 0.84;
    let osc = CoulombOscillator::new(TAU, 0.0, ratio, 1.0, f_start).unwrap();
    let x0 = non_stop_orbit(&osc).unwrap().state(0.0);
    let opts = ContinuationOptions {
        ds: -0.02,
        ds_max: 0.05,
        param_min: 0.36,
        param_max: 0.9,
        ..Default::default()
    };
    let b = Continuation::with_method(
        method,
        osc,
        CoulombParam::F,
        OrbitSpec::symmetric(0),
        x0,
        opts,
    )
    .unwrap()
    .run(None)
    .unwrap();
    let onset = b
        .specials_of(SpecialKind::Nonsmooth)
        .next()
        .unwrap_or_else(|| panic!("μ/F = {ratio}: no nonsmooth point {:?}", b.specials));
    let jump = onset.jump.as_ref().unwrap();
    assert_eq!(jump.events_before.signature(), (1, 0));
    assert!(jump.events_after.sticks > 0);
    (onset.param, onset.precision)
}

#[test]
fn continuation_locates_den_hartogs_published_stop_boundary() {
    // for μ/F ≥ 0.3 stops begin where the reversal turns tangential: Den Hartog's boundary
    for &ratio in &[0.5, 0.7] {
        let (f, prec) = continued_onset_of_stops(ratio);
        let r = published_stop_ratio_root(ratio, 0.45, 0.84);
        eprintln!(
            "μ/F = {ratio}: continuation {f} ± {prec:e}, Den Hartog {r}, difference {:e}",
            f - r
        );
        assert!((f - r).abs() < prec + 1e-9);
    }
}

#[test]
fn below_the_published_boundary_stops_begin_inside_the_half_period() {
    // for μ/F = 0.2 and 0.3 the velocity touches zero inside the half period before the reversal
    // turns tangential: the continuation finds that earlier onset, confirmed by the interior
    // velocity minimum of the closed form, and Den Hartog's formula lies below it
    for &(ratio, lo, hi) in &[(0.2, 0.42, 0.44), (0.3, 0.47, 0.5)] {
        let (f, prec) = continued_onset_of_stops(ratio);
        let vmin = |f: f64| {
            let osc = CoulombOscillator::new(TAU, 0.0, ratio, 1.0, f).unwrap();
            non_stop_orbit(&osc).unwrap().interior_velocity_min().1
        };
        let graze = bisect(vmin, lo, hi, 1e-13);
        let published = published_stop_ratio_root(ratio, 0.36, 0.84);
        eprintln!(
            "μ/F = {ratio}: continuation {f} ± {prec:e}, interior grazing {graze}, \
             Den Hartog {published}"
        );
        assert!((f - graze).abs() < prec + 1e-9, "{f} vs {graze}");
        assert!(graze - published > 5e-4);
    }
}

#[test]
fn dp5_continuation_finds_the_interior_onset_as_exactly() {
    // the continuation's default is the DOP853 (`below_the_published_boundary_…` above), whose
    // steps are 3–7 times longer than the DP5's: with a sign test at 16 points per step it missed
    // the shallow first dip of the velocity through 0 and put the onset at μ/F = 0.2 at
    // 0.4283459102 ± 1.3e-8, 6.7e-8 below the closed form; with the exact search of each step
    // (Bernstein form of the continuous extension) it finds it within the bracket. The DP5 (8
    // probes per step), the second method, finds it within its bracket as well
    for &(ratio, lo, hi) in &[(0.2, 0.42, 0.44), (0.3, 0.47, 0.5)] {
        let (f, prec) = continued_onset_of_stops_with(EventDriven, ratio);
        let vmin = |f: f64| {
            let osc = CoulombOscillator::new(TAU, 0.0, ratio, 1.0, f).unwrap();
            non_stop_orbit(&osc).unwrap().interior_velocity_min().1
        };
        let graze = bisect(vmin, lo, hi, 1e-13);
        eprintln!("μ/F = {ratio}: DP5 continuation {f} ± {prec:e}, interior grazing {graze}");
        assert!((f - graze).abs() < prec + 1e-9, "{f} vs {graze}");
    }
}

#[test]
fn generic_sweep_classifies_den_hartog_orbits() {
    // the sweep and the classification of the gear, run on the Coulomb oscillator through its lens
    use gearbif::analysis::{ClassifyOptions, Dynamics};
    use gearbif::progress::Silent;
    use gearbif::sweep::{sweep_grid, Protocol};
    let opts = ClassifyOptions {
        settle_turns: 40,
        analysis_turns: 20,
        ..ClassifyOptions::default()
    };
    let mus = [0.2, 0.3];
    let fs = [0.8, 1.5];
    let grid = sweep_grid(
        &EventDriven,
        &oscillator(1.0),
        (CoulombParam::Mu, &mus[..]),
        (CoulombParam::F, &fs[..]),
        [0.05, 0.0],
        Protocol::SemiStatic,
        &opts,
        &Silent,
    )
    .unwrap();
    for row in &grid {
        for (sys, r) in row {
            let rig = r.rigorous.as_ref().unwrap();
            let Dynamics::Periodic {
                half_periods,
                symmetric,
                orbit,
                ..
            } = rig.dynamics
            else {
                panic!("{:?}", rig.dynamics);
            };
            assert_eq!((half_periods, symmetric), (1, true));
            let dh = non_stop_orbit(sys).unwrap();
            assert!(dh.is_valid());
            // the classification's Newton-confirmed orbit point is Den Hartog's state at t = 0
            let x = dh.state(0.0);
            assert!((orbit[0] - x[0]).abs() < 1e-8, "{orbit:?} vs {x:?}");
            assert!((orbit[1] - x[1]).abs() < 1e-7, "{orbit:?} vs {x:?}");
        }
    }
}

#[test]
fn outside_the_closed_form_the_errors_are_typed() {
    // overdamped: Den Hartog's solution does not exist
    let over = CoulombOscillator::new(TAU, 1.5, 0.3, 1.0, 1.0).unwrap();
    let r = non_stop_orbit(&over);
    assert!(
        matches!(r, Err(gearbif::Error::OutsideClosedForm { ref needs, .. }) if needs.contains("ξ = 1.5")),
        "{:?}",
        r.err()
    );
    // an interval above the stop boundary: the reversal margin keeps its sign
    let r = stop_boundary_frequency(&oscillator(1.0), 1.5, 2.0, 1e-13);
    match r {
        Err(gearbif::Error::NotBracketed {
            lo, hi, f_lo, f_hi, ..
        }) => {
            assert_eq!((lo, hi), (1.5, 2.0));
            assert!(f_lo * f_hi > 0.0, "{f_lo} {f_hi}");
        }
        other => panic!("{other:?}"),
    }
}
