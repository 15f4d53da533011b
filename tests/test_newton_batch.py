"""Newton's batches (``dalembert.adapters.batch`` on ``NewtonAdapter``): N copies of a case in one Newton model
(``ModelBuilder.replicate``), each world started from its own scene's initial state, stepped by one solver call a
step; each world's result is the run alone's, a diverged world does not stop the others.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter
from dalembert.adapters.batch import has_batches
from installed import needs

# Newton's kernels: loaded from Warp's cache, compiled from a fresh clone
pytestmark = [needs("newton", reason="Newton is not installed: pip install dalembert[newton]"), pytest.mark.long]

ADAPTER = get_adapter("newton")
# A batch's world and the run alone are bit for bit the same: Newton's worlds share no data, and each world's
# kernels run the same float32 operations in the same order whatever the number of worlds (measured on Warp's
# CPU backend for every family here, 4 worlds of free_top over 0.2 s). So parity is equality, not a tolerance.
FAMILIES = ("featherstone", "semi_implicit", "xpbd", "vbd", "steel")
TIMES = np.linspace(0.0, 0.2, 5)
DT = 1e-3


def _spun(scene, factor):
    """``scene`` (one free joint) with its initial velocities scaled by ``factor``: a perturbed initial state."""
    j = scene.joints[0]
    return replace(scene, joints=(replace(j, v0=tuple(float(v) * factor for v in j.v0)),))


@pytest.fixture(scope="module")
def tops():
    scene = make_case("free_top").scene
    return [_spun(scene, 1.0 + 0.01 * k) for k in range(4)]


def test_newton_has_batches():
    assert has_batches(ADAPTER)


@pytest.mark.parametrize("family", FAMILIES)
def test_each_world_is_the_run_alone(tops, family):
    """Four perturbed tops in one call: each world's trajectory equals its run alone's, and the worlds differ."""
    settings = Settings(family, dt=DT)
    assert ADAPTER.batch_problem(tops, TIMES, settings) is None
    batch = ADAPTER.prepare_batch(tops, TIMES, settings)
    out = ADAPTER.run_batch(batch)
    assert len(out.worlds) == 4 and all(w.wall_s == out.wall_s for w in out.worlds)
    for scene, world in zip(tops, out.worlds):
        alone = ADAPTER.run(ADAPTER.prepare(scene, TIMES, settings))
        a, b = world.trajectory.bodies["top"], alone.trajectory.bodies["top"]
        assert np.array_equal(a.quaternion, b.quaternion) and np.array_equal(a.angular_velocity, b.angular_velocity)
        assert world.n_steps == alone.n_steps == 200
    w0, w3 = (out.worlds[k].trajectory.bodies["top"].angular_velocity for k in (0, 3))
    assert not np.allclose(w0[-1], w3[-1])  # the perturbation reached the engine
    audit = ADAPTER.audit(batch.worlds[2], out.worlds[2])
    assert (audit["worlds"], audit["bodies"], audit["joint_dofs"]) == (4, 1, 6)


def test_a_diverged_world_leaves_the_others_going(tops):
    """World 1 spun at 1e19 rad/s overflows float32 (its kinetic energy's 1e38 terms): NaN from its first bad sample,
    the run's message names it; worlds 0 and 2 finish as alone."""
    settings = Settings("featherstone", dt=DT)
    scenes = [tops[0], _spun(tops[0], 2e18), tops[2]]
    out = ADAPTER.run_batch(ADAPTER.prepare_batch(scenes, TIMES, settings))
    bad = out.worlds[1]
    assert "non-finite state" in bad.info["message"] and bad.n_steps < 200
    assert np.isnan(bad.trajectory.bodies["top"].quaternion[-1]).all()
    for k in (0, 2):
        alone = ADAPTER.run(ADAPTER.prepare(scenes[k], TIMES, settings))
        assert out.worlds[k].info["message"] == "" and out.worlds[k].n_steps == 200
        assert np.array_equal(out.worlds[k].trajectory.bodies["top"].quaternion,
                              alone.trajectory.bodies["top"].quaternion)


def test_worlds_of_different_models_are_refused(tops):
    """A batch shares one model: a world whose body differs (mass) is refused, naming it; initial states may differ."""
    heavier = replace(tops[0], bodies=(replace(tops[0].bodies[0], mass=2.0),))
    why = ADAPTER.batch_problem([tops[0], heavier], TIMES, Settings("featherstone", dt=DT))
    assert "world 1's model differs" in why
    assert ADAPTER.batch_problem(tops, TIMES, Settings("featherstone", dt=DT)) is None


def test_dalembert_run_batch_stores_one_record_per_world(tmp_path):
    """``dalembert run --batch`` over ``free_top_fast_spin``'s spin: one engine call, a record per world with the
    batch's size, each the run alone's errors."""
    from dalembert.harness.cli import main
    from dalembert.store import Store

    common = ["run", "--case", "free_top_fast_spin", "--param", "spin=5,50,500", "--param", "t_final=0.2",
              "--param", "sample_interval=0.1", "--engine", "newton", "--integrator", "featherstone", "--dt", "1e-3",
              "--quick", "--jobs", "1"]
    assert main([*common, "--batch", "--out", str(tmp_path / "batch")]) == 0
    assert main([*common, "--out", str(tmp_path / "one")]) == 0
    batch = {r.key: r for r in Store(str(tmp_path / "batch")).records()}
    one = {r.key: r for r in Store(str(tmp_path / "one")).records()}
    assert sorted(batch) == sorted(one) and len(batch) == 3
    for key, r in batch.items():
        assert r.cost.batch_size == 3 and one[key].cost.batch_size == 1
        assert r.status == one[key].status and r.errors == one[key].errors, key


def test_a_collapsed_quaternion_ends_a_world():
    """``free_top_fast_spin`` at dt 0.1 s: Featherstone's quaternion collapses to zero (at ~1e26 rad/s) a sample
    before it turns NaN, a state with finite bodies and no attitude. It ends the world there (its joints NaN from
    then on), so a world whose last sample is such a state is never finite bodies with NaN joints; as the run alone."""
    spins = (199.05358527674863, 270.58476327323183, 500.0)
    cases = [make_case("free_top_fast_spin", spin=s, t_final=1.0, sample_interval=0.1) for s in spins]
    settings = Settings("featherstone", dt=0.1)
    out = ADAPTER.run_batch(ADAPTER.prepare_batch([c.scene for c in cases], cases[0].times, settings))
    for case, world in zip(cases, out.worlds):
        traj = world.trajectory
        assert traj.is_finite() or traj.first_nonfinite_time() is not None, case.params
        alone = ADAPTER.run(ADAPTER.prepare(case.scene, case.times, settings)).trajectory
        assert np.array_equal(traj.joints["top"].v, alone.joints["top"].v, equal_nan=True)
    assert not out.worlds[2].trajectory.is_finite()
