"""Exudyn refuses contact scenes, and its reason says what a mapping onto its contact elements would take (1.13:
GeneralContact, ObjectContactSphereSphere / ObjectContactSphereTriangle); contact-free scenes are not refused."""

import pytest

pytest.importorskip("exudyn")

from dalembert.adapters import get_adapter  # noqa: E402
from dalembert.case import make_case  # noqa: E402
from dalembert.settings import Settings  # noqa: E402

ADAPTER = get_adapter("exudyn")
SETTINGS = Settings("generalized-alpha", dt=1e-3)


@pytest.mark.parametrize("name", ["block_on_incline", "ball_slide_to_roll", "ball_rolling_incline", "bouncing_ball",
                                  "sphere_collision"])
def test_every_contact_case_is_refused_with_what_a_mapping_would_take(name):
    case = make_case(name)
    reason = ADAPTER.unsupported(case.scene, SETTINGS)
    assert reason.startswith("contact not yet mapped for exudyn")
    assert str([c.name for c in case.scene.contacts]) in reason  # the pairs that would be left out
    for element in ("GeneralContact.AddSphereWithMarker", "ObjectContactSphereSphere", "AddTrianglesRigidBodyBased",
                    "contactStiffness", "restitutionCoefficient", "frictionProportionalZone"):
        assert element in reason


def test_the_named_contact_elements_exist_in_the_installed_exudyn():
    import exudyn
    import exudyn.itemInterface as items

    assert hasattr(exudyn.GeneralContact, "AddSphereWithMarker")
    assert hasattr(exudyn.GeneralContact, "AddTrianglesRigidBodyBased")
    for connector in ("ObjectContactSphereSphere", "ObjectContactSphereTriangle"):
        params = getattr(items, connector).__init__.__code__.co_varnames
        assert {"contactStiffness", "contactDamping", "restitutionCoefficient", "frictionProportionalZone",
                "impactModel"} <= set(params)


def test_a_contact_free_scene_is_not_refused_for_contact():
    assert ADAPTER.unsupported(make_case("pivoted_rod").scene, SETTINGS) is None
