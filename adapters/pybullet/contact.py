"""PyBullet's model of a scene's contact: geoms, planes, the named pairs, friction and restitution (hard contact:
PyBullet's constraint solver, impulses at the contact points); read back from the engine for the audit.

* Every scene ``Geom`` of a free body becomes a collision shape of its multibody's base (``sphere``: the radius;
  ``box``: the half edge lengths), at its point and attitude in the base's frame E (the inertial frame,
  ``model``); several geoms of one body a compound (``createCollisionShapeArray``). The mass properties stay the
  scene's: the adapter sets them after the shapes (``changeDynamics``), and checks them. A geom on a jointed body
  (a link) is not mapped yet (``why_not``).
* Every ``Plane`` a static multibody of its own (mass 0) with a ``GEOM_PLANE`` shape, its z the plane's normal.
* Nothing collides by default: every collision object's group and mask are 0, and each ``ContactPair`` is
  enabled by ``setCollisionFilterPair`` (which overrides the masks): nothing touches that the scene does not name.
* Friction and restitution: Bullet gives a contact the product of its two objects' coefficients
  (``btManifoldResult``: friction ``f_a f_b``, capped at 10; restitution ``r_a r_b``). A pair's values are set
  through its two objects (``coefficients``): the first object of a pair with nothing set yet gets the pair's
  value and the other 1; a pair whose product cannot then be the scene's is refused (``why_not``). A pair
  without restitution gets 0 (Bullet's default: plastic, the contact stays closed). Bullet bounces only above a
  relative normal speed (``restitutionVelocityThreshold``, 0.2 m/s by default): set to 0, so every impact of a
  pair with restitution bounces. Rolling and spinning friction 0 (an ideal Coulomb point contact), the contact
  stiffness and damping unset (hard contact), friction anchors off.
* Contact forces (``read_forces``): after a step, ``getContactPoints(A, B)`` lists the step's points between two
  multibodies, each with its ``normalForce`` along ``contactNormalOnB`` (from B towards A) and its two lateral
  friction forces along their directions: their sum is the force ON A, N, world axes (measured, pybullet 3.2.7, on
  block_on_incline and ball_rolling_incline with the body as A: equal to the body's ``m (v+ - v) / h - m g`` over
  the step to 1e-6 N, the print; asked with the plane as A, the normal turns but the friction directions do not, so
  the subject is always asked as A). Summed per pair ON its subject (``dalembert.contact.subject``). A pair whose
  two multibodies carry another pair too is not measured (Bullet reports per multibody, not per shape). Bullet's
  points and their warm-started impulses live in its persistent manifolds, which no reset of a state rebuilds
  (``model.rebuild``), so the force of the step from a sample cannot be had by setting that state: the run is
  replayed in a client of its own, built as the run's was, its states checked bit for bit against the run's at
  every sample, and each sample's force read after the first step from it (the step that starts at the sample, as
  MuJoCo's and Drake's read-backs give theirs).
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial

__all__ = ["why_not", "coefficients", "build", "audit", "read_forces", "MAX_FRICTION"]

# Bullet's cap on a contact's combined friction (btManifoldResult.cpp, MAX_FRICTION).
MAX_FRICTION = 10.0


def why_not(scene):
    """Why PyBullet's adapter cannot represent the scene's contact, or None."""
    if not scene.contacts:
        return None
    jointed = sorted({g.name for g in scene.geoms if scene.joint(g.body).kind != "free"})
    if jointed:
        return (f"contact geoms {jointed} are on jointed bodies: PyBullet's link collision shapes are not mapped "
                "yet (only free bodies' geoms are)")
    for key in ("friction", "restitution"):
        try:
            coefficients(scene, key)
        except ValueError as e:
            return str(e)
    return None


def coefficients(scene, key):
    """Per geom or plane name, the coefficient ``key`` (``friction`` or ``restitution``) its PyBullet object
    takes so that each pair's product is the scene's (module docstring); ValueError where no such values exist."""
    values = {}
    for c in scene.contacts:
        want = getattr(c, key) or 0.0
        a, b = values.get(c.a), values.get(c.b)
        if a is None and b is None:
            values[c.a], values[c.b] = want, 1.0
        elif b is None:
            values[c.b] = want / a if a else 1.0
        elif a is None:
            values[c.a] = want / b if b else 1.0
        if values[c.a] * values[c.b] != want or (key == "friction" and want > MAX_FRICTION):
            raise ValueError(f"contact pairs' {key}: Bullet combines two objects' coefficients as their product, and "
                             f"no values of {c.a!r} and {c.b!r} give pair {c.name!r} its {want!r} beside the other "
                             "pairs they are in")
    return values


def _shape(pb, c, geoms, R_EB):
    """One collision shape index for ``geoms`` (of one free body), placed in its base frame E."""
    kinds, radii, halves, points, quats = [], [], [], [], []
    for g in geoms:
        kinds.append(pb.GEOM_SPHERE if g.kind == "sphere" else pb.GEOM_BOX)
        radii.append(g.size[0] if g.kind == "sphere" else 0.0)
        halves.append([0.0, 0.0, 0.0] if g.kind == "sphere" else [0.5 * s for s in g.size])
        points.append(list(R_EB @ np.asarray(g.point)))
        R = R_EB @ spatial.quat_to_matrix(np.asarray(g.quat) / np.linalg.norm(g.quat))
        quats.append([float(v) for v in spatial.wxyz_to_xyzw(spatial.matrix_to_quat(R))])
    if len(geoms) == 1:
        return pb.createCollisionShape(kinds[0], radius=radii[0], halfExtents=halves[0],
                                       collisionFramePosition=points[0], collisionFrameOrientation=quats[0],
                                       physicsClientId=c)
    return pb.createCollisionShapeArray(kinds, radii=radii, halfExtents=halves, collisionFramePositions=points,
                                        collisionFrameOrientations=quats, physicsClientId=c)


def base_shapes(pb, c, scene, frames):
    """Per free body with geoms, the collision shape of its base (``frames``: body -> ``(moments, R_BE)``)."""
    out = {}
    for b in scene.bodies:
        geoms = [g for g in scene.geoms if g.body == b.name]
        if geoms and scene.joint(b.name).kind == "free":
            out[b.name] = _shape(pb, c, geoms, frames[b.name][1].T)
    return out


def build(pb, c, scene, parts):
    """The planes, the collision filters and the pairs' coefficients, in client ``c`` whose multibodies (with the
    geoms' shapes) are built: ``parts`` body -> ``model.Part``. Returns plane name -> multibody id."""
    planes = {}
    for p in scene.planes:
        shape = pb.createCollisionShape(pb.GEOM_PLANE, planeNormal=[0, 0, 1], physicsClientId=c)
        quat = spatial.matrix_to_quat(spatial.frame_with_z(p.unit_normal))
        planes[p.name] = pb.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=shape, basePosition=list(p.point),
                                            baseOrientation=[float(v) for v in spatial.wxyz_to_xyzw(quat)],
                                            physicsClientId=c)
    owner = {g.name: parts[g.body].mb for g in scene.geoms}
    owner.update(planes)
    for mb in set(owner.values()):
        pb.setCollisionFilterGroupMask(mb, -1, 0, 0, physicsClientId=c)
    for pair in scene.contacts:
        pb.setCollisionFilterPair(owner[pair.a], owner[pair.b], -1, -1, 1, physicsClientId=c)
    friction, restitution = coefficients(scene, "friction"), coefficients(scene, "restitution")
    for name, mb in owner.items():
        pb.changeDynamics(mb, -1, lateralFriction=friction.get(name, 0.0), restitution=restitution.get(name, 0.0),
                          rollingFriction=0.0, spinningFriction=0.0, frictionAnchor=0, physicsClientId=c)
    pb.setPhysicsEngineParameter(restitutionVelocityThreshold=0.0, physicsClientId=c)
    return planes


def audit(pb, model, scene):
    """The contact as the engine holds it (none: empty): per geom and plane, its object's friction, restitution,
    rolling and spinning friction, contact stiffness and damping and collision margin (``getDynamicsInfo``), and
    its shapes (``getCollisionShapeData``); the pairs with the coefficients Bullet combines for them."""
    if not scene.contacts:
        return {}
    c = model.client
    owner = {g.name: model.parts[g.body].mb for g in scene.geoms}
    owner.update(model.planes)
    objects = {}
    for name, mb in owner.items():
        info = pb.getDynamicsInfo(mb, -1, physicsClientId=c)
        objects[name] = {"multibody": int(mb), "friction": float(info[1]), "restitution": float(info[5]),
                         "rolling_friction": float(info[6]), "spinning_friction": float(info[7]),
                         "contact_damping": float(info[8]), "contact_stiffness": float(info[9]),
                         "collision_margin": float(info[11]),
                         "shapes": [{"type": int(s[2]), "dimensions": [float(v) for v in s[3]]}
                                    for s in pb.getCollisionShapeData(mb, -1, physicsClientId=c)]}
    pairs = {p.name: {"objects": [p.a, p.b],
                      "friction": min(objects[p.a]["friction"] * objects[p.b]["friction"], MAX_FRICTION),
                      "restitution": objects[p.a]["restitution"] * objects[p.b]["restitution"]}
             for p in scene.contacts}
    return {"contact_objects": objects, "contact_pairs": pairs,
            "contact_model": "hard: impulses from PyBullet's constraint solver (the solver option), Bullet's "
                             "products of the objects' coefficients, restitution from any approach speed"}


def _pair_bodies(scene, model):
    """Per scene pair, ``(subject's multibody, the other's)`` (``dalembert.contact.subject``), or None where the two
    multibodies carry another pair too (Bullet's points are per multibody: not measured)."""
    from dalembert.contact import subject

    owner = {g.name: model.parts[g.body].mb for g in scene.geoms}
    owner.update(model.planes)
    couples = [frozenset((owner[p.a], owner[p.b])) for p in scene.contacts]
    out = []
    for pair, couple in zip(scene.contacts, couples):
        s = subject(scene, pair)
        other = pair.b if s == pair.a else pair.a
        out.append((owner[s], owner[other]) if couples.count(couple) == 1 else None)
    return out


def _forces(pb, c, bodies):
    """The force ON each subject (N, world) in the client's last step, ndarray (n_pairs, 3) (NaN: not measured)."""
    out = np.full((len(bodies), 3), np.nan)
    for i, ab in enumerate(bodies):
        if ab is None:
            continue
        out[i] = 0.0
        for pt in pb.getContactPoints(ab[0], ab[1], physicsClientId=c):
            out[i] += pt[9] * np.asarray(pt[7]) + pt[10] * np.asarray(pt[11]) + pt[12] * np.asarray(pt[13])
    return out


def read_forces(p, X):
    """The contact force (N, world axes) ON each scene pair's subject over the step that starts at each sample, from
    a replay of the run (module docstring): ``(forces, replayed)``, ``forces`` a dict pair name -> ndarray (n, 3) of
    the pairs measured (``_pair_bodies``), NaN for a non-finite sample and from the first sample whose replayed
    state is not the run's bit for bit; ``replayed``: the number of samples the replay matched. ``p``: the
    ``PybulletPrepared``, ``X`` (n, state_size) the run's sampled states (``stepping.read_state``)."""
    from dalembert.adapters.pybullet.model import build as build_model
    from dalembert.adapters.pybullet.model import engine
    from dalembert.adapters.pybullet.stepping import apply_loads, load_plan, read_state, state_size

    pb, scene = engine(), p.scene
    model = build_model(scene, p.settings)  # a fresh client: its first run, as the run's (rebuilt before it)
    c, plan = model.client, load_plan(model, scene)
    bodies = _pair_bodies(scene, model)
    n = len(p.times)
    out = np.full((n, len(scene.contacts), 3), np.nan)
    row = np.empty(state_size(model))
    replayed = 0
    for k in range(n):
        read_state(pb, model, row)
        if not (np.all(np.isfinite(X[k])) and np.array_equal(row, X[k])):
            break
        replayed += 1
        steps = int(p.steps[k]) if k < len(p.steps) else 1  # the last sample: the one step after it
        for i in range(steps):
            if plan:
                apply_loads(pb, c, plan)
            pb.stepSimulation(physicsClientId=c)
            if i == 0:
                out[k] = _forces(pb, c, bodies)
    return {pair.name: out[:, i] for i, pair in enumerate(scene.contacts) if bodies[i] is not None}, replayed
