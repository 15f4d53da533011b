"""CPU time of one evaluation of the reference solver's right-hand side (Kane's formulation, ``reference.generalized``;
with loops, ``reference.loops``), per registered case, and of each Kane truth.

    python -m benchmarks.reference_rhs [--truths] [--repeats 3] [--case NAME ...]

Each case's scene is built as the truth builds it (``FORMULATIONS["kane"]``: ``Kane``, or ``ClosedLoops`` for a
scene with loops) and its ``acceleration`` evaluated at the initial state with every speed raised by 0.1 (so that
no velocity term is a product with zero), N times in a row; the figure is the least CPU time
(``time.process_time``) over ``--repeats`` such batches, divided by N: the cost of the Python and numpy work
itself, whatever else the machine is doing. Contact scenes are left out (the reference integrates no contact).
``--truths`` adds each case whose truth Kane integrates (no closed form, no planar formulation): the integration
and read-back of ``reference.truth``, least CPU time over the repeats.

The numbers are this machine's; compare two versions within one invocation each, alternated, never with a
number measured on another day.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from dalembert.case import load_cases, make_case
from dalembert.reference import solver

# Evaluations per batch: the small scenes take ~50 us each, the loops and large trees up to ~1 ms.
EVALUATIONS = {"small": 1000, "large": 200}


def least_cpu(fn, repeats):
    """The least CPU time (s) of ``repeats`` calls of ``fn``."""
    best = np.inf
    for _ in range(repeats):
        start = time.process_time()
        fn()
        best = min(best, time.process_time() - start)
    return best


def rhs_seconds(system, repeats):
    """CPU seconds per ``acceleration`` of ``system`` at its initial state, speeds raised by 0.1."""
    q, u = system.q0, system.v0 + 0.1
    n = EVALUATIONS["large" if getattr(system, "loops", None) or len(system.joints) > 10 else "small"]

    def batch():
        for _ in range(n):
            system.acceleration(0.0, q, u)

    return least_cpu(batch, repeats) / n


def truth_seconds(case, repeats):
    """CPU seconds of the case's truth by Kane: its integration and read-back (``reference.simulate``)."""
    return least_cpu(lambda: solver.simulate(case.scene, case.times, solver.truth_settings(case.scene)), repeats)


def kane_truth(case):
    """Whether the case's truth is Kane's integration (no closed form, not the planar formulation)."""
    settings = solver.truth_settings(case.scene)
    return (case.exact is None and "formulation" not in settings.options
            and solver.default_formulation(case.scene) == "kane")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--truths", action="store_true", help="time each Kane truth too")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--case", action="append", help="only these cases (repeatable)")
    args = parser.parse_args(argv)
    names = args.case or sorted(load_cases())
    total = 0.0
    for name in names:
        case = make_case(name)
        if case.scene.contacts:
            continue
        system = solver.FORMULATIONS["kane"](case.scene)
        rhs = rhs_seconds(system, args.repeats)
        line = f"{name:26s} bodies {len(system.joints):3d}  nv {system.nv:3d}  rhs {1e6 * rhs:8.1f} us"
        if args.truths and kane_truth(case):
            seconds = truth_seconds(case, args.repeats)
            total += seconds
            line += f"  truth {seconds:7.3f} s"
        print(line, flush=True)
    if args.truths:
        print(f"Kane truths in all: {total:.2f} CPU s")


if __name__ == "__main__":
    main()
