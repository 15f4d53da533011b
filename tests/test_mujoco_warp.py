"""MuJoCo Warp adapter (Warp's CPU backend, float32) against MuJoCo C at the same settings, and its refusals.

Warp compiles each kernel module on its first launch and caches it on disk (``adapters.mujoco_warp.stepping``):
from a fresh clone the first model here costs ~20-40 s of compilation on 2 cores, the others load most of their
kernels from that. The tests share one process's compiled kernels; each steps at most 1 s of model time.
"""

import mujoco
import numpy as np
import pytest

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter
from installed import needs

# long: the first test compiles Warp's kernels (tens of seconds from a fresh clone)
pytestmark = [needs("mujoco_warp", "warp"), pytest.mark.long]

ADAPTER = get_adapter("mujoco_warp")
EPS32 = float(np.finfo(np.float32).eps)  # 1.19e-7: MuJoCo Warp computes in float32
# The pendulum over 100 steps (dt 1e-3, RK4 and Euler) against MuJoCo C's same integrator in double: each step
# rounds a state of order 1 (rad, rad/s) to float32, at worst all one sign, 100 * EPS32 = 1.2e-5; measured 4e-9
# (qpos) and 1.1e-7 (qvel). Between the two, 20x the measurement; Euler against RK4 over the same 100 steps
# differs by ~1e-4 in qvel, far outside it.
PENDULUM_PARITY_TOL = 20 * EPS32
# The free top over 1 s (RK4, dt 1e-3) against MuJoCo C's RK4: its attitude difference against the float32
# floor (RK4 in float32 against the same RK4 in double, ``mjx.parity.float32_floor``), which no float32
# computation beats in expectation; measured 0.78 of the floor (7.1e-6 rad against 9.0e-6). A roundoff walk may
# land a few times above the floor's sample; a different integrator (Euler) lands ~100 times above it.
FLOOR_FACTOR = 3.0


@pytest.fixture(scope="module")
def pendulum():
    return make_case("pendulum")


@pytest.fixture(scope="module")
def top():
    return make_case("free_top")


class TestParityWithMujocoC:
    """The same compiled model and integrator in MuJoCo Warp and in MuJoCo C: apart by float32 roundoff only."""

    @pytest.mark.parametrize("integrator", ["rk4", "euler"])
    def test_pendulum_100_steps(self, pendulum, integrator):
        from dalembert.adapters.mujoco_warp.parity import one_step

        d = one_step(pendulum, Settings(integrator, dt=1e-3), n_steps=100)
        assert d["qpos"] < PENDULUM_PARITY_TOL and d["qvel"] < PENDULUM_PARITY_TOL, d

    def test_free_top_at_the_float32_floor(self, top):
        from dalembert.adapters.mujoco_warp.parity import horizon

        times = np.asarray(top.times)
        d = horizon(top, Settings("rk4", dt=1e-3), times[times <= 1.0 + 1e-12])
        assert np.isfinite(d["float32_floor"]) and d["float32_floor"] > 0
        assert d["orientation"] < FLOOR_FACTOR * d["float32_floor"], d


class TestRun:
    def test_audit_says_float32_on_the_cpu(self, pendulum):
        times = np.asarray(pendulum.times)[:11]
        p = ADAPTER.prepare(pendulum.scene, times, Settings("rk4", dt=1e-3))
        out = ADAPTER.run(p)
        audit = ADAPTER.audit(p, out)
        assert audit["precision"] == "float32" and audit["device"] == "cpu"
        assert audit["integrator"] == "MuJoCo Warp RK4"
        # float32's nearest to -9.81, not -9.81: the device model is float32's
        assert audit["gravity_device"][2] == float(np.float32(-9.81)) != -9.81
        # the compiled model the read-back uses keeps MuJoCo C's flags: auto-reset stays disabled there
        assert "autoreset" in audit["disabled"] and p.model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_AUTORESET
        assert out.n_steps == int(p.steps.sum()) == 100 and out.n_rhs == 400  # RK4: 4 evaluations a step
        assert np.all(np.isfinite(out.trajectory.bodies["rod"].position))

    def test_non_finite_state_ends_the_run(self, pendulum):
        from dalembert.adapters.mujoco_warp.stepping import put_state, step_samples

        times = np.asarray(pendulum.times)[:4]
        p = ADAPTER.prepare(pendulum.scene, times, Settings("euler", dt=1e-3))
        qvel = np.full_like(p.qvel0, np.inf)  # a state that is already bad: the first sample is non-finite
        Q, V, _, bad = step_samples(p.mx, put_state(p.model, p.qpos0, qvel, p.ctrl), p.steps, p.qpos0, qvel)
        assert bad == 1 and np.all(np.isnan(Q[1:])) and np.all(np.isnan(V[1:]))


class TestRefusals:
    def test_xfrc_applied_is_not_offered(self, pendulum):
        with pytest.raises(ValueError, match="loads"):
            ADAPTER.check(pendulum.scene, pendulum.times, Settings("rk4", dt=1e-3, options={"loads": "xfrc_applied"}))

    def test_integrators_it_lacks_are_refused_before_running(self, pendulum):
        with pytest.raises(ValueError, match="integrator"):
            ADAPTER.check(pendulum.scene, pendulum.times, Settings("discrete", dt=1e-3))

    def test_what_put_model_refuses_comes_with_its_reason(self, pendulum):
        from dalembert.adapters.mujoco.mjcf import mjcf
        from dalembert.adapters.mujoco_warp.adapter import _refusal

        xml = mjcf(pendulum.scene, Settings("rk4", dt=1e-3))
        assert _refusal(xml) is None
        pgs = xml.replace("<option ", '<option solver="PGS" ', 1)  # MuJoCo C has PGS; MuJoCo Warp has not
        assert pgs != xml
        reason = _refusal(pgs)
        assert reason and "mjw.put_model" in reason and "PGS" in reason


def test_the_report_sets_it_against_mujoco_c(tmp_path):
    """The report's parity section holds MuJoCo Warp's run against MuJoCo C's at the same settings, its figures
    those of the two engines run afresh (``parity.horizon``), the float32 floor beside them."""
    import subprocess
    import sys

    from dalembert.adapters.mujoco_warp.parity import horizon
    from dalembert.harness.cli import main
    from dalembert.reports.parity import parities
    from dalembert.store import Store

    out = tmp_path / "r"
    subprocess.run([sys.executable, "-m", "dalembert.harness.cli", "run", "--case", "free_top", "--param", "t_final=1",
                    "--engine", "mujoco", "--engine", "mujoco_warp", "--integrator", "euler", "--dt", "1e-2",
                    "--quick", "--jobs", "1", "--out", str(out)], check=True, capture_output=True)
    assert main(["report", str(out)]) == 0
    store = Store(out)
    [p] = parities(store.records(), store.trajectory, lambda n, v: store.case(n, v).floor)
    assert (p.port, p.original, p.number_type) == ("mujoco_warp", "mujoco", "float32")
    fresh = horizon(make_case("free_top", t_final=1.0), Settings("euler", dt=1e-2))
    assert p.orientation == pytest.approx(fresh["orientation"], rel=1e-12, abs=1e-15)
    assert p.number_floor == pytest.approx(fresh["float32_floor"]) and p.number_floor > 0.0
    assert p.orientation <= FLOOR_FACTOR * p.number_floor
    assert "## MuJoCo Warp against MuJoCo C" in (out / "report.md").read_text()


# Batched worlds: the pendulum's 4 worlds over 0.1 s, world k's velocity raised by k WORLD_DV (1e-3 rad/s): world 3
# ends ~(worlds - 1) * WORLD_DV * t = 3e-4 rad from world 0 (sin(w t) / w = 0.98 t at a sixteenth of the period,
# float32's resolution of the angle 1e-7): a factor 3 either side. Without the perturbation the spread is 0.
SPREAD_RANGE = (1e-4, 1e-3)


def test_batched_worlds_run_world_0_and_time_the_batch(pendulum):
    from dalembert.adapters.mujoco_warp.adapter import WORLD_DV

    times = np.asarray(pendulum.times)[:11]
    one = ADAPTER.prepare(pendulum.scene, times, Settings("rk4", dt=1e-3))
    four = ADAPTER.prepare(pendulum.scene, times, Settings("rk4", dt=1e-3, options={"worlds": 4}))
    a, b = ADAPTER.run(one), ADAPTER.run(four)
    # world 0 is the case's initial state: the same float32 arithmetic as a run of one world
    assert np.array_equal(a.trajectory.bodies["rod"].quaternion, b.trajectory.bodies["rod"].quaternion)
    audit = ADAPTER.audit(four, b)
    assert audit["worlds"] == 4 and audit["world_dv"] == WORLD_DV
    assert audit["world_steps_per_s"] == pytest.approx(4 * b.n_steps / b.wall_s)
    assert SPREAD_RANGE[0] < audit["world_spread_qpos_end"] < SPREAD_RANGE[1]
    assert "worlds" not in ADAPTER.audit(one, a)
    with pytest.raises(ValueError, match="worlds"):
        ADAPTER.check(pendulum.scene, times, Settings("rk4", dt=1e-3, options={"worlds": 0}))


def test_constraint_rows_fit_the_models_equalities():
    """The welded box held by equality welds has 156 constraint rows; MuJoCo Warp's default room (64) would drop
    rows past it with a printed warning only. ``put_state`` sizes each world for them."""
    from dalembert.adapters.mujoco_warp.stepping import put_state

    case = make_case("particle_box_welded")
    settings = Settings("rk4", dt=1e-2, options={"welds": "equality"})
    p = get_adapter("mujoco").prepare(case.scene, np.asarray(case.times)[:2], settings)
    data = mujoco.MjData(p.model)
    data.qpos[:], data.qvel[:] = p.qpos0, p.qvel0
    mujoco.mj_forward(p.model, data)
    assert data.nefc == 156
    assert put_state(p.model, p.qpos0, p.qvel0, None).njmax >= data.nefc
