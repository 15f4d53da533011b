"""``DartAdapter``: the contract (``dalembert.adapters``) for DART (``dartpy``).

``prepare`` builds the world and its skeleton (``model``) and checks the built mass properties against the
scene's; ``run`` steps the world through the sample times (``stepping``) and reads the states back in body terms
(``readback``); ``audit`` (the module) reads the world and skeleton back.

Integrators: DART has one, semi-implicit Euler at a fixed step (``euler``); it offers no error control.
Loop closures: ball and revolute, as DART's dynamic joint constraints (``loops``; their reactions by Newton's law,
``readback``).
Contact: one pair, DART's hard contact (``contact``). What it does not represent, each refused with the reason
(``UNSUPPORTED``, ``contact.why_not``): distance loops, spring-dampers between two points, more than one contact
pair.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, Prepared
from dalembert.adapters.dart.audit import audit
from dalembert.adapters.dart.loops import DISTANCE_REASON, LOOP_KINDS
from dalembert.adapters.dart.model import MODEL_OPTIONS, dart_version
from dalembert.adapters.dart import contact
from dalembert.scene import CONTACT_EFFECTS, EFFECTS, SPRING_EFFECT
from dalembert.settings import steps_per_interval

__all__ = ["DartAdapter", "DartPrepared", "UNSUPPORTED"]

# Built mass properties must reproduce the scene's to this relative accuracy: DART stores the scene's numbers
# (mass, the six moments) as given, so only a unit or frame mistake could move them.
MASS_PROPERTY_REL_TOL = 1e-12
# Why DART does not run these effects (what it would take), by effect tag prefix.
UNSUPPORTED = {
    "loop:distance": DISTANCE_REASON,
    SPRING_EFFECT: ("linear spring-dampers between two points: DART has joint-space springs only "
                    "(Joint.setSpringStiffness); a two-point spring would be an external force set from Python before "
                    "every step; not yet built"),
}


@dataclass(frozen=True, eq=False)
class DartPrepared(Prepared):
    """DART's prepared run (``Prepared``): the world, its skeleton and the initial state.

    Attributes
    ----------
    model : DartModel — the world (time step ``dt``, the scene's gravity), its skeleton, bodies and joints
    steps : ndarray (n - 1,) of int — steps per sample interval (``settings.steps_per_interval``)
    """

    model: object
    steps: np.ndarray


class DartAdapter(Adapter):
    """DART (``dartpy``): the scene as a ``Skeleton`` in a ``World``, DART's semi-implicit Euler.
    Option ``defaults`` = ``scene`` | ``engine`` (``model.MODEL_OPTIONS``)."""

    name = "dart"
    # loops: ball and revolute, DART's dynamic joint constraints (``loops``); a distance loop is refused
    # contact: one pair, DART's hard contact (``contact``)
    effects = EFFECTS | frozenset(f"loop:{k}" for k in LOOP_KINDS) | CONTACT_EFFECTS
    options = MODEL_OPTIONS
    refusal_notes = UNSUPPORTED
    integrators = {
        "euler": IntegratorSpec(True, tuple(MODEL_OPTIONS),
                                "DART's semi-implicit Euler (World.step): velocities first, positions from them",
                                order=1),
    }

    def version(self):
        return dart_version()

    def load(self):
        import dartpy  # noqa: F401  (the dynamics, simulation and math modules a run uses)

        self.version()

    def unsupported(self, scene, settings):
        return super().unsupported(scene, settings) or contact.why_not(scene)

    def describe(self, scene, settings):
        """The world's summary, for reports and ``dalembert show-model``."""
        from dalembert.adapters.dart.model import DartModel

        return DartModel(scene, settings.dt, settings).summary

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        from dalembert.adapters.dart.model import DartModel

        times = np.asarray(times, dtype=float)
        model = DartModel(scene, settings.dt, settings)
        self._check_mass_properties(model, scene)
        return DartPrepared(scene, times, settings, model=model, steps=steps_per_interval(times, settings.dt))

    @staticmethod
    def _check_mass_properties(model, scene):
        for b in scene.bodies:
            node = model.nodes[b.name]
            inertia = np.asarray(node.getInertia().getMoment(), dtype=float)
            scale = np.abs(b.inertia_matrix).max()
            if (abs(node.getMass() - b.mass) > MASS_PROPERTY_REL_TOL * b.mass
                    or np.abs(inertia - b.inertia_matrix).max() > MASS_PROPERTY_REL_TOL * scale
                    or np.abs(node.getLocalCOM()).max() > 0.0):
                raise RuntimeError(f"DART built body {b.name!r} with mass {node.getMass()}, COM "
                                   f"{list(node.getLocalCOM())} and inertia {inertia.tolist()}; the scene has "
                                   f"{b.mass}, [0, 0, 0], {b.inertia_matrix.tolist()}")

    # ------------------------------------------------------------- run
    def run(self, prepared):
        from dalembert.adapters.dart.readback import read_back
        from dalembert.adapters.dart.stepping import EngineLog, plain, simulate

        p = prepared
        Q, V, wall, n_steps, message = simulate(p)
        info = {"message": f"DART: {message}" if message else ""}

        def read():
            with EngineLog() as log:  # DART's warnings while it recomputes the sampled states: not the console's
                traj = read_back(p, Q, V)
            info["readback_message"] = plain(log.text)
            return traj

        return Outcome(read, wall, n_steps, n_steps, info)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        return audit(prepared, outcome)
