"""A rigid body turning about a fixed point (a ball joint at the world origin) under gravity:
the scene, its truth from a closed-form attitude, and its invariants (shared by the tops)."""

from __future__ import annotations

import numpy as np

from dalembert import invariants, spatial
from dalembert.case import Invariant
from dalembert.scene import Joint, Scene
from dalembert.trajectory import BodyStates, JointStates, Trajectory

PIVOT = (0.0, 0.0, 0.0)  # the fixed point, world (m)


def pivoted_scene(name, body, c_B, R0_WB, w0_B, gravity):
    """``body`` on a ball joint at the world origin, its centre of mass at ``c_B`` (m, body axes) from
    the pivot; at t = 0 its attitude is ``R0_WB`` and its angular velocity ``w0_B`` (rad/s, body axes).

    The joint frames are the world's and the body's own axes (at the pivot), so the ball joint's
    coordinates are the body's attitude ``q_WB`` and its angular velocity in the body frame.
    """
    return Scene(name, bodies=[body],
                 joints=[Joint("ball", "world", body.name, q0=spatial.matrix_to_quat(np.asarray(R0_WB, float)),
                               v0=list(w0_B), child_point=[-x for x in c_B])],
                 gravity=gravity)


def pivoted_truth(body, c_B, gravity, t, R_WB, w_B):
    """The ``Trajectory`` of a body on a fixed pivot at times ``t`` (s, (n,)) from its attitude ``R_WB``
    (n, 3, 3) and body angular velocity ``w_B`` (n, 3, rad/s): COM state, ball joint coordinates and the
    pivot reaction (the force ON the body, world, N) by Newton's law, ``m a_com - m g``, with the
    angular acceleration from Euler's equation about the pivot (exact for the given state)."""
    c = np.asarray(c_B, dtype=float)
    g = np.asarray(gravity, dtype=float)
    I_O = inertia_about_pivot(body, c)
    torque_B = np.cross(c, body.mass * np.einsum("nji,j->ni", R_WB, g))  # c x (R^T m g)
    alpha_B = np.linalg.solve(I_O, (torque_B - np.cross(w_B, w_B @ I_O.T)).T).T
    r_W = R_WB @ c
    w_W = np.einsum("nij,nj->ni", R_WB, w_B)
    v_W = np.cross(w_W, r_W)
    a_W = np.cross(np.einsum("nij,nj->ni", R_WB, alpha_B), r_W) + np.cross(w_W, v_W)
    q = spatial.matrix_to_quat(R_WB)
    return Trajectory(t, {body.name: BodyStates(r_W, q, v_W, w_W)}, {body.name: JointStates(q, w_B)},
                      {f"reaction_force:{body.name}": body.mass * (a_W - g)})


def swing_scales(body, c_B, gravity):
    """The angular momentum (kg m^2/s) and rate (rad/s) a swing under gravity reaches: ``sqrt(I m g l)`` and
    ``sqrt(m g l / I)``, with ``I`` the largest moment about the pivot and ``l = |c|``: the scales of the
    invariants of a top that starts at rest."""
    I = float(np.max(np.linalg.eigvalsh(inertia_about_pivot(body, c_B))))
    mgl = body.mass * float(np.linalg.norm(gravity)) * float(np.linalg.norm(c_B))
    return np.sqrt(I * mgl), np.sqrt(mgl / I)


def vertical_momentum(gravity, L0, tolerance, floor):
    """The declared invariant: angular momentum about the pivot along the vertical (gravity's moment
    about the pivot is horizontal), its drift relative to the larger of ``|L0|`` (kg m^2/s), the whole
    initial angular momentum about the pivot, and ``floor`` (``swing_scales``)."""
    up = -np.asarray(gravity, dtype=float) / np.linalg.norm(gravity)
    return Invariant("vertical_angular_momentum", "angular momentum about the pivot, component along the "
                     "upward vertical (world)", "kg m^2/s", max(float(np.linalg.norm(L0)), floor), tolerance,
                     lambda scene, traj: invariants.angular_momentum_about(scene, traj, PIVOT) @ up)


def body_spin(body_name, axis_B, w0_B, tolerance, floor):
    """The declared invariant ``spin``: the angular velocity's component along the body's symmetry axis
    ``axis_B`` (unit, body axes), its drift relative to the larger of the initial angular speed and
    ``floor`` (rad/s, ``swing_scales``)."""
    a = np.asarray(axis_B, dtype=float)
    return Invariant("spin", "angular velocity about the body's symmetry axis (body axes)", "rad/s",
                     max(float(np.linalg.norm(w0_B)), floor), tolerance,
                     lambda scene, traj: traj.bodies[body_name].angular_velocity_body @ a)


def inertia_about_pivot(body, c_B):
    """Inertia about the pivot, body axes (kg m^2), shape (3, 3): the parallel-axis theorem
    ``I_com + m (|c|^2 1 - c c^T)`` with the centre of mass at ``c_B`` (m) from the pivot."""
    c = np.asarray(c_B, dtype=float)
    return body.inertia_matrix + body.mass * (c @ c * np.eye(3) - np.outer(c, c))
