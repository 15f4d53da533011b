"""Judging a run, once, at run time: is it within the case's tolerances, and is it stable?

The verdict is stored with the run (``RunRecord.judgement``), so a report reads how a
run was judged when it ran; changing a tolerance changes the case's version, never
the judgement of runs already stored.

A run is

* ``stable`` when it stays finite over the whole horizon and every conserved
  quantity the case bounds stays within the case's bound for it;
* ``drifts`` when it stays finite but some conserved quantity leaves its bound;
* ``diverged`` when the state became NaN/inf or blew up (the engine's own
  detection included: its status is ``diverged``), or when a conserved
  quantity changed by more than ``BLOWUP`` times its scale on the true motion
  (``dalembert.invariants.growth``: a blow-up that is still finite);
* otherwise the run's own status (``failed``, ``timeout``, ``unsupported``).

Within tolerance means every named tolerance of the case holds: errors against
the truth (``dalembert.errors.QUANTITIES``) and drifts of conserved quantities.
The bounds are the case's named tolerances, each with its reason; nothing here
invents a bound.

A bounded quantity the run did not report (an engine that reads back no
reactions) is *not measured*: never within tolerance, never beyond it. It is
listed in ``Judgement.not_measured``, and ``within_tolerance`` is then None
(not established) unless some measured quantity is beyond (False): True means
every bound was measured and holds. Stores written before this kept no
``not_measured``; their stored ``within_tolerance`` is read as it was judged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dalembert.errors import QUANTITIES

__all__ = ["VERDICTS", "BLOWUP", "Judgement", "judge"]

# A conserved quantity that changed by more than 100 times its own scale has
# not drifted, it has blown up (e.g. energy x100): a divergence, though finite.
BLOWUP = 100.0

VERDICTS = ("stable", "drifts", "diverged", "failed", "timeout", "unsupported")


def _beyond_text(name, value, tol):
    """Why ``name`` is beyond its bound: a conserved quantity's drift as a number ("energy drift 1.20e-03 >
    0.0001"), a metric's figure and bound in its unit ("creep 1.80e-03 m/s > bound 0.0001 m/s": its ``tol`` is a
    ``dalembert.metrics.MetricTolerance``)."""
    unit = getattr(tol, "unit", None)
    if unit is None:
        return f"{name} drift {value:.2e} > {tol.value:g}"
    return f"{name} {tol.in_unit(value):.2e} {unit} > bound {tol.in_unit(tol.value):g} {unit}"


@dataclass(frozen=True)
class Judgement:
    """How a run measured up to its case.

    Attributes
    ----------
    beyond : tuple of str — names of the case's tolerances the run exceeds (empty unless ``ok``)
    verdict : str — one of ``VERDICTS``
    reason : str — why the verdict is not ``stable`` ("" when it is), and why the tolerances were not judged
        where the run simulated more than the scene
    within_tolerance : bool or None — every tolerance was measured and holds (True), some measured one is
        exceeded (False); None for a run that did not finish, or when nothing measured is beyond and some bound
        was not measured
    not_measured : tuple of str — names of the case's tolerances whose quantity the run did not report
        (empty in stores written before it was judged)
    """

    beyond: tuple
    verdict: str
    reason: str
    within_tolerance: bool | None
    not_measured: tuple = ()


def judge(status, message, errors, drifts, tolerances, growths=None, beyond_scene=None):
    """Judge one run.

    Parameters
    ----------
    status, message : str — the run's status (``dalembert.record.STATUSES``) and message
    errors : dict quantity -> float — max error over the horizon, in the unit of
        ``dalembert.errors.QUANTITIES[quantity]``
    drifts : dict name -> float — drift of each conserved quantity, scaled as in
        ``dalembert.invariants.CONSERVED``
    tolerances : dict name -> Tolerance — the case's bounds
    growths : dict name -> float or None — change of each conserved quantity in units of its scale
        on the true motion (``dalembert.invariants.growth``; a drift, scaled by the run's own
        largest value, cannot show a blow-up)
    beyond_scene : str or None — what the run simulated beyond the scene at the user's request
        (``Adapter.beyond_scene``): its stability is judged as any run's, but the case's tolerances hold for the
        scene alone, so ``within_tolerance`` is None (not established) and the reason says why

    Returns
    -------
    Judgement

    A bounded quantity the run did not report (absent, or None) is not measured
    (``Judgement.not_measured``), never within; a non-finite one is beyond.
    """
    if status != "ok":
        return Judgement((), status, message, None)
    values = {name: (errors if name in QUANTITIES else drifts).get(name) for name in tolerances}
    missing = tuple(name for name, value in values.items() if value is None)
    beyond = tuple(name for name, tol in tolerances.items()
                   if values[name] is not None and not values[name] <= tol.value)
    within = False if beyond else None if missing else True
    for name, value in (growths or {}).items():
        if value > BLOWUP:  # NaN (no true scale) compares False
            return Judgement(beyond, "diverged", f"{name} changed by {value:.3g} times its scale in the true motion "
                                                 "(a blow-up, though finite)", False, missing)
    drifted = []
    for name, tol in tolerances.items():
        value = drifts.get(name)
        if value is None:
            continue
        if math.isnan(value):
            return Judgement(beyond, "diverged", f"{name} drift is not finite", False, missing)
        if value > BLOWUP:
            return Judgement(beyond, "diverged", f"{name} changed by {value:.3g} times its scale (blow-up)", False,
                             missing)
        if value > tol.value:
            drifted.append(_beyond_text(name, value, tol))
    verdict, reason = ("drifts", "; ".join(drifted)) if drifted else ("stable", "")
    if beyond_scene:
        reason = "; ".join(filter(None, (reason, f"not judged against the tolerances: {beyond_scene}")))
        within = None
    return Judgement(beyond, verdict, reason, within, missing)
