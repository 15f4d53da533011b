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
import math
from functools import lru_cache

import numpy as np

from dalembert import scalar3, spatial

__all__ = ["ROWS", "RANK_RTOL", "Rows", "ClosureSummary", "LoopRows", "rows", "rows_stacked", "stack_terms", "residuals",
           "initial_rows", "world_state", "summary", "tree_jacobians"]

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


# ``LoopRows`` writes each row's terms once, on scalars (``scalar3``): Python floats at one state, or (m,) arrays,
# one entry per state, where the states come stacked; both paths round every term alike.
def _vector(x):
    """A 3-vector (3,) as 3 floats, or a stack (m, 3) as its 3 components (m,)."""
    x = x if isinstance(x, np.ndarray) else np.asarray(x, dtype=float)
    return x.tolist() if x.ndim == 1 else [x[..., 0], x[..., 1], x[..., 2]]


def _matrix(R):
    """A matrix (3, 3) as its 9 floats, or a stack (m, 3, 3) as its 9 entries (m,); row-major (``scalar3``'s)."""
    R = R if isinstance(R, np.ndarray) else np.asarray(R, dtype=float)
    return R.ravel().tolist() if R.ndim == 2 else [R[..., i, j] for i in range(3) for j in range(3)]


def _point_block(rho):
    """Partial velocity of a point at ``rho`` (world, from the COM) wrt the twist: ``[1, -skew(rho)]`` (3, 6),
    as rows of floats (``rho`` x ``(v, w)`` = ``v + w x rho``)."""
    x, y, z = rho
    return [[1.0, 0.0, 0.0, 0.0, z, -y], [0.0, 1.0, 0.0, -z, 0.0, x], [0.0, 0.0, 1.0, y, -x, 0.0]]


@lru_cache(maxsize=256)
def _normals(axis):
    """Two unit vectors normal to ``axis`` (a 3-tuple) and to each other, in the same frame (cached: a
    loop's axis is fixed)."""
    F = spatial.frame_with_z(np.asarray(axis, dtype=float) / np.linalg.norm(axis))
    return F[:, 0].copy(), F[:, 1].copy()


class LoopRows:
    """``rows`` of one loop at one state after another: the loop's vectors fixed in its bodies turned into Python
    floats once (the joint points; a revolute's axis in a's body frame and its normals in b's), each state's
    terms in floats (a few dozen products per loop, where numpy's per-call cost on 3-vectors was most of a step).

    Parameters
    ----------
    loop : dalembert.scene.Loop
    """

    def __init__(self, loop):
        self.loop, self.kind, self.length = loop, loop.kind, loop.length
        self.point_a, self.point_b = _vector(loop.point_a), _vector(loop.point_b)
        self.size = ROWS[loop.kind]
        if loop.kind == "revolute":
            axis = np.asarray(loop.axis, dtype=float) / np.linalg.norm(loop.axis)
            self.axis_a = (spatial.quat_to_matrix(loop.quat_a) @ axis).tolist()  # in a's body frame
            R_bJ = spatial.quat_to_matrix(loop.quat_b)
            self.normals_b = [(R_bJ @ u).tolist() for u in _normals(tuple(loop.axis))]  # in b's body frame

    def terms(self, A, B, rates=True):
        """The rows at body states ``A``, ``B`` (``rows``' dicts of arrays, or ``rows_stacked``'s) as lists of
        scalars (floats, or (m,) arrays for stacked states; a constant entry stays a float): ``phi`` (k,), ``G_a``,
        ``G_b`` (k rows of 6), and with ``rates`` ``gamma`` and ``velocity`` (k,) (else ``None``: a projection
        needs only the positions and the Jacobian)."""
        R_a, R_b = _matrix(A["R"]), _matrix(B["R"])
        rho_a, rho_b = scalar3.rot(R_a, self.point_a), scalar3.rot(R_b, self.point_b)
        p_a, p_b = _vector(A["p"]), _vector(B["p"])
        d = [p_a[i] + rho_a[i] - (p_b[i] + rho_b[i]) for i in range(3)]  # x_Ja - x_Jb
        if rates:
            w_a, w_b, v_a, v_b = _vector(A["w"]), _vector(B["w"]), _vector(A["v"]), _vector(B["v"])
            wr_a, wr_b = scalar3.cross(w_a, rho_a), scalar3.cross(w_b, rho_b)
            dd = [v_a[i] + wr_a[i] - (v_b[i] + wr_b[i]) for i in range(3)]  # the points' relative velocity
            c_a, c_b = scalar3.cross(w_a, wr_a), scalar3.cross(w_b, wr_b)  # centripetal acceleration of each point
            dc = [c_a[i] - c_b[i] for i in range(3)]
        if self.kind == "distance":
            r = scalar3.dot(d, d)
            r = math.sqrt(r) if isinstance(r, float) else np.sqrt(r)  # (both IEEE's correctly rounded root)
            e = [x / r for x in d]
            n_a, n_b = scalar3.cross(rho_a, e), scalar3.cross(rho_b, e)  # e @ -skew(rho)
            G_a, G_b = [[*e, *n_a]], [[-x for x in (*e, *n_b)]]
            if not rates:
                return [r - self.length], G_a, G_b, None, None
            ed = scalar3.dot(e, dd)
            return [r - self.length], G_a, G_b, [scalar3.dot(e, dc) + (scalar3.dot(dd, dd) - ed * ed) / r], [ed]
        G_a, G_b = _point_block(rho_a), [[-x for x in row] for row in _point_block(rho_b)]
        phi, gamma, vel = d, (dc if rates else None), (dd if rates else None)
        if self.kind == "revolute":
            s_a = scalar3.rot(R_a, self.axis_a)
            if rates:
                dw = [w_a[i] - w_b[i] for i in range(3)]
                ws_a = scalar3.cross(w_a, s_a)
            for u in self.normals_b:
                s_b = scalar3.rot(R_b, u)
                n = scalar3.cross(s_a, s_b)
                phi = phi + [scalar3.dot(s_b, s_a)]
                G_a.append([0.0, 0.0, 0.0, *n])
                G_b.append([0.0, 0.0, 0.0, -n[0], -n[1], -n[2]])
                if rates:
                    n_dot = scalar3.add(scalar3.cross(ws_a, s_b), scalar3.cross(s_a, scalar3.cross(w_b, s_b)))
                    gamma = gamma + [scalar3.dot(dw, n_dot)]
                    vel = vel + [scalar3.dot(dw, n)]
        return phi, G_a, G_b, gamma, vel


@lru_cache(maxsize=256)
def _loop_rows(loop):
    return LoopRows(loop)


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
    phi, G_a, G_b, gamma, vel = _loop_rows(loop).terms(A, B)
    return Rows(np.array(phi), np.array(G_a), np.array(G_b), np.array(gamma), np.array(vel))


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


def stack_terms(scalars, lead):
    """``LoopRows.terms``' scalars (floats and (m,) arrays, a list or a list of rows) as one array with the leading
    sample axis ``lead`` ((m,)) first: (m, k) or (m, k, 6)."""
    flat = np.broadcast_arrays(*(x for row in scalars for x in (row if isinstance(row, list) else [row])),
                               np.zeros(lead))[:-1]
    out = np.stack(flat, axis=-1)
    return out.reshape(lead + (len(scalars), -1)) if isinstance(scalars[0], list) else out


def rows_stacked(loop, A, B):
    """``rows`` at m states at once: ``A``, ``B`` with a leading sample axis (``R`` (m, 3, 3), ``p``, ``v``,
    ``w`` (m, 3); the world's may lack it); a ``Rows`` whose arrays have it too (``phi`` (m, k), ``G_a``
    (m, k, 6), ...). The same terms as ``rows`` (``LoopRows.terms``), rounded alike."""
    lead = np.broadcast_shapes(np.shape(A["p"]), np.shape(B["p"]))[:-1]
    phi, G_a, G_b, gamma, vel = _loop_rows(loop).terms(A, B)
    return Rows(*(stack_terms(x, lead) for x in (phi, G_a, G_b, gamma, vel)))


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

