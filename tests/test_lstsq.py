"""``dalembert.lstsq``: many small least-squares systems at once, against numpy's one-by-one solver and closed forms."""

import numpy as np

from dalembert.lstsq import lstsq_stacked

# Two SVD-based solves of the same system (stacked LAPACK gesdd here, numpy's gelsd one by one) agree to roundoff
# of the solution's size: a few ulps times the systems' condition (well-conditioned random systems here).
ROUNDOFF = 1e-13


def test_each_system_gets_numpys_minimum_norm_solution():
    rng = np.random.default_rng(7)
    A = rng.normal(size=(40, 6, 4))
    A[:10, :, 3] = 2.0 * A[:10, :, 1]  # rank 3: the minimum-norm solution splits its share between the two columns
    A[10:12] = 0.0  # nothing to fit: the solution is zero
    A[12:15, :, :] = A[12:15, :, :1] * rng.normal(size=4)  # rank 1
    b = rng.normal(size=(40, 6))
    x = lstsq_stacked(A, b)
    for Ai, bi, xi in zip(A, b, x):
        truth = np.linalg.lstsq(Ai, bi, rcond=None)[0]
        assert np.allclose(xi, truth, rtol=0.0, atol=ROUNDOFF * max(1.0, np.abs(truth).max()))
    assert np.all(x[10:12] == 0.0)


def test_a_cut_below_the_threshold_gives_the_truncated_solution():
    """diag(1, 1e-8) x = (1, 1): with the cut at 1e-6 the small direction carries nothing (x = (1, 0)), with
    numpy's default it carries its exact share (x = (1, 1e8))."""
    A, b = np.diag([1.0, 1e-8])[None], np.ones((1, 2))
    assert np.allclose(lstsq_stacked(A, b, rcond=1e-6)[0], [1.0, 0.0], rtol=ROUNDOFF, atol=0.0)
    assert np.allclose(lstsq_stacked(A, b)[0], [1.0, 1e8], rtol=ROUNDOFF, atol=0.0)


def test_no_systems_give_no_solutions():
    assert lstsq_stacked(np.zeros((0, 6, 3)), np.zeros((0, 6))).shape == (0, 3)
