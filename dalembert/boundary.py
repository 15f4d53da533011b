"""Where an integrator stops being trustworthy: the stability boundary in the step size.

A *curve* is one case variant (its version), one engine, integrator and option set; its
fixed-step runs at several steps ``dt`` each carry the verdict judged when they ran
(``dalembert.judge``). Verdicts are taken to worsen as the step grows — the premise of a
stability boundary — so the largest step judged ``stable`` below the smallest step not
judged so brackets the *stable* boundary, and likewise for *finite* (``stable`` or
``drifts``: neither diverged, failed nor timed out). A probe that breaks the premise (a
stable step above an unstable one) is reported, not hidden.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["FINITE", "Bracket", "Boundary", "curve_of", "bracket", "boundaries"]

# Verdicts of a run that stayed finite over its horizon (the others diverged or broke down).
FINITE = ("stable", "drifts")


@dataclass(frozen=True)
class Bracket:
    """The boundary between steps that pass and steps that do not, s.

    Attributes
    ----------
    passed : float or None — the largest probed step that passes below every failing one
    failed : float or None — the smallest probed step that does not pass
    monotone : bool — no passing step lies above a failing one
    """

    passed: float | None
    failed: float | None
    monotone: bool

    @property
    def ratio(self):
        """``failed / passed`` (inf when either side is missing): how finely the boundary is known."""
        return self.failed / self.passed if self.passed and self.failed else math.inf


@dataclass(frozen=True)
class Boundary:
    """The stable and finite brackets of one curve.

    Attributes
    ----------
    case, case_version, engine, integrator, options : str — the curve (options as ``key=value`` words)
    params : dict — the case parameters of the variant (the swept values among them)
    stable, finite : Bracket
    probes : int — runs probed on this curve
    """

    case: str
    case_version: str
    engine: str
    integrator: str
    options: str
    params: dict
    stable: Bracket
    finite: Bracket
    probes: int


def curve_of(record):
    """The curve a run belongs to: (case, case_version, engine, integrator, options)."""
    return record.case, record.case_version, record.engine, record.settings.integrator, record.options_label


def bracket(probes, passes):
    """The ``Bracket`` of ``probes`` (``[(dt, verdict)]``) under ``passes(verdict) -> bool``."""
    passed = {v: passes(v) for v in {v for _, v in probes}}  # (asked once per distinct verdict, not per probe)
    failing = [dt for dt, v in probes if not passed[v]]
    first_fail = min(failing) if failing else None
    passing = [dt for dt, v in probes if passed[v] and (first_fail is None or dt < first_fail)]
    monotone = not any(passed[v] and first_fail is not None and dt > first_fail for dt, v in probes)
    return Bracket(max(passing) if passing else None, first_fail, monotone)


def boundaries(records):
    """The ``Boundary`` of every curve among ``records``' fixed-step runs, sorted by curve."""
    curves = {}
    for r in records:
        if r.settings.dt is not None:
            curves.setdefault(curve_of(r), []).append(r)
    out = []
    for key, runs in sorted(curves.items()):
        probes = [(r.settings.dt, r.judgement.verdict) for r in runs]
        out.append(Boundary(*key, runs[0].params, bracket(probes, lambda v: v == "stable"),
                            bracket(probes, lambda v: v in FINITE), len(runs)))
    return out
