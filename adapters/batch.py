"""Batched worlds: one engine call steps several worlds of one model at once.

A batch is a list of scenes that share one engine model (the same bodies, joints, parameters and
settings) and differ only in their initial state: copies of a case with perturbed initial conditions,
or a case swept over a parameter that enters its initial state only (``free_top_fast_spin``'s
``spin``). Engines written for accelerators (MuJoCo Warp's ``nworld``, MJX under ``jax.vmap``) step
such a batch in about the calls of one world, so timing them one world at a time is unfair to them.

An adapter that has batches (``has_batches``) defines, beside the contract's methods
(``dalembert.adapters``, items 5-8):

``batch_problem(scenes, times, settings)``
    Why these scenes cannot share one engine call (their models differ, an option that contradicts a
    batch), or None; cheap, called before anything runs. ``same_model`` words the usual reason.
``prepare_batch(scenes, times, settings)``
    Builds the model once and every world's initial state (not timed); returns a ``BatchPrepared``
    whose ``worlds`` holds one ``Prepared`` per scene, as ``prepare`` would have built it for that
    scene alone (what ``audit`` and the read-back take).
``run_batch(prepared)``
    Steps every world at once from its initial state, sampled at exactly ``times``, and returns a
    ``BatchOutcome``: the batch's stepping wall time and one ``Outcome`` per world (its read-back,
    steps and right-hand sides; a world that diverges is NaN from there on, as in ``run``, while the
    others go on). Repeated calls give identical results, as ``run``'s.

The harness (``dalembert.harness.batches``) times ``run_batch`` as it times ``run``, audits world k with
``audit(prepared.worlds[k], outcome.worlds[k])`` and stores one record per world, its cost per world
(``dalembert.record.Cost``: the batch's size, wall time, throughput and device beside the world's share).

Every world of a batch steps in lock-step with one step ``dt`` (none of the engines here takes a step
per world), so probes of different steps never share a batch: a stability map batches across the
swept parameter at one step (``dalembert.harness.search``).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BatchPrepared", "BatchOutcome", "has_batches", "same_model", "MAX_BATCH"]

# The most worlds one batch may hold: MuJoCo Warp's and MJX's per-world arrays are ~MBs per thousand worlds for
# the cases here; a larger batch is a typo more often than a plan (the same bound as MuJoCo Warp's ``worlds``).
MAX_BATCH = 4096


@dataclass(frozen=True, eq=False)
class BatchPrepared:
    """What ``prepare_batch`` returns and ``run_batch`` takes; each engine extends it with its model.

    Attributes
    ----------
    worlds : tuple of Prepared — one per scene, in the order given, as ``prepare`` builds it for that scene
    device : str — where the batch steps (``cpu``, ``cuda:0``)
    """

    worlds: tuple
    device: str


@dataclass(frozen=True, eq=False)
class BatchOutcome:
    """What ``run_batch`` returns.

    Attributes
    ----------
    wall_s : float — the stepping wall time of the whole batch (every world), s
    worlds : tuple of Outcome — one per world, in the batch's order; each one's ``wall_s`` is the batch's
        (the worlds were not stepped apart), its ``n_steps`` and ``n_rhs`` its own (a world that diverged
        counts the steps up to its first non-finite sample)
    """

    wall_s: float
    worlds: tuple


def has_batches(adapter):
    """Whether ``adapter`` steps batches of worlds (defines ``batch_problem``, ``prepare_batch`` and
    ``run_batch``: module docstring)."""
    return all(callable(getattr(adapter, m, None)) for m in ("batch_problem", "prepare_batch", "run_batch"))


def same_model(models, engine):
    """Why the worlds whose engine models are ``models`` (one text per world, e.g. each scene's MJCF) cannot share
    one engine call, or None when every model is the first's and there are at most ``MAX_BATCH``."""
    if not models:
        return f"{engine}: a batch needs at least one world"
    if len(models) > MAX_BATCH:
        return f"{engine}: {len(models)} worlds in one batch, more than {MAX_BATCH} — split the sweep"
    other = next((k for k, m in enumerate(models) if m != models[0]), None)
    if other is not None:
        return (f"{engine}: world {other}'s model differs from world 0's (a batch shares one model; its worlds "
                "may differ in their initial state only) — sweep a parameter of the initial state, or run "
                "without --batch")
    return None
