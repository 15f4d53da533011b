"""Every bad input is reported, naming its field, before anything runs."""

import numpy as np
import pytest

from dalembert import make_case
from dalembert.case import Case
from dalembert.scene import Body, Joint, Load, Scene, SceneError

FREE_Q0 = [0, 0, 0, 1, 0, 0, 0]
FREE_V0 = [0, 0, 0, 0, 0, 0]


def good_body(name="b", **kw):
    return Body(name, kw.pop("mass", 1.0), kw.pop("inertia", np.diag([1.0, 2.0, 2.5])), **kw)


def scene(bodies=None, joints=None, loads=(), gravity=(0, 0, 0)):
    bodies = bodies if bodies is not None else [good_body()]
    joints = joints if joints is not None else [Joint("free", "world", "b", FREE_Q0, FREE_V0)]
    return Scene("s", bodies, joints, gravity, loads)


def problems(**kw):
    with pytest.raises(SceneError) as info:
        scene(**kw)
    return info.value.problems


def test_a_good_scene_passes():
    s = scene()
    assert s.effects == frozenset({"joint:free"})


@pytest.mark.parametrize("mass", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_mass(mass):
    (p,) = problems(bodies=[good_body(mass=mass)])
    assert "bodies['b'].mass" in p and "positive" in p


@pytest.mark.parametrize("inertia,words", [
    ([[1, 0.1, 0], [0, 2, 0], [0, 0, 2.5]], "not symmetric"),
    (np.diag([1.0, -2.0, 2.5]), "not positive definite"),
    (np.diag([1.0, 1.0, 3.0]), "triangle inequality"),
    (np.diag([1.0, np.nan, 2.0]), "NaN"),
    (np.eye(2), "3x3"),
])
def test_bad_inertia(inertia, words):
    (p,) = problems(bodies=[good_body(inertia=inertia)])
    assert "bodies['b'].inertia" in p and words in p


def test_particles_on_a_line_are_the_degenerate_case():
    body, _ = Body.from_point_masses("b", [1, 1, 1], [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    (p,) = problems(bodies=[body])
    assert "singular" in p and "one line" in p and "rotator" in p


def test_non_unit_quaternions():
    (p,) = problems(joints=[Joint("free", "world", "b", [0, 0, 0, 1, 0.1, 0, 0], FREE_V0)])
    assert "q0[3:7]" in p and "norm" in p
    ps = problems(joints=[Joint("ball", "world", "b", [1, 0, 0, 0], [0, 0, 0], child_quat=[2, 0, 0, 0])])
    assert len(ps) == 1 and "child_quat" in ps[0] and "norm" in ps[0]


def test_unknown_names_suggest():
    ps = problems(joints=[Joint("free", "world", "bb", FREE_Q0, FREE_V0)], loads=[Load("c", "force", [1, 0, 0], "world")])
    assert any("child: no body named 'bb'" in p and "did you mean 'b'" in p for p in ps)
    assert any("loads[0]" in p and "'c'" in p for p in ps)
    assert any("bodies['b']: has no joint" in p for p in ps)


def test_two_parents_and_cycles():
    bodies = [good_body("a"), good_body("b")]
    two = [Joint("weld", "world", "a"), Joint("weld", "world", "b"), Joint("weld", "a", "b")]
    assert any("two parents" in p for p in problems(bodies=bodies, joints=two))
    cycle = [Joint("weld", "b", "a"), Joint("weld", "a", "b")]
    assert any("cycle" in p for p in problems(bodies=bodies, joints=cycle))


def test_zero_length_axis():
    (p,) = problems(joints=[Joint("revolute", "world", "b", [0.0], [0.0], axis=[0, 0, 0])])
    assert "axis" in p and "zero length" in p


def test_a_prismatic_joint_needs_its_sliding_direction_and_a_ball_takes_none():
    (p,) = problems(joints=[Joint("prismatic", "world", "b", [0.0], [0.0])])
    assert p.startswith("joints[0] (prismatic 'world' -> 'b').axis:") and "sliding direction" in p
    (p,) = problems(joints=[Joint("ball", "world", "b", [1.0, 0, 0, 0], [0.0] * 3, axis=[0, 0, 1])])
    assert "only revolute and prismatic joints take an axis" in p


def test_nan_anywhere():
    ps = problems(joints=[Joint("free", "world", "b", FREE_Q0, [0, 0, 0, np.nan, 0, 0])],
                  loads=[Load("b", "force", [np.inf, 0, 0], "body")], gravity=(0, 0, np.nan))
    assert any("v0" in p and "NaN" in p for p in ps)
    assert any(p.startswith("loads[0]") and ".vector: contains NaN" in p for p in ps)
    assert any(p.startswith("gravity") for p in ps)


def test_every_problem_at_once():
    ps = problems(bodies=[good_body(mass=-1, inertia=np.diag([1.0, 1.0, 3.0]))],
                  joints=[Joint("revolute", "world", "b", [0.0, 1.0], [0.0], axis=[0, 0, 0])],
                  loads=[Load("b", "push", [1, 0, 0], "sideways")])
    assert len(ps) == 6, ps


def test_case_times_and_duration():
    s = scene()
    with pytest.raises(SceneError, match="not strictly increasing"):
        Case("c", s, 1.0, [0.0, 0.5, 0.5, 1.0])
    with pytest.raises(SceneError, match="t_final: must be a positive duration"):
        Case("c", s, -1.0, [0.0, 1.0])
    with pytest.raises(SceneError, match="t_final"):
        make_case("free_top", t_final=0.0)
    with pytest.raises(SceneError, match="does not divide"):
        make_case("free_top", t_final=1.0, sample_interval=0.3)
    with pytest.raises(SceneError, match="did you mean 'omega0'"):
        make_case("free_top", omega=(1, 2, 3))


def test_bad_case_parameter_fails_before_running():
    with pytest.raises(SceneError, match="mass"):
        make_case("pivoted_rod", mass=-1.0)
    with pytest.raises(SceneError, match="free_top.inertia: must be positive"):
        make_case("free_top", inertia=(0.0, 1.0, 1.0))
    with pytest.raises(SceneError, match="triangle"):  # positive, but no mass distribution has them
        make_case("free_top", inertia=(1.0, 1.0, 3.0))


@pytest.mark.parametrize("rtol", [1.0, 5.0, 1])
def test_an_adaptive_tolerance_of_one_or_more_is_refused(rtol):
    """rtol >= 1 lets every step err by the state itself: it asks no accuracy (settings.RTOL_MAX)."""
    from dalembert.settings import Settings, SettingsError

    with pytest.raises(SettingsError, match=r"rtol: .* asks no accuracy .* use rtol < 1"):
        Settings("dop853", rtol=rtol)
    assert Settings("dop853", rtol=0.5).rtol == 0.5  # below 1: a (loose) tolerance
