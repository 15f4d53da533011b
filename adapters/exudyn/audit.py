"""What Exudyn simulated, read back from the system that ran: the audit of a run (``Adapter.audit``)."""

from __future__ import annotations

import numpy as np

from dalembert.adapters.base import option_value
from dalembert.adapters.exudyn import contact
from dalembert.adapters.exudyn.model import CONSTRAINED_AXES, MODEL_OPTIONS
from dalembert.adapters.exudyn.readback import STALE_ACCELERATIONS
from dalembert.adapters.exudyn.springs import passive_effects, unexpected_passive
from dalembert.scene import WORLD

__all__ = ["audit", "constraint_rows", "ROTVEC_LG_REACTION"]

# What a run with redundant joints on rotation-vector nodes reports (docs/exudyn_rotvec_lg_reaction.py).
ROTVEC_LG_REACTION = (
    "Exudyn 1.13.6: the joint reaction (ForceLocal of ObjectJointGeneric) on a body with a "
    "NodeRigidBodyRotVecLG node misses the fraction 1 - sin|phi|/|phi| of its velocity-dependent "
    "(centripetal) part, phi the body's rotation vector, at every step size, while the motion is right "
    "(measured: 3.8e-2 relative on the Kovalevskaya top tilted 0.7 rad at dt = 1e-3 and 1e-4; Newton's law on "
    "the run's own states agrees with the truth to 2e-6). Reproduction for upstream: "
    "docs/exudyn_rotvec_lg_reaction.py. Euler-parameter nodes (--option node=ep) report it exactly.")


def constraint_rows(scene, built):
    """The constraint rows of the system ``built``: its redundant joints' constrained axes and its loops' rows."""
    return (sum(sum(CONSTRAINED_AXES[scene.joint(c).kind]) for c in built.redundant_joints)
            + sum(sum(r.axes) for r in built.loop_rows.values()))


def audit(prepared, outcome, solver):
    """What Exudyn simulated, read back from the system that ran (``Adapter.audit``): gravity, nodes and
    joint formulation, the solver (``solver``: Exudyn's name) and its Newton and rejected steps, constraints,
    how reactions are obtained, the loops, the springs and every other passive element, the joints."""
    import exudyn

    built = prepared.system
    scene, st = prepared.scene, prepared.settings
    return {
        "gravity": tuple(scene.gravity) if any(scene.gravity) else (0.0, 0.0, 0.0),
        "gravity_loads": "mass-proportional (CreateRigidBody / KinematicTree)" if any(scene.gravity) else "none",
        "node": option_value(MODEL_OPTIONS, st, "node"), "joints": option_value(MODEL_OPTIONS, st, "joints"),
        "solver": solver,
        "constraints": constraint_rows(scene, built), "contacts": len(scene.contacts),
        "model": built.summary,
        "newton_steps": outcome.info.get("newton_steps", 0),
        "rejected_steps": outcome.info.get("rejected_steps", 0),
        "exudyn_version": exudyn.__version__,
        "reactions": _reaction_method(scene, st),
        **({"loops": _loop_audit(scene, built)} if scene.loops else {}),
        **_spring_audit(scene, built),
        **_joint_audit(built),
        **contact.audit(built.mbs, scene),  # every contact connector as the system holds it
        **({"known_issue": ROTVEC_LG_REACTION} if _rotvec_lg_reactions(scene, st) else {}),
    }


def _loop_audit(scene, built):
    """What the run made of the scene's loop closures (``exudyn.loops``)."""
    rows = {name: dict(constrained=sum(r.axes), dropped=list(r.dropped)) for name, r in built.loop_rows.items()}
    return {
        "closures": {lp.name: (f"{'ObjectConnectorDistance' if lp.kind == 'distance' else 'ObjectJointGeneric'} "
                               f"({lp.kind}), {rows[lp.name]['constrained']} row(s)"
                               + (f"; left out as redundant at t = 0: {', '.join(rows[lp.name]['dropped'])}"
                                  if rows.get(lp.name, {}).get("dropped") else ""))
                     for lp in scene.loops if lp.name in rows},
        "scene": str(scene.loop_summary()),
        "redundant_rows": ("only the rows independent at the initial state are given to Exudyn (its default "
                           "EXUdense solver stops on the singular Jacobian of redundant rows; Eigen's FullPivLU, "
                           "ignoreSingularJacobian=True, stalls Newton at a singular position): see exudyn.loops"),
        "reaction": ("the force ON body b: the ObjectJointGeneric's ForceLocal (on body a, in its marker "
                     "frame) turned into world axes and negated; the ObjectConnectorDistance's Force (a scalar, "
                     "the tension) along the line from b's point to a's"),
    }


def _joint_audit(built):
    """The joints as the system that ran holds them (``joints.read_joints`` once it was assembled: joint
    type, axis, joint point, initial coordinate and rate read from Exudyn, each compared with the scene)."""
    if not built.joint_readout:
        return {}
    return {"joint_readout": {child: {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in got.items()}
                             for child, got in built.joint_readout.items()}}


def _spring_audit(scene, built):
    """The springs as the system that ran holds them (``springs.read_springs`` once it was assembled:
    parameters, ends, initial length and tension read from Exudyn, each compared with the scene) and every
    passive force element it carries (``springs.passive_effects``): the springs' connectors and nothing
    else."""
    passive = passive_effects(built.mbs)
    out = {"passive": passive}
    if scene.springs:
        out["springs"] = built.spring_readout
    rigid = sum(owner != WORLD for owner in built.owners.values())
    out["passive_extra"] = unexpected_passive(passive, scene, rigid)  # empty: no passive force but the scene's
    return out


def _rotvec_lg_reactions(scene, settings):
    """Whether the run reports joint reactions from bodies on rotation-vector nodes."""
    return (option_value(MODEL_OPTIONS, settings, "joints") == "redundant"
            and option_value(MODEL_OPTIONS, settings, "node") == "rotvec-lg"
            and any(j.kind != "free" for j in scene.joints))


def _reaction_method(scene, settings):
    """How the run's joint reactions are obtained (for the audit)."""
    if not any(j.kind != "free" for j in scene.joints):
        return "none (no joints)"
    if option_value(MODEL_OPTIONS, settings, "joints") == "redundant":
        return ("each joint's ForceLocal (ObjectJointGeneric), turned into world axes, negated: the force ON "
                "the child")
    how = ("Newton's law per link, m (a - g) - loads + children's reactions"
           + (" - the loops' forces on the link" if scene.loops else "")
           + ", with a from the tree's acceleration sensors")
    if settings.integrator in STALE_ACCELERATIONS:
        return how + (", evaluated by Exudyn at each sampled state (its step-end accelerations are the "
                      "half-step velocity's)")
    return how
