"""The adapter's stepping beside a bare engine loop: the table ``benchmarks.mujoco`` and
``benchmarks.drake`` print (what the adapter's per-sample work adds to the engine's cost)."""

from __future__ import annotations

import numpy as np

from dalembert import Settings


def adapter_against_bare(adapter, cases, integrators, bare, dt=1e-3, repeats=5, bare_label="bare"):
    """Print, per case and integrator at ``dt``, the adapter's stepping time per simulated second
    (``Outcome.wall_s``) and ``bare(prepared)``'s (a bare engine loop on the same prepared model,
    returning its wall time, s), each the median of ``repeats`` runs after a warm-up, and their
    ratio; returns the ratios."""
    print(f"{'case':<24}{'integrator':<16}{'adapter':>10}{bare_label:>10}{'ratio':>8}")
    ratios = []
    for case in cases:
        for integ in integrators:
            prepared = adapter.prepare(case.scene, case.times, Settings(integ, dt=dt))
            adapter.run(prepared)
            bare(prepared)
            ours = np.median([adapter.run(prepared).wall_s for _ in range(repeats)])
            theirs = np.median([bare(prepared) for _ in range(repeats)])
            ratios.append(ours / theirs)
            print(f"{case.name:<24}{integ:<16}{1e3 * ours / case.t_final:>10.2f}{1e3 * theirs / case.t_final:>10.2f}"
                  f"{ours / theirs:>8.2f}", flush=True)
    print(f"overhead ratio: median {np.median(ratios):.2f}, max {np.max(ratios):.2f} (goal <= 1.2)")
    return ratios
