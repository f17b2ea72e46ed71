"""Result objects: the dicts of the extension with attribute access, a summary repr, tables and plots.

Every result is still the dict of the CLI's JSON (docs/formats.md), so ``r["beta"]`` and ``r.beta``
are the same array. Plots draw on a matplotlib Axes (``ax=None``: the current one) and return it;
tables are lists of dicts, or pandas DataFrames from ``to_pandas()`` when pandas is installed.
"""

from __future__ import annotations

import math
from typing import Any, Dict, Iterator, List, Optional, Sequence

import numpy as np

from . import _core

__all__ = [
    "Result",
    "Trajectory",
    "MapResult",
    "Orbit",
    "Classification",
    "Sweep",
    "Branch",
    "BoundaryCurve",
    "Boundary",
]


def _axes(ax: Any) -> Any:
    """The Axes to draw on: ``ax``, or matplotlib's current one."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    return plt.gca()


def _pandas() -> Any:
    """pandas, or an ImportError that says what to install."""
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("to_pandas() needs pandas: pip install pandas") from e
    return pandas


def _fmt(v: Any) -> str:
    """A number in a repr: 6 significant digits; other values as repr."""
    if isinstance(v, float):
        return f"{v:.6g}"
    return repr(v)


class Result(dict):
    """A dict with attribute access (``r.key`` is ``r["key"]``), as scipy's OptimizeResult."""

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError as e:
            raise AttributeError(
                f"{type(self).__name__} has no field {name!r}; fields: {', '.join(self.keys())}"
            ) from e

    def __dir__(self) -> List[str]:
        return sorted(set(super().__dir__()) | set(self.keys()))

    def _summary(self) -> str:
        return ", ".join(f"{k}={_fmt(v)}" for k, v in self.items() if isinstance(v, (int, float, str)))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._summary()})"


class Trajectory(Result):
    """A simulated trajectory (``gearbif.simulate``): t [s], beta [rad], omega [rad/s], for the gear
    also alpha and delta [rad]; events, x_end, mode, stats; jac with ``jacobians=True``."""

    def _summary(self) -> str:
        t = self["t"]
        span = f"t=[{t[0]:.6g}, {t[-1]:.6g}] s" if len(t) else "t=[]"
        return (
            f"samples={len(t)}, {span}, events={len(self['events'])}, mode={self['mode']!r}, "
            f"x_end=[{self['x_end'][0]:.6g} rad, {self['x_end'][1]:.6g} rad/s]"
        )

    def plot(self, ax: Any = None, y: Optional[str] = None, **kwargs: Any) -> Any:
        """Plots ``y`` against t [s]: "delta" (the gear's default) or "beta" in degrees, "omega"
        in rad/s. Keyword arguments go to ``ax.plot``."""
        ax = _axes(ax)
        y = y or ("delta" if "delta" in self else "beta")
        if y not in ("beta", "omega", "delta") or y not in self:
            raise ValueError(f"y must be one of {[k for k in ('beta', 'omega', 'delta') if k in self]}")
        values = np.asarray(self[y])
        label = {"beta": "β [deg]", "delta": "δ = β − α [deg]", "omega": "ω [rad/s]"}[y]
        if y != "omega":
            values = np.degrees(values)
        ax.plot(self["t"], values, **kwargs)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(label)
        return ax

    def to_pandas(self) -> Any:
        """The samples as a DataFrame: t and the state columns (one row per sample)."""
        cols = [k for k in ("t", "beta", "omega", "alpha", "delta") if k in self]
        return _pandas().DataFrame({k: np.asarray(self[k]) for k in cols})


class MapResult(Result):
    """One application of a Poincaré map (``gearbif.poincare_map``): x, jac_x, jac_p,
    multipliers, mode, events, stats."""

    def _summary(self) -> str:
        x = self["x"]
        s = f"x=[{x[0]:.6g} rad, {x[1]:.6g} rad/s]"
        if "multipliers" in self:
            s += ", |μ|=[" + ", ".join(f"{abs(m):.4g}" for m in self["multipliers"]) + "]"
        return s


class Orbit(Result):
    """A periodic orbit found by shooting (``gearbif.shoot``): x, multipliers, stable, residual,
    newton_iterations, spec, events."""

    def _summary(self) -> str:
        x = self["x"]
        mu = ", ".join(f"{abs(m):.4g}" for m in self["multipliers"])
        return (
            f"x=[{x[0]:.9g} rad, {x[1]:.9g} rad/s], stable={self['stable']}, |μ|=[{mu}], "
            f"residual={self['residual']:.2g}"
        )


class Classification(Result):
    """The classification of one attractor (``gearbif.classify``): the paper's flowchart and the
    rigorous class under ``event_driven``."""

    def _summary(self) -> str:
        ev = self.get("event_driven", {})
        rig = ev.get("rigorous") or {}
        paper = ev.get("paper") or {}
        parts = []
        if "theta_deg" in self:
            parts.append(f"Θ={self['theta_deg']:.6g}°, f={self['f_hz']:.6g} Hz")
        if rig:
            parts.append(f"class={rig.get('label')!r}, rotation_number={_fmt(rig.get('rotation_number'))}")
        if paper:
            parts.append(f"paper_class={paper.get('class')!r}, rms_delta_deg={_fmt(paper.get('rms_delta_deg'))}")
        return ", ".join(parts)


class Sweep(Result):
    """A two-parameter atlas (``gearbif.sweep``; the dict of sweep.json): spec and rows of points."""

    def points(self) -> List[Dict[str, Any]]:
        """Every grid point, rows in order: one dict per point (the columns of points.csv)."""
        return [p for row in self["rows"] for p in row["points"]]

    def _axis(self, which: str) -> Dict[str, Any]:
        return self["spec"][which]

    def _summary(self) -> str:
        r, c = self._axis("rows"), self._axis("cols")
        return (
            f"rows={r['param']} ({len(r['values'])} values), cols={c['param']} ({len(c['values'])} values), "
            f"protocol={self['spec']['protocol']!r}, points={len(self.points())}"
        )

    def grid(self, key: str) -> np.ndarray:
        """The value ``key`` of every point as a (rows, cols) array (NaN where missing)."""
        r, c = self._axis("rows"), self._axis("cols")
        out = np.full((len(r["values"]), len(c["values"])), np.nan)
        for p in self.points():
            v = p.get(key)
            out[p["row"], p["col"]] = np.nan if v is None else float(v)
        return out

    def plot(self, ax: Any = None, value: str = "rms_delta_deg", cmap: str = "viridis", **kwargs: Any) -> Any:
        """A colour map of ``value`` (a numeric column of points.csv, default RMS_δ [deg]) over the
        grid, columns on x, rows on y, with its colour bar."""
        ax = _axes(ax)
        r, c = self._axis("rows"), self._axis("cols")
        z = self.grid(value)
        mesh = ax.pcolormesh(_edges(c["values"]), _edges(r["values"]), z, cmap=cmap, shading="flat", **kwargs)
        ax.figure.colorbar(mesh, ax=ax, label=_UNITS.get(value, value))
        ax.set_xlabel(_UNITS.get(c["param"], c["param"]))
        ax.set_ylabel(_UNITS.get(r["param"], r["param"]))
        return ax

    def to_pandas(self) -> Any:
        """Every point as one row of a DataFrame (the columns of points.csv)."""
        return _pandas().DataFrame(self.points())


_UNITS = {
    "theta_deg": "Θ [deg]",
    "theta": "Θ [deg]",
    "f": "f [Hz]",
    "f_hz": "f [Hz]",
    "zeta": "ζ [1/s]",
    "eta": "η [1/s²]",
    "g": "g [1/s²]",
    "inertia": "inertia [kg m²]",
    "rms_delta_deg": "RMS_δ [deg]",
    "rms_fit_deg": "RMS of the fit residual [deg]",
    "delta_avg_deg": "mean δ [deg]",
    "net_rotation_hz": "net rotation [Hz]",
    "rotation_number": "rotation number [turns per period]",
    "lyapunov": "largest Lyapunov exponent [per period]",
    "thd": "THD_F",
}


def _edges(values: Sequence[float]) -> np.ndarray:
    """Cell edges around grid values (midpoints; the outer cells as wide as their neighbours)."""
    v = np.asarray(values, dtype=float)
    if len(v) == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])


class Branch:
    """A branch of periodic orbits (``gearbif.continuation``, ``gearbif.switch_branch``).

    Attributes (numpy arrays, one entry per point): param, x (n, 2), beta [rad], omega [rad/s],
    stable, multipliers (n, 2) complex, events (n, 3), arclength; param_name, specials (the
    located special points), stop, spec, map_evaluations, system. ``to_dict()`` is one entry of
    ``gearbif continue --json``."""

    __slots__ = ("_branch",)

    def __init__(self, branch: "_core.Branch") -> None:
        self._branch = branch

    def __getattr__(self, name: str) -> Any:
        return getattr(self._branch, name)

    def __len__(self) -> int:
        return len(self._branch)

    def __repr__(self) -> str:
        b = self._branch
        p = np.asarray(b.param)
        span = f"[{p.min():.6g}, {p.max():.6g}]" if len(p) else "[]"
        kinds = ", ".join(s.label for s in b.specials) or "none"
        return (
            f"Branch({b.param_name} in {span}, {len(b)} points, specials: {kinds}, "
            f"stop: {b.stop.get('reason')})"
        )

    def to_dict(self) -> Dict[str, Any]:
        """The branch as a dict: one entry of ``branches`` in ``gearbif continue --json``."""
        return self._branch.to_dict()

    def specials_table(self) -> List[Dict[str, Any]]:
        """The special points, one dict each: kind, label, param, precision, beta, omega,
        stability_change."""
        out = []
        for s in self._branch.specials:
            out.append(
                {
                    "kind": s.kind,
                    "label": s.label,
                    "param": s.param,
                    "precision": s.precision,
                    "beta": float(s.x[0]),
                    "omega": float(s.x[1]),
                    "stability_change": s.stability_change,
                }
            )
        return out

    def to_pandas(self, specials: bool = False) -> Any:
        """The points as a DataFrame (param, beta, omega, stable, |μ₁|, |μ₂|, arclength), or with
        ``specials=True`` the table of special points."""
        pd = _pandas()
        if specials:
            return pd.DataFrame(self.specials_table())
        b = self._branch
        mu = np.abs(np.asarray(b.multipliers))
        return pd.DataFrame(
            {
                b.param_name: np.asarray(b.param),
                "beta": np.asarray(b.beta),
                "omega": np.asarray(b.omega),
                "stable": np.asarray(b.stable),
                "abs_mu1": mu[:, 0] if len(mu) else [],
                "abs_mu2": mu[:, 1] if len(mu) else [],
                "arclength": np.asarray(b.arclength),
            }
        )

    def plot(self, ax: Any = None, y: str = "beta", color: Optional[str] = None, label: Optional[str] = None) -> Any:
        """The branch in the (parameter, y) plane: y = "beta" [deg, on the lift], "omega" [rad/s]
        or "abs_mu" (largest |μ|); stable pieces solid, unstable dashed, special points marked
        and labelled with their kind's short label."""
        ax = _axes(ax)
        b = self._branch
        p = np.asarray(b.param)
        if y == "beta":
            v, ylabel = np.degrees(np.asarray(b.beta)), "β at the section [deg]"
        elif y == "omega":
            v, ylabel = np.asarray(b.omega), "ω at the section [rad/s]"
        elif y == "abs_mu":
            v, ylabel = np.abs(np.asarray(b.multipliers))[:, 0], "largest |μ|"
        else:
            raise ValueError('y must be "beta", "omega" or "abs_mu"')
        stable = np.asarray(b.stable)
        line = None
        for s0, s1, st in _runs(stable):
            seg = slice(s0, min(s1 + 1, len(p)))
            (line,) = ax.plot(
                p[seg], v[seg], "-" if st else "--", color=color if line is None else line.get_color(),
                label=label if line is None else None,
            )
        for s in b.specials:
            sv = {"beta": math.degrees(s.x[0]), "omega": s.x[1]}.get(y)
            if sv is None:
                continue
            ax.plot([s.param], [sv], "o", color="k", ms=4)
            ax.annotate(s.label, (s.param, sv), textcoords="offset points", xytext=(4, 4), fontsize=8)
        ax.set_xlabel(_UNITS.get(b.param_name, b.param_name))
        ax.set_ylabel(ylabel)
        return ax


def _runs(flags: np.ndarray) -> Iterator[tuple]:
    """(start, end, value) of the runs of equal values in ``flags``."""
    n = len(flags)
    i = 0
    while i < n:
        j = i
        while j + 1 < n and flags[j + 1] == flags[i]:
            j += 1
        yield i, j, bool(flags[i])
        i = j + 1


class BoundaryCurve(Result):
    """One lock-loss curve f_c(Θ): label, winding, theta_deg [deg], f_c [Hz], precision [Hz],
    x (n, 2), stopped."""

    def _summary(self) -> str:
        th = np.asarray(self["theta_deg"])
        span = f"Θ in [{th.min():.6g}, {th.max():.6g}]°" if len(th) else "empty"
        return f"label={self['label']!r}, winding={self['winding']}, {span}, points={len(th)}"


class Boundary(list):
    """The lock-loss boundary (``gearbif.lock_loss_boundary``): a list of BoundaryCurve."""

    def __repr__(self) -> str:
        return "Boundary([" + ", ".join(repr(c) for c in self) + "])"

    def plot(self, ax: Any = None) -> Any:
        """f_c [Hz] against Θ [deg], one line per curve with its label in the legend."""
        ax = _axes(ax)
        for c in self:
            ax.plot(c["theta_deg"], c["f_c"], label=c["label"])
        ax.set_xlabel("Θ [deg]")
        ax.set_ylabel("f_c [Hz]")
        ax.legend(loc="best")
        return ax

    def to_pandas(self) -> Any:
        """Every point of every curve: label, winding, theta_deg, f_c, precision."""
        rows = [
            {"label": c["label"], "winding": c["winding"], "theta_deg": t, "f_c": f, "precision": e}
            for c in self
            for t, f, e in zip(c["theta_deg"], c["f_c"], c["precision"])
        ]
        return _pandas().DataFrame(rows)
