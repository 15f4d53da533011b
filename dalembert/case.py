"""Validation cases: ``Case``, ``Tolerance`` and the registry filled by ``@case``.

A case is made by a factory function decorated ``@case(tags=..., units=...)``;
its keyword parameters (all with defaults) give variants for free::

    @case(tags=("jointed",), units={"length": "m"})
    def pivoted_rod(length=1.0, ...) -> Case: ...

    make_case("pivoted_rod", length=2.0)

Everything a case declares is checked when it is made, before anything runs
(``SceneError``, one line per problem, "where.field: what is wrong — the fix"):
unknown ``conserved`` or tolerance names (with a did-you-mean), a tolerance
without a reason, a conserved quantity without a bound, a declared
``Invariant`` whose name clashes with a built-in one, and, when the factory is
registered, a factory without a ``t_final`` parameter or a parameter without a
default. Each parameter's domain (``positive``, ``counts``; finite and within
``params.MAX_MAGNITUDE`` for every numeric one) is declared once in ``@case`` and
checked every time the case is made, before the factory runs (``dalembert.params``).
``docs/cases.md`` walks through writing a case.

``load_cases()`` loads every package registered in the entry-point group
``dalembert.cases``: the built-in ``dalembert.cases`` and any third party's.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import math
import re
from dataclasses import asdict, dataclass, field, is_dataclass
from typing import Callable

import numpy as np

from dalembert.errors import QUANTITIES
from dalembert.invariants import CONSERVED, loop_residual
from dalembert.params import domain_problems
from dalembert.registry import Registry, suggest
from dalembert.scene import Scene, SceneError

__all__ = ["Tolerance", "Invariant", "InvariantLabel", "Case", "CaseRecord", "CaseFactory", "case", "make_case",
           "load_cases", "CASES", "parse_param", "OUT_OF_DEFAULT", "in_default_matrix", "LOOP_RESIDUALS",
           "loop_closure_invariants"]

CASES = Registry("case")
# Tags that keep a case out of the default matrix (``dalembert run`` with no selection, ``dalembert
# validate``): ``hard`` (long, fast, chaotic: run them with ``--tag hard``) and ``variant`` (presets
# and variants of a canonical case, e.g. a published benchmark's set-up: run them by name or with
# ``--tag variant``).
OUT_OF_DEFAULT = ("hard", "variant")


def in_default_matrix(factory):
    """Whether the case family ``factory`` (a ``CaseFactory``) runs in the default matrix."""
    return not set(OUT_OF_DEFAULT) & set(factory.tags)


@dataclass(frozen=True)
class Tolerance:
    """A bound with its reason: ``value`` in the unit of the quantity it bounds."""

    value: float
    reason: str


# A declared invariant's name becomes the column ``drift_<name>`` of a stored run
# (``dalembert.record``): an identifier, and not ``rate_...`` (``drift_rate_<name>`` columns).
_INVARIANT_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


@dataclass(frozen=True)
class InvariantLabel:
    """What a results store keeps of a declared ``Invariant``: its label, no code.

    Attributes
    ----------
    name : str — the key of its drift (``RunRecord.drifts``, column ``drift_<name>``)
    description : str — what is conserved, with its frame and reference point
    unit : str — unit of the quantity (and of ``scale``)
    scale : float — the drift is ``max_t |x(t) - x(0)| / scale`` (dimensionless)
    """

    name: str
    description: str
    unit: str
    scale: float


@dataclass(frozen=True, eq=False)
class Invariant:
    """A conserved quantity a case declares for itself: a named scalar function of the
    scene and a trajectory, computed by the harness from every run (never taken from an
    engine) and stored and judged like the built-in ones (``dalembert.invariants.CONSERVED``).

    Attributes
    ----------
    name : str — lowercase identifier, not a built-in conserved quantity or error name; its drift
        is stored under it (``RunRecord.drifts[name]``, column ``drift_<name>``)
    description : str — what is conserved, with its frame and reference point
        (e.g. "angular momentum about the pivot, world z component")
    unit : str — unit of ``series`` (e.g. "kg m^2/s")
    scale : float — positive, in ``unit``: the typical size of the quantity; the drift is
        ``max_t |x(t) - x(0)| / scale``
    tolerance : Tolerance — bound on that drift (dimensionless), with its reason; the case's
        ``tolerances[name]``
    series : callable ``(scene, traj) -> ndarray (n,)`` — the quantity at each sample of ``traj``
        (a ``dalembert.trajectory.Trajectory``), in ``unit``
    """

    name: str
    description: str
    unit: str
    scale: float
    tolerance: Tolerance
    series: Callable

    def drift_series(self, scene, traj):
        """``|x(t) - x(0)| / scale`` at each sample, ndarray (n,), dimensionless."""
        x = np.asarray(self.series(scene, traj), dtype=float)
        if x.shape != traj.t.shape:
            raise ValueError(f"invariant {self.name!r}: series returned shape {x.shape}, expected {traj.t.shape} "
                             "(one value per sample)")
        return np.abs(x - x[0]) / self.scale

    def drift(self, scene, traj):
        """The largest ``drift_series`` over the trajectory (NaN when a value is not finite)."""
        d = self.drift_series(scene, traj)
        return float(np.max(d)) if np.all(np.isfinite(d)) else float("nan")

    @property
    def label(self):
        """The ``InvariantLabel`` a store keeps."""
        return InvariantLabel(self.name, self.description, self.unit, float(self.scale))


# The declared invariants of a case that closes loops, by level: their drifts are the worst closure
# residuals over a run (``RunRecord.drifts``), and reports look them up by these names.
LOOP_RESIDUALS = {"position": "loop_residual_position", "velocity": "loop_residual_velocity"}


def loop_closure_invariants(where, length, speed, tolerance):
    """The two ``Invariant`` of a scene's loop closures (``invariants.loop_residual``), position and
    velocity level, scaled by the mechanism's ``length`` (m) and its fastest point's ``speed`` (m/s),
    each bounded by ``tolerance``; ``where`` names the closures (e.g. "the coupler-rocker revolute at C")."""
    def one(level, scale, unit, per_s):
        return Invariant(LOOP_RESIDUALS[level], f"largest loop-closure residual at {level} level ({where}; {unit}, "
                         f"or the sine of an axis' tilt{per_s})", unit, scale, tolerance,
                         lambda scene, traj: loop_residual(scene, traj, level))

    return one("position", length, "m", ""), one("velocity", speed, "m/s", ", per s")


def _invariant_problems(invariants):
    problems, seen = [], set()
    for i, inv in enumerate(invariants):
        where = f"invariants[{i}]"
        if not isinstance(inv, Invariant):
            problems.append(f"{where}: expected an Invariant(name, description, unit, scale, tolerance, series), "
                            f"got {type(inv).__name__}")
            continue
        where = f"{where} ({inv.name!r})"
        if not (isinstance(inv.name, str) and _INVARIANT_NAME.match(inv.name)) or inv.name.startswith("rate_"):
            problems.append(f"{where}.name: must be a lowercase identifier (letters, digits, _) not starting with "
                            "'rate_' — it names the stored column drift_<name>")
        elif inv.name in CONSERVED or inv.name in QUANTITIES:
            problems.append(f"{where}.name: {inv.name!r} is a built-in name — list it in conserved, or rename yours")
        elif inv.name in seen:
            problems.append(f"{where}.name: declared twice — give every invariant its own name")
        seen.add(inv.name)
        if not (isinstance(inv.scale, (int, float)) and math.isfinite(inv.scale) and inv.scale > 0.0):
            problems.append(f"{where}.scale: must be a positive number in {inv.unit!r}, got {inv.scale!r} — the "
                            "typical size of the quantity, which makes its drift relative")
        if not (isinstance(inv.description, str) and inv.description.strip()):
            problems.append(f"{where}.description: empty — say what is conserved, with its frame and point")
        if not (isinstance(inv.unit, str) and inv.unit.strip()):
            problems.append(f"{where}.unit: empty — give the unit of the series (\"1\" if dimensionless)")
        if not isinstance(inv.tolerance, Tolerance):
            problems.append(f"{where}.tolerance: must be a Tolerance(value, reason)")
        if not callable(inv.series):
            problems.append(f"{where}.series: must be a function (scene, traj) -> ndarray (n,)")
    return problems


def _dissipation_problems(conserved, springs):
    """``energy`` listed as conserved while a damper takes energy out of the motion."""
    damped = [sp for sp in springs if sp.damping > 0.0]
    if "energy" not in conserved or not damped:
        return []
    names = ", ".join(f"{sp.name!r} (damping {sp.damping:g} N s/m)" for sp in damped)
    return [f"conserved[{list(conserved).index('energy')}]: 'energy' is not conserved: the springs {names} dissipate "
            "it — list 'energy_balance' instead (kinetic + potential energy - the loads' work + the dampers' "
            "dissipation, which is)"]


def _tolerance_problems(tolerances, conserved, declared):
    """Unknown names, missing reasons, and conserved quantities nothing bounds."""
    problems = []
    known = set(QUANTITIES) | set(conserved) | set(declared)
    for name, tol in tolerances.items():
        where = f"tolerances[{name!r}]"
        if not (isinstance(tol, Tolerance) and isinstance(tol.value, (int, float)) and math.isfinite(tol.value)
                and tol.value > 0.0):
            problems.append(f"{where}: must be a Tolerance with a positive value")
        elif not (isinstance(tol.reason, str) and tol.reason.strip()):
            problems.append(f"{where}.reason: empty — say in one line why this bound (its unit, what it is "
                            "measured against)")
        if name in known:
            continue
        if name in CONSERVED:
            problems.append(f"{where}: bounds {name!r}, which the case does not list in conserved, so it would "
                            f"never be checked — add {name!r} to conserved, or drop the tolerance")
        else:
            problems.append(f"{where}: unknown name{suggest(name, known)} (errors: {', '.join(QUANTITIES)}; "
                            "or a conserved quantity of the case)")
    for name in conserved:
        if name in CONSERVED and name not in tolerances:
            problems.append(f"conserved: {name!r} has no bound — add tolerances[{name!r}] = Tolerance(value, reason)")
    return problems


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
    conserved : tuple of str — built-in invariants the physics conserves (names in
        ``dalembert.invariants.CONSERVED``), each bounded in ``tolerances``
    tolerances : dict name -> Tolerance — agreement bounds with the truth, named after
        ``dalembert.errors.QUANTITIES``: ``position`` (m), ``orientation`` (rad), ``velocity``
        (m/s), ``angular_velocity`` (rad/s), ``joint`` (rad), ``reaction_force`` (relative);
        and per conserved quantity its drift (scaled as in ``CONSERVED``). Each declared
        invariant's tolerance is added under its name.
    tags : tuple of str
    params : dict — the factory's keyword arguments that made this case
    floor_fn : callable or None — ``floor_fn() -> dict``, see ``floor``
    invariants : tuple of Invariant — conserved quantities the case declares for itself
    units : dict — the unit of each parameter (from ``@case(units=...)``)
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
    invariants: tuple = ()
    units: dict = field(default_factory=dict)

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
        object.__setattr__(self, "conserved", tuple(self.conserved))
        object.__setattr__(self, "invariants", tuple(self.invariants))
        for i, name in enumerate(self.conserved):
            if name not in CONSERVED:
                problems.append(f"conserved[{i}]: unknown {name!r}{suggest(name, CONSERVED)} — or declare a quantity "
                                "of your own in invariants=(Invariant(...),)")
        problems += _invariant_problems(self.invariants)
        problems += _dissipation_problems(self.conserved, getattr(self.scene, "springs", ()))
        tolerances = dict(self.tolerances)
        for inv in self.invariants:
            if isinstance(inv, Invariant) and isinstance(inv.tolerance, Tolerance):
                if tolerances.setdefault(inv.name, inv.tolerance) != inv.tolerance:
                    problems.append(f"tolerances[{inv.name!r}]: also given by invariants ({inv.name!r}).tolerance "
                                    "with another value — give it once, in the Invariant")
        object.__setattr__(self, "tolerances", tolerances)
        declared = [inv.name for inv in self.invariants if isinstance(inv, Invariant)]
        problems += _tolerance_problems(tolerances, self.conserved, declared)
        if problems:
            raise SceneError(f"case {self.name!r}", problems)

    @property
    def times(self):
        """Sample times as ndarray (n,), s."""
        return np.array(self.sample_times)

    @property
    def version(self):
        """Content hash (12 hex digits) of everything that defines the problem and judges a run:
        scene, horizon, sample times, parameters, tolerance values, conserved quantities, declared
        invariants (name, unit, scale; the code of their series is not covered)."""
        scene = _canonical(self.scene)
        if isinstance(scene, dict) and not scene.get("springs", True):
            del scene["springs"]  # (absent when none, so cases without springs keep their versions)
        payload = {
            "name": self.name,
            "scene": scene,
            "t_final": self.t_final,
            "sample_times": self.sample_times,
            "params": _canonical(self.params),
            # what judges a run is part of the problem: change a bound, and runs stored
            # under the old one are of another version (the reasons are prose, not covered)
            "tolerances": {k: repr(t.value) for k, t in sorted(self.tolerances.items())},
            "conserved": list(self.conserved),
        }
        if self.invariants:  # (absent when none, so cases without any keep their versions)
            payload["invariants"] = [[i.name, i.unit, repr(float(i.scale))] for i in self.invariants]
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
    units : dict — each parameter's unit ({} in stores written before they were recorded)
    invariants : tuple of InvariantLabel — the case's declared invariants (name, description,
        unit, scale), so a report can label their drifts (``RunRecord.drifts[name]``)
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
    invariants: tuple = ()
    units: dict = field(default_factory=dict)

    @property
    def times(self):
        """Sample times as ndarray (n,), s."""
        return np.array(self.sample_times)

    @classmethod
    def from_case(cls, case, truth):
        """Record ``case`` (computing its floor) whose truth came from ``truth``."""
        return cls(case.name, case.version, dict(case.params), case.scene, case.t_final, case.sample_times,
                   dict(case.tolerances), tuple(case.conserved), tuple(case.tags), dict(case.floor()), truth,
                   tuple(i.label for i in case.invariants), dict(case.units))

    def to_json(self):
        return {"name": self.name, "version": self.version, "params": _canonical_json(self.params),
                "scene": self.scene.to_json(), "t_final": self.t_final, "sample_times": list(self.sample_times),
                "tolerances": {k: {"value": t.value, "reason": t.reason} for k, t in self.tolerances.items()},
                "conserved": list(self.conserved), "tags": list(self.tags), "floor": dict(self.floor),
                "truth": self.truth,
                "invariants": [{"name": i.name, "description": i.description, "unit": i.unit, "scale": i.scale}
                               for i in self.invariants], "units": dict(self.units)}

    @classmethod
    def from_json(cls, data):
        return cls(data["name"], data["version"],
                   {k: tuple(v) if isinstance(v, list) else v for k, v in data["params"].items()},
                   Scene.from_json(data["scene"]), float(data["t_final"]), tuple(data["sample_times"]),
                   {k: Tolerance(t["value"], t["reason"]) for k, t in data["tolerances"].items()},
                   tuple(data["conserved"]), tuple(data["tags"]), dict(data["floor"]), data["truth"],
                   tuple(InvariantLabel(i["name"], i["description"], i["unit"], float(i["scale"]))
                         for i in data.get("invariants", ())), dict(data.get("units", {})))


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
    """A registered case family: the factory, its tags, parameter units, and its parameters' domains
    (``dalembert.params``): those that must be positive (every component of a vector one) and those
    that count things (whole numbers >= 1). Calling it checks the parameters, then makes the case."""

    name: str
    func: Callable
    tags: tuple
    units: dict
    positive: tuple = ()
    counts: tuple = ()

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
            raise SceneError(f"case {self.name!r}", [
                f"parameter {k!r}: unknown{suggest(k, known)}" for k in unknown])
        merged = {**known, **params}
        problems = domain_problems(self.name, known, params, self.positive, self.counts, self.units)
        if problems:
            raise SceneError(f"case {self.name!r}", problems)
        made = self.func(**params)
        if not isinstance(made, Case):
            raise SceneError(f"case {self.name!r}", [f"factory: returned {type(made).__name__}, not a Case"])
        if made.name != self.name:
            raise SceneError(f"case {self.name!r}", [f"name: the factory made a case named {made.name!r} — name the "
                                                     "case after its factory (the registry finds it by that name)"])
        return Case(made.name, made.scene, made.t_final, made.sample_times, made.exact, made.conserved,
                    made.tolerances, tuple(sorted(set(made.tags) | set(self.tags))), merged, made.floor_fn,
                    made.invariants, dict(self.units))


def case(tags=(), units=None, positive=(), counts=()):
    """Register a case factory under its function name.

    Every parameter must have a default (a case runs without arguments), and one of
    them is ``t_final`` (s): the contract tests and ``--param t_final=...`` shorten a
    case through it. Each parameter's domain is declared here, once, and checked every time
    the case is made, before the factory runs (``dalembert.params.domain_problems``):
    ``positive`` names the parameters that must be positive (lengths, masses, radii, inertias,
    sample intervals: a zero-length rod would run "ok" with every error exactly 0), ``counts``
    those that are whole numbers >= 1 (links, bodies); every numeric parameter must be finite
    and within ``params.MAX_MAGNITUDE``, and ``t_final`` positive. Raises ``SceneError`` naming
    the case and the parameter ("case.param: what is wrong — the fix"); a declaration the
    defaults themselves break is refused at registration.
    """

    def register(func):
        sig = inspect.signature(func)
        problems = [f"parameter {p.name!r}: has no default — every parameter needs one (a case runs without "
                    "arguments)" for p in sig.parameters.values() if p.default is inspect.Parameter.empty]
        if "t_final" not in sig.parameters:
            problems.append("t_final: the factory has no t_final parameter — add t_final=<horizon, s> and pass it to "
                            "Case (the contract tests and --param t_final=... shorten a case through it)")
        for label, names in (("positive", positive), ("counts", counts)):
            problems += [f"{label}: {k!r} is not a parameter of it" for k in sorted(set(names) - set(sig.parameters))]
        problems += [f"positive, counts: {k!r} is in both — a count is a whole number >= 1, declare it in counts"
                     for k in sorted(set(positive) & set(counts))]
        if problems:
            raise SceneError(f"case {func.__name__!r}", problems)
        defaults = {p.name: p.default for p in sig.parameters.values()}
        problems = [f"default: {p}" for p in domain_problems(func.__name__, defaults, defaults, positive, counts,
                                                             units)]
        if problems:
            raise SceneError(f"case {func.__name__!r}", problems)
        CASES.register(func.__name__, CaseFactory(func.__name__, func, tuple(tags), dict(units or {}),
                                                  tuple(positive), tuple(counts)))
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
