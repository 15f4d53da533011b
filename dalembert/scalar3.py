"""3-vectors and 3x3 matrices as scalars, for the few dozen products of a step that numpy's per-call cost would
dominate (``rotations.skew``'s reason): a vector is 3 scalars, a matrix 9 (row-major); each scalar a Python float
at one state, or an (m,) array where m states come stacked. Each product and sum is then one IEEE operation either
way, so the two round every term alike (the reference's tree pass, ``reference.tree_pass``, and the loop rows,
``closure.LoopRows``, rely on it: their stacked evaluations equal the per-state ones to the last bit)."""

from __future__ import annotations

__all__ = ["mat", "rot", "cross", "dot", "add"]


def mat(A, B):
    """``A B`` of two 9-scalar matrices: 9 scalars."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = A
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = B
    return (a0 * b0 + a1 * b3 + a2 * b6, a0 * b1 + a1 * b4 + a2 * b7, a0 * b2 + a1 * b5 + a2 * b8,
            a3 * b0 + a4 * b3 + a5 * b6, a3 * b1 + a4 * b4 + a5 * b7, a3 * b2 + a4 * b5 + a5 * b8,
            a6 * b0 + a7 * b3 + a8 * b6, a6 * b1 + a7 * b4 + a8 * b7, a6 * b2 + a7 * b5 + a8 * b8)


def rot(A, x):
    """``A x``: a 9-scalar matrix times a 3-scalar vector, 3 scalars."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = A
    x0, x1, x2 = x
    return (a0 * x0 + a1 * x1 + a2 * x2, a3 * x0 + a4 * x1 + a5 * x2, a6 * x0 + a7 * x1 + a8 * x2)


def cross(a, b):
    """``a x b``: 3 scalars."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return (a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0)


def dot(a, b):
    """``a . b``: a scalar."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def add(a, b):
    """``a + b``: 3 scalars."""
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])
