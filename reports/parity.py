"""Parity: an engine's port against its original at the same settings, from stored trajectories.

MJX is MuJoCo's JAX port and MuJoCo Warp its Warp port (float32): the same compiled
model, the same integrators. Where a store holds a port's run and a MuJoCo C run of the
same case version, integrator, step and options (MJX's ``precision`` aside), their largest difference over the horizon
(orientation as the geodesic angle, rad; COM position, m) is set against the floors it
cannot beat: the case's double-precision floor (``CaseRecord.floor``) and, for a float32
run of a torque-free top, the float32 floor its audit carries (RK4 in float32 against
the same RK4 in double, ``dalembert.adapters.mjx.parity.float32_floor``). A difference
near the floor is roundoff; one far above it is a different computation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dalembert import spatial

__all__ = ["PORTS", "PORT_NAMES", "Parity", "pairs", "parities"]

# port -> the engine it ports
PORTS = {"mjx": "mujoco", "mujoco_warp": "mujoco"}
# port -> its name in prose
PORT_NAMES = {"mjx": "MJX", "mujoco_warp": "MuJoCo Warp"}
# options of a port that its original does not have
PORT_ONLY_OPTIONS = {"mjx": ("precision",), "mujoco_warp": ("worlds",)}  # (a batch's world 0 is the run)


@dataclass(frozen=True)
class Parity:
    """One port run against its original's run at the same settings.

    Attributes
    ----------
    case, version : str
    port, original : str — engine names
    label : str — integrator, step and the port's options
    number_type : str — the port run's floating-point type, from its audit ("float32", "float64"; "" if unknown)
    orientation : float — largest geodesic angle between the two over bodies and samples, rad
    position : float — largest COM position difference, m
    floor : float — the case's double-precision orientation floor, rad (NaN where none)
    number_floor : float — the float32 orientation floor from the port run's audit, rad (NaN where none)
    port_key, original_key : str — the two runs
    """

    case: str
    version: str
    port: str
    original: str
    label: str
    number_type: str
    orientation: float
    position: float
    floor: float
    number_floor: float
    port_key: str
    original_key: str


def _finite(x):
    return float(x) if x is not None and math.isfinite(float(x)) else math.nan


def pairs(records):
    """``[(port run, original run)]``: each finished run of a port (``PORTS``) and its original engine's finished
    run of the same case version, integrator, step or tolerance and options (its port-only options aside), both
    with a stored trajectory (a store that keeps none has no pairs)."""
    done = [r for r in records if r.status == "ok" and r.trajectory]
    originals = {}
    for r in done:
        if r.engine in PORTS.values():
            originals[(r.engine, r.case, r.case_version, r.settings.integrator, r.settings.dt, r.settings.rtol,
                       tuple(sorted(r.settings.options.items())))] = r
    out = []
    for r in done:
        if r.engine not in PORTS:
            continue
        original = PORTS[r.engine]
        s = r.settings
        options = tuple(sorted((k, v) for k, v in s.options.items() if k not in PORT_ONLY_OPTIONS.get(r.engine, ())))
        o = originals.get((original, r.case, r.case_version, s.integrator, s.dt, s.rtol, options))
        if o is not None:
            out.append((r, o))
    return out


def parities(records, trajectory_of, floor_of):
    """Every ``Parity`` a store holds. ``trajectory_of(key) -> Trajectory``; ``floor_of(case, version) ->
    {quantity: floor}``. Only runs that finished (status ok) are compared (``pairs``)."""
    out = []
    for r, o in pairs(records):
        original = o.engine
        a, b = trajectory_of(r.key), trajectory_of(o.key)
        with np.errstate(invalid="ignore"):
            orientation = max(float(np.max(spatial.rotation_angle(a.bodies[n].quaternion, b.bodies[n].quaternion)))
                              for n in a.bodies)
            position = max(float(np.max(np.abs(a.bodies[n].position - b.bodies[n].position))) for n in a.bodies)
        step = f"dt={r.settings.dt:g}" if r.settings.dt is not None else f"rtol={r.settings.rtol:g}"
        label = " ".join(x for x in (r.settings.integrator, step, r.options_text) if x)
        out.append(Parity(r.case, r.case_version, r.engine, original, label, str(r.audit.get("precision", "")),
                          orientation, position,
                          _finite(floor_of(r.case, r.case_version).get("orientation")),
                          _finite(r.audit.get("float32_floor")), r.key, o.key))
    return sorted(out, key=lambda p: (p.case, p.version, p.port, p.label))
