"""``PybulletAdapter``: the contract (``dalembert.adapters``) for PyBullet 3.2.7.

``prepare`` builds the scene twice (``model.build``): the run's client and a scratch client for the
read-back and the audit's probe, each checked against the scene's mass properties; ``run`` steps
(``stepping``) and reads the states back in body terms (``readback``); ``audit`` (the module) reads
PyBullet's parameters, bodies and joints back from the engine.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, Prepared
from dalembert.adapters.pybullet import contact
from dalembert.adapters.pybullet.audit import audit
from dalembert.adapters.pybullet.model import MODEL_OPTIONS, build, engine, root_of
from dalembert.adapters.pybullet.stepping import load_plan, simulate
from dalembert.scene import CONTACT_EFFECTS, EFFECTS, SPRING_EFFECT, WORLD
from dalembert.settings import steps_per_interval

__all__ = ["PybulletAdapter", "PybulletPrepared"]

# What each effect PyBullet's adapter does not map would take (``unsupported``).
NOT_MAPPED = {
    "loop": ("closed kinematic loops: PyBullet closes a loop only with createConstraint's point-to-point, fixed "
             "or gear constraints between multibody links, solved by its iterative constraint solver (soft, "
             "ERP-stabilized), not mapped yet; a revolute loop has no multibody hinge constraint at all"),
    SPRING_EFFECT: ("linear spring-dampers: PyBullet has no spring-damper element between bodies; it would be "
                    "the adapter's own force, applied from Python before every step, not the engine's"),
}
# Compiled mass properties must be the scene's to this relative accuracy: PyBullet stores the mass and the
# principal moments as given (doubles), and a non-diagonal inertia costs an eigen-solve (a few ulps).
MASS_PROPERTY_REL_TOL = 1e-12


@dataclass(frozen=True, eq=False)
class PybulletPrepared(Prepared):
    """PyBullet's prepared run (``Prepared``).

    Attributes
    ----------
    model : model.PybulletModel — the run's client, set to the initial state at each run's start
    scratch : model.PybulletModel — the same scene in a second client, for the read-back and the audit's probe
    steps : ndarray (n - 1,) of int — steps per sample interval (``settings.steps_per_interval``)
    loads : list — the loads as PyBullet takes them (``stepping.load_plan``)
    """

    model: object
    scratch: object
    steps: np.ndarray
    loads: list


class PybulletAdapter(Adapter):
    """PyBullet (``pybullet`` 3.2.7): semi-implicit Euler on its Featherstone multibodies. Options: ``defaults`` =
    ``scene`` | ``engine``; ``solver`` = ``si`` | ``pgs`` | ``dantzig``; ``solver_iterations``."""

    name = "pybullet"
    # free, revolute, prismatic, ball and weld joints; gravity; world and follower forces and torques; contact of
    # free bodies' geoms and planes, hard (``contact``). Loops and springs: NOT_MAPPED.
    effects = EFFECTS | CONTACT_EFFECTS
    options = MODEL_OPTIONS
    refusal_notes = NOT_MAPPED
    integrators = {
        "euler": IntegratorSpec(True, tuple(MODEL_OPTIONS),
                                "semi-implicit Euler, first order (PyBullet's one integrator: stepSimulation at a "
                                "fixed step)", order=1),
    }

    def version(self):
        engine()  # ImportError when it is missing
        return _version()

    def unsupported(self, scene, settings):
        return super().unsupported(scene, settings) or _too_many_links(scene) or contact.why_not(scene)

    def describe(self, scene, settings):
        """The multibodies PyBullet builds, read back from the engine, for reports and ``dalembert show-model``."""
        from dalembert.adapters.pybullet.model import summary

        return summary(build(scene, settings))

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        model, scratch = build(scene, settings), build(scene, settings)
        _check_mass_properties(model, scene)
        pb = engine()
        for part in scratch.parts.values():
            if part.link >= 0:
                pb.enableJointForceTorqueSensor(part.mb, part.link, 1, physicsClientId=scratch.client)
        times = np.asarray(times, dtype=float)
        return PybulletPrepared(scene, times, settings, model=model, scratch=scratch,
                                steps=steps_per_interval(times, settings.dt), loads=load_plan(model, scene))

    # ------------------------------------------------------------- run
    def run(self, prepared):
        from dalembert.adapters.pybullet.readback import read_back

        p = prepared
        X, wall, diverged_at = simulate(p)
        n_steps = int(p.steps[:diverged_at].sum()) if diverged_at else int(p.steps.sum())
        info = {"message": f"PyBullet: non-finite state at t = {p.times[diverged_at]:g} s" if diverged_at else ""}

        def read():
            traj, info["read"] = read_back(p, X)
            return traj

        return Outcome(read, wall, n_steps, n_steps, info)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        return audit(prepared, outcome)


def _version():
    """PyBullet's package version (the module reports only its API date)."""
    from importlib.metadata import version

    return version("pybullet")


# The most links one PyBullet multibody holds (measured on 3.2.7: a 300-link chain is built with 127 joints, and
# asking for link 127 fails "Joint index out-of-range").
MAX_LINKS = 127


def _too_many_links(scene):
    """Why PyBullet cannot hold ``scene`` (a tree of more than ``MAX_LINKS`` links below its root), or None."""
    roots = {}  # each tree's root: the bodies below it
    for j in scene.joints:
        root = root_of(scene, j.child)
        roots[root] = roots.get(root, 0) + (j.parent != WORLD)
    # a free root is a multibody's base; every other tree hangs, root and all, off the world's one fixed multibody
    free = [n for r, n in roots.items() if scene.joint(r).kind == "free"]
    fixed = sum(n + 1 for r, n in roots.items() if scene.joint(r).kind != "free")
    worst = max([*free, fixed])
    if worst > MAX_LINKS:
        return (f"a tree of {worst} links: one PyBullet multibody holds at most {MAX_LINKS} (PyBullet 3.2.7 builds "
                f"the first {MAX_LINKS} and drops the rest)")
    return None


def _check_mass_properties(model, scene):
    """PyBullet's mass and principal moments of every body against the scene's (RuntimeError naming the body)."""
    from dalembert.adapters.pybullet.model import principal_frame

    pb = engine()
    for b in scene.bodies:
        part = model.parts[b.name]
        info = pb.getDynamicsInfo(part.mb, part.link, physicsClientId=model.client)
        moments = principal_frame(b)[0]
        if (abs(info[0] - b.mass) > MASS_PROPERTY_REL_TOL * b.mass
                or np.abs(np.asarray(info[2]) - moments).max() > MASS_PROPERTY_REL_TOL * np.abs(moments).max()):
            raise RuntimeError(f"PyBullet built body {b.name!r} with mass {info[0]} and principal moments {info[2]}; "
                               f"the scene has {b.mass} and {moments.tolist()}")
