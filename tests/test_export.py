"""Results a pandas user picks up: ``export`` by options, by run key or all at once in one
long-format table (joint coordinates and reaction forces included, 17 significant digits), and the
Python API's notebook-style example, run as written."""

import os
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from dalembert.harness.cli import main
from dalembert.reports.export import BODY_COLUMNS, IDENTITY
from stores import small_store

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope="module")
def rod(tmp_path_factory):
    """A jointed case: joint coordinates and reaction forces in every trajectory."""
    return small_store(tmp_path_factory.mktemp("rod"), cases=("pivoted_rod", "free_top"), integrators=("rk4",),
                       dts=(1e-2,), t_final=0.5)


def test_all_runs_in_one_long_csv_with_joints_and_reactions_at_full_precision(rod, tmp_path):
    path = tmp_path / "all.csv"
    assert main(["export", rod.path, "--all", "--csv", str(path)]) == 0
    df = pd.read_csv(path, keep_default_na=False, na_values=[""])
    assert list(df.columns[:len(IDENTITY)]) == list(IDENTITY)
    assert set(df.key) == {r.key for r in rod.records()}
    for r in rod.records():
        traj = rod.trajectory(r.key)
        mine = df[df.key == r.key]
        body = mine[mine.kind == "body"]
        name = next(iter(traj.bodies))
        np.testing.assert_array_equal(body[list(BODY_COLUMNS[3:7])].to_numpy(), traj.bodies[name].quaternion)
        if r.case == "pivoted_rod":
            joint = mine[(mine.kind == "joint") & (mine.name == "rod")]
            np.testing.assert_array_equal(joint.q0.to_numpy(), traj.joints["rod"].q[:, 0])  # bit for bit
            np.testing.assert_array_equal(joint.t.to_numpy(), traj.t)
            force = mine[(mine.kind == "reaction_force") & (mine.name == "rod")]
            np.testing.assert_array_equal(force[["fx", "fy", "fz"]].to_numpy(), traj.extras["reaction_force:rod"])


def test_one_run_by_key_to_parquet(rod, tmp_path, capsys):
    r = next(r for r in rod.records() if r.case == "pivoted_rod")
    path = tmp_path / "one.parquet"
    assert main(["export", rod.path, "--key", r.key, "--parquet", str(path)]) == 0
    df = pd.read_parquet(path)
    assert set(df.key) == {r.key} and set(df.kind) == {"body", "joint", "reaction_force"}
    assert main(["export", rod.path, "--engine", "reference", "--csv", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err
    assert "2 stored runs match" in err and r.key in err  # the choices name their keys


def test_an_exudyn_option_variant_exports_by_its_option(tmp_path, capsys):
    pytest.importorskip("exudyn")
    store = small_store(tmp_path / "x", cases=("free_top",), engines=("exudyn",), integrators=("generalized-alpha",),
                        dts=(1e-2,), t_final=0.2)
    assert len(store.records()) == 3  # the engine's node variants
    base = ["export", store.path, "--case", "free_top", "--engine", "exudyn", "--integrator", "generalized-alpha",
            "--dt", "1e-2"]
    assert main([*base, "--csv", str(tmp_path / "x.csv")]) == 2
    assert "node=ep" in capsys.readouterr().err
    assert main([*base, "--option", "node=ep", "--csv", str(tmp_path / "ep.csv")]) == 0
    df = pd.read_csv(tmp_path / "ep.csv", keep_default_na=False)
    assert set(df.options) == {"node=ep"}
    assert main([*base, "--option", "node=", "--csv", str(tmp_path / "default.csv")]) == 0  # the default variant
    assert set(pd.read_csv(tmp_path / "default.csv", keep_default_na=False).options) == {""}


def test_the_api_example_runs_as_written(tmp_path):
    """docs/api_example.py, the README's Python API section as a notebook: it runs, top to bottom."""
    ran = subprocess.run([sys.executable, "-P", os.path.join(ROOT, "docs", "api_example.py"), str(tmp_path)],
                         capture_output=True, text=True, cwd=tmp_path)
    assert ran.returncode == 0, ran.stderr[-3000:]
    assert "regressed: False" in ran.stdout and (tmp_path / "top" / "report.html").exists()
