"""Helpers shared by the contact cases: the truth of one free body, the metrics every contact case measures
(penetration depth, slip speed), and the parameter checks a factory's domains cannot say."""

from __future__ import annotations

import numpy as np

from dalembert import contact
from dalembert.metrics import Metric
from dalembert.scene import SceneError
from dalembert.trajectory import BodyStates, Trajectory

__all__ = ["TAGS", "body_truth", "penetration", "slip_speed", "require"]

# Every contact case: out of the default matrix (``case_registry.OUT_OF_DEFAULT``) until more engines map contact.
TAGS = ("contact",)


def body_truth(t, name, position, quaternion, velocity, angular_velocity):
    """A ``Trajectory`` of one body: COM position (n, 3) m, ``q_WB`` (n, 4), COM velocity (n, 3) m/s and angular
    velocity (n, 3) rad/s, all world."""
    return Trajectory(np.asarray(t, dtype=float), {name: BodyStates(position, quaternion, velocity, angular_velocity)})


def penetration(tolerance):
    """The ``penetration`` metric: the deepest interpenetration of any contact pair at each sample (m,
    ``dalembert.contact.depth``), scale 1 m: a rigid contact has none."""
    return Metric("penetration", "deepest interpenetration of the scene's contact pairs (rigid contact: none)", "m",
                  1.0, tolerance, lambda scene, traj: contact.depth(scene, contact.poses_of(traj)))


def slip_speed(scene, traj, pair=0):
    """The slip speed (m/s) of the geom-plane pair ``scene.contacts[pair]`` at each sample of ``traj``, ndarray (n,)
    (``dalembert.contact.slip_velocity``)."""
    return np.linalg.norm(contact.slip_velocity(scene, scene.contacts[pair], contact.poses_of(traj)), axis=-1)


def require(case_name, checks):
    """Raise ``SceneError`` for every ``(ok, "param: what is wrong — the fix")`` in ``checks`` that is not ok."""
    problems = [f"{case_name}.{message}" for ok, message in checks if not ok]
    if problems:
        raise SceneError(f"case {case_name!r}", problems)

