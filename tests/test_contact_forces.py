"""Contact forces read back from each engine that reports them (``contact_force:<pair>``: the force ON the pair's
subject, N, world), against the closed forms: m g cos(angle) on the incline, the friction that holds a box or
rolls a ball; MJX's own forces agree with MuJoCo C's; and an engine that reports none leaves the normal force and
ContactBench's residuals "not measured", never within tolerance. MuJoCo 4.0 (implicitfast), Drake 1.51 (discrete SAP) at dt = 1e-3, Exudyn
1.13.6 (generalized-alpha) at 5e-4 (its bound for a loaded frictional sphere: ``exudyn.contact``); each measured
figure a bound rests on is in its comment."""

import logging
import math

import numpy as np
import pytest

from dalembert import contact
from dalembert.case import make_case
from dalembert.judge import judge
from dalembert.settings import Settings
from engine_runs import run_case

ANGLE = math.radians(20.0)  # the cases' default slope
G = 9.81
# The normal force from the cases' NORMAL_FORCE_GRACE (0.1 s) on, relative to m g cos(angle): every engine that
# reports forces is judged against the case's bound, 1 % (measured: MuJoCo's box 8.2e-4, Drake's ball 2.9e-12,
# Exudyn's ball 5.3e-9).
# The friction that holds MuJoCo's box, m g sin(angle) up the slope, at t_final: measured 3.3552176059 N against
# 3.3552176060 N; the bound leaves the creep's share of it.
FRICTION_REL_BOUND = 1e-6
# The static friction that rolls a ball down the slope, 2/7 m g sin(angle) = 0.95863 N, at t_final: measured 0.95907
# (MuJoCo), 0.95876 (Drake), 0.95873 (Exudyn): within 5e-4 of it; the bound leaves 2x.
ROLLING_FRICTION_REL_BOUND = 1e-3
# MJX's own contact forces (``mjx.contact``: mjx.forward at each sample) against MuJoCo C's on the same block, in
# float32: measured 3.5e-3 N at most over 9.2 N (float64: 1.3e-7 N), over 0.5 s and over the case's default 1 s alike
# (3.49e-3 N); the bound leaves ~3x.
MJX_FLOAT32_FORCE_BOUND = 1e-2


def _forces(engine, integrator, dt, name, **params):
    case, _, outcome, drifts = run_case(engine, name, Settings(integrator, dt=dt), **params)
    pair = case.scene.contacts[0]
    return case, outcome.trajectory, contact.contact_force(outcome.trajectory, pair), drifts


def _normal(case):
    return contact.geom_and_plane(case.scene, case.scene.contacts[0])[1].unit_normal


def _downhill(case):
    n = _normal(case)
    g = np.asarray(case.scene.gravity)
    d = g - (g @ n) * n
    return d / np.linalg.norm(d)


def test_mujoco_holds_the_box_with_its_weights_normal_part_and_static_friction():
    pytest.importorskip("mujoco")
    case, traj, f, drifts = _forces("mujoco", "implicitfast", 1e-3, "block_on_incline")
    assert f.shape == (len(traj.t), 3)
    assert drifts["normal_force_error"] < case.tolerances["normal_force_error"].value
    # the force ON the box pushes it off the plane and holds it up the slope
    assert f[-1] @ _normal(case) == pytest.approx(G * math.cos(ANGLE), rel=case.tolerances["normal_force_error"].value)
    assert -f[-1] @ _downhill(case) == pytest.approx(G * math.sin(ANGLE), rel=FRICTION_REL_BOUND)
    assert f[0] @ _normal(case) == 0.0  # placed at zero penetration: a soft contact carries nothing yet


@pytest.mark.parametrize("engine, integrator, dt", [("mujoco", "implicitfast", 1e-3), ("drake", "discrete", 1e-3),
                                                    ("exudyn", "generalized-alpha", 5e-4)])
def test_every_engine_that_reports_forces_rolls_the_ball_with_m_g_cos_and_two_sevenths_friction(engine, integrator,
                                                                                                  dt):
    pytest.importorskip({"mujoco": "mujoco", "drake": "pydrake", "exudyn": "exudyn"}[engine])
    logging.getLogger("drake").setLevel(logging.ERROR)
    case, traj, f, drifts = _forces(engine, integrator, dt, "ball_rolling_incline")
    assert drifts["normal_force_error"] < case.tolerances["normal_force_error"].value
    settled = traj.t >= 0.1
    normal = f[settled] @ _normal(case)
    np.testing.assert_allclose(normal, G * math.cos(ANGLE), rtol=case.tolerances["normal_force_error"].value)
    assert -f[-1] @ _downhill(case) == pytest.approx(2.0 / 7.0 * G * math.sin(ANGLE), rel=ROLLING_FRICTION_REL_BOUND)
    for name in ("signorini_residual", "cone_residual", "dissipation_residual"):
        assert name in drifts  # measured where the engine reports forces


@pytest.mark.parametrize("engine, integrator", [("mujoco", "implicitfast"), ("exudyn", "generalized-alpha")])
def test_the_force_of_a_pair_of_spheres_is_the_one_on_its_first_sphere(engine, integrator):
    pytest.importorskip(engine)
    case, traj, f, _ = _forces(engine, integrator, 1e-3, "sphere_collision")
    pair = case.scene.contacts[0]
    push = contact.normal_force(case.scene, pair, traj)
    assert push.max() > 0.0 and push.min() >= 0.0  # pushing the spheres apart, never pulling
    # Newton's third law through the impact: the momentum ball a gains is the impulse of the force on it
    a = case.scene.geom(pair.a).body
    body = next(b for b in case.scene.bodies if b.name == a)
    dp = body.mass * (traj.bodies[a].velocity[-1] - traj.bodies[a].velocity[0])
    assert np.sign(dp @ f.sum(axis=0)) == 1.0


def test_mjx_reports_its_own_solvers_forces_as_mujoco_c_would():
    pytest.importorskip("mujoco.mjx")
    # the case's default horizon, as test_mjx_contact's default block: the same two MJX programs (the rollout and the
    # forces over 101 samples), so a process that ran that test compiles neither again, and one that did not loads
    # them from JAX's persistent cache when it is warm (0.5 s compiled a forces program of its own, ~8 s)
    _, traj, f, drifts = _forces("mjx", "euler", 1e-3, "block_on_incline")
    _, _, f_c, _ = _forces("mujoco", "euler", 1e-3, "block_on_incline")
    assert "normal_force_error" in drifts and "signorini_residual" in drifts
    # MJX in float32 (its default): its forces are MJX's solver's, within float32 of MuJoCo C's (measured 3.5e-3 N)
    np.testing.assert_allclose(f, f_c, atol=MJX_FLOAT32_FORCE_BOUND)


def test_an_engine_that_reports_no_force_leaves_them_not_measured_never_within():
    pytest.importorskip("mujoco")
    case, traj, f, _ = _forces("mujoco", "implicitfast", 1e-3, "block_on_incline")
    for key in [k for k in traj.extras if k.startswith(contact.FORCE_PREFIX)]:
        del traj.extras[key]  # as an engine without contact forces would read back
    from dalembert import invariants

    drifts = invariants.summary(case.scene, traj, case.conserved, case.invariants).drifts
    assert "normal_force_error" not in drifts and "signorini_residual" not in drifts
    assert "creep" in drifts  # the states are measured as ever
    verdict = judge("ok", "", {}, drifts, {k: case.tolerances[k] for k in ("penetration", "normal_force_error")})
    assert verdict.within_tolerance is None and verdict.not_measured == ("normal_force_error",)


def test_a_contact_free_case_carries_no_contact_force():
    pytest.importorskip("mujoco")
    case = make_case("pivoted_rod")
    _, _, outcome, _ = run_case("mujoco", "pivoted_rod", Settings("implicitfast", dt=1e-3))
    assert not case.scene.contacts
    assert not any(k.startswith(contact.FORCE_PREFIX) for k in outcome.trajectory.extras)
