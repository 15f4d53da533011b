"""Compare two results stores, as ``asv compare`` compares two benchmark runs: for every run in
both, each error and the cost before, after and their ratio; runs in one store only, apart.

Runs are matched by case, parameters, engine, integrator, dt, tolerances and
options. A run whose case version differs between the stores is listed as not
compared (unless asked: ``across_versions``, e.g. when only the way versions are
computed changed). Two configurations of one engine pair when asked
(``pair_options``: A's runs with ``cone=pyramidal`` against B's with
``cone=elliptic``, all else equal; the two stores may be one directory; ``noslip=default`` pairs the runs
that leave the option to the engine). When
nothing pairs, ``Comparison.unpaired`` says why (the cases, engines, settings or
options that differ): ``dalembert compare`` then exits non-zero, for a gate that
compared nothing has checked nothing.

An error is worse when it grows by more than ``threshold`` times, better when it
shrinks by as much (errors at roundoff level, below ``ERROR_FLOOR``, are
compared as if they were ``ERROR_FLOOR``); a run that finished before and now
fails, diverges or times out is worse too, and so is an error or a conserved
quantity measured before and missing after (an engine that stopped reporting
reactions: "missing after"). Each is a regression: the exit status of
``dalembert compare`` (the CI gate).

Cost is the stepping wall time. Timings are noisy, so a cost is slower only when
the two runs' measured spreads do not overlap (the fastest repeat after is slower
than the slowest before) and the median grew by more than ``COST_NOTICE``; it is
a regression only when asked (``cost_threshold``) and the median grew by more
than that factor as well. A store timed once per run (``dalembert run --quick``:
its manifest's ``timing``) has single samples, with no spread to judge against:
its costs are shown, with a warning, and never called slower or faster
(``cost_change`` "unjudged").

Text for the terminal (``to_text``) has the store's control characters escaped
(``dalembert.terminal.printable``); JSON and CSV keep the names as stored.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace

from dalembert.errors import QUANTITIES
from dalembert.identity import check_version, run_identity
from dalembert.record import BAD_STATUSES
from dalembert.reports.findings import settings_text
from dalembert.reports.timing import once_note
from dalembert.reports.work_precision import headline_quantity
from dalembert.terminal import printable

__all__ = ["ERROR_FLOOR", "COST_NOTICE", "Change", "Comparison", "compare_stores", "to_text", "to_json",
           "csv_rows", "MACHINE_FIELDS", "unpaired_reason"]

# Errors below this are roundoff; a change among them is neither better nor worse.
ERROR_FLOOR = 1e-13
# A median stepping time that moved by less than this factor is not worth a line, whatever the
# spreads: repeats of one run on one machine scatter by ~10 % (the stores' min-max spreads).
COST_NOTICE = 1.2
# What must be equal for two stores' timings to compare (manifest "machine").
MACHINE_FIELDS = ("cpu", "cores", "os", "python", "host")
CHANGES = ("worse", "better", "status", "same")


# The engine name two runs paired by ``pair_engines`` share in their keys.
PAIRED_ENGINE = "(paired engines)"


def _key(r, drop=(), engines=False):
    """What identifies a run across stores: its ``dalembert.identity.RunIdentity`` (the options named in
    ``drop`` left out: the ones ``pair_options`` sets apart; the engine left out with ``engines``: the ones
    ``pair_engines`` sets apart, e.g. two versions of one engine)."""
    settings = r.settings
    if drop:
        settings = replace(settings, options={k: v for k, v in settings.options.items() if k not in drop})
    return run_identity(r.case, r.params, PAIRED_ENGINE if engines else r.engine, settings)


def _same_value(stored, given):
    """An option value as stored (typed) against one given as text: ``10`` is ``"10"`` and ``"10.0"``."""
    if str(stored) == given:
        return True
    try:
        return float(stored) == float(given)
    except (TypeError, ValueError):
        return False


# The value that pairs a run that does not set an option (it ran with the engine's default): ``noslip=default``.
UNSET = "default"


def _has(r, options):
    """Run ``r`` was run with every one of ``options`` (key -> value as text; ``UNSET``: the option not given)."""
    given = r.settings.options
    return all(k not in given if v == UNSET else k in given and _same_value(given[k], v) for k, v in options.items())


def label(r):
    """``case engine integrator dt=... options`` (and parameters when given)."""
    params = " ".join(f"{k}={v}" for k, v in sorted(r.params.items()))
    return " ".join(x for x in (r.case, f"[{params}]" if params else "", r.engine, settings_text(r)) if x)


@dataclass(frozen=True)
class Change:
    """One run present in both stores.

    Attributes
    ----------
    a, b : RunRecord — before and after
    change : str — one of ``CHANGES`` (worse, better, status, same)
    regression : bool — counts against the exit status
    notes : tuple of str — what changed, in words
    errors : dict quantity -> (before, after, ratio) — max errors (ratio NaN when either is missing)
    missing : tuple of str — errors (quantity names) and conserved quantities (``drift:<name>``) the run
        measured before and not after, both having finished (a regression)
    cost_ratio : float — median stepping time after / before
    cost_change : str — "slower", "faster" or "same" (judged against both spreads); "unjudged" when
        either store timed each run once (single samples: no spread to judge against)
    """

    a: object
    b: object
    change: str
    regression: bool
    notes: tuple
    errors: dict
    cost_ratio: float
    cost_change: str
    missing: tuple = ()

    @property
    def label(self):
        return label(self.b)


@dataclass(frozen=True)
class Comparison:
    """Everything ``compare_stores`` found."""

    changes: tuple  # Change per run in both stores, worst first
    only_in_a: tuple  # RunRecords
    only_in_b: tuple
    not_compared: tuple  # (a, b, reason)
    warnings: tuple  # sentences: machines or engine versions differ
    paths: tuple = ()
    threshold: float = 2.0
    cost_threshold: float | None = None
    stats: dict = field(default_factory=dict)
    unpaired: str = ""  # why nothing pairs ("" when some run does)
    pairing: tuple = ()  # (A's options, B's options) set apart by ``pair_options``; () when runs pair as they are

    @property
    def regressed(self):
        return any(c.regression for c in self.changes)


def _ratio(before, after):
    if not (math.isfinite(before) and math.isfinite(after)):
        return math.nan
    return max(after, ERROR_FLOOR) / max(before, ERROR_FLOOR)


def _cost(a, b, cost_threshold, judged=True):
    """(ratio of medians, slower/faster/same, regression?) judged against both runs' spreads;
    "unjudged" (never a regression) when not ``judged``: single samples have no spread."""
    ca, cb = a.cost, b.cost
    ratio = cb.wall_s_median / ca.wall_s_median if ca.wall_s_median and math.isfinite(ca.wall_s_median) else math.nan
    if not math.isfinite(ratio):
        return ratio, "same", False
    if not judged:
        return ratio, "unjudged", False
    if cb.wall_s_min > ca.wall_s_max and ratio > COST_NOTICE:
        return ratio, "slower", cost_threshold is not None and ratio > cost_threshold
    if cb.wall_s_max < ca.wall_s_min and ratio < 1.0 / COST_NOTICE:
        return ratio, "faster", False
    return ratio, "same", False


def _change(a, b, threshold, cost_threshold, costs_judged=True):
    errors = {q: (a.max_error(q), b.max_error(q), _ratio(a.max_error(q), b.max_error(q)))
              for q in QUANTITIES if q in a.errors or q in b.errors}
    cost_ratio, cost_change, cost_regressed = (_cost(a, b, cost_threshold, costs_judged) if a.ok and b.ok
                                               else (math.nan, "same", False))
    if a.status != b.status:
        regression = a.ok and b.status in BAD_STATUSES
        change = "worse" if regression else "better" if b.ok and a.status in BAD_STATUSES else "status"
        note = f"status {a.status} -> {b.status}" + (f" ({b.message.splitlines()[0]})" if b.message else "")
        return Change(a, b, change, regression, (note,), errors, cost_ratio, cost_change)
    worse = [q for q, (_, _, r) in errors.items() if r > threshold]
    better = [q for q, (_, _, r) in errors.items() if r < 1.0 / threshold]
    notes = [f"{q} x{errors[q][2]:.3g}" for q in worse + better]
    missing = ([q for q in errors if q in a.errors and q not in b.errors]
               + [f"drift:{n}" for n in a.drifts if n not in b.drifts]) if a.ok and b.ok else []
    notes += [f"{q} missing after" for q in missing]
    if a.judgement.verdict and b.judgement.verdict and a.judgement.verdict != b.judgement.verdict:
        notes.append(f"verdict {a.judgement.verdict} -> {b.judgement.verdict}")
    if cost_change in ("slower", "faster"):
        notes.append(f"cost x{cost_ratio:.3g} ({cost_change}, beyond both spreads)")
    blew_up = b.judgement.verdict == "diverged" and a.judgement.verdict not in ("diverged", "")
    regression = bool(worse) or bool(missing) or cost_regressed or blew_up
    if regression or cost_change == "slower":
        change = "worse"
    elif better or cost_change == "faster":
        change = "better"
    else:
        change = "status" if notes else "same"
    return Change(a, b, change, regression, tuple(notes), errors, cost_ratio, cost_change, tuple(missing))


def _differences(ma, mb, records_a, records_b):
    """Warnings: the machines, or an engine's version, differ between the stores (and how)."""
    out = []
    xa, xb = ma.get("machine") or {}, mb.get("machine") or {}
    differ = [f"{k} {xa.get(k)!r} vs {xb.get(k)!r}" for k in MACHINE_FIELDS if xa.get(k) != xb.get(k)]
    if differ:
        out.append("the machines differ (" + "; ".join(differ) + "): costs compare across machines only roughly")
    va = {**{r.engine: r.engine_version for r in records_a if r.engine_version}, **(ma.get("engines") or {})}
    vb = {**{r.engine: r.engine_version for r in records_b if r.engine_version}, **(mb.get("engines") or {})}
    engines = [f"{e} {va[e]} -> {vb[e]}" for e in sorted(set(va) & set(vb)) if va[e] != vb[e]]
    if engines:
        out.append("engine versions differ: " + ", ".join(engines))
    aa, ab = _adapters(records_a), _adapters(records_b)
    adapters = [f"{e} ({' and '.join(sorted(aa[e]))} -> {' and '.join(sorted(ab[e]))})"
                for e in sorted(set(aa) & set(ab)) if aa[e] != ab[e]]
    if adapters:
        out.append("adapter versions differ (the package that provides the engine's adapter): " + ", ".join(adapters))
    return out


def _adapters(records):
    """engine -> the set of ``distribution version`` its runs recorded (runs of stores that kept none left out)."""
    out = {}
    for r in records:
        if r.adapter_distribution:
            out.setdefault(r.engine, set()).add(f"{r.adapter_distribution} {r.adapter_version}")
    return out


def unpaired_reason(records_a, records_b, pairing=()):
    """Why no run of ``records_a`` pairs with one of ``records_b``, in words: what the stores hold differs
    (cases, parameters, engines, integrators, steps or tolerances, options), or one holds no run."""
    if not records_a or not records_b:
        return f"{'A' if not records_a else 'B'} holds no run{' with the options paired' if pairing else ''}"
    out = []
    for what, of in (("cases", lambda r: r.case), ("engines", lambda r: r.engine),
                     ("parameters", lambda r: json.dumps(r.params, sort_keys=True, default=list)),
                     ("integrators", lambda r: r.settings.integrator),
                     ("steps and tolerances", lambda r: r.sweep_label),
                     ("engine options", lambda r: r.options_label or "(defaults)")):
        xa, xb = {of(r) for r in records_a}, {of(r) for r in records_b}
        if not xa & xb:
            out.append(f"{what} differ (A: {', '.join(sorted(xa))}; B: {', '.join(sorted(xb))})")
    if not out:
        out.append("each holds what the other does, but never in the same combination")
    fix = ("; to compare two configurations of one engine, pair their options: --pair-options A_OPTIONS B_OPTIONS"
           if not pairing and any("engine options" in x for x in out) else "")
    return "no run pairs: " + "; ".join(out) + fix


def _timed_once(manifests):
    """A warning when either store timed each run once (``dalembert run --quick``), else None."""
    once = [side for side, m in zip(("A (before)", "B (after)"), manifests) if once_note(m)]
    if not once:
        return None
    # the ~10 %: COST_NOTICE's scatter of one run's repeats on one machine
    return (f"{' and '.join(once)} {'were' if len(once) > 1 else 'was'} timed once per run (dalembert run --quick): "
            "each cost is a single sample, with no spread, and repeats of one run scatter by ~10 % on one machine, "
            "more on a loaded one — costs are shown, not judged (no cost is called slower or faster)")


def compare_stores(store_a, store_b, threshold=2.0, cost_threshold=None, across_versions=False, pair_options=None,
                   pair_engines=None):
    """Compare ``store_a`` (before) with ``store_b`` (after); a ``Comparison``.

    ``pair_options``: ``(options_a, options_b)``, each a dict key -> value (as text; ``UNSET``, "default": the
    option not given): compare A's runs with ``options_a`` against B's with ``options_b``, every other option and
    setting equal (two configurations of one engine; ``store_a`` and ``store_b`` may be one store). Runs without
    them are left out of the comparison.

    ``pair_engines``: ``(engine_a, engine_b)``: compare A's runs of ``engine_a`` against B's of ``engine_b``, every
    setting equal (two versions of one engine, ``mujoco==3.6.0`` against ``mujoco``: the gate an engine's CI runs
    across releases; ``store_a`` and ``store_b`` may be one store). Runs of other engines are left out.
    """
    ra, rb = store_a.records(), store_b.records()
    manifests = store_a.manifest(), store_b.manifest()
    once = _timed_once(manifests)
    warnings = []
    pairing = ()
    if pair_engines:
        engine_a, engine_b = pair_engines
        kept = [r for r in ra if r.engine == engine_a], [r for r in rb if r.engine == engine_b]
        warnings.append(f"pairing A's runs of {engine_a} against B's of {engine_b}, all else equal: "
                        f"{len(ra) - len(kept[0])} of A's {len(ra)} runs and {len(rb) - len(kept[1])} of B's "
                        f"{len(rb)} of other engines are left out")
        ra, rb = kept
    if pair_options:
        opts_a, opts_b = (dict(o) for o in pair_options)
        pairing = (opts_a, opts_b)
        drop = set(opts_a) | set(opts_b)
        kept_a, kept_b = [r for r in ra if _has(r, opts_a)], [r for r in rb if _has(r, opts_b)]
        warnings.append(f"pairing A's runs with {_words(opts_a)} against B's with {_words(opts_b)}, all else equal: "
                        f"{len(ra) - len(kept_a)} of A's {len(ra)} runs and {len(rb) - len(kept_b)} of B's {len(rb)} "
                        "without those options are left out")
        a, b = ({_key(r, drop, bool(pair_engines)): r for r in kept_a},
                {_key(r, drop, bool(pair_engines)): r for r in kept_b})
    else:
        kept_a, kept_b = ra, rb
        a, b = {_key(r, (), bool(pair_engines)): r for r in ra}, {_key(r, (), bool(pair_engines)): r for r in rb}
    changes, not_compared = [], []
    for key in sorted(set(a) & set(b), key=str):
        x, y = a[key], b[key]
        differs = check_version(x.case, x.case_version, y.case_version, "the first store's runs are of",
                                now="in the second store")
        if differs and not across_versions:
            not_compared.append((x, y, f"case version differs ({differs})"))
            continue
        changes.append(_change(x, y, threshold, cost_threshold, costs_judged=once is None))
    changes.sort(key=lambda c: (not c.regression, CHANGES.index(c.change), c.label))
    only_a = tuple(sorted((a[k] for k in set(a) - set(b)), key=label))
    only_b = tuple(sorted((b[k] for k in set(b) - set(a)), key=label))
    stats = {c: sum(1 for x in changes if x.change == c) for c in CHANGES}
    unpaired = "" if changes or not_compared else unpaired_reason(kept_a, kept_b, pairing)
    if not changes and not_compared:
        unpaired = (f"no run compared: the {len(not_compared)} run(s) in both are of another case version "
                    "(compare them anyway with --across-versions)")
    return Comparison(tuple(changes), only_a, only_b, tuple(not_compared),
                      tuple(warnings + _differences(*manifests, kept_a, kept_b) + ([once] if once else [])),
                      (store_a.path, store_b.path), threshold, cost_threshold, stats, unpaired, pairing)


def _words(options):
    return " ".join(f"{k}={v}" for k, v in sorted(options.items()))


# ---------------------------------------------------------------------------------------------- output
MARKS = {"worse": "+", "better": "-", "status": "!", "same": " "}


def _fmt(x):
    return "—" if x is None or not math.isfinite(x) else f"{x:.3e}"


def _mark(ratio, threshold):
    return "+" if ratio > threshold else "-" if ratio < 1.0 / threshold else " "


def _lines(c, only_changed, threshold):
    """Text lines of one change, each marked by its own change: the headline error and the cost,
    and every error that changed (with ``only_changed``: the changed lines alone)."""
    if only_changed and c.change == "same":
        return []
    if not (c.a.ok and c.b.ok):  # nothing measured on one side: its status says what happened
        what = c.notes[0] if c.notes else f"{c.b.status} in both"
        return [f"{'+' if c.regression else '!'} {'':>10} {'':>10} {'':>8}  {'status':<24} {c.label}: {what}"]
    headline = headline_quantity([c.a, c.b])
    out = []
    for q, (before, after, ratio) in c.errors.items():
        mark = _mark(ratio, threshold) if math.isfinite(ratio) else " "
        if (mark != " " or q == headline) and not (only_changed and mark == " "):
            out.append(f"{mark} {_fmt(before):>10} {_fmt(after):>10} {ratio:>8.3g}  "
                       f"{q + ' (' + QUANTITIES[q] + ')':<24} {c.label}")
    ca, cb = c.a.cost, c.b.cost
    mark = {"slower": "+", "faster": "-"}.get(c.cost_change, " ")
    spread = ("one sample each: not judged" if c.cost_change == "unjudged" else f"min–max {_fmt(ca.wall_s_min)}–"
              f"{_fmt(ca.wall_s_max)} -> {_fmt(cb.wall_s_min)}–{_fmt(cb.wall_s_max)}")
    if not (only_changed and mark == " "):
        out.append(f"{mark} {_fmt(ca.wall_s_median):>10} {_fmt(cb.wall_s_median):>10} {c.cost_ratio:>8.3g}  "
                   f"{'cost (s)':<24} {c.label}  [{spread}]")
    for q in c.missing:
        unit = f" ({QUANTITIES[q]})" if q in QUANTITIES else ""
        before = c.a.max_error(q) if q in QUANTITIES else c.a.drifts.get(q.split(":", 1)[1], math.nan)
        out.append(f"+ {_fmt(before):>10} {'missing':>10} {'':>8}  {q + unit:<24} {c.label}: missing after")
    if c.a.judgement.verdict != c.b.judgement.verdict and c.a.judgement.verdict and c.b.judgement.verdict:
        out.append(f"{'+' if c.b.judgement.verdict == 'diverged' else '!'} {'':>10} {'':>10} {'':>8}  {'verdict':<24} "
                   f"{c.label}: {c.a.judgement.verdict} -> {c.b.judgement.verdict}")
    return out


def to_text(cmp, only_changed=False):
    """The comparison as asv prints one: before, after, ratio, what, which run; then the runs in
    one store only (not with ``only_changed``: they are no run's change); then a one-line
    count. Every line's control characters escaped (``printable``): it is for a terminal."""
    out = [f"before: {cmp.paths[0]}", f"after:  {cmp.paths[1]}"] if cmp.paths else []
    out += [f"warning: {w}" for w in cmp.warnings]
    if cmp.unpaired:
        out.append(f"nothing compared: {cmp.unpaired}")
    body = [line for c in cmp.changes for line in _lines(c, only_changed, cmp.threshold)]
    if body:
        out += ["", f"  {'before':>10} {'after':>10} {'ratio':>8}  {'quantity':<24} run",
                f"  (+ worse, - better by more than x{cmp.threshold:g} for errors (maxima over the horizon), beyond "
                f"both min–max spreads and x{COST_NOTICE:g} for the cost (median stepping time); ! status or "
                "verdict changed)"]
        out += body
    for title, runs in (("only in A (before)", cmp.only_in_a), ("only in B (after)", cmp.only_in_b)):
        if runs and not only_changed:
            out += ["", f"{title}: {len(runs)}"] + [f"  {label(r)}" for r in runs]
    if cmp.not_compared:  # kept with only_changed: a case that changed version may hide a regression
        out += ["", f"not compared: {len(cmp.not_compared)}"] + [f"  {label(y)}: {why}" for _, y, why in
                                                                 cmp.not_compared]
    s = cmp.stats
    out += ["", f"{len(cmp.changes)} runs in both: {s['worse']} worse, {s['better']} better, {s['status']} changed "
                f"status, {s['same']} unchanged; {len(cmp.only_in_a)} only in A, {len(cmp.only_in_b)} only in B, "
                f"{len(cmp.not_compared)} not compared" + (" — REGRESSION" if cmp.regressed else "")]
    return "\n".join(printable(line, newlines=False) for line in out) + "\n"


def _identity(r):
    """A run's identity as the JSON and CSV outputs write it (parameters as given, options as words)."""
    i = _key(r)
    return {"case": i.case, "params": r.params, "engine": i.engine, "integrator": i.integrator, "dt": i.dt,
            "rtol": i.rtol, "atol": i.atol, "options": r.options_label, "label": label(r)}


def _num(x):
    return x if x is not None and math.isfinite(x) else None


def _cost_json(cost):
    return {"median": _num(cost.wall_s_median), "min": _num(cost.wall_s_min), "max": _num(cost.wall_s_max),
            "repeats": cost.repeats}


def to_json(cmp):
    """The comparison as a JSON-able dict: before/after/ratio per run for every error and the cost."""
    runs = [{**_identity(c.b), "change": c.change, "regression": c.regression, "notes": list(c.notes),
             "missing_after": list(c.missing),
             "status": {"before": c.a.status, "after": c.b.status},
             "verdict": {"before": c.a.judgement.verdict, "after": c.b.judgement.verdict},
             "errors": {q: {"unit": QUANTITIES[q], "before": _num(x), "after": _num(y), "ratio": _num(r)}
                        for q, (x, y, r) in c.errors.items()},
             "cost": {"unit": "s", "before": _cost_json(c.a.cost), "after": _cost_json(c.b.cost),
                      "ratio": _num(c.cost_ratio), "change": c.cost_change}} for c in cmp.changes]
    return {"before": cmp.paths[0] if cmp.paths else None, "after": cmp.paths[1] if cmp.paths else None,
            "threshold": cmp.threshold, "cost_threshold": cmp.cost_threshold, "warnings": list(cmp.warnings),
            "regressed": cmp.regressed, "counts": dict(cmp.stats), "runs": runs, "unpaired": cmp.unpaired or None,
            "pair_options": ({"a": cmp.pairing[0], "b": cmp.pairing[1]} if cmp.pairing else None),
            "only_in_a": [_identity(r) for r in cmp.only_in_a], "only_in_b": [_identity(r) for r in cmp.only_in_b],
            "not_compared": [{**_identity(y), "reason": why} for _, y, why in cmp.not_compared]}


CSV_COLUMNS = ("case", "params", "engine", "integrator", "dt", "rtol", "atol", "options", "label", "in",
               "quantity", "unit", "before", "after", "ratio", "before_min", "before_max", "after_min", "after_max",
               "change")


def csv_rows(cmp):
    """Long rows (``CSV_COLUMNS``): one per run and error, one per run for the cost (with both
    spreads), one per run in a single store (``in`` = A or B); ``change`` is that quantity's."""
    rows = []
    for c in cmp.changes:
        ident = {**_identity(c.b), "params": json.dumps(c.b.params, sort_keys=True, default=list), "in": "both"}
        for q, (x, y, r) in c.errors.items():
            change = {"+": "worse", "-": "better"}.get(_mark(r, cmp.threshold), "same") if math.isfinite(r) else ""
            change = "missing after" if q in c.missing else change
            rows.append({**ident, "quantity": q, "unit": QUANTITIES[q], "before": x, "after": y, "ratio": r,
                         "change": change})
        ca, cb = c.a.cost, c.b.cost
        rows.append({**ident, "quantity": "cost", "unit": "s", "before": ca.wall_s_median, "after": cb.wall_s_median,
                     "ratio": c.cost_ratio, "before_min": ca.wall_s_min, "before_max": ca.wall_s_max,
                     "after_min": cb.wall_s_min, "after_max": cb.wall_s_max, "change": c.cost_change})
    for side, runs in (("A", cmp.only_in_a), ("B", cmp.only_in_b)):
        rows += [{**_identity(r), "params": json.dumps(r.params, sort_keys=True, default=list), "in": side}
                 for r in runs]
    return [{k: row.get(k, "") for k in CSV_COLUMNS} for row in rows]
