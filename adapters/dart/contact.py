"""A scene's contact as DART's hard contact: geoms and planes as collision shapes, friction and restitution per
shape; read back for the audit.

* Every ``Geom`` of a pair becomes a ``ShapeNode`` of its body (``SphereShape`` of the radius, ``BoxShape`` of the
  full edge lengths, as the scene's) at the geom's point and attitude in the body frame B (DART's body frame),
  with a collision and a dynamics aspect; shapes add no mass (the body's ``Inertia`` is set explicitly). Every
  ``Plane`` of a pair is a ``PlaneShape`` (unit normal, offset ``n . point``) of a body welded to the world in a
  skeleton of its own, not mobile (``GROUND``), so it adds no coordinates to the scene's skeleton. A pair of two
  geoms is two bodies of the scene's skeleton, which DART checks only with its self-collision check (adjacent
  bodies included): both are switched on for it (only the pair's shapes exist, so only it can touch).
* DART's contact is hard: per step, the collision detector (FCL, DART's default) finds the contact points and the
  constraint solver solves a boxed LCP (Dantzig) for impulses that keep the bodies from approaching, with a
  Coulomb friction box per contact and Newton's restitution on the approach speed; penetration is corrected by
  DART's error reduction.
* DART keeps friction and restitution per shape and combines a pair's from its two shapes. The pair's values go on
  its first geom (``a``) and 1 on the other side (a plane or a geom), which leaves them the pair's (measured:
  friction the smaller of the two shapes', the slide-to-roll ball the same with 0.5 or 1 on the ground; with 1 on
  the ground, the bounce's apex and the two spheres' velocities after are Newton's with the first shape's
  restitution; with 0.5 on the ground as well the ball's restitution came out 0.06, neither the product nor the
  smaller: other combinations are not characterised here). So every geom and plane may be in one pair, a
  friction coefficient may not exceed 1, and only one pair is built: DART's collision filter, which would keep
  shapes of different pairs from touching each other, is an attribute of the constraint solver's collision
  option, which dartpy 6.20 returns as a copy (it cannot be set), so a second pair would let unnamed shapes touch
  (``why_not``). A pair without restitution gets 0 (a plastic impact: it stays closed once made).
* Contact forces (``read_forces``): DART keeps each contact point of a step in ``World.getLastCollisionResult()``,
  its ``force`` the constraint solver's impulse over the step (N, world axes), ON the shape of
  ``collisionObject1`` (measured on block_on_incline, dartpy 6.20: the points' sum is the box's ``m (v+ - v) / h - m
  g`` over the step to roundoff, pushing it off the plane). Summed over the pair's points, ON the pair's subject
  (``dalembert.contact.subject``: the other sign where the subject is ``collisionObject2``). The read-back takes one
  ``World.step`` from each sampled state (``readback``), so it is the force of the step that starts at the sample, as
  MuJoCo's and Drake's. DART's box on a plane gets one point per step (FCL's deepest), so the box rocks from corner
  to corner and its per-step force swings about m g cos(angle) (measured: 2.1 to 23.6 N normal over the first
  60 ms, 9.22 N the closed form): the force is the engine's, the harness shows it.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial

__all__ = ["why_not", "add_contact", "audit", "read_forces", "GROUND"]

# The skeleton that carries the scene's planes (a body welded to the world, not mobile).
GROUND = "dalembert_planes"
# The value on the other side of a pair: neutral in DART's combination of friction (the smaller, measured) and of
# restitution (measured on the bounce and the two spheres; module docstring).
NEUTRAL = 1.0


def why_not(scene):
    """Why DART's contact cannot be the scene's, or None."""
    if not scene.contacts:
        return None
    if len(scene.contacts) > 1:
        return ("contact: more than one contact pair (DART 6.20's collision filter is not settable from dartpy, so "
                "shapes of different pairs could touch where the scene names no pair)")
    pair = scene.contacts[0]
    if pair.friction > NEUTRAL:
        return (f"contact: {pair.name}.friction {pair.friction:g} > 1 (DART combines two shapes' friction by the "
                "smaller, and the other side holds 1, the value that leaves a pair's restitution its own)")
    return None


def add_contact(model):
    """The scene's one pair as collision shapes in ``model.world`` (``why_not`` is None); returns the shape nodes
    by geom or plane name."""
    import dartpy

    scene = model.scene
    if not scene.contacts:
        return {}
    dyn = dartpy.dynamics
    pair = scene.contacts[0]
    restitution = 0.0 if pair.restitution is None else pair.restitution
    geoms = {g.name: g for g in scene.geoms}
    planes = {p.name: p for p in scene.planes}
    nodes = {}
    ground = None
    for name, values in ((pair.a, (pair.friction, restitution)), (pair.b, (NEUTRAL, NEUTRAL))):
        if name in geoms:
            g = geoms[name]
            shape = dyn.SphereShape(g.size[0]) if g.kind == "sphere" else dyn.BoxShape(np.asarray(g.size, dtype=float))
            node = model.nodes[g.body].createShapeNode(shape, name)
            from dalembert.adapters.dart.model import isometry

            node.setRelativeTransform(isometry(g.point, spatial.quat_to_matrix(g.quat)))
        else:
            p = planes[name]
            if ground is None:
                ground = dyn.Skeleton(GROUND)
                _, body = ground.createWeldJointAndBodyNodePair()
                body.setInertia(dyn.Inertia(1.0, np.zeros(3), np.eye(3)))  # never moves: not mobile
                ground.setMobile(False)
                model.world.addSkeleton(ground)
            n = p.unit_normal
            node = ground.getBodyNode(0).createShapeNode(dyn.PlaneShape(n, float(n @ np.asarray(p.point))), name)
        node.createCollisionAspect()
        aspect = node.createDynamicsAspect()
        aspect.setFrictionCoeff(float(values[0]))
        aspect.setRestitutionCoeff(float(values[1]))
        nodes[name] = node
    if pair.a in geoms and pair.b in geoms:  # both bodies in the scene's skeleton: DART checks them only as self-
        model.skeleton.enableSelfCollisionCheck()  # collision, adjacent bodies too (the scene names this pair)
        model.skeleton.enableAdjacentBodyCheck()
    return nodes


def audit(model):
    """The contact shapes as DART holds them: per geom or plane its shape type and size, friction and restitution
    coefficients (read from its dynamics aspect), the collision detector, and how DART combines a pair's."""
    if not model.scene.contacts:
        return {}
    solver = model.world.getConstraintSolver()
    shapes = {}
    for name, node in model.contact.items():
        shape, aspect = node.getShape(), node.getDynamicsAspect()
        shapes[name] = {"shape": type(shape).__name__, "friction": float(aspect.getFrictionCoeff()),
                        "restitution": float(aspect.getRestitutionCoeff())}
    return {
        "contact_shapes": shapes,
        "contact_detector": type(solver.getCollisionDetector()).__name__,
        "self_collision_check": bool(model.skeleton.getSelfCollisionCheck()),
        "adjacent_body_check": bool(model.skeleton.getAdjacentBodyCheck()),
        "contact_model": ("hard: boxed LCP (Dantzig) per step, Coulomb friction box, Newton restitution; the pair's "
                          "values on its first shape, 1 on the other (DART combines the two shapes')"),
    }


def read_forces(model):
    """The contact force (N, world axes) ON each of the scene's pairs' subjects (``dalembert.contact.subject``) in
    the world's last step, ndarray (n_pairs, 3) (zero where the pair made no point): the points' ``force`` of
    ``World.getLastCollisionResult()``, each ON its ``collisionObject1``'s shape (module docstring)."""
    from dalembert.contact import subject

    scene = model.scene
    total = np.zeros((len(scene.contacts), 3))
    # per unordered pair of shape names: (its index in scene.contacts, its subject's name)
    index = {frozenset((pair.a, pair.b)): (i, subject(scene, pair)) for i, pair in enumerate(scene.contacts)}
    result = model.world.getLastCollisionResult()
    for j in range(result.getNumContacts()):
        point = result.getContact(j)
        one = point.collisionObject1.getShapeFrame().getName()
        two = point.collisionObject2.getShapeFrame().getName()
        found = index.get(frozenset((one, two)))
        if found is None:  # not a scene pair's (why_not: only the pair's shapes exist)
            continue
        i, name = found
        total[i] += np.asarray(point.force, dtype=float) * (1.0 if one == name else -1.0)
    return total
