"""Integrals of smooth periodic rates to roundoff: Gauss-Legendre on panels, one period tabulated.

The closed forms of the tops give an angle as the integral of a rate that is an analytic,
periodic function of an elliptic argument ``tau`` (the torque-free top's precession, the heavy
top's precession and spin). ``PeriodicIntegral`` integrates such a rate

* on panels no wider than ``panel`` in ``tau``, 16 Gauss-Legendre nodes each: where the rate's
  nearest complex singularity is at least ``panel`` away, the error is below ``rho^-32`` with
  ``rho >= 2.4`` (the Bernstein ellipse through a singularity one panel width off the panel's
  centre line), i.e. roundoff;
* on panels graded geometrically towards any point where the rate is nearly singular (a
  singularity a distance ``d`` off the real axis): panel edges at ``d/2, d, 2d, 4d, ...`` from
  it, so each panel keeps its singularity at least its own width away and the same bound holds
  however small ``d`` is (the heavy top's axis passing near the vertical: ``d`` ~ 1e-7);
* over one period once (a table of the integral at every panel edge), then ``G(tau)`` as whole
  periods plus the table plus one partial panel, so no error accumulates over long horizons.
"""

from __future__ import annotations

import numpy as np

__all__ = ["PeriodicIntegral", "graded_edges", "gauss_legendre"]

NODES, WEIGHTS = np.polynomial.legendre.leggauss(16)


def gauss_legendre(f, a, b, panels):
    """``int_a^b f`` (arrays ``a``, ``b`` of one shape) on ``panels`` equal panels each (int array, same shape)."""
    a, b = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float))
    panels = np.broadcast_to(np.asarray(panels), a.shape)
    total = np.zeros(a.shape)
    for k in range(int(panels.max(initial=1))):
        active = k < panels
        h = (b - a) / panels
        x = (a + k * h)[..., None] + 0.5 * h[..., None] * (NODES + 1.0)
        total += np.where(active, 0.5 * h * (f(x) @ WEIGHTS), 0.0)
    return total


def graded_edges(a, b, panel, near_a=None, near_b=None):
    """Panel edges from ``a`` to ``b`` (ascending ndarray): at most ``panel`` apart, graded towards an end
    whose rate has a singularity ``near_a`` (``near_b``) off the real axis (None: no grading)."""
    def ramp(d):
        if d is None or d >= panel:
            return []
        steps = [0.5 * d]
        while steps[-1] < panel:
            steps.append(2.0 * steps[-1] if len(steps) > 1 else d)
        return steps[:-1]

    left = [a + s for s in ramp(near_a)]
    right = [b - s for s in ramp(near_b)][::-1]
    lo = left[-1] if left else a
    hi = right[0] if right else b
    if lo >= hi:  # the two ramps meet: grade to the midpoint from both sides
        mid = 0.5 * (a + b)
        left, right, lo, hi = [x for x in left if x < mid], [x for x in right if x > mid], mid, mid
    n = max(1, int(np.ceil((hi - lo) / panel)))
    middle = lo + (hi - lo) * np.arange(n + 1) / n
    middle[-1] = hi  # (not an ulp off: no sliver panel)
    return np.unique(np.concatenate([[a], left, middle, right, [b]]))


class PeriodicIntegral:
    """``G(tau) = int_start^tau f``, for ``f`` of period ``period`` (in ``tau``), to roundoff.

    Parameters
    ----------
    f : callable, ndarray (...) -> ndarray (...) — the rate, vectorized
    period : float — ``f(tau + period) = f(tau)``
    start : float — where ``G`` is zero
    edges : ndarray (m,) or None — panel edges over ``[start, start + period]`` (ascending, first and
        last on the ends), e.g. from ``graded_edges``; default: uniform panels of at most ``panel``
    panel : float — largest panel width (see the module docstring)
    """

    def __init__(self, f, period, start=0.0, edges=None, panel=0.5):
        self.f, self.period, self.start, self.panel = f, float(period), float(start), panel
        if edges is None:
            edges = graded_edges(self.start, self.start + self.period, panel)
        self.edges = np.asarray(edges, dtype=float)
        pieces = gauss_legendre(f, self.edges[:-1], self.edges[1:], 1)
        self.table = np.concatenate([[0.0], np.cumsum(pieces)])

    @property
    def per_period(self):
        """``G(start + period)``: the integral over one period."""
        return self.table[-1]

    def __call__(self, tau):
        tau = np.asarray(tau, dtype=float)
        turns = np.floor((tau - self.start) / self.period)
        r = tau - turns * self.period
        idx = np.clip(np.searchsorted(self.edges, r, side="right") - 1, 0, len(self.edges) - 2)
        return turns * self.per_period + self.table[idx] + gauss_legendre(self.f, self.edges[idx], r, 1)
