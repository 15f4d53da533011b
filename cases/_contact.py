"""Helpers shared by the contact cases: the truth of one free body (with its contact force where the closed form
gives one), the metrics every contact case measures (penetration depth, slip speed, the normal force where an
engine reports contact forces), and the parameter checks a factory's domains cannot say."""

from __future__ import annotations

import numpy as np

from dalembert import contact
from dalembert.metrics import Metric
from dalembert.scene import SceneError
from dalembert.trajectory import BodyStates, Trajectory

__all__ = ["TAGS", "NORMAL_FORCE_GRACE", "body_truth", "penetration", "normal_force_error", "slip_speed", "require"]

# Every contact case: out of the default matrix (``case_registry.OUT_OF_DEFAULT``) until more engines map contact.
TAGS = ("contact",)
# The normal force is judged from this time on (s): a compliant contact (MuJoCo's, Drake's, Exudyn's) starts at zero
# penetration, so carries nothing at t = 0, and settles to its load within a few time constants (5 of MuJoCo's
# default 0.02 s: its block on the incline is within 0.1 % of m g cos(angle) by 0.05 s at dt = 1e-3).
NORMAL_FORCE_GRACE = 0.1


def body_truth(t, name, position, quaternion, velocity, angular_velocity, contact_forces=None):
    """A ``Trajectory`` of one body: COM position (n, 3) m, ``q_WB`` (n, 4), COM velocity (n, 3) m/s and angular
    velocity (n, 3) rad/s, all world; ``contact_forces``: dict pair name -> the closed form's contact force ON the
    pair's subject (n, 3), N, world (``dalembert.contact``), kept as the extras ``contact_force:<pair>``."""
    extras = {contact.FORCE_PREFIX + pair: np.asarray(f, dtype=float) for pair, f in (contact_forces or {}).items()}
    return Trajectory(np.asarray(t, dtype=float), {name: BodyStates(position, quaternion, velocity, angular_velocity)},
                      extras=extras)


def penetration(tolerance):
    """The ``penetration`` metric: the deepest interpenetration of any contact pair at each sample (m,
    ``dalembert.contact.depth``), scale 1 m: a rigid contact has none."""
    return Metric("penetration", "deepest interpenetration of the scene's contact pairs (rigid contact: none)", "m",
                  1.0, tolerance, lambda scene, traj: contact.depth(scene, contact.poses_of(traj)))


def normal_force_error(load, tolerance, pair=0):
    """The ``normal_force_error`` metric: the normal force of ``scene.contacts[pair]`` as the engine reports it
    (``dalembert.contact.normal_force``) less the closed form's ``load`` (N, constant), from
    ``NORMAL_FORCE_GRACE`` on (0 before), relative to ``load``; not measured on an engine that reports no contact
    force."""
    def series(scene, traj):
        f = contact.normal_force(scene, scene.contacts[pair], traj)
        return None if f is None else np.where(traj.t >= NORMAL_FORCE_GRACE, f - load, 0.0)

    return Metric("normal_force_error", f"the contact's normal force as the engine reports it, against the closed "
                                        f"form's {load:.4g} N, from {NORMAL_FORCE_GRACE:g} s on (relative to it)",
                  "N", float(load), tolerance, series)


def slip_speed(scene, traj, pair=0):
    """The slip speed (m/s) of the geom-plane pair ``scene.contacts[pair]`` at each sample of ``traj``, ndarray (n,)
    (``dalembert.contact.slip_velocity``)."""
    return np.linalg.norm(contact.slip_velocity(scene, scene.contacts[pair], contact.poses_of(traj)), axis=-1)


def require(case_name, checks):
    """Raise ``SceneError`` for every ``(ok, "param: what is wrong — the fix")`` in ``checks`` that is not ok."""
    problems = [f"{case_name}.{message}" for ok, message in checks if not ok]
    if problems:
        raise SceneError(f"case {case_name!r}", problems)

