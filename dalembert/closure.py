"""Loop closures as constraint rows on body states: residuals, Jacobians, rank.

A ``Loop`` (``dalembert.scene``) closes a kinematic cycle between a frame Ja fixed in body
``a`` (``point_a``, ``quat_a``: in a's body frame, or the world's when ``a`` is the world) and a
frame Jb fixed in body ``b``. Its constraint ``phi = 0`` has one row per scalar condition
(``ROWS``):

* ``ball`` (3): ``x_Ja - x_Jb`` (m, world), the two joint points coincide;
* ``revolute`` (5): the ball's three rows, then ``(R_WJb u_k) . (R_WJa a)`` for the two unit
  vectors ``u_1, u_2`` normal to the axis ``a`` (joint-frame axes): the axis carried by each side
  stays the same line (dimensionless, the sine of the tilt);
* ``distance`` (1): ``|x_Ja - x_Jb| - length`` (m).

Everything here is a function of the two bodies' states in world terms, ``R`` (3, 3) ``R_WB``,
``p`` (3,) COM position (m), ``v`` (3,) COM velocity (m/s), ``w`` (3,) angular velocity
``w_WB_W`` (rad/s), so the harness computes a run's residuals from its trajectory (never from the
engine) and the reference solver, the scene's validation and the invariants share one definition.
With a body's twist ``(v, w)`` and acceleration ``(a, alpha)`` (world, COM), the rows satisfy

    d(phi)/dt     = G_a (v_a, w_a) + G_b (v_b, w_b)
    d2(phi)/dt2   = G_a (a_a, alpha_a) + G_b (a_b, alpha_b) + gamma

(``Rows``): ``G`` (m, 6) are the rows' partial velocities, ``gamma`` (m,) their velocity-product
part. On a tree, body twists are ``J_i u`` (``u``: the joints' generalized speeds), so the loop
Jacobian in the tree's speeds is ``G_a J_a + G_b J_b``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from dalembert import spatial

__all__ = ["ROWS", "RANK_RTOL", "Rows", "ClosureSummary", "rows", "rows_stacked", "residuals", "initial_rows", "world_state", "summary", "tree_jacobians"]

# Scalar conditions per loop kind.
ROWS = {"ball": 3, "revolute": 5, "distance": 1}

# A singular value of the loop Jacobian below RANK_RTOL times the largest counts as zero (a redundant
# or degenerate row). Structurally redundant rows (a planar loop closed by a 3-D revolute: the
# out-of-plane rows) come out at ~1e-16 relative; a row that loses rank at a singular position
# (the parallelogram four-bar flat) shrinks linearly with the distance from it. sqrt(eps) ~ 1.5e-8
# splits the two: the multiplier of a row cut at sigma < 1e-8 carries a generalized force of order
# sigma * lambda for a time of order sigma / rate, far below the truth's 1e-12.
RANK_RTOL = 1e-8


def world_state():
    """The world as a body: identity pose, at rest (dict ``R, p, v, w``)."""
    z = np.zeros(3)
    return dict(R=np.eye(3), p=z, v=z, w=z)


@dataclass(frozen=True, eq=False)
class Rows:
    """A loop's constraint rows at one state (see the module docstring).

    Attributes
    ----------
    phi : ndarray (m,) — position residual (m for point rows, dimensionless for axis rows)
    G_a, G_b : ndarray (m, 6) — partial velocities wrt body a's and b's twist ``(v_com, w)`` (world)
    gamma : ndarray (m,) — velocity-product part of the rows' second derivative
    velocity : ndarray (m,) — the rows' rate ``G_a twist_a + G_b twist_b`` (m/s, rad/s)
    """

    phi: np.ndarray
    G_a: np.ndarray
    G_b: np.ndarray
    gamma: np.ndarray
    velocity: np.ndarray


def _lever(R, point):
    return R @ np.asarray(point, dtype=float)


def _point_block(rho):
    """Partial velocity of a point at ``rho`` (world, from the COM) wrt the twist: ``[1, -skew(rho)]`` (3, 6)."""
    return np.hstack([np.eye(3), -spatial.skew(rho)])


@lru_cache(maxsize=256)
def _normals(axis):
    """Two unit vectors normal to ``axis`` (a 3-tuple) and to each other, in the same frame (cached: a
    loop's axis is fixed)."""
    F = spatial.frame_with_z(np.asarray(axis, dtype=float) / np.linalg.norm(axis))
    return F[:, 0].copy(), F[:, 1].copy()


def _hinge(loop, A, B):
    """A revolute loop's ``R_WJb`` (3, 3), its axis as body a carries it ``s_a`` (3,) (world) and the relative
    angular velocity ``w_a - w_b`` (3,) (rad/s, world); one state or many (leading axes: ``rows_stacked``)."""
    axis = np.asarray(loop.axis, dtype=float) / np.linalg.norm(loop.axis)
    s_a = A["R"] @ spatial.quat_to_matrix(loop.quat_a) @ axis
    return B["R"] @ spatial.quat_to_matrix(loop.quat_b), s_a, A["w"] - B["w"]


def rows(loop, A, B):
    """The constraint rows of ``loop`` at body states ``A`` (of ``loop.body_a``) and ``B`` (of ``loop.body_b``).

    Parameters
    ----------
    loop : dalembert.scene.Loop
    A, B : dict with ``R`` (3, 3) ``R_WB``, ``p`` (3,) COM (m), ``v`` (3,) COM velocity (m/s) and
        ``w`` (3,) angular velocity (rad/s), all world; ``world_state()`` for the world

    Returns
    -------
    Rows
    """
    rho_a, rho_b = _lever(A["R"], loop.point_a), _lever(B["R"], loop.point_b)
    x_a, x_b = A["p"] + rho_a, B["p"] + rho_b
    xd_a = A["v"] + spatial.cross(A["w"], rho_a)
    xd_b = B["v"] + spatial.cross(B["w"], rho_b)
    c_a = spatial.cross(A["w"], spatial.cross(A["w"], rho_a))  # centripetal acceleration of each point
    c_b = spatial.cross(B["w"], spatial.cross(B["w"], rho_b))
    P_a, P_b = _point_block(rho_a), _point_block(rho_b)
    if loop.kind == "distance":
        d, dd = x_a - x_b, xd_a - xd_b
        r = float(np.linalg.norm(d))
        e = d / r
        phi = np.array([r - loop.length])
        gamma = np.array([e @ (c_a - c_b) + (dd @ dd - (e @ dd) ** 2) / r])
        G_a, G_b = (e @ P_a)[None, :], -(e @ P_b)[None, :]
        return Rows(phi, G_a, G_b, gamma, np.array([e @ dd]))
    phi, G_a, G_b, gamma = [x_a - x_b], [P_a], [-P_b], [c_a - c_b]
    vel = [xd_a - xd_b]
    if loop.kind == "revolute":
        R_WJb, s_a, dw = _hinge(loop, A, B)
        for u in _normals(tuple(loop.axis)):
            s_b = R_WJb @ u
            n = spatial.cross(s_a, s_b)
            n_dot = spatial.cross(spatial.cross(A["w"], s_a), s_b) + spatial.cross(s_a, spatial.cross(B["w"], s_b))
            phi.append([s_b @ s_a])
            G_a.append(np.concatenate([np.zeros(3), n])[None, :])
            G_b.append(np.concatenate([np.zeros(3), -n])[None, :])
            gamma.append([dw @ n_dot])
            vel.append([dw @ n])
    return Rows(np.concatenate(phi), np.vstack(G_a), np.vstack(G_b), np.concatenate(gamma), np.concatenate(vel))


def tree_jacobians(scene):
    """Each body's twist Jacobian in the tree's joint speeds at the initial configuration.

    Returns
    -------
    columns : list of (joint name, index) — the joint speeds in order (the scene's joints, ``v0``'s entries)
    J : dict body name -> ndarray (6, nv) — ``(v_com, w)`` (world) per unit joint speed; the world's is zero
    """
    columns = [(j.name, k) for j in scene.joints for k in range(len(j.v0))]
    J = {b.name: np.zeros((6, len(columns))) for b in scene.bodies}
    J["world"] = np.zeros((6, len(columns)))
    sizes = {j.name: len(j.v0) for j in scene.joints}
    for c, (name, k) in enumerate(columns):
        unit = np.zeros(sizes[name])
        unit[k] = 1.0
        states = spatial.initial_body_states(scene, velocities={name: unit})  # twists are linear in the speeds
        for b, s in states.items():
            J[b][:, c] = np.concatenate([s["v"], s["w"]])
    return columns, J


@dataclass(frozen=True)
class ClosureSummary:
    """What a scene's loop closures are at its initial state (``Scene.loop_summary``).

    Attributes
    ----------
    loops : int — loop closures
    rows : int — scalar constraint rows (``ROWS`` summed)
    rank : int — rank of the loop Jacobian in the tree's joint speeds (``RANK_RTOL``)
    dof : int — tree speeds minus ``rank``: the mechanism's degrees of freedom at the initial state
    position_residual : float — largest ``|phi|`` (m or dimensionless)
    velocity_residual : float — largest row rate (m/s or rad/s)
    """

    loops: int
    rows: int
    rank: int
    dof: int
    position_residual: float
    velocity_residual: float

    @property
    def redundant(self):
        """Rows that add no constraint at the initial state (``rows - rank``)."""
        return self.rows - self.rank

    def __str__(self):
        return (f"{self.loops} loop closure(s), {self.rows} constraint rows of rank {self.rank} at the initial state "
                f"({self.redundant} redundant), {self.dof} degree(s) of freedom; residuals {self.position_residual:.3g} "
                f"(position), {self.velocity_residual:.3g} (velocity)")


def initial_rows(scene):
    """Each loop's ``Rows`` at the scene's initial state, in ``scene.loops`` order."""
    states = spatial.initial_body_states(scene)
    states["world"] = world_state()
    return [rows(loop, states[loop.body_a], states[loop.body_b]) for loop in scene.loops]


def summary(scene):
    """The ``ClosureSummary`` of ``scene`` (which must have valid names and joints)."""
    nv = sum(len(j.v0) for j in scene.joints)
    if not scene.loops:
        return ClosureSummary(0, 0, 0, nv, 0.0, 0.0)
    found = initial_rows(scene)
    _, J = tree_jacobians(scene)
    jac = np.vstack([r.G_a @ J[loop.body_a] + r.G_b @ J[loop.body_b] for loop, r in zip(scene.loops, found)])
    s = np.linalg.svd(jac, compute_uv=False)
    rank = int(np.sum(s > RANK_RTOL * s[0])) if len(s) and s[0] > 0.0 else 0
    return ClosureSummary(len(scene.loops), jac.shape[0], rank, nv - rank,
                          float(max(np.abs(r.phi).max() for r in found)),
                          float(max(np.abs(r.velocity).max() for r in found)))


def rows_stacked(loop, A, B):
    """``rows`` at m states at once: ``A``, ``B`` with a leading sample axis (``R`` (m, 3, 3), ``p``, ``v``,
    ``w`` (m, 3)); a ``Rows`` whose arrays have it too (``phi`` (m, k), ``G_a`` (m, k, 6), ...). The same
    terms as ``rows``, summed by numpy's stacked operations (equal to roundoff)."""
    rho_a = A["R"] @ np.asarray(loop.point_a, dtype=float)
    rho_b = B["R"] @ np.asarray(loop.point_b, dtype=float)
    x_a, x_b = A["p"] + rho_a, B["p"] + rho_b
    xd_a = A["v"] + spatial.cross(A["w"], rho_a)
    xd_b = B["v"] + spatial.cross(B["w"], rho_b)
    c_a = spatial.cross(A["w"], spatial.cross(A["w"], rho_a))
    c_b = spatial.cross(B["w"], spatial.cross(B["w"], rho_b))
    eye = np.broadcast_to(np.eye(3), rho_a.shape[:-1] + (3, 3))
    P_a = np.concatenate([eye, -spatial.skew(rho_a)], axis=-1)  # (m, 3, 6): ``_point_block``
    P_b = np.concatenate([eye, -spatial.skew(rho_b)], axis=-1)
    dot = lambda x, y: np.sum(x * y, axis=-1, keepdims=True)  # noqa: E731  (m, 1)
    if loop.kind == "distance":
        d, dd = x_a - x_b, xd_a - xd_b
        r = np.linalg.norm(d, axis=-1, keepdims=True)
        e = d / r
        gamma = dot(e, c_a - c_b) + (dot(dd, dd) - dot(e, dd) ** 2) / r
        return Rows(r - loop.length, e[..., None, :] @ P_a, -(e[..., None, :] @ P_b), gamma, dot(e, dd))
    phi, G_a, G_b, gamma = [x_a - x_b], [P_a], [-P_b], [c_a - c_b]
    vel = [xd_a - xd_b]
    if loop.kind == "revolute":
        R_WJb, s_a, dw = _hinge(loop, A, B)
        zero = np.zeros_like(s_a)
        for u in _normals(tuple(loop.axis)):
            s_b = R_WJb @ u
            n = spatial.cross(s_a, s_b)
            n_dot = spatial.cross(spatial.cross(A["w"], s_a), s_b) + spatial.cross(s_a, spatial.cross(B["w"], s_b))
            phi.append(dot(s_b, s_a))
            G_a.append(np.concatenate([zero, n], axis=-1)[..., None, :])
            G_b.append(np.concatenate([zero, -n], axis=-1)[..., None, :])
            gamma.append(dot(dw, n_dot))
            vel.append(dot(dw, n))
    return Rows(np.concatenate(phi, axis=-1), np.concatenate(G_a, axis=-2), np.concatenate(G_b, axis=-2),
                np.concatenate(gamma, axis=-1), np.concatenate(vel, axis=-1))


def residuals(loop, A, B):
    """The position and velocity residuals of ``loop``'s rows at many states at once: ``rows(loop, A_k, B_k).phi``
    and ``.velocity`` for every sample k (the same formulas, without the Jacobians; tested against ``rows``).

    Parameters
    ----------
    loop : dalembert.scene.Loop
    A, B : dict with ``R`` (n, 3, 3) or (3, 3) ``R_WB``, ``p``, ``v``, ``w`` (n, 3) or (3,): COM (m), its velocity
        (m/s), angular velocity (rad/s), all world; ``world_state()`` for the world

    Returns
    -------
    phi, velocity : ndarray (n, m), (m,) for two single states — m for point rows, dimensionless for axis rows;
        m/s, rad/s
    """
    rho_a, rho_b = A["R"] @ np.asarray(loop.point_a, float), B["R"] @ np.asarray(loop.point_b, float)
    d = A["p"] + rho_a - B["p"] - rho_b
    dd = A["v"] + np.cross(A["w"], rho_a) - B["v"] - np.cross(B["w"], rho_b)
    if loop.kind == "distance":
        r = np.linalg.norm(d, axis=-1)
        return (r - loop.length)[..., None], (np.sum(d * dd, axis=-1) / r)[..., None]
    phi, vel = [d], [dd]
    if loop.kind == "revolute":
        s_a = (A["R"] @ spatial.quat_to_matrix(loop.quat_a)) @ (np.asarray(loop.axis, float) / np.linalg.norm(loop.axis))
        R_WJb = B["R"] @ spatial.quat_to_matrix(loop.quat_b)
        for u in _normals(tuple(loop.axis)):
            s_b = R_WJb @ u
            phi.append(np.sum(s_b * s_a, axis=-1)[..., None])
            vel.append(np.sum((A["w"] - B["w"]) * np.cross(s_a, s_b), axis=-1)[..., None])
    # every piece carries the sample axis of whichever state has one (the world's has none)
    return np.concatenate(phi, axis=-1), np.concatenate(vel, axis=-1)

