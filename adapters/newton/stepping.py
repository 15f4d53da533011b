"""Newton's stepping: ``solver.step`` step by step between two states, the loads applied before each, the
bodies' states copied out at every sample.

Loads: Newton takes an external wrench per body in ``State.body_f`` — force at the COM and torque, both in world
axes — cleared by ``State.clear_forces`` and read by every solver's step. A load is applied before each step from
the state the step starts at (the explicit evaluation the solvers make of every other force): a follower load
turned into world axes by the body's attitude then, a force at a point adds its moment about the COM,
``(R_WB r_B) x F_W``. The wrench is computed in numpy on the CPU arrays' host memory (Warp's CPU backend: no copy;
on a CUDA device, on host copies, the wrench assigned back).

A blow-up is data: the first sample with a non-finite coordinate (or a quaternion collapsed to zero) ends the
run, NaN from there on.
"""

from __future__ import annotations

import time

import numpy as np

from dalembert import spatial
from dalembert.adapters.batch import keep_sample
from dalembert.adapters.newton.engine import engine

__all__ = ["load_plan", "fresh_states", "simulate", "simulate_worlds"]


def load_plan(nm, scene):
    """The loads as the stepping applies them: a list of ``(body index, kind, frame, vector (3,), point_B (3,))``."""
    return [(nm.index[ld.body], ld.kind, ld.frame, np.asarray(ld.vector, dtype=float),
             np.asarray(ld.point, dtype=float)) for ld in scene.loads]


def _apply(plan, body_q, body_f):
    """Write every load of ``plan`` into ``body_f`` (nbody, 6) from the attitudes in ``body_q`` (nbody, 7)."""
    body_f[:] = 0.0
    for i, kind, frame, vec, point in plan:
        R = spatial.quat_to_matrix(spatial.xyzw_to_wxyz(body_q[i, 3:].astype(float)))
        v = R @ vec if frame == "body" else vec
        if kind == "torque":
            body_f[i, 3:] += v
        else:
            body_f[i, :3] += v
            body_f[i, 3:] += np.cross(R @ point, v)


def fresh_states(nm):
    """Two Newton states, the first at the initial state (body and joint coordinates), the second scratch."""
    a, b = nm.model.state(), nm.model.state()
    a.body_q.assign(nm.body_q0)
    a.body_qd.assign(nm.body_qd0)
    a.joint_q.assign(nm.joint_q0)
    a.joint_qd.assign(nm.joint_qd0)
    return a, b


def simulate(p):
    """Run the prepared ``p`` (``NewtonPrepared``) from its initial state: ``(Q (n, nbody, 7), V (n, nbody, 6),
    wall s, sample where it diverged or None)``, float32 as Newton holds them, NaN from the first non-finite
    sample on. The wall time is the stepping and the per-sample copies (host memory on the CPU backend), on the
    model's device."""
    Q, V, wall, bad = simulate_worlds([p])
    return Q[:, 0], V[:, 0], wall, int(bad[0]) or None


def simulate_worlds(ps):
    """Run the worlds ``ps`` (one ``NewtonPrepared`` per world of one model, in world order: every world of it) at
    once from their initial states: ``(Q (n, worlds, nbody, 7), V (n, worlds, nbody, 6), wall s, bad (worlds,) int)``
    with each world's bodies in its own order (``NewtonModel.local``), float32 as Newton holds them; ``bad[k]`` the
    first sample where world k had a non-finite coordinate (0: none), its rows NaN from there on while the others go
    on (Newton's worlds share no data); the stepping ends when every world has diverged. The wall time as
    ``simulate``'s, for all the worlds."""
    wp, _, _ = engine()
    p = ps[0]
    nm, solver, dt = p.model, p.solver, float(p.settings.dt)
    worlds = len(ps)
    if nm.worlds != worlds:
        raise ValueError(f"simulate_worlds: {worlds} worlds given of a model of {nm.worlds} — pass every world")
    control = nm.model.control()
    s0, s1 = fresh_states(nm)
    nb = nm.model.body_count // worlds
    Q = np.full((len(p.times), worlds, nb, 7), np.nan, np.float32)
    V = np.full((len(p.times), worlds, nb, 6), np.nan, np.float32)
    Q[0], V[0] = nm.body_q0.reshape(worlds, nb, 7), nm.body_qd0.reshape(worlds, nb, 6)
    plan, step = [load for w in ps for load in w.loads], solver.step
    bad = np.zeros(worlds, dtype=int)
    device = nm.model.device
    with wp.ScopedDevice(device):
        start = time.perf_counter()
        for k, nstep in enumerate(p.steps, 1):
            for _ in range(int(nstep)):
                s0.clear_forces()
                if plan and device.is_cpu:
                    _apply(plan, s0.body_q.numpy(), s0.body_f.numpy())  # in place: host memory
                elif plan:
                    f = np.zeros((s0.body_f.shape[0], 6), np.float32)  # (nbody, 6): force, torque
                    _apply(plan, s0.body_q.numpy(), f)
                    s0.body_f.assign(f)
                step(s0, s1, control, None, dt)
                s0, s1 = s1, s0
            q, v = s0.body_q.numpy().reshape(worlds, nb, 7), s0.body_qd.numpy().reshape(worlds, nb, 6)
            finite = np.isfinite(q).all(axis=(1, 2)) & np.isfinite(v).all(axis=(1, 2))
            # a quaternion that collapsed to zero (Featherstone's at 1e26 rad/s, the step before NaN) is no attitude
            finite &= (np.abs(q[..., 3:]).max(axis=2) > 0.0).all(axis=1)
            if not keep_sample(Q, V, bad, k, q, v, finite):
                break
        wall = time.perf_counter() - start
    return Q, V, wall, bad
