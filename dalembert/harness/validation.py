"""``dalembert validate``: the reference solver against every case's truth, with several
integrators and formulations.

It is a matrix over the reference engine — the same specs, pool, records and store as
``dalembert run`` — tabulated per case (Markdown and CSV). A run that fails is a row
with its status and message, never a crash of the suite.

A case without a closed form has the reference solver itself for its truth: its rows measure
how the reference converges to its own tight solution, not whether it is right, and the row
run with the truth's own settings compares the truth with itself (an error of roundoff,
"within tol" by construction). The tables say so (``truth`` names the source, that row is
marked ``the truth itself``, its ``within tol`` is no verdict); the independent check of such a
truth is ``dalembert.testing.second_solution`` (another integrator family and formulation),
which the case contract (``dalembert.testing.check_case``) runs.
"""

from __future__ import annotations

import math

from dalembert.harness.execute import QUICK
from dalembert.harness.matrix import spec
from dalembert.harness.pool import run_matrix
from dalembert.settings import Settings

__all__ = ["DEFAULT_SETTINGS", "FREE_BODY_EXTRA", "TIMING", "settings_for", "validation_specs", "validate",
           "to_markdown", "write_csv", "is_the_truth", "CLOSED_FORM"]

# What ``dalembert.harness.truths.truth_source`` stores for a truth that is not the reference's.
CLOSED_FORM = "closed form"

# What the validation runs per case. dt = 1e-3 is the step the engine issues
# quote their accuracy at; the two extra formulations cross-check Newton-Euler.
DEFAULT_SETTINGS = (
    Settings("dop853", rtol=1e-12, atol=1e-12),
    Settings("rk4", dt=1e-3),
    Settings("rkmk4", dt=1e-3),
    Settings("euler", dt=1e-3),
    Settings("euler", dt=1e-4),
)
FREE_BODY_EXTRA = (
    Settings("rk4", dt=1e-3, options={"formulation": "newton-euler-matrix"}),
    Settings("rk4", dt=1e-3, options={"formulation": "kane"}),
)
TIMING = QUICK  # accuracy is what is validated, not cost: each run is timed once


def settings_for(case):
    """The settings the validation runs on ``case``."""
    free = all(j.kind == "free" for j in case.scene.joints)
    return DEFAULT_SETTINGS + (FREE_BODY_EXTRA if free else ())


def validation_specs(case_names=None, notes=None):
    """Specs of the validation matrix: the named cases (default: every case in the default matrix;
    a name given twice counts once, and ``notes`` says so)."""
    from dalembert.case import in_default_matrix, load_cases
    from dalembert.harness.selection import names as unique_names

    registry = load_cases()
    names = unique_names("--case", case_names, [] if notes is None else notes) or [
        n for n, f in registry.items() if in_default_matrix(f)]
    factories = [registry[n] for n in names]  # unknown names fail here, before anything runs
    return [spec(case, "reference", s) for case in (f() for f in factories) for s in settings_for(case)]


def validate(store, case_names=None, jobs=None, progress=None, specs=None):
    """Run the validation matrix (``specs``, default ``validation_specs(case_names)``) into ``store``
    (created by the caller); returns its records."""
    run_matrix(validation_specs(case_names) if specs is None else specs, store, jobs, timing=TIMING,
               progress=progress)
    return store.records()


def is_the_truth(record, case):
    """Whether ``record`` (a RunRecord) ran with the very settings that made the truth of ``case``
    (a CaseRecord): its error is the truth against itself, no check of anything."""
    return case.truth != CLOSED_FORM and case.truth.endswith(", " + record.settings_label)


def _fmt(x):
    if isinstance(x, bool):
        return "yes" if x else "**no**"
    if isinstance(x, float):
        return "—" if math.isnan(x) else f"{x:.2e}"
    return str(x)


def to_markdown(store):
    """A Markdown table per case: errors (max over the horizon), invariant drifts and checks."""
    lines = ["# dalembert — reference solver against the closed forms", "",
             "Errors are the maximum over the horizon against the case's truth; drifts are the maximum change "
             "of each conserved quantity (see `dalembert.invariants`). `within tol` compares with the case's "
             "named tolerances.", ""]
    records = store.records()
    for name in sorted({r.case for r in records}):
        runs = [r for r in records if r.case == name]
        case = store.case(name, runs[0].case_version)
        lines += [f"## {name} (version {case.version})", ""]
        lines += [f"- tolerance `{k}`: {t.value:g} — {t.reason}" for k, t in case.tolerances.items()]
        if case.truth != CLOSED_FORM:
            lines.append(f"- truth: {case.truth} — no closed form, so no independent check here: each row measures "
                         "the reference against its own tight solution (convergence, not correctness), and a row "
                         "run with the truth's own settings (marked *the truth itself*) compares the truth with "
                         "itself; the independent check is "
                         "`dalembert.testing.second_solution`, run by the case contract (`check_case`)")
        else:
            lines.append("- truth: closed form (independent of the solver)")
        lines.append("")
        errors = sorted({q for r in runs for q in r.errors})
        drifts = sorted({n for r in runs for n in r.drifts})
        checks = sorted({c for r in runs for c in r.checks})
        head = ["settings", "status", "wall s", "RHS evals"] + errors + [f"drift:{n}" for n in drifts] + checks
        lines += ["| " + " | ".join(head + ["within tol"]) + " |", "|" + "---|" * (len(head) + 1)]
        for r in sorted(runs, key=lambda r: r.settings_label):
            cells = [r.settings_label, r.status if r.ok else f"{r.status}: {r.message}", _fmt(r.cost.wall_s_median),
                     str(r.cost.n_rhs)]
            cells += [_fmt(r.max_error(q)) for q in errors] + [_fmt(r.drifts.get(n, math.nan)) for n in drifts]
            cells += [_fmt(r.checks.get(c, math.nan)) for c in checks]
            within = r.judgement.within_tolerance
            # a bound the run did not report is not measured: neither yes nor no (``dalembert.judge``)
            missing = r.judgement.not_measured
            shown = f"not measured: {', '.join(missing)}" if within is None and missing else _fmt(bool(within))
            cells.append("— (the truth itself)" if is_the_truth(r, case) else shown)
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def write_csv(store, path):
    """Every validation run as one CSV row, numbers at full precision (17 significant digits);
    ``truth`` names each case's truth, ``is_the_truth`` marks the row that is that truth itself."""
    table = store.table().drop(columns=["traceback", "audit", "model"], errors="ignore")
    records = {r.key: r for r in store.records()}
    cases = {(r.case, r.case_version): store.case(r.case, r.case_version) for r in records.values()}
    case_of = {k: cases[(r.case, r.case_version)] for k, r in records.items()}
    table["truth"] = [case_of[k].truth for k in table["key"]]
    table["is_the_truth"] = [is_the_truth(records[k], case_of[k]) for k in table["key"]]
    table.sort_values(["case", "settings"]).to_csv(path, index=False, float_format="%.17g")
