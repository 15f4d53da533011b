"""The adapter base class and what its methods take and return.

The contract every adapter meets is the numbered checklist in
``dalembert.adapters`` (its package docstring).

Frames. An engine carries each body in a frame of its own, E, which need not
be the scene's body frame B (origin at the COM, docs/DESIGN.md). Every adapter names
the pose of B in E ``X_EB`` (monogram notation, ``dalembert.spatial``), held as
``(p_EB, R_EB)`` with ``x_E = p_EB + R_EB x_B`` (a ``pin.SE3`` in Pinocchio);
where E is B, ``X_EB`` is the identity. E is

* MuJoCo: MuJoCo's body frame: B for a free body, the child joint frame for a
  jointed one (``mujoco.mjcf.engine_frames``);
* Pinocchio: the frame of the joint that carries the body: B for a
  FreeFlyer, the child joint frame (B at a lever) for a revolute or spherical
  joint, the parent's E for a body welded into its parent
  (``PinocchioModel.X_EB``);
* Exudyn: a kinematic-tree link's frame, the child joint frame turned so that
  z is the joint axis (``exudyn.model.build``); B for a rigid body.

The parent's frames, where a joint is placed, are ``Ep`` and ``P``: ``X_EpP``
is the parent's ``X_EB``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable

import numpy as np

from dalembert.registry import suggest
from dalembert.scene import SPRING_EFFECT

__all__ = ["Adapter", "IntegratorSpec", "Option", "Outcome", "Prepared", "option_value", "typed_options"]


@dataclass(frozen=True)
class IntegratorSpec:
    """What an engine's integrator takes: ``dt`` (fixed step) or ``rtol``/``atol``, and options; ``order``: the
    order of accuracy it declares (None: not declared), which ``dalembert check-engine`` measures."""

    fixed_step: bool
    options: tuple = ()
    description: str = ""
    order: int | None = None


@dataclass(frozen=True)
class Option:
    """One engine option and the values it takes, declared once on the adapter (``Adapter.options``, name ->
    ``Option``) and checked by ``Adapter.check`` before anything runs.

    Attributes
    ----------
    choices : tuple of str — the values it takes (empty: a number, bounded by ``minimum``/``maximum``)
    default : object — the value a run takes when the option is not given (None: the engine's own, or one that
        depends on the scene, as ``description`` says)
    description : str — what it chooses, one line (``dalembert engines --verbose``)
    minimum, maximum : float or None — a number's closed bounds
    exclusive_minimum : float or None — a number's open lower bound (``> exclusive_minimum``)
    integer : bool — a number that must be whole (an iteration count)
    only : tuple of str — the integrators that take it (empty: every integrator whose ``IntegratorSpec.options``
        names it)
    """

    choices: tuple = ()
    default: object = None
    description: str = ""
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: float | None = None
    integer: bool = False
    only: tuple = ()

    def allowed(self):
        """The values it takes, in words: ``"tree, equality"`` or ``"a number in [0, 1]"``."""
        if self.choices:
            return ", ".join(str(c) for c in self.choices)
        if self.integer:
            return f"a whole number >= {self.minimum:g}" if self.minimum is not None else "a whole number"
        if self.exclusive_minimum is not None:
            return f"a number > {self.exclusive_minimum:g}" + (f", <= {self.maximum:g}" if self.maximum is not None else "")
        if self.minimum is not None or self.maximum is not None:
            return f"a number in [{'-inf' if self.minimum is None else f'{self.minimum:g}'}, " \
                   f"{'inf' if self.maximum is None else f'{self.maximum:g}'}]"
        return "a number"

    def problem(self, name, value, integrator):
        """What is wrong with ``value`` for option ``name`` under ``integrator``, in the project's words, or None."""
        if self.only and integrator not in self.only:
            return f"options.{name}: only {', '.join(self.only)} takes it — drop it, or use {' or '.join(self.only)}"
        if self.choices:
            if value not in self.choices:
                return f"options.{name}: unknown {value!r} — use one of {self.allowed()}"
            return None
        try:
            number = float(value)
        except (TypeError, ValueError):
            return f"options.{name}: expected a number, got {value!r} — give {self.allowed()}"
        if ((self.minimum is not None and not number >= self.minimum)
                or (self.maximum is not None and not number <= self.maximum)
                or (self.exclusive_minimum is not None and not number > self.exclusive_minimum)
                or not math.isfinite(number)):
            return f"options.{name}: {number!r} is out of range — give {self.allowed()}"
        if self.integer and number != int(number):
            return f"options.{name}: {number!r} is not a whole number — give {self.allowed()}"
        return None

    def typed(self, value):
        """``value`` (as given: option values are text) as the engine takes it: a choice as text, a number as a
        float, or an int where ``integer``; None stays None (the engine's own default)."""
        if value is None or self.choices:
            return value
        return int(float(value)) if self.integer else float(value)


def option_value(options, settings, key):
    """The value of option ``key`` a run with ``settings`` takes: the given one, else its declared default.

    ``options``: name -> ``Option``, an adapter's declaration (``Adapter.options``) or the part of it that a module
    building the engine's model declares where it reads it (``exudyn.model.MODEL_OPTIONS``,
    ``mujoco.mjcf.MJCF_OPTIONS``); a key it does not declare is a KeyError, not a silent default.
    """
    return settings.options.get(key, options[key].default)


def typed_options(options, settings):
    """Every option of ``options`` (name -> ``Option``) that a run with ``settings`` takes, as the engine takes it
    (``Option.typed`` of ``option_value``): a module's parsed view of the declaration that ``Adapter.check`` has
    checked, so no module parses or checks its own options again. ``settings`` None: the declared defaults."""
    given = {} if settings is None else settings.options
    return {key: option.typed(given.get(key, option.default)) for key, option in options.items()}


@dataclass(frozen=True, eq=False)
class Prepared:
    """What ``Adapter.prepare`` returns and ``run`` and ``audit`` take: one scene's engine model, built for one set
    of sample times and settings. Each engine extends it with the fields its runs need (``MujocoPrepared``,
    ``PinocchioPrepared``, ...), each documented there.

    Attributes
    ----------
    scene : dalembert.scene.Scene — what was built
    times : ndarray (n,) — the sample times, s
    settings : dalembert.settings.Settings — the run's settings (integrator, dt or tolerances, options)

    Its fields are read as attributes (``prepared.times``), never by name: a misspelt field is then an
    AttributeError where it is read.
    """

    scene: object
    times: np.ndarray
    settings: object


@dataclass(frozen=True, eq=False)
class Outcome:
    """What ``Adapter.run`` returns: what the stepping cost, and the trajectory it produced.

    Attributes
    ----------
    read_back : callable () -> Trajectory
        Turns the engine's sampled states into body terms. Called once, the first time
        ``trajectory`` is used: the harness's timed repeats never pay for it.
    wall_s : float — wall time of the stepping alone, s
    n_steps, n_rhs : int — steps taken and right-hand-side evaluations
    info : dict — what the engine reported (messages, which loop ran, ...); a read-back may add to it
    """

    read_back: Callable
    wall_s: float
    n_steps: int
    n_rhs: int
    info: dict = field(default_factory=dict)

    @cached_property
    def trajectory(self):
        """The sampled ``Trajectory`` in body terms (read back on first use)."""
        return self.read_back()


class Adapter:
    """Base class with the shared checks; the contract is in ``dalembert.adapters``."""

    name = ""
    effects = frozenset()
    integrators = {}
    # name -> Option: every option an integrator's ``IntegratorSpec.options`` names, and the values it takes
    options = {}
    # The engine versions this adapter runs, a PEP 440 specifier (``">=3.2"``; empty: any), and why not the
    # others (an API or MJCF the adapter needs that older releases lack): an engine environment at a version
    # outside it is refused with the reason (``version_problem``).
    supported_versions = ""
    unsupported_versions_why = ""
    # Integrators that only some of the supported versions have: name -> (PEP 440 specifier, why); a run of one at
    # an engine version outside its specifier is refused with the reason (``unsupported``: ``integrator_problem``).
    integrator_versions = {}
    # Why an effect the engine lacks is lacking, by effect or effect family ("loop" names every "loop:..."): the
    # note ``unsupported`` gives after the effects it names. An engine names its own (the reason, what it would take).
    refusal_notes = {
        "loop": "closed kinematic loops: not yet built for this engine; its tree runs, the closure does not",
        SPRING_EFFECT: ("linear spring-dampers between two points: not yet built for this engine; its bodies and "
                        "joints run, the spring's force does not"),
    }

    def version(self):
        raise NotImplementedError

    def version_problem(self, version):
        """Why engine version ``version`` (str) cannot be run by this adapter (``supported_versions``), or None."""
        from packaging.specifiers import SpecifierSet

        if not self.supported_versions or SpecifierSet(self.supported_versions).contains(version, prereleases=True):
            return None
        why = f" ({self.unsupported_versions_why})" if self.unsupported_versions_why else ""
        return f"{self.name} {version} is outside the versions its adapter supports, {self.supported_versions}{why}"

    def integrator_problem(self, integrator, version):
        """Why ``integrator`` cannot run at engine version ``version`` (str; ``integrator_versions``), or None."""
        from packaging.specifiers import SpecifierSet

        specifier, why = self.integrator_versions.get(integrator, ("", ""))
        if not specifier or SpecifierSet(specifier).contains(version, prereleases=True):
            return None
        return f"{self.name} {version} has no {integrator!r} integrator ({why}): it runs at {self.name}{specifier}"

    def load(self):
        """Import the engine (once per process; ImportError when it is missing): a worker loads its engines
        before its first run, so that no run's time holds an import."""
        self.version()

    def check(self, scene, times, settings):
        """Raise ValueError naming the field when ``settings`` cannot be run."""
        from dalembert.settings import knob_problems

        if settings.integrator not in self.integrators:
            raise ValueError(f"integrator: {self.name} has no {settings.integrator!r}"
                             f"{suggest(settings.integrator, self.integrators)}")
        spec = self.integrators[settings.integrator]
        problems = knob_problems(settings, f"{self.name} {settings.integrator!r}", spec.fixed_step, spec.options, times)
        for key, value in settings.options.items():
            if key in spec.options and key in self.options:
                problem = self.options[key].problem(key, value, settings.integrator)
                if problem:
                    problems.append(problem)
        if problems:
            raise ValueError("; ".join(problems))

    def option(self, settings, key):
        """The value of option ``key`` a run with ``settings`` takes: the given one, else the declared default."""
        return option_value(self.options, settings, key)

    def unsupported(self, scene, settings):
        """The reason this engine cannot represent ``scene`` (the effects it lacks, each with its
        ``refusal_notes`` note) or run ``settings``' integrator at its version (``integrator_versions``), or None."""
        if settings.integrator in self.integrator_versions:
            problem = self.integrator_problem(settings.integrator, self.version())
            if problem:
                return problem
        missing = sorted(scene.effects - self.effects)
        if not missing:
            return None
        notes = []
        for key, note in self.refusal_notes.items():
            if any(m == key or m.startswith(key + ":") for m in missing) and note not in notes:
                notes.append(note)
        reason = f"{self.name} adapter cannot represent {', '.join(missing)}"
        return reason + (f" ({'; '.join(notes)})" if notes else "")

    def unsupported_before_build(self, scene, settings):
        """The part of ``unsupported`` known from ``scene`` and ``settings`` alone, before the engine builds a
        model: what ``dalembert run`` asks before it expands the matrix, so that a refused run is listed once in
        the manifest, never made a run. Default: ``unsupported`` itself (an engine whose every refusal is
        declared: effects, options, the scene's parts). An engine whose ``unsupported`` also builds the model (MJX:
        ``mjx.put_model``) returns here all but that part, with the same text; the rest stays a run's refusal."""
        return self.unsupported(scene, settings)

    def beyond_scene(self, scene, settings):
        """What a run with ``settings`` simulates beyond ``scene`` because the user asked for it (a robot file's own
        damping, friction and limits as the engine read them), as words, or None (this default: the run simulates
        the scene). Such a run is a finding about the engine, not judged against the case's tolerances, which hold
        for the scene alone (``dalembert.judge``'s ``beyond_scene``)."""
        return None

    def variants(self, scene):
        """Engine option sets the default matrix runs on ``scene`` (``[{}]``: the defaults only)."""
        return [{}]

    def describe(self, scene, settings):
        """The model the engine builds for ``scene`` with ``settings``, as text: what a report stores with the run
        (the record's ``model``) and ``dalembert show-model`` prints (MJCF, a plant's or a system's summary).
        Built without stepping; ``""`` where the engine describes none (this default), and then nothing is stored."""
        return ""

    def prepare(self, scene, times, settings):
        """Build the engine's model of ``scene`` for sampling at ``times`` with ``settings`` (already passed by
        ``check`` and ``unsupported``); not timed: everything that is not stepping belongs here.

        Parameters
        ----------
        scene : dalembert.scene.Scene
        times : array_like (n,) — the sample times, s, increasing; the first is the initial state's
        settings : dalembert.settings.Settings

        Returns
        -------
        Prepared — the engine's subclass, with the built model and the initial state; ``run`` may be called on
        it any number of times
        """
        raise NotImplementedError

    def run(self, prepared):
        """Simulate ``prepared`` from its initial state, sampling at exactly ``prepared.times``.

        Parameters
        ----------
        prepared : Prepared — from ``prepare``; a run leaves it as it found it, so repeated runs give identical
            results

        Returns
        -------
        Outcome — the wall time of the stepping alone (s), steps and right-hand-side evaluations, and the
        read-back to a ``Trajectory`` in body terms (run once, on first use). A run that diverges returns NaN
        from the point of divergence on; one the engine stops raises RuntimeError saying where
        """
        raise NotImplementedError

    def repro(self, scene, times, settings, quantity):
        """The engine's part of a standalone reproduction of one run (``dalembert repro``): Python source that
        imports the engine (numpy is imported and ``TIMES``, the sample times (n,) in s, defined before it; never
        dalembert), builds the model as the engine's own input (MJCF, the engine's API calls), sets the run's
        settings and defines ``simulate()``: stepping with the engine's own API from the initial state through
        ``TIMES`` with the arithmetic ``run`` used, it returns ``{name: ndarray (n, k)}`` of ``quantity`` at every
        sample — ``"joint"``: each revolute or prismatic joint's coordinate (n, 1), rad or m, by its child's name;
        ``"orientation"``: each body's ``q_WB`` (n, 4), scalar first, world, as the engine produced it (not
        normalized), or its ``R_WB`` (n, 3, 3) where the read-back turns a matrix into it (the script then does, by
        ``spatial.matrix_to_quat``'s arithmetic) — and sets ``ENGINE_VERSION``.

        The default finds the module ``repro`` beside the adapter's (``adapters/<engine>/repro.py``: its
        ``repro(adapter, scene, times, settings, quantity)``); without one, and wherever that module does not cover
        the run, ValueError "where: what — fix"."""
        import importlib

        package = type(self).__module__.rpartition(".")[0]
        try:
            module = importlib.import_module(f"{package}.repro") if package else None
        except ModuleNotFoundError as e:
            if e.name != f"{package}.repro":
                raise
            module = None
        if module is None:
            raise ValueError(f"engine: no repro for this engine ({self.name}) — dalembert repro writes runs of the "
                             "engines that have one (adapters/<engine>/repro.py); dalembert export gives this run's "
                             "trajectory")
        return module.repro(self, scene, times, settings, quantity)

    def audit(self, prepared, outcome):
        """What the engine actually simulated, read back from the engine (not from the scene): a dict with at
        least ``gravity`` (m/s^2, world axes) and what else the engine reports (loads, joints, constraint rows,
        contacts, passive forces, the integrator by the engine's name). ``outcome``: a ``run`` of ``prepared``."""
        return {}

