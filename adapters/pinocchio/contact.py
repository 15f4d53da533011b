"""Pinocchio's contact time-stepper: rigid Coulomb contact between a scene's named pairs, one cone
complementarity problem per step solved by Pinocchio's own constraint solvers.

Pinocchio 4 solves a contact problem at one instant (``pin.ADMMConstraintSolver``,
``pin.PGSConstraintSolver`` on a Delassus operator, with ``pin.PointContactConstraintModel``'s Coulomb cones)
but integrates none through time; this module is the time-stepper, velocity-level (Moreau, Anitescu-Potra:
impulses over the step, as MuJoCo's and Drake's discrete solvers), on semi-implicit Euler (``step``):

1. contact detection at the step's start ``q``, for the scene's named pairs only (``Contacts.points``),
   analytic: sphere-plane (one point, the sphere's lowest), box-plane (each of the box's 8 corners at or below
   the plane), sphere-sphere (one point on the line of centres). A point is active where its gap is at most
   ``CONTACT_MARGIN``;
2. per active point a contact frame ``(t1, t2, n)`` (``n`` pushes body a out of body b, or out of the plane)
   and its Jacobian rows ``J`` (3 per point, the velocity of a's material point relative to b's, in that
   frame; from ``pin.getJointJacobian``), the mass matrix ``M`` (``pin.crba``), the Delassus matrix
   ``G = J M^-1 J^T``;
3. the free velocity ``v_f = v + h a(q, v)`` (``a``: the adapter's forward dynamics with its loads and
   springs, the same ``acc`` as the contact-free ``euler``), except that a FreeFlyer's linear velocity, held in
   its joint's turning frame, takes the rate of the origin's velocity (``acc``'s plus ``w x v``), and after the
   position update is re-expressed in the turned frame (``R1^T R0 v``): explicit Euler of ``acc``'s ``-w x v``
   grows ``|v|`` by ``sqrt(1 + (h |w|)^2)`` per step, which a rolling contact keeps (a rolling ball sped up
   1.3 % in 0.7 s at dt = 1e-3, measured on ball_slide_to_roll), and leaves the velocity read at ``q+`` with a
   normal part the contact at ``q`` did not see; its contact-frame velocity
   ``c = J v_f``, plus on the normal, at an impact (``u = (J v)_n``, the pre-step normal speed, below
   ``-IMPACT_SPEED``), Newton's restitution ``+ e u``, so the post-step normal speed is at least ``-e u`` (e:
   the pair's restitution, 0 where it has none), and in a resting contact the gap's ``+ max(gap, 0) / h``, so
   the point may close its gap within the step and no more (Anitescu-Potra's position term);
4. the cone complementarity problem ``lambda in K_mu``, ``G lambda + c in K_mu^*``, ``lambda ⟂ (G lambda +
   c)`` with the De Saxcé correction (``solve_ncp``: the nonlinear complementarity problem of an ideal Coulomb
   cone, maximum dissipation), solved by ``pin.ADMMConstraintSolver`` (option ``contact_solver=admm``,
   the default) or ``pin.PGSConstraintSolver`` (``pgs``), to ``contact_tolerance`` in at most
   ``contact_iterations``; ``K_mu`` is each ``pin.PointContactConstraintModel``'s cone, its friction
   coefficient the pair's mu exactly (``setFriction``);
5. ``v+ = v_f + M^-1 J^T lambda``, ``q+ = integrate(q, h v+ + dq)`` (a FreeFlyer's origin moved on the
   straight line ``R0 (h v+ + dq)``, as its velocity is the origin's: ``exp6``'s screw would sink a rolling
   ball by ``h^2 |w| |v| / 2`` per step, 2.6 um at dt = 1e-3, measured): ``dq`` removes the depth found at the
   step's start, in position only (post-stabilisation: Cline & Pai, "Post-stabilization for rigid body
   simulation with contact and constraints", ICRA 2003), the least-norm (in M) displacement that moves each
   penetrating point's normal gap by its depth to first order, ``M^-1 J_n^T pinv(G_nn) depth``: it adds no
   velocity, so no energy, where a Baumgarte term on the velocity would launch a resting body.

Contact forces (``read_forces``, the read-back's ``contact_force:<pair>``): a point's impulse ``lambda`` over the
step is ``R lambda`` ON body a (``R = (t1, t2, n)``, world axes), so a pair's force on its subject (body a: the geom
of a geom-plane pair, the first sphere of two) is the sum of its points' ``R lambda / h``: the mean contact force
over the step. Read at the step that starts at each sample (as MuJoCo's and Drake's read-backs), by solving that
step again from the sampled state: the same arithmetic as the run's (``Stepper``), so the same impulses.

A step with no active point is the contact-free ``euler`` step but for the FreeFlyers' frame (step 3): a body in
free flight keeps its velocity exactly, where ``euler`` turns it by explicit Euler. The audit (``audit``) states the
mapping (mu as the cone's coefficient; restitution by Newton's law at the velocity level) and reads the
cones' mu and the solver settings back from the objects that ran.

Refused (``why_not``): other integrators (the stepper is semi-implicit Euler: impulses), constraints
(welds as constraints, loop closures: ``pin.constraintDynamics`` is an acceleration-level solve, not merged
with the contact one here), box-box and sphere-box pairs (no detection written for them).
"""

from __future__ import annotations

import functools

import numpy as np

from dalembert import contact as geometry
from dalembert.adapters.base import Option, typed_options
from dalembert.rotations import frame_with_z

__all__ = ["CONTACT_OPTIONS", "OPTIONS", "SOLVERS", "CONTACT_MARGIN", "IMPACT_SPEED", "TOLERANCE_DEFAULT", "ITERATIONS_DEFAULT",
           "INTEGRATOR", "why_not", "solver_settings", "read_settings", "solve_cone", "cone_coefficients", "Contacts",
           "Stepper", "fixed_step", "read_forces", "audit"]

INTEGRATOR = "euler"  # the one integrator that steps contact: semi-implicit Euler, impulses at the velocity level
SOLVERS = ("admm", "pgs")
# Absolute feasibility and complementarity tolerance of the cone solve (m/s for the velocities, N s for the
# impulses): the solve's residual slip is a sticking contact's creep. Measured on block_on_incline (the box must
# stick): at pin's own default, 1e-6, it creeps 2.8e-7 m/s (ADMM) and 1e-5 m/s (PGS) at dt = 1e-3; at 1e-10,
# 1.8e-11 and 6e-11 m/s at dt = 1e-3 but 9.2e-8 m/s with PGS at 1e-4 (PGS stops on its impulses' change, which
# shrinks with the step, at a residual slip of 3.4e-7 m/s); at 1e-12 both leave a slip below 2e-12 m/s at either
# step, in at most 23 iterations.
TOLERANCE_DEFAULT = 1e-12
# Iterations of the cone solve at most, pin's own default for both solvers, far above what the contact cases take
# at TOLERANCE_DEFAULT (the audit's contact_solves.max_iterations; none stops short: its unconverged count).
ITERATIONS_DEFAULT = 1000
CONTACT_OPTIONS = {
    "contact_solver": Option(SOLVERS, SOLVERS[0], "Pinocchio's cone solver of each contact step: ADMM "
                                                  "(pin.ADMMConstraintSolver, the default) or projected Gauss-Seidel "
                                                  "(pin.PGSConstraintSolver)"),
    "contact_tolerance": Option(default=TOLERANCE_DEFAULT, exclusive_minimum=0.0,
                                description=f"absolute feasibility and complementarity tolerance of the cone solve "
                                            f"(default {TOLERANCE_DEFAULT:g}; pin's own is 1e-6)"),
    "contact_iterations": Option(default=ITERATIONS_DEFAULT, minimum=1.0, integer=True,
                                 description=f"iterations of the cone solve at most (default {ITERATIONS_DEFAULT})"),
}
OPTIONS = tuple(CONTACT_OPTIONS)
# A point is in contact where its gap is at most this (m). A point in contact with a gap may close it within the
# step (``IMPACT_SPEED``), so an early activation stops nothing short; 1 um is far above the lift a step's solve
# residual leaves (tolerance x dt: 1e-13 m at the defaults, 1e-9 m at pin's own 1e-6 and 1 ms), which would
# otherwise take a resting body out of contact for a step of free fall, and far below any case's bound (1e-3 m).
CONTACT_MARGIN = 1e-6
# A point approaching faster than this (m/s) at the step's start is an impact: its post-step normal speed is
# at least -e times the approach (Newton). Slower, it is a resting contact: it may close its gap within the step
# (``-gap / h``, Anitescu-Potra's position term) and no more, so a solve's residual never leaves it hovering.
# 1e-4 m/s is the landing speed of a 0.5-nm drop, and 1e6 times the solve's residual at the default tolerance.
IMPACT_SPEED = 1e-4
# A box's 8 corners in its own axes, as multiples of its half edge lengths (dalembert.contact's order).
_CORNERS = np.array([[sx, sy, sz] for sx in (-1.0, 1.0) for sy in (-1.0, 1.0) for sz in (-1.0, 1.0)])


def why_not(scene, settings, constrained):
    """Why the contact time-stepper cannot run ``scene`` at ``settings``, or None (no contact pairs: None).
    ``constrained``: whether the model has constraints (welds as constraints, loops)."""
    if not scene.contacts:
        return None
    if settings.integrator != INTEGRATOR:
        return geometry.not_mapped(scene, f"pinocchio's {settings.integrator}",
                                   f"the contact time-stepper is semi-implicit Euler with impulses at the velocity "
                                   f"level (adapters/pinocchio/contact.py) — use --integrator {INTEGRATOR}")
    if constrained:
        return (f"contacts: with welds as constraints or loop closures — the contact step solves impulses at the "
                f"velocity level, pin.constraintDynamics the constraints at the acceleration level, and the two are "
                f"not merged into one cone problem here; use --option welds=tree (loops: not yet with contact)")
    shapes = {g.name: g for g in scene.geoms}
    for pair in scene.contacts:
        kinds = sorted(shapes[n].kind for n in (pair.a, pair.b) if n in shapes)
        if kinds == ["box", "box"] or kinds == ["box", "sphere"]:
            return (f"contacts.{pair.name}: a {' and a '.join(kinds)} — the adapter's contact detection is analytic "
                    "for sphere-plane, box-plane (its corners) and sphere-sphere only; a box against a body would "
                    "need a face-edge-corner search (or pin's GeometryModel with coal)")
    return None


def solver_settings(solver="admm", tolerance=TOLERANCE_DEFAULT, iterations=ITERATIONS_DEFAULT):
    """Pinocchio's settings object for ``solver`` (``pin.ADMMSolverSettings`` or ``pin.PGSSolverSettings``): the
    absolute feasibility and complementarity tolerances ``tolerance``, no relative ones, at most ``iterations``,
    and the nonlinear (De Saxcé) problem of an ideal Coulomb cone (``solve_ncp``)."""
    import pinocchio as pin

    settings = pin.ADMMSolverSettings() if solver == "admm" else pin.PGSSolverSettings()
    settings.absolute_feasibility_tol = settings.absolute_complementarity_tol = float(tolerance)
    settings.relative_feasibility_tol = settings.relative_complementarity_tol = 0.0
    settings.max_iterations = int(iterations)
    settings.solve_ncp = True
    return settings


def read_settings(settings):
    """What a solver settings object (``solver_settings``) holds, read back from it: dict."""
    import pinocchio as pin

    return {"solver": "pin.ADMMConstraintSolver" if isinstance(settings, pin.ADMMSolverSettings)
            else "pin.PGSConstraintSolver",
            **{k: getattr(settings, k) for k in ("absolute_feasibility_tol", "absolute_complementarity_tol",
                                                 "relative_feasibility_tol", "relative_complementarity_tol",
                                                 "max_iterations", "solve_ncp")}}


def solve_cone(G, c, mu, settings=None):
    """The contact impulses of one cone complementarity problem, by Pinocchio's solver.

    Find ``lambda`` (3k,) with each point's ``(lambda_t1, lambda_t2, lambda_n)`` in the Coulomb cone
    ``||lambda_t|| <= mu lambda_n``, and ``sigma = G lambda + c`` with each point's normal part at least
    ``mu ||sigma_t||`` (De Saxcé's correction: the nonlinear problem of an ideal Coulomb contact), the two
    complementary: a point sticks (``sigma_t = 0``) inside the cone, slips against its impulse on the cone's
    surface, and separates (``sigma_n > 0``) with no impulse.

    Parameters
    ----------
    G : ndarray (3k, 3k) — the Delassus matrix ``J M^-1 J^T`` (1/kg for a point's rows)
    c : ndarray (3k,) — the contact-frame velocity the impulses correct, m/s, per point ``(t1, t2, n)``
    mu : sequence of k floats — each point's Coulomb coefficient
    settings : pin.ADMMSolverSettings or pin.PGSSolverSettings — which solver and how (``solver_settings``;
        None: ADMM at the defaults)

    Returns
    -------
    lam : ndarray (3k,) — the impulses, N s, per point ``(t1, t2, n)``
    info : dict — ``converged`` (bool), ``iterations`` (int)
    """
    import pinocchio as pin

    settings = settings if settings is not None else solver_settings()
    cmodels, cdatas = _cones(tuple(float(m) for m in mu))
    if isinstance(settings, pin.ADMMSolverSettings):
        solver, result = pin.ADMMConstraintSolver(len(c)), pin.ADMMSolverResult()
    else:
        solver, result = pin.PGSConstraintSolver(len(c)), pin.PGSSolverResult()
    solver.solve(pin.DelassusOperatorDense(np.asarray(G, dtype=float)), np.asarray(c, dtype=float),
                 cmodels, cdatas, settings, result)
    return np.array(result.retrieveConstraintImpulses()), {"converged": bool(result.converged),
                                                          "iterations": int(result.iterations)}


_CONE_MODEL = []  # a one-joint pin.Model, built once: a PointContactConstraintModel needs a model to exist


@functools.lru_cache(maxsize=64)
def _cones(mu):
    """One ``pin.PointContactConstraintModel`` per point, its cone's coefficient ``mu[i]``, wrapped as the solvers
    take them (``pin.StdVec_ConstraintModel``) with their data. The solvers read only each model's cone and size
    from them: the Delassus matrix and the velocity carry the kinematics (``Contacts``)."""
    import pinocchio as pin

    if not _CONE_MODEL:
        model = pin.Model()
        model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "point")
        _CONE_MODEL.append(model)
    cmodels, cdatas = pin.StdVec_ConstraintModel(), pin.StdVec_ConstraintData()
    for m in mu:
        pc = pin.PointContactConstraintModel(_CONE_MODEL[0], 1)
        pc.setFriction(float(m))
        cmodels.append(pin.ConstraintModel(pc))
        cdatas.append(cmodels[-1].createData())
    return cmodels, cdatas


def cone_coefficients(mu):
    """The Coulomb coefficients of the cones the solver is given for points of coefficients ``mu``, read back
    from them (each wrapped ``PointContactConstraintModel``'s ``set``, a ``pin.CoulombFrictionCone``)."""
    cmodels, _ = _cones(tuple(float(m) for m in mu))
    out = []
    for cm in cmodels:
        pc = cm.extract()
        out.append(float(pc.set(pc.createData()).mu))
    return out


class Contacts:
    """The scene's contact pairs as the time-stepper detects them on a ``PinocchioModel`` ``pm``.

    Each pair is a sphere or a box against a plane, or two spheres (``why_not`` refuses the rest); its
    geoms ride on the joints that carry their bodies (``pm.carrier``, ``pm.frame_ids``).
    """

    def __init__(self, pm, scene):
        from dalembert.rotations import quat_to_matrix

        self.pm = pm
        shapes = {g.name: g for g in scene.geoms}
        self.pairs = []  # (pair, geom a, geom b or None, plane or None)
        for pair in scene.contacts:
            gp = geometry.geom_and_plane(scene, pair)
            if gp:
                self.pairs.append((pair, gp[0], None, gp[1]))
            else:
                self.pairs.append((pair, shapes[pair.a], shapes[pair.b], None))
        self._R_BG = {g.name: quat_to_matrix(np.asarray(g.quat) / np.linalg.norm(g.quat)) for g in scene.geoms}

    def summary(self):
        """One line per pair: what is detected and the cone and restitution it gets (``describe``)."""
        return [f"contact {pair.name}: " + (f"{a.kind} {a.name} on plane {plane.name}" if plane is not None
                                             else f"spheres {a.name}, {b.name}")
                + f", Coulomb cone mu = {pair.friction:g}, restitution {pair.restitution or 0.0:g} (Newton)"
                for pair, a, b, plane in self.pairs]

    def _geom_frame(self, geom):
        """The geom's centre (3,) and axes ``R_WG`` (3, 3) at the last kinematics (``data.oMf``)."""
        X = self.pm.data.oMf[self.pm.frame_ids[geom.body]]
        return X.rotation @ np.asarray(geom.point) + X.translation, X.rotation @ self._R_BG[geom.name]

    def _point_jacobian(self, body, p):
        """The Jacobian (3, nv) of the velocity (world) of ``body``'s material point at ``p`` (world)."""
        import pinocchio as pin

        pm = self.pm
        jid = pm.carrier[body]
        if jid == 0:  # a body welded to the world
            return np.zeros((3, pm.model.nv))
        # (reshaped: the bindings hand a one-column Jacobian, nv = 1, back as a vector)
        J6 = pin.getJointJacobian(pm.model, pm.data, jid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED).reshape(6, -1)
        r = p - pm.data.oMi[jid].translation
        skew = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
        return J6[:3] - skew @ J6[3:]

    def points(self, q):
        """The active contact points at ``q``: ``(J (3k, nv), gap (k,) m, mu (k,), e (k,))``, each point's rows
        the velocity of body a's material point relative to body b's (or the plane) in its contact frame
        ``(t1, t2, n)``, ``n`` pushing a out of b; k = 0: ``J`` is None. Refreshes the model's kinematics and
        joint Jacobians at ``q``."""
        return self.detect(q)[:4]

    def detect(self, q):
        """``points(q)`` and, per point, the index of its pair in ``scene.contacts`` (k,) and its contact frame
        ``R = (t1, t2, n)`` as columns, world axes (k, 3, 3): a point's impulse ``lambda`` (its three rows) is
        ``R lambda`` ON body a, world axes."""
        import pinocchio as pin

        model, data = self.pm.model, self.pm.data
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        rows, gaps, mus, es, owners, frames = [], [], [], [], [], []
        for index, (pair, a, b, plane) in enumerate(self.pairs):
            e = pair.restitution or 0.0
            found = []  # (point (3,) world, normal (3,), gap)
            if plane is not None:
                n, p0 = plane.unit_normal, np.asarray(plane.point)
                c, R = self._geom_frame(a)
                if a.kind == "sphere":
                    found.append((c - a.size[0] * n, n, (c - p0) @ n - a.size[0]))
                else:
                    for corner in c + (_CORNERS * (0.5 * np.asarray(a.size))) @ R.T:
                        found.append((corner, n, (corner - p0) @ n))
            else:
                ca, _ = self._geom_frame(a)
                cb, _ = self._geom_frame(b)
                d = ca - cb
                dist = np.linalg.norm(d)
                n = d / dist
                found.append((cb + b.size[0] * n, n, dist - a.size[0] - b.size[0]))
            for p, n, gap in found:
                if gap > CONTACT_MARGIN:
                    continue
                Jrel = self._point_jacobian(a.body, p) - (self._point_jacobian(b.body, p) if b is not None else 0.0)
                R = frame_with_z(n)
                rows.append(R.T @ Jrel)
                gaps.append(gap)
                mus.append(pair.friction)
                es.append(e)
                owners.append(index)
                frames.append(R)
        if not rows:
            return None, np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0, dtype=int), np.zeros((0, 3, 3))
        return (np.concatenate(rows), np.array(gaps), np.array(mus), np.array(es), np.array(owners),
                np.stack(frames))


class Stepper:
    """One step of the contact time-stepper (the module's docstring) on a ``PinocchioModel`` ``pm`` with its
    ``Contacts`` ``contacts`` and options ``typed_options(CONTACT_OPTIONS, settings)``: ``stepper(t, q, v, h) ->
    (q+, v+)``; ``forces(q, v, h)`` the contact forces of the step from ``(q, v)``. ``stats``: dict
    ``contact_steps`` (steps with an active point), ``max_points``, ``max_iterations`` and ``unconverged`` (the
    cone solves that stopped at ``contact_iterations`` short of the tolerance), ``settings`` (read back)."""

    def __init__(self, pm, contacts, options):
        import pinocchio as pin

        self.pm, self.contacts = pm, contacts
        self.acc, self.integrate = pm.acceleration_function(), pin.integrate
        self.settings = solver_settings(options["contact_solver"], options["contact_tolerance"],
                                        options["contact_iterations"])
        self.stats = {"contact_steps": 0, "max_points": 0, "max_iterations": 0, "unconverged": 0,
                      "settings": read_settings(self.settings)}
        # each FreeFlyer's (q index of its quaternion, v slice of its linear velocity)
        self.free = [(jm.idx_q + 3, jm.idx_v, jm.idx_v + 3) for jm in pm.model.joints
                     if jm.shortname() == "JointModelFreeFlyer"]

    def _turn(self, q):
        """The FreeFlyers' rotations R_WE, from their (x, y, z, w) quaternions."""
        import pinocchio as pin

        return [pin.Quaternion(q[iq + 3], *q[iq:iq + 3]).matrix() for iq, _, _ in self.free]

    def _free_velocity(self, q, v, h):
        v_free = v + h * self.acc(q, v)
        for _, i, j in self.free:  # the rate of the origin's velocity, not of its components in the turning frame
            v_free[i:j] += h * np.cross(v[j:j + 3], v[i:j])
        return v_free

    def __call__(self, t, q, v, h):
        v_next, dq, _ = self._impulses(q, v, self._free_velocity(q, v, h), h)
        move = h * v_next + dq
        q_next = self.integrate(self.pm.model, q, move)
        for (iq, i, j), R0, R1 in zip(self.free, self._turn(q), self._turn(q_next)):
            q_next[iq - 3:iq] = q[iq - 3:iq] + R0 @ move[i:j]  # the origin on a straight line, not on exp6's screw
            v_next[i:j] = R1.T @ (R0 @ v_next[i:j])  # the same velocity in the turned frame
        return q_next, v_next

    def forces(self, q, v, h):
        """The contact force (N, world axes) ON each pair's subject (``dalembert.contact.subject``: body a of the
        time-stepper's points) over the step of ``h`` s from ``(q, v)``, ndarray (n_pairs, 3): each point's impulse
        ``R lambda`` over ``h``, summed per pair (zero where a pair has no active point); one more solve (counted in ``stats``)."""
        _, _, (lam, owners, frames) = self._impulses(q, v, self._free_velocity(q, v, h), h)
        total = np.zeros((len(self.contacts.pairs), 3))
        if len(owners):
            np.add.at(total, owners, np.einsum("kij,kj->ki", frames, lam.reshape(-1, 3)) / h)
        return total

    def _impulses(self, q, v, v_free, h):
        """``(v+, dq, (lambda (3k,), pair index (k,), frames (k, 3, 3)))``: the velocity after the step's
        impulses, the depth's displacement (module docstring) and the impulses, N s, per point (t1, t2, n)."""
        import pinocchio as pin

        model, data, stats = self.pm.model, self.pm.data, self.stats
        J, gap, mu, e, owners, frames = self.contacts.detect(q)
        if J is None:
            return v_free, np.zeros(model.nv), (np.zeros(0), owners, frames)
        k = len(gap)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle
        MinvJT = np.linalg.solve(M, J.T)
        G = J @ MinvJT
        c = J @ v_free
        normal = np.arange(2, 3 * k, 3)
        approach = J[normal] @ v  # the pre-step normal speed (negative: approaching)
        impact = approach < -IMPACT_SPEED
        # an impact: Newton's post-step normal speed at least -e approach; else at least -gap / h (close the gap)
        c[normal] += np.where(impact, e * approach, np.maximum(gap, 0.0) / h)
        lam, info = solve_cone(G, c, mu, self.settings)
        stats["contact_steps"] += 1
        stats["max_points"] = max(stats["max_points"], k)
        stats["max_iterations"] = max(stats["max_iterations"], info["iterations"])
        stats["unconverged"] += not info["converged"]
        v_next = v_free + MinvJT @ lam
        depth = np.maximum(-gap, 0.0)
        dq = np.zeros(model.nv)
        if depth.any():  # post-stabilisation: the depth out in position only (module docstring, step 5)
            dq = MinvJT[:, normal] @ (np.linalg.pinv(G[np.ix_(normal, normal)]) @ depth)
        return v_next, dq, (lam, owners, frames)


def fixed_step(pm, contacts, options, q0, v0, times, steps):
    """The contact time-stepper (the module's docstring, ``Stepper``) with ``steps[k]`` steps per sample interval:
    ``(Q (n, nq), V (n, nv), steps taken, RHS evaluations, stats)``, NaN after a non-finite state
    (``dalembert.stepping.march``). ``options``: ``typed_options(CONTACT_OPTIONS, settings)``. ``stats``:
    ``Stepper.stats``."""
    from dalembert.stepping import march

    step = Stepper(pm, contacts, options)
    Q, V, n = march(step, q0, v0, times, steps)
    return Q, V, n, n, step.stats


def read_forces(p, Q, V):
    """The contact force (N, world axes) ON each scene pair's subject at each sample, ndarray (n, n_pairs, 3): the
    time-stepper's impulses over the step that starts at the sample (``Stepper.forces``; the step the run took
    from there, as MuJoCo's and Drake's read-backs give theirs), the last sample's at the last interval's step;
    NaN where the state is not finite. ``p``: the ``PinocchioPrepared`` of a contact scene (its ``contacts``)."""
    step = Stepper(p.pm, p.contacts, typed_options(CONTACT_OPTIONS, p.settings))
    times, steps = np.asarray(p.times, dtype=float), np.asarray(p.steps)
    h = np.diff(times) / steps
    h = np.append(h, h[-1]) if len(h) else np.array([float(p.settings.dt)])
    out = np.full((len(times), len(p.scene.contacts), 3), np.nan)
    for k in np.flatnonzero(np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1)):
        out[k] = step.forces(Q[k], V[k], h[k])
    return out


def audit(prepared, outcome):
    """The contact mapping and every contact parameter the run used, read back: each pair's cone coefficient
    from the ``pin.PointContactConstraintModel`` the solver is given, its restitution, the solver's settings
    as read back from the settings object that ran, and what the solves did (``fixed_step``'s stats)."""
    if not prepared.scene.contacts:
        return {}
    pairs = {}
    for pair, a, b, plane in prepared.contacts.pairs:
        (mu,) = cone_coefficients([pair.friction])
        pairs[pair.name] = {
            "detection": (f"{a.kind} {a.name} on plane {plane.name}" if plane is not None
                          else f"spheres {a.name}, {b.name}") + (": its 8 corners" if a.kind == "box" else ": 1 point"),
            "cone": "pin.PointContactConstraintModel (pin.CoulombFrictionCone)", "cone_mu": mu,
            "restitution": pair.restitution or 0.0}
    stats = dict(outcome.info.get("contact", {}))
    return {
        "contact_pairs": pairs,
        "contact_mapping": ("rigid unilateral contact at the velocity level (impulses over the step, semi-implicit "
                            "Euler); mu: each point's Coulomb cone coefficient exactly (ideal cone, the De Saxce "
                            "correction: solve_ncp); restitution e: Newton's law on the normal, post-step normal speed "
                            ">= -e times the pre-step approach speed (no restitution: e = 0); depth removed in "
                            "position only (post-stabilisation)"),
        "contact_solver": stats.pop("settings", {}),
        "contact_margin": CONTACT_MARGIN,
        "contact_solves": stats,
    }
