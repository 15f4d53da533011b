"""How far a contact force and the contact's velocity are from the laws of rigid Coulomb contact: the residuals
ContactBench measures (Le Lidec, Jallet, Montaut, Laptev, Schmid, Carpentier, "Contact Models in Robotics: a
Comparative Analysis", IEEE Transactions on Robotics 40, 2024; its criteria section, and its open-source
``contactbench`` library's ``computeSignoriniComplementarity`` / ``computeContactComplementarity``).

Per contact point, with the contact force ``lambda = (lambda_N, lambda_T)`` (normal component along the contact
normal, tangential vector in the plane) and the contact point's velocity ``v = (v_N, v_T)`` (normal positive when
leaving), rigid Coulomb contact is the nonlinear complementarity problem

* Signorini: ``0 <= lambda_N  _|_  v_N >= 0`` — the residual is ContactBench's ``|lambda_N v_N|``;
* Coulomb's cone: ``||lambda_T|| <= mu lambda_N`` — the residual is how far the force lies outside it,
  ``max(0, ||lambda_T|| - mu lambda_N, -lambda_N)`` (the last term: a pulling contact, outside the cone even at
  mu = 0);
* maximum dissipation: a sliding contact's friction is ``lambda_T = -mu lambda_N v_T / ||v_T||`` (the force in
  the cone that dissipates the most power). ContactBench's contact complementarity
  ``|<lambda, v + mu ||v_T|| e_N>|`` holds the Signorini term ``lambda_N v_N`` and the friction term
  ``lambda_T . v_T + mu lambda_N ||v_T||``; the residual here is the friction term alone, ``|lambda_T . v_T +
  mu lambda_N ||v_T|||``: for a force in the cone it is >= 0 (Cauchy-Schwarz) and 0 exactly when the contact
  sticks (``v_T = 0``) or its friction is at the cone's edge opposite the slip.

ContactBench evaluates them on the impulses and the velocity of one time step (N s, m/s); here they take forces
and velocities (N, m/s), so the Signorini and dissipation residuals are powers (W). The harness computes them
from a run's trajectory: the engine's contact force per pair (``dalembert.contact.contact_force``, the extras
``contact_force:<pair>``, where the engine reports one) and the velocity of the contact point at the same sample
(``dalembert.contact.contact_point_velocity``, from the body states), for a geom-plane pair, whose force is taken
at the foot of the geom's centre: exact for a sphere's single point, and for a box face that does not turn (its
points share one velocity). An engine that reports no force has no residual: "not measured", never zero.
``residual_metrics`` makes them ``dalembert.metrics.Metric``s, judged on their largest value over a run.
"""

from __future__ import annotations

import numpy as np

from dalembert import contact
from dalembert.metrics import Metric
from dalembert.tolerance import Tolerance

__all__ = ["RESIDUALS", "signorini", "friction_cone", "max_dissipation", "pair_residuals", "residual_metrics"]

# The residuals' metric names, with what each measures (descriptions, for the store and the reports).
RESIDUALS = {
    "signorini_residual": "ContactBench's Signorini residual |lambda_N v_N| (contact force by the contact point's "
                          "normal velocity), over the pair's normal load",
    "cone_residual": "how far the contact force lies outside Coulomb's cone, max(0, |lambda_T| - mu lambda_N, "
                     "-lambda_N), over the pair's normal load",
    "dissipation_residual": "maximum-dissipation residual |lambda_T . v_T + mu lambda_N |v_T|| (friction short of "
                            "the cone's edge opposite the slip, times the slip), over the pair's normal load",
}


def _split(force, velocity, normal):
    """Normal and tangential parts of a force (n, 3) and a velocity (n, 3) along the unit ``normal`` (3,)."""
    lam_n, v_n = force @ normal, velocity @ normal
    return lam_n, force - np.outer(lam_n, normal), v_n, velocity - np.outer(v_n, normal)


def signorini(lam_n, v_n):
    """ContactBench's Signorini residual ``|lambda_N v_N|`` (W for N and m/s), ndarray like the inputs:
    ``lam_n`` the normal force, ``v_n`` the contact point's normal velocity (positive leaving)."""
    return np.abs(np.asarray(lam_n, dtype=float) * np.asarray(v_n, dtype=float))


def friction_cone(lam_n, lam_t, mu):
    """How far the force lies outside Coulomb's cone of coefficient ``mu`` (N): ``max(0, ||lambda_T|| - mu
    lambda_N, -lambda_N)``; ``lam_n`` (n,), ``lam_t`` (n, 3) or (n, 2), the tangential force."""
    lam_n = np.asarray(lam_n, dtype=float)
    t = np.linalg.norm(np.asarray(lam_t, dtype=float), axis=-1)
    return np.maximum(0.0, np.maximum(t - mu * lam_n, -lam_n))


def max_dissipation(lam_n, lam_t, v_t, mu):
    """The maximum-dissipation residual ``|lambda_T . v_T + mu lambda_N ||v_T|||`` (W for N and m/s), (n,):
    ``lam_t`` and ``v_t`` (n, 3) or (n, 2), the tangential force and slip velocity in the same axes."""
    lam_t, v_t = np.asarray(lam_t, dtype=float), np.asarray(v_t, dtype=float)
    power = np.einsum("ni,ni->n", lam_t, v_t)
    return np.abs(power + mu * np.asarray(lam_n, dtype=float) * np.linalg.norm(v_t, axis=-1))


def pair_residuals(scene, pair, traj):
    """The three residuals of the geom-plane ``pair`` at each sample of ``traj``: dict name (``RESIDUALS``) ->
    ndarray (n,), W, N and W; None when the engine reported no contact force (not measured)."""
    force = contact.contact_force(traj, pair)
    if force is None:
        return None
    normal = contact.geom_and_plane(scene, pair)[1].unit_normal
    velocity = contact.contact_point_velocity(scene, pair, contact.poses_of(traj))
    lam_n, lam_t, v_n, v_t = _split(force, velocity, normal)
    return {"signorini_residual": signorini(lam_n, v_n), "cone_residual": friction_cone(lam_n, lam_t, pair.friction),
            "dissipation_residual": max_dissipation(lam_n, lam_t, v_t, pair.friction)}


def residual_metrics(pair_index, load, tolerances):
    """The residuals of the geom-plane pair ``scene.contacts[pair_index]`` as ``Metric``s, each scaled by ``load``
    (N, the pair's closed-form normal force: the Signorini and dissipation residuals then read as a speed, m/s,
    the cone residual as a fraction of the load) and bounded by ``tolerances[name]`` (a ``Tolerance`` per name of
    ``RESIDUALS``). A run whose engine reported no contact force gets none of them (not measured)."""
    units = {"signorini_residual": "W", "cone_residual": "N", "dissipation_residual": "W"}

    def one(name):
        def series(scene, traj):
            found = pair_residuals(scene, scene.contacts[pair_index], traj)
            return None if found is None else found[name]

        return Metric(name, RESIDUALS[name], units[name], float(load), tolerances[name], series)

    missing = sorted(set(RESIDUALS) - set(tolerances))
    if missing or not all(isinstance(t, Tolerance) for t in tolerances.values()):
        raise ValueError(f"residual_metrics.tolerances: needs a Tolerance for each of {sorted(RESIDUALS)}, "
                         f"missing {missing} — give each its bound and reason")
    return tuple(one(name) for name in RESIDUALS)
