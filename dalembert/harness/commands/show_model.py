"""``dalembert show-model``: the model an engine builds for a case (MJCF, an Exudyn system, ...),
or why the engine does not run it and which of its variants would."""

from __future__ import annotations

import sys

from dalembert.harness.commands.console import fail
from dalembert.harness.selection import given, pairs
from dalembert.registry import UnknownNameError
from dalembert.scene import SceneError

__all__ = ["run", "main", "describe"]


def describe(case_name, engine, integrator=None, dt=1e-3, params=(), options=()):
    """``(text, None)``: the model ``engine`` builds for ``case_name`` (``params``, ``options``:
    ``KEY=VALUE`` texts, each key once) with ``integrator`` (default: the engine's first that runs
    the case) at step ``dt`` (s); or ``(None, why)`` when the engine does not run it. ValueError,
    KeyError or ImportError naming the field on a bad input."""
    from dalembert.adapters import get_adapter
    from dalembert.case import load_cases, parse_param
    from dalembert.settings import Settings

    factory = load_cases()[given("case", case_name)]
    case = factory(**dict(parse_param(factory, f"{k}={v}") for k, v in pairs("--param", params).items()))
    options = pairs("--option", options)
    adapter = get_adapter(given("--engine", engine))

    def settings(integ, opts):
        spec = adapter.integrators.get(integ)
        if spec is None or spec.fixed_step:
            return Settings(integ, dt=dt, options=opts)
        return Settings(integ, rtol=1e-8, atol=1e-8, options=opts)

    def first_supported(opts):
        """(settings, None) for the first integrator that runs the case with ``opts``, else
        (the last settings tried, the reason)."""
        reason = None
        for integ in [integrator] if integrator else list(adapter.integrators):
            chosen = settings(integ, opts)
            adapter.check(case.scene, case.times, chosen)
            reason = adapter.unsupported(case.scene, chosen)
            if reason is None:
                return chosen, None
        return chosen, reason

    chosen, reason = first_supported(options)
    if reason is not None:  # say so, and which of the engine's own variants would run it
        runs = [o for o in adapter.variants(case.scene) if o != options and first_supported(o)[1] is None]
        hint = ("; it runs with " + " or ".join(" ".join(f"--option {k}={v}" for k, v in sorted(o.items()))
                                                or "its default options" for o in runs)) if runs else ""
        what = " ".join(f"{k}={v}" for k, v in sorted(options.items())) or "its default options"
        if integrator:  # the same options may run with another integrator
            others = [i for i in adapter.integrators if i != integrator
                      and adapter.unsupported(case.scene, settings(i, options)) is None]
            if others:
                hint += f"; with {what} it runs {', '.join(others)}"
        which = chosen.integrator if integrator else "any integrator"
        return None, f"unsupported: {engine} does not run {case_name} ({which}, {what}): {reason}{hint}"
    text = adapter.describe(case.scene, chosen)
    if not text.strip():
        return None, f"{engine} describes no model for {case_name} with {chosen.integrator}"
    return text, None


def run(case, engine, integrator=None, dt=1e-3, params=(), options=()):
    """Print the model (``describe``); returns the exit status: 0, 1 when the engine does not run
    the case, 2 on a bad input."""
    try:
        text, why = describe(case, engine, integrator, dt, params, options)
    except (UnknownNameError, ValueError, SceneError, ImportError) as e:
        return fail(str(e))
    if why is not None:
        print(f"dalembert: {why}", file=sys.stderr)
        return 1
    print(text, end="" if text.endswith("\n") else "\n")
    return 0


def main(args):
    return run(args.case, args.engine, args.integrator, args.dt, args.param, args.option)
