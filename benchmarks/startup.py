"""A fresh interpreter's start, by kind: its CPU and the packages it imports beyond the standard library.

    python -m benchmarks.startup [--repeats 5]

Every command line (``python -m dalembert.harness.cli``), a pool's forkserver, an engine environment's worker
(``harness/boot.py``) and a Dask task's group (``python -m dalembert.harness.batches``) is a fresh interpreter that
imports dalembert before it does anything; the test suite starts over a hundred. A package imported at a module's
top that the start does not use is paid by each: scipy.integrate, at the top of ``invariants`` and
``reference.integrators``, was ~0.3 CPU-s of every start until it moved into the functions that call it.

Prints, per kind, the least CPU (user + system, s, of the process and its children) over ``--repeats`` runs and
the third-party top-level packages it imported, and exits 1 when a start imported one of ``NOT_AT_START``.
Measured on 2 shared cores (no bytecode cache: ``PYTHONDONTWRITEBYTECODE=1``), min of 5: ``import dalembert``
0.52 -> 0.17 CPU-s, ``dalembert --help`` 0.52 -> 0.20, ``dalembert cases`` 0.62 -> 0.29, a worker's start
0.59 -> 0.26 with that move.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys

# Imported where they are used, never by a start: scipy's integrate (the solver's adaptive integrators, the
# invariants' quadratures), special (the elliptic closed forms), linalg (normal modes) and optimize; the reports'
# matplotlib and pandas, the stores' pyarrow; every engine and Dask.
NOT_AT_START = ("scipy.integrate", "scipy.special", "scipy.linalg", "scipy.optimize", "matplotlib", "pandas",
                "pyarrow", "mujoco", "pinocchio", "exudyn", "pydrake", "jax", "warp", "newton", "pybullet", "dartpy",
                "opensim", "dask", "distributed")

# Each start's code; the modules it imported are written to stderr as JSON when it exits.
_REPORT = ("import atexit, json, sys\n"
           "atexit.register(lambda: print(json.dumps(sorted(sys.modules)), file=sys.stderr))\n")
STARTS = {
    "python": "",
    "import dalembert": "import dalembert\n",
    "dalembert --help": ("import runpy, sys\nsys.argv = ['dalembert', '--help']\n"
                         "try:\n    runpy.run_module('dalembert.harness.cli', run_name='__main__')\n"
                         "except SystemExit:\n    pass\n"),
    "dalembert cases": ("import runpy, sys\nsys.argv = ['dalembert', 'cases']\n"
                        "try:\n    runpy.run_module('dalembert.harness.cli', run_name='__main__')\n"
                        "except SystemExit:\n    pass\n"),
    # what harness/boot.py imports before it reads its runs (its ``_install``, then the worker and the groups)
    "worker (boot.py)": ("import dalembert.cases\nfrom dalembert.case_registry import load_modules\n"
                         "from dalembert.harness import batches, worker\nload_modules({})\n"),
}


def _cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def start(code):
    """One fresh interpreter running ``code``: ``(cpu_s, modules)``."""
    before = _cpu()
    done = subprocess.run([sys.executable, "-c", _REPORT + code], capture_output=True, text=True,
                          stdin=subprocess.DEVNULL)
    cpu = _cpu() - before
    if done.returncode != 0:
        raise RuntimeError(f"start failed: {done.stderr[-2000:]}")
    return cpu, json.loads(done.stderr.strip().splitlines()[-1])


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=5, help="runs per kind; the least CPU is shown (default 5)")
    args = p.parse_args(argv)
    cpu = {k: [] for k in STARTS}
    imported = {}
    for _ in range(args.repeats):  # the kinds alternate: a busy moment slows one run of each, not one kind
        for kind, code in STARTS.items():
            seconds, modules = start(code)
            cpu[kind].append(seconds)
            imported[kind] = modules
    stdlib = set(sys.stdlib_module_names)
    bad = False
    print(f"{'start':<20}{'CPU s':>8}  third-party packages imported")
    for kind in STARTS:
        tops = sorted({m.split(".")[0] for m in imported[kind]} - stdlib - {"dalembert"})
        tops = [t for t in tops if not t.startswith("_")]
        wrong = sorted(set(imported[kind]) & set(NOT_AT_START))
        bad = bad or bool(wrong)
        print(f"{kind:<20}{min(cpu[kind]):>8.3f}  {' '.join(tops) or '-'}"
              + (f"   NOT AT START: {' '.join(wrong)}" if wrong else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
