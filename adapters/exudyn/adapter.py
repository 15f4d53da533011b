"""``ExudynAdapter``: the contract (``dalembert.adapters``) for Exudyn, with its own solvers.

The system is built by ``model.build`` (``describe`` gives its summary, kept for
reports), solved and sampled by ``sampling.solve``, and read back here in body
terms. Console output is switched off while solving.

Solvers by name: ``generalized-alpha`` (options ``spectral_radius``,
``newton_rtol``, ``newton_atol`` — Exudyn's default Newton tolerances cap its
accuracy), ``trapezoidal-index2``, ``explicit-euler``, ``explicit-midpoint``,
``rk33``, ``rk44``, ``rk67``, ``velocity-verlet`` (fixed step) and ``dopri5``,
``ode23`` (adaptive: ``rtol``/``atol``, driven sample by sample). ``DVERK6`` is
listed by Exudyn 1.13 but not implemented, so it is not offered. A solver that
stops before the end raises, and the run is stored as ``failed`` with the time
reached.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, option_choice
from dalembert.adapters.exudyn import sampling
from dalembert.adapters.exudyn.model import CONSTRAINED_AXES, JOINTS, NODES, build, rigid_bodies
from dalembert.scene import EFFECTS, WORLD

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


class ExudynAdapter(Adapter):
    """Exudyn (``exudyn``), its own solvers."""

    name = "exudyn"
    effects = EFFECTS  # ball joints and welds only with joints=redundant (see ``unsupported``)
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
        reason = super().unsupported(scene, settings)
        if reason:
            return reason
        node = settings.options.get("node", "rotvec-lg")
        redundant = settings.options.get("joints", "minimal") == "redundant"
        explicit = settings.integrator in EXPLICIT
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
            if j.kind == "revolute" and j.parent != WORLD and j.parent in free:
                return ("a revolute joint on a free body: the kinematic tree here has a fixed base — use "
                        "--option joints=redundant")
        return None

    def variants(self, scene):
        """Default matrix: each node type where the scene has rigid-body nodes, both joint formulations
        where it has joints."""
        out = [{}]
        if any(j.kind == "free" for j in scene.joints):
            out += [{"node": n} for n in NODES if n != "rotvec-lg"]
        if any(j.kind != "free" for j in scene.joints):
            out.append({"joints": "redundant"})
        return out

    # ------------------------------------------------------------- build
    def describe(self, scene, settings):
        return build(scene, settings, assemble=False)["summary"]

    def prepare(self, scene, times, settings):
        return dict(scene=scene, times=np.asarray(times, dtype=float), settings=settings)

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
            solved = self._solve(p, stored=True)
            if solved["late"] is not None:  # Exudyn's own sampling missed a sample: sample from Python
                solved = dict(self._solve(p, stored=False), sampling=f"from Python ({solved['late']})")
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
                self._initial_accelerations(p, solved["values"])
            return self._read_back(p, built, solved["values"])

        rejected = int(it.rejectedAutomaticStepSizeSteps) if it is not None else 0
        info = {"newton_steps": int(it.newtonStepsCount) if it is not None else 0, "rejected_steps": rejected,
                "summary": built["summary"], "sampling": solved["sampling"],
                "constraints": sum(sum(CONSTRAINED_AXES[p["scene"].joint(c).kind]) for c in built["redundant_joints"])}
        n_rhs = (solved["steps"] + rejected) * STAGES.get(integrator, 1)
        return Outcome(read, solved["wall"], solved["steps"], n_rhs, info)

    def _solve(self, p, stored):
        """One solve on a fresh system (Exudyn keeps state): ``sampling.solve`` on it, and the
        system built (``built``)."""
        st = p["settings"]
        built = build(p["scene"], st)
        return dict(sampling.solve(built["mbs"], built["sensors"], self._settings(p), p["times"],
                                   None if st.integrator in ADAPTIVE else st.dt, stored), built=built)

    def _initial_accelerations(self, p, values):
        """Exudyn's explicit solvers compute accelerations only at step ends, so the sample-0
        accelerations (for the tree's reactions) come from one explicit Euler step of 1e-30 s on a fresh
        system, which leaves every coordinate unchanged in double precision."""
        import exudyn as exu

        built = build(p["scene"], p["settings"])
        s = exu.SimulationSettings()
        s.solution.file.write = False
        s.timeIntegration.verboseMode = 0
        s.timeIntegration.endTime = 1e-30
        s.timeIntegration.numberOfSteps = 1
        built["mbs"].SolveDynamic(s, solverType=exu.DynamicSolverType.ExplicitEuler)
        for name in built["links"]:
            values[(name, "a")][0] = np.array(built["mbs"].GetSensorValues(built["sensors"][name]["a"]), dtype=float)

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
                reactions[name] = f
        for child, R0 in built["redundant_joints"].items():  # redundant coordinates: from the bodies
            j = scene.joint(child)
            R_WP = np.eye(3) if j.parent == WORLD else R_WB[j.parent]
            w_P = np.zeros((n, 3)) if j.parent == WORLD else bodies[j.parent].angular_velocity
            joints[child] = spatial.joint_coordinates(j, R_WP, R_WB[child], w_P, bodies[child].angular_velocity)
            f_local = series(f"__joint:{child}", "f", 3)
            reactions[child] = -np.einsum("...ij,...j->...i", R_WP @ R0, f_local)  # ON the child, world axes
        joints = {k: v if isinstance(v, JointStates) else JointStates(*v) for k, v in joints.items()}
        extras = {f"reaction_force:{c}": f for c, f in reactions.items()}
        return Trajectory(times, bodies, joints, extras)

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
        }
