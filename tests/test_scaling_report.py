"""The report's scaling section: a case swept over its size, cost against the number of bodies."""

import numpy as np
import pytest

from dalembert.harness.cli import main
from dalembert.reports.scaling import fitted_exponent, size_sweeps
from dalembert.store import Store


def test_the_fitted_exponent_recovers_a_power_law():
    """cost = c N^p exactly gives p back (to roundoff), whatever c; one size gives no exponent."""
    for p, c in ((1.0, 3e-3), (1.5, 0.2), (3.0, 1e-6)):
        assert abs(fitted_exponent([(n, c * n ** p) for n in (2, 4, 8, 16, 64)]) - p) < 1e-12
    assert fitted_exponent([(4, 1.0), (4, 2.0)]) is None


@pytest.mark.long
def test_a_size_sweep_is_drawn_with_its_exponents(tmp_path):
    """chain swept over n: the section lists, per engine line, the sizes run and the exponent fitted
    to the stored costs; a case of one size has no such section."""
    out = tmp_path / "r"
    assert main(["run", "--case", "chain", "--param", "n=2,4,8", "--param", "t_final=0.2", "--engine", "mujoco",
                 "--integrator", "rk4", "--dt", "1e-3", "--out", str(out)]) == 0
    assert main(["report", str(out)]) == 0
    md = (out / "report.md").read_text()
    assert "## Scaling with the number of bodies" in md and "chain run with 2, 4, 8 bodies" in md
    assert "timed once" not in md  # the default policy: each run's median of its repeats
    store = Store(out)
    records = store.records()
    (sweep,) = size_sweeps(records, lambda name, version: len(store.case(name, version).scene.bodies))
    assert sweep.sizes == (2, 4, 8)
    points = sweep.lines["mujoco", "rk4 dt=0.001"]
    slope = np.polyfit(np.log([n for n, _ in points]), np.log([c for _, c in points]), 1)[0]
    assert f"- mujoco rk4 dt=0.001: p = {slope:.2f}" in md
    assert "chain-scaling" in "".join(p.name for p in (out / "report_files").iterdir())
    single = tmp_path / "s"
    assert main(["run", "--case", "chain", "--param", "t_final=0.2", "--engine", "mujoco", "--integrator", "rk4",
                 "--dt", "1e-3", "--out", str(single)]) == 0
    assert main(["report", str(single)]) == 0
    assert "Scaling with" not in (single / "report.md").read_text()
