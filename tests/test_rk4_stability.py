"""The reference's RK4 finite boundary against the linear stability analysis of RK4, on the
case where that analysis is exact: the axisymmetric torque-free top."""

import math

from dalembert.boundary import boundaries
from dalembert.harness.cli import main
from dalembert.store import Store

# RK4's stability interval on the imaginary axis: |R(iy)|^2 = 1 - y^6/72 + y^8/576 <= 1 iff |y| <= 2 sqrt 2
# (Hairer & Wanner, Solving ODEs II, IV.2).
RK4_IMAGINARY_LIMIT = 2.0 * math.sqrt(2.0)
# "Finite" fails only on a non-finite state, so just past the limit the unstable mode must first grow
# (by |R(iy)| ~ 1 + 2.51 (y - 2 sqrt 2) per step) until the state overflows: the measured boundary
# lies above 2 sqrt 2 by a margin that shrinks with the number of steps (0.3-1.0% at 141 steps, at
# most 0.21% at the 442 here, at most 0.16% at 707). 1% is five times the overshoot at 442 steps
# and equal to the search's resolution; a boundary set by any other eigenvalue would be far off
# (the quaternion kinematics' +-i|w|/2 alone would put it at 4 sqrt 2).
HORIZON_MARGIN = 0.01


def test_rk4_finite_boundary_is_the_linear_one_on_the_axisymmetric_top(tmp_path):
    """Moments (1, 1, 2): Euler's equations are exactly linear, w3 = W constant and (w1, w2)
    rotating at lambda = +-i (I3 - I1)/I1 W = +-i W, so RK4 keeps them bounded iff W dt <= 2 sqrt 2.
    t_final 250 s (442 steps at the boundary) is beyond the horizons whose extended-precision floor
    is computed; one sample interval lets every dt = 250/n be probed."""
    W, out = 5.0, tmp_path / "r"
    predicted = RK4_IMAGINARY_LIMIT / W
    assert main(["run", "--case", "free_top", "--param", "inertia=1,1,2", "--param", f"omega0=0.1,0,{W:g}",
                 "--param", "t_final=250", "--param", "sample_interval=250", "--engine", "reference",
                 "--integrator", "rk4", "--search", "dt", "--dt", "0.5,0.625", "--resolution", "1.01",
                 "--jobs", "1", "--quick", "--out", str(out)]) == 0
    (b,) = boundaries(Store(out).records())
    assert b.finite.monotone and b.finite.ratio <= 1.01
    assert b.finite.failed > predicted  # below the limit every mode contracts: nothing can blow up
    assert b.finite.passed < predicted * (1 + HORIZON_MARGIN)
