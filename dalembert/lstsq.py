"""Many small least-squares systems at once: ``np.linalg.lstsq`` over a leading axis, and the rank-cut SVD behind it."""

from __future__ import annotations

import numpy as np

__all__ = ["svd_cut", "lstsq_stacked"]


def svd_cut(A, rcond):
    """The thin SVD of each matrix ``A[i]``, its singular values at or below ``rcond`` times its largest cut
    (each matrix by its own): cut directions zeroed, not dropped, so every matrix keeps ``r = min(k, n)``
    columns and the sums over them are the kept ones', plus exact zeros.

    Parameters
    ----------
    A : ndarray, shape (m, k, n)
    rcond : float

    Returns
    -------
    U : ndarray, shape (m, k, r) — left singular vectors, cut columns zero
    inv_S : ndarray, shape (m, r) — ``1 / S``, zero where cut
    V : ndarray, shape (m, n, r) — right singular vectors, cut columns zero
    """
    U, S, Vt = np.linalg.svd(A, full_matrices=False)
    keep = S > rcond * S[..., :1]  # (none kept where the largest is 0)
    inv_S = np.divide(1.0, S, out=np.zeros_like(S), where=keep)
    return U * keep[..., None, :], inv_S, Vt.swapaxes(-1, -2) * keep[..., None, :]


def lstsq_stacked(A, b, rcond=None):
    """Per system ``i``, the ``x[i]`` of least norm among those minimizing ``|A[i] x - b[i]|``: what
    ``np.linalg.lstsq(A[i], b[i], rcond)`` returns, for all systems in one stacked SVD (``svd_cut``).

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
    U, inv_S, V = svd_cut(A, rcond)
    return np.einsum("mij,mj->mi", V, inv_S * np.einsum("mji,mj->mi", U, b))  # V S^+ U^T b
