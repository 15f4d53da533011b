"""``dalembert check-engine`` finds real mistakes: the guide's example engine (docs/example_engine, tinyrigid)
passes it and runs in ``dalembert run`` once pip-installed from a temporary directory; the same adapter with each
of issue 35's faults injected fails with a message that names the fault; every problem is listed, not the first.

The faults are subclasses of the example adapter registered for one test each (the example imported from
docs/example_engine on sys.path: installing it once per fault would cost a pip run each)."""

import json
import os
import re
import shutil
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from dalembert import spatial
from dalembert.adapters import IntegratorSpec
from dalembert.adapters import registry as adapter_registry
from dalembert.engine_check import PROBES, Problem, check_engine
from dalembert.trajectory import BodyStates, Trajectory

from cli_script import PRELUDE

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLE = os.path.join(ROOT, "docs", "example_engine")
sys.path.insert(0, EXAMPLE)  # tinyrigid, as the guide writes it (a fresh interpreter gets sys.path too)

from tinyrigid.adapter import TinyRigidAdapter  # noqa: E402


class GravityNotSet(TinyRigidAdapter):
    def build(self, scene):
        return replace(super().build(scene), gravity=np.zeros(3))


class GravityHardCoded(TinyRigidAdapter):
    def build(self, scene):
        return replace(super().build(scene), gravity=np.array([0.0, 0.0, -9.81]))


class StateNotReset(TinyRigidAdapter):
    """The simulation lives with the prepared model: a second run goes on from where the first stopped."""

    def start(self, prepared):
        sims = self.__dict__.setdefault("_sims", {})
        return sims.setdefault(id(prepared), (prepared, super().start(prepared)))[1]


class InertiaDropped(TinyRigidAdapter):
    """The engine's inertia is a sphere's of the same trace (as an engine that computes it from a shape)."""

    def build(self, scene):
        model = super().build(scene)
        return replace(model, inertia=np.array([np.eye(3) * np.trace(i) / 3.0 for i in model.inertia]))


class JointMotor(TinyRigidAdapter):
    """Each hinge held at its start angle by a motor the engine adds by default."""

    def build(self, scene):
        return replace(super().build(scene), hinge_stiffness=50.0, hinge_damping=5.0)


class Damped(TinyRigidAdapter):
    """PyBullet's default velocity damping, 0.04 1/s, left on."""

    def build(self, scene):
        return replace(super().build(scene), linear_damping=0.04, angular_damping=0.04)


class QuaternionXYZW(TinyRigidAdapter):
    """The engine's quaternions passed on as it orders them, scalar last."""

    def read_back(self, prepared, states):
        traj = super().read_back(prepared, states)
        return _with(traj, lambda b: BodyStates(b.position, spatial.wxyz_to_xyzw(b.quaternion), b.velocity,
                                                b.angular_velocity))


class AngularVelocityInBody(TinyRigidAdapter):
    """Angular velocity read back in body axes."""

    def read_back(self, prepared, states):
        traj = super().read_back(prepared, states)
        return _with(traj, lambda b: BodyStates(b.position, b.quaternion, b.velocity,
                                                spatial.world_to_body(b.quaternion, b.angular_velocity)))


class ReactionFlipped(TinyRigidAdapter):
    """The reaction on the parent passed on as the child's."""

    def read_back(self, prepared, states):
        traj = super().read_back(prepared, states)
        return Trajectory(traj.t, traj.bodies, traj.joints, {k: -v for k, v in traj.extras.items()})


class OrderOverDeclared(TinyRigidAdapter):
    integrators = {"euler": IntegratorSpec(True, (), "semi-implicit Euler, declared second order", order=2)}


class SupportsNothing(TinyRigidAdapter):
    effects = frozenset()


class ContactEverywhere(TinyRigidAdapter):
    """Every body a collision sphere, as engines that make collision shapes by default."""

    def build(self, scene):
        return replace(super().build(scene), collision_radius=0.05)


class OwnClock(TinyRigidAdapter):
    """Samples reported at the engine's accumulated time (n dt, off the times asked by roundoff)."""

    def read_back(self, prepared, states):
        traj = super().read_back(prepared, states)
        return Trajectory(traj.t + 1e-12, traj.bodies, traj.joints, traj.extras)


class GravityAndQuaternion(GravityNotSet, QuaternionXYZW):
    pass


class QuaternionAndReaction(QuaternionXYZW, ReactionFlipped):
    pass


class InertiaAndContact(InertiaDropped, ContactEverywhere):
    pass


def _with(traj, change):
    return Trajectory(traj.t, {n: change(b) for n, b in traj.bodies.items()}, traj.joints, traj.extras)


PRINTS_ON_IMPORT = """import numpy
print("tinyrigid: using numpy", numpy.__version__)
from tinyrigid.adapter import TinyRigidAdapter


class Loud(TinyRigidAdapter):
    pass
"""

# fault -> (adapter class, or None: the module above; what a problem's message must say)
FAULTS = {
    "gravity not set": (GravityNotSet, "gravity is not the scene's"),
    "gravity wrong": (GravityHardCoded, "gravity is not the scene's"),
    "state not reset between runs": (StateNotReset, "state not reset between runs"),
    "inertia silently dropped": (InertiaDropped, "inertia is not the scene's"),
    "a default joint motor": (JointMotor, "motor"),
    "damping added": (Damped, "velocity damping the engine adds by default"),
    "print on import": (None, "printed during import"),
    "quaternion order x,y,z,w": (QuaternionXYZW, "quaternion order x, y, z, w"),
    "angular velocity in the wrong frame": (AngularVelocityInBody, "angular velocity in the wrong frame"),
    "reaction sign flipped": (ReactionFlipped, "reaction sign flipped"),
    "integrator order lower than declared": (OrderOverDeclared, "integrator order lower than declared"),
    "supports nothing": (SupportsNothing, "supports none of the"),
    "contact where none asked": (ContactEverywhere, "contact where none was asked"),
}


@pytest.fixture
def register(monkeypatch):
    """Register an adapter class under a name for one test (taken out again after it)."""
    def add(name, cls):
        monkeypatch.setitem(adapter_registry._REGISTRY._items, name, cls)
        return name
    return add


def test_the_example_engine_passes(register):
    found = check_engine(register("tinyrigid", TinyRigidAdapter))
    assert found.problems == (), "\n".join(map(str, found.problems))
    assert set(found.probes) == {f"{n} [euler]" if e.per_integrator else n for n, e in PROBES.items()}
    assert any("observed order" in n and "declared 1" in n for n in found.notes), found.notes


@pytest.mark.parametrize("fault", FAULTS)
def test_each_fault_is_found_and_named(fault, register, tmp_path, monkeypatch):
    cls, says = FAULTS[fault]
    if cls is None:
        (tmp_path / "loud_tinyrigid.py").write_text(PRINTS_ON_IMPORT)
        monkeypatch.syspath_prepend(str(tmp_path))
        from loud_tinyrigid import Loud  # (prints here, in pytest's capture)

        cls = Loud
    found = check_engine(register("faulty", cls))
    assert any(says in str(p) for p in found.problems), f"{fault}: {says!r} not in\n" + "\n".join(map(str, found.problems))
    for p in found.problems:
        assert p.probe and p.saw and p.look_at


@pytest.mark.parametrize("engine", ["reference", "mujoco", "pinocchio", "exudyn", "drake"])
def test_the_built_in_engines_pass(engine):
    """Every built-in engine passes with its first integrator (MJX too, in 20 s of compiling: left out here)."""
    from dalembert.adapters import get_adapter

    try:
        get_adapter(engine).version()
    except ImportError as e:
        pytest.skip(f"{engine} is not installed: {e}")
    found = check_engine(engine)
    assert found.problems == (), "\n".join(map(str, found.problems))


def test_every_problem_is_listed_not_the_first(register):
    """Two faults at once: both found, each by its own probe."""
    found = check_engine(register("both", GravityAndQuaternion))
    assert {"free_fall [euler]", "spin_frames [euler]"} <= {p.probe for p in found.problems}


def test_a_built_in_case_run_off_its_times_is_found(register):
    found = check_engine(register("own_clock", OwnClock))
    assert [p.probe for p in found.problems if "not at exactly the times" in p.saw] == ["supported_cases"]


def test_output_from_c_and_python_is_captured():
    """Both file descriptors (where C code writes) and sys.stdout/stderr (Python's print, warnings)."""
    from dalembert.engine_check import capture

    with capture.output() as printed:
        os.write(1, b"from C\n")
        print("from Python", file=sys.stderr)
    assert "from C" in printed.text and "from Python" in printed.text


COUNTED_ADAPTER = """
with open({log!r}, "a") as log:
    log.write("imported\\n")
print({says!r})


class Counted:
    def load(self):
        pass
"""


def test_the_import_probe_asks_a_fresh_interpreter_once_per_adapter_until_its_file_changes(tmp_path, monkeypatch):
    """``capture.import_output`` starts one interpreter per adapter, ``sys.path`` and module file: asked again, the
    same answer without a second start; the module rewritten (a new modification time), asked anew."""
    from dalembert.engine_check.capture import import_output

    log, module = tmp_path / "imports.log", tmp_path / "counted_adapter.py"
    module.write_text(COUNTED_ADAPTER.format(log=str(log), says="first"))
    monkeypatch.syspath_prepend(str(tmp_path))
    assert import_output("counted_adapter:Counted") == import_output("counted_adapter:Counted") == ("first", "")
    assert log.read_text().splitlines() == ["imported"]
    module.write_text(COUNTED_ADAPTER.format(log=str(log), says="second"))
    stat = module.stat()
    os.utime(module, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))  # a later time, on any file system's clock
    assert import_output("counted_adapter:Counted") == ("second", "")
    assert log.read_text().splitlines() == ["imported", "imported"]


def test_the_cli_prints_every_problem_and_exits_1(register, capsys):
    from dalembert.harness.cli import main

    register("both", QuaternionAndReaction)
    assert main(["check-engine", "both"]) == 1
    out = capsys.readouterr().out
    assert "quaternion order x, y, z, w" in out and "reaction sign flipped" in out and "look at:" in out
    assert main(["check-engine", "both", "--integrator", "rk4"]) == 2  # refused, naming the flag
    assert "--integrator: both has no 'rk4'" in capsys.readouterr().err


def test_testing_check_engine_raises_listing_every_problem(register):
    from dalembert.testing import EngineCheckError
    from dalembert.testing import check_engine as check_in_pytest

    register("tinyrigid", TinyRigidAdapter)
    assert check_in_pytest("tinyrigid").ok
    register("both", InertiaAndContact)
    with pytest.raises(EngineCheckError, match="(?s)contact where none was asked.*inertia is not the scene's"):
        check_in_pytest("both")


def test_a_problem_reads_as_probe_saw_look_at():
    assert str(Problem("free_fall", "saw this", "look there")) == "free_fall: saw this — look at: look there"


def test_the_guide_quotes_the_example_as_it_is():
    """Every code block docs/engines.md marks as an excerpt of a file is in that file, verbatim."""
    guide = open(os.path.join(ROOT, "docs", "engines.md")).read()
    excerpts = re.findall(r"<!-- excerpt: (\S+) -->\n```python\n(.*?)```", guide, re.S)
    assert len(excerpts) >= 5
    for path, code in excerpts:
        assert code in open(os.path.join(ROOT, path)).read(), f"docs/engines.md quotes {path} as it is not:\n{code}"


# The user's three commands, in one interpreter that sees the pip-installed example only through PYTHONPATH (what is
# tested is that its entry point is found from outside; one interpreter start, not one per command): what each
# said, as JSON on stdout's last line.
COMMANDS = PRELUDE + """
said = {"engines": command("engines"), "check-engine": command("check-engine", "tinyrigid")}
said["run"] = command("run", "--case", "pendulum", "--case", "free_top", "--engine", "tinyrigid", "--param",
                      "t_final=0.5", "--dt", "1e-2", "--jobs", "1", "--quick", "--out", sys.argv[1])
print(json.dumps(said))
"""


def test_the_example_installed_from_a_temporary_directory_passes_and_runs(tmp_path):
    """pip-installed (its entry point in ``dalembert.adapters``) from a copy in a temporary directory: listed by
    ``dalembert engines``, no problem in ``dalembert check-engine``, its runs stored by ``dalembert run``."""
    source, site = tmp_path / "example", tmp_path / "site"
    shutil.copytree(EXAMPLE, source, ignore=shutil.ignore_patterns("__pycache__", "build", "*.egg-info"))
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
                    "--no-index", "--target", str(site), str(source)], check=True, capture_output=True)
    env = dict(os.environ, PYTHONPATH=str(site))
    done = subprocess.run([sys.executable, "-c", COMMANDS, str(tmp_path / "runs")], capture_output=True, text=True,
                          env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    said = json.loads(done.stdout.splitlines()[-1])
    listed, checked, ran = said["engines"], said["check-engine"], said["run"]
    assert listed["status"] == 0 and "tinyrigid  0.1.0" in listed["stdout"], listed["stderr"]
    assert checked["status"] == 0 and "no problems" in checked["stdout"], checked["stdout"] + checked["stderr"]
    assert ran["status"] == 0 and "2 runs stored" in ran["stderr"] and "2 ok" in ran["stderr"], ran["stderr"]
