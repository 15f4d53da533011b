"""Engine environments (``dalembert.environments``): the engine spec with a version, the refusals before
anything runs, and the pool's workers started from an environment's interpreter.

No test here reaches the network unasked: an environment is faked by a directory whose ``bin/python`` runs this
interpreter (noting its pid, so that a run's record shows which interpreter ran it) and whose
``environment.json`` names the engine version installed here. A real environment (``dalembert env create``)
is made only by ``test_a_real_environment_runs_its_engine_version``, with ``DALEMBERT_NETWORK_TESTS=1`` and the
package index reachable.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from importlib import metadata

import pytest

from dalembert.environments import DISTRIBUTIONS, INFO, environment, environments, is_versioned, parse_engine
from dalembert.harness.cli import main
from dalembert.store import Store

mujoco = pytest.importorskip("mujoco")


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    """A cache of this test's own: no environment made elsewhere is seen, none made here stays."""
    monkeypatch.setenv("DALEMBERT_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def fake(name, version, tmp_path, numpy=None):
    """Make the environment of ``name`` as this interpreter (``version``: what its ``environment.json`` says is
    installed; ``numpy``: the numpy version its site-packages say they hold, default this process's); returns the
    file its interpreter appends each worker's pid to.

    Its own dalembert is a stale one (as an environment's editable install of a checkout since deleted), ahead
    of this one on its path, which raises on import: its workers must import the starting process's code."""
    env = environment(name)
    pids = tmp_path / f"pids-{env.spec.directory}"
    stale = tmp_path / "stale"
    os.makedirs(stale / "dalembert", exist_ok=True)
    (stale / "dalembert" / "__init__.py").write_text("raise ImportError('a stale dalembert was imported')\n")
    os.makedirs(os.path.join(env.path, "bin"))
    info = os.path.join(env.path, "lib", f"python{sys.version_info[0]}.{sys.version_info[1]}", "site-packages",
                        f"numpy-{numpy or metadata.version('numpy')}.dist-info")
    os.makedirs(info)
    with open(os.path.join(info, "METADATA"), "w") as f:
        f.write(f"Metadata-Version: 2.1\nName: numpy\nVersion: {numpy or metadata.version('numpy')}\n")
    with open(env.python, "w") as f:
        f.write(f"#!/bin/sh\necho $$ >> {pids}\nPYTHONPATH={stale} exec {sys.executable} \"$@\"\n")
    os.chmod(env.python, 0o755)
    with open(os.path.join(env.path, INFO), "w") as f:
        json.dump({"engine": env.spec.name, "requirement": env.spec.requirement, "engine_version": version,
                   "python": sys.version.split()[0], "installer": "fake", "checkout": "", "created": "now"}, f)
    return pids


# ---------------------------------------------------------------- the spec, read
def test_an_engine_spec_is_a_requirement_written_one_way():
    assert parse_engine("mujoco==3.6.0").name == "mujoco==3.6.0"
    assert parse_engine("mujoco == 3.6.0").name == "mujoco==3.6.0"  # one store key whatever the spacing
    spec = parse_engine("pinocchio>=2.6, <3")
    assert (spec.name, spec.distribution, spec.requirement) == ("pinocchio<3,>=2.6", "pin", "pin<3,>=2.6")
    assert environment("mujoco==3.6.0").path != environment("mujoco==3.6.1").path
    assert is_versioned("mujoco==3.6.0") and not is_versioned("mujoco") and not is_versioned("mujoco-mjx")


@pytest.mark.parametrize("text,said", [
    ("mujoco=3.6", "not a requirement"),
    ("mujco==3.6.0", "did you mean 'mujoco'"),
    ("reference==0.1", "distribution of its own"),
    ("mujoco[render]==3.6.0", "extras, URLs and markers"),
    ("mujoco==3.6.0; python_version>'3'", "extras, URLs and markers"),
])
def test_a_spec_that_is_not_an_engine_at_a_version_is_refused_naming_the_fix(text, said):
    with pytest.raises(ValueError, match="--engine") as err:
        parse_engine(text)
    assert said in str(err.value)


def test_each_engine_names_its_installed_distribution():
    """The distribution ``env create`` installs is the one whose metadata this environment's engine has."""
    import importlib

    modules = {"mujoco": "mujoco", "pinocchio": "pinocchio", "exudyn": "exudyn", "drake": "pydrake",
               "mjx": "mujoco.mjx", "pybullet": "pybullet", "dart": "dartpy", "newton": "newton"}
    checked = 0
    for engine, dist in DISTRIBUTIONS.items():
        try:
            importlib.import_module(modules[engine])
        except Exception:  # not installed here
            continue
        assert metadata.version(dist), engine
        checked += 1
    assert checked >= 1


# ---------------------------------------------------------------- refused before anything runs
RUN = ["run", "--case", "free_top_intermediate", "--integrator", "rk4", "--dt", "5e-3", "--param", "t_final=0.5",
       "--quick", "--jobs", "1"]


def test_run_refuses_a_missing_environment_naming_the_command_that_makes_it(tmp_path, capsys):
    assert main([*RUN, "--engine", "mujoco==3.6.0", "--out", str(tmp_path / "r")]) == 2
    assert "dalembert env create mujoco==3.6.0" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_a_version_outside_the_adapters_is_refused_with_its_reason(tmp_path, capsys, monkeypatch):
    from dalembert.adapters.mujoco import MujocoAdapter

    monkeypatch.setattr(MujocoAdapter, "supported_versions", ">=3.2")
    monkeypatch.setattr(MujocoAdapter, "unsupported_versions_why", "an older API")
    fake("mujoco==2.3.7", "2.3.7", tmp_path)
    assert main([*RUN, "--engine", "mujoco==2.3.7", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "mujoco 2.3.7 is outside the versions its adapter supports, >=3.2 (an older API)" in err, err
    assert not (tmp_path / "r").exists()


def test_env_list_and_remove(tmp_path, capsys):
    assert main(["env", "list"]) == 0
    assert "no engine environments" in capsys.readouterr().out
    fake("mujoco==3.6.0", "3.6.0", tmp_path)
    assert main(["env", "list"]) == 0
    assert "mujoco==3.6.0" in capsys.readouterr().out
    assert main(["env", "create", "mujoco == 3.6.0"]) == 2  # made already: never reinstalled behind the user
    assert "already made" in capsys.readouterr().err
    assert main(["env", "remove", "mujoco==3.5.0"]) == 2
    assert "made: mujoco==3.6.0" in capsys.readouterr().err
    assert main(["env", "remove", "mujoco==3.6.0"]) == 0
    assert environments() == []


def test_an_environment_of_an_engine_this_dalembert_cannot_version_is_listed_and_removed(tmp_path, capsys):
    """An environment another dalembert made (an engine this one has no distribution for at a version, e.g. a
    newer release's) neither breaks ``env list`` nor is beyond ``env remove``: listed, saying why this one cannot
    run it, and removed by the name it is listed under."""
    fake("mujoco==3.6.0", "3.6.0", tmp_path)
    other = os.path.join(os.path.dirname(environment("mujoco==3.6.0").path), "warpish_1.0-0000")
    os.makedirs(other)
    with open(os.path.join(other, INFO), "w") as f:
        json.dump({"engine": "warpish==1.0", "requirement": "warpish==1.0", "engine_version": "1.0",
                   "python": sys.version.split()[0], "installer": "pip", "created": "now"}, f)
    assert [e[0] for e in environments()] == ["mujoco==3.6.0", "warpish==1.0"]
    assert main(["env", "list"]) == 0
    out = capsys.readouterr().out
    assert "warpish==1.0" in out and "not runnable by this dalembert: 'warpish' is no engine" in out, out
    assert "mujoco==3.6.0            3.6.0      python" in out
    assert main(["env", "remove", "warpish==1.0"]) == 0
    assert not os.path.exists(other) and [e[0] for e in environments()] == ["mujoco==3.6.0"]
    assert main(["env", "remove", "warpish==2.0"]) == 2  # one not made: the engine's error, naming the fix
    assert "'warpish' is no engine" in capsys.readouterr().err


def test_a_stale_environment_is_refused_and_listed_naming_the_command_that_remakes_it(tmp_path, capsys):
    """An environment whose numpy differs from this process's (made before this one's numpy was upgraded) cannot
    serve its workers' arrays: ``run`` refuses it before anything runs, ``env list`` marks it, both naming
    ``env create --force``; one at this numpy is not stale."""
    fake("mujoco==3.6.0", "3.6.0", tmp_path, numpy="1.26.4")
    fake("mujoco==3.7.0", "3.7.0", tmp_path)
    assert environment("mujoco==3.6.0").stale() == [f"numpy 1.26.4 there, {metadata.version('numpy')} here"]
    assert environment("mujoco==3.7.0").stale() == []
    assert main([*RUN, "--engine", "mujoco==3.6.0", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "its environment is stale (numpy 1.26.4 there" in err and "env create --force mujoco==3.6.0" in err, err
    assert not (tmp_path / "r").exists()
    assert main(["env", "list"]) == 0
    out = capsys.readouterr().out
    assert "stale: numpy 1.26.4 there" in out and "env create --force mujoco==3.6.0" in out
    assert "--force mujoco==3.7.0" not in out


def test_create_force_replaces_an_environment_only_once_the_new_one_is_made(tmp_path, monkeypatch):
    """``env create --force`` makes a made environment again (the installer faked: no network), the old one kept
    until the new one is whole, and kept when the install fails."""
    from dalembert import environments

    fake("mujoco==3.6.0", "3.6.0", tmp_path, numpy="1.26.4")
    old = environment("mujoco==3.6.0")
    fail = {"install": False}

    def call(command, what, log):  # venv: a directory; pip: nothing, or a failure; the version: 3.6.0
        if "venv" in command:
            os.makedirs(os.path.join(command[-1], "bin"))
        elif "install" in command and fail["install"]:
            assert os.path.isfile(os.path.join(old.path, INFO))  # the old one is there while the new one is made
            raise RuntimeError("env create: installing failed")
        return "3.6.0\n"

    monkeypatch.setattr(environments, "_call", call)
    with pytest.raises(ValueError, match="already made"):
        environments.create("mujoco==3.6.0", tool="pip")
    fail["install"] = True
    with pytest.raises(RuntimeError):
        environments.create("mujoco==3.6.0", tool="pip", force=True)
    assert old.info()["installer"] == "fake" and old.stale()  # the old one, untouched
    fail["install"] = False
    environments.create("mujoco==3.6.0", tool="pip", force=True)
    assert old.info()["installer"] == "pip" and not os.path.exists(old.path + ".partial")


def test_env_list_is_sorted_by_engine_then_version(tmp_path, capsys):
    for version in ("3.10.0", "3.9.0", "3.2.7"):
        fake(f"mujoco=={version}", version, tmp_path)
    fake("exudyn==1.13.6", "1.13.6", tmp_path)
    assert [name for name, _, _ in environments()] == ["exudyn==1.13.6", "mujoco==3.2.7", "mujoco==3.9.0",
                                                      "mujoco==3.10.0"]
    assert main(["env", "list"]) == 0
    out = capsys.readouterr().out
    assert out.index("mujoco==3.9.0") < out.index("mujoco==3.10.0")


# ---------------------------------------------------------------- workers in their environment
def _pids(path):
    return {int(p) for p in open(path).read().split()} if os.path.exists(path) else set()


def test_a_versioned_engines_runs_go_to_its_environments_interpreter_and_resume(tmp_path):
    """The runs of ``mujoco==V`` run in workers of the environment's interpreter, those of ``mujoco`` in this
    one's, in one store under two engine names; a run left out is run by ``--resume`` in the environment."""
    version = mujoco.__version__
    name = f"mujoco=={version}"
    pids = fake(name, version, tmp_path)
    out = tmp_path / "r"
    argv = [*RUN, "--integrator", "implicitfast", "--engine", name, "--engine", "mujoco", "--out", str(out)]
    assert main(argv) == 0
    store = Store(out)
    records = store.records()
    assert sorted(r.engine for r in records) == sorted([name] * 2 + ["mujoco"] * 2)
    assert {r.engine_version for r in records} == {version}
    # each run names the libraries loaded where it ran: the engine's, numpy's; not dalembert's nor the stdlib's
    for r in records:
        libraries = r.provenance["libraries"]
        assert libraries["mujoco"] == version and libraries["numpy"] == metadata.version("numpy")
        assert "dalembert" not in libraries and "json" not in libraries
    inside = {r.provenance["pid"] for r in records if r.engine == name}
    outside = {r.provenance["pid"] for r in records if r.engine == "mujoco"}
    assert inside and inside <= _pids(pids) and not outside & _pids(pids)
    # the two versions' errors are the same engine's here: the environment changes where, not what, runs
    by = {(r.engine, r.settings.integrator): r.errors for r in records}
    assert by[(name, "rk4")] == by[("mujoco", "rk4")]

    dropped = next(r for r in records if r.engine == name)
    os.remove(os.path.join(out, "rows", dropped.key + ".json"))
    before = _pids(pids)
    assert main(["run", "--resume", str(out)]) == 0
    again = next(r for r in Store(out).records() if r.key == dropped.key)
    assert again.provenance["pid"] in _pids(pids) - before


def test_a_run_past_its_timeout_in_an_environment_is_stored_as_timeout(tmp_path):
    """The per-run limit holds for a worker of another interpreter: killed, replaced, the run stored as timeout.
    A limit shorter than any worker's start (the interpreter's imports alone take longer) times out each run."""
    version = mujoco.__version__
    fake(f"mujoco=={version}", version, tmp_path)
    out = tmp_path / "r"
    assert main([*RUN, "--dt", "5e-3,1e-2", "--engine", f"mujoco=={version}", "--timeout", "0.01",
                 "--out", str(out)]) in (0, 1)
    assert [r.status for r in Store(out).records()] == ["timeout", "timeout"]


ORPHAN = """
import multiprocessing as mp, sys, time
from dalembert.harness.pool import _Worker
w = _Worker(mp.get_context("fork"), 1, (), python=sys.executable)
print(w.proc.popen.pid, flush=True)
time.sleep(600)
"""


def test_a_worker_of_another_interpreter_dies_with_its_parent():
    """SIGKILL to the matrix process (which no handler sees): its environment's workers end too."""
    psutil = pytest.importorskip("psutil")
    parent = subprocess.Popen([sys.executable, "-c", ORPHAN], stdout=subprocess.PIPE, text=True)
    try:
        # (whenever the parent dies, the worker ends: before its prctl is armed, die_with_parent finds its parent gone)
        worker = psutil.Process(int(parent.stdout.readline()))
        parent.send_signal(signal.SIGKILL)
        parent.wait()
        gone, alive = psutil.wait_procs([worker], timeout=60)
        assert not alive
    finally:
        parent.kill()
        parent.wait()


def _index_reachable():
    try:
        import urllib.request

        urllib.request.urlopen("https://pypi.org/simple/mujoco/", timeout=5)
        return True
    except Exception:
        return False


# The one test that reaches the network (the package index): run only when asked, since a test run must not
# reach the network (nor spend ~40 s installing MuJoCo 3.6.0) unasked.
NETWORK_TESTS = os.environ.get("DALEMBERT_NETWORK_TESTS") == "1"


@pytest.mark.long
@pytest.mark.skipif(not NETWORK_TESTS, reason="reaches the package index: set DALEMBERT_NETWORK_TESTS=1 to run it")
def test_a_real_environment_runs_its_engine_version(tmp_path, monkeypatch):
    """``dalembert env create mujoco==3.6.0`` (~40 s with pip), then a run records MuJoCo 3.6.0 under that name;
    the environment is made under a temporary cache, not the user's."""
    if not _index_reachable():
        pytest.skip("the package index is not reachable: env create cannot install MuJoCo 3.6.0")
    monkeypatch.setenv("DALEMBERT_CACHE", str(tmp_path / "cache"))
    assert main(["env", "create", "mujoco==3.6.0"]) == 0
    out = tmp_path / "r"
    assert main([*RUN, "--engine", "mujoco==3.6.0", "--out", str(out)]) in (0, 1)
    (record,) = Store(out).records()
    assert (record.engine, record.engine_version, record.status) == ("mujoco==3.6.0", "3.6.0", "ok")


# ---------------------------------------------------------------- the report pairs the versions
def _record(engine, version, integrator, energy, case="free_top_intermediate", absl="2.1.0"):
    from types import SimpleNamespace

    from dalembert.settings import Settings

    libraries = {"mujoco": version, "numpy": "2.4.6", "absl-py": absl}
    return SimpleNamespace(engine=engine, engine_version=version, case=case, case_version="v", params={},
                           settings=Settings(integrator, dt=5e-3), errors={"orientation": (1e-3, 1e-3)},
                           drifts={"energy": energy, "angular_momentum": 1e-3}, key=f"{engine}-{integrator}",
                           provenance={"pid": 1, "libraries": libraries})


def test_the_report_sets_an_engines_versions_side_by_side_and_names_what_changed():
    """Each version a column, a group per case and settings; a drift that moved by more than CHANGE_FACTOR is
    named with each version's value, one that did not is not; an engine at one version has no table."""
    from types import SimpleNamespace

    from dalembert.reports.sections.versions import CHANGE_FACTOR, version_groups, versions

    records = [_record("mujoco==3.6.0", "3.6.0", "implicitfast", 4e-3),
               _record("mujoco", "4.0.0", "implicitfast", 0.35),
               _record("mujoco==3.11.0", "3.11.0", "implicitfast", 0.35),
               _record("mujoco==3.6.0", "3.6.0", "rk4", 3e-10), _record("mujoco", "4.0.0", "rk4", 1.5 * 3e-10),
               _record("mujoco==3.11.0", "3.11.0", "rk4", 3e-10), _record("pinocchio", "4.1.0", "rk4", 1e-9)]
    groups = version_groups(records)
    assert sorted(k[4] for k in groups) == ["implicitfast dt=0.005", "rk4 dt=0.005"]  # pinocchio: one version
    rk4 = next(g for k, g in groups.items() if k[4].startswith("rk4"))
    assert [r.engine_version for r in rk4] == ["3.6.0", "3.11.0", "4.0.0"]  # PEP 440 order, not the text's
    md = versions(SimpleNamespace(records=records)).md
    (figure,) = [m for m in md if not isinstance(m, str)]  # the changed quantity's panel, not the unchanged rk4's
    assert "free_top_intermediate, implicitfast" in figure.svg and "rk4" not in figure.svg
    assert "3.11.0" in figure.svg and figure.name == "versions-mujoco"
    text = "\n".join(m for m in md if isinstance(m, str))
    assert "implicitfast dt=0.005 energy drift on free_top_intermediate: 3.6.0 0.004, 3.11.0-4.0.0 0.35" in text
    assert "rk4 dt=0.005 energy drift" not in text.split("|")[0]  # 1.5x: under CHANGE_FACTOR, no finding
    assert CHANGE_FACTOR > 1.5
    assert "| mujoco==3.6.0 (3.6.0) | mujoco==3.11.0 (3.11.0) | mujoco (4.0.0) |" in text


def test_the_versions_section_names_the_libraries_that_differ_between_an_engines_versions():
    """A library whose versions differ between the engine's versions is a row (its version per engine name);
    one at the same version everywhere (numpy) is not, nor one only one name's worker loaded."""
    from types import SimpleNamespace

    from dalembert.reports.sections.versions import library_rows, versions

    records = [_record("mujoco==3.6.0", "3.6.0", "rk4", 1e-9, absl="2.1.0"),
               _record("mujoco", "4.0.0", "rk4", 1e-9, absl="2.3.1")]
    records[1].provenance["libraries"]["mujoco-core"] = "4.0.0"
    rows = library_rows(records, ["mujoco==3.6.0", "mujoco"])
    assert rows == [("absl-py", ["2.1.0", "2.3.1"]), ("mujoco", ["3.6.0", "4.0.0"])]
    text = "\n".join(m for m in versions(SimpleNamespace(records=records)).md if isinstance(m, str))
    assert "| absl-py | 2.1.0 | 2.3.1 |" in text and "numpy |" not in text


def test_a_versioned_engine_never_runs_outside_its_environment(tmp_path):
    """In a process that is not its environment's worker, a versioned engine's adapter reports the environment's
    version but refuses to build or run: a run of this process's engine is never recorded under another version."""
    from dalembert.adapters import get_adapter

    fake("mujoco==3.6.0", "3.6.0", tmp_path)
    adapter = get_adapter("mujoco==3.6.0")
    assert adapter.version() == "3.6.0" and get_adapter("mujoco").version() == mujoco.__version__
    with pytest.raises(RuntimeError, match="runs in its environment's workers only"):
        adapter.prepare(None, None, None)


def test_a_dask_task_runs_a_versioned_engine_in_its_environment(tmp_path):
    """``execute_isolated`` (a Dask task's run) starts the environment's interpreter for a versioned engine."""
    from dataclasses import asdict

    from dalembert.harness.dask import execute_isolated
    from dalembert.harness.execute import QUICK
    from dalembert.harness.matrix import expand
    from dalembert.harness.truths import build
    from dalembert.store import trajectory_to_npz

    version = mujoco.__version__
    name = f"mujoco=={version}"
    pids = fake(name, version, tmp_path)
    (spec,), _ = expand(["free_top_intermediate"], engines=[name], integrators=["rk4"], dts=[5e-3],
                        params={"t_final": 0.5})
    (_, made), = build([spec]).values()
    record, _ = execute_isolated(spec.to_json(), asdict(QUICK), trajectory_to_npz(made), 120)
    assert (record.engine, record.status) == (name, "ok"), record.message
    assert record.provenance["pid"] in _pids(pids)


def test_a_dask_group_task_runs_a_versioned_engine_in_its_environment(tmp_path, monkeypatch):
    """``execute_group_isolated`` (the Dask task every chunk of runs is) starts the environment's interpreter on
    this process's code, as ``execute_isolated`` does: an environment holds no dalembert (here a stale one)."""
    from dataclasses import asdict

    from dalembert.harness.dask import execute_group_isolated
    from dalembert.harness.execute import QUICK
    from dalembert.harness.matrix import expand
    from dalembert.harness.truths import build
    from dalembert.store import trajectory_to_npz

    version = mujoco.__version__
    name = f"mujoco=={version}"
    pids = fake(name, version, tmp_path)
    monkeypatch.chdir(tmp_path)  # (a checkout's root as the working directory would put its dalembert on the path)
    specs, _ = expand(["free_top_intermediate"], engines=[name], integrators=["rk4"], dts=[5e-3, 1e-2],
                      params={"t_final": 0.5})
    truths = [(k, trajectory_to_npz(made)) for k, (_, made) in build(specs).items()]
    results = execute_group_isolated([s.to_json() for s in specs], asdict(QUICK), truths, 120)
    assert [(r.engine, r.status) for r, _ in results] == [(name, "ok")] * 2, [r.message for r, _ in results]
    assert {r.provenance["pid"] for r, _ in results} <= _pids(pids)


def test_mujoco_before_its_spring_and_damper_flags_disables_passive_forces_by_their_old_name(monkeypatch):
    """MuJoCo 3.2 and older have one ``passive`` flag where later releases have ``spring`` and ``damper``: the
    MJCF names the one the installed MuJoCo knows (3.2.7 refused ``spring`` as an unknown attribute)."""
    from types import SimpleNamespace

    from dalembert.adapters.mujoco.mjcf import mjcf
    from dalembert.case import load_cases
    from dalembert.settings import Settings

    case = load_cases()["free_top_intermediate"]()
    now = mjcf(case.scene, Settings("rk4", dt=5e-3))
    assert 'spring="disable"' in now and "passive" not in now
    old = SimpleNamespace(**{n: getattr(mujoco.mjtDisableBit, n) for n in dir(mujoco.mjtDisableBit)
                             if n.startswith("mjDSBL") and n not in ("mjDSBL_SPRING", "mjDSBL_DAMPER")})
    monkeypatch.setattr(mujoco, "mjtDisableBit", old)
    before = mjcf(case.scene, Settings("rk4", dt=5e-3))
    assert 'passive="disable"' in before and "spring=" not in before and "damper=" not in before


def test_a_workers_packages_are_every_package_with_a_directory_of_its_own():
    """``boot.PACKAGES`` names each package pyproject installs from a directory of its own (``package-dir``):
    one left out would be imported, in an environment's worker, from the environment (or not at all)."""
    import tomllib

    from dalembert.harness.boot import PACKAGES, sources

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    with open(os.path.join(root, "pyproject.toml"), "rb") as f:
        assert set(PACKAGES) == set(tomllib.load(f)["tool"]["setuptools"]["package-dir"])
    import dalembert.reference

    assert sources()["dalembert.reference"] == os.path.dirname(os.path.abspath(dalembert.reference.__file__))


def test_an_integrator_an_older_version_lacks_is_refused_with_the_reason(monkeypatch):
    """MuJoCo's ``discrete`` integrator arrived in 3.13.0 (3.12.0's MJCF parser rejects it): a run of it at 3.12.0
    is refused with the reason, at 3.13.0 it runs, and the other integrators run at either."""
    from dalembert.adapters import get_adapter
    from dalembert.case import load_cases
    from dalembert.settings import Settings

    adapter = get_adapter("mujoco")
    scene = load_cases()["free_top"]().scene
    monkeypatch.setattr(type(adapter), "version", lambda self: "3.12.0")
    why = adapter.unsupported(scene, Settings("discrete", dt=5e-3))
    assert "mujoco 3.12.0 has no 'discrete' integrator" in why and "mujoco>=3.13" in why
    assert adapter.unsupported(scene, Settings("implicitfast", dt=5e-3)) is None
    monkeypatch.setattr(type(adapter), "version", lambda self: "3.13.0")
    assert adapter.unsupported(scene, Settings("discrete", dt=5e-3)) is None


def test_a_runs_libraries_name_each_loaded_distribution_once_found():
    """The libraries loaded here, by distribution: Pinocchio's ``pin`` though its package lives inside cmeel's
    prefix folder (not a top-level name of its own), and of the distributions sharing MuJoCo's folder only those
    whose files are loaded (``mujoco-mjx`` only once ``mujoco.mjx`` is imported)."""
    pytest.importorskip("pinocchio")
    from dalembert.harness.execute import _libraries

    libraries = _libraries()
    assert libraries["pin"] == metadata.version("pin") and libraries["mujoco"] == mujoco.__version__
    assert ("mujoco-mjx" in libraries) == ("mujoco.mjx" in sys.modules)
    assert "dalembert" not in libraries and "json" not in libraries
