"""What Simbody simulated, read back from the OpenSim model and its system: the audit of a run (``Adapter.audit``)."""

from __future__ import annotations

from dalembert.adapters.simbody.model import opensim_version
from dalembert.adapters.simbody.stepping import METHODS

__all__ = ["audit", "defaults"]


def audit(prepared, outcome):
    """What Simbody simulated, read back from the model: gravity, the integrator and its step or accuracy, every
    joint as OpenSim holds it, the bodies' mass properties, the forces (the scene's loads and nothing else), the
    coordinates' defaults (``defaults``), and what the run reported."""
    model, settings = prepared.model, prepared.settings
    m = model.model
    g = m.getGravity()
    return {
        "gravity": tuple(float(g.get(i)) for i in range(3)),
        "integrator": f"Simbody {METHODS[settings.integrator]}Integrator (OpenSim Manager), "
                      + (f"fixed step {settings.dt!r} s" if settings.dt is not None else f"accuracy {settings.rtol!r}"),
        "defaults": model.defaults,
        **defaults(model),
        "joints": {name: {"type": j.getConcreteClassName(), "coordinates": j.numCoordinates(),
                          "mobilized_body": int(model.bodies[name].getMobilizedBodyIndex())}
                   for name, j in model.joints.items()},
        "bodies": {name: {"mass": float(b.getMass()), "com": b.getMassCenter().to_numpy().tolist(),
                          "moments": b.getInertia().getMoments().to_numpy().tolist(),
                          "products": b.getInertia().getProducts().to_numpy().tolist()}
                   for name, b in model.bodies.items()},
        "loads": [f"{f.getName()}: PrescribedForce on {f.getFrame().getName()}, "
                  f"{'ground' if f.getForceIsInGlobalFrame() else 'body'} axes" for f in model.forces],
        "springs": {f.getName(): {"bodies": [f.getBody1Name(), f.getBody2Name()],
                                  "points": [f.getPoint1().to_numpy().tolist(), f.getPoint2().to_numpy().tolist()],
                                  "tension": f.get_expression()} for f in model.springs},
        "steps": int(outcome.n_steps),
        "realizations": int(outcome.n_rhs),
        "message": outcome.info.get("message", ""),
        "opensim_version": opensim_version(),
    }


def defaults(model):
    """What a scene never calls for, read back from the model: every force in its force set (the loads and springs
    are the only ones the adapter adds), contact geometry, constraints, controllers (actuators, muscles), probes, and each
    coordinate's locked, clamped and prescribed flags and its range."""
    m = model.model
    forces = m.getForceSet()
    coords = m.getCoordinateSet()
    loads = {f.getName() for f in model.forces + model.springs}
    return {
        "other_forces": [forces.get(i).getConcreteClassName() + " " + forces.get(i).getName()
                         for i in range(forces.getSize()) if forces.get(i).getName() not in loads],
        "contact_geometry": int(m.getContactGeometrySet().getSize()),
        "constraints": int(m.getConstraintSet().getSize()),
        "controllers": int(m.getControllerSet().getSize()),
        "actuators": int(m.getActuators().getSize()),
        "muscles": int(m.getMuscles().getSize()),
        "coordinates": {coords.get(i).getName(): {
            "locked": bool(coords.get(i).get_locked()), "clamped": bool(coords.get(i).get_clamped()),
            "prescribed": bool(coords.get(i).get_prescribed()),
            "range": [float(coords.get(i).getRangeMin()), float(coords.get(i).getRangeMax())]}
            for i in range(coords.getSize())},
    }
