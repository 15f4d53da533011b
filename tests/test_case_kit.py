"""The case author's kit works from outside: the example of docs/cases.md, built as a package of its
own in a temporary directory, installed with pip (into that directory, not into the environment),
found through the ``dalembert.cases`` entry point, listed, checked and run by ``dalembert run``."""

import json
import os
import re
import subprocess
import sys
import textwrap

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PYPROJECT = textwrap.dedent("""\
    [build-system]
    requires = ["setuptools>=77"]
    build-backend = "setuptools.build_meta"

    [project]
    name = "my-cases"
    version = "0.1"

    [project.entry-points."dalembert.cases"]
    mine = "my_cases"

    [tool.setuptools]
    py-modules = ["my_cases"]
    """)


def _example():
    """The code block marked as the example in docs/cases.md."""
    text = open(os.path.join(ROOT, "docs", "cases.md")).read()
    return re.search(r"<!-- example: my_cases.py.*?-->\n```python\n(.*?)```", text, re.S).group(1)


def _run(args, env, cwd):
    done = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return done.stdout + done.stderr


def test_an_out_of_tree_case_package_runs_through_dalembert(tmp_path):
    package, site = tmp_path / "my-cases", tmp_path / "site"
    package.mkdir()
    (package / "pyproject.toml").write_text(PYPROJECT)
    (package / "my_cases.py").write_text(_example())
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    _run(["-m", "pip", "install", "--no-deps", "--no-build-isolation", "-q", "--target", str(site), str(package)],
         env, tmp_path)
    assert any(p.name.startswith("my_cases-0.1.dist-info") for p in site.iterdir())
    env["PYTHONPATH"] = str(site)  # the installed package and its entry point, for these commands only
    listed = _run(["-m", "dalembert.harness.cli", "cases"], env, tmp_path)
    assert "spherical_pendulum" in listed and "pendulum " in listed
    _run(["-c", "from dalembert.testing import check_case; from my_cases import spherical_pendulum; "
                "check_case(spherical_pendulum, horizon=0.5)"], env, tmp_path)
    refused = subprocess.run([sys.executable, "-m", "dalembert.harness.cli", "run", "--case", "spherical_pendulum",
                              "--param", "length=0", "--out", str(tmp_path / "refused")],
                             capture_output=True, text=True, env=env, cwd=tmp_path, timeout=600)
    assert refused.returncode == 2 and "spherical_pendulum.length: must be positive (m)" in refused.stderr, \
        refused.stderr  # its declared domain (positive=), checked when the case is made
    assert not (tmp_path / "refused").exists()
    out = tmp_path / "out"
    _run(["-m", "dalembert.harness.cli", "run", "--case", "spherical_pendulum", "--engine", "reference",
          "--integrator", "rk4", "--dt", "1e-2", "--param", "t_final=0.5", "--jobs", "1", "--quick", "--out", str(out)],
         env, tmp_path)
    (row_file,) = (out / "rows").iterdir()
    row = json.loads(row_file.read_text())
    assert row["status"] == "ok" and row["case"] == "spherical_pendulum"
    assert row["drift_vertical_angular_momentum"] < 1e-6 and row["drift_energy"] < 1e-4
    (case_file,) = (out / "cases").iterdir()
    (label,) = json.loads(case_file.read_text())["invariants"]
    assert label["name"] == "vertical_angular_momentum" and label["unit"] == "kg m^2/s"
