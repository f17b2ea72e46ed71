"""The generic bindings: continuation, classification and sweeps of the systems other than the gear
(CoulombOscillator, ForcedPendulum) through the same functions, checked against Den Hartog's closed
form (computed here in numpy) and against each other."""

import math

import numpy as np
import pytest

import gearbif

W0, MU, F = 2 * math.pi, 0.3, 1.0  # ω₀ = 2π (f₀ = 1 Hz), μ/F = 0.3, no viscous damping


def den_hartog_amplitude(f):
    """Den Hartog (1931): X / (F/ω₀²) = √(V² − (μ/F)² U²), V = 1/(1 − r²),
    U = sin(π/r) / (r (1 + cos(π/r))), r = Ω/ω₀ — the continuous-motion steady state, ξ = 0."""
    r = 2 * math.pi * f / W0
    v = 1 / (1 - r * r)
    u = math.sin(math.pi / r) / (r * (1 + math.cos(math.pi / r)))
    return F / W0**2 * math.sqrt(v * v - (MU / F) ** 2 * u * u)


def coulomb(f):
    return gearbif.CoulombOscillator(omega0=W0, xi=0.0, mu=MU, force=F, f=f)


def reversal_amplitude(osc, x):
    """|x| at the reversals (ẋ = 0 crossings) of one period of the orbit through x."""
    r = gearbif.simulate(osc, x, osc.period, tol=1e-12)
    rev = [abs(e["beta"]) for e in r["events"] if e["kind"] == "crossing"]
    assert len(rev) == 2, r["events"]
    return 0.5 * sum(rev)


def test_coulomb_continuation_in_f_follows_den_hartog():
    osc = coulomb(2.0)
    # a start on the attractor (the dry friction damps the transient), then Newton on G
    x = gearbif.simulate(osc, [0.0, 0.0], 300 * osc.period, samples_per_period=1)["x_end"]
    b = gearbif.continuation(osc, x, range=(1.3, 2.0), ds=-0.05, ds_max=0.1)
    assert b.param_name == "f" and b.spec == {"section": "half_period", "iterations": 1, "winding": 0}
    assert isinstance(b.system, gearbif.CoulombOscillator)
    assert b.param.min() == pytest.approx(1.3, abs=1e-9) and len(b) > 4
    assert np.all(b.events[:, 0] == 1) and np.all(b.events[:, 1] == 0)  # one crossing, no stop per T/2
    for k in range(0, len(b), 3):
        f = float(b.param[k])
        x_num = reversal_amplitude(b.system.with_param("f", f), b.x[k])
        assert x_num == pytest.approx(den_hartog_amplitude(f), rel=1e-8), f
    d = b.to_dict()
    assert d["system"]["mu"] == MU and len(d["points"]) == len(b)


def test_coulomb_classification_and_sweep_agree():
    osc = coulomb(1.5)
    c = gearbif.classify(osc, settle_turns=150, analysis_turns=10)
    assert c["system"] == "CoulombOscillator" and c["params"]["f"] == 1.5 and "theta_deg" not in c
    ev = c["event_driven"]
    # the odd-symmetric continuous motion: period T, invariant under x → −x (label T/2), no drift
    assert ev["rigorous"]["label"] == "T/2"
    assert abs(ev["rigorous"]["rotation_number"]) < 1e-9 and ev["net_rotation_hz"] == pytest.approx(0, abs=1e-9)
    # δ = x for an oscillator: the standard deviation of x over the window, in degrees of x [rad],
    # is X/√2 for a (nearly) harmonic response
    x_amp = den_hartog_amplitude(1.5)
    assert ev["paper"]["rms_delta_deg"] == pytest.approx(math.degrees(x_amp) / math.sqrt(2), rel=0.02)
    s = gearbif.sweep_grid(osc, ("mu", [0.3]), ("f", np.array([1.5, 1.8])), settle_turns=150, analysis_turns=10)
    assert s["row_param"] == "mu" and s["col_param"] == "f"
    assert s["rotation_number"].shape == (1, 2) and s["label"] == [["T/2", "T/2"]]
    assert s["points"][0][0]["net_rotation_hz"] == pytest.approx(ev["net_rotation_hz"], abs=1e-12)
    assert s["rms_delta_deg"][0, 0] == pytest.approx(ev["paper"]["rms_delta_deg"], rel=1e-12)


def test_pendulum_shoot_continue_and_sweep_through_the_same_functions():
    pend = gearbif.ForcedPendulum(omega0=3.0, gamma=0.2, mu=0.4, amplitude=5.0, f=0.7)
    assert pend.params == {"f": 0.7, "omega0": 3.0, "gamma": 0.2, "mu": 0.4, "amplitude": 5.0}
    x = gearbif.simulate(pend, [0.1, 0.0], 100 * pend.period, samples_per_period=1)["x_end"]
    o = gearbif.shoot(pend, x)
    assert o["spec"]["winding"] == 0 and o["residual"] < 1e-9
    # a fixed point of G = R⁻¹ ∘ P_{T/2} with R(θ, ω) = (−θ, −ω): half a period later, −x
    half = gearbif.simulate(pend, o["x"], pend.period / 2, tol=1e-12)["x_end"]
    assert np.allclose(half, -o["x"], atol=1e-8)
    b = gearbif.continuation(pend, o["x"], param="amplitude", range=(4.0, 5.0), ds=-0.1, max_steps=50)
    assert b.param_name == "amplitude" and b.param.min() == pytest.approx(4.0, abs=1e-9)
    # every point is an orbit of the pendulum at its amplitude: G(x) = x
    for k in (0, len(b) - 1):
        p = b.system.with_param("amplitude", float(b.param[k]))
        g = gearbif.poincare_map(p, b.x[k], section="half_period", jacobians=False, tol=1e-12)["x"]
        assert np.allclose(g, b.x[k], atol=1e-8)
    s = gearbif.sweep_grid(pend, ("gamma", [0.2]), ("amplitude", [4.0, 5.0]), x0=o["x"], settle_turns=50,
                           analysis_turns=10, protocol="semi_static")
    assert s["label"][0][1] == "T/2"
    with pytest.raises(gearbif.InvalidInputError):
        gearbif.sweep_grid(pend, ("gamma", [0.2]), ("gamma", [0.1]))  # the same parameter twice
    with pytest.raises(gearbif.InvalidInputError):
        gearbif.continuation(pend, o["x"], param="theta", range=(0, 1))  # the gear's parameter


def test_generic_systems_share_the_parameter_interface():
    for s in (gearbif.Gear.paper(25.0, 2.7), coulomb(1.0), gearbif.ForcedPendulum(3.0, 0.2, 0.4, 5.0, 0.7)):
        p = s.params
        assert list(p)[: len(s.param_names)] == s.param_names
        for name, v in p.items():
            assert s.with_param(name, v).params[name] == pytest.approx(v, rel=1e-12, abs=1e-12)
        assert s.period == pytest.approx(1 / p["f"], rel=1e-15)
        assert repr(s).startswith(type(s).__name__ + "(")
        with pytest.raises(gearbif.InvalidInputError):
            s.with_param("nonexistent", 1.0)
        with pytest.raises(gearbif.InvalidParameterError):
            s.with_param("f", float("nan"))
        with pytest.raises(gearbif.InvalidInputError):
            s.forces(0.0, float("inf"), 0.0)


def test_coulomb_onset_of_stops_is_located_as_a_nonsmooth_point():
    """Below some frequency the reversals become stops: the continuation sees the events per half
    period change from one crossing to one stick phase and locates the change; shooting on either
    side of the located value (independently of the branch) finds the two event sequences."""
    osc = gearbif.CoulombOscillator(omega0=W0, xi=0.05, mu=MU, force=F, f=0.8)
    x = gearbif.simulate(osc, [0.0, 0.0], 300 * osc.period, samples_per_period=1)["x_end"]
    b = gearbif.continuation(osc, x, range=(0.4, 0.8), ds=-0.02, ds_max=0.05)
    ns = [s for s in b.specials if s.kind == "nonsmooth"]
    assert ns, b.specials
    fb, eps = ns[0].param, 20 * ns[0].precision + 1e-7
    # Den Hartog's boundary F cos ψ + ω₀²X = μ for these parameters (docs/second_system.md)
    assert abs(fb - 0.5072053168) < ns[0].precision + 1e-9
    counts = []
    for f in (fb + eps, fb - eps):
        o = gearbif.shoot(osc.with_param("f", f), ns[0].x, tol=1e-12, newton_tol=1e-10)
        counts.append((o["events"]["crossings"], o["events"]["sticks"]))
    assert counts == [(1, 0), (0, 1)], (fb, counts)
