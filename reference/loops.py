"""Closed kinematic loops: Kane's equations of the spanning tree plus loop-closure constraints with
Lagrange multipliers (the reference's ``kane`` formulation on a scene with ``loops``).

Equations. The tree's coordinates ``q`` and speeds ``u`` are Kane's (``generalized.Kane``); each
loop adds constraint rows ``phi(q) = 0`` (``dalembert.closure``) whose Jacobian in the speeds is
``J`` (m, nv), so that ``d(phi)/dt = J u`` and ``d2(phi)/dt2 = J u' + b``. With Kane's
``M u' = f`` of the tree and the loops' generalized reaction ``J^T lambda``::

    M u' = f + J^T lambda,        J u' + b = 0                                  (index 1)

Solved in the metric of the mass matrix: with ``M = L L^T`` (Cholesky), ``g = L^-1 f`` and
``Jt = J L^-T = U S V^T`` (SVD, singular values below ``closure.RANK_RTOL`` times the largest cut),

    L^T u' = g - V_r (V_r^T g + S_r^-1 U_r^T b),     lambda = -U_r S_r^-1 (V_r^T g + S_r^-1 U_r^T b)

which is the minimum-norm (least-squares) solution of the KKT system: redundant rows (a planar
loop closed by a 3-D revolute has three) get no multiplier and change nothing, and near a singular
position (the parallelogram four-bar flat: a row's singular value goes to zero and back) only
``S^-1`` appears, never the ``S^-2`` of the normal equations ``J M^-1 J^T lambda = ...``.

Why index 1 with projection rather than coordinate partitioning: partitioning picks independent
coordinates from a non-singular minor of ``J``, and at a singular position every choice of the
minor's columns may go singular (the four-bar flat), forcing a re-partition exactly where the
motion is hardest; the least-squares solve has no choice to make and passes through it. The drift
of the index-1 form (``phi`` grows like the integration error, twice integrated) is removed by
projecting after every step of a fixed-step integrator and at every sample of an adaptive one
(``integrators``): the configuration onto ``phi = 0`` by Gauss-Newton steps
``dq = -M^-1 J^T (J M^-1 J^T)^+ phi`` (the nearest point in the kinetic-energy metric, on the
group for quaternion blocks), then the velocity onto ``J u = 0`` by the same projector (the
kinetic-energy-nearest velocity: no Baumgarte terms, no parameters to tune). On an exact solution
both projections are the identity, so they change nothing but the drift.

Singular positions. Where the Jacobian loses rank (the parallelogram four-bar flat, where it and
the anti-parallelogram branch cross), the index-1 equations are ill-posed off the manifold: a
residual ``eps`` in the degenerate row puts the state on a neighbouring level set that turns from
one branch into the other within ``sqrt(eps)``, and the accelerations there grow like
``eps / sigma``. Measured on the four-bar before the fix: RK4 at dt = 1e-3 lost 1e-2 J passing it,
and DOP853 at 1e-12 shrank its steps without end. So the accelerations (and reactions) are
evaluated at the state projected onto both manifolds first: the right-hand side is then that of
the exact constrained motion at every stage, whose degenerate row is consistent, and the motion
passes the singular position on the branch it came on (``tests/test_loops.py``).

Reactions: a loop's multipliers act on body a as the wrench ``G_a^T lambda`` and on body b as
``G_b^T lambda`` (``closure.Rows``: force and moment about the COM, world); the force ON body b
is the trajectory's ``reaction_force:<loop name>``, and the tree joints' reactions include the
loops' forces on their bodies. The read-back solves every sample at once (``_solve_stacked``, as
``generalized.Kane``'s): each state projected by its own iterations, its own rank cut.

Self-stresses. Redundant rows (a planar loop's out-of-plane ones, Bricard's one) leave multipliers
``lambda0`` with ``J^T lambda0 = 0``: loads the joints carry without moving anything, so a rigid model
determines the reactions only up to them, and the truth's least-squares choice is one of many.
``reaction_modes`` gives, at each sample, the joint and loop forces of each such ``lambda0`` (static
equilibrium with nothing else acting), so that reactions are compared modulo them
(``dalembert.errors``).
"""

from __future__ import annotations

import numpy as np

from dalembert import closure
from dalembert.lstsq import svd_cut
from dalembert.reference import configuration as cfg
from dalembert.reference.generalized import Kane, _mtv, _mv
from dalembert.scene import WORLD

__all__ = ["ClosedLoops", "PROJECTION_TOL", "PROJECTION_ITERATIONS", "reaction_modes"]

# Gauss-Newton stops when every position row is below this (m, or the sine of a tilt): bodies of a
# metre carry roundoff of ~2e-16 m per coordinate, and a closure sums a few of them.
PROJECTION_TOL = 1e-14
# ... or after this many steps (from a step's drift, ~1e-10 on the truth, one step reaches roundoff;
# near a singular position the degenerate row cannot be reduced, and the steps stop making progress).
PROJECTION_ITERATIONS = 4


def _inverse_cholesky(M):
    """``L^-1`` (nv, nv) of ``M = L L^T``: the inverse is formed once per call because the systems
    are small (a few speeds), where one product beats repeated triangular solves' call overhead."""
    return np.linalg.inv(np.linalg.cholesky(M))


class ClosedLoops(Kane):
    """A ``System`` (``integrators``) for a tree scene with loop closures (``Scene.loops``).

    The coordinates, speeds and read-back are Kane's (``generalized.Kane``); ``acceleration``
    solves the index-1 system above and ``project(q, v)`` returns the state moved onto the
    position and velocity manifolds (the integrators call it after each step).
    """

    def __init__(self, scene):
        super().__init__(scene)
        self.loops = scene.loops
        # All loops' rows as one G (m, 6 k) against the twists of the k bodies they join (the world among them where
        # a loop ends on it: its zero twist adds exact zeros, and its side's G gives the loop's force ON it), so that
        # J = G [Jv; Jw] and b = G [a_bias; alpha_bias] + gamma are one product each per state.
        self._closures = [closure.LoopRows(loop) for loop in self.loops]
        self._bodies = list(dict.fromkeys(b for loop in self.loops for b in (loop.body_a, loop.body_b)))
        column = {b: 6 * i for i, b in enumerate(self._bodies)}
        width, rows, spots, self._sides = 6 * len(self._bodies), 0, [], []
        for loop, c in zip(self.loops, self._closures):
            sides = (column[loop.body_a], column[loop.body_b])
            for col in sides:  # the order in which ``_rows`` lists the entries: a's rows, then b's
                spots.append((np.arange(rows, rows + c.size)[:, None] * width + col + np.arange(6)).ravel())
            self._sides.append((slice(rows, rows + c.size), sides))
            rows += c.size
        self._shape = (rows, width)
        self._spots = np.concatenate(spots)

    # ------------------------------------------------------------ constraints
    def _rows(self, kin, rates):
        """All loops' rows at the state of ``kin`` (``kinematics``): ``phi`` (m,), ``J`` (m, nv), ``G`` (m, 6 k)
        (against the twists of ``self._bodies``) and, with ``rates``, ``(b, gamma, velocity)`` (m,) each, else
        ``None`` (a projection needs only ``phi`` and ``J``). At n states at once (stacked ``kin``), the same
        terms rounded alike (``closure.LoopRows``), each with a leading sample axis: ``phi`` (n, m), ``J``
        (n, m, nv), ..."""
        lead = kin[WORLD]["p"].shape[:-1]
        phi, entries, gamma, vel = [], [], [], []
        for c in self._closures:
            p, G_a, G_b, g, v = c.terms(kin[c.loop.body_a], kin[c.loop.body_b], rates)
            phi += p
            for row in G_a + G_b:  # (the order of ``_spots``)
                entries += row
            if rates:
                gamma += g
                vel += v
        G = np.zeros(lead + (self._shape[0] * self._shape[1],))
        G[..., self._spots] = closure.stack_terms(entries, lead) if lead else entries
        G = G.reshape(lead + self._shape)
        J = G @ np.concatenate([kin[body][key] for body in self._bodies for key in ("Jv", "Jw")], axis=-2)
        phi = closure.stack_terms(phi, lead) if lead else np.array(phi)
        if not rates:
            return phi, J, G, None
        gamma, vel = (closure.stack_terms(x, lead) if lead else np.array(x) for x in (gamma, vel))
        bias = np.concatenate([kin[body][key] for body in self._bodies for key in ("a_bias", "alpha_bias")], axis=-1)
        b = _mv(G, bias)
        return phi, J, G, (b + gamma, gamma, vel)

    def _loop_forces(self, kin, G, lam):
        """Each loop's wrench ``G^T lambda`` (force, moment about the COM; world) on body a and on body b for the
        multipliers ``lam`` (m,) or (n, m) (``G``: ``_rows``'): the force added to each body's ``F`` in ``kin``
        (the tree reactions see the loop forces), and under ``("loops",)`` each loop's ON its body b (3,) or
        (n, 3)."""
        forces = {}
        for loop, (rows, sides) in zip(self.loops, self._sides):
            wa, wb = (_mtv(G[..., rows, col:col + 6], lam[..., rows]) for col in sides)
            for body, wrench in ((loop.body_a, wa), (loop.body_b, wb)):
                if body != WORLD:
                    kin[body]["F"] = kin[body]["F"] + wrench[..., :3]
            forces[loop.name] = wb[..., :3]
        kin[("loops",)] = forces  # (a tuple key: never a body name)

    def constraints(self, kin):
        """Loop rows at the state of ``kin`` (``kinematics``): ``phi`` (m,), ``J`` (m, nv), ``b`` (m,)
        and each loop's ``closure.Rows``."""
        phi, J, G, (b, gamma, vel) = self._rows(kin, rates=True)
        found = [closure.Rows(phi[..., rows], *(G[..., rows, col:col + 6] for col in sides), gamma[..., rows],
                              vel[..., rows]) for rows, sides in self._sides]
        return phi, J, b, found

    @staticmethod
    def _range(Jt):
        """``U_r, S_r, V_r`` of ``Jt``'s SVD, singular values above ``closure.RANK_RTOL`` times the largest."""
        U, S, Vt = np.linalg.svd(Jt, full_matrices=False)
        r = int(np.sum(S > closure.RANK_RTOL * S[0])) if len(S) and S[0] > 0.0 else 0
        return U[:, :r], S[:r], Vt[:r].T

    def _accelerations(self, t, q, u):
        """The index-1 system's ``udot`` (nv,) at ``(q, u)`` projected (module docstring: singular positions), the
        kinematics there, the multipliers ``lambda`` (m,) and the rows' ``G`` (``_rows``)."""
        q, u, pos = self._project(q, u)  # every evaluation on the manifolds (module docstring: singular positions)
        M, f, kin = self.mass_and_forces(t, q, u, self.velocities(pos, u))  # (the positions at the projected q)
        _, J, G, (b, _, _) = self._rows(kin, rates=True)
        Li = _inverse_cholesky(M)
        g = Li @ f
        U, S, V = self._range(J @ Li.T)
        c = V.T @ g + (U.T @ b) / S
        return Li.T @ (g - V @ c), kin, -U @ (c / S), G

    def acceleration(self, t, q, v):
        """Generalized accelerations ``u'`` (nv,) of the constrained motion (the reactions are not formed)."""
        return self._accelerations(t, q, v)[0]

    def _solve(self, t, q, u):
        udot, kin, lam, G = self._accelerations(t, q, u)
        self._loop_forces(kin, G, lam)
        return udot, kin

    def _solve_stacked(self, Q, U):
        """``_solve`` at m states at once (``Q`` (m, nq), ``U`` (m, nv)): each state projected, then the same
        index-1 system, its rank cut per state (``lstsq.svd_cut``); ``udot`` (m, nv) and the stacked kinematics
        with the loop forces on their bodies and, under ``("loops",)``, each loop's on its body b (m, 3)."""
        Q, U = self._project_stacked(Q, U)
        M, f, kin = self.mass_and_forces(None, Q, U)
        _, J, G, (b, _, _) = self._rows(kin, rates=True)
        Li = _inverse_cholesky(M)
        LiT = Li.swapaxes(-1, -2)
        g = _mv(Li, f)
        Ur, inv_S, Vr = svd_cut(J @ LiT, closure.RANK_RTOL)
        c = _mtv(Vr, g) + _mtv(Ur, b) * inv_S
        udot = _mv(LiT, g - _mv(Vr, c))
        self._loop_forces(kin, G, -_mv(Ur, c * inv_S))
        return udot, kin

    def _project_stacked(self, Q, U):
        """``project`` at m states at once (``Q`` (m, nq), ``U`` (m, nv)): each state's Gauss-Newton iterations
        stop where its own stop (``PROJECTION_TOL``, or no halving), as ``project``'s."""
        kin = self.positions(Q)  # (one pass serves the metric and the first rows, as in ``project``)
        L = np.linalg.cholesky(self.mass_matrix(kin))
        LiT = np.linalg.inv(L).swapaxes(-1, -2)
        phi, J, _, _ = self._rows(kin, rates=False)
        Q, last, going = Q.copy(), np.full(len(Q), np.inf), np.ones(len(Q), dtype=bool)
        for _ in range(PROJECTION_ITERATIONS):
            worst = np.max(np.abs(phi), axis=-1)
            going &= (worst > PROJECTION_TOL) & (worst < 0.5 * last)
            if not going.any():
                break
            i = np.flatnonzero(going)
            last[i] = worst[i]
            Ur, inv_S, Vr = svd_cut(J[i] @ LiT[i], closure.RANK_RTOL)
            Q[i] = cfg.retract(self.blocks, Q[i], _mv(LiT[i], -_mv(Vr, _mtv(Ur, phi[i]) * inv_S)))
            phi[i], J[i], _, _ = self._rows(self.positions(Q[i]), rates=False)
        Ur, inv_S, Vr = svd_cut(J @ LiT, closure.RANK_RTOL)
        w = _mtv(L, U)  # L^T v
        return Q, _mv(LiT, w - _mv(Vr, _mtv(Vr, w)))

    def _forces_stacked(self, udot, kin):
        """``forces`` at m states at once: Kane's reactions and each loop's force ON its body b, (m, 3) each."""
        return {**super()._forces_stacked(udot, kin), **kin[("loops",)]}

    def self_stresses(self, q):
        """The self-stresses at configuration ``q`` (nq,) (module docstring): one dict per independent
        ``lambda0`` (an orthonormal basis of ``J``'s left null space in the solver's own rank decision),
        joint or loop name -> the force it exerts ON its child (loop: ON body b), N, world."""
        kin = self.kinematics(q, np.zeros(self.nv))
        _, J, _, found = self.constraints(kin)
        Li = _inverse_cholesky(self.mass_matrix(kin))
        U, S, _ = np.linalg.svd(J @ Li.T, full_matrices=True)  # left null space of J L^-T = that of J
        rank = int(np.sum(S > closure.RANK_RTOL * S[0])) if len(S) and S[0] > 0.0 else 0
        modes = []
        for lam in U[:, rank:].T:
            on_body, loops, i = {}, {}, 0
            for loop, r in zip(self.loops, found):
                m = len(r.phi)
                for body, G in ((loop.body_a, r.G_a), (loop.body_b, r.G_b)):
                    on_body[body] = on_body.get(body, 0.0) + (G.T @ lam[i:i + m])[:3]
                loops[loop.name] = (r.G_b.T @ lam[i:i + m])[:3]
                i += m
            # at rest and unloaded but for the loop forces: each body's unbalanced force is -F_loops
            tree = self.joint_forces({jd["joint"].child: -on_body.get(jd["joint"].child, np.zeros(3))
                                      for jd in self.joints})
            modes.append({**tree, **loops})
        return modes

    # ------------------------------------------------------------ projection
    def project(self, q, v):
        """``(q, v)`` moved onto ``phi(q) = 0`` and ``J(q) v = 0`` in the kinetic-energy metric
        (see the module docstring); ``q`` (nq,), ``v`` (nv,)."""
        return self._project(q, v)[:2]

    def _project(self, q, v):
        """``project``'s ``(q, v)`` and the ``positions`` at that ``q`` (its last Gauss-Newton pass: the solve's)."""
        pos = self.positions(q)  # (one pass serves the metric and the first rows: configuration only)
        L = np.linalg.cholesky(self.mass_matrix(pos))  # the metric (loads do not enter it)
        Li = np.linalg.inv(L)
        phi, J, _, _ = self._rows(pos, rates=False)
        last = np.inf
        for _ in range(PROJECTION_ITERATIONS):
            worst = float(np.max(np.abs(phi)))
            if worst <= PROJECTION_TOL or not worst < 0.5 * last:
                break
            last = worst
            U, S, V = self._range(J @ Li.T)
            q = cfg.retract(self.blocks, q, Li.T @ (-V @ ((U.T @ phi) / S)))
            pos = self.positions(q)
            phi, J, _, _ = self._rows(pos, rates=False)
        U, S, V = self._range(J @ Li.T)
        w = _mtv(L, v)  # L^T v (as ``_project_stacked``'s)
        return q, Li.T @ (w - V @ (V.T @ w)), pos

    # ------------------------------------------------------------ read-back
    def forces(self, udot, kin):
        """Kane's reactions (the tree joints', which include the loops' forces on their bodies) plus each
        loop's force ON its body b (N, world), from the same ``_solve``: the trajectory's
        ``reaction_force:<loop name>``."""
        return {**super().forces(udot, kin), **kin[("loops",)]}

    @property
    def force_names(self):
        return super().force_names + [loop.name for loop in self.loops]


def reaction_modes(scene, traj):
    """The self-stresses of ``scene`` along ``traj`` (its joints' coordinates, any source: a closed
    form's or a solver's), as extras ``reaction_mode:<k>:<joint or loop>`` (n, 3), N per unit
    ``lambda0``, world: mode ``k`` at each sample (zero where a sample has fewer modes, e.g. away
    from a singular position; NaN where the sample is not finite). Empty for a scene without
    redundant rows anywhere along ``traj``."""
    system = ClosedLoops(scene)
    n = len(traj.t)
    Q = np.concatenate([traj.joints[jd["joint"].child].q for jd in system.joints], axis=1)
    per_sample = [system.self_stresses(Q[i]) if np.all(np.isfinite(Q[i])) else None for i in range(n)]
    count = max((len(m) for m in per_sample if m is not None), default=0)
    names = [jd["joint"].child for jd in system.joints if jd["joint"].kind != "free"] + [lp.name for lp in scene.loops]
    out = {f"reaction_mode:{k}:{name}": np.zeros((n, 3)) for k in range(count) for name in names}
    for i, modes in enumerate(per_sample):
        for k in range(count):
            for name in names:
                key = f"reaction_mode:{k}:{name}"
                out[key][i] = np.nan if modes is None else (modes[k][name] if k < len(modes) else 0.0)
    return out
