"""gearbif: exact (Filippov, event-driven) simulation, Poincaré maps with Jacobians, periodic
orbits, continuation with special points, classification, sweeps and identification of
periodically driven oscillators with dry friction — the dipole magnetic gear of Hartung & Rehberg
(2020) built in, and any system written in Python (UserSystem).

Units: t [s], f [Hz], β [rad], ω [rad/s] (states on the lift); shaft angles Θ, Φ in degrees
(arguments ending in ``_deg``).

Results are objects: ``simulate`` returns a Trajectory, ``continuation`` a Branch, ``sweep`` a
Sweep, …; each is also the dict of the CLI's JSON (docs/formats.md) and has ``plot(ax=...)`` or
``to_pandas()`` where they make sense. Errors are subclasses of GearbifError and of the builtin a
Python user expects (a bad value is also a ValueError).
"""

from __future__ import annotations

import functools
from typing import Any, Callable

from . import _core, _results
from ._core import (
    ContinuationError,
    CoulombOscillator,
    ForcedPendulum,
    Gear,
    GearbifError,
    GearbifIOError,
    GearParams,
    IntegrationError,
    InvalidInputError,
    InvalidParameterError,
    Model,
    NewtonError,
    NoPeriodError,
    RecordingError,
    SpecialPoint,
    UnsupportedError,
    UserSystem,
    __version__,
    multipliers,
    synth,
)
from ._results import (
    Boundary,
    BoundaryCurve,
    Branch,
    Classification,
    MapResult,
    Orbit,
    Result,
    Sweep,
    Trajectory,
)

# the public names by what a user does with them (docs/python-api.md is written in this order)
_GROUPS = {
    "Systems": ["GearParams", "Gear", "CoulombOscillator", "ForcedPendulum", "UserSystem", "Model"],
    "Dynamics": ["simulate", "poincare_map", "multipliers", "shoot"],
    "Continuation": ["continuation", "switch_branch", "lock_loss_boundary", "SpecialPoint"],
    "Atlas": ["classify", "sweep", "sweep_grid"],
    "Recordings": ["synth", "fit", "diagnose"],
    "Results": list(_results.__all__),
    "Errors": [
        "GearbifError",
        "InvalidParameterError",
        "InvalidInputError",
        "IntegrationError",
        "NewtonError",
        "ContinuationError",
        "GearbifIOError",
        "UnsupportedError",
        "NoPeriodError",
        "RecordingError",
    ],
}

__all__ = ["__version__"] + [name for names in _GROUPS.values() for name in names]


def _wrap(name: str, result: Callable[[Any], Any]) -> Callable[..., Any]:
    """The extension's function ``name`` with its result made a result object by ``result``; the
    docstring and the signature (``inspect.signature`` follows ``__wrapped__``) are the
    extension's."""
    core = getattr(_core, name)

    @functools.wraps(core)
    def call(*args: Any, **kwargs: Any) -> Any:
        return result(core(*args, **kwargs))

    call.__module__ = __name__
    return call


def _boundary(curves: Any) -> Boundary:
    return Boundary(BoundaryCurve(c) for c in curves)


def _switched(out: Any) -> Any:
    branch, start = out
    return Branch(branch), Orbit(start)


simulate = _wrap("simulate", Trajectory)
poincare_map = _wrap("poincare_map", MapResult)
shoot = _wrap("shoot", Orbit)
classify = _wrap("classify", Classification)
sweep = _wrap("sweep", Sweep)
sweep_grid = _wrap("sweep_grid", Result)
fit = _wrap("fit", Result)
diagnose = _wrap("diagnose", Result)
continuation = _wrap("continuation", Branch)
lock_loss_boundary = _wrap("lock_loss_boundary", _boundary)
_switch_core = _wrap("switch_branch", _switched)


@functools.wraps(_core.switch_branch)
def switch_branch(branch: Any, special: Any, **kwargs: Any) -> Any:
    return _switch_core(branch._branch if isinstance(branch, Branch) else branch, special, **kwargs)


switch_branch.__module__ = __name__
