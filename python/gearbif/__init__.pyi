# Type stubs of the package gearbif: what editors and type checkers see. The signatures are the
# extension's (python/src); python/tests/test_stubs.py checks names, parameters and defaults
# against the module at run time.
from os import PathLike
from typing import Any, Callable, Dict, Iterator, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

__version__: str

Section = Literal["stroboscopic", "half_period"]
Method = Literal["dop853", "event"]
Convention = Literal["physical", "paper"]
Axis = Union[str, Tuple[str, Sequence[float]]]
StrPath = Union[str, "PathLike[str]"]

# ---------------------------------------------------------------- errors
class GearbifError(Exception): ...
class InvalidParameterError(GearbifError, ValueError):
    name: str
    value: float
class InvalidInputError(GearbifError, ValueError):
    kind: str
class IntegrationError(GearbifError, RuntimeError): ...
class NewtonError(GearbifError, RuntimeError): ...
class ContinuationError(GearbifError, RuntimeError):
    kind: str
class GearbifIOError(GearbifError, OSError): ...
class UnsupportedError(GearbifError, NotImplementedError):
    kind: str
class NoPeriodError(GearbifError, RuntimeError): ...
class RecordingError(GearbifError, ValueError):
    file: str
    line: Optional[int]

# ---------------------------------------------------------------- systems
class GearParams:
    def __init__(
        self,
        m1: float = 3.51,
        m2: float = 3.51,
        r: float = 0.040,
        inertia: float = 6.45e-5,
        theta_deg: float = 0.0,
        phi_deg: Optional[float] = None,
        zeta: float = 1.1,
        eta: float = 23.1,
    ) -> None: ...
    @staticmethod
    def paper(theta_deg: float = 0.0) -> GearParams: ...
    def driven(self, f: float, alpha0_deg: float = 0.0, convention: Convention = "physical") -> Gear: ...
    def to_dict(self) -> Dict[str, float]: ...
    @property
    def m1(self) -> float: ...
    @property
    def m2(self) -> float: ...
    @property
    def r(self) -> float: ...
    @property
    def inertia(self) -> float: ...
    @property
    def theta_deg(self) -> float: ...
    @property
    def phi_deg(self) -> float: ...
    @property
    def zeta(self) -> float: ...
    @property
    def eta(self) -> float: ...
    @property
    def g(self) -> float: ...
    @property
    def delta(self) -> float: ...
    @property
    def lock_loss_frequency(self) -> Optional[float]: ...

class _System:
    @property
    def period(self) -> float: ...
    @property
    def param_names(self) -> List[str]: ...
    @property
    def params(self) -> Dict[str, float]: ...

class Gear(_System):
    def __init__(
        self,
        g: float,
        delta: float,
        zeta: float,
        eta: float,
        f: float,
        alpha0_deg: float = 0.0,
        convention: Convention = "physical",
    ) -> None: ...
    @staticmethod
    def paper(theta_deg: float, f: float) -> Gear: ...
    def with_param(self, name: str, value: float) -> Gear: ...
    def forces(self, t: float, beta: float, omega: float) -> Tuple[float, float]: ...
    @property
    def f(self) -> float: ...
    @property
    def g(self) -> float: ...
    @property
    def delta(self) -> float: ...
    @property
    def zeta(self) -> float: ...
    @property
    def eta(self) -> float: ...
    @property
    def theta_deg(self) -> float: ...
    @property
    def alpha0_deg(self) -> float: ...
    @property
    def convention(self) -> str: ...
    @property
    def lock_loss_frequency(self) -> Optional[float]: ...
    def lock_branch(self) -> Dict[str, Any]: ...

class CoulombOscillator(_System):
    def __init__(self, omega0: float, xi: float, mu: float, force: float, f: float) -> None: ...
    def with_param(self, name: str, value: float) -> CoulombOscillator: ...
    def forces(self, t: float, x: float, v: float) -> Tuple[float, float]: ...
    @property
    def f(self) -> float: ...
    @property
    def omega0(self) -> float: ...
    @property
    def xi(self) -> float: ...
    @property
    def mu(self) -> float: ...
    @property
    def force(self) -> float: ...

class ForcedPendulum(_System):
    def __init__(self, omega0: float, gamma: float, mu: float, amplitude: float, f: float) -> None: ...
    def with_param(self, name: str, value: float) -> ForcedPendulum: ...
    def forces(self, t: float, x: float, v: float) -> Tuple[float, float]: ...
    @property
    def f(self) -> float: ...
    @property
    def omega0(self) -> float: ...
    @property
    def gamma(self) -> float: ...
    @property
    def mu(self) -> float: ...
    @property
    def amplitude(self) -> float: ...

class UserSystem(_System):
    def __init__(
        self,
        forces: Union[Callable[[float, float, float, Dict[str, float]], Tuple[float, float]], Tuple[str, str]],
        params: Dict[str, float],
        *,
        jacobian: Optional[Callable[..., Any]] = None,
        symmetry: Optional[Tuple[float, float]] = None,
        angular: bool = True,
    ) -> None: ...
    def with_param(self, name: str, value: float) -> UserSystem: ...
    def forces(self, t: float, beta: float, omega: float) -> Tuple[float, float]: ...

class Model(_System):
    @staticmethod
    def load(path: StrPath, f: float = 1.0) -> Model: ...
    def with_param(self, name: str, value: float) -> Model: ...
    def locate(
        self,
        kind: Literal["fold", "flip", "sb", "ns"],
        x: ArrayLike,
        *,
        param: str = "f",
        section: Section = "stroboscopic",
        period: int = 1,
        winding: int = 1,
        tol: float = 1e-11,
    ) -> Dict[str, Any]: ...
    @property
    def covariance(self) -> Tuple[List[str], List[List[float]]]: ...
    def forces(self, t: float, beta: float, omega: float) -> Tuple[float, float]: ...
    @property
    def f(self) -> float: ...

System = Union[Gear, CoulombOscillator, ForcedPendulum, UserSystem, Model]

# ---------------------------------------------------------------- results
class Result(Dict[str, Any]):
    def __getattr__(self, name: str) -> Any: ...

class Trajectory(Result):
    t: NDArray[np.float64]
    beta: NDArray[np.float64]
    omega: NDArray[np.float64]
    events: List[Dict[str, Any]]
    x_end: NDArray[np.float64]
    mode: str
    def plot(self, ax: Any = None, y: Optional[str] = None, **kwargs: Any) -> Any: ...
    def to_pandas(self) -> Any: ...

class MapResult(Result):
    x: NDArray[np.float64]

class Orbit(Result):
    x: NDArray[np.float64]
    stable: bool

class Classification(Result): ...

class Sweep(Result):
    def points(self) -> List[Dict[str, Any]]: ...
    def grid(self, key: str) -> NDArray[np.float64]: ...
    def plot(self, ax: Any = None, value: str = "rms_delta_deg", cmap: str = "viridis", **kwargs: Any) -> Any: ...
    def to_pandas(self) -> Any: ...

class SpecialPoint:
    @property
    def kind(self) -> str: ...
    @property
    def label(self) -> str: ...
    @property
    def param(self) -> float: ...
    @property
    def precision(self) -> float: ...
    @property
    def x(self) -> NDArray[np.float64]: ...
    @property
    def multipliers(self) -> NDArray[np.complex128]: ...
    @property
    def test_value(self) -> float: ...
    @property
    def eigenvector(self) -> Optional[NDArray[np.float64]]: ...
    @property
    def stability_change(self) -> bool: ...
    @property
    def index(self) -> int: ...
    @property
    def jump(self) -> Optional[Dict[str, Any]]: ...
    def to_dict(self) -> Dict[str, Any]: ...

class Branch:
    param_name: str
    param: NDArray[np.float64]
    x: NDArray[np.float64]
    beta: NDArray[np.float64]
    omega: NDArray[np.float64]
    stable: NDArray[np.bool_]
    multipliers: NDArray[np.complex128]
    events: NDArray[np.float64]
    arclength: NDArray[np.float64]
    specials: List[SpecialPoint]
    stop: Dict[str, Any]
    spec: Dict[str, Any]
    map_evaluations: int
    system: System
    gear: System
    def __len__(self) -> int: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def specials_table(self) -> List[Dict[str, Any]]: ...
    def to_pandas(self, specials: bool = False) -> Any: ...
    def plot(self, ax: Any = None, y: str = "beta", color: Optional[str] = None, label: Optional[str] = None) -> Any: ...

class BoundaryCurve(Result):
    label: str
    winding: int
    theta_deg: NDArray[np.float64]
    f_c: NDArray[np.float64]
    precision: NDArray[np.float64]

class Boundary(List[BoundaryCurve]):
    def plot(self, ax: Any = None) -> Any: ...
    def to_pandas(self) -> Any: ...

# ---------------------------------------------------------------- functions
def simulate(
    system: System,
    x0: ArrayLike,
    t_end: float,
    *,
    t0: float = 0.0,
    samples_per_period: int = 50,
    sample_times: Optional[ArrayLike] = None,
    tol: float = 1e-9,
    method: Method = "dop853",
    jacobians: bool = False,
) -> Trajectory: ...
def poincare_map(
    system: System,
    x: ArrayLike,
    *,
    section: Section = "stroboscopic",
    iterations: int = 1,
    tol: float = 1e-10,
    jacobians: bool = True,
    method: Method = "dop853",
) -> MapResult: ...
def multipliers(jac: ArrayLike) -> NDArray[np.complex128]: ...
def shoot(
    system: System,
    x0: ArrayLike,
    *,
    section: Section = "half_period",
    iterations: int = 1,
    winding: Optional[int] = None,
    tol: float = 1e-11,
    newton_tol: float = 1e-9,
    max_iter: int = 30,
) -> Orbit: ...
def continuation(
    system: System,
    x0: Optional[ArrayLike] = None,
    *,
    param: str = "f",
    range: Tuple[float, float],
    lock: Optional[Literal["stable", "unstable"]] = None,
    section: Section = "half_period",
    iterations: int = 1,
    winding: Optional[int] = None,
    ds: float = 0.02,
    ds_max: float = 0.1,
    ds_min: float = 1e-7,
    max_steps: int = 2000,
    tol: float = 1e-11,
    newton_tol: float = 1e-9,
    max_multiplier: float = 1e4,
    locate_tol: float = 1e-8,
) -> Branch: ...
def switch_branch(
    branch: Branch,
    special: Union[SpecialPoint, int],
    *,
    dparam: float = -1e-3,
    ds: Optional[float] = None,
    ds_max: Optional[float] = None,
    max_steps: Optional[int] = None,
    range: Optional[Tuple[float, float]] = None,
) -> Tuple[Branch, Orbit]: ...
def lock_loss_boundary(
    gear: Optional[Union[Gear, GearParams]] = None, *, step_deg: float = 2.0, tol: float = 1e-11
) -> Boundary: ...
def classify(
    system: System,
    x0: Optional[ArrayLike] = None,
    *,
    settle_turns: int = 90,
    record_turns: int = 10,
    samples_per_turn: int = 50,
    rigorous: bool = True,
    analysis_turns: int = 60,
    tol: float = 1e-9,
    keep_samples: bool = False,
    method: Method = "dop853",
) -> Classification: ...
def sweep(
    rows: Optional[Axis] = None,
    cols: Optional[Axis] = None,
    *,
    params: Optional[GearParams] = None,
    f: float = 1.0,
    protocol: Literal["fresh", "semi_static"] = "fresh",
    alpha0_deg: float = 90.0,
    beta0_deg: float = 90.0,
    convention: Convention = "physical",
    settle_turns: Optional[int] = None,
    record_turns: int = 10,
    analysis_turns: int = 60,
    tol: float = 1e-9,
    out_dir: Optional[StrPath] = None,
    method: Method = "dop853",
) -> Sweep: ...
def sweep_grid(
    system: System,
    rows: Axis,
    cols: Axis,
    *,
    x0: Optional[ArrayLike] = None,
    protocol: Literal["fresh", "semi_static"] = "fresh",
    settle_turns: int = 90,
    record_turns: int = 10,
    samples_per_turn: int = 50,
    analysis_turns: int = 60,
    tol: float = 1e-9,
    method: Method = "dop853",
) -> Result: ...
def synth(
    out_dir: StrPath,
    effect: str = "none",
    size: float = 0.0,
    *,
    ringdowns: int = 12,
    driven: int = 8,
    turns: float = 80.0,
    f_range: Optional[Tuple[float, float]] = None,
    samples_per_turn: int = 50,
    fps: float = 100.0,
    noise_deg: float = 0.5,
    seed: int = 1,
) -> Dict[str, Any]: ...
def fit(set_dir: StrPath, *, tol: Optional[float] = None) -> Result: ...
def diagnose(
    set_dir: StrPath,
    *,
    heldout: bool = True,
    out_dir: Optional[StrPath] = None,
    tol: Optional[float] = None,
    profile_shapes: bool = False,
) -> Result: ...
