"""Invariants computed by the harness from scene + trajectory, never taken from an engine.

Series functions return one value per sample; ``drift(name, ...)`` turns a
conserved quantity into one number: its largest change from the initial value,
relative to a scale stated per quantity (``CONSERVED``). A case may also declare
conserved quantities of its own (``dalembert.case.Invariant``: a named series
with its unit and scale); ``summary`` computes their drifts beside the built-in ones.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert import spatial, springs
from dalembert.scene import WORLD

__all__ = [
    "CONSERVED",
    "Conserved",
    "kinetic_energy",
    "potential_energy",
    "spring_lengths",
    "spring_energy",
    "dissipated_energy",
    "load_power",
    "load_work",
    "total_energy",
    "energy_balance",
    "linear_momentum",
    "angular_momentum",
    "angular_momentum_com",
    "angular_momentum_about",
    "orthonormality_error",
    "quaternion_norm_error",
    "joint_residual",
    "loop_residual",
    "pairwise_distance_change",
    "drift",
    "drift_series",
    "drift_rate",
    "Summary",
    "summary",
]


def _R(traj, name):
    """Unit rotation ``R_WB`` (n, 3, 3) for physics (the attitude's direction, not its drift)."""
    return spatial.quat_to_matrix(spatial.quat_normalize(traj.bodies[name].quaternion))


def kinetic_energy(scene, traj):
    """``sum 1/2 m v.v + 1/2 w_B . I w_B`` (J), shape (n,)."""
    total = np.zeros(len(traj.t))
    for body in scene.bodies:
        b = traj.bodies[body.name]
        w_B = b.angular_velocity_body
        total += 0.5 * body.mass * np.einsum("ni,ni->n", b.velocity, b.velocity)
        total += 0.5 * np.einsum("ni,ij,nj->n", w_B, body.inertia_matrix, w_B)
    return total


def potential_energy(scene, traj):
    """Gravitational potential ``-sum m g . p`` (J, zero at the world origin) plus the energy stored in
    the spring-dampers (``spring_energy``), shape (n,)."""
    g = np.array(scene.gravity)
    gravity = -sum(body.mass * traj.bodies[body.name].position @ g for body in scene.bodies)
    return gravity + spring_energy(scene, traj) if scene.springs else gravity


def _point_track(scene, traj, body, point):
    """World position (n, 3) and velocity (n, 3) of a point fixed in ``body`` (``point`` in its frame, m)."""
    point = np.asarray(point, dtype=float)
    if body == WORLD:
        n = len(traj.t)
        return np.broadcast_to(point, (n, 3)), np.zeros((n, 3))
    b = traj.bodies[body]
    lever = np.einsum("nij,j->ni", _R(traj, body), point)
    return b.position + lever, b.velocity + np.cross(b.angular_velocity, lever)


def spring_lengths(scene, traj):
    """Each spring's length ``l`` (m) and its rate ``l'`` (m/s) along the trajectory: dict spring name ->
    ``(l, l')``, each ndarray (n,) (``dalembert.springs``), from the bodies' states in the trajectory."""
    out = {}
    for sp in scene.springs:
        x_a, v_a = _point_track(scene, traj, sp.body_a, sp.point_a)
        x_b, v_b = _point_track(scene, traj, sp.body_b, sp.point_b)
        d = x_b - x_a
        length = np.linalg.norm(d, axis=1)
        out[sp.name] = (length, np.einsum("ni,ni->n", d, v_b - v_a) / length)
    return out


def spring_energy(scene, traj):
    """Energy stored in the springs, ``sum 1/2 k (l - l0)^2`` (J), shape (n,)."""
    lengths = spring_lengths(scene, traj)
    return sum((springs.potential_energy(sp, lengths[sp.name][0]) for sp in scene.springs), np.zeros(len(traj.t)))


def dissipated_energy(scene, traj):
    """Energy the dampers took out of the motion since ``t[0]``, ``int sum c l'^2 dt`` (J, >= 0), shape (n,).

    Cumulative Simpson quadrature of the sampled power, as ``load_work``: error O(h^4) in the sample
    interval h.
    """
    if not any(sp.damping > 0.0 for sp in scene.springs):
        return np.zeros(len(traj.t))
    lengths = spring_lengths(scene, traj)
    power = sum(springs.dissipated_power(sp, lengths[sp.name][1]) for sp in scene.springs)
    from scipy.integrate import cumulative_simpson  # here, not at the top: scipy.integrate is most of `import dalembert`

    return cumulative_simpson(power, x=traj.t, initial=0.0)


def load_power(scene, traj):
    """Power of the applied loads (W), shape (n,): ``F.v_point + tau.w``, world axes."""
    power = np.zeros(len(traj.t))
    for ld in scene.loads:
        b = traj.bodies[ld.body]
        R = _R(traj, ld.body)
        vec_W = spatial.load_to_world(ld, R)
        if ld.kind == "force":
            r_W = np.einsum("nij,j->ni", R, np.array(ld.point))
            v_point = b.velocity + np.cross(b.angular_velocity, r_W)
            power += np.einsum("ni,ni->n", vec_W, v_point)
        else:
            power += np.einsum("ni,ni->n", vec_W, b.angular_velocity)
    return power


def load_work(scene, traj):
    """Work done by the applied loads since ``t[0]`` (J), shape (n,).

    Cumulative Simpson quadrature of the sampled power: error O(h^4) in the
    sample interval h, exact for power polynomial of degree <= 2 in t.
    """
    if not scene.loads:
        return np.zeros(len(traj.t))
    from scipy.integrate import cumulative_simpson  # lazily, as in dissipated_energy

    return cumulative_simpson(load_power(scene, traj), x=traj.t, initial=0.0)


def total_energy(scene, traj):
    """Kinetic + potential energy (J; gravity's and the springs'), shape (n,)."""
    return kinetic_energy(scene, traj) + potential_energy(scene, traj)


def energy_balance(scene, traj):
    """Kinetic + potential energy minus the work of the loads plus the energy the dampers dissipated
    (J), shape (n,): constant."""
    return total_energy(scene, traj) - load_work(scene, traj) + dissipated_energy(scene, traj)


def linear_momentum(scene, traj):
    """``sum m v`` (kg m/s), world, shape (n, 3)."""
    return sum(body.mass * traj.bodies[body.name].velocity for body in scene.bodies)


def angular_momentum_com(scene, traj):
    """Angular momentum about the system's centre of mass (kg m^2/s), world, shape (n, 3):
    ``sum m (x - x_c) x (v - v_c) + R I R^T w``. Conserved under uniform gravity; for one body,
    its spin ``R I R^T w``."""
    masses = np.array([b.mass for b in scene.bodies])
    x = np.stack([traj.bodies[b.name].position for b in scene.bodies])  # (bodies, n, 3)
    v = np.stack([traj.bodies[b.name].velocity for b in scene.bodies])
    x_c = np.einsum("b,bni->ni", masses, x) / masses.sum()
    v_c = np.einsum("b,bni->ni", masses, v) / masses.sum()
    total = np.einsum("b,bni->ni", masses, np.cross(x - x_c, v - v_c)) if len(masses) > 1 else np.zeros_like(x_c)
    return total + _spins(scene, traj)


def _spins(scene, traj):
    """``sum R I R^T w``: the bodies' angular momenta about their own COMs (kg m^2/s), world, (n, 3)."""
    total = np.zeros((len(traj.t), 3))
    for body in scene.bodies:
        R = _R(traj, body.name)
        I_W = R @ body.inertia_matrix @ np.swapaxes(R, 1, 2)
        total = total + np.einsum("nij,nj->ni", I_W, traj.bodies[body.name].angular_velocity)
    return total


def angular_momentum(scene, traj):
    """Angular momentum about the world origin (kg m^2/s), world, shape (n, 3)."""
    return angular_momentum_about(scene, traj, (0.0, 0.0, 0.0))


def angular_momentum_about(scene, traj, point_W):
    """Angular momentum about the fixed world point ``point_W`` (m, shape (3,)) (kg m^2/s), world axes,
    shape (n, 3): ``sum m (x - point) x v + R I R^T w`` (e.g. about a pivot, where gravity's moment is
    horizontal, so its vertical component is conserved)."""
    o = np.asarray(point_W, dtype=float)
    orbital = sum(body.mass * np.cross(traj.bodies[body.name].position - o, traj.bodies[body.name].velocity)
                  for body in scene.bodies)
    return orbital + _spins(scene, traj)  # (the orbital part about the COM is in ``orbital`` already)


def orthonormality_error(scene, traj):
    """``max_bodies |R R^T - I|`` (max-abs entry) of each body's attitude as stored, shape (n,).

    A quaternion of norm ``s`` gives ``|s^4 - 1|``; a rotation matrix its own drift.
    """
    err = np.zeros(len(traj.t))
    for body in scene.bodies:
        R = traj.bodies[body.name].rotation_matrix
        err = np.maximum(err, np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max(axis=(1, 2)))
    return err


def quaternion_norm_error(scene, traj):
    """``max_bodies ||q| - 1|``, shape (n,)."""
    return np.max([np.abs(np.linalg.norm(traj.bodies[b.name].quaternion, axis=1) - 1.0) for b in scene.bodies],
                  axis=0)


def loop_residual(scene, traj, level="position"):
    """Largest violation of any loop closure (``Scene.loops``, rows in ``dalembert.closure``), shape (n,).

    ``level="position"``: the rows ``phi`` (m for points, the sine of the tilt for axes);
    ``"velocity"``: their rates (m/s, rad/s), from the bodies' states in the trajectory (never from
    the engine). Zero for a scene without loops; NaN where a state is not finite.
    """
    from dalembert import closure

    if level not in ("position", "velocity"):
        raise ValueError(f"level: {level!r} — use 'position' or 'velocity'")
    states = {"world": closure.world_state()}
    for name in {n for loop in scene.loops for n in (loop.body_a, loop.body_b)} - {"world"}:
        b = traj.bodies[name]
        states[name] = dict(R=spatial.quat_to_matrix(spatial.quat_normalize(b.quaternion)), p=b.position,
                            v=b.velocity, w=b.angular_velocity)
    err = np.zeros(len(traj.t))
    for loop in scene.loops:
        phi, velocity = closure.residuals(loop, states[loop.body_a], states[loop.body_b])
        # NaN where a state is not finite (np.maximum keeps NaN; a plain max would drop it)
        err = np.maximum(err, np.max(np.abs(phi if level == "position" else velocity), axis=-1))
    return err


def joint_residual(scene, traj):
    """Largest violation of any joint (m for points, rad for axes), shape (n,).

    Per non-free joint: distance between the joint point as placed by the
    parent and by the child (for prismatic joints, its part normal to the
    sliding axis: the slide itself is the joint's coordinate); for revolute
    joints also the angle between the axis as carried by each side; for welds
    and prismatic joints the relative rotation angle.
    """
    n = len(traj.t)
    err = np.zeros(n)
    for j in scene.joints:
        if j.kind == "free":
            continue
        if j.parent == WORLD:
            p_P, R_P = np.zeros((n, 3)), np.broadcast_to(np.eye(3), (n, 3, 3))
        else:
            p_P, R_P = traj.bodies[j.parent].position, _R(traj, j.parent)
        p_C, R_C = traj.bodies[j.child].position, _R(traj, j.child)
        x_P = p_P + np.einsum("nij,j->ni", R_P, np.array(j.parent_point))
        x_C = p_C + np.einsum("nij,j->ni", R_C, np.array(j.child_point))
        R_WJp = R_P @ spatial.quat_to_matrix(j.parent_quat)
        R_WJc = R_C @ spatial.quat_to_matrix(j.child_quat)
        gap = x_C - x_P
        if j.kind == "prismatic":  # the slide along the parent's axis is free
            a_P = R_WJp @ (np.array(j.axis) / np.linalg.norm(j.axis))
            gap = gap - np.einsum("ni,ni->n", gap, a_P)[:, None] * a_P
        err = np.maximum(err, np.linalg.norm(gap, axis=1))
        if j.kind == "revolute":
            a = np.array(j.axis) / np.linalg.norm(j.axis)
            a_P, a_C = R_WJp @ a, R_WJc @ a
            err = np.maximum(err, np.arctan2(np.linalg.norm(np.cross(a_P, a_C), axis=1),
                                             np.einsum("ni,ni->n", a_P, a_C)))
        elif j.kind in ("weld", "prismatic"):
            err = np.maximum(err, spatial.rotation_angle(spatial.matrix_to_quat(R_WJp),
                                                         spatial.matrix_to_quat(R_WJc)))
    return err


def pairwise_distance_change(scene, traj):
    """Largest change of any distance between two particles of the scene (m), shape (n,).

    Particles of one body and of different bodies alike (a body of one particle
    at its COM is a particle held to others by joints). Uses each body's
    attitude as stored (a drifting quaternion norm or matrix stretches the
    body); zero for scenes with fewer than two particles.
    """
    # world positions as (3, k, n): one contiguous track per coordinate and particle, so a distance
    # is three subtractions and a sqrt on rows (3x faster than a norm over a trailing axis of 3,
    # same bits); a particle at its body's origin is the body's position (no rotation to apply)
    tracks, owner, local = [], [], []
    for b, body in enumerate(scene.bodies):
        if not body.particles:
            continue
        u = np.array([p for _, p in body.particles])
        states = traj.bodies[body.name]
        p_W = states.position.T[:, None, :]  # (3, 1, n)
        tracks.append(np.repeat(p_W, len(u), axis=1) if not u.any()
                      else p_W + np.einsum("nij,kj->ikn", states.rotation_matrix, u))
        owner += [b] * len(u)
        local.append(u)
    if len(owner) < 2:
        return np.zeros(len(traj.t))
    owner, local = np.array(owner), np.concatenate(local)
    x = np.concatenate(tracks, axis=1)  # (3, k, n)
    worst = np.zeros(len(traj.t))
    for a in range(len(owner) - 1):  # particle a against every later one (no (n, pairs, 3) temporaries)
        dx, dy, dz = (x[i, a] - x[i, a + 1:] for i in range(3))
        d = np.sqrt(dx * dx + dy * dy + dz * dz)  # (later, n)
        # nominal distances: within a body, from its definition (so a stretched attitude shows from
        # t = 0); across bodies (held by joints), as at the first sample
        same = owner[a] == owner[a + 1:]
        nominal = np.where(same[:, None], np.linalg.norm(local[a] - local[a + 1:], axis=1)[:, None], d[:, :1])
        worst = np.maximum(worst, np.abs(d - nominal).max(axis=0))
    return worst


@dataclass(frozen=True)
class Conserved:
    """A built-in conserved quantity, labelled as a case's declared ones are (``dalembert.case.Invariant``),
    so a reader takes its unit from here and never parses prose.

    Attributes
    ----------
    name : str — the key of its drift (``RunRecord.drifts``, column ``drift_<name>``)
    description : str — what is conserved, with its frame and reference point
    unit : str — unit of the quantity itself
    drift_unit : str — unit of its stored drift: "relative" (dimensionless), a unit where the drift is
        absolute, or "absolute when zero, else relative"
    scaled_by : str — what the drift is measured against (``_measured`` computes it)
    """

    name: str
    description: str
    unit: str
    drift_unit: str
    scaled_by: str


# name -> its label; ``_measured`` computes each series and scale.
CONSERVED = {c.name: c for c in (
    Conserved("energy", "total mechanical energy: kinetic + gravitational + stored in springs", "J", "relative",
              "max(|E(0)|, max kinetic energy)"),
    Conserved("energy_balance", "E - W(loads) + D(dampers): energy with the loads' work and the dampers' "
              "dissipation accounted", "J", "relative", "the max kinetic energy"),
    Conserved("linear_momentum", "total linear momentum, world axes", "kg m/s", "absolute when zero, else relative",
              "max |p|, or 1 kg m/s when it is zero"),
    Conserved("angular_momentum", "total angular momentum about the world origin, world axes", "kg m^2/s",
              "relative", "max |L|"),
    Conserved("angular_momentum_com", "the bodies' spin about their own centres of mass, summed, world axes",
              "kg m^2/s", "relative", "max |L|"),
    Conserved("pairwise_distance", "distances between the particles of rigidly joined bodies", "m", "m",
              "1 m (absolute)"),
)}


# The conserved vectors, by name (world axes, shape (n, 3)).
_VECTORS = {"linear_momentum": linear_momentum, "angular_momentum": angular_momentum,
            "angular_momentum_com": angular_momentum_com}


def _measured(name, scene, traj):
    """The series of the conserved quantity ``name`` on ``traj`` and the scale its drift is measured
    against (``CONSERVED``): energy-like (n,) J; momenta (n, 3); the pairwise distance change (n,) m,
    scale 1 (absolute). A drift, its rate and its growth are all taken from this one evaluation."""
    if name in ("energy", "energy_balance"):
        ke = kinetic_energy(scene, traj)
        x = ke + potential_energy(scene, traj)
        if name == "energy_balance":  # (energy_balance's terms, the kinetic energy computed once)
            x = x - load_work(scene, traj) + dissipated_energy(scene, traj)
        peak = float(np.max(ke))
        return x, (max(abs(x[0]), peak) if name == "energy" else peak)
    if name == "pairwise_distance":
        return pairwise_distance_change(scene, traj), 1.0
    if name in _VECTORS:
        x = _VECTORS[name](scene, traj)
        return x, float(np.max(np.linalg.norm(x, axis=1)))
    raise KeyError(f"unknown conserved quantity {name!r} — known: {sorted(CONSERVED)}")


def _change(name, x):
    """Unsigned change of a ``_measured`` series from its initial value, shape (n,)."""
    if name == "pairwise_distance":  # already a change
        return x
    return np.abs(x - x[0]) if x.ndim == 1 else np.linalg.norm(x - x[0], axis=1)


def _per_scale(change, scale):
    return change / (scale if scale > 0 else 1.0)


def _rate(t, x, scale):
    """Least-squares slope (1/s) through the origin of the signed scaled change of ``x`` (n,)."""
    y = _per_scale(x - x[0], scale)
    t = t - t[0]
    return float(np.sum(t * y) / np.sum(t * t)) if np.sum(t * t) > 0 else 0.0


def _growth(change, true_scale):
    return float(np.max(change)) / true_scale if true_scale > 0 else float("nan")


def drift_series(name, scene, traj):
    """Change of the conserved quantity ``name`` from its initial value at each sample, shape (n,),
    scaled as in ``CONSERVED`` (so ``max(drift_series) == drift``)."""
    x, scale = _measured(name, scene, traj)
    return _per_scale(_change(name, x), scale)


def drift_rate(name, scene, traj):
    """Least-squares slope (1/s) of the signed relative change of an energy-like quantity.

    Secular drift (most integrators) shows as a steady slope; bounded
    oscillation (symplectic and geometric integrators) as a slope near zero.
    Negative: energy lost (e.g. numerical damping).
    """
    return _rate(traj.t, *_measured(name, scene, traj))


# The conserved quantities ``growth`` measures blow-ups of (a pairwise distance has no true scale but zero).
GROWING = ("energy", "energy_balance", "linear_momentum", "angular_momentum", "angular_momentum_com")


def growth(name, scene, traj, truth):
    """The largest change of the conserved quantity ``name`` over ``traj``, in units of the scale
    its drift has on the true motion ``truth``; NaN where that scale is zero.

    A drift is scaled by the run's own largest value, so it stays below ~2 however far the run
    blows up; measured against the truth's scale, a blow-up shows (``dalembert.judge``), and a run
    that follows the truth has ``growth`` close to its drift.
    """
    x, _ = _measured(name, scene, traj)
    return _growth(_change(name, x), _measured(name, scene, truth)[1])


def drift(name, scene, traj):
    """Drift of the conserved quantity ``name`` (see ``CONSERVED``) over the whole trajectory."""
    return float(np.max(drift_series(name, scene, traj)))


@dataclass(frozen=True)
class Summary:
    """The invariant figures of one trajectory.

    Attributes
    ----------
    drifts : dict name -> float — ``drift`` of each conserved quantity, built-in or declared
    growths : dict name -> float — ``growth`` of each built-in one in ``GROWING`` against the truth
        (empty without a truth; NaN where the truth's scale is zero)
    drift_rates : dict name -> float — ``drift_rate`` (1/s) of the energy-like ones
    checks : dict name -> float — maxima of ``orthonormality``, ``quaternion_norm`` and, for
        jointed scenes, ``joint_residual`` (``dalembert.record.CHECKS``)
    """

    drifts: dict
    growths: dict
    drift_rates: dict
    checks: dict


def summary(scene, traj, conserved=(), declared=(), truth=None):
    """The ``Summary`` of ``traj``: drifts of the ``conserved`` quantities (names in ``CONSERVED``) and
    of the ``declared`` ones (``dalembert.case.Invariant``: each under its own name), and the checks."""
    measured = {name: _measured(name, scene, traj) for name in conserved}  # each series once
    changes = {name: _change(name, x) for name, (x, _) in measured.items()}
    drifts = {name: float(np.max(_per_scale(changes[name], scale))) for name, (_, scale) in measured.items()}
    declared_drifts = {inv.name: inv.drift(scene, traj) for inv in declared}
    drifts.update({name: d for name, d in declared_drifts.items() if d is not None})  # None: a metric not measured
    rates = {name: _rate(traj.t, x, scale) for name, (x, scale) in measured.items()
             if name in ("energy", "energy_balance")}
    checks = {"orthonormality": float(np.max(orthonormality_error(scene, traj))),
              "quaternion_norm": float(np.max(quaternion_norm_error(scene, traj)))}
    if any(j.kind != "free" for j in scene.joints):
        checks["joint_residual"] = float(np.max(joint_residual(scene, traj)))
    growths = {} if truth is None else {name: _growth(changes[name], _measured(name, scene, truth)[1])
                                        for name in conserved if name in GROWING}
    return Summary(drifts, growths, rates, checks)
