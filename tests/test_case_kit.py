"""The case author's kit works from outside: the example of docs/cases.md, built as a package of its
own in a temporary directory, installed with pip (into that directory, not into the environment),
found through the ``dalembert.cases`` entry point, listed, checked and run by ``dalembert run``."""

import json
import os
import re
import subprocess
import sys
import textwrap

from cli_script import PRELUDE

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


# The author's commands, in one interpreter that sees the installed package only through PYTHONPATH (what is tested
# is that the entry point is found from outside; one interpreter start, not one per command): ``dalembert cases``,
# ``check_case``, a run its declared domain refuses, a run; what each said, as JSON on stdout.
COMMANDS = PRELUDE + """
from dalembert.testing import check_case

said = {"cases": command("cases")}
from my_cases import spherical_pendulum
check_case(spherical_pendulum, horizon=0.5)
said["refused"] = command("run", "--case", "spherical_pendulum", "--param", "length=0", "--out", sys.argv[1])
said["run"] = command("run", "--case", "spherical_pendulum", "--engine", "reference", "--integrator", "rk4", "--dt",
                      "1e-2", "--param", "t_final=0.5", "--jobs", "1", "--quick", "--out", sys.argv[2])
print(json.dumps(said))
"""


def _run(args, env, cwd):
    done = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return done.stdout


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
    out = tmp_path / "out"
    said = json.loads(_run(["-c", COMMANDS, str(tmp_path / "refused"), str(out)], env, tmp_path).splitlines()[-1])  # (the last line)
    listed = said["cases"]
    assert listed["status"] == 0 and "spherical_pendulum" in listed["stdout"] and "pendulum " in listed["stdout"]
    refused = said["refused"]
    assert refused["status"] == 2 and "spherical_pendulum.length: must be positive (m)" in refused["stderr"], \
        refused["stderr"]  # its declared domain (positive=), checked when the case is made
    assert not (tmp_path / "refused").exists()
    assert said["run"]["status"] == 0, said["run"]["stderr"]
    (row_file,) = (out / "rows").iterdir()
    row = json.loads(row_file.read_text())
    assert row["status"] == "ok" and row["case"] == "spherical_pendulum"
    assert row["drift_vertical_angular_momentum"] < 1e-6 and row["drift_energy"] < 1e-4
    (case_file,) = (out / "cases").iterdir()
    (label,) = json.loads(case_file.read_text())["invariants"]
    assert label["name"] == "vertical_angular_momentum" and label["unit"] == "kg m^2/s"
