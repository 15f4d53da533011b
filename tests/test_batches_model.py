"""Batches whose worlds differ in model parameters (``dalembert.adapters.batch``'s ``world_fields``): a swept mass or
inertia shares one engine call where the engine holds the fields it changes per world (MuJoCo Warp's batched
``mjw.Model`` arrays, MJX's vmapped ``Model`` leaves); a parameter that changes the model's structure, or a field
the engine shares, is refused with the reason and its runs go one by one.

The swept parameter is ``heavy_top``'s ``mass`` (15 kg in Terze, Mueller & Zlatar's benchmark; 5 and 40 kg
here): it changes MuJoCo's ``body_mass`` and what the compiler derives from it (``body_subtreemass``,
``body_invweight0``, ``dof_invweight0``), and with it the top's motion (the gravity torque against the inertia
about the pivot, which holds m l^2). ``chain``'s ``n`` (the number of links) is the structural one.
"""

import numpy as np
import pytest

from dalembert.adapters.batch import differing, same_value, world_fields, world_fields_problem
from dalembert.settings import Settings

# A world of a batch against its scene run alone, in the largest difference of any body's quaternion component or
# position (m) over the samples. MuJoCo Warp computes every world by the same kernels, its per-world fields being
# the float32 values ``mjw.put_model`` makes for the world alone: measured bit for bit (0.0) over heavy_top's
# 0.2 s at dt 1e-2, masses 5, 15 and 40 kg. MJX's vmap vectorizes the arithmetic differently: agreement to float32
# round-off (~3 ulps of 1, 3e-7, measured on swept spins: tests/test_batches.py's VMAP_TOL), and this bound is that
# one, ~30x the round-off. Two worlds of different masses differ by 0.25 in a quaternion component at the end, so
# a batch that stepped every world with world 0's mass fails it.
WORLD_TOL = 1e-5
MASSES = (5.0, 15.0, 40.0)


def _cases(name, key, values, **params):
    from dalembert import make_case

    return [make_case(name, **{key: v}, **params) for v in values]


def _largest_difference(a, b):
    """The largest difference of any body's quaternion component or position (m) between trajectories a and b."""
    return max(max(np.max(np.abs(a.bodies[n].quaternion - b.bodies[n].quaternion)),
                   np.max(np.abs(a.bodies[n].position - b.bodies[n].position))) for n in a.bodies)


def test_fields_allowed_per_world_may_differ_and_any_other_is_refused_with_its_name():
    world = {"nbody": 2, "body_mass": np.array([[0.0, 1.0]], np.float32), "body_tree": (np.array([1], np.int32),),
             "dof_length": np.array([1.0], np.float32)}
    heavier = {**world, "body_mass": np.array([[0.0, 2.0]], np.float32)}
    assert world_fields_problem([world, heavier], {"body_mass"}, "engine") is None
    assert differing([world, heavier, world], {"body_mass", "dof_length"}) == ("body_mass",)
    assert differing([world, world], {"body_mass"}) == ()
    shared = world_fields_problem([world, heavier], set(), "engine")
    assert "world 1's model differs from world 0's in body_mass (a field engine shares" in shared
    assert "run without --batch" in shared
    longer = {**world, "nbody": 3, "body_tree": (np.array([1, 2], np.int32),)}
    assert "in nbody (its structure" in world_fields_problem([world, longer], {"body_mass"}, "engine")
    wider = {**world, "body_mass": np.array([[0.0, 1.0, 1.0]], np.float32)}
    assert "has shape (1, 3)" in world_fields_problem([world, wider], {"body_mass"}, "engine")
    assert "other fields" in world_fields_problem([world, {**world, "extra": 1}], {"body_mass"}, "engine")
    assert "at least one world" in world_fields_problem([], {"body_mass"}, "engine")


def test_values_compare_by_shape_type_and_every_element():
    assert same_value(np.array([1.0, np.nan]), np.array([1.0, np.nan]))
    assert not same_value(np.array([1.0]), np.array([1.0, 1.0]))
    assert not same_value(np.array([1], np.int32), np.array([1.0]))
    assert same_value((np.array([1]), 2), (np.array([1]), 2)) and not same_value((np.array([1]),), (np.array([2]),))
    assert not same_value((1, 2), 1) and same_value("a", "a")


def test_an_adapter_without_world_fields_holds_none_per_world():
    from dalembert.adapters import get_adapter

    assert world_fields(get_adapter("reference")) == frozenset()
    assert world_fields(type("Adapter", (), {"world_fields": lambda self: ("body_mass",)})()) == {"body_mass"}


warp = pytest.mark.skipif(not __import__("importlib").util.find_spec("mujoco_warp"), reason="dalembert[mujoco-warp]")



def _each_world_is_its_mass_alone(adapter, settings, cases, batch):
    """Run ``batch`` (one world per case of ``cases``, swept over mass): each world within ``WORLD_TOL`` of its case
    run alone, the lightest and heaviest worlds far apart (a batch that used one mass everywhere fails), and the
    audit naming ``body_mass`` among the fields the batch varied per world."""
    out = adapter.run_batch(batch)
    for case, world in zip(cases, out.worlds):
        alone = adapter.run(adapter.prepare(case.scene, case.times, settings)).trajectory
        assert _largest_difference(world.trajectory, alone) <= WORLD_TOL
    assert _largest_difference(out.worlds[0].trajectory, out.worlds[-1].trajectory) > 100 * WORLD_TOL
    assert "body_mass" in adapter.audit(batch.worlds[0], out.worlds[0])["batch_world_fields"]

@warp
@pytest.mark.long  # Warp's kernels: loaded from its cache, compiled (tens of seconds) from a fresh clone
def test_mujoco_warp_worlds_of_swept_masses_are_each_mass_run_alone():
    from dalembert.adapters import get_adapter

    adapter, settings = get_adapter("mujoco_warp"), Settings("rk4", 1e-2)
    cases = _cases("heavy_top", "mass", MASSES)
    assert adapter.batch_problem([c.scene for c in cases], cases[0].times, settings) is None
    assert {"body_mass", "body_inertia"} <= adapter.world_fields()
    batch = adapter.prepare_batch([c.scene for c in cases], cases[0].times, settings)
    assert "body_mass" in batch.world_fields and batch.mx.body_mass.shape[0] == len(MASSES)
    _each_world_is_its_mass_alone(adapter, settings, cases, batch)


@warp
@pytest.mark.long
def test_mujoco_warp_refuses_a_structural_parameter_and_a_shared_field_from_a_batch():
    """``chain``'s ``n`` changes the number of bodies; ``pendulum``'s ``length`` changes ``dof_length``, which
    MuJoCo Warp shares across worlds. Both are refused with the field's name, and their runs go one by one."""
    from dalembert.adapters import get_adapter
    from dalembert.harness.batches import execute_batch
    from dalembert.harness.execute import QUICK
    from dalembert.harness.matrix import expand

    adapter, settings = get_adapter("mujoco_warp"), Settings("rk4", 1e-2)
    chains = _cases("chain", "n", (2, 3))
    assert "in nq (its structure" in adapter.batch_problem([c.scene for c in chains], None, settings)
    pendulums = _cases("pendulum", "length", (1.0, 2.0))
    assert "in dof_length (a field mujoco_warp shares" in adapter.batch_problem([c.scene for c in pendulums], None,
                                                                                  settings)
    specs, _ = expand(cases=["chain"], engines=["mujoco_warp"], integrators=["rk4"], dts=[0.05],
                      params={"n": [2, 3], "t_final": 0.2, "sample_interval": 0.1})
    records = [r for r, _ in execute_batch(specs, QUICK)]
    assert [r.status for r in records] == ["ok", "ok"] and {r.cost.batch_size for r in records} == {1}
    assert all("in nq (its structure" in r.audit["batch_refused"] for r in records)


@warp
@pytest.mark.long
def test_a_batch_of_masses_makes_each_mass_record_per_world():
    """Through the harness: a swept mass is one batch (before, a refused model), each world's record the run
    alone's status, errors and drifts, its cost the batch's share."""
    from dalembert.harness.batches import execute_batch
    from dalembert.harness.execute import QUICK, execute
    from dalembert.harness.matrix import expand

    specs, _ = expand(cases=["heavy_top"], engines=["mujoco_warp"], integrators=["rk4"], dts=[1e-2],
                      params={"mass": list(MASSES)})
    batch = execute_batch(specs, QUICK)
    assert {r.cost.batch_size for r, _ in batch} == {len(MASSES)}
    for spec, (record, _) in zip(specs, batch):
        alone, _ = execute(spec, QUICK)
        assert record.status == alone.status and record.errors == alone.errors and record.drifts == alone.drifts


@pytest.mark.skipif(not __import__("importlib").util.find_spec("jax"), reason="dalembert[mjx]")
@pytest.mark.long  # MJX compiles the vmapped rollout and each world's alone (~1.5 min on 2 busy cores)
def test_mjx_worlds_of_swept_masses_are_each_mass_alone_to_float32_roundoff():
    """The masses' ``body_mass`` (and what MuJoCo derives from it) vmapped with the state: each world within
    ``WORLD_TOL`` of the mass run alone (measured 3.0e-7, 1.7e-7, 1.9e-7 in a quaternion component), the worlds far
    apart; ``chain``'s ``n`` refused with the static field's name."""
    from dalembert.adapters import get_adapter

    adapter, settings = get_adapter("mjx"), Settings("rk4", 1e-2)
    cases = _cases("heavy_top", "mass", MASSES)
    assert adapter.batch_problem([c.scene for c in cases], None, settings) is None
    assert "in nq (its structure" in adapter.batch_problem([c.scene for c in _cases("chain", "n", (2, 3))], None,
                                                           settings)
    batch = adapter.prepare_batch([c.scene for c in cases], cases[0].times, settings)
    assert "body_mass" in batch.world_fields and batch.rows[1][0].shape[0] == 4  # three worlds padded to four
    _each_world_is_its_mass_alone(adapter, settings, cases, batch)


@warp
@pytest.mark.long
def test_the_runs_table_marks_a_batched_run_s_costs_per_world(tmp_path):
    """``dalembert run --batch`` over swept masses, then ``report``: the case's runs table shows each run's batch and
    its world-steps/s (``BATCH_COLUMNS``) and says its cost is per world; the same runs one by one show neither."""
    from dalembert.harness.cli import main
    from dalembert.reports.render import build_report
    from dalembert.reports.sections.runs import BATCH_COLUMNS
    from dalembert.store import Store

    common = ["run", "--case", "heavy_top", "--param", "mass=5,40", "--engine", "mujoco_warp", "--integrator", "rk4",
              "--dt", "1e-2", "--quick", "--jobs", "1"]
    for name, batched in (("one", False), ("batch", True)):
        out = tmp_path / name
        assert main([*common, *(["--batch"] if batched else []), "--out", str(out)]) == 0
        build_report(Store(str(out)))
        details = open(out / "report_details.md").read()
        runs = details[details.index("### Every run"):]
        assert all((column in runs) == batched for column in BATCH_COLUMNS)
        assert (" per world |" in runs) == batched
