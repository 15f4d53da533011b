"""tinyrigid's dalembert adapter: the contract of ``dalembert.adapters``, item by item (docs/engines.md).

The engine (``tinyrigid.engine``) is imported where it is used (contract item 2), so that listing engines
costs nothing; dalembert's own frames and rotations are converted through ``dalembert.spatial`` only.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from dalembert.adapters import Adapter, IntegratorSpec, Outcome, Prepared

__all__ = ["TinyRigidAdapter", "TinyRigidPrepared"]


@dataclass(frozen=True, eq=False)
class TinyRigidPrepared(Prepared):
    """A scene built for tinyrigid (``Prepared``, plus):

    Attributes
    ----------
    model : tinyrigid.engine.Model — the bodies, hinges, loads and gravity, the engine's knobs off
    initial : tinyrigid.engine.State — the initial state (copied by every run)
    steps : ndarray (n-1,) of int — engine steps per sample interval
    """

    model: object
    initial: object
    steps: np.ndarray


class TinyRigidAdapter(Adapter):
    """tinyrigid: free bodies and bodies hinged to the world, semi-implicit Euler (``tinyrigid.engine``)."""

    name = "tinyrigid"
    # (3) what it represents: gravity, free bodies, hinges (to the world only: ``unsupported`` says so), loads
    effects = frozenset({"gravity", "joint:free", "joint:revolute", "load:world_force", "load:world_torque",
                         "load:follower_force", "load:follower_torque"})
    # (4) its one integrator, with the order of accuracy it has (check-engine measures it)
    integrators = {"euler": IntegratorSpec(True, (), "semi-implicit Euler: velocities, then positions", order=1)}
    options = {}

    def version(self):  # (2) the engine's version; ImportError when it is missing
        import tinyrigid

        return tinyrigid.__version__

    def unsupported(self, scene, settings):  # (5) a valid scene it cannot represent: why, in words
        reason = super().unsupported(scene, settings)  # every effect not in ``effects``, named
        if reason:
            return reason
        nested = sorted(j.child for j in scene.joints if j.kind == "revolute" and j.parent != "world")
        if nested:
            return f"tinyrigid hinges bodies to the world only: {', '.join(nested)} hang from another body"
        return None

    def describe(self, scene, settings):
        model = self.build(scene)
        return (f"tinyrigid: {len(model.mass)} bodies, hinges {[h.body for h in model.hinges]}, "
                f"{len(model.loads)} loads, gravity {model.gravity.tolist()}\n")

    def build(self, scene):
        """The engine's ``Model`` of ``scene``: masses, inertias, gravity, hinges, loads; its default knobs off."""
        from dalembert import spatial
        from tinyrigid import engine

        index = {b.name: i for i, b in enumerate(scene.bodies)}
        hinges = []
        for j in scene.joints:
            if j.kind == "revolute":  # the axis is given in the joint frame: turned into the world by parent_quat
                axis = spatial.quat_to_matrix(np.array(j.parent_quat)) @ np.array(j.axis)
                hinges.append(engine.Hinge(index[j.child], np.array(j.parent_point), axis / np.linalg.norm(axis)))
        loads = [engine.Load(index[ld.body], np.array(ld.vector) if ld.kind == "force" else np.zeros(3),
                             np.array(ld.vector) if ld.kind == "torque" else np.zeros(3), ld.frame == "body",
                             np.array(ld.point)) for ld in scene.loads]
        return engine.Model(np.array([b.mass for b in scene.bodies]),
                            np.array([b.inertia_matrix for b in scene.bodies]), np.array(scene.gravity, dtype=float),
                            tuple(hinges), tuple(loads), linear_damping=0.0, angular_damping=0.0,
                            hinge_stiffness=0.0, hinge_damping=0.0, collision_radius=0.0)

    def prepare(self, scene, times, settings):  # (6) the model, not timed
        from dalembert import spatial
        from dalembert.settings import steps_per_interval
        from tinyrigid import engine

        times = np.asarray(times, dtype=float)
        start = spatial.initial_body_states(scene)  # world poses and velocities from the joints' q0, v0
        names = [b.name for b in scene.bodies]
        initial = engine.State(np.array([start[n]["p"] for n in names]),
                               spatial.wxyz_to_xyzw(np.array([spatial.matrix_to_quat(start[n]["R"]) for n in names])),
                               np.array([start[n]["v"] for n in names]), np.array([start[n]["w"] for n in names]),
                               np.zeros(len(names)), np.array([scene.joint(n).v0[0] if scene.joint(n).kind ==
                                                               "revolute" else 0.0 for n in names]))
        return TinyRigidPrepared(scene, times, settings, self.build(scene), initial,
                                 steps_per_interval(times, settings.dt))

    def start(self, prepared):
        """A simulation from the prepared initial state (``Simulation`` copies it: every run starts afresh)."""
        from tinyrigid import engine

        return engine.Simulation(prepared.model, prepared.initial)

    def run(self, prepared):  # (7) step, sample at exactly the times, read back later
        sim = self.start(prepared)
        states = [sim.state.copy()]
        began = time.perf_counter()
        for n in prepared.steps:
            for _ in range(n):
                sim.step(prepared.settings.dt)
            states.append(sim.state.copy())
        wall = time.perf_counter() - began
        steps = int(np.sum(prepared.steps))
        return Outcome(lambda: self.read_back(prepared, states), wall, steps, steps)

    def read_back(self, prepared, states):
        """The sampled engine states in body terms: quaternions scalar first, angular velocity in world axes,
        joint coordinates, and each hinge's reaction force on its body."""
        from dalembert import spatial
        from dalembert.trajectory import BodyStates, JointStates, Trajectory
        from tinyrigid import engine

        scene = prepared.scene
        sim = engine.Simulation(prepared.model, prepared.initial)  # evaluates the hinges' reactions
        bodies, joints, extras = {}, {}, {}
        for i, b in enumerate(scene.bodies):
            q = spatial.xyzw_to_wxyz(np.array([s.q[i] for s in states]))
            w = np.array([s.w[i] for s in states])
            bodies[b.name] = BodyStates(np.array([s.p[i] for s in states]), q, np.array([s.v[i] for s in states]), w)
            j = scene.joint(b.name)
            if j.kind == "revolute":
                joints[j.name] = JointStates(j.q0[0] + np.array([[s.angle[i]] for s in states]),
                                             np.array([[s.rate[i]] for s in states]))
                extras[f"reaction_force:{j.name}"] = np.array([sim.reaction(s, i) for s in states])
            else:  # free: the COM pose, and the angular velocity in body axes (the Joint convention)
                joints[j.name] = JointStates(np.hstack([bodies[b.name].position, q]),
                                             np.hstack([bodies[b.name].velocity, spatial.world_to_body(q, w)]))
        return Trajectory(prepared.times, bodies, joints, extras)

    def audit(self, prepared, outcome):  # (8) what the engine simulated, read from its model
        m = prepared.model
        return {"gravity": tuple(float(g) for g in m.gravity), "integrator": "semi-implicit Euler",
                "hinges": len(m.hinges), "loads": len(m.loads),
                "damping": {"linear": m.linear_damping, "angular": m.angular_damping,
                            "hinge": m.hinge_damping, "hinge_stiffness": m.hinge_stiffness},
                "contacts": 0 if m.collision_radius == 0.0 else "every body pair"}
