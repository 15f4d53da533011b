"""Why MuJoCo 3.7.0 changed the four-bar under RK4: the J̇v term of its equality constraints' reference acceleration.

MuJoCo 3.7.0's changelog, General, item 5: "Added the centripetal/Coriolis acceleration term J̇v to the constraint
solver bias for connect and weld equality constraints" (commit 412cee205, "Add Jdot correction for connect and weld
constaints": ``mj_referenceConstraint`` subtracts ``mj_Jdotv`` from ``efc_aref`` whenever the model has equality
rows; no flag turns it off). Up to 3.6.0 a row's reference acceleration is ``-B vel - K I (pos - margin)``
(``efc_KBIP``); from 3.7.0 it is that minus J̇v. The adapter closes the four-bar's revolute loop with two connects
(``adapters/mujoco/mjcf.py``), so the term applies to it.

The experiment: MuJoCo's RK4 (``mj_RungeKutta``, engine_forward.c: the classic tableau, the final update as
``mj_advance``) stepped by hand on the adapter's model of ``four_bar``, each stage's forward pass split
(``mj_fwdPosition``, ``mj_fwdVelocity``, then ``efc_aref`` set, ``mj_fwdActuation``, ``mj_fwdAcceleration``,
``mj_fwdConstraint``) so that the rows' reference acceleration follows either rule whatever the installed release:
``old`` (3.6.0's) or ``new`` (3.7.0's, J̇v from ``mj_jacDot`` at each connect's two sites). If the term is the whole
change, each release's ``mj_step`` equals the hand RK4 under its own rule, and the two releases run the same under
either rule. Run it with the environments made (``dalembert env create mujoco==3.6.0``, ``mujoco==3.7.0``)::

    python docs/mujoco_jdotv_four_bar.py 3.6.0 3.7.0          # default: dt 5e-3; --dt 1e-3 for another step

It starts itself in each environment's interpreter on this checkout's code (``dalembert.harness.boot``), as a
worker is, and prints each release's crank-angle error against the closed form and the loop residual per rule.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

MODES = ("mj_step", "old", "new")
# MuJoCo's RK4 tableau (engine_forward.c, RK4_A row-major 3 x 3 and RK4_B)
RK4_A = ((0.5,), (0.0, 0.5), (0.0, 0.0, 1.0))
RK4_B = (1 / 6, 1 / 3, 1 / 3, 1 / 6)


def jdotv(model, data):
    """J̇v of every connect's three rows (m/s^2, world): the first site's point acceleration from J̇ minus the
    second's (``mj_jacDot``; the rows are the first site's position minus the second's)."""
    import mujoco
    import numpy as np

    out = []
    for i in range(model.neq):
        acc = []
        for site in (model.eq_obj1id[i], model.eq_obj2id[i]):
            jac = np.zeros((3, model.nv))
            mujoco.mj_jacDot(model, data, jac, None, data.site_xpos[site], model.site_bodyid[site])
            acc.append(jac @ data.qvel)
        out.append(acc[0] - acc[1])
    return np.concatenate(out)


def forward(model, data, rule):
    """``mj_forward``'s stages with the equality rows' reference acceleration by ``rule``: ``old`` (3.6.0's),
    ``new`` (3.7.0's: minus J̇v)."""
    import mujoco

    mujoco.mj_fwdPosition(model, data)
    mujoco.mj_fwdVelocity(model, data)
    ne = data.ne
    K, B, I = data.efc_KBIP[:ne, 0], data.efc_KBIP[:ne, 1], data.efc_KBIP[:ne, 2]
    aref = -B * data.efc_vel[:ne] - K * I * (data.efc_pos[:ne] - data.efc_margin[:ne])
    data.efc_aref[:ne] = aref if rule == "old" else aref - jdotv(model, data)
    mujoco.mj_fwdActuation(model, data)
    mujoco.mj_fwdAcceleration(model, data)
    mujoco.mj_fwdConstraint(model, data)


def rk4_step(model, data, rule):
    """One step of MuJoCo's RK4 (``mj_RungeKutta``) with ``forward(..., rule)`` at each stage."""
    import mujoco

    h = model.opt.timestep
    forward(model, data, rule)
    q0, v0 = data.qpos.copy(), data.qvel.copy()
    V, F = [v0], [data.qacc.copy()]
    for row in RK4_A:
        q = q0.copy()
        mujoco.mj_integratePos(model, q, sum(a * v for a, v in zip(row, V)), h)
        data.qpos[:], data.qvel[:] = q, v0 + h * sum(a * f for a, f in zip(row, F))
        forward(model, data, rule)
        V.append(data.qvel.copy())
        F.append(data.qacc.copy())
    q = q0.copy()
    mujoco.mj_integratePos(model, q, sum(b * v for b, v in zip(RK4_B, V)), h)
    data.qpos[:], data.qvel[:] = q, v0 + h * sum(b * f for b, f in zip(RK4_B, F))
    data.time += h


def runs(dt=5e-3):
    """The four-bar under RK4 at ``dt`` by each of ``MODES``: ``{mode: (crank angle error max (rad) against the
    closed form, loop residual max (m), crank angle at each sample (rad))}``, with this interpreter's MuJoCo."""
    import mujoco
    import numpy as np

    from dalembert.adapters import get_adapter
    from dalembert.case import make_case
    from dalembert.settings import Settings

    case = make_case("four_bar")
    prepared = get_adapter("mujoco").prepare(case.scene, case.times, Settings("rk4", dt=dt))
    model, per = prepared.model, int(round((case.times[1] - case.times[0]) / dt))
    truth = case.exact(case.times).joints["crank"].q[:, 0]
    out = {}
    for mode in MODES:
        data = mujoco.MjData(model)
        data.qpos[:], data.qvel[:] = prepared.qpos0, prepared.qvel0
        crank, residual = [data.qpos[0]], 0.0
        for k in range(per * (len(case.times) - 1)):
            mujoco.mj_step(model, data) if mode == "mj_step" else rk4_step(model, data, mode)
            if (k + 1) % per == 0:
                crank.append(data.qpos[0])
                mujoco.mj_fwdPosition(model, data)
                residual = max(residual, float(np.abs(data.efc_pos[:data.ne]).max()))
        crank = np.array(crank)
        out[mode] = (float(np.abs(crank - truth).max()), residual, crank.tolist())
    return out


def in_environment(version, dt=5e-3):
    """``runs(dt)`` in the environment of ``mujoco==version`` (made: ``dalembert env create``), with ``version``:
    the MuJoCo that ran (dict)."""
    from dalembert.environments import require
    from dalembert.harness import boot

    env = require(f"mujoco=={version}")
    done = subprocess.run([env.python, os.path.abspath(__file__), "--inside", json.dumps(boot.code()), "--dt",
                           repr(dt)], capture_output=True, text=True, check=True)
    return json.loads(done.stdout.splitlines()[-1])


def main(argv=None):
    parser = argparse.ArgumentParser(description="MuJoCo's four-bar under RK4 with 3.6.0's and 3.7.0's rule")
    parser.add_argument("versions", nargs="*", default=["3.6.0", "3.7.0"])
    parser.add_argument("--dt", type=float, default=5e-3)
    parser.add_argument("--inside", help=argparse.SUPPRESS)  # (in an environment: the starting process's code)
    args = parser.parse_args(argv)
    if args.inside:
        sys.path.insert(0, os.path.join(json.loads(args.inside)["packages"]["dalembert"], "harness"))
        import boot

        boot._install(json.loads(args.inside))
        import mujoco

        print(json.dumps({"version": mujoco.__version__, **runs(args.dt)}))
        return 0
    for version in args.versions:
        result = in_environment(version, args.dt)
        for mode in MODES:
            err, residual, _ = result[mode]
            print(f"MuJoCo {result['version']:<7} dt {args.dt:g}  {mode:<8} crank angle error max {err:.3e} rad, "
                  f"loop residual max {residual:.3e} m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
