"""A run's record keeps every timed repeat (schema 3), and reads the stores that kept only three figures."""

import json

import numpy as np

from dalembert.harness.api import load
from dalembert.harness.cli import main
from dalembert.record import Cost, RunRecord
from dalembert.settings import Settings


def test_every_timed_repeat_is_stored_and_its_figures_are_theirs(tmp_path):
    out = tmp_path / "r"
    assert main(["run", "--case", "pendulum", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-2",
                 "--param", "t_final=0.5", "--jobs", "1", "--out", str(out)]) == 0
    (record,) = load(out).records()
    walls = np.array(record.cost.wall_s_repeats)
    assert record.ok and len(walls) == record.cost.repeats >= 3  # execute.Timing.min_repeats
    assert (walls > 0).all()
    assert record.cost.wall_s_median == np.median(walls)
    assert (record.cost.wall_s_min, record.cost.wall_s_max) == (walls.min(), walls.max())


def test_repeats_survive_the_row_and_older_schemas_read_without_them():
    record = RunRecord(key="k", case="c", case_version="v", engine="e", settings=Settings("rk4", 1e-3), status="ok",
                       cost=Cost(wall_s_median=0.2, wall_s_min=0.1, wall_s_max=0.3, wall_s_repeats=(0.3, 0.1, 0.2),
                                 repeats=3))
    row = json.loads(json.dumps(record.to_row()))  # strict JSON, as stored
    assert RunRecord.from_row(row).cost == record.cost
    old = {k: v for k, v in row.items() if k != "wall_s_repeats"} | {"schema_version": 2}
    back = RunRecord.from_row(old)
    assert back.cost.wall_s_repeats == () and back.cost.wall_s_median == 0.2 and back.schema_version == 2


def test_the_manifest_records_numpy_and_scipy(tmp_path):
    import numpy
    import scipy

    out = tmp_path / "r"
    assert main(["run", "--case", "pendulum", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-2",
                 "--param", "t_final=0.1", "--quick", "--jobs", "1", "--out", str(out)]) == 0
    assert load(out).manifest()["libraries"] == {"numpy": numpy.__version__, "scipy": scipy.__version__}


def test_the_settings_label_is_one_function_and_reads_as_it_always_did():
    """``Settings.label()`` is THE label: the stored ``settings`` column and the report's text are it."""
    from dalembert.reports.findings import settings_text

    fixed = RunRecord("k", "pendulum", "v", "mujoco", Settings("rk4", 1e-3, options={"jacobian": "dense"}), status="ok")
    adaptive = RunRecord("k", "pendulum", "v", "reference", Settings("dop853", rtol=1e-9, atol=1e-9), status="ok")
    # the labels stores have always held (byte for byte: a store's `settings` column is filtered on)
    assert fixed.to_row()["settings"] == "rk4 dt=0.001 jacobian=dense" == Settings("rk4", 1e-3, options={"jacobian": "dense"}).label()
    assert adaptive.settings_label == "dop853 rtol=1e-09 atol=1e-09"
    # the report's text leaves out an atol equal to the rtol, and only that
    assert settings_text(adaptive) == "dop853 rtol=1e-09" == adaptive.settings.label(brief=True)
    assert settings_text(fixed) == fixed.settings_label
    assert Settings("rk45", rtol=1e-6, atol=1e-8).label(brief=True) == "rk45 rtol=1e-06 atol=1e-08"


def test_a_report_prints_option_values_at_four_digits_and_the_store_keeps_them_exact():
    from dalembert.reports.findings import settings_text

    # a log: grid's value (0.002 to 0.05 in 5 steps), a whole count, a name
    options = {"contact_timeconst": "0.00447213595499958", "noslip_iterations": "10", "cone": "elliptic"}
    r = RunRecord("k", "block_on_incline", "v", "mujoco", Settings("implicitfast", 1e-3, options=options), status="ok")
    assert r.options_text == "cone=elliptic contact_timeconst=0.004472 noslip_iterations=10"
    assert settings_text(r) == "implicitfast dt=0.001 " + r.options_text
    # the stored label and the run's identity keep every digit
    assert r.to_row()["settings"] == "implicitfast dt=0.001 " + r.options_label
    assert "contact_timeconst=0.00447213595499958" in r.options_label


def test_settings_and_judgement_are_nested_and_the_row_stays_flat():
    """``RunRecord`` holds a ``Settings`` and a ``Judgement``; its row keeps the flat columns every store
    was written with, and reads back into the same nested record."""
    from dalembert.judge import Judgement

    record = RunRecord("k", "pendulum", "v", "mujoco", Settings("rk45", rtol=1e-6, atol=1e-8, options={"a": "b"}),
                       status="ok", judgement=Judgement(("energy", "joint"), "drifts", "energy grows", False))
    row = json.loads(json.dumps(record.to_row()))
    assert {k: row[k] for k in ("integrator", "dt", "rtol", "atol", "options", "settings")} == {
        "integrator": "rk45", "dt": None, "rtol": 1e-6, "atol": 1e-8, "options": '{"a": "b"}',
        "settings": "rk45 rtol=1e-06 atol=1e-08 a=b"}
    assert {k: row[k] for k in ("within_tolerance", "beyond_tolerance", "verdict", "verdict_reason")} == {
        "within_tolerance": False, "beyond_tolerance": "energy joint", "verdict": "drifts",
        "verdict_reason": "energy grows"}
    assert not {"judgement", "beyond", "reason"} & set(row)
    back = RunRecord.from_row(row)
    assert back.settings == record.settings and back.judgement == record.judgement
    assert back.to_row() == row


def test_lines_whose_options_differ_beyond_the_digits_shown_do_not_merge():
    """Two runs of one engine and integrator whose option values print alike at four digits are two
    work-precision lines, each labelled by its exact options; one line alone keeps the short label."""
    from dalembert.reports.work_precision import Point, lines_of

    def run(value, dt):
        return RunRecord(f"k{value}{dt}", "block_on_incline", "v", "mujoco",
                         Settings("implicitfast", dt, options={"impratio": value}), status="ok")

    pts = [Point(1.0, 1e-3, run(v, dt)) for v in ("3.16227766", "3.16227767") for dt in (1e-3, 1e-4)]
    lines = lines_of(pts)
    assert sorted(lines) == ["mujoco implicitfast impratio=3.16227766", "mujoco implicitfast impratio=3.16227767"]
    assert all(len(v) == 2 for v in lines.values())
    assert list(lines_of(pts[:2])) == ["mujoco implicitfast impratio=3.162"]
