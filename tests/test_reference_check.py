"""The contract's closed-form check gets the reference through a closed loop's singular positions."""

import numpy as np

from dalembert.case import CASES, load_cases
from truths import shared_reference

load_cases()

# The reference against n_four_bar's closed form through its flat position (0.714 s), rad: DOP853 at
# either of the check's tolerances lands ~4e-14 from it (testing.SINGULAR_RTOL's measurement), 1e-11
# leaves room for roundoff across library versions.
THROUGH_FLAT_TOL = 1e-11


def test_the_reference_passes_n_four_bars_flat_position(shared_dir):
    case = CASES["n_four_bar"]()
    label, traj = shared_reference(case, shared_dir)  # the case contract's independent solution, computed once
    exact = case.exact(case.times)
    q, q_exact = traj.joints["rocker0"].q[:, 0], exact.joints["rocker0"].q[:, 0]
    assert np.isfinite(q).all(), label
    assert case.times[-1] > 0.72  # past the flat instant
    assert np.max(np.abs(q - q_exact)) < THROUGH_FLAT_TOL, label
