"""Closed kinematic loops: the scene vocabulary (``Loop``), its validation and closure summary, the
reference's constrained formulation (``reference.loops``) against the parallelogram four-bar's
closed form, and every engine declaring what it cannot run."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from dalembert import invariants
from dalembert.cases._four_bar import four_bar, parallelogram_pendulum
from dalembert.reference import simulate
from dalembert.reference.closed_form import RigidPendulum
from dalembert.scene import Joint, Loop, Scene, SceneError
from dalembert.settings import Settings

# RK4 at dt = 1e-3 on the four-bar is within 4.3e-12 rad of the closed form over 1 s (measured): a
# fourth-order method at this step; 1e-10 leaves room for the machine, and would catch a wrong
# force or a lost multiplier (those show at 1e-3 and above).
ANGLE_TOL = 1e-10
# The loop closes to roundoff after each projected step (measured ~1e-14).
CLOSURE_TOL = 1e-12


def _scene(**kw):
    return four_bar(**kw).scene


def test_summary_counts_loops_rows_rank_and_redundant_rows():
    s = _scene().loop_summary()
    # a revolute closing a planar loop in 3-D: 5 rows, of which the out-of-plane 3 are redundant
    assert (s.loops, s.rows, s.rank, s.redundant, s.dof) == (1, 5, 2, 3, 1)
    assert s.position_residual < 1e-15 and s.velocity_residual < 1e-14
    assert "3 redundant" in str(s)
    assert "loop:revolute" in _scene().effects


def test_an_open_initial_state_is_refused_with_its_residual():
    base = _scene()
    joints = list(base.joints)
    joints[2] = Joint(**{**joints[2].__dict__, "q0": (np.pi / 2 + 1e-3,)})
    with pytest.raises(SceneError) as e:
        Scene("open", base.bodies, joints, base.gravity, loops=base.loops)
    msg = str(e.value)
    assert "violates the closure at position level by 0.001" in msg and "LOOP_CLOSURE_TOL" in msg


def test_bad_loops_are_refused_each_naming_its_field():
    base = _scene()
    loops = [Loop("revolute", "coupler", "rockr", point_a=[0.5, 0, 0]),
             Loop("distance", "crank", "crank"),
             Loop("hinge", "world", "rocker", axis=[0, 0, 1])]
    with pytest.raises(SceneError) as e:
        Scene("bad", base.bodies, base.joints, base.gravity, loops=loops)
    msg = str(e.value)
    assert "loops[0] (revolute 'coupler' -> 'rockr').body_b: no body named 'rockr'" in msg
    assert "loops[0] (revolute 'coupler' -> 'rockr').axis: a revolute loop needs" in msg
    assert "loops[1] (distance 'crank' -> 'crank'): closes a body on itself" in msg
    assert "loops[1] (distance 'crank' -> 'crank').length: a distance loop needs" in msg
    assert "loops[2] (hinge 'world' -> 'rocker').kind: unknown 'hinge'" in msg


def test_scene_json_round_trips_loops_and_a_tree_scene_has_none():
    s = _scene()
    back = Scene.from_json(s.to_json())
    assert back.loops == s.loops and back.loops[0].name == "C"
    tree = Scene("tree", s.bodies, s.joints, s.gravity)
    assert "loops" not in tree.to_json()  # tree cases keep their versions


def test_reference_passes_the_singular_positions_on_the_parallelogram_closed_form():
    """Over 1 s the crank turns over twice-singular ground: all bars flat at phi = pi (t = 0.23 s) and the
    coupler on the rocker at phi = 2 pi (t ~ 0.6 s). Truth: the parallelogram's pendulum in closed form
    (Jacobi elliptic functions) and, independently, its ODE integrated by scipy."""
    c = four_bar(t_final=1.0)
    traj = simulate(c.scene, c.times, Settings("rk4", dt=1e-3))[0]
    m, d, I, g, theta0, rate0 = parallelogram_pendulum()
    exact = RigidPendulum(m, d, I, g, theta0, rate0).angle(c.times) - np.pi / 2
    ode = solve_ivp(lambda t, y: [y[1], -m * g * d * np.cos(y[0]) / I], (0, 1.0), [np.pi / 2, 6.0],
                    method="DOP853", rtol=1e-13, atol=1e-13, t_eval=c.times).y[0]
    assert np.abs(ode - exact).max() < 1e-11  # the two truths agree
    crank, rocker = traj.joints["crank"].q[:, 0], traj.joints["rocker"].q[:, 0]
    assert exact.max() > 2 * np.pi + 0.1  # both singular positions are passed
    assert np.abs(crank - exact).max() < ANGLE_TOL
    assert np.abs(rocker - exact).max() < ANGLE_TOL  # the parallelogram branch, not the anti-parallelogram
    assert np.abs(traj.joints["coupler"].q[:, 0] + crank).max() < ANGLE_TOL  # the coupler translates
    assert invariants.loop_residual(c.scene, traj, "position").max() < CLOSURE_TOL
    assert invariants.loop_residual(c.scene, traj, "velocity").max() < CLOSURE_TOL * 10
    E = invariants.total_energy(c.scene, traj)
    assert np.abs(E - E[0]).max() / abs(E[0]) < 1e-10


def test_loop_reaction_is_the_rockers_share_of_newtons_law():
    """The force of the closure ON the rocker at C, plus the rocker's pivot reaction and gravity, is the
    rocker's mass times its COM acceleration (the closed form's: a rod turning at phi about D)."""
    c = four_bar(t_final=0.3)
    traj = simulate(c.scene, c.times, Settings("rk4", dt=1e-3))[0]
    m, d, I, g, theta0, rate0 = parallelogram_pendulum()
    pend = RigidPendulum(m, d, I, g, theta0, rate0)
    phi, rate = pend.angle(c.times) - np.pi / 2, pend.rate(c.times)
    acc = -m * g * d * np.cos(phi) / I
    r = 0.5  # D -> rocker COM, m
    a_com = np.stack([-r * (acc * np.sin(phi) + rate**2 * np.cos(phi)), np.zeros_like(phi),
                      r * (acc * np.cos(phi) - rate**2 * np.sin(phi))], axis=1)
    total = traj.extras["reaction_force:C"] + traj.extras["reaction_force:rocker"] + np.array([0, 0, -9.81])
    assert np.abs(total - 1.0 * a_com).max() < 1e-7 * np.abs(a_com).max() + 1e-8


@pytest.mark.parametrize("engine", ["mujoco", "drake", "mjx"])  # exudyn, pinocchio: tests/test_{exudyn,pinocchio}_loops.py
def test_engines_without_loops_declare_them_unsupported(engine):
    from dalembert.adapters.registry import get_adapter

    try:
        adapter = get_adapter(engine)
    except Exception as e:  # an optional engine not installed
        pytest.skip(f"{engine}: {e}")
    reason = adapter.unsupported(_scene(), Settings(next(iter(adapter.integrators)), dt=0.01))
    assert reason and "loop:revolute" in reason and "not yet" in reason


def test_reference_declares_loops_and_refuses_formulations_without_them():
    from dalembert.adapters.registry import get_adapter

    ref = get_adapter("reference")
    assert ref.unsupported(_scene(), Settings("rk4", dt=0.01)) is None
    assert "loop closures" in ref.unsupported(_scene(), Settings("rk4", dt=0.01, options={"formulation": "planar"}))
