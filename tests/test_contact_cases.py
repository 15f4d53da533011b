"""The five contact cases' closed forms against independent computations.

The reference solver has no contact (``testing.reference_cannot_judge``), so each closed form is checked here
against an event-driven numerical integration of the same motion, written from the laws alone (Coulomb's
friction with its stick-slip switch, Newton's impact law), by scipy's ``solve_ivp`` with events at tight
tolerance; and against the energy and momentum identities each motion obeys. Each case's truth, its metrics
(zero on the truth) and its declared validation are checked too.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from dalembert import invariants
from dalembert.case import make_case
from dalembert.reference import truth
from dalembert.reference.closed_form import BouncingBall, HeadOnCollision, RollingBall, SlidingBall, SlidingBlock
from dalembert.scene import SceneError
from dalembert.testing import (check_csv_round_trip, check_truth_conserves, check_truth_starts_at_initial_state,
                               reference_cannot_judge)

G = 9.81
# The event-driven integrations run DOP853 at this tolerance: ~1e4 above double's roundoff on these smooth
# phases, so the closed forms must agree to ~1e-10 (AGREE).
RTOL = 1e-12
AGREE = 1e-10

CONTACT_CASES = ("block_on_incline", "ball_slide_to_roll", "ball_rolling_incline", "bouncing_ball",
                 "sphere_collision")


def _ivp(rhs, t0, t1, y0, events=()):
    return solve_ivp(rhs, (t0, t1), y0, method="DOP853", rtol=RTOL, atol=RTOL, events=events, dense_output=True)


# ------------------------------------------------------------------ block: stick-slip along the slope
def block_event_driven(angle, mu, v0, t_end):
    """``(t -> (s, v), stop)``: a block on the slope, sliding (kinetic friction against v) until v = 0, then sticking
    while static friction can hold it (``m g sin <= mu m g cos``), else sliding on."""
    down = G * math.sin(angle)
    fric = mu * G * math.cos(angle)
    holds = down <= fric
    if v0 == 0.0 and holds:
        return (lambda t: (np.zeros_like(t), np.zeros_like(t))), 0.0

    def slide(t, y):  # sliding down (v > 0: the phase's sign, held so that a step may cross v = 0 to the event)
        return [y[1], down - fric]

    stopped = lambda t, y: y[1]  # noqa: E731
    stopped.terminal, stopped.direction = True, -1
    sol = _ivp(slide, 0.0, t_end, [0.0, v0], [stopped])
    stop = float(sol.t_events[0][0]) if len(sol.t_events[0]) else None
    s_stop = sol.sol(stop)[0] if stop is not None else None

    def at(t):
        t = np.asarray(t, dtype=float)
        if stop is None:
            y = sol.sol(t)
            return y[0], y[1]
        y = sol.sol(np.minimum(t, stop))
        return np.where(t >= stop, s_stop, y[0]), np.where(t >= stop, 0.0, y[1])

    return at, stop


@pytest.mark.parametrize("angle, mu, v0", [(math.radians(20.0), 0.5, 1.0), (math.radians(20.0), 0.2, 0.5),
                                           (math.radians(20.0), 0.5, 0.0), (math.radians(30.0), 0.1, 0.0),
                                           (0.0, 0.3, 2.0)])
def test_block_closed_form_against_the_stick_slip_integration(angle, mu, v0):
    t = np.linspace(0.0, 2.0, 201)
    exact = SlidingBlock(angle, mu, v0, G, 1.0)
    at, stop = block_event_driven(angle, mu, v0, 2.0)
    s, v = at(t)
    assert np.abs(exact.displacement(t) - s).max() < AGREE
    assert np.abs(exact.speed(t) - v).max() < AGREE
    if stop is None:
        assert exact.stop_time is None or exact.stop_time > 2.0
    else:
        assert exact.stop_time == pytest.approx(stop, abs=AGREE)


def test_block_energy_identity_and_normal_force():
    """The energy lost along the slope is the friction's work, mu N s, with N = m g cos(angle) (the box stays on the
    plane: no acceleration along the normal, so the normal force balances gravity's normal component)."""
    case = make_case("block_on_incline", v0=1.0)
    exact = SlidingBlock(case.params["angle"], 0.5, 1.0, G, 1.0)
    traj = truth(case)
    e = invariants.total_energy(case.scene, traj)
    assert np.abs((e[0] - e) - exact.dissipated_energy(traj.t)).max() < 1e-12
    n = np.array(case.scene.planes[0].unit_normal)
    assert np.abs(traj.bodies["box"].position @ n - 0.05).max() < 1e-15  # on the plane throughout
    assert exact.normal_force == pytest.approx(-1.0 * np.array(case.scene.gravity) @ n, rel=1e-15)
    # once stuck, static friction carries gravity's pull down the slope, below mu N
    assert exact.friction_force(np.array([5.0]))[0] == pytest.approx(G * math.sin(case.params["angle"]))
    assert exact.friction_force(np.array([5.0]))[0] < 0.5 * exact.normal_force


# ------------------------------------------------------------------ a sphere on a slope: slip and roll
def sphere_event_driven(angle, mu, R, v0, w0, t_end):
    """``(t -> (s, v, theta, w), onsets)``: a solid sphere on a slope (angle 0: level), ``v`` down the slope, ``w``
    its spin in the rolling sense. Slipping (``u = v - w R != 0``): kinetic friction ``mu N`` against u, on the
    centre and, with its moment, on the spin. Rolling (``u = 0``): the friction the constraint needs,
    ``f = I/(I + m R^2) m g sin``, while ``|f| <= mu N``; else it slips. Switches by events."""
    m, I = 1.0, 0.4 * R * R
    down, N = G * math.sin(angle), G * math.cos(angle)

    def slip_rhs(t, y):
        f = mu * N * sign  # on m = 1, against the slip (its sign held over the phase, so a step may cross u = 0)
        return [y[1], down - f, y[3], f * R / I]

    def roll_rhs(t, y):
        a = down / (1.0 + I / (m * R * R))
        return [y[1], a, y[3], a / R]

    rolled = lambda t, y: y[1] - y[3] * R  # noqa: E731
    rolled.terminal = True
    pieces, onsets, t0, y0 = [], [], 0.0, [0.0, v0, 0.0, w0]
    rolling = v0 - w0 * R == 0.0
    while t0 < t_end:
        if rolling:
            assert I / (m * R * R + I) * down <= mu * N, "the integration only models rolling that Coulomb allows"
            sol = _ivp(roll_rhs, t0, t_end, y0)
        else:
            sign = np.sign(y0[1] - y0[3] * R)
            sol = _ivp(slip_rhs, t0, t_end, y0, [rolled])
        pieces.append((t0, sol.t[-1], sol.sol))
        if sol.status == 1:  # the slip vanished: it rolls from here
            onsets.append(float(sol.t_events[0][0]))
            t0, y0, rolling = sol.t[-1], sol.y[:, -1].copy(), True
            y0[3] = y0[1] / R  # u = 0 exactly (the event's root, to roundoff)
        else:
            break

    def at(t):
        out = np.empty((4, len(t)))
        for a, b, f in pieces:
            k = (t >= a) & (t <= b)
            out[:, k] = f(t[k])
        return out

    return at, onsets


@pytest.mark.parametrize("v0, w0, mu", [(1.0, 0.0, 0.1), (2.0, -5.0, 0.3), (1.0, 30.0, 0.2)])
def test_slide_to_roll_against_the_event_driven_integration(v0, w0, mu):
    R, t = 0.1, np.linspace(0.0, 2.0, 401)
    exact = SlidingBall(v0, w0, mu, R, G, 1.0)
    at, onsets = sphere_event_driven(0.0, mu, R, v0, w0, 2.0)
    s, v, theta, w = at(t)
    assert onsets[0] == pytest.approx(exact.roll_time, abs=AGREE)
    for mine, theirs in ((exact.distance(t), s), (exact.speed(t), v), (exact.angle(t), theta), (exact.spin(t), w)):
        assert np.abs(mine - theirs).max() < AGREE * 10
    assert exact.roll_speed == pytest.approx(v[-1], abs=AGREE)


def test_slide_to_roll_issue_numbers_and_energy_identity():
    """t* = 2 v0 / (7 mu g) = 0.2912 s for the issue's launch; the slip dissipates mu m g times the slip distance
    (the integral of the slip speed), and keeps the angular momentum about the contact point."""
    exact = SlidingBall(1.0, 0.0, 0.1, 0.1, G, 1.0)
    assert exact.roll_time == pytest.approx(0.2912, abs=5e-5)
    t = np.linspace(0.0, exact.roll_time, 20001)
    slip_distance = np.trapezoid(np.abs(exact.slip(t)), t)
    assert exact.dissipated_energy == pytest.approx(0.1 * G * slip_distance, rel=1e-8)
    L = exact.mass * exact.radius * exact.speed(t) + exact.inertia * exact.spin(t)
    assert np.abs(L - L[0]).max() < 1e-15


@pytest.mark.parametrize("angle, mu", [(math.radians(20.0), 0.5), (math.radians(40.0), 0.24)])
def test_rolling_incline_against_the_event_driven_integration(angle, mu):
    R, t = 0.1, np.linspace(0.0, 1.0, 101)
    exact = RollingBall(angle, mu, R, G, 1.0)
    assert mu > exact.min_mu
    at, onsets = sphere_event_driven(angle, mu, R, 0.0, 0.0, 1.0)
    s, v, theta, w = at(t)
    assert onsets == []  # it never slips
    for mine, theirs in ((exact.distance(t), s), (exact.speed(t), v), (exact.angle_turned(t), theta),
                         (exact.spin(t), w)):
        assert np.abs(mine - theirs).max() < AGREE
    assert exact.friction_force <= mu * exact.normal_force


def test_rolling_incline_refuses_a_slipping_mu_and_conserves_energy():
    with pytest.raises(SceneError, match=r"ball_rolling_incline\.mu: .* is at most 2/7 tan\(angle\)"):
        make_case("ball_rolling_incline", mu=0.1)
    case = make_case("ball_rolling_incline")
    check_truth_conserves(case, truth(case))
    e = invariants.total_energy(case.scene, truth(case))
    assert np.abs(e - e[0]).max() < 1e-12


# ------------------------------------------------------------------ bouncing ball: Newton's impact law
def bounce_event_driven(h, e, t_end, count):
    """Impact times and apex heights of a ball dropped from ``h``: free flight until z = 0, then ``w -> -e w``."""
    hit = lambda t, y: y[0]  # noqa: E731
    hit.terminal, hit.direction = True, -1
    top = lambda t, y: y[1]  # noqa: E731
    top.direction = -1
    t0, y0, impacts, apexes = 0.0, [h, 0.0], [], []
    while len(impacts) < count and t0 < t_end:
        sol = _ivp(lambda t, y: [y[1], -G], t0, t_end, y0, [hit, top])
        apexes += [float(sol.sol(ta)[0]) for ta in sol.t_events[1] if ta > t0]
        if sol.status != 1:
            break
        t0 = float(sol.t_events[0][0])
        impacts.append(t0)
        y0 = [0.0, -e * sol.y_events[0][0][1]]
    return np.array(impacts), np.array(apexes)


@pytest.mark.parametrize("h, e", [(1.0, 0.5), (0.3, 0.9), (2.0, 1.0)])
def test_bouncing_ball_against_the_event_driven_integration(h, e):
    exact = BouncingBall(h, e, G)
    impacts, tops = bounce_event_driven(h, e, 10.0, 4)
    assert np.abs(exact.impacts(10.0)[:4] - impacts).max() < AGREE
    assert np.abs(exact.apex_heights(3) - tops[:3]).max() < AGREE
    # the height between impacts
    t = np.linspace(0.0, impacts[-1], 500)
    z = np.empty_like(t)
    starts = np.concatenate([[0.0], impacts])
    for k in range(len(impacts)):
        sel = (t >= starts[k]) & (t <= impacts[k])
        up = 0.0 if k == 0 else e * math.sqrt(2 * G * h) * e ** (k - 1)
        z[sel] = (h if k == 0 else 0.0) + up * (t[sel] - starts[k]) - 0.5 * G * (t[sel] - starts[k]) ** 2
    assert np.abs(exact.height_at(t) - z).max() < 1e-9


def test_bouncing_ball_rests_after_the_accumulation_time():
    exact = BouncingBall(1.0, 0.5, G)
    assert exact.rest_time == pytest.approx(3.0 * math.sqrt(2.0 / G))
    assert exact.height_at(np.array([exact.rest_time + 0.1]))[0] == 0.0
    assert len(BouncingBall(1.0, 0.0, G).impacts(5.0)) == 1  # e = 0: it stops at its first impact


# ------------------------------------------------------------------ head-on collision
@pytest.mark.parametrize("e", [0.0, 0.8, 1.0])
def test_sphere_collision_momentum_restitution_and_energy_identities(e):
    c = HeadOnCollision(1.0, 3.0, 1.0, -0.2, 0.0, 0.5, 0.1, 0.15, e)
    a1, a2 = c.velocities_after
    assert c.m1 * a1 + c.m2 * a2 == pytest.approx(c.m1 * c.v1 + c.m2 * c.v2, abs=1e-15)
    assert a2 - a1 == pytest.approx(e * (c.v1 - c.v2), abs=1e-15)
    before = 0.5 * (c.m1 * c.v1**2 + c.m2 * c.v2**2)
    after = 0.5 * (c.m1 * a1**2 + c.m2 * a2**2)
    assert before - after == pytest.approx(c.energy_lost, abs=1e-15)
    # the impact time: free flight until the gap closes (an event of the integration)
    touch = lambda t, y: (y[1] - y[0]) - (c.r1 + c.r2)  # noqa: E731
    touch.terminal = True
    sol = _ivp(lambda t, y: [c.v1, c.v2], 0.0, 5.0, [c.x1, c.x2], [touch])
    assert sol.t_events[0][0] == pytest.approx(c.impact_time, abs=AGREE)


# ------------------------------------------------------------------ the cases themselves
@pytest.mark.parametrize("name", CONTACT_CASES)
def test_contact_case_truth_starts_at_its_scene_and_zeroes_its_metrics(name, tmp_path):
    case = make_case(name)
    assert "contact" in case.tags and "contact" in case.scene.effects
    assert reference_cannot_judge(case) and "event-driven" in reference_cannot_judge(case)
    traj = truth(case)
    check_truth_starts_at_initial_state(case, traj)
    check_truth_conserves(case, traj)  # every metric is ~0 on the truth
    check_csv_round_trip(case, traj, tmp_path)
    assert case.invariants and all(inv.name in case.tolerances for inv in case.invariants)


def test_metrics_see_a_wrong_motion():
    """A motion other than the truth's is measured: the block creeping down the slope, the ball never rolling, the
    ball bouncing too high."""
    from dataclasses import replace

    block = make_case("block_on_incline")
    traj = truth(block)
    downhill = np.array([math.cos(block.params["angle"]), 0.0, -math.sin(block.params["angle"])])
    creeping = replace(traj.bodies["box"], position=traj.bodies["box"].position + 1e-3 * traj.t[:, None] * downhill)
    creep = {i.name: i for i in block.invariants}["creep"]
    assert creep.drift(block.scene, replace(traj, bodies={"box": creeping})) == pytest.approx(1e-3, rel=1e-9)

    ball = make_case("ball_slide_to_roll")
    traj = truth(ball)
    b = traj.bodies["ball"]
    sliding = replace(b, angular_velocity=np.zeros_like(b.angular_velocity))
    onset = {i.name: i for i in ball.invariants}["roll_onset_error"]
    assert onset.drift(ball.scene, replace(traj, bodies={"ball": sliding})) > 0.5  # never rolls in the 1-s horizon

    bounce = make_case("bouncing_ball")
    higher = make_case("bouncing_ball", restitution=0.6)
    apex = {i.name: i for i in bounce.invariants}["apex_error"]
    assert apex.drift(bounce.scene, truth(higher)) == pytest.approx(0.6**2 - 0.5**2, rel=1e-6)


def test_case_parameters_outside_their_domain_are_refused():
    for name, params, text in [("block_on_incline", dict(mu=-0.1), "block_on_incline.mu: must be >= 0"),
                               ("block_on_incline", dict(v0=-1.0), "block_on_incline.v0: must be >= 0"),
                               ("bouncing_ball", dict(restitution=1.2), "bouncing_ball.restitution: must lie in"),
                               ("sphere_collision", dict(v1=0.0), "sphere_collision.v1: 0.0 m/s does not exceed"),
                               ("ball_slide_to_roll", dict(omega0=10.0), "ball_slide_to_roll.v0: equals omega0")]:
        with pytest.raises(SceneError, match=text.replace(".", r"\.")):
            make_case(name, **params)


def test_contact_cases_stay_out_of_the_default_matrix():
    from dalembert.case import CASES, in_default_matrix, load_cases

    load_cases()
    for name in CONTACT_CASES:
        assert not in_default_matrix(CASES[name])


def test_a_metric_beyond_its_bound_is_said_in_its_unit_and_an_invariant_as_before():
    from dalembert.judge import judge

    case = make_case("block_on_incline")
    # MuJoCo's default cone: creep 1.8 mm/s where the bound is 0.1 mm/s (the case's CREEP_TOL)
    verdict = judge("ok", "", {}, {"creep": 1.8e-3, "penetration": 0.0}, {k: case.tolerances[k]
                                                                          for k in ("creep", "penetration")})
    assert verdict.reason == "creep 1.80e-03 m/s > bound 0.0001 m/s" and verdict.beyond == ("creep",)
    # a metric with a scale other than 1: bouncing_ball's apex_error is stored over the drop height (1 m by default)
    ball = make_case("bouncing_ball", height=2.0)
    verdict = judge("ok", "", {}, {"apex_error": 0.05}, {"apex_error": ball.tolerances["apex_error"]})
    bound = ball.tolerances["apex_error"].value * 2.0
    assert verdict.reason == f"apex_error {0.1:.2e} m > bound {bound:g} m"
    # a declared invariant keeps its wording
    rolling = make_case("ball_rolling_incline")
    verdict = judge("ok", "", {}, {"energy": 0.5}, {"energy": rolling.tolerances["energy"]})
    assert verdict.reason == f"energy drift 5.00e-01 > {rolling.tolerances['energy'].value:g}"
