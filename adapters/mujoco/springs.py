"""The scene's spring-dampers as MuJoCo compiled them, read back from the model and the data.

``mjcf`` writes each spring as a spatial tendon between two sites (``spring_tendon``). Here the
compiled model is read, never the scene: each tendon's stiffness, damping, spring length, its
nonlinear terms, and its two sites' bodies and positions, turned back into the scene's body
frames (``read_springs``); ``check_springs`` compares them with the scene before anything runs;
``other_passive`` lists every other passive parameter that the spring and damper flags switch on
(joint stiffness and damping, the other tendons', their polynomials) and MuJoCo's fluid model; and
``spring_tension`` is a spring's tension at the state an ``MjData`` holds, from MuJoCo's own tendon
length and velocity (the read-back compares ``qfrc_passive`` with the springs' ``J^T f``).
"""

from __future__ import annotations

import numpy as np

from dalembert.adapters.mujoco.mjcf import spring_tendon

__all__ = ["read_springs", "check_springs", "other_passive", "spring_tendon_ids", "spring_tension", "SPRING_REL_TOL"]

# The compiled spring must reproduce the scene's to this relative accuracy: the numbers go through
# repr() into the MJCF and back (exact), the site positions through one rotation to MuJoCo's body frame
# and back (a few ulps of the lever).
SPRING_REL_TOL = 1e-12


def spring_tendon_ids(model, scene):
    """MuJoCo's tendon id of each spring (``scene.springs`` order)."""
    import mujoco

    return [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, spring_tendon(sp.name)) for sp in scene.springs]


def read_springs(model, scene, X_EB):
    """Each spring as the compiled ``model`` holds it: a list (``scene.springs`` order) of dicts with
    ``name``, ``stiffness`` (N/m), ``damping`` (N s/m), ``rest_length`` (m, the dead band's two ends),
    ``stiffnesspoly``/``dampingpoly`` (MuJoCo's higher-order terms), ``body_a``, ``body_b`` and
    ``point_a``, ``point_b`` (m, each site in its body's scene frame B, from ``site_pos`` in MuJoCo's frame
    E through ``X_EB``)."""
    import mujoco

    frames = {**X_EB, "world": (np.zeros(3), np.eye(3))}
    out = []
    for sp, t in zip(scene.springs, spring_tendon_ids(model, scene)):
        if t < 0:
            raise RuntimeError(f"MuJoCo's model has no tendon {spring_tendon(sp.name)!r} for spring {sp.name!r}")
        adr, num = model.tendon_adr[t], model.tendon_num[t]
        ends = []
        for w in range(adr, adr + num):
            if model.wrap_type[w] != mujoco.mjtWrap.mjWRAP_SITE:
                raise RuntimeError(f"tendon {spring_tendon(sp.name)!r} wraps a {mujoco.mjtWrap(model.wrap_type[w]).name}, "
                                   "not a site")
            site = model.wrap_objid[w]
            body = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.site_bodyid[site])
            p_EB, R_EB = frames[body]
            ends.append((body, R_EB.T @ (model.site_pos[site] - p_EB)))  # x_B = R_EB^T (x_E - p_EB)
        out.append(dict(name=sp.name, stiffness=float(model.tendon_stiffness[t]), damping=float(model.tendon_damping[t]),
                        rest_length=tuple(float(v) for v in model.tendon_lengthspring[t]),
                        stiffnesspoly=tuple(float(v) for v in model.tendon_stiffnesspoly[t]),
                        dampingpoly=tuple(float(v) for v in model.tendon_dampingpoly[t]),
                        sites=len(ends), body_a=ends[0][0] if ends else None, body_b=ends[-1][0] if ends else None,
                        point_a=ends[0][1] if ends else None, point_b=ends[-1][1] if ends else None))
    return out


def check_springs(model, scene, X_EB):
    """RuntimeError naming the spring and the field where the compiled model is not the scene's spring."""
    for sp, got in zip(scene.springs, read_springs(model, scene, X_EB)):
        problems = []
        if got["sites"] != 2:
            problems.append(f"{got['sites']} sites, not 2")
        for field in ("body_a", "body_b"):
            if got[field] != getattr(sp, field):
                problems.append(f"{field} {got[field]!r}, not {getattr(sp, field)!r}")
        for field in ("stiffness", "damping"):
            want = getattr(sp, field)
            if abs(got[field] - want) > SPRING_REL_TOL * max(want, 1.0):
                problems.append(f"{field} {got[field]!r}, not {want!r}")
        if any(abs(v - sp.rest_length) > SPRING_REL_TOL * max(sp.rest_length, 1.0) for v in got["rest_length"]):
            problems.append(f"spring length {got['rest_length']}, not {sp.rest_length!r}")
        if any(got["stiffnesspoly"]) or any(got["dampingpoly"]):
            problems.append(f"nonlinear terms {got['stiffnesspoly']}, {got['dampingpoly']}")
        for field in ("point_a", "point_b"):
            want = np.array(getattr(sp, field))
            if got[field] is not None and np.abs(got[field] - want).max() > SPRING_REL_TOL * max(1.0, np.abs(want).max()):
                problems.append(f"{field} {got[field].tolist()}, not {want.tolist()}")
        if problems:
            raise RuntimeError(f"MuJoCo compiled spring {sp.name!r} with {'; '.join(problems)}")


def other_passive(model, scene):
    """The largest magnitude of every passive parameter other than the springs' own (all zero in a model
    ``mjcf`` wrote): joint stiffness, dof damping, their polynomial terms, the other tendons' stiffness and
    damping, gravity compensation and the fluid model's density, viscosity and wind. Dict name -> float."""
    springs = set(spring_tendon_ids(model, scene))
    others = [t for t in range(model.ntendon) if t not in springs]

    def peak(a):
        return float(np.abs(np.asarray(a, float)).max(initial=0.0))

    return {
        "jnt_stiffness": peak(model.jnt_stiffness), "jnt_stiffnesspoly": peak(model.jnt_stiffnesspoly),
        "dof_damping": peak(model.dof_damping), "dof_dampingpoly": peak(model.dof_dampingpoly),
        "other_tendon_stiffness": peak(model.tendon_stiffness[others]),
        "other_tendon_damping": peak(model.tendon_damping[others]),
        "body_gravcomp": peak(model.body_gravcomp),
        "fluid": peak([model.opt.density, model.opt.viscosity, *model.opt.wind]),
    }


def spring_tension(model, d, tendon):
    """The tension (N, > 0 pulls) of the spring whose tendon is ``tendon`` at the state ``d`` holds, from
    MuJoCo's own ``ten_length`` and ``ten_velocity`` and the compiled stiffness, damping and spring length:
    ``k (L - L0) + c L'``. MuJoCo's tendon force is its negative, applied as ``J^T f`` (``qfrc_passive``)."""
    return float(model.tendon_stiffness[tendon] * (d.ten_length[tendon] - model.tendon_lengthspring[tendon][0])
                 + model.tendon_damping[tendon] * d.ten_velocity[tendon])
