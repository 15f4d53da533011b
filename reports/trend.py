"""Drifts or varies: whether a conserved quantity that left its bound has a secular trend or oscillates within
bounds, decided from its stored series.

The stored verdict ``drifts`` (``dalembert.judge``) says a conserved quantity's largest change over the horizon,
max |x(t) - x(0)| / scale, left the case's bound; it does not say whether the change grows. The report writes

* "drifts by" when the change has a trend: its largest value over the horizon's second half is more than
  ``TREND_GROWTH`` times that over its first half (a linear drift doubles, a random walk of roundoff grows
  by sqrt(2));
* "varies by" when it does not: a bounded oscillation whose period is shorter than half the horizon reaches
  its amplitude in the first half and does not exceed it after (symplectic and geometric integrators keep
  energy so).

The series is ``dalembert.invariants.drift_series`` of the stored trajectory (``reports.time_series``), the one
``max`` of which is the stored drift: stored samples only, nothing is run. The verdict stays the stored one;
only its word changes.
"""

from __future__ import annotations

import numpy as np

from dalembert.reports import time_series

__all__ = ["TREND_GROWTH", "has_trend", "beyond_conserved", "trend_words", "verdict_word", "reason_text"]

# A change whose largest value over the second half exceeds that over the first half by more than 25 % has a
# trend: a linear drift gives 2, a random walk sqrt(2) ~ 1.41; a bounded oscillation gives 1 (sample jitter and a
# slowly beating amplitude stay within a few per cent).
TREND_GROWTH = 1.25


def has_trend(t, change):
    """Whether ``change`` (n,), a quantity's unsigned change from its initial value at times ``t`` (n,) s, grows
    (module docstring); a series with no finite second half is a trend (it stopped being finite)."""
    t, change = np.asarray(t, float), np.asarray(change, float)
    if len(t) < 4:
        return True
    half = t - t[0] >= 0.5 * (t[-1] - t[0])
    late = change[half]
    if not np.all(np.isfinite(late)):
        return True
    first = float(np.max(change[~half], initial=0.0))
    last = float(np.max(late, initial=0.0))
    return last > TREND_GROWTH * first if first > 0.0 else last > 0.0


def beyond_conserved(r, case):
    """The conserved quantities (``case.conserved``) of run ``r`` whose stored drift is beyond the case's bound."""
    return [n for n in case.conserved if n in case.tolerances and r.drifts.get(n, 0.0) > case.tolerances[n].value]


_CACHE = {}  # (store path, run key, trajectory, quantity, drift) -> has_trend: a run's series is read once per report


def trend_words(store, r, case):
    """``{quantity: "drifts by" | "varies by"}`` for each conserved quantity of ``r`` beyond its bound ({} for a run
    not judged ``drifts`` or without a stored trajectory)."""
    if r.judgement.verdict != "drifts" or not r.trajectory:
        return {}
    out = {}
    for name in beyond_conserved(r, case):
        key = (store.path, r.key, r.trajectory, name, r.drifts.get(name))
        if key not in _CACHE:
            _CACHE[key] = has_trend(*time_series.drift_series(store, r, case, name))
        out[name] = "drifts by" if _CACHE[key] else "varies by"
    return out


def verdict_word(store, r, case):
    """The word for ``r``'s stored verdict: "varies" for a ``drifts`` verdict whose every quantity beyond its bound
    oscillates within bounds, else the stored verdict."""
    words = trend_words(store, r, case)
    if words and all(w == "varies by" for w in words.values()):
        return "varies"
    return r.judgement.verdict


def reason_text(store, r, case):
    """``r``'s stored verdict reason with each conserved quantity's "<name> drift <value>" written "<name> drifts by
    <value>" or "<name> varies by <value>" (``trend_words``); other reasons as stored."""
    text = r.judgement.reason
    for name, word in trend_words(store, r, case).items():
        text = text.replace(f"{name} drift ", f"{name} {word} ")
    return text
