"""Drake's model of a scene's contact: geoms, planes, the explicit pairs, friction, restitution, and the
contact options; read back from the plant and its SceneGraph for the audit.

* A scene with contact pairs is built with a ``SceneGraph`` (``AddMultibodyPlantSceneGraph``); a scene without
  them builds the plant alone, exactly as before contact existed. Every scene ``Geom`` becomes a collision
  geometry of its body (``Sphere(radius)``, ``Box(sx, sy, sz)``: Drake's box takes the full edge lengths), posed
  in the body frame B (Drake's body frame is B: ``model``); every ``Plane`` a ``HalfSpace`` of the world body
  (``HalfSpace.MakePose(normal, point)``). The bodies keep their explicit spatial inertia: geometry adds no mass.
* Nothing touches that the scene does not name: after ``Finalize`` every pair of geometries that no
  ``ContactPair`` names is excluded (``CollisionFilterDeclaration().ExcludeBetween``); the audit reads the
  remaining collision candidates back (``GetCollisionCandidates``), and the model checks they are the named pairs.
* Point contact (``ContactModel.kPoint``): the normal force ``k x (1 + d xdot)+`` of the penetration x
  (Drake's documentation, Modeling Compliant Contact), ``k`` the pair's combined stiffness ``k1 k2 / (k1 + k2)``
  and ``d`` its combined Hunt-Crossley dissipation ``(k2 d1 + k1 d2) / (k1 + k2)``. Drake's contact parameters are
  per geometry: every geometry gets ``point_contact_stiffness`` (option, Drake's default 1e6 N/m, so a pair's
  combined stiffness is half of it) and the dissipation of its pairs; a geometry whose pairs ask for different
  friction or dissipation cannot be built (``why_not``). Drake's own default model, hydroelastic with a point
  fallback, is not used as such: ``contact_model`` (option) sets point contact (the default here) or
  hydroelastic contact, every geom compliant (modulus ``HYDROELASTIC_MODULUS`` and mesh ``RESOLUTION_HINT``,
  Drake's defaults) and every plane rigid, with the same Hunt-Crossley dissipation on the pressure.
* Friction: ``CoulombFriction(mu, mu)`` on both geometries of a pair (static = kinetic: the scene's ideal cone);
  Drake combines two geometries' coefficients as ``2 mu1 mu2 / (mu1 + mu2)``, which is mu for equal ones.
* Restitution: Drake has no restitution coefficient. Its Hunt-Crossley law gives a restitution that depends on
  the approach speed v: for ``m xddot = -k x (1 + d xdot)`` the energy integral ``m w dw / (1 + d w) = -k x dx``
  over the impact closes in closed form, whatever k and m,
  ``a - ln(1 + a) = -b - ln(1 - b)``, ``a = d v``, ``b = d e v`` (derived here from the force law above;
  for small ``d v`` it gives Hunt & Crossley's ``e = 1 - 2/3 d v``, J. Appl. Mech. 42, 1975, their alpha = 2/3 d).
  So no d gives the scene's constant e at every impact: a pair's restitution is mapped only at an approach speed
  the user names (option ``impact_speed``, m/s), ``d = a / v`` for the root a of the relation
  (``restitution_dissipation``); without it a scene with restitution is unsupported (``why_not``). e = 0 (d
  infinite) cannot be mapped. A pair without restitution keeps the dissipation option, Drake's default 50 s/m
  (a bounce of at most ``1 / d`` = 0.02 m/s: a closed contact).
* Options (``CONTACT_OPTIONS``): ``contact_model`` = ``point`` | ``hydroelastic``; ``contact_solver`` = ``sap``
  (Drake's default: the SAP solver with its default lagged approximation, ``DiscreteContactApproximation.kLagged``)
  | ``tamsi`` (``kTamsi``), discrete mode only, for every discrete plant (with contact or without; loops need SAP);
  ``point_contact_stiffness`` (N/m per geometry); ``hunt_crossley_dissipation`` (s/m, pairs without restitution);
  ``impact_speed`` (m/s, the speed restitution is mapped at). Drake's stiction tolerance (1e-4 m/s,
  ``MultibodyPlantConfig``'s default; the regularized friction of TAMSI and of continuous mode) is left at
  Drake's default: the plant offers no getter, so the audit states it rather than reads it.
* Continuous mode (Drake's integrators on the same penalty force) runs frictionless contact only: there the
  Hunt-Crossley law is integrated as written, so the restitution mapping holds to the integrator's accuracy
  (sphere_collision, rk3-adaptive at 1e-6: the closed form's velocities to 1.5e-5 m/s). Friction in continuous mode
  is Drake's Stribeck-regularized law, stiff while a contact sticks: unsupported (``CONTINUOUS_FRICTION_REASON``).
* Contact forces (``read_forces``): per sample, the plant's ``get_contact_results_output_port()`` at the sample's
  state (in discrete mode the contact results of the step that starts there: the model turns sampled output ports
  off), every point pair's ``contact_force()`` (on body B, world) and every hydroelastic surface's ``F_Ac_W()``
  (the spatial force on the body of geometry M, world) whose two geometries are a scene pair's, summed per pair ON
  the pair's subject (``dalembert.contact.subject``).
  In discrete mode the step is implicit in the contact force, which damps a contact lasting a few steps (the
  point contact's half period ``pi sqrt(m / k)``, ~4 ms for the cases' balls, against dt = 1e-3): measured on
  sphere_collision (e = 0.8 mapped at 1 m/s), restitution 0.29 at dt = 1e-3 and 0.72 at 1e-4, SAP and TAMSI alike.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from dalembert import spatial
from dalembert.adapters.base import Option, typed_options

__all__ = ["CONTACT_OPTIONS", "SOLVERS", "MODELS", "STIFFNESS_DEFAULT", "DISSIPATION_DEFAULT", "STICTION_TOLERANCE",
           "contact_options", "restitution_dissipation", "why_not", "add_geometry", "set_solver", "exclude_unnamed",
           "candidates", "audit", "summary_lines", "read_forces", "HALF_SPACE_WARNING"]

SOLVERS = ("sap", "tamsi")
# Why frictional contact runs in discrete mode only (measured on Drake 1.51, this adapter).
CONTINUOUS_FRICTION_REASON = (
    "Drake's continuous mode regularizes friction with its 1e-4 m/s stiction tolerance, so a contact that sticks "
    "makes the ODE stiff (mu g / 1e-4 ~ 5e4 1/s): rk3-adaptive at rtol 1e-6 had not finished block_on_incline's "
    "1 s after 300 s — use the integrator discrete (SAP or TAMSI)")
MODELS = ("point", "hydroelastic")
# Drake's defaults (its documentation, Default Contact Parameters; geometry.DefaultProximityProperties).
STIFFNESS_DEFAULT = 1.0e6  # N/m per geometry
DISSIPATION_DEFAULT = 50.0  # s/m
STICTION_TOLERANCE = 1.0e-4  # m/s, MultibodyPlantConfig.stiction_tolerance (not read back: no getter)
HYDROELASTIC_MODULUS = 1.0e7  # Pa, of every compliant geometry (contact_model=hydroelastic)
RESOLUTION_HINT = 0.02  # m, the tetrahedral mesh's edge length of a compliant sphere (Drake's default)
# The Hunt-Crossley root a = d v is found by bisection on [0, A_MAX]: e(a) falls from 1 at a = 0 to ~1 / a for
# large a, ~1e-6 at A_MAX (a restitution the cases never ask for), to A_TOL relative (a double's resolution).
A_MAX = 1.0e6
A_TOL = 1e-15

CONTACT_OPTIONS = {
    "contact_solver": Option(SOLVERS, SOLVERS[0], "Drake's discrete contact solver: sap (its default, lagged "
                                                  "approximation) or tamsi", only=("discrete",)),
    "point_contact_stiffness": Option(default=STIFFNESS_DEFAULT, exclusive_minimum=0.0,
                                      description=f"point contact stiffness of every geometry, N/m (Drake's default "
                                                  f"{STIFFNESS_DEFAULT:g}; a pair's is half of it)"),
    "hunt_crossley_dissipation": Option(default=DISSIPATION_DEFAULT, minimum=0.0,
                                        description=f"Hunt-Crossley dissipation of pairs without restitution, s/m "
                                                    f"(Drake's default {DISSIPATION_DEFAULT:g})"),
    "contact_model": Option(MODELS, MODELS[0], "Drake's contact model: point (Hunt-Crossley point "
                            "contact) or hydroelastic (compliant geoms, rigid planes)"),
    "impact_speed": Option(default=None, exclusive_minimum=0.0,
                           description="approach speed (m/s) at which a pair's restitution is mapped to a "
                                       "Hunt-Crossley dissipation (none: restitution unsupported)"),
}


def contact_options(settings):
    """The contact options of ``settings`` (None: the defaults) with their declared defaults (``CONTACT_OPTIONS``,
    checked by ``Adapter.check``): dict ``solver`` (str), ``stiffness`` (N/m), ``dissipation`` (s/m),
    ``impact_speed`` (m/s or None), ``model`` (str)."""
    o = typed_options(CONTACT_OPTIONS, settings)
    return {"solver": o["contact_solver"], "stiffness": o["point_contact_stiffness"],
            "dissipation": o["hunt_crossley_dissipation"], "impact_speed": o["impact_speed"],
            "model": o["contact_model"]}


def _restitution_of(a):
    """The restitution e of a Hunt-Crossley impact with ``a = d v`` (the closed form in the module docstring):
    the root ``b = e a`` in (0, 1) of ``-b - ln(1 - b) = a - ln(1 + a)``."""
    if a == 0.0:
        return 1.0
    target = a - math.log1p(a)
    lo, hi = 0.0, 1.0  # -b - ln(1 - b) rises from 0 to infinity on [0, 1)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid >= 1.0:  # b within a roundoff of 1: e = 1 / a to double precision
            break
        if -mid - math.log1p(-mid) < target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi) / a


def restitution_dissipation(e, speed):
    """The Hunt-Crossley dissipation d (s/m) that returns ``e`` of the approach ``speed`` (m/s) under Drake's
    point contact (module docstring): ``a / speed`` for the root a of ``e(a) = e`` (bisection; e(a) decreases)."""
    if e >= 1.0:
        return 0.0
    lo, hi = 0.0, A_MAX
    while hi - lo > A_TOL * hi:
        mid = 0.5 * (lo + hi)
        if _restitution_of(mid) > e:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi) / speed


def _pair_material(pair, options):
    """(friction, dissipation) of a pair's geometries."""
    if pair.restitution is None:
        return pair.friction, options["dissipation"]
    return pair.friction, restitution_dissipation(pair.restitution, options["impact_speed"])


def why_not(scene, settings):
    """Why Drake cannot represent the scene's contact (or its loops under TAMSI), or None."""
    options = contact_options(settings)
    if scene.loops and settings.integrator == "discrete" and options["solver"] != "sap":
        return (f"loops with contact_solver={options['solver']}: Drake's loop constraints are SAP's (TAMSI "
                "does not support constraints: Drake refuses the plant) — use contact_solver=sap")
    if not scene.contacts:
        return None
    rubbing = [c.name for c in scene.contacts if c.friction > 0.0]
    if rubbing and settings.integrator != "discrete":
        return f"friction (pairs {rubbing}) with a continuous-time integrator: {CONTINUOUS_FRICTION_REASON}"
    bouncing = [c.name for c in scene.contacts if c.restitution is not None]
    if bouncing and options["impact_speed"] is None:
        return (f"restitution (pairs {bouncing}): Drake has no restitution coefficient; its Hunt-Crossley "
                "dissipation d returns e(d v) of an approach speed v (a - ln(1 + a) = -e a - ln(1 - e a), a = d v), "
                "so one d gives the scene's e at one speed only — give --option impact_speed=<m/s> to map it there")
    plastic = [c.name for c in scene.contacts if c.restitution == 0.0]
    if plastic:
        return (f"contact pairs {plastic} are perfectly plastic (restitution 0): Drake's Hunt-Crossley law needs an "
                "infinite dissipation for it")
    material = {}
    for c in scene.contacts:
        for end in (c.a, c.b):
            material.setdefault(end, set()).add(_pair_material(c, options))
    mixed = sorted(name for name, m in material.items() if len(m) > 1)
    if mixed:
        return (f"geometries {mixed} are in pairs with different friction or restitution: Drake's contact "
                "parameters are per geometry (combined per pair), so one geometry cannot take several")
    return None


# Drake warns, once per process, that a rigid HalfSpace with proximity properties is invisible to deformable contact
# ("Rigid (non-deformable) half spaces are not currently supported for deformable contact; registration is allowed,
# but no contact data will be reported"). A scene's plane is a HalfSpace and no scene has a deformable body, so the
# warning never concerns a run: dropped, that exact message alone, from Drake's logger (``_quiet_half_spaces``).
HALF_SPACE_WARNING = "half spaces are not currently supported for deformable contact"


class _HalfSpaceWarning(logging.Filter):
    """Drops Drake's ``HALF_SPACE_WARNING`` and nothing else."""

    def filter(self, record):
        return HALF_SPACE_WARNING not in record.getMessage()


def _quiet_half_spaces():
    """Install ``_HalfSpaceWarning`` on Drake's logger (once per process)."""
    logger = logging.getLogger("drake")
    if not any(isinstance(f, _HalfSpaceWarning) for f in logger.filters):
        logger.addFilter(_HalfSpaceWarning())


def add_geometry(plant, scene, bodies, settings):
    """Register the scene's geoms and planes with ``plant`` (before ``Finalize``) and set point contact and the
    discrete approximation; return ``(scene_graph, ids)``, ``ids`` a dict geom or plane name -> ``GeometryId``.
    ``exclude_unnamed`` must follow ``Finalize``."""
    from pydrake.geometry import (AddCompliantHydroelasticProperties, AddContactMaterial,
                                  AddRigidHydroelasticProperties, Box, HalfSpace, ProximityProperties, Sphere)
    from pydrake.math import RigidTransform, RotationMatrix
    from pydrake.multibody.plant import ContactModel, CoulombFriction

    options = contact_options(settings)
    material = {}
    for c in scene.contacts:
        for end in (c.a, c.b):
            material[end] = _pair_material(c, options)

    hydro = options["model"] == "hydroelastic"

    def props(name, plane=False):
        mu, d = material.get(name, (0.0, options["dissipation"]))
        p = ProximityProperties()
        AddContactMaterial(d, options["stiffness"], CoulombFriction(mu, mu), p)
        if hydro and plane:
            AddRigidHydroelasticProperties(p)
        elif hydro:
            AddCompliantHydroelasticProperties(RESOLUTION_HINT, HYDROELASTIC_MODULUS, p)
        return p

    ids = {}
    for g in scene.geoms:
        shape = Sphere(g.size[0]) if g.kind == "sphere" else Box(*g.size)
        X_BG = RigidTransform(RotationMatrix(spatial.quat_to_matrix(np.asarray(g.quat) / np.linalg.norm(g.quat))),
                              np.asarray(g.point, dtype=float))
        ids[g.name] = plant.RegisterCollisionGeometry(bodies[g.body], X_BG, shape, g.name, props(g.name))
    if scene.planes:
        _quiet_half_spaces()
    for pl in scene.planes:
        X_WG = HalfSpace.MakePose(pl.unit_normal, np.asarray(pl.point, dtype=float))
        ids[pl.name] = plant.RegisterCollisionGeometry(plant.world_body(), X_WG, HalfSpace(), pl.name,
                                                     props(pl.name, plane=True))
    plant.set_contact_model(ContactModel.kHydroelastic if hydro else ContactModel.kPoint)
    return ids


def set_solver(plant, settings):
    """Set a discrete plant's contact solver (before ``Finalize``): ``sap`` is Drake's default (the SAP solver,
    lagged approximation), set again as it is; ``tamsi`` the TAMSI solver. Every discrete plant, with contact or
    without (the solver also steps a contact-free plant: TAMSI's and SAP's implicit joint terms differ)."""
    from pydrake.multibody.plant import DiscreteContactApproximation

    solver = contact_options(settings)["solver"]
    plant.set_discrete_contact_approximation(DiscreteContactApproximation.kLagged if solver == "sap"
                                             else DiscreteContactApproximation.kTamsi)


def exclude_unnamed(scene_graph, scene, ids):
    """Exclude every pair of geometries the scene does not name (after ``Finalize``, which adds the plant's own
    filters), and check that the collision candidates left are exactly the named pairs."""
    from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

    named = {frozenset((c.a, c.b)) for c in scene.contacts}
    names = list(ids)
    declaration = CollisionFilterDeclaration()
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            if frozenset((a, b)) not in named:
                declaration.ExcludeBetween(GeometrySet(ids[a]), GeometrySet(ids[b]))
    scene_graph.collision_filter_manager().Apply(declaration)
    left = candidates(scene_graph)
    if left != named:
        raise ValueError(f"contacts: Drake would let {sorted(map(sorted, left))} collide, not the scene's pairs "
                         f"{sorted(map(sorted, named))} (a pair of welded or jointed bodies is filtered by the plant) "
                         "— name pairs between bodies Drake lets collide")


def candidates(scene_graph):
    """The collision candidates SceneGraph holds: a set of frozensets of two geometry names."""
    inspector = scene_graph.model_inspector()
    return {frozenset((inspector.GetName(a), inspector.GetName(b))) for a, b in inspector.GetCollisionCandidates()}


def _read_geometry(scene_graph, ids):
    """Each geometry's shape and contact material, read back from SceneGraph."""
    inspector = scene_graph.model_inspector()
    out = {}
    for name, gid in ids.items():
        p = inspector.GetProximityProperties(gid)
        friction = p.GetProperty("material", "coulomb_friction")
        shape = inspector.GetShape(gid)
        out[name] = {
            "shape": type(shape).__name__,
            "size": ([shape.radius()] if hasattr(shape, "radius") else
                     [shape.width(), shape.depth(), shape.height()] if hasattr(shape, "width") else []),
            "static_friction": float(friction.static_friction()),
            "dynamic_friction": float(friction.dynamic_friction()),
            "point_contact_stiffness": float(p.GetProperty("material", "point_contact_stiffness")),
            "hunt_crossley_dissipation": float(p.GetProperty("material", "hunt_crossley_dissipation")),
        }
    return out


def audit(model):
    """Every contact parameter as the plant and its SceneGraph hold them (none: empty): the contact model, the
    discrete solver and approximation, every geometry (shape, size, friction, stiffness, dissipation), every
    pair's combined friction, stiffness and dissipation and the restitution its dissipation stands for at the
    mapped speed, and the collision candidates (the named pairs, and nothing else)."""
    from pydrake.multibody.plant import CalcContactFrictionFromSurfaceProperties, CoulombFriction

    scene, plant = model.scene, model.plant
    if not scene.contacts:
        return {}
    geometry = _read_geometry(model.scene_graph, model.geometry_ids)
    options = contact_options(model.settings)
    pairs = {}
    for c in scene.contacts:
        ga, gb = geometry[c.a], geometry[c.b]
        mu = CalcContactFrictionFromSurfaceProperties(
            CoulombFriction(ga["static_friction"], ga["dynamic_friction"]),
            CoulombFriction(gb["static_friction"], gb["dynamic_friction"]))
        ka, kb = ga["point_contact_stiffness"], gb["point_contact_stiffness"]
        d = (kb * ga["hunt_crossley_dissipation"] + ka * gb["hunt_crossley_dissipation"]) / (ka + kb)
        speed = options["impact_speed"]
        pairs[c.name] = {
            "geoms": [c.a, c.b],
            "friction": [float(mu.static_friction()), float(mu.dynamic_friction())],
            "point_contact_stiffness": ka * kb / (ka + kb), "hunt_crossley_dissipation": d,
            "restitution_at_impact_speed": (None if c.restitution is None or speed is None else
                                            _restitution_of(d * speed)),
        }
    discrete = plant.time_step() > 0.0
    return {
        "contact_model": plant.get_contact_model().name,
        "contact_solver": plant.get_discrete_contact_solver().name if discrete else "none (continuous mode)",
        "contact_approximation": plant.get_discrete_contact_approximation().name if discrete else "",
        "contact_geometries": geometry,
        "contact_pairs": pairs,
        "collision_candidates": sorted(sorted(p) for p in candidates(model.scene_graph)),
        "impact_speed": options["impact_speed"],
        "stiction_tolerance": (f"{STICTION_TOLERANCE:g} m/s, Drake's default (MultibodyPlantConfig; not read "
                               "back: the plant has no getter)"),
        "restitution_mapping": ("restitution e -> Hunt-Crossley dissipation d = a / v at v = impact_speed, a the "
                                "root of a - ln(1 + a) = -e a - ln(1 - e a) (exact for Drake's point contact "
                                "k x (1 + d xdot)); other approach speeds get other restitutions"),
    }


def summary_lines(model):
    """The contact lines of the plant's summary (``dalembert show-model``)."""
    a = audit(model)
    if not a:
        return []
    lines = [f"contact: {a['contact_model']}, {a['contact_solver']} {a['contact_approximation']}".rstrip()]
    for name, g in a["contact_geometries"].items():
        lines.append(f"geometry {name}: {g['shape']} {g['size']}, mu {g['static_friction']!r}, stiffness "
                     f"{g['point_contact_stiffness']:g} N/m, dissipation {g['hunt_crossley_dissipation']!r} s/m")
    for name, p in a["contact_pairs"].items():
        lines.append(f"pair {name}: {p['geoms'][0]} - {p['geoms'][1]}, mu {p['friction'][0]!r}, stiffness "
                     f"{p['point_contact_stiffness']:g} N/m, dissipation {p['hunt_crossley_dissipation']!r} s/m")
    return lines


def read_forces(model, times, X):
    """The contact force (N, world) ON each of the scene's pairs' subjects at the plant states ``X (n, nq + nv)``,
    ndarray (n, n_pairs, 3) (NaN where a state is not finite); None for a scene without contact."""
    from dalembert.contact import subject

    scene, plant = model.scene, model.plant
    if not scene.contacts:
        return None
    names = {gid: name for name, gid in model.geometry_ids.items()}
    index = {frozenset((c.a, c.b)): (i, subject(scene, c)) for i, c in enumerate(scene.contacts)}
    context = model.diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    port = plant.get_contact_results_output_port()
    out = np.full((len(times), len(scene.contacts), 3), np.nan)

    def add(total, a, b, force_on_b):
        found = index.get(frozenset((names.get(a), names.get(b))))
        if found is not None:
            i, on = found
            total[i] += force_on_b if names[b] == on else -force_on_b

    for k in np.flatnonzero(np.all(np.isfinite(X), axis=1)):
        context.SetTime(float(times[k]))
        plant.SetPositionsAndVelocities(plant_context, X[k])
        results = port.Eval(plant_context)
        total = np.zeros((len(scene.contacts), 3))
        for c in range(results.num_point_pair_contacts()):
            info = results.point_pair_contact_info(c)
            pair = info.point_pair()
            add(total, pair.id_A, pair.id_B, np.asarray(info.contact_force()))
        for c in range(results.num_hydroelastic_contacts()):
            info = results.hydroelastic_contact_info(c)
            surface = info.contact_surface()
            # F_Ac_W acts on the body of geometry M: the force on N's is its opposite
            add(total, surface.id_N(), surface.id_M(), np.asarray(info.F_Ac_W().translational()))
        out[k] = total
    return out
