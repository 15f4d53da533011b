"""Errors of a trajectory against a truth trajectory at the same sample times."""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.lstsq import lstsq_stacked

__all__ = ["error_series", "trajectory_errors", "QUANTITIES"]

# quantity -> unit
QUANTITIES = {
    "position": "m",
    "orientation": "rad",
    "velocity": "m/s",
    "angular_velocity": "rad/s",
    "joint": "rad",
    "reaction_force": "relative",
}


def error_series(traj, truth):
    """Per quantity in ``QUANTITIES``, the error at each sample, shape (n,) (max over bodies/joints).

    Orientation is the geodesic angle; vectors by Euclidean norm; joint
    coordinates by max-abs over the joint's ``q`` (revolute angles); reaction
    forces relative to the largest true reaction, modulo the truth's self-stresses.
    """
    if traj.t.shape != truth.t.shape or np.any(np.abs(traj.t - truth.t) > 1e-12 * max(1.0, truth.t[-1])):
        raise ValueError("trajectory and truth must share sample times")
    n = len(truth.t)
    out = {}
    for name, tb in truth.bodies.items():
        b = traj.bodies[name]
        for q, e in (("position", np.linalg.norm(b.position - tb.position, axis=1)),
                     ("orientation", spatial.rotation_angle(b.quaternion, tb.quaternion)),
                     ("velocity", np.linalg.norm(b.velocity - tb.velocity, axis=1)),
                     ("angular_velocity", np.linalg.norm(b.angular_velocity - tb.angular_velocity, axis=1))):
            out[q] = np.maximum(out.get(q, np.zeros(n)), e)
    for name, tj in truth.joints.items():
        if name in traj.joints and tj.q.shape[1] == 1:
            out["joint"] = np.maximum(out.get("joint", np.zeros(n)), np.abs(traj.joints[name].q - tj.q).max(axis=1))
    reactions = _reaction_errors(traj, truth)
    if reactions is not None:
        out["reaction_force"] = reactions
    return out


def _reaction_errors(traj, truth):
    """Per sample, the largest reaction error (n,) relative to the largest true reaction of any joint,
    modulo the truth's self-stresses (``reaction_mode:<k>:<joint>`` extras, ``reference.loops``):
    loads a rigid model leaves undetermined, removed from the errors by least squares in the
    relative units the errors are measured in. None when neither side has reactions."""
    names = [k.split(":", 1)[1] for k in truth.extras if k.startswith("reaction_force:") and k in traj.extras]
    if not names:
        return None
    tf = np.stack([truth.extras[f"reaction_force:{j}"] for j in names], axis=1)  # (n, J, 3)
    # One scale for every joint, the largest true reaction anywhere: a joint that carries ~nothing (the
    # flyball governor's slider, by symmetry: 4e-15 N) would make its own roundoff a relative error of 1.
    scale = float(np.max(np.linalg.norm(tf, axis=2), initial=0.0)) or 1.0
    E = (np.stack([traj.extras[f"reaction_force:{j}"] for j in names], axis=1) - tf) / scale
    modes = sorted({int(k.split(":")[1]) for k in truth.extras if k.startswith("reaction_mode:")})
    if modes:
        A = np.stack([np.stack([truth.extras.get(f"reaction_mode:{k}:{j}", np.zeros_like(tf[:, 0])) for j in names],
                               axis=1) / scale for k in modes], axis=1)  # (n, K, J, 3)
        rows = np.flatnonzero(np.all(np.isfinite(A), axis=(1, 2, 3)) & np.all(np.isfinite(E), axis=(1, 2)))
        basis = A[rows].reshape(len(rows), len(modes), 3 * len(names)).swapaxes(1, 2)  # (m, 3J, K)
        coef = lstsq_stacked(basis, E[rows].reshape(len(rows), 3 * len(names)))  # (m, K)
        E[rows] -= np.einsum("mik,mk->mi", basis, coef).reshape(E[rows].shape)
    return np.max(np.linalg.norm(E, axis=2), axis=1)


def trajectory_errors(traj, truth):
    """``{quantity: (max over time, at the final time)}``; NaN when the run is not finite."""
    return {q: (float(np.max(e)) if np.all(np.isfinite(e)) else float("nan"), float(e[-1]))
            for q, e in error_series(traj, truth).items()}
