"""MuJoCo's model of a scene's contact: geoms, planes, the explicit pairs, friction, restitution, and the
contact options; read back from the compiled model for the audit.

* Every scene ``Geom`` becomes a MuJoCo geom (``sphere``: size = radius; ``box``: size = the half edge lengths)
  in its body, at its point and attitude in MuJoCo's body frame E; every ``Plane`` a ``plane`` geom of the
  worldbody whose z axis is the plane's normal. The bodies keep their explicit ``<inertial>``: geoms add no mass.
* Nothing collides by default: every geom has ``contype = conaffinity = 0``, so MuJoCo's broad phase makes no
  contact of its own; the scene's ``ContactPair``s are listed explicitly as ``<contact><pair>`` (which MuJoCo
  checks whatever the contype/conaffinity): nothing touches that the scene does not name.
* Friction: MuJoCo's pair friction is five numbers (two sliding, one torsional, two rolling). The sliding ones are
  the scene's Coulomb coefficient mu; torsional and rolling are 0 (an ideal Coulomb point contact resists neither
  spin about the normal nor rolling) and ``condim = 3`` (normal and two tangential directions; ``condim = 1``,
  normal only, where mu = 0). ``cone`` (option) chooses MuJoCo's pyramidal or elliptic friction cone.
* Restitution: MuJoCo has none. Its soft contact makes the normal direction a damped spring with reference
  acceleration ``-b v - k r``, ``b = 2 / (d_max timeconst)``, ``k = d(r) / (d_max^2 timeconst^2 dampratio^2)``
  (MuJoCo documentation, Modeling: Solver parameters, solref = (timeconst, dampratio)): a linear oscillator of
  damping ratio ``dampratio``. A linear spring-damper contact of damping ratio zeta returns a body after half its
  damped period with ``e = exp(-zeta pi / sqrt(1 - zeta^2))`` of its approach speed (the Kelvin-Voigt contact:
  Hunt & Crossley, J. Appl. Mech. 42, 1975, where this constant restitution is their starting point), so a
  pair's restitution e is mapped to ``dampratio = -ln e / sqrt(pi^2 + ln^2 e)`` (``restitution_dampratio``; e = 0:
  critically damped, 1). The mapping ignores what MuJoCo adds to the oscillator (the impedance d(r) < 1 mixes in
  the unconstrained acceleration; gravity acts during the contact), so MuJoCo's restitution is not e: the
  bouncing_ball case measures how far. A pair without restitution keeps MuJoCo's default dampratio, 1. e = 1
  (dampratio 0, an infinite stiffness) cannot be mapped: ``why_not``.
* Options (the adapter's, ``OPTIONS``): ``cone`` = pyramidal (MuJoCo's default) | elliptic; ``impratio`` (the
  ratio of frictional to normal impedance, MuJoCo's default 1); ``noslip_iterations`` (MuJoCo's post-processing
  that removes slip, default 0); ``contact_timeconst`` (solref's time constant of every pair, s, default MuJoCo's
  0.02). The contact impedance is MuJoCo's default solimp, ``SOLIMP``.
* Contact forces (``force_reader``): per sample, after ``mj_forward`` at the sample's state, every active contact
  of ``data.contact`` whose two geoms are a scene pair's: ``mj_contactForce`` gives its force in the contact frame
  (normal first, then the two tangents; MuJoCo's ``contact.frame`` rows, the normal pointing from ``geom[0]`` to
  ``geom[1]``), the force ``geom[0]`` exerts on ``geom[1]``; turned into world axes and summed per pair, ON the
  pair's subject (``dalembert.contact.subject``). It is the force of the step that starts at the sample's state.
"""

from __future__ import annotations

import math

import numpy as np

from dalembert import spatial
from dalembert.adapters.base import Option, typed_options

__all__ = ["OPTIONS", "CONTACT_OPTIONS", "CONES", "TIMECONST_DEFAULT", "SOLIMP", "contact_options", "restitution_dampratio", "why_not",
           "geom_lines", "plane_lines", "pair_lines", "option_attributes", "audit", "force_reader"]

CONES = ("pyramidal", "elliptic")
# MuJoCo's defaults (its XML reference: option cone, impratio, noslip_iterations; solref 0.02 1; solimp).
TIMECONST_DEFAULT = 0.02
# The contact options as the adapter declares them (``Adapter.options``); ``contact_options`` parses them.
CONTACT_OPTIONS = {
    "cone": Option(CONES, CONES[0], "MuJoCo's friction cone: pyramidal (its default) or elliptic"),
    "impratio": Option(default=1.0, exclusive_minimum=0.0,
                       description="ratio of frictional to normal constraint impedance (MuJoCo's default 1)"),
    "noslip_iterations": Option(default=0, minimum=0.0, integer=True,
                                description="noslip solver iterations after the main solver (MuJoCo's default 0)"),
    "contact_timeconst": Option(default=TIMECONST_DEFAULT, exclusive_minimum=0.0,
                                description=f"solref's time constant of every contact pair, s (MuJoCo's default "
                                            f"{TIMECONST_DEFAULT:g})"),
}
OPTIONS = tuple(CONTACT_OPTIONS)  # the options every integrator takes
SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)


def _f(x):
    return " ".join(repr(float(v)) for v in np.ravel(x))


def contact_options(settings):
    """The contact options of ``settings`` with their declared defaults (``CONTACT_OPTIONS``, checked by
    ``Adapter.check``), as MuJoCo takes them: dict ``cone`` (str), ``impratio`` (float), ``noslip_iterations``
    (int), ``timeconst`` (float, s)."""
    o = typed_options(CONTACT_OPTIONS, settings)
    return {"cone": o["cone"], "impratio": o["impratio"], "noslip_iterations": o["noslip_iterations"],
            "timeconst": o["contact_timeconst"]}


def restitution_dampratio(e):
    """solref's damping ratio for Newton's restitution ``e`` (None: MuJoCo's default, 1): the damping ratio of the
    linear oscillator whose half-period bounce keeps ``e`` of the speed, ``-ln e / sqrt(pi^2 + ln^2 e)``."""
    if e is None or e == 0.0:
        return 1.0
    log = math.log(e)
    return -log / math.sqrt(math.pi**2 + log**2)


def why_not(scene):
    """Why MuJoCo cannot represent the scene's contact, or None."""
    elastic = [c.name for c in scene.contacts if c.restitution == 1.0]
    if elastic:
        return (f"contact pairs {elastic} are perfectly elastic (restitution 1): MuJoCo's soft contact would need a "
                "damping ratio of 0, an infinite stiffness (solref's k ~ 1/dampratio^2)")
    return None


def geom_lines(scene, body, p_EB, R_EB):
    """The MJCF lines of ``body``'s geoms, in its MuJoCo frame E (``x_E = p_EB + R_EB x_B``)."""
    out = []
    for g in scene.geoms:
        if g.body != body:
            continue
        pos = p_EB + R_EB @ np.asarray(g.point)
        quat = spatial.matrix_to_quat(R_EB @ spatial.quat_to_matrix(np.asarray(g.quat) / np.linalg.norm(g.quat)))
        size = g.size if g.kind == "sphere" else 0.5 * np.asarray(g.size)  # MuJoCo's box size: half lengths
        out.append(f'<geom name="{g.name}" type="{g.kind}" size="{_f(size)}" pos="{_f(pos)}" quat="{_f(quat)}" '
                   'contype="0" conaffinity="0" mass="0"/>')
    return out


def plane_lines(scene):
    """The MJCF lines of the scene's planes (worldbody geoms, z along the normal)."""
    return [f'<geom name="{p.name}" type="plane" size="0 0 1" pos="{_f(p.point)}" '
            f'quat="{_f(spatial.matrix_to_quat(spatial.frame_with_z(p.unit_normal)))}" contype="0" conaffinity="0"/>'
            for p in scene.planes]


def pair_lines(scene, settings):
    """The ``<contact>`` section: one explicit pair per ``ContactPair`` (empty when the scene has none)."""
    if not scene.contacts:
        return []
    tc = contact_options(settings)["timeconst"]
    out = ["  <contact>"]
    for c in scene.contacts:
        condim = 3 if c.friction > 0.0 else 1
        friction = f"{c.friction!r} {c.friction!r} 0 0 0"
        out.append(f'    <pair name="{c.name}" geom1="{c.a}" geom2="{c.b}" condim="{condim}" friction="{friction}" '
                   f'solref="{tc!r} {restitution_dampratio(c.restitution)!r}" solimp="{_f(SOLIMP)}" margin="0" '
                   'gap="0"/>')
    out.append("  </contact>")
    return out


def option_attributes(scene, settings):
    """The ``<option>`` attributes of the contact options (empty for a scene without contact)."""
    if not scene.contacts:
        return ""
    o = contact_options(settings)
    return f' cone="{o["cone"]}" impratio="{o["impratio"]!r}" noslip_iterations="{o["noslip_iterations"]}"'


def audit(model, scene):
    """Every contact parameter as the compiled model holds it (none: empty): the cone, impratio, noslip
    iterations, whether contact is enabled, every pair (geoms, condim, the five friction numbers, solref, solimp,
    margin, gap, and the restitution its damping ratio stands for), the geoms' types and sizes, and that no geom
    collides by default (contype and conaffinity all 0)."""
    import mujoco

    if not scene.contacts:
        return {}
    name = lambda kind, i: mujoco.mj_id2name(model, kind, int(i))  # noqa: E731
    pairs = {}
    for i in range(model.npair):
        zeta = float(model.pair_solref[i][1])
        pairs[name(mujoco.mjtObj.mjOBJ_PAIR, i)] = {
            "geoms": [name(mujoco.mjtObj.mjOBJ_GEOM, model.pair_geom1[i]),
                      name(mujoco.mjtObj.mjOBJ_GEOM, model.pair_geom2[i])],
            "condim": int(model.pair_dim[i]),
            "friction": [float(v) for v in model.pair_friction[i]],
            "solref": [float(v) for v in model.pair_solref[i]],
            "solimp": [float(v) for v in model.pair_solimp[i]],
            "margin": float(model.pair_margin[i]), "gap": float(model.pair_gap[i]),
            "restitution_of_dampratio": math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta**2)) if zeta < 1.0 else 0.0,
        }
    return {
        "contact_enabled": not model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT),
        "cone": mujoco.mjtCone(model.opt.cone).name[len("mjCONE_"):].lower(),
        "impratio": float(model.opt.impratio),
        "noslip_iterations": int(model.opt.noslip_iterations),
        "contact_pairs": pairs,
        "geoms": {name(mujoco.mjtObj.mjOBJ_GEOM, i): {"type": mujoco.mjtGeom(model.geom_type[i]).name[len("mjGEOM_"):]
                                                      .lower(), "size": [float(v) for v in model.geom_size[i]]}
                  for i in range(model.ngeom)},
        "default_collisions": int(np.count_nonzero(model.geom_contype) + np.count_nonzero(model.geom_conaffinity)),
        "restitution_mapping": ("restitution e -> solref dampratio -ln e / sqrt(pi^2 + ln^2 e), the damping ratio of "
                                "a linear oscillator that keeps e of the speed over half its period; MuJoCo's "
                                "impedance and gravity during the contact make its restitution differ"),
    }


def force_reader(model, scene):
    """A function ``data -> ndarray (n_pairs, 3)``: the contact force (N, world) ON each of ``scene.contacts``'
    subjects (``dalembert.contact.subject``) at the state ``data`` holds after ``mj_forward``; None for a scene
    without contact."""
    import mujoco

    from dalembert.contact import subject

    if not scene.contacts:
        return None
    gid = lambda name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)  # noqa: E731
    # per unordered geom pair: (its index in scene.contacts, the subject's geom id)
    index = {}
    for i, pair in enumerate(scene.contacts):
        index[frozenset((gid(pair.a), gid(pair.b)))] = (i, gid(subject(scene, pair)))
    out6 = np.zeros(6)

    def read(d):
        total = np.zeros((len(scene.contacts), 3))
        for c in range(d.ncon):
            con = d.contact[c]
            found = index.get(frozenset((int(con.geom[0]), int(con.geom[1]))))
            if found is None or con.efc_address < 0:  # not a scene pair's, or excluded from the solver
                continue
            mujoco.mj_contactForce(model, d, c, out6)
            f_W = con.frame.reshape(3, 3).T @ out6[:3]  # on geom[1], world
            i, subject_id = found
            total[i] += f_W if int(con.geom[1]) == subject_id else -f_W
        return total

    return read
