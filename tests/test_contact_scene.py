"""The contact vocabulary of a scene: geoms, planes, contact pairs, their effect tags and their validation
("where.field: what is wrong — the fix", every problem at once, before anything runs), and the geometry of
``dalembert.contact`` (gaps, slip) against hand-computed values."""

import math

import numpy as np
import pytest

from dalembert import contact
from dalembert.scene import (INITIAL_OVERLAP_TOL, Body, ContactPair, Geom, Joint, Plane, Scene, SceneError)

G = (0.0, 0.0, -9.81)


def ball_scene(z=0.1, radius=0.1, pairs=None, geoms=None, planes=None, v0=(0.0,) * 6):
    ball = Body("ball", 1.0, np.eye(3) * 0.004)
    return Scene("ball", [ball], [Joint("free", "world", "ball", q0=[0.0, 0.0, z, 1.0, 0.0, 0.0, 0.0], v0=v0)], G,
                 geoms=geoms if geoms is not None else [Geom("ball", "sphere", (radius,))],
                 planes=planes if planes is not None else [Plane()],
                 contacts=pairs if pairs is not None else [ContactPair("geom_ball", "ground", 0.5)])


def problems(**kw):
    with pytest.raises(SceneError) as e:
        ball_scene(**kw)
    return e.value.problems


def test_effects_follow_the_pairs():
    assert {"contact", "friction"} <= ball_scene().effects and "restitution" not in ball_scene().effects
    frictionless = ball_scene(pairs=[ContactPair("geom_ball", "ground", 0.0, restitution=0.5)])
    assert "friction" not in frictionless.effects and {"contact", "restitution"} <= frictionless.effects
    # a geom without a pair touches nothing: no contact effect
    assert not {"contact", "friction", "restitution"} & ball_scene(pairs=[]).effects


def test_a_scene_without_contact_keeps_its_data_and_json():
    scene = ball_scene(pairs=[], geoms=[], planes=[])
    assert not {"geoms", "planes", "contacts"} & set(scene.to_json())
    with_contact = ball_scene()
    assert Scene.from_json(with_contact.to_json()) == with_contact


def test_unknown_names_in_a_pair_are_refused_with_a_suggestion():
    (p,) = problems(pairs=[ContactPair("geom_ball", "grund", 0.5)])
    assert p.startswith("contacts[0]") and ".b: no geom or plane named 'grund'" in p and "'ground'" in p


def test_negative_or_non_finite_friction_is_refused():
    for mu in (-0.1, math.inf, math.nan):
        (p,) = problems(pairs=[ContactPair("geom_ball", "ground", mu)])
        assert ".friction: must be finite and >= 0" in p and " — " in p


def test_restitution_outside_zero_one_is_refused():
    for e in (-0.1, 1.5, math.nan):
        (p,) = problems(pairs=[ContactPair("geom_ball", "ground", 0.5, restitution=e)])
        assert ".restitution: must lie in [0, 1]" in p
    for e in (0.0, 1.0):  # the ends are physical
        ball_scene(pairs=[ContactPair("geom_ball", "ground", 0.5, restitution=e)])


def test_geometry_sizes_must_be_positive_and_complete():
    (p,) = problems(geoms=[Geom("ball", "sphere", (0.0,))])
    assert p.startswith("geoms[0] ('geom_ball' on 'ball').size: radius must be positive")
    (p,) = problems(geoms=[Geom("ball", "box", (0.2, -0.1, 0.2))], pairs=[])
    assert "sx, sy, sz must be positive" in p
    (p,) = problems(geoms=[Geom("ball", "box", (0.2, 0.2))], pairs=[])
    assert ".size: needs 3 numbers (sx, sy, sz, m), got 2" in p
    (p,) = problems(geoms=[Geom("ball", "cone", (0.2,))], pairs=[])
    assert ".kind: unknown 'cone'" in p


def test_geom_on_unknown_body_plane_without_normal_and_bad_pairs():
    found = problems(geoms=[Geom("bal", "sphere", (0.1,), name="g")], planes=[Plane(normal=(0.0, 0.0, 0.0))],
                     pairs=[ContactPair("ground", "ground"), ContactPair("g", "ground"), ContactPair("ground", "g")])
    text = "\n".join(found)
    assert ".body: no body named 'bal' — did you mean 'ball'?" in text
    assert "planes[0] ('ground').normal: zero length" in text
    assert "pairs 'ground' with itself" in text
    assert "contacts[2]" in text and "the same shapes as contacts[1]" in text


def test_two_geoms_of_one_body_cannot_pair_and_names_are_unique():
    found = problems(geoms=[Geom("ball", "sphere", (0.1,), name="a"), Geom("ball", "sphere", (0.05,), name="a")],
                     pairs=[ContactPair("a", "a", name="p")])
    assert any("name 'a' used twice" in p for p in found)
    found = problems(geoms=[Geom("ball", "sphere", (0.1,), name="a"), Geom("ball", "sphere", (0.05,), name="b")],
                     pairs=[ContactPair("a", "b")])
    assert any("both geoms are on body 'ball'" in p for p in found)


def test_initial_interpenetration_is_refused_beyond_its_tolerance():
    (p,) = problems(z=0.09)
    assert "interpenetrate by 0.01 m at the initial state" in p and "INITIAL_OVERLAP_TOL" in p
    ball_scene(z=0.1 - 0.5 * INITIAL_OVERLAP_TOL)  # touching, to roundoff: accepted
    ball_scene(z=0.5)  # apart: accepted


def test_gaps_against_hand_computed_distances():
    # a box of edges (0.4, 0.2, 0.1) turned 30 degrees about y, its centre 0.2 m above a level ground:
    # its lowest corners sit sx/2 sin(30) + sz/2 cos(30) below the centre
    a = math.radians(30.0)
    box = Body.box("box", 1.0, (0.4, 0.2, 0.1))
    q = [math.cos(a / 2), 0.0, math.sin(a / 2), 0.0]
    scene = Scene("b", [box], [Joint("free", "world", "box", q0=[0.0, 0.0, 0.2, *q], v0=[0.0] * 6)], G,
                  geoms=[Geom("box", "box", (0.4, 0.2, 0.1))], planes=[Plane()],
                  contacts=[ContactPair("geom_box", "ground", 0.3)])
    g = contact.gap(scene, scene.contacts[0], contact.initial_poses(scene))
    assert g[0] == pytest.approx(0.2 - 0.2 * math.sin(a) - 0.05 * math.cos(a), abs=1e-15)
    # two spheres: centre distance minus the radii; a sphere against a box face
    b1, b2 = Body("s1", 1.0, np.eye(3)), Body("s2", 1.0, np.eye(3))
    two = Scene("two", [b1, b2], [Joint("free", "world", "s1", q0=[0.0, 0.0, 0.0, 1, 0, 0, 0], v0=[0.0] * 6),
                                  Joint("free", "world", "s2", q0=[0.5, 0.0, 0.0, 1, 0, 0, 0], v0=[0.0] * 6)], G,
                geoms=[Geom("s1", "sphere", (0.1,)), Geom("s2", "box", (0.2, 0.2, 0.2)),
                       Geom("s2", "sphere", (0.15,), name="s2_ball")],
                contacts=[ContactPair("geom_s1", "geom_s2"), ContactPair("geom_s1", "s2_ball")])
    poses = contact.initial_poses(two)
    assert contact.gap(two, two.contacts[0], poses)[0] == pytest.approx(0.5 - 0.1 - 0.1, abs=1e-15)
    assert contact.gap(two, two.contacts[1], poses)[0] == pytest.approx(0.5 - 0.1 - 0.15, abs=1e-15)


def test_slip_is_zero_when_a_ball_rolls_and_its_speed_when_it_slides():
    R = 0.1
    rolling = ball_scene(z=R, v0=(2.0, 0.0, 0.0, 0.0, 2.0 / R, 0.0))  # w about +y: v = w R rolls along +x
    poses = contact.initial_poses(rolling)
    assert np.abs(contact.slip_velocity(rolling, rolling.contacts[0], poses)).max() < 1e-15
    sliding = ball_scene(z=R, v0=(2.0, 0.0, 0.0, 0.0, 0.0, 0.0))
    slip = contact.slip_velocity(sliding, sliding.contacts[0], contact.initial_poses(sliding))
    assert slip[0] == pytest.approx([2.0, 0.0, 0.0], abs=1e-15)
