"""``DrakeAdapter``: the contract (``dalembert.adapters``) for Drake's ``MultibodyPlant``.

``prepare`` builds the plant and its diagram (``model``) in continuous mode, or
in discrete mode for the integrator ``discrete`` (``time_step = dt``); ``run``
steps a ``Simulator`` through the sample times (``stepping``) and reads the
states back in body terms (``readback``); ``audit`` reads the plant back.

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

Prismatic joints (``PrismaticJoint``, ``model``): in both modes, with every integrator, springs and loops; no
limits, no damping. The audit reads each back from the finalized plant (type, axis, limits, damping:
``prismatic_joints``) and checks it against the scene (``prismatic_as_scene``).
"""

from __future__ import annotations

import functools

import numpy as np

from dalembert import contact
from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome
from dalembert.adapters.drake.charts import RECHART_PITCH
from dalembert.adapters.drake.loops import ANCHOR, CONTINUOUS_REASON, LOOP_KINDS
from dalembert.adapters.drake.springs import refusal as spring_refusal
from dalembert.adapters.drake.stepping import SCHEMES, simulate
from dalembert.scene import EFFECTS, SPRING_EFFECTS

__all__ = ["DrakeAdapter"]

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
ADAPTIVE_SUFFIX = "-adaptive"


def _integrators():
    out = {k: IntegratorSpec(True, (), f"Drake {v}") for k, v in FIXED.items()}
    out.update({k + ADAPTIVE_SUFFIX: IntegratorSpec(False, (), f"Drake {FIXED[k]}, error-controlled")
                for k in ADAPTIVE})
    out["discrete"] = IntegratorSpec(True, (), "the plant in discrete mode (time_step = dt; SAP, semi-implicit)")
    return out


class DrakeAdapter(Adapter):
    """Drake (``pydrake``): the scene as a ``MultibodyPlant``, Drake's integrators or its discrete mode."""

    name = "drake"
    # loops: the discrete integrator only; springs: both modes, a positive rest length only; prismatic joints: both
    # modes, every integrator (``PrismaticJoint``, model)
    effects = EFFECTS | frozenset(f"loop:{k}" for k in LOOP_KINDS) | SPRING_EFFECTS
    integrators = _integrators()

    def version(self):
        import pydrake

        return pydrake.__version__ if hasattr(pydrake, "__version__") else _distribution_version()

    def unsupported(self, scene, settings):
        if (why := contact.not_mapped(scene, self.name)):  # contact: not mapped here yet
            return why
        reason = super().unsupported(scene, settings)
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

        return DrakeModel(scene, settings.dt if settings.integrator == "discrete" else 0.0).summary

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        from dalembert.adapters.drake.model import DrakeModel

        discrete = settings.integrator == "discrete"
        model = DrakeModel(scene, settings.dt if discrete else 0.0)
        q0, v0 = model.initial_state()
        scheme = None if discrete else SCHEMES[settings.integrator.removesuffix(ADAPTIVE_SUFFIX)]
        return dict(scene=scene, times=np.asarray(times, dtype=float), settings=settings, model=model, q0=q0, v0=v0,
                    scheme=scheme)

    # ------------------------------------------------------------- run
    def run(self, prepared):
        from dalembert.adapters.drake.readback import read_back

        p = prepared
        X, wall, n_steps, n_rhs, message, recharts = simulate(p)
        loads = p["model"].loads
        info = {"message": message, "load_evaluations": loads.evaluations if loads is not None else 0,
                "ball_recharts": recharts}
        return Outcome(lambda: read_back(p, X), wall, n_steps, n_rhs, info)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        p = prepared
        s = p["settings"]
        loads = p["model"].loads
        follower = any(ld.frame == "body" for ld in p["scene"].loads)
        return {
            **p["model"].audit(),
            "mode": "discrete" if p["scheme"] is None else "continuous",
            "integrator": p["scheme"] or "discrete update (MultibodyPlant)",
            "fixed_step": s.dt is not None,
            "target_accuracy": s.rtol, "atol_used": False,
            "loads": ([f"{ld.effect} on {ld.body}" for ld in p["scene"].loads]),
            "load_path": ("" if loads is None else
                          "SceneLoads system -> applied_spatial_force; follower forces turned into world axes from "
                          "the body_poses port at every evaluation of the dynamics" if follower else
                          "SceneLoads system -> applied_spatial_force (world-frame loads)"),
            "load_evaluations": outcome.info.get("load_evaluations", 0),
            "stopped": outcome.info.get("message", ""),
            "ball_joint_charts": ("" if not any(j.kind == "ball" for j in p["scene"].joints) else
                                  f"BallRpyJoint frames re-set {outcome.info.get('ball_recharts', 0)} times (rpy = 0, "
                                  f"x along w; at t = 0 and when |pitch| > {RECHART_PITCH} rad) to stay clear of "
                                  "pitch = +-pi/2 (dalembert.adapters.drake.charts)"),
            **(self._loop_audit(p["model"]) if p["model"].loops else {}),
            **self._spring_audit(p["model"]),
            "drake_version": self.version(),
        }

    @staticmethod
    def _loop_audit(model):
        """How the loops were closed (``loops``): constraints, their stiffness, what is not read back."""
        plant = model.plant
        return {
            "loops": {lc.loop.name: (f"{lc.loop.kind}: " + (
                "AddDistanceConstraint (stiffness inf, damping 0)" if lc.loop.kind == "distance" else
                f"2 AddBallConstraint, the second {lc.lever:g} m along the axis" if lc.loop.kind == "revolute" else
                "AddBallConstraint")) for lc in model.loops},
            "loop_summary": str(model.scene.loop_summary()),
            "loop_constraints": int(plant.num_constraints()),
            "loop_solver": f"SAP ({plant.get_discrete_contact_solver().name}, "
                           f"{plant.get_discrete_contact_approximation().name}), time_step {plant.time_step()!r} s",
            "loop_stiffness": ("near-rigid (SAP's regime for infinite stiffness: regularization beta^2/(4 pi^2) times "
                               "the Delassus diagonal, beta = 0.1 fixed in Drake; gap relaxed over one time step): "
                               "the stiffest Drake offers, soft by an amount that shrinks with dt"),
            "loop_world_anchor": (f"{ANCHOR} welded to the world (Drake 1.51 crashes on constraints to the world body)"
                                  if any("world" in (lc.loop.body_a, lc.loop.body_b) for lc in model.loops) else ""),
            "loop_reactions": ("reaction_force:<loop> from the constraints' generalized force in the step "
                               "(M a + C v - tau_g - tau_loads; Drake reports no constraint forces) resolved on the "
                               "loop's rows, minimum-norm (loops.LoopForces)"),
        }


    @staticmethod
    def _spring_audit(model):
        """The springs as the plant holds them (``springs.read_springs``: bodies, points, free length, stiffness,
        damping read from its ``LinearSpringDamper`` elements, not from the scene), whether they are exactly the
        scene's, and the plant's other passive elements (none: joint damping is ``max_joint_damping``)."""
        from dalembert.adapters.drake.springs import passive_elements, read_springs

        plant = model.plant
        built = read_springs(plant)
        wanted = [dict(body_a=sp.body_a, point_a=sp.point_a, body_b=sp.body_b, point_b=sp.point_b,
                       rest_length=sp.rest_length, stiffness=sp.stiffness, damping=sp.damping)
                  for sp in model.scene.springs]
        return {
            "springs": {sp.name: (f"LinearSpringDamper {b['body_a']} {list(b['point_a'])} -> {b['body_b']} "
                                  f"{list(b['point_b'])}, free length {b['rest_length']!r} m, stiffness "
                                  f"{b['stiffness']!r} N/m, damping {b['damping']!r} N s/m")
                        for sp, b in zip(model.scene.springs, built)},
            "springs_as_scene": built == wanted,  # bit for bit: every number went in unchanged
            "spring_force_path": ("" if not built else
                                  "force element: at every stage (continuous)" if plant.time_step() == 0.0 else
                                  "force element: explicit, at the step's start (q0, v0), damper included "
                                  "(discrete update; SAP's implicit damping is joint damping only)"),
            "other_passive_elements": passive_elements(plant),
        }


@functools.cache  # (installed packages do not change under a process; every run asks twice: ~1 ms a time)
def _distribution_version():
    from importlib.metadata import version

    return version("drake")
