"""``dalembert repro``: a MuJoCo, a Pinocchio and an Exudyn run each written as a standalone script that,
run where dalembert cannot be imported, reproduces the stored headline error to 1e-9 relative; a tampered
stored figure or model makes it fail; the runs and engines it does not cover are refused, saying why."""

import os
import re
import subprocess
import sys

import pytest

from dalembert.harness import api
from dalembert.harness.cli import main
from dalembert.harness.commands.repro import REPRO_REL_TOL
from dalembert.reports.work_precision import headline_quantity

for _engine in ("mujoco", "pinocchio", "exudyn"):
    pytest.importorskip(_engine)

# Runs the script at argv[1] as __main__ with dalembert unimportable: ``import dalembert`` raises ImportError.
PRELUDE = "import runpy, sys; sys.modules['dalembert'] = None; runpy.run_path(sys.argv[1], run_name='__main__')"
# The runs reproduced: (case, engine, integrator) and the headline quantity each stores.
RUNS = [("free_top", "mujoco", "rk4", "orientation"), ("pendulum", "mujoco", "rk4", "joint"),
        ("pendulum", "pinocchio", "rk4", "joint"), ("free_top", "pinocchio", "rk4", "orientation"),
        ("pendulum", "exudyn", "generalized-alpha", "joint"), ("free_top", "exudyn", "generalized-alpha", "orientation"),
        ("pendulum", "pinocchio", "dop853", "joint"), ("free_top", "exudyn", "dopri5", "orientation")]


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """Short runs of each engine, case and integrator (dt 1e-2 or rtol 1e-6 over 1 s), with each engine's variants."""
    out = tmp_path_factory.mktemp("repro") / "store"
    api.run(cases=["free_top", "pendulum"], engines=["mujoco", "pinocchio", "exudyn", "reference"],
            integrators=["rk4", "generalized-alpha", "dop853", "dopri5"], dts=[1e-2], rtols=[1e-6],
            params={"t_final": 1.0}, jobs=1,
            quick=True, out=str(out))
    return api.load(str(out))


def _record(store, case, engine, integrator):
    """The run of ``case`` on ``engine`` with ``integrator`` at the engine's default options."""
    (r,) = [r for r in store.records()
            if (r.case, r.engine, r.settings.integrator) == (case, engine, integrator) and not r.settings.options]
    return r


def _script(store, record, path):
    assert main(["repro", store.path, "--key", record.key, "--out", str(path)]) == 0
    return path.read_text()


def _run(path):
    """Run the script in a fresh interpreter (-I: no PYTHONPATH, no user site) in its own directory, dalembert
    unimportable: (exit status, output)."""
    proc = subprocess.run([sys.executable, "-I", "-c", PRELUDE, str(path)], cwd=path.parent, capture_output=True,
                          text=True, timeout=None)
    return proc.returncode, proc.stdout + proc.stderr


@pytest.mark.parametrize("case, engine, integrator, quantity", RUNS)
def test_the_script_reproduces_the_stored_error_without_dalembert(store, tmp_path, case, engine, integrator, quantity):
    r = _record(store, case, engine, integrator)
    assert headline_quantity([r]) == quantity
    text = _script(store, r, tmp_path / "repro.py")
    assert not re.search(r"^\s*(import|from)\s+dalembert", text, re.M)
    assert len(text) < 20_000  # a few KB: the truth at a few samples, not the trajectory
    rc, out = _run(tmp_path / "repro.py")
    assert rc == 0, out
    mine = float(re.search(rf"{quantity} error, max over the samples: (\S+)", out).group(1))
    stored = r.max_error(quantity)
    assert abs(mine - stored) <= REPRO_REL_TOL * stored, (mine, stored)
    assert "reproduced" in out and "NOT" not in out


@pytest.mark.parametrize("case, engine, integrator, quantity", [run for run in RUNS if run[0] == "pendulum"])
def test_the_script_fails_on_a_tampered_figure_or_model(store, tmp_path, case, engine, integrator, quantity):
    """The stored figure off by 1e-8 relative (ten times the tolerance), or gravity 9.80 for 9.81 in the model:
    the script exits 1 and says so (it computes its figure, it does not echo the stored one)."""
    r = _record(store, case, engine, integrator)
    text = _script(store, r, tmp_path / "repro.py")
    stored = r.max_error(quantity)
    figure = tmp_path / "figure.py"
    figure.write_text(text.replace(f"STORED_ERROR = {stored!r}", f"STORED_ERROR = {stored * (1 + 1e-8)!r}"))
    assert figure.read_text() != text
    rc, out = _run(figure)
    assert rc == 1 and "NOT reproduced" in out, out
    model = tmp_path / "model.py"
    model.write_text(text.replace("-9.81", "-9.8"))
    assert model.read_text() != text
    rc, out = _run(model)
    assert rc == 1 and "NOT reproduced" in out, out


def test_an_engine_without_a_repro_is_refused_with_exit_2(store, tmp_path, capsys):
    r = _record(store, "pendulum", "reference", "rk4")
    assert main(["repro", store.path, "--key", r.key, "--out", str(tmp_path / "x.py")]) == 2
    err = capsys.readouterr().err
    assert "no repro for this engine (reference)" in err and "dalembert export" in err
    assert not (tmp_path / "x.py").exists()


def test_a_run_the_engine_repro_does_not_cover_says_why(store, tmp_path, capsys):
    (r,) = [r for r in store.records() if r.case == "pendulum" and r.engine == "exudyn" and r.status == "ok"
            and r.settings.integrator == "generalized-alpha" and r.settings.options == {"joints": "redundant"}]
    # (rigid bodies held by a generic joint)
    assert main(["repro", store.path, "--key", r.key, "--out", str(tmp_path / "x.py")]) == 2
    assert "options.joints: redundant joints' coordinates are read back" in capsys.readouterr().err


def test_an_unknown_key_suggests_the_close_ones(store, capsys):
    r = _record(store, "pendulum", "mujoco", "rk4")
    assert main(["repro", store.path, "--key", r.key[:-1] + "x"]) == 2
    err = capsys.readouterr().err
    assert "--key: no run" in err and f"did you mean {r.key}" in err


def test_the_script_goes_to_standard_output_by_default(store, capsys):
    r = _record(store, "pendulum", "mujoco", "rk4")
    assert main(["repro", store.path, "--key", r.key]) == 0
    out = capsys.readouterr().out
    assert out.startswith('"""Reproduction of a stored dalembert run: pendulum on mujoco') and "import mujoco" in out


def test_the_prelude_leaves_dalembert_unimportable(tmp_path):
    """What the scripts above run under: a script that imports dalembert fails there."""
    script = tmp_path / "imports.py"
    script.write_text("import dalembert\n")
    rc, out = _run(script)
    assert rc == 1 and "import of dalembert halted" in out
