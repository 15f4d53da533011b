"""MJX's stepping: one compiled rollout per model structure, ``jax.lax.scan`` over the samples.

``rollout(m, d, steps)`` scans over ``CHUNK`` sample intervals; within interval
k a ``fori_loop`` takes ``steps[k]`` MJX steps (a traced count: one compiled
function serves every dt). A run of any length is a sequence of such calls,
its last chunk padded with intervals of zero steps, so the compiled function
does not depend on the number of samples either: one compilation per model
structure (array shapes and dtypes, MJX's static fields such as the joint
types and the integrator) serves every horizon, sample interval and dt. The
jitted function is built once per process and JAX caches its compilations, so
a prepared model of a structure already seen in this process compiles
nothing. A batch of worlds (``dalembert.adapters.batch``) runs the same rollout under ``jax.vmap``
over the state (the model shared), compiled once per structure and batch size; where the worlds' models
differ in some of the model's JAX arrays (``traced_fields``: a swept mass changes ``body_mass`` and what
MuJoCo derives from it), those leaves are vmapped too, one row per world (``varying``), the rest shared. ``compile_rollout`` compiles it by calling it once with zero steps
(nothing is stepped); ``run_rollout`` times the calls through
``block_until_ready``.

Device (option ``device``): JAX's CPU backend, or its first GPU where JAX has one; the model, the initial state
and the steps are put on it (MJX's JAX implementation named: on a GPU, MJX may pick its Warp one by default), and
the compiled rollout runs where its arguments are.

Precision: float32 (JAX's default, MJX's) or float64 (``jax_enable_x64``),
switched per call with ``jax.enable_x64`` so runs of both precisions can share a
worker process; each precision compiles its own rollout. JAX 0.10's caches do
not keep the two apart everywhere (measured: after a float32 RK4 rollout, the
float64 one fails to lower — an inner ``jit(tril)`` reused with float32
operands), so JAX's caches are cleared whenever a process switches precision.

Compilations persist across processes in JAX's compilation cache, under
``dalembert.cache.cache_dir("jax")`` unless JAX is given its own
(``JAX_COMPILATION_CACHE_DIR``): the workers of a matrix, and later matrices,
load a model's rollout instead of compiling it again (measured: ``prepare`` of
``free_top`` in float64, 9-11 s compiling, 3.6 s from the cache). JAX keys an
entry by the lowered computation, the compile options and the JAX and XLA
versions, so what is loaded is the executable a compilation would make.
"""

from __future__ import annotations

import contextlib
import functools
import io
import time

import numpy as np

__all__ = ["mjx", "precision", "device_problem", "jax_device", "device_name", "chunks", "compile_rollout",
           "run_rollout", "stack", "to_host", "traced_fields", "model_fields", "varying", "PRECISIONS", "DEVICES",
           "CHUNK"]

PRECISIONS = ("float32", "float64")
# Option ``device``: JAX's CPU backend (the default: every stored MJX number is from it) or its first GPU.
DEVICES = ("cpu", "gpu")
# Sample intervals per compiled call. A call costs ~1.5 ms beyond its steps (measured on 2 cores: free_top,
# RK4, 16 to 1024 intervals of zero steps, 1.3-2.0 ms a call) and a padded interval ~1 us, against >= 20 us
# for an MJX step: 1024 keeps every default-horizon run in one call (free_top: 1000 intervals) and adds
# < 1.5 ms per 1024 steps (< 7 %) to the longest ones.
CHUNK = 1024


def mjx():
    """``mujoco.mjx``, imported without the lines it prints when MuJoCo Warp is absent (the adapter prints nothing)."""
    with contextlib.redirect_stdout(io.StringIO()):
        from mujoco import mjx as module
    return module


def device_problem(name):
    """Why JAX cannot step on device ``name`` (one of ``DEVICES``) in this process, in the project's words, or
    None. ``cpu`` asks nothing; ``gpu`` imports JAX (a worker's, never the harness's main process) to find out."""
    if name == "cpu":
        return None
    import jax

    try:
        jax.devices(name)
    except RuntimeError:
        return (f"options.device: no GPU here (JAX found none: its backend is {jax.default_backend()}) — run with "
                f"device=cpu, or on a machine with a GPU and JAX's CUDA build (jax[cuda12])")
    return None


def jax_device(name):
    """The JAX device of option ``device`` ``name``: JAX's first device of that platform (``device_problem``
    first). Named even for ``cpu``: MJX puts a model given no device on JAX's first device, which is a GPU
    wherever JAX has one, so the CPU default would not be the CPU there."""
    import jax

    return jax.devices(name)[0]


def device_name(device):
    """Where a run on ``device`` (``jax_device``'s) steps, as the record stores it: ``cpu``, or the device's
    platform and index (``gpu:0``)."""
    return "cpu" if device.platform == "cpu" else f"{device.platform}:{device.id}"


_LAST_PRECISION = []  # the precision this process compiled for last


def precision(name):
    """Context manager: JAX's 64-bit mode on for ``"float64"``, off for ``"float32"`` (JAX's caches
    cleared first when the last compilation in this process was for the other one)."""
    import jax

    if _LAST_PRECISION and _LAST_PRECISION[-1] != name:
        jax.clear_caches()
    _LAST_PRECISION[:] = [name]
    return jax.enable_x64(name == "float64")


@functools.cache
def _rollout():
    """The rollout, jitted (one world)."""
    import jax

    return jax.jit(_rollout_fn())


@functools.cache
def _batch_rollout():
    """The rollout over a batch of worlds: ``jax.vmap`` over the state's leading axis (the model shared), jitted;
    its samples ``(nworld, CHUNK, nq)``."""
    import jax

    return jax.jit(jax.vmap(_rollout_fn(), in_axes=(None, 0, None)))


@functools.lru_cache(maxsize=16)
def _varying_rollout(positions):
    """The rollout over a batch of worlds whose models differ in the leaves at ``positions`` (indices into
    ``jax.tree.flatten`` of the model, ``varying``): ``jax.vmap`` over those leaves' rows and the state, the rest
    of the model shared, jitted; called as ``(rows, m, d, steps)``."""
    import jax

    rollout = _rollout_fn()

    def world(rows, m, d, steps):
        leaves, treedef = jax.tree.flatten(m)
        for i, row in zip(positions, rows):
            leaves[i] = row
        return rollout(jax.tree.unflatten(treedef, leaves), d, steps)

    return jax.jit(jax.vmap(world, in_axes=(0, None, 0, None)))


def _batched(rows):
    """The batch rollout, as ``(m, d, steps)``: over the state alone, or with the per-world leaves ``rows``
    (``varying``'s ``(positions, arrays)``)."""
    if not rows:
        return _batch_rollout()
    return functools.partial(_varying_rollout(rows[0]), rows[1])


@functools.cache
def traced_fields():
    """The ``mjx.Model`` fields that are JAX arrays (the model's pytree leaves, which a vmap can give a row per
    world), nested ones as ``opt.timestep``, ``stat.meaninertia``: a frozenset of names (from ``mjx.Model``'s
    annotations: its NumPy arrays and numbers are static, its structure)."""
    import dataclasses
    import typing

    import jax

    mjx()
    from mujoco.mjx._src import types

    def walk(cls, prefix):
        for f in dataclasses.fields(cls):
            kinds = typing.get_args(f.type) if typing.get_origin(f.type) is typing.Union else (f.type,)
            for t in kinds:
                if t is jax.Array:
                    yield prefix + f.name
                elif dataclasses.is_dataclass(t):
                    yield from walk(t, f"{prefix}{f.name}.")

    return frozenset(walk(types.Model, ""))


def model_fields(mx):
    """The fields of the device model ``mx`` as host values (``adapters.batch.model_fields``): NumPy arrays (a
    JAX array's copy), arrays, numbers, enums or bytes."""
    import jax

    from dalembert.adapters.batch import model_fields as fields

    return fields(mx, lambda v: np.asarray(v) if isinstance(v, jax.Array) else v)


def varying(models, names):
    """The per-world leaves of a batch whose device models are ``models`` (one per world, one structure), the
    fields ``names`` (``traced_fields``) differing between them: ``(positions, arrays)``, positions the leaves'
    indices in ``jax.tree.flatten`` of a model, each array the worlds' values stacked on a leading axis; ``()``
    without ``names``."""
    import jax
    import jax.numpy as jnp

    if not names:
        return ()
    paths = [".".join(k.name for k in path) for path, _ in jax.tree_util.tree_flatten_with_path(models[0])[0]]
    positions = tuple(paths.index(n) for n in names)
    per_world = [jax.tree.leaves(m) for m in models]
    return positions, tuple(jnp.stack([leaves[i] for leaves in per_world]) for i in positions)


@functools.cache
def _rollout_fn():
    import jax

    from dalembert.cache import cache_dir

    if not jax.config.jax_compilation_cache_dir:
        jax.config.update("jax_compilation_cache_dir", cache_dir("jax"))
    step = mjx().step

    def same_types(new, old):
        # MJX 3.17 in float64 returns a tendon's wrap indices (ten_wrapadr, ten_wrapnum, wrap_obj) as int64
        # where mjx.put_data made them int32; the loop's carry must keep its types (a model without tendons has
        # none to cast: every astype is then the identity)
        return jax.tree.map(lambda a, b: a.astype(b.dtype) if a.dtype != b.dtype else a, new, old)

    def rollout(m, d, steps):
        def interval(d, n):
            d = jax.lax.fori_loop(0, n, lambda i, d: same_types(step(m, d), d), d)
            return d, (d.qpos, d.qvel)

        d, (Q, V) = jax.lax.scan(interval, d, steps)
        return d, Q, V

    return rollout


def chunks(steps):
    """MJX steps per sample interval ``steps`` ((n - 1,) ints) as ``CHUNK``-long int32 host arrays, the last
    padded with zeros (at least one chunk)."""
    steps = np.asarray(steps, dtype=np.int32)
    padded = np.zeros(max(1, -(-len(steps) // CHUNK)) * CHUNK, dtype=np.int32)
    padded[:len(steps)] = steps
    return [padded[i:i + CHUNK] for i in range(0, len(padded), CHUNK)]


def compile_rollout(m, d, batched=False, rows=()):
    """Compile the rollout for ``m`` and ``d`` (JAX's cache keeps it): one call with zero steps per
    interval, so nothing is stepped. ``batched``: ``d`` is a batch of worlds (``stack``), ``rows`` the model's
    per-world leaves (``varying``). Returns the compile wall time, s.

    The zeros are put on the state's device, as the run's steps are (``jax.device_put``): JAX keys a compiled
    function by its arguments' placement too, and host zeros compiled another executable than the run's (measured:
    each run lowered the rollout again and loaded it from the cache, 0.2-0.7 s inside its stepping wall)."""
    import jax

    zeros = jax.device_put(np.zeros(CHUNK, dtype=np.int32), next(iter(jax.tree.leaves(d)[0].devices())))
    start = time.perf_counter()
    _, Q, V = (_batched(rows) if batched else _rollout())(m, d, zeros)
    Q.block_until_ready()
    return time.perf_counter() - start


def run_rollout(m, d, steps, batched=False, rows=()):
    """Step from ``d`` through the intervals, ``steps`` from ``chunks``: ``(Q, V, wall s)``, ``Q`` and ``V``
    lists of ``(CHUNK, nq)`` and ``(CHUNK, nv)`` device arrays, one per chunk (``batched``: ``d`` a batch of
    worlds, the arrays ``(nworld, CHUNK, nq)``, ``rows`` the model's per-world leaves: ``varying``); the wall
    time of the compiled calls alone (each call waits for the state of the one before it;
    ``block_until_ready`` on the last)."""
    rollout, Q, V = _batched(rows) if batched else _rollout(), [], []
    start = time.perf_counter()
    for chunk in steps:
        d, q, v = rollout(m, d, chunk)
        Q.append(q)
        V.append(v)
    Q[-1].block_until_ready()
    V[-1].block_until_ready()
    return Q, V, time.perf_counter() - start


def stack(states):
    """One ``mjx.Data`` of a batch of worlds from one per world (each leaf stacked on a new leading axis)."""
    import jax
    import jax.numpy as jnp

    return jax.tree.map(lambda *leaves: jnp.stack(leaves), *states)


def to_host(Q, V, q0, v0, n):
    """The ``n`` samples as float64 host arrays ``(n, nq)``, ``(n, nv)`` with the initial state first (``Q``,
    ``V`` from ``run_rollout``, padding dropped); NaN from the first non-finite sample on (MJX does not stop:
    a blow-up runs on as inf and NaN)."""
    Q = np.vstack([q0, *(np.asarray(q, dtype=float) for q in Q)])[:n]
    V = np.vstack([v0, *(np.asarray(v, dtype=float) for v in V)])[:n]
    bad = ~(np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1))
    if bad.any():
        first = int(np.argmax(bad))
        Q[first:], V[first:] = np.nan, np.nan
    return Q, V
