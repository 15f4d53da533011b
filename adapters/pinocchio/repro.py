"""Pinocchio's part of a standalone reproduction (``dalembert repro``): the model as ``pin`` API calls,
the initial state, and the adapter's integrator written out in numpy around ``pin.aba`` (its adaptive ones
around scipy's solvers).

What it writes is ``Adapter.repro``'s contract (``dalembert.adapters.base``). The model is rebuilt
by the calls ``PinocchioModel`` makes, with the arguments it passed (joint placements read back from
the built model, where ``addJoint`` stores them as given; each body's ``pin.Inertia`` from its mass,
its frame in the joint's and its inertia, as the adapter computes them), so ``aba`` sees the same
numbers. The integrators are ``integrators.fixed_step``'s, the readable specification of the compiled
loop (``stepper.cpp``) that a run takes by default: the same operations in the same order. The one place
the two loops' arithmetic differs is ``dexp^-1`` with free or ball joints, a solve of ``dIntegrate``: numpy's
(LAPACK) in the Python loop, Eigen's ``partialPivLu`` in the compiled one; the script writes the one of
the loop the adapter runs here (``prepare``: the compiled loop where it is built and ``loop=native``),
Eigen's written out in numpy operation for operation (measured: the free tops' rk4 runs on the compiled
loop, 4e-9 relative off with numpy's solve, reproduce bit for bit).

The adaptive integrators are ``integrators.adaptive`` written out: scipy's ``RK45`` or ``DOP853`` over the horizon
in local coordinates, its chart re-centred after every step (such a script needs scipy too). Follower loads
are the constant per-joint forces ``aba`` takes (``PinocchioModel.const_f``). Not covered, with the reason in
the error: world-fixed loads and spring-dampers (external forces rebuilt from the pose at every evaluation) and
constraints (loop closures, welds as constraints: ``pin.constraintDynamics`` with the adapter's proximal
settings and Baumgarte gains).
"""

from __future__ import annotations

import numpy as np

from dalembert.adapters.pinocchio.model import depth_first_order

__all__ = ["repro"]

# The joint models ``PinocchioModel`` builds, and whether they take the scene's axis.
_JOINT_MODELS = {"JointModelFreeFlyer": False, "JointModelSpherical": False, "JointModelRevoluteUnaligned": True,
                 "JointModelPrismaticUnaligned": True}

_STEPS = {
    "euler": '''def step(q, v, h):  # semi-implicit Euler on the group
    v = v + h * acc(q, v)
    return pin.integrate(model, q, h * v), v
''',
    "rk4": '''def step(q, v, h):  # Runge-Kutta-Munthe-Kaas, classical tableau: stage tangents k_i, all from q
    hh = 0.5 * h
    a1 = acc(q, v)
    v2 = v + hh * a1
    th2 = hh * v
    k2 = dexpinv(q, th2, v2)
    a2 = acc(pin.integrate(model, q, th2), v2)
    v3 = v + hh * a2
    th3 = hh * k2
    k3 = dexpinv(q, th3, v3)
    a3 = acc(pin.integrate(model, q, th3), v3)
    v4 = v + h * a3
    th4 = h * k3
    k4 = dexpinv(q, th4, v4)
    a4 = acc(pin.integrate(model, q, th4), v4)
    h6 = h / 6.0
    return (pin.integrate(model, q, h6 * (v + 2.0 * (k2 + k3) + k4)),
            v + h6 * (a1 + 2.0 * (a2 + a3) + a4))
''',
    "rk4-naive": '''def step(q, v, h):  # RK4 with stagewise integrate, no dexp^-1 correction
    hh = 0.5 * h
    a1 = acc(q, v)
    v2 = v + hh * a1
    a2 = acc(pin.integrate(model, q, hh * v), v2)
    v3 = v + hh * a2
    a3 = acc(pin.integrate(model, q, hh * v2), v3)
    v4 = v + h * a3
    a4 = acc(pin.integrate(model, q, h * v3), v4)
    h6 = h / 6.0
    return (pin.integrate(model, q, h6 * (v + 2.0 * (v2 + v3) + v4)),
            v + h6 * (a1 + 2.0 * (a2 + a3) + a4))
''',
}

# The fixed-step loop (``dalembert.stepping.march``): ``step`` from sample to sample, stopping at a non-finite state.
_FIXED = '''def simulate():
    """The run: ``step`` from sample to sample; ``{name: ndarray (n, k)}`` of the quantity at every sample."""
    Q = np.full((len(TIMES), model.nq), np.nan)
    V = np.full((len(TIMES), model.nv), np.nan)
    q, v = Q0.copy(), V0.copy()
    Q[0], V[0] = q, v
    for k, n in enumerate(STEPS):
        h = (TIMES[k + 1] - TIMES[k]) / n
        for _ in range(n):
            q, v = step(q, v, h)
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            break
        Q[k + 1], V[k + 1] = q, v
'''
# The adaptive loop (``integrators.adaptive``): one scipy solver over the horizon, sampled by its dense output, its
# chart re-centred on each step's end (same state, same derivative).
_ADAPTIVE = '''def simulate():
    """The run: one METHOD solver over the horizon; ``{name: ndarray (n, k)}`` of the quantity at every sample."""
    nv = model.nv
    Q = np.full((len(TIMES), model.nq), np.nan)
    V = np.full((len(TIMES), nv), np.nan)
    Q[0], V[0] = Q0, V0
    centre = [np.array(Q0, dtype=float)]  # the chart's centre q_c: q = integrate(q_c, delta)

    def rhs(t, y):
        delta, vel = y[:nv], y[nv:]
        return np.concatenate([dexpinv(centre[0], delta, vel), acc(pin.integrate(model, centre[0], delta), vel)])

    solver = METHOD(rhs, float(TIMES[0]), np.concatenate([np.zeros(nv), V0]), float(TIMES[-1]), rtol=RTOL, atol=ATOL)
    k = 1  # the next sample to read
    while k < len(TIMES) and solver.status == "running":
        if solver.step() is not None or not np.all(np.isfinite(solver.y)):
            break
        passed = k + int(np.searchsorted(TIMES[k:], solver.t, side="right"))  # samples up to the step's end
        dense = solver.dense_output() if TIMES[k] < solver.t else None
        for j in range(k, passed):
            y = solver.y if TIMES[j] == solver.t else dense(TIMES[j])
            Q[j], V[j] = pin.integrate(model, centre[0], y[:nv]), y[nv:]
        k = passed
        # re-centre the chart on the step's end: scipy's Runge-Kutta solvers step from their y and f
        centre[0] = pin.integrate(model, centre[0], solver.y[:nv])
        v = solver.y[nv:].copy()
        solver.y = np.concatenate([np.zeros(nv), v])
        solver.f = np.concatenate([v, solver.f[nv:]])
'''
# The adapter's adaptive integrators: scipy's classes.
ADAPTIVE = {"rk45": "RK45", "dop853": "DOP853"}

# dexp^-1 as each loop computes it (``PinocchioModel.dexpinv_function``, ``stepper.cpp`` ``Stepper::dexpinv``).
_DEXPINV = {
    "identity": '''def dexpinv(q, theta, vel):  # revolute and prismatic joints only: a vector space, dexp^-1 is the identity
    return vel''',
    "numpy": '''def dexpinv(q, theta, vel):
    """The tangent of q (+) theta moving with velocity vel: dIntegrate(q, theta, ARG1)^-1 vel, solved by numpy
    (LAPACK), as the adapter's Python loop solves it."""
    return np.linalg.solve(pin.dIntegrate(model, q, theta, pin.ArgumentPosition.ARG1), vel)''',
    "numpy-blocks": '''def dexpinv(q, theta, vel):
    """The tangent of q (+) theta moving with velocity vel: dIntegrate(q, theta, ARG1)^-1 vel. FreeFlyers only:
    dIntegrate is block diagonal, solved 6 x 6 block by block by numpy (LAPACK), as the adapter's Python loop does."""
    n = model.nv // 6
    diag = np.arange(n)
    J = pin.dIntegrate(model, q, theta, pin.ArgumentPosition.ARG1).reshape(n, 6, n, 6)[diag, :, diag, :]
    return np.linalg.solve(J, vel.reshape(n, 6, 1)).ravel()''',
    "eigen": '''def dexpinv(q, theta, vel):
    """The tangent of q (+) theta moving with velocity vel: dIntegrate(q, theta, ARG1)^-1 vel, solved as the
    adapter's compiled loop solves it, J.partialPivLu().solve(vel) in Eigen 3.4, operation for operation:
    the unblocked LU of a matrix of at most 16 rows (the first largest |pivot| of each column, the column below
    it divided by it, a rank-1 update of the rest), then the unit-lower and the upper triangular solves,
    column by column (a zero entry skipped)."""
    lu = np.array(pin.dIntegrate(model, q, theta, pin.ArgumentPosition.ARG1), dtype=float)
    n = len(lu)
    x = np.array(vel, dtype=float)
    for k in range(n):
        p = k + int(np.argmax(np.abs(lu[k:, k])))
        if lu[p, k] != 0.0:
            if p != k:
                lu[[k, p]] = lu[[p, k]]
                x[[k, p]] = x[[p, k]]  # the same transposition of the right-hand side: x = P vel
            lu[k + 1:, k] /= lu[k, k]
        lu[k + 1:, k + 1:] -= np.outer(lu[k + 1:, k], lu[k, k + 1:])
    for i in range(n):  # L x = P vel, L unit lower
        if x[i] != 0.0:
            x[i + 1:] -= x[i] * lu[i + 1:, i]
    for i in range(n - 1, -1, -1):  # U x = ...
        if x[i] != 0.0:
            x[i] /= lu[i, i]
            x[:i] -= x[i] * lu[:i, i]
    return x''',
}
# Eigen's PartialPivLU blocks its factorization above this size (Eigen/src/LU/PartialPivLU.h, UnBlockedBound).
EIGEN_UNBLOCKED_ROWS = 16


def _model_calls(pm, scene):
    """The ``pin`` calls that build ``pm.model``, as source lines (``model`` is the name they build)."""
    model = pm.model
    lines = ["model = pin.Model()",
             f"model.gravity = pin.Motion(np.array({model.gravity.linear.tolist()!r}), np.zeros(3))  # m/s^2, world"]
    joints = {}
    for jid in range(1, model.njoints):
        kind, name = model.joints[jid].shortname(), model.names[jid]
        if kind not in _JOINT_MODELS:
            raise ValueError(f"joints.{name}: Pinocchio joint {kind} is not one the adapter builds — no repro for it")
        if _JOINT_MODELS[kind]:  # the axis the adapter passed: the scene's, made unit
            axis = np.asarray(scene.joint(name).axis, dtype=float) / np.linalg.norm(scene.joint(name).axis)
            jm = f"pin.{kind}(np.array({axis.tolist()!r}))"
        else:
            jm = f"pin.{kind}()"
        X = model.jointPlacements[jid]
        joints[jid] = f"j{jid}"
        lines.append(f"j{jid} = model.addJoint({joints.get(model.parents[jid], 0)}, {jm}, "
                     f"pin.SE3(np.array({X.rotation.tolist()!r}), np.array({X.translation.tolist()!r})), {name!r})")
    for body in depth_first_order(scene):  # the adapter's order: a joint's bodies are summed in it
        X_EB = pm.X_EB[body.name]
        R, p = X_EB.rotation, X_EB.translation
        inertia = R @ body.inertia_matrix @ R.T  # kg m^2 about the COM, the joint frame's axes
        lines.append(f"model.appendBodyToJoint({joints.get(pm.carrier[body.name], 0)}, pin.Inertia({body.mass!r}, "
                     f"np.array({p.tolist()!r}), np.array({inertia.tolist()!r})), pin.SE3.Identity())  # {body.name}")
        lines.append(f"model.addFrame(pin.Frame({body.name!r}, {joints.get(pm.carrier[body.name], 0)}, "
                     f"pin.SE3(np.array({R.tolist()!r}), np.array({p.tolist()!r})), pin.FrameType.OP_FRAME))  "
                     "# its frame at B")
    return "\n".join(lines)


def _loads(pm):
    """The follower loads as source: ``FEXT``, the constant spatial force on each joint (``pm.const_f``), or ""."""
    if not pm.const_f:
        return ""
    rows = "".join(f"    pin.Force(np.array({np.asarray(pm.const_f[jid].vector).tolist()!r})),  # on joint {jid} "
                   f"({pm.model.names[jid]})\n" if jid in pm.const_f else f"    pin.Force.Zero(),  # joint {jid}\n"
                   for jid in range(pm.model.njoints))
    return ("# The follower loads: per joint, the spatial force (linear N, angular N m) in its LOCAL frame about its "
            "origin,\n# constant as the body turns.\nFEXT = pin.StdVec_Force()\nfor force in [\n" + rows
            + "]:\n    FEXT.append(force)\n")


def repro(adapter, scene, times, settings, quantity):
    """The Pinocchio part of a reproduction of a run of ``scene`` sampled at ``times`` with ``settings``: Python
    source defining ``simulate()`` (``Adapter.repro``); ValueError "where: what — fix" where it does not apply."""
    p = adapter.prepare(scene, times, settings)
    pm = p.pm
    attitudes = ""
    if pm.constrained:
        raise ValueError("scene: constraints (loop closures, or welds=constraint) run pin.constraintDynamics with the "
                         "adapter's proximal settings — no repro for them; reproduce a run of a tree")
    if pm.world_loads or pm.springs:
        raise ValueError("scene: world-fixed loads and spring-dampers are external forces rebuilt from the pose at "
                         "every evaluation — no repro for them yet; reproduce a run under gravity and follower loads")
    if quantity == "joint":
        names = [j.child for j in scene.joints if j.kind in ("revolute", "prismatic")]
        read = "{name: Q[:, model.joints[model.getJointId(name)].idx_q][:, None] for name in NAMES}"
        what = "each revolute or prismatic joint's coordinate (rad or m), by joint name"
    elif quantity == "orientation":
        names = [b.name for b in scene.bodies]
        free = [j.child for j in scene.joints if j.kind == "free"]
        read = "attitudes(Q, V)"
        what = ("each body's attitude: a FreeFlyer's quaternion q_WB (w, x, y, z; world; as integrated, not "
                "normalized), any other's R_WB, the rotation of its frame at B after forward kinematics")
        attitudes = f"""

FREE = {free!r}  # the bodies on a FreeFlyer, whose attitude is its quaternion as integrated


def attitudes(Q, V):
    \"\"\"Each body's attitude at the sampled states: R_WB (n, 3, 3) of its frame at B, or a FreeFlyer's quaternion
    (n, 4), (x, y, z, w) turned to (w, x, y, z).\"\"\"
    out = {{name: np.full((len(Q), 3, 3), np.nan) for name in NAMES}}
    for k in np.flatnonzero(np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1)):
        pin.forwardKinematics(model, data, Q[k], V[k])
        pin.updateFramePlacements(model, data)
        for name in NAMES:
            out[name][k] = data.oMf[model.getFrameId(name)].rotation
    for name in FREE:
        a = model.joints[model.getJointId(name)].idx_q
        out[name] = np.concatenate([Q[:, a + 6:a + 7], Q[:, a + 3:a + 6]], axis=1)
    return out"""
    else:
        raise ValueError(f"quantity: no Pinocchio repro of {quantity!r} — it reproduces 'joint' and 'orientation'")
    if settings.integrator in ADAPTIVE:
        rtol, atol = settings.rtol or 1e-8, settings.atol or 1e-8  # as ``integrators.adaptive`` passes them
        stepping = (f"# {settings.integrator}: scipy's {ADAPTIVE[settings.integrator]} in local coordinates about a chart "
                    f"centre moved after every step\n# (the adapter's integrators.adaptive).\nRTOL, ATOL = {rtol!r}, "
                    f"{atol!r}")
        loop = _ADAPTIVE.replace("METHOD", ADAPTIVE[settings.integrator])
        imports = f"import pinocchio as pin\nfrom scipy.integrate import {ADAPTIVE[settings.integrator]}"
    else:
        steps = np.asarray(p.steps, dtype=int)
        steps_src = (f"np.full({len(steps)}, {int(steps[0])})" if np.all(steps == steps[0])
                     else f"np.array({steps.tolist()!r})")
        loop, imports = None, "import pinocchio as pin"
    kind = pm.dexpinv_kind()
    native = p.native is not None and loop is None  # the compiled loop runs (``PinocchioAdapter._fixed_loop``)
    if kind == 0:
        dexpinv = "identity"
    elif not native:
        dexpinv = "numpy-blocks" if kind == 3 else "numpy"
    elif pm.model.nv <= EIGEN_UNBLOCKED_ROWS:
        dexpinv = "eigen"
    else:
        raise ValueError(f"scene: {pm.model.nv} velocities — the compiled loop's dexp^-1 is Eigen's blocked LU, which "
                         f"the repro writes out for at most {EIGEN_UNBLOCKED_ROWS}; reproduce a run with "
                         "--option loop=python")
    if loop is None:
        which = "the compiled loop (stepper.cpp)" if native else "the Python loop"
        stepping = (f"# {settings.integrator}, the arithmetic of the adapter's {which}: steps between consecutive "
                    f"samples, each of\n# (TIMES[k + 1] - TIMES[k]) / STEPS[k] s.\nSTEPS = {steps_src}")
        loop = _STEPS[settings.integrator] + "\n\n\n" + _FIXED
    return f'''{imports}

# The model, by the calls the adapter makes (joint placements in the parent joint's frame, m; each body's
# mass (kg), centre of mass in its joint's frame (m) and inertia about it (kg m^2), and its scene frame B there).
{_model_calls(pm, scene)}
data = model.createData()
TAU = np.zeros(model.nv)  # no actuation: gravity{" and the follower loads below" if pm.const_f else " alone"}
{_loads(pm)}# The initial state, Pinocchio's coordinates (a FreeFlyer: position, quaternion x, y, z, w; velocity in its
# joint's LOCAL frame).
Q0 = np.array({p.q0.tolist()!r})
V0 = np.array({p.v0.tolist()!r})
{stepping}
# Read for each of these: {what}.
NAMES = {names!r}


def acc(q, v):
    return pin.aba(model, data, q, v, TAU{", FEXT" if pm.const_f else ""})


{_DEXPINV[dexpinv]}


{loop}    return {read}{attitudes}


ENGINE_VERSION = pin.__version__
'''
