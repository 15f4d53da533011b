"""Pinocchio adapter against the closed forms, the reference, and its own conventions."""

import numpy as np
import pytest

from dalembert.adapters import get_adapter
from dalembert import Settings, make_case, spatial
from dalembert.errors import trajectory_errors
from dalembert.scene import Body, Joint, Scene
from dalembert.reference import simulate
from bounds import (BOX_COM_TOL, BOX_ORIENTATION_TOL, CROSS_CHECK_TOL, ORDER_SLACK, ROD_ANGLE_TOL,
                    ROD_REACTION_TOL, TOP_ORIENTATION_TOL)
from scenes import chain_case, free_body_world_loads_case

pin = pytest.importorskip("pinocchio")  # CI installs it: this never skips there

ADAPTER = get_adapter("pinocchio")
ROUND_TRIP_TOL = 1e-15
# rk45 and dop853 at rtol = atol = 1e-10 over 5 s, one solver over the horizon (its steps set by the tolerance,
# not by the 0.01-s samples): local error control lets the global error grow over the motion; measured 1.9e-10
# and 1.1e-10 rad (restarted at every sample, as before, the sample interval was their step: 1.5e-12 and
# 1.1e-14). 100x rtol: a wrong dexp^-1 or a chart moved wrongly between steps costs far more.
ADAPTIVE_TOL = 1e-8


def errors(case, settings):
    out = ADAPTER.run(ADAPTER.prepare(case.scene, case.times, settings))
    return trajectory_errors(out.trajectory, case.exact(case.times))


def test_lie_group_rk4_matches_the_closed_forms():
    s = Settings("rk4", dt=1e-3)
    rod = errors(make_case("pivoted_rod"), s)
    assert rod["joint"][0] < ROD_ANGLE_TOL and rod["reaction_force"][0] < ROD_REACTION_TOL
    assert errors(make_case("free_top"), s)["orientation"][0] < TOP_ORIENTATION_TOL
    box = errors(make_case("particle_box"), s)
    assert box["position"][0] < BOX_COM_TOL and box["orientation"][0] < BOX_ORIENTATION_TOL


@pytest.mark.parametrize("integrator,expected,dt", [("euler", 1, 2e-3), ("rk4", 4, 1e-2), ("rk4-naive", 2, 1e-2)])
def test_convergence_order(integrator, expected, dt):
    """``rk4-naive`` takes the stage tangents as the stage velocities v_i, where the Lie-group form
    takes dexp^-1_theta_i(v_i) = v_i - [theta_i, v_i] / 2 + ... (Runge-Kutta-Munthe-Kaas: A.
    Iserles, H. Munthe-Kaas, S. Norsett, A. Zanna, "Lie-group methods", Acta Numerica 9 (2000)
    215-365). The stage angles theta_i are O(h) and the v_i differ by O(h), so each bracket is
    O(h^2), and with the classical weights the missing terms add up to h^3 [v, v'] / 12 per step,
    which vanishes only if the angular velocity and its rate are parallel (not on the top): local
    error O(h^3), second order."""
    top = make_case("free_top", t_final=2.0)
    e1, e2 = (errors(top, Settings(integrator, dt=h))["orientation"][0] for h in (dt, dt / 2))
    assert np.log2(e1 / e2) == pytest.approx(expected, abs=ORDER_SLACK)


def test_adaptive_integrators_reach_their_tolerance():
    top = make_case("free_top", t_final=5.0)
    for method in ("rk45", "dop853"):
        assert errors(top, Settings(method, rtol=1e-10, atol=1e-10))["orientation"][0] < ADAPTIVE_TOL


def test_gravity_free_scene_has_zero_gravity_in_the_model():
    prepared = ADAPTER.prepare(make_case("free_top").scene, make_case("free_top").times, Settings("rk4", dt=1e-2))
    assert np.array_equal(prepared.pm.model.gravity.linear, np.zeros(3))
    box = make_case("particle_box")
    prepared = ADAPTER.prepare(box.scene, box.times, Settings("rk4", dt=1e-2))
    assert np.array_equal(prepared.pm.model.gravity.linear, [0.0, 0.0, -9.8])


def test_conventions_round_trip_exactly():
    """Random free-body states through spatial.py into Pinocchio's q, v and back."""
    rng = np.random.default_rng(3)
    for _ in range(20):
        quat = spatial.quat_normalize(rng.normal(size=4))
        q0 = [*rng.normal(size=3), *quat]
        v0 = rng.normal(size=6)
        scene = Scene("s", [Body("b", 1.0, np.diag([1.0, 2.0, 2.5]))], [Joint("free", "world", "b", q0, v0)],
                      gravity=(0, 0, 0))
        times = np.array([0.0, 0.01])
        prepared = ADAPTER.prepare(scene, times, Settings("euler", dt=0.01))
        b = ADAPTER.run(prepared).trajectory.bodies["b"]
        assert np.max(np.abs(b.position[0] - q0[:3])) <= ROUND_TRIP_TOL
        assert spatial.rotation_angle(b.quaternion[0], quat) <= 2 * ROUND_TRIP_TOL
        assert np.max(np.abs(b.velocity[0] - v0[:3])) <= 4 * ROUND_TRIP_TOL
        assert np.max(np.abs(b.angular_velocity_body[0] - v0[3:])) <= 8 * ROUND_TRIP_TOL


@pytest.mark.parametrize("make", [chain_case, free_body_world_loads_case])
def test_every_joint_kind_frame_and_load_against_the_reference(make):
    case = make()
    ref = simulate(case.scene, case.times, Settings("dop853", rtol=1e-12, atol=1e-12,
                                                    options={"formulation": "kane"}))[0]
    out = ADAPTER.run(ADAPTER.prepare(case.scene, case.times, Settings("rk4", dt=1e-3))).trajectory
    for q, (mx, _) in trajectory_errors(out, ref).items():
        assert mx < CROSS_CHECK_TOL, q


# The compiled and the Python loops do the same arithmetic in a different order here and there
# (Eigen's and numpy's sums): they agree to roundoff, relative to the state's size (measured:
# <= 4e-15 relative on the particle box over 20 s, 1e-15 rad on the top).
LOOPS_AGREE_REL = 1e-12


@pytest.mark.parametrize("integrator", ["euler", "rk4", "rk4-naive"])
@pytest.mark.parametrize("make", [chain_case, free_body_world_loads_case,
                                  lambda: make_case("pivoted_rod"), lambda: make_case("particle_box", t_final=2.0)])
def test_the_compiled_loop_is_the_python_loop(make, integrator):
    """Every joint kind, follower and world loads, each dexp^-1 (identity, Jlog6, dIntegrate solve)."""
    case = make()
    runs = {}
    for loop in ("native", "python"):
        out = ADAPTER.run(ADAPTER.prepare(case.scene, case.times, Settings(integrator, dt=1e-3, options={"loop": loop})))
        runs[loop] = out
    assert runs["native"].info["loop"].startswith("C++"), runs["native"].info["loop"]
    assert runs["native"].n_steps == runs["python"].n_steps
    for name, b in runs["native"].trajectory.bodies.items():
        c = runs["python"].trajectory.bodies[name]
        for field in ("position", "quaternion", "velocity", "angular_velocity"):
            x, y = getattr(b, field), getattr(c, field)
            scale = max(1.0, float(np.max(np.abs(y))))
            assert np.max(np.abs(x - y)) <= LOOPS_AGREE_REL * scale, (name, field)


# welds=constraint, rk4 at dt = 1e-3 over 0.5 s on the welded particle box (measured: COM
# 5.1e-13 m, attitude 9.0e-14 rad, welds stretched 9.4e-14 m — constraintDynamics meets the
# welds at the acceleration level, so only the integrator's roundoff moves them): 100x.
WELD_CONSTRAINT_TOL = 1e-10


def test_welds_as_constraints_hold_the_box():
    """27 FreeFlyers held by 26 6D constraints through pin.constraintDynamics: the rigid body's
    closed form, and pairwise distances kept to roundoff."""
    from dalembert import invariants

    case = make_case("particle_box_welded", t_final=0.5)
    settings = Settings("rk4", dt=1e-3, options={"welds": "constraint"})
    prepared = ADAPTER.prepare(case.scene, case.times, settings)
    assert len(prepared.pm.constraints) == 26 and prepared.pm.model.nv == 27 * 6
    out = ADAPTER.run(prepared)
    e = trajectory_errors(out.trajectory, case.exact(case.times))
    assert e["position"][0] < WELD_CONSTRAINT_TOL and e["orientation"][0] < WELD_CONSTRAINT_TOL
    assert invariants.drift("pairwise_distance", case.scene, out.trajectory) < WELD_CONSTRAINT_TOL
    assert ADAPTER.unsupported(make_case("pivoted_rod").scene, settings).startswith("welds=constraint with loads")


def test_audit_reports_the_model():
    case = make_case("pivoted_rod")
    prepared = ADAPTER.prepare(case.scene, case.times, Settings("rk4", dt=1e-2))
    audit = ADAPTER.audit(prepared, ADAPTER.run(prepared))
    assert audit["gravity"] == (0.0, 0.0, 0.0)
    assert audit["joints"] == {"rod": "JointModelRevoluteUnaligned"}
    assert audit["external_forces_per_evaluation"] == ["load:follower_force on rod"]
