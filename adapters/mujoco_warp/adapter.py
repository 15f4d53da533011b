"""``MujocoWarpAdapter``: the contract (``dalembert.adapters``) for MuJoCo Warp (``mujoco_warp``) on a Warp device.

The model is the MuJoCo adapter's: the same generated MJCF (``mujoco.mjcf``),
compiled by MuJoCo C and checked against the scene (``MujocoAdapter.prepare``),
then put on the device with ``mjw.put_model`` (the auto-reset flag cleared on a
copy: ``stepping.device_model``); the initial state likewise with
``mjw.put_data``. ``prepare`` also takes one step on a scratch state, so Warp's
kernels are compiled (or loaded from its cache) before any timed run. The
read-back is the MuJoCo adapter's (``mujoco.readback``), as for MJX: MuJoCo
Warp's sampled ``qpos``/``qvel``, widened to double exactly, are set into a
MuJoCo C ``MjData``, so poses and velocities are MuJoCo Warp's states and the
joint reactions are MuJoCo C's ``mj_rnePostConstraint`` evaluated on them (the
audit says so).

Number type: float32 only (MuJoCo Warp's kernels are written in it); the
float32 attitude floor of a torque-free top (``mjx.parity.float32_floor``) is in
every run's audit, so a reader sees whether an error is the method's or the
number type's. Option ``device``: Warp's CPU backend (``cpu``, the default) or a CUDA device (``cuda``,
``cuda:N``), refused with a reason where Warp finds none; the record's device is the one stepped on. Options:
``welds`` as for MuJoCo, contact as MuJoCo's (``cone``,
``impratio``, ``noslip_iterations``, ``contact_timeconst``: MuJoCo Warp reads
all four); ``worlds`` = N steps N copies of the case at once (MuJoCo Warp's ``nworld``), world k's initial
velocities raised by k ``WORLD_DV``: the trajectory is world 0's (the case's own, the same float32 arithmetic as
one world), the run's wall time the batch's (``Outcome.info["batch_size"]``: its record's cost is per world, the
batch's beside it, ``dalembert.record.Cost``), and the audit holds the batch size, its throughput (world-steps per
second) and the worlds' spread at the end. Loads go through MuJoCo's site actuators only (applied inside every
integrator stage); MuJoCo's ``loads=xfrc_applied`` path, a Python call per
step, is not offered. What MuJoCo Warp refuses (``mjw.put_model``: a geometry
type, a solver, a flag, an integrator it lacks) is refused with its reason
before anything runs.

Batches (``dalembert.adapters.batch``): ``prepare_batch`` and ``run_batch`` step the scenes of one model
structure as the worlds of one ``mjw.Data``, each world's arithmetic that of the scene run alone (MuJoCo Warp's
kernels compute every world by the same code); each world's read-back and audit are its own scene's. The
scenes may differ in their initial state and in the ``mjw.Model`` fields MuJoCo Warp holds per world
(``world_fields``: ``body_mass``, ``body_inertia``, ``body_ipos``, ``geom_size``, ... — a swept mass, inertia
or length); one model holds each such field with a row per world (``stepping.worlds_model``). A scene whose
model differs elsewhere (another number of bodies, a field MuJoCo Warp shares across worlds) is refused from
the batch with the reason (``batch_problem``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, fields, replace

import numpy as np

from dalembert.adapters.base import IntegratorSpec, Option, Outcome
from dalembert.adapters.batch import (MAX_BATCH, BatchOutcome, BatchPrepared, differing, same_model,
                                     world_fields_problem)
from dalembert.adapters.mujoco import MujocoAdapter
from dalembert.adapters.mujoco import contact
from dalembert.adapters.mujoco.adapter import MujocoPrepared
from dalembert.adapters.mujoco.readback import read_back
from dalembert.adapters.mujoco_warp.stepping import (batched_fields, compile_step, device_model, model_fields,
                                                     put_state, put_worlds, step_samples, step_worlds, warp,
                                                     worlds_model)
from dalembert.adapters.warp_runtime import DEVICE_OPTION, device, device_problem

__all__ = ["MujocoWarpAdapter", "MujocoWarpPrepared", "MujocoWarpBatch"]

OPTIONS = ("welds", "worlds", "device", *contact.OPTIONS)
# Batched worlds (option ``worlds``): world k starts with every velocity coordinate raised by k WORLD_DV (m/s,
# rad/s), ~1e-4 of the cases' velocities (~1-10), so the worlds' spread at the end measures how the case amplifies
# a small difference. A smaller one is lost in float32: its change of qpos per step, dv dt, falls below float32's
# resolution of qpos (measured: 1e-6 rad/s at dt 1e-3 leaves the pendulum's worlds' angles bit-identical).
WORLD_DV = 1e-3
# The most worlds a run may step (each holds MuJoCo Warp's contact and constraint arrays: ~MBs per thousand worlds
# for the cases here); a larger batch is a typo more often than a plan.
MAX_WORLDS = 4096
STAGES = {"euler": 1, "rk4": 4, "implicitfast": 1}  # evaluations of the dynamics per step
# The step the refusal check compiles every model with: ``mjw.put_model`` refuses features (integrator, cone,
# solver, flags, geometry, actuator and sensor types), never a step, which enters the MJCF only as numbers
# (timestep, solref), so one check serves every step of a sweep.
REFUSAL_DT = 1e-3


@dataclass(frozen=True, eq=False)
class MujocoWarpPrepared(MujocoPrepared):
    """MuJoCo Warp's prepared run: MuJoCo's (``MujocoPrepared``: the model compiled by MuJoCo C, its initial
    state, the read-back's scratch data), put on the device, its step's kernels compiled.

    Attributes
    ----------
    mx : mujoco_warp.Model — the model on the device (float32)
    ctrl : float or None — the site actuators' constant control (1: the loads at full value), None without
    worlds : int — option ``worlds``: the worlds each run steps at once (world 0 the case's)
    compile_s : float — the first step's wall time in ``prepare``: Warp's kernel compilation, or its load from the
        kernel cache, s (build, not stepping)
    device : str — Warp's device the run steps on (option ``device``: ``cpu``, ``cuda:0``)
    """

    mx: object
    ctrl: object
    worlds: int
    compile_s: float
    device: str


@dataclass(frozen=True, eq=False)
class MujocoWarpBatch(BatchPrepared):
    """A batch on MuJoCo Warp (``BatchPrepared``: ``worlds``, each a ``MujocoWarpPrepared`` of its scene sharing
    the one device model; ``device``).

    Attributes
    ----------
    mx : mujoco_warp.Model — the model on the device, every world's; the fields ``world_fields`` with a row per
        world
    world_fields : tuple of str — the ``mjw.Model`` fields whose values differ between the worlds (empty: the
        worlds differ in their initial state only)
    """

    mx: object
    world_fields: tuple = ()


class MujocoWarpAdapter(MujocoAdapter):
    """MuJoCo Warp (``mujoco-warp``) on Warp's CPU backend or a CUDA device (option ``device``), float32. Options:
    ``welds`` = ``tree`` | ``equality``; contact as MuJoCo's (``cone``, ``impratio``, ``noslip_iterations``,
    ``contact_timeconst``)."""

    name = "mujoco_warp"
    options = {
        "welds": MujocoAdapter.options["welds"],
        "worlds": Option(default=1, minimum=1.0, maximum=float(MAX_WORLDS), integer=True,
                         description="worlds stepped at once (mjw nworld); world k's initial velocities raised by "
                                     f"k * {WORLD_DV:g}; the trajectory is world 0's, the audit has the batch's "
                                     "throughput and spread"),
        "device": DEVICE_OPTION,
        **contact.CONTACT_OPTIONS,
    }
    effects = MujocoAdapter.effects  # MuJoCo's mapping; what MuJoCo Warp lacks is refused (``_refusal``)
    integrators = {
        "euler": IntegratorSpec(True, OPTIONS, "MuJoCo Warp semi-implicit Euler", order=1),
        "rk4": IntegratorSpec(True, OPTIONS, "MuJoCo Warp classical RK4", order=4),
        "implicitfast": IntegratorSpec(True, OPTIONS, "MuJoCo Warp implicit in velocity, no Coriolis derivatives",
                                       order=1),
    }

    def version(self):
        """MuJoCo Warp's version; ImportError when it or Warp is missing. Neither is imported here: the harness
        asks before forking its workers, and each worker initializes Warp itself (``load``)."""
        return _version()

    def load(self):
        """Warp initialized and MuJoCo Warp imported (``version`` imports neither)."""
        self.version()
        warp()

    def unsupported(self, scene, settings):
        """The base check, then option ``device`` where Warp finds no such device here
        (``warp_runtime.device_problem``: it imports Warp, so not in ``unsupported_before_build``), then where
        ``mjw.put_model`` refuses the compiled model (NotImplementedError or ValueError: a feature MuJoCo Warp
        lacks), the reason is MuJoCo Warp's."""
        reason = self.unsupported_before_build(scene, settings) or device_problem(self.option(settings, "device"))
        if reason:
            return reason
        from dalembert.adapters.mujoco.mjcf import mjcf

        return _refusal(mjcf(scene, replace(settings, dt=REFUSAL_DT)))

    def unsupported_before_build(self, scene, settings):
        """``unsupported`` but for the device's refusal of the compiled model (known only once it is built)."""
        return super().unsupported(scene, settings)

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        p = super().prepare(scene, times, settings)  # compiled MJCF, checked; the initial state
        ctrl = 1.0 if p.load_path == "actuator" and p.model.nu else None
        worlds = int(self.option(settings, "worlds"))
        on = device(self.option(settings, "device"))
        mx = device_model(p.model, on)
        compile_s = compile_step(mx, p.model, p.qpos0, p.qvel0, ctrl, worlds, on)
        return MujocoWarpPrepared(**{f.name: getattr(p, f.name) for f in fields(p)}, mx=mx, ctrl=ctrl,
                                  worlds=worlds, compile_s=compile_s, device=on)

    # ------------------------------------------------------------- run
    def run(self, prepared):
        p = prepared
        d = put_state(p.model, p.qpos0, p.qvel0, p.ctrl, p.worlds, WORLD_DV, p.device)  # a fresh state, not timed
        Q, V, wall, bad = step_samples(p.mx, d, p.steps, p.qpos0, p.qvel0)
        n_steps = int(p.steps[:bad].sum()) if bad else int(p.steps.sum())  # interval `bad` was stepped whole
        message = f"MuJoCo Warp: non-finite state at t = {p.times[bad]:g} s" if bad else ""
        info = {"message": message, "device": p.device, "batch_size": p.worlds}
        if p.worlds > 1:
            # the batch: every world stepped n_steps in ``wall``; world 0 is the run's, the others its perturbed
            # copies (their spread from world 0 at the end: NaN if a world diverged)
            q = d.qpos.numpy().astype(float)
            with np.errstate(invalid="ignore"):
                spread = float(np.max(np.abs(q[1:] - q[0]))) if bad is None else float("nan")
            info["worlds"] = {"worlds": p.worlds, "world_dv": WORLD_DV, "world_steps_per_s": p.worlds * n_steps / wall,
                              "batch_s_per_step": wall / max(n_steps, 1), "world_spread_qpos_end": spread}

        def read():
            traj, info["audit"] = read_back(p, Q, V)
            info["audit"].update(info.get("worlds", {}))
            return traj

        return Outcome(read, wall, n_steps, n_steps * STAGES[p.settings.integrator], info)

    # ------------------------------------------------------------- batches
    def world_fields(self):
        """The ``mjw.Model`` fields MuJoCo Warp holds per world (``stepping.batched_fields``: ``body_mass``,
        ``body_inertia``, ``body_ipos``, ``geom_size``, ``opt``'s none: the step and gravity are every world's)."""
        return batched_fields()

    def batch_problem(self, scenes, times, settings):
        """Why ``scenes`` cannot be the worlds of one ``mjw.Data``: their device models differ in a field MuJoCo Warp
        shares across worlds or in structure (``batch.world_fields_problem``), or option ``worlds`` is given (a
        batch's worlds are its scenes); None when they can."""
        from dalembert.adapters.mujoco.mjcf import mjcf

        if int(self.option(settings, "worlds")) != 1:
            return ("options.worlds: a batch's worlds are its scenes, not copies of one — drop --option worlds, or "
                    "run without --batch")
        xmls = [mjcf(s, settings) for s in scenes]
        if same_model(xmls, self.name) is None or not 0 < len(xmls) <= MAX_BATCH:
            return same_model(xmls, self.name)  # one MJCF (no device model needed), or a wrong size
        return world_fields_problem([_fields(x) for x in xmls], self.world_fields(), self.name)

    def prepare_batch(self, scenes, times, settings):
        """Each scene's MuJoCo model and initial state (``MujocoAdapter.prepare``), one device model (world 0's, with a
        row per world of each field the worlds' models differ in: ``stepping.worlds_model``), and the step's kernels
        compiled for the batch's size."""
        from dalembert.adapters.mujoco.mjcf import mjcf

        ps = [MujocoAdapter.prepare(self, s, times, settings) for s in scenes]
        ctrl = 1.0 if ps[0].load_path == "actuator" and ps[0].model.nu else None
        on = device(self.option(settings, "device"))
        xmls = [mjcf(s, settings) for s in scenes]
        names = () if same_model(xmls, self.name) is None else differing([_fields(x) for x in xmls],
                                                                         self.world_fields())
        mx = worlds_model([p.model for p in ps], names, on)
        compile_s = compile_step(mx, ps[0].model, ps[0].qpos0, ps[0].qvel0, ctrl, len(ps), on)
        worlds = tuple(MujocoWarpPrepared(**{f.name: getattr(p, f.name) for f in fields(p)}, mx=mx, ctrl=ctrl,
                                          worlds=1, compile_s=compile_s, device=on) for p in ps)
        return MujocoWarpBatch(worlds=worlds, device=on, mx=mx, world_fields=names)

    def run_batch(self, prepared):
        """Every world stepped at once from its own initial state (a fresh ``mjw.Data`` each call, not timed)."""
        ps = prepared.worlds
        Q0, V0 = np.array([p.qpos0 for p in ps]), np.array([p.qvel0 for p in ps])
        d = put_worlds([p.model for p in ps], Q0, V0, ps[0].ctrl, prepared.device)
        Q, V, wall, bad = step_worlds(prepared.mx, d, ps[0].steps, Q0, V0)
        return BatchOutcome(wall, tuple(self._world(p, Q[:, k], V[:, k], int(bad[k]) or None, wall,
                                                    prepared.world_fields) for k, p in enumerate(ps)))

    def _world(self, p, Q, V, bad, wall, world_fields=()):
        """World ``p``'s ``Outcome`` of a batch: its samples ``Q (n, nq)``, ``V (n, nv)``, first bad sample ``bad``
        (None: none), the batch's ``wall``, the model fields the batch holds per world ``world_fields`` (in the audit
        where any); as ``run`` makes one."""
        n_steps = int(p.steps[:bad].sum()) if bad else int(p.steps.sum())  # interval `bad` was stepped whole
        info = {"message": f"MuJoCo Warp: non-finite state at t = {p.times[bad]:g} s" if bad else "",
                "device": p.device}

        def read():
            traj, info["audit"] = read_back(p, Q, V)
            if world_fields:
                info["audit"]["batch_world_fields"] = ", ".join(world_fields)
            return traj

        return Outcome(read, wall, n_steps, n_steps * STAGES[p.settings.integrator], info)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        wp, mjw, init_message = warp()
        p, mx = prepared, prepared.mx
        out = super().audit(prepared, outcome)  # MuJoCo C's compiled model: flags, gravity, actuators
        out.update({
            # the gravity put on the device, in float32 (-9.81 becomes -9.8100004)
            "gravity_device": tuple(float(g) for g in np.asarray(mx.opt.gravity.numpy()).reshape(-1)[:3]),
            "integrator": f"MuJoCo Warp {mjw.IntegratorType(int(mx.opt.integrator)).name}",
            "timestep": float(np.asarray(mx.opt.timestep.numpy()).reshape(-1)[0]),
            "precision": str(mx.opt.timestep.numpy().dtype),
            "device": p.device, "warp_version": wp.__version__, "mujoco_warp_version": self.version(),
            "warp_init": init_message,
            "kernel_compile_s": p.compile_s,
            "autoreset": "none: MuJoCo Warp has no auto-reset (the flag is cleared on the device model's copy); "
                         "a non-finite state ends the run",
            "reactions": "MuJoCo C mj_rnePostConstraint on MuJoCo Warp's sampled states (double)",
        })
        if p.settings.dt is not None:
            # the attitude floor of the number type (rad; torque-free tops only, else NaN), for the report's parity
            from dalembert.adapters.mjx.parity import float32_floor

            out["float32_floor"] = float32_floor(p.scene, p.times, p.settings.dt)
        return out


@functools.lru_cache(maxsize=64)
def _refusal(xml):
    """Why ``mjw.put_model`` refuses the model compiled from the MJCF ``xml``, or None; once per model in a
    worker (every integrator and step of a case asks)."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(xml)
    try:
        device_model(model)
    except (NotImplementedError, ValueError) as e:
        return f"MuJoCo Warp cannot put this model on the device (mjw.put_model: {type(e).__name__}: {e})"
    return None


@functools.lru_cache(maxsize=64)
def _fields(xml):
    """The fields of the device model of the MJCF ``xml`` as host values (``stepping.model_fields``, on Warp's CPU),
    to compare a batch's worlds' models; once per model in a worker (~15 ms each)."""
    import mujoco

    return model_fields(device_model(mujoco.MjModel.from_xml_string(xml)))


@functools.cache  # (installed packages do not change under a process)
def _version():
    from dalembert.adapters.warp_runtime import distribution_version

    return distribution_version(("warp", "mujoco_warp"), "mujoco-warp", "mujoco-warp")
