"""Torque-free rigid body: angular velocity and attitude in closed form.

Source: L. D. Landau & E. M. Lifshitz, *Mechanics*, 3rd ed. (1976), section 37
("Free rotation of a top"): for principal moments ``I1 < I2 < I3`` and
``M^2 > 2 E I2``::

    w1 = sqrt((2E I3 - M^2) / (I1 (I3 - I1))) cn(tau)
    w2 = sqrt((2E I3 - M^2) / (I2 (I3 - I2))) sn(tau)
    w3 = sqrt((M^2 - 2E I1) / (I3 (I3 - I1))) dn(tau)
    tau = t sqrt((I3 - I2)(M^2 - 2E I1) / (I1 I2 I3))
    k^2 = (I2 - I1)(2E I3 - M^2) / ((I3 - I2)(M^2 - 2E I1))

(eqs. 37.10-37.11; for ``M^2 < 2E I2`` exchange the suffixes 1 and 3), and the
Euler angles relative to the constant angular momentum ``M`` along the
invariable axis: ``M_B = M (sin th sin psi, sin th cos psi, cos th)`` and
``phi' = M (I1 w1^2 + I2 w2^2) / (I1^2 w1^2 + I2^2 w2^2)`` (eqs. 37.12-37.13).
Euler's equations in principal axes conserve two quantities (L&L sections 36-37;
Goldstein, *Classical Mechanics*, ch. 5): the energy ``2E = sum_i I_i w_i^2`` (the rotational kinetic
energy is ``1/2 (I w) . w``, Landau & Lifshitz section 32, not ``1/2 w . w``) and
``M^2 = sum_i I_i^2 w_i^2`` (multiply the i-th of ``I_i w_i' = (I_j - I_k) w_j w_k``
by ``I_i w_i`` and sum: the right-hand sides cancel).

Numerics, so that the result is exact to roundoff even a hair off the
separatrix (where ``k^2`` is within 1e-9 of one):

* every quantity Landau writes as a difference is computed as a sum of terms of
  one sign from the initial angular velocity, e.g.
  ``2E I3 - M^2 = sum_i I_i w_i^2 (I3 - I_i)``; the one genuine difference,
  ``M^2 - 2E I2``, is the separatrix distance itself, and the complementary
  parameter ``1 - k^2 = (I3 - I1)(M^2 - 2E I2) / ((I3 - I2)(M^2 - 2E I1))`` is
  formed from it directly (see ``elliptic``);
* the Euler-angle reference axis is chosen, of the two non-intermediate axes,
  as the one the angular momentum stays farthest from (its polar angle then
  stays within [45, 135] degrees), so ``phi'`` never has a small denominator;
* the precession angle is a quadrature of ``phi'`` (a function of ``tau``
  only): Gauss-Legendre on panels of width at most ``_PANEL`` in ``tau``
  (the nearest complex singularity is ``K' >= pi/2`` away, so 16 nodes reach
  roundoff), one full period ``2K`` tabulated once, and ``phi(t)`` assembled
  as whole periods plus a remainder, so no error accumulates over long horizons.

Special cases: the spherical body and a spin exactly about a principal axis
(uniform rotation), the axisymmetric body (``k = 0``: trigonometric), and the
separatrix itself (``k = 1``: hyperbolic functions).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dalembert import spatial
from dalembert.reference.closed_form.elliptic import ellipj, ellipk, inverse_amplitude
from dalembert.reference.closed_form.quadrature import PeriodicIntegral, gauss_legendre

__all__ = ["TorqueFreeTop"]

_PANEL = 0.5  # max panel width in tau; see module docstring


def _principal_frame(inertia):
    """Principal moments (ascending) and ``R_BP`` (proper rotation, columns = axes).

    A diagonal tensor gets an exact signed permutation, so the common case
    introduces no roundoff.
    """
    inertia = np.asarray(inertia, dtype=float)
    if np.count_nonzero(inertia - np.diag(np.diag(inertia))) == 0:
        moments = np.diag(inertia).copy()
        order = np.argsort(moments, kind="stable")
        R = np.eye(3)[:, order]
        moments = moments[order]
    else:
        moments, R = np.linalg.eigh(inertia)
    if np.linalg.det(R) < 0.0:
        R[:, 1] *= -1.0
    return moments, R


@dataclass(frozen=True, eq=False)
class TorqueFreeTop:
    """Exact motion of a torque-free rigid body about its centre of mass.

    Parameters
    ----------
    inertia : array_like, shape (3, 3)
        Inertia tensor about the COM, in the body frame B (kg m^2).
    w0_B : array_like, shape (3,)
        Initial angular velocity ``w_WB_B`` (rad/s), body frame.
    q0_WB : array_like, shape (4,)
        Initial attitude, scalar-first quaternion body-to-world.
    """

    inertia: np.ndarray
    w0_B: np.ndarray
    q0_WB: np.ndarray = field(default_factory=lambda: np.array(spatial.IDENTITY_QUAT))

    def __post_init__(self):
        get = lambda name: np.asarray(getattr(self, name), dtype=float)  # noqa: E731
        object.__setattr__(self, "inertia", get("inertia"))
        object.__setattr__(self, "w0_B", get("w0_B"))
        object.__setattr__(self, "q0_WB", spatial.quat_normalize(get("q0_WB")))
        object.__setattr__(self, "_solution", self._solve())

    # ------------------------------------------------------------------ set-up
    def _solve(self):
        I, R_BP = _principal_frame(self.inertia)
        w = R_BP.T @ self.w0_B  # initial angular velocity in principal axes
        s = {"R_BP": R_BP}
        if I[0] == I[2] or np.count_nonzero(w) <= 1:
            s["kind"] = "uniform"  # spherical body, or a spin about a principal axis
            return s
        # Separatrix distance M^2 - 2E I2, the one genuine difference.
        D = I[2] * w[2] ** 2 * (I[2] - I[1]) - I[0] * w[0] ** 2 * (I[1] - I[0])
        if D < 0.0:  # circulates about axis 1: relabel (e3, -e2, e1), a proper rotation
            # (D itself is invariant under this relabelling: it stays negative, and
            # the sign-consistent formulas below then give positive ratios.)
            R = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
            R_BP, I, w = R_BP @ R, I[::-1].copy(), R.T @ w
        # Now the angular momentum circulates about P-axis 3; "o" is axis 1.
        Io, I2, Ic = I
        sg = 1.0 if Ic > I2 else -1.0  # sign of Ic - I2 (same as of Ic - Io, I2 - Io)
        two_E_Ic_minus_M2 = Io * w[0] ** 2 * (Ic - Io) + I2 * w[1] ** 2 * (Ic - I2)
        M2_minus_two_E_Io = I2 * w[1] ** 2 * (I2 - Io) + Ic * w[2] ** 2 * (Ic - Io)
        A = np.sqrt(two_E_Ic_minus_M2 / (Io * (Ic - Io)))
        B = np.sqrt(two_E_Ic_minus_M2 / (I2 * (Ic - I2)))
        C = np.sqrt(M2_minus_two_E_Io / (Ic * (Ic - Io)))
        lam = np.sqrt((Ic - I2) * M2_minus_two_E_Io / (Io * I2 * Ic))
        m1 = (Ic - Io) * D / ((Ic - I2) * M2_minus_two_E_Io)
        m1 = min(max(m1, 0.0), 1.0)
        # Signs from Euler's equations: sign(B) = sg sign(A) sign(C), A > 0.
        C = np.copysign(C, w[2])
        B = sg * np.sign(C) * B
        tau0 = inverse_amplitude(w[1] / B, w[0] / A, m1)
        # Euler-angle reference axis: the non-intermediate axis M stays farthest from.
        L_amp = np.array([Io * A, I2 * B, Ic * C])
        cyc = [1, 2, 0] if abs(L_amp[2]) > abs(L_amp[0]) else [0, 1, 2]
        s.update(kind="elliptic", R_BP=R_BP, I=I, A=A, B=B, C=C, lam=lam, m1=m1, tau0=tau0, cyc=cyc)
        s["M"] = float(np.linalg.norm(I * w))
        K = ellipk(m1)
        s["period_tau"] = 2.0 * K  # w^2 (hence phi') has period 2K in tau
        if np.isfinite(K):
            s["phi"] = PeriodicIntegral(lambda tau: self._phi_rate(s, tau), 2.0 * K, tau0, panel=_PANEL)
        return s

    def _omega_P(self, s, tau):
        sn, cn, dn = ellipj(tau, s["m1"])
        return np.stack([s["A"] * cn, s["B"] * sn, s["C"] * dn], axis=-1)

    def _phi_rate(self, s, tau):
        """d phi / d tau, shape like tau."""
        w = self._omega_P(s, tau)[..., s["cyc"]]
        I = s["I"][s["cyc"]]
        num = I[0] * w[..., 0] ** 2 + I[1] * w[..., 1] ** 2
        den = (I[0] * w[..., 0]) ** 2 + (I[1] * w[..., 1]) ** 2
        return s["M"] * num / den / s["lam"]

    def _phi(self, s, tau):
        if "phi" in s:
            return s["phi"](tau)
        # the separatrix: aperiodic, integrate directly from tau0
        a = np.full_like(tau, s["tau0"])
        panels = np.maximum(1, np.ceil(np.abs(tau - a) / _PANEL)).astype(int)
        return gauss_legendre(lambda x: self._phi_rate(s, x), a, tau, panels)

    # ---------------------------------------------------------------- results
    @property
    def regime(self):
        """``'uniform'`` or ``'elliptic'`` (with ``m1 == 0`` on the separatrix)."""
        return self._solution["kind"]

    @property
    def m1(self):
        """Complementary parameter ``1 - k^2`` of the elliptic solution (nan if uniform)."""
        return self._solution.get("m1", np.nan)

    def angular_velocity_body(self, t):
        """``w_WB_B`` (rad/s), shape (n, 3), at times ``t`` (s), shape (n,)."""
        s, t = self._solution, np.asarray(t, dtype=float)
        if s["kind"] == "uniform":
            return np.broadcast_to(self.w0_B, t.shape + (3,)).copy()
        return self._omega_P(s, s["lam"] * t + s["tau0"]) @ s["R_BP"].T

    def rotation(self, t):
        """``R_WB`` at times ``t`` (s), shape (n,) -> (n, 3, 3)."""
        s, t = self._solution, np.asarray(t, dtype=float)
        R0 = spatial.quat_to_matrix(self.q0_WB)
        if s["kind"] == "uniform":
            return R0 @ spatial.so3_exp(t[..., None] * self.w0_B)
        R_BQ = s["R_BP"][:, s["cyc"]]  # Q: principal axes cycled so the reference axis is 3rd
        I = s["I"][s["cyc"]]

        def R_NQ(tau, phi):
            L = I * self._omega_P(s, tau)[..., s["cyc"]]
            theta = np.arctan2(np.hypot(L[..., 0], L[..., 1]), L[..., 2])
            psi = np.arctan2(L[..., 0], L[..., 1])
            return spatial.matrix_from_euler_zxz(phi, theta, psi)

        tau = s["lam"] * t + s["tau0"]
        R_WN = R0 @ R_BQ @ R_NQ(np.array(s["tau0"]), 0.0).T
        return R_WN @ R_NQ(tau, self._phi(s, tau)) @ R_BQ.T

    def quaternion(self, t):
        """``q_WB`` scalar first at times ``t`` (s), shape (n,) -> (n, 4)."""
        return spatial.matrix_to_quat(self.rotation(t))

    def angular_velocity_world(self, t):
        """``w_WB_W`` (rad/s), shape (n, 3)."""
        return np.einsum("nij,nj->ni", self.rotation(t), self.angular_velocity_body(t))

    def angular_momentum_world(self):
        """Constant angular momentum about the COM in world axes (kg m^2/s), shape (3,)."""
        return spatial.quat_rotate(self.q0_WB, self.inertia @ self.w0_B)

    def kinetic_energy(self):
        """Constant rotational kinetic energy ``1/2 w . I w`` (J)."""
        return 0.5 * float(self.w0_B @ self.inertia @ self.w0_B)
