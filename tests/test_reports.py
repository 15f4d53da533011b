"""Reports: built from a small store made here; checked as files, in a real browser, and by compare."""

import json
import os
import re
import shutil
import subprocess

import numpy as np
import pandas as pd
import pytest

from dalembert.harness.run import Timing, expand, run_matrix
from dalembert.store import Store
from dalembert.reports.compare import compare_stores
from dalembert.reports.render import build_report

FAST = Timing(min_repeats=1, min_total_s=0.0, max_repeats=1)
ARTIFACTS = os.path.join(os.path.dirname(__file__), "..", "test-artifacts")


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    path = tmp_path_factory.mktemp("store")
    specs, _ = expand(cases=["pivoted_rod", "free_top"], engines=["reference"], integrators=["rk4", "euler"],
                      dts=[1e-2, 5e-3], params={"t_final": 1.0})
    s = Store(path).create({"harness_version": "test", "engines": {"reference": "test"}, "specs": []})
    run_matrix(specs, s, jobs=2, timing=FAST)
    build_report(s)
    return s


def test_report_files_and_values_equal_the_store(store):
    for name in ("report.html", "report.md", "summary.csv"):
        assert os.path.getsize(os.path.join(store.path, name)) > 0
    rows = store.table()
    summary = pd.read_csv(os.path.join(store.path, "summary.csv"))
    for _, s in summary.iterrows():
        sub = rows[(rows.case == s.case) & (rows.engine == s.engine)]
        col = "err_joint_max" if s.case == "pivoted_rod" else "err_orientation_max"
        assert s.best_error == sub[col].min()  # full precision in the CSV
    md = open(os.path.join(store.path, "report.md")).read()
    for _, r in rows.iterrows():  # every stored headline error appears as shown (3 significant digits)
        col = "err_joint_max" if r.case == "pivoted_rod" else "err_orientation_max"
        assert f"{r[col]:.2e}" in md
    figures = re.findall(r"!\[[^\]]*\]\((report_files/[^)]+)\)", md)
    assert figures and all(os.path.exists(os.path.join(store.path, f)) for f in figures)


def test_energy_drift_rates_are_shown_as_stored(store):
    """The drift-rate table: every successful run's stored slope, signed, per engine + integrator
    and step (explicit Euler's secular drift and RK4's near-zero one side by side)."""
    md = open(os.path.join(store.path, "report.md")).read()
    section = md.split("## free_top")[1].split("### Energy drift rate")[1].split("###")[0]
    rows = store.table()
    top = rows[(rows.case == "free_top") & (rows.status == "ok")]
    assert len(top) == 4
    for _, r in top.iterrows():
        line = next(x for x in section.splitlines() if x.startswith(f"| {r.engine} {r.integrator} |"))
        assert f"{r.drift_rate_energy:+.2e} /s" in line
    euler, rk4 = (top[top.integrator == k].drift_rate_energy.abs().max() for k in ("euler", "rk4"))
    assert euler > 1e3 * rk4


def test_report_is_self_contained(store):
    page = open(os.path.join(store.path, "report.html")).read()
    # no resource is fetched from anywhere: every src/href is local (anchors) or inline
    refs = re.findall(r'(?:src|href)="([^"]*)"', page)
    assert refs and all(r.startswith("#") for r in refs), [r for r in refs if not r.startswith("#")]
    assert "<link" not in page and "@import" not in page


def _chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser")


def test_report_renders_in_a_real_browser(store, tmp_path):
    browser = _chromium()
    if browser is None:
        if os.environ.get("CI"):
            pytest.fail("CI must install Debian's chromium (see .ci/run)")
        pytest.skip("chromium not installed (apt-get install chromium); CI installs it")
    url = "file://" + os.path.join(store.path, "report.html")
    flags = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={tmp_path / 'profile'}", "--enable-logging=stderr", "--v=0",
             "--virtual-time-budget=5000", "--window-size=1300,2000"]
    dom = subprocess.run(flags + ["--dump-dom", url], capture_output=True, text=True, timeout=120)
    drawn = re.search(r'data-figures="(\d+)/(\d+)"', dom.stdout)
    assert drawn, "the report's self-check did not run"
    assert int(drawn.group(2)) > 0 and drawn.group(1) == drawn.group(2), f"figures drawn: {drawn.group(0)}"
    console = [line for line in dom.stderr.splitlines() if "CONSOLE" in line]
    assert console == [], console
    assert not re.search(r"net::ERR_|Failed to load resource", dom.stderr)
    os.makedirs(ARTIFACTS, exist_ok=True)
    shot = os.path.join(ARTIFACTS, "report-summary.png")
    subprocess.run(flags + [f"--screenshot={shot}", url], capture_output=True, timeout=120)
    assert os.path.getsize(shot) > 10_000


def test_compare_detects_a_tenfold_error_regression(store, tmp_path):
    same, regressed = compare_stores(store, store)
    assert not regressed and all(r["change"] == "same" for r in same)
    worse = Store(tmp_path / "worse")
    shutil.copytree(store.path, worse.path)
    key = sorted(worse.done_keys())[0]
    path = os.path.join(worse.rows_dir, f"{key}.json")
    row = json.load(open(path))
    col = next(c for c in sorted(row) if c.startswith("err_") and c.endswith("_max") and row[c] > 1e-10)
    row[col] *= 10.0
    json.dump(row, open(path, "w"))
    rows, regressed = compare_stores(store, worse)
    assert regressed
    assert [r for r in rows if r["change"].startswith("REGRESSION")][0]["error_ratio"] == pytest.approx(10.0)
    from dalembert.harness.cli import main

    assert main(["compare", store.path, worse.path]) == 1
    assert main(["compare", store.path, store.path]) == 0


def test_compare_flags_a_changed_case_instead_of_comparing(store, tmp_path):
    other = Store(tmp_path / "other")
    shutil.copytree(store.path, other.path)
    key = sorted(other.done_keys())[0]
    path = os.path.join(other.rows_dir, f"{key}.json")
    row = json.load(open(path))
    row["case_version"] = "different"
    row["err_orientation_max"] = 1.0
    json.dump(row, open(path, "w"))
    rows, regressed = compare_stores(store, other)
    assert not regressed
    assert any("case version differs" in r["change"] for r in rows)
