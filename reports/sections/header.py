"""The report's head: what was run, where and when, warnings on the timings, and the page's links."""

from __future__ import annotations

from dalembert.reports.page import Part
from dalembert.reports.sections.common import section_id
from dalembert.reports.tables import escape_html
from dalembert.reports.timing import once_note, timing_note

__all__ = ["header", "page_title"]


def page_title(rep):
    """The page's title (a ``Part``): first, so the answers (``sections.recommend``) follow it at once."""
    part = Part()
    part.heading("dalembert report", 1)
    return part


def header(rep, answers=()):
    """The machine and command the store was run with, warnings on the timings, and the navigation (a ``Part``);
    ``answers``: ``(anchor, text)`` of the sections above it, linked first."""
    part, manifest = Part(), rep.manifest
    machine = manifest.get("machine", {})
    part.para(f"{len(rep.records)} runs on {machine.get('cpu')} ({machine.get('cores')} cores), {machine.get('os')}, "
              f"Python {machine.get('python')}; engines "
              + ", ".join(f"{k} {v}" for k, v in sorted(manifest.get("engines", {}).items()))
              + f"; harness {manifest.get('harness_version')} at {manifest.get('harness_commit')}; "
              f"command: {manifest.get('command')}; {manifest.get('started')} to {manifest.get('ended')}.")
    for note in (timing_note(manifest, rep.records), once_note(manifest)):
        if note:
            part.para(note, cls="warning")
    links = list(answers) + [("findings", "findings"), ("hazards", "hazards")] + [(section_id(f), rep.titles[f]) for f in rep.found]
    part.raw("<nav>" + "".join(f'<a href="#{escape_html(a)}">{escape_html(t)}</a>' for a, t in links) + "</nav>")
    return part
