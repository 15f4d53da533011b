"""What Pinocchio simulated, read back from the model that ran: the audit of a run (``Adapter.audit``)."""

from __future__ import annotations

import numpy as np

from dalembert.adapters.pinocchio import contact, loops, springs
from dalembert.scene import AXIS_KINDS

__all__ = ["audit"]


def audit(prepared, outcome):
    """What Pinocchio simulated, read back from the built model (``Adapter.audit``): gravity, joints and their
    axes, the loads and springs applied as external forces, which loop ran, constraint rows, and (with loops or
    springs) how they were closed and each spring identified from the run's dynamics."""
    import pinocchio

    pm = prepared.pm
    model = pm.model
    return {
        "gravity": tuple(float(g) for g in model.gravity.linear),
        "joints": {name: model.joints[jid].shortname() for name, jid in pm.joint_ids.items()},
        # the unaligned revolute and prismatic joints' axes as the built model holds them (unit, joint frame)
        "joint_axes": {j.child: model.joints[pm.joint_ids[j.child]].extract().axis.tolist()
                       for j in prepared.scene.joints if j.kind in AXIS_KINDS},
        "external_forces_per_evaluation": [f"{ld.effect} on {ld.body}" for ld in prepared.scene.loads]
        + [f"spring_damper {el.name}: frames {model.frames[el.frame_a].name} -> {model.frames[el.frame_b].name}"
           for el in pm.springs],
        "nq": int(model.nq), "nv": int(model.nv),
        "integrator": prepared.settings.integrator,
        "loop": outcome.info.get("loop", ""),
        "pinocchio_version": pinocchio.__version__,
        "contacts": len(prepared.scene.contacts),  # pairs, each detected every step (contact)
        "constraint_rows": int(sum(cm.residualSize() for cm in pm.cmodels)) if pm.constrained else 0,
        # what Pinocchio's joints could add on their own: none is set (springs are external forces only)
        "joint_passive_effects": {name: float(np.abs(getattr(model, name)).max(initial=0.0))
                                  for name in ("damping", "friction", "armature", "rotorInertia")},
        **(_loop_audit(pm) if pm.loop_contacts else {}),
        **(_spring_audit(prepared, outcome) if pm.springs else {}),
        **contact.audit(prepared, outcome),
    }


def _spring_audit(prepared, outcome):
    """Each spring identified from the generalized force the run's right-hand side gives it at the initial
    configuration (``springs.identify``): the compiled one's where the compiled loop ran, else the Python
    one's (the joint torques ``constraintDynamics`` is given, with loops or welds as constraints)."""
    import pinocchio as pin

    pm = prepared.pm
    model, data = pm.model, pm.data
    native = prepared.native if outcome.info.get("loop", "").startswith("C++") else None
    if native is not None:
        by = "the compiled right-hand side (stepper.cpp): M a"

        def forces(q, v, elements):
            return springs.mass_matrix(model, data, q) @ native.acceleration(q, v, elements)
    elif pm.constrained:
        by = "the joint torques given to pin.constraintDynamics (PinocchioModel.load_torques)"
        forces = pm.load_torques
    else:
        by = "the Python right-hand side (pin.aba with the external forces): M a"

        def forces(q, v, elements):
            a = pin.aba(model, data, q, v, pm.tau, pm.external_forces(q, v, elements))
            return springs.mass_matrix(model, data, q) @ a
    q0 = prepared.q0
    return {"springs": {el.name: springs.identify(pm, el, forces, q0) for el in pm.springs},
            "springs_identified_from": by}


def _loop_audit(pm):
    """How the loops were closed and solved (``loops``): constraints, regularisation, drift correction."""
    Kp, Kd = loops.baumgarte()
    return {
        "loops": {lc.loop.name: f"{lc.loop.kind}: {len(lc.indices)} CONTACT_3D (LOCAL)"
                  + (f", the second {lc.lever:g} m along the axis" if lc.loop.kind == "revolute" else "")
                  for lc in pm.loop_contacts},
        "loop_summary": str(pm.scene.loop_summary()),
        "proximal": {"mu": pm.mu, "mu_relative_to_delassus": loops.PROXIMAL_MU_REL,
                     "max_iter": loops.PROXIMAL_ITERATIONS, "accuracy": loops.PROXIMAL_ACCURACY},
        "drift_correction": {"method": "Baumgarte (RigidConstraintModel corrector)", "Kp": Kp, "Kd": Kd},
    }
