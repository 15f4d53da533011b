"""What differs between the Exudyn releases the adapter runs on, and the shim that bridges it.

The adapter is written against Exudyn 1.13 (the version installed with dalembert). Exudyn 1.11.0, the newest
release before it with a CPython 3.11 wheel on the package index (no 1.12 has one), was run in an engine
environment (``dalembert env create exudyn==1.11.0``) and differs in these items the adapter uses:

* a rigid marker's frame: 1.13's ``MarkerBodyRigid`` and ``MarkerKinematicTreeRigid`` take ``localHT`` (a
  point and a frame in the body's, made by ``exudyn.HT``); 1.11's take ``localPosition`` only, their frame is
  the body's, and a joint's frames are the ``ObjectJointGeneric``'s ``rotationMarker0``/``rotationMarker1``
  (each the joint frame in its marker's axes; 1.13.6 keeps them as identities, "deprecated since 1.12.244" in its
  own warning). ``Markers`` puts a frame where the installed release takes it, and ``joint_frame`` and
  ``turned`` read it back from either;
* ``exudyn.HT``: absent from 1.11 (only the markers' frames use it here);
* the solver: 1.13's ``timeIntegration.solverType``; 1.11 has none (``SolveDynamic`` is told the type, and its
  explicit solvers read ``explicitIntegration.dynamicSolverType``): ``set_solver``, ``solver_of``;
* ``SimulationSettings.solution.file.write`` and ``solution.sensors.writePeriod`` (1.13) are
  ``solutionSettings.writeSolutionToFile`` and ``solutionSettings.sensorsWritePeriod`` in 1.11
  (``no_solution_file``, ``set_sensors_write_period``);
* ``ObjectContactSphereTriangle``'s ``sphereRadius`` (1.13) is ``radiusSphere`` in 1.11 (``SPHERE_RADIUS``;
  "deprecated since 1.12.258" in 1.13.6's warning).

Not shimmed: ``repro`` writes 1.13's calls (``localHT``, ``solution``) only.

Which API the installed Exudyn has is asked of Exudyn itself (the parameters its item classes take, the
attributes of its settings), not read off its version number, so a release between the two is served by what it
has. On 1.13 every call is the one the adapter made before this module: its systems and numbers are unchanged.
"""

from __future__ import annotations

import inspect
from functools import cache

import numpy as np

__all__ = ["framed_markers", "Markers", "joint_frame", "marker_point", "no_solution_file", "sphere_radius_field",
           "SPHERE_RADIUS", "turned",
           "set_sensors_write_period", "set_solver", "solver_of"]

# ObjectContactSphereTriangle's names for its sphere's radius: 1.13's, 1.11's (``sphere_radius_field`` asks which
# the installed Exudyn takes).
SPHERE_RADIUS = ("sphereRadius", "radiusSphere")


@cache
def framed_markers():
    """Whether the installed Exudyn's rigid markers take a frame (``localHT``: 1.13) or a point only (1.11)."""
    from exudyn.itemInterface import MarkerBodyRigid

    return "localHT" in inspect.signature(MarkerBodyRigid.__init__).parameters


@cache
def sphere_radius_field():
    """``ObjectContactSphereTriangle``'s name for the sphere's radius in the installed Exudyn."""
    from exudyn.itemInterface import ObjectContactSphereTriangle

    params = inspect.signature(ObjectContactSphereTriangle.__init__).parameters
    return next(name for name in SPHERE_RADIUS if name in params)


def no_solution_file(settings):
    """Switch off the solution file Exudyn writes by default, in either release's settings (in place)."""
    if hasattr(settings, "solution"):
        settings.solution.file.write = False
    else:  # Exudyn 1.11
        settings.solutionSettings.writeSolutionToFile = False


def set_sensors_write_period(settings, period):
    """Set how often, in s, Exudyn writes (or stores) the sensors, in either release's settings (in place)."""
    if hasattr(settings, "solution"):
        settings.solution.sensors.writePeriod = period
    else:  # Exudyn 1.11
        settings.solutionSettings.sensorsWritePeriod = period


def set_solver(settings, solver_type):
    """Name the dynamic solver (an ``exudyn.DynamicSolverType``) in ``settings`` (in place), where ``solver_of``
    reads it: 1.13's ``timeIntegration.solverType``; 1.11 has none, and its explicit solvers read
    ``explicitIntegration.dynamicSolverType`` (its implicit ones ignore it: ``SolveDynamic`` is told the type)."""
    if hasattr(settings.timeIntegration, "solverType"):
        settings.timeIntegration.solverType = solver_type
    else:  # Exudyn 1.11
        settings.timeIntegration.explicitIntegration.dynamicSolverType = solver_type


def solver_of(settings):
    """The dynamic solver ``set_solver`` named in ``settings``."""
    if hasattr(settings.timeIntegration, "solverType"):
        return settings.timeIntegration.solverType
    return settings.timeIntegration.explicitIntegration.dynamicSolverType  # Exudyn 1.11


class Markers:
    """Rigid markers with a frame, in ``mbs``, and the generic joints between them, in either release's terms.

    ``add`` makes a marker at point ``p`` with frame ``R`` (both in the owner's frame, m and a rotation (3, 3));
    on a release without marker frames it makes it at the point and keeps ``R`` for the joint that uses the
    marker (``generic_joint``: ``rotationMarker0/1``). Connectors that read the markers' positions only (distance
    loops, springs, contact) and loads (whose markers' frames are their bodies') are the same either way.
    """

    def __init__(self, mbs):
        self.mbs = mbs
        self.frames = {}  # marker number -> its frame R (3, 3) in its owner's axes, where Exudyn keeps none

    def add(self, cls, p, R, **owner):
        """The number of a new marker ``cls(**owner)`` at ``p`` (3,) with frame ``R`` (3, 3) in the owner's frame."""
        if framed_markers():
            import exudyn as exu

            return self.mbs.AddMarker(cls(**owner, localHT=exu.HT(rotation=R, translation=list(p))))
        number = self.mbs.AddMarker(cls(**owner, localPosition=list(p)))
        self.frames[int(number)] = np.asarray(R, dtype=float)
        return number

    def generic_joint(self, cls, m0, m1, **fields):
        """The object number of a new ``ObjectJointGeneric`` (``cls``) between markers ``m0`` and ``m1``, its
        frames theirs (``add``'s ``R``)."""
        if not framed_markers():
            fields = {**fields, "rotationMarker0": self.frames.get(int(m0), np.eye(3)).tolist(),
                      "rotationMarker1": self.frames.get(int(m1), np.eye(3)).tolist()}
        return self.mbs.AddObject(cls(markerNumbers=[m0, m1], **fields))


def marker_point(marker):
    """A rigid marker's point in its owner's frame (m, (3,)), from ``mbs.GetMarker``'s dict of either release."""
    if "localHT" in marker:
        return np.asarray(marker["localHT"], dtype=float)[:3, 3]
    return np.asarray(marker["localPosition"], dtype=float)


def joint_frame(mbs, joint, side):
    """The frame of ``ObjectJointGeneric`` dict ``joint``'s marker ``side`` (0 or 1) in its owner's frame, as a
    homogeneous transformation (4, 4): the marker's frame (``localHT``; 1.11: the owner's) turned by the joint's
    ``rotationMarker<side>`` (1.13: an identity)."""
    marker = mbs.GetMarker(int(joint["markerNumbers"][side]))
    HT = np.eye(4)
    if "localHT" in marker:
        HT = np.asarray(marker["localHT"], dtype=float).copy()
    else:
        HT[:3, 3] = marker_point(marker)
    HT[:3, :3] = turned(HT[:3, :3], joint, side)
    return HT


def turned(R, joint, side):
    """Rotation ``R`` (3, 3) of marker ``side`` (0 or 1) of ``ObjectJointGeneric`` dict ``joint`` turned into the
    joint's frame there: ``R @ rotationMarker<side>``; ``R`` itself where that is an identity (1.13), bit for bit."""
    turn = np.asarray(joint[f"rotationMarker{side}"], dtype=float)
    return R if np.array_equal(turn, np.eye(3)) else R @ turn
