"""Contact forces read back from Pinocchio (the adapter's contact time-stepper), PyBullet 3.2.7 and DART 6.20
(``contact_force:<pair>``: the force ON the pair's subject, N, world, over the step that starts at the sample), all
three on semi-implicit Euler at dt = 1e-3: each force is the whole force of its step (the body's momentum balance
over the step, step by step), its normal part m g cos(angle) on the incline within the cases' bound, its friction
the closed form's, and Pinocchio's exact cone solve leaves ContactBench's residuals at roundoff. Each measured
figure a bound rests on is in its comment."""

import math

import numpy as np
import pytest

from dalembert import contact
from dalembert.case import make_case
from dalembert.settings import Settings
from engine_runs import run_case

ANGLE = math.radians(20.0)  # the cases' default slope
G = 9.81
DT = 1e-3
ENGINES = ("pinocchio", "pybullet", "dart")
MODULES = {"pinocchio": "pinocchio", "pybullet": "pybullet", "dart": "dartpy"}
# The momentum balance of one step of semi-implicit Euler on a free body, m (v+ - v) = h (f + m g), with f the
# reported contact force of that step, relative to the weight's impulse m g h: measured at most 2.3e-13 (DART's
# ball), 4.0e-14 (Pinocchio's), 5.5e-15 (PyBullet's), 1.1e-15 on the boxes; the bound leaves ~40x. A force of the
# wrong sign, or missing, is off by the load itself (~1); one of the wrong step by DART's box's swing (~1.8).
IMPULSE_REL_BOUND = 1e-11
# The friction that holds the box, m g sin(angle) up the slope, and that rolls the ball, 2/7 m g sin(angle), at
# t_final, relative: measured 2.2e-16 and 2.7e-14 (Pinocchio), 3.7e-10 and 3.2e-13 (PyBullet), DART's ball 5.4e-8;
# the bound leaves 100x above the largest.
FRICTION_REL_BOUND = 1e-5
# DART's box: FCL gives one point a step (the deepest corner), so the box rocks and each step's normal force swings
# about m g cos(angle) (measured 1.8 of it at most, per step, from 0.1 to 0.3 s); its mean over those 200 steps is
# 2.9e-3 below; the bound leaves ~3x.
DART_BOX_MEAN_REL_BOUND = 1e-2
# ContactBench's residuals on Pinocchio's exact cone solve (tolerance 1e-12 m/s and N s), as stored (over the load:
# m/s, m/s and a fraction): measured at most 1.3e-13 (dissipation, the box) and 5.5e-14 (Signorini, the ball); the
# bound leaves ~1000x, far below what the soft or iterative engines leave (PyBullet's box: 6.0e-4 Signorini).
PINOCCHIO_RESIDUAL_BOUND = 1e-10


def _case(engine, name, **params):
    pytest.importorskip(MODULES[engine])
    case, _, outcome, drifts = run_case(engine, name, Settings("euler", dt=DT), **params)
    traj = outcome.trajectory
    return case, traj, contact.contact_force(traj, case.scene.contacts[0]), drifts


def _normal_and_downhill(case):
    n = contact.geom_and_plane(case.scene, case.scene.contacts[0])[1].unit_normal
    g = np.asarray(case.scene.gravity)
    d = g - (g @ n) * n
    return n, d / np.linalg.norm(d)


@pytest.mark.parametrize("name", ["block_on_incline", "ball_rolling_incline"])
@pytest.mark.parametrize("engine", ENGINES)
def test_each_sampled_force_is_the_whole_contact_force_of_the_step_from_that_sample(engine, name):
    # sampled at every step, so each sample's force is the one step between it and the next
    case, traj, f, _ = _case(engine, name, t_final=0.3, sample_interval=DT)
    body = case.scene.bodies[0]
    m, g = body.mass, np.asarray(case.scene.gravity)
    assert f.shape == (len(traj.t), 3)
    momentum = m * np.diff(traj.bodies[body.name].velocity, axis=0)
    np.testing.assert_allclose(momentum, DT * (f[:-1] + m * g), rtol=0.0, atol=IMPULSE_REL_BOUND * m * G * DT)
    if engine == "dart" and name == "block_on_incline":  # the rocking box: its mean load (module constants)
        n, _ = _normal_and_downhill(case)
        mean = (f[traj.t >= 0.1] @ n).mean()
        assert mean == pytest.approx(m * G * math.cos(ANGLE), rel=DART_BOX_MEAN_REL_BOUND)


@pytest.mark.parametrize("engine", ENGINES)
def test_every_engine_rolls_the_ball_with_m_g_cos_and_two_sevenths_friction(engine):
    case, traj, f, drifts = _case(engine, "ball_rolling_incline")
    bound = case.tolerances["normal_force_error"].value
    assert drifts["normal_force_error"] < bound
    n, downhill = _normal_and_downhill(case)
    np.testing.assert_allclose(f[traj.t >= 0.1] @ n, G * math.cos(ANGLE), rtol=bound)
    assert -f[-1] @ downhill == pytest.approx(2.0 / 7.0 * G * math.sin(ANGLE), rel=FRICTION_REL_BOUND)
    for key in ("signorini_residual", "cone_residual", "dissipation_residual"):
        assert key in drifts  # measured where the engine reports forces


@pytest.mark.parametrize("engine", ["pinocchio", "pybullet"])
def test_pinocchio_and_pybullet_hold_the_box_with_its_weights_normal_part_and_static_friction(engine):
    case, traj, f, drifts = _case(engine, "block_on_incline")
    bound = case.tolerances["normal_force_error"].value
    assert drifts["normal_force_error"] < bound
    n, downhill = _normal_and_downhill(case)
    np.testing.assert_allclose(f[traj.t >= 0.1] @ n, G * math.cos(ANGLE), rtol=bound)
    assert -f[-1] @ downhill == pytest.approx(G * math.sin(ANGLE), rel=FRICTION_REL_BOUND)


@pytest.mark.parametrize("name", ["block_on_incline", "ball_rolling_incline"])
def test_pinocchios_exact_cone_solve_leaves_contactbenchs_residuals_at_roundoff(name):
    _, _, _, drifts = _case("pinocchio", name)
    for key in ("signorini_residual", "cone_residual", "dissipation_residual"):
        assert drifts[key] < PINOCCHIO_RESIDUAL_BOUND, key


@pytest.mark.parametrize("engine", ENGINES)
def test_the_force_of_a_pair_of_spheres_is_the_one_on_its_first_sphere(engine):
    # sphere_collision is sampled at every step (1e-3 s): the impact's impulse is in the samples
    case, traj, f, _ = _case(engine, "sphere_collision")
    pair = case.scene.contacts[0]
    push = contact.normal_force(case.scene, pair, traj)
    assert push.max() > 0.0 and push.min() >= 0.0  # pushing the spheres apart, never pulling
    a = case.scene.geom(pair.a).body
    body = next(b for b in case.scene.bodies if b.name == a)
    dp = body.mass * (traj.bodies[a].velocity[-1] - traj.bodies[a].velocity[0])  # no gravity: contact alone
    np.testing.assert_allclose(DT * f[:-1].sum(axis=0), dp, rtol=0.0, atol=IMPULSE_REL_BOUND * np.abs(dp).max())


@pytest.mark.parametrize("engine", ENGINES)
def test_a_contact_free_case_carries_no_contact_force(engine):
    pytest.importorskip(MODULES[engine])
    _, _, outcome, drifts = run_case(engine, "pivoted_rod", Settings("euler", dt=DT))
    assert not make_case("pivoted_rod").scene.contacts
    assert not any(k.startswith(contact.FORCE_PREFIX) for k in outcome.trajectory.extras)
    assert "normal_force_error" not in drifts
