"""Stability verdicts: the policy, in one place.

A run is

* ``stable`` when it stays finite over the whole horizon and every conserved
  quantity the case declares stays within the case's bound for it;
* ``drifts`` when it stays finite but some conserved quantity leaves its bound;
* ``diverged`` when the state became NaN/inf or blew up (the engine's own
  detection included: its status is ``diverged``), or when a conserved
  quantity changed by more than ``BLOWUP`` times its scale (a blow-up that is
  still finite);
* otherwise the run's own status (``failed``, ``timeout``, ``unsupported``).

The bounds are the case's named tolerances (``Case.tolerances[<conserved>]``),
each with its reason; nothing here invents a bound.
"""

from __future__ import annotations

import math

__all__ = ["VERDICTS", "BLOWUP", "verdict"]

# A conserved quantity that changed by more than 100 times its own scale has
# not drifted, it has blown up (e.g. energy x100): a divergence, though finite.
BLOWUP = 100.0

VERDICTS = ("stable", "drifts", "diverged", "failed", "timeout", "unsupported")


def verdict(row, tolerances):
    """Verdict for a stored run ``row`` (dict) of a case with ``tolerances`` (name -> Tolerance).

    Returns ``(verdict, reason)``.
    """
    status = row.get("status")
    if status != "ok":
        return status, row.get("message", "")
    beyond = []
    for name, tol in tolerances.items():
        value = row.get(f"drift_{name}")
        if value is None:
            continue
        if isinstance(value, float) and math.isnan(value):
            return "diverged", f"{name} drift is not finite"
        if value > BLOWUP:
            return "diverged", f"{name} changed by {value:.3g} times its scale (blow-up)"
        if value > tol.value:
            beyond.append(f"{name} drift {value:.2e} > {tol.value:g}")
    return ("drifts", "; ".join(beyond)) if beyond else ("stable", "")
