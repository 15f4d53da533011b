"""MuJoCo's part of a standalone reproduction (``dalembert repro``): the generated MJCF, the initial state
and the stepping loop in MuJoCo's own API, reading the run's headline quantity from ``qpos``.

What it writes is ``Adapter.repro``'s contract (``dalembert.adapters.base``). The stepping is the
adapter's ``step_loop``: ``mj_step(nstep)`` per sample interval, which gives the same numbers as
``mujoco.rollout`` (``stepping``'s docstring: measured identical), with the actuators that carry the
scene's loads at full control. The quantities come straight from ``qpos`` as the read-back takes
them: a hinge's or slide's coordinate, and a free joint's quaternion (w first, as integrated).

Not covered, with the reason in the error: loads applied as ``xfrc_applied`` (the lagging path
recomputes them from the pose before every step, in the adapter's Python), and orientations of bodies
that are not free (their attitude is MuJoCo's frame turned into the scene's body frame, not ``qpos``).
"""

from __future__ import annotations

import numpy as np

from dalembert.adapters.mujoco.mjcf import floating

__all__ = ["repro"]


def repro(adapter, scene, times, settings, quantity):
    """The MuJoCo part of a reproduction of a run of ``scene`` sampled at ``times`` with ``settings``: Python
    source defining ``simulate()`` (``Adapter.repro``); ValueError "where: what — fix" where it does not apply."""
    p = adapter.prepare(scene, times, settings)
    if p.load_path != "actuator":
        raise ValueError("options.loads: xfrc_applied recomputes the loads from the pose before every step in "
                         "the adapter's Python — no repro for it; reproduce a run with loads=actuator")
    if quantity == "joint":
        names = [j.child for j in scene.joints if j.kind in ("revolute", "prismatic")]
        read = "{name: Q[:, model.jnt_qposadr[joint_id(name)]][:, None] for name in NAMES}"
        what = "each hinge's or slide's qpos (rad or m), by joint name"
    elif quantity == "orientation":
        stuck = [j.child for j in scene.joints if not floating(j, p.welds)]
        if stuck:
            raise ValueError(f"quantity: the orientation of {', '.join(stuck)} (not free bodies) is MuJoCo's body frame "
                             "turned into the scene's, not qpos — no repro for it; reproduce a run whose headline is "
                             "a joint angle, or of free bodies only")
        names = [b.name for b in scene.bodies]
        read = "{name: Q[:, model.jnt_qposadr[joint_id(name)] + 3:model.jnt_qposadr[joint_id(name)] + 7] for name in NAMES}"
        what = "each free joint's quaternion q_WB from qpos (w, x, y, z; world; as integrated, not normalized)"
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

    return {read}


ENGINE_VERSION = mujoco.__version__
'''
