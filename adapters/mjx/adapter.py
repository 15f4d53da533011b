"""``MjxAdapter``: the contract (``dalembert.adapters``) for MuJoCo XLA (``mujoco.mjx``) on JAX's CPU backend or a GPU.

The model is the MuJoCo adapter's: the same generated MJCF (``mujoco.mjcf``),
compiled by MuJoCo C and checked against the scene (``MujocoAdapter.prepare``),
then put on the device with ``mjx.put_model``; the initial ``MjData`` likewise
with ``mjx.put_data``. ``prepare`` also compiles the rollout (``stepping``):
JIT compilation is build, not stepping. ``run`` times the compiled rollout
alone. The read-back is the MuJoCo adapter's (``mujoco.readback``): MJX's
sampled ``qpos``/``qvel``, widened to double exactly, are set into a MuJoCo C
``MjData``, so poses and velocities are MJX's states and the joint reactions
are MuJoCo C's ``mj_rnePostConstraint`` evaluated on them (the audit says so).

Options: ``precision`` = ``float32`` (MJX's default) | ``float64``
(``jax_enable_x64``); ``welds`` as for MuJoCo. Loads go through MuJoCo's site
actuators only (MJX applies them inside every integrator stage); MuJoCo's
``loads=xfrc_applied`` path, a Python call per step, is not offered.

Contact: MuJoCo's mapping (``mujoco.contact``: the same geoms, planes, explicit
pairs, friction and restitution-as-dampratio in the same MJCF), with MuJoCo's
contact options ``cone``, ``impratio`` and ``contact_timeconst`` (MJX's
constraint rows and solver read ``cone`` and ``impratio`` as MuJoCo C does).
What MJX lacks is refused with the reason, before anything runs (``why_not``):
``noslip_iterations`` > 0 (the JAX implementation this adapter runs has no
noslip pass — only MJX's Warp backend, a GPU one, has: ``mujoco.mjx._src``
would ignore the option silently, and the run would be one without noslip), and,
from MJX itself, a frictionless pair (condim 1) under the elliptic cone
(``mjx.make_data``: "condim=1 with ConeType.ELLIPTIC not implemented") and any
geometry pair MJX has no collision function for (``mjx.put_model``). Contact forces are MJX's
own (``mjx.contact``): ``mjx.forward`` at each sampled state, its ``efc_force`` decoded per
contact as ``mj_contactForce`` does (MuJoCo C's solver on MJX's states would be another solver's).

Batches (``dalembert.adapters.batch``): the scenes of one model structure are stepped as one ``jax.vmap``
of the rollout over their stacked initial states and, where their models differ (a swept mass or inertia),
over the model's JAX arrays they differ in (``world_fields``: every array leaf of ``mjx.Model``; its static
fields, the structure, must agree, else the batch is refused with the field's name); each world's
read-back, contact forces and audit are its own scene's.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass, fields, replace

import numpy as np

from dalembert.adapters.base import IntegratorSpec, Option, Outcome
from dalembert.adapters.batch import (MAX_BATCH, BatchOutcome, BatchPrepared, differing, same_model,
                                     world_fields_problem)
from dalembert.adapters.mujoco import MujocoAdapter
from dalembert.adapters.mujoco import contact
from dalembert.adapters.mujoco.adapter import MujocoPrepared
from dalembert.adapters.mujoco.readback import read_back
from dalembert.adapters.mjx.contact import read_forces
from dalembert.adapters.mjx.stepping import (DEVICES, PRECISIONS, chunks, compile_rollout, device_name,
                                             device_problem, jax_device, model_fields, mjx, precision, run_rollout,
                                             stack, to_host, traced_fields, varying)

__all__ = ["MjxAdapter", "MjxPrepared", "MjxBatch"]

OPTIONS = ("precision", "welds", "device", *contact.OPTIONS)
STAGES = {"euler": 1, "rk4": 4, "implicitfast": 1}  # evaluations of the dynamics per step
# The step the refusal check compiles every model with: ``mjx.put_model`` and ``mjx.make_data`` refuse features
# (integrator, cone, solver, flags, geometry pairs, condim, sensors), never a step, which enters the MJCF only as
# numbers (timestep, solref), so one check serves every step of a sweep (~8 ms a check).
REFUSAL_DT = 1e-3
# MJX's implementation, named: the one the adapter maps (on a GPU, MJX may otherwise pick its Warp one)
IMPL = "jax"


@dataclass(frozen=True, eq=False)
class MjxPrepared(MujocoPrepared):
    """MJX's prepared run: MuJoCo's (``MujocoPrepared``: the model compiled by MuJoCo C, its initial state, the
    read-back's scratch data), put on the device and its rollout compiled.

    Attributes
    ----------
    precision : str — option ``precision``: ``float32`` or ``float64``
    mx : mjx.Model — the model on the device, in ``precision``
    dx0 : mjx.Data — the initial state on the device
    steps_device : list of jax.Array — the steps per sample interval, in the rollout's chunks
    compile_s : float — the rollout's JIT compilation, s (build, not stepping)
    backend : str — where it steps (option ``device``): JAX's default backend (``cpu``), or a GPU (``gpu:0``)
    """

    precision: str
    mx: object
    dx0: object
    steps_device: list
    compile_s: float
    backend: str


@dataclass(frozen=True, eq=False)
class MjxBatch(BatchPrepared):
    """A batch on MJX (``BatchPrepared``: ``worlds``, each an ``MjxPrepared`` of its scene sharing the one device
    model; ``device``: JAX's backend).

    Attributes
    ----------
    mx : mjx.Model — the model on the device, every world's
    dx0 : mjx.Data — the worlds' initial states, stacked on a leading axis (``stepping.stack``), padded to a power of
        two with copies of the last (``_padded``; their samples are dropped)
    world_fields : tuple of str — the ``mjx.Model`` fields whose values differ between the worlds (empty: the
        worlds differ in their initial state only)
    rows : tuple — those fields' per-world values, padded as ``dx0`` (``stepping.varying``; empty without any)
    """

    mx: object
    dx0: object
    world_fields: tuple = ()
    rows: tuple = ()


class MjxAdapter(MujocoAdapter):
    """MJX (``mujoco-mjx``) on JAX's CPU backend or its GPU (option ``device``). Options: ``precision`` =
    ``float32`` | ``float64``; ``welds`` = ``tree`` | ``equality``; contact as MuJoCo's (``cone``, ``impratio``,
    ``contact_timeconst``;
    ``noslip_iterations`` only at its default 0: MJX's JAX implementation has no noslip pass)."""

    name = "mjx"
    options = {
        "precision": Option(PRECISIONS, PRECISIONS[0], "JAX's number type: float32 (MJX's default) or float64 "
                            "(jax_enable_x64)"),
        "welds": MujocoAdapter.options["welds"],
        "device": Option(DEVICES, DEVICES[0], "where JAX steps: its CPU backend, or its first GPU; refused where JAX "
                         "finds none"),
        **contact.CONTACT_OPTIONS,
    }
    effects = MujocoAdapter.effects  # contact included: MuJoCo's mapping, what MJX lacks refused (``why_not``)
    integrators = {
        "euler": IntegratorSpec(True, OPTIONS, "MJX semi-implicit Euler", order=1),
        "rk4": IntegratorSpec(True, OPTIONS, "MJX classical RK4", order=4),
        "implicitfast": IntegratorSpec(True, OPTIONS, "MJX implicit in velocity, no Coriolis derivatives", order=1),
    }

    def version(self):
        """MJX's version; ImportError when MJX or JAX is missing. Neither is imported here: the
        harness asks before forking its workers, and a process that has started JAX's threads
        must not fork (JAX warns of deadlocks) — each worker imports JAX itself."""
        return _version()

    def load(self):
        """MJX and JAX imported (``version`` imports neither)."""
        self.version()
        mjx()

    def unsupported(self, scene, settings):
        """The base check, then MJX's own: the contact options MJX lacks (``why_not``), and where
        ``mjx.put_model`` or ``mjx.make_data`` refuses the compiled model (NotImplementedError, e.g. a
        feature MJX lacks), the reason is MJX's; option ``device`` where JAX has no such device here
        (``stepping.device_problem``: it imports JAX, so not in ``unsupported_before_build``)."""
        reason = self.unsupported_before_build(scene, settings) or device_problem(self.option(settings, "device"))
        if reason:
            return reason
        from dalembert.adapters.mujoco.mjcf import mjcf

        return _refusal(mjcf(scene, replace(settings, dt=REFUSAL_DT)))

    def unsupported_before_build(self, scene, settings):
        """``unsupported`` but for the device's refusal of the compiled model (known only once it is built)."""
        return super().unsupported(scene, settings) or why_not(scene, settings)

    def variants(self, scene):
        """Default matrix: both precisions (and, where the scene has welds, MuJoCo's weld variants)."""
        return [{**v, **p} for v in super().variants(scene) for p in ({}, {"precision": "float64"})]

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        import jax

        p = super().prepare(scene, times, settings)  # compiled MJCF, checked; the initial state
        chosen, on = self.option(settings, "precision"), jax_device(self.option(settings, "device"))
        with precision(chosen):
            mx = mjx().put_model(p.model, device=on, impl=IMPL)
            dx0 = _initial(p, on)
            steps_device = [jax.device_put(c, on) for c in chunks(p.steps)]
            compile_s = compile_rollout(mx, dx0)
        return MjxPrepared(**{f.name: getattr(p, f.name) for f in fields(p)}, precision=chosen, mx=mx, dx0=dx0,
                           steps_device=steps_device, compile_s=compile_s, backend=device_name(on))

    # ------------------------------------------------------------- batches
    def world_fields(self):
        """The ``mjx.Model`` fields a batch may hold per world: its JAX arrays (``stepping.traced_fields``), which
        the vmapped rollout maps over like the state."""
        return traced_fields()

    def batch_problem(self, scenes, times, settings):
        """Why ``scenes`` cannot be the worlds of one vmapped rollout: their device models differ in structure (a
        static field of ``mjx.Model``: ``batch.world_fields_problem``); None when they can."""
        from dalembert.adapters.mujoco.mjcf import mjcf

        xmls = [mjcf(s, settings) for s in scenes]
        if same_model(xmls, self.name) is None or not 0 < len(xmls) <= MAX_BATCH:
            return same_model(xmls, self.name)  # one MJCF (no device model needed), or a wrong size
        chosen = self.option(settings, "precision")
        return world_fields_problem([_fields(x, chosen) for x in xmls], self.world_fields(), self.name)

    def prepare_batch(self, scenes, times, settings):
        """Each scene's MuJoCo model and initial state (``MujocoAdapter.prepare``), one device model (world 0's:
        they are one MJCF), the initial states stacked, the vmapped rollout compiled for the batch's size."""
        import jax

        from dalembert.adapters.mujoco.mjcf import mjcf

        ps = [MujocoAdapter.prepare(self, s, times, settings) for s in scenes]
        chosen, on = self.option(settings, "precision"), jax_device(self.option(settings, "device"))
        xmls = [mjcf(s, settings) for s in scenes]
        with precision(chosen):
            names = () if same_model(xmls, self.name) is None else differing([_fields(x, chosen) for x in xmls],
                                                                             self.world_fields())
            # world k's own device model where the worlds differ (its float32 values those of the world alone)
            mxs = [mjx().put_model(p.model, device=on, impl=IMPL) for p in (ps if names else ps[:1])]
            mx = mxs[0]
            starts = [_initial(p, on) for p in ps]
            # padded with copies of the last world to a power of two: one compilation serves every size up to it
            pad = _padded(len(starts)) - len(starts)
            dx0 = stack(starts + starts[-1:] * pad)
            rows = varying(mxs + mxs[-1:] * pad, names)
            steps_device = [jax.device_put(c, on) for c in chunks(ps[0].steps)]
            compile_s = compile_rollout(mx, dx0, batched=True, rows=rows)
        backend = device_name(on)
        worlds = tuple(MjxPrepared(**{f.name: getattr(p, f.name) for f in fields(p)}, precision=chosen,
                                   mx=mxs[k] if names else mx, dx0=d, steps_device=steps_device, compile_s=compile_s,
                                   backend=backend)
                       for k, (p, d) in enumerate(zip(ps, starts)))
        return MjxBatch(worlds=worlds, device=backend, mx=mx, dx0=dx0, world_fields=names, rows=rows)

    def run_batch(self, prepared):
        """Every world stepped at once (one vmapped rollout from the stacked initial states)."""
        p0 = prepared.worlds[0]
        with precision(p0.precision):
            Q, V, wall = run_rollout(prepared.mx, prepared.dx0, p0.steps_device, batched=True, rows=prepared.rows)
        return BatchOutcome(wall, tuple(self._outcome(p, [q[k] for q in Q], [v[k] for v in V], wall,
                                                      prepared.world_fields)
                                        for k, p in enumerate(prepared.worlds)))

    # ------------------------------------------------------------- run
    def run(self, prepared):
        p = prepared
        with precision(p.precision):
            Q, V, wall = run_rollout(p.mx, p.dx0, p.steps_device)
        return self._outcome(p, Q, V, wall)

    def _outcome(self, p, Q, V, wall, world_fields=()):
        """The ``Outcome`` of the rollout's samples ``Q``, ``V`` (``run_rollout``'s chunks, one world's) from ``p``;
        ``world_fields``: the model fields a batch varied per world (in the audit where any, as MuJoCo Warp's)."""
        n_steps = int(p.steps.sum())
        info = {"message": "", "device": p.backend}

        def read():
            Qh, Vh = to_host(Q, V, p.qpos0, p.qvel0, len(p.times))
            # the contact forces MJX's own solver gives at its states (``contact.read_forces``), not MuJoCo C's
            traj, info["audit"] = read_back(p, Qh, Vh, contact_forces=read_forces(p, Qh, Vh))
            if world_fields:
                info["audit"]["batch_world_fields"] = ", ".join(world_fields)
            return traj

        return Outcome(read, wall, n_steps, n_steps * STAGES[p.settings.integrator], info)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        import jax

        p, mx = prepared, prepared.mx
        out = super().audit(prepared, outcome)  # MuJoCo C's compiled model: flags, gravity, actuators
        out.update({
            # the gravity put on the device, in its precision (float32 rounds -9.81 to -9.8100004)
            "gravity_device": tuple(float(g) for g in np.asarray(mx.opt.gravity)),
            "integrator": f"MJX {mx.opt.integrator.name}",
            "timestep": float(np.asarray(mx.opt.timestep)),
            "precision": str(np.asarray(mx.opt.timestep).dtype),
            "dtype_qpos": str(p.dx0.qpos.dtype),
            "backend": p.backend, "jax_version": jax.__version__,
            # XLA's flags shape MJX's cost (with the CPU fusion emitters on, its kinematics are exponential in a
            # chain's depth: benchmarks/scaling.py): the run says which it had
            "xla_flags": os.environ.get("XLA_FLAGS", ""),
            "jit_compile_s": p.compile_s,
            "mjx_version": self.version(),
            "reactions": "MuJoCo C mj_rnePostConstraint on MJX's sampled states (double)",
        })
        if p.scene.contacts:  # the contact options as the device model holds them (MuJoCo C's are read back above)
            out.update({"cone_device": mx.opt.cone.name.lower(), "impratio_device": float(np.asarray(mx.opt.impratio)),
                        "noslip": "none: MJX's JAX solver has no noslip pass (noslip_iterations > 0 is refused)"})
        if p.precision == "float32" and p.settings.dt is not None:
            # the attitude floor of the number type (rad; torque-free tops only, else NaN), for the report's parity
            from dalembert.adapters.mjx.parity import float32_floor

            out["float32_floor"] = float32_floor(p.scene, p.times, p.settings.dt)
        return out


def why_not(scene, settings):
    """Why MJX cannot run ``scene``'s contact at ``settings`` where MuJoCo C could, or None: a noslip pass, which
    MJX's JAX implementation does not have (``mujoco.mjx._src`` reads no ``noslip_iterations``: it would be ignored
    silently; only the Warp backend, a GPU one, has a noslip pass)."""
    if scene.contacts and contact.contact_options(settings)["noslip_iterations"] > 0:
        return ("options.noslip_iterations: MJX's JAX implementation has no noslip pass (its solver never reads "
                "noslip_iterations, so the run would silently be one without noslip; only MJX's Warp backend, a GPU "
                "one, has one) — run noslip on MuJoCo C (--engine mujoco), or MJX with noslip_iterations=0")
    return None


def _padded(n):
    """The worlds a batch of ``n`` is stepped as: the next power of two. JAX compiles the vmapped rollout once per
    batch size (~1.5-2 min on 2 busy cores: ``benchmarks.batches``), and a search's rounds batch 1 to N worlds, so
    sizes share a compilation; the padding at most doubles a batch's arithmetic (the cheap part on the CPU: 64
    worlds cost ~14x one, measured there)."""
    return 1 << max(0, n - 1).bit_length()


def _initial(p, device):
    """The initial state of MuJoCo's prepared ``p`` on ``device`` (``stepping.jax_device``'s; ``mjx.put_data``, in
    the precision in force)."""
    import mujoco

    data = mujoco.MjData(p.model)
    data.qpos[:], data.qvel[:] = p.qpos0, p.qvel0
    if p.load_path == "actuator":
        data.ctrl[:] = 1.0
    return mjx().put_data(p.model, data, device=device, impl=IMPL)


@functools.lru_cache(maxsize=64)
def _fields(xml, chosen):
    """The fields of MJX's device model of the MJCF ``xml`` in precision ``chosen`` as host values
    (``stepping.model_fields``), to compare a batch's worlds' models; once per model and precision in a worker."""
    import mujoco

    with precision(chosen):
        return model_fields(mjx().put_model(mujoco.MjModel.from_xml_string(xml), impl=IMPL))


@functools.lru_cache(maxsize=64)
def _refusal(xml):
    """Why ``mjx.put_model`` or ``mjx.make_data`` refuses the model compiled from the MJCF ``xml``, or None;
    once per model in a worker (every integrator and step of a case asks: ~8-20 ms a time)."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(xml)
    for step, call in (("put_model", lambda: mjx().put_model(model)),  # host to device only: nothing is compiled
                       # the data's contact rows: MJX refuses some here only (condim 1 under the elliptic cone)
                       ("make_data", lambda: mjx().make_data(model))):
        try:
            call()
        except NotImplementedError as e:
            return f"MJX cannot put this model on the device (mjx.{step}: NotImplementedError: {e})"
    return None


@functools.cache  # (installed packages do not change under a process; every run asks twice: ~1 ms a time)
def _version():
    from importlib.metadata import PackageNotFoundError, version
    from importlib.util import find_spec

    for module in ("jax", "mujoco.mjx"):
        if find_spec(module) is None:
            raise ImportError(f"No module named {module!r} (install dalembert[mjx])")
    try:
        return version("mujoco-mjx")
    except PackageNotFoundError:  # MJX inside a MuJoCo that ships it
        import mujoco

        return f"mujoco {mujoco.__version__}"
