"""``dalembert repro``: a MuJoCo, a Pinocchio and an Exudyn run each written as a standalone script that,
run where dalembert cannot be imported, reproduces the stored headline error to 1e-9 relative; a tampered
stored figure or model makes it fail; the runs and engines it does not cover are refused, saying why."""

import re
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from dalembert.adapters import get_adapter
from dalembert.harness import api
from dalembert.harness.cli import main
from dalembert.harness.commands.repro import REPRO_REL_TOL
from dalembert.reports.work_precision import headline_quantity
from dalembert.settings import Settings
from scenes import chain_case, free_body_world_loads_case

for _engine in ("mujoco", "pinocchio", "exudyn"):
    pytest.importorskip(_engine)

# Runs the script at argv[1] as __main__ with dalembert unimportable: ``import dalembert`` raises ImportError.
PRELUDE = "import runpy, sys; sys.modules['dalembert'] = None; runpy.run_path(sys.argv[1], run_name='__main__')"
# The runs reproduced: (case, engine, integrator) and the headline quantity each stores (the heavy top's: the
# attitude of a body on a ball joint, turned from the engine's rotation matrix).
RUNS = [("free_top", "mujoco", "rk4", "orientation"), ("pendulum", "mujoco", "rk4", "joint"),
        ("pendulum", "pinocchio", "rk4", "joint"), ("free_top", "pinocchio", "rk4", "orientation"),
        ("pendulum", "exudyn", "generalized-alpha", "joint"), ("free_top", "exudyn", "generalized-alpha", "orientation"),
        ("pendulum", "pinocchio", "dop853", "joint"), ("free_top", "exudyn", "dopri5", "orientation"),
        ("heavy_top", "mujoco", "rk4", "orientation"), ("heavy_top", "pinocchio", "rk4", "orientation")]


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """Short runs of each engine, case and integrator (dt 1e-2 or rtol 1e-6 over 1 s), with each engine's variants."""
    out = tmp_path_factory.mktemp("repro") / "store"
    api.run(cases=["free_top", "pendulum", "heavy_top"], engines=["mujoco", "pinocchio", "exudyn", "reference"],
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


def _script_functions(quantity):
    """The error functions a script of ``quantity`` defines (``matrix_to_quat``, ``angle``, ``error``), run here."""
    from dalembert.harness.commands.repro import _ERRORS

    namespace = {"np": np}
    exec(_ERRORS[quantity], namespace)
    return namespace


def _engine_values(engine, scene, times, settings, quantity):
    """``simulate()`` of the engine's part of a script (``Adapter.repro``), run here with ``TIMES`` as a script has it."""
    namespace = {"np": np, "TIMES": np.asarray(times, dtype=float)}
    exec(get_adapter(engine).repro(scene, times, settings, quantity), namespace)
    return namespace["simulate"]()


def _body_loads_only(scene):
    return replace(scene, loads=tuple(ld for ld in scene.loads if ld.frame == "body"))


@pytest.mark.parametrize("engine, make, integrator", [
    ("mujoco", lambda: chain_case(0.2), "rk4"),  # a ball joint, a weld, a revolute joint; turned, off-centre frames
    ("pinocchio", lambda: chain_case(0.2), "rk4"),
    ("pinocchio", lambda: chain_case(0.2), "dop853"),
    ("exudyn", lambda: free_body_world_loads_case(0.2), "generalized-alpha"),  # world loads on a free body
])
def test_the_engine_part_reads_what_the_adapter_reads_back(engine, make, integrator):
    """Bit for bit on scenes whose frames are all turned (the built-in cases' are not): each body's attitude as the
    script turns it into a quaternion, and each revolute joint's coordinate, against the adapter's read-back."""
    case = make()
    scene = _body_loads_only(case.scene) if engine == "pinocchio" else case.scene  # (world loads: refused there)
    settings = Settings(integrator, rtol=1e-8, atol=1e-8) if integrator == "dop853" else Settings(integrator, dt=0.01)
    adapter = get_adapter(engine)
    traj = adapter.run(adapter.prepare(scene, case.times, settings)).trajectory
    functions = _script_functions("orientation")
    attitudes = _engine_values(engine, scene, case.times, settings, "orientation")
    assert set(attitudes) == set(traj.bodies)
    for name, values in attitudes.items():
        quat = functions["matrix_to_quat"](values) if values.shape[1:] == (3, 3) else values
        np.testing.assert_array_equal(quat, traj.bodies[name].quaternion, err_msg=name)
    if engine != "exudyn":
        joints = _engine_values(engine, scene, case.times, settings, "joint")
        assert set(joints) == {"c"}
        np.testing.assert_array_equal(joints["c"], traj.joints["c"].q)


def test_pinocchio_world_loads_are_refused_naming_them():
    case = chain_case(0.2)
    with pytest.raises(ValueError, match="scene: world-fixed loads and spring-dampers .* no repro for them"):
        get_adapter("pinocchio").repro(case.scene, case.times, Settings("rk4", dt=0.01), "joint")
