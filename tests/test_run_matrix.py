"""The run matrix: failures are data, timeouts stop, interrupted runs resume, Dask matches local."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from dalembert.adapters import adapter_names, check_adapter, register_adapter
from broken_adapters import Broken, NoFollower
from dalembert.harness.run import RunSpec, Timing, execute, expand, run_matrix
from dalembert.store import Store

FAST = Timing(min_repeats=1, min_total_s=0.0, max_repeats=1)


ENGINES = adapter_names()  # before the test-only adapters below are registered
for _name, _cls in (("broken", Broken), ("no-follower", NoFollower)):
    if _name not in adapter_names():
        register_adapter(_name, _cls)


@pytest.mark.parametrize("engine", ENGINES)
def test_every_adapter_meets_the_contract(engine):
    from dalembert.case import load_cases

    # every registered case; the hard ones on a short horizon (their full ones take minutes)
    cases = [f(t_final=2.0) if "hard" in f.tags else f() for _, f in load_cases().items()]
    assert check_adapter(engine, cases=cases) == []


@pytest.mark.parametrize("engine,integrator", [("reference", "rkmk4"), ("reference", "rk4"), ("pinocchio", "rk4"),
                                               ("pinocchio", "euler"), ("mujoco", "rk4")])
def test_a_blow_up_is_nan_not_an_exception(engine, integrator):
    """500 rad/s at dt = 1e-2 (5 rad per step): the state blows up; the run returns NaN from there."""
    from dalembert.adapters import get_adapter
    from dalembert import Settings, make_case

    case = make_case("free_top_fast_spin", spin=500.0, t_final=2.0)
    adapter = get_adapter(engine)
    out = adapter.run(adapter.prepare(case.scene, case.times, Settings(integrator, dt=1e-2)))
    assert not out.trajectory.is_finite()


def test_failures_are_stored_not_raised(tmp_path):
    specs, _ = expand(cases=["pivoted_rod"], engines=["broken"], dts=[1e-2])
    store = Store(tmp_path).create({"specs": [s.to_json() for s in specs]})
    run_matrix(specs, store, jobs=2, timeout=5.0, timing=FAST)
    rows = {r["integrator"]: r for r in store.rows()}
    assert rows["raises"]["status"] == "failed" and "exploded on purpose" in rows["raises"]["message"]
    assert rows["nan"]["status"] == "diverged" and "t = 1.0" in rows["nan"]["message"]
    assert rows["hangs"]["status"] == "timeout" and "5 s" in rows["hangs"]["message"]
    assert rows["rk4"]["status"] == "ok" and rows["rk4"]["within_tolerance"]
    table = store.write_table()
    assert len(table) == 4 and (tmp_path / "runs.parquet").exists()


def test_unsupported_effect_is_a_stored_result():
    (spec,), _ = expand(cases=["pivoted_rod"], engines=["no-follower"], integrators=["rk4"], dts=[1e-2])
    row, npz = execute(spec, FAST)
    assert row["status"] == "unsupported" and "load:follower_force" in row["message"] and npz is None


def test_stored_row_and_trajectory_round_trip(tmp_path):
    (spec,), _ = expand(cases=["free_top"], engines=["reference"], integrators=["rk4"], dts=[1e-2],
                        params={"t_final": 1.0})
    store = Store(tmp_path).create({})
    run_matrix([spec], store, jobs=1, timing=FAST)
    (row,) = store.rows()
    assert row["key"] == spec.key and row["status"] == "ok" and row["repeats"] == 1
    traj = store.trajectory(spec.key)
    assert traj.t[-1] == 1.0 and "top" in traj.bodies
    from dalembert.case import make_case
    from dalembert.errors import trajectory_errors

    case = make_case("free_top", t_final=1.0)
    assert trajectory_errors(traj, case.exact(case.times))["orientation"][0] == row["err_orientation_max"]
    assert RunSpec.from_json(json.loads(json.dumps(spec.to_json()))) == spec


def _cli(*args, **kw):
    return subprocess.Popen([sys.executable, "-m", "dalembert.harness.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, **kw)


def test_interrupted_run_resumes_to_the_same_store(tmp_path):
    selection = ["--case", "free_top", "--case", "pivoted_rod", "--engine", "reference", "--dt", "1e-2,5e-3",
                 "--rtol", "1e-6", "--param", "t_final=2", "--jobs", "1"]
    full = tmp_path / "full"
    assert _cli("run", *selection, "--out", str(full)).wait() == 0
    cut = tmp_path / "cut"
    proc = _cli("run", *selection, "--out", str(cut))
    store = Store(cut)
    deadline = time.monotonic() + 120
    while len(store.done_keys()) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    n_before = len(store.done_keys())
    assert 2 <= n_before < len(Store(full).done_keys())
    before = {r["key"]: r for r in store.rows()}
    assert _cli("run", "--resume", str(cut)).wait() == 0
    after = {r["key"]: r for r in store.rows()}
    reference = {r["key"]: r for r in Store(full).rows()}
    assert set(after) == set(reference)  # same rows, none missing, no duplicates
    for key, row in before.items():  # nothing finished was redone
        assert after[key]["wall_s_median"] == row["wall_s_median"]
    for key, row in reference.items():  # deterministic numbers
        assert after[key]["status"] == row["status"]
        assert after[key].get("err_orientation_max") == row.get("err_orientation_max")


def test_dask_cluster_gives_the_same_rows(tmp_path):
    distributed = pytest.importorskip("distributed")
    from dalembert.harness.run import run_matrix_dask

    specs, _ = expand(cases=["pivoted_rod"], engines=["reference"], integrators=["rk4", "dop853"], dts=[1e-2],
                      rtols=[1e-6], params={"t_final": 1.0})
    local = Store(tmp_path / "local").create({})
    run_matrix(specs, local, jobs=1, timing=FAST)
    remote = Store(tmp_path / "dask").create({})
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, host="127.0.0.1", dashboard_address=None,
                                  processes=True) as cluster, distributed.Client(cluster) as client:
        run_matrix_dask(specs, remote, client, timing=FAST)
    drop = {"wall_s_median", "wall_s_min", "wall_s_max", "overhead_s", "build_s", "worker_s", "stepping_total_s"}
    strip = lambda rows: [{k: v for k, v in r.items() if k not in drop} for r in rows]  # noqa: E731
    assert strip(local.rows()) == strip(remote.rows())
    for key in local.done_keys():
        a, b = local.trajectory(key), remote.trajectory(key)
        assert np.array_equal(a.bodies["rod"].quaternion, b.bodies["rod"].quaternion)


@pytest.mark.parametrize("args,words", [
    (["--case", "free_tops"], "did you mean 'free_top'"),
    (["--engine", "mujocoo"], "unknown engine"),
    (["--integrator", "rk5", "--engine", "reference"], "did you mean 'rk4'"),
    (["--dt=-1e-3"], "--dt: must be positive"),
    (["--rtol", "0"], "--rtol: must be positive"),
    (["--rtol=-1e-6,1e-3"], "--rtol: must be positive"),
    (["--dt", "3e-3", "--engine", "reference", "--integrator", "rk4"], "does not divide"),
    (["--tag", "fre"], "did you mean 'free'"),
    (["--out", "/proc/forbidden"], "--out"),
])
def test_bad_command_lines_fail_fast_and_write_nothing(args, words, tmp_path, capsys, monkeypatch):
    from dalembert.harness.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["run", *args]) == 2
    assert words in capsys.readouterr().err
    assert not os.path.exists(tmp_path / "results")


def test_a_diverged_run_is_a_finding_unless_strict(tmp_path):
    """Tait-Bryan nodes pass their singularity in the first intermediate-axis flip (t = 0.35 s)."""
    pytest.importorskip("exudyn")
    from dalembert.harness.cli import main

    args = ["run", "--case", "free_top_intermediate", "--engine", "exudyn", "--integrator", "rk44",
            "--option", "node=rxyz", "--dt", "1e-2", "--param", "t_final=1", "--jobs", "1"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    assert main([*args, "--out", str(tmp_path / "b"), "--strict"]) == 1
    assert [r["status"] for r in Store(tmp_path / "a").rows()] == ["diverged"]


def test_export_writes_a_stored_trajectory(tmp_path, capsys):
    from dalembert.harness.cli import main
    from dalembert.trajectory import read_csv

    out = tmp_path / "r"
    assert main(["run", "--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-2",
                 "--param", "t_final=0.5", "--out", str(out)]) == 0
    assert main(["report", str(out)]) == 0
    assert "## free_top" in (out / "report.md").read_text() and (out / "report.html").exists()
    assert main(["export", str(out), "--case", "free_top", "--engine", "reference", "--integrator", "rk4",
                 "--csv", str(tmp_path / "x.csv")]) == 0
    traj = read_csv(tmp_path / "x.csv")
    assert np.array_equal(traj.t, np.linspace(0, 0.5, 51))
