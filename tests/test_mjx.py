"""MJX adapter against the closed forms, MuJoCo C and the reference solver, in float64 and float32.

Every new model structure costs MJX a JIT compilation of seconds to a minute on a busy machine, so
the tests share prepared models (``_prepared``) and each precision's tests run together (a process
switching precision clears JAX's caches: ``adapters.mjx.stepping``): float64 first, float32 last.
The one-step parity steps the top's own compiled rollout. ``particle_box`` is not here: its welded
particles are one free body in the model MuJoCo compiles (as the top is), so MJX runs it on the top's
code path, and its model would cost a compilation of its own (MuJoCo C checks the box's welds).
"""

import numpy as np
import pytest

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter
from dalembert.errors import trajectory_errors
from dalembert.reference import simulate
from bounds import ORDER_SLACK, ROD_ANGLE_TOL, ROD_REACTION_TOL
from scenes import chain_case
from installed import needs

pytestmark = [needs("mujoco.mjx", "jax"), pytest.mark.long]  # every test here compiles an MJX rollout (seconds each)

ADAPTER = get_adapter("mjx")
F64 = {"precision": "float64"}

# MJX's RK4 is second order on a rotating free body (float64; measured on the top over 2 s:
# 4.18e-6, 1.04e-6, 2.61e-7 rad at dt 1e-2, 5e-3, 2.5e-3 — MuJoCo C's RK4 on the same model,
# 4.9e-9, 3.1e-10, 1.9e-11: fourth order). One step shows why: qvel agrees with MuJoCo C to
# roundoff, qpos differs by O(dt^3) (2.1e-7 and 2.1e-10 after two steps at dt 1e-2 and 1e-3): the
# stages advance the quaternion by the stage velocities without the dexp^-1 correction (Pinocchio's
# rk4-naive). MuJoCo C 3.14.0's RK4 measured the same way is second order too (log2 ratio 1.999 on
# this top against itself at dt 1e-4): MJX 3.17 keeps MuJoCo's RK4 from before 4.0.
MJX_RK4_ORDER = 2
# The attitude bound for MJX's RK4 at dt = 1e-3 in float64: measured 5.9e-8 rad on the top over 20 s
# and 5.3e-7 on the box (its spin is slower but longer-lasting); both C dt^2 t, 5x the larger.
MJX_RK4_ORIENTATION_TOL = 3e-6
# One step of MJX's RK4 against MuJoCo C's in float64: qvel equal up to a few roundings of the
# ~5 rad/s velocities; qpos apart by ~C dt^3 (measured 1.0e-7 per step at dt = 1e-2 on the top).
ONE_STEP_QVEL_TOL = 1e-14
ONE_STEP_QPOS_RANGE = (1e-8, 1e-6)
# Against the reference (Kane, DOP853 at 1e-12) on the chain, MJX RK4 at dt = 1e-3 in float64:
# its second-order defect, measured 1.1e-6 rad, 6.6e-7 m, 4.6e-6 rad/s, 5.8e-7 N (x1/4 at 5e-4);
# frames mixed up would give O(1).
MJX_CROSS_CHECK_TOL = 2e-5
# float32 on the rod (RK4, dt = 1e-3, 2000 steps to 12 rad): measured 2.8e-5 rad; the worst case,
# one rounding per step all of one sign, is N eps32 |phi| = 2000 * 6e-8 * 12 = 1.4e-3 rad: a bound
# between the two, 4x the measurement.
F32_ROD_ANGLE_TOL = 1e-4

_CACHE = {}


def _prepared(case, settings):
    key = (case.name, case.version, settings)
    if key not in _CACHE:
        _CACHE[key] = ADAPTER.prepare(case.scene, case.times, settings)
    return _CACHE[key]


def run(case, settings):
    prepared = _prepared(case, settings)
    return prepared, ADAPTER.run(prepared)


def errors(case, settings):
    return trajectory_errors(run(case, settings)[1].trajectory, case.exact(case.times))


# ------------------------------------------------------------------ float64
def test_float64_rk4_on_the_canonical_cases():
    s = Settings("rk4", dt=1e-3, options=F64)
    rod = errors(make_case("pivoted_rod"), s)
    assert rod["joint"][0] < ROD_ANGLE_TOL and rod["reaction_force"][0] < ROD_REACTION_TOL, rod
    assert errors(make_case("free_top"), s)["orientation"][0] < MJX_RK4_ORIENTATION_TOL


def test_float64_rk4_is_second_order_on_the_top():
    """The finding: MJX's RK4 converges at second order where MuJoCo C's is fourth (test_mujoco)."""
    top = make_case("free_top", t_final=2.0)
    coarse, fine = (errors(top, Settings("rk4", dt=dt, options=F64))["orientation"][0] for dt in (1e-2, 5e-3))
    assert np.log2(coarse / fine) == pytest.approx(MJX_RK4_ORDER, abs=ORDER_SLACK)


def test_float64_one_step_parity_with_mujoco_c():
    from dalembert.adapters.mjx.parity import one_step

    d = one_step(make_case("free_top"), Settings("rk4", dt=1e-2, options=F64))
    assert d["qvel"] < ONE_STEP_QVEL_TOL
    assert ONE_STEP_QPOS_RANGE[0] < d["qpos"] < ONE_STEP_QPOS_RANGE[1], d


def test_implicitfast_is_first_order_on_the_rod():
    rod = make_case("pivoted_rod")
    coarse, fine = (errors(rod, Settings("implicitfast", dt=dt, options=F64))["joint"][0] for dt in (1e-2, 1e-3))
    assert coarse / fine == pytest.approx(10.0, rel=0.01)


def test_every_joint_kind_frame_and_load_against_the_reference():
    case = chain_case()
    ref = simulate(case.scene, case.times, Settings("dop853", rtol=1e-12, atol=1e-12,
                                                    options={"formulation": "kane"}))[0]
    traj = run(case, Settings("rk4", dt=1e-3, options=F64))[1].trajectory
    e = trajectory_errors(traj, ref)
    for q in ("position", "orientation", "velocity", "angular_velocity", "reaction_force"):
        assert e[q][0] < MJX_CROSS_CHECK_TOL, (q, e[q])
    assert np.max(np.abs(traj.joints["c"].q - ref.joints["c"].q)) < MJX_CROSS_CHECK_TOL


def test_audit_proves_only_the_scene_physics_and_the_precision():
    for name in ("pivoted_rod", "free_top"):
        case = make_case(name)
        prepared, outcome = run(case, Settings("rk4", dt=1e-3, options=F64))
        audit = ADAPTER.audit(prepared, outcome)
        assert audit["gravity"] == case.scene.gravity and audit["gravity_device"] == case.scene.gravity
        assert audit["precision"] == "float64" and audit["dtype_qpos"] == "float64"
        assert audit["integrator"] == "MJX RK4" and audit["backend"] == "cpu" and audit["jit_compile_s"] > 0.0
        assert audit["max_contacts"] == 0 and audit["max_constraint_rows"] == 0 and audit["ngeom"] == 0
        assert audit["max_armature"] == 0.0 and audit["max_damping"] == 0.0
        assert len(audit["actuators"]) == len(case.scene.loads)


def test_an_effect_mjx_cannot_put_on_the_device_is_unsupported(monkeypatch):
    """No effect of today's scenes is beyond MJX 3.17; where ``put_model`` refuses a model
    (NotImplementedError), the run is unsupported with MJX's reason, not a failure."""
    from dalembert.adapters.mjx import adapter as mjx_adapter

    class Refusing:
        @staticmethod
        def put_model(model):
            raise NotImplementedError("mjtJoint.mjJNT_BALL")

    case = make_case("pivoted_rod")
    assert ADAPTER.unsupported(case.scene, Settings("rk4", dt=1e-3)) is None
    monkeypatch.setattr(mjx_adapter, "mjx", lambda: Refusing)
    mjx_adapter._refusal.cache_clear()  # the answer is kept per model; this MJX changed its mind
    reason = ADAPTER.unsupported(case.scene, Settings("rk4", dt=1e-3))
    before = ADAPTER.unsupported_before_build(case.scene, Settings("rk4", dt=1e-3))
    mjx_adapter._refusal.cache_clear()
    assert before is None  # known once the model is built: the matrix keeps the run, its worker stores the refusal
    assert reason.startswith("MJX cannot put this model on the device") and "mjJNT_BALL" in reason


def test_prepare_compiles_the_rollout_the_run_calls():
    """``prepare``'s compilation is the run's (``stepping.compile_rollout`` puts its zero steps where the run's steps
    are): the run adds no executable to the rollout's, so its stepping wall holds no compilation. JAX's caches are
    cleared first, so that a rollout another test ran cannot hide a second one (this one is then loaded from JAX's
    persistent cache: well under a second). The one-step parity (``parity.one_step``) steps that program too."""
    import jax

    from dalembert.adapters.mjx import stepping
    from dalembert.adapters.mjx.parity import one_step

    case, settings = make_case("pivoted_rod"), Settings("rk4", dt=1e-3, options=F64)
    jax.clear_caches()
    prepared = ADAPTER.prepare(case.scene, case.times, settings)
    compiled = stepping._rollout()._cache_size()
    ADAPTER.run(prepared)
    one_step(case, settings)
    assert compiled == stepping._rollout()._cache_size() == 1


def test_the_default_matrix_runs_both_precisions():
    # (option values and MuJoCo's loads option, which MJX does not take, are refused in test_adapter_contract)
    assert {"precision": "float64"} in ADAPTER.variants(make_case("free_top").scene)


# ------------------------------------------------------------------ float32 (last: see the docstring)
def test_float32_rod_and_its_precision():
    prepared, outcome = run(make_case("pivoted_rod"), Settings("rk4", dt=1e-3))
    e = trajectory_errors(outcome.trajectory, make_case("pivoted_rod").exact(prepared.times))
    assert ROD_ANGLE_TOL < e["joint"][0] < F32_ROD_ANGLE_TOL  # float32 shows, and stays bounded
    audit = ADAPTER.audit(prepared, outcome)
    assert audit["precision"] == "float32" and audit["dtype_qpos"] == "float32"


def test_divergence_is_data():
    """Euler at 500 rad/s with 5 rad per step: MJX runs on as inf/NaN; the adapter reports NaN from
    the first non-finite sample on, no exception."""
    case = make_case("free_top_fast_spin", spin=500.0, t_final=2.0)
    outcome = run(case, Settings("euler", dt=1e-2))[1]
    traj = outcome.trajectory
    assert not traj.is_finite() and 0.0 < traj.first_nonfinite_time() <= 2.0
    k = int(np.searchsorted(traj.t, traj.first_nonfinite_time()))
    assert np.all(np.isnan(traj.bodies["top"].quaternion[k:]))
