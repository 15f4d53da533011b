"""The roundoff floor (reference/roundoff.py) against truths that do not come from it.

The floor is the attitude difference between classical RK4 in double and the same RK4 in
extended precision. It is the roundoff of double arithmetic on the motion if

* the extended run is RK4 on the right equations: it converges to the closed form
  (``TorqueFreeTop``, checked in test_closed_forms.py against a 40-digit Taylor integration) at
  fourth order. The truncation error, the same in both runs, then cancels in their difference,
  and what is left is arithmetic;
* that difference scales with the unit roundoff of the arithmetic: float32 against double must
  give 2^29 (eps32 / eps64) times what double against extended gives. A floor that were
  truncation, or a difference between the equations of the two runs, would not scale with it
  (such a difference shows once it exceeds the roundoff: 1e-11 relative in one moment of inertia
  of the double runs moves the ratio to 0.03 times 2^29).

Not asserted, because a single run does not obey them closely enough to separate them from
other laws: the t^(3/2) growth of roundoff in the phase of an integrable motion (Brouwer's law,
D. Brouwer, "On the accumulation of errors in numerical integration", Astron. J. 46, 149
(1937)), seen at dt = 1e-3 on the stable top but not at 1e-2;
and exponential growth at the intermediate axis's rate before the first flip, which roundoff
does not excite: its rounding in the small components is relative to their own size, so the
error grows no faster than the deviation it rides on, and the phase error about the spin axis
dominates.

``case.floor()`` (the larger of this roundoff and the closed form's own sensitivity) is checked
against a lower bound from the time-scaling symmetry of Euler's equations, not against the
functions it calls.
"""

import numpy as np
import pytest

from dalembert import make_case, spatial
from dalembert.cases.free_top import FLOOR_DT
from dalembert.reference.closed_form import TorqueFreeTop
from dalembert.reference.roundoff import EXTENDED, rk4_top, top_roundoff
from bounds import ORDER_SLACK  # the twin's observed order from dt = 1e-2 to 1e-3: 3.89 to 4.10

pytestmark = pytest.mark.skipif(EXTENDED is None, reason="this platform's longdouble is plain double")

# Unit roundoffs: eps(float32) / eps(float64) = 2^-23 / 2^-52 = 2^29.
UNIT_RATIO = np.finfo(np.float32).eps / np.finfo(np.float64).eps
# One floor is one sample of a sum of ~1e4 roundings, each a different fraction of an ulp in
# each precision, so two precisions' floors are in the ratio of their units only to within a
# random factor: measured 0.15 to 3.6 times 2^29 over both canonical tops, horizons 0.5 to 20 s
# and dt = 1e-2 and 1e-3. Within 10x of 2^29 (5e8) still tells roundoff (which scales) from
# truncation or a wrong equation (which would not: ratio ~1).
SCALING_FACTOR = 10.0
# The horizon of the scaling test: short, so that the float32 error (~1e-5 rad) stays small and
# the error stays linear in the roundings (the regime in which it is proportional to eps).
SHORT = 2.0


def _top(case):
    body = case.scene.bodies[0]
    return np.diag(body.inertia_matrix), np.array(case.scene.joint(body.name).v0[3:])


def test_the_extended_twin_is_fourth_order_rk4_towards_the_closed_form():
    """The extended run at the floor's step and at twice it, against the closed form on the
    intermediate-axis top over 20 s (flips included): the error falls as dt^4 (measured 8.0e-10
    and 4.7e-11 rad, order 4.10). An error in the twin's equations or tableau would stall or
    converge at a lower order; its own roundoff (eps 1.1e-19) is far below both."""
    case = make_case("free_top_intermediate")
    truth = case.exact(case.times).bodies["top"].quaternion
    err = {}
    for dt in (2 * FLOOR_DT, FLOOR_DT):
        q = rk4_top(*_top(case), case.times, dt, EXTENDED).astype(float)
        err[dt] = float(np.max(spatial.rotation_angle(truth, q)))
    assert np.log2(err[2 * FLOOR_DT] / err[FLOOR_DT]) == pytest.approx(4.0, abs=ORDER_SLACK), err


@pytest.mark.parametrize("name", ["free_top", "free_top_intermediate"])
def test_the_floor_scales_with_the_unit_roundoff(name):
    """float32 against double (as its extended twin) over double against extended, at the floor's
    step over SHORT: 2^29 (measured 1.25 and 2.21 times 2^29 on the stable and intermediate-axis
    tops; floors 2.2e-14 and 1.9e-14 rad in double, 1.4e-5 and 2.3e-5 rad in float32)."""
    case = make_case(name, t_final=SHORT)
    double = top_roundoff(*_top(case), case.times, FLOOR_DT)
    single = top_roundoff(*_top(case), case.times, FLOOR_DT, working=np.float32, extended=float)
    assert 0.0 < double and np.isfinite(single)
    assert 1.0 / SCALING_FACTOR < single / double / UNIT_RATIO < SCALING_FACTOR, (double, single)


@pytest.mark.parametrize("name", ["free_top_fast_spin", "free_top_long_horizon"])
def test_the_case_floor_is_above_the_phase_of_a_rate_known_to_one_rounding(name):
    """The right-hand side of Euler's equations (Landau & Lifshitz, Mechanics, section 36) is
    quadratic in w and that of q' = q w / 2 linear, so scaling the initial rate by 1 + eps runs the
    same motion 1 + eps times faster: w(t; (1 + eps) w0) = (1 + eps) w((1 + eps) t; w0) and
    q(t; (1 + eps) w0) = q((1 + eps) t; w0). The attitudes q(t) and
    q((1 + eps) t) of the closed form then differ by what one rounding of the rate costs the phase.
    The floor moves each component of w0 by two units of roundoff of |w0| (case FLOOR_ULPS), and
    a unit vector has a component of at least 1/sqrt(3), so to first order its spread is at least
    2/sqrt(3) times this; where roundoff dominates (the fast spin, 7.7e-5 rad) far more. Covers
    both branches: the fast spin's floor is measured roundoff, the long horizon's (1e6 steps) is
    the closed form's sensitivity alone (measured 4.4e-11 rad, 3.0 times the bound)."""
    case = make_case(name)
    floor = case.floor()["orientation"]
    body = case.scene.bodies[0]
    top = TorqueFreeTop(body.inertia_matrix, np.array(case.scene.joint(body.name).v0[3:]))
    t = case.times
    rescaled = float(np.max(spatial.rotation_angle(top.quaternion(t), top.quaternion((1 + np.finfo(float).eps) * t))))
    assert np.isfinite(floor) and floor >= rescaled > 0.0, (floor, rescaled)
