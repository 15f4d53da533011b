"""A row of ``n`` parallelogram four-bars under gravity in closed form: one degree of freedom, a physical
pendulum, and every pin force from Newton's law on each link (``four_bar`` is ``n = 1``, ``n_four_bar`` any n).

The mechanism, in its own plane with ``h`` along the ground line and ``v`` up (against gravity): ``n + 1``
rockers of length ``L`` pivoted on the ground at ``A_i = i L h`` (i = 0..n), their tips ``B_i``, and ``n``
couplers ``B_{i-1} B_i`` (i = 1..n), each as long as the ground spacing. Every window is a parallelogram, so
all rockers keep one angle ``phi`` (from ``h`` towards ``v``), the couplers translate, and every point of a
coupler moves with the rockers' tips, ``L phi' (-sin phi, cos phi)``. With ``m`` the mass of every link and
``I_A`` a rocker's moment about its pivot (COM at mid-length):

    T = 1/2 ((n+1) I_A + n m L^2) phi'^2,     V = g L ((n+1) m/2 + n m) sin(phi) = (3n+1)/2 m g L sin(phi)

so Lagrange's equation is the physical pendulum's in ``theta = phi + pi/2`` (the angle from the downward
vertical), ``I theta'' = -M g L sin(theta)`` with ``I = (n+1) I_A + n m L^2`` and ``M = (3n+1) m / 2``:
``RigidPendulum(mass=M, com_distance=L, inertia_pivot=I)``; ``alpha = phi'' = -M g L cos(phi) / I``.

Pin forces (planar components along ``h``, ``v``; nothing acts out of the plane). Unknowns: ``G_i``, the force
of rocker i-1 ON coupler i at ``B_{i-1}``, and ``H_i``, the force ON rocker i at ``B_i`` from coupler i (so
``-H_i`` on the coupler), i = 1..n: 4n unknowns. With ``a = L (alpha n_ - phi'^2 u)`` the tips' (and the
couplers') acceleration, ``u = (cos phi, sin phi)``, ``n_ = (-sin phi, cos phi)``:

* coupler i (does not turn; forces at its two ends, lever ``L/2`` along ``h`` each way): moments give
  ``G_i,v = -H_i,v``, the vertical balance ``H_i,v = -m (a_v + g) / 2``, the horizontal ``G_i,h = H_i,h + m a_h``;
* rocker i, moments about ``A_i`` (planar cross product, ``u x F = cos(phi) F_v - sin(phi) F_h``):
  ``L u x (H_i - G_{i+1}) = I_A alpha + m g (L/2) cos(phi) = K`` (``H_0 = G_{n+1} = 0``).

That is 4n + 1 equations, one of them Lagrange's (they sum to it), so the 4n forces are determined wherever
``sin phi != 0``. The rockers' moments, end to end, give ``sin(phi) H_1,h``, the steps ``sin(phi) (H_{i+1,h} -
H_i,h)`` and ``sin(phi) H_n,h``; with Lagrange's equation they reduce to

    H_i,h = (n + 1 - 2 i) E - m a_h / 2,        E = m g (m L^2 - 2 I_A) cos(phi) / (4 I sin(phi)),

antisymmetric about the row's middle. For n = 1 the ``E`` term drops out and ``H_1,h = m L (alpha sin(phi) +
phi'^2 cos(phi)) / 2`` is bounded through the flat positions (``four_bar``'s formula). For n >= 2 it does not
(``m L^2 - 2 I_A`` is ``m L^2 / 3`` for slender rods): the inner rockers carry two couplers and the outer ones
one, yet all must turn alike, and only horizontal forces along the couplers can even it out, whose lever about
the pivots vanishes as the row lies flat; so the horizontal pin forces grow as ``1 / sin(phi)`` near
``sin phi = 0``, where the constraint Jacobian loses n of its 2n planar rows (the n + 1 degrees of freedom the
IFToMM A02 statement names). Their impulse over a passage stays finite (the ``1 / sin`` is odd about the
crossing). The pivots' forces ON the rockers follow from Newton's law on each: ``F_A,i = m a / 2 + m g v -
H_i + G_{i+1}``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dalembert.reference.closed_form import RigidPendulum


def rod_pivot_inertia(length, mass, radius):
    """Moment (kg m^2) about an end, across the axis, of a solid cylinder of ``length`` (m), ``mass`` (kg) and
    ``radius`` (m): ``Body.cylinder``'s transverse moment plus ``mass (length / 2)^2``."""
    return mass * (3.0 * radius**2 + length**2) / 12.0 + mass * (0.5 * length) ** 2


@dataclass(frozen=True, eq=False)
class ParallelogramChain:
    """The motion and pin forces of ``n`` parallelogram windows in a row (module docstring), in the plane.

    Parameters
    ----------
    n : int — windows (``n + 1`` rockers, ``n`` couplers)
    length : float — every link's length and the ground spacing, ``L`` (m)
    mass : float — every link's mass, ``m`` (kg)
    inertia_pivot : float — a rocker's moment about its pivot, ``I_A`` (kg m^2)
    gravity : float — magnitude of gravity (m/s^2), along ``-v``
    phi0, rate0 : float — the rockers' initial angle from ``h`` towards ``v`` (rad) and rate (rad/s)
    """

    n: int
    length: float
    mass: float
    inertia_pivot: float
    gravity: float
    phi0: float
    rate0: float
    pendulum: RigidPendulum = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "pendulum", RigidPendulum(
            self.equivalent_mass, self.length, self.inertia, self.gravity, self.phi0 + np.pi / 2, self.rate0))

    @property
    def inertia(self):
        """``I = (n+1) I_A + n m L^2`` (kg m^2): the row's moment in ``phi``."""
        return (self.n + 1) * self.inertia_pivot + self.n * self.mass * self.length**2

    @property
    def equivalent_mass(self):
        """``M = (3n+1) m / 2`` (kg): the pendulum's mass at distance ``L`` (``V = M g L sin phi``)."""
        return 0.5 * (3 * self.n + 1) * self.mass

    def angle(self, t):
        """The rockers' angle ``phi`` (rad, continuous), shape of ``t`` (s)."""
        return self.pendulum.angle(t) - np.pi / 2

    def rate(self, t):
        """``phi'`` (rad/s), shape of ``t`` (s)."""
        return self.pendulum.rate(t)

    def acceleration(self, phi):
        """``phi''`` (rad/s^2) at angle ``phi`` (rad): Lagrange's equation."""
        return -self.equivalent_mass * self.gravity * self.length * np.cos(phi) / self.inertia

    def energy(self):
        """Total energy (J), potential zero on the ground line: ``T + V`` at the start."""
        return 0.5 * self.inertia * self.rate0**2 + self.equivalent_mass * self.gravity * self.length * np.sin(self.phi0)

    def tip_acceleration(self, phi, rate):
        """Acceleration of the rockers' tips and of every coupler point: ndarray (k, 2), m/s^2, (h, v)."""
        alpha = self.acceleration(phi)
        c, s = np.cos(phi), np.sin(phi)
        return self.length * np.stack([-alpha * s - rate**2 * c, alpha * c - rate**2 * s], axis=1)

    def pin_forces(self, t):
        """Every pin force at times ``t`` (ndarray (k,), s), planar (h, v) components, N.

        Returns
        -------
        loop : ndarray (k, n, 2) — ``H_i``, ON rocker i at its tip ``B_i`` from coupler i, i = 1..n
        coupler : ndarray (k, n, 2) — ``G_i``, ON coupler i at ``B_{i-1}`` from rocker i-1, i = 1..n
        pivot : ndarray (k, n + 1, 2) — ``F_A,i``, ON rocker i at its ground pivot ``A_i``, i = 0..n
        (for n >= 2 the horizontal components grow as ``1 / sin(phi)`` near the flat positions: module docstring)
        """
        t = np.asarray(t, dtype=float)
        L, m, g, n = self.length, self.mass, self.gravity, self.n
        phi, rate = self.angle(t), self.rate(t)
        a = self.tip_acceleration(phi, rate)
        with np.errstate(divide="ignore", invalid="ignore"):  # E is infinite exactly at sin(phi) = 0
            E = m * g * (m * L**2 - 2.0 * self.inertia_pivot) * np.cos(phi) / (4.0 * self.inertia * np.sin(phi))
        if n == 1:
            E = np.zeros_like(phi)  # its factor n + 1 - 2i is 0: no 0 * inf at the flat positions
        i = np.arange(1, n + 1)
        H = np.empty((len(t), n, 2))
        H[:, :, 0] = (n + 1 - 2 * i)[None, :] * E[:, None] - 0.5 * m * a[:, None, 0]
        H[:, :, 1] = (-0.5 * m * (a[:, 1] + g))[:, None]
        G = np.stack([H[:, :, 0] + m * a[:, None, 0], -H[:, :, 1]], axis=2)
        on_tip = np.zeros((len(t), n + 1, 2))  # what the pins at B_i exert ON rocker i: H_i - G_{i+1}
        on_tip[:, 1:] += H
        on_tip[:, :-1] -= G
        pivot = (0.5 * m * a + np.array([0.0, m * g]))[:, None, :] - on_tip
        return H, G, pivot
