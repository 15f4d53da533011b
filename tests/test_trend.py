"""Drifts or varies (``reports.trend``): a conserved quantity beyond its bound with a trend "drifts by", one that
oscillates within bounds "varies by", decided from its series; the stored verdict stays, only its word changes."""

from types import SimpleNamespace

import numpy as np
import pytest

from dalembert.reports import time_series, trend
from dalembert.reports.trend import has_trend, reason_text, verdict_word

T = np.linspace(0.0, 10.0, 1001)


@pytest.mark.parametrize("change, grows", [
    (1e-3 * T, True),  # a linear drift: twice as large at the end as at mid-horizon
    (1e-3 * np.sqrt(T), True),  # a random walk's envelope: sqrt(2)
    (1e-3 * np.abs(np.sin(2 * np.pi * T / 1.3)), False),  # a bounded oscillation about the start
    (1e-3 * (1 - np.cos(2 * np.pi * T / 0.7)), False),  # one-sided: its mean is off the start, still bounded
    (1e-3 * (1 - np.cos(2 * np.pi * T / 0.7)) * (1 + 0.1 * T), True),  # an oscillation whose amplitude grows
    (np.where(T < 8, 1e-3, np.nan), True),  # not finite before the end: no bound
])
def test_a_trend_is_a_change_that_keeps_growing_after_mid_horizon(change, grows):
    assert has_trend(T, change) is grows


def _run(verdict="drifts", energy=2e-3, momentum=5e-9):
    return SimpleNamespace(key="k", trajectory="k.npz", drifts={"energy": energy, "angular_momentum": momentum},
                           judgement=SimpleNamespace(verdict=verdict,
                                                     reason=f"energy drift {energy:.2e} > 1e-08"))


CASE = SimpleNamespace(conserved=("energy", "angular_momentum"),
                       tolerances={"energy": SimpleNamespace(value=1e-8), "angular_momentum": SimpleNamespace(value=1e-8)})


def test_the_verdict_word_and_reason_follow_the_stored_series(monkeypatch, tmp_path):
    series = {}
    monkeypatch.setattr(time_series, "drift_series", lambda store, r, case, name: (T, series[name]))
    store = SimpleNamespace(path=str(tmp_path / "bounded"))
    series["energy"] = 2e-3 * np.abs(np.sin(T))
    assert verdict_word(store, _run(), CASE) == "varies"
    assert reason_text(store, _run(), CASE) == "energy varies by 2.00e-03 > 1e-08"
    store = SimpleNamespace(path=str(tmp_path / "trend"))  # (the words are cached per store and run)
    series["energy"] = 2e-4 * T
    assert verdict_word(store, _run(), CASE) == "drifts"
    assert reason_text(store, _run(), CASE) == "energy drifts by 2.00e-03 > 1e-08"
    assert verdict_word(store, _run("stable", energy=0.0), CASE) == "stable"  # other verdicts as stored
    assert trend.trend_words(store, _run(), CASE) == {"energy": "drifts by"}  # the momentum is within its bound
