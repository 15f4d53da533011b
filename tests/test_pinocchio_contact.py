"""Pinocchio's contact time-stepper (``adapters/pinocchio/contact.py``): the cone solve on hand-made problems with
known answers, the contact cases against their closed forms (creep, roll onset, apex heights, velocities after an
impact), what it refuses and why, its options and its audit."""

import dataclasses
import math

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from dalembert.adapters import check_adapter, get_adapter  # noqa: E402
from dalembert.adapters.pinocchio import contact  # noqa: E402
from dalembert.case import make_case  # noqa: E402
from dalembert.metrics import apexes  # noqa: E402
from dalembert.rotations import frame_with_z  # noqa: E402
from dalembert.scene import Body, ContactPair, Geom, Joint  # noqa: E402
from dalembert.settings import Settings  # noqa: E402

ADAPTER = get_adapter("pinocchio")
CONTACT_CASES = ("block_on_incline", "ball_slide_to_roll", "ball_rolling_incline", "bouncing_ball", "sphere_collision")

# Bounds against the closed forms, each with why it holds for a rigid contact solved to the solve's tolerance
# (contact.TOLERANCE_DEFAULT = 1e-12) by semi-implicit Euler:
# a sticking box: only the solve's residual slip is left, 100 times its tolerance (measured 1.4e-13 m/s with ADMM,
# 2e-13 with PGS at dt 1e-3; 2.6e-13 and 3.1e-13 at 1e-4)
CREEP_BOUND = 1e-10  # m/s
# the slip phase is a constant deceleration, which semi-implicit Euler integrates exactly, and the solve ends it
# on the step where the contact point stops (measured: t* off by 2e-12 s at dt 1e-3)
ONSET_BOUND = 1e-6  # s
ROLL_SPEED_BOUND = 1e-9  # m/s; the rolling speed 5/7 v0 is the angular momentum about the contact point (measured 1e-14)
# the impulse of one impact, solved to 1e-12, divided by masses of 1 and 3 kg (measured 1.7e-13 m/s)
VELOCITY_AFTER_BOUND = 1e-8  # m/s


def _run(name, dt, params=None, **options):
    case = make_case(name, **(params or {}))
    settings = Settings("euler", dt=dt, options={k: str(v) for k, v in options.items()})
    ADAPTER.check(case.scene, case.times, settings)
    assert ADAPTER.unsupported(case.scene, settings) is None
    prepared = ADAPTER.prepare(case.scene, case.times, settings)
    outcome = ADAPTER.run(prepared)
    return case, prepared, outcome, outcome.trajectory


# ---------------------------------------------------------------- the cone solve
@pytest.mark.parametrize("solver", contact.SOLVERS)
def test_the_cone_solve_sticks_inside_the_cone_and_slides_on_its_surface(solver):
    """One point, G = I, approaching at 1 m/s with a tangential 0.3 m/s: the normal impulse stops the approach
    (1 N s); mu = 0.5 holds the point (-0.3 N s: inside the cone), mu = 0.2 cannot (the impulse on the cone's
    surface, -0.2 N s, and the point slides on at 0.1 m/s); moving apart, no impulse."""
    settings = contact.solver_settings(solver)
    G, c = np.eye(3), np.array([0.3, 0.0, -1.0])
    lam, info = contact.solve_cone(G, c, [0.5], settings)
    assert info["converged"] and np.allclose(lam, [-0.3, 0.0, 1.0], atol=1e-8)
    lam, _ = contact.solve_cone(G, c, [0.2], settings)
    assert np.allclose(lam, [-0.2, 0.0, 1.0], atol=1e-8)
    assert np.allclose(G @ lam + c, [0.1, 0.0, 0.0], atol=1e-8)
    lam, _ = contact.solve_cone(G, np.array([0.3, 0.0, 1.0]), [0.5], settings)
    assert np.allclose(lam, 0.0, atol=1e-8)


@pytest.mark.parametrize("solver", contact.SOLVERS)
def test_the_cone_solve_slides_against_the_slip_at_the_cone_coefficient(solver):
    """G = diag(2, 2, 1), c = (0.3, 0.4, -1), mu = 0.2: holding would take |(0.15, 0.2)| = 0.25 N s > 0.2, so it
    slides; maximum dissipation puts the friction impulse against the slip: -0.2 (0.6, 0.8) N s, the slip
    G lambda_t + c_t = (0.06, 0.08) m/s along the tangential velocity it started with."""
    G = np.diag([2.0, 2.0, 1.0])
    lam, info = contact.solve_cone(G, np.array([0.3, 0.4, -1.0]), [0.2], contact.solver_settings(solver))
    assert info["converged"]
    assert np.allclose(lam, [-0.12, -0.16, 1.0], atol=1e-7)
    assert np.allclose(G @ lam + [0.3, 0.4, -1.0], [0.06, 0.08, 0.0], atol=1e-7)


def test_the_cones_carry_the_pairs_coefficient_exactly():
    assert contact.cone_coefficients([0.5, 0.1, 0.0]) == [0.5, 0.1, 0.0]


# ---------------------------------------------------------------- the cases against their closed forms
@pytest.mark.parametrize("solver,dt", [("admm", 1e-3), ("pgs", 1e-3), ("pgs", 1e-4)])
def test_a_box_that_must_stick_on_the_incline_does_not_creep(solver, dt):
    """(PGS at dt 1e-4: its stopping test is on the impulses' change, which shrinks with the step; at a tolerance
    of 1e-10 it left 9.2e-8 m/s: contact.TOLERANCE_DEFAULT.)"""
    case, prepared, outcome, traj = _run("block_on_incline", dt, {"t_final": 0.3}, contact_solver=solver)
    creep = next(m for m in case.invariants if m.name == "creep")
    assert np.max(creep.series(case.scene, traj)) < CREEP_BOUND
    assert outcome.info["contact"]["unconverged"] == 0 and outcome.info["contact"]["max_points"] == 4


def test_the_ball_starts_rolling_at_t_star_at_five_sevenths_of_its_launch_speed():
    """ball_slide_to_roll at its defaults (v0 = 1 m/s, mu = 0.1): t* = 2 v0 / (7 mu g) = 0.2912 s, then v = 5/7 v0."""
    case, _, _, traj = _run("ball_slide_to_roll", 1e-3)
    onset = next(m for m in case.invariants if m.name == "roll_onset_error")
    assert np.max(np.abs(onset.series(case.scene, traj))) < ONSET_BOUND
    assert abs(2.0 / (7.0 * 0.1 * 9.81) - 0.2912) < 1e-4  # the case's defaults give the t*
    v = traj.bodies["ball"].velocity
    assert np.max(np.abs(v[traj.t > 0.3, 0] - 5.0 / 7.0)) < ROLL_SPEED_BOUND


@pytest.mark.parametrize("dt", [1e-3, 1e-4])
def test_the_bouncing_ball_rebounds_to_its_apexes_within_one_step_of_impact(dt):
    """Apexes e^(2k) h (h = 1 m, e = 0.5: 0.25 and 0.0625 m). The impact is resolved up to one step late: the ball
    sinks up to u dt (u the landing speed) before the contact sees it, then leaves from the surface at e times
    its speed there after one step's rise at e u, so an apex is off by at most (e + e^2) u dt, plus e^2 times the
    previous apex's error (measured at dt 1e-3: 0.25164, 0.06319 m; at 1e-4: 0.25008, 0.06255 m)."""
    case, _, _, traj = _run("bouncing_ball", dt)
    h, e, g = 1.0, 0.5, 9.81
    z = traj.bodies["ball"].position[:, 2] - 0.1
    tops = [top for _, top in apexes(traj.t, z, math.sqrt(2.0 * h / g))][:2]
    truth = [e**2 * h, e**4 * h]
    u1 = math.sqrt(2.0 * g * h)
    bound1 = (e + e**2) * u1 * dt
    bound2 = (e + e**2) * e * u1 * dt + e**2 * bound1
    assert len(tops) == 2
    assert abs(tops[0] - truth[0]) < bound1 and abs(tops[1] - truth[1]) < bound2


def test_the_spheres_leave_the_impact_at_newtons_velocities():
    """m1 = 1, m2 = 3 kg, v1 = 1 m/s, e = 0.8: v1' = (m1 - e m2) / (m1 + m2) v1 = -0.35, v2' = (1 + e) m1 / (m1 + m2) v1
    = 0.45 m/s; the momentum is kept."""
    _, _, _, traj = _run("sphere_collision", 1e-3)
    v1, v2 = traj.bodies["ball1"].velocity[-1], traj.bodies["ball2"].velocity[-1]
    assert np.allclose(v1, [-0.35, 0.0, 0.0], atol=VELOCITY_AFTER_BOUND)
    assert np.allclose(v2, [0.45, 0.0, 0.0], atol=VELOCITY_AFTER_BOUND)
    assert abs(v1[0] + 3.0 * v2[0] - 1.0) < VELOCITY_AFTER_BOUND


def test_the_adapter_contract_holds_on_the_contact_cases():
    """Repeated runs identical, sampled at the case's times, gravity read back, on every contact case."""
    assert check_adapter("pinocchio", cases=[make_case(n) for n in CONTACT_CASES], integrators=["euler"]) == []


# ---------------------------------------------------------------- the audit
def test_the_audit_reads_the_mapping_and_the_solver_back():
    _, prepared, outcome, _ = _run("bouncing_ball", 1e-3, contact_solver="pgs", contact_tolerance=1e-9,
                                   contact_iterations=500)
    a = ADAPTER.audit(prepared, outcome)
    assert a["contacts"] == 1
    (pair,) = a["contact_pairs"].values()
    assert pair["cone_mu"] == 0.0 and pair["restitution"] == 0.5 and "1 point" in pair["detection"]
    s = a["contact_solver"]
    assert s["solver"] == "pin.PGSConstraintSolver" and s["max_iterations"] == 500 and s["solve_ncp"]
    assert s["absolute_feasibility_tol"] == 1e-9 and s["absolute_complementarity_tol"] == 1e-9
    assert a["contact_solves"]["contact_steps"] > 0 and a["contact_solves"]["unconverged"] == 0
    assert "Newton" in a["contact_mapping"] and "cone coefficient exactly" in a["contact_mapping"]
    assert "Python (the contact time-stepper" in a["loop"]


def test_a_contact_free_scene_audits_no_contact():
    case = make_case("pivoted_rod")
    settings = Settings("euler", dt=1e-3)
    prepared = ADAPTER.prepare(case.scene, case.times, settings)
    a = ADAPTER.audit(prepared, ADAPTER.run(prepared))
    assert a["contacts"] == 0 and "contact_pairs" not in a and prepared.contacts is None


# ---------------------------------------------------------------- what is refused, and bad options
@pytest.mark.parametrize("integrator", ["rk4", "rk4-naive", "rk45", "dop853"])
def test_other_integrators_refuse_contact_and_name_the_one_that_steps_it(integrator):
    case = make_case("ball_slide_to_roll")
    spec = ADAPTER.integrators[integrator]
    settings = Settings(integrator, dt=1e-3) if spec.fixed_step else Settings(integrator, rtol=1e-6, atol=1e-6)
    reason = ADAPTER.unsupported(case.scene, settings)
    assert reason.startswith(f"contact not yet mapped for pinocchio's {integrator}")
    assert "--integrator euler" in reason


def _with_second_body(kind):
    """block_on_incline with a second free body (a box or a sphere), 1 m above the first, paired with its box."""
    scene = make_case("block_on_incline").scene
    size = (0.1, 0.1, 0.1) if kind == "box" else (0.05,)
    body = Body.box("lid", 1.0, (0.1, 0.1, 0.1)) if kind == "box" else Body("lid", 1.0, np.eye(3) * 1e-3)
    return dataclasses.replace(
        scene, bodies=[*scene.bodies, body],
        joints=[*scene.joints, Joint("free", "world", "lid", q0=[0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0], v0=[0.0] * 6)],
        geoms=[*scene.geoms, Geom("lid", kind, size)],
        contacts=[*scene.contacts, ContactPair("geom_box", "geom_lid", 0.5)])


@pytest.mark.parametrize("kind", ["box", "sphere"])
def test_a_box_against_a_body_is_refused_with_what_it_would_take(kind):
    reason = ADAPTER.unsupported(_with_second_body(kind), Settings("euler", dt=1e-3))
    assert reason.startswith("contacts.contact_geom_box_geom_lid: a ") and "box" in reason
    assert "sphere-plane, box-plane (its corners) and sphere-sphere only" in reason


@pytest.mark.parametrize("options,field", [({"contact_solver": "lcp"}, "options.contact_solver"),
                                           ({"contact_tolerance": "0"}, "options.contact_tolerance"),
                                           ({"contact_iterations": "1.5"}, "options.contact_iterations"),
                                           ({"contact_iterations": "0"}, "options.contact_iterations")])
def test_bad_contact_options_are_refused_naming_the_field(options, field):
    case = make_case("block_on_incline")
    with pytest.raises(ValueError, match=field):
        ADAPTER.check(case.scene, case.times, Settings("euler", dt=1e-3, options=options))


def test_contact_options_belong_to_euler_only():
    case = make_case("block_on_incline")
    with pytest.raises(ValueError, match=r"\['contact_solver'\] unknown to pinocchio 'rk4'"):
        ADAPTER.check(case.scene, case.times, Settings("rk4", dt=1e-3, options={"contact_solver": "pgs"}))


def test_a_contact_free_scene_is_not_refused_for_contact():
    assert ADAPTER.unsupported(make_case("pivoted_rod").scene, Settings("rk4", dt=1e-3)) is None


# ---------------------------------------------------------------- the contact Jacobian
def _touching(scene, body, point, normal):
    """``scene`` with a sphere of 0.05 m at ``point`` of ``body`` and a plane of ``normal`` touching it there."""
    from dalembert import contact as geometry
    from dalembert.scene import Plane

    geom = Geom(body, "sphere", (0.05,), point=point, name="tip")
    poses = geometry.initial_poses(dataclasses.replace(scene, geoms=[geom]))
    R = poses[body]["R"][0]
    centre = poses[body]["p"][0] + R @ np.asarray(point)
    n = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    return dataclasses.replace(scene, geoms=[geom], planes=[Plane("floor", n, centre - 0.05 * n)],
                               contacts=[ContactPair("tip", "floor", 0.3)])


@pytest.mark.parametrize("name,body", [("pivoted_rod", "rod"), ("free_top", "top")])
def test_the_contact_rows_are_the_contact_points_velocity_in_its_frame(name, body):
    """On a revolute joint and a FreeFlyer, the rows J (t1, t2, n) of a sphere touching a plane, times a
    velocity v, are the velocity of the sphere's material point at the contact, in the contact frame: the
    central difference of that material point's position along ``integrate(q, +-eps v)`` (eps = 1e-6; the
    difference's error is eps^2 times the point's acceleration along v)."""
    scene = _touching(make_case(name).scene, body, (0.3, 0.1, -0.2), (0.2, -0.3, 1.0))
    prepared = ADAPTER.prepare(scene, np.array([0.0, 0.1]), Settings("euler", dt=0.1))
    pm, contacts = prepared.pm, prepared.contacts
    q = prepared.q0
    J, gap, mu, e = contacts.points(q)
    assert J.shape == (3, pm.model.nv) and abs(gap[0]) < 1e-12 and mu[0] == 0.3 and e[0] == 0.0
    X = pm.data.oMf[pm.frame_ids[body]]
    n = scene.planes[0].unit_normal
    point_B = X.inverse().act(np.asarray(scene.planes[0].point))  # the contact point (on the plane), in B

    def at(dq):
        qq = pin.integrate(pm.model, q, dq)
        pin.forwardKinematics(pm.model, pm.data, qq)
        pin.updateFramePlacements(pm.model, pm.data)
        return pm.data.oMf[pm.frame_ids[body]].act(point_B)

    rng = np.random.default_rng(7)
    frame = frame_with_z(n)
    for _ in range(3):
        v = rng.normal(size=pm.model.nv)
        eps = 1e-6
        velocity = (at(eps * v) - at(-eps * v)) / (2.0 * eps)
        assert np.allclose(J @ v, frame.T @ velocity, atol=1e-8)


def test_contact_with_welds_as_constraints_is_refused_and_runs_with_welds_as_a_tree():
    """A cap welded on the bouncing ball: as a constraint (pin.constraintDynamics, acceleration level) it is not
    merged with the contact's impulses, and the reason says to weld it into the tree, which runs."""
    scene = make_case("bouncing_ball").scene
    scene = dataclasses.replace(scene, bodies=[*scene.bodies, Body("cap", 0.1, np.eye(3) * 1e-4)],
                                joints=[*scene.joints, Joint("weld", "ball", "cap", parent_point=[0.0, 0.0, 0.1])])
    reason = ADAPTER.unsupported(scene, Settings("euler", dt=1e-3, options={"welds": "constraint"}))
    assert reason.startswith("contacts: with welds as constraints or loop closures") and "welds=tree" in reason
    assert ADAPTER.unsupported(scene, Settings("euler", dt=1e-3)) is None
