"""``dalembert check-engine NAME``: the probes of ``dalembert.engine_check`` on one engine; every problem printed
with its probe, what it saw and what to look at; exit 1 when there is any."""

from __future__ import annotations

from dalembert.terminal import printable

__all__ = ["run", "main"]


def run(engine, integrators=None, options=None, verbose=False, out=print):
    """Probe ``engine`` (``integrators``: the ones to probe, default every one; ``options``: KEY=VALUE texts for
    every run whose integrator takes them) and print what was found through ``out``.

    Returns the exit status: 0 when no probe found a problem, 1 when any did. ValueError naming the flag (an
    unknown integrator or option), ImportError when the engine is not installed, before any probe runs.
    """
    from dalembert.engine_check import check_engine
    from dalembert.harness.selection import pairs

    found = check_engine(engine, integrators, pairs("--option", options))
    head = f"check-engine {engine} ({', '.join(found.integrators)}): {len(found.probes)} probes, "
    out(head + (f"{len(found.problems)} problem{'s' if len(found.problems) != 1 else ''}" if found.problems
                else "no problems"))
    for p in found.problems:
        out(printable(f"  {p.probe}: {p.saw}"))
        out(printable(f"      look at: {p.look_at}"))
    if verbose or found.problems:
        for text in found.notes:
            out(printable(f"  note: {text}"))
    return 1 if found.problems else 0


def main(args):
    return run(args.engine, args.integrator, args.option, args.verbose)
