"""The geometry of a scene's contact pairs on any motion: gaps (penetration when negative) and the slip velocity
at a geom's contact with a plane, computed from body poses and velocities alone (never from an engine).

A pair's *gap* is the signed distance between its two shapes: positive apart, zero touching, negative
interpenetrating (minus the depth). Computed in closed form for sphere-plane, box-plane, sphere-sphere and
sphere-box; a box-box pair has no gap here (``gap`` returns None: its depth is not measured).

The *slip velocity* of a geom on a plane is the tangential velocity (world, m/s) of the body point at the foot of
the geom's centre on the plane: a sphere's contact point, the centre of a box's face lying on the plane. It is
zero while the contact sticks or rolls.

The *contact force* of a pair is what an engine reports, where it reports one: the total force (N, world axes) the
pair's contact exerts ON its *subject*, the geom of a geom-plane pair, or the first geom ``a`` of a pair of geoms,
stored per sample in the trajectory's extras as ``contact_force:<pair>`` (n, 3) (an engine that does not report
it stores nothing: the quantities made from it are then not measured). Its *normal force* is its component along
the contact normal: the plane's normal, or from the other geom's centre to the subject's for a pair of spheres.

Used by the scene's checks (no pair may start interpenetrating: ``scene_checks.INITIAL_OVERLAP_TOL``) and by the
contact cases' metrics (``dalembert.metrics.Metric``: penetration depth, creep, normal force,
``dalembert.contact_residuals``).
"""

from __future__ import annotations

import itertools

import numpy as np

from dalembert.rotations import cross, quat_to_matrix

__all__ = ["FORCE_PREFIX", "poses_of", "initial_poses", "gap", "depth", "contact_point_velocity", "slip_velocity",
           "geom_and_plane", "subject", "contact_force", "normal_force", "not_mapped"]

# The trajectory extras key of a pair's contact force, ``FORCE_PREFIX + pair.name`` (n, 3), N, world, ON its subject.
FORCE_PREFIX = "contact_force:"

# A box's 8 corners in its own axes, as multiples of its half edge lengths.
_CORNERS = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))


# Poses: body poses and velocities at n samples, a dict body name -> dict ``p`` (n, 3) COM position (m),
# ``R`` (n, 3, 3) ``R_WB``, ``v`` (n, 3) COM velocity (m/s), ``w`` (n, 3) angular velocity ``w_WB_W`` (rad/s),
# world axes: what every function here takes.


def poses_of(traj):
    """The poses of a ``dalembert.trajectory.Trajectory``."""
    return {name: dict(p=b.position, R=b.rotation_matrix, v=b.velocity, w=b.angular_velocity)
            for name, b in traj.bodies.items()}


def initial_poses(scene):
    """The poses of ``scene`` at its initial state (one sample; ``dalembert.spatial.initial_body_states``)."""
    from dalembert import spatial

    return {name: {k: np.asarray(v)[None] for k, v in s.items()}
            for name, s in spatial.initial_body_states(scene).items()}


def _geom_frame(geom, pose):
    """The geom's centre (n, 3) and axes ``R_WG`` (n, 3, 3) in the world."""
    R_BG = quat_to_matrix(np.asarray(geom.quat) / np.linalg.norm(geom.quat))
    return pose["p"] + pose["R"] @ np.asarray(geom.point), pose["R"] @ R_BG


def geom_and_plane(scene, pair):
    """``(geom, plane)`` of a geom-plane pair, or None when neither end is a plane."""
    planes = {p.name: p for p in scene.planes}
    for g, p in ((pair.a, pair.b), (pair.b, pair.a)):
        if p in planes and g not in planes:
            return scene.geom(g), planes[p]
    return None


def _plane_gap(geom, plane, pose):
    n, p0 = plane.unit_normal, np.asarray(plane.point)
    c, R = _geom_frame(geom, pose)
    height = (c - p0) @ n
    if geom.kind == "sphere":
        return height - geom.size[0]
    half = 0.5 * np.asarray(geom.size)
    # each corner's height is the centre's plus its offset R (s * half) along n
    return height + np.min((R.transpose(0, 2, 1) @ n) @ (_CORNERS * half).T, axis=-1)


def _sphere_box_gap(sphere, box, pose_s, pose_b):
    c, _ = _geom_frame(sphere, pose_s)
    cb, R = _geom_frame(box, pose_b)
    half = 0.5 * np.asarray(box.size)
    x = np.einsum("nji,nj->ni", R, c - cb)  # the sphere's centre in the box's axes
    outside = np.linalg.norm(np.maximum(np.abs(x) - half, 0.0), axis=-1)
    inside = np.min(half - np.abs(x), axis=-1)  # distance to the nearest face, for a centre inside
    return np.where(outside > 0.0, outside, -inside) - sphere.size[0]


def gap(scene, pair, poses):
    """The signed distance (m) between ``pair``'s shapes at each sample of ``poses``, ndarray (n,): positive apart,
    negative interpenetrating; None for a box-box pair (not computed)."""
    shapes = {g.name: g for g in scene.geoms}
    ends = [shapes.get(pair.a), shapes.get(pair.b)]
    gp = geom_and_plane(scene, pair)
    if gp is not None:
        geom, plane = gp
        return _plane_gap(geom, plane, poses[geom.body])
    a, b = sorted(ends, key=lambda g: g.kind != "sphere")  # a sphere first
    if a.kind == "sphere" and b.kind == "sphere":
        ca, cb = _geom_frame(a, poses[a.body])[0], _geom_frame(b, poses[b.body])[0]
        return np.linalg.norm(ca - cb, axis=-1) - a.size[0] - b.size[0]
    if a.kind == "sphere":
        return _sphere_box_gap(a, b, poses[a.body], poses[b.body])
    return None


def depth(scene, poses):
    """The deepest interpenetration (m, >= 0) over the scene's contact pairs at each sample, ndarray (n,)."""
    n = len(next(iter(poses.values()))["p"])
    worst = np.zeros(n)
    for pair in scene.contacts:
        g = gap(scene, pair, poses)
        if g is not None:
            worst = np.maximum(worst, -g)
    return worst


def contact_point_velocity(scene, pair, poses):
    """The velocity (m/s, world) of the body point at the foot of a geom-plane ``pair``'s geom centre on the plane,
    at each sample, ndarray (n, 3): its component along the plane's normal is the contact's normal velocity
    (positive: leaving the plane), the rest its slip velocity."""
    geom, plane = geom_and_plane(scene, pair)
    pose = poses[geom.body]
    n, p0 = plane.unit_normal, np.asarray(plane.point)
    c, _ = _geom_frame(geom, pose)
    foot = c - np.outer((c - p0) @ n, n)
    return pose["v"] + cross(pose["w"], foot - pose["p"])


def slip_velocity(scene, pair, poses):
    """The slip velocity (m/s, world) of a geom-plane ``pair`` at each sample, ndarray (n, 3): the tangential
    velocity of the body point at the foot of the geom's centre on the plane."""
    n = geom_and_plane(scene, pair)[1].unit_normal
    v = contact_point_velocity(scene, pair, poses)
    return v - np.outer(v @ n, n)


def subject(scene, pair):
    """The name of the geom ``pair``'s contact force acts on: the geom of a geom-plane pair, else ``pair.a``."""
    gp = geom_and_plane(scene, pair)
    return gp[0].name if gp is not None else pair.a


def contact_force(traj, pair):
    """The contact force (N, world) ON ``pair``'s subject at each sample of ``traj``, ndarray (n, 3), as the engine
    reported it; None when the engine reported none (not measured)."""
    f = traj.extras.get(FORCE_PREFIX + pair.name)
    return None if f is None else np.asarray(f, dtype=float)


def normal_force(scene, pair, traj):
    """The normal component (N) of ``pair``'s contact force at each sample of ``traj``, ndarray (n,): along the
    plane's normal for a geom-plane pair, along the line from ``b``'s centre to ``a``'s for two geoms (positive:
    pushing them apart); None when the engine reported no force, or for a pair of geoms other than two spheres."""
    f = contact_force(traj, pair)
    if f is None:
        return None
    gp = geom_and_plane(scene, pair)
    if gp is not None:
        return f @ gp[1].unit_normal
    a, b = scene.geom(pair.a), scene.geom(pair.b)
    if a.kind != "sphere" or b.kind != "sphere":
        return None
    poses = poses_of(traj)
    d = _geom_frame(a, poses[a.body])[0] - _geom_frame(b, poses[b.body])[0]
    return np.einsum("ni,ni->n", f, d / np.linalg.norm(d, axis=-1, keepdims=True))


def not_mapped(scene, engine, would_take=None):
    """The reason an adapter that does not map contact yet gives for a scene with contact pairs, or None: what its
    ``unsupported`` returns first (contact is never silently left out: the bodies would fall through).
    ``would_take`` (str, optional): what mapping it would take in this engine, appended to the reason."""
    if scene.contacts:
        return (f"contact not yet mapped for {engine} (the scene's pairs {[c.name for c in scene.contacts]} would be "
                "left out, and its bodies pass through each other)" + (f": {would_take}" if would_take else ""))
    return None
