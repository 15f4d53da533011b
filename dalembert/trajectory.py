"""The one common output of every engine, in body terms: ``Trajectory``.

Column naming of the CSV/flat form (one row per sample time and body):
``t, body, x, y, z, qw, qx, qy, qz, vx, vy, vz, wx, wy, wz`` — COM position in
world (m), attitude ``q_WB`` scalar first, COM velocity in world (m/s),
angular velocity ``w_WB_W`` in world (rad/s); numbers at full double
precision (17 significant digits: round-trip exact).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field

import numpy as np

from dalembert import spatial

__all__ = ["BodyStates", "JointStates", "Trajectory", "CSV_COLUMNS", "write_csv", "read_csv"]

CSV_COLUMNS = ("t", "body", "x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz")


def _arr(x, shape_tail, n, what):
    a = np.ascontiguousarray(x, dtype=float)
    if a.shape != (n,) + shape_tail:
        raise ValueError(f"{what}: expected shape {(n,) + shape_tail}, got {a.shape}")
    return a


@dataclass(frozen=True, eq=False)
class BodyStates:
    """Sampled states of one body.

    Attributes
    ----------
    position : ndarray (n, 3) — COM in world, m (``p_WB``)
    quaternion : ndarray (n, 4) — ``q_WB`` scalar first, as the engine produced it
        (not renormalized: norm drift is an observable)
    velocity : ndarray (n, 3) — COM velocity in world, m/s
    angular_velocity : ndarray (n, 3) — ``w_WB_W``, world, rad/s
    rotation : ndarray (n, 3, 3) or None — ``R_WB`` when the engine's own attitude
        is a matrix (its orthonormality drift is then measured from it)
    """

    position: np.ndarray
    quaternion: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    rotation: np.ndarray | None = None

    def check(self, n, name):
        for f, tail in (("position", (3,)), ("quaternion", (4,)), ("velocity", (3,)), ("angular_velocity", (3,))):
            object.__setattr__(self, f, _arr(getattr(self, f), tail, n, f"bodies[{name!r}].{f}"))
        if self.rotation is not None:
            object.__setattr__(self, "rotation", _arr(self.rotation, (3, 3), n, f"bodies[{name!r}].rotation"))

    @property
    def angular_velocity_body(self):
        """``w_WB_B``, ndarray (n, 3), rad/s (derived from the world value)."""
        return spatial.world_to_body(spatial.quat_normalize(self.quaternion), self.angular_velocity)

    @property
    def rotation_matrix(self):
        """``R_WB`` (n, 3, 3): the engine's matrix if it had one, else from the quaternion as stored."""
        return self.rotation if self.rotation is not None else spatial.quat_to_matrix(self.quaternion)


@dataclass(frozen=True, eq=False)
class JointStates:
    """Sampled joint coordinates (``Joint`` conventions): ``q (n, nq)``, ``v (n, nv)``."""

    q: np.ndarray
    v: np.ndarray


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Sampled motion of a scene.

    Attributes
    ----------
    t : ndarray (n,) — sample times, s
    bodies : dict name -> BodyStates
    joints : dict joint name -> JointStates — for jointed scenes
    extras : dict name -> ndarray (n, ...) — further named series, e.g.
        ``reaction_force:<joint>`` (n, 3): the force the joint exerts ON its
        child, world axes, N; ``contact_force:<pair>`` (n, 3): the total force
        a contact pair exerts ON its subject (``dalembert.contact``), world axes,
        N, where the engine reports one (a contact scene's only)
    """

    t: np.ndarray
    bodies: dict
    joints: dict = field(default_factory=dict)
    extras: dict = field(default_factory=dict)

    def __post_init__(self):
        t = np.ascontiguousarray(self.t, dtype=float)
        if t.ndim != 1:
            raise ValueError(f"t: expected a 1-D array, got shape {t.shape}")
        object.__setattr__(self, "t", t)
        for name, b in self.bodies.items():
            b.check(len(t), name)

    def __len__(self):
        return len(self.t)

    def is_finite(self):
        """True when every stored number is finite."""
        arrays = [self.t] + [a for b in self.bodies.values() for a in
                             (b.position, b.quaternion, b.velocity, b.angular_velocity)]
        arrays += [a for j in self.joints.values() for a in (j.q, j.v)] + list(self.extras.values())
        return all(np.all(np.isfinite(a)) for a in arrays)

    def is_still(self):
        """True when nothing moves: every body's position and attitude, and every joint's
        coordinates, equal their first sample at every sample (exactly)."""
        arrays = [a for b in self.bodies.values() for a in (b.position, b.quaternion)]
        arrays += [j.q for j in self.joints.values()]
        return all(np.array_equal(a, np.broadcast_to(a[:1], a.shape)) for a in arrays)

    def first_nonfinite_time(self):
        """Earliest sample time with a NaN/inf in any body state, joint coordinate or extra sampled at
        ``t``, or None (every array ``is_finite`` reads: a joint can blow up while the bodies stay finite)."""
        n = len(self.t)
        arrays = [a for b in self.bodies.values() for a in
                  (b.position, b.quaternion, b.velocity, b.angular_velocity)]
        arrays += [a for j in self.joints.values() for a in (j.q, j.v)]
        arrays += [a for a in map(np.asarray, self.extras.values()) if a.ndim and a.shape[0] == n]
        bad = np.zeros(n, dtype=bool)
        for a in arrays:
            bad |= ~np.all(np.isfinite(np.reshape(a, (n, -1))), axis=1)
        return float(self.t[np.argmax(bad)]) if bad.any() else None


def write_csv(traj, path):
    """Write ``traj`` as CSV (``CSV_COLUMNS``), rows time-major then by body name, to ``path``
    (a file name, or an open text file: ``dalembert truth`` writes it where the user said)."""
    if hasattr(path, "write"):
        return _write_csv(traj, path)
    with open(path, "w", newline="") as fh:
        _write_csv(traj, fh)


def _write_csv(traj, fh):
    w = csv.writer(fh)
    w.writerow(CSV_COLUMNS)
    names = sorted(traj.bodies)
    for i, t in enumerate(traj.t):
        for name in names:
            b = traj.bodies[name]
            nums = [t, *b.position[i], *b.quaternion[i], *b.velocity[i], *b.angular_velocity[i]]
            w.writerow([repr(float(nums[0])), name] + [repr(float(x)) for x in nums[1:]])


def read_csv(path):
    """Read a CSV written by ``write_csv`` back into a ``Trajectory`` (bodies only)."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    if tuple(rows[0]) != CSV_COLUMNS:
        raise ValueError(f"{path}: header must be {','.join(CSV_COLUMNS)}")
    names = sorted({r[1] for r in rows[1:]})
    data = {n: np.array([[float(x) for x in r[2:]] for r in rows[1:] if r[1] == n]) for n in names}
    t = np.array([float(r[0]) for r in rows[1:] if r[1] == names[0]])
    bodies = {n: BodyStates(d[:, 0:3], d[:, 3:7], d[:, 7:10], d[:, 10:13]) for n, d in data.items()}
    return Trajectory(t, bodies)
