"""Minimum-norm least squares of many small systems at once: ``np.linalg.lstsq`` over a leading axis."""

from __future__ import annotations

import numpy as np

__all__ = ["lstsq_stacked"]


def lstsq_stacked(A, b, rcond=None):
    """Per system ``i``, the ``x[i]`` of least norm among those minimizing ``|A[i] x - b[i]|``: what
    ``np.linalg.lstsq(A[i], b[i], rcond)`` returns, for all systems in one stacked SVD.

    Parameters
    ----------
    A : ndarray, shape (m, k, n)
    b : ndarray, shape (m, k)
    rcond : float, optional
        Singular values at or below ``rcond`` times their system's largest are cut (taken as zero), each
        system by its own; ``None``: numpy's default, ``eps * max(k, n)``.

    Returns
    -------
    ndarray, shape (m, n)
    """
    A, b = np.asarray(A, dtype=float), np.asarray(b, dtype=float)
    if rcond is None:
        rcond = np.finfo(float).eps * max(A.shape[-2:])
    U, S, Vt = np.linalg.svd(A, full_matrices=False)
    keep = S > rcond * S[:, :1]
    inv_S = np.divide(1.0, S, out=np.zeros_like(S), where=keep)
    return np.einsum("mji,mj->mi", Vt, inv_S * np.einsum("mji,mj->mi", U, b))  # V S^+ U^T b
