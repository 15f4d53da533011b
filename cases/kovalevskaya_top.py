"""The Kovalevskaya top: the third integrable heavy top, on a ball joint under gravity."""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.case import Case, Invariant, Tolerance, case
from dalembert.cases._fixed_point import inertia_about_pivot, pivoted_scene, swing_scales, vertical_momentum
from dalembert.cases._sampling import sample_times
from dalembert.scene import Body, SceneError

UNITS = dict(mass="kg", moment="kg m^2", com_offset="m", gravity="m/s^2", tilt="rad", omega0="rad/s",
             t_final="s", sample_interval="s")

# Hard case: stability bounds, as for the free tops' hard variants (cases/free_top.py): a run that
# changes an integral by more than this is adding or removing energy, whatever its phase accuracy.
STABILITY_ENERGY = Tolerance(1e-3, "relative; 0.1% of the energy gained or lost over 100 s is no longer roundoff "
                                   "or truncation but an integrator pumping or damping the motion")
STABILITY_INTEGRAL = Tolerance(1e-3, "relative to the integral's scale; as STABILITY_ENERGY, for the other three "
                                     "integrals of the motion")
# The truth (the reference, DOP853 at 1e-12) against a 40-digit Taylor integration of the Euler-Poisson
# equations (tests/taylor.py): 1.3e-11 rad at 10 s (tests/test_kovalevskaya.py), 2.1e-9 rad over the 100 s.
ORIENTATION_TOL = Tolerance(1e-3, "rad over 100 s; the truth is good to 2.1e-9 rad here (against a 40-digit "
                                  "Taylor integration), so a miss is the engine's")
RATE_TOL = Tolerance(1e-3, "rad/s at rates of ~5 rad/s; as ORIENTATION_TOL")
POSITION_TOL = Tolerance(1e-3, "m and m/s for the COM, 0.5 m from the pivot; as ORIENTATION_TOL")


def kovalevskaya_integral(p, q, r, gamma, eps):
    """Kovalevskaya's integral ``(p^2 - q^2 - eps g1)^2 + (2 p q - eps g2)^2`` ((rad/s)^4), shape (n,), for
    body rates ``p, q, r`` (rad/s, each (n,)) about principal axes with moments (2C, 2C, C) about the
    pivot, the centre of mass on axis 1, ``gamma`` (n, 3) the upward vertical in the body and
    ``eps = m g x0 / C`` (1/s^2). Conserved by ``2 p' = q r``, ``2 q' = -p r + eps g3``, ``r' = -eps g2``,
    ``gamma' = gamma x w`` (S. Kovalevskaya, Acta Math. 12 (1889) 177-232): with ``z = p + i q`` and
    ``zeta = g1 + i g2`` these give ``(z^2 - eps zeta)' = -i r (z^2 - eps zeta)``, so its modulus squared,
    the integral, is constant."""
    return (p * p - q * q - eps * gamma[:, 0]) ** 2 + (2.0 * p * q - eps * gamma[:, 1]) ** 2


@case(tags=("hard", "jointed", "gravity", "ball", "integrable", "long-horizon"), units=UNITS,
      positive=("mass", "moment", "com_offset", "gravity", "sample_interval"))
def kovalevskaya_top(mass=1.0, moment=1.0, com_offset=0.5, gravity=9.81, tilt=0.7, omega0=(0.5, 1.0, 3.0),
                     t_final=100.0, sample_interval=0.1):
    """A body on a fixed point with principal moments (2C, 2C, C) about it (``moment`` = C) and its
    centre of mass ``com_offset`` along the first axis, in the plane of the equal moments: the
    Kovalevskaya top. Tilted ``tilt`` about world x at t = 0, spinning at ``omega0`` (body axes).

    Its four integrals are checked as conserved quantities: the energy (built in), the angular
    momentum about the pivot along the vertical, the length of the vertical as the body sees it
    (1 for an attitude that stays a rotation) and Kovalevskaya's integral (declared invariants).
    No closed form here (Kovalevskaya's solution is in hyperelliptic functions): the truth is the
    reference at tight tolerance, checked against a 40-digit Taylor integration.
    """
    C, m, x0 = float(moment), float(mass), float(com_offset)
    if not 0.0 < m * x0 * x0 <= 0.5 * C:
        raise SceneError("case 'kovalevskaya_top'", [
            f"com_offset: m x0^2 = {m * x0 * x0:g} kg m^2 must lie in (0, moment/2 = {0.5 * C:g}] — the body's own "
            "inertia about its centre of mass, diag(2C, 2C - m x0^2, C - m x0^2), must be positive and obey the "
            "triangle inequality"])
    c_B = (x0, 0.0, 0.0)
    body = Body("top", m, np.diag([2.0 * C, 2.0 * C - m * x0 * x0, C - m * x0 * x0]))
    g = (0.0, 0.0, -float(gravity))
    up = np.array([0.0, 0.0, 1.0])
    w0 = np.asarray(omega0, dtype=float)
    eps = m * gravity * x0 / C
    scene = pivoted_scene("kovalevskaya_top", body, c_B, spatial.so3_exp([float(tilt), 0.0, 0.0]), w0, g)

    def gamma(traj):  # the upward vertical in the body, from the attitude as stored (not renormalized)
        return np.einsum("nji,j->ni", traj.bodies["top"].rotation_matrix, up)

    def k_series(scene, traj):
        w = traj.bodies["top"].angular_velocity_body
        return kovalevskaya_integral(w[:, 0], w[:, 1], w[:, 2], gamma(traj), eps)

    k_scale = float(w0 @ w0 + eps) ** 2
    invariants = (
        vertical_momentum(g, inertia_about_pivot(body, c_B) @ w0, STABILITY_INTEGRAL, swing_scales(body, c_B, g)[0]),
        Invariant("vertical_norm", "length of the upward vertical in the body frame, R^T e_z, from the attitude as "
                  "stored (1 while it stays a rotation)", "1", 1.0, STABILITY_INTEGRAL,
                  lambda scene, traj: np.linalg.norm(gamma(traj), axis=1)),
        Invariant("kovalevskaya_integral", "Kovalevskaya's integral (p^2 - q^2 - eps g1)^2 + (2pq - eps g2)^2, body "
                  f"rates and vertical, eps = m g x0 / C = {eps:g} 1/s^2", "rad^4/s^4", k_scale, STABILITY_INTEGRAL,
                  k_series),
    )
    return Case("kovalevskaya_top", scene, t_final, sample_times(t_final, sample_interval, "kovalevskaya_top"),
                conserved=("energy",),
                tolerances=dict(orientation=ORIENTATION_TOL, angular_velocity=RATE_TOL, position=POSITION_TOL,
                                velocity=POSITION_TOL, energy=STABILITY_ENERGY),
                invariants=invariants)
