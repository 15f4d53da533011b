"""MuJoCo adapter: the scene as generated MJCF, exactly the scene's physics.

Model (``mjcf(scene, settings)``, kept as text for reports and ``show-model``):

* Every body has an explicit ``<inertial>`` (mass, COM, full inertia) and no
  geoms. A free body's MuJoCo frame is the scene's body frame at the COM
  (``alignfree="false"``, so qpos/qvel refer to it); a jointed body's MuJoCo
  frame is its child joint frame, so its inertial has a COM offset — MuJoCo's
  diagonalized ``body_ipos/iquat/inertia`` are checked against the scene after
  compiling.
* ``<freejoint/>`` (no inherited damping/armature), hinge, ball; a weld is a
  body without a joint.
* Gravity from the scene, and the gravity stage disabled when it is zero
  (MuJoCo's default is -9.81). Contact, constraint, equality, limit,
  frictionloss, spring, damper, control clamping and auto-reset are disabled.
* Loads through site actuators with a constant control of 1 and
  ``gear = (force, torque)``: a follower load in a site whose axes are the body
  axes, a world-frame load with a ``refsite`` at the world origin. MuJoCo then
  applies the load inside every integrator stage. Option
  ``loads=xfrc_applied`` instead rewrites ``data.xfrc_applied`` before each
  step, which lags follower forces by a step (kept to show the difference; never
  the default).

Stepping: ``mujoco.rollout`` (native loop) in chunks of at most
``ROLLOUT_CHUNK_STEPS`` steps, subsampled at the sample times. Measured on the
free top (20000 RK4 steps): rollout 0.146 s, ``mj_step(nstep=10)`` per sample
0.147 s, a Python loop of ``mj_step`` 0.153 s — identical numbers; per sample
interval the ``mj_step(nstep)`` path adds ~4.5 us of Python (a ratio of up to
1.3 against a bare rollout on the cheap integrators), so rollout is the default.
MuJoCo with auto-reset disabled does not produce NaN on a bad acceleration — it
raises a warning counter (which rollout records in the ``MjData`` it is given)
and freezes the state. When a chunk ends with a warning, the run is repeated
with ``mj_step(nstep)`` per sample interval to find the first bad sample; the
adapter reports NaN from there on with MuJoCo's message. Warnings go to the
adapter, not to ``MUJOCO_LOG.TXT``.

Read-back (after stepping, not timed): for every sample the state is set in a
scratch ``MjData`` and ``mj_forward`` + ``mj_rnePostConstraint`` recompute the
derived quantities (right after ``mj_step`` they describe the previous state).
Poses and velocities of the scene's body frames come from the MuJoCo frames
through ``dalembert.spatial``. The joint reaction on a child is
``cfrc_int``'s force part minus the loads that the site actuators routed
through joint space onto the child's subtree (MuJoCo counts them as joint
torques, not as external forces).
"""

from __future__ import annotations

import time

import numpy as np

from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, option_choice
from dalembert import spatial
from dalembert.scene import EFFECTS, WORLD
from dalembert.settings import steps_per_interval

__all__ = ["MujocoAdapter", "mjcf"]

# Engine name -> MJCF integrator attribute.
INTEGRATORS = {"euler": "Euler", "rk4": "RK4", "implicit": "implicit", "implicitfast": "implicitfast",
               "discrete": "discrete"}
LOAD_PATHS = ("actuator", "xfrc_applied")
# Welds: nested bodies (``tree``, exact: no constraint) or free bodies held by equality
# constraints (``equality``: MuJoCo's constraint solver, whose constraints are soft).
WELDS = ("tree", "equality")
OPTIONS = ("loads", "welds")
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
# Longest rollout call: its state output (steps x nstate doubles) stays ~10 MB
# for the small models here, whatever the horizon.
ROLLOUT_CHUNK_STEPS = 50_000
# Compiled mass properties must reproduce the scene's to this relative accuracy:
# MuJoCo diagonalizes the full inertia (an eigen-solve), which costs a few ulps.
MASS_PROPERTY_REL_TOL = 1e-10


def _f(x):
    return " ".join(repr(float(v)) for v in np.ravel(x))


def _floating(j, welds):
    """Whether MuJoCo gets this body as a free body: a free joint, or a weld with ``welds=equality``."""
    return j.kind == "free" or (j.kind == "weld" and welds == "equality")


def _frames(scene, welds="tree"):
    """Per body: the scene body frame B in the MuJoCo body frame M, as ``(p_MB, R_MB)``
    with ``x_M = p_MB + R_MB x_B``."""
    out = {}
    for j in scene.joints:
        if _floating(j, welds):
            out[j.child] = (np.zeros(3), np.eye(3))
        else:  # M = the child joint frame Jc
            R_CJ = spatial.quat_to_matrix(j.child_quat)
            out[j.child] = (-R_CJ.T @ np.array(j.child_point), R_CJ.T)
    return out


def mjcf(scene, settings):
    """MJCF text of ``scene`` for ``settings`` (dt, integrator, options)."""
    welds = settings.options.get("welds", "tree")
    frames = _frames(scene, welds)
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
        p_MB, R_MB = frames[j.child]
        body = scene.body(j.child)
        if j.kind == "free":
            pos, quat = np.array(j.q0[:3]), np.array(j.q0[3:])  # placed by qpos anyway
        elif _floating(j, welds):  # a weld held by a constraint, at its initial pose: the weld's reference
            pos, quat = state0[j.child]["p"], spatial.matrix_to_quat(state0[j.child]["R"])
        else:
            # M (= Jc) coincides with the parent joint frame Jp at q = 0.
            # (p, R) of the parent's scene frame in the parent's MuJoCo frame: x_M = p + R x_B.
            p_PM, R_PM = (np.zeros(3), np.eye(3)) if j.parent == WORLD else frames[j.parent]
            R_PJ = spatial.quat_to_matrix(j.parent_quat)
            pos = p_PM + R_PM @ np.array(j.parent_point)
            quat = spatial.matrix_to_quat(R_PM @ R_PJ)
        I_M = R_MB @ body.inertia_matrix @ R_MB.T
        fi = [I_M[0, 0], I_M[1, 1], I_M[2, 2], I_M[0, 1], I_M[0, 2], I_M[1, 2]]
        out = [f'{indent}<body name="{body.name}" pos="{_f(pos)}" quat="{_f(quat)}">',
               f'{indent}  <inertial pos="{_f(p_MB)}" mass="{body.mass!r}" fullinertia="{_f(fi)}"/>']
        if _floating(j, welds):
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
                    site_pos = p_MB + R_MB @ np.array(ld.point)
                    out.append(f'{indent}  <site name="load{k}" pos="{_f(site_pos)}" '
                               f'quat="{_f(spatial.matrix_to_quat(R_MB))}"/>')
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
            X = {}
            for name in (j.parent, j.child):
                s0, (p_MB, R_MB) = state0[name], frames.get(name, (np.zeros(3), np.eye(3)))
                R_WM = s0["R"] @ R_MB.T
                X[name] = (s0["p"] - R_WM @ p_MB, R_WM)
            (p1, R1), (p2, R2) = X[j.parent], X[j.child]
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


class MujocoAdapter(Adapter):
    """MuJoCo (``mujoco`` Python bindings). Options: ``loads`` = ``actuator`` | ``xfrc_applied``;
    ``welds`` = ``tree`` | ``equality``."""

    name = "mujoco"
    effects = EFFECTS
    integrators = {
        "euler": IntegratorSpec(True, OPTIONS, "semi-implicit Euler"),
        "rk4": IntegratorSpec(True, OPTIONS, "classical RK4"),
        "implicit": IntegratorSpec(True, OPTIONS, "implicit in velocity (Coriolis and damping)"),
        "implicitfast": IntegratorSpec(True, OPTIONS, "implicit in velocity, no Coriolis derivatives"),
        "discrete": IntegratorSpec(True, OPTIONS, "MuJoCo 4's discrete integrator"),
    }

    def version(self):
        import mujoco

        return mujoco.__version__

    def check(self, scene, times, settings):
        super().check(scene, times, settings)
        option_choice(settings, "loads", LOAD_PATHS)
        option_choice(settings, "welds", WELDS)

    def variants(self, scene):
        """Default matrix: where the scene has welds, also as equality constraints."""
        return [{}, {"welds": "equality"}] if any(j.kind == "weld" for j in scene.joints) else [{}]

    def describe(self, scene, settings):
        """The generated model, for reports and ``dalembert show-model``."""
        return mjcf(scene, settings)

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        import mujoco

        text = mjcf(scene, settings)
        model = mujoco.MjModel.from_xml_string(text)
        welds = settings.options.get("welds", "tree")
        frames = _frames(scene, welds)
        ids = {b.name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b.name) for b in scene.bodies}
        self._check_mass_properties(model, scene, frames, ids)
        data = mujoco.MjData(model)
        qpos0, qvel0 = np.zeros(model.nq), np.zeros(model.nv)
        state0 = spatial.initial_body_states(scene) if welds == "equality" else {}
        for j in scene.joints:
            if j.kind == "weld" and welds == "tree":
                continue
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j.child)
            a, v = model.jnt_qposadr[jid], model.jnt_dofadr[jid]
            if j.kind == "weld":  # a free body at its initial state: qvel = (v world, w body)
                s0 = state0[j.child]
                qpos0[a:a + 7] = np.concatenate([s0["p"], spatial.matrix_to_quat(s0["R"])])
                qvel0[v:v + 6] = np.concatenate([s0["v"], s0["R"].T @ s0["w"]])
                continue
            qpos0[a:a + len(j.q0)] = j.q0
            qvel0[v:v + len(j.v0)] = j.v0
        steps = steps_per_interval(np.asarray(times, float), settings.dt)
        return dict(scene=scene, times=np.asarray(times, float), settings=settings, model=model, data=data,
                    scratch=mujoco.MjData(model), qpos0=qpos0, qvel0=qvel0, steps=steps, frames=frames, ids=ids,
                    mjcf=text, load_path=settings.options.get("loads", "actuator"), welds=welds)

    @staticmethod
    def _check_mass_properties(model, scene, frames, ids):
        for b in scene.bodies:
            i = ids[b.name]
            p_MB, R_MB = frames[b.name]
            R = spatial.quat_to_matrix(model.body_iquat[i])
            I_M = R @ np.diag(model.body_inertia[i]) @ R.T
            expected = R_MB @ b.inertia_matrix @ R_MB.T
            scale = np.abs(expected).max()
            if (abs(model.body_mass[i] - b.mass) > MASS_PROPERTY_REL_TOL * b.mass
                    or np.abs(I_M - expected).max() > MASS_PROPERTY_REL_TOL * scale
                    or np.abs(model.body_ipos[i] - p_MB).max() > MASS_PROPERTY_REL_TOL * max(1.0, np.abs(p_MB).max())):
                raise RuntimeError(f"MuJoCo compiled body {b.name!r} with mass {model.body_mass[i]}, "
                                   f"COM {model.body_ipos[i]} and inertia {I_M.tolist()}; the scene has "
                                   f"{b.mass}, {p_MB.tolist()}, {expected.tolist()}")

    # ------------------------------------------------------------- run
    def run(self, prepared):
        import mujoco

        p = prepared
        messages = []
        previous = mujoco.get_mju_user_warning()
        mujoco.set_mju_user_warning(messages.append)  # no MUJOCO_LOG.TXT, no printing
        try:
            if p["load_path"] == "actuator":
                Q, V, wall, diverged_at = self._step_rollout(p)
                if diverged_at is not None:  # locate the first bad sample
                    messages.clear()
                    Q, V, wall, diverged_at = self._step_loop(p)
            else:
                Q, V, wall, diverged_at = self._step_loop(p)
        finally:
            mujoco.set_mju_user_warning(previous)
        n_steps = int(p["steps"][:diverged_at].sum()) if diverged_at else int(p["steps"].sum())
        stages = 4 if p["settings"].integrator == "rk4" else 1
        info = {"message": f"MuJoCo: {messages[0]}" if messages else "", "warnings": messages[:5]}
        traj, audit = self._read_back(p, Q, V)
        info["audit"] = audit
        return Outcome(traj, wall, n_steps, n_steps * stages, info)

    @staticmethod
    def _reset(p):
        import mujoco

        model, data = p["model"], p["data"]
        mujoco.mj_resetData(model, data)  # also clears the warning counters
        data.qpos[:], data.qvel[:] = p["qpos0"], p["qvel0"]
        if p["load_path"] == "actuator":
            data.ctrl[:] = 1.0
        n = len(p["times"])
        Q, V = np.full((n, model.nq), np.nan), np.full((n, model.nv), np.nan)
        Q[0], V[0] = data.qpos, data.qvel
        return model, data, Q, V

    @staticmethod
    def _diverged(data):
        import mujoco

        return any(data.warning[w].number for w in (mujoco.mjtWarning.mjWARN_BADQACC,
                                                     mujoco.mjtWarning.mjWARN_BADQVEL,
                                                     mujoco.mjtWarning.mjWARN_BADQPOS))

    def _step_rollout(self, p):
        """Native stepping: rollout in chunks, subsampled. Returns (Q, V, wall, diverged sample or None)."""
        import mujoco
        from mujoco import rollout

        model, data, Q, V = self._reset(p)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        state = np.empty(mujoco.mj_stateSize(model, spec))
        mujoco.mj_getState(model, data, state, spec)
        control = np.ones((1, 1, model.nu)) if model.nu else None
        cum = np.concatenate([[0], np.cumsum(p["steps"])])
        start = time.perf_counter()
        k0 = 0
        while k0 < len(p["steps"]):
            k1 = k0 + 1
            while k1 < len(p["steps"]) and cum[k1 + 1] - cum[k0] <= ROLLOUT_CHUNK_STEPS:
                k1 += 1
            nstep = int(cum[k1] - cum[k0])
            states, _ = rollout.rollout(model, data, state[None], control, nstep=nstep)
            if self._diverged(data):
                return Q, V, time.perf_counter() - start, k1
            rows = states[0, cum[k0 + 1:k1 + 1] - cum[k0] - 1]
            Q[k0 + 1:k1 + 1] = rows[:, 1:1 + model.nq]  # FULLPHYSICS: time, qpos, qvel, ...
            V[k0 + 1:k1 + 1] = rows[:, 1 + model.nq:1 + model.nq + model.nv]
            state = states[0, -1]
            k0 = k1
        return Q, V, time.perf_counter() - start, None

    def _step_loop(self, p):
        """``mj_step(nstep)`` per sample interval (or per step with xfrc_applied), checking divergence."""
        import mujoco

        model, data, Q, V = self._reset(p)
        start = time.perf_counter()
        for k, nstep in enumerate(p["steps"], 1):
            if p["load_path"] == "actuator":
                mujoco.mj_step(model, data, nstep=int(nstep))
            else:
                for _ in range(nstep):
                    self._apply_xfrc(p, data)
                    mujoco.mj_step(model, data)
            if self._diverged(data):
                return Q, V, time.perf_counter() - start, k
            Q[k], V[k] = data.qpos, data.qvel
        return Q, V, time.perf_counter() - start, None

    @staticmethod
    def _apply_xfrc(p, data):
        """The lagging path: loads as xfrc_applied (at the COM, world axes) from the current pose."""
        scene, model = p["scene"], p["model"]
        data.xfrc_applied[:] = 0.0
        import mujoco

        mujoco.mj_kinematics(model, data)
        for ld in scene.loads:
            i = p["ids"][ld.body]
            p_MB, R_MB = p["frames"][ld.body]
            R_WB = data.xmat[i].reshape(3, 3) @ R_MB
            vec = R_WB @ np.array(ld.vector) if ld.frame == "body" else np.array(ld.vector)
            if ld.kind == "force":
                r = R_WB @ np.array(ld.point)  # from the COM (= xipos) to the point
                data.xfrc_applied[i, :3] += vec
                data.xfrc_applied[i, 3:] += np.cross(r, vec)
            else:
                data.xfrc_applied[i, 3:] += vec

    def _read_back(self, p, Q, V):
        import mujoco

        from dalembert.trajectory import BodyStates, JointStates, Trajectory

        model, d, scene = p["model"], p["scratch"], p["scene"]
        n, nb = len(p["times"]), len(scene.bodies)
        pos, quat = np.full((nb, n, 3), np.nan), np.full((nb, n, 4), np.nan)
        vel, omega = np.full((nb, n, 3), np.nan), np.full((nb, n, 3), np.nan)
        # a weld held by an equality constraint has no joint force to read (cfrc_int is zero)
        reactions = {j.child: np.full((n, 3), np.nan) for j in scene.joints if not _floating(j, p["welds"])}
        max_ncon = max_nefc = 0
        max_passive = 0.0
        res = np.zeros(6)
        if p["load_path"] == "actuator":
            d.ctrl[:] = 1.0
        subtree = {b.name: self._subtree(scene, b.name, p["welds"]) for b in scene.bodies}
        for k in range(n):
            if not np.all(np.isfinite(Q[k])):
                continue
            d.qpos[:], d.qvel[:] = Q[k], V[k]
            if p["load_path"] == "xfrc_applied":
                self._apply_xfrc(p, d)
            mujoco.mj_forward(model, d)
            mujoco.mj_rnePostConstraint(model, d)
            max_ncon, max_nefc = max(max_ncon, d.ncon), max(max_nefc, d.nefc)
            max_passive = max(max_passive, float(np.abs(d.qfrc_passive).max(initial=0.0)))
            R_WB_all = {}
            for bi, b in enumerate(scene.bodies):
                i = p["ids"][b.name]
                p_MB, R_MB = p["frames"][b.name]
                R_WM = d.xmat[i].reshape(3, 3)
                R_WB = R_WM @ R_MB  # W <- M <- B
                R_WB_all[b.name] = R_WB
                r = R_WM @ p_MB
                # XBODY: velocity at the body frame origin (mjOBJ_BODY would be at the COM), world axes
                mujoco.mj_objectVelocity(model, d, mujoco.mjtObj.mjOBJ_XBODY, i, res, 0)
                pos[bi, k] = d.xpos[i] + r
                quat[bi, k] = spatial.matrix_to_quat(R_WB)
                omega[bi, k] = res[:3]
                vel[bi, k] = res[3:] + np.cross(res[:3], r)
            for child in reactions:
                f = d.cfrc_int[p["ids"][child], 3:].copy()
                if p["load_path"] == "actuator":  # loads MuJoCo routed through joint space
                    for ld in scene.loads:
                        if ld.kind == "force" and ld.body in subtree[child]:
                            f -= R_WB_all[ld.body] @ np.array(ld.vector) if ld.frame == "body" else np.array(ld.vector)
                reactions[child][k] = f
        # Free bodies: the attitude is MuJoCo's own quaternion as integrated (its norm is data).
        for bi, b in enumerate(scene.bodies):
            j = scene.joint(b.name)
            if _floating(j, p["welds"]):
                jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, b.name)
                a = model.jnt_qposadr[jid]
                quat[bi] = Q[:, a + 3:a + 7]
        bodies = {b.name: BodyStates(pos[bi], quat[bi], vel[bi], omega[bi]) for bi, b in enumerate(scene.bodies)}
        joints = {}
        for j in scene.joints:
            if j.kind == "weld":
                continue
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j.child)
            a, v = model.jnt_qposadr[jid], model.jnt_dofadr[jid]
            joints[j.child] = JointStates(Q[:, a:a + len(j.q0)], V[:, v:v + len(j.v0)])
        extras = {f"reaction_force:{c}": f for c, f in reactions.items()}
        audit = {"max_contacts": int(max_ncon), "max_constraint_rows": int(max_nefc),
                 "max_abs_passive_force": max_passive}
        return Trajectory(p["times"], bodies, joints, extras), audit

    @staticmethod
    def _subtree(scene, name, welds="tree"):
        """``name`` and the bodies below it in MuJoCo's tree (a weld held by a constraint is not)."""
        out, frontier = {name}, [name]
        while frontier:
            parent = frontier.pop()
            for j in scene.joints:
                if j.parent == parent and j.child not in out and not _floating(j, welds):
                    out.add(j.child)
                    frontier.append(j.child)
        return out

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        import mujoco

        model = prepared["model"]
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
            "load_path": prepared["load_path"],
            "actuators": [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, i) for i in range(model.nu)],
            "max_armature": float(np.abs(model.dof_armature).max(initial=0.0)),
            "max_damping": float(np.abs(model.dof_damping).max(initial=0.0)),
            "ngeom": int(model.ngeom),
            **outcome.info.get("audit", {}),
        }
