"""A worker in an engine environment knows the starting process's third-party cases (``dalembert.harness.boot``,
``dalembert.case_registry.case_modules`` / ``load_modules``).

A case package is made in a temporary directory and registered the documented way (a distribution on
``sys.path`` declaring it in the entry-point group ``dalembert.cases``), on this process's path only: a worker
started as another interpreter finds it only through what ``boot`` hands it. The environment is faked as in
``tests/test_environments.py`` (a ``bin/python`` that runs this interpreter, with a stale dalembert ahead on its
path); ``test_a_cached_real_environment_runs_a_third_party_case`` uses a real one where ``dalembert env list``
has one made (none is made here: that needs the package index).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from importlib import metadata

import pytest

from dalembert import case_registry
from dalembert.case_registry import CASES, MAIN, case_modules, load_cases, load_modules
from dalembert.harness import boot
from dalembert.harness.cli import main
from dalembert.store import Store

# The case package: its __init__ imports the module that registers the case through a helper of its own package
# (a worker must find the whole package, not one file, and import the module whose import registers the case,
# not the helper's).
PACKAGE = {
    "__init__.py": "from boot_cases import swing  # noqa: F401\n",
    "helpers.py": textwrap.dedent('''\
        from dalembert.case import case

        HORIZON = 0.5  # s: a short run


        def register(factory):
            """Register ``factory`` as a case of this package."""
            return case(tags=("variant",), units={"t_final": "s"}, positive=("t_final",))(factory)
        '''),
    "swing.py": textwrap.dedent('''\
        from dataclasses import replace

        from boot_cases.helpers import HORIZON, register
        from dalembert.cases.pendulum import pendulum


        def boot_swing(t_final=HORIZON):
            """The built-in pendulum, registered by a package of its own."""
            return replace(pendulum(t_final=t_final), name="boot_swing")


        register(boot_swing)
        '''),
}
RUN = ["run", "--case", "boot_swing", "--integrator", "rk4", "--dt", "5e-3", "--quick", "--jobs", "1"]


def _forget(*names):
    """Unregister cases ``names`` and unload ``boot_cases``: nothing of this test stays in the process."""
    for name in names:
        CASES._items.pop(name, None)
        CASES.modules.pop(name, None)
    for module in [m for m in sys.modules if m == "boot_cases" or m.startswith("boot_cases.")]:
        del sys.modules[module]


@pytest.fixture
def case_package(tmp_path, monkeypatch):
    """``boot_cases`` as an installed distribution on this process's path, loaded through its entry point."""
    site = tmp_path / "site"
    (site / "boot_cases").mkdir(parents=True)
    for name, text in PACKAGE.items():
        (site / "boot_cases" / name).write_text(text)
    info = site / "boot_cases-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: boot-cases\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[dalembert.cases]\nmine = boot_cases\n")
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.setattr(case_registry, "_LOADED", False)  # (read the entry points again: this one is new)
    load_cases()
    yield site
    _forget("boot_swing")


def fake_environment(name, version, tmp_path):
    """The environment of ``name`` as this interpreter, with nothing of ``case_package`` on its path and a stale
    dalembert ahead of this one's (``tests/test_environments.py``'s ``fake``)."""
    from dalembert.environments import INFO, environment

    env = environment(name)
    stale = tmp_path / "stale"
    (stale / "dalembert").mkdir(parents=True)
    (stale / "dalembert" / "__init__.py").write_text("raise ImportError('a stale dalembert was imported')\n")
    site = os.path.join(env.path, "lib", f"python{sys.version_info[0]}.{sys.version_info[1]}", "site-packages",
                        f"numpy-{metadata.version('numpy')}.dist-info")
    os.makedirs(site)
    with open(os.path.join(site, "METADATA"), "w") as f:
        f.write(f"Metadata-Version: 2.1\nName: numpy\nVersion: {metadata.version('numpy')}\n")
    os.makedirs(os.path.dirname(env.python))
    with open(env.python, "w") as f:
        f.write(f"#!/bin/sh\nPYTHONPATH={stale} exec {sys.executable} \"$@\"\n")
    os.chmod(env.python, 0o755)
    with open(os.path.join(env.path, INFO), "w") as f:
        json.dump({"engine": env.spec.name, "requirement": env.spec.requirement, "engine_version": version,
                   "python": sys.version.split()[0], "installer": "fake", "created": "now"}, f)
    return env


# ---------------------------------------------------------------- what the starting process hands over
def test_the_code_a_worker_gets_names_each_third_party_case_and_where_its_package_is(case_package):
    code = boot.code()
    assert code["cases"] == {"boot_swing": "boot_cases.swing"}  # the module whose import registers it
    assert code["modules"] == {"boot_cases": [str(case_package / "boot_cases")]}
    assert not any(m.startswith("dalembert") for m in code["cases"].values())  # dalembert's own: the worker's
    assert set(code["packages"]) == set(boot.PACKAGES)


def test_a_case_a_script_defines_is_handed_over_as_the_script_with_no_path(monkeypatch):
    from dalembert.case import case
    from dalembert.cases.pendulum import pendulum

    monkeypatch.setattr(case_registry, "_REGISTERED_IN", dict(case_registry._REGISTERED_IN))
    try:
        exec(compile("@case(units={'t_final': 's'})\ndef boot_script_swing(t_final=0.5):\n"
                     "    return pendulum(t_final=t_final)\n", "script.py", "exec"),
             {"__name__": MAIN, "case": case, "pendulum": pendulum})
        assert case_modules()["boot_script_swing"] == MAIN
        cases, modules = boot.case_sources()
        assert cases["boot_script_swing"] == MAIN and MAIN not in modules
    finally:
        _forget("boot_script_swing")


# ---------------------------------------------------------------- the worker's side
def test_source_finder_imports_a_module_a_package_and_a_namespace_package_from_their_paths(tmp_path):
    (tmp_path / "boot_single.py").write_text("X = 1\n")
    (tmp_path / "pkg" / "boot_pkg").mkdir(parents=True)
    (tmp_path / "pkg" / "boot_pkg" / "__init__.py").write_text("")
    (tmp_path / "pkg" / "boot_pkg" / "sub.py").write_text("Y = 2\n")
    for portion in ("a", "b"):
        (tmp_path / portion / "boot_ns").mkdir(parents=True)
        (tmp_path / portion / "boot_ns" / f"part_{portion}.py").write_text(f"Z = {portion!r}\n")
    finder = boot.SourceFinder({"boot_single": str(tmp_path / "boot_single.py"),
                                "boot_pkg": [str(tmp_path / "pkg" / "boot_pkg")],
                                "boot_ns": [str(tmp_path / "a" / "boot_ns"), str(tmp_path / "b" / "boot_ns")]})
    sys.meta_path.insert(0, finder)
    try:
        import boot_ns.part_a
        import boot_ns.part_b
        import boot_pkg.sub
        import boot_single

        assert (boot_single.X, boot_pkg.sub.Y, boot_ns.part_a.Z, boot_ns.part_b.Z) == (1, 2, "a", "b")
        assert finder.find_spec("boot_elsewhere") is None  # any other name: the default machinery's
    finally:
        sys.meta_path.remove(finder)
        for name in [m for m in sys.modules if m.split(".")[0] in ("boot_single", "boot_pkg", "boot_ns")]:
            del sys.modules[name]


def test_a_case_whose_module_cannot_be_imported_in_the_worker_fails_naming_it_and_the_fix():
    """A worker told of cases imports each one's module when it is asked for: one that cannot be imported there,
    or a script's, fails the lookup of its own cases only, saying why and what to do."""
    try:
        load_modules({"boot_missing": "boot_no_such_module", "boot_scripted": MAIN, "boot_silent": "json"})
        with pytest.raises(ImportError, match=r"case 'boot_missing': its module 'boot_no_such_module' cannot be "
                                              r"imported in this worker's interpreter .*ModuleNotFoundError.* — "
                                              r"install what it imports into that environment"):
            CASES["boot_missing"]
        with pytest.raises(ImportError, match=r"case 'boot_scripted': its module '__main__' is the script that "
                                              r"started the run.* — move the case into a module of its own"):
            CASES["boot_scripted"]
        with pytest.raises(ImportError, match=r"registered no case 'boot_silent' — register it with @case"):
            CASES["boot_silent"]
        assert CASES["pendulum"].name == "pendulum"  # the others still resolve
    finally:
        for name in ("boot_missing", "boot_scripted", "boot_silent"):
            CASES.modules.pop(name, None)


# ---------------------------------------------------------------- a run, end to end
def test_a_third_party_case_runs_in_a_versioned_engines_environment(case_package, tmp_path, monkeypatch):
    """``--engine mujoco==V`` on a case of a package only this process has on its path: the environment's worker
    imports it from where this process does, and runs it as this process's own engine does."""
    mujoco = pytest.importorskip("mujoco")
    monkeypatch.setenv("DALEMBERT_CACHE", str(tmp_path / "cache"))
    name = f"mujoco=={mujoco.__version__}"
    fake_environment(name, mujoco.__version__, tmp_path)
    out = tmp_path / "out"
    assert main([*RUN, "--engine", name, "--engine", "mujoco", "--out", str(out)]) == 0
    records = {r.engine: r for r in Store(out).records()}
    assert set(records) == {name, "mujoco"}
    assert records[name].status == "ok", records[name].message
    assert records[name].provenance["pid"] != os.getpid()
    assert records[name].errors == records["mujoco"].errors  # one engine, two interpreters: the same numbers


def _cached_mujoco():
    """A made, usable MuJoCo environment in the user's cache (``dalembert env list``), or None."""
    from dalembert.environments import environment, environments

    for engine, _, _ in environments():
        if engine.startswith("mujoco"):
            env = environment(engine)
            if not env.stale():
                return env
    return None


def test_a_cached_real_environment_runs_a_third_party_case(case_package, tmp_path):
    env = _cached_mujoco()
    if env is None:
        pytest.skip("no MuJoCo environment made in this cache (dalembert env create mujoco==3.6.0 makes one; "
                    "it needs the package index, so no test makes it)")
    out = tmp_path / "out"
    assert main([*RUN, "--engine", env.spec.name, "--out", str(out)]) == 0
    (record,) = Store(out).records()
    assert record.status == "ok", record.message
    assert record.engine_version == env.engine_version
    assert record.provenance["libraries"]["mujoco"] == env.engine_version  # imported in the environment


def test_a_worker_interpreter_imports_the_case_package_and_dalembert_from_the_code_it_is_given(case_package,
                                                                                                 tmp_path):
    """``boot``'s start (``_install``) in an interpreter that has not the package on its path and a stale
    dalembert ahead of this one's: both come from ``CODE``."""
    stale = tmp_path / "stale"
    (stale / "dalembert").mkdir(parents=True)
    (stale / "dalembert" / "__init__.py").write_text("raise ImportError('a stale dalembert was imported')\n")
    script = ("import json, sys; from importlib.util import spec_from_file_location, module_from_spec; "
              f"spec = spec_from_file_location('boot', {os.path.abspath(boot.__file__)!r}); "
              "boot = module_from_spec(spec); spec.loader.exec_module(boot); boot._install(json.loads(sys.argv[1])); "
              "from dalembert.case_registry import CASES; print(CASES['boot_swing'].summary); "
              "import boot_cases, dalembert; print(boot_cases.__file__); print(dalembert.__file__)")
    env = {**{k: v for k, v in os.environ.items() if k != "PYTHONPATH"}, "PYTHONPATH": str(stale)}
    done = subprocess.run([sys.executable, "-c", script, json.dumps(boot.code())], capture_output=True, text=True,
                          env=env, cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    summary, package, own = done.stdout.split("\n")[:3]
    assert summary == "The built-in pendulum, registered by a package of its own."
    assert package == str(case_package / "boot_cases" / "__init__.py")
    assert own == os.path.join(boot.sources()["dalembert"], "__init__.py")
