"""``SimbodyAdapter``: the contract (``dalembert.adapters``) for Simbody through OpenSim 4.6 (``opensim``).

``prepare`` builds the OpenSim model and its initial state (``model``) and checks the built mass properties
against the scene's; ``run`` integrates through the sample times with OpenSim's ``Manager`` (``stepping``) and
reads the states back in body terms (``readback``); ``audit`` (the module) reads the model back.

Integrators: five of Simbody's eight, each offered in the mode it is built for (``INTEGRATORS``): the fourth-order
Runge-Kuttas and CPodes error-controlled (``rtol``: Simbody's accuracy), Verlet and forward Euler at a fixed step
(``dt``); the other three are left out to keep the default matrix small (``LEFT_OUT``, with the measurement). What
it does not represent, each refused with the reason (``UNSUPPORTED``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, Prepared
from dalembert.adapters.simbody.audit import audit
from dalembert.adapters.simbody.model import MODEL_OPTIONS, opensim_version
from dalembert.adapters.simbody.stepping import METHODS
from dalembert.scene import EFFECTS, SPRING_EFFECTS

__all__ = ["SimbodyAdapter", "SimbodyPrepared", "UNSUPPORTED", "INTEGRATORS", "LEFT_OUT"]

# Built mass properties must reproduce the scene's to this relative accuracy: OpenSim stores the scene's numbers
# (mass, moments, products) as given, so only a unit or frame mistake could move them.
MASS_PROPERTY_REL_TOL = 1e-12
# Why Simbody's adapter does not run these effects (what it would take), by effect tag prefix.
UNSUPPORTED = {
    "loop": ("closed kinematic loops: OpenSim has the constraints (PointConstraint for a ball, "
              "ConstantDistanceConstraint for a distance, a point and two PointOnLine or a CoordinateCoupler for a "
              "revolute) with Simbody's constraint projection; not yet mapped"),
    "contact": ("contact: OpenSim's contact is compliant (Hunt-Crossley, elastic foundation), with no hard "
                "contact to take the scene's pairs, friction and restitution as given; not mapped"),
}
# (fixed step, order the method is built to, Simbody's description), by the adapter's integrator name: each method
# in the mode it is built for. Orders measured at a fixed step on a pendulum (dalembert check-engine; Merson and
# Fehlberg both advance their fourth-order solution); CPodes varies its order (1 to 5) and declares none.
INTEGRATORS = {
    "rk-merson": (False, 4, "Runge-Kutta-Merson, 4th order, embedded error estimate"),
    "rk-feldberg": (False, 4, "Runge-Kutta-Fehlberg 4(5), 4th order advanced"),
    "cpodes": (False, None, "CPODES: variable-order, variable-step Adams or BDF multistep with projection"),
    "verlet": (True, 2, "velocity Verlet, 2nd order"),
    "explicit-euler": (True, 1, "explicit (forward) Euler, 1st order"),
}
# Simbody's other three integrators, which OpenSim's Manager also offers, left out of ``INTEGRATORS`` because the
# default matrix runs every declared integrator on every case, and these three doubled Simbody's share of it
# (measured, dalembert run --engine simbody --quick: 87 s of 8 integrators' runs, 48 s of them these three; OpenSim
# costs 10-100 us a step) while adding no kind of scheme the others lack: a fixed step's order measured on a
# pendulum at dt = 1e-2, 5e-3, 2.5e-3 (errors 6.7e-6, 8.4e-7, 1.0e-7 for RungeKutta3). Declaring one is one line
# here (``stepping.METHODS`` has them all).
LEFT_OUT = {
    "rk3": (True, 3, "Runge-Kutta 3rd order with a 2nd order error estimate"),
    "rk2": (True, 2, "Runge-Kutta 2nd order (explicit trapezoid), the same order as verlet"),
    "semi-explicit-euler2": (True, 1, "semi-explicit Euler, 1st order at a fixed step, as explicit-euler"),
}


@dataclass(frozen=True, eq=False)
class SimbodyPrepared(Prepared):
    """Simbody's prepared run (``Prepared``).

    Attributes
    ----------
    model : model.SimbodyModel — the OpenSim model, its system and its initial state (each run starts from a copy)
    """

    model: object


class SimbodyAdapter(Adapter):
    """Simbody through OpenSim 4.6 (``opensim``): the scene as an OpenSim ``Model``, Simbody's integrators through
    OpenSim's ``Manager``. Option ``defaults`` = ``scene`` | ``engine`` (``model.MODEL_OPTIONS``)."""

    name = "simbody"
    # free, revolute, prismatic, ball and weld joints; gravity; world and follower forces and torques; springs
    effects = EFFECTS | SPRING_EFFECTS
    options = MODEL_OPTIONS
    refusal_notes = UNSUPPORTED
    integrators = {
        name: IntegratorSpec(fixed, tuple(MODEL_OPTIONS), f"Simbody {METHODS[name]}: {text}"
                             + ("" if fixed else ", error-controlled (accuracy = rtol)"), order=order)
        for name, (fixed, order, text) in INTEGRATORS.items()
    }

    def version(self):
        return opensim_version()

    def load(self):
        from dalembert.adapters.simbody.model import engine

        engine()
        self.version()

    def describe(self, scene, settings):
        """The model's summary, for reports and ``dalembert show-model``."""
        from dalembert.adapters.simbody.model import SimbodyModel

        return SimbodyModel(scene, settings).summary

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        from dalembert.adapters.simbody.model import SimbodyModel

        model = SimbodyModel(scene, settings)
        _check_mass_properties(model, scene)
        return SimbodyPrepared(scene, np.asarray(times, dtype=float), settings, model=model)

    # ------------------------------------------------------------- run
    def run(self, prepared):
        from dalembert.adapters.simbody.readback import read_back
        from dalembert.adapters.simbody.stepping import simulate

        p = prepared
        Y, wall, steps, realizations, message = simulate(p)
        info = {"message": f"Simbody: {message}" if message else ""}
        return Outcome(lambda: read_back(p, Y), wall, steps, realizations, info)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        return audit(prepared, outcome)


def _check_mass_properties(model, scene):
    """OpenSim's mass, mass center and inertia of every body against the scene's (RuntimeError naming the body)."""
    for b in scene.bodies:
        body = model.bodies[b.name]
        inertia = body.getInertia()
        moments, products = inertia.getMoments().to_numpy(), inertia.getProducts().to_numpy()
        I = np.diag(moments)
        I[0, 1] = I[1, 0] = products[0]
        I[0, 2] = I[2, 0] = products[1]
        I[1, 2] = I[2, 1] = products[2]
        scale = np.abs(b.inertia_matrix).max()
        if (abs(body.getMass() - b.mass) > MASS_PROPERTY_REL_TOL * b.mass
                or np.abs(I - b.inertia_matrix).max() > MASS_PROPERTY_REL_TOL * scale
                or np.abs(body.getMassCenter().to_numpy()).max() > 0.0):
            raise RuntimeError(f"OpenSim built body {b.name!r} with mass {body.getMass()}, mass center "
                               f"{body.getMassCenter().to_numpy().tolist()} and inertia {I.tolist()}; the scene has "
                               f"{b.mass}, [0, 0, 0], {b.inertia_matrix.tolist()}")
