"""The ``run`` command's flags, checked: every one means something or is refused, before anything runs.

Refused, naming the flag and the fix: an empty value (``--out ''``, ``--case ''``: empty never
means "not given"), empty lists (``--dt ,``), non-positive or non-finite steps, tolerances,
timeouts; a parameter no selected case has (did-you-mean from those cases); ``--rtol`` when no
selected integrator is adaptive, ``--dt`` when none is fixed-step; and, unless ``--force`` says
the size is meant, a sweep or matrix of more than ``MAX_RUNS`` runs, a model of more than
``MAX_MODEL_PARTS`` parts, a run of more than ``matrix.MAX_STEPS_PER_RUN`` steps.
Capped and said: ``--jobs`` beyond the cores (the timings would share them).

Left out before anything runs: the runs an engine refuses by its declarations (``matrix.split``), each
engine's refusals of a case listed once (``Selection.refused``: a note per refusal when engines or cases were
named, else one per engine); a selection whose every run is refused is refused itself, with the reasons.

Duplicates, one rule for every command: a single-valued thing given twice (``--param K``,
``--option K``, ``--out``) is refused, since which one was meant is a guess; a name or value
repeated in a list (``--case a --case a``, ``--dt 1e-3,1e-3``) is kept once, in the order
first given, and a note says so.

A parameter sweeps when given several values: ``spin=5,50,500`` (a scalar's values
comma-separated), ``spin=log:5,500,7`` or ``lin:0,1,5`` (``n`` values log- or evenly
spaced from ``a`` to ``b``), ``omega0=0,1,5;0,2,5`` (a vector's values separated by ``;``).
Each value makes its own case variant (its own version); several swept parameters form
their product.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from dalembert.refusal import group
from dalembert.registry import suggest

__all__ = ["Selection", "select", "numbers", "names", "versioned", "given", "pairs", "values", "sweep", "option_sweep",
           "MAX_RUNS", "MAX_MODEL_PARTS"]

# A guard against a slip of the keyboard (lin:1,2,100000000 for lin:1,2,10): the default matrix is
# a few hundred runs and the largest shipped sweeps (the stability maps) a few hundred more; a
# matrix, or one parameter's sweep, of more than this many runs is refused unless ``--force``
# (at the reference's ~0.1-10 s a run, 1e4 runs are hours to days on a workstation).
MAX_RUNS = 10_000
# A guard on a model's size: every whole-number case parameter counts parts of the model (the
# chain's links, n_four_bar's windows). The largest shipped use is n = 40 (IFToMM A02) and the
# README's size sweep stops at 16; a 1e4-link chain already takes ~12 s to build and validate
# before its first step, and the pure-Python reference hours per run. More is refused unless
# ``--force``.
MAX_MODEL_PARTS = 1000


@dataclass(frozen=True)
class Selection:
    """What ``dalembert run`` will do: its specs, and what the user is told about them."""

    specs: list
    skipped: list  # engines not installed (when none was named)
    notes: list  # merged duplicates, capped jobs, options that apply to some engines only
    jobs: int
    timeout: float
    searches: tuple = ()  # (first probes, resolution) of each boundary search: --search dt, or a map
    refused: tuple = ()  # dalembert.refusal.Refusal: what the engines refuse, once each; not among ``specs``


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


def versioned(engines, notes):
    """``engines`` (names, or None) with each versioned one (``mujoco == 3.6.0``) written as its records carry it
    (``mujoco==3.6.0``), its environment made and its version one the adapter supports: ValueError naming
    ``--engine`` and the command that makes the environment otherwise (``run`` never installs anything)."""
    from dalembert.adapters import get_adapter
    from dalembert.environments import is_versioned, parse_engine, require

    if engines is None:
        return None
    out = []
    for name in engines:
        if is_versioned(name):
            spec = parse_engine(name)
            require(spec.name, problem=get_adapter(spec.engine).version_problem)
            name = spec.name
        if name in out:
            notes.append(f"--engine: {name} given more than once; each counts once")
            continue
        out.append(name)
    return out


def given(flag, value):
    """``value`` unless it is an empty (or blank) string: ValueError naming ``flag`` (an empty value
    is a mistake, never "not given")."""
    if isinstance(value, str) and not value.strip():
        raise ValueError(f"{flag}: empty — give a value, or leave {flag} out (an empty value is never the default)")
    return value


def names(flag, values, notes):
    """The names of a repeatable flag, each checked non-empty, a repeated one kept once (first
    place kept) and ``notes`` saying so; None when the flag was not given."""
    if values is None:
        return None
    if isinstance(values, str):
        values = [values]
    values = [given(flag, v) for v in values]
    if not values:
        raise ValueError(f"{flag}: an empty list — give at least one name, or leave {flag} out for the default")
    unique = list(dict.fromkeys(values))
    if len(unique) < len(values):
        notes.append(f"{flag}: {', '.join(v for v in unique if values.count(v) > 1)} given more than once; "
                     "each counts once")
    return unique


def values(flag, key, text, real, separator=",", force=False):
    """The values ``text`` gives ``key`` of ``flag`` (``--param`` or ``--option``): a ``log:``/``lin:``
    grid as floats (only where ``real``: the key takes a real number), else the texts between
    ``separator``s as written. ValueError naming the flag on a malformed grid, an empty value, or
    more than ``MAX_RUNS`` values unless ``force``."""
    grid = text.split(":", 1)
    if len(grid) == 2 and grid[0] in ("log", "lin"):
        if real is not True:
            raise ValueError(f"{flag} {key}={text}: a {grid[0]}: grid sweeps a real number; {key!r} is {real}")
        try:
            a, b, n = (float(x) for x in grid[1].split(","))
        except ValueError:
            raise ValueError(f"{flag} {key}={text}: write {grid[0]}:FIRST,LAST,COUNT") from None
        if not (math.isfinite(n) and n >= 2 and n == int(n)) or (grid[0] == "log" and not (a > 0 and b > 0)):
            raise ValueError(f"{flag} {key}={text}: COUNT must be an integer >= 2"
                             + (", FIRST and LAST positive" if grid[0] == "log" else ""))
        if n > MAX_RUNS and not force:
            raise ValueError(f"{flag} {key}={text}: {n:.0f} values, more than {MAX_RUNS} runs of each selected "
                             "integrator — check COUNT, or pass --force if the sweep is meant")
        points = (np.geomspace if grid[0] == "log" else np.linspace)(a, b, int(n))
        return [float(v) for v in points]
    parts = text.split(separator)
    if any(not p.strip() for p in parts):
        raise ValueError(f"{flag} {key}={text}: an empty value — separate values with "
                         + ("';' (a vector's numbers with ',')" if separator == ";" else "','"))
    if len(parts) > MAX_RUNS and not force:
        raise ValueError(f"{flag} {key}: {len(parts)} values, more than {MAX_RUNS} runs — pass --force if the "
                         "sweep is meant")
    return [p.strip() for p in parts]


def sweep(factory, key, text, force=False):
    """The values ``text`` gives parameter ``key`` of ``factory`` (one or several: a sweep, read by
    ``values``), each typed as the parameter's default; ValueError naming ``--param`` otherwise, and
    for a whole number above ``MAX_MODEL_PARTS`` unless ``force``."""
    from dalembert.case import parse_param

    default = factory.params[key]
    real = True if isinstance(default, float) else f"{type(default).__name__} like {default!r}"
    found = values("--param", key, text, real, ";" if isinstance(default, tuple) else ",", force)
    if found and isinstance(found[0], float):
        return found
    typed = [parse_param(factory, f"{key}={p}")[1] for p in found]
    big = [v for v in typed if type(v) is int and v > MAX_MODEL_PARTS]
    if big and not force:
        raise ValueError(f"--param {key}={big[0]}: a model of more than {MAX_MODEL_PARTS} parts ({key!r} counts "
                         f"{factory.units.get(key, 'parts')}) takes minutes to build and hours to run — check the "
                         "value, or pass --force if it is meant")
    return list(dict.fromkeys(typed))


def option_sweep(key, text, declared, force=False):
    """The values ``text`` gives engine option ``key`` (one or several: a sweep, read by ``values``
    as ``--param``'s are), as texts (a grid's numbers written by ``repr``: the text a run's settings
    and key hold), each checked against every ``Option`` that declares ``key`` (``declared``);
    ValueError naming ``--option`` and the fix."""
    choices = sorted({c for o in declared for c in o.choices})
    real = True if not choices else f"one of {', '.join(map(str, choices))}"
    found = [repr(v) if isinstance(v, float) else v for v in values("--option", key, text, real, ",", force)]
    for value in found:
        for option in declared:
            problem = replace(option, only=()).problem(key, value, None)  # which integrator takes it: expand's
            if problem:
                raise ValueError(f"--option {key}={value}: {problem.split(': ', 1)[1]}")
    return list(dict.fromkeys(found))


def pairs(flag, texts):
    """``KEY=VALUE`` texts as a dict; ValueError on a malformed or repeated key (a single-valued
    thing given twice: which one was meant is a guess)."""
    pairs = {}
    for text in texts or []:
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
    from dalembert.harness.matrix import expand, split
    from dalembert.harness.pool import DEFAULT_TIMEOUT_S

    notes = []
    if args.out is not None:
        given("--out", args.out)
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
    cases, tag_list = names("--case", args.case, notes), names("--tag", args.tag, notes)
    engines, integrators = versioned(names("--engine", args.engine, notes), notes), names("--integrator",
                                                                                        args.integrator, notes)
    registry = load_cases()
    for n in cases or []:
        registry[n]  # did-you-mean for unknown names
    tags = set(tag_list or [])
    selected = [f for n, f in registry.items() if n in (cases or []) or tags & set(f.tags)] or (
        [] if cases or tags else [f for _, f in registry.items() if "hard" not in f.tags])
    params = {}
    for key, value in pairs("--param", args.param).items():
        owners = [f for f in selected if key in f.params]
        if not owners:
            known = {k for f in selected for k in f.params}
            raise ValueError(f"--param {key}: no selected case has this parameter{suggest(key, known)}")
        swept = sweep(owners[0], key, value, args.force)
        params[key] = swept if len(swept) > 1 else swept[0]
    variants = sum(math.prod(len(v) for k, v in params.items() if k in f.params and isinstance(v, list))
                   for f in selected)
    if variants > MAX_RUNS and not args.force:  # each variant is at least one run; refused before any is built
        raise ValueError(f"--param: the sweeps make {variants} case variants, more than {MAX_RUNS} runs — sweep "
                         "fewer values, or pass --force if the matrix is meant")
    options = {key: option_sweep(key, text, _declared(key, engines), args.force)
               for key, text in pairs("--option", args.option).items()}
    if math.prod(len(v) for v in options.values()) > MAX_RUNS and not args.force:
        raise ValueError(f"--option: the sweeps make {math.prod(len(v) for v in options.values())} option sets, "
                         f"more than {MAX_RUNS} runs — sweep fewer values, or pass --force if the matrix is meant")
    specs, skipped = _each_option_set(options, lambda chosen: expand(
        cases, tag_list, engines, integrators, dts or None, rtols or None, params, chosen, force=args.force))
    if len(specs) > MAX_RUNS and not args.force:
        raise ValueError(f"the selection is {len(specs)} runs, more than {MAX_RUNS} — select fewer cases, engines, "
                         "integrators, steps or sweep values, or pass --force if the matrix is meant")
    if rtols and not any(s.settings.rtol is not None for s in specs):
        raise ValueError("--rtol: no selected integrator is adaptive — drop --rtol, or select one (e.g. "
                         "--integrator dop853)")
    if dts and not any(s.settings.dt is not None for s in specs):
        raise ValueError("--dt: no selected integrator takes a fixed step — drop --dt, or select one (e.g. "
                         "--integrator rk4)")
    named = bool(engines or cases)  # (before ``engines`` is rebound below: the maps take the engines an option names)
    for key in options:
        engines = sorted({s.engine for s in specs if key in dict(s.settings.options)})
        if engines != sorted({s.engine for s in specs}):
            notes.append(f"--option {key}: applies to {', '.join(engines)} only; the other engines run their defaults")
    specs, refused = split(specs)  # (after the checks above: a flag's meaning does not hang on what is refused)
    refused = dict(refused)
    searches = []
    if args.search:
        from dalembert.harness.search import RESOLUTION

        resolution = RESOLUTION if args.resolution is None else args.resolution
        if not (math.isfinite(resolution) and resolution > 1.0):
            raise ValueError(f"--resolution: a factor between steps, must be greater than 1, got {resolution}")
        if len(dts) < 2:
            raise ValueError("--search dt: give the bracket as --dt SMALLEST,LARGEST (e.g. --dt 1e-4,1e-2)")
        adaptive = sorted({f"{s.engine} {s.settings.integrator}" for s in specs if s.settings.dt is None})
        if adaptive:
            notes.append(f"--search dt: adaptive integrators have no step to search, left out: {', '.join(adaptive)}")
        specs = [s for s in specs if s.settings.dt is not None]
        if not specs and not refused:  # (every one refused: said below, with the reasons)
            raise ValueError("--search dt: no selected integrator takes a fixed step")
        searches.append((tuple(specs), resolution))
    elif args.resolution is not None:
        raise ValueError("--resolution: only with --search")
    if tags and not args.no_maps and not args.search:
        for plan, first in _maps(engines, integrators, args.force, tags, registry, options, refused):
            notes.append(f"stability map {plan.name}: {plan.case} over {plan.parameter} = {plan.values}, each "
                         f"fixed-step integrator's boundary searched in [{plan.bracket[0]:g}, {plan.bracket[1]:g}] s "
                         "(--no-maps leaves it out)")
            specs = specs + [s for s in first if s not in specs]
            searches.append((tuple(first), plan.resolution))
    refusals = group(refused.items())
    if refusals and not specs:
        raise ValueError("the selection holds no run its engines can run: " + "; ".join(r.text() for r in refusals)
                         + " — select another engine or case (dalembert engines lists what each represents)")
    notes += _refusal_notes(refusals, named)
    return Selection(specs, skipped, notes, jobs, timeout, tuple(searches), refusals)


def _refusal_notes(refusals, named):
    """What the user is told of ``refusals``: each in full where engines or cases were ``named`` (what was asked
    for is refused), else a count per engine (the default matrix's are many; the manifest and report list them)."""
    if named:
        return [f"not run: {r.text()}" for r in refusals]
    runs = {}
    for r in refusals:
        runs[r.engine] = runs.get(r.engine, 0) + r.runs
    return [f"{sum(runs.values())} run(s) the engines refuse are left out of the matrix, each engine's refusal of a "
            "case listed once in the manifest and the report: " + ", ".join(f"{e} {n}" for e, n in sorted(runs.items()))
            ] if runs else []


def _maps(engines, integrators, force, tags, registry, options, refused):
    """The default stability maps the selected tags carry: ``[(MapPlan, first probes)]``; the probes an engine
    refuses are left out, added to ``refused`` (spec -> reason)."""
    from dalembert.harness.matrix import expand, split
    from dalembert.maps import MAPS

    out = []
    for _, plan in MAPS.items():
        if not tags & set(plan.tags):
            continue
        swept = sweep(registry[plan.case], plan.parameter, plan.values, force)
        first, _ = _each_option_set(options, lambda chosen: expand(
            [plan.case], None, engines, integrators, list(plan.bracket), None,
            {**plan.params, plan.parameter: swept}, chosen, force=force))
        first, more = split([s for s in first if s.settings.dt is not None])
        refused.update(more)
        if first:
            out.append((plan, first))
    return out


def _declared(key, engines):
    """Every ``Option`` that declares engine option ``key``, on the named engines (default: every registered
    one); an engine that cannot be named is left to ``expand`` to refuse."""
    from dalembert.adapters import adapter_names, get_adapter

    found = []
    for e in engines or adapter_names():
        try:
            adapter = get_adapter(e)
        except (KeyError, ImportError):
            continue
        if key in adapter.options:
            found.append(adapter.options[key])
    return found


def _each_option_set(options, expand_one):
    """``expand_one(chosen)`` (``matrix.expand`` of one option set) for each set the option sweeps make (their
    product; ``options``: key -> values), its specs joined in order, a run made by several sets (an engine that
    takes none of the options runs its own variants each time) kept once: ``(specs, skipped)``."""
    import itertools

    specs, skipped = {}, []
    for chosen in itertools.product(*options.values()):
        more, skipped = expand_one(dict(zip(options, chosen)))
        specs.update(dict.fromkeys(more))
    return list(specs), skipped
