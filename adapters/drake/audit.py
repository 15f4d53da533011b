"""What Drake simulated, read back from the plant: the audit of a run (``Adapter.audit``)."""

from __future__ import annotations

from dalembert.adapters.drake import contact
from dalembert.adapters.drake.charts import RECHART_PITCH
from dalembert.adapters.drake.loops import ANCHOR
from dalembert.adapters.drake.model import drake_version

__all__ = ["audit"]


def audit(prepared, outcome):
    """What Drake simulated, read back from the plant (``DrakeModel.audit``): mode and integrator, loads and
    their path, ball joints' charts, the loops, springs and contact (``contact.audit``) as the plant holds them."""
    p = prepared
    s = p.settings
    loads = p.model.loads
    follower = any(ld.frame == "body" for ld in p.scene.loads)
    return {
        **p.model.audit(),
        "mode": "discrete" if p.scheme is None else "continuous",
        "integrator": p.scheme or "discrete update (MultibodyPlant)",
        "fixed_step": s.dt is not None,
        "target_accuracy": s.rtol, "atol_used": False,
        "loads": ([f"{ld.effect} on {ld.body}" for ld in p.scene.loads]),
        "load_path": ("" if loads is None else
                      "SceneLoads system -> applied_spatial_force; follower forces turned into world axes from "
                      "the body_poses port at every evaluation of the dynamics" if follower else
                      "SceneLoads system -> applied_spatial_force (world-frame loads)"),
        "load_evaluations": outcome.info.get("load_evaluations", 0),
        "stopped": outcome.info.get("message", ""),
        "ball_joint_charts": ("" if not any(j.kind == "ball" for j in p.scene.joints) else
                              f"BallRpyJoint frames re-set {outcome.info.get('ball_recharts', 0)} times (rpy = 0, "
                              f"x along w; at t = 0 and when |pitch| > {RECHART_PITCH} rad) to stay clear of "
                              "pitch = +-pi/2 (dalembert.adapters.drake.charts)"),
        **(_loop_audit(p.model) if p.model.loops else {}),
        **_spring_audit(p.model),
        **contact.audit(p.model),
        "drake_version": drake_version(),
    }


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
