"""The reference solver as an engine: the first adapter, and the yardstick."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert import contact
from dalembert.adapters.base import Adapter, IntegratorSpec, Option, Outcome, Prepared
from dalembert.scene import EFFECTS, LOOP_EFFECTS, SPRING_EFFECTS

__all__ = ["ReferenceAdapter", "ReferencePrepared"]


@dataclass(frozen=True, eq=False)
class ReferencePrepared(Prepared):
    """The reference solver's prepared run (``Prepared``; ``settings`` is the integrator's: the options
    without ``formulation``, which chose ``system``).

    Attributes
    ----------
    system : the formulation's equations of motion (``reference.solver.FORMULATIONS``: ``NewtonEuler``,
        ``Kane``, ``ClosedLoops`` or ``PlanarChain``), with its initial state
    """

    system: object


class ReferenceAdapter(Adapter):
    """dalembert's own Newton-Euler / Kane solver (``reference``).

    Options: ``formulation`` = ``newton-euler`` (free bodies; default there),
    ``newton-euler-matrix`` (the attitude as a rotation matrix, ``R' = R [w]x``), ``kane``
    (any tree; default for jointed scenes) or ``planar`` (serial revolute chains
    with parallel axes under gravity: Lagrange's equations in absolute angles).
    """

    name = "reference"
    # loops: Kane's tree plus multipliers (reference.loops); prismatic joints: Kane's (reference.generalized)
    effects = EFFECTS | LOOP_EFFECTS | SPRING_EFFECTS
    # the names of ``reference.solver.FORMULATIONS`` (not imported here: listing engines imports no solver;
    # tests/test_adapter_contract.py checks that the two agree)
    options = {
        "formulation": Option(("newton-euler", "newton-euler-matrix", "kane", "planar"), None,
                              "how the equations are written (default: newton-euler for free bodies, kane otherwise)"),
    }
    integrators = {
        "dop853": IntegratorSpec(False, ("formulation",), "scipy DOP853, adaptive 8th order", order=8),
        "rk4": IntegratorSpec(True, ("formulation",), "classical RK4 on embedded coordinates", order=4),
        "rkmk4": IntegratorSpec(True, ("formulation",), "Runge-Kutta-Munthe-Kaas 4 on the Lie group", order=4),
        "euler": IntegratorSpec(True, ("formulation",), "symplectic (semi-implicit) Euler on the group", order=1),
    }

    def version(self):
        import dalembert

        return dalembert.__version__

    def check(self, scene, times, settings):
        super().check(scene, times, settings)
        from dalembert.reference.solver import build

        if self.unsupported(scene, settings) is None:  # (an unsupported formulation is a stored finding)
            build(scene, settings, np.asarray(times))  # formulation and integrator checks

    def unsupported(self, scene, settings):
        if (why := contact.not_mapped(scene, self.name)):  # contact: not mapped here yet
            return why
        reason = super().unsupported(scene, settings)
        formulation = self.option(settings, "formulation")  # None: the scene's default (kane where it has joints)
        if reason is None and formulation in ("newton-euler", "newton-euler-matrix"):
            if any(j.kind != "free" for j in scene.joints):
                return "Newton-Euler formulations handle free bodies only (use formulation=kane)"
            if scene.loops:
                return "Newton-Euler formulations handle no loop closures (use formulation=kane)"
        if reason is None and formulation == "planar":
            from dalembert.reference.planar import why_not

            return why_not(scene)
        return reason

    def describe(self, scene, settings):
        from dalembert.reference.solver import FORMULATIONS, default_formulation

        formulation = self.option(settings, "formulation") or default_formulation(scene)
        system = FORMULATIONS[formulation](scene)
        return (f"reference {formulation} ({type(system).__name__}): nq = {len(system.q0)}, nv = {len(system.v0)}; "
                f"blocks {[b.kind for b in system.blocks]}; gravity {list(scene.gravity)}; "
                f"loads {[ld.effect + ' on ' + ld.body for ld in scene.loads]}; "
                f"springs {[sp.name for sp in scene.springs]}\n")

    def prepare(self, scene, times, settings):
        from dalembert.reference.solver import build

        times = np.asarray(times, dtype=float)
        system, inner = build(scene, settings, times)
        return ReferencePrepared(scene, times, inner, system)

    def run(self, prepared):
        import time

        from dalembert.reference.integrators import INTEGRATORS

        p = prepared
        start = time.perf_counter()
        Q, V, stats = INTEGRATORS[p.settings.integrator]().run(p.system, p.times, p.settings)
        wall = time.perf_counter() - start
        return Outcome(lambda: p.system.trajectory(p.times, Q, V), wall, stats.n_steps, stats.n_rhs,
                       {"message": stats.message})  # why an adaptive run stopped early, if it did

    def audit(self, prepared, outcome):
        from dalembert import closure

        scene = prepared.scene
        system = prepared.system
        return {
            "gravity": tuple(scene.gravity),
            "gravity_computed": any(g != 0.0 for g in scene.gravity),
            "formulation": type(system).__name__,
            "joints": {j.child: j.kind for j in scene.joints},
            "loads": [f"{ld.effect} on {ld.body}" for ld in scene.loads],
            "springs": [f"{sp.name}: {sp.body_a} -> {sp.body_b}, k = {sp.stiffness:g} N/m, c = {sp.damping:g} N s/m, "
                        f"l0 = {sp.rest_length:g} m" for sp in scene.springs],
            "constraint_rows": sum(len(r.phi) for r in closure.initial_rows(scene)),
            "loops": str(scene.loop_summary()) if scene.loops else "none",
            "contacts": 0,
            "integrator": prepared.settings.integrator,
        }
