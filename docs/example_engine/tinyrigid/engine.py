"""A small rigid-body engine in numpy: free bodies and bodies hinged to the world, stepped by semi-implicit Euler.

It knows nothing of dalembert, and has the conventions of engines met in practice: quaternions scalar LAST
(x, y, z, w), velocities and angular velocities in WORLD axes, a hinge given by a pivot and an axis in the
world, and knobs an engine may turn on by default (velocity damping, a motor holding each hinge, collision
spheres on every body), which the adapter must turn off.

Units: SI (m, kg, s, rad, N, N m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Load", "Hinge", "Model", "State", "Simulation", "quat_multiply", "quat_from_rotvec", "quat_to_matrix"]


def quat_multiply(a, b):
    """Product ``a b`` of quaternions (x, y, z, w), shape (4,)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz])


def quat_from_rotvec(r):
    """The quaternion (x, y, z, w) of the rotation vector ``r`` (3,), rad."""
    angle = float(np.linalg.norm(r))
    half = np.sinc(angle / (2.0 * np.pi)) * 0.5  # sin(angle / 2) / angle, smooth at 0
    return np.array([*(half * np.asarray(r)), np.cos(0.5 * angle)])


def quat_to_matrix(q):
    """The rotation matrix (3, 3) of the quaternion (x, y, z, w) ``q`` (normalised first)."""
    x, y, z, w = np.asarray(q) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


@dataclass(frozen=True)
class Load:
    """A constant force (N) at ``point`` (m, body axes, from the COM) and torque (N m) on body ``body`` (index);
    ``follower``: both given in body axes (they turn with the body), else in world axes."""

    body: int
    force: np.ndarray
    torque: np.ndarray
    follower: bool = False
    point: tuple = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Hinge:
    """Body ``body`` (index) turns about the world ``axis`` (unit, 3) through the world point ``pivot`` (m)."""

    body: int
    pivot: np.ndarray
    axis: np.ndarray


@dataclass(frozen=True)
class Model:
    """Bodies, their hinges and loads, gravity, and the engine's knobs (defaults: all off).

    mass (n,) kg; inertia (n, 3, 3) about the COM in body axes, kg m^2; gravity (3,) m/s^2, world;
    linear_damping, angular_damping: 1/s, velocities scaled by (1 - damping h) each step;
    hinge_stiffness (N m/rad), hinge_damping (N m s/rad): a motor holding each hinge at its start angle;
    collision_radius (m): every body a sphere pushing every other away (0: none), contact_stiffness N/m.
    """

    mass: np.ndarray
    inertia: np.ndarray
    gravity: np.ndarray
    hinges: tuple = ()
    loads: tuple = ()
    linear_damping: float = 0.0
    angular_damping: float = 0.0
    hinge_stiffness: float = 0.0
    hinge_damping: float = 0.0
    collision_radius: float = 0.0
    contact_stiffness: float = 1e4


@dataclass
class State:
    """COM positions p (n, 3), quaternions q (n, 4) x, y, z, w, COM velocities v (n, 3) and angular velocities
    w (n, 3), world axes; each hinge's angle from its start (rad) and rate (rad/s), by body index (n,)."""

    p: np.ndarray
    q: np.ndarray
    v: np.ndarray
    w: np.ndarray
    angle: np.ndarray
    rate: np.ndarray

    def copy(self):
        return State(*(np.array(a, dtype=float) for a in (self.p, self.q, self.v, self.w, self.angle, self.rate)))


class Simulation:
    """A model stepped from an initial state (copied: the caller's is never changed)."""

    def __init__(self, model, initial):
        self.model, self.state = model, initial.copy()
        self.hinged = {h.body: h for h in model.hinges}
        self.q_start = initial.q.copy()  # a hinged body's attitude at angle 0
        self.r_start = initial.p.copy() - np.array([self.hinged[i].pivot if i in self.hinged else np.zeros(3)
                                                    for i in range(len(model.mass))])

    def wrenches(self, state):
        """Force (n, 3) N and torque about the COM (n, 3) N m on every body, world axes: gravity, loads, contact."""
        m = self.model
        force = m.mass[:, None] * m.gravity[None, :]
        torque = np.zeros_like(force)
        for load in m.loads:
            R = quat_to_matrix(state.q[load.body])
            f, t = (R @ load.force, R @ load.torque) if load.follower else (load.force, load.torque)
            force[load.body] += f
            torque[load.body] += t + np.cross(R @ np.asarray(load.point), f)
        if m.collision_radius > 0.0:
            for i in range(len(m.mass)):
                for j in range(i + 1, len(m.mass)):
                    d = state.p[j] - state.p[i]
                    gap = float(np.linalg.norm(d))
                    if 0.0 < gap < 2.0 * m.collision_radius:
                        push = m.contact_stiffness * (2.0 * m.collision_radius - gap) * d / gap
                        force[i] -= push
                        force[j] += push
        return force, torque

    def hinge_acceleration(self, state, i, force, torque):
        """Angular acceleration (rad/s^2) of hinged body ``i`` about its axis, and its moment J (kg m^2)."""
        m, h = self.model, self.hinged[i]
        R = quat_to_matrix(state.q[i])
        r = state.p[i] - h.pivot
        inertia = R @ m.inertia[i] @ R.T + m.mass[i] * (r @ r * np.eye(3) - np.outer(r, r))
        J = float(h.axis @ inertia @ h.axis)
        drive = h.axis @ (torque[i] + np.cross(r, force[i]))
        drive -= m.hinge_stiffness * state.angle[i] + m.hinge_damping * state.rate[i]
        return drive / J, J

    def step(self, dt):
        """One semi-implicit Euler step of ``dt`` s: velocities from the forces, then positions from them."""
        m, s = self.model, self.state
        force, torque = self.wrenches(s)
        for i in range(len(m.mass)):
            if i in self.hinged:
                h = self.hinged[i]
                s.rate[i] += dt * self.hinge_acceleration(s, i, force, torque)[0]
                s.rate[i] *= 1.0 - m.angular_damping * dt
                s.angle[i] += dt * s.rate[i]
                turn = h.axis * s.angle[i]
                s.q[i] = quat_multiply(quat_from_rotvec(turn), self.q_start[i])
                r = quat_to_matrix(quat_from_rotvec(turn)) @ self.r_start[i]
                s.p[i], s.w[i] = h.pivot + r, h.axis * s.rate[i]
                s.v[i] = np.cross(s.w[i], r)
                continue
            s.v[i] += dt * force[i] / m.mass[i]
            s.v[i] *= 1.0 - m.linear_damping * dt
            s.p[i] += dt * s.v[i]
            R = quat_to_matrix(s.q[i])
            inertia = R @ m.inertia[i] @ R.T
            s.w[i] += dt * np.linalg.solve(inertia, torque[i] - np.cross(s.w[i], inertia @ s.w[i]))
            s.w[i] *= 1.0 - m.angular_damping * dt
            s.q[i] = quat_multiply(quat_from_rotvec(s.w[i] * dt), s.q[i])
            s.q[i] /= np.linalg.norm(s.q[i])

    def reaction(self, state, i):
        """The force (N, world) hinge ``i`` exerts on its body at ``state``: m a_COM minus every other force."""
        force, torque = self.wrenches(state)
        h = self.hinged[i]
        acc = self.hinge_acceleration(state, i, force, torque)[0]
        r = state.p[i] - h.pivot
        a_com = acc * np.cross(h.axis, r) + state.rate[i] ** 2 * np.cross(h.axis, np.cross(h.axis, r))
        return self.model.mass[i] * a_com - force[i]
