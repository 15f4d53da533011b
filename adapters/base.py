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

from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable

from dalembert.registry import suggest
from dalembert.scene import SPRING_EFFECT

__all__ = ["Adapter", "IntegratorSpec", "Outcome", "option_choice"]


@dataclass(frozen=True)
class IntegratorSpec:
    """What an engine's integrator takes: ``dt`` (fixed step) or ``rtol``/``atol``, and options."""

    fixed_step: bool
    options: tuple = ()
    description: str = ""


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

    def version(self):
        raise NotImplementedError

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
        if problems:
            raise ValueError("; ".join(problems))

    def unsupported(self, scene, settings):
        """The reason this engine cannot represent ``scene``, or None."""
        missing = sorted(scene.effects - self.effects)
        if missing:
            reason = f"{self.name} adapter cannot represent {', '.join(missing)}"
            notes = []
            if any(m.startswith("loop:") for m in missing):
                notes.append("closed kinematic loops: not yet built for this engine; its tree runs, the closure does not")
            if SPRING_EFFECT in missing:
                notes.append("linear spring-dampers between two points: not yet built for this engine; its bodies and "
                             "joints run, the spring's force does not")
            return reason + (f" ({'; '.join(notes)})" if notes else "")
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


def option_choice(settings, key, choices):
    """The value of engine option ``key`` (``choices[0]`` when absent); a ValueError naming the
    option and its choices when it is not one of them."""
    value = settings.options.get(key, choices[0])
    if value not in choices:
        raise ValueError(f"options.{key}: unknown {value!r} — use one of {list(choices)}")
    return value
