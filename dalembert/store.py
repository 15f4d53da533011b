"""Results store: one directory per matrix run, immutable files, atomic writes.

Layout of a run directory::

    manifest.json          harness version/commit, machine, OS, Python, engine versions,
                           command line, start/end time, and the full list of run specs
    rows/<key>.json        one finished run (written atomically when it ends)
    runs.parquet           all rows as a table (rebuilt from rows/ after every batch)
    trajectories/<key>.npz one trajectory per run that produced one
    truth/<case>__<version>.npz  each case's truth at its sample times (what reports compare with)

Trajectory files (``.npz``) use these array names: ``t`` (n,); per body
``body.<name>.position`` (n,3) COM in world, m; ``body.<name>.quaternion``
(n,4) q_WB scalar first; ``body.<name>.velocity`` (n,3) COM velocity in world,
m/s; ``body.<name>.angular_velocity`` (n,3) w_WB_W, rad/s; optionally
``body.<name>.rotation`` (n,3,3) R_WB when the engine's attitude is a matrix;
per joint ``joint.<name>.q`` (n,nq) and ``joint.<name>.v`` (n,nv); extras as
``extra.<name>`` (e.g. ``extra.reaction_force:rod`` (n,3), N, world).

Every write goes to a temporary file in the same directory, then ``os.replace``:
a reader or an interrupted run never sees half a file. ``resume`` runs only the
specs without a row file.
"""

from __future__ import annotations

import io
import json
import os
import platform
import socket
import subprocess
import sys
import tempfile
from datetime import datetime, timezone

import numpy as np

from dalembert.trajectory import BodyStates, JointStates, Trajectory

__all__ = ["Store", "atomic_write", "trajectory_to_npz", "trajectory_from_npz", "machine_info", "harness_commit"]


def atomic_write(path, data):
    """Write ``data`` (bytes or str) to ``path`` atomically."""
    mode = "wb" if isinstance(data, bytes) else "w"
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=".tmp-", suffix=os.path.basename(path))
    try:
        with os.fdopen(fd, mode) as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def trajectory_to_npz(traj):
    """Serialize a Trajectory to ``.npz`` bytes (array names in the module docstring)."""
    arrays = {"t": traj.t}
    for name, b in traj.bodies.items():
        for f in ("position", "quaternion", "velocity", "angular_velocity"):
            arrays[f"body.{name}.{f}"] = getattr(b, f)
        if b.rotation is not None:
            arrays[f"body.{name}.rotation"] = b.rotation
    for name, j in traj.joints.items():
        arrays[f"joint.{name}.q"], arrays[f"joint.{name}.v"] = j.q, j.v
    for name, x in traj.extras.items():
        arrays[f"extra.{name}"] = x
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    return buf.getvalue()


def trajectory_from_npz(source):
    """Inverse of ``trajectory_to_npz``; ``source`` is a path or bytes."""
    if isinstance(source, bytes):
        source = io.BytesIO(source)
    with np.load(source) as z:
        data = {k: z[k] for k in z.files}
    bodies, joints, extras = {}, {}, {}
    for key in data:
        kind, _, rest = key.partition(".")
        if kind == "body":
            name, field = rest.rsplit(".", 1)
            bodies.setdefault(name, {})[field] = data[key]
        elif kind == "joint":
            name, field = rest.rsplit(".", 1)
            joints.setdefault(name, {})[field] = data[key]
        elif kind == "extra":
            extras[rest] = data[key]
    return Trajectory(data["t"], {n: BodyStates(**f) for n, f in bodies.items()},
                      {n: JointStates(f["q"], f["v"]) for n, f in joints.items()}, extras)


def harness_commit():
    """The git commit of the harness source (with ``-dirty`` if modified), or 'unknown'."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True,
                                timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here,
                               capture_output=True, text=True, timeout=10).stdout.strip()
        return (commit + ("-dirty" if dirty else "")) or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def machine_info():
    """CPU model, cores, OS, Python, host."""
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"cpu": cpu or "unknown", "cores": os.cpu_count(), "os": platform.platform(),
            "python": sys.version.split()[0], "host": socket.gethostname()}


def now():
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


class Store:
    """A results directory (see the module docstring)."""

    def __init__(self, path):
        self.path = os.path.abspath(path)
        self.rows_dir = os.path.join(self.path, "rows")
        self.traj_dir = os.path.join(self.path, "trajectories")

    # -------------------------------------------------------------- create
    def create(self, manifest):
        os.makedirs(self.rows_dir, exist_ok=True)
        os.makedirs(self.traj_dir, exist_ok=True)
        self.write_manifest(manifest)
        return self

    def write_manifest(self, manifest):
        atomic_write(os.path.join(self.path, "manifest.json"), json.dumps(manifest, indent=2, sort_keys=True))

    def manifest(self):
        with open(os.path.join(self.path, "manifest.json")) as fh:
            return json.load(fh)

    def exists(self):
        return os.path.exists(os.path.join(self.path, "manifest.json"))

    # -------------------------------------------------------------- rows
    def write_result(self, row, trajectory_npz=None):
        """Store one finished run: its trajectory (if any), then its row (the commit point)."""
        key = row["key"]
        if trajectory_npz is not None:
            atomic_write(os.path.join(self.traj_dir, f"{key}.npz"), trajectory_npz)
            row = {**row, "trajectory": f"trajectories/{key}.npz"}
        atomic_write(os.path.join(self.rows_dir, f"{key}.json"), json.dumps(row, sort_keys=True, default=_json))

    def done_keys(self):
        if not os.path.isdir(self.rows_dir):
            return set()
        return {f[:-5] for f in os.listdir(self.rows_dir) if f.endswith(".json") and not f.startswith(".tmp-")}

    def rows(self):
        """Every stored row, sorted by key."""
        out = []
        for key in sorted(self.done_keys()):
            with open(os.path.join(self.rows_dir, f"{key}.json")) as fh:
                out.append(json.load(fh))
        return out

    def table(self):
        """All rows as a pandas DataFrame."""
        import pandas as pd

        return pd.DataFrame(self.rows())

    def write_table(self):
        """Rebuild ``runs.parquet`` from the row files (atomically)."""
        df = self.table()
        buf = io.BytesIO()
        df.to_parquet(buf, index=False)
        atomic_write(os.path.join(self.path, "runs.parquet"), buf.getvalue())
        return df

    def trajectory(self, key):
        return trajectory_from_npz(os.path.join(self.traj_dir, f"{key}.npz"))

    # -------------------------------------------------------------- truths
    def truth_path(self, case, version):
        return os.path.join(self.path, "truth", f"{case}__{version}.npz")

    def write_truth(self, case, version, trajectory):
        """Store a case's truth at its sample times (written once per case version)."""
        os.makedirs(os.path.join(self.path, "truth"), exist_ok=True)
        atomic_write(self.truth_path(case, version), trajectory_to_npz(trajectory))

    def truth(self, case, version):
        path = self.truth_path(case, version)
        return trajectory_from_npz(path) if os.path.exists(path) else None


def _json(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.bool_):
        return bool(x)
    raise TypeError(f"not JSON serializable: {type(x).__name__}")
