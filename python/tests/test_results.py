"""Result objects and error classes: a result is its dict with attribute access, tables and plots
that show what they claim; every error is a GearbifError and the builtin a Python user catches."""

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import gearbif  # noqa: E402

pd = pytest.importorskip("pandas")


def paper_g():
    return gearbif.GearParams().g


@pytest.mark.parametrize(
    "cls,builtin",
    [
        ("InvalidParameterError", ValueError),
        ("InvalidInputError", ValueError),
        ("RecordingError", ValueError),
        ("IntegrationError", RuntimeError),
        ("NewtonError", RuntimeError),
        ("ContinuationError", RuntimeError),
        ("NoPeriodError", RuntimeError),
        ("GearbifIOError", OSError),
        ("UnsupportedError", NotImplementedError),
    ],
)
def test_every_error_is_a_gearbif_error_and_its_builtin(cls, builtin):
    c = getattr(gearbif, cls)
    assert issubclass(c, gearbif.GearbifError) and issubclass(c, builtin)
    assert c.__module__ == "gearbif" and c.__doc__


def test_a_bad_value_raised_by_the_library_is_caught_as_a_value_error():
    with pytest.raises(ValueError) as e:
        gearbif.Gear.paper(25.0, -1.0)
    assert isinstance(e.value, gearbif.InvalidParameterError)
    assert e.value.name == "f" and e.value.value == -1.0
    with pytest.raises(NotImplementedError):
        gearbif.Gear.paper(25.0, 1.0).lock_branch()  # Δ ≠ ±1: no closed-form lock


def test_a_trajectory_is_its_dict_with_a_table_and_a_plot_of_delta_in_degrees():
    gear = gearbif.Gear.paper(25.0, 1.5)
    r = gearbif.simulate(gear, [0.5, 2.0], 2 * gear.period, samples_per_period=20)
    assert isinstance(r, gearbif.Trajectory) and isinstance(r, dict)
    assert r.beta is r["beta"] and set(r) >= {"t", "beta", "omega", "delta", "events"}
    with pytest.raises(AttributeError, match="fields"):
        r.no_such_field
    df = r.to_pandas()
    assert list(df.columns) == ["t", "beta", "omega", "alpha", "delta"] and len(df) == len(r.t)
    fig, ax = plt.subplots()
    assert r.plot(ax=ax) is ax
    (line,) = ax.get_lines()
    assert np.allclose(line.get_ydata(), np.degrees(r.delta)) and "deg" in ax.get_ylabel()
    assert "samples=41" in repr(r)
    plt.close(fig)


def test_a_branch_tabulates_and_plots_its_fold_where_the_closed_form_puts_it():
    gear = gearbif.Gear.paper(0.0, 30.0)
    b = gearbif.continuation(gear, lock="stable", range=(25.0, 45.0), ds=0.5, ds_max=5.0, max_multiplier=1e3)
    assert isinstance(b, gearbif.Branch) and len(b) == len(b.param)
    fc = (paper_g() - 23.1) / (2 * math.pi * 1.1)
    table = b.specials_table()
    folds = [s for s in table if s["kind"] == "fold"]
    assert folds and abs(folds[0]["param"] - fc) < 1e-6
    sp = b.to_pandas(specials=True)
    assert list(sp["kind"]) == [s["kind"] for s in table]
    pts = b.to_pandas()
    assert len(pts) == len(b) and (pts["stable"] == b.stable).all()
    assert "fold" in repr(b) and "f in" in repr(b)
    fig, ax = plt.subplots()
    b.plot(ax=ax)
    solid = [ln for ln in ax.get_lines() if ln.get_linestyle() == "-"]
    dashed = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
    # the stable lock up to the fold, the unstable one beyond: both drawn, in degrees
    assert solid and dashed
    xs = np.concatenate([ln.get_xdata() for ln in solid + dashed])
    assert xs.min() >= 25.0 - 1e-9 and xs.max() <= 45.0 + 1e-9
    assert [t.get_text() for t in ax.texts] == [s.label for s in b.specials]
    plt.close(fig)
    # a switched branch comes back as a Branch, and a Branch can be switched again
    b2 = gearbif.continuation(gearbif.Gear.paper(25.0, 2.2), [2.98, 0.6], range=(2.2, 2.7), ds_max=0.05)
    sb = [s for s in b2.specials if s.kind == "symmetry_breaking"][-1]
    nb, start = gearbif.switch_branch(b2, sb, dparam=-1e-3, max_steps=5, range=(2.2, 2.7))
    assert isinstance(nb, gearbif.Branch) and isinstance(start, gearbif.Orbit) and start.x.shape == (2,)


def test_a_sweep_grid_plot_and_table_show_its_points():
    s = gearbif.sweep(rows="theta:0:10:10", cols=("f", [1.0, 5.0]), settle_turns=20, analysis_turns=10)
    assert isinstance(s, gearbif.Sweep) and s.schema == "gearbif.sweep/1"
    g = s.grid("net_rotation_hz")
    assert g.shape == (2, 2)
    for p in s.points():
        assert g[p["row"], p["col"]] == p["net_rotation_hz"]
    df = s.to_pandas()
    assert len(df) == 4 and {"row", "col", "f_hz", "class"} <= set(df.columns)
    fig, ax = plt.subplots()
    s.plot(ax=ax, value="net_rotation_hz")
    assert len(fig.axes) == 2  # the map and its colour bar
    assert fig.axes[1].get_ylabel() == "net rotation [Hz]" and ax.get_xlabel() == "f [Hz]"
    plt.close(fig)


def test_the_boundary_plots_f_c_against_theta():
    curves = gearbif.lock_loss_boundary(step_deg=30.0)
    assert isinstance(curves, gearbif.Boundary) and all(isinstance(c, gearbif.BoundaryCurve) for c in curves)
    df = curves.to_pandas()
    assert len(df) == sum(len(c.theta_deg) for c in curves)
    fig, ax = plt.subplots()
    curves.plot(ax=ax)
    assert len(ax.get_lines()) == len(curves) and ax.get_legend() is not None
    assert ax.get_xlabel() == "Θ [deg]" and ax.get_ylabel() == "f_c [Hz]"
    plt.close(fig)
