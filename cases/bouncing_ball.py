"""A ball dropped on a level plane, bouncing with Newton's coefficient of restitution: impacts at
t_(k+1) = t_k + 2 e^k sqrt(2 h / g), apexes at e^(2k) h."""

from __future__ import annotations

import numpy as np

from dalembert.case import Case, Tolerance, case
from dalembert.cases._contact import TAGS, body_truth, penetration, require
from dalembert.cases._sampling import sample_times
from dalembert.metrics import Metric, apexes, constant
from dalembert.reference.closed_form import BouncingBall
from dalembert.scene import Body, ContactPair, Geom, Joint, Plane, Scene

POSITION_TOL = Tolerance(1e-2, "m; 1 % of the 1-m drop: an impact 2 ms off moves the ball ~1 cm at its ~4-m/s "
                               "landing speed")
VELOCITY_TOL = Tolerance(0.5, "m/s; ~10 % of the 4.4-m/s landing speed: the velocity jumps at each impact, so a "
                              "sample just after an impact the engine resolves over a few ms differs by a jump")
# The apexes and impacts judged: the first two bounces (a soft contact's error compounds bounce after bounce;
# the first two say how the engine maps restitution).
BOUNCES = 2
APEX_TOL = Tolerance(1e-2, "relative to the drop height; each apex is e^(2k) h, which measures the restitution "
                           "squared: 1 % of h is 4 % of the first apex for e = 0.5")
IMPACT_TOL = Tolerance(2e-3, "s; 2 ms, 0.4 % of the 0.45-s fall: a contact that yields a few mm shifts it so")
PENETRATION_TOL = Tolerance(2e-3, "m; 2 % of the 0.1-m radius, at a 4.4-m/s impact")


@case(tags=(*TAGS, "restitution", "impact"),
      units=dict(height="m", restitution="1", radius="m", mass="kg", g="m/s^2", t_final="s", sample_interval="s"),
      positive=("height", "radius", "mass", "g", "sample_interval"))
def bouncing_ball(height=1.0, restitution=0.5, radius=0.1, mass=1.0, g=9.81, t_final=1.3, sample_interval=0.001):
    """A solid ball dropped from rest with its lowest point ``height`` above a level plane, frictionless, bouncing
    with Newton's coefficient ``restitution``: impacts at ``t_1 = sqrt(2 h / g)``, then every ``2 e^k u_1 / g``,
    apexes ``e^(2k) h``. The default horizon covers two bounces, with room for an engine that bounces higher.
    Judged on the motion, the first two apex heights and impact times, and the penetration.
    """
    require("bouncing_ball", [(0.0 <= restitution <= 1.0, f"restitution: must lie in [0, 1], got {restitution!r} — "
                                                          "Newton's coefficient (0 plastic, 1 elastic)")])
    scene = Scene(
        "bouncing_ball", bodies=[Body("ball", mass, np.eye(3) * 0.4 * mass * radius**2)],
        joints=[Joint("free", "world", "ball", q0=[0.0, 0.0, height + radius, 1.0, 0.0, 0.0, 0.0], v0=[0.0] * 6)],
        gravity=[0.0, 0.0, -g], geoms=[Geom("ball", "sphere", (radius,))], planes=[Plane("ground")],
        contacts=[ContactPair("geom_ball", "ground", 0.0, restitution=restitution)])
    exact = BouncingBall(height, restitution, g)
    times = sample_times(t_final, sample_interval, "bouncing_ball")

    def truth(t):
        t = np.asarray(t, dtype=float)
        n, zero = len(t), np.zeros((len(t), 3))
        z, w = exact.height_at(t), exact.vertical_velocity(t)
        position = np.stack([np.zeros(n), np.zeros(n), z + radius], -1)
        velocity = np.stack([np.zeros(n), np.zeros(n), w], -1)
        return body_truth(t, "ball", position, np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)), velocity, zero)

    def lowest(traj):
        return traj.bodies["ball"].position[:, 2] - radius

    def events(traj, count):
        """The first ``count`` impacts and the apexes after them. An impact is where the lowest point, on its free
        flight from the last sample before it touches (or turns, for a rigid contact between samples), reaches
        the plane: ``z + w tau - g tau^2 / 2 = 0`` (exact for the free flight)."""
        t, z, w = traj.t, lowest(traj), traj.bodies["ball"].velocity[:, 2]
        hits, tops, k = [], [], 1
        for _ in range(count):
            while k < len(t) - 1 and not (z[k] <= 0.0 or (z[k] < z[k - 1] and z[k] <= z[k + 1])):
                k += 1
            j = k - 1  # the last sample of the free flight
            if k >= len(t) - 1 or z[j] < 0.0:
                break
            hits.append(t[j] + (w[j] + np.sqrt(w[j] ** 2 + 2.0 * g * z[j])) / g)
            after = apexes(t, z, hits[-1])
            if not after:
                break
            tops.append(after[0][1])
            k = int(np.searchsorted(t, after[0][0])) + 1
        return hits, tops

    counted = min(BOUNCES, len(exact.impacts(t_final)))
    true_hits = exact.impacts(t_final)[:counted]
    true_tops = exact.apex_heights(counted)
    apex_times = exact.apex_times(counted)
    metrics = [penetration(PENETRATION_TOL)]
    if counted:
        def impact_error(scene, traj):
            hits, _ = events(traj, counted)
            missing = [t_final - h for h in true_hits[len(hits):]]  # an impact not found is at least this late
            return constant(traj, max([abs(a - b) for a, b in zip(hits, true_hits)] + missing))

        metrics.append(Metric("impact_time_error", f"largest error of the first {counted} impact times (the lowest "
                                                   "point reaching the plane), against the closed form's (s)", "s",
                              1.0, IMPACT_TOL, impact_error))
    counted_tops = int(np.sum(apex_times < t_final))
    if counted_tops:
        def apex_error(scene, traj):
            _, tops = events(traj, counted_tops)
            tops = list(tops) + [0.0] * (counted_tops - len(tops))  # a bounce not found: no apex
            return constant(traj, max(abs(a - b) for a, b in zip(tops, true_tops[:counted_tops])))

        metrics.append(Metric("apex_error", f"largest error of the first {counted_tops} apex heights e^(2k) h, "
                                            "relative to the drop height", "m", height, APEX_TOL, apex_error,
                              headline=True))
    return Case("bouncing_ball", scene, t_final, times, exact=truth,
                tolerances=dict(position=POSITION_TOL, velocity=VELOCITY_TOL), invariants=tuple(metrics))
