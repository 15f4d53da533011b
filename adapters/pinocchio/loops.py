"""Loop closures (``Scene.loops``) as Pinocchio ``RigidConstraintModel``s, solved by ``pin.constraintDynamics``.

Each loop becomes point constraints between the joints that carry its two bodies (``joint1``: body
a's, the universe 0 for the world; ``joint2``: body b's), placed at the loop's frames Ja and Jb:

* ``ball``: one ``CONTACT_3D`` at the loop point (3 rows);
* ``revolute``: a ``CONTACT_3D`` at the loop point and a second one ``lever`` metres along the loop's
  axis on both sides (6 rows). Two points of the axis held together leave exactly the rotation about
  the line through them free: the revolute's five conditions, plus one row that repeats the rigid
  distance between the two points and is always redundant. ``CONTACT_6D`` cannot release a rotation
  (its rows are the whole relative twist), and a massless intermediate body on a revolute joint
  would make the mass matrix singular; so two points. ``lever`` is the larger distance of the loop
  point from the two bodies' centres of mass (1 m if both are zero), so the second point's rows
  weigh the axis tilt as the bodies' own rotations move the loop point (rows of one scale);
* ``distance``: not representable (``DISTANCE_REASON``).

Redundant rows (the revolute's own, and three of a planar loop closed by a 3-D revolute) make the
KKT matrix singular: with ``mu = 0`` Pinocchio's Cholesky returns NaN (measured on the four-bar).
``constraintDynamics`` regularises it with its proximal iterations (``ProximalSettings``): each
iteration solves ``(J M^-1 J^T + mu) lambda_k+1 = rhs + mu lambda_k`` from ``lambda_0 = 0``, so the
multipliers converge to the minimum-norm solution, and in a direction of the Delassus operator
with eigenvalue ``s`` the error shrinks by ``mu / (s + mu)`` per iteration (``PROXIMAL_MU_REL``,
``PROXIMAL_ITERATIONS``). Redundant directions get no force that moves anything (they are the null
space of ``J^T``), so accelerations are unique; how a redundant load is split between rows (e.g.
between the revolute's two points) is the statically indeterminate part, and only the total force
is read back, from the minimum-norm multipliers (``PinocchioModel.minimum_norm``: the
iterations leave roundoff amplified by ``1/mu`` in the null space, which moves nothing). Near a
singular position the vanishing direction converges slowest: the few iterations damp it, as the
reference cuts it (``closure.RANK_RTOL``).

Drift: Baumgarte stabilisation, Pinocchio's own corrector (``setBaumgarteCorrectorParameters``):
the constraint acceleration is set to ``-Kp e - Kd e'`` (``e`` the points' gap) instead of zero,
critically damped at ``BAUMGARTE_RATE``. Chosen over projection because it is the engine's own
mechanism (projection would be the reference's Gauss-Newton on Pinocchio's Jacobians: the
reference's method measured on the engine), it acts inside every evaluation of every integrator,
fixed-step and adaptive, at no extra pass, and it changes nothing on an exact solution (``e = 0``).
Measured on the parallelogram four-bar with rk4 over 1 s (both singular positions) at dt = 1e-4:
without it the angle error was 2.0e-10 rad (the gap's roundoff, divided by the singular value that
vanishes at the flat position, kicks the motion); with it 3.5e-13 rad (``BAUMGARTE_RATE``).

Sign and frame of the multipliers (``LOCAL``, read in ``constraintDynamics``'s source and checked
against the reference's reactions): a ``CONTACT_3D``'s ``lambda`` (3,) is the force ON joint1's
side, in the frame c1 of its placement; joint2's side gets ``-lambda``. So the force of a loop ON
body b is ``-sum R_Wc1 lambda`` over its contacts (N, world).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert import spatial
from dalembert.scene import WORLD

__all__ = ["LOOP_KINDS", "DISTANCE_REASON", "PROXIMAL_MU_REL", "PROXIMAL_ITERATIONS", "PROXIMAL_ACCURACY",
           "BAUMGARTE_RATE", "LoopContacts", "loop_contacts", "proximal_settings", "baumgarte", "force_on_b"]

# The loop kinds built here (the adapter declares ``loop:<kind>`` for these only).
LOOP_KINDS = ("ball", "revolute")
DISTANCE_REASON = ("loop:distance: Pinocchio's RigidConstraintModel holds 3 (CONTACT_3D) or 6 (CONTACT_6D) relative "
                   "coordinates of two frames and constraintDynamics takes no other kind; a fixed distance between two "
                   "points is one scalar row it cannot express (a massless rod with ball ends would make the mass "
                   "matrix singular)")
# mu, relative to the largest eigenvalue of the Delassus operator J M^-1 J^T at the initial state (so
# it scales with the mechanism's units). mu > 0 makes the regularised KKT matrix factorisable with
# redundant rows; the smaller it is, the faster the iterations converge (by mu / s per iteration in a
# direction of eigenvalue s), and the more they amplify roundoff in the redundant multipliers (~eps / mu,
# ~1e-6 of the largest force here: it moves nothing, and the read-back removes it). Measured on the
# four-bar, rk4 over 1 s (both singular positions), angle error at dt = 1e-3 / 1e-4: mu 1e-4: 1.1e-6 /
# 1.2e-6 rad; 1e-6: 2.0e-8 / 1.5e-9; 1e-8: 4.6e-12 / 1.1e-12; 1e-10, 1e-12 and 1e-14 alike: 4.3e-12 /
# 3.5e-13. 1e-10 is the largest on that plateau.
PROXIMAL_MU_REL = 1e-10
# Measured as above at mu 1e-10: one iteration 2.1e-7 / 6.9e-4 rad (it has not converged at the singular
# position), two and three both 4.3e-12 / 3.5e-13; three for margin (each is one more triangular solve).
PROXIMAL_ITERATIONS = 3
# Stop earlier when the multipliers change less than this (N; Pinocchio's relative criterion): with
# redundant rows the change settles at roundoff / mu instead, and the iterations run to the cap.
PROXIMAL_ACCURACY = 1e-14
# Baumgarte gains Kp = w^2, Kd = 2 w (critically damped gap dynamics) with w in rad/s: faster than the
# mechanisms' motions (the four-bar turns at up to 9 rad/s), so drift is pulled back within a fraction
# of a turn, and w * dt <= 0.3 at the largest step the matrix runs (1e-2 s): well inside the stability
# regions of the explicit integrators (euler, rk4), so the corrector never drives the step. Measured
# on the four-bar as above (mu 1e-10; w = 10 and 100 at mu 1e-8): w = 0: 4.4e-12 / 2.0e-10 rad;
# w = 10: 2.4e-11 / 2.2e-9; w = 30: 4.3e-12 / 3.5e-13; w = 100: 4.4e-12 / 8.5e-13.
BAUMGARTE_RATE = 30.0


def baumgarte():
    """``(Kp, Kd)`` (1/s^2, 1/s) of the corrector, from ``BAUMGARTE_RATE``."""
    return BAUMGARTE_RATE**2, 2.0 * BAUMGARTE_RATE


def proximal_settings(mu):
    """A ``pin.ProximalSettings`` for the loops' solve with regularisation ``mu`` (absolute)."""
    import pinocchio as pin

    return pin.ProximalSettings(PROXIMAL_ACCURACY, mu, PROXIMAL_ITERATIONS)


@dataclass(frozen=True)
class LoopContacts:
    """One loop's contacts: ``loop`` (``Loop``), ``indices`` (positions in the model's constraint list),
    ``lever`` (m, the revolute's second point along the axis; 0 for a ball)."""

    loop: object
    indices: tuple
    lever: float


def _placement(pm, body, point, quat):
    """``(joint id, pin.SE3)``: the loop frame (``point``, ``quat`` in ``body``'s frame B, or the world's)
    in the frame E of the joint that carries the body (the universe for the world)."""
    import pinocchio as pin

    R_BJ = spatial.quat_to_matrix(quat)
    if body == WORLD:
        return 0, pin.SE3(R_BJ, np.asarray(point, dtype=float))
    X_EB = pm.X_EB[body]
    return pm.carrier[body], pin.SE3(X_EB.rotation @ R_BJ, X_EB.rotation @ np.asarray(point) + X_EB.translation)


def _lever(loop):
    """The revolute's second point along the axis (m): the larger distance of the loop point from the
    two bodies' COMs (points in the world's frame when a side is the world do not count), or 1 m."""
    arms = [float(np.linalg.norm(p)) for body, p in ((loop.body_a, loop.point_a), (loop.body_b, loop.point_b))
            if body != WORLD]
    return max(arms, default=0.0) or 1.0


def loop_contacts(pm, first_index):
    """The ``CONTACT_3D`` models of every loop of ``pm.scene`` (``pin.RigidConstraintModel``, ``LOCAL``,
    Baumgarte-corrected) and a ``LoopContacts`` per loop; indices count from ``first_index``."""
    import pinocchio as pin

    Kp, Kd = baumgarte()
    models, found = [], []
    for loop in pm.scene.loops:
        j1, X1 = _placement(pm, loop.body_a, loop.point_a, loop.quat_a)
        j2, X2 = _placement(pm, loop.body_b, loop.point_b, loop.quat_b)
        pairs, lever = [(X1, X2)], 0.0
        if loop.kind == "revolute":
            lever = _lever(loop)
            axis = np.asarray(loop.axis, dtype=float) / np.linalg.norm(loop.axis)  # in Ja and in Jb
            pairs.append((pin.SE3(X1.rotation, X1.translation + lever * X1.rotation @ axis),
                          pin.SE3(X2.rotation, X2.translation + lever * X2.rotation @ axis)))
        idx = []
        for k, (Xa, Xb) in enumerate(pairs):
            cm = pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, pm.model, j1, Xa, j2, Xb,
                                          pin.ReferenceFrame.LOCAL)
            cm.name = f"{loop.name}:{k}"
            cm.setBaumgarteCorrectorParameters(pin.BaumgarteCorrectorParameters(Kp, Kd))
            idx.append(first_index + len(models))
            models.append(cm)
        found.append(LoopContacts(loop, tuple(idx), lever))
    return models, found


def force_on_b(forces, contacts):
    """The force of one loop ON its body b (N, world), at m states: ``-sum R_Wc1 lambda`` over its contacts
    (module docstring), ``forces (m, n_constraints, 3)`` every constraint's ``R_Wc1 lambda``
    (``PinocchioModel.constraint_forces``) -> ``(m, 3)``."""
    return -forces[:, list(contacts.indices)].sum(axis=1)
