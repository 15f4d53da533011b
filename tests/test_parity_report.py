"""The report's parity section: MJX against MuJoCo C from the stored trajectories, against the floors."""

import math

import pytest

from dalembert import Settings, make_case
from dalembert.harness.cli import main
from dalembert.reports.parity import parities
from dalembert.store import Store
from installed import needs

pytestmark = needs("mujoco.mjx", "jax")  # CI installs it (dalembert[mjx]): this never skips there

# MJX's semi-implicit Euler is MuJoCo C's, operation for operation, so the two differ by roundoff alone:
# in float64 below the case's double-precision floor (measured 1.3e-15 rad against a floor of 1.0e-14 over
# 1 s of free_top at dt 1e-2), in float32 below the float32 floor (9.1e-7 rad against 1.7e-6).
ROUNDOFF_ONLY = 1.0  # times the floor of the run's number type


@pytest.mark.long
def test_parity_is_the_difference_of_the_two_engines_runs(tmp_path):
    """The section's figures equal MJX and MuJoCo C run afresh at the same settings
    (``adapters.mjx.parity.horizon``, which steps both engines itself), with the float32 floor of
    the roundoff machinery beside the float32 run."""
    from dalembert.adapters.mjx.parity import horizon

    out = tmp_path / "r"
    # in this process: where other tests left JAX's runtime up, the matrix's workers start from a forkserver
    # (``harness.pool``), not forked from it
    assert main(["run", "--case", "free_top", "--param", "t_final=1", "--engine", "mujoco", "--engine", "mjx",
                 "--integrator", "euler", "--dt", "1e-2", "--quick", "--out", str(out)]) == 0
    assert main(["report", str(out)]) == 0
    store = Store(out)
    found = {p.number_type: p for p in parities(store.records(), store.trajectory,
                                                 lambda n, v: store.case(n, v).floor)}
    assert sorted(found) == ["float32", "float64"]
    case = make_case("free_top", t_final=1.0)
    for name, p in found.items():
        fresh = horizon(case, Settings("euler", dt=1e-2, options={"precision": name}))
        assert p.orientation == pytest.approx(fresh["orientation"], rel=1e-12, abs=1e-15)
        assert p.position == pytest.approx(fresh["position"], rel=1e-12, abs=1e-15)
        assert p.floor == pytest.approx(fresh["floor"])
        if name == "float32":
            assert p.number_floor == pytest.approx(fresh["float32_floor"]) and p.number_floor > 0.0
        else:
            assert math.isnan(p.number_floor)
    assert found["float64"].orientation <= ROUNDOFF_ONLY * found["float64"].floor
    assert found["float32"].orientation <= ROUNDOFF_ONLY * found["float32"].number_floor
    md = (out / "report.md").read_text()
    assert "## MJX against MuJoCo C" in md and f"{found['float32'].orientation:.2e}" in md
