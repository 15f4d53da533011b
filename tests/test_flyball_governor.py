"""The stiff flyball governor (IFToMM A05, ``cases/flyball_governor.py``): its initial geometry against the
benchmark's numbers, the folded rod's inertia against the bar's and the ball's closed forms, the truth's
invariants and its reading of the published curve, its convergence, and its stiffness."""

from __future__ import annotations

import numpy as np
import pytest

from dalembert import invariants, make_case, spatial
from dalembert.cases import flyball_governor as fg
from dalembert.errors import trajectory_errors
from dalembert.reference import simulate
from dalembert.reference.solver import STIFF_DECAY_RATE, decay_rate, truth_settings
from dalembert.settings import Settings
from truths import shared_truth

ROUNDOFF = 1e-14  # m, kg m^2: sums of a few metre-sized (kilogram-sized) terms
# LSODA (the contract's second integrator, another family than the truth's Radau) 100 times tighter: its error
# against the truth falls 160-fold from rtol 1e-8 to 1e-10 (measured: 2.6e-7 to 1.6e-9 rad or m). The fall is
# as uneven as LSODA's steps at 1e-10: with the accelerations moved by 1 to 16 roundoffs (udot * (1 + k eps)),
# it measured 36- to 325-fold at 40b4c4a and 17- to 206-fold with Kane's scalar pass (ee2304f), 12 runs each.
# At least 10-fold shows convergence to the truth; a truth off by more than LSODA's error at 1e-10 would stop it.
CONVERGENCE_RATIO = 10.0
# The folded rods' attitude and the slider's: the shaft's spin leaves them on the x-z plane turned by the
# shaft's angle; the truth keeps the mirror symmetry of the two rods to roundoff (measured 0 and 1e-16).
SYMMETRY_TOL = 1e-12


@pytest.fixture(scope="module")
def case():
    return make_case("flyball_governor")


@pytest.fixture(scope="module")
def truth(case, shared_dir):
    return shared_truth(case, shared_dir)


def test_the_initial_position_is_the_benchmarks(case):
    """[A05-CPP]: the slider's centre at s = 0.5 m up the shaft, the rods from the pins at (+-0.05, 0, 1) m
    pointing 30 degrees below the horizontal, the balls at their far ends 1 m away, the springs from the
    slider's sides to the rods' middles exactly their rest length, 0.5 m, long."""
    states = spatial.initial_body_states(case.scene)
    np.testing.assert_allclose(states["shaft"]["p"], [0.0, 0.0, 0.5], rtol=0, atol=ROUNDOFF)
    np.testing.assert_allclose(states["slider"]["p"], [0.0, 0.0, 0.5], rtol=0, atol=ROUNDOFF)
    c30, s30 = np.cos(np.pi / 6), np.sin(np.pi / 6)
    for rod, side in (("rod1", 1.0), ("rod2", -1.0)):
        R, p = states[rod]["R"], states[rod]["p"]
        along = R @ [0.0, 0.0, 1.0]  # the rod's axis, pivot -> ball
        np.testing.assert_allclose(along, [side * c30, 0.0, -s30], rtol=0, atol=ROUNDOFF)
        pivot = p - fg.ROD_COM * along
        np.testing.assert_allclose(pivot, [side * 0.05, 0.0, 1.0], rtol=0, atol=ROUNDOFF)
        np.testing.assert_allclose(pivot + along, [side * (0.05 + c30), 0.0, 0.5], rtol=0, atol=ROUNDOFF)  # ball
    initial = fg._initial_trajectory(case.scene)
    for length, rate in invariants.spring_lengths(case.scene, initial).values():
        assert abs(length[0] - 0.5) < ROUNDOFF and abs(rate[0]) < ROUNDOFF  # at rest length, not stretching
    assert case.scene.joint("shaft").v0 == (2 * np.pi,)
    assert invariants.kinetic_energy(case.scene, initial)[0] > 0.0


def test_a_rod_with_its_ball_is_the_bar_and_the_point_mass_together():
    """About the pivot (the bar's end), across the rod: m_bar (L^2 / 3 + w^2 / 12) + m_ball L^2, the bar's and
    the point's own closed forms; along the rod: the bar's m_bar w^2 / 6 alone (the ball lies on the axis)."""
    rod = fg._rod("rod")
    assert rod.mass == pytest.approx(5.3, rel=1e-15)
    I = rod.inertia_matrix
    L, w = 1.0, 0.01
    about_pivot = fg.BAR_MASS * (L**2 / 3 + w**2 / 12) + fg.BALL_MASS * L**2
    assert I[0, 0] + rod.mass * fg.ROD_COM**2 == pytest.approx(about_pivot, rel=1e-14)
    assert I[1, 1] == I[0, 0]
    assert I[2, 2] == pytest.approx(fg.BAR_MASS * w**2 / 6, rel=1e-14)
    assert rod.mass * fg.ROD_COM == pytest.approx(fg.BAR_MASS * 0.5 + fg.BALL_MASS * 1.0, rel=1e-15)


def test_the_truth_reads_the_published_curve_and_stays_inside_the_sliders_range(case, truth):
    s = truth.joints["slider"].q[:, 0]
    for t, published in fg.PUBLISHED_READINGS:
        k = int(np.argmin(np.abs(case.times - t)))
        assert abs(s[k] - published) < fg.READING_TOL, (t, s[k], published)
    assert 0.0 < s.min() and s.max() < 1.0  # OpenSim's clamp range, never reached
    assert s.max() > 0.74  # (the governor does swing)


def test_the_truth_keeps_its_invariants_and_its_symmetry(case, truth):
    """Angular momentum about the shaft (no moment about z), the energy with the dampers' dissipation, the
    joints, and the mirror symmetry of the two rods (their pin angles opposite, the slider on the axis)."""
    drifts = invariants.summary(case.scene, truth, case.conserved, case.invariants).drifts
    assert drifts["vertical_angular_momentum"] < case.tolerances["vertical_angular_momentum"].value
    assert drifts["energy_balance"] < case.tolerances["energy_balance"].value
    assert np.max(invariants.joint_residual(case.scene, truth)) < ROUNDOFF
    q1, q2 = truth.joints["rod1"].q[:, 0], truth.joints["rod2"].q[:, 0]
    assert np.abs(q1 + q2).max() < SYMMETRY_TOL
    assert np.abs(truth.bodies["slider"].position[:, :2]).max() < SYMMETRY_TOL
    # the spin falls as the balls fly out (L_z conserved, the moment of inertia about z grows)
    rate = truth.joints["shaft"].v[:, 0]
    assert rate.min() < 0.85 * rate[0]


def test_an_independent_integrator_converges_to_the_truth(case, truth):
    errors = [trajectory_errors(simulate(case.scene, case.times, Settings("lsoda", rtol=tol, atol=tol))[0],
                                truth)["joint"][0] for tol in (1e-8, 1e-10)]
    assert errors[0] / errors[1] > CONVERGENCE_RATIO, errors
    assert errors[1] < case.tolerances["joint"].value


def test_it_is_stiff_its_truth_is_radau_and_rk4_diverges_above_its_stability_bound(case):
    """The linearised equations decay at 8117 1/s (the dampers against the balls): above the threshold, so
    the truth is Radau; RK4's stability bound is 2.8 / 8117 = 3.4e-4 s, and at dt = 5e-4 it diverges within
    the first 0.01 s."""
    rate = decay_rate(case.scene)
    assert rate == pytest.approx(8117.2, rel=1e-4)
    assert rate > STIFF_DECAY_RATE
    assert truth_settings(case.scene).integrator == "radau"
    short = make_case("flyball_governor", t_final=0.05)
    run = simulate(short.scene, short.times, Settings("rk4", dt=5e-4))[0]
    assert not run.is_finite()
