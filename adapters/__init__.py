"""Engine adapters: one interface, many engines, chosen by name.

The contract — every adapter class:

1. is registered under a lowercase engine name: built-in ones in ``BUILTIN``
   below (``"module:Class"``, imported only when asked for), third-party ones
   through the entry-point group ``dalembert.adapters``;
2. imports its engine lazily, inside its methods, so listing and help work
   without it; ``version()`` returns the engine's version (and raises
   ImportError when the engine is missing);
3. declares ``effects``: the ``Scene.effects`` tags it can represent. A scene
   that needs another effect is not run: the harness stores it as
   ``unsupported`` with the reason — never a silent approximation;
4. declares ``integrators``: name -> ``IntegratorSpec`` (fixed-step or
   adaptive, and the engine options it accepts); ``variants(scene)`` lists the
   option sets the default matrix runs on a scene (e.g. each formulation);
5. ``check(scene, times, settings)`` raises ValueError naming the field for
   settings it cannot run (unknown option, dt that does not divide the sample
   interval, ...) — cheap, called before anything runs; ``unsupported(scene,
   settings)`` returns the reason a valid request cannot be represented, or None;
6. ``prepare(scene, times, settings)`` builds the engine model (not timed);
7. ``run(prepared)`` simulates from the initial state and samples at exactly
   ``times``, returning an ``Outcome``: a ``Trajectory`` in body terms
   (converted through ``dalembert.spatial`` only), the wall time of the
   stepping alone, steps and right-hand-side evaluations. It can be called
   repeatedly on one prepared model and gives identical results each time (the
   harness warms up once, then repeats for timing). A run that diverges
   returns NaN from the point of divergence on, never an exception;
8. ``audit(prepared, outcome)`` returns what the engine actually simulated,
   read back from the engine: gravity vector, loads, joints, constraint rows,
   contacts, passive forces, the integrator as the engine names it;
9. writes no files and prints nothing.

``check_adapter(name)`` runs this contract on every registered case the
adapter supports.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field

from dalembert.registry import Registry, UnknownNameError, suggest

__all__ = ["Adapter", "IntegratorSpec", "Outcome", "BUILTIN", "adapter_names", "adapter_path", "get_adapter",
           "register_adapter", "check_adapter", "option_choice"]

BUILTIN = {
    "reference": "dalembert.adapters.reference:ReferenceAdapter",
    "mujoco": "dalembert.adapters.mujoco:MujocoAdapter",
    "pinocchio": "dalembert.adapters.pinocchio:PinocchioAdapter",
    "exudyn": "dalembert.adapters.exudyn:ExudynAdapter",
}


@dataclass(frozen=True)
class IntegratorSpec:
    """What an engine's integrator takes: ``dt`` (fixed step) or ``rtol``/``atol``, and options."""

    fixed_step: bool
    options: tuple = ()
    description: str = ""


@dataclass(frozen=True, eq=False)
class Outcome:
    """What ``Adapter.run`` returns: trajectory, stepping wall time (s), steps, RHS evaluations."""

    trajectory: object
    wall_s: float
    n_steps: int
    n_rhs: int
    info: dict = field(default_factory=dict)


class Adapter:
    """Base class with the shared checks; see the module docstring for the contract."""

    name = ""
    effects = frozenset()
    integrators = {}

    def version(self):
        raise NotImplementedError

    def check(self, scene, times, settings):
        """Raise ValueError naming the field when ``settings`` cannot be run."""
        from dalembert.settings import knob_problems

        if settings.integrator not in self.integrators:
            raise ValueError(f"integrator: {self.name} has no {settings.integrator!r}"
                             f"{suggest(settings.integrator, self.integrators)}")
        spec = self.integrators[settings.integrator]
        problems = knob_problems(settings, f"{self.name} {settings.integrator!r}", spec.fixed_step, spec.options, times)
        if problems:
            raise ValueError("; ".join(problems))

    def unsupported(self, scene, settings):
        """The reason this engine cannot represent ``scene``, or None."""
        missing = sorted(scene.effects - self.effects)
        if missing:
            return f"{self.name} adapter cannot represent {', '.join(missing)}"
        return None

    def variants(self, scene):
        """Engine option sets the default matrix runs on ``scene`` (``[{}]``: the defaults only)."""
        return [{}]

    def prepare(self, scene, times, settings):
        raise NotImplementedError

    def run(self, prepared):
        raise NotImplementedError

    def audit(self, prepared, outcome):
        return {}


_REGISTRY = Registry("engine")


def option_choice(settings, key, choices):
    """The value of engine option ``key`` (``choices[0]`` when absent); a ValueError naming the
    option and its choices when it is not one of them."""
    value = settings.options.get(key, choices[0])
    if value not in choices:
        raise ValueError(f"options.{key}: unknown {value!r} — use one of {list(choices)}")
    return value


def _entry_points():
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group="dalembert.adapters")}


def register_adapter(name, cls):
    """Register an adapter class under ``name`` programmatically (plugins, tests).

    The class must be importable by module and name: worker processes that do
    not share this process's memory (forkserver, Dask) import it from there.
    """
    BUILTIN.pop(name, None)
    _REGISTRY.register(name, cls)
    return cls


def adapter_path(name):
    """``"module:Class"`` of the adapter registered as ``name`` (how another process imports it)."""
    if name in _REGISTRY:
        cls = _REGISTRY[name]
        return f"{cls.__module__}:{cls.__qualname__}"
    if name in BUILTIN:
        return BUILTIN[name]
    eps = _entry_points()
    if name in eps:
        return eps[name].value
    raise UnknownNameError(f"unknown engine {name!r}{suggest(name, adapter_names())}")


def adapter_names():
    """Every registered engine name (built-in, programmatic and entry points), sorted."""
    return sorted(set(BUILTIN) | set(_entry_points()) | set(_REGISTRY))


def get_adapter(name, path=None):
    """An instance of the adapter registered as ``name`` (imported on first use).

    ``path`` (``"module:Class"``) lets a worker process import an adapter that
    was registered programmatically in its parent.
    """
    if name not in _REGISTRY and path and name not in BUILTIN:
        module, cls = path.split(":")
        obj = getattr(importlib.import_module(module), cls)
        if name not in _REGISTRY:  # importing the module may have registered it already
            _REGISTRY.register(name, obj)
    if name not in _REGISTRY:
        if name in BUILTIN:
            module, cls = BUILTIN[name].split(":")
            _REGISTRY.register(name, getattr(importlib.import_module(module), cls))
        elif name in (eps := _entry_points()):
            _REGISTRY.register(name, eps[name].load())
        else:
            raise UnknownNameError(f"unknown engine {name!r}{suggest(name, adapter_names())}")
    return _REGISTRY[name]()


def check_adapter(name, cases=None, settings=None):
    """Run the contract on every registered case ``name`` supports; returns a list of problems.

    Parameters
    ----------
    name : str — engine name
    cases : iterable of Case, optional — default: every registered case (defaults)
    settings : callable(integrator name, IntegratorSpec) -> Settings, optional —
        default: dt = the sample interval for fixed-step, rtol = atol = 1e-8 otherwise
    """
    import numpy as np

    from dalembert.case import load_cases
    from dalembert.settings import Settings
    from dalembert.trajectory import Trajectory

    adapter = get_adapter(name)
    problems = []
    adapter.version()
    if cases is None:
        cases = [factory() for _, factory in load_cases().items()]
    for case in cases:
        for integ, spec in adapter.integrators.items():
            if settings is not None:
                s = settings(integ, spec)
            elif spec.fixed_step:
                s = Settings(integ, dt=float(case.times[1] - case.times[0]))
            else:
                s = Settings(integ, rtol=1e-8, atol=1e-8)
            where = f"{name} {case.name} {s.label()}"
            adapter.check(case.scene, case.times, s)
            if adapter.unsupported(case.scene, s):
                continue
            prepared = adapter.prepare(case.scene, case.times, s)
            first, second = adapter.run(prepared), adapter.run(prepared)
            traj = first.trajectory
            if not isinstance(traj, Trajectory):
                problems.append(f"{where}: run() must return a Trajectory")
                continue
            if not np.array_equal(traj.t, case.times):
                problems.append(f"{where}: not sampled at exactly the case's times")
            if set(traj.bodies) != {b.name for b in case.scene.bodies}:
                problems.append(f"{where}: bodies {sorted(traj.bodies)} != scene's")
            for bname, b in traj.bodies.items():
                if not np.array_equal(b.quaternion, second.trajectory.bodies[bname].quaternion,
                                      equal_nan=True):
                    problems.append(f"{where}: a repeated run gave different results")
            if not (first.wall_s >= 0.0 and first.n_steps >= 0 and first.n_rhs >= 0):
                problems.append(f"{where}: cost figures must be non-negative")
            audit = adapter.audit(prepared, first)
            if "gravity" not in audit:
                problems.append(f"{where}: the audit must report the gravity vector")
            elif not np.allclose(audit["gravity"], case.scene.gravity, rtol=0, atol=0):
                problems.append(f"{where}: engine gravity {audit['gravity']} != scene {case.scene.gravity}")
    return problems
