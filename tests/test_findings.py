"""The findings the report opens with: every hazard shown by a small store that has it, named in the
report's text; the cheapest setting per accuracy; nothing constant in the summary; a loaded machine."""

import json
import math
import os
import shutil
from dataclasses import replace

import pytest

from dalembert.reports.findings import ACCURACY_TARGETS, DISAGREEMENT_FACTOR, ENERGY_HAZARD, find, known_points
from dalembert.reports.render import build_report
from dalembert.reports.tables import escape_md
from dalembert.reports.work_precision import points
from dalembert.store import Store
from stores import add_run, base, seed_store, small_store, tamper


@pytest.fixture(scope="module")
def seed(tmp_path_factory):
    return seed_store(tmp_path_factory.mktemp("seed"))


@pytest.fixture
def store(seed, tmp_path):
    """A fresh copy of the one-run store for each test to add its runs to."""
    shutil.copytree(seed.path, tmp_path / "s")
    return Store.open(tmp_path / "s")


def _hazards(store, kind):
    (case,) = find(store)
    return [h for h in case.hazards if h.kind == kind]


def _reported(store, text):
    """``text`` appears in the report built from ``store``: Markdown (escaped) and HTML."""
    build_report(store)
    md = open(os.path.join(store.path, "report.md")).read()
    page = open(os.path.join(store.path, "report.html")).read()
    return escape_md(text) in md and text.replace("&", "&amp;").replace("'", "&#x27;") in page


def test_a_diverged_run_is_named_with_its_time(store):
    add_run(store, "div", integrator="euler", dt=1e-2, status="diverged", t_diverged=0.4, verdict="diverged",
            verdict_reason="non-finite state", message="non-finite state from t = 0.4 s", within_tolerance=None,
            errors={q: (math.nan, math.nan) for q in base(store).errors}, nan_from=0.4)
    (h,) = _hazards(store, "diverged")
    assert h.engine == "reference" and "euler dt=0.01 at t = 0.4 s" in h.text
    assert _reported(store, h.text)
    assert 'id="fig-free_top-diverged"' in open(os.path.join(store.path, "report.html")).read()


def test_a_run_that_stopped_early_is_named_with_its_message(store):
    add_run(store, "failed", integrator="dop853", dt=None, rtol=1e-6, atol=1e-6, status="failed",
            verdict="failed", message="RuntimeError: solver stopped at t = 0.3 s", within_tolerance=None)
    (h,) = _hazards(store, "failed")
    assert "dop853 rtol=1e-06 (failed: RuntimeError: solver stopped at t = 0.3 s)" in h.text
    assert _reported(store, h.text)


def test_energy_lost_beyond_one_percent_is_named(store):
    first = base(store)
    add_run(store, "lossy", integrator="euler", dt=1e-2, drifts={**first.drifts, "energy": 5 * ENERGY_HAZARD},
            drift_rates={"energy": -0.05}, verdict="drifts")
    add_run(store, "fine", integrator="euler", dt=5e-3, drifts={**first.drifts, "energy": ENERGY_HAZARD / 2},
            drift_rates={"energy": -0.01}, verdict="drifts")
    (h,) = _hazards(store, "energy")
    assert [r.key for r in h.runs] == ["lossy"]
    assert "euler dt=0.01 (up to 5 %, losing 5 %/s)" in h.text and "dt=0.005" not in h.text
    assert _reported(store, h.text)


def test_a_finite_run_beyond_the_tolerance_is_named_and_a_quiet_one_said_so(store):
    first = base(store)
    add_run(store, "off", integrator="rk4", dt=1e-2, errors={**first.errors, "orientation": (1e-4, 1e-4)},
            within_tolerance=False, beyond=("orientation",), verdict="stable")
    (h,) = _hazards(store, "tolerance")
    assert "rk4 dt=0.01 (beyond orientation)" in h.text
    assert "only the comparison with the truth shows it" in h.text  # its conserved quantities held
    assert _reported(store, h.text)


def test_engines_that_disagree_at_one_setting_are_named(store):
    first = base(store)
    tol = store.case(first.case, first.case_version).tolerances["orientation"].value
    add_run(store, "alpha", engine="alpha", errors={**first.errors, "orientation": (tol / 100, tol / 100)})
    far = tol * DISAGREEMENT_FACTOR * 10
    add_run(store, "beta", engine="beta", errors={**first.errors, "orientation": (far, far)},
            within_tolerance=False, beyond=("orientation",))
    (h,) = _hazards(store, "disagreement")
    assert h.engine == "" and {r.engine for r in h.runs} == {"alpha", "beta", "reference"}
    assert "at rk4 dt=0.005" in h.text and f"beta {far:.2e}" in h.text and f"alpha {tol / 100:.2e}" in h.text
    assert _reported(store, h.text)


def test_one_engine_within_tolerance_and_another_diverged_disagree(store):
    add_run(store, "gamma", engine="gamma", status="diverged", verdict="diverged", t_diverged=0.2,
            errors={q: (math.nan, math.nan) for q in base(store).errors}, within_tolerance=None)
    (h,) = _hazards(store, "disagreement")
    assert "at rk4 dt=0.005, reference stays within the orientation tolerance while gamma diverged" in h.text


def _adaptive(store, key, rtol, scale=1.0, steps=None, **changes):
    """An adaptive run beside the seed's, its errors the seed's times ``scale`` (1: the same, bit for bit). (``key``
    sorts after the seed's, which stays ``base``, the template of every added run.)"""
    assert key > base(store).key
    first = base(store)
    errors = {q: (mx * scale, fin * scale) for q, (mx, fin) in first.errors.items()}
    cost = replace(first.cost, n_steps=steps if steps is not None else first.cost.n_steps)
    return add_run(store, key, **{"integrator": "dop853", "dt": None, "rtol": rtol, "atol": rtol, "errors": errors,
                                  "cost": cost, **changes})


def test_two_tolerances_with_the_same_errors_are_named(store):
    _adaptive(store, "loose", 1e-6, steps=1032)
    _adaptive(store, "tight", 1e-9, steps=1032)
    _adaptive(store, "other", 1e-9, options={"welds": "constraint"})  # another variant: alone at its tolerance
    (h,) = _hazards(store, "inert")
    assert h.engine == "reference" and {r.key for r in h.runs} == {"loose", "tight"}
    err = base(store).max_error("orientation")
    assert f"a tolerance changed nothing: dop853 at rtol 1e-06 and 1e-09 (orientation {err:.2e} rad, 1032 steps each)" \
        in h.text
    assert _reported(store, h.text)
    assert "A tolerance changed nothing" in open(os.path.join(store.path, "report.md")).read()


def test_two_tolerances_with_different_errors_are_no_hazard(store):
    _adaptive(store, "loose", 1e-6)
    _adaptive(store, "tight", 1e-9, scale=1.0 - 1e-12)  # the smallest change is a change
    assert _hazards(store, "inert") == []


def test_engines_are_not_compared_where_a_tolerance_changed_nothing(store):
    """The issue's artefact: an engine restarted at every sample, its error at rtol 1e-6 its sample interval's,
    against one whose tolerance reached its steps; 1e6-fold apart, and no disagreement between them."""
    tol = store.case(base(store).case, base(store).case_version).tolerances["orientation"].value
    far = tol * DISAGREEMENT_FACTOR * 10 / base(store).max_error("orientation")
    _adaptive(store, "x-ref-loose", 1e-6, scale=far, within_tolerance=False, beyond=("orientation",))
    _adaptive(store, "x-ref-tight", 1e-9)
    _adaptive(store, "x-capped-loose", 1e-6, scale=1e-3, engine="capped")
    _adaptive(store, "x-capped-tight", 1e-9, scale=1e-3, engine="capped")
    assert {r.key for (h,) in [_hazards(store, "inert")] for r in h.runs} == {"x-capped-loose", "x-capped-tight"}
    assert _hazards(store, "disagreement") == []
    _adaptive(store, "x-capped-tight", 1e-9, scale=2e-3, engine="capped")  # its tolerance now reaches it
    (h,) = _hazards(store, "disagreement")
    assert "at dop853 rtol=1e-06" in h.text and {r.key for r in h.runs} == {"x-ref-loose", "x-capped-loose"}


def test_adaptive_runs_with_an_engine_s_own_atol_are_not_compared(store):
    """An atol left to the engine means its own default (the reference's 1e-12, Pinocchio's 1e-8)."""
    tol = store.case(base(store).case, base(store).case_version).tolerances["orientation"].value
    far = tol * DISAGREEMENT_FACTOR * 10 / base(store).max_error("orientation")
    _adaptive(store, "x-a", 1e-6, atol=None, scale=far, within_tolerance=False, beyond=("orientation",))
    _adaptive(store, "x-b", 1e-6, atol=None, engine="beta")
    assert _hazards(store, "disagreement") == []
    _adaptive(store, "x-a", 1e-6, scale=far, within_tolerance=False, beyond=("orientation",))
    _adaptive(store, "x-b", 1e-6, engine="beta")
    (h,) = _hazards(store, "disagreement")
    assert {r.key for r in h.runs} == {"x-a", "x-b"}


def test_an_unsupported_integrator_is_listed_once_with_its_reason(store):
    for key, rtol in (("u1", 1e-6), ("u2", 1e-9)):
        add_run(store, key, integrator="dop853", dt=None, rtol=rtol, atol=rtol, status="unsupported",
                verdict="unsupported", message="reference adapter cannot represent load:magic",
                within_tolerance=None)
    (h,) = _hazards(store, "unsupported")
    assert h.text == "reference cannot run dop853: reference adapter cannot represent load:magic"
    assert _reported(store, h.text)
    md = open(os.path.join(store.path, "report.md")).read()
    assert md.count("cannot represent load:magic") == 1  # not once per run, not in the stability figure


def test_the_cheapest_run_reaching_each_accuracy_is_a_stored_run(store):
    first = base(store)
    add_run(store, "cheap", integrator="euler", dt=1e-2, errors={**first.errors, "orientation": (2e-4, 2e-4)},
            cost=replace(first.cost, wall_s_median=first.cost.wall_s_median / 10))
    (case,) = find(store)
    (engine,) = case.engines
    reach = {r.target: r.point for r in engine.reaches}
    assert reach[ACCURACY_TARGETS[0]].run.key == "cheap"  # 2e-4 reaches 1e-3, and it is the cheapest
    assert reach[ACCURACY_TARGETS[1]].run.key == first.key
    assert reach[ACCURACY_TARGETS[1]].cost == first.cost.wall_s_median / first.t_final
    if first.max_error("orientation") > ACCURACY_TARGETS[2]:
        assert reach[ACCURACY_TARGETS[2]] is None and "never" in open(_summary_md(store)).read()


def test_the_points_found_are_made_once_and_read_by_the_maps_as_made(store):
    first = base(store)
    add_run(store, "other", engine="other", integrator="euler", dt=1e-2)
    add_run(store, "failed", integrator="euler", dt=2e-2, status="failed", verdict="failed", within_tolerance=None)
    (case,) = find(store)
    assert {p.run.key for p in case.points} == {first.key, "other"}  # (a finished run's point only)
    for e in case.engines:  # each engine's summary reads its own of them
        assert e.best == min(points(e.runs, case.ranked, case.case), key=lambda p: p.error)
    known = known_points([case])
    assert known(case.case.name, case.case.version, case.quantity) == tuple(points(case.runs, case.quantity))
    assert known(case.case.name, case.case.version, "velocity") is None  # (made of another error: not these)
    assert known(case.case.name, "another version", case.quantity) is None


def _summary_md(store):
    build_report(store)
    return os.path.join(store.path, "report.md")


def test_nothing_in_the_summary_is_constant_across_its_rows(tmp_path):
    """Two engines, no hazard of some kinds: those columns leave the table for one sentence."""
    store = small_store(tmp_path / "s", cases=("free_top",), engines=("reference",), integrators=("rk4", "rkmk4"),
                        dts=(1e-2, 5e-3))
    add_run(store, "other", engine="other")
    md = open(_summary_md(store)).read()
    summary = md.split("## Findings")[1].split("## Hazards")[0]
    header = next(line for line in summary.splitlines() if line.startswith("| engine"))
    cells = [c.strip() for c in header.strip("|").split("|")]
    assert "diverged" not in cells and "case" not in cells  # the same in both rows
    assert "In every row: case free\\_top" in summary or "In every row: case free_top" in summary
    rows = [line for line in summary.splitlines() if line.startswith("| ") and not line.startswith("| engine")]
    for j in range(len(cells)):
        assert len({r.strip("|").split("|")[j] for r in rows}) > 1, cells[j]


def _manifest_load(store, start, end):
    """Plant the matrix's own load readings (the seed store holds the test machine's, whatever it was then)."""
    path = os.path.join(store.path, "manifest.json")
    with open(path) as f:
        manifest = json.load(f)
    manifest["load_average"] = {"start": [start, start, start], "end": [end, end, end]}
    with open(path, "w") as f:
        json.dump(manifest, f)


def test_a_loaded_machine_is_warned_about(store):
    quiet = replace(base(store).cost, load_start=0.5, load_end=0.5)  # whatever the machine had when it ran
    tamper(store, lambda r: replace(r, cost=quiet))
    _manifest_load(store, 0.5, 0.5)
    add_run(store, "busy", integrator="euler", dt=1e-2, cost=replace(quiet, load_start=3.5))
    md = open(_summary_md(store)).read()
    assert "Timings shared the machine: the 1-minute load average reached 3.5 on 2 cores" in md
    assert "free_top reference euler dt=0.01" in md.split("Timings shared the machine")[1].split("\n")[0]


def test_a_matrix_s_own_load_is_not_a_warning(store):
    """Two workers on two cores with the parent and the OS: the load of a quiet default matrix (the highest of
    seven quiet runs' peaks, 2.97, reports.timing.OWN_LOAD) is not another process's; one more busy process (+1 on
    their median, 2.35) is."""
    quiet = replace(base(store).cost, load_start=2.97, load_end=2.35)
    tamper(store, lambda r: replace(r, cost=quiet))
    _manifest_load(store, 2.0, 2.97)
    assert "Timings shared the machine" not in open(_summary_md(store)).read()
    add_run(store, "busy", integrator="euler", dt=1e-2, cost=replace(quiet, load_end=2.35 + 1.0))
    assert "Timings shared the machine: the 1-minute load average reached 3.35 on 2 cores" in open(_summary_md(store)).read()


def test_stored_strings_are_escaped(store):
    add_run(store, "evil", integrator="euler", dt=1e-2, status="failed", verdict="failed",
            message="<script>alert(1)</script> | *boom*", within_tolerance=None)
    build_report(store)
    page = open(os.path.join(store.path, "report.html")).read()
    md = open(os.path.join(store.path, "report.md")).read()
    assert "<script>alert" not in page and "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    assert "\\<script\\>alert(1)\\</script\\> \\| \\*boom\\*" in md
