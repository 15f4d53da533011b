"""A report is a function of its store: two builds of one store, each in a process of its own (its own hash seed,
its own uuids), write the same bytes (``reports/svg_text.py``: no date, no random ids in the figures)."""

import os
import re
import shutil
import subprocess
import sys

from dalembert.reports import svg_text
from stores import small_store

plt = svg_text.plt

# An id matplotlib makes from a hash, where it is defined (``svg_text._HASHED_ID``'s kinds)
_DEFINED_ID = re.compile(r'id="((?:[pmh]|image|C[0-9a-f]+_[0-9a-f]+_)[0-9a-f]{10})"')
# The report's own files (the rest of the directory is the store, copied); one of them at least is a figure.
REPORT_FILES = ("report.html", "report.md", "summary.csv")


def _files(root):
    """Every file under ``root``, by its path relative to it, with its bytes."""
    out = {}
    for folder, _, names in os.walk(root):
        for name in names:
            path = os.path.join(folder, name)
            with open(path, "rb") as f:
                out[os.path.relpath(path, root)] = f.read()
    return out


def _report(store_dir, hash_seed):
    """``dalembert report store_dir`` in a process of its own, with Python's string hashes seeded by ``hash_seed``."""
    env = dict(os.environ, PYTHONHASHSEED=str(hash_seed))
    subprocess.run([sys.executable, "-P", "-m", "dalembert.harness.cli", "report", str(store_dir)], env=env,
                   check=True, capture_output=True)


def test_two_builds_of_one_store_in_two_processes_write_the_same_bytes(tmp_path):
    store = small_store(tmp_path / "store", cases=("pivoted_rod",), integrators=("rk4", "euler"), dts=(1e-2, 5e-3))
    first, second = tmp_path / "first", tmp_path / "second"  # two places: the store's path is no part of its report
    shutil.copytree(store.path, first)
    shutil.copytree(store.path, second)
    _report(first, 1)
    _report(second, 2)
    a, b = _files(first), _files(second)
    assert all(name in a for name in REPORT_FILES)
    assert any(name.endswith(".svg") for name in a)
    assert sorted(a) == sorted(b)
    assert [name for name in a if a[name] != b[name]] == []


def _line_figure(height):
    """A line of ``height`` in axes placed by hand: the same tick marks for any height."""
    fig = plt.figure(figsize=(3, 2))
    ax = fig.add_axes((0.2, 0.2, 0.7, 0.7))
    ax.plot([0.0, 1.0], [0.0, height], "o-")
    return fig


def test_a_figure_s_ids_are_its_own_and_the_same_in_every_save():
    """One drawing saved twice is one text; two drawings with the same tick marks (under a fixed salt alone, one id
    per tick mark for both) share no id: inlined in one page, each uses its own."""
    one, again = svg_text.svg(_line_figure(1.0)), svg_text.svg(_line_figure(1.0))
    other = svg_text.svg(_line_figure(2.0))
    assert one == again
    assert plt.rcParams["svg.hashsalt"] is None  # the fixed salt was the save's, not the process's
    ids = set(_DEFINED_ID.findall(one))
    assert {i[0] for i in ids} >= {"p", "m"}
    assert ids.isdisjoint(_DEFINED_ID.findall(other))
    references = set(re.findall(r'(?:url\(#|href="#)([^")]+)', one))  # each renamed where it is used too
    assert ids <= references <= set(re.findall(r'id="([^"]+)"', one))
