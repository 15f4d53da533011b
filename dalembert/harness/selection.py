"""The ``run`` command's flags, checked: every one means something or is refused, before anything runs.

Refused, naming the flag and the fix: empty lists (``--dt ,``), non-positive or
non-finite steps, tolerances, timeouts; a parameter no selected case has
(did-you-mean from those cases), the same parameter or option given twice, an
empty ``--out``; ``--rtol`` when no selected integrator is adaptive, ``--dt``
when none is fixed-step. Merged and said once: a value given twice in a list.
Capped and said: ``--jobs`` beyond the cores (the timings would share them).

A parameter sweeps when given several values: ``spin=5,50,500`` (a scalar's values
comma-separated), ``spin=log:5,500,7`` or ``lin:0,1,5`` (``n`` values log- or evenly
spaced from ``a`` to ``b``), ``omega0=0,1,5;0,2,5`` (a vector's values separated by ``;``).
Each value makes its own case variant (its own version); several swept parameters form
their product.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dalembert.registry import suggest

__all__ = ["Selection", "select", "numbers"]


@dataclass(frozen=True)
class Selection:
    """What ``dalembert run`` will do: its specs, and what the user is told about them."""

    specs: list
    skipped: list  # engines not installed (when none was named)
    notes: list  # merged duplicates, capped jobs, options that apply to some engines only
    jobs: int
    timeout: float
    searches: tuple = ()  # (first probes, resolution) of each boundary search: --search dt, or a map


def numbers(flag, groups, notes, lower=0.0):
    """The numbers of a repeatable comma-separated flag (``groups``: one list per use), checked:
    ValueError on an empty use or a value that is not finite and above ``lower``; a value given
    twice is kept once and ``notes`` says so."""
    values = []
    for group in groups or []:
        if not group:
            raise ValueError(f"{flag}: no value given — write e.g. {flag} 1e-2,1e-3")
        values += group
    bad = [x for x in values if not (math.isfinite(x) and x > lower)]
    if bad:
        raise ValueError(f"{flag}: must be positive and finite, got {bad}")
    unique = list(dict.fromkeys(values))
    if len(unique) < len(values):
        notes.append(f"{flag}: {', '.join(f'{x:g}' for x in unique if values.count(x) > 1)} given more than once; "
                     "each runs once")
    return unique


def sweep(factory, key, text):
    """The values ``text`` gives parameter ``key`` of ``factory`` (one or several: a sweep), each
    typed as the parameter's default; ValueError naming ``--param`` otherwise."""
    from dalembert.case import parse_param

    default = factory.params[key]
    grid = text.split(":", 1)
    if len(grid) == 2 and grid[0] in ("log", "lin"):
        if not isinstance(default, float):
            raise ValueError(f"--param {key}={text}: a {grid[0]}: grid sweeps a real number; {key!r} is "
                             f"{type(default).__name__} like {default!r}")
        try:
            a, b, n = (float(x) for x in grid[1].split(","))
        except ValueError:
            raise ValueError(f"--param {key}={text}: write {grid[0]}:FIRST,LAST,COUNT") from None
        if not (n >= 2 and n == int(n)) or (grid[0] == "log" and not (a > 0 and b > 0)):
            raise ValueError(f"--param {key}={text}: COUNT must be an integer >= 2"
                             + (", FIRST and LAST positive" if grid[0] == "log" else ""))
        points = (np.geomspace if grid[0] == "log" else np.linspace)(a, b, int(n))
        return [float(v) for v in points]
    parts = text.split(";") if isinstance(default, tuple) else text.split(",")
    if any(not p.strip() for p in parts):
        raise ValueError(f"--param {key}={text}: an empty value — separate values with "
                         + ("';' (a vector's numbers with ',')" if isinstance(default, tuple) else "','"))
    values = [parse_param(factory, f"{key}={p}")[1] for p in parts]
    return list(dict.fromkeys(values))


def _pairs(flag, texts):
    """``KEY=VALUE`` texts as (key, value) pairs; ValueError on a malformed or repeated key."""
    pairs = {}
    for text in texts:
        if "=" not in text or not text.split("=", 1)[0]:
            raise ValueError(f"{flag} {text!r}: write KEY=VALUE")
        key, value = text.split("=", 1)
        if key in pairs:
            raise ValueError(f"{flag} {key}: given twice ({pairs[key]!r} and {value!r}) — give it once"
                             + (" (several values sweep it: KEY=V1,V2)" if flag == "--param" else ""))
        pairs[key] = value
    return pairs


def select(args, cores):
    """Check the ``run`` flags in ``args`` (argparse namespace) and expand the matrix.

    ``cores``: this machine's cores (``--jobs`` beyond them is capped). Raises ValueError,
    KeyError (unknown names, with did-you-mean) or ImportError (a named engine not installed),
    each naming the flag, before anything runs.
    """
    from dalembert.case import load_cases
    from dalembert.harness.matrix import expand
    from dalembert.harness.pool import DEFAULT_TIMEOUT_S

    notes = []
    if args.out is not None and not args.out.strip():
        raise ValueError("--out: empty — give a directory, or leave --out out for results/<timestamp>")
    if args.jobs is not None and args.jobs < 1:
        raise ValueError(f"--jobs: must be at least 1, got {args.jobs}")
    jobs = args.jobs or cores
    if jobs > cores:
        notes.append(f"--jobs {jobs}: this machine has {cores} cores; running {cores} at once (more would share "
                     "the cores and slow every timing)")
        jobs = cores
    timeout = DEFAULT_TIMEOUT_S if args.timeout is None else args.timeout
    if not (math.isfinite(timeout) and timeout > 0):
        raise ValueError(f"--timeout: must be a positive number of seconds, got {timeout}")
    dts, rtols = numbers("--dt", args.dt, notes), numbers("--rtol", args.rtol, notes)
    registry = load_cases()
    names = list(args.case or [])
    for n in names:
        registry[n]  # did-you-mean for unknown names
    tags = set(args.tag or [])
    selected = [f for n, f in registry.items() if n in names or tags & set(f.tags)] or (
        [] if names or tags else [f for _, f in registry.items() if "hard" not in f.tags])
    params = {}
    for key, value in _pairs("--param", args.param).items():
        owners = [f for f in selected if key in f.params]
        if not owners:
            known = {k for f in selected for k in f.params}
            raise ValueError(f"--param {key}: no selected case has this parameter{suggest(key, known)}")
        values = sweep(owners[0], key, value)
        params[key] = values if len(values) > 1 else values[0]
    options = _pairs("--option", args.option)
    specs, skipped = expand(args.case, args.tag, args.engine, args.integrator, dts or None, rtols or None, params,
                            options, force=args.force)
    if rtols and not any(s.rtol is not None for s in specs):
        raise ValueError("--rtol: no selected integrator is adaptive — drop --rtol, or select one (e.g. "
                         "--integrator dop853)")
    if dts and not any(s.dt is not None for s in specs):
        raise ValueError("--dt: no selected integrator takes a fixed step — drop --dt, or select one (e.g. "
                         "--integrator rk4)")
    for key in options:
        engines = sorted({s.engine for s in specs if key in dict(s.options)})
        if engines != sorted({s.engine for s in specs}):
            notes.append(f"--option {key}: applies to {', '.join(engines)} only; the other engines run their defaults")
    searches = []
    if args.search:
        from dalembert.harness.search import RESOLUTION

        resolution = RESOLUTION if args.resolution is None else args.resolution
        if not (math.isfinite(resolution) and resolution > 1.0):
            raise ValueError(f"--resolution: a factor between steps, must be greater than 1, got {resolution}")
        if len(dts) < 2:
            raise ValueError("--search dt: give the bracket as --dt SMALLEST,LARGEST (e.g. --dt 1e-4,1e-2)")
        adaptive = sorted({f"{s.engine} {s.integrator}" for s in specs if s.dt is None})
        if adaptive:
            notes.append(f"--search dt: adaptive integrators have no step to search, left out: {', '.join(adaptive)}")
        specs = [s for s in specs if s.dt is not None]
        if not specs:
            raise ValueError("--search dt: no selected integrator takes a fixed step")
        searches.append((tuple(specs), resolution))
    elif args.resolution is not None:
        raise ValueError("--resolution: only with --search")
    if tags and not args.no_maps and not args.search:
        for plan, first in _maps(args, tags, registry, options):
            notes.append(f"stability map {plan.name}: {plan.case} over {plan.parameter} = {plan.values}, each "
                         f"fixed-step integrator's boundary searched in [{plan.bracket[0]:g}, {plan.bracket[1]:g}] s "
                         "(--no-maps leaves it out)")
            specs = specs + [s for s in first if s not in specs]
            searches.append((tuple(first), plan.resolution))
    return Selection(specs, skipped, notes, jobs, timeout, tuple(searches))


def _maps(args, tags, registry, options):
    """The default stability maps the selected tags carry: ``[(MapPlan, first probes)]``."""
    from dalembert.harness.matrix import expand
    from dalembert.maps import MAPS

    out = []
    for _, plan in MAPS.items():
        if not tags & set(plan.tags):
            continue
        values = sweep(registry[plan.case], plan.parameter, plan.values)
        first, _ = expand([plan.case], None, args.engine, args.integrator, list(plan.bracket), None,
                          {**plan.params, plan.parameter: values}, options, force=args.force)
        first = [s for s in first if s.dt is not None]
        if first:
            out.append((plan, first))
    return out
