"""What makes a scene valid, checked when it is made: every problem collected, each naming its
field and the fix, and raised at once (``SceneError``) before anything runs.

Bodies (a positive mass, a symmetric positive definite inertia that some mass distribution has; a
free body's not singular), joints (known kinds, known bodies, the right number of coordinates,
unit quaternions, an axis where the kind takes one, a tree rooted at the world), loads, loop
closures (closed at the initial state to ``LOOP_CLOSURE_TOL``), spring-dampers (points apart at
the initial state) and contact (geoms on known bodies with positive sizes, planes with a normal, pairs
naming known geoms and planes with a Coulomb coefficient >= 0 and a restitution in [0, 1], no pair
interpenetrating at the initial state beyond ``INITIAL_OVERLAP_TOL``). ``dalembert.scene`` re-exports
``SceneError`` and the tolerances.
"""

from __future__ import annotations

import math

import numpy as np

from dalembert import closure, contact, spatial, springs
from dalembert.kinds import AXIS_KINDS, GEOM_KINDS, JOINT_KINDS, LOAD_FRAMES, LOAD_KINDS, LOOP_KINDS, WORLD
from dalembert.registry import suggest

__all__ = ["SceneError", "scene_problems", "QUAT_NORM_TOL", "INERTIA_REL_TOL", "SINGULAR_INERTIA_RATIO",
           "LOOP_CLOSURE_TOL", "INITIAL_OVERLAP_TOL"]

# |q| may differ from 1 by this much (roundoff in user-typed decimals is ~1e-16;
# anything larger is a real mistake, not roundoff).
QUAT_NORM_TOL = 1e-9
# Inertia symmetry and the triangle inequality are checked to this relative
# tolerance: tensors computed from point masses carry roundoff of a few ulps.
INERTIA_REL_TOL = 1e-12
# A free body's smallest principal moment below this fraction of the largest is
# treated as singular: the rotation about that axis is then undetermined
# (all particles on one line: the rotator of Landau & Lifshitz, Mechanics, section 32, whose
# moment about that line is zero).
SINGULAR_INERTIA_RATIO = 1e-14
# An initial state whose loop closures are violated by more than this (m for points, the sine of
# the tilt for axes; m/s and rad/s for their rates) is refused: initial coordinates solved in
# double precision close a loop to ~1e-15, and anything beyond 1e-9 is a state the solver would
# have to move (the case's initial state would not be the one simulated).
LOOP_CLOSURE_TOL = 1e-9
# A contact pair whose shapes interpenetrate by more than this (m) at the initial state is refused: an engine
# would push them apart at once, so the motion simulated would not start from the case's state. Shapes placed
# to touch (a ball's centre at its radius above the ground) overlap by roundoff, ~1e-16 m.
INITIAL_OVERLAP_TOL = 1e-9


class SceneError(ValueError):
    """A scene or case is invalid; ``problems`` lists every issue found."""

    def __init__(self, where, problems):
        self.problems = list(problems)
        lines = "\n".join(f"  - {p}" for p in self.problems)
        super().__init__(f"{where}: {len(self.problems)} problem(s)\n{lines}")



def scene_problems(scene):
    """Every problem of ``scene`` (a ``dalembert.scene.Scene``), as a list of messages "where.field: what is
    wrong — the fix"; empty when it is valid. ``Scene.validate`` raises them at once as a ``SceneError``."""
    problems = []
    add = problems.append
    names = [b.name for b in scene.bodies]
    if not scene.bodies:
        add("bodies: empty — add at least one Body")
    for dup in sorted({n for n in names if names.count(n) > 1}):
        add(f"bodies: name {dup!r} used twice — give every body a unique name")
    if WORLD in names:
        add(f"bodies: {WORLD!r} is reserved for the fixed world frame — rename the body")
    if len(scene.gravity) != 3 or not all(math.isfinite(g) for g in scene.gravity):
        add(f"gravity: must be 3 finite numbers (m/s^2, world frame), got {scene.gravity} — "
            "use (0, 0, 0) for none")
    free_bodies = {j.child for j in scene.joints if j.kind == "free"}
    for b in scene.bodies:
        problems += _body_problems(b, b.name in free_bodies)
    problems += _joint_problems(scene, set(names))
    for i, ld in enumerate(scene.loads):
        problems += _load_problems(i, ld, set(names))
    for i, lp in enumerate(scene.loops):
        problems += _loop_problems(i, lp, set(names))
    loop_names = [lp.name for lp in scene.loops]
    for dup in sorted({n for n in loop_names if loop_names.count(n) > 1}):
        add(f"loops: name {dup!r} used twice — give each loop a unique name=")
    for clash in sorted(set(loop_names) & set(names)):
        add(f"loops: name {clash!r} is a body's (its joint's reactions are keyed by it) — rename the loop")
    for i, sp in enumerate(scene.springs):
        problems += _spring_problems(i, sp, set(names))
    spring_names = [sp.name for sp in scene.springs]
    for dup in sorted({n for n in spring_names if spring_names.count(n) > 1}):
        add(f"springs: name {dup!r} used twice — give each spring a unique name=")
    if scene.loops and not problems:  # the closure needs valid names, joints and numbers
        problems += _closure_problems(scene)
    if scene.springs and not problems:  # the initial lengths need valid names, joints and numbers
        problems += _spring_length_problems(scene)
    problems += _contact_problems(scene, set(names))
    if scene.contacts and not problems:  # the initial gaps need valid names, joints and numbers
        problems += _overlap_problems(scene)
    return problems


def _contact_problems(scene, names):
    """Geoms, planes and contact pairs: known names, sizes, numbers, coefficients."""
    problems = []
    add = problems.append
    for i, g in enumerate(scene.geoms):
        where = f"geoms[{i}] ({g.name!r} on {g.body!r})"
        if g.body not in names:
            add(f"{where}.body: no body named {g.body!r}{_did_you_mean(g.body, names)} — a geom is fixed in a body "
                f"of the scene (the ground is a Plane)")
        if g.kind not in GEOM_KINDS:
            add(f"{where}.kind: unknown {g.kind!r} — use one of {list(GEOM_KINDS)}")
        else:
            sizes = GEOM_KINDS[g.kind]
            shape = _numbers_problems(where, "size", g.size, len(sizes), f" ({', '.join(sizes)}, m)")
            problems += shape
            if not shape and not all(v > 0.0 for v in g.size):
                add(f"{where}.size: {', '.join(sizes)} must be positive (m), got {g.size} — give the shape's "
                    "dimensions")
        problems += _numbers_problems(where, "point", g.point, 3, " (m, in the body's frame)")
        shape = _numbers_problems(where, "quat", g.quat, 4)
        problems += shape
        if not shape and abs(math.sqrt(sum(x * x for x in g.quat)) - 1.0) > QUAT_NORM_TOL:
            add(f"{where}.quat: quaternion norm is {math.sqrt(sum(x * x for x in g.quat)):.12g}, not 1 — "
                "normalize it (scalar first: w, x, y, z)")
    for i, p in enumerate(scene.planes):
        where = f"planes[{i}] ({p.name!r})"
        shape = _numbers_problems(where, "normal", p.normal, 3, " (the outward normal, world)")
        problems += shape
        if not shape and not any(p.normal):
            add(f"{where}.normal: zero length — give the plane's outward normal (e.g. (0, 0, 1) for a level ground)")
        problems += _numbers_problems(where, "point", p.point, 3, " (m, a point of the plane, world)")
    shapes = [g.name for g in scene.geoms] + [p.name for p in scene.planes]
    for dup in sorted({n for n in shapes if shapes.count(n) > 1}):
        add(f"geoms, planes: name {dup!r} used twice — give every geom and plane a unique name=")
    planes = {p.name for p in scene.planes}
    seen = {}
    for i, c in enumerate(scene.contacts):
        where = f"contacts[{i}] ({c.name!r}: {c.a!r} - {c.b!r})"
        for field_name in ("a", "b"):
            end = getattr(c, field_name)
            if end not in shapes:
                add(f"{where}.{field_name}: no geom or plane named {end!r}{_did_you_mean(end, set(shapes))} — a pair "
                    "names two of the scene's geoms, or a geom and a plane")
        if c.a == c.b:
            add(f"{where}: pairs {c.a!r} with itself — a pair names two different shapes")
        elif c.a in planes and c.b in planes:
            add(f"{where}: pairs two planes, which are fixed — a pair needs at least one geom")
        else:
            bodies = {g.name: g.body for g in scene.geoms}
            if c.a in bodies and bodies.get(c.b) == bodies[c.a]:
                add(f"{where}: both geoms are on body {bodies[c.a]!r}, which cannot touch itself — pair geoms of "
                    "different bodies")
        key = frozenset((c.a, c.b))
        if key in seen:
            add(f"{where}: the same shapes as contacts[{seen[key]}] — name each pair once")
        seen.setdefault(key, i)
        if not (math.isfinite(c.friction) and c.friction >= 0.0):
            add(f"{where}.friction: must be finite and >= 0 (the Coulomb coefficient, static = kinetic), got "
                f"{c.friction!r} — give 0 for a frictionless contact")
        if c.restitution is not None and not (math.isfinite(c.restitution) and 0.0 <= c.restitution <= 1.0):
            add(f"{where}.restitution: must lie in [0, 1] (Newton's coefficient: 0 plastic, 1 elastic), got "
                f"{c.restitution!r} — or None where the case calls for none")
    pair_names = [c.name for c in scene.contacts]
    for dup in sorted({n for n in pair_names if pair_names.count(n) > 1}):
        add(f"contacts: name {dup!r} used twice — give each pair a unique name=")
    return problems


def _overlap_problems(scene):
    poses = contact.initial_poses(scene)
    problems = []
    for i, c in enumerate(scene.contacts):
        g = contact.gap(scene, c, poses)
        if g is not None and not -g[0] <= INITIAL_OVERLAP_TOL:
            problems.append(f"contacts[{i}] ({c.name!r}: {c.a!r} - {c.b!r}): the shapes interpenetrate by "
                            f"{-g[0]:.3g} m at the initial state, above INITIAL_OVERLAP_TOL = "
                            f"{INITIAL_OVERLAP_TOL:g} m — place them touching or apart (q0, the geoms' points or the "
                            "plane's)")
    return problems


def _joint_problems(scene, names):
    problems = []
    add = problems.append
    parents = {}
    for i, j in enumerate(scene.joints):
        where = f"joints[{i}] ({j.kind} {j.parent!r} -> {j.child!r})"
        if j.kind not in JOINT_KINDS:
            add(f"{where}.kind: unknown {j.kind!r} — use one of {sorted(JOINT_KINDS)}")
            continue
        if j.child not in names:
            add(f"{where}.child: no body named {j.child!r}{_did_you_mean(j.child, names)}")
        if j.parent != WORLD and j.parent not in names:
            add(f"{where}.parent: no body named {j.parent!r}{_did_you_mean(j.parent, names | {WORLD})}")
        if j.parent == j.child:
            add(f"{where}: a body cannot be its own parent")
        if j.child in parents:
            add(f"bodies[{j.child!r}]: has two parents ({parents[j.child]!r} and {j.parent!r}) — "
                "a scene is a tree: one joint per body")
        parents.setdefault(j.child, j.parent)
        nq, nv = JOINT_KINDS[j.kind]
        if len(j.q0) != nq:
            add(f"{where}.q0: {j.kind} needs {nq} numbers, got {len(j.q0)}")
        if len(j.v0) != nv:
            add(f"{where}.v0: {j.kind} needs {nv} numbers, got {len(j.v0)}")
        for field_name in ("q0", "v0", "parent_point", "child_point", "parent_quat", "child_quat"):
            if not all(math.isfinite(v) for v in getattr(j, field_name)):
                add(f"{where}.{field_name}: contains NaN or inf")
        for field_name, n in (("parent_point", 3), ("child_point", 3), ("parent_quat", 4), ("child_quat", 4)):
            if len(getattr(j, field_name)) != n:
                add(f"{where}.{field_name}: needs {n} numbers")
        quats = [("parent_quat", j.parent_quat), ("child_quat", j.child_quat)]
        if j.kind == "free" and len(j.q0) == 7:
            quats.append(("q0[3:7] (attitude)", j.q0[3:]))
        if j.kind == "ball" and len(j.q0) == 4:
            quats.append(("q0 (relative attitude)", j.q0))
        for label, q in quats:
            if len(q) == 4 and all(math.isfinite(v) for v in q):
                norm = math.sqrt(sum(v * v for v in q))
                if abs(norm - 1.0) > QUAT_NORM_TOL:
                    add(f"{where}.{label}: quaternion norm is {norm:.12g}, not 1 — "
                        "normalize it (scalar first: w, x, y, z)")
        if j.kind == "free":
            if j.parent != WORLD:
                add(f"{where}.parent: a free joint connects a body to {WORLD!r}, got {j.parent!r}")
            frames = (j.parent_point, j.child_point, j.parent_quat, j.child_quat)
            if frames != ((0.0,) * 3, (0.0,) * 3, (1.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)):
                add(f"{where}: a free joint's q0 is the COM pose itself — leave the joint frames at identity")
        if j.kind in AXIS_KINDS:
            what = "rotation axis" if j.kind == "revolute" else "sliding direction"
            if j.axis is None or len(j.axis) != 3:
                add(f"{where}.axis: a {j.kind} joint needs a 3-vector axis (its {what}, in the joint frame)")
            elif not all(math.isfinite(v) for v in j.axis):
                add(f"{where}.axis: contains NaN or inf")
            elif math.sqrt(sum(v * v for v in j.axis)) == 0.0:
                add(f"{where}.axis: zero length — give the {what}")
        elif j.axis is not None:
            add(f"{where}.axis: only {' and '.join(AXIS_KINDS)} joints take an axis")
    for b in sorted(names - set(parents)):
        add(f"bodies[{b!r}]: has no joint — give it one (a free body: Joint('free', 'world', {b!r}, ...))")
    # Cycles: follow parents up from every body; a path that never reaches the
    # world loops (only reachable when the parent names are all known).
    for start in sorted(parents):
        seen, node = set(), start
        while node in parents and node not in seen:
            seen.add(node)
            node = parents[node]
        if node in seen:
            add(f"joints: cycle through {sorted(seen)!r} — joints must form a tree rooted at {WORLD!r}")
            break
    return problems


def _closure_problems(scene):
    problems = []
    add = problems.append
    for i, (lp, r) in enumerate(zip(scene.loops, closure.initial_rows(scene))):
        where = f"loops[{i}] ({lp.kind} {lp.body_a!r} -> {lp.body_b!r})"
        for level, res, unit in (("position", r.phi, "m or the sine of a tilt"),
                                 ("velocity", r.velocity, "m/s or rad/s")):
            worst = float(np.max(np.abs(res))) if np.all(np.isfinite(res)) else float("nan")
            if not worst <= LOOP_CLOSURE_TOL:
                add(f"{where}: the initial state violates the closure at {level} level by {worst:.3g} "
                    f"({unit}; row residuals {np.round(res, 12).tolist()}), above LOOP_CLOSURE_TOL = "
                    f"{LOOP_CLOSURE_TOL:g} — choose the tree joints' {'q0' if level == 'position' else 'v0'} "
                    "so that the loop closes")
    return problems

def _spring_length_problems(scene):
    states = {**spatial.initial_body_states(scene), WORLD: closure.world_state()}
    problems = []
    for i, sp in enumerate(scene.springs):
        length = springs.state(sp, states[sp.body_a], states[sp.body_b]).length
        if not length > springs.MIN_LENGTH:
            problems.append(f"{_spring_where(i, sp)}: its points are {length:.3g} m apart at the initial state, "
                            f"below MIN_LENGTH = {springs.MIN_LENGTH:g} m (the force's direction, along the line "
                            "between them, is undefined) — move point_a or point_b, or the bodies")
    return problems


def _spring_where(i, sp):
    return f"springs[{i}] ({sp.name!r}: {sp.body_a!r} -> {sp.body_b!r})"


def _end_problems(where, element, names):
    """The problems naming ``element``'s two ends (``body_a``, ``body_b``: bodies of the scene or the world)."""
    return [f"{where}.{field_name}: no body named {b!r}{_did_you_mean(b, names | {WORLD})}"
            for field_name in ("body_a", "body_b") for b in [getattr(element, field_name)]
            if b != WORLD and b not in names]


def _numbers_problems(where, field_name, v, n, note=""):
    """The problem with ``v``, which must hold ``n`` finite numbers (``note``: what they are), as a list."""
    if len(v) != n:
        return [f"{where}.{field_name}: needs {n} numbers{note}, got {len(v)}"]
    if not _finite(v):
        return [f"{where}.{field_name}: contains NaN or inf"]
    return []


def _spring_problems(i, sp, names):
    where = _spring_where(i, sp)
    problems = []
    add = problems.append
    problems += _end_problems(where, sp, names)
    if sp.body_a == sp.body_b:
        add(f"{where}: joins a body to itself — a spring joins two different bodies (or a body and {WORLD!r})")
    for field_name in ("point_a", "point_b"):
        problems += _numbers_problems(where, field_name, getattr(sp, field_name), 3, " (m, in the body's frame)")
    for field_name, unit in (("stiffness", "N/m"), ("damping", "N s/m"), ("rest_length", "m")):
        v = getattr(sp, field_name)
        if not (math.isfinite(v) and v >= 0.0):
            add(f"{where}.{field_name}: must be finite and >= 0 ({unit}), got {v!r}")
    if sp.stiffness == 0.0 and sp.damping == 0.0:
        add(f"{where}: stiffness and damping are both zero, so it exerts no force — give one of them, or drop the spring")
    return problems


def _loop_problems(i, lp, names):
    where = f"loops[{i}] ({lp.kind} {lp.body_a!r} -> {lp.body_b!r})"
    problems = []
    add = problems.append
    if lp.kind not in LOOP_KINDS:
        add(f"{where}.kind: unknown {lp.kind!r} — use one of {list(LOOP_KINDS)}")
    problems += _end_problems(where, lp, names)
    if lp.body_a == lp.body_b:
        add(f"{where}: closes a body on itself — a loop joins two different bodies (or a body and {WORLD!r})")
    for field_name, n in (("point_a", 3), ("point_b", 3), ("quat_a", 4), ("quat_b", 4)):
        v = getattr(lp, field_name)
        shape = _numbers_problems(where, field_name, v, n)
        problems += shape
        if not shape and n == 4 and abs(math.sqrt(sum(x * x for x in v)) - 1.0) > QUAT_NORM_TOL:
            add(f"{where}.{field_name}: quaternion norm is {math.sqrt(sum(x * x for x in v)):.12g}, not 1 — "
                "normalize it (scalar first: w, x, y, z)")
    if lp.kind == "revolute":
        if lp.axis is None or len(lp.axis) != 3:
            add(f"{where}.axis: a revolute loop needs a 3-vector axis (in the joint frames)")
        elif not _finite(lp.axis) or math.sqrt(sum(v * v for v in lp.axis)) == 0.0:
            add(f"{where}.axis: must be finite and non-zero — give the rotation axis direction")
    elif lp.axis is not None:
        add(f"{where}.axis: only revolute loops take an axis")
    if lp.kind == "distance":
        if lp.length is None or not (math.isfinite(lp.length) and lp.length > 0.0):
            add(f"{where}.length: a distance loop needs a positive finite length (m), got {lp.length!r} — "
                "for coincident points use a ball loop")
    elif lp.length is not None:
        add(f"{where}.length: only distance loops take a length")
    return problems


def _finite(x):
    return all(math.isfinite(v) for v in np.ravel(x))


def _body_problems(b, is_free):
    where = f"bodies[{b.name!r}]"
    problems = []
    add = problems.append
    if not (math.isfinite(b.mass) and b.mass > 0.0):
        add(f"{where}.mass: must be positive and finite, got {b.mass!r} — give the mass in kg")
    I = np.asarray(b.inertia, dtype=float)
    if I.shape != (3, 3):
        add(f"{where}.inertia: must be 3x3 (kg m^2 about the COM, body frame), got shape {I.shape}")
        return problems
    if not _finite(I):
        add(f"{where}.inertia: contains NaN or inf")
        return problems
    scale = max(np.abs(I).max(), np.finfo(float).tiny)
    if np.abs(I - I.T).max() > INERTIA_REL_TOL * scale:
        add(f"{where}.inertia: not symmetric (max |I - I^T| = {np.abs(I - I.T).max():.3g}) — "
            "an inertia tensor is symmetric")
        return problems
    moments = np.linalg.eigvalsh(I)
    if moments[0] < 0.0 or moments[-1] <= 0.0:
        add(f"{where}.inertia: not positive definite (principal moments {moments.tolist()}) — "
            "principal moments must be positive")
    elif moments[0] <= SINGULAR_INERTIA_RATIO * moments[-1]:
        if is_free:
            add(f"{where}.inertia: singular (principal moments {moments.tolist()}): all mass lies on "
                "one line — a rotator (Landau & Lifshitz, Mechanics, section 32) — so the spin about that line is "
                "undetermined; a free body needs three positive principal moments (give the body a "
                "thickness)")
        else:
            add(f"{where}.inertia: not positive definite (principal moments {moments.tolist()}) — "
                "give the body a finite thickness")
    elif moments[0] + moments[1] < moments[2] * (1.0 - INERTIA_REL_TOL):
        add(f"{where}.inertia: principal moments {moments.tolist()} violate the triangle inequality "
            "I1 + I2 >= I3 — no mass distribution has them")
    for k, (m, u) in enumerate(b.particles):
        if not (math.isfinite(m) and m > 0.0) or len(u) != 3 or not _finite(u):
            add(f"{where}.particles[{k}]: needs a positive finite mass and 3 finite coordinates")
    return problems


def _load_problems(i, ld, names):
    where = f"loads[{i}] ({ld.kind} on {ld.body!r})"
    problems = []
    add = problems.append
    if ld.body not in names:
        add(f"{where}.body: no body named {ld.body!r}{_did_you_mean(ld.body, names)}")
    if ld.kind not in LOAD_KINDS:
        add(f"{where}.kind: unknown {ld.kind!r} — use one of {list(LOAD_KINDS)}")
    if ld.frame not in LOAD_FRAMES:
        add(f"{where}.frame: unknown {ld.frame!r} — use 'body' (a follower load) or 'world'")
    for field_name in ("vector", "point"):
        problems += _numbers_problems(where, field_name, getattr(ld, field_name), 3)
    if ld.kind == "torque" and any(ld.point):
        add(f"{where}.point: a torque has no point of application — leave point at (0, 0, 0)")
    return problems


def _did_you_mean(name, candidates):
    return suggest(name, candidates)
