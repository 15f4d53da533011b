"""MuJoCo's states in body terms: poses, velocities, joint coordinates and reactions.

Once per run, after stepping (never timed): for every sample the state is set in a scratch
``MjData`` and ``mj_forward`` + ``mj_rnePostConstraint`` recompute the derived
quantities (right after ``mj_step`` they describe the previous state). Poses and
velocities of the scene's body frames come from the MuJoCo frames through
``dalembert.spatial``. The joint reaction on a child is ``cfrc_int``'s force
part minus the loads that the site actuators routed through joint space onto
the child's subtree (MuJoCo counts them as joint torques, not as external
forces). A spring's tendon force is not subtracted: MuJoCo counts a spatial
tendon's force in ``cfrc_ext`` (measured: a hinged body pulled by a tendon of
tension 10 N has ``cfrc_ext`` the 10 N and ``cfrc_int`` the joint's -10 N), so
``cfrc_int`` is the joint's reaction already. The contact force of each scene pair
(``contact.force_reader``, N, world, ON the pair's subject) is read in the same pass, as the
extras ``contact_force:<pair>``.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.contact import FORCE_PREFIX
from dalembert.adapters.mujoco.contact import force_reader
from dalembert.adapters.mujoco.mjcf import floating
from dalembert.adapters.mujoco.springs import spring_tendon_ids, spring_tension
from dalembert.adapters.mujoco.stepping import apply_xfrc

__all__ = ["read_back"]


def read_back(p, Q, V, contact_forces=None):
    """The ``Trajectory`` of the sampled states ``Q (n, nq)``, ``V (n, nv)`` (NaN rows stay
    NaN), with the reaction forces on jointed children (N, world axes) as extras; and the
    audit figures read on the way (contacts, constraint rows, passive forces), and each contact pair's force
    (``contact.force_reader``) as the extras ``contact_force:<pair>``. ``contact_forces`` (n, n_pairs, 3): the
    pairs' forces another solver computed at these states, stored in their place (MJX's own, ``mjx.contact``:
    MuJoCo C's solver did not make MJX's states).

    MuJoCo recomputes each sample (one ``mj_forward``, plus ``mj_rnePostConstraint`` where
    reactions are read); what it computed is copied out per sample, and the conversion to the
    scene's body frames is done once, on every sample at a time.
    """
    import mujoco

    from dalembert.trajectory import BodyStates, JointStates, Trajectory

    model, d, scene = _state_dynamics(p.model), p.scratch, p.scene
    n, nb = len(p.times), len(scene.bodies)
    ids = np.array([p.ids[b.name] for b in scene.bodies])
    # a weld held by an equality constraint has no joint force to read (cfrc_int is zero)
    children = [j.child for j in scene.joints if not floating(j, p.welds)]
    child_ids = np.array([p.ids[c] for c in children], dtype=int)
    roots = model.body_rootid[ids]
    # every MuJoCo body's figures per sample, whole arrays copied (a fancy-indexed copy costs ~7x a
    # slice copy, and this loop runs once per sample); the scene's bodies are picked out after it
    nbody = model.nbody
    xpos_all, xmat_all = np.full((n, nbody, 3), np.nan), np.full((n, nbody, 9), np.nan)
    cvel_all = np.full((n, nbody, 6), np.nan)  # MuJoCo's (w, v) of each body at its tree's centre of mass, world axes
    com_all = np.full((n, nbody, 3), np.nan)  # each body's subtree centre of mass
    cfrc_all = np.full((n, nbody, 6), np.nan)
    ncon, nefc = np.zeros(n, dtype=int), np.zeros(n, dtype=int)
    passive = np.zeros((n, model.nv))
    loops = _loop_rows(model, scene)
    loop_force = {name: np.full((n, 3), np.nan) for name in loops}
    tendons = spring_tendon_ids(model, scene)
    other_passive = np.zeros(n)  # |qfrc_passive - the springs' J^T f|: any passive force that is not a spring's
    reader = force_reader(model, scene) if contact_forces is None else None
    pair_force = np.full((n, len(scene.contacts), 3), np.nan) if contact_forces is None else contact_forces
    if p.load_path == "actuator":
        d.ctrl[:] = 1.0
    finite = np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1)
    # views of MjData's arrays, taken once: each attribute access builds a new array object
    qpos, qvel, d_xpos, d_xmat, d_cvel, d_com = d.qpos, d.qvel, d.xpos, d.xmat, d.cvel, d.subtree_com
    d_passive, d_cfrc = d.qfrc_passive, d.cfrc_int
    for k in np.flatnonzero(finite):
        qpos[:], qvel[:] = Q[k], V[k]
        if p.load_path == "xfrc_applied":
            apply_xfrc(p, d)
        mujoco.mj_forward(model, d)
        if children:
            mujoco.mj_rnePostConstraint(model, d)
            cfrc_all[k] = d_cfrc
        ncon[k], nefc[k] = d.ncon, d.nefc
        for name, (kind, eq_ids, sites) in loops.items():
            loop_force[name][k] = _loop_force(d, kind, eq_ids, sites)
        passive[k] = d_passive
        if reader is not None:
            pair_force[k] = reader(d)
        if tendons:
            J = _tendon_jacobian(model, d)
            springs_q = np.zeros(model.nv)
            for t in tendons:
                springs_q -= spring_tension(model, d, t) * J[t]  # MuJoCo's tendon force is -tension, applied as J^T f
            other_passive[k] = np.abs(d_passive - springs_q).max(initial=0.0)
        xpos_all[k], xmat_all[k], cvel_all[k], com_all[k] = d_xpos, d_xmat, d_cvel, d_com
    xpos, xmat, cvel, com = xpos_all[:, ids], xmat_all[:, ids], cvel_all[:, ids], com_all[:, roots]  # (n, nb, .)
    cfrc = cfrc_all[:, child_ids, 3:]  # (n, children, 3)
    max_ncon, max_nefc = ncon.max(initial=0), nefc.max(initial=0)
    R_WE = xmat.reshape(n, nb, 3, 3)
    p_EB = np.array([p.frames[b.name][0] for b in scene.bodies])  # (nb, 3)
    R_EB = np.array([p.frames[b.name][1] for b in scene.bodies])  # (nb, 3, 3)
    R_WB = R_WE @ R_EB  # W <- E <- B
    r = (R_WE @ p_EB[:, :, None])[..., 0]  # from the origin of E to that of B, world axes
    pos = xpos + r
    quat = spatial.matrix_to_quat(R_WB)
    # the velocity at each MuJoCo body frame's origin, as mj_objectVelocity(mjOBJ_XBODY) shifts it
    # (mju_transformSpatial: v - (x - c) x w)
    omega = cvel[..., :3]
    vel = (cvel[..., 3:] - np.cross(xpos - com, omega)) + np.cross(omega, r)
    # Free bodies: the attitude is MuJoCo's own quaternion as integrated (its norm is data).
    for bi, b in enumerate(scene.bodies):
        if floating(scene.joint(b.name), p.welds):
            a = model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, b.name)]
            quat[:, bi] = Q[:, a + 3:a + 7]
    order = {b.name: bi for bi, b in enumerate(scene.bodies)}
    reactions = {}
    for ci, child in enumerate(children):
        f = cfrc[:, ci].copy()
        if p.load_path == "actuator":  # loads MuJoCo routed through joint space
            for ld in scene.loads:
                if ld.kind == "force" and ld.body in _subtree(scene, child, p.welds):
                    f -= spatial.load_to_world(ld, R_WB[:, order[ld.body]])
        reactions[child] = f
    bodies = {b.name: BodyStates(pos[:, bi], quat[:, bi], vel[:, bi], omega[:, bi]) for bi, b in enumerate(scene.bodies)}
    joints = {}
    for j in scene.joints:
        if j.kind == "weld":
            continue
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j.child)
        a, v = model.jnt_qposadr[jid], model.jnt_dofadr[jid]
        joints[j.child] = JointStates(Q[:, a:a + len(j.q0)], V[:, v:v + len(j.v0)])
    extras = {f"reaction_force:{c}": f for c, f in reactions.items()}
    extras.update({f"reaction_force:{name}": f for name, f in loop_force.items()})
    extras.update({FORCE_PREFIX + pair.name: pair_force[:, i] for i, pair in enumerate(scene.contacts)})
    audit = {"max_contacts": int(max_ncon), "max_constraint_rows": int(max_nefc),
             "max_abs_passive_force": float(np.abs(passive).max(initial=0.0))}
    if tendons:
        audit["max_abs_passive_force_not_springs"] = float(np.nanmax(other_passive, initial=0.0))
    return Trajectory(p.times, bodies, joints, extras), audit


def _state_dynamics(model):
    """``model``, or for MuJoCo's discrete integrator a copy of it at Euler: the model whose ``mj_forward``
    gives the dynamics of the state alone. The discrete integrator's ``mj_forward`` solves for its step's
    acceleration, implicit in the springs' stiffness and damping (measured: a slider on a 50 N/m spring,
    h = 1e-2, qacc 7.481 m/s^2 where k x / m = 7.5, and reactions first order in h: 0.48 N off at 1e-2,
    0.12 N at 2.5e-3); the reaction of the state is the one the harness compares. Euler's own implicit
    term (eulerdamp) acts on joint damping only, zero in every model ``mjcf`` writes."""
    import copy

    import mujoco

    discrete = getattr(mujoco.mjtIntegrator, "mjINT_DISCRETE", None)  # MuJoCo 4's; earlier releases have none
    if discrete is None or model.opt.integrator != discrete:
        return model
    out = copy.copy(model)
    out.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
    return out


def _tendon_jacobian(model, d):
    """The tendons' Jacobian ``ten_J`` as a dense (ntendon, nv) array, whether MuJoCo keeps it sparse
    (the model's ``ten_J_rownnz/rowadr/colind``) or dense."""
    import mujoco

    if d.ten_J.size == model.ntendon * model.nv and not mujoco.mj_isSparse(model):
        return d.ten_J.reshape(model.ntendon, model.nv)
    J = np.zeros((model.ntendon, model.nv))
    mujoco.mju_sparse2dense(J, d.ten_J, model.ten_J_rownnz, model.ten_J_rowadr, model.ten_J_colind)
    return J


def _subtree(scene, name, welds="tree"):
    """``name`` and the bodies below it in MuJoCo's tree (a weld held by a constraint is not)."""
    out, frontier = {name}, [name]
    while frontier:
        parent = frontier.pop()
        for j in scene.joints:
            if j.parent == parent and j.child not in out and not floating(j, welds):
                out.add(j.child)
                frontier.append(j.child)
    return out


def _loop_rows(model, scene):
    """Per loop name: ``(kind, equality ids, (site a, site b) ids)`` of its constraints (``mjcf``)."""
    import mujoco

    out = {}
    for i, lp in enumerate(scene.loops):
        names = [lp.name] + ([f"{lp.name}:axis"] if lp.kind == "revolute" else [])
        ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_EQUALITY, n) for n in names]
        sites = tuple(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"loop{i}_{end}0") for end in "ab")
        out[lp.name] = (lp.kind, ids, sites)
    return out


def _loop_force(d, kind, ids, sites):
    """The force (3,) ON body b (N, world) of one loop's equality rows at the state ``d`` holds."""
    import mujoco

    equality = d.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    total = np.zeros(3)
    for eq in ids:
        f = d.efc_force[equality & (d.efc_id == eq)]
        if kind == "distance":
            e = d.site_xpos[sites[1]] - d.site_xpos[sites[0]]
            total += f[0] * e / np.linalg.norm(e)
        else:
            total -= f
    return total
