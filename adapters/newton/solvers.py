"""Newton's solvers as integrator families: which solver each family builds, its options and their defaults.

Each family is one ``newton.solvers`` class that steps rigid bodies on joints, at a fixed step:

* ``featherstone`` — ``SolverFeatherstone``: reduced (joint) coordinates, the articulated mass matrix by the
  composite-rigid-body algorithm, semi-implicit Euler;
* ``semi_implicit`` — ``SolverSemiImplicit``: maximal coordinates, each joint a penalty spring-damper
  (``joint_attach_ke``, ``joint_attach_kd``), symplectic Euler;
* ``xpbd`` — ``SolverXPBD``: maximal coordinates, joints as position constraints projected ``iterations`` times a
  step (extended position-based dynamics, Macklin et al. 2016), relaxed by ``joint_*_relaxation``;
* ``vbd`` — ``SolverVBD``: maximal coordinates, augmented vertex block descent (AVBD: implicit Euler solved by
  block coordinate descent, joints as stiffening penalties), ``iterations`` sweeps a step;
* ``steel`` — ``SolverSteel``: reduced coordinates, joints and constraints as velocity rows solved by projected
  Gauss-Seidel (``iterations``), Baumgarte stabilization (``baumgarte``), ``cfm`` regularization;
* ``mujoco_euler``, ``mujoco_implicitfast``, ``mujoco_rk4`` — ``SolverMuJoCo``: MuJoCo Warp on Newton's model with
  each MuJoCo integrator, in an engine environment of its own (``mujoco_solver``: Newton pins mujoco ~= 3.17).

Left out, with the reason (``NOT_FAMILIES``): Kamino (measured 0.21 s a step on the pendulum on Warp's CPU
backend: 1000 times Featherstone's, hours for one case's horizon) and the solvers of particles and deformables (implicit MPM, Style3D).

What ``dalembert check-engine newton`` finds (Newton 1.8.0, the defaults here): Featherstone passes every probe;
the body-coordinate solvers' joints are not rigid (XPBD at its 2 iterations starts the hinge at 1.6 times gravity's
drive, 20 iterations fix that; VBD's joints hold the hinge near still at first; the semi-implicit one's penalty
springs blow up on the pendulum's rod, 5e-5 kg m^2 about its axis, at dt 1e-3) and a free spin's rate or energy
moves by ~1e-4 over 0.5 s in every family but Featherstone (float32 roundoff over 500 steps against the probe's
1e-5; VBD's implicit Euler damps it by 1.7e-3). Steel's attitude error on the free top grows as the step shrinks
(3.7e-4 rad at 1e-3 s, 8.8e-4 at 5e-4 over 1 s).

Options: one declaration per name (``OPTIONS``), each taken only by the families that have it (``Option.only``),
and ``defaults`` (every family). An option's default is the value this adapter builds with: Newton's own default,
except ``angular_damping`` under ``defaults=scene``,
whose Newton default (0.05 in Featherstone, semi-implicit and, on free bodies, Steel: PhysX's default) is a damping
no scene asks for, so it is 0 here. Steel takes it as a model attribute, not a constructor argument
(``model.build``: ``steel_angular_damping``).
The audit reads every setting back from the solver object the run stepped with (``settings``).
"""

from __future__ import annotations

from dalembert.adapters.base import Option
from dalembert.adapters.newton import mujoco_solver

__all__ = ["FAMILIES", "NOT_FAMILIES", "OPTIONS", "angular_damping", "make", "settings"]

# family -> (Newton's class, description, order of accuracy, its options in the order its constructor takes them)
FAMILIES = {
    "featherstone": ("SolverFeatherstone", "Newton Featherstone: joint coordinates, semi-implicit Euler", 1,
                     ("angular_damping", "update_mass_matrix_interval")),
    "semi_implicit": ("SolverSemiImplicit", "Newton semi-implicit: body coordinates, joints as penalty springs, "
                      "symplectic Euler", 1, ("angular_damping", "joint_attach_ke", "joint_attach_kd")),
    "xpbd": ("SolverXPBD", "Newton XPBD: body coordinates, joints as projected position constraints", 1,
             ("angular_damping", "iterations", "joint_linear_relaxation", "joint_angular_relaxation",
              "joint_linear_compliance", "joint_angular_compliance")),
    "vbd": ("SolverVBD", "Newton VBD: body coordinates, implicit Euler by augmented vertex block descent", 1,
            ("iterations", "rigid_avbd_gamma")),
    "steel": ("SolverSteel", "Newton Steel: joint coordinates, constraint rows by projected Gauss-Seidel", 1,
              ("angular_damping", "iterations", "baumgarte", "cfm", "relaxation", "update_mass_matrix_interval")),
    **mujoco_solver.FAMILIES,
}
NOT_FAMILIES = {
    "kamino": "SolverKamino: 0.21 s a step on the pendulum on Warp's CPU backend (measured, kernels cached), "
              "1000 times Featherstone's",
    "implicit_mpm": "SolverImplicitMPM: particles (material point method), no rigid joints",
    "style3d": "SolverStyle3D: cloth, no rigid joints",
}


def _only(name):
    return tuple(f for f, (_, _, _, opts) in FAMILIES.items() if name in opts)


OPTIONS = {
    "defaults": Option(choices=("scene", "engine"), default="scene",
                       description="scene: nothing the scene does not ask for (angular damping 0, the inertia as "
                                   "given); engine: Newton's own defaults (angular damping 0.05 in Featherstone, "
                                   "semi-implicit and Steel, inertia balancing on), to measure what they do"),
    "angular_damping": Option(default=None, minimum=0.0, only=_only("angular_damping"),
                              description="angular velocity damping (1/s); default: 0 with defaults=scene, Newton's "
                                          "own (0.05 in Featherstone, semi-implicit and Steel) with defaults=engine"),
    "update_mass_matrix_interval": Option(default=1, minimum=1.0, integer=True,
                                          only=_only("update_mass_matrix_interval"),
                                          description="steps between mass-matrix updates (Newton's default 1)"),
    "joint_attach_ke": Option(default=1.0e4, exclusive_minimum=0.0, only=_only("joint_attach_ke"),
                              description="joint penalty stiffness (Newton's default 1e4)"),
    "joint_attach_kd": Option(default=1.0e2, minimum=0.0, only=_only("joint_attach_kd"),
                              description="joint penalty damping (Newton's default 1e2)"),
    "iterations": Option(default=None, minimum=1.0, integer=True, only=_only("iterations"),
                         description="solver iterations a step (default: the solver's own: XPBD 2, VBD 10, "
                                     "Steel 12)"),
    "joint_linear_relaxation": Option(default=0.7, exclusive_minimum=0.0, maximum=2.0,
                                      only=_only("joint_linear_relaxation"),
                                      description="relaxation of linear joint corrections (Newton's default 0.7)"),
    "joint_angular_relaxation": Option(default=0.4, exclusive_minimum=0.0, maximum=2.0,
                                       only=_only("joint_angular_relaxation"),
                                       description="relaxation of angular joint corrections (Newton's default 0.4)"),
    "joint_linear_compliance": Option(default=0.0, minimum=0.0, only=_only("joint_linear_compliance"),
                                      description="linear joint compliance, m/N (Newton's default 0: rigid)"),
    "joint_angular_compliance": Option(default=0.0, minimum=0.0, only=_only("joint_angular_compliance"),
                                       description="angular joint compliance, rad/(N m) (Newton's default 0)"),
    "rigid_avbd_gamma": Option(default=0.999, minimum=0.0, maximum=1.0, only=_only("rigid_avbd_gamma"),
                               description="per-step decay of VBD's persisted multipliers (Newton's default 0.999)"),
    "baumgarte": Option(default=0.2, minimum=0.0, maximum=1.0, only=_only("baumgarte"),
                        description="Steel's Baumgarte position-error feedback (Newton's default 0.2)"),
    "cfm": Option(default=1.0e-6, minimum=0.0, only=_only("cfm"),
                  description="Steel's constraint-force mixing regularization (Newton's default 1e-6)"),
    "relaxation": Option(default=1.0, exclusive_minimum=0.0, maximum=2.0, only=_only("relaxation"),
                         description="Steel's PGS relaxation (Newton's default 1)"),
}


def angular_damping(options):
    """The angular damping a run builds with (1/s), or None: Newton's own (``defaults=engine``, none given)."""
    given = options.get("angular_damping")
    if given is not None:
        return given
    return 0.0 if options.get("defaults", "scene") == "scene" else None


def make(newton, model, family, options):
    """The solver of ``family`` on ``model``, built with ``options`` (name -> typed value, ``typed_options``):
    only the family's own, and ``iterations`` only when given (None: the solver's own default)."""
    cls, _, _, names = FAMILIES[family]
    if family in mujoco_solver.FAMILIES:
        return getattr(newton.solvers, cls)(model, **mujoco_solver.make_kwargs(family))
    options = {**options, "angular_damping": angular_damping(options)}
    kwargs = {n: options[n] for n in names if options.get(n) is not None and (family, n) not in _MODEL_SETTINGS}
    return getattr(newton.solvers, cls)(model, **kwargs)


# Settings a family takes on the model (``model.build``), not in its constructor: (family, option) -> the model's
# attribute, read back from there
_MODEL_SETTINGS = {("steel", "angular_damping"): ("steel", "rigid_body_angular_damping")}
# The attribute each setting is held under on the solver object (Steel keeps some private)
_ATTRIBUTES = {"iterations": ("iterations", "_iterations"), "cfm": ("cfm", "_cfm"),
               "update_mass_matrix_interval": ("update_mass_matrix_interval", "_update_mass_matrix_interval")}


def settings(solver, family, model):
    """Every option of ``family`` as the solver object (or, for a model setting, ``model``) holds it (read back,
    not the request): name -> value; a per-body model setting as its largest value. The MuJoCo solver's: what its
    MuJoCo model holds (``mujoco_solver.settings``)."""
    if family in mujoco_solver.FAMILIES:
        return mujoco_solver.settings(solver)
    out = {}
    for name in FAMILIES[family][3]:
        if (family, name) in _MODEL_SETTINGS:
            namespace, attr = _MODEL_SETTINGS[(family, name)]
            held = getattr(getattr(model, namespace, None), attr, None)
            out[name] = (float(held.numpy().max(initial=0.0)) if held is not None
                         else f"Newton's default ({namespace}:{attr} not registered on the model)")
            continue
        for attr in _ATTRIBUTES.get(name, (name,)):
            if hasattr(solver, attr):
                value = getattr(solver, attr)
                out[name] = value if isinstance(value, (int, float, str, bool)) else repr(value)
                break
        else:
            out[name] = "not held by the solver object"
    return out
