"""The order a hazard names its runs in: ``reports.hazards._by_sweep`` sorts them by integrator, options and sweep
(``work_precision.sweep_key``), stably, as ``sorted`` with that key does — its key made once per distinct settings."""

import random

from dalembert.record import RunRecord
from dalembert.reports.hazards import _by_sweep
from dalembert.reports.work_precision import sweep_key
from dalembert.settings import Settings


def test_runs_are_in_sweep_order_and_runs_of_one_key_in_their_order():
    shared = [Settings("rk4", dt=1e-2), Settings("rk4", dt=1e-3), Settings("euler", dt=1e-2),
              Settings("rk4", dt=1e-2, options={"solver": "newton"})]
    # two settings of one key (they differ in atol only): their runs keep their order, interleaved
    alike = [Settings("dop853", rtol=1e-6, atol=1e-6), Settings("dop853", rtol=1e-6, atol=1e-9)]
    rng = random.Random(4)
    runs = [RunRecord(f"k{i}", "c", "v", "e", rng.choice(shared + alike)) for i in range(200)]
    want = sorted(runs, key=lambda r: (r.settings.integrator, r.options_label, sweep_key(r)))
    assert [r.key for r in _by_sweep(runs)] == [r.key for r in want]
    assert [r.key for r in _by_sweep(runs) if r.settings in alike] == [r.key for r in runs if r.settings in alike]
