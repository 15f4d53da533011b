"""MJCF generation needs no MuJoCo, and the text says what the scene says.

The MJCF of every built-in case (and of the test scenes with a ball joint, a
weld, world loads and full inertia tensors), for both weld formulations, is
generated in a subprocess where ``import mujoco`` fails; each test then reads
the XML and checks it against the scene: gravity, step, integrator, the
disabled stages, masses, inertias, COM offsets, joints, load sites and
actuators, weld constraints.
"""

import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from dalembert.case import load_cases
from scenes import chain_case, free_body_world_loads_case

TESTS = os.path.dirname(os.path.abspath(__file__))
DT = 1e-3
WELDS = ("tree", "equality")
SCENES = {**{name: factory().scene for name, factory in load_cases().items()},
          "chain": chain_case().scene, "free_world_loads": free_body_world_loads_case().scene}
# Every stage the scenes never call for, disabled in every model: MuJoCo would otherwise add
# contacts, joint limits, friction loss, springs, dampers, control clamping, auto-reset.
ALWAYS_DISABLED = ("contact", "limit", "frictionloss", "clampctrl", "autoreset")
# What a model without spring-dampers also disables (the springs' tendons are the only passive forces).
PASSIVE_STAGES = ("spring", "damper")
# What a model without weld constraints also disables (nothing holds it then).
CONSTRAINT_STAGES = ("constraint", "equality")
INERTIA_REL_TOL = 1e-12  # a rotated inertia tensor keeps its principal moments to roundoff

GENERATE = r"""
import json, sys
sys.modules["mujoco"] = None  # MuJoCo unimportable: ``import mujoco`` raises ImportError
try:
    import mujoco
except ImportError:
    pass
else:
    raise SystemExit("mujoco was importable")
sys.path.insert(0, sys.argv[1])
from dalembert import Settings
from dalembert.adapters.mujoco.mjcf import mjcf
from dalembert.case import load_cases
from scenes import chain_case, free_body_world_loads_case

scenes = {name: factory().scene for name, factory in load_cases().items()}
scenes.update(chain=chain_case().scene, free_world_loads=free_body_world_loads_case().scene)
dt, welds = float(sys.argv[2]), sys.argv[3].split(",")
texts = {f"{name}|{w}": mjcf(scene, Settings("rk4", dt=dt, options={"welds": w}))
         for name, scene in scenes.items() for w in welds}
assert sys.modules["mujoco"] is None, "something imported MuJoCo"
print(json.dumps(texts))
"""


@pytest.fixture(scope="module")
def models():
    """``"case|welds"`` -> the parsed MJCF, generated without MuJoCo."""
    proc = subprocess.run([sys.executable, "-P", "-c", GENERATE, TESTS, repr(DT), ",".join(WELDS)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return {key: ET.fromstring(text) for key, text in json.loads(proc.stdout).items()}


def floats(element, attribute):
    return np.array([float(x) for x in element.get(attribute).split()])


def body_element(root, name):
    (element,) = [b for b in root.iter("body") if b.get("name") == name]
    return element


def joint_kind(scene, welds, body):
    kind = scene.joint(body).kind
    return "free" if kind == "weld" and welds == "equality" else kind


CASES = [(name, welds) for name in SCENES for welds in WELDS]


@pytest.mark.parametrize("name, welds", CASES)
def test_option_gravity_step_and_integrator_are_the_scenes(models, name, welds):
    scene, root = SCENES[name], models[f"{name}|{welds}"]
    (option,) = root.iter("option")
    assert root.get("model") == scene.name
    assert list(floats(option, "gravity")) == list(scene.gravity)
    assert float(option.get("timestep")) == DT and option.get("integrator") == "RK4"


@pytest.mark.parametrize("name, welds", CASES)
def test_every_stage_the_scene_does_not_call_for_is_disabled(models, name, welds):
    scene, root = SCENES[name], models[f"{name}|{welds}"]
    (flag,) = root.iter("flag")
    constrained = (welds == "equality" and any(j.kind == "weld" for j in scene.joints)) or bool(scene.loops)
    disabled = {k for k, v in flag.attrib.items() if v == "disable"}
    expected = set(ALWAYS_DISABLED) | (set() if constrained else set(CONSTRAINT_STAGES))
    expected |= set() if scene.springs else set(PASSIVE_STAGES)
    if scene.contacts:  # contact pairs: the contact stage and its constraint rows
        expected -= {"contact", "constraint"}
    if scene.loops:  # RK4 runs loop constraints at one step, below refsafe's two (mjcf.LOOP_SOLREF_STEPS)
        expected.add("refsafe")
    assert disabled == expected | ({"gravity"} if not any(scene.gravity) else set())
    (compiler,) = root.iter("compiler")
    # no mass or inertia bound, no realigned free bodies: the inertial is the scene's as given
    assert (compiler.get("boundmass"), compiler.get("boundinertia"), compiler.get("alignfree")) == ("0", "0", "false")


@pytest.mark.parametrize("name, welds", CASES)
def test_bodies_carry_the_scenes_mass_and_inertia_and_no_geoms(models, name, welds):
    scene, root = SCENES[name], models[f"{name}|{welds}"]
    # no geoms but the scene's collision shapes (contact scenes), massless and colliding with nothing by default
    geoms = list(root.iter("geom"))
    assert sorted(g.get("name") for g in geoms) == sorted([g.name for g in scene.geoms] + [p.name for p in scene.planes])
    assert all(g.get("contype") == g.get("conaffinity") == "0" for g in geoms)
    assert sorted(b.get("name") for b in root.iter("body")) == sorted(b.name for b in scene.bodies)
    for body in scene.bodies:
        (inertial,) = body_element(root, body.name).findall("inertial")
        assert float(inertial.get("mass")) == body.mass
        full = floats(inertial, "fullinertia")  # xx yy zz xy xz yz
        com = floats(inertial, "pos")
        j = scene.joint(body.name)
        if joint_kind(scene, welds, body.name) == "free":  # MuJoCo's frame is the body frame itself
            I_B = body.inertia_matrix
            assert np.array_equal(full, [I_B[0, 0], I_B[1, 1], I_B[2, 2], I_B[0, 1], I_B[0, 2], I_B[1, 2]])
            assert not com.any()
        else:  # MuJoCo's frame is the child joint frame: rotated inertia, COM at the joint's lever
            xx, yy, zz, xy, xz, yz = full
            I = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
            assert np.allclose(np.linalg.eigvalsh(I), np.linalg.eigvalsh(body.inertia_matrix),
                               rtol=INERTIA_REL_TOL, atol=0)
            assert np.isclose(np.linalg.norm(com), np.linalg.norm(j.child_point), rtol=1e-15, atol=0)


@pytest.mark.parametrize("name, welds", CASES)
def test_joints_are_the_scenes_without_damping_armature_or_limits(models, name, welds):
    scene, root = SCENES[name], models[f"{name}|{welds}"]
    for j in scene.joints:
        element = body_element(root, j.child)
        kind = joint_kind(scene, welds, j.child)
        free, joints = element.findall("freejoint"), element.findall("joint")
        assert (len(free), len(joints)) == {"free": (1, 0), "weld": (0, 0)}.get(kind, (0, 1))
        if kind == "free" and j.kind == "free":
            assert np.array_equal(floats(element, "pos"), j.q0[:3])
            assert np.array_equal(floats(element, "quat"), j.q0[3:])
        if joints:
            (joint,) = joints
            assert joint.get("type") == {"revolute": "hinge", "prismatic": "slide", "ball": "ball"}[kind]
            for attribute in ("damping", "armature", "stiffness", "frictionloss"):
                assert float(joint.get(attribute)) == 0.0, attribute
            assert joint.get("limited") == "false"
            if kind in ("revolute", "prismatic"):  # in MuJoCo's body frame E = Jc, whose attitude is Jp's at q = 0
                assert np.array_equal(floats(joint, "axis"), j.axis)
    welds_held = [j for j in scene.joints if j.kind == "weld" and welds == "equality"]
    constraints = list(root.iter("weld"))
    assert sorted((c.get("body1"), c.get("body2")) for c in constraints) == sorted(
        (j.parent, j.child) for j in welds_held)
    for c in constraints:
        assert float(c.get("solref").split()[0]) > 0.0 and len(floats(c, "relpose")) == 7


@pytest.mark.parametrize("name, welds", CASES)
def test_loads_are_site_actuators_with_the_scenes_vectors(models, name, welds):
    scene, root = SCENES[name], models[f"{name}|{welds}"]
    actuators = list(root.iter("general"))
    assert len(actuators) == len(scene.loads)
    for k, (ld, actuator) in enumerate(zip(scene.loads, actuators)):
        assert actuator.get("site") == f"load{k}"
        force, torque = np.split(floats(actuator, "gear"), 2)
        assert np.array_equal(force if ld.kind == "force" else torque, ld.vector)
        assert not (torque if ld.kind == "force" else force).any()
        assert actuator.get("refsite") == ("world_origin" if ld.frame == "world" else None)
        # the site sits on the loaded body at the load's point: its distance from the COM is the scene's
        (site,) = [s for s in body_element(root, ld.body).findall("site") if s.get("name") == f"load{k}"]
        com = floats(body_element(root, ld.body).find("inertial"), "pos")
        assert np.isclose(np.linalg.norm(floats(site, "pos") - com), np.linalg.norm(ld.point), rtol=1e-15, atol=1e-15)


@pytest.mark.parametrize("name", [n for n in SCENES if SCENES[n].loops])
def test_loops_are_equality_constraints_between_sites_at_the_loops_points(models, name):
    """A ball loop is one connect, a revolute two (the second AXIS_LEVER along the axis), between sites on the
    loop's bodies; at the scene's initial state each connect's two sites coincide, i.e. they sit at the loop's
    points (and along its axis) in the right bodies; the softness is the generated solref/solimp."""
    from dalembert import spatial
    from dalembert.adapters.mujoco.mjcf import AXIS_LEVER, LOOP_SOLIMP, engine_frames

    scene, root = SCENES[name], models[f"{name}|tree"]
    connects = list(root.iter("connect"))
    assert len(connects) == sum({"ball": 1, "revolute": 2}[lp.kind] for lp in scene.loops)
    sites = {}
    for body in root.iter("body"):
        for site in body.findall("site"):
            sites[site.get("name")] = (body.get("name"), floats(site, "pos"))
    for site in root.find("worldbody").findall("site"):
        sites[site.get("name")] = ("world", floats(site, "pos"))
    state = spatial.initial_body_states(scene)
    state["world"] = dict(R=np.eye(3), p=np.zeros(3))
    X_EB = {**engine_frames(scene), "world": (np.zeros(3), np.eye(3))}

    def world(body, p_E):  # a site's position in the world at the initial state
        p_EB, R_EB = X_EB[body]
        return state[body]["p"] + state[body]["R"] @ (R_EB.T @ (p_E - p_EB))

    for i, lp in enumerate(scene.loops):
        mine = [c for c in connects if c.get("name") in (lp.name, f"{lp.name}:axis")]
        for k, c in enumerate(mine):
            (a, pa), (b, pb) = sites[c.get("site1")], sites[c.get("site2")]
            assert (a, b) == (lp.body_a, lp.body_b)
            assert np.allclose(world(a, pa), world(b, pb), rtol=0, atol=1e-12)
            assert floats(c, "solimp").tolist() == list(LOOP_SOLIMP) and float(c.get("solref").split()[0]) == DT
        if lp.kind == "revolute":
            (a, p0), (_, p1) = sites[mine[0].get("site1")], sites[mine[1].get("site1")]
            assert np.isclose(np.linalg.norm(p1 - p0), AXIS_LEVER, rtol=1e-15)
