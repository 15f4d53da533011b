"""The hazards: per case, what to know before trusting a setting, each naming its runs."""

from __future__ import annotations

from dalembert.reports.findings import CLOSURE_GROWTH, DISAGREEMENT_FACTOR, ENERGY_HAZARD, HAZARDS, NAMED
from dalembert.reports.page import Part
from dalembert.reports.tables import escape_html, escape_md

__all__ = ["hazards", "HAZARD_TITLES"]

HAZARD_TITLES = {"diverged": "Diverged", "failed": "Stopped early", "energy": "Energy not kept",
                 "creep": "Creeps where it must stick",
                 "closure": "Loops still opening", "reactions": "Motion right, reactions wrong",
                 "tolerance": "Finite but beyond the tolerance", "inert": "A tolerance changed nothing",
                 "disagreement": "Engines disagree", "unsupported": "Not supported (not run, not drawn)"}


def hazards(rep):
    """The hazards section (a ``Part``): a list per case and kind of hazard."""
    part = Part()
    part.heading("Hazards", 2, anchor="hazards")
    part.para("What to know before trusting a setting: every run named is in its case's table of runs. Energy is "
              f"judged against {100 * ENERGY_HAZARD:g} % of its scale over the horizon, disagreement at a factor "
              f"{DISAGREEMENT_FACTOR:g} between engines with the same integrator and step, beyond the case's "
              "tolerance (an adaptive run only where both rtol and atol were given and its tolerance changed its "
              "result); a tolerance changed nothing when two tolerances of one integrator gave the same "
              f"trajectory; a loop is still opening when its closure residual is beyond the case's bound and its "
              f"largest value over the horizon's last quarter is more than {CLOSURE_GROWTH:g} times that over its "
              "first half.")
    if any(h.kind == "creep" for f in rep.found for h in f.hazards):  # (said only where it applies)
        part.para("A run creeps where its case's closed form sticks when its creep (the body's mean speed along the "
                  "plane over the phase the closed form holds it still) is beyond the case's bound.")
    for f in rep.found:
        if not f.hazards:
            continue
        part.heading(rep.titles[f], 3)
        for kind in HAZARDS:
            mine = [h for h in f.hazards if h.kind == kind]
            if not mine:
                continue
            html = [f'<p class="hz">{escape_html(HAZARD_TITLES[kind])}</p><ul>']
            md = [f"*{escape_md(HAZARD_TITLES[kind])}*", ""]
            for h in mine:
                listed = len(h.details) > NAMED  # the sentence names only a few: every run in a list beside it
                runs = (f"<details><summary>the {len(h.details)} runs</summary><ul>"
                        + "".join(f"<li>{escape_html(d)}</li>" for d in h.details) + "</ul></details>") if listed else ""
                html.append(f"<li>{escape_html(h.text)}{runs}</li>")
                md.append(f"- {escape_md(h.text)}")
                if listed:
                    md += [f"  <details><summary>the {len(h.details)} runs</summary>", ""]
                    md += [f"  - {escape_md(d)}" for d in h.details] + ["", "  </details>"]
            html.append("</ul>")
            md.append("")
            part.raw("".join(html), md)
    return part
