"""MuJoCo Warp's stepping on a Warp device: the model and state put on the device, ``mjw.step`` per step.

Warp compiles each kernel module on its first launch in a process and keeps the
compiled code on disk (Warp's kernel cache, keyed by the kernel's source, its
options and Warp's version, so a stale entry is never loaded). The cache is put
under ``dalembert.cache.cache_dir("warp")`` unless Warp is given its own
(``WARP_CACHE_PATH``), so the workers of a matrix, later matrices and a fresh
clone's second run load instead of compiling. Measured on 2 shared cores (load
~3), one ``mjw.step`` of the pendulum in RK4 in a fresh process: 18.6 s with an
empty cache, 0.12 s from the cache (41 s for the adapter's first ``prepare`` at a
load of ~9). ``compile_step`` takes that first step
on a scratch copy of the state, so a run's timed loop never compiles.

There are no CUDA graphs on the CPU: every ``mjw.step`` launches its kernels
one by one from Python (~70 launches a semi-implicit Euler step, most of its
time Warp's argument packing: cProfile), so a step of the pendulum costs ~1.4 ms
(Euler) to ~4.5 ms (RK4) on 2 cores at a load of ~3, little of it arithmetic. MuJoCo Warp has no warning
counters and no auto-reset: a blow-up runs on as inf and NaN, so the loop
checks each sample and stops at the first non-finite one.

A ``mjw.Data`` holds ``nworld`` worlds; each kernel launch covers them all, so a batch costs about the launches
of one world plus the arithmetic of each (``benchmarks.mujoco_warp worlds``). The worlds may differ in the
``mjw.Model`` fields MuJoCo Warp batches (``batched_fields``: those whose spec's leading axis is ``*``, e.g.
``body_mass`` and ``body_inertia``): ``mjw.put_model`` gives such a field a leading axis of ``nworld`` instead of
1 (its ``batch_sizes``), and every kernel reads world w's row (``worlds_model``).

The number type is float32: MuJoCo Warp's kernels are written in it (``wp.float32``
fields throughout ``mujoco_warp._src.types``); there is no float64 build.
"""

from __future__ import annotations

import copy
import functools
import time

import numpy as np

from dalembert.adapters.batch import keep_sample

__all__ = ["warp", "device_model", "batched_fields", "model_fields", "worlds_model", "sizes", "put_state", "put_worlds",
           "compile_step", "step_samples", "step_worlds", "DEVICE", "NCONMAX"]

DEVICE = "cpu"  # Warp's CPU backend, the default (option ``device``: ``warp_runtime.DEVICES``)
# Contacts allocated per world: MuJoCo Warp's own default for a model without height fields, flexes or SDFs (45,
# rounded up to its size 48); the contact cases here touch at most 4 points at once (a box on a plane).
NCONMAX = 48


@functools.cache
def warp():
    """``(warp, mujoco_warp, init message)``: Warp initialized once per process on its kernel cache, its log
    quiet (``adapters.warp_runtime.init``); the message is what Warp's native code printed on stderr at init (on a
    machine without a GPU: that no CUDA driver was found), kept for the audit instead of printed."""
    from dalembert.adapters.warp_runtime import init

    wp, message = init()
    import mujoco_warp as mjw

    return wp, mjw, message


def device_model(model, device=DEVICE, batch_sizes=None):
    """``mjw.put_model`` of a copy of MuJoCo C's ``model`` with the auto-reset flag cleared: the MJCF disables
    MuJoCo C's auto-reset (a bad state must show, not restart), MuJoCo Warp has none to disable and refuses the
    flag; the copy keeps the compiled model the read-back and audit read unchanged. ``device``: Warp's device
    name (``cpu``, ``cuda:0``); ``batch_sizes``: field name -> the leading size of that batched field
    (``mjw.put_model``'s; ``worlds_model``)."""
    import mujoco

    wp, mjw, _ = warp()
    m = copy.copy(model)
    m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
    with wp.ScopedDevice(device):
        return mjw.put_model(m, batch_sizes=batch_sizes)


@functools.cache
def batched_fields():
    """The ``mjw.Model`` fields MuJoCo Warp can hold per world: its array fields whose spec's leading axis is
    ``*`` (``mjw.put_model``'s ``batch_sizes`` accepts those alone), a frozenset of names."""
    import dataclasses

    warp()
    from mujoco_warp._src import types, warp_util

    return frozenset(f.name for f in dataclasses.fields(types.Model)
                     if warp_util.is_array_spec(f.type) and tuple(getattr(f.type, "shape", ()))[:1] == ("*",))


def model_fields(mx):
    """The fields of the device model ``mx`` as host values (``adapters.batch.model_fields``): numpy arrays
    (a Warp array's copy), tuples, numbers or text."""
    from dalembert.adapters.batch import model_fields as fields

    wp, _, _ = warp()

    def host(v):
        if isinstance(v, wp.array):
            return v.numpy()
        if isinstance(v, (tuple, list)):
            return tuple(host(x) for x in v)
        return v

    return fields(mx, host)


def worlds_model(models, names, device=DEVICE):
    """One device model of the worlds whose MuJoCo C models are ``models`` (one per world, every one the same
    structure: ``adapters.batch.world_fields_problem``), the batched fields ``names`` (``batched_fields``) given a
    leading axis of one row per world, each row that world's own ``mjw.put_model`` value (the same float32
    conversion as the world run alone); every other field world 0's."""
    wp, _, _ = warp()
    mx = device_model(models[0], device, {n: len(models) for n in names})
    if names:
        alone = [model_fields(device_model(m, DEVICE)) for m in models]
        with wp.ScopedDevice(device):
            for n in names:
                getattr(mx, n).assign(np.concatenate([a[n] for a in alone]))
    return mx


def sizes(model, data):
    """``(nconmax, njmax)``: the contacts and constraint rows a world holds. MuJoCo Warp's default njmax (53, for
    contacts) is short of a model's equality constraints (the welded particle box: 26 welds, 156 rows), and a
    world past it drops rows with a printed warning only, so njmax is the rows MuJoCo C finds at the initial state
    (``data`` after ``mj_forward``: equalities, and any contact there) plus every allocated contact at the
    model's largest condim (pyramidal: 2 (condim - 1) rows, elliptic: condim)."""
    import mujoco

    if model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT):
        return NCONMAX, max(int(data.nefc), 1)
    condim = max([1, *model.geom_condim.tolist(), *model.pair_dim.tolist()])
    rows = condim if model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC else max(1, 2 * (condim - 1))
    return NCONMAX, int(data.nefc) + NCONMAX * rows


def put_state(model, qpos, qvel, ctrl, nworld=1, dv=0.0, device=DEVICE):
    """A device ``mjw.Data`` of ``nworld`` worlds at ``qpos (nq,)``, ``qvel (nv,)`` with ``ctrl`` (None, or
    the actuators' constant control), its contact and constraint arrays sized by ``sizes``. World k's velocity is
    ``qvel + k dv`` in every coordinate (m/s, rad/s): world 0 is the given state. ``device``: Warp's device name."""
    import mujoco

    wp, mjw, _ = warp()
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = qpos, qvel
    if ctrl is not None:
        data.ctrl[:] = ctrl
    mujoco.mj_forward(model, data)  # the initial state's constraint rows, for ``sizes``
    nconmax, njmax = sizes(model, data)
    with wp.ScopedDevice(device):
        d = mjw.put_data(model, data, nworld=nworld, nconmax=nconmax, njmax=njmax)
        if nworld > 1 and dv:
            d.qvel.assign((np.asarray(qvel) + dv * np.arange(nworld)[:, None]).astype(np.float32))
        return d


def put_worlds(models, qpos, qvel, ctrl, device=DEVICE):
    """A device ``mjw.Data`` of one world per row of ``qpos (nworld, nq)`` and ``qvel (nworld, nv)`` (a batch's
    initial states), world w's MuJoCo C model ``models[w]`` (one structure), with ``ctrl`` (None, or the actuators'
    constant control); its contact and constraint arrays sized by ``sizes`` for the world that needs the most rows at
    its initial state. ``device``: Warp's device name."""
    import mujoco

    wp, mjw, _ = warp()
    qpos, qvel = np.atleast_2d(qpos), np.atleast_2d(qvel)
    most = (NCONMAX, 1)
    for model, q, v in zip(models, qpos, qvel):
        data = mujoco.MjData(model)
        if ctrl is not None:
            data.ctrl[:] = ctrl
        data.qpos[:], data.qvel[:] = q, v
        mujoco.mj_forward(model, data)
        most = max(most, sizes(model, data), key=lambda s: s[1])
    with wp.ScopedDevice(device):  # (the last world's data: every row of qpos and qvel is set below)
        d = mjw.put_data(models[-1], data, nworld=len(qpos), nconmax=most[0], njmax=most[1])
        d.qpos.assign(qpos.astype(np.float32))
        d.qvel.assign(qvel.astype(np.float32))
        return d


def compile_step(mx, model, qpos, qvel, ctrl, nworld=1, device=DEVICE):
    """One step on a scratch state of ``nworld`` worlds on ``device`` (``mx``'s), so that every kernel a step
    launches is compiled (or loaded from the cache) before a timed run: the wall time, s."""
    wp, mjw, _ = warp()
    d = put_state(model, qpos, qvel, ctrl, nworld, device=device)
    start = time.perf_counter()
    with wp.ScopedDevice(device):
        mjw.step(mx, d)
        wp.synchronize_device(device)
    return time.perf_counter() - start


def step_samples(mx, d, steps, q0, v0):
    """Step ``d`` through the sample intervals (``steps[k]`` steps in interval k) and read world 0's samples
    back: ``(Q (n, nq), V (n, nv), wall s, first bad sample or None)``, float64 widened exactly from float32, the
    initial state first, NaN from the first non-finite sample of world 0 on (the loop stops there). The wall time
    is the stepping of every world and the per-sample copies to the host (the CPU backend's arrays are host
    memory; a CUDA device's, copies). The other worlds' last state stays in ``d``."""
    wp, mjw, _ = warp()
    n = len(steps) + 1
    Q, V = np.full((n, len(q0)), np.nan), np.full((n, len(v0)), np.nan)
    Q[0], V[0] = q0, v0
    step = mjw.step
    bad = None
    with wp.ScopedDevice(d.qpos.device):  # the state's device (a CUDA copy's .numpy() waits for its kernels)
        start = time.perf_counter()
        for k, nstep in enumerate(steps, 1):
            for _ in range(int(nstep)):
                step(mx, d)
            q, v = d.qpos.numpy()[0], d.qvel.numpy()[0]
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
                bad = k
                break
            Q[k], V[k] = q, v
        wall = time.perf_counter() - start
    return Q, V, wall, bad


def step_worlds(mx, d, steps, Q0, V0):
    """Step every world of ``d`` through the sample intervals (``steps[k]`` steps in interval k) and read all
    worlds' samples back: ``(Q (n, nworld, nq), V (n, nworld, nv), wall s, bad (nworld,))``, float64 widened
    exactly from float32, the initial states ``Q0 (nworld, nq)``, ``V0`` first; world w is NaN from its first
    non-finite sample ``bad[w]`` on (0: none). The loop stops once every world is non-finite. The wall time is
    the stepping of the batch and the per-sample copies to the host."""
    wp, mjw, _ = warp()
    n, nworld = len(steps) + 1, len(Q0)
    Q, V = np.full((n, nworld, Q0.shape[1]), np.nan), np.full((n, nworld, V0.shape[1]), np.nan)
    Q[0], V[0] = Q0, V0
    bad = np.zeros(nworld, dtype=int)
    step = mjw.step
    with wp.ScopedDevice(d.qpos.device):
        start = time.perf_counter()
        for k, nstep in enumerate(steps, 1):
            for _ in range(int(nstep)):
                step(mx, d)
            q, v = d.qpos.numpy(), d.qvel.numpy()
            finite = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(v), axis=1)
            if not keep_sample(Q, V, bad, k, q, v, finite):
                break
        wall = time.perf_counter() - start
    return Q, V, wall, bad
