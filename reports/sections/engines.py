"""What each engine simulated in one case: the effects audit it read back and the model it generated."""

from __future__ import annotations

import json

from dalembert.reports.findings import settings_text
from dalembert.reports.page import Part

__all__ = ["engines_simulated"]


def engines_simulated(rep, f):
    """Per engine of case version ``f``, its most accurate run's (else its first run's) effects audit
    and generated model, folded (a ``Part``)."""
    part = Part()
    part.heading("What each engine simulated", 3)
    for e in f.engines:
        r = e.best.run if e.best else e.runs[0]
        if r.audit:
            part.details(f"{e.engine}: effects audit ({settings_text(r)})", json.dumps(r.audit, indent=2))
        if r.model:
            part.details(f"{e.engine}: generated model", r.model)
    return part
