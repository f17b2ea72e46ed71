//! Curves of nonsmooth points in (Θ, f) and the re-lock of the slip-through state at Θ = 0, each
//! against a second, independent route.

use gearbif::analysis::relock::{homoclinic_frequency, ramp_relock, saddle, slip_cycle};
use gearbif::continuation::minaug::nearest_edge_arrival;
use gearbif::continuation::palc2::{
    continue_event_edge_curve, continue_grazing_curve, locate_grazing, CurveOptions,
};
use gearbif::continuation::{Continuation, ContinuationOptions, SpecialPoint};
use gearbif::integrator::{EventDriven, EventDriven853, FlowMethod, DEFAULT_METHOD};
use gearbif::model::{Gear, GearParam};
use gearbif::orbits::{shoot_with, OrbitSpec, ShootingOptions};

/// The stick onset (a nonsmooth point with no events on one side) that a one-parameter
/// continuation in f over [f0 − w, f0 + w] at Θ = `theta` locates.
fn onset_by_continuation(
    theta: f64,
    spec: OrbitSpec,
    x: [f64; 2],
    f0: f64,
    w: f64,
) -> SpecialPoint {
    nonsmooth_by_continuation(theta, spec, x, f0, w, &[(0, 0)], false)
}

/// The nonsmooth point of a one-parameter continuation in f over [f0 − w, f0 + w] at Θ = `theta`
/// whose event signatures are in `sigs` (on one side if `!both`, on both sides if `both`), with
/// the default integrator.
fn nonsmooth_by_continuation(
    theta: f64,
    spec: OrbitSpec,
    x: [f64; 2],
    f0: f64,
    w: f64,
    sigs: &[(usize, usize)],
    both: bool,
) -> SpecialPoint {
    let place = (theta, spec, x, f0, w);
    nonsmooth_by_continuation_with(DEFAULT_METHOD, place, sigs, both)
}

/// [`nonsmooth_by_continuation`] integrated by `method`; `place` = (Θ, spec, x, f0, w).
fn nonsmooth_by_continuation_with<M: FlowMethod<Gear>>(
    method: M,
    place: (f64, OrbitSpec, [f64; 2], f64, f64),
    sigs: &[(usize, usize)],
    both: bool,
) -> SpecialPoint {
    let (theta, spec, x, f0, w) = place;
    let b = Continuation::with_method(
        method,
        Gear::paper(theta, f0 + w).unwrap(),
        GearParam::F,
        spec,
        x,
        ContinuationOptions {
            ds: -0.2 * w,
            ds_max: 0.5 * w,
            param_min: f0 - w,
            param_max: f0 + w,
            ..Default::default()
        },
    )
    .unwrap()
    .run(None)
    .unwrap();
    b.specials
        .iter()
        .find(|s| {
            s.jump.as_ref().is_some_and(|j| {
                let (a, b) = (j.events_before.signature(), j.events_after.signature());
                if both {
                    sigs.contains(&a) && sigs.contains(&b)
                } else {
                    sigs.contains(&a) || sigs.contains(&b)
                }
            })
        })
        .cloned()
        .expect("a nonsmooth point of that kind")
}

#[test]
fn grazing_curve_point_agrees_with_the_stick_onset_of_a_continuation_in_f() {
    // the symmetric T/2 orbit at Θ = 25° starts to stick near 1.4733 Hz going down in f
    let spec = OrbitSpec::symmetric(1);
    let sp = onset_by_continuation(25.0, spec, [2.98, 0.6], 1.49, 0.03);
    let g = Gear::paper(25.0, sp.param).unwrap();
    let opts = CurveOptions {
        ds: 0.3,
        max_steps: 5,
        ..Default::default()
    };
    let args = (GearParam::F, GearParam::ThetaDeg);
    let p0 = locate_grazing(
        &EventDriven,
        &g,
        &spec,
        1.0,
        args.0,
        args.1,
        sp.x,
        sp.param,
        &opts,
    )
    .unwrap();
    println!(
        "Θ = 25°: continuation {:.10}, grazing {:.10} Hz",
        sp.param, p0.free
    );
    assert!((p0.free - sp.param).abs() < 1e-7);
    // a few pseudo-arclength steps of the grazing curve towards larger Θ
    let c = continue_grazing_curve(
        &EventDriven,
        &g,
        &spec,
        1.0,
        args.0,
        args.1,
        sp.x,
        sp.param,
        &opts,
    )
    .unwrap();
    let p = c.points.last().unwrap();
    assert!(p.along > 25.5, "the curve moved to Θ = {}", p.along);
    assert!(p.test_value.abs() < 1e-8, "margin {}", p.test_value);
    // the one-parameter route at that Θ: the orbit's event sequence changes at the same f
    let q = onset_by_continuation(p.along, spec, p.x, p.free, 0.004);
    println!(
        "Θ = {:.6}°: grazing curve {:.10}, continuation {:.10} ± {:.1e} Hz",
        p.along, p.free, q.param, q.precision
    );
    assert!((q.param - p.free).abs() < 1e-7);
}

#[test]
fn theta0_relock_is_the_homoclinic_of_the_slip_cycle() {
    let base = Gear::paper(0.0, 3.7).unwrap();
    // the homoclinic frequency at two tolerances and start offsets
    let a = homoclinic_frequency(&base, 3.6, 3.7, 1e-6, 1e-9, 1e-9).unwrap();
    let b = homoclinic_frequency(&base, 3.6, 3.7, 1e-7, 1e-10, 1e-9).unwrap();
    println!(
        "f_h = {:.11} (tol 1e-9), {:.11} Hz (tol 1e-10)",
        a.value(),
        b.value()
    );
    assert!((a.value() - b.value()).abs() < 3e-9);
    let f_h = b.value();
    // the slip cycle exists just above f_h, is stable and slips (winding between 0 and 1)
    let d0 = -std::f64::consts::FRAC_PI_2;
    let g = base.with_f(3.70).unwrap();
    let c = slip_cycle(&g, d0, (-2.90, 0.485), 1e-11).unwrap();
    assert!(
        c.multiplier.abs() < 1.0 && c.winding > 0.0 && c.winding < 1.0,
        "{c:?}"
    );
    // its saddle's unstable eigenvalue sets the logarithmic law; the cycle is longer than 1/λ_u
    let lam = saddle(&g).unwrap().unstable;
    assert!(c.duration * lam > 1.0);
    // a slow down-ramp from the cycle re-locks within 0.4·|ḟ|·(1 s) of f_h (docs: |Δ|/|ḟ| ≤ 0.36 s)
    let rate = -1e-3;
    let r = ramp_relock(&g, [d0 + g.alpha(0.0), c.omega0], rate, 3.66, 1e-10).unwrap();
    println!(
        "ramp {rate}: last slip {:.7} Hz, {} slips",
        r.last_slip, r.slips
    );
    assert!((r.last_slip - f_h).abs() < 0.4 * rate.abs(), "{r:?}");
    assert!(r.lock_offset < 1e-4 && r.slips > 10);
}

/// From the nonsmooth point between the event signatures `sigs` that a continuation in f locates
/// on the asymmetric T orbit at Θ = 25°, 4 steps of the event-edge curve; at the last point's Θ a
/// continuation in f locates the same point.
fn event_edge_curve_agrees(sigs: [(usize, usize); 2]) {
    let spec = OrbitSpec::stroboscopic(1, 1);
    let sp = nonsmooth_by_continuation(25.0, spec, [2.9748, 24.3248], 2.36, 0.025, &sigs, true);
    let g = Gear::paper(25.0, sp.param).unwrap();
    let opts = CurveOptions {
        ds: 0.3,
        max_steps: 4,
        ..Default::default()
    };
    let (f, th) = (GearParam::F, GearParam::ThetaDeg);
    let c =
        continue_event_edge_curve(&EventDriven, &g, &spec, f, th, sp.x, sp.param, &opts).unwrap();
    assert!(
        (c.points[0].free - sp.param).abs() < 1e-7,
        "{} {}",
        c.points[0].free,
        sp.param
    );
    let p = c.points.last().unwrap();
    assert!(p.along > 25.5 && p.test_value.abs() < 1e-8, "{p:?}");
    let q = nonsmooth_by_continuation(p.along, spec, p.x, p.free, 0.004, &sigs, true);
    println!(
        "{sigs:?}: Θ = 25°: {:.10} (continuation {:.10}); Θ = {:.6}°: edge curve {:.10}, \
         continuation {:.10} ± {:.1e} Hz",
        c.points[0].free, sp.param, p.along, p.free, q.param, q.precision
    );
    assert!((q.param - p.free).abs() < 1e-7);
}

#[test]
fn end_of_sticking_curve_point_agrees_with_a_continuation_in_f() {
    // the asymmetric T orbit's stick phase shrinks to nothing near 2.343 Hz
    event_edge_curve_agrees([(1, 1), (2, 0)]);
}

#[test]
fn crossing_onset_curve_point_agrees_with_a_continuation_in_f() {
    // near 2.364 Hz the arrival before the stick phase starts to cross first
    event_edge_curve_agrees([(0, 1), (1, 1)]);
}

/// The crossing onset (0, 1) → (1, 1) on the asymmetric T orbit at Θ = 25° from both sides of the
/// bracket a continuation in f locates, by the DP5 and by the DOP853. On the (1, 1) side the
/// arrival from ω > 0 crosses with a = −η − ε and the orbit returns to Σ at once from ω < 0 with
/// a ≈ −η + ε, a tangential arrival as near to |a| = η as the crossing; only the crossing (the
/// stick entry on the (0, 1) side) exists on both sides, so the edge curve must track it from
/// either side. Before the edge arrival was chosen by its side, the start on the (1, 1) side could
/// pick the return and the curve's corrector then crossed the edge onto the side where the
/// return does not exist ("no arrival on Σ to track"): with the DOP853 as the continuation's
/// method in `crossing_onset_curve_point_agrees_with_a_continuation_in_f`.
#[test]
fn crossing_onset_edge_curve_starts_from_either_side_with_either_method() {
    edge_curves_from_both_sides(EventDriven, "DP5");
    edge_curves_from_both_sides(EventDriven853, "DOP853");
}

/// The crossing onset near 2.364 Hz located by a continuation in f with `method`, and the edge
/// curve from both ends of its bracket.
fn edge_curves_from_both_sides<M: FlowMethod<Gear> + Copy>(method: M, name: &str) {
    let spec = OrbitSpec::stroboscopic(1, 1);
    let place = (25.0, spec, [2.9748, 24.3248], 2.36, 0.025);
    let sp = nonsmooth_by_continuation_with(method, place, &[(0, 1), (1, 1)], true);
    let jump = sp.jump.clone().unwrap();
    let sides = [
        (jump.param_before, jump.events_before.signature()),
        (jump.param_after, jump.events_after.signature()),
    ];
    for (param, sig) in sides {
        edge_curve_from(&method, name, &sp, param, sig);
    }
}

/// The orbit at `param` (one end of the bracket of `sp`, event signature `sig`), the edge arrival
/// chosen there, and two steps of the event-edge curve from it, all integrated by `method`.
fn edge_curve_from<M: FlowMethod<Gear>>(
    method: &M,
    name: &str,
    sp: &SpecialPoint,
    param: f64,
    sig: (usize, usize),
) {
    let spec = OrbitSpec::stroboscopic(1, 1);
    let g = Gear::paper(25.0, param).unwrap();
    let sh = ShootingOptions::default();
    let o = shoot_with(method, &g, &spec, sp.x, &sh).unwrap();
    assert_eq!(o.events.signature(), sig, "{name}: orbit at {param}");
    // the arrival from ω > 0 at its edge a = −η (σ = −1), on either side
    let (sigma, side, t) = nearest_edge_arrival(method, &g, &spec, o.x, sh.tol).unwrap();
    assert_eq!((sigma, side), (-1.0, 1.0), "{name}: {sig:?} side, t = {t}");
    let opts = CurveOptions {
        ds: 0.3,
        max_steps: 2,
        ..Default::default()
    };
    let (f, th) = (GearParam::F, GearParam::ThetaDeg);
    let c = continue_event_edge_curve(method, &g, &spec, f, th, o.x, param, &opts).unwrap();
    let (p0, p) = (&c.points[0], c.points.last().unwrap());
    println!(
        "{name}, from the {sig:?} side: continuation {:.10}, edge curve {:.12} Hz; 2 steps: \
         Θ = {:.6}°, {:.12} Hz",
        sp.param, p0.free, p.along, p.free
    );
    assert!((p0.free - sp.param).abs() < 1e-7, "{name}: {}", p0.free);
    assert!(
        c.points.len() == 3 && p.along > 25.1,
        "{name}: {:?}",
        c.stopped
    );
    assert!(p.test_value.abs() < 1e-8, "{name}: {p:?}");
}
