"""The report's closed-loop section on a real four-bar store: each engine line's best error, worst
closure and the cost of LOOP_TARGET, against what the engines' formulations give the four-bar."""

import math

from dalembert.reports.loops import LOOP_TARGET, loop_lines
from dalembert.reports.render import build_report
from dalembert.reports.work_precision import headline_quantity
from stores import small_store

# A rigid constraint with stabilisation (Pinocchio's constraintDynamics) keeps the closure to
# roundoff on 1-m bars (measured <= 7e-15 m); a thousand ulps of room.
RIGID_CLOSURE = 1e-12
# MuJoCo's connects are soft by design (a time constant of one or two steps): on the four-bar its
# rk4 leaves the loop open by 7e-5 m at dt = 1e-2 and 1e-9 m at 1e-3 (measured): far above roundoff.
SOFT_CLOSURE = 1e-10


def test_the_section_ranks_each_engine_line_on_the_four_bar(tmp_path):
    store = small_store(tmp_path / "r", cases=("four_bar",), engines=("pinocchio", "mujoco", "exudyn"),
                        integrators=("rk4", "generalized-alpha"), dts=(1e-2, 1e-3), t_final=0.5,
                        options={"joints": "minimal"})
    build_report(store)
    records = store.records()
    assert headline_quantity(records) == "joint"
    lines = {ln.line: ln for ln in loop_lines(records, "joint")}
    # fourth order from 1e-2 reaches 1e-6 at the coarser step (3.8e-8 rad against the closed form);
    # Exudyn's generalized-alpha is second order: 3.7e-6 rad at dt = 1e-3, short of it
    # (the reference engine is left out: its Python projections make rk4 at dt = 1e-3 ~6 s a run)
    rk4 = lines["pinocchio rk4"]
    assert rk4.target_settings == "rk4 dt=0.01" and rk4.best_error < 1e-10
    assert rk4.worst_position_residual < RIGID_CLOSURE
    assert lines["exudyn generalized-alpha joints=minimal"].target_settings == ""
    assert math.isnan(lines["exudyn generalized-alpha joints=minimal"].target_cost)
    assert lines["mujoco rk4"].worst_position_residual > SOFT_CLOSURE
    md = (tmp_path / "r" / "report.md").read_text()
    section = md[md.index("## Closed loops"):]
    assert "1 degree(s) of freedom" in section and f"s/s to reach {LOOP_TARGET:g}" in section
    assert "| pinocchio | rk4 |" in section and "not reached" in section
    time_grid = next(p for p in (tmp_path / "r" / "report_files").iterdir() if p.name.endswith("four_bar-time.svg"))
    svg = time_grid.read_text()
    assert "loop closure, position" in svg and "loop closure, velocity" in svg


def test_no_section_without_loops(tmp_path):
    store = small_store(tmp_path / "r", cases=("pivoted_rod",), integrators=("rk4",), dts=(1e-2,), t_final=0.2)
    build_report(store)
    assert "Closed loops" not in (tmp_path / "r" / "report.md").read_text()
