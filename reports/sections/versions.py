"""One engine at several versions, side by side: per case, settings and quantity, each version's error or
drift (the runs of ``mujoco==3.6.0``, ``mujoco==3.11.0`` and ``mujoco`` in one store, ``dalembert.environments``),
a line for each quantity that changed by more than ``CHANGE_FACTOR`` between two versions, a figure of those
quantities against the version (``dalembert.reports.versions_figure``), and the libraries whose versions differ
between the engine's versions (each run's ``provenance["libraries"]``, recorded in its worker)."""

from __future__ import annotations

import math
from collections import defaultdict

from dalembert.reports.names import settings_text
from dalembert.reports.page import Part
from dalembert.reports.tables import Cell, Table, num

__all__ = ["versions", "version_groups", "library_rows", "QUANTITIES", "CHANGE_FACTOR", "MAX_PANELS"]

# What the table shows per run: (label, where in the record, the key there). The orientation error says where
# the body ends; the energy and angular momentum drifts (max relative change) say what the integrator conserves.
QUANTITIES = (("orientation error (rad)", "errors", "orientation"), ("energy drift", "drifts", "energy"),
              ("angular momentum drift", "drifts", "angular_momentum"))
# A change between two versions worth a finding: a factor of ten. A run is deterministic (the same version
# gives the same numbers run after run), so any change is the engine's; ten times is what changes a
# verdict or a choice of integrator, where a few percent is a rounding order or a refactoring.
CHANGE_FACTOR = 10.0
# A table of more rows than this (ten settings' three quantities) is folded, its summary line shown.
SHOWN_ROWS = 30
# The figure draws at most this many panels (four rows of four), the largest changes first; the table has all.
MAX_PANELS = 16


def _engine(name):
    """The engine of a record's engine name (``mujoco`` for ``mujoco==3.6.0``)."""
    from dalembert.environments import engine_of

    return engine_of(name)


def _version_key(record):
    """Sorts records by engine version (PEP 440 order; a version ``packaging`` cannot read last, by text)."""
    from packaging.version import InvalidVersion, Version

    try:
        return (0, Version(record.engine_version), record.engine)
    except InvalidVersion:
        return (1, record.engine_version, record.engine)


def _value(record, where, key):
    value = getattr(record, where).get(key)
    if isinstance(value, (tuple, list)):  # an error: (max, final)
        value = value[0]
    return math.nan if value is None else float(value)


def version_groups(records):
    """``{(engine, case, case_version, params, settings label): [record, ...]}`` for each engine run under two
    or more names (versions), each group's records in version order; a group of one version left out."""
    engine_of = {name: _engine(name) for name in {r.engine for r in records}}  # (once per name: a map has 1e6 runs)
    names = defaultdict(set)
    for name, engine in engine_of.items():
        names[engine].add(name)
    groups = defaultdict(list)
    for r in records:
        engine = engine_of[r.engine]
        if len(names[engine]) > 1:
            groups[(engine, r.case, r.case_version, tuple(sorted(r.params.items())), settings_text(r))].append(r)
    return {k: sorted(v, key=_version_key) for k, v in groups.items() if len({r.engine for r in v}) > 1}


def _changes(group, label):
    """The line saying how ``group``'s quantity ``label`` changed across versions (``3.2.7-3.6.0 0.085, 3.7.0
    1.3e-10``), or None under ``CHANGE_FACTOR``."""
    where, key = next((w, k) for lab, w, k in QUANTITIES if lab == label)
    values = [(r, _value(r, where, key)) for r in group]
    finite = [v for _, v in values if math.isfinite(v) and v > 0]
    if len(finite) < 2 or max(finite) / min(finite) < CHANGE_FACTOR:
        return None
    spans = []  # consecutive versions with one value (as written) are one span: the change shows where it happened
    for r, v in values:
        text = f"{v:.2g}"
        if spans and spans[-1][2] == text:
            spans[-1][1] = r.engine_version
        else:
            spans.append([r.engine_version, r.engine_version, text])
    return ", ".join(f"{a}{'' if a == b else '-' + b} {text}" for a, b, text in spans)


def _figure(mine, names, versions_of):
    """The SVG of one engine's quantities that changed by more than ``CHANGE_FACTOR`` between its versions (a panel
    per case, integrator and quantity, a line per setting), and how many such panels there were; None when none."""
    from dalembert.reports.versions_figure import versions_figure

    panels = {}
    for (_, case, _, _, label), group in mine.items():
        by = {r.engine: r for r in group}
        for quantity, where, key in QUANTITIES:
            values = [_value(by[n], where, key) if n in by else math.nan for n in names]
            finite = [v for v in values if math.isfinite(v) and v > 0]
            if len(finite) < 2 or max(finite) / min(finite) < CHANGE_FACTOR:
                continue
            panel = panels.setdefault((case, group[0].settings.integrator, quantity),
                                      {"lines": {}, "change": 1.0})
            panel["lines"][label] = values
            panel["change"] = max(panel["change"], max(finite) / min(finite))
    if not panels:
        return None, 0
    shown = sorted(panels.items(), key=lambda kv: -kv[1]["change"])[:MAX_PANELS]
    order = [q for q, _, _ in QUANTITIES]
    shown.sort(key=lambda kv: (kv[0][0], kv[0][1], order.index(kv[0][2])))
    return versions_figure([versions_of[n] for n in names],
                           [{"title": f"{case}, {integrator}", "ylabel": quantity, "lines": p["lines"]}
                            for (case, integrator, quantity), p in shown]), len(panels)


def library_rows(records, names):
    """The libraries whose versions differ between engine names ``names`` (each name's runs'
    ``provenance["libraries"]``): ``[(library, [version or "" per name])]``, by library. A library one name's
    worker did not load is left out unless two names that loaded it differ (a forked worker holds what its
    parent had loaded, which is the process's history, not the engine's)."""
    loaded = {}
    for r in records:
        if r.engine in names and r.engine not in loaded and r.provenance.get("libraries"):
            loaded[r.engine] = r.provenance["libraries"]
    out = []
    for library in sorted({lib for libs in loaded.values() for lib in libs}):
        versions = [loaded.get(n, {}).get(library, "") for n in names]
        if len({v for v in versions if v}) > 1:
            out.append((library, versions))
    return out


def versions(rep):
    """The versions section (a ``Part``; empty when no engine ran at two versions)."""
    part = Part()
    groups = version_groups(rep.records)
    if not groups:
        return part
    part.heading("Engine versions side by side", 2, anchor="versions")
    lines = []
    for (engine, case, _, _, label), group in groups.items():
        for quantity, _, _ in QUANTITIES:
            said = _changes(group, quantity)
            if said:
                lines.append(f"{engine} {label} {quantity} on {case}: {said}")
    part.para("The same case, integrator and step run by each version of an engine (each in its environment: "
              "dalembert env create). " + (f"Changed by more than {CHANGE_FACTOR:g}x between versions (each span of "
                                           "versions with its value):" if lines else
                                           f"No quantity changed by more than {CHANGE_FACTOR:g}x between versions."))
    if lines:
        part.items(lines)
    for engine in sorted({k[0] for k in groups}):
        mine = {k: g for k, g in groups.items() if k[0] == engine}
        names = sorted({r.engine for g in mine.values() for r in g},
                       key=lambda n: min(_version_key(r) for g in mine.values() for r in g if r.engine == n))
        versions_of = {n: next(r.engine_version for g in mine.values() for r in g if r.engine == n) for n in names}
        head = ["case", "settings", "quantity"] + [f"{n} ({versions_of[n]})" if n != versions_of[n] else n
                                                   for n in names]
        rows = []
        for (_, case, _, _, label), group in sorted(mine.items(), key=lambda kv: kv[0][1:]):
            by = {r.engine: r for r in group}
            for quantity, where, key in QUANTITIES:
                rows.append([Cell(case), Cell(label, wrap=True), Cell(quantity)]
                            + [num(_value(by[n], where, key)) if n in by else num(None) for n in names])
        figure, n_panels = _figure(mine, names, versions_of)
        if figure:
            more = f" (the {MAX_PANELS} that changed most of {n_panels}; the table has all)" if n_panels > MAX_PANELS \
                else ""
            part.figure(figure, f"{engine}: each quantity that changed by more than {CHANGE_FACTOR:g}x between "
                        f"versions{more}, against the version (log scale; a gap: no finished run, or zero), one line "
                        "per setting.", f"versions-{engine}")
        part.table(Table(head, rows), collapsed=f"{engine}: {len(names)} versions, {len(mine)} settings"
                   if len(rows) > SHOWN_ROWS else None)
        libraries = library_rows([r for g in mine.values() for r in g], names)
        if libraries:
            part.para(f"{engine}: the libraries loaded in the workers whose versions differ between its versions "
                      "(each run records the versions of every library loaded where it ran).")
            part.table(Table(["library"] + head[3:], [[Cell(lib)] + [Cell(v or "-") for v in versions]
                                                     for lib, versions in libraries]))
    return part
