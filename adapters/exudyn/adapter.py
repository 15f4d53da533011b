"""``ExudynAdapter``: the contract (``dalembert.adapters``) for Exudyn, with its own solvers.

The system is built by ``model.build`` (``describe`` gives its summary, kept for
reports), solved and sampled by ``sampling.solve``, and read back here in body
terms. Console output is switched off while solving.

Solvers by name: ``generalized-alpha`` (options ``spectral_radius``,
``newton_rtol``, ``newton_atol`` — Exudyn's default Newton tolerances cap its
accuracy), ``trapezoidal-index2``, ``explicit-euler``, ``explicit-midpoint``,
``rk33``, ``rk44``, ``rk67``, ``velocity-verlet`` (fixed step) and ``dopri5``,
``ode23`` (adaptive: ``rtol``/``atol``, driven sample by sample). ``DVERK6`` is
listed by Exudyn 1.13 but not implemented, so it is not offered. Loop closures
(``Scene.loops``, built by ``model``) run with the two implicit solvers only; each
loop's force ON its body b is read back as ``reaction_force:<loop name>``. Spring-dampers
(``Scene.springs``, ``springs``) run with every solver and both joint formulations; the audit reads
each back from the system that ran. Prismatic joints (``joint:prismatic``) are built in both joint
formulations (``model``); like revolute ones, on a free body only with redundant joints, and with
redundant joints only by the implicit solvers. Every joint is read back from the system that ran
(``joints.read_joints``: its type, axis, joint point, initial coordinate) into the audit's
``joint_readout``. A solver that
stops before the end raises, and the run is stored as ``failed`` with the time
reached.
"""

from __future__ import annotations

import numpy as np

from dalembert import contact
from dalembert import spatial
from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, option_choice
from dalembert.adapters.exudyn import sampling
from dalembert.adapters.exudyn.loops import loop_axes
from dalembert.adapters.exudyn.model import CONSTRAINED_AXES, JOINTS, NODES, TREE_JOINTS, build, rigid_bodies
from dalembert.adapters.exudyn.springs import passive_effects, unexpected_passive
from dalembert.scene import EFFECTS, LOOP_EFFECTS, SPRING_EFFECTS, WORLD

__all__ = ["ExudynAdapter"]

IMPLICIT = {"generalized-alpha": "GeneralizedAlpha", "trapezoidal-index2": "TrapezoidalIndex2"}
EXPLICIT = {"explicit-euler": "ExplicitEuler", "explicit-midpoint": "ExplicitMidpoint", "rk33": "RK33",
            "rk44": "RK44", "rk67": "RK67", "velocity-verlet": "VelocityVerlet", "dopri5": "DOPRI5", "ode23": "ODE23"}
ADAPTIVE = ("dopri5", "ode23")
STAGES = {"rk44": 4, "rk33": 3, "rk67": 7, "explicit-midpoint": 2, "dopri5": 7, "ode23": 4}
OPTIONS = ("node", "joints", "spectral_radius", "newton_rtol", "newton_atol")
# Newton tolerances used unless the options say otherwise: Exudyn's defaults
# (1e-8 relative, 1e-10 absolute) cap generalized-alpha's accuracy (measured: an orientation
# error of 9.4e-3 rad instead of 2.6e-6 on the intermediate-axis top at dt = 1e-4).
NEWTON_RTOL = 1e-12
NEWTON_ATOL = 1e-14
# Explicit solvers whose accelerations at a step's end are not those of the state they report:
# VelocityVerlet's are f(q_{n+1}, v_{n+1/2}), of the half-step velocity (measured on the double
# pendulum, against the model evaluated at the run's own sampled states: reactions off by 1.4e-3,
# 1.4e-4, 1.4e-5 relative at dt = 1e-2, 1e-3, 1e-4, every other explicit solver within 1e-15). For
# them the link accelerations are evaluated again at every sample (``_link_accelerations``).
STALE_ACCELERATIONS = ("velocity-verlet",)
# What a run with redundant joints on rotation-vector nodes reports (docs/exudyn_rotvec_lg_reaction.py).
ROTVEC_LG_REACTION = (
    "Exudyn 1.13.6: the joint reaction (ForceLocal of ObjectJointGeneric) on a body with a "
    "NodeRigidBodyRotVecLG node misses the fraction 1 - sin|phi|/|phi| of its velocity-dependent "
    "(centripetal) part, phi the body's rotation vector, at every step size, while the motion is right "
    "(measured: 3.8e-2 relative on the Kovalevskaya top tilted 0.7 rad at dt = 1e-3 and 1e-4; Newton's law on "
    "the run's own states agrees with the truth to 2e-6). Reproduction for upstream: "
    "docs/exudyn_rotvec_lg_reaction.py. Euler-parameter nodes (--option node=ep) report it exactly.")


class ExudynAdapter(Adapter):
    """Exudyn (``exudyn``), its own solvers."""

    name = "exudyn"
    # ball joints and welds only with joints=redundant, loops only with implicit solvers (see ``unsupported``)
    effects = EFFECTS | LOOP_EFFECTS | SPRING_EFFECTS
    integrators = {
        **{k: IntegratorSpec(True, OPTIONS, f"Exudyn {v}") for k, v in IMPLICIT.items()},
        **{k: IntegratorSpec(k not in ADAPTIVE, OPTIONS, f"Exudyn {v}") for k, v in EXPLICIT.items()},
    }

    def version(self):
        import exudyn

        return exudyn.__version__

    def check(self, scene, times, settings):
        super().check(scene, times, settings)
        o = settings.options
        option_choice(settings, "node", tuple(NODES))
        option_choice(settings, "joints", JOINTS)
        for key in ("spectral_radius", "newton_rtol", "newton_atol"):
            if key in o:
                try:
                    value = float(o[key])
                except (TypeError, ValueError):
                    raise ValueError(f"options.{key}: expected a number, got {o[key]!r}") from None
                if key == "spectral_radius" and not 0.0 <= value <= 1.0:
                    raise ValueError(f"options.spectral_radius: must lie in [0, 1], got {value}")
                if key != "spectral_radius" and not value > 0.0:
                    raise ValueError(f"options.{key}: must be positive, got {value}")
                if settings.integrator != "generalized-alpha":
                    raise ValueError(f"options.{key}: only generalized-alpha takes it")
        if settings.integrator in ADAPTIVE and settings.rtol is None:
            raise ValueError(f"rtol: {settings.integrator!r} is adaptive — give rtol (and atol)")

    def unsupported(self, scene, settings):
        if (why := contact.not_mapped(scene, self.name)):  # contact: not mapped here yet
            return why
        reason = super().unsupported(scene, settings)
        if reason:
            return reason
        node = settings.options.get("node", "rotvec-lg")
        redundant = settings.options.get("joints", "minimal") == "redundant"
        explicit = settings.integrator in EXPLICIT
        if scene.loops and explicit:
            return ("loop closures with an explicit integrator: Exudyn's explicit solvers solve no algebraic "
                    "constraints (a closure is an index-3 DAE: use generalized-alpha or trapezoidal-index2)")
        for name, rows in loop_axes(scene).items() if scene.loops else ():
            if rows.axes == (0,):
                return (f"loop {name!r}: a distance loop whose one row is redundant at the initial state — Exudyn's "
                        "Newton solver needs independent constraint rows (exudyn.loops)")
        if node == "ep" and explicit and rigid_bodies(scene, redundant):
            return ("Exudyn: explicit integrator detected node which contains algebraic variables — "
                    "Euler-parameter nodes need an implicit solver")
        if redundant:
            if explicit and any(j.kind != "free" for j in scene.joints):
                return ("Exudyn: explicit integrator detected object which contains constraints that cannot be "
                        "solved — redundant-coordinate joints (an index-3 DAE) need an implicit solver")
            return None
        kinds = sorted({j.kind for j in scene.joints if j.kind in ("ball", "weld")})
        if kinds:
            return (f"joint:{', joint:'.join(kinds)} with joints=minimal: ObjectKinematicTree has single-axis "
                    f"joints only — use --option joints=redundant")
        free = {j.child for j in scene.joints if j.kind == "free"}
        for j in scene.joints:
            if j.kind in TREE_JOINTS and j.parent != WORLD and j.parent in free:
                return (f"a {j.kind} joint on a free body: the kinematic tree here has a fixed base — use "
                        "--option joints=redundant")
        return None

    def variants(self, scene):
        """Default matrix: each node type where the scene has rigid-body nodes, both joint formulations
        where it has joints, the redundant one on rotation-vector (the default) and Euler-parameter nodes
        (whose joint reactions are exact where the rotation-vector node's are not: ROTVEC_LG_REACTION)."""
        out = [{}]
        if any(j.kind == "free" for j in scene.joints):
            out += [{"node": n} for n in NODES if n != "rotvec-lg"]
        if any(j.kind != "free" for j in scene.joints):
            out += [{"joints": "redundant"}, {"joints": "redundant", "node": "ep"}]
        return out

    # ------------------------------------------------------------- build
    def describe(self, scene, settings):
        return build(scene, settings, assemble=False)["summary"]

    def prepare(self, scene, times, settings):
        # The system is built once: Exudyn's solvers start every solve from its initial configuration, so each solve
        # of it repeats the first bit for bit (measured: every run of the default matrix Exudyn supports, three
        # solves of one system against one of a fresh system each: samples, samples read, misses and errors equal).
        # ``run`` adds ``late`` here once Exudyn's stored sensors have missed a sample of this run (then it samples
        # from Python)
        return dict(scene=scene, times=np.asarray(times, dtype=float), settings=settings, built=build(scene, settings))

    # ------------------------------------------------------------- run
    def _settings(self, p):
        import exudyn as exu

        s = exu.SimulationSettings()
        st = p["settings"]
        times = p["times"]
        s.solution.file.write = False
        s.timeIntegration.verboseMode = 0
        s.timeIntegration.endTime = float(times[-1])
        s.timeIntegration.startTime = float(times[0])
        s.timeIntegration.solverType = getattr(exu.DynamicSolverType, {**IMPLICIT, **EXPLICIT}[st.integrator])
        if st.integrator in ADAPTIVE:
            s.timeIntegration.automaticStepSize = True
            s.timeIntegration.relativeTolerance = float(st.rtol)
            s.timeIntegration.absoluteTolerance = float(st.atol if st.atol is not None else st.rtol)
            s.timeIntegration.numberOfSteps = 1  # Exudyn's largest step = horizon / numberOfSteps: the samples cap it
            s.timeIntegration.initialStepSize = float(times[1] - times[0])
            s.timeIntegration.minimumStepSize = sampling.MIN_STEP_FRACTION * float(times[1] - times[0])
        else:
            s.timeIntegration.automaticStepSize = False
            s.timeIntegration.numberOfSteps = int(round((times[-1] - times[0]) / st.dt))
        if st.integrator == "generalized-alpha":
            o = st.options
            if "spectral_radius" in o:  # else Exudyn's own default
                s.timeIntegration.generalizedAlpha.spectralRadius = float(o["spectral_radius"])
            s.timeIntegration.newton.relativeTolerance = float(o.get("newton_rtol", NEWTON_RTOL))
            s.timeIntegration.newton.absoluteTolerance = float(o.get("newton_atol", NEWTON_ATOL))
        return s

    def run(self, prepared):
        import exudyn as exu

        p = prepared
        times, integrator = p["times"], p["settings"].integrator
        console = exu.config.printToConsole
        exu.config.printToConsole = False  # silent unless the user asks (Exudyn prints solver banners)
        try:
            # once Exudyn's own sampling has missed a sample of this run, its next solves sample from Python
            # at once: the run repeats the same steps, and a solve thrown away was the timed repeats' overhead
            late = p.get("late")
            solved = self._solve(p, stored=late is None)
            if late is None and solved["late"] is not None:  # Exudyn's own sampling missed a sample
                late = p["late"] = solved["late"]
                solved = self._solve(p, stored=False)
            if late is not None:
                solved["sampling"] = f"from Python ({late})"
        finally:
            exu.config.printToConsole = console
        built, it, error, read = solved["built"], solved["it"], solved["error"], solved["read"]
        # complete = every sample read (Exudyn's accumulated time may end a few ulps short of the horizon)
        if error is not None or read != len(times):
            missing = "" if read == len(times) else f" ({len(times) - read} sample(s) not reached)"
            if solved["stalled"] is not None:  # our stop, not Exudyn's: its message would only echo ours
                missing, error = f"{missing}: {solved['stalled']}", None
            raise RuntimeError(f"Exudyn solver stopped at t = {solved['reached']:g} s of {times[-1]:g} s{missing}"
                               + (f": {error}" if error else ""))

        def read():
            if built["links"] and integrator in EXPLICIT:
                # explicit solvers keep no accelerations at sample 0, and some none of the sampled state
                # at any sample (STALE_ACCELERATIONS): Exudyn evaluates them at the sampled states instead
                self._link_accelerations(p, solved["values"],
                                         range(len(times)) if integrator in STALE_ACCELERATIONS else [0])
            return self._read_back(p, built, solved["values"])

        rejected = int(it.rejectedAutomaticStepSizeSteps) if it is not None else 0
        info = {"newton_steps": int(it.newtonStepsCount) if it is not None else 0, "rejected_steps": rejected,
                "summary": built["summary"], "sampling": solved["sampling"],
                "constraints": sum(sum(CONSTRAINED_AXES[p["scene"].joint(c).kind]) for c in built["redundant_joints"])
                + sum(sum(r.axes) for r in built["loop_rows"].values()),
                "loop_rows": {name: dict(constrained=sum(r.axes), dropped=list(r.dropped))
                              for name, r in built["loop_rows"].items()},
                "built": built}  # the system that ran, for the audit to read back
        n_rhs = (solved["steps"] + rejected) * STAGES.get(integrator, 1)
        return Outcome(read, solved["wall"], solved["steps"], n_rhs, info)

    def _solve(self, p, stored):
        """One solve of the prepared system: ``sampling.solve`` on it, and the system (``built``)."""
        st, built = p["settings"], p["built"]
        return dict(sampling.solve(built["mbs"], built["sensors"], self._settings(p), p["times"],
                                   None if st.integrator in ADAPTIVE else st.dt, stored), built=built)

    def _link_accelerations(self, p, values, samples):
        """The kinematic tree's link accelerations at the sampled joint states ``values[("__q", "q")]``,
        ``values[("__v", "v")]`` for the sample indices ``samples``, written over ``values[(link, "a")]``:
        on a fresh system, each state is set and its joint accelerations solved from Exudyn's own mass
        matrix and ODE2 right-hand side (``M q'' = f(q, q')``), then the links' acceleration sensors read."""
        import exudyn as exu

        built = build(p["scene"], p["settings"])
        mbs, current = built["mbs"], exu.ConfigurationType.Current
        console = exu.config.printToConsole
        exu.config.printToConsole = False
        try:
            solver = exu.MainSolverExplicit()
            solver.InitializeSolver(mbs, self._settings(p))
            n = solver.GetODE2size()
            for k in samples:
                mbs.systemData.SetODE2Coordinates(list(values[("__q", "q")][k][:n]), configuration=current)
                mbs.systemData.SetODE2Coordinates_t(list(values[("__v", "v")][k][:n]), configuration=current)
                solver.ComputeMassMatrix(mbs)
                solver.ComputeODE2RHS(mbs)
                mass = np.asarray(solver.GetSystemMassMatrix(), dtype=float)[:n, :n]
                rhs = np.asarray(solver.GetSystemResidual(), dtype=float)[:n]
                mbs.systemData.SetODE2Coordinates_tt(list(np.linalg.solve(mass, rhs)), configuration=current)
                for name in built["links"]:
                    values[(name, "a")][k] = np.array(mbs.GetSensorValues(built["sensors"][name]["a"]), dtype=float)
            solver.FinalizeSolver(mbs, self._settings(p))
        finally:
            exu.config.printToConsole = console

    def _read_back(self, p, built, values):
        from dalembert.trajectory import BodyStates, JointStates, Trajectory

        scene, times = p["scene"], p["times"]
        n = len(times)

        def series(body, key, width):  # (n, width): stored rows, or the samples read from Python
            v = values[(body, key)]
            return (v if isinstance(v, np.ndarray) else np.vstack(v))[:, :width]

        bodies, R_WB = {}, {}
        for b in scene.bodies:
            R_WE = series(b.name, "R", 9).reshape(n, 3, 3)  # row-major in sensor output
            R_EB = built["X_EB"].get(b.name, (None, np.eye(3)))[1]  # a rigid body's E is B
            R_WB[b.name] = R_WE @ R_EB
            finite = np.all(np.isfinite(R_WB[b.name]), axis=(1, 2))
            quat = np.full((n, 4), np.nan)
            quat[finite] = spatial.matrix_to_quat(R_WB[b.name][finite])
            bodies[b.name] = BodyStates(series(b.name, "p", 3), quat, series(b.name, "v", 3),
                                        series(b.name, "w", 3), rotation=R_WB[b.name])
        joints, reactions = {}, {}
        loop_forces = self._loop_forces(scene, built, bodies, R_WB, series)
        if built["links"]:  # minimal coordinates: the tree's own; reactions by Newton's law per link
            q, v = series("__q", "q", len(built["links"])), series("__v", "v", len(built["links"]))
            for i, name in enumerate(built["links"]):
                joints[name] = JointStates(q[:, i:i + 1], v[:, i:i + 1])
            for name in reversed(built["links"]):  # children first
                body = scene.body(name)
                f = body.mass * (series(name, "a", 3) - np.asarray(scene.gravity))
                for ld in scene.loads:
                    if ld.body == name and ld.kind == "force":
                        f -= spatial.load_to_world(ld, R_WB[name])
                for child in built["links"]:
                    if scene.joint(child).parent == name:
                        f += reactions[child]
                for lp in scene.loops:  # the loop forces on this link (equal and opposite on a and b)
                    if name in (lp.body_a, lp.body_b):
                        f -= loop_forces[lp.name] if lp.body_b == name else -loop_forces[lp.name]
                for sp in scene.springs:  # Exudyn's spring force: its Force is the one on a's point
                    if name in (sp.body_a, sp.body_b):
                        f_a = series(f"__spring:{sp.name}", "f", 3)
                        f -= f_a if sp.body_a == name else -f_a
                reactions[name] = f
        for child, R0 in built["redundant_joints"].items():  # redundant coordinates: from the bodies
            j = scene.joint(child)
            R_WP = np.eye(3) if j.parent == WORLD else R_WB[j.parent]
            zero = np.zeros((n, 3))
            P = None if j.parent == WORLD else bodies[j.parent]
            C = bodies[child]
            joints[child] = spatial.joint_coordinates(
                j, R_WP, R_WB[child], zero if P is None else P.angular_velocity, C.angular_velocity,
                p_WP=zero if P is None else P.position, p_WC=C.position,
                v_WP_W=zero if P is None else P.velocity, v_WC_W=C.velocity)
            f_local = series(f"__joint:{child}", "f", 3)
            reactions[child] = -np.einsum("...ij,...j->...i", R_WP @ R0, f_local)  # ON the child, world axes
        joints = {k: v if isinstance(v, JointStates) else JointStates(*v) for k, v in joints.items()}
        extras = {f"reaction_force:{c}": f for c, f in {**reactions, **loop_forces}.items()}
        return Trajectory(times, bodies, joints, extras)

    @staticmethod
    def _loop_forces(scene, built, bodies, R_WB, series):
        """Each loop's force ON its body b (N, world), (n, 3) per loop name, from its constraint object's
        sensor: an ObjectJointGeneric's ForceLocal is the force on marker 0's side (body a) in marker 0's
        frame Ja (as a tree joint's, ``model``), so ON b it is ``-R_WB_a R_BJa ForceLocal``; an
        ObjectConnectorDistance's Force is a scalar, the tension, pulling b towards a along the line
        between the points (both checked against the reference's multipliers, tests/test_exudyn_loops.py)."""
        def point(body, p):  # the loop point in world, (n, 3)
            if body == WORLD:
                return np.broadcast_to(np.asarray(p, dtype=float), bodies[next(iter(bodies))].position.shape)
            return bodies[body].position + R_WB[body] @ np.asarray(p, dtype=float)

        out = {}
        for lp in scene.loops:
            f = series(f"__loop:{lp.name}", "f", 1 if lp.kind == "distance" else 3)
            if lp.kind == "distance":
                d_ba = point(lp.body_a, lp.point_a) - point(lp.body_b, lp.point_b)
                out[lp.name] = f * d_ba / np.linalg.norm(d_ba, axis=-1, keepdims=True)
            else:
                R_WJa = (np.eye(3) if lp.body_a == WORLD else R_WB[lp.body_a]) @ built["loops"][lp.name]
                out[lp.name] = -np.einsum("...ij,...j->...i", R_WJa, f)
        return out

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        scene, st = prepared["scene"], prepared["settings"]
        return {
            "gravity": tuple(scene.gravity) if any(scene.gravity) else (0.0, 0.0, 0.0),
            "gravity_loads": "mass-proportional (CreateRigidBody / KinematicTree)" if any(scene.gravity) else "none",
            "node": st.options.get("node", "rotvec-lg"), "joints": st.options.get("joints", "minimal"),
            "solver": {**IMPLICIT, **EXPLICIT}[st.integrator],
            "constraints": outcome.info.get("constraints", 0), "contacts": 0,
            "model": outcome.info.get("summary", ""),
            "newton_steps": outcome.info.get("newton_steps", 0),
            "rejected_steps": outcome.info.get("rejected_steps", 0),
            "exudyn_version": self.version(),
            "reactions": self._reaction_method(scene, st),
            **({"loops": self._loop_audit(scene, outcome)} if scene.loops else {}),
            **self._spring_audit(scene, outcome),
            **self._joint_audit(outcome),
            **({"known_issue": ROTVEC_LG_REACTION} if self._rotvec_lg_reactions(scene, st) else {}),
        }

    @staticmethod
    def _loop_audit(scene, outcome):
        """What the run made of the scene's loop closures (``exudyn.loops``)."""
        rows = outcome.info.get("loop_rows", {})
        return {
            "closures": {lp.name: (f"{'ObjectConnectorDistance' if lp.kind == 'distance' else 'ObjectJointGeneric'} "
                                   f"({lp.kind}), {rows[lp.name]['constrained']} row(s)"
                                   + (f"; left out as redundant at t = 0: {', '.join(rows[lp.name]['dropped'])}"
                                      if rows.get(lp.name, {}).get("dropped") else ""))
                         for lp in scene.loops if lp.name in rows},
            "scene": str(scene.loop_summary()),
            "redundant_rows": ("only the rows independent at the initial state are given to Exudyn (its default "
                               "EXUdense solver stops on the singular Jacobian of redundant rows; Eigen's FullPivLU, "
                               "ignoreSingularJacobian=True, stalls Newton at a singular position): see exudyn.loops"),
            "reaction": ("the force ON body b: the ObjectJointGeneric's ForceLocal (on body a, in its marker "
                         "frame) turned into world axes and negated; the ObjectConnectorDistance's Force (a scalar, "
                         "the tension) along the line from b's point to a's"),
        }

    @staticmethod
    def _joint_audit(outcome):
        """The joints as the system that ran holds them (``joints.read_joints`` once it was assembled: joint
        type, axis, joint point, initial coordinate and rate read from Exudyn, each compared with the scene)."""
        built = outcome.info.get("built")
        if built is None or not built["joint_readout"]:
            return {}
        return {"joint_readout": {child: {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in got.items()}
                                 for child, got in built["joint_readout"].items()}}

    @staticmethod
    def _spring_audit(scene, outcome):
        """The springs as the system that ran holds them (``springs.read_springs`` once it was assembled:
        parameters, ends, initial length and tension read from Exudyn, each compared with the scene) and every
        passive force element it carries (``springs.passive_effects``): the springs' connectors and nothing
        else."""
        built = outcome.info.get("built")
        if built is None:  # an outcome that did not come from ``run`` (which always keeps its system)
            return {}
        passive = passive_effects(built["mbs"])
        out = {"passive": passive}
        if scene.springs:
            out["springs"] = built["spring_readout"]
        rigid = sum(owner != WORLD for owner in built["owners"].values())
        out["passive_extra"] = unexpected_passive(passive, scene, rigid)  # empty: no passive force but the scene's
        return out

    @staticmethod
    def _rotvec_lg_reactions(scene, settings):
        """Whether the run reports joint reactions from bodies on rotation-vector nodes."""
        o = settings.options
        return (o.get("joints", "minimal") == "redundant" and o.get("node", "rotvec-lg") == "rotvec-lg"
                and any(j.kind != "free" for j in scene.joints))

    @staticmethod
    def _reaction_method(scene, settings):
        """How the run's joint reactions are obtained (for the audit)."""
        if not any(j.kind != "free" for j in scene.joints):
            return "none (no joints)"
        if settings.options.get("joints", "minimal") == "redundant":
            return ("each joint's ForceLocal (ObjectJointGeneric), turned into world axes, negated: the force ON "
                    "the child")
        how = ("Newton's law per link, m (a - g) - loads + children's reactions"
               + (" - the loops' forces on the link" if scene.loops else "")
               + ", with a from the tree's acceleration sensors")
        if settings.integrator in STALE_ACCELERATIONS:
            return how + (", evaluated by Exudyn at each sampled state (its step-end accelerations are the "
                          "half-step velocity's)")
        return how
