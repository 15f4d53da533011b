"""Drake runs the contact cases: the plant's collision geometry (only the named pairs collide, ideal Coulomb
friction), the audit read back from the plant and its SceneGraph, the contact options, the restitution mapping,
and what Drake does on the closed forms (Drake 1.51, discrete mode, dt = 1e-3; the numbers each bound rests on
are in its comment)."""


import numpy as np
import pytest
from installed import needs

pytestmark = needs("pydrake")

from scipy.integrate import solve_ivp  # noqa: E402

from dalembert.adapters import get_adapter  # noqa: E402
from dalembert.adapters.drake import contact  # noqa: E402
from dalembert.case import make_case  # noqa: E402
from dalembert.scene import Body, ContactPair, Geom, Joint, Plane, Scene  # noqa: E402
from dalembert.settings import Settings  # noqa: E402
from engine_runs import run_case  # noqa: E402

DT = 1e-3
# Drake's SAP (lagged approximation, point contact) holds the box that must stick at a measured creep of 6.5e-4 m/s
# over the default block_on_incline at dt = 1e-3; TAMSI creeps 3.3e-3 m/s there (its regularized friction's
# stiction tolerance). The bound leaves 3x over SAP and tells the two apart.
SAP_CREEP_BOUND = 2e-3
# SAP starts the ball rolling 1.1 ms from the closed form's t* = 0.2912 s (the slip down to 1 % of its launch
# value; TAMSI 0.06 ms), measured at dt = 1e-3; the bound leaves ~3x.
ROLL_ONSET_BOUND = 3e-3
# The Hunt-Crossley closed form against a direct integration of m xddot = -k x (1 + d xdot) at rtol 1e-11: the
# restitution agrees to the integration's accuracy.
HC_RESTITUTION_TOL = 1e-7
# Hunt & Crossley's e = 1 - 2/3 d v is the closed form's first order in 1 - e: at 1 - e = 1e-4 they differ by
# ~(1e-4)^2; the bound leaves 10x.
HC_SMALL_DAMPING_TOL = 1e-7
# Continuous mode integrates the Hunt-Crossley law as written, so the mapped restitution returns the closed
# form's velocities after the impact (sphere_collision, e = 0.8 mapped at its 1-m/s approach speed): measured
# within 1.5e-5 m/s with rk3-adaptive at rtol 1e-6 (gravity-free, frictionless); the bound leaves ~7x.
CONTINUOUS_AFTER_TOL = 1e-4


def run(name, options=None, integrator="discrete", **params):
    settings = (Settings(integrator, dt=DT, options=options or {}) if integrator == "discrete" else
                Settings(integrator, rtol=1e-6, options=options or {}))
    return run_case("drake", name, settings, **params)


def test_block_that_must_stick_creeps_below_the_bound_with_sap():
    *_, sap = run("block_on_incline")
    *_, tamsi = run("block_on_incline", {"contact_solver": "tamsi"})
    assert sap["creep"] < SAP_CREEP_BOUND < tamsi["creep"]


def test_ball_starts_rolling_at_the_closed_forms_time():
    case, _, outcome, drifts = run("ball_slide_to_roll")
    assert drifts["roll_onset_error"] < ROLL_ONSET_BOUND
    assert drifts["roll_speed_error"] < case.tolerances["roll_speed_error"].value


def test_the_audit_reads_every_contact_parameter_back():
    options = {"contact_solver": "tamsi", "point_contact_stiffness": "2e6", "hunt_crossley_dissipation": "10"}
    case, prepared, outcome, _ = run("block_on_incline", options)
    audit = get_adapter("drake").audit(prepared, outcome)
    (pair,) = audit["contact_pairs"].values()
    assert pair["friction"] == [0.5, 0.5]  # mu, static = kinetic, as the plant combines its geometries'
    assert set(pair["geoms"]) == {"geom_box", "slope"}
    assert pair["point_contact_stiffness"] == 1e6 and pair["hunt_crossley_dissipation"] == 10.0  # k/2 per pair
    geoms = audit["contact_geometries"]
    assert geoms["geom_box"]["shape"] == "Box" and geoms["geom_box"]["size"] == [0.2, 0.2, 0.1]
    assert geoms["slope"]["shape"] == "HalfSpace" and geoms["slope"]["static_friction"] == 0.5
    assert audit["contact_model"] == "kPoint" and audit["contact_approximation"] == "kTamsi"
    assert audit["collision_candidates"] == [["geom_box", "slope"]]
    case, prepared, outcome, _ = run("block_on_incline")
    audit = get_adapter("drake").audit(prepared, outcome)
    assert (audit["contact_solver"], audit["contact_approximation"]) == ("kSap", "kLagged")  # Drake's default
    (pair,) = audit["contact_pairs"].values()
    assert pair["point_contact_stiffness"] == contact.STIFFNESS_DEFAULT / 2
    assert pair["hunt_crossley_dissipation"] == contact.DISSIPATION_DEFAULT


def _drop(contacts, heights=(0.5,), t_final=0.5):
    """Balls of radius 0.1 dropped from ``heights`` (lowest point above the ground), the given pairs."""
    names = [f"ball{i}" for i in range(len(heights))]
    return Scene("drop", bodies=[Body(n, 1.0, np.eye(3) * 0.004) for n in names],
                 joints=[Joint("free", "world", n, q0=[0.5 * i, 0.0, h + 0.1, 1.0, 0.0, 0.0, 0.0], v0=[0.0] * 6)
                         for i, (n, h) in enumerate(zip(names, heights))],
                 gravity=[0.0, 0.0, -9.81], geoms=[Geom(n, "sphere", (0.1,)) for n in names],
                 planes=[Plane("ground")], contacts=contacts), np.linspace(0.0, t_final, 51)


def _heights(scene, times, integrator="discrete"):
    adapter = get_adapter("drake")
    settings = Settings(integrator, dt=DT)
    adapter.check(scene, times, settings)
    assert adapter.unsupported(scene, settings) is None
    traj = adapter.run(adapter.prepare(scene, times, settings)).trajectory
    return {n: b.position[-1, 2] - 0.1 for n, b in traj.bodies.items()}


def test_only_the_named_pairs_collide():
    # no pair: the ball falls through the plane (0.5 s of free fall from 0.5 m ends 0.73 m below it)
    scene, times = _drop([])
    assert _heights(scene, times)["ball0"] == pytest.approx(0.5 - 0.5 * 9.81 * 0.25, abs=1e-2)
    # one ball named with the ground, one not: the first rests on it, the second falls through
    scene, times = _drop([ContactPair("geom_ball0", "ground", 0.5)], heights=(0.2, 0.2))
    h = _heights(scene, times)
    assert abs(h["ball0"]) < 1e-3 and h["ball1"] < -0.5
    adapter = get_adapter("drake")
    prepared = adapter.prepare(scene, times, Settings("discrete", dt=DT))
    assert contact.candidates(prepared.model.scene_graph) == {frozenset(("geom_ball0", "ground"))}


@pytest.mark.parametrize("e,speed", [(0.5, 4.43), (0.8, 1.0), (0.95, 3.0)])
def test_the_restitution_mapping_is_the_hunt_crossley_law_integrated(e, speed):
    d = contact.restitution_dissipation(e, speed)
    k, m = 5e5, 0.75  # the result depends on neither (module docstring); any values check it

    def rhs(t, y):
        x, xdot = y
        return [xdot, -k * max(x, 0.0) * max(1.0 + d * xdot, 0.0) / m]

    out = solve_ivp(rhs, [0.0, 1.0], [0.0, speed], rtol=1e-11, atol=1e-14, max_step=1e-4,
                    events=lambda t, y: y[0] if t > 0.0 else 1.0)
    assert -out.y_events[0][0][1] / speed == pytest.approx(e, abs=HC_RESTITUTION_TOL)
    # Hunt & Crossley's small-damping form, e = 1 - 2/3 d v, as e -> 1
    near = 1.0 - 1e-4
    assert 1.0 - 2.0 / 3.0 * contact.restitution_dissipation(near, speed) * speed == pytest.approx(
        near, abs=HC_SMALL_DAMPING_TOL)


def test_restitution_is_mapped_at_the_named_speed_and_unsupported_without_it():
    adapter = get_adapter("drake")
    case = make_case("sphere_collision")
    reason = adapter.unsupported(case.scene, Settings("discrete", dt=DT))
    assert reason.startswith("restitution") and "impact_speed" in reason
    case, prepared, outcome, drifts = run("sphere_collision", {"impact_speed": "1.0"}, integrator="rk3-adaptive")
    assert drifts["velocity_after_error"] * 1.0 < CONTINUOUS_AFTER_TOL  # scale v1 - v2 = 1 m/s
    audit = adapter.audit(prepared, outcome)
    (pair,) = audit["contact_pairs"].values()
    assert pair["restitution_at_impact_speed"] == pytest.approx(0.8, abs=1e-12)


def test_friction_in_continuous_mode_is_unsupported_with_the_reason():
    case = make_case("block_on_incline")
    reason = get_adapter("drake").unsupported(case.scene, Settings("rk3-adaptive", rtol=1e-6))
    assert reason.startswith("friction") and "discrete" in reason


def test_contact_solver_is_a_discrete_option():
    case = make_case("ball_slide_to_roll")
    with pytest.raises(ValueError, match="contact_solver"):
        get_adapter("drake").check(case.scene, case.times, Settings("rk3", dt=DT, options={"contact_solver": "sap"}))
    with pytest.raises(ValueError, match="contact_solver"):
        get_adapter("drake").check(case.scene, case.times, Settings("discrete", dt=DT,
                                                                     options={"contact_solver": "pgs"}))


def test_a_geometry_in_pairs_of_different_friction_is_unsupported():
    # Drake's friction is per geometry (combined per pair): the ground cannot be mu 0.2 with one ball, 0.6 with another
    scene, times = _drop([ContactPair("geom_ball0", "ground", 0.2), ContactPair("geom_ball1", "ground", 0.6)],
                         heights=(0.2, 0.2))
    reason = get_adapter("drake").unsupported(scene, Settings("discrete", dt=DT))
    assert reason.startswith("geometries ['ground']") and "per geometry" in reason
    scene, times = _drop([ContactPair("geom_ball0", "ground", 0.6), ContactPair("geom_ball1", "ground", 0.6)],
                         heights=(0.2, 0.2))
    assert get_adapter("drake").unsupported(scene, Settings("discrete", dt=DT)) is None


def test_a_scene_without_contact_gets_no_scene_graph():
    case = make_case("pendulum")
    prepared = get_adapter("drake").prepare(case.scene, case.times, Settings("discrete", dt=DT))
    assert prepared.model.scene_graph is None and prepared.model.plant.num_collision_geometries() == 0
    assert get_adapter("drake").audit(prepared, get_adapter("drake").run(prepared)).get("contact_pairs") is None


def test_drakes_half_space_warning_is_dropped_and_no_other(caplog):
    # Drake warns once per process that a rigid half space is invisible to deformable contact (no scene has a
    # deformable body); a contact scene's plane installs a filter for that message alone on Drake's logger
    import logging

    run_case("drake", "ball_rolling_incline", Settings("discrete", dt=DT))
    logger = logging.getLogger("drake")
    with caplog.at_level(logging.WARNING, logger="drake"):
        logger.warning("Rigid (non-deformable) half spaces are not currently supported for deformable contact; "
                       "registration is allowed, but no contact data will be reported.")
        logger.warning("any other warning of Drake's")
    assert [r.getMessage() for r in caplog.records] == ["any other warning of Drake's"]
