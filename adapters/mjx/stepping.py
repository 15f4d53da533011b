"""MJX's stepping: one compiled rollout per model structure, ``jax.lax.scan`` over the samples.

``rollout(m, d, steps)`` scans over the sample intervals; within interval k a
``fori_loop`` takes ``steps[k]`` MJX steps (a traced count: one compiled
function serves every dt). The jitted function is built once per process and
JAX caches its compilations by the model's structure (array shapes and dtypes,
MJX's static fields such as the joint types and the integrator), so a
prepared model of a structure already seen in this process compiles nothing.
``compile_rollout`` compiles it by calling it once with zero steps (nothing is
stepped); ``run_rollout`` times a call through ``block_until_ready``.

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

__all__ = ["mjx", "precision", "compile_rollout", "run_rollout", "to_host", "PRECISIONS"]

PRECISIONS = ("float32", "float64")


def mjx():
    """``mujoco.mjx``, imported without the lines it prints when MuJoCo Warp is absent (the adapter prints nothing)."""
    with contextlib.redirect_stdout(io.StringIO()):
        from mujoco import mjx as module
    return module


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

        _, (Q, V) = jax.lax.scan(interval, d, steps)
        return Q, V

    return jax.jit(rollout)


def compile_rollout(m, d, steps):
    """Compile the rollout for ``m``, ``d`` and a steps array shaped like ``steps`` (JAX's cache keeps it):
    one call with zero steps per interval, so nothing is stepped. Returns the compile wall time, s."""
    import jax.numpy as jnp

    start = time.perf_counter()
    Q, V = _rollout()(m, d, jnp.zeros_like(steps))
    Q.block_until_ready()
    return time.perf_counter() - start


def run_rollout(m, d, steps):
    """Step from ``d`` through the intervals: ``(Q (n - 1, nq), V (n - 1, nv) device arrays, wall s)``,
    the wall time of the compiled call alone (``block_until_ready``)."""
    start = time.perf_counter()
    Q, V = _rollout()(m, d, steps)
    Q.block_until_ready()
    V.block_until_ready()
    return Q, V, time.perf_counter() - start


def to_host(Q, V, q0, v0):
    """The samples as float64 host arrays ``(n, nq)``, ``(n, nv)`` with the initial state first; NaN from the
    first non-finite sample on (MJX does not stop: a blow-up runs on as inf and NaN)."""
    Q = np.vstack([q0, np.asarray(Q, dtype=float)])
    V = np.vstack([v0, np.asarray(V, dtype=float)])
    bad = ~(np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1))
    if bad.any():
        first = int(np.argmax(bad))
        Q[first:], V[first:] = np.nan, np.nan
    return Q, V
