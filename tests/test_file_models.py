"""Engines reading the robot's file themselves (``--option model_file=PATH``; adapters/file_model.py and each
engine's ``from_file``): without the file's effects each reading moves as the scene does, with them the engine's
own effects show (and its audit says which), and a file that is not the scene's, or a request that cannot be
run, is refused naming the option and the fix."""

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from dalembert import Settings
from dalembert.adapters import file_model, get_adapter
from dalembert.models import read_mjcf, read_urdf

from installed import found
from test_models_urdf import ARM, _write

# the engines whose package is found (by its spec: not imported while pytest collects)
ENGINES = [e for e, module in (("mujoco", "mujoco"), ("pinocchio", "pinocchio"), ("drake", "pydrake")) if found(module)]
# Each engine's fixed-step method of order four or more (Drake has no fixed-step RK4: its RK5).
INTEGRATOR = {"mujoco": "rk4", "pinocchio": "rk4", "drake": "rk5"}
DT = 1e-3
TIMES = np.linspace(0.0, 1.0, 101)
# The same engine and integrator on the scene it built and on the file it read, effects off: the same motion
# up to the roundoff of the readers' mass properties (measured 9e-16 to 4.4e-15 rad over the 1-s swing below; the
# floating base's frame moves, 5e-15 to 5.1e-13 in m, m/s and rad/s, MuJoCo's the largest).
SAME_MOTION_TOL = 1e-11
# The file's shoulder damping (0.5 N m s/rad) on the 2-kg arm's 1-s swing (4.8 rad peak to peak): 1.3 rad apart
# from the scene's in MuJoCo (with its friction loss, 0.1 N m) and Drake (measured); near roundoff would mean
# the damping was not applied.
DAMPING_SHOWS = 1e-2
POSE = {"shoulder": 0.7}


# The test arm with its transmission typed as ROS writes it (Drake's parser refuses an untyped one).
TYPED_ARM = ARM.replace('<transmission name="t1">',
                        '<transmission name="t1"><type>transmission_interface/SimpleTransmission</type>')


@pytest.fixture()
def arm(tmp_path):
    """``(path, scene)``: the test arm (a continuous shoulder with damping and friction, a massless slider the
    scene drops) with its base fixed."""
    path = _write(tmp_path, TYPED_ARM)
    return path, read_urdf(path, positions=POSE).scene


def _run(engine, scene, **options):
    adapter = get_adapter(engine)
    settings = Settings(INTEGRATOR[engine], dt=DT, options=options)
    adapter.check(scene, TIMES, settings)
    assert adapter.unsupported(scene, settings) is None
    prepared = adapter.prepare(scene, TIMES, settings)
    outcome = adapter.run(prepared)
    return outcome.trajectory, adapter.audit(prepared, outcome)


def _angle(traj):
    return traj.joints["upper"].q[:, 0]


@pytest.mark.parametrize("engine", ENGINES)
def test_without_the_file_s_effects_the_engine_s_reading_moves_as_its_scene_does(engine, arm):
    path, scene = arm
    built, _ = _run(engine, scene)
    read, audit = _run(engine, scene, model_file=path, file_effects="off")
    assert np.abs(_angle(read) - _angle(built)).max() < SAME_MOTION_TOL
    assert np.ptp(_angle(read)) > 1.0  # it swings (from 0.7 rad, under gravity)
    for name, body in built.bodies.items():  # body terms through the scene's kinematics
        assert np.abs(read.bodies[name].position - body.position).max() < SAME_MOTION_TOL
    assert audit["file_effects"] == "off" and audit["locked"] == ["marker_slide"]  # the massless slider, fixed
    assert "arm.urdf" in audit["model_source"] and audit["gravity"] == scene.gravity
    assert not any(k.startswith("reaction_force") for k in read.extras)  # the scene's, not the engine's: left out


@pytest.mark.parametrize("engine", ENGINES)
def test_a_floating_base_freed_from_the_file_s_root_link_moves_as_the_scene_s(engine, tmp_path):
    """The engine frees the file's root link (its frame at the link's origin); the scene's base is the root's COM,
    the weight merged in: the state is moved between the two frames both ways (``base_initial``, ``base_series``)."""
    path = _write(tmp_path, TYPED_ARM)
    scene = read_urdf(path, base="free", gravity=(0.0, 0.0, 0.0), positions=POSE,
                      velocities={"base": (0.1, 0.0, 0.2, 0.5, 1.0, 2.0), "shoulder": 3.0}).scene
    built, _ = _run(engine, scene)
    read, audit = _run(engine, scene, model_file=path, file_effects="off")
    json.dumps(audit, sort_keys=True, default=str)  # as the store writes it (a free joint of no name broke it)
    for name, body in built.bodies.items():
        assert np.abs(read.bodies[name].position - body.position).max() < SAME_MOTION_TOL
        assert np.abs(read.bodies[name].velocity - body.velocity).max() < SAME_MOTION_TOL
        assert np.abs(read.bodies[name].angular_velocity - body.angular_velocity).max() < SAME_MOTION_TOL
    assert np.ptp(read.bodies["base"].position[:, 2]) > 0.1  # it flies (0.2 m/s up) and tumbles
    assert np.abs(_angle(read) - _angle(built)).max() < SAME_MOTION_TOL


@pytest.mark.parametrize("engine", ENGINES)
def test_with_the_file_s_effects_the_engine_s_own_reading_shows_and_its_audit_says_so(engine, arm):
    """MuJoCo and Drake apply the file's joint damping; Pinocchio reads it but its ``aba`` applies none."""
    path, scene = arm
    built, _ = _run(engine, scene)
    read, audit = _run(engine, scene, model_file=path)
    gap = np.abs(_angle(read) - _angle(built)).max()
    damping = audit["file_effects_read"]["damping"]
    assert "0.5" in damping and audit["file_effects"] == "on"
    if engine == "pinocchio":
        assert gap < SAME_MOTION_TOL and "not applied" in damping
    else:
        assert gap > DAMPING_SHOWS and "applied" in damping and "not applied" not in damping


@pytest.mark.parametrize("engine", ENGINES)
def test_a_file_that_is_not_the_scene_s_is_refused_naming_the_option(engine, arm, tmp_path):
    path, scene = arm
    heavier = _write(tmp_path, TYPED_ARM.replace('<mass value="1.5"/>', '<mass value="1.6"/>'), "heavier.urdf")
    with pytest.raises(ValueError, match=r"options.model_file: .* kg below link 'upper' from heavier.urdf.*give the "
                                         r"file the case's scene was read from"):
        _run(engine, scene, model_file=heavier)
    renamed = _write(tmp_path, TYPED_ARM.replace('"upper"', '"forearm"'), "renamed.urdf")
    with pytest.raises(ValueError, match=r"options.model_file: .* no joint moving link 'upper' from renamed.urdf"):
        _run(engine, scene, model_file=renamed)


@pytest.mark.parametrize("engine", ENGINES)
def test_requests_that_cannot_run_are_refused_before_anything_runs(engine, arm, tmp_path):
    path, scene = arm
    adapter = get_adapter(engine)
    settings = lambda **o: Settings(INTEGRATOR[engine], dt=DT, options=o)  # noqa: E731
    with pytest.raises(ValueError, match=r"options.model_file: no file .*missing.urdf.*--param model"):
        adapter.check(scene, TIMES, settings(model_file=str(tmp_path / "missing.urdf")))
    with pytest.raises(ValueError, match=r"options.model_file: .*robot.obj.* is not a .urdf or .xml file"):
        adapter.check(scene, TIMES, settings(model_file="robot.obj"))
    assert adapter.unsupported(scene, settings(file_effects="off")).startswith(
        "options.file_effects: off only with options.model_file — give model_file=PATH")
    adapter.check(scene, TIMES, settings(model_file=file_model.SCENE))  # the default, spelt out: the scene
    free = _write(tmp_path, MJCF_ARM.replace('<joint name="shoulder" type="hinge" axis="0 1 0" damping="0.5"/>',
                                             "<freejoint/>"), "free.xml")
    assert adapter.unsupported(read_mjcf(free).scene, settings(model_file=free)).startswith(
        "options.model_file: a floating base is mapped from a URDF's root link only")
    ball = _write(tmp_path, MJCF_ARM.replace('type="hinge" axis="0 1 0" range="-1 1"', 'type="ball"'), "ball.xml")
    assert "ball joints" in adapter.unsupported(read_mjcf(ball).scene, settings(model_file=ball))


def test_the_file_as_the_engines_read_it_has_no_geometry_and_the_scene_s_locked_joints_fixed(tmp_path):
    path = _write(tmp_path, ARM.replace("<link name=\"tool\"/>", "<link name=\"tool\"><visual><geometry><mesh "
                                        "filename=\"package://arm/tool.stl\"/></geometry></visual></link>")
                  .replace('<origin xyz="0.5 0 0"/>', '<origin xyz="0.5 0 0"/><mimic joint="shoulder"/>'))
    scene = read_urdf(path).scene
    joints = file_model.urdf_joints(path)
    assert [(j.name, j.kind, j.child) for j in joints][:2] == [("shoulder", "continuous", "upper"),
                                                               ("tool_mount", "fixed", "tool")]
    assert file_model.locked_joints(scene, joints) == ["marker_slide"]
    root = ET.fromstring(file_model.bare_urdf(path, ["marker_slide"]))
    assert not list(root.iter("visual")) and not list(root.iter("collision"))
    assert not list(root.iter("mimic"))  # on a fixed joint it moves nothing (and Drake's parser refuses it)
    types = {j.get("name"): j.get("type") for j in root.findall("joint")}
    assert types == {"shoulder": "continuous", "tool_mount": "fixed", "weight_mount": "fixed", "marker_slide": "fixed"}
    masses = file_model.scene_subtree_masses(scene)
    assert masses["upper"] == pytest.approx(2.0)  # the arm, its weight merged in (1.5 + 0.5 kg)


def _record(key, engine, integrator, dt, error, status="ok", **options):
    from dalembert.record import Cost, RunRecord

    audit = {"file_effects_read": {"damping": f"read by {engine}"}} if options.get("model_file", "scene") != "scene" \
        else {}
    return RunRecord(key, "robot_arm", "v1", engine, Settings(integrator, dt, options=options), status=status,
                     t_final=2.0, errors={"joint": (error, error)}, audit=audit, cost=Cost(wall_s_median=0.1))


def test_the_report_pairs_each_reading_of_a_file_with_its_engine_s_scene_built_run():
    from dalembert.reports.file_models import file_readings

    records = [_record("a", "mujoco", "rk4", 1e-3, 2e-4, model_file="scene"),
               _record("b", "mujoco", "rk4", 1e-3, 2e-4, model_file="/x/panda.urdf", file_effects="off"),
               _record("c", "mujoco", "rk4", 1e-3, 13.0, model_file="/x/panda.urdf", file_effects="on"),
               _record("d", "mujoco", "rk4", 1e-3, 9.9, status="unsupported", model_file="scene", file_effects="off"),
               _record("e", "mujoco", "rk4", 1e-2, 0.5),  # another step: its own pair, with no file read
               _record("f", "pinocchio", "rk4", 1e-3, 3e-4),  # the scene's default, left out
               _record("g", "pinocchio", "rk4", 1e-3, 3e-4, model_file="/x/panda.urdf")]
    found = file_readings(records)
    assert [(f.engine, f.label, f.file) for f in found] == [("mujoco", "rk4 dt=0.001", "panda.urdf"),
                                                            ("pinocchio", "rk4 dt=0.001", "panda.urdf")]
    mj, pin = found
    assert (mj.scene_error, mj.bare_error, mj.file_error) == (2e-4, 2e-4, 13.0)
    assert mj.effects == {"damping": "read by mujoco"} and mj.scene_cost == pytest.approx(0.05)
    assert pin.scene_error == 3e-4 and np.isnan(pin.bare_error) and pin.file_error == 3e-4
    assert file_readings(records[:1] + records[4:6]) == []  # no file read: no section


MJCF_ARM = """\
<mujoco model="arm2">
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" damping="0.5"/>
      <inertial pos="0.25 0 0" mass="1.5" diaginertia="0.001 0.03 0.031"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.02"/>
      <body name="fore" pos="0.5 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0" range="-1 1"/>
        <inertial pos="0.2 0 0" mass="1" diaginertia="0.001 0.02 0.021"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.skipif("mujoco" not in ENGINES, reason="MuJoCo not installed")
def test_mujoco_reads_an_mjcf_file_itself_and_the_other_engines_say_they_read_urdf_only(tmp_path):
    path = _write(tmp_path, MJCF_ARM, "arm2.xml")
    scene = read_mjcf(path, positions={"shoulder": 0.7, "elbow": 0.3}).scene
    built, _ = _run("mujoco", scene)
    bare, _ = _run("mujoco", scene, model_file=path, file_effects="off")
    read, audit = _run("mujoco", scene, model_file=path)
    assert np.abs(bare.joints["fore"].q - built.joints["fore"].q).max() < SAME_MOTION_TOL
    assert np.abs(read.joints["fore"].q - built.joints["fore"].q).max() > DAMPING_SHOWS  # damping, the elbow's range
    assert audit["model_source"] == "arm2.xml read by MuJoCo's MJCF compiler"
    assert audit["file_effects_read"]["limits"] == "1 of 2 joints, enforced by the constraint solver"
    for engine in set(ENGINES) - {"mujoco"}:
        with pytest.raises(ValueError, match=r"options.model_file: arm2.xml — .* reads URDF files here"):
            _run(engine, scene, model_file=path)


@pytest.mark.parametrize("engine", [e for e in ENGINES if e != "drake"])  # (Drake has no repro at all)
def test_a_file_read_run_is_not_written_as_a_repro_of_the_scene_s_model(engine, arm):
    path, scene = arm
    settings = Settings(INTEGRATOR[engine], dt=DT, options={"model_file": path})
    with pytest.raises(ValueError, match="options.model_file: dalembert repro writes runs of the model an engine"):
        get_adapter(engine).repro(scene, TIMES, settings, "joint")


def test_the_report_section_names_the_largest_change_or_says_there_was_none():
    from types import SimpleNamespace

    from dalembert.reports.sections.file_models import file_models

    records = [_record("a", "mujoco", "rk4", 1e-3, 2e-4, model_file="scene"),
               _record("c", "mujoco", "rk4", 1e-3, 13.0, model_file="/x/panda.urdf"),
               _record("f", "pinocchio", "rk4", 1e-3, 3e-4),
               _record("g", "pinocchio", "rk4", 1e-3, 3e-4, model_file="/x/panda.urdf")]
    md = "\n".join(x for x in file_models(SimpleNamespace(records=records)).md if isinstance(x, str))
    assert ("Largest change: mujoco on robot_arm (panda.urdf, rk4 dt=0.001) ends 13 rad from the truth with the "
            "file's effects on, against 0.0002 rad built from the scene (joint).") in md
    assert "read by pinocchio" in md  # the effects each engine's audit says it read
    md = "\n".join(x for x in file_models(SimpleNamespace(records=records[2:])).md if isinstance(x, str))
    assert "No engine's reading of the file, with its effects on, changed the error" in md
    assert not file_models(SimpleNamespace(records=records[2:3]))  # no file read: no section


def test_a_run_with_the_file_s_effects_is_judged_for_stability_but_not_against_the_scene_s_tolerances(arm):
    """The case's tolerances hold for the scene: a run that read the file with its damping is a finding about the
    engine (``Adapter.beyond_scene``), its ``within_tolerance`` not established; with the effects off it is the
    scene's motion and is judged."""
    from dalembert.adapters import get_adapter
    from dalembert.judge import judge
    from dalembert.settings import Settings
    from dalembert.tolerance import Tolerance

    path, scene = arm
    adapter = get_adapter("mujoco")
    on = adapter.beyond_scene(scene, Settings("rk4", dt=1e-3, options={"model_file": path}))
    off = adapter.beyond_scene(scene, Settings("rk4", dt=1e-3, options={"model_file": path, "file_effects": "off"}))
    assert "file_effects=on" in on and off is None
    assert adapter.beyond_scene(scene, Settings("rk4", dt=1e-3)) is None
    tolerances = {"joint": Tolerance(1e-6, "test bound")}
    beyond = judge("ok", "", {"joint": 9.0}, {}, tolerances, beyond_scene=on)
    assert beyond.within_tolerance is None and "not judged against the tolerances" in beyond.reason
    assert beyond.verdict == "stable"
    assert judge("ok", "", {"joint": 9.0}, {}, tolerances, beyond_scene=off).within_tolerance is False
