"""MuJoCo's part of a standalone reproduction (``dalembert repro``): the generated MJCF, the initial state
and the stepping loop in MuJoCo's own API, reading the run's headline quantity from ``qpos``.

What it writes is ``Adapter.repro``'s contract (``dalembert.adapters.base``). The stepping is the
adapter's ``step_loop``: ``mj_step(nstep)`` per sample interval, which gives the same numbers as
``mujoco.rollout`` (``stepping``'s docstring: measured identical), with the actuators that carry the
scene's loads at full control. The quantities come straight from ``qpos`` as the read-back takes
them: a hinge's or slide's coordinate, and a free joint's quaternion (w first, as integrated).

A body that is not free has its attitude from MuJoCo's ``xmat`` at the sampled state, turned into the
scene's body frame (``R_WB = R_WE R_EB``) as the read-back turns it, with the same numpy operations on arrays
of the same shapes. Not covered, with the reason in the error: loads applied as ``xfrc_applied`` (the
lagging path recomputes them from the pose before every step, in the adapter's Python).
"""

from __future__ import annotations

import numpy as np

from dalembert.adapters.mujoco.mjcf import floating

__all__ = ["repro"]


def repro(adapter, scene, times, settings, quantity):
    """The MuJoCo part of a reproduction of a run of ``scene`` sampled at ``times`` with ``settings``: Python
    source defining ``simulate()`` (``Adapter.repro``); ValueError "where: what — fix" where it does not apply."""
    p = adapter.prepare(scene, times, settings)
    attitudes = ""
    if p.load_path != "actuator":
        raise ValueError("options.loads: xfrc_applied recomputes the loads from the pose before every step in "
                         "the adapter's Python — no repro for it; reproduce a run with loads=actuator")
    if quantity == "joint":
        names = [j.child for j in scene.joints if j.kind in ("revolute", "prismatic")]
        read = "{name: Q[:, model.jnt_qposadr[joint_id(name)]][:, None] for name in NAMES}"
        what = "each hinge's or slide's qpos (rad or m), by joint name"
    elif quantity == "orientation":
        names = [b.name for b in scene.bodies]
        free = [b.name for b in scene.bodies if floating(scene.joint(b.name), p.welds)]
        frames = np.array([p.frames[name][1] for name in names])
        read = "attitudes(Q)"
        what = ("each body's attitude: a free body's quaternion q_WB from qpos (w, x, y, z; world; as integrated, "
                "not normalized), any other's R_WB = R_WE R_EB from MuJoCo's xmat at the sampled state")
        attitudes = f"""

# Each body's scene frame B in MuJoCo's body frame E, R_EB (``mjcf.engine_frames``: B itself for a free body),
# in NAMES' order; the free bodies, whose attitude is their free joint's quaternion as integrated.
R_EB = np.array({frames.tolist()!r})
FREE = {free!r}


def attitudes(Q):
    \"\"\"Each body's attitude at the sampled states Q (n, nq): R_WB (n, 3, 3), or a free body's quaternion (n, 4).\"\"\"
    model = mujoco.MjModel.from_xml_string(MJCF)
    scratch = mujoco.MjData(model)
    ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name) for name in NAMES]
    xmat = np.full((len(Q), model.nbody, 9), np.nan)
    for k in np.flatnonzero(np.all(np.isfinite(Q), axis=1)):
        scratch.qpos[:] = Q[k]
        mujoco.mj_kinematics(model, scratch)  # the poses of this state (after mj_step, xmat is the previous one's)
        xmat[k] = scratch.xmat
    R_WB = xmat[:, ids].reshape(len(Q), len(NAMES), 3, 3) @ R_EB  # W <- E <- B
    out = {{name: R_WB[:, i] for i, name in enumerate(NAMES)}}
    for name in FREE:
        a = model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)]
        out[name] = Q[:, a + 3:a + 7]
    return out"""
    else:
        raise ValueError(f"quantity: no MuJoCo repro of {quantity!r} — it reproduces 'joint' and 'orientation'")
    steps = np.asarray(p.steps, dtype=int)
    steps_src = (f"np.full({len(steps)}, {int(steps[0])})" if np.all(steps == steps[0])
                 else f"np.array({steps.tolist()!r})")
    return f'''import mujoco

# The model: the MJCF the adapter generated (the timestep, integrator and options are in <option>).
MJCF = """{p.mjcf.rstrip()}
"""
# The initial state in MuJoCo's coordinates (a free joint: position, quaternion w first; velocity: linear
# in world axes, angular in body axes).
QPOS0 = np.array({p.qpos0.tolist()!r})
QVEL0 = np.array({p.qvel0.tolist()!r})
# Steps of the model's timestep between consecutive samples.
STEPS = {steps_src}
# Read for each of these: {what}.
NAMES = {names!r}


def simulate():
    """The run: ``mj_step(nstep)`` from sample to sample; ``{{name: ndarray (n, k)}}`` of the quantity at every sample."""
    model = mujoco.MjModel.from_xml_string(MJCF)
    data = mujoco.MjData(model)
    mujoco.mj_resetData(model, data)
    data.qpos[:], data.qvel[:] = QPOS0, QVEL0
    if model.nu:  # the scene's loads, carried by actuators at full control
        data.ctrl[:] = 1.0
    Q = np.full((len(STEPS) + 1, model.nq), np.nan)
    Q[0] = data.qpos
    for k, nstep in enumerate(STEPS, 1):
        mujoco.mj_step(model, data, nstep=int(nstep))
        Q[k] = data.qpos

    def joint_id(name):
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)

    return {read}{attitudes}


ENGINE_VERSION = mujoco.__version__
'''
