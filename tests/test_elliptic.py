"""Jacobi elliptic functions against mpmath at 40 digits."""

import mpmath as mp
import numpy as np
import pytest

from dalembert.reference.closed_form.elliptic import ellipj, ellipk, inverse_amplitude

# Absolute error bound of sn, cn, dn for m1 >= 1e-9 (measured <= 1e-15 for |u| <= 2K;
# worst near u = K/2 where asin is ill-conditioned) ...
ELLIPJ_ABS = 5e-15
# ... plus the error of the argument itself: u is known to half an ulp, ~eps |u|,
# and |d sn/du| <= 1 (likewise cn, and dn up to a factor m <= 1).
ARG_ULPS = 4.0


@pytest.mark.parametrize("m1", [1.0, 0.7, 0.3, 1e-3, 8e-8, 1e-9])
def test_ellipj_against_mpmath(m1):
    K = ellipk(m1)
    with mp.workdps(40):
        m = 1 - mp.mpf(m1)
        assert abs(K - mp.ellipk(m)) < 4e-16 * K
        for u in np.linspace(-3 * K, 7 * K, 23):
            sn, cn, dn = (x[0] for x in ellipj(np.array([u]), m1))
            bound = ELLIPJ_ABS + ARG_ULPS * np.finfo(float).eps * abs(u)
            assert abs(sn - mp.ellipfun("sn", u, m=m)) < bound
            assert abs(cn - mp.ellipfun("cn", u, m=m)) < bound
            assert abs(dn - mp.ellipfun("dn", u, m=m)) < bound


def test_special_values():
    assert ellipk(1.0) == pytest.approx(np.pi / 2, rel=1e-16)
    sn, cn, dn = ellipj(np.array([ellipk(0.25)]), 0.25)
    assert sn[0] == pytest.approx(1.0, abs=1e-15) and abs(cn[0]) < 1e-15 and dn[0] == pytest.approx(0.5, rel=1e-15)
    # m = 0: trigonometric; m = 1: hyperbolic (A&S 16.6)
    u = np.linspace(-3, 3, 7)
    assert np.allclose(ellipj(u, 1.0), (np.sin(u), np.cos(u), np.ones_like(u)), atol=1e-16)
    assert np.allclose(ellipj(u, 0.0), (np.tanh(u), 1 / np.cosh(u), 1 / np.cosh(u)), atol=1e-16)


@pytest.mark.parametrize("m1", [0.5, 1e-3, 8e-8])
def test_inverse_amplitude(m1):
    K = ellipk(m1)
    u = np.linspace(-1.95 * K, 1.95 * K, 13)
    sn, cn, _ = ellipj(u, m1)
    back = np.array([inverse_amplitude(s, c, m1) for s, c in zip(sn, cn)])
    # the inverse is ill-conditioned where sn' = cn dn is small; 1e-12 covers it here
    assert np.max(np.abs(back - u)) < 1e-12 * K
    with pytest.raises(ValueError):
        inverse_amplitude(0.5, -0.5, 0.0)
