"""MuJoCo's stepping: ``mujoco.rollout`` (native loop) in chunks, and where it diverges.

``step_rollout`` runs ``mujoco.rollout`` in chunks of at most
``ROLLOUT_CHUNK_STEPS`` steps, subsampled at the sample times. Measured on the
free top (20000 RK4 steps): rollout 0.146 s, ``mj_step(nstep=10)`` per sample
0.147 s, a Python loop of ``mj_step`` 0.153 s — identical numbers; per sample
interval the ``mj_step(nstep)`` path adds ~4.5 us of Python (a ratio of up to
1.3 against a bare rollout on the cheap integrators), so rollout is the default.
MuJoCo with auto-reset disabled does not produce NaN on a bad acceleration — it
raises a warning counter (which rollout records in the ``MjData`` it is given)
and freezes the state. When a chunk ends with a warning, the run is repeated
with ``step_loop`` (``mj_step(nstep)`` per sample interval) to find the first
bad sample; the adapter reports NaN from there on with MuJoCo's message.

``prepared`` (``p``) is the ``MujocoPrepared`` that ``MujocoAdapter.prepare`` returns.
"""

from __future__ import annotations

import time

import numpy as np

from dalembert import spatial

__all__ = ["step_rollout", "step_loop", "apply_xfrc", "ROLLOUT_CHUNK_STEPS"]

# Longest rollout call: its state output (steps x nstate doubles) stays ~10 MB
# for the small models here, whatever the horizon.
ROLLOUT_CHUNK_STEPS = 50_000


def reset(p):
    """Initial state in ``p.data`` (warning counters cleared); sample arrays ``Q (n, nq)``,
    ``V (n, nv)`` NaN but for row 0. Returns ``(model, data, Q, V)``."""
    import mujoco

    model, data = p.model, p.data
    mujoco.mj_resetData(model, data)  # also clears the warning counters
    data.qpos[:], data.qvel[:] = p.qpos0, p.qvel0
    if p.load_path == "actuator":
        data.ctrl[:] = 1.0
    n = len(p.times)
    Q, V = np.full((n, model.nq), np.nan), np.full((n, model.nv), np.nan)
    Q[0], V[0] = data.qpos, data.qvel
    return model, data, Q, V


def diverged(data):
    """Whether MuJoCo raised a bad-acceleration, -velocity or -position warning."""
    import mujoco

    return any(data.warning[w].number for w in (mujoco.mjtWarning.mjWARN_BADQACC,
                                                 mujoco.mjtWarning.mjWARN_BADQVEL,
                                                 mujoco.mjtWarning.mjWARN_BADQPOS))


def step_rollout(p):
    """Native stepping: rollout in chunks, subsampled. Returns (Q, V, wall, diverged sample or None)."""
    import mujoco
    from mujoco import rollout

    model, data, Q, V = reset(p)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    control = np.ones((1, 1, model.nu)) if model.nu else None
    cum = np.concatenate([[0], np.cumsum(p.steps)])
    start = time.perf_counter()
    k0 = 0
    while k0 < len(p.steps):
        k1 = k0 + 1
        while k1 < len(p.steps) and cum[k1 + 1] - cum[k0] <= ROLLOUT_CHUNK_STEPS:
            k1 += 1
        nstep = int(cum[k1] - cum[k0])
        states, _ = rollout.rollout(model, data, state[None], control, nstep=nstep)
        if diverged(data):
            return Q, V, time.perf_counter() - start, k1
        rows = states[0, cum[k0 + 1:k1 + 1] - cum[k0] - 1]
        Q[k0 + 1:k1 + 1] = rows[:, 1:1 + model.nq]  # FULLPHYSICS: time, qpos, qvel, ...
        V[k0 + 1:k1 + 1] = rows[:, 1 + model.nq:1 + model.nq + model.nv]
        state = states[0, -1]
        k0 = k1
    return Q, V, time.perf_counter() - start, None


def step_loop(p):
    """``mj_step(nstep)`` per sample interval (or per step with xfrc_applied), checking divergence."""
    import mujoco

    model, data, Q, V = reset(p)
    start = time.perf_counter()
    for k, nstep in enumerate(p.steps, 1):
        if p.load_path == "actuator":
            mujoco.mj_step(model, data, nstep=int(nstep))
        else:
            for _ in range(nstep):
                apply_xfrc(p, data)
                mujoco.mj_step(model, data)
        if diverged(data):
            return Q, V, time.perf_counter() - start, k
        Q[k], V[k] = data.qpos, data.qvel
    return Q, V, time.perf_counter() - start, None


def apply_xfrc(p, data):
    """The lagging path: loads as xfrc_applied (at the COM, world axes) from the current pose."""
    import mujoco

    scene, model = p.scene, p.model
    data.xfrc_applied[:] = 0.0
    mujoco.mj_kinematics(model, data)
    for ld in scene.loads:
        i = p.ids[ld.body]
        R_EB = p.frames[ld.body][1]
        R_WB = data.xmat[i].reshape(3, 3) @ R_EB
        vec = spatial.load_to_world(ld, R_WB)
        if ld.kind == "force":
            r = R_WB @ np.array(ld.point)  # from the COM (= xipos) to the point
            data.xfrc_applied[i, :3] += vec
            data.xfrc_applied[i, 3:] += np.cross(r, vec)
        else:
            data.xfrc_applied[i, 3:] += vec
