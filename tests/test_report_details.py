"""The report's details: the diverged runs' plot shows every run whole, a declared conserved quantity
is shown with its description and unit, times and parameters print without float noise, and a
case's versions read in the order of their parameter's values."""

import gc
import math
import os
import re

import numpy as np
import pytest

from dalembert.harness.execute import QUICK
from dalembert.harness.matrix import expand
from dalembert.harness.pool import run_matrix
from dalembert.reports import figures
from dalembert.reports.formatting import params_text, value_text
from dalembert.reports.render import build_report
from dalembert.reports.tables import escape_html, escape_md
from dalembert.store import Store
from stores import add_run, base, seed_store, small_store

# A number printed with float noise: a run of six or more 0s or 9s inside its digits (0.35000000000000003,
# 0.30000000000000004, 0.19999999999999998); no measured value the report prints has that many digits.
FLOAT_NOISE = re.compile(r"\d\.\d*(?:0{6,}|9{6,})\d")


def test_value_text_prints_times_and_parameters_without_float_noise():
    assert value_text(0.05 * 7, "s") == "0.35 s"
    assert value_text(0.1 + 0.2) == "0.3"
    assert value_text(20.0) == "20" and value_text(3) == "3" and value_text(1e-5) == "1e-05"
    assert value_text(np.float64(2) / 3) == "0.6667"
    assert value_text(True) == "True" and value_text("rk4") == "rk4"
    assert params_text({"spin": 0.1 + 0.2, "axis": (0.0, 1.0, 0.1 + 0.2)}) == "axis=[0, 1, 0.3], spin=0.3"


def test_diverged_plot_covers_every_diverged_run():
    """Two runs of an engine, one blowing up to 1e25 and one diverging from errors near 1e-3: the axis
    spans both (an axis clipped to the larger one's last twelve decades would hide the other), each
    from its low end (``DIVERGED_LOW_PERCENTILE``: below it only a run's start at roundoff) to its largest error."""
    t = np.linspace(0.0, 1.0, 101)
    big = np.where(t < 0.9, 1e-6 * np.exp(t * 80.0), np.nan)  # 1e-6 .. ~1e25, then not finite
    big[0] = 1e-16  # its first sample at roundoff
    small = np.where(t < 0.5, 1e-3 + t * 1e-2, np.inf)
    early = np.where(t < 0.2, 1e-12 * (1.0 + t), np.nan)  # another engine, tiny errors
    panels = {"alpha": [("rk4 dt=0.1", t, big, 0.9), ("euler dt=0.1", t, small, 0.5)],
              "beta": [("rk4 dt=0.01", t, early, None)]}
    fig = figures.diverged_figure(panels, "orientation error (rad)")
    axes = {ax.get_title(loc="left").split(":")[0]: ax for ax in fig.axes}
    assert set(axes) == {"alpha", "beta"}
    for engine, runs in panels.items():
        lo, hi = axes[engine].get_ylim()
        assert axes[engine].get_yscale() == "log"
        for label, _, y, _ in runs:
            shown = y[np.isfinite(y) & (y > 0)]
            low = np.percentile(shown, figures.DIVERGED_LOW_PERCENTILE)
            assert lo <= low and shown.max() <= hi, \
                f"{engine} {label}: {low:.3g}..{shown.max():.3g} outside the axis {lo:.3g}..{hi:.3g}"
    assert axes["alpha"].get_ylim()[0] > 1e-16  # the roundoff start does not set the axis
    assert "(t = 0.9 s)" in [t.get_text() for t in axes["alpha"].get_legend().get_texts()][0]
    import matplotlib.pyplot as plt

    plt.close(fig)


@pytest.fixture(scope="module")
def diverged_store(tmp_path_factory):
    """The seed run and two diverged ones, one at a time with float noise (0.05 * 7 = 0.35000000000000003 s)."""
    store = seed_store(tmp_path_factory.mktemp("diverged"))
    nan_errors = {q: (math.nan, math.nan) for q in base(store).errors}
    for key, t_bad, dt in (("div-a", 0.05 * 7, 1e-2), ("div-b", 0.6, 2e-2)):
        add_run(store, key, integrator="euler", dt=dt, status="diverged", t_diverged=t_bad, verdict="diverged",
                verdict_reason="energy changed by inf times its scale (blow-up)", errors=nan_errors,
                message=f"non-finite state from t = {t_bad} s", nan_from=t_bad)
    build_report(store)
    return store


def _md(path):
    """report.md, then report_details.md (the evidence report.md links to)."""
    return "".join(open(f"{path}/{name}").read() for name in ("report.md", "report_details.md")
                   if os.path.exists(f"{path}/{name}"))


def test_no_float_noise_in_times(diverged_store):
    md = _md(diverged_store.path)
    page = open(f"{diverged_store.path}/report.html").read()
    assert "at t = 0.35 s" in md and "t=0.35 s" in page  # the hazard's sentence, the status cell
    assert "(t = 0.35 s)" in open(next(f for f in _figures(diverged_store) if f.endswith("-diverged.svg"))).read()
    assert not FLOAT_NOISE.search(md), FLOAT_NOISE.search(md).group(0)
    text = re.sub(r'title="[^"]*"', "", page)  # a stored run's message is shown as stored, on hover
    text = re.sub(r"<svg.*?</svg>", "", text, flags=re.S)  # figures: coordinates, not times
    assert not FLOAT_NOISE.search(text), FLOAT_NOISE.search(text).group(0)


def _figures(store):
    import glob

    return sorted(glob.glob(f"{store.path}/report_files/*.svg"))


@pytest.fixture(scope="module")
def declared_store(tmp_path_factory):
    """The heavy top (it declares the vertical angular momentum and the spin), one short run."""
    store = small_store(tmp_path_factory.mktemp("declared"), cases=("heavy_top",), integrators=("rk4",),
                        dts=(1e-2,), t_final=0.1)
    build_report(store)
    return store


def test_declared_quantities_show_description_and_unit(declared_store):
    case = declared_store.case(base(declared_store).case, base(declared_store).case_version)
    assert {inv.name for inv in case.invariants} >= {"vertical_angular_momentum", "spin"}
    md = _md(declared_store.path)
    page = open(f"{declared_store.path}/report.html").read()
    for inv in case.invariants:
        assert escape_md(inv.description) in md and escape_html(inv.description) in page, inv.name
        row = next(line for line in md.splitlines() if line.startswith(f"| {escape_md(inv.name)} |"))
        assert f"| {escape_md(inv.unit)} |" in row, row
        # its drift's column says what the drift is relative to, in the quantity's unit
        assert escape_md(f"{inv.name} drift (relative to {value_text(inv.scale, inv.unit)})") in md


SWEEP = (0.3, 0.1 + 0.05, 0.2, 0.1)  # horizons (s): 0.15000000000000002 prints as 0.15


@pytest.fixture(scope="module")
def sweep_store(tmp_path_factory):
    """free_top at four horizons: four versions of one case, their hashes in another order than their values."""
    specs, _ = expand(cases=["free_top"], engines=["reference"], integrators=["rk4"], dts=[1e-2],
                      params={"t_final": list(SWEEP)})
    store = Store(tmp_path_factory.mktemp("sweep")).create(
        {"harness_version": "test", "engines": {"reference": "test"}, "specs": [],
         "machine": {"cores": 2, "cpu": "test", "host": "test", "os": "test", "python": "test"}})
    run_matrix(specs, store, jobs=1, timing=QUICK)
    return store


@pytest.fixture(scope="module")
def sweep_report(sweep_store):
    """The sweep's report, built once (a report's figures take seconds) from the store opened afresh, with what
    it read counted: ``(store, case records read, trajectories read)``, each read as ``(name, version)`` or key."""
    cases, trajectories = [], []
    read_case, read_trajectory = Store._read_case, Store._read_trajectory

    def counted_case(self, name, version):
        cases.append((name, version))
        return read_case(self, name, version)

    def counted_trajectory(self, key):
        trajectories.append(key)
        return read_trajectory(self, key)

    store = Store.open(sweep_store.path)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Store, "_read_case", counted_case)
        patch.setattr(Store, "_read_trajectory", counted_trajectory)
        build_report(store)
    return store, cases, trajectories


def test_sweep_rows_in_value_order(sweep_store, sweep_report):
    by_hash = [r.params["t_final"] for r in sorted(sweep_store.records(), key=lambda r: r.case_version)]
    assert by_hash != sorted(by_hash), "the sweep's hashes happen to sort by value: the test would prove nothing"
    md = open(f"{sweep_store.path}/report.md").read()
    summary = [line for line in md.split("## Findings")[1].splitlines() if line.startswith("| free_top (")]
    shown = [float(re.search(r"t_final=([0-9.e-]+);", line).group(1)) for line in summary]
    assert shown == [float(value_text(v)) for v in sorted(SWEEP)]
    headings = [float(h) for h in re.findall(r"^## free_top \(t_final=([0-9.e-]+);", md, flags=re.M)]
    assert headings == shown
    assert not FLOAT_NOISE.search(md), FLOAT_NOISE.search(md).group(0)


def test_each_case_record_is_read_once(sweep_store, sweep_report):
    """The sections share the store's case records: building the report reads each case file once."""
    _, reads, _ = sweep_report
    stored = {(r.case, r.case_version) for r in sweep_store.records()}
    assert sorted(reads) == sorted(stored), reads


def test_each_trajectory_is_read_once(sweep_report):
    """The sections and findings share the store's trajectories: building the report reads each run's file
    at most once, and the shared arrays are read-only (no reader can change another's data)."""
    store, _, reads = sweep_report
    assert reads and len(reads) == len(set(reads)), reads
    traj = store.trajectory(reads[0])
    assert not traj.t.flags.writeable
    assert not next(iter(traj.bodies.values())).position.flags.writeable


def test_building_a_report_leaves_the_garbage_collector_as_it_found_it(tmp_path):
    """``build_report`` tunes Python's collector for the records it reads (``render.YOUNG_COLLECTION``): every
    setting is back after it, enabled or not, and nothing is left frozen."""
    store = seed_store(tmp_path / "store")
    thresholds = gc.get_threshold()
    try:
        for enabled in (True, False):
            gc.set_threshold(500, 7, 9)
            (gc.enable if enabled else gc.disable)()
            build_report(store, str(tmp_path / f"out-{enabled}"))
            assert (gc.isenabled(), gc.get_threshold(), gc.get_freeze_count()) == (enabled, (500, 7, 9), 0)
    finally:
        gc.set_threshold(*thresholds)
        gc.enable()
