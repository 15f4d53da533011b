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
* Jointed scenes two ways (option ``joints``):

  - ``minimal`` (default): one ``ObjectKinematicTree`` whose links rotate about
    their local z; each link frame is the scene's child joint frame turned so
    that z is the joint axis. It runs with every solver. Ball joints and welds
    are not single-axis joints: ``unsupported``. The pivot reaction is read back
    by Newton's law on each link, ``R = m a_com - F_ext - m g + sum R_children``,
    with ``a_com`` from the tree's acceleration sensor;
  - ``redundant``: every body an ``ObjectRigidBody`` (the node type as above),
    each joint an ``ObjectJointGeneric`` (revolute: the five axes other than the
    joint axis constrained; ball: translations; weld: all six) from a marker on
    the parent (marker 0) to one on the child, each marker frame = joint frame. An index-3 DAE: implicit solvers
    only. The reaction is the joint's ``ForceLocal``: the force on the marker-0
    (parent) side in the marker-0 frame, so the force ON the child in world axes is
    ``-R_WP R_PJ ForceLocal``. Initial body states come from the
    scene's joint coordinates by forward kinematics.
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
``ode23`` (adaptive: ``rtol``/``atol``). The adaptive ones are driven sample by
sample (``MainSolverExplicit.SolveSteps`` with the end time set to the next
sample, which Exudyn's step control lands on exactly), so their steps never
exceed the sample interval: without dense output, sampling at fixed times caps
the step. ``DVERK6`` is listed by Exudyn 1.13 but not implemented, so it is not
offered. A solver that stops before the end raises, and the run is stored as
``failed`` with the time reached. Steps are counted as Exudyn takes them (a post-
step call per new time), so steps Exudyn shrinks on Newton failure are counted.
"""

from __future__ import annotations

import time

import numpy as np

from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, option_choice
from dalembert import spatial
from dalembert.scene import EFFECTS, WORLD

__all__ = ["ExudynAdapter"]

IMPLICIT = {"generalized-alpha": "GeneralizedAlpha", "trapezoidal-index2": "TrapezoidalIndex2"}
EXPLICIT = {"explicit-euler": "ExplicitEuler", "explicit-midpoint": "ExplicitMidpoint", "rk33": "RK33",
            "rk44": "RK44", "rk67": "RK67", "velocity-verlet": "VelocityVerlet", "dopri5": "DOPRI5", "ode23": "ODE23"}
ADAPTIVE = ("dopri5", "ode23")
NODES = {"rotvec-lg": "RotationRotationVector", "ep": "RotationEulerParameters", "rxyz": "RotationRxyz"}
JOINTS = ("minimal", "redundant")
# ObjectJointGeneric's constrainedAxes (x, y, z translation; x, y, z rotation) in the
# joint frame, whose z is a revolute joint's axis.
CONSTRAINED_AXES = {"revolute": [1, 1, 1, 1, 1, 0], "ball": [1, 1, 1, 0, 0, 0], "weld": [1, 1, 1, 1, 1, 1]}
STAGES = {"rk44": 4, "rk33": 3, "rk67": 7, "explicit-midpoint": 2, "dopri5": 7, "ode23": 4}
OPTIONS = ("node", "joints", "spectral_radius", "newton_rtol", "newton_atol")
# Newton tolerances used unless the options say otherwise: Exudyn's defaults
# (1e-8 relative, 1e-10 absolute) cap generalized-alpha's accuracy (issue 6:
# 9.4e-3 rad instead of 2.6e-6 on the intermediate-axis top at dt = 1e-4).
# Adaptive solvers stop (the run is stored as failed, with the time reached) when a step
# would fall below this fraction of the sample interval: such a step means the solver is
# stuck (measured: ode23 on Tait-Bryan nodes at their singularity on the 50 rad/s fast spin
# shrinks its steps without end); the hard cases need no step below ~1e-3 of the interval.
MIN_STEP_FRACTION = 1e-6
# Adaptive solvers also stop after this many rejected attempts in a row at one time: Exudyn
# retries a rejected step without end once it sits at its minimum step (measured: ode23 at
# rtol 1e-9 on Tait-Bryan nodes at their singularity, t = 0.314 s on the intermediate-axis
# top, 1.2e7 attempts in a minute); a controller that shrinks the step on each rejection
# reaches any step it could accept in far fewer.
MAX_REJECTIONS_IN_A_ROW = 100
# Fixed-step runs are sampled by Exudyn's sensor schedule, shortened so that it leads the
# sample times by this many steps at the horizon: enough to stay ahead of the ulps its
# accumulated time loses (measured: 2e-8 s behind after 1e6 steps of 1e-3 s, i.e. 2e-5
# steps), and short of half a step, so each write is still the step nearest its sample.
SCHEDULE_LEAD = 0.25
# A fixed-step sample is read at the step that lands on its time to within this fraction of a
# step (Exudyn's accumulated time is off by 2e-5 steps after 1e6 steps). Exudyn shrinks
# implicit steps when Newton fails, and its grid is then lost: a sample no step lands on ends
# the run (no dense output to interpolate; reading the nearest step would shift the sample).
ON_TIME = 1e-3
NEWTON_RTOL = 1e-12
NEWTON_ATOL = 1e-14


def _rigid_bodies(scene, redundant):
    """Names of the bodies Exudyn models as ``ObjectRigidBody``: free ones, or all with redundant joints."""
    return [b.name for b in scene.topological_order() if redundant or scene.joint(b.name).kind == "free"]


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
        if node == "ep" and explicit and _rigid_bodies(scene, redundant):
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
        return self._build(scene, np.array([0.0, 1.0]), settings, describe_only=True)

    def _build(self, scene, times, settings, describe_only=False):
        import exudyn as exu
        from exudyn.itemInterface import (LoadForceVector, LoadTorqueVector, MarkerBodyRigid,
                                          MarkerKinematicTreeRigid, NodeGenericODE2, ObjectGround,
                                          ObjectJointGeneric, ObjectKinematicTree, SensorBody, SensorKinematicTree,
                                          SensorNode, SensorObject)
        from exudyn.rigidBodyUtilities import RigidBodyInertia

        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        g = np.array(scene.gravity, dtype=float)
        node_type = getattr(exu.NodeType, NODES[settings.options.get("node", "rotvec-lg")])
        redundant = settings.options.get("joints", "minimal") == "redundant"
        OV = exu.OutputVariableType
        summary, sensors, markers, bodies = [], {}, {}, {}
        # --- rigid bodies: free bodies, and every body with joints=redundant
        rigid = _rigid_bodies(scene, redundant)
        state0 = spatial.initial_body_states(scene) if rigid else {}  # world states at t = 0
        for name in rigid:
            body, s0 = scene.body(name), state0[name]
            kwargs = dict(inertia=RigidBodyInertia(body.mass, body.inertia_matrix, [0.0, 0.0, 0.0], True),
                          referencePosition=list(s0["p"]), referenceRotationMatrix=s0["R"],
                          initialVelocity=list(s0["v"]), initialAngularVelocity=list(s0["w"]),
                          nodeType=node_type, returnDict=True)
            if np.any(g):
                kwargs["gravity"] = list(g)
            obj = mbs.CreateRigidBody(**kwargs)["bodyNumber"]
            bodies[name] = obj
            markers[name] = lambda p, obj=obj: mbs.AddMarker(MarkerBodyRigid(bodyNumber=obj, localPosition=list(p)))
            sensors[name] = {k: mbs.AddSensor(SensorBody(bodyNumber=obj, outputVariableType=v))
                             for k, v in (("p", OV.Position), ("R", OV.RotationMatrix), ("v", OV.Velocity),
                                          ("w", OV.AngularVelocity))}
            summary.append(f"{name}: ObjectRigidBody on {node_type.name} node, mass {body.mass:g} kg, "
                           f"inertia at COM (inertiaTensorAtCOM=True)")
        # --- joints=redundant: generic joints between rigid bodies (marker 0 on the parent)
        redundant_joints = {}
        if redundant and any(j.kind != "free" for j in scene.joints):
            ground = mbs.AddObject(ObjectGround())
            for j in scene.joints:
                if j.kind == "free":
                    continue
                R_A = _axis_frame(j.axis) if j.kind == "revolute" else np.eye(3)
                R0 = spatial.quat_to_matrix(j.parent_quat) @ R_A  # joint frame in the parent's frame
                R1 = spatial.quat_to_matrix(j.child_quat) @ R_A
                parent = ground if j.parent == WORLD else bodies[j.parent]
                # the marker frames are the joint frames (rotationMarker0/1 are deprecated since 1.12)
                m0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=parent,
                                                   localHT=exu.HT(rotation=R0, translation=list(j.parent_point))))
                m1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=bodies[j.child],
                                                   localHT=exu.HT(rotation=R1, translation=list(j.child_point))))
                joint = mbs.AddObject(ObjectJointGeneric(markerNumbers=[m0, m1],
                                                         constrainedAxes=CONSTRAINED_AXES[j.kind]))
                sensors[f"__joint:{j.child}"] = {"f": mbs.AddSensor(SensorObject(
                    objectNumber=joint, outputVariableType=OV.ForceLocal))}
                redundant_joints[j.child] = R0
                summary.append(f"ObjectJointGeneric {j.parent} -> {j.child} ({j.kind}), constrainedAxes "
                               f"{CONSTRAINED_AXES[j.kind]} (redundant coordinates)")
        # --- joints=minimal: revolute tree(s) in one kinematic tree
        links = [] if redundant else [b for b in scene.topological_order() if scene.joint(b.name).kind == "revolute"]
        link_frames = {}  # body -> (p_LB, R_LB): x_L = p_LB + R_LB x_B
        if links:
            index = {b.name: i for i, b in enumerate(links)}
            Ts, offsets, coms, inertias, masses, parents, q0, v0 = [], [], [], [], [], [], [], []
            for b in links:
                j = scene.joint(b.name)
                R_CJ = spatial.quat_to_matrix(j.child_quat)
                R_A = _axis_frame(j.axis)
                R_LB = R_A.T @ R_CJ.T
                p_LB = -R_LB @ np.array(j.child_point)
                link_frames[b.name] = (p_LB, R_LB)
                R_PJ = spatial.quat_to_matrix(j.parent_quat)
                if j.parent == WORLD:
                    p_PL, R_PL = np.zeros(3), np.eye(3)
                else:
                    p_PL, R_PL = link_frames[j.parent]
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
            outputs = (("p", OV.Position), ("R", OV.RotationMatrix), ("v", OV.Velocity), ("w", OV.AngularVelocity),
                       ("a", OV.Acceleration))
            for b in links:
                i, (p_LB, R_LB) = index[b.name], link_frames[b.name]
                markers[b.name] = lambda p, i=i, p_LB=p_LB, R_LB=R_LB: mbs.AddMarker(MarkerKinematicTreeRigid(
                    objectNumber=tree, linkNumber=i, localPosition=list(p_LB + R_LB @ np.array(p))))
                sensors[b.name] = {k: mbs.AddSensor(SensorKinematicTree(
                    objectNumber=tree, linkNumber=i, localPosition=list(p_LB), outputVariableType=v))
                    for k, v in outputs}
            sensors["__q"] = {"q": mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=OV.Coordinates))}
            sensors["__v"] = {"v": mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=OV.Coordinates_t))}
            summary.append(f"ObjectKinematicTree: {n} RevoluteZ link(s) {[b.name for b in links]} "
                           f"(minimal coordinates), gravity {g.tolist()}")
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
                    redundant_joints=redundant_joints, summary=text)

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
            s.timeIntegration.minimumStepSize = MIN_STEP_FRACTION * float(times[1] - times[0])
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
        if built["links"] and integrator in EXPLICIT:
            self._initial_accelerations(p, solved["values"])
        traj = self._read_back(p, built, solved["values"])
        rejected = int(it.rejectedAutomaticStepSizeSteps) if it is not None else 0
        info = {"newton_steps": int(it.newtonStepsCount) if it is not None else 0, "rejected_steps": rejected,
                "summary": built["summary"], "sampling": solved["sampling"],
                "constraints": sum(sum(CONSTRAINED_AXES[p["scene"].joint(c).kind]) for c in built["redundant_joints"])}
        n_rhs = (solved["steps"] + rejected) * STAGES.get(integrator, 1)
        return Outcome(traj, solved["wall"], solved["steps"], n_rhs, info)

    def _solve(self, p, stored):
        """One solve on a fresh system (Exudyn keeps state), sampled by Exudyn or from Python.

        ``stored``: Exudyn keeps the sensors in memory, with no Python per step or sample.
        Fixed-step solvers write on Exudyn's schedule, which fires when its accumulated time
        passes its accumulated schedule; both lose ulps over many steps (measured: every sample
        one step late after 3e5 steps of 1e-3 s at the exact interval), so the schedule is
        shortened to lead the samples by ``SCHEDULE_LEAD`` steps at the horizon, still the step
        nearest each sample. Adaptive solvers run one ``SolveSteps`` per sample interval, each
        ending on its sample, where Exudyn writes the sensors (the schedule is set beyond the
        horizon, so it writes nowhere else). The time column is then checked against the
        samples, and ``late`` names the first miss. Otherwise ``_Sampler`` reads from Python.
        """
        import exudyn as exu

        built = self._build(p["scene"], p["times"], p["settings"])
        mbs, times, st = built["mbs"], p["times"], p["settings"]
        adaptive = st.integrator in ADAPTIVE
        settings = self._settings(p)
        interval, horizon = float(times[1] - times[0]), float(times[-1] - times[0])
        min_step = settings.timeIntegration.minimumStepSize if adaptive else None
        tol = ON_TIME * (min_step if adaptive else st.dt)  # a sample is on time within this, s
        flat = [(body, key, sid) for body, group in built["sensors"].items() for key, sid in group.items()]
        sampler = None
        if stored:
            for _, _, sid in flat:
                mbs.SetSensorParameter(sid, "storeInternal", True)
            settings.solution.sensors.writePeriod = (
                2.0 * horizon if adaptive else interval * (1.0 - SCHEDULE_LEAD * st.dt / horizon))
        else:
            sampler = _Sampler(mbs, flat, times, None if adaptive else tol)
        guard = _Guard(mbs, min_step) if adaptive else None
        solver = exu.MainSolverExplicit() if adaptive else None
        error = None
        start = time.perf_counter()
        try:
            if adaptive:
                self._solve_per_sample(solver, mbs, settings, times, tol, sampler)
            else:
                mbs.SolveDynamic(settings, solverType=settings.timeIntegration.solverType)
        except Exception as e:  # Exudyn raises on solver failure; what was sampled so far is kept
            error = e
        wall = time.perf_counter() - start
        it = solver.it if adaptive else mbs.sys["dynamicSolver"].it if "dynamicSolver" in mbs.sys else None
        late = None
        if stored:
            values, read, late = self._stored_samples(mbs, flat, times, tol, error)
        else:
            values, read = sampler.values, sampler.next
        stalled = guard.stalled if guard else sampler.stalled if sampler else None
        return dict(built=built, values=values, read=read, late=late, it=it, error=error, wall=wall,
                    steps=_steps(it), stalled=stalled, sampling="Exudyn's stored sensors",
                    reached=float(it.currentTime) if it is not None else float(times[max(read, 1) - 1]))

    @staticmethod
    def _stored_samples(mbs, flat, times, tol, error):
        """The stored rows at the sample times: (values, samples read, first miss or None)."""
        stored = {}
        for body, key, sid in flat:
            data = np.asarray(mbs.GetSensorStoredData(sid), dtype=float)
            stored[(body, key)] = data if data.ndim == 2 else np.empty((0, 1))
        # every sensor is written at the same steps: one time column speaks for all; extra rows
        # (written between samples, or at the horizon again) are ignored
        t = next(iter(stored.values()))[:, 0]
        rows = np.minimum(np.searchsorted(t, times - tol), max(len(t) - 1, 0))
        on_time = np.abs(t[rows] - times) <= tol if len(t) else np.zeros(len(times), bool)
        read = len(times) if on_time.all() else int(np.argmin(on_time))
        late = None
        if read < len(times) and (error is None or (len(t) and t[-1] > times[read])):
            late = (f"Exudyn's stored sensors have no row at sample {read} (t = {times[read]:.12g} s), the "
                    f"nearest at {t[rows[read]]:.12g} s" if len(t) else "Exudyn stored no sensor rows")
        return {k: v[rows[:read], 1:] for k, v in stored.items()}, read, late

    @staticmethod
    def _solve_per_sample(solver, mbs, settings, times, tol, sampler=None):
        """Adaptive explicit solvers: one ``SolveSteps`` per sample interval, ending on the sample."""
        solver.InitializeSolver(mbs, settings)
        try:
            for k in range(1, len(times)):
                solver.it.endTime = float(times[k])
                solver.SolveSteps(mbs, settings)
                if solver.it.currentTime < times[k] - tol:
                    break  # the solver gave up (step size below its minimum): the run is incomplete
                if sampler is not None:
                    sampler.read(k)
        finally:
            solver.FinalizeSolver(mbs, settings)

    def _initial_accelerations(self, p, values):
        """Exudyn's explicit solvers compute accelerations only at step ends, so the sample-0
        accelerations (for the tree's reactions) come from one explicit Euler step of 1e-30 s on a fresh
        system, which leaves every coordinate unchanged in double precision."""
        import exudyn as exu

        built = self._build(p["scene"], p["times"], p["settings"])
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
            R_WL = series(b.name, "R", 9).reshape(n, 3, 3)  # row-major in sensor output
            R_LB = built["link_frames"].get(b.name, (None, np.eye(3)))[1]
            R_WB[b.name] = R_WL @ R_LB
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
                        f -= R_WB[name] @ np.array(ld.vector) if ld.frame == "body" else np.array(ld.vector)
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


def _steps(it):
    """Accepted steps of a solve: Exudyn counts one discontinuous iteration per step where nothing
    switches (no scene here has contacts or switches); ``currentStepIndex`` restarts with each
    ``SolveSteps``. A last step of a few ulps, taken when the accumulated time ends short of the
    horizon, counts."""
    return int(it.discontinuousIterationsCount) if it is not None else 0


class _Stuck(RuntimeError):
    """An adaptive run that retries one step without end."""


class _Guard:
    """Stops an adaptive solve where Exudyn would go on forever: at a step of ``min_step``, or
    after ``MAX_REJECTIONS_IN_A_ROW`` attempts at one time.

    Installed as the pre-step user function, which Exudyn calls before every attempt, rejected
    ones included, with the attempt's END time: the same time again is a retry of the same step
    (rejected at the minimum step); a time just past the last one is a step of the minimum.
    Returning False does not stop Exudyn there, raising does (what was sampled so far is kept).
    """

    def __init__(self, mbs, min_step):
        self.min_step, self.stalled, self.last_time, self.attempts = min_step, None, None, 0
        mbs.SetPreStepUserFunction(self._pre_step)

    def _pre_step(self, mbs, t):
        if t == self.last_time:
            self.attempts += 1
            if self.attempts > MAX_REJECTIONS_IN_A_ROW:
                self.stalled = f"stuck: {MAX_REJECTIONS_IN_A_ROW} rejected attempts in a row at t = {t:g} s"
                raise _Stuck(self.stalled)
            return True
        if self.last_time is not None and 0.0 < t - self.last_time <= self.min_step * (1.0 + 1e-9):
            self.stalled = f"stuck: the adaptive step fell to its minimum {self.min_step:g} s"
            raise _Stuck(self.stalled)
        self.last_time, self.attempts = t, 1
        return True


class _Sampler:
    """Reads every sensor at the sample times from Python (when Exudyn's stored sensors miss one).

    With ``tol`` (fixed-step solvers) it is the post-step user function and reads at the step
    that lands on each sample time to within ``tol`` s; a sample passed without landing stops
    the run. Without (adaptive solvers), ``read`` is called after each ``SolveSteps``. Sample 0
    is the initial state.
    """

    def __init__(self, mbs, flat, times, tol=None):
        self.mbs, self.flat, self.times, self.tol, self.stalled = mbs, flat, times, tol, None
        self.values = {(body, key): [None] * len(times) for body, key, _ in flat}
        self.last_time, self.next = float(times[0]), 1
        self.read(0)
        if tol is not None:
            mbs.SetPostStepUserFunction(self._post_step)

    def read(self, k):
        for body, key, sid in self.flat:
            self.values[(body, key)][k] = np.array(self.mbs.GetSensorValues(sid), dtype=float)
        self.next = k + 1

    def _post_step(self, mbs, t):
        if t == self.times[0]:  # once before the first step, with accelerations and constraint
            self.read(0)  # forces of the initial state computed (not yet at assembly)
            return True
        if t > self.last_time:  # Exudyn also calls this once per solve without stepping
            self.last_time = t
            k = self.next
            if k < len(self.times):
                if abs(t - self.times[k]) <= self.tol:
                    self.read(k)
                elif t > self.times[k]:
                    self.stalled = (f"no step landed on sample {k} at t = {self.times[k]:g} s (Exudyn shrank its "
                                    f"steps after a Newton failure, so its grid is lost; the step went to t = {t:.9g} s)")
                    return False
        return True
