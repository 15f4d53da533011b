"""``dalembert repro``: one stored run as a standalone script that reproduces its headline error.

The script does not import dalembert: it needs the engine and numpy only, so a finding goes upstream as a
reproduction anyone can run. It holds the engine's part (``Adapter.repro``: the model as the engine's own
input, the run's settings, the stepping loop in the engine's API), the stored truth at a few samples and
the error the run stored; it computes its own error on those samples, prints both, and exits 1 when they
differ by more than ``REPRO_REL_TOL`` relative (0 when they agree).

Which figure: the run's headline error (``reports.work_precision.headline_quantity``: the joint angle for
jointed cases, else the orientation), its maximum over the horizon as the record stores it
(``dalembert.errors.error_series``). The samples embedded are ``SPREAD`` spread over the horizon plus the one
where the stored run's error is largest, so the maximum over them is the stored maximum; the script computes
the error with the harness's arithmetic (``error_series``: the largest over joints of ``|q - q_true|``; the
geodesic angle ``2 atan2(|vec(q1* q2)|, |scalar(q1* q2)|)`` of the normalized quaternions).

What each engine's part covers, and why not the rest, is in its module (``adapters/<engine>/repro.py``).
Measured on every finished run of ``dalembert run --tag canonical --engine mujoco --engine pinocchio --engine
exudyn --dt 1e-2,1e-3 --param t_final=0.5`` and of ``--tag contact --tag variant --tag hard --dt 1e-3 --rtol 1e-6
--param t_final=0.3``: every script written (MuJoCo 176 runs, Pinocchio 124, Exudyn 334) reproduced its stored
error bit for bit (the maximum printed equal to the stored one), run where dalembert cannot be imported.
"""

from __future__ import annotations

import inspect
import math
import re
import sys
import textwrap

import numpy as np

from dalembert import rotations
from dalembert.harness.commands.console import fail

__all__ = ["REPRO_REL_TOL", "SPREAD", "write", "run", "main"]

# The script's error must equal the stored one to this relative accuracy: the engine repeats its arithmetic
# bit for bit on one machine (the contract's repeated runs), so what is left is the last bits of an error
# that is itself a difference of nearby numbers (a 2.8e-9 rad error of a unit quaternion moves by ~1e-16 per
# ulp of it: 4e-8 relative); 1e-9 is the bar: any real change of the engine shows far above it.
REPRO_REL_TOL = 1e-9
# Samples embedded besides the one of the largest error: first, last and evenly between (a few KB of truth).
SPREAD = 6
# The quantities a script can reproduce, and what the truth holds of each.
QUANTITIES = {"joint": "each revolute or prismatic joint's coordinate q, by joint (child) name",
              "orientation": "each body's attitude q_WB, a unit quaternion (w, x, y, z) turning body axes to world"}

_ERRORS = {
    "joint": '''def error(values, truth):
    """The largest |q - q_true| over the joints, per sample: as the harness measures joints."""
    return np.max([np.abs(values[name][:, 0] - np.asarray(truth[name])) for name in truth], axis=0)
''',
    # the harness's own conversions, as source: the script measures exactly as the harness does
    "orientation": "\n\n".join(inspect.getsource(f) for f in (
        rotations.quat_multiply, rotations.quat_conjugate, rotations.quat_normalize, rotations.rotation_angle,
        rotations.matrix_to_quat)) + '''

def error(values, truth):
    """The largest geodesic angle over the bodies, per sample (rad): as the harness measures orientations (an
    attitude the engine gives as a matrix, (m, 3, 3), is turned into a quaternion first)."""
    quats = {name: matrix_to_quat(q) if q.shape[1:] == (3, 3) else q for name, q in values.items()}
    return np.max([rotation_angle(quats[name], np.asarray(truth[name])) for name in truth], axis=0)
''',
}


def _times_source(times):
    """``TIMES`` as source: exactly ``interval * arange(n)`` where that is what they are, else every number."""
    n, interval = len(times), float(times[1] - times[0])
    if np.array_equal(interval * np.arange(n), times):
        return f"{interval!r} * np.arange({n})  # s, every {interval:g} s"
    return f"np.array({np.asarray(times).tolist()!r})  # s"


def _samples(series):
    """Indices embedded: ``SPREAD`` evenly from first to last, and the largest error's."""
    n = len(series)
    return sorted({int(i) for i in np.linspace(0, n - 1, min(SPREAD, n)).round()} | {int(np.argmax(series))})


def write(store, key):
    """The reproduction script of run ``key`` of ``store`` (a ``dalembert.store.Store``), as text.

    Raises ValueError "where: what — fix" for a key the store does not hold (with the closest keys), a run
    with no finite stored error, or a run its engine's repro does not cover (``Adapter.repro``)."""
    import difflib

    from dalembert.adapters import get_adapter
    from dalembert.errors import error_series
    from dalembert.reports.work_precision import headline_quantity

    records = {r.key: r for r in store.records()}
    if key not in records:
        close = difflib.get_close_matches(key, sorted(records), n=3, cutoff=0.5)
        hint = f"did you mean {' or '.join(close)}?" if close else "the report's run tables and runs.parquet list them"
        raise ValueError(f"--key: no run {key!r} in {store.path} — {hint}")
    r = records[key]
    quantity = headline_quantity([r])
    stored = r.max_error(quantity) if quantity else math.nan
    if r.status == "ok" and not (r.trajectory and store.has_trajectory(key)) and store.kept().keep != "all":
        raise ValueError(f"--key: {store.kept().not_kept(key)}")  # (a repro compares with the stored trajectory)
    if r.status != "ok" or not r.trajectory or not math.isfinite(stored):
        raise ValueError(f"--key: run {key} is {r.status} with no finite stored error "
                         f"({r.message or 'nothing measured'}) — reproduce a run that finished")
    if quantity not in QUANTITIES:
        raise ValueError(f"--key: run {key}'s headline error is {quantity}, which a repro does not compute — "
                         f"it reproduces {', '.join(QUANTITIES)}")
    case = store.case(r.case, r.case_version)
    truth = store.truth(r.case, r.case_version)
    traj = store.trajectory(key)
    series = error_series(traj, truth)[quantity]
    if not float(np.max(series)) == stored:  # the store's own figure, from its own trajectory
        raise ValueError(f"{store.path}: run {key}'s stored {quantity} error {stored!r} is not that of its stored "
                         f"trajectory ({float(np.max(series))!r}) — the store was edited or damaged")
    engine = get_adapter(r.engine).repro(case.scene, truth.t, r.settings, quantity)
    picks = _samples(series)
    if quantity == "joint":
        names = [n for n, j in truth.joints.items() if j.q.shape[1] == 1 and n in traj.joints]
        kinds = {case.scene.joint(n).kind for n in names}
        unit = "rad" if kinds == {"revolute"} else "m" if kinds == {"prismatic"} else "rad (revolute) or m (prismatic)"
        embedded = {n: truth.joints[n].q[picks, 0] for n in names}
    else:
        unit, embedded = "rad", {n: truth.bodies[n].quaternion[picks] for n in truth.bodies}
    # what the script imports: numpy, and the engine part's top-level imports
    needs = sorted({"numpy"} | set(re.findall(r"^(?:from|import) (\w+)", engine, re.M)))
    needs = [", ".join(needs[:-1]), needs[-1]] if len(needs) > 1 else needs
    peak = int(np.argmax(series))
    loop = (r.audit or {}).get("loop")  # Pinocchio's: which stepping loop the run took
    paragraphs = [
        f"Run {key} of the store {store.path}: the case {r.case} (version {r.case_version}, parameters "
        f"{dict(r.params) or 'its defaults'}) stepped by {r.engine} {r.engine_version} with {r.settings.label()}"
        + (f" ({loop})" if loop else "") + f", against the case's truth ({case.truth}).",
        f"The figure reproduced: the run's {quantity} error against the truth ({QUANTITIES[quantity]}), its maximum "
        f"over the run's {len(truth.t)} samples, {unit}, as the store holds it: {stored!r}. The truth is embedded at "
        f"{len(picks)} of those samples, one of them the sample where the stored run's error is largest (sample "
        f"{peak}, t = {float(truth.t[peak])!r} s), so the maximum over them is the stored figure. The script steps "
        f"the engine as the run did, computes the same error on those samples, prints it beside the stored one "
        f"sample by sample, and exits 1 when the maxima differ by more than REPRO_REL_TOL relative (0 when they "
        f"agree).",
        f"Needs {' and '.join(needs)} only: python this_file.py. Written by: dalembert repro {store.path} --key {key}",
    ]
    doc = "\n\n".join(textwrap.fill(p, 110) for p in paragraphs)
    rows = "".join(f"    {n!r}: [\n" + "".join(f"        {v.tolist()!r},  # t = {float(truth.t[i])!r} s\n"
                                                for i, v in zip(picks, values)) + "    ],\n"
                   for n, values in embedded.items())
    return f'''"""Reproduction of a stored dalembert run: {r.case} on {r.engine} {r.engine_version}, {r.settings.label()}.

{doc}
"""

import sys

import numpy as np

# The run's sample times.
TIMES = {_times_source(truth.t)}

# ---------------------------------------------------------------- the engine: model, settings, stepping
{engine}
# ---------------------------------------------------------------- the stored truth and the stored error
# The samples embedded (indices into TIMES); the truth there, {unit}: {QUANTITIES[quantity]};
# the stored run's error there, {unit}.
SAMPLES = {picks!r}
TRUTH = {{
{rows}}}
STORED_ERRORS = {series[picks].tolist()!r}
STORED_ERROR = {stored!r}  # {unit}: the {quantity} error's maximum over the run, as the store holds it
STORED_ENGINE_VERSION = {r.engine_version!r}
# The error computed here must equal the stored one to this relative accuracy (the engine repeats its
# arithmetic bit for bit; a real change of it shows far above this).
REPRO_REL_TOL = {REPRO_REL_TOL!r}

{_ERRORS[quantity]}

def main():
    values = simulate()
    mine = error({{name: np.asarray(v)[SAMPLES] for name, v in values.items()}}, TRUTH)
    print(f"{r.engine} {{ENGINE_VERSION}} (the stored run: {{STORED_ENGINE_VERSION}}), {r.case}, {r.settings.label()}")
    print(f"{{'t (s)':<22}}  {{'{quantity} error here':<24}}  stored")
    for i, here, there in zip(SAMPLES, mine, STORED_ERRORS):
        print(f"{{float(TIMES[i])!r:<22}}  {{float(here)!r:<24}}  {{there!r}}")
    peak = float(np.max(mine))
    print(f"{quantity} error, max over the samples: {{peak!r}} {unit} here, {{STORED_ERROR!r}} stored")
    same = abs(peak - STORED_ERROR) <= REPRO_REL_TOL * abs(STORED_ERROR)
    print("reproduced" if same else f"NOT reproduced: relative difference "
          f"{{abs(peak - STORED_ERROR) / abs(STORED_ERROR) if STORED_ERROR else float('inf'):.3e}} > {{REPRO_REL_TOL:g}}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
'''


def run(run_dir, key, out="-"):
    """Write the reproduction of run ``key`` of the store ``run_dir`` to ``out`` (a file; ``-``: standard
    output); returns the exit status: 0, or 2 with a message on a bad input or a run no repro covers."""
    from dalembert import output
    from dalembert.harness.commands.stores import open_store
    from dalembert.terminal import printable

    try:
        output.check(out, "--out")
        output.write(out, write(open_store(run_dir), key), "--out")
    except (ValueError, KeyError, ImportError, OSError) as e:
        return fail(str(e))
    if out != output.STDOUT:
        print(f"wrote {printable(output.shown(out))}: run {printable(key)} (python {printable(out)} reproduces it)")
    return 0


def main(args):
    return run(args.run_dir, args.key, args.out)
