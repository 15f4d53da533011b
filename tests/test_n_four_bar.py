"""The IFToMM A02 N-four-bar (``cases/n_four_bar.py``): its loop rows and rank, its closed form
(``cases/_parallelogram.py``) against the reference's constrained solver through a flat position, its energy,
and its one-window case against ``four_bar``'s closed form."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from dalembert import invariants
from dalembert.cases.four_bar import four_bar
from dalembert.cases.n_four_bar import b0, n_four_bar, n_four_bar_scene
from dalembert.errors import error_series
from dalembert.reference import integrators, simulate
from dalembert.scene import SceneError
from dalembert.settings import Settings

# RK4 at dt = 1e-2 is within 5.4e-8 rad (n = 2) and 5.7e-8 rad (n = 3) of the closed form over 1 s, through the
# first flat position (measured); a wrong mass, lever or inertia term shows at 1e-3 rad and above.
ANGLE_TOL = 2e-7
# Its velocities: 3.7e-7 m/s and 9.7e-8 rad/s (n = 2, measured); rates reach 6.8 rad/s.
VELOCITY_TOL = 2e-6
# Its reactions relative to the largest true one: 5.7e-7 (n = 2) and 1.4e-6 (n = 3, measured). For n >= 2 the
# horizontal pin forces grow as 1/sin(phi) near the flat position, so a sign or factor slip in the closed form's
# E term shows at the 1e-2 level.
REACTION_REL_TOL = 5e-6
# Halving the step divides RK4's error by 16 (measured 15.9): the agreement is the method's truncation error,
# not a modelling difference, which would not shrink; 12 leaves room for the sampling of the error's maximum.
RK4_RATIO_MIN = 12.0
# The closed form's energy, computed from its body states (invariants.total_energy, independent of the pendulum
# it comes from), stays to roundoff: measured 3e-15 relative over 20 s for n = 40.
ENERGY_REL_TOL = 1e-12
# The n = 1 row and four_bar's closed form are the same motion in other axes: roundoff only (measured 1.4e-14).
SAME_TOL = 1e-12


def test_the_scene_reports_n_loops_rank_2n_and_one_degree_of_freedom_and_n_plus_1_when_flat():
    """5 rows per revolute loop, 3 of them out of the plane; the planar 2n rows full rank, so one degree of
    freedom; at a flat position the rank drops to n and the degrees of freedom rise to n + 1 (the A02 statement)."""
    for n in (1, 2, 4):
        s = n_four_bar(n=n).scene.loop_summary()
        assert (s.loops, s.rows, s.rank, s.redundant, s.dof) == (n, 5 * n, 2 * n, 3 * n, 1)
        assert s.position_residual < 1e-15 and s.velocity_residual < 1e-14
        flat = n_four_bar_scene(n, phi0=0.0, rate0=-6.0).loop_summary()
        assert (flat.rank, flat.dof) == (n, n + 1)
    assert len(n_four_bar(n=40).scene.bodies) == 81  # the library's 2N+1 links


def test_bad_n_is_refused_with_the_fix():
    for bad in (0, 2.5, True):
        with pytest.raises(SceneError) as e:
            n_four_bar(n=bad)
        assert "n: must be a whole number of windows >= 1" in str(e.value) and "the library's is 40" in str(e.value)


def test_b0_starts_at_the_library_start_and_reaches_x_1_when_flat():
    """B0 (rocker0's tip) starts at (0, 1) moving along +x at 1 m/s, and lies at (1, 0) at the first flat
    position, 0.71436 s for n = 2 (the closed form's time, module docstring)."""
    c = n_four_bar()
    t_flat = brentq(lambda t: c.exact(np.array([t])).joints["rocker0"].q[0, 0], 0.5, 0.9, xtol=1e-14)
    assert abs(t_flat - 0.71436) < 5e-6
    truth = c.exact(np.array([0.0, t_flat]))
    np.testing.assert_allclose(b0(truth), [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]], atol=1e-12)
    assert abs(truth.bodies["rocker0"].velocity[0, 0] - 0.5) < 1e-15  # the rocker's COM: half B0's 1 m/s


@pytest.mark.parametrize("n", [2, 3])
def test_the_closed_form_is_the_reference_through_a_flat_position(n):
    """Poses, joint angles, velocities and every pin force (Newton's law on each link, the 1/sin(phi) growth
    included) against the reference's constrained Kane formulation (RK4, multipliers for the reactions)."""
    c = n_four_bar(n=n)
    truth = c.exact(c.times)
    phi = truth.joints["rocker0"].q[:, 0]
    assert phi[0] > 0.0 > phi[-1]  # the first flat position is passed
    ref = simulate(c.scene, c.times, Settings("rk4", dt=1e-2))[0]
    e = {q: s.max() for q, s in error_series(ref, truth).items()}
    assert e["position"] < ANGLE_TOL and e["orientation"] < ANGLE_TOL and e["joint"] < ANGLE_TOL
    assert e["velocity"] < VELOCITY_TOL and e["angular_velocity"] < VELOCITY_TOL
    assert e["reaction_force"] < REACTION_REL_TOL
    assert len([k for k in truth.extras if k.startswith("reaction_force:")]) == (n + 1) + n + n
    assert not any(f[:, 2].any() for f in truth.extras.values())  # nothing out of the plane
    if n == 2:  # the agreement is RK4's truncation error: a fourth of the step, 1/16 of the error
        finer = simulate(c.scene, c.times, Settings("rk4", dt=5e-3))[0]
        assert e["joint"] / error_series(finer, truth)["joint"].max() > RK4_RATIO_MIN


@pytest.mark.parametrize("n", [2, 40])
def test_the_closed_form_keeps_its_energy_over_the_librarys_20_s(n):
    c = n_four_bar(n=n, t_final=20.0, sample_interval=0.05)  # the library's 400 output steps
    E = invariants.total_energy(c.scene, c.exact(c.times))
    assert np.abs(E - E[0]).max() < ENERGY_REL_TOL * abs(E[0])


def test_one_window_is_four_bars_closed_form():
    """n = 1 is ``four_bar`` started as A02 starts (vertical, B0 at 1 m/s along +x): four_bar's plane is x-z with
    its angle from +x towards +z, this case's x-y, so its y is four_bar's z. Its loop force against four_bar's
    formula for F_C written out here (four_bar's docstring), not through the shared closed form."""
    one = n_four_bar(n=1, t_final=2.0)
    fb = four_bar(phi0=np.pi / 2, rate0=-1.0, t_final=2.0)
    a, b = one.exact(one.times), fb.exact(fb.times)
    phi = a.joints["rocker0"].q[:, 0]
    assert phi.min() < -np.pi  # both flat positions
    for mine, theirs in (("rocker0", "crank"), ("coupler1", "coupler"), ("rocker1", "rocker")):
        assert np.abs(a.joints[mine].q - b.joints[theirs].q).max() < SAME_TOL
        assert np.abs(a.bodies[mine].position[:, [0, 1]] - b.bodies[theirs].position[:, [0, 2]]).max() < SAME_TOL
    for mine, theirs in (("rocker0", "crank"), ("coupler1", "coupler"), ("rocker1", "rocker"), ("B1", "C")):
        f, g = a.extras[f"reaction_force:{mine}"], b.extras[f"reaction_force:{theirs}"]
        assert np.abs(f[:, [0, 1]] - g[:, [0, 2]]).max() < SAME_TOL * np.abs(g).max()
    m, L, grav, r = 1.0, 1.0, 9.81, 0.01
    I = 2 * (m * (3 * r**2 + L**2) / 12 + m * L**2 / 4) + m * L**2
    rate = a.joints["rocker0"].v[:, 0]
    F_Cx = m * L * rate**2 * np.cos(phi) / 2 - m**2 * grav * L**2 * np.cos(phi) * np.sin(phi) / I
    assert np.abs(a.extras["reaction_force:B1"][:, 0] - F_Cx).max() < SAME_TOL * np.abs(F_Cx).max()


def test_a_scipy_failure_in_a_projected_adaptive_run_ends_as_data_with_scipys_message(monkeypatch):
    """An adaptive step that scipy refuses (status "failed", e.g. "Required step size is less than spacing between
    numbers", which DOP853 at rtol = 1e-9 hits at this case's second flat position for n = 4, t = 1.23599 s,
    measured) ends a loop scene's run with NaN from that sample on and scipy's message: scipy's solvers keep no
    message attribute, ``step()`` returns it. Here the solvers (one per sample interval) fail from the fourth
    step of the run on."""
    taken = []

    class Failing(integrators.DOP853.stepper()):
        def _step_impl(self):
            taken.append(1)
            return (False, "refused by the test") if len(taken) > 3 else super()._step_impl()

    monkeypatch.setattr(integrators.DOP853, "stepper", classmethod(lambda cls: Failing))
    c = n_four_bar(t_final=0.05)
    traj, stats, _ = simulate(c.scene, c.times, Settings("dop853", rtol=1e-9, atol=1e-9))
    q = traj.joints["rocker0"].q[:, 0]
    assert np.isfinite(q[0]) and np.isnan(q[-1])
    assert "dop853 stopped at t = " in stats.message and stats.message.endswith(": refused by the test")
