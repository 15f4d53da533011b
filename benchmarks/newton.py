"""Newton on Warp's CPU backend: what the adapter's stepping costs against bare Newton, and each solver family's
accuracy against the truth beside the float32 floor.

    python -m benchmarks.newton                         # both parts, 0.2 s of each canonical case Newton runs
    python -m benchmarks.newton cost                    # part 1 only (also: accuracy)
    python -m benchmarks.newton --seconds 1             # the cases' first second
    python -m benchmarks.newton --family featherstone   # one family (repeatable; default all)

1. Cost, per canonical case Newton supports and family at dt = 1e-3: the first step's kernel compilation or cache
   load (build), the adapter's stepping per simulated second (``Outcome.wall_s``: loads into ``body_f``,
   ``solver.step``, a host copy per sample) against a bare loop of ``solver.step`` over the same steps on the
   same model and solver (no loads, no sampling), each the median of 3 runs after a warm-up.
2. Accuracy, the same runs: the largest attitude error (rad) and position error (m) against the case's truth
   over the span, beside the float32 floor of the torque-free tops (RK4 in float32 against itself in double:
   ``mjx.parity.float32_floor``; NaN for the other cases), and whether the run diverged.

Every step launches its kernels one by one from Python (no CUDA graphs on the CPU), so the cost is Python's
launch overhead more than arithmetic; the figures scale with how busy the machine is.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from dalembert import Settings, spatial
from dalembert.adapters import get_adapter
from dalembert.case import load_cases

REPEATS = 3
DT = 1e-3
SECONDS = 0.2  # model time per case (``--seconds``): VBD costs ~10-30 ms a step here
FAMILIES = ()  # (``--family``; empty: every family)


def cases():
    """The canonical cases Newton supports."""
    adapter = get_adapter("newton")
    out = []
    for _, f in load_cases().items():
        if "canonical" in f.tags:
            case = f()
            if adapter.unsupported(case.scene, Settings("featherstone", dt=DT)) is None:
                out.append(case)
    return out


def span(case):
    """The case's samples within its first ``SECONDS`` (s)."""
    t = np.asarray(case.times, dtype=float)
    return t[t <= t[0] + SECONDS + 1e-12]


def families():
    return FAMILIES or tuple(get_adapter("newton").integrators)


def bare_loop(prepared):
    """All the run's steps as ``solver.step`` calls between two states, no loads, no sampling (median, s)."""
    from dalembert.adapters.newton.engine import DEVICE, engine
    from dalembert.adapters.newton.stepping import fresh_states

    wp, _, _ = engine()
    p, n, walls = prepared, int(prepared.steps.sum()), []
    control = p.model.model.control()
    for _ in range(REPEATS):
        a, b = fresh_states(p.model)
        with wp.ScopedDevice(DEVICE):
            t0 = time.perf_counter()
            for _ in range(n):
                p.solver.step(a, b, control, None, DT)
                a, b = b, a
            wp.synchronize_device(DEVICE)
            walls.append(time.perf_counter() - t0)
    return float(np.median(walls))


def _errors(case, traj, times):
    truth = case.exact(times) if case.exact is not None else None
    if truth is None:
        return float("nan"), float("nan")
    att = max(float(np.nanmax(spatial.rotation_angle(traj.bodies[n].quaternion, truth.bodies[n].quaternion)))
              for n in truth.bodies)
    pos = max(float(np.nanmax(np.abs(traj.bodies[n].position - truth.bodies[n].position))) for n in truth.bodies)
    return att, pos


def cost(accuracy=False, timing=True):
    adapter = get_adapter("newton")
    print(f"Newton {adapter.version()} (float32, CPU), dt = {DT:g}, first {SECONDS:g} s; kernel compile or cache "
          "load (s), stepping per simulated second (s)")
    print(f"{'case':<24}{'family':<15}{'compile':>9}" + (f"{'adapter':>10}{'bare':>10}{'ratio':>7}" if timing else "")
          + (f"{'attitude':>10}{'position':>10}{'f32 floor':>10}  diverged" if accuracy else ""))
    for case in cases():
        times = span(case)
        per_s = 1.0 / (times[-1] - times[0])
        for family in families():
            p = adapter.prepare(case.scene, times, Settings(family, dt=DT))
            out = adapter.run(p)
            row = f"{case.name:<24}{family:<15}{p.compile_s:>9.2f}"
            if timing:
                ours = np.median([adapter.run(p).wall_s for _ in range(REPEATS)])
                theirs = bare_loop(p)
                row += f"{ours * per_s:>10.2f}{theirs * per_s:>10.2f}{ours / theirs:>7.2f}"
            if accuracy:
                att, pos = _errors(case, out.trajectory, times)
                floor = adapter.audit(p, out).get("float32_floor", float("nan"))
                row += f"{att:>10.1e}{pos:>10.1e}{floor:>10.1e}  {bool(out.info.get('message'))}"
            print(row, flush=True)


def main(argv):
    global SECONDS, FAMILIES
    while "--family" in argv:
        i = argv.index("--family")
        FAMILIES = (*FAMILIES, argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if "--seconds" in argv:
        i = argv.index("--seconds")
        SECONDS = float(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    parts = argv or ["cost", "accuracy"]
    cost(accuracy="accuracy" in parts, timing="cost" in parts)


if __name__ == "__main__":
    main(sys.argv[1:])
