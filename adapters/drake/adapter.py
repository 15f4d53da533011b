"""``DrakeAdapter``: the contract (``dalembert.adapters``) for Drake's ``MultibodyPlant``.

``prepare`` builds the plant and its diagram (``model``) in continuous mode, or
in discrete mode for the integrator ``discrete`` (``time_step = dt``); ``run``
steps a ``Simulator`` through the sample times (``stepping``) and reads the
states back in body terms (``readback``); ``audit`` (the module) reads the plant back.

Integrators: Drake's, by its scheme names (``stepping.SCHEMES``), each in
fixed-step mode (``dt``) and, where Drake estimates its error, error-controlled
(``<name>-adaptive``: ``rtol`` is Drake's target accuracy, ``atol`` unused).

Loop closures (``loops``): SAP constraints of the discrete plant, so only the integrator
``discrete`` runs a scene with loops; every continuous integrator declares them unsupported
(``loops.CONTINUOUS_REASON``). Their reactions are recovered from the step's generalized
constraint force (Drake reports no constraint forces: ``loops.LoopForces``).

Spring-dampers (``springs``): ``LinearSpringDamper`` force elements, in both modes; a spring of rest
length 0 is unsupported (Drake's element needs a positive free length: ``springs.ZERO_REST_REASON``).
The audit reads every spring back from the plant and checks it against the scene.

Contact (``contact``): the geoms and planes as collision geometry of a SceneGraph, only the named pairs
colliding, point contact with ``CoulombFriction(mu, mu)``; discrete mode with SAP (Drake's default) or TAMSI
(option ``contact_solver``), continuous mode on the same penalty force; restitution mapped to a Hunt-Crossley
dissipation at a named approach speed (option ``impact_speed``), unsupported without one. The audit reads every
contact parameter back from the plant and its SceneGraph.

Prismatic joints (``PrismaticJoint``, ``model``): in both modes, with every integrator, springs and loops; no
limits, no damping. The audit reads each back from the finalized plant (type, axis, limits, damping:
``prismatic_joints``) and checks it against the scene (``prismatic_as_scene``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert.adapters import file_model
from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, Prepared
from dalembert.adapters.drake import contact, from_file
from dalembert.adapters.drake.audit import audit
from dalembert.adapters.drake.loops import CONTINUOUS_REASON, LOOP_KINDS
from dalembert.adapters.drake.model import drake_version
from dalembert.adapters.drake.springs import refusal as spring_refusal
from dalembert.adapters.drake.stepping import SCHEMES, simulate
from dalembert.scene import CONTACT_EFFECTS, EFFECTS, SPRING_EFFECTS

__all__ = ["DrakeAdapter", "DrakePrepared"]

FIXED = {
    "explicit-euler": "explicit (forward) Euler, first order",
    "semi-explicit-euler": "semi-explicit (symplectic) Euler, first order",
    "rk2": "Runge-Kutta 2 (explicit trapezoid)",
    "rk3": "Runge-Kutta 3",
    "rk5": "Runge-Kutta 5 (Dormand-Prince)",
    "bs3": "Bogacki-Shampine 3",
    "implicit-euler": "implicit Euler (Newton, finite-difference Jacobian)",
    "velocity-implicit-euler": "implicit Euler in the velocities (the configuration follows them)",
    "radau1": "one-stage Radau IIA (implicit Euler)",
    "radau3": "two-stage Radau IIA, third order",
}
# Offered error-controlled too: the schemes Drake estimates the error of, but for the two first-order
# implicit Eulers, whose error control at the matrix's tolerances takes millions of steps per simulated
# second (measured at rtol 1e-8: 13-25 s of stepping for 0.5 s of a fast top or the violent rod):
# they are offered fixed-step only.
ADAPTIVE = ("rk3", "rk5", "bs3", "radau3")
# The order each scheme is built to (Drake's integrator documentation; Hairer & Wanner II for Radau IIA); the
# discrete plant's step is first order (semi-implicit Euler with SAP's implicit velocity update).
ORDER = {"explicit-euler": 1, "semi-explicit-euler": 1, "rk2": 2, "rk3": 3, "rk5": 5, "bs3": 3, "implicit-euler": 1,
         "velocity-implicit-euler": 1, "radau1": 1, "radau3": 3, "discrete": 1}
ADAPTIVE_SUFFIX = "-adaptive"


# The contact options (``contact.CONTACT_OPTIONS``), named by every integrator; ``contact_solver`` is the
# discrete plant's alone (its ``Option.only``).
OPTIONS = (*contact.CONTACT_OPTIONS, *file_model.FILE_OPTION_NAMES)


def _integrators():
    out = {k: IntegratorSpec(True, OPTIONS, f"Drake {v}", order=ORDER[k]) for k, v in FIXED.items()}
    out.update({k + ADAPTIVE_SUFFIX: IntegratorSpec(False, OPTIONS, f"Drake {FIXED[k]}, error-controlled", order=ORDER[k])
                for k in ADAPTIVE})
    out["discrete"] = IntegratorSpec(True, OPTIONS,
                                     "the plant in discrete mode (time_step = dt; SAP, semi-implicit)",
                                     order=ORDER["discrete"])
    return out


@dataclass(frozen=True, eq=False)
class DrakePrepared(Prepared):
    """Drake's prepared run (``Prepared``): the plant and its diagram, and the initial state.

    Attributes
    ----------
    model : DrakeModel — the plant (continuous, or discrete with ``time_step = dt``), its diagram and loads
    q0 : ndarray (nq,) — the initial positions, Drake's coordinates (a free body's: quaternion w x y z, position)
    v0 : ndarray (nv,) — the initial velocities (a free body's: w_WB_W, v_WB_W)
    scheme : str or None — Drake's integrator scheme (``stepping.SCHEMES``); None: the plant's discrete update
    """

    model: object
    q0: np.ndarray
    v0: np.ndarray
    scheme: str | None


class DrakeAdapter(Adapter):
    """Drake (``pydrake``): the scene as a ``MultibodyPlant``, Drake's integrators or its discrete mode."""

    name = "drake"
    # loops: the discrete integrator only; springs: both modes, a positive rest length only; prismatic joints: both
    # modes, every integrator (``PrismaticJoint``, model)
    # contact: both modes, point contact (``contact``); restitution where an impact speed maps it
    effects = EFFECTS | frozenset(f"loop:{k}" for k in LOOP_KINDS) | SPRING_EFFECTS | CONTACT_EFFECTS
    # contact_solver, point_contact_stiffness, hunt_crossley_dissipation, ...; model_file, file_effects (from_file)
    options = {**contact.CONTACT_OPTIONS, **file_model.FILE_OPTIONS}
    integrators = _integrators()

    def version(self):
        return drake_version()

    def beyond_scene(self, scene, settings):
        return file_model.beyond(settings)  # the robot file's effects, when the engine reads the file with them

    def unsupported(self, scene, settings):
        if (why := file_model.why_not(scene, settings)):
            return why
        reason = super().unsupported(scene, settings) or contact.why_not(scene, settings)
        if reason is None and scene.loops and settings.integrator != "discrete":
            kinds = ", ".join(sorted({lp.effect for lp in scene.loops}))
            # (no integrator name in it: the report groups the integrators refused for one reason)
            return f"{kinds} with a continuous-time integrator: {CONTINUOUS_REASON}"
        if reason is None and scene.springs:
            return spring_refusal(scene)
        return reason

    def describe(self, scene, settings):
        """The plant's summary, for reports and ``dalembert show-model``."""
        from dalembert.adapters.drake.model import DrakeModel

        if file_model.model_file(settings):
            return from_file.describe(scene, settings)
        return DrakeModel(scene, settings.dt if settings.integrator == "discrete" else 0.0, settings).summary

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        from dalembert.adapters.drake.model import DrakeModel

        if file_model.model_file(settings):
            return from_file.prepare(scene, times, settings)
        discrete = settings.integrator == "discrete"
        model = DrakeModel(scene, settings.dt if discrete else 0.0, settings)
        q0, v0 = model.initial_state()
        scheme = None if discrete else SCHEMES[settings.integrator.removesuffix(ADAPTIVE_SUFFIX)]
        return DrakePrepared(scene, np.asarray(times, dtype=float), settings, model, q0, v0, scheme)

    # ------------------------------------------------------------- run
    def run(self, prepared):
        from dalembert.adapters.drake.readback import read_back

        if isinstance(prepared, file_model.FilePrepared):
            return from_file.run(prepared)
        p = prepared
        X, wall, n_steps, n_rhs, message, recharts = simulate(p)
        loads = p.model.loads
        info = {"message": message, "load_evaluations": loads.evaluations if loads is not None else 0,
                "ball_recharts": recharts}
        return Outcome(lambda: read_back(p, X), wall, n_steps, n_rhs, info)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        if isinstance(prepared, file_model.FilePrepared):
            return from_file.audit(prepared, outcome)
        return audit(prepared, outcome)

