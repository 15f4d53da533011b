"""Newton's MuJoCo solver (``SolverMuJoCo``): MuJoCo Warp stepping Newton's model, one family per MuJoCo integrator,
in an engine environment of its own.

``SolverMuJoCo`` turns Newton's model into a MuJoCo model (joints as MuJoCo joints, bodies at their COMs, no
geoms here: the adapter builds no shapes) and steps it with MuJoCo Warp (float32, Warp's kernels) between Newton's
states: each step pushes ``state_in``'s joint coordinates and ``body_f`` (as ``xfrc_applied``) into MuJoCo Warp's
data, steps, and pulls the joint coordinates and body states back. The integrator is MuJoCo's
(``integrator=``): each is a family here, so that the order each declares is its own
(``FAMILIES``): ``mujoco_euler`` (semi-implicit Euler, order 1), ``mujoco_implicitfast`` (Newton's default;
implicit in the velocity-dependent forces, order 1) and ``mujoco_rk4`` (order 4).

Newton pins the MuJoCo it was built against in its extra ``sim`` (newton 1.8.0: ``mujoco~=3.17.0`` and
``mujoco-warp~=3.17.0``), while dalembert's own environment runs MuJoCo 4.0: the families run in the environment
``dalembert env create newton==1.8.0`` makes (it installs ``newton[sim]``: ``NewtonAdapter.environment_extras``),
and ``problem`` refuses them, before anything is built, wherever the installed MuJoCo does not meet Newton's own
declared requirement (read from Newton's metadata, so a later Newton's pin needs no edit here).

Measured (Newton 1.8.0, MuJoCo and MuJoCo Warp 3.17.0, Warp's CPU backend; ``dalembert run --engine newton==1.8.0
--integrator mujoco_rk4 --tag canonical --param t_final=1 --quick``): on revolute joints RK4 is at float32's floor
(pendulum 2.2e-7 rad, chain 2.9e-7); bodies on a free or ball joint lose accuracy with every step, not with its
size: free_top's attitude error 5.9e-5 rad at dt 1e-2, 5.8e-4 at 1e-3 (its float32 floor 1.7e-6 and 9.0e-6), its
energy 5e-7 a step; heavy_top 1.5e-2 rad at 1e-3. MuJoCo Warp stepping the solver's own model and data alone keeps
free_top's energy to 4.9e-8 over 399 steps at dt 5e-3, where Newton's steps (the state pushed into MuJoCo Warp's data
and pulled back every step) lose 1.9e-4: the loss is Newton's transfer of free and ball joints' state between its
``State`` and MuJoCo Warp's data, not MuJoCo's RK4.
"""

from __future__ import annotations

import glob
import os

__all__ = ["EXTRA", "FAMILIES", "INTEGRATORS", "problem", "make_kwargs", "settings"]

# Newton's extra that brings the MuJoCo and MuJoCo Warp its MuJoCo solver needs
EXTRA = "sim"
# family -> MuJoCo's integrator name as ``SolverMuJoCo(integrator=...)`` takes it
INTEGRATORS = {"mujoco_euler": "euler", "mujoco_implicitfast": "implicitfast", "mujoco_rk4": "rk4"}
# family -> (Newton's class, description, order of accuracy, options): ``solvers.FAMILIES``' shape
FAMILIES = {
    "mujoco_euler": ("SolverMuJoCo", "Newton MuJoCo solver (MuJoCo Warp, float32): joint coordinates, "
                     "semi-implicit Euler", 1, ()),
    "mujoco_implicitfast": ("SolverMuJoCo", "Newton MuJoCo solver (MuJoCo Warp, float32): joint coordinates, "
                            "implicitfast (Newton's default)", 1, ()),
    "mujoco_rk4": ("SolverMuJoCo", "Newton MuJoCo solver (MuJoCo Warp, float32): joint coordinates, RK4", 4, ()),
}


def _sites(path):
    """The site-packages directories of the environment at ``path`` (a list; None: this process's ``sys.path``)."""
    return None if path is None else glob.glob(os.path.join(path, "lib", "python*", "site-packages"))


def _distribution(name, sites):
    from importlib import metadata

    return next(iter(metadata.distributions(name=name, path=sites) if sites is not None
                     else metadata.distributions(name=name)), None)


def requirements(sites=None):
    """What Newton's extra ``EXTRA`` requires of MuJoCo (``packaging`` Requirements whose name starts ``mujoco``),
    as the Newton installed in ``sites`` (None: this process's) declares it; empty when Newton is not installed."""
    from packaging.requirements import Requirement

    newton = _distribution("newton", sites)
    out = []
    for text in (newton.requires or []) if newton is not None else []:
        req = Requirement(text)
        if req.name.startswith("mujoco") and req.marker is not None and req.marker.evaluate({"extra": EXTRA}):
            out.append(req)
    return out


def problem(environment_path=None):
    """Why Newton's MuJoCo solver cannot run in the environment at ``environment_path`` (None: this process's), or
    None: each MuJoCo distribution Newton's ``sim`` extra requires, missing or at a version outside it (a text naming
    the command that makes an environment with them)."""
    sites = _sites(environment_path)
    reqs = requirements(sites)
    newton = _distribution("newton", sites)
    version = newton.version if newton is not None else "1.8.0"
    wrong = []
    for req in reqs:
        found = _distribution(req.name, sites)
        if found is None:
            wrong.append(f"{req.name} not installed")
        elif not req.specifier.contains(found.version, prereleases=True):
            wrong.append(f"{req.name} {found.version} installed")
    if not wrong:
        return None
    needs = ", ".join(f"{r.name}{r.specifier}" for r in reqs)
    return (f"Newton's MuJoCo solver needs newton[{EXTRA}]'s {needs}, and this environment has "
            f"{', '.join(wrong)} — make an environment for it with: dalembert env create newton=={version}, and run "
            f"it as --engine newton=={version}")


def make_kwargs(family):
    """``SolverMuJoCo``'s constructor arguments for ``family``: its MuJoCo integrator, MuJoCo Warp (not MuJoCo C),
    contact off (the model has no shapes: no collision pass is run), and no weld on each free root (Newton adds an
    inactive one by default, so that a root can be made kinematic at run time: an equality the scene has not)."""
    return dict(integrator=INTEGRATORS[family], use_mujoco_cpu=False, disable_contacts=True,
                kinematic_switchable_roots=False)


def settings(solver):
    """What the MuJoCo model the solver built holds (read back): its integrator, solver, iterations, the joints'
    armature, damping and frictionloss at their largest, and MuJoCo's and MuJoCo Warp's versions."""
    import numpy as np

    mujoco, mujoco_warp = solver.import_mujoco()
    m = solver.mj_model
    return {
        "integrator": mujoco.mjtIntegrator(int(m.opt.integrator)).name,
        "solver": mujoco.mjtSolver(int(m.opt.solver)).name,
        "iterations": int(m.opt.iterations),
        "nq": int(m.nq), "nv": int(m.nv), "ngeom": int(m.ngeom), "neq": int(m.neq),
        "dof_armature_max": float(np.abs(m.dof_armature).max(initial=0.0)),
        "dof_damping_max": float(np.abs(m.dof_damping).max(initial=0.0)),
        "dof_frictionloss_max": float(np.abs(m.dof_frictionloss).max(initial=0.0)),
        "disableflags": int(m.opt.disableflags),
        "mujoco_version": mujoco.__version__,
        "mujoco_warp_version": getattr(mujoco_warp, "__version__", "unknown"),
    }
