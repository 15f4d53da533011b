"""Exudyn's model of a scene's contact: its contact connectors for the scene's pairs, their penalty stiffness,
restitution and friction, and the options that set them; read back from the system for the audit.

* A sphere against a plane is one ``ObjectContactSphereTriangle``: marker 0 a rigid marker at the sphere's centre,
  marker 1 one at the ground's origin, the triangle a single one lying in the plane that contains the disc of
  radius ``PLANE_EXTENT`` about the plane's point (one triangle, so a sphere never meets two at once; its edges
  are left out, ``includeEdges = 0``: the plane has none). Two spheres are one ``ObjectContactSphereSphere``.
  Each connector keeps its contact state (gap, slip speed, impact speed) in a ``NodeGenericData`` of 4
  coordinates, the gap set to the pair's gap at t = 0 (``dalembert.contact.gap``). Nothing touches but the
  scene's pairs: each pair is its own connector.
* Normal force: a linear penalty spring (``contactStiffnessExponent = 1``) of stiffness ``contact_stiffness``
  (option, N/m; the scene's contact is rigid, Exudyn's is not, and it has no default: ``contactStiffness = 0`` is
  no contact).
* Restitution e in (0, 1]: Exudyn's impact model 2 (Gonthier et al. / Carvalho-Martins, a nonlinear damping set
  from e: "much more accurate regarding the coefficient of restitution, in the full range [0, 1] except for 0",
  the connectors' documentation), ``restitutionCoefficient = e``, no linear damping. A pair without restitution
  (None, or 0) stays closed once made: impact model 0 (linear damping only) with the critical damping
  ``2 sqrt(k m)`` of the pair's mass (the body's for a sphere on a plane, the reduced mass for two spheres).
* Friction: ``dynamicFriction`` = the scene's mu, regularized: below ``friction_zone`` (option, m/s: Exudyn's
  ``frictionProportionalZone``, its default 1e-3) the friction force is proportional to the slip speed, so a
  contact that must stick slips at a speed of up to that zone.
* What Exudyn cannot represent is refused (``why_not``): a box in a pair (its connectors pair spheres with
  spheres and triangles), a geom on a link of the kinematic tree (``joints=minimal``: not checked), the
  explicit solvers (they refuse the connectors' data nodes), and a frictional sphere on a plane that gravity
  pulls it along at steps above ``LOADED_FRICTION_DT_MAX`` (Exudyn's Newton iteration fails there).
* The steps stay on the run's dt: Exudyn's connectors would shrink a step at an impact to the one they recommend
  (``discontinuous.useRecommendedStepSize``), which takes the solve off the samples' grid for good; the adapter
  turns that off, so an impact is resolved at the user's step (bouncing_ball's apexes: 0.2462 and 0.0602 m for
  0.25 and 0.0625 at dt = 1e-4, 0.1905 and 0.0312 m at 1e-3).
"""

from __future__ import annotations

import math

import numpy as np

from dalembert import contact as geometry
from dalembert import spatial
from dalembert.adapters.base import Option, typed_options
from dalembert.adapters.exudyn.compat import sphere_radius_field

__all__ = ["OPTIONS", "CONTACT_OPTIONS", "STIFFNESS_DEFAULT", "FRICTION_ZONE_DEFAULT", "PLANE_EXTENT", "ELEMENTS",
           "LOADED_FRICTION_DT_MAX", "contact_options", "why_not", "add_contacts", "audit"]

# 1e6 N/m: a 1-kg body's contact period 2 pi sqrt(m/k) = 6.3 ms spans six steps at dt = 1e-3, and the 4.4-m/s
# impact of the 1-m drop (bouncing_ball) penetrates 1.8 mm (measured; the case's tolerance is 2 mm).
STIFFNESS_DEFAULT = 1e6
FRICTION_ZONE_DEFAULT = 1e-3  # m/s: Exudyn's own default frictionProportionalZone
CONTACT_OPTIONS = {
    "contact_stiffness": Option(default=STIFFNESS_DEFAULT, exclusive_minimum=0.0,
                                description=f"penalty stiffness of every contact pair, N/m (linear; default "
                                            f"{STIFFNESS_DEFAULT:g}: Exudyn has none)"),
    "friction_zone": Option(default=FRICTION_ZONE_DEFAULT, exclusive_minimum=0.0,
                            description=f"slip speed below which friction is proportional to it, m/s (Exudyn's "
                                        f"frictionProportionalZone, its default {FRICTION_ZONE_DEFAULT:g})"),
}
OPTIONS = tuple(CONTACT_OPTIONS)
# The plane's triangle contains the disc of this radius (m) about the plane's point: far beyond any case's travel.
PLANE_EXTENT = 1e3
ELEMENTS = ("ObjectContactSphereSphere", "ObjectContactSphereTriangle")
# The largest step (s) at which a frictional sphere may rest on a plane that gravity pulls it along: Exudyn's Newton
# iteration fails within the first 0.02 s above it (measured on ball_rolling_incline, 20 degrees, both implicit
# solvers, default options: failing at dt = 1e-2 and 1e-3, running at 5e-4, 2e-4 and 1e-4; a standalone Exudyn
# model of the same ball fails alike, so it is Exudyn's regularized friction under a sustained tangential load).
LOADED_FRICTION_DT_MAX = 5e-4
# Exudyn's impact models (the connectors' ``impactModel``): linear damping only; Gonthier / Carvalho-Martins.
LINEAR, GONTHIER = 0, 2


def contact_options(settings):
    """The contact options of ``settings`` with their declared defaults (``CONTACT_OPTIONS``, checked by
    ``Adapter.check``), as floats: dict ``stiffness`` (N/m) and ``friction_zone`` (m/s)."""
    o = typed_options(CONTACT_OPTIONS, settings)
    return {"stiffness": o["contact_stiffness"], "friction_zone": o["friction_zone"]}


def why_not(scene, settings, rigid, explicit):
    """Why Exudyn cannot run ``scene``'s contact at ``settings``, or None. ``rigid``: the names of the scene's
    bodies that are Exudyn rigid bodies (``model.rigid_bodies``); ``explicit``: whether the solver is explicit."""
    if not scene.contacts:
        return None
    if explicit:
        return ("contact with an explicit solver: Exudyn's contact connectors keep their state in a NodeGenericData, "
                "whose algebraic coordinates its explicit solvers refuse — use generalized-alpha or "
                "trapezoidal-index2")
    shapes = {g.name: g for g in scene.geoms}
    for pair in scene.contacts:
        kinds = {shapes[n].kind for n in (pair.a, pair.b) if n in shapes}
        if kinds != {"sphere"}:
            return (f"contacts.{pair.name}: a box in a pair — Exudyn's contact connectors pair a sphere with a "
                    "sphere or a triangle (ObjectContactSphereSphere, ObjectContactSphereTriangle; GeneralContact "
                    "likewise, never two triangles): a box would need spheres at its corners or its faces as "
                    "triangles against the other's spheres")
        for n in (pair.a, pair.b):
            if n in shapes and shapes[n].body not in rigid:
                return (f"contacts.{pair.name}: geom {n!r} is on {shapes[n].body!r}, a link of Exudyn's kinematic "
                        "tree, where contact connectors are not checked — use --option joints=redundant")
        gp = geometry.geom_and_plane(scene, pair)
        if gp and pair.friction > 0.0 and settings.dt is not None and settings.dt > LOADED_FRICTION_DT_MAX:
            g, n = np.asarray(scene.gravity, dtype=float), np.asarray(gp[1].unit_normal)
            if np.linalg.norm(g - (g @ n) * n) > 0.0:
                return (f"contacts.{pair.name}: friction on a plane that gravity pulls the sphere along, at dt = "
                        f"{settings.dt:g} s — Exudyn's regularized friction under a sustained tangential load "
                        f"fails its Newton iteration above dt = {LOADED_FRICTION_DT_MAX:g} s (measured on "
                        f"ball_rolling_incline): use --dt {LOADED_FRICTION_DT_MAX:g} or smaller")
    return None


def _pair_mass(scene, spheres):
    masses = [scene.body(g.body).mass for g in spheres]
    return masses[0] if len(masses) == 1 else masses[0] * masses[1] / (masses[0] + masses[1])


def add_contacts(mbs, scene, settings, markers, sensors):
    """One contact connector per scene pair in ``mbs`` (``markers``: scene body name or ``WORLD`` -> a function of
    a body point (3,) that adds a rigid marker there, ``model.build``'s). Returns the summary lines. ``sensors``
    gets ``__contact:<pair>`` -> ``{"f": sensor}``: the connector's ``Force`` output (Exudyn's documentation of both
    connectors: "global contact force vector"), the force on its marker 0, the pair's subject sphere (``pair.a``
    for two spheres), N, world (3,)."""
    import exudyn as exu
    from exudyn.itemInterface import (NodeGenericData, ObjectContactSphereSphere, ObjectContactSphereTriangle,
                                      SensorObject)

    from dalembert.scene import WORLD

    o = contact_options(settings)
    poses = geometry.initial_poses(scene)
    shapes, lines = {g.name: g for g in scene.geoms}, []
    for pair in scene.contacts:
        gp = geometry.geom_and_plane(scene, pair)
        spheres = [gp[0]] if gp else [shapes[pair.a], shapes[pair.b]]
        k = o["stiffness"]
        e = pair.restitution
        if e:  # restitution in (0, 1]: the impact model sets the damping from it
            impact = dict(impactModel=GONTHIER, restitutionCoefficient=float(e), contactDamping=0.0)
        else:  # stays closed once made: critically damped
            impact = dict(impactModel=LINEAR, restitutionCoefficient=1.0,
                          contactDamping=2.0 * math.sqrt(k * _pair_mass(scene, spheres)))
        gap0 = float(geometry.gap(scene, pair, poses)[0])
        node = mbs.AddNode(NodeGenericData(initialCoordinates=[gap0, 0.0, 0.0, 0.0], numberOfDataCoordinates=4))
        common = dict(nodeNumber=node, contactStiffness=k, contactStiffnessExponent=1.0,
                      dynamicFriction=float(pair.friction), frictionProportionalZone=o["friction_zone"], **impact)
        m0 = markers[spheres[0].body](spheres[0].point)
        if gp:
            plane = gp[1]
            R = spatial.frame_with_z(plane.unit_normal)
            p0 = np.asarray(plane.point, dtype=float)
            # a triangle whose inscribed circle, about p0, has radius PLANE_EXTENT (an equilateral one)
            corners = [p0 + R @ (2.0 * PLANE_EXTENT * np.array([math.cos(a), math.sin(a), 0.0]))
                       for a in (0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0)]
            obj = mbs.AddObject(ObjectContactSphereTriangle(
                name=pair.name, markerNumbers=[m0, markers[WORLD]([0.0, 0.0, 0.0])],
                **{sphere_radius_field(): float(spheres[0].size[0])}, trianglePoints=exu.Vector3DList([list(c) for c in corners]),
                includeEdges=0, **common))
            lines.append(f"ObjectContactSphereTriangle {pair.name}: sphere {spheres[0].name} on plane {plane.name}")
        else:
            m1 = markers[spheres[1].body](spheres[1].point)
            obj = mbs.AddObject(ObjectContactSphereSphere(
                name=pair.name, markerNumbers=[m0, m1],
                spheresRadii=[float(spheres[0].size[0]), float(spheres[1].size[0])], **common))
            lines.append(f"ObjectContactSphereSphere {pair.name}: spheres {spheres[0].name}, {spheres[1].name}")
        sensors[f"__contact:{pair.name}"] = {"f": mbs.AddSensor(SensorObject(
            objectNumber=obj, outputVariableType=exu.OutputVariableType.Force))}
        lines[-1] += (f", contactStiffness {k:g} N/m, impactModel {impact['impactModel']}, restitution "
                      f"{pair.restitution}, dynamicFriction {pair.friction:g}")
    return lines


def audit(mbs, scene):
    """Every contact connector as the system holds it (none: empty): its type, its markers' bodies, radii,
    stiffness and its exponent, damping, impact model and restitution, friction and its proportional zone, and the
    mapping of the scene's restitution and friction onto them."""
    if not scene.contacts:
        return {}
    keys = ("contactStiffness", "contactStiffnessExponent", "contactDamping", "impactModel", "restitutionCoefficient",
            "dynamicFriction", "frictionProportionalZone")
    pairs = {}
    for i in range(mbs.systemData.NumberOfObjects()):
        obj = mbs.GetObject(i)
        if f"Object{obj['objectType']}" not in ELEMENTS:
            continue
        # (Exudyn 1.13.6 reports an ObjectContactSphereTriangle's objectType as ContactSphereSphere: its fields tell)
        triangle = "trianglePoints" in obj
        row = {"type": ELEMENTS[1] if triangle else ELEMENTS[0], **{k: float(obj[k]) for k in keys}}
        row["impactModel"] = int(obj["impactModel"])
        if not triangle:
            row["radii"] = [float(r) for r in obj["spheresRadii"]]
        else:
            row["radius"] = float(obj[sphere_radius_field()])
            points = obj["trianglePoints"]  # (indexed: iterating Exudyn's list runs past its end)
            row["triangle"] = [[float(v) for v in np.asarray(points[i])] for i in range(len(points))]
            row["includeEdges"] = int(obj["includeEdges"])
        pairs[obj["name"]] = row
    return {
        "contact_pairs": pairs,
        "contact_mapping": ("normal: linear penalty spring contactStiffness (option contact_stiffness); restitution e "
                            "> 0: impactModel 2 (Gonthier / Carvalho-Martins) with restitutionCoefficient e, no linear "
                            "damping; no restitution: impactModel 0 with critical damping 2 sqrt(k m); friction: "
                            "dynamicFriction mu, proportional to the slip below frictionProportionalZone (option "
                            "friction_zone)"),
    }
