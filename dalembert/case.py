"""Validation cases: ``Case`` (a named, versioned problem) and ``CaseRecord`` (a case as a store keeps it).

The one import path of a case author: it re-exports ``Tolerance``, ``Invariant`` and the loop-closure
invariants (``dalembert.tolerance``), the registry, ``@case``, ``load_cases`` and ``make_case``
(``dalembert.case_registry``) and ``parse_param`` (``dalembert.params``).

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
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field, is_dataclass
from typing import Callable

import numpy as np

from dalembert.case_registry import CASES, OUT_OF_DEFAULT, CaseFactory, case, in_default_matrix, load_cases, make_case
from dalembert.errors import QUANTITIES
from dalembert.invariants import CONSERVED
from dalembert.params import parse_param
from dalembert.registry import suggest
from dalembert.scene import Scene, SceneError
from dalembert.tolerance import (LOOP_RESIDUALS, Invariant, InvariantLabel, Tolerance, invariant_problems,
                                 loop_closure_invariants)

__all__ = ["Tolerance", "Invariant", "InvariantLabel", "Case", "CaseRecord", "CaseFactory", "case", "make_case",
           "load_cases", "CASES", "parse_param", "OUT_OF_DEFAULT", "in_default_matrix", "LOOP_RESIDUALS",
           "loop_closure_invariants"]


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
        problems += invariant_problems(self.invariants)
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

    def in_family(self, name, tags, params, units):
        """This case as the registered family ``name`` made it (``case_registry.CaseFactory``): its tags joined
        with the family's, with every parameter of the factory (``params``, defaults included) and their
        ``units``. Raises ``SceneError`` when the factory named its case otherwise."""
        if self.name != name:
            raise SceneError(f"case {name!r}", [f"name: the factory made a case named {self.name!r} — name the "
                                                "case after its factory (the registry finds it by that name)"])
        return Case(self.name, self.scene, self.t_final, self.sample_times, self.exact, self.conserved,
                    self.tolerances, tuple(sorted(set(self.tags) | set(tags))), dict(params), self.floor_fn,
                    self.invariants, dict(units))

    @property
    def version(self):
        """Content hash (12 hex digits) of everything that defines the problem and judges a run:
        scene, horizon, sample times, parameters, tolerance values, conserved quantities, declared
        invariants (name, unit, scale; the code of their series is not covered)."""
        scene = _canonical(self.scene)
        for name in ("springs", "geoms", "planes", "contacts"):
            if isinstance(scene, dict) and not scene.get(name, True):
                del scene[name]  # (absent when none, so cases without springs or contact keep their versions)
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
                # (a metric's kind is written, an invariant's left out: stores without metrics keep their files)
                "invariants": [{"name": i.name, "description": i.description, "unit": i.unit, "scale": i.scale,
                                **({"kind": i.kind} if i.kind != "invariant" else {}),
                                **({"headline": True} if i.headline else {})}
                               for i in self.invariants], "units": dict(self.units)}

    @classmethod
    def from_json(cls, data):
        return cls(data["name"], data["version"],
                   {k: tuple(v) if isinstance(v, list) else v for k, v in data["params"].items()},
                   Scene.from_json(data["scene"]), float(data["t_final"]), tuple(data["sample_times"]),
                   {k: Tolerance(t["value"], t["reason"]) for k, t in data["tolerances"].items()},
                   tuple(data["conserved"]), tuple(data["tags"]), dict(data["floor"]), data["truth"],
                   tuple(InvariantLabel(i["name"], i["description"], i["unit"], float(i["scale"]),
                                        i.get("kind", "invariant"), bool(i.get("headline", False)))
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
