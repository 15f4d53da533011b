"""Batched worlds (``dalembert.adapters.batch``, ``dalembert.harness.batches``): the records a batch makes, how runs
are grouped into batches and tasks, and the batches of MuJoCo Warp against its runs of one world.

MuJoCo Warp computes every world of a ``mjw.Data`` by the same kernels, so a world of a batch is bit for bit the
scene run alone; the tests hold it to that. They use ``free_top_fast_spin`` over half a second sampled every
0.1 s (tens of steps per run): the swept spin enters the initial state only, so its values share one model.
"""

import json
import math

import numpy as np
import pytest

from dalembert.harness.batches import batch_key, execute_batch, groups
from dalembert.harness.execute import QUICK, execute
from dalembert.harness.matrix import expand
from dalembert.record import Cost, RunRecord
from dalembert.settings import Settings

SHORT = {"t_final": 0.5, "sample_interval": 0.1}


def _specs(engine, spins, dts=(0.05,), **params):
    specs, _ = expand(cases=["free_top_fast_spin"], engines=[engine], integrators=["rk4"], dts=list(dts),
                      params={**SHORT, "spin": list(spins), **params})
    return specs


def test_batch_fields_survive_the_row_and_rows_without_them_read_as_one_world():
    cost = Cost(wall_s_median=0.1, batch_size=8, batch_wall_s=0.8, world_steps_per_s=800.0, device="cpu")
    record = RunRecord(key="k", case="c", case_version="v", engine="e", settings=Settings("rk4", 1e-3), status="ok",
                       cost=cost)
    row = json.loads(json.dumps(record.to_row()))  # strict JSON, as stored
    assert RunRecord.from_row(row).cost == cost
    old = {k: v for k, v in row.items() if k not in ("batch_size", "batch_wall_s", "world_steps_per_s", "device")}
    back = RunRecord.from_row(old).cost
    assert (back.batch_size, back.device) == (1, "") and math.isnan(back.batch_wall_s)
    assert RunRecord.from_row({**row, "batch_size": float("nan"), "device": None}).cost.batch_size == 1  # (pandas)


def test_a_run_that_stepped_copies_beside_it_is_timed_per_world():
    """MuJoCo Warp's ``worlds=4`` times 4 copies of the run at once (``Outcome.info["batch_size"]``): its record's
    stepping times are per world, the batch's beside them; a run alone keeps its times and gains its device."""
    from dalembert.harness.batches import per_world

    cost = Cost(wall_s_median=0.8, wall_s_min=0.4, wall_s_max=1.2, wall_s_repeats=(0.8, 0.4, 1.2), n_steps=100,
                overhead_s=0.04, stepping_total_s=3.2, build_s=2.0)
    four = per_world(cost, {"batch_size": 4, "device": "cpu"})
    assert (four.batch_size, four.batch_wall_s, four.device, four.build_s) == (4, 0.8, "cpu", 2.0)
    assert (four.wall_s_median, four.wall_s_min, four.wall_s_max) == (0.2, 0.1, 0.3)
    assert four.wall_s_repeats == (0.2, 0.1, 0.3) and four.world_steps_per_s == pytest.approx(4 * 100 / 0.8)
    assert per_world(cost, {"device": "cpu"}) == Cost(**{**cost.__dict__, "device": "cpu"})


def test_runs_group_into_batches_by_everything_but_the_case_parameters():
    # MJX (in dalembert[all], so the test runs wherever the suite does): its matrix runs two precisions
    specs = _specs("mjx", [5, 50, 500], dts=(0.05, 0.1))
    variants = len({tuple(sorted(s.settings.options.items())) for s in specs})
    assert variants == 2
    made = groups(specs, batched=True)
    assert sorted(len(g) for g, batched in made) == [3] * 2 * variants and all(batched for _, batched in made)
    for group, _ in made:
        assert len({batch_key(s) for s in group}) == 1 and len({s.params for s in group}) == 3
    # without --batch, or on an engine without batches: chunks of one case, engine, integrator and options
    assert sorted(len(g) for g, batched in groups(specs, batched=False, chunk=4) if not batched) == [2, 2, 4, 4]
    assert [len(g) for g, _ in groups(specs, batched=False, chunk=1)] == [1] * 12
    reference = _specs("reference", [5, 50], dts=(0.05, 0.1))
    assert not any(batched for _, batched in groups(reference, batched=True))
    with pytest.raises(ValueError, match="chunk"):
        groups(specs, chunk=0)


def test_the_work_precision_lines_keep_batched_runs_apart():
    from dalembert.reports.work_precision import Point, lines_of

    def run(n, dt):
        return RunRecord(f"k{n}{dt}", "free_top_fast_spin", "v", "mujoco_warp", Settings("rk4", dt), status="ok",
                         cost=Cost(batch_size=n))

    lines = lines_of([Point(1.0, 1e-3, run(n, dt)) for n in (1, 16, 3) for dt in (1e-3, 1e-2)])
    assert sorted(lines) == ["mujoco_warp rk4", "mujoco_warp rk4 (per world of a batch)"]
    assert [len(v) for _, v in sorted(lines.items())] == [2, 4]


warp = pytest.mark.skipif(not __import__("importlib").util.find_spec("mujoco_warp"), reason="dalembert[mujoco-warp]")


@warp
@pytest.mark.long  # Warp's kernels: loaded from its cache, compiled (tens of seconds) from a fresh clone
def test_a_batch_of_spins_is_each_spin_run_alone_and_says_it_is_per_world():
    """Three spins at dt 0.05: 5 and 50 rad/s finish, 500 diverges at 0.2 s. Each world's record is the run alone's
    (same status, errors and drifts, bit for bit), its cost the batch's share with the batch beside it."""
    specs = _specs("mujoco_warp", [5, 50, 500])
    batch = execute_batch(specs, QUICK)
    for spec, (record, _) in zip(specs, batch):
        alone, _ = execute(spec, QUICK)
        assert record.key == spec.key and record.status == alone.status
        assert record.errors == alone.errors and record.drifts == alone.drifts and record.message == alone.message
        assert record.cost.n_steps == alone.cost.n_steps and alone.cost.batch_size == 1
        assert (record.cost.batch_size, record.cost.device) == (3, "cpu")
    assert [r.status for r, _ in batch] == ["ok", "ok", "diverged"]
    ok = batch[0][0].cost
    assert ok.wall_s_median == pytest.approx(ok.batch_wall_s / 3)
    steps = sum(r.cost.n_steps for r, _ in batch)
    assert ok.world_steps_per_s == pytest.approx(steps / ok.batch_wall_s)


@warp
@pytest.mark.long
def test_worlds_of_two_inertias_share_a_batch():
    """Two inertias are two MJCF models that differ only in fields MuJoCo Warp holds per world (``body_inertia`` and
    what MuJoCo derives from it): one batch, each world the inertia run alone (a structural parameter is refused:
    tests/test_batches_model.py)."""
    from dalembert.adapters import get_adapter
    from dalembert.harness.truths import built_case

    specs, _ = expand(cases=["free_top_fast_spin"], engines=["mujoco_warp"], integrators=["rk4"], dts=[0.05],
                      params={**SHORT, "inertia": [(1.0, 2.0, 3.0), (1.0, 2.0, 2.5)]})
    scenes = [built_case(s.case, s.params)[0].scene for s in specs]
    adapter = get_adapter("mujoco_warp")
    assert adapter.batch_problem(scenes, None, specs[0].settings) is None
    assert "options.worlds" in adapter.batch_problem(scenes[:1], None, Settings("rk4", 0.05, options={"worlds": 2}))
    records = [r for r, _ in execute_batch(specs, QUICK)]
    assert [r.status for r in records] == ["ok", "ok"] and {r.cost.batch_size for r in records} == {2}
    for spec, record in zip(specs, records):
        alone, _ = execute(spec, QUICK)
        assert record.errors == alone.errors and record.drifts == alone.drifts


@warp
@pytest.mark.long
def test_a_searched_map_finds_the_same_boundaries_batched(tmp_path):
    """``--search dt --batch``: each round's probes of one step share a batch; every probe is the run alone's, so the
    search takes the same probes to the same boundaries as probe by probe."""
    from dalembert.boundary import boundaries
    from dalembert.harness.cli import main
    from dalembert.store import Store

    common = ["run", "--case", "free_top_fast_spin", "--param", "spin=5,500", "--param", "t_final=0.5",
              "--param", "sample_interval=0.1", "--engine", "mujoco_warp", "--integrator", "rk4", "--search", "dt",
              "--dt", "1e-2,1e-1", "--resolution", "1.5", "--quick", "--jobs", "1"]
    assert main([*common, "--out", str(tmp_path / "one")]) == 0
    assert main([*common, "--batch", "--out", str(tmp_path / "batch")]) == 0
    one, batch = Store(str(tmp_path / "one")).records(), Store(str(tmp_path / "batch")).records()
    assert sorted(r.key for r in one) == sorted(r.key for r in batch)
    assert max(r.cost.batch_size for r in batch) == 2 and {r.cost.batch_size for r in one} == {1}
    assert [(b.stable, b.finite) for b in boundaries(one)] == [(b.stable, b.finite) for b in boundaries(batch)]
    assert Store(str(tmp_path / "batch")).manifest()["batch"] is True
    from dalembert.reports.maps import stability_maps

    units = lambda name: {"spin": "rad/s"}  # noqa: E731
    assert [m.batch for m in stability_maps(batch, units)] == [2] and [m.batch for m in stability_maps(one, units)] == [1]


# MJX's vmapped worlds against the same scene run alone: XLA vectorizes the batch's arithmetic differently, so they
# agree to float32 round-off, not bit for bit. Measured over 10 RK4 steps of free_top_fast_spin: 6e-12 (spin 5) and
# 3.0e-7 (spin 50) in a quaternion component, ~3 float32 ulps of 1; this bound is ~30x that. Another world's state
# (another spin) differs by O(1).
VMAP_TOL = 1e-5


@pytest.mark.skipif(not __import__("importlib").util.find_spec("jax"), reason="dalembert[mjx]")
@pytest.mark.long  # MJX compiles the vmapped rollout (~1 min on 2 busy cores; JAX's cache keeps it)
def test_mjx_worlds_are_each_scene_alone_to_float32_roundoff():
    from dalembert import make_case
    from dalembert.adapters import get_adapter

    adapter, settings = get_adapter("mjx"), Settings("rk4", dt=0.05)
    cases = [make_case("free_top_fast_spin", spin=s, **SHORT) for s in (5.0, 20.0, 50.0)]
    batch = adapter.prepare_batch([c.scene for c in cases], cases[0].times, settings)
    out = adapter.run_batch(batch)
    # three worlds stepped as four (padded to a power of two with a copy of the last), three read back
    assert batch.device == "cpu" and len(out.worlds) == 3 and batch.dx0.qpos.shape[0] == 4
    for case, world in zip(cases, out.worlds):
        alone = adapter.run(adapter.prepare(case.scene, case.times, settings)).trajectory
        assert np.max(np.abs(world.trajectory.bodies["top"].quaternion - alone.bodies["top"].quaternion)) < VMAP_TOL


def test_a_dask_task_runs_its_chunk_in_one_process():
    """``execute_group_isolated`` (a Dask task's body, here without a cluster): the chunk's runs in one subprocess,
    their records those of the runs in this process, in order."""
    from dalembert.harness.dask import execute_group_isolated
    from dalembert.harness.truths import built_case
    from dalembert.reference import truth
    from dalembert.store import trajectory_to_npz

    specs, _ = expand(cases=["pivoted_rod"], engines=["reference"], integrators=["rk4"], dts=[1e-2, 5e-3],
                      params={"t_final": 0.5})
    truths = [((s.case, s.case_version), trajectory_to_npz(truth(built_case(s.case, s.params)[0]))) for s in specs[:1]]
    results = execute_group_isolated([s.to_json() for s in specs], vars(QUICK), truths, timeout=600.0)
    assert [r.key for r, _ in results] == [s.key for s in specs]
    for spec, (record, npz) in zip(specs, results):
        alone, _ = execute(spec, QUICK)
        assert record.status == alone.status == "ok" and record.errors == alone.errors and npz is not None


@warp
@pytest.mark.long
def test_a_dask_task_runs_its_batch_in_one_process():
    """``execute_group_isolated`` with ``batched``: the spins of one step as one batch in the task's process."""
    from dalembert.harness.dask import execute_group_isolated

    specs = _specs("mujoco_warp", [5, 50])
    results = execute_group_isolated([s.to_json() for s in specs], vars(QUICK), [], timeout=600.0, batched=True)
    assert [r.key for r, _ in results] == [s.key for s in specs]
    assert [(r.status, r.cost.batch_size) for r, _ in results] == [("ok", 2), ("ok", 2)]
