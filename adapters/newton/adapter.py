"""``NewtonAdapter``: the contract (``dalembert.adapters``) for Newton (``newton`` 1.8) on a Warp device (option
``device``: its CPU backend by default, or a CUDA device; refused with a reason where Warp finds none).

``prepare`` builds the scene's Newton model (``model.build``: bodies at their COMs, joints in their frames,
nothing the scene does not call for; mass properties checked), the solver of the run's family
(``solvers.make``) and takes one step on a scratch state, so that Warp's kernels are compiled (or loaded from its
cache) before any timed run; ``run`` steps (``stepping.simulate``) and reads the bodies' states back; ``audit``
reads what Newton simulated back from its model and the solver object.

Batches (``dalembert.adapters.batch``): ``prepare_batch`` builds one Newton model of N worlds
(``model.build_worlds``: ``ModelBuilder.replicate`` of the first scene, each world's initial state its own scene's)
and one solver on it; ``run_batch`` steps them all with one ``solver.step`` a step (``stepping.simulate_worlds``).
A single run is the batch of one world, through the same code.

Number type: float32 only (Newton's arrays are ``wp.float32``; there is no float64 build). The float32 attitude
floor of a torque-free top (``mjx.parity.float32_floor``: RK4 in float32 against the same RK4 in double) is in
every run's audit, so a reader sees whether an error is the method's or the number type's.

Read-back: Newton's ``body_q`` and ``body_qd`` at each sample, widened exactly to double: COM position, the
quaternion as Newton integrated it (x, y, z, w, turned scalar first), COM velocity and angular velocity in world
axes. Joint coordinates come from the bodies' motion (``spatial.joint_coordinates``), the same for the
joint-coordinate solvers and the body-coordinate ones, so a body-coordinate solver's joint error shows in them.
Reactions are not read back (Newton 1.8 reports none the same way for every solver): not measured.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from dalembert import spatial
from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, Prepared, typed_options
from dalembert.adapters.batch import BatchOutcome, BatchPrepared, same_model
from dalembert.adapters.newton import mujoco_solver, solvers
from dalembert.adapters.newton.engine import engine, version
from dalembert.adapters.newton.model import build_worlds, check_mass_properties, model_text, summary, why_not
from dalembert.adapters.newton.stepping import fresh_states, load_plan, simulate_worlds
from dalembert.adapters.warp_runtime import DEVICE_OPTION, device, device_problem
from dalembert.scene import EFFECTS, SPRING_EFFECT, WORLD
from dalembert.settings import steps_per_interval

__all__ = ["NewtonAdapter", "NewtonPrepared", "NewtonBatch"]

# The solvers' options (``solvers.OPTIONS``) and the Warp device it steps on
OPTIONS = {**solvers.OPTIONS, "device": DEVICE_OPTION}
# What each effect Newton's adapter does not map would take (``unsupported``).
NOT_MAPPED = {
    "loop": ("closed kinematic loops: Newton closes a loop with a joint outside every articulation or an equality "
             "constraint, which Featherstone ignores and the others solve each their own way; not mapped"),
    SPRING_EFFECT: ("linear spring-dampers between two points: Newton's springs join particles, not rigid bodies' "
                    "points; the adapter would apply the force itself from Python, not the engine"),
    "contact": ("contact: Newton's contact is between shapes, each solver with its own contact model (penalty, "
                "compliant, position-based, complementarity); not mapped yet"),
}


@dataclass(frozen=True, eq=False)
class NewtonPrepared(Prepared):
    """Newton's prepared run (``Prepared``).

    Attributes
    ----------
    model : model.NewtonModel — the finalized model and the initial state
    solver : newton.solvers.SolverBase — the family's solver on it (stateless between runs but for its
        warm starts, which ``run`` rebuilds: see ``NewtonAdapter.run``)
    family : str — the integrator family (``solvers.FAMILIES``)
    steps : ndarray (n - 1,) of int — steps per sample interval
    loads : list — the loads as the stepping applies them (``stepping.load_plan``)
    compile_s : float — the scratch step's wall time in ``prepare``: kernel compilation or cache load, s
    """

    model: object
    solver: object
    family: str
    steps: np.ndarray
    loads: list
    compile_s: float


@dataclass(frozen=True, eq=False)
class NewtonBatch(BatchPrepared):
    """A batch on Newton (``BatchPrepared``: ``worlds``, one ``NewtonPrepared`` per scene, all on one Newton model
    of ``len(worlds)`` worlds and one solver; ``device``)."""


class NewtonAdapter(Adapter):
    """Newton (``newton`` 1.8, NVIDIA, Google DeepMind and Disney Research) on Warp's CPU backend or a CUDA device
    (option ``device``), float32: each rigid-body solver an integrator family (``solvers.FAMILIES``), its settings
    as options."""

    name = "newton"
    # gravity, free, revolute, prismatic, ball and weld joints, world and follower loads; loops, springs and
    # contact: NOT_MAPPED
    effects = EFFECTS
    options = OPTIONS
    refusal_notes = NOT_MAPPED
    # What an engine environment (``dalembert env create newton==1.8.0``) installs with Newton: its ``sim`` extra,
    # the MuJoCo and MuJoCo Warp its MuJoCo solver pins (``mujoco_solver.problem`` reads the same extra back)
    environment_extras = (mujoco_solver.EXTRA,)
    # every family names every option; ``Option.only`` says which families take it (``check`` refuses the others)
    integrators = {family: IntegratorSpec(True, tuple(OPTIONS), description, order=order)
                   for family, (_, description, order, _) in solvers.FAMILIES.items()}

    def version(self):
        return version()

    def load(self):
        """Warp initialized and Newton imported (``version`` imports neither)."""
        self.version()
        engine()

    def unsupported(self, scene, settings):
        """The base check, what the adapter does not map (``model.why_not``), a MuJoCo-solver family where Newton's
        MuJoCo is not installed (``mujoco_solver.problem``), then option ``device`` where Warp
        finds no such device here (``warp_runtime.device_problem``: it imports Warp, so the harness's main process,
        which asks ``unsupported_before_build``, never does)."""
        return self.unsupported_before_build(scene, settings) or device_problem(self.option(settings, "device"))

    def unsupported_before_build(self, scene, settings):
        """``unsupported`` but for the device check (which imports Warp)."""
        return super().unsupported(scene, settings) or why_not(scene) or self._mujoco_problem(settings)

    def _mujoco_problem(self, settings):
        """Why a MuJoCo-solver family cannot run where this adapter's runs go (``mujoco_solver.problem``), or None:
        a versioned engine's adapter outside its environment (``adapters.registry``: its ``version`` is the
        environment's) asks of the environment's packages, any other of this process's."""
        if settings.integrator not in mujoco_solver.FAMILIES:
            return None
        env = getattr(self.version, "__self__", None)
        return mujoco_solver.problem(getattr(env, "path", None) if env is not self else None)

    def describe(self, scene, settings):
        """Newton's model, read back from its arrays, and the solver settings it is stepped with, for reports and
        ``dalembert show-model``."""
        options = typed_options(self.options, settings)
        family = settings.integrator
        damping = solvers.angular_damping(options)
        nm = _build([scene], family, options)[0]
        names = solvers.FAMILIES[family][3]
        given = {n: options[n] for n in names if n != "angular_damping" and options[n] is not None}
        return (summary(nm) + f"\nsolver: Newton {solvers.FAMILIES[family][0]}, defaults={options['defaults']}, "
                f"angular damping {'Newton' + chr(39) + 's own' if damping is None else damping}"
                + (f", {given}" if given else ""))

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        return self._prepare([scene], times, settings)[0]

    def _prepare(self, scenes, times, settings):
        """One ``NewtonPrepared`` per scene, the scenes the worlds of one Newton model (``build_worlds``) stepped
        by one solver, its kernels compiled by a scratch step."""
        wp, newton, _ = engine()
        family = settings.integrator
        options = typed_options(self.options, settings)
        nms = _build(scenes, family, options)
        for nm, scene in zip(nms, scenes):
            check_mass_properties(nm, scene)
        with wp.ScopedDevice(nms[0].model.device):
            solver = solvers.make(newton, nms[0].model, family, options)
            compile_s = _scratch_step(nms[0], solver, settings.dt)
        times = np.asarray(times, dtype=float)
        steps = steps_per_interval(times, settings.dt)
        return [NewtonPrepared(scene, times, settings, model=nm, solver=solver, family=family, steps=steps,
                               loads=load_plan(nm, scene), compile_s=compile_s) for nm, scene in zip(nms, scenes)]

    # ------------------------------------------------------------- run
    def run(self, prepared):
        wall, (outcome,) = self._step([prepared])
        return outcome

    def _step(self, ps):
        """Step the worlds ``ps`` (every world of one model) at once: ``(wall s, one Outcome per world)``."""
        if ps[0].family in ("vbd", "steel"):
            # their warm starts (VBD's persisted multipliers, Steel's impulses) live on the solver: a fresh one per
            # run, so every run starts from the same solver state (not timed)
            wp, newton, _ = engine()
            with wp.ScopedDevice(ps[0].model.model.device):
                solver = solvers.make(newton, ps[0].model.model, ps[0].family,
                                      typed_options(self.options, ps[0].settings))
            ps = [_replace_solver(p, solver) for p in ps]
        Q, V, wall, bad = simulate_worlds(ps)
        return wall, tuple(_outcome(p, Q[:, k], V[:, k], int(bad[k]) or None, wall) for k, p in enumerate(ps))

    # ------------------------------------------------------------- batches
    def batch_problem(self, scenes, times, settings):
        """Why ``scenes`` cannot be the worlds of one Newton model: their models differ (``model.model_text``: the
        scene but its joints' initial coordinates; ``batch.same_model``), or None."""
        return same_model([model_text(s) for s in scenes], self.name)

    def prepare_batch(self, scenes, times, settings):
        """One Newton model of ``len(scenes)`` worlds (``ModelBuilder.replicate``), each started from its own
        scene's initial state, one solver on it, its kernels compiled for the batch (not timed)."""
        worlds = tuple(self._prepare(scenes, times, settings))
        return NewtonBatch(worlds=worlds, device=str(worlds[0].model.model.device))

    def run_batch(self, prepared):
        """Every world stepped at once from its initial state (``stepping.simulate_worlds``)."""
        wall, outcomes = self._step(prepared.worlds)
        return BatchOutcome(wall, outcomes)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        wp, newton, init_message = engine()
        p, m = prepared, prepared.model.model
        dofs, n = m.joint_dof_count, prepared.model.worlds
        out = {
            # Newton holds gravity in float32 only: each component as the shortest decimal that float32 value reads
            # back as (numpy's float32 repr: -9.81 for the float32 nearest -9.81), and the float32 value widened
            # exactly (-9.8100004196167)
            "gravity": tuple(float(str(g)) for g in m.gravity.numpy()[0]),
            "gravity_float32": tuple(float(g) for g in m.gravity.numpy()[0]),
            "integrator": f"Newton {solvers.FAMILIES[p.family][0]}",
            "solver_settings": solvers.settings(p.solver, p.family, m),
            "timestep": float(np.float32(p.settings.dt)),
            "precision": str(m.body_q.dtype.__name__ if hasattr(m.body_q.dtype, "__name__") else m.body_q.dtype),
            "number_type": str(m.body_mass.numpy().dtype),
            "device": str(m.device), "warp_version": wp.__version__, "newton_version": self.version(),
            "warp_init": init_message, "kernel_compile_s": p.compile_s,
            # one world's (a batch's model holds ``worlds`` copies)
            "bodies": m.body_count // n, "joints": m.joint_count // n, "articulations": m.articulation_count // n,
            "joint_dofs": dofs // n,
            # what Newton adds to the joints by default, as stored in the model the run stepped with
            "joint_armature_max": float(np.abs(m.joint_armature.numpy()).max(initial=0.0)),
            "joint_damping_max": float(np.abs(m.joint_target_kd.numpy()).max(initial=0.0)),
            "joint_passive_damping_max": _max_of(m, "joint_damping"),
            "joint_stiffness_max": float(np.abs(m.joint_target_ke.numpy()).max(initial=0.0)),
            "joint_friction_max": _max_of(m, "joint_friction"),
            "joint_limit_ke_max": _max_of(m, "joint_limit_ke"),
            "shapes": m.shape_count, "contact": "none: no shapes are built",
            "loads": [f"{ld.kind} ({ld.frame}) on {ld.body} in State.body_f, from the step's start state"
                      for ld in p.scene.loads],
            "reactions": "not read back",
        }
        if n > 1:
            out["worlds"] = n
        if p.settings.dt is not None:
            from dalembert.adapters.mjx.parity import float32_floor

            out["float32_floor"] = float32_floor(p.scene, p.times, p.settings.dt)
        return out


def _build(scenes, family, options):
    """The Newton model of ``scenes`` (one world each) for a run of ``family`` with ``options``: coloured for VBD;
    Steel's angular damping set on the model (unless Newton's own is asked for); Newton's inertia balancing only with
    ``defaults=engine``. One ``NewtonModel`` per world."""
    damping = solvers.angular_damping(options)
    return build_worlds(scenes, color=family == "vbd", steel_angular_damping=damping if family == "steel" else None,
                 balance_inertia=options["defaults"] == "engine", device=device(options["device"]))


def _max_of(model, name):
    """The largest magnitude of the model's per-dof array ``name`` (0 where the model has none)."""
    a = getattr(model, name, None)
    return float(np.abs(a.numpy()).max(initial=0.0)) if a is not None else 0.0


def _outcome(p, Q, V, bad, wall):
    """World ``p``'s ``Outcome``: its samples ``Q (n, nbody, 7)``, ``V (n, nbody, 6)``, first bad sample ``bad``
    (None: none), the stepping's ``wall`` (a batch's: every world's)."""
    n_steps = int(p.steps[:bad].sum()) if bad else int(p.steps.sum())
    info = {"message": f"Newton: non-finite state (or a zero quaternion) at t = {p.times[bad]:g} s" if bad else "",
            "device": str(p.model.model.device)}
    return Outcome(lambda: _read_back(p, Q, V), wall, n_steps, n_steps, info)


def _replace_solver(p, solver):
    from dataclasses import replace

    return replace(p, solver=solver)


def _scratch_step(nm, solver, dt):
    """One step of ``solver`` on scratch states, so every kernel a step launches is compiled (or loaded from the
    cache) before a timed run: the wall time, s."""
    wp, _, _ = engine()
    a, b = fresh_states(nm)
    start = time.perf_counter()
    solver.step(a, b, nm.model.control(), None, float(dt))
    wp.synchronize_device(nm.model.device)
    return time.perf_counter() - start


def _read_back(p, Q, V):
    """The ``Trajectory`` of the sampled body states ``Q (n, nbody, 7)``, ``V (n, nbody, 6)`` (float32, NaN rows
    stay NaN), widened to double; joint coordinates from the bodies' motion."""
    from dalembert.trajectory import BodyStates, JointStates, Trajectory

    scene, index = p.scene, p.model.local
    Q, V = Q.astype(float), V.astype(float)
    bodies, joints, R = {}, {}, {}
    for b in scene.bodies:
        i = index[b.name]
        quat = spatial.xyzw_to_wxyz(Q[:, i, 3:])
        with np.errstate(invalid="ignore"):  # a diverged run's NaN rows stay NaN
            R[b.name] = spatial.quat_to_matrix(spatial.quat_normalize(quat))
        bodies[b.name] = BodyStates(Q[:, i, :3].copy(), quat, V[:, i, :3].copy(), V[:, i, 3:].copy())
    n = len(p.times)
    world = dict(R=np.broadcast_to(np.eye(3), (n, 3, 3)), p=np.zeros((n, 3)), v=np.zeros((n, 3)),
                 w=np.zeros((n, 3)))
    for j in scene.joints:
        c = bodies[j.child]
        if j.kind == "free":
            joints[j.name] = JointStates(*spatial.free_joint_coordinates(c.position, c.quaternion, c.velocity,
                                                                         c.angular_velocity, R[j.child]))
            continue
        if j.parent == WORLD:
            P = world
        else:
            pb = bodies[j.parent]
            P = dict(R=R[j.parent], p=pb.position, v=pb.velocity, w=pb.angular_velocity)
        with np.errstate(invalid="ignore"):
            q, v = spatial.joint_coordinates(j, P["R"], R[j.child], P["w"], c.angular_velocity, P["p"], c.position,
                                             P["v"], c.velocity)
        joints[j.name] = JointStates(q, v)
    return Trajectory(p.times, bodies, joints, {})
