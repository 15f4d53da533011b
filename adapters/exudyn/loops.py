"""Which constraint rows each loop closure gives Exudyn: ``loop_axes``.

Exudyn solves its index-3 (generalized-alpha) and index-2 (trapezoidal) systems by Newton's method
on the full Jacobian ``[[M', C_q^T], [C_q, 0]]``, which is singular when constraint rows are
redundant. A planar loop closed by a 3-D revolute (the parallelogram four-bar) carries 3 such rows
of its 5: the out-of-plane translation and the two tilts, implied by the tree's parallel axes.
Measured on the four-bar (generalized-alpha, minimal coordinates, 0.5 s, passing the singular
position at t = 0.23 s):

* all 5 rows, Exudyn's default dense solver (``EXUdense``): "matrix is not factorized" at the first
  step;
* all 5 rows, ``linearSolver.solverType = EigenDense`` with ``ignoreSingularJacobian = True`` (Eigen's
  FullPivLU, which resolves redundant rows on purpose): runs at dt = 1e-2 and 1e-3, but at 1e-4 Newton
  does not meet the adapter's tolerances (``NEWTON_RTOL``) at the singular position and the solve
  stops at t = 0.238 s; with Exudyn's default Newton tolerances it passes, 30x less accurate
  (1.1e-6 rad instead of 3.7e-8) with closure residuals of 4e-8 m and 7e-5 m/s;
* the independent rows only (this module; the default dense solver): runs at every step size, the
  same angle error as FullPivLU where both run (3.7e-4 and 3.7e-6 rad at dt = 1e-2 and 1e-3), closure
  residuals <= 4e-16 m and 5e-10 m/s.

So each loop constrains only its rows that are independent at the initial state: the candidate
rows of an ``ObjectJointGeneric`` in its marker-0 frame Ja (translation x, y, z; for a revolute,
rotation about x and y, z being the loop's axis) are taken in that order, with the previous loops'
kept rows, and one is kept when it raises the rank of their Jacobian in the tree's joint speeds
(``dalembert.closure.tree_jacobians``; a singular value below ``closure.RANK_RTOL`` times the
largest counts as zero, as in ``Scene.loop_summary``). The kept rows have the rank of all of them,
so they constrain the same motion near the initial state, and the dropped rows' reactions are
zero (the least-squares choice the reference makes as well). A scene started AT a singular
position would lose a row that is degenerate only there (the rows are chosen once, at t = 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert import closure, spatial
from dalembert.scene import WORLD

__all__ = ["LoopRows", "loop_axes", "joint_frame", "AXIS_NAMES"]

# Candidate rows of an ObjectJointGeneric (its constrainedAxes positions), by loop kind.
CANDIDATES = {"ball": (0, 1, 2), "revolute": (0, 1, 2, 3, 4)}
AXIS_NAMES = ("translation x", "translation y", "translation z", "rotation x", "rotation y", "rotation z")


@dataclass(frozen=True)
class LoopRows:
    """The rows one loop gives Exudyn.

    Attributes
    ----------
    axes : tuple of 6 ints — ``constrainedAxes`` of its ObjectJointGeneric (1 = constrained); for a
        distance loop ``(1,)``, its one row
    dropped : tuple of str — the candidate rows left out as redundant at the initial state (``AXIS_NAMES``)
    """

    axes: tuple
    dropped: tuple


def joint_frame(loop):
    """``(R_BJa, R_BJb)``: the loop's joint frames in body a's and b's scene frames, z along a
    revolute loop's axis (the frame Exudyn's marker carries), (3, 3) each."""
    R_A = spatial.frame_with_z(loop.axis) if loop.kind == "revolute" else np.eye(3)
    return spatial.quat_to_matrix(loop.quat_a) @ R_A, spatial.quat_to_matrix(loop.quat_b) @ R_A


def _candidates(loop, states, J):
    """Each candidate row's Jacobian in the tree's speeds at the initial state, (k, nv)."""
    A, B = states[loop.body_a], states[loop.body_b]
    rho_a, rho_b = A["R"] @ np.asarray(loop.point_a), B["R"] @ np.asarray(loop.point_b)
    # velocity of point b minus point a, and angular velocity of b minus a (world), per unit speed
    dv = (J[loop.body_b][:3] - spatial.skew(rho_b) @ J[loop.body_b][3:]
          - J[loop.body_a][:3] + spatial.skew(rho_a) @ J[loop.body_a][3:])
    dw = J[loop.body_b][3:] - J[loop.body_a][3:]
    if loop.kind == "distance":
        d = (B["p"] + rho_b) - (A["p"] + rho_a)
        return (d / np.linalg.norm(d))[None, :] @ dv
    R_WJa = A["R"] @ joint_frame(loop)[0]
    rows = R_WJa.T @ dv  # translations in Ja
    if loop.kind == "revolute":
        rows = np.vstack([rows, (R_WJa.T @ dw)[:2]])  # tilts about Ja's x and y
    return rows


def loop_axes(scene):
    """The rows each loop of ``scene`` constrains in Exudyn (module docstring), dict loop name -> ``LoopRows``."""
    _, J = closure.tree_jacobians(scene)
    states = spatial.initial_body_states(scene)
    states[WORLD] = closure.world_state()
    found = [_candidates(loop, states, J) for loop in scene.loops]
    stacked = np.vstack(found)
    top = np.linalg.svd(stacked, compute_uv=False)[0] if stacked.size else 0.0

    def rank(rows):
        if not rows:
            return 0
        s = np.linalg.svd(np.vstack(rows), compute_uv=False)
        return int(np.sum(s > closure.RANK_RTOL * top)) if top > 0.0 else 0

    kept, out = [], {}
    for loop, rows in zip(scene.loops, found):
        axes, dropped = [0] * 6, []
        positions = (0,) if loop.kind == "distance" else CANDIDATES[loop.kind]
        for k, row in zip(positions, rows):
            if rank(kept + [row]) > len(kept):
                kept.append(row)
                axes[k] = 1
            else:
                dropped.append("distance" if loop.kind == "distance" else AXIS_NAMES[k])
        out[loop.name] = LoopRows(tuple(axes[:1]) if loop.kind == "distance" else tuple(axes), tuple(dropped))
    return out
