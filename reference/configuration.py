"""Configuration spaces of the reference formulations: products of blocks.

A formulation's configuration ``q`` is a concatenation of blocks, each with its
velocity coordinates in ``v``:

* ``vector``: ``q`` in R^n, ``v = dq/dt`` (positions, joint angles);
* ``quat``: a unit quaternion ``q_AB`` (4), ``v = w_AB_B`` (3) in the moving frame;
* ``rotmat``: a rotation matrix ``R_AB`` stored row-major (9), ``v = w_AB_B`` (3)
  — the attitude's kinematics ``R' = R [w]x`` (w in the moving frame; any rigid-body text).

Two ways to move along a velocity, which is what separates integrators:
``qdot`` (the embedded ODE, used by vector-space methods: unit norm and
orthonormality then drift) and ``retract`` (the group exponential, used by
Lie-group methods: they stay on the group to roundoff).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert import spatial

__all__ = ["Block", "qdot", "retract", "dexpinv"]


@dataclass(frozen=True)
class Block:
    kind: str  # "vector" | "quat" | "rotmat"
    q: slice
    v: slice


def qdot(blocks, q, v):
    """Time derivative of ``q`` (nq,) for velocity ``v`` (nv,)."""
    out = np.empty_like(q)
    for b in blocks:
        if b.kind == "vector":
            out[b.q] = v[b.v]
        elif b.kind == "quat":
            out[b.q] = spatial.quat_derivative(q[b.q], v[b.v])
        else:
            out[b.q] = (q[b.q].reshape(3, 3) @ spatial.skew(v[b.v])).ravel()
    return out


def retract(blocks, q, dv):
    """``q`` (..., nq) moved along the tangent vector ``dv`` (..., nv): ``q + dv`` or ``q exp(dv)`` (leading axes:
    many states at once, each as alone)."""
    out = q.copy()
    for b in blocks:
        if b.kind == "vector":
            out[..., b.q] += dv[..., b.v]
        elif b.kind == "quat":
            out[..., b.q] = spatial.quat_multiply(q[..., b.q], spatial.quat_exp(dv[..., b.v]))
        else:
            R = q[..., b.q].reshape(q.shape[:-1] + (3, 3)) @ spatial.so3_exp(dv[..., b.v])
            out[..., b.q] = R.reshape(q.shape[:-1] + (9,))
    return out


def dexpinv(blocks, theta, k):
    """Inverse tangent of the exponential at ``theta`` (nv,) applied to ``k`` (nv,)."""
    out = k.copy()
    for b in blocks:
        if b.kind != "vector":
            out[b.v] = spatial.so3_dexpinv(theta[b.v], k[b.v])
    return out
