"""What MuJoCo simulated, read back from the compiled model: the audit of a run (``Adapter.audit``)."""

from __future__ import annotations

import numpy as np

from dalembert.adapters.mujoco import contact
from dalembert.adapters.mujoco.mjcf import loop_softness
from dalembert.adapters.mujoco.springs import other_passive, read_springs

__all__ = ["audit", "SPRING_INTEGRATION"]

# How each integrator treats a spring's tendon force (measured, one step of a damper alone: Euler's velocity
# falls by h c / m, implicit's and implicitfast's by the factor 1 / (1 + h c / m); the eulerdamp flag changes
# neither, it covers joint damping only).
SPRING_INTEGRATION = {
    "euler": "stiffness and damping explicit (semi-implicit Euler); MuJoCo's eulerdamp covers joint damping only",
    "rk4": "stiffness and damping explicit, in every RK4 stage",
    "implicit": "stiffness explicit; tendon damping implicit in velocity (backward Euler: -h c J^T J in the matrix)",
    "implicitfast": "stiffness explicit; tendon damping implicit in velocity (backward Euler: -h c J^T J in the matrix)",
    "discrete": "stiffness explicit; tendon damping implicit in velocity (MuJoCo's discrete integrator)",
}


def audit(prepared, outcome):
    """What MuJoCo simulated, read back from the compiled model: gravity, flags, integrator and step, the load
    path and actuators, passive parameters, joints, loop constraints and their softness, springs, and the figures
    the read-back collects (contacts, constraint rows, passive forces)."""
    import mujoco

    model = prepared.model
    disabled = [name[len("mjDSBL_"):].lower() for name in dir(mujoco.mjtDisableBit) if name.startswith("mjDSBL_")
                and model.opt.disableflags & int(getattr(mujoco.mjtDisableBit, name))]
    enabled = [name[len("mjENBL_"):].lower() for name in dir(mujoco.mjtEnableBit) if name.startswith("mjENBL_")
               and model.opt.enableflags & int(getattr(mujoco.mjtEnableBit, name))]
    return {
        "gravity": tuple(float(g) for g in model.opt.gravity),
        "disabled": sorted(disabled),
        "enabled": sorted(enabled),
        "integrator": mujoco.mjtIntegrator(model.opt.integrator).name,
        "timestep": float(model.opt.timestep),
        "mujoco_version": mujoco.__version__,
        "load_path": prepared.load_path,
        "actuators": [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, i) for i in range(model.nu)],
        "max_armature": float(np.abs(model.dof_armature).max(initial=0.0)),
        "max_damping": float(np.abs(model.dof_damping).max(initial=0.0)),
        "ngeom": int(model.ngeom),
        "joints": _joint_audit(prepared),
        **_loop_audit(prepared),
        **_spring_audit(prepared),
        **contact.audit(model, prepared.scene),
        **_read_audit(outcome),
    }


def _joint_audit(prepared):
    """Every scene joint MuJoCo builds as a joint, as the compiled model holds it: dict joint (child) name ->
    ``type`` (MuJoCo's: free, ball, slide, hinge), ``axis_W`` (hinge and slide: the unit axis in world axes at
    the initial state, MuJoCo's ``xaxis``; else None) and the joint's own limit, stiffness, damping,
    armature and friction loss (``limited`` a bool, the others the largest magnitude over its dofs)."""
    import mujoco

    model, scene = prepared.model, prepared.scene
    d = mujoco.MjData(model)
    d.qpos[:] = prepared.qpos0
    mujoco.mj_kinematics(model, d)
    out = {}
    for j in scene.joints:
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j.child)
        if jid < 0:  # a weld built as nesting: no joint
            continue
        kind = mujoco.mjtJoint(model.jnt_type[jid])
        dofs = np.flatnonzero(model.dof_jntid == jid)
        axial = kind in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE)
        out[j.child] = {
            "type": kind.name[len("mjJNT_"):].lower(),
            "axis_W": [float(v) for v in d.xaxis[jid]] if axial else None,
            "limited": bool(model.jnt_limited[jid]),
            "stiffness": float(abs(model.jnt_stiffness[jid])),
            "damping": float(np.abs(model.dof_damping[dofs]).max()),
            "armature": float(np.abs(model.dof_armature[dofs]).max()),
            "frictionloss": float(np.abs(model.dof_frictionloss[dofs]).max()),
        }
    return out


def _loop_audit(prepared):
    """The loops' constraints and their softness, read back from the compiled model (none: empty)."""
    import mujoco

    model, scene = prepared.model, prepared.scene
    if not scene.loops:
        return {}
    (tc, zeta), _ = loop_softness(prepared.settings)
    refsafe = not model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_REFSAFE)
    kinds = [mujoco.mjtEq(t).name[len("mjEQ_"):].lower() for t in model.eq_type]
    return {
        "loop_constraints": {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_EQUALITY, i): kinds[i]
                             for i in range(model.neq)},
        "loop_solref": [float(v) for v in model.eq_solref[0]],
        "loop_solimp": [float(v) for v in model.eq_solimp[0]],
        "loop_softness": (f"MuJoCo's soft equality constraints: reference acceleration -b v - k r with time "
                          f"constant {tc:g} s ({tc / prepared.settings.dt:g} steps; refsafe {'on' if refsafe else 'off'}) "
                          f"and damping ratio {zeta:g}; impedance {model.eq_solimp[0][0]:g} (MuJoCo's largest), so the "
                          "solver's regularization leaves each constraint force ~1e-4 relative short, made up by the "
                          "residual's spring: the closure is not exact, its residual is the run's loop_residual"),
    }


def _spring_audit(prepared):
    """The springs as the compiled model holds them (``springs.read_springs``: stiffness, damping, rest
    length, the bodies and points of the tendon's sites), every other passive parameter (all zero), and
    how the integrator treats them (none: empty)."""
    model, scene = prepared.model, prepared.scene
    if not scene.springs:
        return {}
    springs = [{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in s.items()}
               for s in read_springs(model, scene, prepared.frames)]
    return {"springs": springs, "passive_not_springs": other_passive(model, scene),
            "spring_integration": SPRING_INTEGRATION.get(prepared.settings.integrator, "")}


def _read_audit(outcome):
    """The figures the read-back collects on its way (contacts, constraint rows, passive forces)."""
    outcome.trajectory  # reads back, once, if nothing has yet
    return outcome.info["audit"]
