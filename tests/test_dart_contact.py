"""DART's hard contact (``adapters/dart/contact.py``) on the contact cases' closed forms."""

import dataclasses

import numpy as np
import pytest

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter
from dalembert.errors import trajectory_errors
from dalembert.scene import ContactPair, Plane
from installed import needs

pytestmark = needs("dartpy")

ADAPTER = get_adapter("dart")

# Two spheres meeting head on (restitution 0.8, frictionless), dt = 1e-3: the velocities after the impact against
# Newton's, measured 1.35e-5 m/s (the same at 1e-4: the impact is solved as one LCP); 7x. Without the self-collision
# check switched on the spheres pass through each other (measured: the test fails).
SPHERES_VELOCITY_TOL = 1e-4
# The ball launched sliding (mu = 0.1), dt = 1e-4: the velocities against the closed form's slide then roll,
# measured 3.7e-9 m/s (9.0e-8 at 1e-3); 30x. With the pair's friction 1 instead of 0.1 the slide ends ten times
# sooner (measured: the test fails).
SLIDE_TO_ROLL_VELOCITY_TOL = 1e-7
# The ball dropped on the ground (restitution 0.5), dt = 1e-4: the position against the closed form's bounces,
# measured 3.1e-4 m (the impact lands on a step, 1e-4 s at ~4.4 m/s) and the apex 6.4e-5 m; 3x.
BOUNCE_POSITION_TOL = 1e-3


def run(case, dt):
    prepared = ADAPTER.prepare(case.scene, case.times, Settings("euler", dt=dt))
    return prepared, ADAPTER.run(prepared)


def test_two_spheres_leave_with_newton_s_restitution():
    case = make_case("sphere_collision")
    _, outcome = run(case, 1e-3)
    e = trajectory_errors(outcome.trajectory, case.exact(case.times))
    assert e["velocity"][1] < SPHERES_VELOCITY_TOL


def test_a_sliding_ball_rolls_where_coulomb_says():
    case = make_case("ball_slide_to_roll")
    _, outcome = run(case, 1e-4)
    e = trajectory_errors(outcome.trajectory, case.exact(case.times))
    assert e["velocity"][0] < SLIDE_TO_ROLL_VELOCITY_TOL and e["angular_velocity"][0] < SLIDE_TO_ROLL_VELOCITY_TOL


def test_a_dropped_ball_bounces_with_its_restitution():
    case = make_case("bouncing_ball")
    prepared, outcome = run(case, 1e-4)
    assert trajectory_errors(outcome.trajectory, case.exact(case.times))["position"][0] < BOUNCE_POSITION_TOL
    audit = ADAPTER.audit(prepared, outcome)
    assert audit["contact_shapes"] == {"geom_ball": {"shape": "SphereShape", "friction": 0.0, "restitution": 0.5},
                                       "ground": {"shape": "PlaneShape", "friction": 1.0, "restitution": 1.0}}
    assert audit["shapes"] == 1 and audit["collision_shape_frames"] == 2  # the ball's and the ground's


def test_two_pairs_and_a_friction_above_one_are_refused_with_the_reason():
    scene = make_case("bouncing_ball").scene
    two = dataclasses.replace(scene, planes=scene.planes + (Plane("wall", (1.0, 0.0, 0.0), (-5.0, 0.0, 0.0)),),
                              contacts=scene.contacts + (ContactPair("geom_ball", "wall"),))
    assert "more than one contact pair" in ADAPTER.unsupported(two, Settings("euler", dt=1e-3))
    rough = dataclasses.replace(scene, contacts=(dataclasses.replace(scene.contacts[0], friction=1.5),))
    assert "friction 1.5 > 1" in ADAPTER.unsupported(rough, Settings("euler", dt=1e-3))


def test_a_scene_without_contact_has_no_shape():
    case = make_case("particle_box", t_final=0.1)
    prepared, outcome = run(case, 1e-2)
    audit = ADAPTER.audit(prepared, outcome)
    assert audit["collision_shape_frames"] == 0 and "contact_shapes" not in audit


def test_dart_s_own_defaults_put_a_slow_slide_to_sleep():
    """``defaults=engine``: DART's deactivation (on by default, 0.5 s below 1 mm/s for a body in a contact island)
    freezes a box sliding frictionless on the ground at 0.5 mm/s; ``defaults=scene`` (the default) lets it slide,
    exactly: 1.5 mm in 3 s. Measured: asleep from 0.5 s, the box stops 0.25 mm from its start."""
    from dalembert.scene import Body, ContactPair, Geom, Joint, Scene

    box = Body.box("box", 1.0, (0.2, 0.2, 0.1))
    scene = Scene("slow_slide", (box,), (Joint("free", "world", "box", (0, 0, 0.05, 1, 0, 0, 0), (5e-4, 0, 0, 0, 0, 0)),),
                  (0.0, 0.0, -9.81), geoms=(Geom("box", "box", (0.2, 0.2, 0.1)),), planes=(Plane("ground"),),
                  contacts=(ContactPair("geom_box", "ground"),))
    times = np.linspace(0.0, 3.0, 31)
    slid = {}
    for defaults in ("scene", "engine"):
        prepared = ADAPTER.prepare(scene, times, Settings("euler", dt=1e-3, options={"defaults": defaults}))
        slid[defaults] = ADAPTER.run(prepared).trajectory.bodies["box"].position[-1, 0]
    assert slid["scene"] == pytest.approx(1.5e-3, rel=1e-9)
    assert slid["engine"] < 0.5e-3  # asleep
