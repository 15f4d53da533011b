"""The robot cases (cases/robot.py): the case contract on the default one, a user's own file by path, the
free fall's conserved quantities, and clear refusals."""

import importlib.metadata

import numpy as np
import pytest

from dalembert.case import CASES, in_default_matrix, load_cases, parse_param
from dalembert.models import library
from dalembert.scene import SceneError
from dalembert.testing import check_case

from test_models_urdf import ARM, robots

load_cases()

# check_case runs the truth and its second solution: half a second of the swing keeps it to a few seconds.
CONTRACT_HORIZON = 0.5


def test_one_robot_case_is_in_the_default_matrix():
    assert in_default_matrix(CASES["robot_arm"])
    assert not in_default_matrix(CASES["robot_tree"]) and not in_default_matrix(CASES["robot_free_fall"])
    assert all("robot" in CASES[n].tags for n in ("robot_arm", "robot_free_fall", "robot_tree"))


@robots
def test_the_default_robot_case_meets_the_case_contract():
    case = check_case("robot_arm", horizon=CONTRACT_HORIZON)
    assert len(case.scene.bodies) == 6 and sum(len(j.v0) for j in case.scene.joints) == 6  # UR5, its base the world's


@robots
def test_the_free_fall_conserves_momentum_and_energy_in_its_truth():
    case = check_case("robot_free_fall", horizon=0.2)
    assert case.scene.joint("base_link").kind == "free" and case.scene.gravity == (0.0, 0.0, 0.0)
    assert sum(len(j.v0) for j in case.scene.joints) == 18  # Solo12: 6 + 12


def test_a_file_of_the_user_s_own_by_path(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(ARM)
    key, value = parse_param(CASES["robot_arm"], f"model={path}")
    assert (key, value) == ("model", str(path))
    case = CASES["robot_arm"](model=value, pose="0.7", t_final=0.3)
    assert case.scene.joint("upper").q0 == (0.7,)
    default = CASES["robot_arm"](model=value, t_final=0.3)
    assert default.scene.joint("upper").q0 == (0.5,)  # spread on every joint
    assert default.version != case.version


@pytest.mark.parametrize("params, words", [
    (dict(model="nosuchbot"), ["robot.model: 'nosuchbot' is neither a known robot", "ur5"]),
    (dict(model=""), ["robot_arm.model: must be a robot's name"]),
])
def test_bad_models_are_refused_by_name(params, words):
    with pytest.raises(SceneError) as err:
        CASES["robot_arm"](**params)
    for w in words:
        assert w in str(err.value)


def test_a_pose_of_the_wrong_length_names_the_joints(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(ARM)
    with pytest.raises(SceneError, match=r"robot_arm.pose: 1 comma-separated joint coordinates wanted .*shoulder"):
        CASES["robot_arm"](model=str(path), pose="0.1,0.2")


def test_a_missing_robot_package_is_refused_with_the_install_line(monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)
    monkeypatch.setattr(library.importlib.metadata, "distribution", missing)
    with pytest.raises(SceneError, match=r"robot.model: 'panda' comes from example-robot-data, not installed — pip "
                                         r"install dalembert\[robots\]"):
        CASES["robot_arm"](model="panda")


@robots
def test_panda_s_fingers_are_held_and_its_pose_is_set():
    case = CASES["robot_arm"](model="panda", t_final=0.1)
    assert {j.kind for j in case.scene.joints} == {"revolute", "weld"}
    assert np.isclose(case.scene.joint("panda_link4").q0[0], -1.0)
