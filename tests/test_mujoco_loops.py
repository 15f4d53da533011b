"""MuJoCo closes loops with soft equality constraints (``adapters/mujoco/mjcf.py``): the parallelogram
four-bar against its closed form (``cases/four_bar.py``), a ball loop against the reference, the softness
in the audit, and MJX running the same constraints (one compile)."""

import numpy as np
import pytest
from installed import needs

pytestmark = needs("mujoco")

from dalembert import Settings, invariants  # noqa: E402
from dalembert.adapters import get_adapter  # noqa: E402
from dalembert.case import make_case  # noqa: E402
from dalembert.errors import error_series  # noqa: E402
from engine_runs import run_with_audit  # noqa: E402
from dalembert.reference import simulate  # noqa: E402
from dalembert.scene import Loop, Scene  # noqa: E402

# Measured (four_bar, 0.5 s, max joint-angle error against the closed form, rad):
#   rk4   3.75e-4, 3.89e-8, 2.21e-10 at dt = 1e-2, 1e-3, 1e-4 (time constant 1 step, refsafe off)
#   euler 4.07e-4, 7.00e-6, 3.03e-8 (time constant 2 steps)
# RK4 falls 1e4-fold (fourth order) from 1e-2 to 1e-3, then 176-fold: the floor of the constraint's
# softness (impedance 0.9999) shows at 1e-4.
RK4_DECADE_DROP = 3e3  # fourth order gives 1e4 per decade of dt; measured 9.6e3 from 1e-2 to 1e-3
RK4_FLOOR = 1e-9  # rad at dt = 1e-4: measured 2.2e-10, the softness's floor, not the integrator's
EULER_DECADE_DROP = 10.0  # at least first order per decade of dt (measured 58 and 231)
# Loop-closure residual (m) at dt = 1e-3: rk4 1.24e-9, euler 1.64e-7 (measured); the soft constraint's
# spring holds it at ~ its time constant squared times the acceleration it leaves unmet.
RK4_RESIDUAL_TOL = 1e-8
EULER_RESIDUAL_TOL = 1e-6
# Energy drift (relative) of rk4 at dt = 1e-3: 4.1e-8 (measured); euler's is first order, 1.6e-3.
RK4_ENERGY_TOL = 1e-7
# The loop's reaction at dt = 1e-4 (rk4): 3.9e-5 of the largest (measured; the impedance 0.9999 leaves
# constraint forces ~1e-4 relative short); at dt = 1e-3 the sample nearest the singular position phi = pi
# is 10 % off (the soft constraint's force there is not the rigid limit), so only 1e-4 is judged.
REACTION_TOL = 1e-4


_run = run_with_audit  # (trajectory, audit) of one fixed-step run


@pytest.fixture(scope="module")
def four_bar():
    c = make_case("four_bar")
    return c, c.exact(c.times)


def _joint_error(traj, truth):
    return error_series(traj, truth)["joint"].max()


def test_rk4_converges_at_fourth_order_to_the_softness_floor(four_bar):
    c, truth = four_bar
    e = {dt: _joint_error(_run(c.scene, c.times, "rk4", dt)[0], truth) for dt in (1e-2, 1e-3, 1e-4)}
    assert e[1e-2] / e[1e-3] > RK4_DECADE_DROP
    assert e[1e-4] < RK4_FLOOR < e[1e-3]


def test_euler_converges_and_keeps_the_loop_closed(four_bar):
    c, truth = four_bar
    runs = {dt: _run(c.scene, c.times, "euler", dt)[0] for dt in (1e-2, 1e-3, 1e-4)}
    e = {dt: _joint_error(t, truth) for dt, t in runs.items()}
    assert e[1e-2] / e[1e-3] > EULER_DECADE_DROP and e[1e-3] / e[1e-4] > EULER_DECADE_DROP
    assert invariants.loop_residual(c.scene, runs[1e-3], "position").max() < EULER_RESIDUAL_TOL


def test_rk4_closure_energy_reaction_and_the_audits_softness(four_bar):
    c, truth = four_bar
    traj, audit = _run(c.scene, c.times, "rk4", 1e-3)
    assert invariants.loop_residual(c.scene, traj, "position").max() < RK4_RESIDUAL_TOL
    E = invariants.total_energy(c.scene, traj)
    assert np.abs(E - E[0]).max() / abs(E[0]) < RK4_ENERGY_TOL
    assert audit["loop_constraints"] == {"C": "connect", "C:axis": "connect"}
    assert audit["loop_solref"] == [1e-3, 1.0] and audit["loop_solimp"][:2] == [0.9999, 0.9999]
    assert "refsafe off" in audit["loop_softness"] and "impedance 0.9999" in audit["loop_softness"]
    fine, audit = _run(c.scene, c.times, "rk4", 1e-4)
    assert error_series(fine, truth)["reaction_force"].max() < REACTION_TOL  # loop and pin reactions
    _, euler = _run(c.scene, c.times, "euler", 1e-3)
    assert euler["loop_solref"] == [2e-3, 1.0] and "refsafe on" in euler["loop_softness"]


def test_a_ball_loop_is_one_connect_and_follows_the_reference():
    """The four-bar closed by a ball at C instead of the revolute (the coupler may then twist about BC;
    started without, it does not): MuJoCo rk4 at dt = 1e-4 within 2.2e-10 m of the reference's rk4 at 1e-3
    (itself 4e-12 from the closed form) and its loop reaction within 8e-5 (measured)."""
    c = make_case("four_bar", t_final=0.4)
    s = c.scene
    scene = Scene("four_bar_ball", s.bodies, s.joints, s.gravity,
                  loops=[Loop("ball", "coupler", "rocker", point_a=[0.5, 0, 0], point_b=[0.5, 0, 0], name="C")])
    ref = simulate(scene, c.times, Settings("rk4", dt=1e-3))[0]
    traj, audit = _run(scene, c.times, "rk4", 1e-4)
    assert audit["loop_constraints"] == {"C": "connect"}
    e = error_series(traj, ref)
    assert e["position"].max() < 1e-9 and e["reaction_force"].max() < REACTION_TOL


def test_distance_loops_are_unsupported_with_the_reason():
    c = make_case("four_bar")
    s = c.scene
    scene = Scene("four_bar_massless_rocker", [s.body("crank"), s.body("coupler")],
                  [j for j in s.joints if j.child != "rocker"], s.gravity,
                  loops=[Loop("distance", "world", "coupler", point_a=[1, 0, 0], point_b=[0.5, 0, 0], length=1.0)])
    reason = get_adapter("mujoco").unsupported(scene, Settings("rk4", dt=1e-3))
    assert "loop:distance" in reason and "efc_force" in reason


@pytest.mark.long
def test_mjx_runs_the_same_equality_constraints(four_bar):
    """One compile (rk4, float64, dt = 1e-3): MJX's four-bar within 1e-7 rad of the closed form (measured
    4.3e-8; MuJoCo C 3.9e-8) and its loop closed like MuJoCo C's (measured 1.6e-9 m)."""
    pytest.importorskip("mujoco.mjx")
    c, truth = four_bar
    assert get_adapter("mjx").unsupported(c.scene, Settings("rk4", dt=1e-3)) is None
    traj, audit = _run(c.scene, c.times, "rk4", 1e-3, engine="mjx", precision="float64")
    assert _joint_error(traj, truth) < 1e-7
    assert invariants.loop_residual(c.scene, traj, "position").max() < RK4_RESIDUAL_TOL
    assert audit["loop_constraints"] == {"C": "connect", "C:axis": "connect"}
