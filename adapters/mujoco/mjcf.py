"""MuJoCo's model of a scene: generated MJCF text, exactly the scene's physics.

Kept as text (for reports and ``dalembert show-model``), and importable without
MuJoCo: nothing here calls it.

* Every body has an explicit ``<inertial>`` (mass, COM, full inertia) and no
  geoms. A free body's MuJoCo frame is the scene's body frame at the COM
  (``alignfree="false"``, so qpos/qvel refer to it); a jointed body's MuJoCo
  frame is its child joint frame, so its inertial has a COM offset — MuJoCo's
  diagonalized ``body_ipos/iquat/inertia`` are checked against the scene after
  compiling.
* ``<freejoint/>`` (no inherited damping/armature), hinge, slide, ball; a weld is a
  body without a joint (option ``welds=tree``), or a free body held by an
  equality constraint (``welds=equality``). A slide joint (the scene's prismatic) has its axis in
  the body's MuJoCo frame E = Jc, which keeps Jp's attitude, so the scene's axis (given in Jp) is
  written as is; MuJoCo moves E by ``qpos * a`` from its placement at ``qpos0`` = 0, which is Jp:
  the scene's child joint frame at ``d * a`` in Jp.
* Gravity from the scene, and the gravity stage disabled when it is zero
  (MuJoCo's default is -9.81). Contact, constraint, equality, limit,
  frictionloss, spring, damper, control clamping and auto-reset are disabled (spring and
  damper stay enabled in a scene with spring-dampers: every joint's own stiffness and damping
  are written as zero, and the audit reads them back).
* Loop closures (``Scene.loops``) as equality constraints between sites at the loop's points
  (``loop_sites``): ``ball`` a ``<connect>``; ``revolute`` two connects, at the points and at
  ``AXIS_LEVER`` along the axis from them (MuJoCo has no revolute equality; its documentation:
  "two connect constraints for the same pair of bodies can be used to model a hinge joint");
  ``distance`` a spatial tendon between the two sites held at the loop's length by a ``<tendon>``
  equality (whose offset is the length minus the tendon's length at MuJoCo's reference
  configuration ``qpos0``, computed here from the MJCF's own body placements). All as stiff as
  MuJoCo allows (``LOOP_SOLREF_STEPS``, ``LOOP_SOLIMP``).
* Spring-dampers (``Scene.springs``) as spatial tendons between two sites at the spring's points
  (``spring_sites``; a site on the worldbody for a world end) with ``stiffness``, ``damping`` and
  ``springlength`` the spring's (the rest length, both ends of MuJoCo's dead band). MuJoCo's tendon
  force ``-stiffness (L - springlength) - damping L'``, with ``L'`` its ``ten_velocity`` and the force
  applied through the tendon Jacobian, is ``dalembert.springs``' tension with its sign (measured:
  ``qfrc_passive`` along the line, ``ten_velocity`` the rate of the length). Tendons are named
  ``spring_tendon(name)``.
* Loads through site actuators with a constant control of 1 and
  ``gear = (force, torque)``: a follower load in a site whose axes are the body
  axes, a world-frame load with a ``refsite`` at the world origin. MuJoCo then
  applies the load inside every integrator stage. Option
  ``loads=xfrc_applied`` instead rewrites ``data.xfrc_applied`` before each
  step (``stepping.apply_xfrc``), which lags follower forces by a step (kept to
  show the difference; never the default).
* Contact (``Scene.geoms``, ``planes``, ``contacts``): geoms, planes and explicit pairs, with nothing colliding by
  default, and the contact options (``contact``: its docstring states every mapping). A scene with contact pairs
  keeps the contact and constraint stages enabled.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.adapters.base import Option, option_value
from dalembert.adapters.mujoco import contact
from dalembert.scene import WORLD

__all__ = ["mjcf", "engine_frames", "floating", "loop_sites", "loop_softness", "spring_sites", "spring_tendon", "INTEGRATORS", "LOAD_PATHS", "WELDS",
           "AXIS_LEVER", "LOOP_SOLREF_STEPS", "LOOP_SOLREF_STEPS_DEFAULT", "LOOP_SOLIMP"]

# Engine name -> MJCF integrator attribute.
INTEGRATORS = {"euler": "Euler", "rk4": "RK4", "implicit": "implicit", "implicitfast": "implicitfast",
               "discrete": "discrete"}
LOAD_PATHS = ("actuator", "xfrc_applied")
# Welds: nested bodies (``tree``, exact: no constraint) or free bodies held by equality
# constraints (``equality``: MuJoCo's constraint solver, whose constraints are soft).
WELDS = ("tree", "equality")
# The options the MJCF is written by, declared here where ``mjcf`` reads them (``MujocoAdapter.options``; MJX's
# takes ``welds``): their defaults are read from here by the MJCF and the adapters alike.
MJCF_OPTIONS = {
    "loads": Option(LOAD_PATHS, LOAD_PATHS[0], "how loads enter: site actuators (every integrator stage) or "
                    "xfrc_applied set from Python once per step"),
    "welds": Option(WELDS, WELDS[0], "welds as nested bodies (exact) or free bodies held by equality constraints"),
}
# Weld constraints as stiff as MuJoCo allows, since the scene's welds are rigid: the time
# constant at 2 timesteps (MuJoCo clamps anything shorter, refsafe) with critical damping,
# and the impedance at 0.9999 (MuJoCo's largest). What softness remains is MuJoCo's, and the
# pairwise-distance invariant shows it: the stretch falls as dt^2, but the impedance leaves
# the constraint forces ~1e-4 relative short at any step (measured: 3.9e-4 N on the chain's
# joint reactions at dt = 1e-3 and 1e-4).
WELD_SOLREF_STEPS = 2.0
WELD_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)
# Loop closures, as stiff as MuJoCo runs them (measured on the four-bar, dt = 1e-2 to 1e-4): the time
# constant in steps per integrator. RK4 runs 1 step (refsafe disabled: MuJoCo would clamp it to 2), which
# cuts its angle error 17-fold at dt = 1e-3 against 2 steps; at 0.5 steps its errors grow again. Euler,
# implicit, implicitfast (and discrete) diverge at 1 step at every dt: they keep refsafe's minimum, 2.
LOOP_SOLREF_STEPS = {"rk4": 1.0}
LOOP_SOLREF_STEPS_DEFAULT = 2.0
LOOP_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)
# A revolute loop's second connect sits this far (m) along the axis from the loop's points: its rows
# then measure the axes' tilt in metres, on the scale of the point rows (bars of ~1 m).
AXIS_LEVER = 1.0
DISABLED = ("contact", "constraint", "equality", "limit", "frictionloss", "spring", "damper", "clampctrl",
            "autoreset")


def _disabled_names():
    """``DISABLED`` as the installed MuJoCo names its flags: releases without the ``spring`` and ``damper`` flags
    (3.2 and older: no ``mjDSBL_SPRING``) disable both with one, ``passive``. Without MuJoCo (the model written
    as text alone), the current names."""
    try:
        import mujoco
    except ImportError:
        return DISABLED
    if hasattr(mujoco.mjtDisableBit, "mjDSBL_SPRING"):
        return DISABLED
    return tuple(dict.fromkeys("passive" if f in ("spring", "damper") else f for f in DISABLED))


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


def loop_softness(settings):
    """``(solref, solimp)`` of every loop constraint for ``settings`` (integrator and step): the time
    constant at ``LOOP_SOLREF_STEPS`` steps of the integrator (the shortest it runs), critically damped,
    and the impedance at ``LOOP_SOLIMP`` (MuJoCo's largest, 0.9999)."""
    return (_loop_steps(settings) * settings.dt, 1.0), LOOP_SOLIMP


def _loop_steps(settings):
    return LOOP_SOLREF_STEPS.get(settings.integrator, LOOP_SOLREF_STEPS_DEFAULT)


def loop_sites(scene, welds="tree"):
    """The sites every loop constraint joins, per loop (``scene.loops`` order): a list of pairs
    ``((body_a, p_Ea), (body_b, p_Eb))``, each point in its body's MuJoCo frame E (the world's for
    ``"world"``), m. One pair for ``ball`` and ``distance`` (the loop's points); two for ``revolute``:
    the points, then the points moved ``AXIS_LEVER`` along the axis as each side carries it."""
    X_EB = engine_frames(scene, welds)
    X_EB["world"] = (np.zeros(3), np.eye(3))
    out = []
    for lp in scene.loops:
        ends = []
        for body, point, quat in ((lp.body_a, lp.point_a, lp.quat_a), (lp.body_b, lp.point_b, lp.quat_b)):
            p_EB, R_EB = X_EB[body]
            p = p_EB + R_EB @ np.array(point)
            ends.append((body, p, R_EB @ spatial.quat_to_matrix(quat)))  # R_EJ: the joint frame in E
        pairs = [((a, pa), (b, pb)) for (a, pa, _), (b, pb, _) in [ends]]
        if lp.kind == "revolute":
            axis = np.array(lp.axis) / np.linalg.norm(lp.axis)
            (a, pa, Ra), (b, pb, Rb) = ends
            pairs.append(((a, pa + AXIS_LEVER * Ra @ axis), (b, pb + AXIS_LEVER * Rb @ axis)))
        out.append(pairs)
    return out


def spring_tendon(name):
    """The MuJoCo name of the spatial tendon of the spring ``name`` (kept apart from the loops' tendons)."""
    return f"spring:{name}"


def spring_sites(scene, welds="tree"):
    """The two sites of every spring (``scene.springs`` order): a list of pairs ``((body_a, p_Ea),
    (body_b, p_Eb))``, each point in its body's MuJoCo frame E (the world's for ``"world"``), m."""
    X_EB = engine_frames(scene, welds)
    X_EB["world"] = (np.zeros(3), np.eye(3))
    out = []
    for sp in scene.springs:
        out.append(tuple((body, X_EB[body][0] + X_EB[body][1] @ np.array(point))
                         for body, point in ((sp.body_a, sp.point_a), (sp.body_b, sp.point_b))))
    return out


def _placement(scene, j, X_EB, welds, state0):
    """Where the MJCF places the child of ``j`` in its parent's MuJoCo frame (the world's for a
    floating body): ``(pos (3,), quat (4,))``, MuJoCo's reference configuration ``qpos0``."""
    if j.kind == "free":
        return np.array(j.q0[:3]), np.array(j.q0[3:])  # placed by qpos anyway
    if floating(j, welds):  # a weld held by a constraint, at its initial pose: the weld's reference
        return state0[j.child]["p"], spatial.matrix_to_quat(state0[j.child]["R"])
    # E (= Jc) coincides with the parent joint frame Jp at q = 0, placed in the parent's
    # MuJoCo frame Ep, where the parent's scene frame P sits at X_EpP (its X_EB).
    p_EpP, R_EpP = (np.zeros(3), np.eye(3)) if j.parent == WORLD else X_EB[j.parent]
    R_PJ = spatial.quat_to_matrix(j.parent_quat)
    return p_EpP + R_EpP @ np.array(j.parent_point), spatial.matrix_to_quat(R_EpP @ R_PJ)


def _reference_poses(scene, X_EB, welds, state0):
    """Each body's MuJoCo frame in the world at ``qpos0`` (hinges at 0, balls at identity, free bodies
    where the MJCF places them): dict body -> ``(p_WE, R_WE)``, the world's included."""
    poses = {WORLD: (np.zeros(3), np.eye(3))}
    for body in scene.topological_order():
        j = scene.joint(body.name)
        pos, quat = _placement(scene, j, X_EB, welds, state0)
        parent = WORLD if floating(j, welds) else j.parent
        p, R = poses[parent]
        poses[body.name] = (p + R @ pos, R @ spatial.quat_to_matrix(quat))
    return poses


def mjcf(scene, settings):
    """MJCF text of ``scene`` for ``settings`` (dt, integrator, options)."""
    welds = option_value(MJCF_OPTIONS, settings, "welds")
    X_EB = engine_frames(scene, welds)
    load_path = option_value(MJCF_OPTIONS, settings, "loads")
    weld_constraints = [j for j in scene.joints if j.kind == "weld" and welds == "equality"]
    state0 = spatial.initial_body_states(scene) if weld_constraints else {}  # the welded bodies' poses
    sites = loop_sites(scene, welds)
    site_lines = {}  # body -> its loop sites' MJCF lines
    for i, pairs in enumerate(sites):
        for k, ((a, pa), (b, pb)) in enumerate(pairs):
            for end, body, pos in (("a", a, pa), ("b", b, pb)):
                site_lines.setdefault(body, []).append(f'<site name="loop{i}_{end}{k}" pos="{_f(pos)}"/>')
    for i, ends in enumerate(spring_sites(scene, welds)):
        for end, (body, pos) in zip("ab", ends):
            site_lines.setdefault(body, []).append(f'<site name="spring{i}_{end}" pos="{_f(pos)}"/>')
    children = {}
    for j in scene.joints:  # a welded body held by a constraint hangs from the world, free
        children.setdefault(WORLD if j in weld_constraints else j.parent, []).append(j)
    gravity = np.array(scene.gravity)
    constrained = bool(weld_constraints or scene.loops)
    disabled = [f for f in _disabled_names() if not (constrained and f in ("constraint", "equality"))
                and not (scene.springs and f in ("spring", "damper", "passive"))
                and not (scene.contacts and f in ("constraint", "contact"))]
    if scene.loops and _loop_steps(settings) < 2.0:
        disabled.append("refsafe")  # MuJoCo would clamp the time constant to 2 steps
    flags = " ".join(f'{f}="disable"' for f in disabled)
    if not np.any(gravity):
        flags += ' gravity="disable"'
    lines = ['<mujoco model="%s">' % scene.name,
             '  <compiler angle="radian" alignfree="false" autolimits="true" boundmass="0" boundinertia="0"/>',
             f'  <option timestep="{settings.dt!r}" integrator="{INTEGRATORS[settings.integrator]}" '
             f'gravity="{_f(gravity)}"{contact.option_attributes(scene, settings)}>',
             f"    <flag {flags}/>", "  </option>", "  <worldbody>"]
    if load_path == "actuator" and any(ld.frame == "world" for ld in scene.loads):
        lines.append('    <site name="world_origin" pos="0 0 0"/>')
    lines += ["    " + line for line in site_lines.get(WORLD, [])]
    lines += ["    " + line for line in contact.plane_lines(scene)]

    def body_xml(j, indent):
        p_EB, R_EB = X_EB[j.child]
        body = scene.body(j.child)
        pos, quat = _placement(scene, j, X_EB, welds, state0)
        I_E = R_EB @ body.inertia_matrix @ R_EB.T
        fi = [I_E[0, 0], I_E[1, 1], I_E[2, 2], I_E[0, 1], I_E[0, 2], I_E[1, 2]]
        out = [f'{indent}<body name="{body.name}" pos="{_f(pos)}" quat="{_f(quat)}">',
               f'{indent}  <inertial pos="{_f(p_EB)}" mass="{body.mass!r}" fullinertia="{_f(fi)}"/>']
        if floating(j, welds):
            out.append(f'{indent}  <freejoint name="{body.name}"/>')
        elif j.kind == "revolute":
            out.append(f'{indent}  <joint name="{body.name}" type="hinge" pos="0 0 0" axis="{_f(j.axis)}" '
                       'damping="0" armature="0" stiffness="0" frictionloss="0" limited="false"/>')
        elif j.kind == "prismatic":  # E = Jc keeps Jp's attitude: the axis in E is the scene's, in Jp
            out.append(f'{indent}  <joint name="{body.name}" type="slide" pos="0 0 0" axis="{_f(j.axis)}" '
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
        out += [f"{indent}  {line}" for line in site_lines.get(body.name, [])]
        out += [f"{indent}  {line}" for line in contact.geom_lines(scene, body.name, p_EB, R_EB)]
        for c in children.get(body.name, []):
            out += body_xml(c, indent + "  ")
        out.append(f"{indent}</body>")
        return out

    for j in children.get(WORLD, []):
        lines += body_xml(j, "    ")
    lines.append("  </worldbody>")
    distance = [(i, lp) for i, lp in enumerate(scene.loops) if lp.kind == "distance"]
    if distance or scene.springs:
        lines.append("  <tendon>")
        for i, lp in distance:
            lines += [f'    <spatial name="{lp.name}" limited="false" stiffness="0" damping="0" frictionloss="0">',
                      f'      <site site="loop{i}_a0"/>', f'      <site site="loop{i}_b0"/>', "    </spatial>"]
        for i, sp in enumerate(scene.springs):
            rest = f"{sp.rest_length!r} {sp.rest_length!r}"  # no dead band: both ends at the rest length
            lines += [f'    <spatial name="{spring_tendon(sp.name)}" limited="false" stiffness="{sp.stiffness!r}" '
                      f'damping="{sp.damping!r}" springlength="{rest}" frictionloss="0">',
                      f'      <site site="spring{i}_a"/>', f'      <site site="spring{i}_b"/>', "    </spatial>"]
        lines.append("  </tendon>")
    if weld_constraints or scene.loops:
        lines.append("  <equality>")
    if scene.loops:
        (tc, zeta), solimp = loop_softness(settings)
        soft = f'solref="{tc!r} {zeta!r}" solimp="{_f(solimp)}"'
        poses = _reference_poses(scene, X_EB, welds, state0) if distance else {}
        for i, (lp, pairs) in enumerate(zip(scene.loops, sites)):
            if lp.kind == "distance":
                (a, pa), (b, pb) = pairs[0]
                x = [poses[body][0] + poses[body][1] @ p for body, p in ((a, pa), (b, pb))]
                length0 = float(np.linalg.norm(x[0] - x[1]))  # the tendon's length at qpos0 (MuJoCo's L0)
                # MuJoCo holds L - L0 = polycoef[0]: the offset that makes L the loop's length
                lines.append(f'    <tendon name="{lp.name}" tendon1="{lp.name}" '
                             f'polycoef="{lp.length - length0!r} 0 0 0 0" {soft}/>')
                continue
            for k in range(len(pairs)):
                name = lp.name if k == 0 else f"{lp.name}:axis"
                lines.append(f'    <connect name="{name}" site1="loop{i}_a{k}" site2="loop{i}_b{k}" {soft}/>')
    if weld_constraints:
        solref = f"{WELD_SOLREF_STEPS * settings.dt!r} 1"
        for j in weld_constraints:
            # relpose: the child's MuJoCo frame in the parent's, as the scene's weld holds them
            X_WE = {}
            for name in (j.parent, j.child):
                if name == WORLD:  # the world's frame is MuJoCo's world frame
                    X_WE[name] = (np.zeros(3), np.eye(3))
                    continue
                s0, (p_EB, R_EB) = state0[name], X_EB.get(name, (np.zeros(3), np.eye(3)))
                R_WE = s0["R"] @ R_EB.T
                X_WE[name] = (s0["p"] - R_WE @ p_EB, R_WE)
            (p1, R1), (p2, R2) = X_WE[j.parent], X_WE[j.child]
            relpose = np.concatenate([R1.T @ (p2 - p1), spatial.matrix_to_quat(R1.T @ R2)])
            body1 = "world" if j.parent == WORLD else j.parent  # MuJoCo's world body is named "world"
            lines.append(f'    <weld name="{j.child}" body1="{body1}" body2="{j.child}" relpose="{_f(relpose)}" '
                         f'solref="{solref}" solimp="{_f(WELD_SOLIMP)}"/>')
    if weld_constraints or scene.loops:
        lines.append("  </equality>")
    lines += contact.pair_lines(scene, settings)
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
