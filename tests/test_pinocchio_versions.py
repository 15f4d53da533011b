"""Pinocchio 4.0.0 run in its engine environment beside the installed Pinocchio (4.1.x): the same adapter
drives both (``supported_versions``), each run records its own version, and the dynamics agree.

Pinocchio 4.0.0 cannot compile the adapter's fixed-step stepper (its own ``constraints/utils.hxx`` static
assertion), so its runs take the Python loop over the same ABA calls; the failed compile is remembered
(``adapters/pinocchio/native.py``), so this test compiles nothing after the environment's first use. Without the
environment (``dalembert env create pinocchio==4.0.0``) it skips, naming the command: no test reaches the network.
"""

import pytest

from installed import needs

pytestmark = needs("pinocchio")

OLD = "pinocchio==4.0.0"
# The errors of the two versions' runs against the same truth, relative. Measured (`dalembert run --engine
# pinocchio==4.0.0 --engine pinocchio --case pendulum --case free_top --case chain --dt 5e-3 --param t_final=0.5`,
# every integrator): identical to the last digit where both take the Python loop, and at most 3.3e-8 (RK4 on
# free_top, its angular velocity) where 4.1.x takes its compiled stepper, which rounds the quaternion update
# otherwise; a changed ABA, a lost joint or a wrong version's model moves them by O(1).
CROSS_VERSION_REL = 1e-6


def test_pinocchio_4_0_runs_in_its_environment_as_4_1_does(tmp_path):
    from dalembert.environments import environment
    from dalembert.harness.cli import main
    from dalembert.store import Store

    if not environment(OLD).exists:
        pytest.skip(f"no {OLD} environment here: make it with dalembert env create {OLD} (reaches the package index)")
    out = tmp_path / "r"
    assert main(["run", "--engine", OLD, "--engine", "pinocchio", "--case", "pendulum", "--case", "free_top",
                 "--integrator", "rk4", "--integrator", "euler", "--dt", "5e-3", "--param", "t_final=0.5",
                 "--quick", "--jobs", "1", "--no-maps", "--out", str(out)]) == 0
    records = Store(out).records()
    old = [r for r in records if r.engine == OLD]
    new = {(r.case, r.settings.integrator): r for r in records if r.engine == "pinocchio"}
    assert len(old) == 4 and {r.engine_version for r in old} == {"4.0.0"}
    assert all(r.engine_version != "4.0.0" for r in new.values())
    assert all(r.status == "ok" for r in records), [(r.key, r.message) for r in records if r.status != "ok"]
    for r in old:
        twin = new[r.case, r.settings.integrator]
        assert r.errors.keys() == twin.errors.keys()
        for quantity, (value, _) in r.errors.items():
            assert value == pytest.approx(twin.errors[quantity][0], rel=CROSS_VERSION_REL), (r.key, quantity)
