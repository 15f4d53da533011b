"""MJCF into scenes (dalembert.models.mjcf): a file the test writes against the same robot as a URDF, MuJoCo's own
conversion of example-robot-data URDFs, trivial geom inertias, and the errors."""

import textwrap
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from dalembert import spatial
from dalembert.models import ModelError, read_mjcf, read_urdf

from test_models_urdf import ARM, robots

# The same decimals read two ways (URDF rpy and MJCF euler in degrees, inertial rpy and quat): the frames agree
# to a few ulps; 1e-12 catches any wrong convention (errors of O(1)).
SAME_FILE_TOL = 1e-12
# MuJoCo's XML writer (mj_saveLastXML) prints 6 significant digits, and rewrites each inertia as principal
# moments and a quaternion: the two routes agree to ~5e-6 of each quantity (measured 3.5e-6 on Talos), not to
# roundoff; 2e-5 is four printed digits' worth of margin above that and far below any real error.
MUJOCO_PRINT_TOL = 2e-5
# MuJoCo's compiled model (before printing) keeps doubles: it rewrites each inertia as principal moments and a
# quaternion by an eigen-decomposition, exact to a few ulps (measured 1.1e-14 relative on Panda's links, the
# worst of four robots); 1e-12 leaves room and catches any wrong frame or inertia rotation (O(1) errors).
MUJOCO_COMPILED_TOL = 1e-12

ARM_MJCF = """\
<mujoco model="arm">
  <default><joint damping="0.5"/></default>
  <worldbody>
    <body name="base">
      <inertial pos="0 0 0.1" mass="2.0" diaginertia="0.02 0.03 0.04"/>
      <body name="upper" pos="0 0 0.3" euler="90 0 0">
        <joint name="shoulder" axis="0 0 1" frictionloss="0.1"/>
        <inertial pos="0.25 0 0" quat="0.7071067811865476 0 0 0.7071067811865476" mass="1.5"
                  diaginertia="0.001 0.03 0.031"/>
        <body name="tool" pos="0.5 0 0">
          <body name="weight" pos="0 0.2 0">
            <inertial pos="0.1 0 0" mass="0.5" diaginertia="0 0 0"/>
          </body>
        </body>
      </body>
      <body name="marker"><joint name="marker_slide" type="slide" axis="1 0 0" range="0 1"/></body>
    </body>
  </worldbody>
  <actuator><motor name="m1" joint="shoulder"/></actuator>
</mujoco>
"""


def _write(tmp_path, text, name):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return str(path)


def _same_scene(a, b, tol, rel=False):
    """Same bodies (mass, inertia), same joint tree (kind, parent, frames, axis) to ``tol``."""
    assert sorted(x.name for x in a.bodies) == sorted(x.name for x in b.bodies)
    for ba in a.bodies:
        bb = b.body(ba.name)
        assert abs(ba.mass - bb.mass) <= tol * (ba.mass if rel else 1.0), ba.name
        scale = np.abs(ba.inertia_matrix).max() if rel else 1.0
        assert np.abs(ba.inertia_matrix - bb.inertia_matrix).max() <= tol * scale, ba.name
        ja, jb = a.joint(ba.name), b.joint(ba.name)
        assert (ja.kind, ja.parent) == (jb.kind, jb.parent), ba.name
        for f in ("parent_point", "child_point"):
            assert np.abs(np.subtract(getattr(ja, f), getattr(jb, f))).max() <= tol, (ba.name, f)
        for f in ("parent_quat", "child_quat"):
            Ra, Rb = spatial.quat_to_matrix(getattr(ja, f)), spatial.quat_to_matrix(getattr(jb, f))
            assert np.abs(Ra - Rb).max() <= tol, (ba.name, f)
        if ja.axis is not None:
            assert np.abs(np.subtract(ja.axis, jb.axis) / np.linalg.norm(ja.axis)).max() <= tol, ba.name


def test_a_written_mjcf_file_is_the_same_scene_as_its_urdf(tmp_path):
    urdf = read_urdf(_write(tmp_path, ARM, "arm.urdf"), positions={"shoulder": 0.3})
    mjcf = read_mjcf(_write(tmp_path, ARM_MJCF, "arm.xml"), positions={"shoulder": 0.3})
    _same_scene(urdf.scene, mjcf.scene, SAME_FILE_TOL)
    assert mjcf.joint_names == {"shoulder": "upper"}
    kinds = mjcf.effects.kinds()
    assert {"damping", "friction", "actuator", "merged", "dropped"} <= set(kinds)  # damping from the default class


def test_trivial_geom_inertia_and_a_free_joint(tmp_path):
    text = """\
    <mujoco><compiler angle="radian"/>
      <worldbody>
        <body name="ball" pos="1 2 3" quat="0 0 0 1"><freejoint/>
          <geom type="sphere" size="0.1" pos="0.2 0 0"/>
        </body>
        <body name="slab" pos="0 0 1"><joint/><geom type="box" size="0.1 0.2 0.3" mass="3"/></body>
      </worldbody>
    </mujoco>"""
    scene = read_mjcf(_write(tmp_path, text, "g.xml")).scene
    ball = scene.body("ball")
    m = 1000.0 * 4.0 / 3.0 * np.pi * 0.1 ** 3  # MuJoCo's default density
    assert ball.mass == pytest.approx(m, rel=SAME_FILE_TOL)
    np.testing.assert_allclose(ball.inertia_matrix, np.eye(3) * 0.4 * m * 0.01, rtol=SAME_FILE_TOL)
    j = scene.joint("ball")
    assert j.kind == "free"  # the COM at (1, 2, 3) + R_z(pi) (0.2, 0, 0)
    np.testing.assert_allclose(j.q0[:3], [0.8, 2.0, 3.0], atol=SAME_FILE_TOL)
    slab = scene.body("slab")  # half-lengths 0.1, 0.2, 0.3: edges 0.2, 0.4, 0.6
    np.testing.assert_allclose(slab.inertia_matrix, np.diag([0.16 + 0.36, 0.04 + 0.36, 0.04 + 0.16]) * 3 / 12,
                               rtol=SAME_FILE_TOL)


@pytest.mark.parametrize("body, words, reason", [
    ('<body name="b"><joint/><joint/><inertial mass="1" diaginertia="1 1 1"/></body>',
     ["<body name='b'>", "2 joints", "one joint"], "several joints"),
    ('<body name="b"><joint/><geom type="capsule" size="0.1 0.2"/></body>',
     ["<body name='b'>", "capsule", "give the body an <inertial>"], "geom inertia"),
    ('<body name="a"><inertial mass="1" diaginertia="1 1 1"/><body name="b"><freejoint/>'
     '<inertial mass="1" diaginertia="1 1 1"/></body></body>', ["is free", "'a'"], "inner floating joint"),
    ('<body name="b"><joint class="nope"/><inertial mass="1" diaginertia="1 1 1"/></body>',
     ["class='nope'", "define it in <default>"], "bad default"),
    ('<body name="b"><joint type="hinge" axis="0 0 0"/><inertial mass="1" diaginertia="1 1 1"/></body>',
     ["axis='0 0 0'"], "bad axis"),
    ('<body name="b"><joint/><inertial mass="1" diaginertia="1 1 5"/></body>',
     ["<body name='b'>", "triangle inequality"], "bad inertia"),
])
def test_errors_name_the_file_the_element_and_the_fix(tmp_path, body, words, reason):
    with pytest.raises(ModelError) as err:
        read_mjcf(_write(tmp_path, f"<mujoco><worldbody>{body}</worldbody></mujoco>", "bad.xml"))
    assert str(err.value).startswith("bad.xml: ")
    for w in words:
        assert w in str(err.value), (w, str(err.value))
    assert err.value.reason == reason


def _mujoco_model(urdf_path):
    """MuJoCo's own reading of a URDF (an ``MjModel``): geometry stripped first (meshes are not needed and their
    package:// paths do not resolve), static bodies kept apart (``fusestatic="false"``)."""
    mujoco = pytest.importorskip("mujoco")
    root = ET.parse(urdf_path).getroot()
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for e in link.findall(tag):
                link.remove(e)
    for e in root.findall("transmission") + root.findall("gazebo"):
        root.remove(e)
    ET.SubElement(root, "mujoco").append(ET.Element("compiler", discardvisual="true", fusestatic="false"))
    return mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))


def _mujoco_conversion(urdf_path, out):
    """MuJoCo's own reading of a URDF written back as MJCF (``mj_saveLastXML``)."""
    mujoco = pytest.importorskip("mujoco")
    mujoco.mj_saveLastXML(str(out), _mujoco_model(urdf_path))
    return str(out)


@robots
@pytest.mark.parametrize("robot", ["double_pendulum", "ur5", "panda", "solo12"])
def test_mujoco_s_compiled_reading_of_a_urdf_has_the_same_bodies(robot):
    """Masses, inertias (link axes) and COMs of every body against MuJoCo's compiled model, in doubles."""
    from dalembert.models import robot_path
    mujoco = pytest.importorskip("mujoco")
    path = robot_path(robot)
    model, scene = _mujoco_model(path), read_urdf(path).scene
    for b in scene.bodies:
        i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b.name)
        R = spatial.quat_to_matrix(model.body_iquat[i])
        inertia = R @ np.diag(model.body_inertia[i]) @ R.T
        assert abs(model.body_mass[i] - b.mass) <= MUJOCO_COMPILED_TOL * b.mass, b.name
        assert np.abs(inertia - b.inertia_matrix).max() <= MUJOCO_COMPILED_TOL * np.abs(inertia).max(), b.name
        j = scene.joint(b.name)  # a URDF joint frame is the child link's frame: child_point = -COM in the link
        np.testing.assert_allclose(-np.asarray(j.child_point), model.body_ipos[i], rtol=0, atol=MUJOCO_COMPILED_TOL)


@robots
@pytest.mark.parametrize("robot", ["double_pendulum", "ur5", "panda", "solo12"])
def test_mujoco_s_conversion_of_a_urdf_reads_as_the_same_scene(tmp_path, robot):
    from dalembert.models import robot_path
    path = robot_path(robot)
    urdf = read_urdf(path)
    mjcf = read_mjcf(_mujoco_conversion(path, tmp_path / f"{robot}.xml"))
    _same_scene(urdf.scene, mjcf.scene, MUJOCO_PRINT_TOL, rel=True)
    assert set(urdf.joint_names) == set(mjcf.joint_names)
