"""Simbody adapter (through OpenSim 4.6) against the reference solver and the closed forms.

Simbody's error-controlled integrators at a tight accuracy reproduce the reference's dop853 at 1e-12 to ~1e-10:
that checks every frame, coordinate, chart and load conversion of the adapter far more tightly than any
truncation error could hide a mistake; its fixed-step integrators converge at their declared order.
"""

import subprocess
import sys

import numpy as np
import pytest

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter
from dalembert.errors import trajectory_errors
from dalembert.reference import simulate
from bounds import ORDER_SLACK
from scenes import cart_pendulum, chain_case, free_body_world_loads_case
from installed import needs

pytestmark = needs("opensim")  # the optional extra dalembert[simbody]

ADAPTER = get_adapter("simbody")

# Simbody's Runge-Kutta-Merson at accuracy 1e-10 against the reference's dop853 at 1e-12 over 1 s: measured at most
# 2.1e-10 (rad/s, the chain's angular velocity; rad, m, m/s, N elsewhere) on the chain of every joint kind and load
# and the free body with world loads, 1.2e-11 on the welded box, 4.7e-9 N on the flyball governor's reactions (its
# springs' 8e5 N/m); a frame, sign or chart mistake gives O(1e-3).
TIGHT_TOL = 1e-8
# Verlet at dt = 1e-3 over 1 s: second-order truncation, measured at most 4.4e-5 (rad/s, the free body).
SECOND_ORDER_TOL = 1e-4
# The heavy top (150 rad/s about its symmetry axis) with Verlet at dt = 1e-3 over 0.2 s: measured 3.9e-3 rad.
# Without the adapter's chart turn (the spin about the middle Euler axis), 2.95 rad: every fixed-step method failed.
HEAVY_TOP_VERLET_TOL = 1e-2
# Simbody's accuracy 1e-9 on the heavy top: measured 8.9e-10 rad against the closed form.
HEAVY_TOP_MERSON_TOL = 1e-8


def run(case, settings):
    prepared = ADAPTER.prepare(case.scene, case.times, settings)
    return prepared, ADAPTER.run(prepared)


def errors(case, settings, truth):
    return trajectory_errors(run(case, settings)[1].trajectory, truth)


def reference(scene, times):
    return simulate(scene, times, Settings("dop853", rtol=1e-12, atol=1e-12, options={"formulation": "kane"}))[0]


def test_importing_and_running_prints_nothing_and_writes_no_file(tmp_path):
    """OpenSim logs every Manager call to the console and to ``opensim.log`` in the working directory: the
    adapter silences both. A fresh process in an empty directory imports, builds and runs a pendulum."""
    code = ("import opensim; from dalembert import Settings, make_case; from dalembert.adapters import get_adapter; "
            "a = get_adapter('simbody'); a.load(); c = make_case('pendulum', t_final=0.1); "
            "p = a.prepare(c.scene, c.times, Settings('rk-merson', rtol=1e-6, atol=1e-6)); a.run(p).trajectory")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path)
    assert out.stdout == "" and out.stderr == ""
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("make", [chain_case, free_body_world_loads_case])
def test_every_joint_kind_frame_and_load_matches_the_reference(make):
    """Ball, weld and revolute joints with rotated and offset joint frames, full inertia tensors, follower and
    world forces and torques, a free body with world loads: every body state, joint coordinate and reaction."""
    case = make()
    e = errors(case, Settings("rk-merson", rtol=1e-10, atol=1e-10), reference(case.scene, case.times))
    for q in ("position", "orientation", "velocity", "angular_velocity", "joint", "reaction_force"):
        if q in e:
            assert e[q][0] < TIGHT_TOL, (q, e[q][0])


@pytest.mark.parametrize("make", [chain_case, free_body_world_loads_case])
def test_verlet_converges_at_second_order(make):
    case = make()
    ref = reference(case.scene, case.times)
    coarse, fine = (errors(case, Settings("verlet", dt=dt), ref) for dt in (1e-3, 5e-4))
    for q in ("orientation", "angular_velocity", "joint"):
        if q in coarse:
            assert coarse[q][0] < SECOND_ORDER_TOL, (q, coarse[q][0])
            assert np.log2(coarse[q][0] / fine[q][0]) == pytest.approx(2.0, abs=ORDER_SLACK), q


def test_prismatic_joint_matches_the_reference():
    scene, times = cart_pendulum(), np.linspace(0.0, 1.0, 101)
    ours = ADAPTER.run(ADAPTER.prepare(scene, times, Settings("rk-merson", rtol=1e-10, atol=1e-10))).trajectory
    ref = reference(scene, times)
    e = trajectory_errors(ours, ref)
    assert max(v[0] for v in e.values()) < TIGHT_TOL, e
    assert np.abs(ours.joints["cart"].v - ref.joints["cart"].v).max() < TIGHT_TOL


def test_spring_dampers_match_the_reference():
    """The flyball governor: two stiff spring-dampers (k = 8e5 N/m, c = 4e4 N s/m) between a slider on a prismatic
    joint and two hinged rods, as OpenSim's expression-based point-to-point forces; the audit reads them back."""
    case = make_case("flyball_governor", t_final=0.05)  # the reference costs ~1 s per 10 ms of it
    prepared, outcome = run(case, Settings("rk-merson", rtol=1e-10, atol=1e-10))
    e = trajectory_errors(outcome.trajectory, reference(case.scene, case.times))
    for q in ("position", "orientation", "velocity", "angular_velocity", "joint", "reaction_force"):
        assert e[q][0] < TIGHT_TOL, (q, e[q][0])
    springs = ADAPTER.audit(prepared, outcome)["springs"]
    assert {name: s["tension"] for name, s in springs.items()} == {
        sp.name: f"{sp.stiffness!r}*(d-{sp.rest_length!r})+{sp.damping!r}*ddot" for sp in case.scene.springs}


def test_a_star_of_welds_matches_the_closed_form():
    """The welded particle box (26 bodies welded to a free centre, Simbody's Weld mobilizers) falls and spins as
    one rigid body."""
    case = make_case("particle_box_welded", t_final=0.5)
    e = errors(case, Settings("rk-merson", rtol=1e-10, atol=1e-10), case.exact(case.times))
    for q in ("position", "orientation", "velocity", "angular_velocity"):
        assert e[q][0] < TIGHT_TOL, (q, e[q][0])


def test_the_fast_heavy_top_is_regular_in_the_adapter_s_chart():
    """OpenSim's ball joint has X-Y-Z Euler angles; the heavy top spins at 150 rad/s about its body y, the middle
    axis, which without the chart's turn passes the singularity every 10 ms. With it, a fixed step works."""
    case = make_case("heavy_top")
    truth = case.exact(case.times)
    assert errors(case, Settings("verlet", dt=1e-3), truth)["orientation"][0] < HEAVY_TOP_VERLET_TOL
    assert errors(case, Settings("rk-merson", rtol=1e-9, atol=1e-9), truth)["orientation"][0] < HEAVY_TOP_MERSON_TOL


def test_statistics_are_simbody_s():
    """Steps and realizations from OpenSim's summary: a fixed step takes the horizon over dt steps; an adaptive
    Runge-Kutta-Merson several realizations (stages) per step."""
    case = make_case("pendulum", t_final=1.0)
    _, fixed = run(case, Settings("verlet", dt=1e-3))
    assert fixed.n_steps == 1000 and fixed.n_rhs >= 2 * fixed.n_steps
    _, adaptive = run(case, Settings("rk-merson", rtol=1e-9, atol=1e-9))
    assert 0 < adaptive.n_steps < adaptive.n_rhs


def test_audit_reads_back_that_nothing_else_is_simulated():
    case = make_case("pivoted_rod")
    prepared, outcome = run(case, Settings("rk-merson", rtol=1e-9, atol=1e-9))
    audit = ADAPTER.audit(prepared, outcome)
    assert audit["gravity"] == case.scene.gravity
    assert audit["other_forces"] == [] and len(audit["loads"]) == len(case.scene.loads)
    assert audit["contact_geometry"] == audit["constraints"] == audit["controllers"] == 0
    assert audit["actuators"] == audit["muscles"] == 0
    for c in audit["coordinates"].values():
        assert not (c["locked"] or c["clamped"] or c["prescribed"]) and c["range"] == [-1e300, 1e300]
    assert "RungeKuttaMerson" in audit["integrator"] and audit["steps"] == outcome.n_steps
    for b in case.scene.bodies:
        assert audit["bodies"][b.name]["mass"] == b.mass and audit["bodies"][b.name]["com"] == [0.0, 0.0, 0.0]


def test_engine_defaults_are_read_back_and_do_not_act_in_the_integration():
    """``defaults=engine`` keeps OpenSim's coordinate range [-10, 10]: its clamp acts only where a coordinate is
    set, never while Simbody integrates, so the pivoted rod turns past 10 rad bit for bit as with ``scene``."""
    case = make_case("pivoted_rod")
    out = {}
    for defaults in ("scene", "engine"):
        prepared, outcome = run(case, Settings("rk-merson", rtol=1e-9, atol=1e-9, options={"defaults": defaults}))
        audit = ADAPTER.audit(prepared, outcome)
        assert audit["defaults"] == defaults
        ranges = {tuple(c["range"]) for c in audit["coordinates"].values()}
        assert ranges == ({(-10.0, 10.0)} if defaults == "engine" else {(-1e300, 1e300)})
        out[defaults] = outcome.trajectory
    name = case.scene.joints[0].child
    assert out["engine"].joints[name].q.max() > 10.0
    assert np.array_equal(out["scene"].joints[name].q, out["engine"].joints[name].q)


def test_a_blow_up_is_nan_and_prints_nothing(capfd):
    case = make_case("free_top_fast_spin", t_final=5.0)  # 50 rad/s, forward Euler at 0.5 rad per step
    _, outcome = run(case, Settings("explicit-euler", dt=1e-2))
    assert not outcome.trajectory.is_finite() and 0.0 < outcome.trajectory.first_nonfinite_time() < 5.0
    captured = capfd.readouterr()
    assert captured.out == "" and captured.err == ""


@pytest.mark.parametrize("case,words", [("four_bar", "PointConstraint"), ("andrews_squeezer", "PointConstraint"),
                                        ("bouncing_ball", "compliant")])
def test_what_simbody_does_not_run_is_refused_with_the_reason(case, words):
    c = make_case(case)
    reason = ADAPTER.unsupported(c.scene, Settings("rk-merson", rtol=1e-6, atol=1e-6))
    assert reason.startswith("simbody adapter cannot represent") and words in reason


def test_options_are_checked_before_anything_runs():
    case = make_case("pendulum")
    with pytest.raises(ValueError, match="options.defaults: unknown 'opensim'"):
        ADAPTER.check(case.scene, case.times, Settings("verlet", dt=1e-3, options={"defaults": "opensim"}))
    with pytest.raises(ValueError, match="dt"):
        ADAPTER.check(case.scene, case.times, Settings("verlet", dt=3e-3))


def test_show_model_describes_the_model():
    text = ADAPTER.describe(make_case("pendulum").scene, Settings("verlet", dt=1e-3))
    assert "PinJoint" in text and "defaults=scene" in text and "OpenSim 4.6" in text
