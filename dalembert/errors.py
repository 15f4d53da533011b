"""Errors of a trajectory against a truth trajectory at the same sample times."""

from __future__ import annotations

import numpy as np

from dalembert import spatial

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
    forces relative to the largest true reaction.
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
    for key, tf in truth.extras.items():
        if key.startswith("reaction_force:") and key in traj.extras:
            scale = float(np.max(np.linalg.norm(tf, axis=1))) or 1.0
            e = np.linalg.norm(traj.extras[key] - tf, axis=1) / scale
            out["reaction_force"] = np.maximum(out.get("reaction_force", np.zeros(n)), e)
    return out


def trajectory_errors(traj, truth):
    """``{quantity: (max over time, at the final time)}``; NaN when the run is not finite."""
    return {q: (float(np.max(e)) if np.all(np.isfinite(e)) else float("nan"), float(e[-1]))
            for q, e in error_series(traj, truth).items()}
