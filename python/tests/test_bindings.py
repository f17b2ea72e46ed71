"""The Python bindings, each checked against a fact computed independently here (closed forms,
finite differences in numpy, numpy's eigenvalues, the Rust CLI's JSON)."""

import json
import math
import subprocess

import numpy as np
import pytest

import gearbif

MU0_OVER_4PI = 1e-7 * 1.00000000055  # μ0/(4π) in T m/A (CODATA 2018: μ0 = 1.25663706212e-6)


def paper_g():
    """g = μ0 m1 m2 / (4π r³ I) of the paper's gear, 1/s²."""
    return 1.25663706212e-6 / (4 * math.pi) * 3.51**2 / (0.040**3 * 6.45e-5)


# ---------------------------------------------------------------- systems and errors


def test_gear_params_reduce_to_g_delta_and_fc():
    p = gearbif.GearParams()
    g = paper_g()
    assert p.g == pytest.approx(g, rel=1e-14)
    assert p.delta == 1.0
    assert p.lock_loss_frequency == pytest.approx((g - 23.1) / (2 * math.pi * 1.1), rel=1e-14)
    # Δ = cosΘ cosΦ − 2 sinΘ sinΦ
    q = gearbif.GearParams(theta_deg=25.0, phi_deg=10.0)
    t, f = math.radians(25.0), math.radians(10.0)
    assert q.delta == pytest.approx(math.cos(t) * math.cos(f) - 2 * math.sin(t) * math.sin(f), abs=1e-15)
    gear = gearbif.GearParams.paper(25.0).driven(2.7)
    assert gear.delta == pytest.approx(1 - 3 * math.sin(math.radians(25)) ** 2, abs=1e-15)
    assert gear.theta_deg == pytest.approx(25.0, abs=1e-12)
    assert gear.period == pytest.approx(1 / 2.7, rel=1e-15)
    assert gear.with_param("theta", 25.0).delta == pytest.approx(gear.delta, abs=1e-15)


# ---------------------------------------------------------------- simulation


def test_simulation_of_a_frictionless_linear_oscillator_matches_the_closed_form():
    w0, xi, F, f = 2.0, 0.05, 1.0, 0.5
    osc = gearbif.CoulombOscillator(omega0=w0, xi=xi, mu=0.0, force=F, f=f)
    x0, v0 = 0.3, -0.2
    r = gearbif.simulate(osc, [x0, v0], 6.0, samples_per_period=40, tol=1e-11)
    t = r["t"]
    W = 2 * math.pi * f
    D = (w0**2 - W**2) ** 2 + (2 * xi * w0 * W) ** 2
    A, B = F * (w0**2 - W**2) / D, F * 2 * xi * w0 * W / D
    wd = w0 * math.sqrt(1 - xi**2)
    c1 = x0 - A
    c2 = (v0 - B * W + xi * w0 * c1) / wd
    env = np.exp(-xi * w0 * t)
    x = env * (c1 * np.cos(wd * t) + c2 * np.sin(wd * t)) + A * np.cos(W * t) + B * np.sin(W * t)
    v = (
        env * ((-xi * w0 * c1 + wd * c2) * np.cos(wd * t) + (-xi * w0 * c2 - wd * c1) * np.sin(wd * t))
        - A * W * np.sin(W * t)
        + B * W * np.cos(W * t)
    )
    assert np.max(np.abs(r["beta"] - x)) < 1e-8
    assert np.max(np.abs(r["omega"] - v)) < 1e-8
    # every event is a crossing of ω = 0 of the closed form
    ev = r["events"]
    assert ev and all(e["kind"] == "crossing" for e in ev)
    for e in ev:
        te = e["t"]
        ve = np.exp(-xi * w0 * te) * (
            (-xi * w0 * c1 + wd * c2) * math.cos(wd * te) + (-xi * w0 * c2 - wd * c1) * math.sin(wd * te)
        ) - A * W * math.sin(W * te) + B * W * math.cos(W * te)
        assert abs(ve) < 1e-8


def test_gear_simulation_returns_alpha_delta_and_ends_where_the_map_does():
    gear = gearbif.Gear.paper(25.0, 2.7)
    r = gearbif.simulate(gear, [0.5, 2.0], 3 * gear.period, tol=1e-11)
    assert r["t"][0] == 0.0 and r["t"][-1] == pytest.approx(3 * gear.period, rel=1e-12)
    assert np.allclose(r["alpha"], 2 * math.pi * 2.7 * r["t"], atol=1e-12)
    assert np.allclose(r["delta"], r["beta"] - r["alpha"], atol=1e-15)
    m = gearbif.poincare_map(gear, [0.5, 2.0], iterations=3, tol=1e-11, jacobians=False)
    assert np.allclose(r["x_end"], m["x"], atol=1e-12)
    kinds = {e["kind"] for e in r["events"]}
    assert kinds <= {"crossing", "stick_start", "release", "graze"}


def test_sample_jacobians_match_finite_differences_through_crossings():
    # the paper's gear from a state whose first periods cross ω = 0: every sample's
    # ∂(β, ω)/∂(β₀, ω₀) against central differences in numpy
    gear = gearbif.Gear.paper(25.0, 2.7)
    x0 = np.array([0.5, 2.0])
    tol, h = 1e-12, np.array([1e-6, 1e-5])
    times = np.linspace(0.0, 2 * gear.period, 61)[1:]
    r = gearbif.simulate(gear, x0, times[-1], sample_times=times, tol=tol, jacobians=True)
    assert r["jac"].shape == (len(times), 2, 2)
    kinds = {e["kind"] for e in r["events"]}
    assert "crossing" in kinds
    fd = np.zeros((len(times), 2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = h[j]
        up = gearbif.simulate(gear, x0 + e, times[-1], sample_times=times, tol=tol)
        dn = gearbif.simulate(gear, x0 - e, times[-1], sample_times=times, tol=tol)
        fd[:, 0, j] = (up["beta"] - dn["beta"]) / (2 * h[j])
        fd[:, 1, j] = (up["omega"] - dn["omega"]) / (2 * h[j])
    scale = np.maximum(np.abs(fd).max(axis=(1, 2)), 1.0)
    err = np.abs(r["jac"] - fd).max(axis=(1, 2)) / scale
    assert err.max() < 1e-4, err.max()
    # without the flag there is no "jac"
    assert "jac" not in gearbif.simulate(gear, x0, times[-1], sample_times=times, tol=tol)


# ---------------------------------------------------------------- maps and Jacobians


@pytest.mark.parametrize("section", ["stroboscopic", "half_period"])
def test_map_jacobians_match_finite_differences(section):
    gear = gearbif.Gear.paper(25.0, 2.7)
    x = np.array([0.5, 2.0])  # its first period crosses ω = 0
    tol = 1e-13
    m = gearbif.poincare_map(gear, x, section=section, tol=tol)
    assert m["param_names"] == ["f", "g", "zeta", "eta", "delta"]
    h = [1e-6, 1e-5]
    fd = np.zeros((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = h[j]
        xp = gearbif.poincare_map(gear, x + e, section=section, tol=tol, jacobians=False)["x"]
        xm = gearbif.poincare_map(gear, x - e, section=section, tol=tol, jacobians=False)["x"]
        fd[:, j] = (xp - xm) / (2 * h[j])
    assert np.allclose(m["jac_x"], fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
    # parameter columns: f (including the period's dependence), g, ζ, η, Δ
    names = ["f", "g", "zeta", "eta", "delta"]
    for k, name in enumerate(names):
        v = getattr(gear, name)
        dv = 1e-6 * max(abs(v), 1.0)
        xp = gearbif.poincare_map(gear.with_param(name, v + dv), x, section=section, tol=tol, jacobians=False)["x"]
        xm = gearbif.poincare_map(gear.with_param(name, v - dv), x, section=section, tol=tol, jacobians=False)["x"]
        col = (xp - xm) / (2 * dv)
        assert np.allclose(m["jac_p"][:, k], col, rtol=1e-4, atol=1e-6 * max(np.abs(col).max(), 1e-3)), name


def test_multipliers_are_the_eigenvalues_of_the_jacobian():
    gear = gearbif.Gear.paper(25.0, 2.7)
    m = gearbif.poincare_map(gear, [0.5, 2.0], iterations=2, tol=1e-12)
    ev = np.linalg.eigvals(m["jac_x"])
    mu = m["multipliers"]
    assert np.allclose(sorted(ev, key=abs), sorted(mu, key=abs), rtol=1e-10, atol=1e-14)
    assert abs(mu[0]) >= abs(mu[1])
    assert m["trace"] == pytest.approx(np.trace(m["jac_x"]), rel=1e-14)
    assert m["det"] == pytest.approx(np.linalg.det(m["jac_x"]), rel=1e-10)
    assert np.allclose(gearbif.multipliers(m["jac_x"]), mu, rtol=1e-15)
    with pytest.raises(gearbif.InvalidInputError):
        gearbif.multipliers(np.eye(3))


def test_user_parameterised_pendulum_jacobian_columns_match_finite_differences():
    args = dict(omega0=3.0, gamma=0.2, mu=0.4, amplitude=5.0, f=0.7)
    pend = gearbif.ForcedPendulum(**args)
    x = np.array([0.4, 1.5])
    m = gearbif.poincare_map(pend, x, tol=1e-13)
    assert m["param_names"] == ["f", "omega0", "gamma", "mu", "amplitude"]
    for k, name in enumerate(m["param_names"]):
        dv = 1e-6 * max(abs(args[name]), 1.0)
        up = gearbif.ForcedPendulum(**{**args, name: args[name] + dv})
        dn = gearbif.ForcedPendulum(**{**args, name: args[name] - dv})
        col = (
            gearbif.poincare_map(up, x, tol=1e-13, jacobians=False)["x"]
            - gearbif.poincare_map(dn, x, tol=1e-13, jacobians=False)["x"]
        ) / (2 * dv)
        assert np.allclose(m["jac_p"][:, k], col, rtol=1e-4, atol=1e-6), name


# ---------------------------------------------------------------- orbits


def test_lock_branch_at_theta0_is_the_closed_form_and_shooting_finds_it():
    f = 10.0
    gear = gearbif.Gear.paper(0.0, f)
    g, zeta, eta = paper_g(), 1.1, 23.1
    load = (2 * math.pi * f * zeta + eta) / g
    delta_stable = math.pi - math.asin(load)  # sin δ = (2πfζ + η)/g, stable root
    lb = gear.lock_branch()
    assert lb["load"] == pytest.approx(load, rel=1e-14)
    assert np.allclose(lb["stable"]["state"], [delta_stable, 2 * math.pi * f], atol=1e-12)
    # Newton shooting on G from a perturbed guess lands on the analytic orbit
    o = gearbif.shoot(gear, [delta_stable + 0.05, 2 * math.pi * f - 1.0], winding=1)
    assert np.allclose(o["x"], [delta_stable, 2 * math.pi * f], atol=1e-8)
    assert o["stable"] and o["events"]["crossings"] == 0 and o["events"]["sticks"] == 0
    # multipliers of P_T: exp(λT) with λ² + ζλ + k = 0, k = g cos(arcsin(load)) (linearised lock)
    k = g * math.sqrt(1 - load**2)
    lam = (-zeta + np.sqrt(complex(zeta**2 - 4 * k)) * np.array([1, -1])) / 2
    mu = np.exp(lam / f)
    assert np.allclose(sorted(o["stroboscopic_multipliers"], key=lambda z: z.imag),
                       sorted(mu, key=lambda z: z.imag), atol=1e-7)
    # and the same from the Jacobian of P_T at the orbit, by numpy
    m = gearbif.poincare_map(gear, o["x"], tol=1e-12)
    assert np.allclose(sorted(np.linalg.eigvals(m["jac_x"]), key=lambda z: z.imag),
                       sorted(mu, key=lambda z: z.imag), atol=1e-7)


def test_continuation_of_the_lock_at_theta0_folds_at_the_analytic_fc():
    gear = gearbif.Gear.paper(0.0, 30.0)
    b = gearbif.continuation(gear, lock="stable", range=(25.0, 45.0), ds=0.5, ds_max=5.0,
                             max_multiplier=1e3)
    folds = [s for s in b.specials if s.kind == "fold"]
    assert folds, b
    fc = (paper_g() - 23.1) / (2 * math.pi * 1.1)
    assert abs(folds[0].param - fc) < 1e-6
    # along the stable part, β − 0 = π − arcsin((2πfζ + η)/g) at every point
    p, beta, stable = b.param, b.beta, b.stable
    load = (2 * math.pi * p * 1.1 + 23.1) / paper_g()
    on = stable & (load < 1)
    assert on.sum() > 3
    assert np.allclose(np.mod(beta[on], 2 * math.pi), math.pi - np.arcsin(load[on]), atol=1e-7)
    assert b.multipliers.shape == (len(b), 2) and b.x.shape == (len(b), 2)
    d = b.to_dict()
    assert d["param"] == "f" and len(d["points"]) == len(b)


def test_theta25_special_points_agree_with_the_rust_cli(gearbif_cli):
    """The special points of the symmetric branch at Θ = 25° (continuation in f from the
    README's start) against `gearbif continue --json` run on the same problem."""
    rng, start = (1.5, 3.0), [2.98, 0.6]
    out = subprocess.run(
        [gearbif_cli, "continue", "--theta-deg", "25", "--f", "1.5", "--range", "1.5:3",
         "--state-rad", "2.98,0.6", "--winding", "1", "--ds-max", "0.05", "--json"],
        check=True, capture_output=True, text=True,
    ).stdout
    doc = json.loads(out)
    assert doc["schema"] == "gearbif.branches/1"
    cli = doc["branches"][0]["specials"]
    b = gearbif.continuation(gearbif.Gear.paper(25.0, 1.5), start, range=rng, ds_max=0.05)
    py = b.specials
    assert [s.kind for s in py] == [s["kind"] for s in cli]
    assert any(s.kind == "symmetry_breaking" for s in py)
    for s, c in zip(py, cli):
        assert abs(s.param - c["param"]) <= s.precision + c["precision"] + 1e-12, (s, c["param"])
        assert np.allclose(s.x, c["x"], atol=1e-6)


def test_switching_at_symmetry_breaking_gives_an_asymmetric_branch():
    b = gearbif.continuation(gearbif.Gear.paper(25.0, 2.2), [2.98, 0.6], range=(2.2, 2.7), ds_max=0.05)
    sb = [s for s in b.specials if s.kind == "symmetry_breaking"]
    assert sb, b
    nb, start = gearbif.switch_branch(b, sb[-1], dparam=-1e-3, max_steps=40, range=(2.2, 2.7))
    assert nb.spec["section"] == "stroboscopic" and nb.spec["iterations"] == 1
    assert start["separation"] > 1e-4
    # an asymmetric orbit is not a fixed point of G: G(x) ≠ x + (π − π, 0) for the gear
    x = nb.x[len(nb) // 2]
    gear = nb.gear.with_param("f", float(nb.param[len(nb) // 2]))
    gx = gearbif.poincare_map(gear, x, section="half_period", jacobians=False)["x"]
    assert np.hypot(*(gx - x)) > 1e-3
    # but it is a fixed point of P_T up to one turn
    px = gearbif.poincare_map(gear, x, jacobians=False)["x"]
    assert abs(px[0] - x[0] - 2 * math.pi) < 1e-7 and abs(px[1] - x[1]) < 1e-7


def test_lock_loss_boundary_starts_at_the_analytic_fc():
    curves = gearbif.lock_loss_boundary(step_deg=10.0)
    fwd = [c for c in curves if c["winding"] == 1][0]
    assert fwd["theta_deg"][0] == 0.0
    fc0 = (paper_g() - 23.1) / (2 * math.pi * 1.1)
    assert fwd["f_c"][0] == pytest.approx(fc0, abs=1e-6)
    # f_c falls with Θ (the coupling at the lock weakens)
    assert np.all(np.diff(fwd["f_c"]) < 0)


# ---------------------------------------------------------------- classification, sweeps


def test_locked_gear_classifies_as_symmetric_and_rotates_at_f():
    gear = gearbif.Gear.paper(0.0, 5.0)
    lock = gear.lock_branch()["stable"]["state"]  # the analytic lock: an invariant orbit
    r = gearbif.classify(gear, lock, settle_turns=20, analysis_turns=10)
    assert r["schema"] == "gearbif.classify/1" and r["f_hz"] == 5.0
    ev = r["event_driven"]
    # the locked output turns with the input: net rotation f, δ = β − α constant, period T/2
    assert ev["net_rotation_hz"] == pytest.approx(5.0, rel=1e-9)
    assert ev["paper"]["rms_delta_deg"] < 1e-6
    assert ev["rigorous"]["label"] == "T/2" and ev["rigorous"]["locked"]
    # a sweep point is the classification of the same point from the same start
    s = gearbif.sweep(rows="theta:0:0:1", cols=("f", [1.0, 5.0]), settle_turns=20, analysis_turns=10,
                      alpha0_deg=90.0, beta0_deg=90.0)
    assert s["schema"] == "gearbif.sweep/1"
    pts = s["rows"][0]["points"]
    assert [p["f_hz"] for p in pts] == [1.0, 5.0]
    for p in pts:
        g = gearbif.GearParams.paper(0.0).driven(p["f_hz"], alpha0_deg=90.0)
        c = gearbif.classify(g, [math.radians(90.0), 0.0], settle_turns=20, analysis_turns=10)["event_driven"]
        assert p["net_rotation_hz"] == pytest.approx(c["net_rotation_hz"], rel=1e-12)
        assert p["class"] == c["rigorous"]["label"]
    with pytest.raises(gearbif.InvalidInputError):
        gearbif.sweep(rows="theta:0:0:1", cols="f:1:2:0.5", protocol="sideways")


# ---------------------------------------------------------------- recordings: fit and diagnosis


def test_synth_fit_and_diagnose_recover_the_concealed_gear(tmp_path):
    truth = gearbif.synth(tmp_path / "set", "none", ringdowns=3, driven=2, turns=12.0, seed=5)
    assert (tmp_path / "set" / "experiment.toml").is_file()
    fit = gearbif.fit(tmp_path / "set")
    assert fit["schema"] == "gearbif.fit/1"
    g = fit["baseline"]["params"]["g"]
    assert abs(g - truth["g"]) < 0.02 * truth["g"]
    rep = gearbif.diagnose(tmp_path / "set", heldout=False, out_dir=tmp_path / "out")
    assert rep["schema"] == "gearbif.diagnosis/1"
    assert isinstance(rep["verdict"], str)
    assert json.loads((tmp_path / "out" / "report.json").read_text())["verdict"] == rep["verdict"]
