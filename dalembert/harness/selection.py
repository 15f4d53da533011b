"""The ``run`` command's flags, checked: every one means something or is refused, before anything runs.

Refused, naming the flag and the fix: empty lists (``--dt ,``), non-positive or
non-finite steps, tolerances, timeouts; a parameter no selected case has
(did-you-mean from those cases), the same parameter or option given twice, an
empty ``--out``; ``--rtol`` when no selected integrator is adaptive, ``--dt``
when none is fixed-step. Merged and said once: a value given twice in a list.
Capped and said: ``--jobs`` beyond the cores (the timings would share them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

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


def _pairs(flag, texts):
    """``KEY=VALUE`` texts as (key, value) pairs; ValueError on a malformed or repeated key."""
    pairs = {}
    for text in texts:
        if "=" not in text or not text.split("=", 1)[0]:
            raise ValueError(f"{flag} {text!r}: write KEY=VALUE")
        key, value = text.split("=", 1)
        if key in pairs:
            raise ValueError(f"{flag} {key}: given twice ({pairs[key]!r} and {value!r}) — give it once")
        pairs[key] = value
    return pairs


def select(args, cores):
    """Check the ``run`` flags in ``args`` (argparse namespace) and expand the matrix.

    ``cores``: this machine's cores (``--jobs`` beyond them is capped). Raises ValueError,
    KeyError (unknown names, with did-you-mean) or ImportError (a named engine not installed),
    each naming the flag, before anything runs.
    """
    from dalembert.case import load_cases, parse_param
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
        params.update([parse_param(owners[0], f"{key}={value}")])
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
    return Selection(specs, skipped, notes, jobs, timeout)
