"""Validation cases: ``Case``, ``Tolerance`` and the registry filled by ``@case``.

A case is made by a factory function decorated ``@case(tags=..., units=...)``;
its keyword parameters (all with defaults) give variants for free::

    @case(tags=("jointed",), units={"length": "m"})
    def pivoted_rod(length=1.0, ...) -> Case: ...

    make_case("pivoted_rod", length=2.0)

``load_cases()`` loads every package registered in the entry-point group
``dalembert.cases``: the built-in ``dalembert.cases`` and any third party's.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import math
from dataclasses import asdict, dataclass, field, is_dataclass
from typing import Callable

import numpy as np

from dalembert.registry import Registry
from dalembert.scene import Scene, SceneError

__all__ = ["Tolerance", "Case", "CaseRecord", "CaseFactory", "case", "make_case", "load_cases", "CASES", "parse_param"]

CASES = Registry("case")


@dataclass(frozen=True)
class Tolerance:
    """A bound with its reason: ``value`` in the unit of the quantity it bounds."""

    value: float
    reason: str


@dataclass(frozen=True, eq=False)
class Case:
    """A named, versioned validation problem.

    Attributes
    ----------
    name : str
    scene : Scene
    t_final : float — horizon (s)
    sample_times : tuple of float — strictly increasing, from 0 to ``t_final`` (s)
    exact : callable or None — ``exact(t) -> Trajectory``, the closed-form truth at
        times ``t`` (ndarray (n,), s); None when the truth is the reference solver
    conserved : tuple of str — invariants the physics conserves (names in
        ``dalembert.invariants.CONSERVED``)
    tolerances : dict name -> Tolerance — agreement bounds with the truth:
        ``position`` (m), ``orientation`` (rad), ``velocity`` (m/s),
        ``angular_velocity`` (rad/s), ``joint`` (rad), and per conserved quantity
        its relative drift
    tags : tuple of str
    params : dict — the factory's keyword arguments that made this case
    """

    name: str
    scene: object
    t_final: float
    sample_times: tuple
    exact: Callable | None = None
    conserved: tuple = ()
    tolerances: dict = field(default_factory=dict)
    tags: tuple = ()
    params: dict = field(default_factory=dict)
    floor_fn: Callable | None = None

    def floor(self):
        """The achievable-accuracy floor, dict quantity -> value (e.g. ``orientation`` in rad), or {}.

        Computed once, on first use, from ``floor_fn`` (closed forms only: cheap, engine-free).
        """
        if self.floor_fn is None:
            return {}
        if "_floor" not in self.__dict__:
            self.__dict__["_floor"] = dict(self.floor_fn())
        return self.__dict__["_floor"]

    def __post_init__(self):
        object.__setattr__(self, "t_final", float(self.t_final))
        object.__setattr__(self, "sample_times", tuple(float(t) for t in np.ravel(self.sample_times)))
        problems = []
        if not (math.isfinite(self.t_final) and self.t_final > 0.0):
            problems.append(f"t_final: must be a positive duration (s), got {self.t_final!r}")
        ts = np.array(self.sample_times)
        if len(ts) < 2:
            problems.append("sample_times: need at least the start and the end")
        elif not np.all(np.isfinite(ts)):
            problems.append("sample_times: contains NaN or inf")
        else:
            if not np.all(np.diff(ts) > 0.0):
                k = int(np.argmin(np.diff(ts) > 0.0))
                problems.append(f"sample_times: not strictly increasing at index {k + 1} "
                                f"({ts[k]!r} then {ts[k + 1]!r}) — sort them and drop duplicates")
            if ts[0] != 0.0:
                problems.append(f"sample_times: must start at 0 (the initial state), got {ts[0]!r}")
            if ts[-1] != self.t_final:
                problems.append(f"sample_times: must end at t_final = {self.t_final!r}, got {ts[-1]!r}")
        for name, tol in self.tolerances.items():
            if not (isinstance(tol, Tolerance) and math.isfinite(tol.value) and tol.value > 0.0):
                problems.append(f"tolerances[{name!r}]: must be a Tolerance with a positive value")
        if problems:
            raise SceneError(f"case {self.name!r}", problems)

    @property
    def times(self):
        """Sample times as ndarray (n,), s."""
        return np.array(self.sample_times)

    @property
    def version(self):
        """Content hash (12 hex digits) of everything that defines the problem and judges a run:
        scene, horizon, sample times, parameters, tolerance values, conserved quantities."""
        payload = {
            "name": self.name,
            "scene": _canonical(self.scene),
            "t_final": self.t_final,
            "sample_times": self.sample_times,
            "params": _canonical(self.params),
            # what judges a run is part of the problem: change a bound, and runs stored
            # under the old one are of another version (the reasons are prose, not covered)
            "tolerances": {k: repr(t.value) for k, t in sorted(self.tolerances.items())},
            "conserved": list(self.conserved),
        }
        text = json.dumps(payload, sort_keys=True, default=repr)
        return hashlib.sha256(text.encode()).hexdigest()[:12]


@dataclass(frozen=True, eq=False)
class CaseRecord:
    """A case as it was run, as a results store keeps it: everything a report or a
    comparison needs, and no code (no closed form, no factory).

    Attributes
    ----------
    name, version : str — the case and its content hash (``Case.version``)
    params : dict — every parameter of the factory, defaults included
    scene : Scene
    t_final : float — horizon, s
    sample_times : tuple of float — s
    tolerances : dict name -> Tolerance — with their reasons
    conserved : tuple of str
    tags : tuple of str
    floor : dict quantity -> float — the achievable-accuracy floor (``Case.floor``), unit of the quantity
    truth : str — where the truth came from ("closed form", or the reference solver's settings)
    """

    name: str
    version: str
    params: dict
    scene: Scene
    t_final: float
    sample_times: tuple
    tolerances: dict
    conserved: tuple
    tags: tuple
    floor: dict
    truth: str

    @property
    def times(self):
        """Sample times as ndarray (n,), s."""
        return np.array(self.sample_times)

    @classmethod
    def from_case(cls, case, truth):
        """Record ``case`` (computing its floor) whose truth came from ``truth``."""
        return cls(case.name, case.version, dict(case.params), case.scene, case.t_final, case.sample_times,
                   dict(case.tolerances), tuple(case.conserved), tuple(case.tags), dict(case.floor()), truth)

    def to_json(self):
        return {"name": self.name, "version": self.version, "params": _canonical_json(self.params),
                "scene": self.scene.to_json(), "t_final": self.t_final, "sample_times": list(self.sample_times),
                "tolerances": {k: {"value": t.value, "reason": t.reason} for k, t in self.tolerances.items()},
                "conserved": list(self.conserved), "tags": list(self.tags), "floor": dict(self.floor),
                "truth": self.truth}

    @classmethod
    def from_json(cls, data):
        return cls(data["name"], data["version"],
                   {k: tuple(v) if isinstance(v, list) else v for k, v in data["params"].items()},
                   Scene.from_json(data["scene"]), float(data["t_final"]), tuple(data["sample_times"]),
                   {k: Tolerance(t["value"], t["reason"]) for k, t in data["tolerances"].items()},
                   tuple(data["conserved"]), tuple(data["tags"]), dict(data["floor"]), data["truth"])


def _canonical_json(params):
    return {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()}


def _canonical(obj):
    if is_dataclass(obj):
        return {k: _canonical(v) for k, v in asdict(obj).items()}
    if isinstance(obj, dict):
        return {str(k): _canonical(v) for k, v in sorted(obj.items())}
    if isinstance(obj, (list, tuple)):
        return [_canonical(v) for v in obj]
    if isinstance(obj, float):
        return repr(obj)  # round-trip exact
    return obj


@dataclass(frozen=True)
class CaseFactory:
    """A registered case family: the factory, its tags, parameter units, and the parameters that
    must be positive (every component of a vector one)."""

    name: str
    func: Callable
    tags: tuple
    units: dict
    positive: tuple = ()

    @property
    def params(self):
        """Keyword parameters and their defaults, as a dict."""
        return {p.name: p.default for p in inspect.signature(self.func).parameters.values()}

    @property
    def summary(self):
        """First paragraph of the factory's docstring, on one line."""
        doc = inspect.getdoc(self.func) or ""
        return " ".join(doc.split("\n\n")[0].split())

    def __call__(self, **params):
        known = self.params
        unknown = sorted(set(params) - set(known))
        if unknown:
            from dalembert.registry import suggest

            raise SceneError(f"case {self.name!r}", [
                f"parameter {k!r}: unknown{suggest(k, known)}" for k in unknown])
        problems = []
        for key, value in params.items():
            default = known[key]
            if isinstance(default, tuple) and (not isinstance(value, (tuple, list)) or len(value) != len(default)):
                problems.append(f"parameter {key!r}: expected {len(default)} numbers like {default!r}, got {value!r}")
        merged = {**known, **params}
        for key in self.positive:
            value = merged[key]
            if not all(math.isfinite(v) and v > 0.0 for v in (value if isinstance(value, (tuple, list)) else (value,))):
                unit = f" ({self.units[key]})" if key in self.units else ""
                problems.append(f"parameter {key!r}: must be positive{unit}, got {value!r}")
        if problems:
            raise SceneError(f"case {self.name!r}", problems)
        made = self.func(**params)
        return Case(made.name, made.scene, made.t_final, made.sample_times, made.exact, made.conserved,
                    made.tolerances, tuple(sorted(set(made.tags) | set(self.tags))), merged, made.floor_fn)


def case(tags=(), units=None, positive=()):
    """Register a case factory under its function name.

    Every parameter must have a default (a case runs without arguments). ``positive`` names the
    parameters that must be positive and finite (lengths, masses, radii: a zero-length rod would
    run "ok" with every error exactly 0), checked before the factory runs.
    """

    def register(func):
        sig = inspect.signature(func)
        missing = [p.name for p in sig.parameters.values() if p.default is inspect.Parameter.empty]
        if missing:
            raise TypeError(f"case {func.__name__!r}: parameters {missing} need defaults")
        unknown = sorted(set(positive) - set(sig.parameters))
        if unknown:
            raise TypeError(f"case {func.__name__!r}: positive={unknown} are not parameters of it")
        CASES.register(func.__name__, CaseFactory(func.__name__, func, tuple(tags), dict(units or {}),
                                                  tuple(positive)))
        return func

    return register


_LOADED = False


def load_cases():
    """Load every case package registered in the entry-point group ``dalembert.cases``
    (the built-in ``dalembert.cases`` is one of them) and return the registry."""
    global _LOADED
    if _LOADED:
        return CASES
    from importlib.metadata import entry_points

    for ep in entry_points(group="dalembert.cases"):
        try:
            ep.load()
        except Exception as e:
            raise ImportError(f"cases entry point {ep.name!r} ({ep.value}) failed to load: "
                              f"{type(e).__name__}: {e} — fix or uninstall the package that declares it") from e
    _LOADED = True
    return CASES


def make_case(name, **params):
    """Build the registered case ``name`` with keyword ``params`` overriding defaults."""
    return load_cases()[name](**params)


def parse_param(factory, text):
    """Parse ``KEY=VALUE`` for ``factory``, typed after the parameter's default.

    Vectors are comma-separated numbers (``omega0=0,1,1``).
    """
    if "=" not in text:
        raise ValueError(f"--param {text!r}: write KEY=VALUE")
    key, value = text.split("=", 1)
    defaults = factory.params
    if key not in defaults:
        from dalembert.registry import suggest

        raise ValueError(f"--param {key!r}: case {factory.name!r} has no such parameter{suggest(key, defaults)}")
    default = defaults[key]
    try:
        if isinstance(default, bool):
            if value.lower() not in ("true", "false", "1", "0"):
                raise ValueError
            return key, value.lower() in ("true", "1")
        if isinstance(default, int):
            return key, int(value)
        if isinstance(default, float):
            return key, float(value)
        if isinstance(default, tuple):
            return key, tuple(float(v) for v in value.split(","))
        return key, value
    except ValueError:
        raise ValueError(f"--param {key}={value!r}: expected {type(default).__name__} "
                         f"like {default!r}") from None
