"""Helpers shared by the case modules."""

from __future__ import annotations

import numpy as np

from dalembert.scene import SceneError

# Every sample costs ~100 bytes per body in every trajectory held and stored (13 doubles of
# state, more for joints): 1e7 samples are ~1 GB per body; beyond, refuse before allocating.
MAX_SAMPLES = 10_000_000


def sample_times(t_final, sample_interval, case_name):
    """``0, h, 2h, ..., t_final``: ndarray (n+1,), s. ``t_final`` must be a multiple of ``h``."""
    problems = []
    if not (np.isfinite(t_final) and t_final > 0):
        problems.append(f"t_final: must be a positive duration (s), got {t_final!r}")
    if not (np.isfinite(sample_interval) and sample_interval > 0):
        problems.append(f"sample_interval: must be positive (s), got {sample_interval!r}")
    if problems:
        raise SceneError(f"case {case_name!r}", problems)
    if t_final / sample_interval > MAX_SAMPLES:
        raise SceneError(f"case {case_name!r}", [
            f"t_final: {t_final!r} s sampled every {sample_interval!r} s is {t_final / sample_interval:.3g} samples, "
            f"more than {MAX_SAMPLES:.0e} (~1 GB per body) — shorten t_final or raise sample_interval"])
    n = int(round(t_final / sample_interval))
    if n < 1 or abs(n * sample_interval - t_final) > 1e-9 * t_final:
        raise SceneError(f"case {case_name!r}", [
            f"sample_interval: {sample_interval!r} s does not divide t_final = {t_final!r} s — "
            "choose t_final as a multiple of it"])
    return np.linspace(0.0, t_final, n + 1)
