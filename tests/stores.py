"""Small results stores for the report, findings, compare and export tests.

``small_store`` runs a tiny real matrix (seconds). ``seed_store`` runs one real run and
``add_run`` writes further records beside it, made from that run with some fields changed: a store
that shows one hazard at a time, with the real case record, truth and trajectory behind it.
"""

import json
import math
import os
import shutil
from dataclasses import fields, replace

import numpy as np

from dalembert.harness.execute import QUICK
from dalembert.harness.matrix import expand
from dalembert.harness.pool import run_matrix
from dalembert.record import RunRecord
from dalembert.store import Store, trajectory_to_npz
from dalembert.trajectory import BodyStates, Trajectory


def small_store(path, cases=("pivoted_rod", "free_top"), engines=("reference",), integrators=("rk4", "euler"),
                dts=(1e-2, 5e-3), t_final=1.0, options=None):
    specs, _ = expand(cases=list(cases), engines=list(engines), integrators=list(integrators), dts=list(dts),
                      params={"t_final": t_final}, options=options)
    store = Store(path).create({"harness_version": "test", "engines": {e: "test" for e in engines}, "specs": [],
                                "machine": {"cores": 2, "cpu": "test", "host": "test", "os": "test",
                                            "python": "test"}})
    run_matrix(specs, store, jobs=2, timing=QUICK)
    return store


def seed_store(path):
    """One real run: the reference engine's rk4 at dt = 5e-3 on a 1 s free top."""
    return small_store(path, cases=("free_top",), integrators=("rk4",), dts=(5e-3,))


def base(store):
    return store.records()[0]


# The fields of a record's ``settings`` and ``judgement`` (as its row's columns name them), which
# ``changed`` takes flat.
SETTINGS_FIELDS = ("integrator", "dt", "rtol", "atol", "options")
JUDGEMENT_FIELDS = {"beyond": "beyond", "verdict": "verdict", "verdict_reason": "reason",
                    "not_measured": "not_measured",
                    "within_tolerance": "within_tolerance"}


def changed(record, **changes):
    """``replace(record, **changes)``, where the fields of its settings and its judgement may be given
    flat (``dt=...``, ``verdict=...``), as the row's columns name them."""
    settings = {k: changes.pop(k) for k in SETTINGS_FIELDS if k in changes}
    judgement = {JUDGEMENT_FIELDS[k]: changes.pop(k) for k in list(JUDGEMENT_FIELDS) if k in changes}
    if settings:
        changes["settings"] = replace(record.settings, **settings)
    if judgement:
        changes["judgement"] = replace(record.judgement, **judgement)
    return replace(record, **changes)


def add_run(store, key, nan_from=None, **changes):
    """Write a record made from the store's first run with ``changes`` (``changed``'s); its trajectory is
    the first run's, with NaN from ``nan_from`` (s) on when given (a divergence), none when ``status`` is
    not ok and ``nan_from`` is None."""
    first = base(store)
    record = changed(first, key=key, trajectory="", **changes)
    npz = None
    if record.status == "ok" or nan_from is not None:
        traj = store.trajectory(first.key)
        if nan_from is not None:
            bad = traj.t >= nan_from

            def spoil(a):
                a = a.copy()
                a[bad] = np.nan
                return a

            traj = Trajectory(traj.t, {n: BodyStates(spoil(b.position), spoil(b.quaternion), spoil(b.velocity),
                                                     spoil(b.angular_velocity)) for n, b in traj.bodies.items()})
        npz = trajectory_to_npz(traj)
    store.write_record(record, npz)
    return record


def tamper(store, change, index=0):
    """Rewrite the ``index``-th stored run of ``store`` as ``change(record)`` returns it."""
    key = sorted(store.done_keys())[index]
    path = os.path.join(store.rows_dir, f"{key}.json")
    with open(path) as fh:
        record = RunRecord.from_row(json.load(fh))
    with open(path, "w") as fh:
        json.dump(change(record).to_row(), fh)


def segmented(files, path, records=None):
    """A layout-2 store at ``path`` holding ``records`` (default: every run of the store ``files``), written one by
    one, with ``files``' cases, truths and trajectories."""
    store = Store(path).create(files.manifest(), layout=2)
    for d in ("cases", "truth", "trajectories"):
        shutil.copytree(os.path.join(files.path, d), os.path.join(path, d), dirs_exist_ok=True)
    for r in files.records() if records is None else records:
        store.write_record(r)
    return store


def plain(value):
    """``value`` with NaN as None, tuples as lists, dataclasses as dicts, recursively: to compare exactly."""
    if isinstance(value, float) and math.isnan(value):
        return None
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if hasattr(value, "__dataclass_fields__"):
        return {f.name: plain(getattr(value, f.name)) for f in fields(value)}
    return value
