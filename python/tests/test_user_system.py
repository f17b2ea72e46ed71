"""A system defined in Python (gearbif.UserSystem) runs through the same functions as the
built-in ones: here the forced pendulum with dry friction written in Python, checked against the
built-in ForcedPendulum (the same equations in Rust)."""

import math

import numpy as np
import pytest

import gearbif

P = dict(f=0.7, omega0=3.0, gamma=0.2, mu=0.4, amplitude=5.0)


def pendulum_forces(t, th, v, p):
    """θ̈ = A cos 2πft − γθ̇ − ω₀² sin θ − μ sgn θ̇: (a, r)."""
    a = p["amplitude"] * math.cos(2 * math.pi * p["f"] * t) - p["gamma"] * v - p["omega0"] ** 2 * math.sin(th)
    return a, p["mu"]


def pendulum_jacobian(t, th, v, p):
    """(a, ∂a/∂θ, ∂a/∂θ̇, r, ∂r/∂θ, ∂r/∂θ̇, ∂a/∂(f, ω₀, γ, μ, A), ∂r/∂(f, ω₀, γ, μ, A))."""
    a, r = pendulum_forces(t, th, v, p)
    w = 2 * math.pi * p["f"] * t
    a_p = [-p["amplitude"] * math.sin(w) * 2 * math.pi * t, -2 * p["omega0"] * math.sin(th), -v, 0.0, math.cos(w)]
    r_p = [0.0, 0.0, 0.0, 1.0, 0.0]
    return a, -p["omega0"] ** 2 * math.cos(th), -p["gamma"], r, 0.0, 0.0, a_p, r_p


# the same forces as two expressions, compiled once (symbolic derivatives, evaluated in Rust)
EXPRESSIONS = ("amplitude*cos(2*PI*f*t) - gamma*v - omega0^2*sin(x)", "mu")


def user(jacobian=None):
    if jacobian == "expressions":
        return gearbif.UserSystem(EXPRESSIONS, dict(P), symmetry=(-1.0, 0.0))
    return gearbif.UserSystem(pendulum_forces, dict(P), jacobian=jacobian, symmetry=(-1.0, 0.0))


BUILTIN = gearbif.ForcedPendulum(**P)


@pytest.mark.parametrize(
    "jacobian, rtol",
    [(None, 1e-6), (pendulum_jacobian, 1e-9), ("expressions", 1e-9)],
    ids=["differences", "analytic", "expressions"],
)
def test_map_and_jacobians_equal_the_builtin_pendulum(jacobian, rtol):
    u = user(jacobian)
    assert u.param_names == list(P) and u.period == pytest.approx(1 / 0.7, rel=1e-15)
    x = [0.4, 1.5]
    mu_ = gearbif.poincare_map(u, x, tol=1e-12)
    mb = gearbif.poincare_map(BUILTIN, x, tol=1e-12)
    assert mu_["param_names"] == mb["param_names"]
    assert np.allclose(mu_["x"], mb["x"], rtol=1e-10, atol=1e-10)
    assert np.allclose(mu_["jac_x"], mb["jac_x"], rtol=rtol, atol=rtol)
    assert np.allclose(mu_["jac_p"], mb["jac_p"], rtol=rtol, atol=rtol)


def test_continuation_classification_and_sweep_equal_the_builtin_pendulum():
    u = user(pendulum_jacobian)
    x = gearbif.simulate(BUILTIN, [0.1, 0.0], 100 * BUILTIN.period, samples_per_period=1)["x_end"]
    kw = dict(param="amplitude", range=(4.0, 5.0), ds=-0.1, max_steps=50)
    bu = gearbif.continuation(u, x, **kw)
    bb = gearbif.continuation(BUILTIN, x, **kw)
    assert isinstance(bu.system, gearbif.UserSystem) and bu.param_name == "amplitude"
    assert len(bu) == len(bb) and [s.kind for s in bu.specials] == [s.kind for s in bb.specials]
    assert np.allclose(bu.param, bb.param, atol=1e-9) and np.allclose(bu.x, bb.x, atol=1e-8)
    assert bu.to_dict()["system"] == P
    cu = gearbif.classify(u, x, settle_turns=30, analysis_turns=10)
    cb = gearbif.classify(BUILTIN, x, settle_turns=30, analysis_turns=10)
    assert cu["system"] == "UserSystem" and cu["params"] == P
    assert cu["event_driven"]["rigorous"]["label"] == cb["event_driven"]["rigorous"]["label"]
    assert cu["event_driven"]["paper"]["rms_delta_deg"] == pytest.approx(cb["event_driven"]["paper"]["rms_delta_deg"], rel=1e-8)
    s = gearbif.sweep_grid(u, ("mu", [0.4]), ("amplitude", [4.0, 5.0]), x0=x, settle_turns=30, analysis_turns=10)
    t = gearbif.sweep_grid(BUILTIN, ("mu", [0.4]), ("amplitude", [4.0, 5.0]), x0=x, settle_turns=30, analysis_turns=10)
    assert s["label"] == t["label"] and np.allclose(s["rms_delta_deg"], t["rms_delta_deg"], rtol=1e-8)


def test_user_errors_are_raised_and_bad_definitions_rejected():
    def broken(t, th, v, p):
        if t > 0.3:
            raise ValueError("the user's model failed")
        return 0.0, 0.1

    b = gearbif.UserSystem(broken, {"f": 1.0})
    with pytest.raises(ValueError, match="the user's model failed"):
        gearbif.simulate(b, [0.0, 1.0], 1.0)
    with pytest.raises(ValueError):
        gearbif.poincare_map(b, [0.0, 1.0])
    short = gearbif.UserSystem(lambda t, x, v, p: (1.0,), {"f": 1.0})
    with pytest.raises(gearbif.InvalidInputError):
        gearbif.simulate(short, [0.0, 1.0], 1.0)
    nan = gearbif.UserSystem(lambda t, x, v, p: (float("nan"), 0.0), {"f": 1.0})
    with pytest.raises(gearbif.InvalidInputError):
        gearbif.poincare_map(nan, [0.0, 1.0])
    ok = lambda t, x, v, p: (0.0, 0.0)  # noqa: E731
    with pytest.raises(gearbif.InvalidInputError):
        gearbif.UserSystem(ok, {"omega0": 1.0})  # no drive frequency
    with pytest.raises(gearbif.InvalidParameterError):
        gearbif.UserSystem(ok, {"f": -1.0})
    with pytest.raises(gearbif.InvalidParameterError):
        gearbif.UserSystem(ok, {"f": 1.0, "k": float("inf")})
    with pytest.raises(gearbif.InvalidInputError):
        gearbif.UserSystem("not callable", {"f": 1.0})
    with pytest.raises(gearbif.InvalidInputError):
        gearbif.UserSystem(ok, {"f": 1.0}, symmetry=(0.5, 0.0))
    with pytest.raises(gearbif.InvalidInputError):
        gearbif.UserSystem(ok, {f"p{k}": 1.0 for k in range(8)} | {"f": 1.0})  # nine parameters
    u = gearbif.UserSystem(ok, {"f": 1.0, "k": 2.0})
    assert u.with_param("k", 3.0).params == {"f": 1.0, "k": 3.0}
    with pytest.raises(gearbif.InvalidInputError):
        u.with_param("omega0", 1.0)
    with pytest.raises(gearbif.InvalidParameterError):
        u.with_param("f", 0.0)
    with pytest.raises(gearbif.UnsupportedError):  # no half-period symmetry declared
        gearbif.shoot(u, [0.0, 0.0], section="half_period")


def test_expressions_give_the_forces_and_refuse_what_they_cannot_compile():
    u = user("expressions")
    t, th, v = 0.3, 0.5, -1.2
    assert u.forces(t, th, v) == pytest.approx(pendulum_forces(t, th, v, P), rel=1e-14)
    # the expressions' continuation is the built-in one's
    x = gearbif.simulate(BUILTIN, [0.1, 0.0], 100 * BUILTIN.period, samples_per_period=1)["x_end"]
    kw = dict(param="omega0", range=(2.8, 3.0), ds=-0.05, max_steps=10)
    bu, bb = gearbif.continuation(u, x, **kw), gearbif.continuation(BUILTIN, x, **kw)
    assert np.allclose(bu.param, bb.param, atol=1e-10) and np.allclose(bu.x, bb.x, atol=1e-9)
    with pytest.raises(ValueError, match="`k`"):
        gearbif.UserSystem(("k*x", "mu"), dict(P))
    with pytest.raises(ValueError, match="may not be called"):
        gearbif.UserSystem(("x", "0"), dict(f=1.0, v=2.0))
    with pytest.raises(ValueError, match="column 4"):
        gearbif.UserSystem(("x +* 2", "0"), dict(f=1.0))
    # the grammar's precedences: -x^2 is -(x²), ** is ^
    signs = gearbif.UserSystem(("-x^2 + 2**-v", "0"), dict(f=1.0))
    assert signs.forces(0.0, 3.0, 1.0) == (-8.5, 0.0)
    with pytest.raises(ValueError, match="no jacobian"):
        gearbif.UserSystem(EXPRESSIONS, dict(P), jacobian=pendulum_jacobian)
    with pytest.raises(ValueError, match="pair of expressions"):
        gearbif.UserSystem(42, dict(P))
