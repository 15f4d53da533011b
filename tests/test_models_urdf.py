"""URDF into scenes (dalembert.models.urdf): frames and inertias by hand, the file's effects, the errors, every
URDF of example-robot-data, and the mass matrix against Pinocchio's own URDF reader."""

import importlib.metadata
import os
import textwrap

import numpy as np
import pytest

from dalembert import spatial
from dalembert.models import ModelError, read_urdf, robot_path
from dalembert.models import library
from dalembert.models.tree import rpy_to_matrix

# Sums of ~10-100 products of doubles, done two ways (Kane's Jacobians here, Pinocchio's CRBA): they agree to a
# few ulps of the largest entry (measured 4e-16 on UR5, Panda, Solo12, Talos); 1e-12 leaves room for longer
# trees and still catches any wrong frame, sign or inertia (errors of O(1) relative).
MASS_MATRIX_REL_TOL = 1e-12
# Frames and inertias computed by hand from the file's decimals: a few ulps.
EXACT_TOL = 1e-14

ARM = """\
<robot name="arm">
  <link name="base">
    <inertial><origin xyz="0 0 0.1"/><mass value="2.0"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.04"/></inertial>
  </link>
  <link name="upper">
    <inertial><origin xyz="0.25 0 0" rpy="0 0 1.5707963267948966"/><mass value="1.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.031"/></inertial>
  </link>
  <link name="tool"/>
  <link name="weight"><inertial><origin xyz="0.1 0 0"/><mass value="0.5"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <link name="marker"/>
  <joint name="shoulder" type="continuous">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.3" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/>
    <dynamics damping="0.5" friction="0.1"/>
  </joint>
  <joint name="tool_mount" type="fixed"><parent link="upper"/><child link="tool"/><origin xyz="0.5 0 0"/></joint>
  <joint name="weight_mount" type="fixed"><parent link="tool"/><child link="weight"/><origin xyz="0 0.2 0"/></joint>
  <joint name="marker_slide" type="prismatic"><parent link="base"/><child link="marker"/>
    <limit lower="0" upper="1" effort="10" velocity="1"/></joint>
  <transmission name="t1"><joint name="shoulder"/><actuator name="m1"/></transmission>
</robot>
"""


def _write(tmp_path, text, name="arm.urdf"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return str(path)


def test_bodies_sit_at_their_coms_with_the_inertia_rotated_into_the_link_frame(tmp_path):
    model = read_urdf(_write(tmp_path, ARM), positions={"shoulder": 0.3})
    scene = model.scene
    # The fixed base is the world's; tool and weight merged into upper; the massless marker dropped.
    assert [b.name for b in scene.bodies] == ["upper"]
    upper = scene.body("upper")
    # The inertial frame is turned 90 degrees about z: its x and y moments swap in the link frame; the
    # 0.5 kg point mass merged at (0.6, 0.2, 0) in the link frame moves the COM and adds m d^2 terms.
    m1, c1, m2, c2 = 1.5, np.array([0.25, 0.0, 0.0]), 0.5, np.array([0.6, 0.2, 0.0])
    c = (m1 * c1 + m2 * c2) / (m1 + m2)
    I = np.diag([0.03, 0.001, 0.031])
    for m, ci in ((m1, c1), (m2, c2)):
        d = ci - c
        I = I + m * (d @ d * np.eye(3) - np.outer(d, d))
    assert upper.mass == pytest.approx(2.0, abs=EXACT_TOL)
    np.testing.assert_allclose(upper.inertia_matrix, I, atol=EXACT_TOL)
    j = scene.joint("upper")
    assert j.kind == "revolute" and j.parent == "world" and j.q0 == (0.3,)
    # The joint origin (0, 0, 0.3) in the base link frame, which is the world's; the child's link origin (the
    # joint frame) seen from its COM.
    np.testing.assert_allclose(j.parent_point, [0.0, 0.0, 0.3], atol=EXACT_TOL)
    np.testing.assert_allclose(j.child_point, -c, atol=EXACT_TOL)
    np.testing.assert_allclose(spatial.quat_to_matrix(j.parent_quat), rpy_to_matrix([np.pi / 2, 0, 0]), atol=EXACT_TOL)
    merged = {e.element: e.value for e in model.effects.effects if e.kind == "merged"}
    assert merged["<link name='base'>"] == "into the world (the fixed root)"
    assert model.joint_names == {"shoulder": "upper"}


def test_the_file_s_effects_are_collected_and_left_out(tmp_path):
    effects = read_urdf(_write(tmp_path, ARM)).effects
    assert effects.kinds() == ["damping", "dropped", "friction", "limit", "merged", "transmission"]
    assert "damping" in str(effects) and "left out" in str(effects)
    assert read_urdf(_write(tmp_path, ARM)).scene.effects == {"gravity", "joint:revolute"}


def test_rpy_is_fixed_axis_roll_pitch_yaw():
    r, p, y = 0.3, -0.4, 1.1
    Rx = spatial.quat_to_matrix(spatial.quat_from_axis_angle([1, 0, 0], r))
    Ry = spatial.quat_to_matrix(spatial.quat_from_axis_angle([0, 1, 0], p))
    Rz = spatial.quat_to_matrix(spatial.quat_from_axis_angle([0, 0, 1], y))
    np.testing.assert_allclose(rpy_to_matrix([r, p, y]), Rz @ Ry @ Rx, atol=EXACT_TOL)


@pytest.mark.parametrize("edit, words, reason", [
    (('type="prismatic"', 'type="planar"'), ["arm.urdf", "<joint name='marker_slide'>", "planar",
                                               "no planar joint"], "joint type planar"),
    (('<link name="marker"/>', '<link name="marker"/><link name="hand"><inertial><mass value="1"/>'
      '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link><joint name="wrist" '
      'type="revolute"><parent link="marker"/><child link="hand"/></joint>'),
     ["<link name='marker'>", "no mass but moves", "<joint name='marker_slide'>", "give it an <inertial>"],
     "massless moving link"),
    (('<child link="marker"/>', '<child link="markr"/>'), ["<joint name='marker_slide'>", "'markr'"], "broken tree"),
    (('<mass value="1.5"/>', '<mass value="-1.5"/>'), ["<link name='upper'>", "negative"], "bad inertia"),
    (('iyy="0.03" iyz="0" izz="0.031"', 'iyy="0.03" iyz="0" izz="0.5"'),
     ["<link name='upper'>", "triangle inequality", "fix the <inertia>"], "bad inertia"),
    (('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>'), ["<joint name='shoulder'>", "axis"], "bad axis"),
    (('<robot name="arm">', '<mujoco model="arm">'), ["not <robot>", "read_mjcf"], None),
])
def test_errors_name_the_file_the_element_and_the_fix(tmp_path, edit, words, reason):
    text = ARM.replace(*edit)
    if reason is None:
        text = text.replace("</robot>", "</mujoco>")
    with pytest.raises(ModelError) as err:
        read_urdf(_write(tmp_path, text))
    for w in words:
        assert w in str(err.value), (w, str(err.value))
    assert "—" in str(err.value)
    if reason:
        assert err.value.reason == reason


def test_a_massless_floating_root_is_refused(tmp_path):
    text = ARM.replace('<link name="base">', '<link name="root"/><joint name="r" type="fixed"><parent link="root"/>'
                       '<child link="base"/></joint><link name="base">').replace(
        '<joint name="marker_slide" type="prismatic"><parent link="base"/>',
        '<joint name="marker_slide" type="prismatic"><parent link="root"/>')
    assert read_urdf(_write(tmp_path, text), base="free").scene.joint("root").kind == "free"  # base merged in
    bare = ARM.replace('<link name="base">', '<link name="root"/><joint name="r" type="revolute"><parent '
                       'link="root"/><child link="base"/></joint><link name="base">')
    with pytest.raises(ModelError, match="has no mass") as err:
        read_urdf(_write(tmp_path, bare), base="free")
    assert err.value.reason == "massless floating root"


def test_a_missing_robot_package_is_refused_with_the_install_line(monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)
    monkeypatch.setattr(library.importlib.metadata, "distribution", missing)
    with pytest.raises(ModelError) as err:
        robot_path("panda")
    assert str(err.value) == ("robot.model: 'panda' comes from example-robot-data, not installed — pip install "
                              "dalembert[robots]")


def _have_robots():
    try:
        importlib.metadata.distribution(library.DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        return False
    return True


robots = pytest.mark.skipif(not _have_robots(), reason="example-robot-data not installed (pip install "
                                                       "dalembert[robots])")

# example-robot-data 6.0.0: the 69 URDFs it installs, of which these 12 do not import with a fixed base, by
# reason; the other 57 do (test below). "bad inertia": a moving link whose <inertia> no rigid body has (zero
# moments with a mass: icub's ankles; the triangle inequality broken: allegro, romeo, pr2's head plate; a zero
# moment: finger_edu); human.urdf moves massless "virtual" links; ur3.urdf is an empty xacro stub; the two
# quadrotors are single rigid bodies (no moving joint), which import with a floating base instead.
REFUSED = {
    "allegro_hand_description/urdf/allegro_left_hand.urdf": "bad inertia",
    "allegro_hand_description/urdf/allegro_right_hand.urdf": "bad inertia",
    "finger_edu_description/robots/finger_edu.urdf": "bad inertia",
    "hector_description/robots/quadrotor_base.urdf": "no moving joints",
    "human_description/robots/human.urdf": "massless moving link",
    "icub_description/robots/icub.urdf": "bad inertia",
    "icub_description/robots/icub_reduced.urdf": "bad inertia",
    "iris_description/robots/iris_simple.urdf": "no moving joints",
    "pr2_description/urdf/pr2.urdf": "bad inertia",
    "romeo_description/urdf/romeo_laas_small.urdf": "bad inertia",
    "romeo_description/urdf/romeo_small.urdf": "bad inertia",
    "ur_description/urdf/ur3.urdf": "no links",
}
IMPORTED_COUNT = 57


@robots
def test_every_urdf_of_example_robot_data_imports_or_says_why():
    folder = library._robots_folder("every robot")
    refused, imported = {}, []
    for path in library.robot_files():
        rel = os.path.relpath(path, folder)
        try:
            read_urdf(path)
        except ModelError as err:
            assert os.path.basename(path) in str(err)
            refused[rel] = err.reason
            if err.reason == "no moving joints":
                assert read_urdf(path, base="free").scene.joints[0].kind == "free"
        else:
            imported.append(rel)
    assert refused == REFUSED
    assert len(imported) == IMPORTED_COUNT


def _pinocchio_mass_matrix(path, angles):
    pin = pytest.importorskip("pinocchio")
    model = pin.buildModelFromUrdf(path)
    q = pin.neutral(model)
    for name, a in angles.items():
        jm = model.joints[model.getJointId(name)]
        q[jm.idx_q:jm.idx_q + jm.nq] = [a] if jm.nq == 1 else [np.cos(a), np.sin(a)]  # continuous: (cos, sin)
    M = pin.crba(model, model.createData(), q)
    return model, np.triu(M) + np.triu(M, 1).T


@robots
@pytest.mark.parametrize("robot", ["ur5", "panda", "solo12", "talos"])
def test_the_mass_matrix_agrees_with_pinocchio_s_own_urdf_reader(robot):
    from dalembert.reference.generalized import Kane
    path = robot_path(robot)
    pin = pytest.importorskip("pinocchio")
    names = [n for n in pin.buildModelFromUrdf(path).names[1:]]
    angles = dict(zip(names, np.random.default_rng(7).uniform(-1.5, 1.5, len(names))))
    model, M_pin = _pinocchio_mass_matrix(path, angles)
    imported = read_urdf(path, positions=angles)
    kane = Kane(imported.scene)
    M = kane.mass_matrix(kane.kinematics(kane.q0, kane.v0))
    file_name = {child: name for name, child in imported.joint_names.items()}
    cols = [model.joints[model.getJointId(file_name[jd["joint"].child])].idx_v for jd in kane.joints
            if jd["joint"].kind != "weld"]
    assert len(cols) == model.nv
    M_ref = M_pin[np.ix_(cols, cols)]
    assert np.abs(M - M_ref).max() <= MASS_MATRIX_REL_TOL * np.abs(M_ref).max()
