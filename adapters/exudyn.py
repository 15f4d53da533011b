"""Exudyn adapter: free bodies on rigid-body nodes, jointed trees in minimal
coordinates (``ObjectKinematicTree``), with Exudyn's own solvers.

Model (``describe`` gives the summary kept for reports):

* Free bodies: ``CreateRigidBody`` with ``RigidBodyInertia(mass, I, com=0,
  inertiaTensorAtCOM=True)`` — the inertia an ``ObjectRigidBody`` takes is
  about the node reference point, so saying "at COM" explicitly matters (the
  reference point is the COM here); ``initialAngularVelocity`` is given in
  world axes and ``initialVelocity`` is the reference point's. Node type by
  option ``node``: ``rotvec-lg`` (``NodeRigidBodyRotVecLG``, default: works
  with explicit and implicit solvers), ``ep`` (Euler parameters: an algebraic
  unit-norm constraint, so implicit solvers only), ``rxyz`` (Tait-Bryan angles,
  singular at +-90 degrees of the middle angle).
* Revolute trees (option ``joints=minimal``, the default): one
  ``ObjectKinematicTree`` whose links rotate about their local z; each link
  frame is the scene's child joint frame turned so that z is the joint axis.
  Ball joints and welds are not single-axis joints: ``unsupported``.
* Loads: ``LoadForceVector``/``LoadTorqueVector`` on a rigid marker at the
  body point, ``bodyFixed=True`` for follower loads (with ``bodyFixed=False``
  the force stays world-fixed: phi(2 s) = 2.44 rad instead of 12 on the rod).
* Gravity only when the scene has it (Exudyn adds none by default).

Output stays in memory: no solution file and no stored sensor series. A
post-step user function reads the sensors at the step that lands on each sample
time (fixed-step solvers use a step that divides the sample interval). Exudyn's
own sensor schedule is not used: it compares an accumulated time with the
schedule and, after ~3e4 steps, writes a sample one step late (measured on the
1000-s long-horizon case at dt = 1e-2: 275.81 s for 275.8 s). Console output
is switched off while solving.

Solvers by name: ``generalized-alpha`` (options ``spectral_radius``,
``newton_rtol``, ``newton_atol`` — Exudyn's default Newton tolerances cap its
accuracy), ``trapezoidal-index2``, ``explicit-euler``, ``explicit-midpoint``,
``rk33``, ``rk44``, ``rk67``, ``velocity-verlet`` (fixed step) and ``dopri5``,
``ode23`` (adaptive: ``rtol``/``atol``; not yet runnable here — their steps do not
end on the sample times, see ``unsupported``). ``DVERK6`` is listed by Exudyn
1.13 but not implemented, so it is not offered. Redundant-coordinate joints
(``joints=redundant``) are not implemented yet. A solver that stops before the end
raises, and the run is stored as ``failed`` with the time reached.
"""

from __future__ import annotations

import time

import numpy as np

from adapters import Adapter, IntegratorSpec, Outcome
from dalembert import spatial
from dalembert.scene import EFFECTS, WORLD

__all__ = ["ExudynAdapter"]

IMPLICIT = {"generalized-alpha": "GeneralizedAlpha", "trapezoidal-index2": "TrapezoidalIndex2"}
EXPLICIT = {"explicit-euler": "ExplicitEuler", "explicit-midpoint": "ExplicitMidpoint", "rk33": "RK33",
            "rk44": "RK44", "rk67": "RK67", "velocity-verlet": "VelocityVerlet", "dopri5": "DOPRI5", "ode23": "ODE23"}
ADAPTIVE = ("dopri5", "ode23")
NODES = {"rotvec-lg": "RotationRotationVector", "ep": "RotationEulerParameters", "rxyz": "RotationRxyz"}
JOINTS = ("minimal",)
OPTIONS = ("node", "joints", "spectral_radius", "newton_rtol", "newton_atol")
# Newton tolerances used unless the options say otherwise: Exudyn's defaults
# (1e-8 relative, 1e-10 absolute) cap generalized-alpha's accuracy (issue 6:
# 9.4e-3 rad instead of 2.6e-6 on the intermediate-axis top at dt = 1e-4).
NEWTON_RTOL = 1e-12
NEWTON_ATOL = 1e-14


def _axis_frame(axis):
    """A rotation whose third column is the unit ``axis`` (link z = joint axis)."""
    z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


class ExudynAdapter(Adapter):
    """Exudyn (``exudyn``), its own solvers."""

    name = "exudyn"
    effects = EFFECTS - {"joint:ball", "joint:weld"}  # ObjectKinematicTree: single-axis joints only
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
        if o.get("node", "rotvec-lg") not in NODES:
            raise ValueError(f"options.node: unknown {o['node']!r} — use one of {list(NODES)}")
        if o.get("joints", "minimal") not in JOINTS:
            raise ValueError(f"options.joints: unknown {o['joints']!r} — use one of {list(JOINTS)}")
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
        if settings.integrator in ADAPTIVE:
            return ("not yet supported by this adapter: Exudyn's adaptive explicit solvers write sensors at "
                    "their own step ends, which do not fall on the sample times, and the adapter does not yet "
                    "stop the solver at each sample")
        node = settings.options.get("node", "rotvec-lg")
        if node == "ep" and settings.integrator in EXPLICIT and any(j.kind == "free" for j in scene.joints):
            return ("Exudyn: explicit integrator detected node which contains algebraic variables — "
                    "Euler-parameter nodes need an implicit solver")
        free = {j.child for j in scene.joints if j.kind == "free"}
        for j in scene.joints:
            if j.kind == "revolute" and j.parent != WORLD and j.parent in free:
                return "a revolute joint on a free body: the kinematic tree here has a fixed base"
        return None

    # ------------------------------------------------------------- build
    def describe(self, scene, settings):
        return self._build(scene, np.array([0.0, 1.0]), settings, describe_only=True)

    def _build(self, scene, times, settings, describe_only=False):
        import exudyn as exu
        from exudyn.itemInterface import (LoadForceVector, LoadTorqueVector, MarkerBodyRigid,
                                          MarkerKinematicTreeRigid, NodeGenericODE2, ObjectKinematicTree,
                                          SensorBody, SensorKinematicTree, SensorNode)
        from exudyn.rigidBodyUtilities import RigidBodyInertia

        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        g = np.array(scene.gravity, dtype=float)
        node_type = getattr(exu.NodeType, NODES[settings.options.get("node", "rotvec-lg")])
        OV = exu.OutputVariableType
        summary, sensors, markers = [], {}, {}
        # --- free bodies
        for j in scene.joints:
            if j.kind != "free":
                continue
            body = scene.body(j.child)
            R0 = spatial.quat_to_matrix(j.q0[3:])
            kwargs = dict(inertia=RigidBodyInertia(body.mass, body.inertia_matrix, [0.0, 0.0, 0.0], True),
                          referencePosition=list(j.q0[:3]), referenceRotationMatrix=R0,
                          initialVelocity=list(j.v0[:3]), initialAngularVelocity=list(R0 @ np.array(j.v0[3:])),
                          nodeType=node_type, returnDict=True)
            if np.any(g):
                kwargs["gravity"] = list(g)
            made = mbs.CreateRigidBody(**kwargs)
            obj = made["bodyNumber"]
            markers[body.name] = lambda p, obj=obj: mbs.AddMarker(MarkerBodyRigid(bodyNumber=obj, localPosition=list(p)))
            sensors[body.name] = {k: mbs.AddSensor(SensorBody(bodyNumber=obj, outputVariableType=v))
                                  for k, v in (("p", OV.Position), ("R", OV.RotationMatrix), ("v", OV.Velocity),
                                               ("w", OV.AngularVelocity))}
            summary.append(f"{body.name}: ObjectRigidBody on {node_type.name} node, mass {body.mass:g} kg, "
                           f"inertia at COM (inertiaTensorAtCOM=True)")
        # --- revolute tree(s) in one kinematic tree
        links = [b for b in scene.topological_order() if scene.joint(b.name).kind == "revolute"]
        tree = None
        if links:
            index = {b.name: i for i, b in enumerate(links)}
            frames = {}  # body -> (p_LB, R_LB): x_L = p_LB + R_LB x_B
            Ts, offsets, coms, inertias, masses, parents, q0, v0 = [], [], [], [], [], [], [], []
            for b in links:
                j = scene.joint(b.name)
                R_CJ = spatial.quat_to_matrix(j.child_quat)
                R_A = _axis_frame(j.axis)
                R_LB = R_A.T @ R_CJ.T
                p_LB = -R_LB @ np.array(j.child_point)
                frames[b.name] = (p_LB, R_LB)
                R_PJ = spatial.quat_to_matrix(j.parent_quat)
                if j.parent == WORLD:
                    p_PL, R_PL = np.zeros(3), np.eye(3)
                else:
                    p_PL, R_PL = frames[j.parent]
                Ts.append(R_PL @ R_PJ @ R_A)
                offsets.append(p_PL + R_PL @ np.array(j.parent_point))
                coms.append(p_LB)
                inertias.append(R_LB @ b.inertia_matrix @ R_LB.T)
                masses.append(b.mass)
                parents.append(-1 if j.parent == WORLD else index[j.parent])
                q0.append(j.q0[0])
                v0.append(j.v0[0])
            n = len(links)
            node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * n, initialCoordinates=q0,
                                               initialCoordinates_t=v0, numberOfODE2Coordinates=n))
            tree = mbs.AddObject(ObjectKinematicTree(
                nodeNumber=node, jointTypes=[exu.JointType.RevoluteZ] * n, linkParents=parents,
                jointTransformations=exu.Matrix3DList(Ts), jointOffsets=exu.Vector3DList(offsets),
                linkInertiasCOM=exu.Matrix3DList(inertias), linkCOMs=exu.Vector3DList(coms), linkMasses=masses,
                baseOffset=[0.0, 0.0, 0.0], gravity=list(g)))
            for b in links:
                i, (p_LB, R_LB) = index[b.name], frames[b.name]
                markers[b.name] = lambda p, i=i, p_LB=p_LB, R_LB=R_LB: mbs.AddMarker(MarkerKinematicTreeRigid(
                    objectNumber=tree, linkNumber=i, localPosition=list(p_LB + R_LB @ np.array(p))))
                sensors[b.name] = {k: mbs.AddSensor(SensorKinematicTree(
                    objectNumber=tree, linkNumber=i, localPosition=list(p_LB), outputVariableType=v)) for k, v in (("p", OV.Position), ("R", OV.RotationMatrix),
                                                        ("v", OV.Velocity), ("w", OV.AngularVelocity))}
            sensors["__q"] = {"q": mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=OV.Coordinates))}
            sensors["__v"] = {"v": mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=OV.Coordinates_t))}
            summary.append(f"ObjectKinematicTree: {n} RevoluteZ link(s) {[b.name for b in links]} "
                           f"(minimal coordinates), gravity {g.tolist()}")
            link_frames = frames
        else:
            link_frames = {}
        # --- loads
        for ld in scene.loads:
            R_LB = link_frames.get(ld.body, (None, np.eye(3)))[1]
            marker = markers[ld.body](ld.point)
            follower = ld.frame == "body"
            vec = list(R_LB @ np.array(ld.vector)) if follower else list(ld.vector)
            Load = LoadForceVector if ld.kind == "force" else LoadTorqueVector
            mbs.AddLoad(Load(markerNumber=marker, loadVector=vec, bodyFixed=follower))
            summary.append(f"{Load.__name__} on {ld.body} at {list(ld.point)}, bodyFixed={follower}")
        text = "\n".join(summary) + "\n"
        if describe_only:
            return text
        mbs.Assemble()
        return dict(SC=SC, mbs=mbs, sensors=sensors, link_frames=link_frames, links=[b.name for b in links],
                    summary=text)

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
        if st.integrator in ADAPTIVE:
            s.timeIntegration.automaticStepSize = True
            s.timeIntegration.relativeTolerance = float(st.rtol)
            s.timeIntegration.absoluteTolerance = float(st.atol if st.atol is not None else st.rtol)
            s.timeIntegration.numberOfSteps = len(times) - 1  # initial step guess: the sample interval
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
        built = self._build(p["scene"], p["times"], p["settings"])  # a fresh system per run (Exudyn keeps state)
        mbs = built["mbs"]
        solver = getattr(exu.DynamicSolverType, {**IMPLICIT, **EXPLICIT}[p["settings"].integrator])
        settings = self._settings(p)
        samples = self._sampler(p, built)
        console = exu.config.printToConsole
        exu.config.printToConsole = False  # silent unless the user asks (Exudyn prints solver banners)
        try:
            start = time.perf_counter()
            try:
                ok = mbs.SolveDynamic(settings, solverType=solver)
                error = None
            except Exception as e:  # Exudyn raises on solver failure
                ok, error = False, e
            wall = time.perf_counter() - start
        finally:
            exu.config.printToConsole = console
        it = mbs.sys["dynamicSolver"].it if "dynamicSolver" in mbs.sys else None
        reached = float(it.currentTime) if it is not None else float("nan")
        if not ok or error is not None or reached < p["times"][-1] * (1 - 1e-12):
            raise RuntimeError(f"Exudyn solver stopped at t = {reached:g} s of {p['times'][-1]:g} s"
                               + (f": {error}" if error else ""))
        if samples["next"] != len(p["times"]):
            raise RuntimeError(f"Exudyn: {len(p['times']) - samples['next']} sample(s) not reached "
                               f"(first at t = {p['times'][samples['next']]!r} s)")
        traj = self._read_back(p, built, samples["values"])
        n_steps = int(it.currentStepIndex) - 1 if it is not None else 0
        stages = {"rk44": 4, "rk33": 3, "rk67": 7, "explicit-midpoint": 2}.get(p["settings"].integrator, 1)
        info = {"newton_steps": int(it.newtonStepsCount) if it is not None else 0,
                "rejected_steps": int(it.rejectedAutomaticStepSizeSteps) if it is not None else 0,
                "summary": built["summary"]}
        return Outcome(traj, wall, n_steps, n_steps * stages, info)

    @staticmethod
    def _sampler(p, built):
        """Install a post-step user function that reads every sensor at each sample time."""
        mbs, times = built["mbs"], p["times"]
        n = len(times)
        # A step "is" sample k when its time is within half a step of t_k (fixed step: exactly one step is).
        half = 0.5 * (p["settings"].dt or (times[1] - times[0]))
        flat = [(body, key, sid) for body, group in built["sensors"].items() for key, sid in group.items()]
        values = {(body, key): [None] * n for body, key, _ in flat}
        state = {"next": 1, "values": values}
        for body, key, sid in flat:  # sample 0: the assembled initial state
            values[(body, key)][0] = np.array(mbs.GetSensorValues(sid), dtype=float)

        def post_step(mbs_, t):
            k = state["next"]
            if k < n and abs(t - times[k]) <= half:
                for body, key, sid in flat:
                    values[(body, key)][k] = np.array(mbs_.GetSensorValues(sid), dtype=float)
                state["next"] = k + 1
            return True

        mbs.SetPostStepUserFunction(post_step)
        return state

    def _read_back(self, p, built, values):
        from dalembert.trajectory import BodyStates, JointStates, Trajectory

        scene, times = p["scene"], p["times"]
        n = len(times)

        def series(body, key, width):
            return np.array([np.ravel(v)[:width] if v is not None else np.full(width, np.nan)
                             for v in values[(body, key)]], dtype=float)

        bodies = {}
        for b in scene.bodies:
            R_WL = series(b.name, "R", 9).reshape(n, 3, 3)  # row-major in sensor output
            R_LB = built["link_frames"].get(b.name, (None, np.eye(3)))[1]
            R_WB = R_WL @ R_LB
            finite = np.all(np.isfinite(R_WB), axis=(1, 2))
            quat = np.full((n, 4), np.nan)
            quat[finite] = spatial.matrix_to_quat(R_WB[finite])
            bodies[b.name] = BodyStates(series(b.name, "p", 3), quat, series(b.name, "v", 3),
                                        series(b.name, "w", 3), rotation=R_WB)
        joints = {}
        if built["links"]:
            q, v = series("__q", "q", len(built["links"])), series("__v", "v", len(built["links"]))
            for i, name in enumerate(built["links"]):
                joints[name] = JointStates(q[:, i:i + 1], v[:, i:i + 1])
        return Trajectory(times, bodies, joints)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        scene, st = prepared["scene"], prepared["settings"]
        return {
            "gravity": tuple(scene.gravity) if any(scene.gravity) else (0.0, 0.0, 0.0),
            "gravity_loads": "mass-proportional (CreateRigidBody / KinematicTree)" if any(scene.gravity) else "none",
            "node": st.options.get("node", "rotvec-lg"), "joints": st.options.get("joints", "minimal"),
            "solver": {**IMPLICIT, **EXPLICIT}[st.integrator],
            "constraints": 0, "contacts": 0,
            "model": outcome.info.get("summary", ""),
            "newton_steps": outcome.info.get("newton_steps", 0),
            "rejected_steps": outcome.info.get("rejected_steps", 0),
            "exudyn_version": self.version(),
        }
