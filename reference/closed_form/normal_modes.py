"""Small oscillations about a stable equilibrium: the linearised normal modes.

Source: H. Goldstein, C. Poole, J. Safko, *Classical Mechanics*, 3rd ed. (2002), chapter 6
("Oscillations"), sections 6.2-6.3: with the mass matrix ``M`` and the stiffness ``K`` at the
equilibrium, ``M q'' + K q = 0``; the generalized eigenproblem ``K u = w^2 M u`` gives the
frequencies ``w_k`` and the modes ``u_k`` (normalized ``U^T M U = 1``), and

    q(t) = sum_k u_k (a_k cos(w_k t) + b_k sin(w_k t)),  a = U^T M q0,  b_k = (U^T M v0)_k / w_k

For the nonlinear system this is exact to first order in the amplitude ``e``: the neglected
terms are O(e^3) in the equations of motion (they are odd in ``q``), so the motion differs
from the modes by O(e^3) over a fixed horizon (tests/test_chain.py checks that scaling).

``rod_chain_matrices`` gives ``M`` and ``K`` of a hanging chain of identical uniform rods in its
joint angles (each relative to the link above), from the planar double-pendulum Lagrangian
(Goldstein 1.4, the double pendulum of exercise 1.21, generalized to n links).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["NormalModes", "rod_chain_matrices"]


def rod_chain_matrices(n, mass, length, moment_com, gravity):
    """Mass matrix (kg m^2) and stiffness (N m / rad) of ``n`` identical uniform rods hanging in a
    chain, at rest straight down, in the joint angles ``q`` (rad): ``(M, K)``, each (n, n).

    Parameters
    ----------
    n : int — links; mass : float — each rod's mass (kg); length : float — each rod's length (m),
    joints at its ends, centre of mass in the middle; moment_com : float — each rod's moment of
    inertia about the joint axis through its centre of mass (kg m^2); gravity : float — m/s^2

    In the absolute angles ``phi`` (``phi_i = q_1 + ... + q_i``), with ``b_i = n - 1 - i`` links
    below link i (from 0): ``M_ii = I + m l^2 / 4 + b_i m l^2``, ``M_ij = m l^2 (b_j + 1/2)`` (i < j),
    ``K = diag(m g l (b_i + 1/2))``; then ``M_q = T^T M T`` and ``K_q = T^T K T`` with ``phi = T q``.
    """
    i = np.arange(n)
    below = n - 1 - i
    ml2 = mass * length**2
    M = ml2 * (np.minimum.outer(below, below) + 0.5)  # (b_j + 1/2) m l^2, link j the lower one
    np.fill_diagonal(M, moment_com + ml2 / 4.0 + below * ml2)
    K = np.diag(mass * gravity * length * (below + 0.5))
    T = np.tril(np.ones((n, n)))
    return T.T @ M @ T, T.T @ K @ T


@dataclass(frozen=True, eq=False)
class NormalModes:
    """The linear motion ``M q'' + K q = 0`` from ``q0``, ``v0``.

    Parameters
    ----------
    mass_matrix : array_like (n, n) — symmetric positive definite
    stiffness : array_like (n, n) — symmetric positive definite (a stable equilibrium)
    q0 : array_like (n,) — initial coordinates; v0 : array_like (n,) — initial rates
    """

    mass_matrix: np.ndarray
    stiffness: np.ndarray
    q0: np.ndarray
    v0: np.ndarray
    _modes: tuple = field(init=False, repr=False)

    def __post_init__(self):
        from scipy.linalg import eigh  # here, not at the top: scipy.linalg is ~0.15 s of a process's start

        M, K = np.asarray(self.mass_matrix, float), np.asarray(self.stiffness, float)
        w2, U = eigh(K, M)  # U^T M U = 1
        if not np.all(w2 > 0.0):
            raise ValueError(f"NormalModes: stiffness not positive definite on M (w^2 = {w2}) — not a stable "
                             "equilibrium")
        w = np.sqrt(w2)
        a = U.T @ M @ np.asarray(self.q0, float)
        b = U.T @ M @ np.asarray(self.v0, float) / w
        object.__setattr__(self, "_modes", (w, U, a, b))

    @property
    def frequencies(self):
        """Angular frequencies ``w_k`` (rad/s), ascending, shape (n,)."""
        return self._modes[0]

    def coordinates(self, t):
        """``q(t)``, shape (len(t), n), at times ``t`` (s)."""
        w, U, a, b = self._modes
        wt = np.outer(np.asarray(t, float), w)
        return (a * np.cos(wt) + b * np.sin(wt)) @ U.T

    def rates(self, t):
        """``q'(t)``, shape (len(t), n)."""
        w, U, a, b = self._modes
        wt = np.outer(np.asarray(t, float), w)
        return (w * (b * np.cos(wt) - a * np.sin(wt))) @ U.T
