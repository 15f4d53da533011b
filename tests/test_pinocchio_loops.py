"""Pinocchio closing kinematic loops (``adapters/pinocchio/loops.py``): the parallelogram four-bar against its
closed form and the reference's reactions, a spatial four-bar closed by a ball loop against the reference
solver, a free body held by a ball loop to the world against the reference's ball joint, and what it declares."""

from __future__ import annotations

import numpy as np
import pytest
from installed import needs

pytestmark = needs("pinocchio")

from dalembert import invariants, spatial  # noqa: E402
from dalembert.adapters.registry import get_adapter  # noqa: E402
# The four-bar's one import.
from dalembert.cases.four_bar import four_bar, parallelogram_pendulum  # noqa: E402
from dalembert.reference import simulate  # noqa: E402
from dalembert.reference.closed_form import RigidPendulum  # noqa: E402
from dalembert.scene import Body, Joint, Load, Loop, Scene  # noqa: E402
from dalembert.settings import Settings  # noqa: E402

ADAPTER = get_adapter("pinocchio")

# Four-bar, default horizon (0.5 s: through the flat singular position at t = 0.23 s), crank angle against the
# closed form. Measured: rk4 3.8e-8 rad at dt = 1e-2 and 3.8e-12 at 1e-3 (fourth order: x1e4 a decade);
# the bounds leave the machine a factor ~3 and would catch a lost or wrong constraint force (>1e-3 rad).
FOUR_BAR_RK4_COARSE_TOL = 1e-7    # rad, dt = 1e-2
FOUR_BAR_RK4_FINE_TOL = 1e-11     # rad, dt = 1e-3
FOURTH_ORDER_GAIN = 1e3           # error ratio over a decade of dt: 1e4 for fourth order, 1e2 would be second
# Adaptive, rtol = atol = 1e-9, one solver over the horizon (steps set by the tolerance, not by the 0.01-s
# samples): measured dop853 1.4e-9 rad, rk45 1.2e-9 rad (restarted at every sample, as before, the sample
# interval capped their steps: 4.7e-13 and 1.1e-12); ~3x the worst, far below a lost constraint force (>1e-3).
FOUR_BAR_ADAPTIVE_TOL = 5e-9      # rad
# Their loop residual at the samples, which are read from the solver's dense output between its steps (the
# Baumgarte corrector holds it at roundoff at the steps' ends only): measured dop853 1.9e-11 m (8 steps over the
# 0.5 s), rk45 1.3e-15 m (31 steps); 5x the worst, still far below a loop that opens (the rk4 runs' 1e-12 bound
# is LOOP_POSITION_TOL).
FOUR_BAR_ADAPTIVE_LOOP_TOL = 1e-10  # m
# Loop residuals along every four-bar run above: measured <= 3.1e-14 m (position) and 2.3e-12 m/s (velocity);
# the Baumgarte corrector keeps them at roundoff, without it they grow with the integration error.
LOOP_POSITION_TOL = 1e-12         # m
LOOP_VELOCITY_TOL = 1e-10         # m/s
# Reactions (the loop's at C on the rocker and the three tree joints'), Pinocchio's rk4 at dt = 1e-3 against the
# reference's rk4 at dt = 1e-2 (its reactions are within ~1e-8 of its dt = 1e-3 ones, at a seventh of the time):
# measured 5.6e-8 of the largest (46 N), at the sample next to the flat position (0.02 rad away), where the force
# along the collinear bars is nearly indeterminate; 1e-8 elsewhere. (Against the reference at dt = 1e-3: 1.9e-7.)
REACTION_REL_TOL = 1e-6
# The spatial four-bar (ball loop) with rk4 against the reference's kane at rtol 1e-12 over 0.5 s: measured
# 5.4e-6 m at dt = 1e-2, 3.7e-10 m at 1e-3 (loop residual 4.2e-10 m, reactions 7.0e-7 N of 33 N).
RSSR_FINE_TOL = 1e-9              # m, dt = 1e-3
RSSR_LOOP_TOL = 1e-9              # m, dt = 1e-3 (the four-bar's planar geometry drifts less)
RSSR_REACTION_TOL = 1e-5          # N, dt = 1e-3
# The free body on a ball loop to the world against the reference's ball joint (an independent formulation:
# a tree, no multipliers), rk4 at dt = 1e-3 over 1 s with loads: measured 9.7e-12 m and 4.1e-10 N.
PIVOT_POSITION_TOL = 1e-10        # m
PIVOT_REACTION_TOL = 1e-8         # N


def _four_bar_run(settings, t_final=0.5):
    c = four_bar(t_final=t_final)
    ADAPTER.check(c.scene, c.times, settings)
    prepared = ADAPTER.prepare(c.scene, c.times, settings)
    outcome = ADAPTER.run(prepared)
    return c, prepared, outcome


def _closed_form_angle(times):
    return RigidPendulum(*parallelogram_pendulum()).angle(times) - np.pi / 2


def _angle_error(c, traj):
    """Largest crank, rocker and coupler angle error (rad) against the closed form: the crank and rocker turn by
    phi, the coupler (relative to the crank) by -phi."""
    phi = _closed_form_angle(c.times)
    return max(np.abs(traj.joints["crank"].q[:, 0] - phi).max(), np.abs(traj.joints["rocker"].q[:, 0] - phi).max(),
               np.abs(traj.joints["coupler"].q[:, 0] + phi).max())


@pytest.fixture(scope="module")
def four_bar_rk4():
    return {dt: _four_bar_run(Settings("rk4", dt=dt)) for dt in (1e-2, 1e-3)}


def test_four_bar_rk4_converges_to_the_closed_form_at_fourth_order(four_bar_rk4):
    errors = {dt: _angle_error(c, o.trajectory) for dt, (c, _, o) in four_bar_rk4.items()}
    assert errors[1e-2] < FOUR_BAR_RK4_COARSE_TOL
    assert errors[1e-3] < FOUR_BAR_RK4_FINE_TOL
    assert errors[1e-2] / errors[1e-3] > FOURTH_ORDER_GAIN
    for c, _, o in four_bar_rk4.values():
        assert invariants.loop_residual(c.scene, o.trajectory, "position").max() < LOOP_POSITION_TOL
        assert invariants.loop_residual(c.scene, o.trajectory, "velocity").max() < LOOP_VELOCITY_TOL
        assert o.info["loop"].startswith("Python (constraint dynamics")


def test_four_bar_reactions_agree_with_the_references(four_bar_rk4):
    c, _, o = four_bar_rk4[1e-3]
    ref = simulate(c.scene, c.times, Settings("rk4", dt=1e-2))[0]
    for key in ("reaction_force:C", "reaction_force:crank", "reaction_force:coupler", "reaction_force:rocker"):
        scale = np.abs(ref.extras[key]).max()
        assert np.abs(o.trajectory.extras[key] - ref.extras[key]).max() < REACTION_REL_TOL * scale, key


@pytest.mark.parametrize("method", ["dop853", "rk45"])
def test_four_bar_adaptive_integrators_pass_the_singular_position(method):
    c, _, o = _four_bar_run(Settings(method, rtol=1e-9, atol=1e-9))
    assert _angle_error(c, o.trajectory) < FOUR_BAR_ADAPTIVE_TOL
    assert invariants.loop_residual(c.scene, o.trajectory, "position").max() < FOUR_BAR_ADAPTIVE_LOOP_TOL


def test_four_bar_audit_records_the_constraints_regularisation_and_drift_correction(four_bar_rk4):
    from dalembert.adapters.pinocchio import loops

    _, prepared, o = four_bar_rk4[1e-3]
    audit = ADAPTER.audit(prepared, o)
    assert audit["constraint_rows"] == 6 and "2 CONTACT_3D" in audit["loops"]["C"]
    assert "3 redundant" in audit["loop_summary"]
    assert audit["proximal"]["mu_relative_to_delassus"] == loops.PROXIMAL_MU_REL and audit["proximal"]["mu"] > 0.0
    assert audit["proximal"]["max_iter"] == loops.PROXIMAL_ITERATIONS
    assert (audit["drift_correction"]["Kp"], audit["drift_correction"]["Kd"]) == loops.baumgarte()


def test_model_mass_matrix_is_the_references_in_depth_first_order():
    """constraintDynamics builds the mass matrix by crba, which needs each subtree's speeds contiguous: the
    four-bar's parents-first order (crank, rocker, coupler) put the crank-coupler coupling on the rocker."""
    import pinocchio as pin

    from dalembert.adapters.pinocchio.model import PinocchioModel, depth_first_order
    from dalembert.reference.loops import ClosedLoops

    scene = four_bar().scene
    assert [b.name for b in depth_first_order(scene)] == ["crank", "coupler", "rocker"]
    pm = PinocchioModel(scene)
    q0, _ = pm.initial_state()
    M = pin.crba(pm.model, pm.data, q0)
    M = np.triu(M) + np.triu(M, 1).T
    ref = ClosedLoops(scene)
    M_ref = ref.mass_and_forces(0.0, ref.q0, ref.v0)[0]
    names = [b.name for b in ref.order]  # the reference's speeds: parents first (crank, rocker, coupler)
    order = [names.index(pm.model.names[i]) for i in range(1, pm.model.njoints)]
    assert np.allclose(M, M_ref[np.ix_(order, order)], rtol=0, atol=1e-14)


def _frame_x(x, hint):
    """Rotation (3, 3) whose x axis is along ``x`` and whose z axis is normal to ``x`` and ``hint``."""
    x = np.asarray(x, dtype=float) / np.linalg.norm(x)
    z = np.cross(x, hint)
    z /= np.linalg.norm(z)
    return np.column_stack([x, np.cross(z, x), z])


def rssr_four_bar(t_final=0.5):
    """A spatial four-bar (revolute, ball, ball, revolute) released from rest: crank A -> B on a revolute about
    y at A, the coupler B -> C on a ball at B, the rocker D -> C on a revolute about a skew axis at D; a ball
    loop closes the coupler's tip on the rocker's at C. Every rod 1 kg (rods along their x axes); 2 degrees of
    freedom (the motion and the coupler's spin), 3 loop rows, none redundant. Geometry chosen here, closed
    at q = 0 by construction."""
    A, D = np.zeros(3), np.array([1.0, 0.3, 0.0])
    ax1, ax3 = np.array([0.0, 1.0, 0.0]), np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])
    B = A + 0.5 * np.array([0.6, 0.0, 0.8])
    u = np.cross(ax3, [1.0, 0.0, 0.0])
    C = D + 0.7 * np.sign(u[2]) * u / np.linalg.norm(u)
    L1, L2, L3 = np.linalg.norm(B - A), np.linalg.norm(C - B), np.linalg.norm(C - D)
    R1, R2, R3 = _frame_x(B - A, ax1), _frame_x(C - B, [0.0, 0.0, 1.0]), _frame_x(C - D, ax3)
    R_J1, R_J3 = spatial.frame_with_z(ax1), spatial.frame_with_z(ax3)  # revolute frames: z on the axis
    quat = spatial.matrix_to_quat
    bodies = [Body.cylinder("crank", 1.0, L1, 0.02), Body.cylinder("coupler", 1.0, L2, 0.02),
              Body.cylinder("rocker", 1.0, L3, 0.02)]
    joints = [Joint("revolute", "world", "crank", q0=[0.0], v0=[0.0], axis=[0, 0, 1], parent_point=A,
                    parent_quat=quat(R_J1), child_point=[-L1 / 2, 0, 0], child_quat=quat(R1.T @ R_J1)),
              Joint("ball", "crank", "coupler", q0=[1, 0, 0, 0], v0=[0, 0, 0], parent_point=[L1 / 2, 0, 0],
                    child_point=[-L2 / 2, 0, 0], child_quat=quat(R2.T @ R1)),
              Joint("revolute", "world", "rocker", q0=[0.0], v0=[0.0], axis=[0, 0, 1], parent_point=D,
                    parent_quat=quat(R_J3), child_point=[-L3 / 2, 0, 0], child_quat=quat(R3.T @ R_J3))]
    loops = [Loop("ball", "coupler", "rocker", point_a=[L2 / 2, 0, 0], point_b=[L3 / 2, 0, 0], name="C")]
    return Scene("rssr", bodies, joints, [0.0, 0.0, -9.81], loops=loops), np.linspace(0.0, t_final, 51)


def _run(scene, times, settings):
    prepared = ADAPTER.prepare(scene, times, settings)
    return ADAPTER.run(prepared).trajectory


def test_ball_loop_spatial_four_bar_against_the_reference():
    scene, times = rssr_four_bar()
    s = scene.loop_summary()
    assert (s.rows, s.rank, s.dof) == (3, 3, 2)
    ref = simulate(scene, times, Settings("dop853", rtol=1e-12, atol=1e-12, options={"formulation": "kane"}))[0]
    assert np.ptp(ref.joints["crank"].q[:, 0]) > 1.0  # it moves (the crank swings through 1.4 rad)
    errors = {}
    for dt in (1e-2, 1e-3):
        traj = _run(scene, times, Settings("rk4", dt=dt))
        errors[dt] = max(np.abs(traj.bodies[b].position - ref.bodies[b].position).max() for b in ref.bodies)
    assert errors[1e-3] < RSSR_FINE_TOL and errors[1e-2] / errors[1e-3] > FOURTH_ORDER_GAIN
    assert invariants.loop_residual(scene, traj, "position").max() < RSSR_LOOP_TOL
    for key in ("reaction_force:C", "reaction_force:crank", "reaction_force:coupler", "reaction_force:rocker"):
        assert np.abs(traj.extras[key] - ref.extras[key]).max() < RSSR_REACTION_TOL, key


def test_ball_loop_to_the_world_holds_a_free_body_as_the_references_ball_joint():
    """A rod on a free joint, its top held at the world point O by a ball loop (the world as body a), under
    gravity, a world force and a follower torque: the reference's rod on a ball joint at O is the same motion,
    and its joint reaction on the rod is the loop's force on it (body b)."""
    O = np.array([0.2, -0.1, 1.0])
    q_WB = spatial.quat_from_axis_angle([0.3, 1.0, 0.0], -1.2)
    R = spatial.quat_to_matrix(q_WB)
    w_W = np.array([0.5, -0.2, 3.0])
    p = O + R @ np.array([0.5, 0.0, 0.0])
    rod = Body.cylinder("rod", 1.0, 1.0, 0.02)
    loads = [Load("rod", "force", [2.0, 0.0, 1.0], "world", point=[0.5, 0, 0]), Load("rod", "torque", [0.0, 0.3, 0.1], "body")]
    looped = Scene("pivot_loop", [rod], [Joint("free", "world", "rod", q0=[*p, *q_WB], v0=[*np.cross(w_W, p - O), *R.T @ w_W])],
                   [0.0, 0.0, -9.81], loads, loops=[Loop("ball", "world", "rod", point_a=O, point_b=[-0.5, 0, 0], name="pivot")])
    tree = Scene("pivot_tree", [rod], [Joint("ball", "world", "rod", q0=q_WB, v0=R.T @ w_W, parent_point=O,
                                             child_point=[-0.5, 0, 0])], [0.0, 0.0, -9.81], loads)
    times = np.linspace(0.0, 1.0, 101)
    ref = simulate(tree, times, Settings("dop853", rtol=1e-12, atol=1e-12, options={"formulation": "kane"}))[0]
    traj = _run(looped, times, Settings("rk4", dt=1e-3))
    assert np.abs(traj.bodies["rod"].position - ref.bodies["rod"].position).max() < PIVOT_POSITION_TOL
    assert np.abs(traj.extras["reaction_force:pivot"] - ref.extras["reaction_force:rod"]).max() < PIVOT_REACTION_TOL


def test_declares_ball_and_revolute_loops_and_refuses_distance_with_its_reason():
    assert {"loop:ball", "loop:revolute"} <= ADAPTER.effects and "loop:distance" not in ADAPTER.effects
    base = four_bar().scene
    assert ADAPTER.unsupported(base, Settings("rk4", dt=1e-3)) is None
    # the coupler's tip C and a point of the rocker 1 mm short of it: 1 mm apart at every instant
    rod = Loop("distance", "coupler", "rocker", point_a=[0.5, 0, 0], point_b=[0.5 - 1e-3, 0, 0], length=1e-3, name="rod")
    scene = Scene("distance", base.bodies, base.joints, base.gravity, loops=[rod])
    reason = ADAPTER.unsupported(scene, Settings("rk4", dt=1e-3))
    assert reason.startswith("loop:distance: Pinocchio's RigidConstraintModel") and "not yet" not in reason
