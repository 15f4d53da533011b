"""Loop closures as DART's dynamic joint constraints: ball and revolute; distance refused.

DART 6.20 closes a loop with a ``DynamicJointConstraint`` in the world's constraint solver: a
``BallJointConstraint`` (three rows: the points coincide) or a ``RevoluteJointConstraint`` (five: the points
coincide and the axes stay parallel). Each is built at the initial state from the loop's point in world
coordinates and, for a revolute loop, each side's axis in world coordinates (measured: a body on a free joint held
by a ``RevoluteJointConstraint`` to the world swings as the same body on a ``RevoluteJoint`` to first order in the
step, 2.4e-4 m over 1 s at dt = 1e-3, with the axis given in world coordinates; given in body coordinates it
does not, 0.36 m); DART stores the points and axes in each body's frame. A loop to the world takes the
one-body form. The rows are velocity-level, solved with the step's boxed LCP (Dantzig), and the drift of the
closure corrected by an error-reduction parameter (Baumgarte's stabilisation): ``ERP``, ``CFM``, the error
allowance and the largest correction velocity are DART's class-wide settings, left as DART has them and read
back in the audit (``parameters``).

DART has no distance constraint (its dynamic joint constraints are ball, revolute, weld and cylindrical):
``DISTANCE_REASON``.

Reactions: DART reports a constraint's impulse only as generalized forces of the whole skeleton
(``Skeleton.getConstraintForces``), not per loop: the read-back takes one step from each sample and finds a loop's
force by Newton's second law on one of its bodies (``readback``); ``REACTIONS_REASON`` says so in the audit.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.scene import WORLD

__all__ = ["LOOP_KINDS", "DISTANCE_REASON", "REACTIONS_REASON", "add_loops", "parameters"]

LOOP_KINDS = ("ball", "revolute")
DISTANCE_REASON = ("a distance loop: DART 6.20 has no distance constraint (its dynamic joint constraints are ball, "
                   "revolute, weld and cylindrical); a massless rod would be a body of its own")
REACTIONS_REASON = ("joints' from BodyNode.getBodyForce after one World.step from each sample (the constraint "
                    "impulses are in it only then); each loop's by Newton's second law on one of its bodies over that "
                    "step (DART reports constraint impulses only as the skeleton's generalized forces); none for a "
                    "loop both of whose bodies other loops hold too")


def add_loops(model):
    """Every loop of ``model.scene`` as a constraint in ``model.world``'s constraint solver, built at the state the
    skeleton is in (``DartModel.reset``: the initial state); returns the constraints, in ``scene.loops`` order."""
    import dartpy

    solver = model.world.getConstraintSolver()
    out = []
    for lp in model.scene.loops:
        ends = []
        for body, point, quat in ((lp.body_a, lp.point_a, lp.quat_a), (lp.body_b, lp.point_b, lp.quat_b)):
            if body == WORLD:
                R, p = np.eye(3), np.zeros(3)
                node = None
            else:
                node = model.nodes[body]
                T = node.getWorldTransform()
                R, p = T.rotation(), T.translation()
            axis = None if lp.axis is None else R @ spatial.quat_to_matrix(quat) @ np.asarray(lp.axis, dtype=float)
            ends.append((node, p + R @ np.asarray(point, dtype=float), axis))
        (na, pa, axis_a), (nb, _, axis_b) = ends
        nodes = [n for n in (na, nb) if n is not None]
        if lp.kind == "ball":
            constraint = dartpy.constraint.BallJointConstraint(*nodes, pa)
        elif na is not None and nb is not None:
            constraint = dartpy.constraint.RevoluteJointConstraint(na, nb, pa, axis_a, axis_b)
        else:  # to the world: the body's side of the axis (the sides coincide on a closed loop)
            constraint = dartpy.constraint.RevoluteJointConstraint(nodes[0], pa, axis_b if na is None else axis_a)
        solver.addConstraint(constraint)
        out.append(constraint)
    return out


def parameters():
    """DART's class-wide settings of its dynamic joint constraints, read back (the audit)."""
    import dartpy

    c = dartpy.constraint.DynamicJointConstraint
    return {"error_reduction_parameter": float(c.getErrorReductionParameter()),
            "constraint_force_mixing": float(c.getConstraintForceMixing()),
            "error_allowance": float(c.getErrorAllowance()),
            "max_error_reduction_velocity": float(c.getMaxErrorReductionVelocity())}
