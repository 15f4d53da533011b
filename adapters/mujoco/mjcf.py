"""MuJoCo's model of a scene: generated MJCF text, exactly the scene's physics.

Kept as text (for reports and ``dalembert show-model``), and importable without
MuJoCo: nothing here calls it.

* Every body has an explicit ``<inertial>`` (mass, COM, full inertia) and no
  geoms. A free body's MuJoCo frame is the scene's body frame at the COM
  (``alignfree="false"``, so qpos/qvel refer to it); a jointed body's MuJoCo
  frame is its child joint frame, so its inertial has a COM offset — MuJoCo's
  diagonalized ``body_ipos/iquat/inertia`` are checked against the scene after
  compiling.
* ``<freejoint/>`` (no inherited damping/armature), hinge, ball; a weld is a
  body without a joint (option ``welds=tree``), or a free body held by an
  equality constraint (``welds=equality``).
* Gravity from the scene, and the gravity stage disabled when it is zero
  (MuJoCo's default is -9.81). Contact, constraint, equality, limit,
  frictionloss, spring, damper, control clamping and auto-reset are disabled.
* Loads through site actuators with a constant control of 1 and
  ``gear = (force, torque)``: a follower load in a site whose axes are the body
  axes, a world-frame load with a ``refsite`` at the world origin. MuJoCo then
  applies the load inside every integrator stage. Option
  ``loads=xfrc_applied`` instead rewrites ``data.xfrc_applied`` before each
  step (``stepping.apply_xfrc``), which lags follower forces by a step (kept to
  show the difference; never the default).
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.scene import WORLD

__all__ = ["mjcf", "engine_frames", "floating", "INTEGRATORS", "LOAD_PATHS", "WELDS"]

# Engine name -> MJCF integrator attribute.
INTEGRATORS = {"euler": "Euler", "rk4": "RK4", "implicit": "implicit", "implicitfast": "implicitfast",
               "discrete": "discrete"}
LOAD_PATHS = ("actuator", "xfrc_applied")
# Welds: nested bodies (``tree``, exact: no constraint) or free bodies held by equality
# constraints (``equality``: MuJoCo's constraint solver, whose constraints are soft).
WELDS = ("tree", "equality")
# Weld constraints as stiff as MuJoCo allows, since the scene's welds are rigid: the time
# constant at 2 timesteps (MuJoCo clamps anything shorter, refsafe) with critical damping,
# and the impedance at 0.9999 (MuJoCo's largest). What softness remains is MuJoCo's, and the
# pairwise-distance invariant shows it: the stretch falls as dt^2, but the impedance leaves
# the constraint forces ~1e-4 relative short at any step (measured: 3.9e-4 N on the chain's
# joint reactions at dt = 1e-3 and 1e-4).
WELD_SOLREF_STEPS = 2.0
WELD_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)
DISABLED = ("contact", "constraint", "equality", "limit", "frictionloss", "spring", "damper", "clampctrl",
            "autoreset")


def _f(x):
    return " ".join(repr(float(v)) for v in np.ravel(x))


def floating(j, welds):
    """Whether MuJoCo gets this body as a free body: a free joint, or a weld with ``welds=equality``."""
    return j.kind == "free" or (j.kind == "weld" and welds == "equality")


def engine_frames(scene, welds="tree"):
    """Per body, ``X_EB`` (``dalembert.adapters.base``): the scene body frame B in MuJoCo's
    body frame E, as ``(p_EB, R_EB)`` with ``x_E = p_EB + R_EB x_B``."""
    out = {}
    for j in scene.joints:
        if floating(j, welds):
            out[j.child] = (np.zeros(3), np.eye(3))
        else:  # E = the child joint frame Jc
            R_CJ = spatial.quat_to_matrix(j.child_quat)
            out[j.child] = (-R_CJ.T @ np.array(j.child_point), R_CJ.T)
    return out


def mjcf(scene, settings):
    """MJCF text of ``scene`` for ``settings`` (dt, integrator, options)."""
    welds = settings.options.get("welds", "tree")
    X_EB = engine_frames(scene, welds)
    load_path = settings.options.get("loads", "actuator")
    weld_constraints = [j for j in scene.joints if j.kind == "weld" and welds == "equality"]
    state0 = spatial.initial_body_states(scene) if weld_constraints else {}  # the welded bodies' poses
    children = {}
    for j in scene.joints:  # a welded body held by a constraint hangs from the world, free
        children.setdefault(WORLD if j in weld_constraints else j.parent, []).append(j)
    gravity = np.array(scene.gravity)
    disabled = [f for f in DISABLED if not (weld_constraints and f in ("constraint", "equality"))]
    flags = " ".join(f'{f}="disable"' for f in disabled)
    if not np.any(gravity):
        flags += ' gravity="disable"'
    lines = ['<mujoco model="%s">' % scene.name,
             '  <compiler angle="radian" alignfree="false" autolimits="true" boundmass="0" boundinertia="0"/>',
             f'  <option timestep="{settings.dt!r}" integrator="{INTEGRATORS[settings.integrator]}" '
             f'gravity="{_f(gravity)}">',
             f"    <flag {flags}/>", "  </option>", "  <worldbody>"]
    if load_path == "actuator" and any(ld.frame == "world" for ld in scene.loads):
        lines.append('    <site name="world_origin" pos="0 0 0"/>')

    def body_xml(j, indent):
        p_EB, R_EB = X_EB[j.child]
        body = scene.body(j.child)
        if j.kind == "free":
            pos, quat = np.array(j.q0[:3]), np.array(j.q0[3:])  # placed by qpos anyway
        elif floating(j, welds):  # a weld held by a constraint, at its initial pose: the weld's reference
            pos, quat = state0[j.child]["p"], spatial.matrix_to_quat(state0[j.child]["R"])
        else:
            # E (= Jc) coincides with the parent joint frame Jp at q = 0, placed in the parent's
            # MuJoCo frame Ep, where the parent's scene frame P sits at X_EpP (its X_EB).
            p_EpP, R_EpP = (np.zeros(3), np.eye(3)) if j.parent == WORLD else X_EB[j.parent]
            R_PJ = spatial.quat_to_matrix(j.parent_quat)
            pos = p_EpP + R_EpP @ np.array(j.parent_point)
            quat = spatial.matrix_to_quat(R_EpP @ R_PJ)
        I_E = R_EB @ body.inertia_matrix @ R_EB.T
        fi = [I_E[0, 0], I_E[1, 1], I_E[2, 2], I_E[0, 1], I_E[0, 2], I_E[1, 2]]
        out = [f'{indent}<body name="{body.name}" pos="{_f(pos)}" quat="{_f(quat)}">',
               f'{indent}  <inertial pos="{_f(p_EB)}" mass="{body.mass!r}" fullinertia="{_f(fi)}"/>']
        if floating(j, welds):
            out.append(f'{indent}  <freejoint name="{body.name}"/>')
        elif j.kind == "revolute":
            out.append(f'{indent}  <joint name="{body.name}" type="hinge" pos="0 0 0" axis="{_f(j.axis)}" '
                       'damping="0" armature="0" stiffness="0" frictionloss="0" limited="false"/>')
        elif j.kind == "ball":
            out.append(f'{indent}  <joint name="{body.name}" type="ball" pos="0 0 0" '
                       'damping="0" armature="0" stiffness="0" frictionloss="0" limited="false"/>')
        if load_path == "actuator":
            for k, ld in enumerate(scene.loads):
                if ld.body == body.name:
                    site_pos = p_EB + R_EB @ np.array(ld.point)
                    out.append(f'{indent}  <site name="load{k}" pos="{_f(site_pos)}" '
                               f'quat="{_f(spatial.matrix_to_quat(R_EB))}"/>')
        for c in children.get(body.name, []):
            out += body_xml(c, indent + "  ")
        out.append(f"{indent}</body>")
        return out

    for j in children.get(WORLD, []):
        lines += body_xml(j, "    ")
    lines.append("  </worldbody>")
    if weld_constraints:
        solref = f"{WELD_SOLREF_STEPS * settings.dt!r} 1"
        lines.append("  <equality>")
        for j in weld_constraints:
            # relpose: the child's MuJoCo frame in the parent's, as the scene's weld holds them
            X_WE = {}
            for name in (j.parent, j.child):
                s0, (p_EB, R_EB) = state0[name], X_EB.get(name, (np.zeros(3), np.eye(3)))
                R_WE = s0["R"] @ R_EB.T
                X_WE[name] = (s0["p"] - R_WE @ p_EB, R_WE)
            (p1, R1), (p2, R2) = X_WE[j.parent], X_WE[j.child]
            relpose = np.concatenate([R1.T @ (p2 - p1), spatial.matrix_to_quat(R1.T @ R2)])
            body1 = "" if j.parent == WORLD else f' body1="{j.parent}"'
            lines.append(f'    <weld name="{j.child}"{body1} body2="{j.child}" relpose="{_f(relpose)}" '
                         f'solref="{solref}" solimp="{_f(WELD_SOLIMP)}"/>')
        lines.append("  </equality>")
    if load_path == "actuator" and scene.loads:
        lines.append("  <actuator>")
        for k, ld in enumerate(scene.loads):
            gear = np.concatenate([ld.vector, np.zeros(3)] if ld.kind == "force" else [np.zeros(3), ld.vector])
            ref = ' refsite="world_origin"' if ld.frame == "world" else ""
            lines.append(f'    <general name="load{k}" site="load{k}"{ref} gear="{_f(gear)}" gainprm="1" '
                         'biasprm="0 0 0" ctrllimited="false" forcelimited="false"/>')
        lines.append("  </actuator>")
    lines.append("</mujoco>")
    return "\n".join(lines) + "\n"
