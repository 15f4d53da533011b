"""Stored trajectories as one long-format table a pandas user picks up.

One row per run, sample time and item, where an item is a body, a joint or a
joint's reaction force (``kind``, ``name``); the run's identity repeats on every
row, so the rows of many runs stack into one frame (``frame``) and filter with
``df[df.engine == "mujoco"]``. Columns:

=================  =============================================================
identity           ``key``, ``case``, ``case_version``, ``params`` (JSON), ``engine``,
                   ``integrator``, ``dt`` (s), ``rtol``, ``atol``, ``options``
                   (``node=ep``; "" for the engine's defaults), ``status``
sample             ``t`` (s), ``kind`` (``body``, ``joint``, ``reaction_force``), ``name``
body               ``x y z`` COM in world (m), ``qw qx qy qz`` q_WB scalar first,
                   ``vx vy vz`` COM velocity in world (m/s), ``wx wy wz`` angular
                   velocity in world (rad/s) — ``dalembert.trajectory.CSV_COLUMNS``
joint              ``q0 q1 ...`` its coordinates, ``v0 v1 ...`` its velocities
                   (``dalembert.scene.Joint`` conventions; a revolute joint: the angle
                   in rad and its rate in rad/s)
reaction_force     ``fx fy fz``: the force the joint exerts on its child, world axes, N
=================  =============================================================

Columns an item does not have are empty (NaN). CSV is written with 17
significant digits (every double round-trips); Parquet keeps the doubles as they are.
The file is the user's: written in place (``dalembert.output``), ``-`` for standard output.
"""

from __future__ import annotations

import io
import json

import numpy as np
import pandas as pd

from dalembert import output
from dalembert.trajectory import CSV_COLUMNS

__all__ = ["BODY_COLUMNS", "FORMATS", "IDENTITY", "select", "trajectory_frame", "frame", "write"]

BODY_COLUMNS = CSV_COLUMNS[2:]  # x ... wz (CSV_COLUMNS starts with t, body)
IDENTITY = ("key", "case", "case_version", "params", "engine", "integrator", "dt", "rtol", "atol", "options", "status")
REACTION = "reaction_force:"  # the prefix of a joint's reaction force among a trajectory's extras


def select(records, keys=(), case=None, engine=None, integrator=None, dt=None, rtol=None, options=None):
    """The records that match every criterion given: run keys (any of them), case, engine,
    integrator, dt, rtol, and engine ``options`` (a dict; each given key must have the given value,
    "" for an option the run did not set)."""
    options = options or {}
    return [r for r in records
            if (not keys or r.key in keys) and (case is None or r.case == case)
            and (engine is None or r.engine == engine) and (integrator is None or r.settings.integrator == integrator)
            and (dt is None or r.settings.dt == dt) and (rtol is None or r.settings.rtol == rtol)
            and all(r.settings.options.get(k, "") == v for k, v in options.items())]


def trajectory_frame(traj):
    """The samples of one ``Trajectory``: columns ``t``, ``kind``, ``name`` and the item's values."""
    parts = []

    def part(kind, name, values):
        block = pd.DataFrame(values)
        block.insert(0, "name", name)
        block.insert(0, "kind", kind)
        block.insert(0, "t", traj.t)
        parts.append(block)

    for name, b in sorted(traj.bodies.items()):
        data = np.hstack([b.position, b.quaternion, b.velocity, b.angular_velocity])
        part("body", name, dict(zip(BODY_COLUMNS, data.T)))
    for name, j in sorted(traj.joints.items()):
        q, v = np.atleast_2d(j.q.T).T, np.atleast_2d(j.v.T).T
        part("joint", name, {**{f"q{i}": q[:, i] for i in range(q.shape[1])},
                             **{f"v{i}": v[:, i] for i in range(v.shape[1])}})
    for key, x in sorted(traj.extras.items()):
        if key.startswith(REACTION):
            part("reaction_force", key[len(REACTION):], dict(zip(("fx", "fy", "fz"), np.asarray(x).T)))
    return pd.concat(parts, ignore_index=True)


def frame(store, records):
    """Every one of ``records`` that left a trajectory the store kept (``Store.has_trajectory``: a store that keeps
    only the drawn ones, or none, leaves the others out), as one long-format frame (the columns above)."""
    frames = []
    keeps_all = store.kept().keep == "all"
    for r in records:
        if not r.trajectory or not (keeps_all or store.has_trajectory(r.key)):
            continue
        f = trajectory_frame(store.trajectory(r.key))
        identity = dict(key=r.key, case=r.case, case_version=r.case_version,
                        params=json.dumps(r.params, sort_keys=True, default=list), engine=r.engine,
                        integrator=r.settings.integrator, dt=r.settings.dt, rtol=r.settings.rtol,
                        atol=r.settings.atol, options=r.options_label,
                        status=r.status)
        for k, (name, value) in enumerate(identity.items()):
            f.insert(k, name, value)
        frames.append(f)
    if not frames:
        return pd.DataFrame(columns=list(IDENTITY) + ["t", "kind", "name"])
    out = pd.concat(frames, ignore_index=True)
    for col in ("dt", "rtol", "atol"):
        out[col] = out[col].astype(float)
    return out


FORMATS = ("csv", "parquet")


def write(df, path, fmt=None):
    """Write ``df`` to ``path`` in place (``dalembert.output.write``; ``-`` is standard output).

    ``fmt``: ``"csv"`` (17 significant digits) or ``"parquet"``; by default Parquet when ``path``
    ends in ``.parquet``, else CSV. An ``OutputError`` naming ``--<fmt>`` when it cannot be written."""
    fmt = fmt or ("parquet" if str(path).endswith(".parquet") else "csv")
    if fmt not in FORMATS:
        raise ValueError(f"fmt: {fmt!r} is not one of {', '.join(FORMATS)} — pick one")
    if fmt == "parquet":
        buf = io.BytesIO()
        df.to_parquet(buf, index=False)
        data = buf.getvalue()
    else:
        data = df.to_csv(index=False, float_format="%.17g")
    output.write(path, data, f"--{fmt}")
