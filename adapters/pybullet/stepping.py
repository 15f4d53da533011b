"""PyBullet's stepping: ``stepSimulation`` step by step, the loads applied before each, the state copied
out at every sample.

PyBullet clears applied forces after every ``stepSimulation``, so the loads (``apply_loads``) are applied
before each step, from the state the step starts at — the explicit evaluation its semi-implicit Euler
makes of every other force. A follower load goes in PyBullet's link frame (``LINK_FRAME``: the inertial
frame E, turned by the engine with the body), a world torque in world axes; a world force is applied at
its point's world position, read from the engine's pose of the body at the step's start (a link's
kinematics refreshed first: ``apply_loads``).

A blow-up is data: the first sample with a non-finite coordinate ends the run, NaN from there on.

``p`` is the ``PybulletPrepared`` that ``PybulletAdapter.prepare`` returns.
"""

from __future__ import annotations

import time

import numpy as np

from dalembert import spatial
from dalembert.adapters.pybullet.model import engine, rebuild

__all__ = ["simulate", "apply_loads", "load_plan", "read_state", "state_size"]


def load_plan(model, scene):
    """The loads as PyBullet takes them: a list of ``(kind, frame, mb, link, vector_E or W (3,), point_E (3,))``,
    a follower load's vector and every point turned into E axes once (``R_EB``)."""
    plan = []
    for ld in scene.loads:
        part = model.parts[ld.body]
        vec = np.asarray(ld.vector, dtype=float)
        point_E = part.R_EB @ np.asarray(ld.point, dtype=float)
        if ld.frame == "body":
            vec = part.R_EB @ vec
        plan.append((ld.kind, ld.frame, part.mb, part.link, [float(v) for v in vec], point_E))
    return plan


def apply_loads(pb, c, plan):
    """Apply every load of ``plan`` (``load_plan``) for the next step of client ``c``, from the state it holds.

    A link's pose in PyBullet's cache is the one before the last step's position update (measured: a follower
    force in ``LINK_FRAME`` turned with it makes the pivoted rod's rate, exact for semi-implicit Euler under a
    constant torque, 1.4e-4 rad/s off at dt = 1e-3 and 1.4e-6 at 1e-4: a force one step stale), so a load on a
    link that turns with it or acts at a point first refreshes the multibody's kinematics
    (``getLinkState(computeForwardKinematics=1)``); a base's pose is its state itself."""
    for kind, frame, mb, link, vec, point_E in plan:
        if kind == "torque" and frame == "world":
            pb.applyExternalTorque(mb, link, vec, pb.WORLD_FRAME, physicsClientId=c)
            continue
        if link >= 0:
            com, orn = pb.getLinkState(mb, link, computeForwardKinematics=1, physicsClientId=c)[:2]
        else:
            com, orn = pb.getBasePositionAndOrientation(mb, physicsClientId=c)
        if kind == "torque":
            pb.applyExternalTorque(mb, link, vec, pb.LINK_FRAME, physicsClientId=c)
        elif frame == "body":
            pb.applyExternalForce(mb, link, vec, list(point_E), pb.LINK_FRAME, physicsClientId=c)
        else:  # world axes: at the point's world position, from the engine's pose of E
            R_WE = spatial.quat_to_matrix(spatial.xyzw_to_wxyz(np.asarray(orn, dtype=float)))
            pb.applyExternalForce(mb, link, vec, list(np.asarray(com) + R_WE @ point_E), pb.WORLD_FRAME,
                                  physicsClientId=c)


def state_size(model):
    """The length of one sampled state row (``read_state``)."""
    # 13 per floating base; 7 per link: up to 4 positions and 3 rates a joint, padded
    return 13 * len(model.floating) + 7 * sum(len(links) for links in model.links.values())


def read_state(pb, model, out):
    """Copy the client's state into ``out`` (``state_size``,): per floating base ``(x y z, qx qy qz qw, v_W,
    w_W)``; per link, its joint's positions padded to 4 and rates padded to 3 (PyBullet's multi-dof layout:
    a spherical joint's ``(x, y, z, w)`` and rate in E axes)."""
    return pack(model, snapshot(pb, model), out)


def snapshot(pb, model):
    """The client's state as PyBullet's calls return it (a list of their tuples), unpacked by ``pack``: the
    cheapest copy a sample can take (its unpacking waits until the stepping's clock has stopped)."""
    c = model.client
    out = []
    for mb in model.floating:
        out.append(pb.getBasePositionAndOrientation(mb, physicsClientId=c))
        out.append(pb.getBaseVelocity(mb, physicsClientId=c))
    for mb, links in model.link_lists:
        out.append(pb.getJointStatesMultiDof(mb, links, physicsClientId=c))
    return out


def pack(model, snap, out):
    """A ``snapshot`` as a row of ``read_state``'s layout, written into ``out``; returns ``out``."""
    k, i = 0, 0
    for _ in model.floating:
        (pos, orn), (lin, ang) = snap[i], snap[i + 1]
        out[k:k + 13] = (*pos, *orn, *lin, *ang)
        k, i = k + 13, i + 2
    for _ in model.link_lists:
        for q, v, *_ in snap[i]:
            out[k:k + 7] = 0.0
            out[k:k + len(q)] = q
            out[k + 4:k + 4 + len(v)] = v
            k += 7
        i += 1
    return out


def write_state(pb, model, row):
    """Set the client's state from a row of ``read_state`` (the read-back's scratch client)."""
    c, k = model.client, 0
    for mb in model.floating:
        pb.resetBasePositionAndOrientation(mb, list(row[k:k + 3]), list(row[k + 3:k + 7]), physicsClientId=c)
        pb.resetBaseVelocity(mb, list(row[k + 7:k + 10]), list(row[k + 10:k + 13]), physicsClientId=c)
        k += 13
    kinds = {(part.mb, part.link): part.kind for part in model.parts.values()}
    for mb, links in model.links.items():
        for link in links:
            kind = kinds[(mb, link)]
            if kind == "ball":
                pb.resetJointStateMultiDof(mb, link, list(row[k:k + 4]), list(row[k + 4:k + 7]), physicsClientId=c)
            elif kind != "weld":
                pb.resetJointState(mb, link, float(row[k]), float(row[k + 4]), physicsClientId=c)
            k += 7


def simulate(p):
    """Run ``p`` from its initial state: ``(X (n, state_size), wall s, sample where it diverged or None)``.

    Each sample's state is copied out as PyBullet returns it (``snapshot``) and unpacked after the clock
    stops; a blow-up is found there too (PyBullet steps on through NaN without complaint), NaN from the first
    sample with a non-finite coordinate on."""
    pb = engine()
    model, c = p.model, p.model.client
    if p.scene.contacts:  # Bullet's contact state outlives a reset of the bodies' states (model.rebuild)
        rebuild(model, p.scene, p.settings)
    else:
        model.state0(p.scene)
    X = np.full((len(p.times), state_size(model)), np.nan)
    read_state(pb, model, X[0])
    step, plan, shot = pb.stepSimulation, p.loads, snapshot
    snaps = []
    start = time.perf_counter()
    for nstep in p.steps:
        if plan:
            for _ in range(nstep):
                apply_loads(pb, c, plan)
                step(physicsClientId=c)
        else:
            for _ in range(nstep):
                step(physicsClientId=c)
        snaps.append(shot(pb, model))
    wall = time.perf_counter() - start
    for k, snap in enumerate(snaps, 1):
        pack(model, snap, X[k])
    bad = ~np.all(np.isfinite(X), axis=1)
    if bad.any():
        first = int(np.argmax(bad))
        X[first:] = np.nan
        return X, wall, first
    return X, wall, None
