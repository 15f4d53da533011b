"""Linear spring-dampers (``dalembert.scene.Spring``) as forces on body states: length, rate, tension,
the wrench on each body, stored energy and dissipated power.

A spring joins a point ``x_a`` of body a (``point_a``, in a's body frame, or the world's when a is the
world) to a point ``x_b`` of body b. With ``d = x_b - x_a``, its length ``l = |d|``, the unit vector
``e = d / l`` and the rate ``l' = e . (xd_b - xd_a)`` (the points' velocities), the tension is

    s = stiffness (l - rest_length) + damping l'                                (N, > 0 pulls)

and the spring exerts ``-s e`` ON body b at ``x_b`` and ``+s e`` on body a at ``x_a``. The elastic
part derives from the potential ``V = 1/2 stiffness (l - rest_length)^2`` (J); the damper's part
dissipates the power ``damping l'^2`` (W), so that on a motion

    kinetic + potential energy - work of the loads + dissipated energy = constant

(``dalembert.invariants.energy_balance``). Everything here is a function of the two bodies' states in
world terms, like ``dalembert.closure``: ``R`` (3, 3) ``R_WB``, ``p`` (3,) COM position (m), ``v``
(3,) COM velocity (m/s), ``w`` (3,) angular velocity ``w_WB_W`` (rad/s), so the reference solver and the
invariants computed from any engine's trajectory share one definition.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert import spatial

__all__ = ["MIN_LENGTH", "SpringState", "state", "wrenches", "wrenches_stacked", "potential_energy", "dissipated_power"]

# A spring whose points are closer than this at the initial state is refused (``Scene.validate``): the
# direction of its force is the line between them, undefined when they coincide; 1e-9 m is far below
# any attachment a mechanism has and far above the roundoff of a computed point (~1e-16 m).
MIN_LENGTH = 1e-9


@dataclass(frozen=True, eq=False)
class SpringState:
    """A spring at one state of its two bodies.

    Attributes
    ----------
    length : float — ``l`` (m)
    rate : float — ``l'`` (m/s)
    tension : float — ``stiffness (l - rest_length) + damping l'`` (N; positive pulls the points together)
    force_b : ndarray (3,) — force ON body b at its point, ``-tension e`` (N, world); body a gets ``-force_b``
    lever_a, lever_b : ndarray (3,) — each body's COM to its point (m, world)
    """

    length: float
    rate: float
    tension: float
    force_b: np.ndarray
    lever_a: np.ndarray
    lever_b: np.ndarray


def state(spring, A, B):
    """The ``SpringState`` of ``spring`` at body states ``A`` (of ``spring.body_a``) and ``B`` (of
    ``spring.body_b``): dicts with ``R`` (3, 3), ``p``, ``v``, ``w`` (3,), world (``closure.world_state()``
    for the world)."""
    rho_a = A["R"] @ np.asarray(spring.point_a, dtype=float)
    rho_b = B["R"] @ np.asarray(spring.point_b, dtype=float)
    d = B["p"] + rho_b - A["p"] - rho_a
    length = float(np.linalg.norm(d))
    e = d / length if length > 0.0 else np.zeros(3)
    rate = float(e @ (B["v"] + spatial.cross(B["w"], rho_b) - A["v"] - spatial.cross(A["w"], rho_a)))
    tension = spring.stiffness * (length - spring.rest_length) + spring.damping * rate
    return SpringState(length, rate, tension, -tension * e, rho_a, rho_b)


def wrenches(springs, states):
    """The springs' resultant wrench on each body: dict body name -> ``(F, tau)``, the force (N) and its
    moment about the body's COM (N m), both (3,) world; the world's share is left out.

    Parameters
    ----------
    springs : sequence of Spring
    states : dict body name -> state dict (``R``, ``p``, ``v``, ``w``, world), ``"world"`` included
    """
    out = {}
    for sp in springs:
        s = state(sp, states[sp.body_a], states[sp.body_b])
        for body, force, lever in ((sp.body_a, -s.force_b, s.lever_a), (sp.body_b, s.force_b, s.lever_b)):
            if body == "world":
                continue
            F, tau = out.get(body, (np.zeros(3), np.zeros(3)))
            out[body] = (F + force, tau + spatial.cross(lever, force))
    return out


def wrenches_stacked(springs, states):
    """``wrenches`` at m states at once: each state dict's arrays with a leading sample axis (``R`` (m, 3, 3),
    ``p``, ``v``, ``w`` (m, 3)); dict body name -> ``(F, tau)``, each (m, 3), world, the world's share left out.
    The same terms as ``state`` and ``wrenches`` (a zero-length spring pulls nowhere, as there)."""
    out = {}
    for sp in springs:
        A, B = states[sp.body_a], states[sp.body_b]
        rho_a = A["R"] @ np.asarray(sp.point_a, dtype=float)
        rho_b = B["R"] @ np.asarray(sp.point_b, dtype=float)
        d = B["p"] + rho_b - A["p"] - rho_a
        length = np.linalg.norm(d, axis=-1, keepdims=True)
        e = np.divide(d, length, out=np.zeros_like(d), where=length > 0.0)
        rate = np.sum(e * (B["v"] + spatial.cross(B["w"], rho_b) - A["v"] - spatial.cross(A["w"], rho_a)),
                      axis=-1, keepdims=True)
        force_b = -(sp.stiffness * (length - sp.rest_length) + sp.damping * rate) * e
        for body, force, lever in ((sp.body_a, -force_b, rho_a), (sp.body_b, force_b, rho_b)):
            if body == "world":
                continue
            F, tau = out.get(body, (0.0, 0.0))
            out[body] = (F + force, tau + spatial.cross(lever, force))
    return out


def potential_energy(spring, length):
    """``1/2 stiffness (length - rest_length)^2`` (J); ``length`` (m) a float or an ndarray."""
    return 0.5 * spring.stiffness * (np.asarray(length) - spring.rest_length) ** 2


def dissipated_power(spring, rate):
    """``damping rate^2`` (W, >= 0): the power the damper takes out of the motion; ``rate`` (m/s)."""
    return spring.damping * np.asarray(rate) ** 2
