"""Exudyn runs the contact cases its connectors can represent (a sphere against a plane or a sphere:
ObjectContactSphereTriangle, ObjectContactSphereSphere), with its penalty stiffness and friction zone as options,
every connector read back in the audit; what it cannot represent is refused with the reason (a box; explicit
solvers; a geom on a link of the kinematic tree). Exudyn 1.13.6, generalized-alpha (the numbers each bound rests on
are in its comment, measured at the default options: contact_stiffness 1e6 N/m, friction_zone 1e-3 m/s)."""

import numpy as np
import pytest
from installed import needs

pytestmark = needs("exudyn")

from dalembert.adapters import get_adapter  # noqa: E402
from dalembert.adapters.exudyn import contact  # noqa: E402
from dalembert.case import make_case  # noqa: E402
from dalembert.kinds import CONTACT_EFFECTS  # noqa: E402
from dalembert.scene import Body, ContactPair, Geom, Joint, Plane, Scene  # noqa: E402
from dalembert.settings import Settings  # noqa: E402
from engine_runs import run_case  # noqa: E402

ADAPTER = get_adapter("exudyn")
# The ball starts rolling 0.03 ms after the closed form's onset at dt = 1e-3 (t* = 0.2912 s; the same at 1e-4):
# the friction is regularized only below 1e-3 m/s of slip; the bound leaves ~3x.
ROLL_ONSET_BOUND = 1e-4
# Rolling down the 20-degree incline, the contact slips at a measured 2.08e-4 m/s at dt = 1e-4: the fraction of
# friction_zone that the friction rolling needs (2/7 m g sin(angle) of mu m g cos(angle)) takes; leaves ~2.4x.
ROLLING_SLIP_BOUND = 5e-4
# Restitution 0.5 through impact model 2 at dt = 1e-4: the first two apexes 0.2462 and 0.0602 m for 0.25 and
# 0.0625 (3.8 mm off at most, of the 1-m drop); at dt = 1e-3 the fixed steps lose more (0.1905, 0.0312 m). The
# bound is the case's APEX_TOL, ~2.6x the measured error.
APEX_ERROR_BOUND = 1e-2
# The spheres leave at -0.3502 and 0.4501 m/s for -0.35 and 0.45 at dt = 1e-4 (at 1e-3: -0.4105, 0.4702); the
# bound leaves 5x over the 2e-4-m/s error.
AFTER_BOUND = 1e-3


def run(name, dt, integrator="generalized-alpha", options=None, **params):
    return run_case("exudyn", name, Settings(integrator, dt=dt, options=options or {}), **params)[1:]


def test_exudyn_declares_contact_and_its_options():
    assert CONTACT_EFFECTS <= ADAPTER.effects
    assert {"contact_stiffness", "friction_zone"} <= set(ADAPTER.options)
    with pytest.raises(ValueError, match="options.contact_stiffness"):
        ADAPTER.check(make_case("bouncing_ball").scene, [0.0, 0.1],
                      Settings("generalized-alpha", dt=1e-3, options={"contact_stiffness": "-1"}))


def test_ball_starts_rolling_at_t_star_and_the_audit_reads_the_connector_back():
    prepared, outcome, drifts = run("ball_slide_to_roll", 1e-3)
    assert abs(drifts["roll_onset_error"]) < ROLL_ONSET_BOUND
    audit = ADAPTER.audit(prepared, outcome)
    (pair,) = audit["contact_pairs"].values()
    assert pair["type"] == "ObjectContactSphereTriangle" and pair["includeEdges"] == 0
    assert (pair["contactStiffness"], pair["dynamicFriction"], pair["frictionProportionalZone"]) == (
        contact.STIFFNESS_DEFAULT, 0.1, contact.FRICTION_ZONE_DEFAULT)
    # no restitution: critically damped, 2 sqrt(k m) for the 1-kg ball
    assert pair["impactModel"] == 0 and pair["contactDamping"] == pytest.approx(2.0 * np.sqrt(1e6))
    assert audit["contacts"] == 1 and audit["passive_extra"] == []
    assert audit["newton_tolerances"] == [1e-8, 1e-10] and "off" in audit["recommended_step_size"]


def test_ball_rolls_down_the_incline_slipping_within_the_friction_zone():
    *_, drifts = run("ball_rolling_incline", 1e-4)
    assert drifts["slip"] < ROLLING_SLIP_BOUND


def test_restitution_through_the_impact_model():
    prepared, outcome, ball = run("bouncing_ball", 1e-4, integrator="trapezoidal-index2")
    assert ball["apex_error"] < APEX_ERROR_BOUND
    (pair,) = ADAPTER.audit(prepared, outcome)["contact_pairs"].values()
    assert (pair["impactModel"], pair["restitutionCoefficient"], pair["contactDamping"]) == (2, 0.5, 0.0)
    prepared, outcome, spheres = run("sphere_collision", 1e-4)
    assert spheres["velocity_after_error"] < AFTER_BOUND
    assert spheres["linear_momentum"] < 1e-9  # (equal and opposite connector forces)
    (pair,) = ADAPTER.audit(prepared, outcome)["contact_pairs"].values()
    assert pair["type"] == "ObjectContactSphereSphere" and pair["radii"] == [0.1, 0.1]


def _pendulum_ball():
    """A ball on a rod pivoted at the world by a revolute joint, over a plane: its geom is on a tree link."""
    return Scene("pendulum_ball", bodies=[Body("rod", 1.0, np.eye(3) * 0.004)],
                 joints=[Joint("revolute", "world", "rod", axis=(0.0, 1.0, 0.0), parent_point=(0.0, 0.0, 1.0),
                               child_point=(0.0, 0.0, 0.5), q0=[0.0], v0=[0.0])],
                 gravity=[0.0, 0.0, -9.81], geoms=[Geom("rod", "sphere", (0.1,))],
                 planes=[Plane("ground")], contacts=[ContactPair("geom_rod", "ground", 0.0, restitution=0.5)])


def test_what_exudyn_cannot_represent_is_refused_with_the_reason():
    block = make_case("block_on_incline").scene
    reason = ADAPTER.unsupported(block, Settings("generalized-alpha", dt=1e-3))
    assert reason.startswith("contacts.contact_geom_box_slope: a box in a pair") and "spheres at its corners" in reason
    reason = ADAPTER.unsupported(make_case("bouncing_ball").scene, Settings("rk44", dt=1e-3))
    assert reason.startswith("contact with an explicit solver") and "generalized-alpha" in reason
    rolling = make_case("ball_rolling_incline").scene  # friction under gravity along the plane: small steps only
    reason = ADAPTER.unsupported(rolling, Settings("generalized-alpha", dt=1e-3))
    assert reason.startswith("contacts.contact_geom_ball_slope: friction on a plane that gravity pulls") and (
        f"--dt {contact.LOADED_FRICTION_DT_MAX:g}" in reason)
    assert ADAPTER.unsupported(rolling, Settings("generalized-alpha", dt=contact.LOADED_FRICTION_DT_MAX)) is None
    level = make_case("ball_slide_to_roll").scene  # (gravity normal to the plane: any step)
    assert ADAPTER.unsupported(level, Settings("generalized-alpha", dt=1e-2)) is None
    scene = _pendulum_ball()
    reason = ADAPTER.unsupported(scene, Settings("generalized-alpha", dt=1e-3))
    assert "link of Exudyn's kinematic tree" in reason and "joints=redundant" in reason
    assert ADAPTER.unsupported(scene, Settings("generalized-alpha", dt=1e-3, options={"joints": "redundant"})) is None
