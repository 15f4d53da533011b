"""Contact maps: where an engine's contact stops being trustworthy. For a contact case whose runs sweep a numeric
engine option against the step (``dalembert run --option contact_timeconst=log:0.002,0.05,5 --dt ...``), per
engine, integrator and swept option, a heatmap of each figure the case stores (its contact metrics: creep,
penetration, ...; the drift of each conserved quantity it judges) over (option value x dt), on a log colour scale,
the cells beyond the case's bound hatched.

Read from the store only: the runs' settings and their stored figures (``RunRecord.drifts``), judged as
``dalembert.judge`` judges them (a stored value above the case's tolerance).
"""

from __future__ import annotations

import math

import numpy as np

from dalembert.reports import contact_figures
from dalembert.reports.page import Part
from dalembert.reports.sections.common import declared, has_contact, is_metric, shown_value, stored_label

__all__ = ["contact_maps", "option_grids", "MIN_SIDE"]

# A map needs at least this many option values and this many steps: one row or one column is the creep bars'
# or the work-precision figure's business, not a map.
MIN_SIDE = 2


def option_grids(runs):
    """The option x step sweeps among ``runs`` (RunRecords of one case version): ``{(engine, integrator, key,
    other options): [(option value, run), ...]}``, one per engine, integrator and numeric option that takes at
    least ``MIN_SIDE`` values over at least ``MIN_SIDE`` fixed steps, the engine's other options held."""
    groups = {}
    for r in runs:
        if r.settings.dt is None:
            continue
        for key, text in r.settings.options.items():
            try:
                value = float(text)
            except (TypeError, ValueError):
                continue  # a named choice (cone=elliptic) is not an axis
            if not math.isfinite(value):
                continue
            rest = tuple(sorted((k, v) for k, v in r.settings.options.items() if k != key))
            groups.setdefault((r.engine, r.settings.integrator, key, rest), []).append((value, r))
    return {k: v for k, v in groups.items()
            if len({x for x, _ in v}) >= MIN_SIDE and len({r.settings.dt for _, r in v}) >= MIN_SIDE}


def contact_maps(rep, f, name):
    """Case version ``f``'s contact maps (a ``Part``; empty for a case without contact or without an option x step
    sweep); ``name`` prefixes its figures."""
    part = Part()
    if not has_contact(f.case):
        return part
    grids = option_grids(f.runs)
    if not grids:
        return part
    part.heading("Contact maps: an engine option against the step", 3)
    for (engine, integrator, key, rest), cells in sorted(grids.items()):
        xs = sorted({r.settings.dt for _, r in cells})
        ys = sorted({x for x, _ in cells})
        figures = sorted({k for _, r in cells for k in r.drifts}, key=lambda k: (not is_metric(f.case, k), k))
        panels = []
        for figure in figures:
            values = np.full((len(ys), len(xs)), np.nan)
            beyond = np.zeros(values.shape, dtype=bool)
            tol = f.case.tolerances.get(figure)
            for x, r in cells:
                i, j = ys.index(x), xs.index(r.settings.dt)
                values[i, j] = shown_value(r, figure, f.case)
                beyond[i, j] = tol is not None and r.drifts.get(figure, math.nan) > tol.value  # as judge.py
            bound = tol.value * (declared(f.case, figure).scale if is_metric(f.case, figure) else 1.0) if tol else None
            unit = stored_label(figure, f.case)
            panels.append(dict(title=figure + (f" (bound {bound:.3g})" if bound is not None else ""),
                               values=values, beyond=beyond, unit=unit))
        held = " ".join(f"{k}={v}" for k, v in rest)
        what = f"{engine} {integrator}" + (f" {held}" if held else "")
        part.figure(contact_figures.contact_map(panels, xs, ys, "dt (s)", key),
                    f"{name}: {what}, each stored figure over {key} (rows) and the step (columns), a cell per run "
                    "(its value written; blank: no value stored) on a log colour scale; hatched and outlined: beyond "
                    "the case's bound (in each panel's title, in its colour bar's unit).",
                    f"{name}-contact-map-{engine}-{integrator}-{key}")
    return part

