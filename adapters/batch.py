"""Batched worlds: one engine call steps several worlds of one model at once.

A batch is a list of scenes that share one engine model (the same bodies, joints and settings) and
differ in their initial state: copies of a case with perturbed initial conditions, or a case swept over
a parameter that enters its initial state only (``free_top_fast_spin``'s ``spin``). Where the engine
holds some of its model's fields per world, the worlds may also differ in those: a swept mass, inertia
or length (``heavy_top``'s ``mass``) changes numbers of the model, not its structure, and MuJoCo Warp
(batched ``Model`` arrays) and MJX (``jax.vmap`` over the ``Model``'s leaves) step such worlds in one
call. A parameter that changes the model's structure (``chain``'s ``n``: the number of bodies) or a
field the engine shares across worlds is refused from a batch with the reason. Engines written for
accelerators (MuJoCo Warp's ``nworld``, MJX under ``jax.vmap``) step such a batch in about the calls of
one world, so timing them one world at a time is unfair to them.

An adapter that has batches (``has_batches``) defines, beside the contract's methods
(``dalembert.adapters``, items 5-8):

``batch_problem(scenes, times, settings)``
    Why these scenes cannot share one engine call (their models differ where the engine shares them, an
    option that contradicts a batch), or None; cheap, called before anything runs. ``same_model`` words
    the usual reason for an engine whose worlds share every model field, ``world_fields_problem`` for
    one that holds some per world.
``prepare_batch(scenes, times, settings)``
    Builds the model once and every world's initial state (not timed); returns a ``BatchPrepared``
    whose ``worlds`` holds one ``Prepared`` per scene, as ``prepare`` would have built it for that
    scene alone (what ``audit`` and the read-back take).
``run_batch(prepared)``
    Steps every world at once from its initial state, sampled at exactly ``times``, and returns a
    ``BatchOutcome``: the batch's stepping wall time and one ``Outcome`` per world (its read-back,
    steps and right-hand sides; a world that diverges is NaN from there on, as in ``run``, while the
    others go on). Repeated calls give identical results, as ``run``'s.

and may define

``world_fields()``
    The names of its engine model's fields that it holds per world (a frozenset; ``world_fields`` below
    reads it, an empty set where the adapter does not define it: every world then shares the model).
    ``batch_problem`` allows the worlds' models to differ in these fields only (``world_fields_problem``),
    and ``prepare_batch`` gives each world its own values of them.

The harness (``dalembert.harness.batches``) times ``run_batch`` as it times ``run``, audits world k with
``audit(prepared.worlds[k], outcome.worlds[k])`` and stores one record per world, its cost per world
(``dalembert.record.Cost``: the batch's size, wall time, throughput and device beside the world's share).

Every world of a batch steps in lock-step with one step ``dt`` (none of the engines here takes a step
per world), so probes of different steps never share a batch: a stability map batches across the
swept parameter at one step (``dalembert.harness.search``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

__all__ = ["BatchPrepared", "BatchOutcome", "has_batches", "same_model", "world_fields", "world_fields_problem",
           "model_fields", "keep_sample",
           "differing", "same_value", "MAX_BATCH"]

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


def world_fields(adapter):
    """The names of the engine model's fields ``adapter`` holds per world (its ``world_fields()``, module
    docstring); an empty frozenset where it holds none (its worlds share one model: ``same_model``)."""
    fields = getattr(adapter, "world_fields", None)
    return frozenset(fields()) if callable(fields) else frozenset()


def world_fields_problem(models, per_world, engine):
    """Why worlds whose engine models are ``models`` cannot share one engine call when the fields ``per_world``
    may differ between them, or None; with None, the fields that do differ (``differing``) are the caller's to
    hold per world.

    Parameters
    ----------
    models : sequence of mapping — one per world: the engine model's field name -> value (arrays, numbers,
        tuples, strings), every world's with the same names (a world with other names differs in structure)
    per_world : collection of str — the fields the engine holds per world
    engine : str — names the engine in the reason

    Returns
    -------
    str or None — "engine: world k's model differs from world 0's in FIELD ... — the fix"
    """
    if not models or len(models) > MAX_BATCH:
        return same_model(models, engine)
    first = models[0]
    for k, model in enumerate(models[1:], 1):
        if set(model) != set(first):
            return (f"{engine}: world {k}'s model has other fields than world 0's (another structure) — run "
                    "without --batch")
        for name, value in model.items():
            if name not in per_world and not same_value(value, first[name]):
                why = ("its structure: the bodies, joints, sizes a parameter changes"
                       if _structural(value) else f"a field {engine} shares across the worlds of a batch")
                return (f"{engine}: world {k}'s model differs from world 0's in {name} ({why}) — sweep a parameter "
                        "of the initial state or one the engine holds per world, or run without --batch")
            if name in per_world and np.shape(value) != np.shape(first[name]):
                return (f"{engine}: world {k}'s {name} has shape {np.shape(value)}, world 0's {np.shape(first[name])} "
                        "(another structure) — run without --batch")
    return None


def differing(models, per_world):
    """The names of the fields in ``per_world`` whose value differs between ``models`` (``world_fields_problem``'s
    mappings), sorted."""
    return tuple(sorted(n for n in per_world if n in models[0]
                        and any(not same_value(m[n], models[0][n]) for m in models[1:])))


def same_value(a, b):
    """Whether two values of a model field are equal: arrays by shape and every element (NaN equal to NaN),
    tuples and lists element by element, anything else by ``==``."""
    if isinstance(a, (tuple, list)) or isinstance(b, (tuple, list)):
        return (isinstance(a, (tuple, list)) and isinstance(b, (tuple, list)) and len(a) == len(b)
                and all(same_value(x, y) for x, y in zip(a, b)))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and a.dtype == b.dtype and bool(
            np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))
    return bool(a == b)


def _structural(value):
    """Whether a field's value describes structure (integers: sizes, indices, types), not numbers of the model."""
    if isinstance(value, (tuple, list)):
        return all(_structural(v) for v in value)
    return np.asarray(value).dtype.kind in "iub"


def model_fields(model, host):
    """The fields of an engine's device model (a dataclass) as host values, for ``world_fields_problem``:
    field name -> ``host(value)``; a nested dataclass's fields (``opt``, ``stat``) as ``opt.timestep`` and so on.
    ``host``: the engine's copy of one of its arrays to the host (a number, tuple or text as it is)."""
    out = {}
    for f in dataclasses.fields(model):
        v = getattr(model, f.name)
        if dataclasses.is_dataclass(v) and not isinstance(v, type):
            out.update({f"{f.name}.{k}": x for k, x in model_fields(v, host).items()})
        else:
            out[f.name] = host(v)
    return out


def keep_sample(Q, V, bad, k, q, v, finite):
    """Sample ``k`` of a batch stepped world by world in lockstep: each world's state ``q``, ``v`` (worlds first) kept
    in ``Q[k]``, ``V[k]`` while it is ``finite`` (bool per world); a world's first non-finite sample goes into ``bad``
    (0: none yet) and the world keeps no later sample. Returns whether any world is still finite (else stop)."""
    bad[(bad == 0) & ~finite] = k
    good = bad == 0
    Q[k, good], V[k, good] = q[good], v[good]
    return bool(good.any())
