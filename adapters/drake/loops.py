"""Loop closures (``Scene.loops``) as ``MultibodyPlant`` constraints, solved by SAP in discrete mode.

Each loop becomes Drake constraints between the bodies that carry its two sides (body a, body b;
Drake's body frames are the scene's body frames, so the loop's points go in as they are):

* ``ball``: one ``AddBallConstraint`` at the loop point (3 equations);
* ``revolute``: two ball constraints, at the loop point and ``lever`` metres along the loop's axis
  on both sides (6 equations). Two points of the axis held together leave exactly the rotation
  about the line through them free: the revolute's five conditions plus one that repeats the rigid
  distance between the two points (always redundant). Drake's weld constraint cannot release a
  rotation and has no revolute constraint, so two points, as the Pinocchio adapter does
  (``dalembert.adapters.pinocchio.loops``; ``lever`` chosen by the same rule, ``lever``);
* ``distance``: one ``AddDistanceConstraint`` (1 equation), ``stiffness = inf`` and
  ``damping = 0``, Drake's rigid massless rod.

How stiff (read in Drake's source, ``multibody/contact_solvers/sap``: ``SapBallConstraint``,
``SapDistanceConstraint``, ``SapHolonomicConstraint``). Every one of these is a
``SapHolonomicConstraint``; with infinite stiffness (the ball's always, the distance's with
``stiffness = inf``) SAP puts it in its *near-rigid* regime: the regularization of each equation is
``R = beta^2 / (4 pi^2) w`` (``w`` the diagonal of the Delassus operator, ``beta = 0.1`` fixed in
Drake's source, not exposed) and the constraint's own relaxation time is the time step, so the gap
``g`` is driven back as ``-g / (2 dt)`` in the step's velocity: a constraint as stiff as the step can
resolve, whose softness and drift shrink with ``dt`` (measured: ``tests/test_drake_loops.py``). No
compliant setting is stiffer: a finite stiffness ``k`` with ``1 / (dt^2 k) < R`` is clamped to
the same regime. Redundant equations (the revolute's own, and those of a planar loop closed by a
3-D joint) are harmless: the regularization makes SAP's problem strictly convex.

Only in discrete mode: Drake's continuous-time plant refuses constraints when it is simulated
("Continuous time does not support constraints"), so Drake's integrators cannot close loops
(``CONTINUOUS_REASON``).

The world as a side: Drake 1.51 crashes (a segmentation fault in ``SapDriver::AddBallConstraints``,
``SpanningForest::Tree::nv``; the same for a distance constraint) on a constraint whose body is the
world body, measured on a single rod. A loop to the world is attached instead to ``ANCHOR``, a body
welded to the world at the world frame (its pose is the world's, so the loop's world point goes in
as it is); welded to the world it has no coordinates and its mass moves nothing.

Accuracy (the parallelogram four-bar over 0.5 s, ``tests/test_drake_loops.py``): crank angle
3.4e-4 / 3.1e-6 / 2.1e-7 rad from the closed form at dt = 1e-2 / 1e-3 / 1e-4, the loop's gap
1.3e-5 / 2.1e-8 / 2.1e-10 m (as dt^2). Below 1e-4 the error grows again (1.2e-3 rad at 1e-5,
linear in time from the start): SAP stops its Newton iterations when the momentum residual is
below 1e-6 of the whole momentum (``SapSolverParameters.rel_tolerance``, not exposed in pydrake),
an error per step that adds up over more steps (our reading of the measurement, not verified in
Drake).

Reactions: Drake reports no constraint forces: its ``reaction_forces`` port is the tree joints'
(whose values do include the constraints' push), its generalized contact forces and contact
results hold contacts only (zero on the four-bar, measured), and SAP's impulses stay inside the
plant. ``reaction_force:<loop>`` is recovered from the step instead (``LoopForces``): the
generalized force the constraints applied, from Drake's own acceleration, mass matrix, bias and
gravity terms, resolved on the loop's rows. First order in dt like the motion (4.8e-4 of the
largest reaction at dt = 1e-3 on the four-bar), but near the flat singular position, where SAP's
near-rigid force along the bars is not the rigid one (0.25 at the sample 2 ms after it at dt = 1e-3,
4.4e-4 at 1e-4). And the first step: SAP holds a constraint at the velocity level, ``J(q_n) v_n+1``
driven to ``-g / (2 dt)``, which has no velocity-product term (the points' relative centripetal
acceleration); from the second step on, the O(dt) constraint velocity each step leaves carries it,
but the step from a state exactly on the constraint (t = 0) applies a force short of it: on a
tilted hinge (``tests/test_drake_loops.py``) 0.2 of the largest reaction at every dt, on the
parallelogram four-bar nothing (its coupler translates: no relative centripetal term). Checked on
the hinge at dt = 1e-3: the force's shortfall, (1.408, 0.986, 0.658) N, is the velocity-product share
``-(J M^-1 J^T)^+ Jdot v`` of the rigid force, (1.409, 0.979, 0.670) N. The read-back reports the force
Drake applied.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert import spatial
from dalembert.lstsq import lstsq_stacked
from dalembert.scene import WORLD

__all__ = ["LOOP_KINDS", "CONTINUOUS_REASON", "ANCHOR", "LoopConstraints", "add_loops", "lever", "LoopForces"]

# The loop kinds built here: all of them, in discrete mode.
LOOP_KINDS = ("ball", "revolute", "distance")
CONTINUOUS_REASON = ("Drake's continuous-time MultibodyPlant takes no constraints (ball, distance, weld: SAP "
                     "constraints, solved only in the discrete update; simulating them raises \"Continuous time "
                     "does not support constraints\"), so its integrators cannot close loops — use the integrator "
                     "'discrete'")
# The body that stands for the world in loop constraints (module docstring); not a scene body.
ANCHOR = "dalembert_world_anchor"


@dataclass(frozen=True, eq=False)  # (arrays: identity is equality)
class LoopConstraints:
    """One loop's Drake constraints: ``loop`` (``Loop``), ``ids`` (``MultibodyConstraintId``s),
    ``lever`` (m, the revolute's second point along the axis; 0 otherwise), the Drake bodies of its sides
    ``body_a``, ``body_b`` (``ANCHOR`` for the world) and the constrained points ``points_a``,
    ``points_b`` ((3, k) m, each side's body frame, one column per ball constraint: the read-back's rows
    are at the points the constraints hold); ``force_map`` (3, 3 k): the balls' multipliers to the force ON
    B (N, world; a distance's is the state's unit vector, ``_rows``)."""

    loop: object
    ids: tuple
    lever: float
    body_a: object
    body_b: object
    points_a: np.ndarray
    points_b: np.ndarray
    force_map: np.ndarray


def lever(loop):
    """The revolute's second point along the axis (m): the larger distance of the loop point from the
    two bodies' COMs (a world side does not count), or 1 m: the second point's equations then weigh the
    axis tilt as the bodies' own rotations move the loop point (equations of one scale)."""
    arms = [float(np.linalg.norm(p)) for body, p in ((loop.body_a, loop.point_a), (loop.body_b, loop.point_b))
            if body != WORLD]
    return max(arms, default=0.0) or 1.0


def add_anchor(plant):
    """``ANCHOR``: a unit-mass body welded to the world at the world frame (module docstring)."""
    from pydrake.math import RigidTransform
    from pydrake.multibody.tree import SpatialInertia

    anchor = plant.AddRigidBody(ANCHOR, SpatialInertia.SolidSphereWithMass(1.0, 0.1))
    plant.WeldFrames(plant.world_frame(), anchor.body_frame(), RigidTransform())
    return anchor


def add_loops(plant, scene, bodies):
    """Add every loop of ``scene`` to ``plant`` (discrete, not finalized; ``bodies``: name -> ``RigidBody``);
    a ``LoopConstraints`` per loop."""
    anchor = add_anchor(plant) if any(WORLD in (lp.body_a, lp.body_b) for lp in scene.loops) else None
    side = lambda name: anchor if name == WORLD else bodies[name]  # noqa: E731
    out = []
    for loop in scene.loops:
        A, B = side(loop.body_a), side(loop.body_b)
        p_AP, p_BQ = np.asarray(loop.point_a, dtype=float), np.asarray(loop.point_b, dtype=float)
        arm, pairs = 0.0, [(p_AP, p_BQ)]
        if loop.kind == "distance":
            ids = (plant.AddDistanceConstraint(A, p_AP, B, p_BQ, loop.length),)  # stiffness inf, damping 0
        elif loop.kind == "ball":
            ids = (plant.AddBallConstraint(A, p_AP, B, p_BQ),)
        else:
            arm = lever(loop)
            axis = np.asarray(loop.axis, dtype=float) / np.linalg.norm(loop.axis)  # in Ja and in Jb
            a_A = spatial.quat_to_matrix(loop.quat_a) @ axis  # the axis in A's and in B's body frame
            a_B = spatial.quat_to_matrix(loop.quat_b) @ axis
            pairs.append((p_AP + arm * a_A, p_BQ + arm * a_B))
            ids = tuple(plant.AddBallConstraint(A, p, B, q) for p, q in pairs)
        points_a, points_b = (np.stack(side, axis=1) for side in zip(*pairs))
        out.append(LoopConstraints(loop, ids, arm, A, B, points_a, points_b, np.tile(np.eye(3), len(pairs))))
    return out


class _Rows:
    """The loops' constraint rows at a state: called with a plant context, per loop ``(J (k, nv), D (3, k))``:
    the rows in the generalized velocities (the velocity of point Q on B relative to P on A, per ball; along the
    unit vector P -> Q for a distance) and the map from the rows' multipliers to the force ON B (N, world). The
    frames are looked up once, at construction: a read-back calls it at every sample."""

    def __init__(self, model):
        from pydrake.multibody.tree import JacobianWrtVariable

        self.plant, self.wrt, self.world = model.plant, JacobianWrtVariable.kV, model.plant.world_frame()
        self.loops = [(lc, lc.body_a.body_frame(), lc.body_b.body_frame()) for lc in model.loops]

    def __call__(self, context):
        plant, wrt, W = self.plant, self.wrt, self.world
        out = []
        for lc, A, B in self.loops:  # three rows per point, one Drake call per side for all its points
            J = (plant.CalcJacobianTranslationalVelocity(context, wrt, B, lc.points_b, W, W)
                 - plant.CalcJacobianTranslationalVelocity(context, wrt, A, lc.points_a, W, W))
            if lc.loop.kind == "distance":
                d = (plant.CalcPointsPositions(context, B, lc.points_b, W).ravel()
                     - plant.CalcPointsPositions(context, A, lc.points_a, W).ravel())
                u = d / np.linalg.norm(d)
                out.append(((u @ J)[None], u[:, None]))
            else:
                out.append((J, lc.force_map))
        return out


class LoopForces:
    """The force of each loop ON its body b (N, world) over a run's samples: ``add`` reads the engine's terms at
    one sample's state, ``forces`` resolves them all at once.

    SAP's step solves ``M (v' - v) / dt = tau(q, v) - C(q, v) v + J^T gamma / dt`` (no joint damping, no
    contact: the ``kLagged`` approximation changes contact only; ``tau`` holds gravity, the loads and the
    spring-dampers, all explicit at ``(q, v)``: ``springs``), so the constraints' generalized force is
    ``tau_c = M a + C v - tau_g - tau_springs - tau_loads`` (Drake's ``CalcInverseDynamics`` with the applied
    forces) with ``a = (v' - v) / dt`` the plant's generalized acceleration (its output port, evaluated from
    this state: ``SetUseSampledOutputPorts(False)``). The loop forces ``f`` solve ``J^T f = tau_c`` in the
    least-squares, minimum-norm sense (singular values at or below ``rcond`` of the largest cut, as the reference
    cuts its redundant rows: ``closure.RANK_RTOL``), so a redundant row (the revolute's own, a planar loop's
    out-of-plane ones) carries no force, and a revolute's two points add up to its total force.

    Parameters
    ----------
    model : DrakeModel (with ``loops``)
    rcond : float — the relative singular-value cut
    """

    def __init__(self, model, rcond):
        from pydrake.multibody.tree import MultibodyForces

        self.model, self.rcond = model, rcond
        self._applied = MultibodyForces(model.plant)  # reused: zeroed at every sample
        self._rows, self._acceleration = _Rows(model), model.plant.get_generalized_acceleration_output_port()
        self._J, self._tau, self._D = [], [], []

    def add(self, context, plant_context):
        """Read the step's terms at the state in ``plant_context`` (``context``: the diagram's, for the loads)."""
        model, plant, forces = self.model, self.model.plant, self._applied
        a = self._acceleration.Eval(plant_context)
        forces.SetZero()
        plant.CalcForceElementsContribution(plant_context, forces)  # gravity and the spring-dampers, at (q, v)
        if model.loads is not None:
            for F in model.loads.get_output_port(0).Eval(model.loads.GetMyContextFromRoot(context)):
                body = plant.get_body(F.body_index)
                R_WB = plant.EvalBodyPoseInWorld(plant_context, body).rotation().matrix()
                body.AddInForce(plant_context, R_WB @ F.p_BoBq_B, F.F_Bq_W, plant.world_frame(), forces)
        self._tau.append(plant.CalcInverseDynamics(plant_context, a, forces))  # M a + C v - tau_applied
        rows = self._rows(plant_context)
        self._J.append(np.concatenate([J for J, _ in rows]))
        self._D.append([D for _, D in rows])

    def forces(self):
        """Per loop, its force ON body b at every sample added (dict loop name -> (m, 3)): one stacked SVD of
        the samples' ``J^T`` for the minimum-norm least-squares solves (``np.linalg.lstsq``'s, each sample's
        own cut)."""
        if not self._tau:
            return {lc.loop.name: np.zeros((0, 3)) for lc in self.model.loops}
        f = lstsq_stacked(np.stack(self._J).swapaxes(-1, -2), np.stack(self._tau), self.rcond)
        out, k = {}, 0
        for i, lc in enumerate(self.model.loops):
            n = self._D[0][i].shape[1]
            D = np.stack([Ds[i] for Ds in self._D])
            out[lc.loop.name] = np.einsum("mij,mj->mi", D, f[:, k:k + n])
            k += n
        return out
