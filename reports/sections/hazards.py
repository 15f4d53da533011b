"""The hazards: per case, what to know before trusting a setting, each naming its runs — the ones that mean
something (``reports.hazards.LISTED``: a run that blew up, stopped, lost its energy, crept, kept opening its loop, got its reactions
wrong, or engines disagreeing for a cause the store names); the rest (beyond the tolerance: the tables' business,
disagreements without a named cause, tolerances that changed nothing, what an engine cannot run) folded below."""

from __future__ import annotations

from dalembert.reports.findings import CLOSURE_GROWTH, DISAGREEMENT_FACTOR, ENERGY_HAZARD, HAZARDS, NAMED
from dalembert.reports.hazards import LISTED_RUNS, listed
from dalembert.reports.page import Part
from dalembert.reports.tables import escape_html, escape_md
from dalembert.refusal import manifest_refusals

__all__ = ["hazards", "HAZARD_TITLES"]

HAZARD_TITLES = {"diverged": "Diverged", "failed": "Stopped early", "energy": "Energy not kept",
                 "creep": "Creeps where it must stick",
                 "closure": "Loops still opening", "reactions": "Motion right, reactions wrong",
                 "tolerance": "Finite but beyond the tolerance", "inert": "A tolerance changed nothing",
                 "disagreement": "Engines disagree", "unsupported": "Not supported (not run, not drawn)"}


def _count(h):
    """The runs hazard ``h`` lists (its ``details``: the first ``LISTED_RUNS`` of them): all its runs, or 0 where it
    lists none."""
    return len(h.runs) if h.details else 0


def _listed(h):
    """The lines hazard ``h`` lists: its ``details``, and past ``LISTED_RUNS`` runs, the first ones and a line counting
    the rest."""
    n = _count(h)
    if n <= LISTED_RUNS:
        return list(h.details)
    return list(h.details[:LISTED_RUNS]) + [f"… and {n - LISTED_RUNS} more runs (every run is in the store: "
                                            "dalembert export --all)"]


def _block(mine_by_kind):
    """HTML and Markdown of hazards grouped by kind (``[(kind, [Hazard])]``)."""
    html, md = [], []
    for kind, mine in mine_by_kind:
        title = HAZARD_TITLES[kind] + (" (cause named)" if kind == "disagreement" and mine[0].causes else "")
        html.append(f'<p class="hz">{escape_html(title)}</p><ul>')
        md += [f"*{escape_md(title)}*", ""]
        for h in mine:
            text = h.text + (" Cause: " + "; ".join(h.causes) + "." if h.causes else "")
            n = _count(h)
            many = n > NAMED  # the sentence names only a few: every run in a list beside it
            shown = _listed(h) if many else []
            runs = (f"<details><summary>the {n} runs</summary><ul>"
                    + "".join(f"<li>{escape_html(d)}</li>" for d in shown) + "</ul></details>") if many else ""
            html.append(f"<li>{escape_html(text)}{runs}</li>")
            md.append(f"- {escape_md(text)}")
            if many:
                md += [f"  <details><summary>the {n} runs</summary>", ""]
                md += [f"  - {escape_md(d)}" for d in shown] + ["", "  </details>"]
        html.append("</ul>")
        md.append("")
    return html, md


def _grouped(hs):
    return [(k, [h for h in hs if h.kind == k]) for k in HAZARDS if any(h.kind == k for h in hs)]


def hazards(rep):
    """The hazards section (a ``Part``): the listed hazards per case, then the rest folded."""
    part = Part()
    part.heading("Hazards", 2, anchor="hazards")
    part.para(f"What to know before trusting a setting (every run named is in its case's table of runs): divergence, "
              f"early stops, energy changed by more than {100 * ENERGY_HAZARD:g} % of its scale, creep, loops still "
              f"opening (closure residual beyond the bound and its last quarter's peak more than {CLOSURE_GROWTH:g} "
              f"times its first half's), reactions wrong under a right motion, and engines disagreeing (a factor "
              f"{DISAGREEMENT_FACTOR:g} at one integrator and step, beyond the tolerance) where the store names a "
              "cause. A run beyond its case's tolerance is in the tables, not here.")
    if any(h.kind == "creep" for f in rep.found for h in f.hazards):  # (said only where it applies)
        part.para("A run creeps where its case's closed form sticks when its creep (the body's mean speed along the "
                  "plane over the phase the closed form holds it still) is beyond the case's bound.")
    rest_html, rest_md, counts = [], [], {}
    for f in rep.found:
        shown = [h for h in f.hazards if listed(h)]
        if shown:  # one line per case, its list folded under it
            said = ", ".join(f"{HAZARD_TITLES[k].lower()} ({len(hs)})" for k, hs in _grouped(shown))
            html, md = _block(_grouped(shown))
            part.raw(f'<details class="fold"><summary><b>{escape_html(rep.titles[f])}</b>: {escape_html(said)}'
                     f"</summary>{''.join(html)}</details>", [f"### {escape_md(rep.titles[f])}", ""] + md)
        folded = [h for h in f.hazards if not listed(h)]
        if folded:
            html, md = _block(_grouped(folded))
            rest_html += [f"<h4>{escape_html(rep.titles[f])}</h4>"] + html
            rest_md += [f"#### {escape_md(rep.titles[f])}", ""] + md
            for h in folded:
                counts[h.kind] = counts.get(h.kind, 0) + 1
    # a case every selected engine refused has no run, so no findings of its own: its refusals are listed here
    run_cases = {(f.case.name, f.case.version) for f in rep.found}
    orphans = [r for r in manifest_refusals(rep.manifest) if (r.case, r.case_version) not in run_cases]
    for r in sorted(orphans, key=lambda r: (r.case, r.params, r.engine, r.reason)):
        params = ", ".join(f"{k}={v}" for k, v in r.params)
        text = f"{r.engine} cannot run {r.case}{f' ({params})' if params else ''} with {r.what}: {r.reason}"
        rest_html.append(f"<ul><li>{escape_html(text)}</li></ul>")
        rest_md += [f"- {escape_md(text)}", ""]
        counts["unsupported"] = counts.get("unsupported", 0) + 1
    if counts:
        summary = ("The rest: " + ", ".join(f"{HAZARD_TITLES[k].lower()} ({n})" for k, n in
                                            sorted(counts.items(), key=lambda kv: HAZARDS.index(kv[0])))
                   + " — disagreements here have no cause the store names")
        part.raw(f"<details><summary>{escape_html(summary)}</summary>{''.join(rest_html)}</details>",
                 [f"<details><summary>{escape_html(summary)}</summary>", ""] + rest_md + ["</details>", ""])
    return part
