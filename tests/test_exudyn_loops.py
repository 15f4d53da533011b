"""Exudyn closing kinematic loops (``Scene.loops``): the parallelogram four-bar against its closed form
and the reference's reactions, spatial chains closed by a ball and by a distance loop against the
reference solver (Kane with loop multipliers, DOP853 at 1e-12), the rows each loop gives Exudyn, and
what it cannot run.

Numbers measured with Exudyn 1.13.6.
"""

import numpy as np
import pytest

from dalembert import invariants
from dalembert.adapters import get_adapter
from dalembert.adapters.exudyn.loops import LoopRows, loop_axes
from dalembert.cases.four_bar import four_bar, parallelogram_pendulum  # the one line naming the module (it may be renamed)
from dalembert.reference import simulate
from dalembert.reference.closed_form import RigidPendulum
from dalembert.settings import Settings
from bounds import ORDER_SLACK
from scenes import spatial_chain

exudyn = pytest.importorskip("exudyn")  # CI installs it: this never skips there

ADAPTER = get_adapter("exudyn")
IMPLICIT = ("generalized-alpha", "trapezoidal-index2")  # the solvers that solve constraints
# The truth of the chains: the reference's loop formulation at a tight tolerance (its closure stays
# at ~1e-14, and RK4 at dt = 1e-3 agrees with it to <= 3.4e-10 m over 1 s on these chains).
TRUTH = Settings("dop853", rtol=1e-12, atol=1e-12, options={"formulation": "kane"})

# Both solvers are second order on the four-bar over 0.5 s (through its singular position at
# t = 0.23 s), measured at dt = 1e-2, 1e-3, 1e-4: generalized-alpha 3.7e-4, 3.7e-6, 3.7e-8 rad,
# trapezoidal-index2 3.7e-4, 3.7e-6, 3.7e-8 rad.
FOUR_BAR_ANGLE_TOL = 1e-7  # rad at dt = 1e-4: 2.7x the measured 3.7e-8; a first-order method would be ~1e-4
# Closure residuals (``invariants.loop_residual``) per solver. generalized-alpha (index 3) solves the
# position rows at every step: measured <= 1.5e-15 m; its velocities are the Newmark update's, not
# constrained: measured 4.4e-6 (ball) and 4.8e-5 m/s (distance chain) at dt = 1e-3. trapezoidal-index2
# (index 2) solves the velocity rows and lets the positions drift: measured <= 1.7e-10 m on the
# four-bar (dt = 1e-2) and 2.4e-6 m on the distance chain (dt = 1e-3); velocities <= 6.4e-9 m/s.
POSITION_RESIDUAL = {"generalized-alpha": 1e-13, "trapezoidal-index2": 1e-5}  # m: roundoff; 4x the drift
CHAIN_VELOCITY_RESIDUAL = {"generalized-alpha": 5e-4, "trapezoidal-index2": 1e-7}  # m/s at dt = 1e-3: 10x, 15x
FOUR_BAR_VELOCITY_RESIDUAL = 1e-7  # m/s, both solvers at every dt: measured <= 1.1e-8 (trapezoidal, dt = 1e-2)
# Reactions at dt = 1e-3 relative to the largest of each (the loop's at C and the three tree joints'),
# against the reference's multipliers: measured <= 3.6e-6 (generalized-alpha) and 6.7e-6
# (trapezoidal-index2, at the sample nearest the singular position); a wrong frame or sign is O(1).
FOUR_BAR_REACTION_REL = 2e-5
# The chains' positions at dt = 1e-3 over 0.3 s, measured <= 2.9e-6 m (both solvers, both loops).
CHAIN_POSITION_TOL = 1e-5  # m: 3.4x the measured error
# The chains' reactions at dt = 1e-3 from t = 0.1 s on, relative to the largest loop force: measured
# <= 1.9e-4 (generalized-alpha on the distance chain; trapezoidal <= 8.4e-5). generalized-alpha's
# start-up transient (an O(dt) error of the index-3 multipliers that decays like the spectral radius
# 0.9 per step: 0.5 N at t = 0.01 s on the ball chain at dt = 1e-3, 0.05 N at 1e-4) is over by then.
CHAIN_REACTION_REL = 1e-3  # 5x the measured error; a sign or frame error is O(1)
START_UP = 0.1  # s: 100 steps of 1e-3, the transient decayed by 0.9^100 ~ 3e-5
# The four-bar in redundant coordinates (Euler-parameter nodes) with generalized-alpha at dt = 1e-3:
# measured 5.05e-5 rad (second order: 5.0e-3, 5.05e-5, 5.05e-7 at dt = 1e-2, 1e-3, 1e-4).
REDUNDANT_ANGLE_TOL = 1e-4  # rad: 2x the measured error


def _run(scene, times, integrator, dt, **options):
    return ADAPTER.run(ADAPTER.prepare(scene, times, Settings(integrator, dt=dt, options=options))).trajectory


def _closed_form_angle(times):
    m, d, I, g, theta0, rate0 = parallelogram_pendulum()
    return RigidPendulum(m, d, I, g, theta0, rate0).angle(times) - np.pi / 2


@pytest.fixture(scope="module")
def four_bar_truth():
    c = four_bar()
    return c, simulate(c.scene, c.times, TRUTH)[0]


@pytest.fixture(scope="module", params=["ball", "distance"])
def chain_truth(request):
    scene = spatial_chain(request.param)
    times = np.linspace(0.0, 0.3, 31)
    return scene, times, simulate(scene, times, TRUTH)[0]


def test_each_loop_gives_exudyn_its_independent_rows():
    """The four-bar's revolute at C keeps its two in-plane translations; the out-of-plane translation
    and both tilts are implied by the tree's parallel axes (the scene's summary: 3 of 5 redundant)."""
    rows = loop_axes(four_bar().scene)
    assert rows == {"C": LoopRows((1, 1, 0, 0, 0, 0), ("translation z", "rotation x", "rotation y"))}
    assert loop_axes(spatial_chain("ball")) == {"tip": LoopRows((1, 1, 1, 0, 0, 0), ())}
    assert loop_axes(spatial_chain("distance")) == {"tip": LoopRows((1,), ())}
    assert "left out: translation z, rotation x, rotation y" in ADAPTER.describe(
        four_bar().scene, Settings("generalized-alpha", dt=1e-3))


def test_all_five_rows_stop_exudyns_dense_solver(monkeypatch):
    """Why the rows are chosen (``exudyn.loops``): with the redundant rows, Exudyn's Newton matrix is
    singular and its default solver stops at the first step."""
    from dalembert.adapters.exudyn import model

    monkeypatch.setattr(model, "loop_axes", lambda scene: {"C": LoopRows((1, 1, 1, 1, 1, 0), ())})
    c = four_bar()
    with pytest.raises(RuntimeError, match="not factorized"):
        _run(c.scene, c.times, "generalized-alpha", 1e-3)


@pytest.mark.parametrize("integrator", IMPLICIT)
def test_four_bar_follows_its_closed_form_at_second_order(integrator):
    """Minimal coordinates (the kinematic tree with the loop's joint on markers of its links), through
    the singular position at t = 0.23 s on the parallelogram branch (the rocker turns with the crank)."""
    c = four_bar()
    exact = _closed_form_angle(c.times)
    errors = []
    for dt in (1e-2, 1e-3, 1e-4):
        traj = _run(c.scene, c.times, integrator, dt)
        errors.append(max(np.abs(traj.joints[b].q[:, 0] - exact).max() for b in ("crank", "rocker")))
        assert invariants.loop_residual(c.scene, traj).max() < POSITION_RESIDUAL[integrator]
        assert invariants.loop_residual(c.scene, traj, "velocity").max() < FOUR_BAR_VELOCITY_RESIDUAL
    assert errors[-1] < FOUR_BAR_ANGLE_TOL
    for coarse, fine in zip(errors, errors[1:]):
        assert np.log10(coarse / fine) == pytest.approx(2, abs=ORDER_SLACK)


@pytest.mark.parametrize("integrator", IMPLICIT)
def test_four_bar_reactions_agree_with_the_references(integrator, four_bar_truth):
    """The loop's force ON the rocker at C (from the joint's ForceLocal) and the tree joints' reactions
    (Newton's law per link, the loop's force included) against the reference's multipliers."""
    c, truth = four_bar_truth
    traj = _run(c.scene, c.times, integrator, 1e-3)
    for key in ("reaction_force:C", "reaction_force:crank", "reaction_force:coupler", "reaction_force:rocker"):
        scale = np.abs(truth.extras[key]).max()
        assert np.abs(traj.extras[key] - truth.extras[key]).max() < FOUR_BAR_REACTION_REL * scale, key


def test_four_bar_in_redundant_coordinates():
    """Rigid bodies on Euler-parameter nodes, every joint and the loop an ObjectJointGeneric: the same
    motion at the same order (measured 5.05e-5 rad at dt = 1e-3; the kinematic tree 3.7e-6)."""
    c = four_bar()
    traj = _run(c.scene, c.times, "generalized-alpha", 1e-3, joints="redundant", node="ep")
    exact = _closed_form_angle(c.times)
    assert max(np.abs(traj.joints[b].q[:, 0] - exact).max() for b in ("crank", "rocker")) < REDUNDANT_ANGLE_TOL
    assert invariants.loop_residual(c.scene, traj).max() < POSITION_RESIDUAL["generalized-alpha"]


@pytest.mark.parametrize("integrator", IMPLICIT)
def test_spatial_chains_against_the_reference(integrator, chain_truth):
    scene, times, truth = chain_truth
    errors = []
    for dt in (1e-2, 1e-3):
        traj = _run(scene, times, integrator, dt)
        errors.append(max(np.abs(traj.bodies[b].position - truth.bodies[b].position).max() for b in truth.bodies))
    assert errors[-1] < CHAIN_POSITION_TOL
    assert np.log10(errors[0] / errors[1]) == pytest.approx(2, abs=ORDER_SLACK)
    assert invariants.loop_residual(scene, traj).max() < POSITION_RESIDUAL[integrator]
    assert invariants.loop_residual(scene, traj, "velocity").max() < CHAIN_VELOCITY_RESIDUAL[integrator]
    late = times >= START_UP - 1e-12
    force, exact = traj.extras["reaction_force:tip"][late], truth.extras["reaction_force:tip"][late]
    assert np.abs(force - exact).max() < CHAIN_REACTION_REL * np.abs(truth.extras["reaction_force:tip"]).max()


def test_loops_need_an_implicit_solver_and_the_audit_says_what_ran():
    c = four_bar()
    reason = ADAPTER.unsupported(c.scene, Settings("rk44", dt=1e-3))
    assert reason and "explicit" in reason and "generalized-alpha" in reason
    for integrator in IMPLICIT:
        for options in ADAPTER.variants(c.scene):
            assert ADAPTER.unsupported(c.scene, Settings(integrator, dt=1e-3, options=options)) is None
    settings = Settings("generalized-alpha", dt=1e-2)
    prepared = ADAPTER.prepare(c.scene, c.times, settings)
    outcome = ADAPTER.run(prepared)
    audit = ADAPTER.audit(prepared, outcome)
    assert audit["constraints"] == 2  # the kinematic tree has none; the loop's two in-plane rows
    assert "ObjectJointGeneric (revolute), 2 row(s)" in audit["loops"]["closures"]["C"]
    assert "3 redundant" in audit["loops"]["scene"]
