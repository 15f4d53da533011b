"""The probes' scenes: small systems built in code whose motion has a known answer (not the registered cases,
which may change), and one scene per effect tag for the refusal probe.

Every number here is chosen so that the answer is exact or closed form: a sphere-inertia body keeps its spin, a
spin about a principal axis keeps its rate, a constant force gives a constant acceleration, a rod on a hinge
swings with the pendulum's elliptic-integral period.
"""

from __future__ import annotations

import math

import numpy as np

from dalembert import spatial
from dalembert.collision import ContactPair, Geom, Plane
from dalembert.kinds import CONTACT_EFFECTS, EFFECTS, LOOP_EFFECTS, SPRING_EFFECTS
from dalembert.scene import Body, Joint, Load, Loop, Scene, Spring

__all__ = ["ALL_EFFECTS", "STANDARD_G", "ODD_GRAVITY", "spinning_sphere", "tilted_spin", "asymmetric_body",
           "pushed_body", "twisted_body", "falling_body", "passing_bodies", "Pendulum", "scene_needing"]

# Every effect tag a scene can call for: what the refusal probe asks an adapter about.
ALL_EFFECTS = EFFECTS | LOOP_EFFECTS | SPRING_EFFECTS | CONTACT_EFFECTS
STANDARD_G = 9.81  # m/s^2, the pendulum's gravity
# A gravity no engine has as its default, with a component on every axis: a hard-coded -9.81 z, a flipped
# sign or swapped axes all show (m/s^2, world).
ODD_GRAVITY = (1.0, -2.0, -8.0)

# An asymmetric inertia tensor (kg m^2) with off-diagonal terms in its body frame: principal moments
# 0.05, 0.10, 0.13 about axes turned 0.6 rad about (1, 2, 3) from B's. An engine that keeps the diagonal only,
# or takes an inertia of its own, moves it differently.
_PRINCIPAL = np.array([0.05, 0.10, 0.13])
_Q_BP = spatial.quat_to_matrix(spatial.quat_from_axis_angle(np.array([1.0, 2.0, 3.0]), 0.6))
ASYMMETRIC_INERTIA = _Q_BP @ np.diag(_PRINCIPAL) @ _Q_BP.T
# An attitude that is nowhere near the identity, so that a quaternion read in the wrong order or an angular
# velocity in the wrong axes cannot pass (0.9 rad about (1, -2, 0.5)).
TILT = tuple(spatial.quat_from_axis_angle(np.array([1.0, -2.0, 0.5]), 0.9))


def _free(body, position=(0.0, 0.0, 0.0), quat=spatial.IDENTITY_QUAT, v=(0.0, 0.0, 0.0), w_B=(0.0, 0.0, 0.0)):
    return Joint("free", "world", body, q0=(*position, *quat), v0=(*v, *w_B))


def spinning_sphere():
    """Two sphere-inertia bodies (2 kg, 0.02 kg m^2), no gravity: ``spinner`` spins at (1, 2, 3) rad/s in place,
    ``drifter`` drifts at (0.3, -0.2, 0.1) m/s without turning. Each keeps its velocity, and its kinetic energy
    (0.5 m |v|^2, 0.5 I |w|^2), exactly and in every coordinate: a spin and a drift apart, neither couples into the
    other in an engine that carries the linear velocity in body axes."""
    bodies = [Body("spinner", 2.0, np.eye(3) * 0.02), Body("drifter", 2.0, np.eye(3) * 0.02)]
    return Scene("probe_spinning_sphere", bodies,
                 [_free("spinner", (0.0, 0.0, 1.0), TILT, w_B=(1.0, 2.0, 3.0)),
                  _free("drifter", (0.0, 1.0, 0.0), TILT, v=(0.3, -0.2, 0.1))], (0.0, 0.0, 0.0))


def tilted_spin(rate=4.0):
    """An axisymmetric body (moments 0.2, 0.2, 0.35 kg m^2) at attitude ``TILT`` spinning at ``rate`` rad/s about
    its symmetry axis z (a principal axis): ``w_WB_B`` stays (0, 0, rate), ``w_WB_W`` stays ``R(TILT) (0, 0, rate)``
    and ``q(t) = TILT * exp((0, 0, rate t))``. No gravity."""
    body = Body("top", 1.0, np.diag([0.2, 0.2, 0.35]))
    return Scene("probe_tilted_spin", [body], [_free("top", (0.0, 0.0, 0.0), TILT, w_B=(0.0, 0.0, rate))],
                 (0.0, 0.0, 0.0))


def asymmetric_body(w_B=(1.0, -2.0, 3.0)):
    """The asymmetric body (1.5 kg, ``ASYMMETRIC_INERTIA``) at the identity attitude spinning at ``w_B`` rad/s, no
    load, no gravity: Euler's equations give ``w' = I^-1 ((I w) x w)`` at t = 0."""
    body = Body("body", 1.5, ASYMMETRIC_INERTIA)
    return Scene("probe_asymmetric_body", [body], [_free("body", w_B=w_B)], (0.0, 0.0, 0.0))


def pushed_body(force=(0.6, -0.3, 0.9)):
    """A 2 kg body at rest under a constant world force ``force`` (N) at its COM, no gravity: ``a = F / m``."""
    body = Body("body", 2.0, ASYMMETRIC_INERTIA)
    return Scene("probe_pushed_body", [body], [_free("body")], (0.0, 0.0, 0.0),
                 [Load("body", "force", force, "world")])


def twisted_body(torque=(0.02, -0.05, 0.03)):
    """The asymmetric body at rest at the identity attitude under a constant world torque ``torque`` (N m), no
    gravity: ``w'(0) = I^-1 torque``."""
    body = Body("body", 1.5, ASYMMETRIC_INERTIA)
    return Scene("probe_twisted_body", [body], [_free("body")], (0.0, 0.0, 0.0),
                 [Load("body", "torque", torque, "world")])


def falling_body():
    """A body at rest under ``ODD_GRAVITY``: its COM velocity is ``g t``, exactly, for any consistent integrator."""
    body = Body("body", 1.0, np.diag([0.1, 0.2, 0.25]))
    return Scene("probe_falling_body", [body], [_free("body")], ODD_GRAVITY)


def passing_bodies(geoms=True, speed=1.0, gap=0.2):
    """Two 1 kg bodies ``2 gap`` m apart on the x axis flying at each other at ``speed`` m/s, no gravity; with
    ``geoms``, each carries a 0.05 m sphere, and no ``ContactPair`` names them: they pass through each other, each
    keeping its velocity."""
    bodies = [Body("a", 1.0, np.eye(3) * 1e-3), Body("b", 1.0, np.eye(3) * 1e-3)]
    joints = [_free("a", (-gap, 0.0, 0.0), v=(speed, 0.0, 0.0)), _free("b", (gap, 0.0, 0.0), v=(-speed, 0.0, 0.0))]
    shapes = [Geom("a", "sphere", (0.05,)), Geom("b", "sphere", (0.05,))] if geoms else []
    return Scene("probe_passing_bodies", bodies, joints, (0.0, 0.0, 0.0), geoms=shapes)


class Pendulum:
    """A uniform rod (``mass`` kg, ``length`` m, radius 0.01 m) hung from the world at (0, 0, 1) m by a revolute
    joint whose frame is turned 90 deg about z: its axis (1, 0, 0) in the joint frame is the world's y axis.
    The COM hangs ``length / 2`` below the pivot; the child joint frame is turned 30 deg about the rod's axis.

    Known answers (rigid-body pendulum, any mechanics text; e.g. Goldstein, Classical Mechanics, 3rd ed., 1.3):
    about the pivot its moment is ``J = I_c + m l^2`` (``l = length / 2``); released at rest at ``theta0`` it
    starts with the angular acceleration ``-m g l sin(theta0) / J`` about ``axis_W``, and half its period is
    ``2 K(sin^2(theta0 / 2)) sqrt(J / (m g l))`` (K: the complete elliptic integral of the first kind, in the
    parameter ``m = k^2``). Hanging at rest, the joint holds the rod up with ``m g`` (N, world +z) on the child.
    """

    def __init__(self, theta0, mass=1.0, length=0.2):
        self.theta0, self.mass, self.length = float(theta0), float(mass), float(length)
        self.body = Body.cylinder("rod", self.mass, self.length, 0.01, axis=2)
        self.arm = 0.5 * self.length  # pivot to COM, m
        turn = tuple(spatial.quat_from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.5 * math.pi))
        # the child joint frame turned 30 deg about the rod's own axis: the rod's attitude shows it, its motion
        # (axisymmetric about that axis) does not
        twist = tuple(spatial.quat_from_axis_angle(np.array([0.0, 0.0, 1.0]), math.pi / 6.0))
        self.joint = Joint("revolute", "world", "rod", q0=(self.theta0,), v0=(0.0,), axis=(1.0, 0.0, 0.0),
                           parent_point=(0.0, 0.0, 1.0), parent_quat=turn, child_point=(0.0, 0.0, self.arm),
                           child_quat=twist)
        self.axis_W = spatial.quat_to_matrix(np.array(turn)) @ np.array([1.0, 0.0, 0.0])
        # the rod's moment about the joint axis: the cylinder's transverse moment (its axis is z, the joint's
        # axis lies in its xy plane) plus the parallel-axis term
        self.J = float(self.body.inertia_matrix[0, 0]) + self.mass * self.arm**2

    @property
    def scene(self):
        return Scene("probe_pendulum", [self.body], [self.joint], (0.0, 0.0, -STANDARD_G))

    @property
    def acceleration0(self):
        """The angular acceleration at release about ``axis_W`` (rad/s^2)."""
        return -self.mass * STANDARD_G * self.arm * math.sin(self.theta0) / self.J

    @property
    def half_period(self):
        """Half the period of the swing (s), exact for any amplitude."""
        from scipy.special import ellipk

        return 2.0 * float(ellipk(math.sin(0.5 * self.theta0) ** 2)) * math.sqrt(self.J /
                                                                                (self.mass * STANDARD_G * self.arm))


def _hinged(extra=(), loops=(), springs=(), gravity=(0.0, 0.0, -STANDARD_G)):
    p = Pendulum(0.3)
    return Scene("probe_needs", [p.body, *[b for b, _ in extra]], [p.joint, *[j for _, j in extra]], gravity,
                 loops=loops, springs=springs)


def scene_needing(tag):
    """A small valid scene that calls for the effect ``tag`` (one of ``ALL_EFFECTS``), for the refusal probe."""
    free = Body("body", 1.0, np.eye(3) * 0.01)
    if tag == "gravity":
        return falling_body()
    if tag == "joint:free":
        return spinning_sphere()
    if tag.startswith("joint:"):
        kind = tag.split(":")[1]
        q0, v0 = {"revolute": ((0.3,), (0.0,)), "prismatic": ((0.1,), (0.0,)), "ball": ((1.0, 0.0, 0.0, 0.0),
                                                                                        (0.0, 0.0, 0.0)),
                  "weld": ((), ())}[kind]
        axis = (0.0, 1.0, 0.0) if kind in ("revolute", "prismatic") else None
        return Scene("probe_needs", [free], [Joint(kind, "world", "body", q0, v0, axis, child_point=(0.0, 0.0, 0.1))],
                     (0.0, 0.0, 0.0))
    if tag.startswith("load:"):
        frame, kind = tag.split(":")[1].split("_")
        return Scene("probe_needs", [free], [_free("body")], (0.0, 0.0, 0.0),
                     [Load("body", kind, (0.0, 0.1, 0.0), "body" if frame == "follower" else "world")])
    if tag in LOOP_EFFECTS:  # a loop at the hinge's own pivot: closed at the start, as the scene requires
        p = Pendulum(0.3)
        kind = tag.split(":")[1]
        loop = Loop(kind, "world", "rod", point_a=p.joint.parent_point, point_b=p.joint.child_point,
                    quat_a=p.joint.parent_quat, quat_b=p.joint.child_quat, axis=p.joint.axis if kind == "revolute" else None)
        if kind == "distance":
            loop = Loop(kind, "world", "rod", point_a=(0.0, 0.0, 1.5), point_b=(0.0, 0.0, 0.0),
                        length=float(np.linalg.norm(np.array([0.0, 0.0, 1.5]) - _com(p))))
        return _hinged(loops=[loop])
    if tag in SPRING_EFFECTS:
        return Scene("probe_needs", [free], [_free("body")], (0.0, 0.0, 0.0),
                     springs=[Spring("world", "body", (0.0, 0.0, 1.0), stiffness=10.0, rest_length=0.5)])
    if tag in CONTACT_EFFECTS:
        ball = Body("ball", 1.0, np.eye(3) * 4e-3)
        pair = ContactPair("ball", "ground", friction=0.5 if tag == "friction" else 0.0,
                           restitution=0.5 if tag == "restitution" else None)
        return Scene("probe_needs", [ball], [_free("ball", (0.0, 0.0, 0.2))], (0.0, 0.0, -STANDARD_G),
                     geoms=[Geom("ball", "sphere", (0.1,), name="ball")], planes=[Plane()], contacts=[pair])
    raise ValueError(f"tag: no probe scene needs {tag!r} — one of {', '.join(sorted(ALL_EFFECTS))}")


def _com(p):
    """The pendulum's COM (m, world) at its ``theta0``."""
    return spatial.initial_body_states(p.scene)["rod"]["p"]
