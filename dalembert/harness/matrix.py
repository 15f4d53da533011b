"""The run matrix: cases x engines x integrators x step sizes (or tolerances), as ``RunSpec``s.

``expand(...)`` turns a selection into specs, checking every name and setting
before anything runs; ``spec(...)`` makes one spec from explicit settings; ``split(specs)``
leaves out the runs an engine refuses by its declarations (``dalembert.refusal``), before
anything runs.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from dalembert.identity import run_identity, run_key
from dalembert.registry import suggest
from dalembert.settings import Settings, steps_per_interval

__all__ = ["RunSpec", "expand", "spec", "split", "DEFAULT_DTS", "DEFAULT_RTOLS", "ATOL_PER_RTOL"]

# Default sweeps: steps 1, 2, 5 per decade from 1e-2 to 1e-3 s (successive steps at most 2.5x apart, so the
# cheapest setting to an accuracy is decided by the engines, not by a tenfold gap in the grid; ~1.5x the
# two-step matrix's time) and two decades of tolerance, affordable for the pure-Python reference on 2 cores.
DEFAULT_DTS = (1e-2, 5e-3, 2e-3, 1e-3)
DEFAULT_RTOLS = (1e-6, 1e-9)
# atol = rtol * ATOL_PER_RTOL: the states are O(1) in SI units for the cases here.
ATOL_PER_RTOL = 1.0
# A guard against typos (1e-300 for 1e-3): the finest default step (1e-3 s) over the longest
# built-in horizon (1000 s) is 1e6 steps; a run of more than 100x that is refused unless the
# user says it is meant (``force``).
MAX_STEPS_PER_RUN = 1e8


@dataclass(frozen=True)
class RunSpec:
    """One (case, engine, settings) run. ``params``: sorted (key, value) pairs.

    Its JSON (``to_json``, a manifest's ``specs``) keeps the settings flat (``integrator``, ``dt``,
    ``rtol``, ``atol``, ``options`` as sorted pairs), as every manifest has been written.
    """

    case: str
    engine: str
    settings: Settings
    params: tuple = ()
    case_version: str = ""
    adapter: str = ""  # "module:Class" of the engine's adapter, for workers that must import it

    @property
    def key(self):
        """Deterministic, readable file key: case, engine, integrator and a content hash."""
        return run_key(self.identity, self.case_version)

    @property
    def identity(self):
        """The run's ``dalembert.identity.RunIdentity``."""
        return run_identity(self.case, self.params, self.engine, self.settings)

    def to_json(self):
        s = self.settings
        return {"case": self.case, "engine": self.engine, "integrator": s.integrator, "dt": s.dt, "rtol": s.rtol,
                "atol": s.atol, "options": [[k, v] for k, v in sorted(s.options.items())],
                "params": [[k, list(v) if isinstance(v, tuple) else v] for k, v in self.params],
                "case_version": self.case_version, "adapter": self.adapter}

    @classmethod
    def from_json(cls, d):
        """Inverse of ``to_json``; a TypeError or KeyError when ``d`` is not a spec's JSON."""
        d = dict(d)
        settings = Settings(d.pop("integrator"), d.pop("dt"), d.pop("rtol"), d.pop("atol"),
                            dict(tuple(x) for x in d.pop("options")))
        d["params"] = tuple((k, tuple(v) if isinstance(v, list) else v) for k, v in d["params"])
        return cls(settings=settings, **d)


def spec(case, engine, settings, params=(), force=False, version=None):
    """The spec of running ``case`` (a Case made with ``params``) on ``engine`` with ``settings``;
    ValueError naming the field when the engine cannot take the settings, or when the run would
    take more than ``MAX_STEPS_PER_RUN`` steps and ``force`` is not given. ``version``: ``case.version``
    where the caller has it (a content hash of the whole case: computed once per case, not per run)."""
    from dalembert.adapters import adapter_path, get_adapter

    if settings.dt is not None and not force and case.t_final / settings.dt > MAX_STEPS_PER_RUN:
        raise ValueError(f"dt: {settings.dt:g} s over the {case.t_final:g}-s horizon of {case.name!r} is "
                         f"{case.t_final / settings.dt:.3g} steps, more than {MAX_STEPS_PER_RUN:.0e} — check the "
                         "value, or pass --force if the run is meant")
    adapter = get_adapter(engine)
    made = RunSpec(case.name, engine, settings, tuple(sorted(dict(params).items())),
                   case.version if version is None else version,
                   adapter_path(engine))
    adapter.check(case.scene, case.times, made.settings)
    return made


def _dividing(dts, case):
    """The default steps that divide ``case``'s sample interval (a case sampled every 1 ms runs no
    1e-2 step), or that interval itself where none does; given steps are never changed (a step
    that does not divide is then refused, naming the fix)."""
    fit = []
    for dt in dts:
        try:
            steps_per_interval(case.times, dt)
            fit.append(dt)
        except ValueError:
            pass
    return fit or [float(np.min(np.diff(case.times)))]


def expand(cases=None, tags=None, engines=None, integrators=None, dts=None, rtols=None, params=None,
           options=None, force=False):
    """Turn a selection into run specs. Raises ValueError/KeyError before anything runs.

    Parameters
    ----------
    cases, tags : names / tags of cases (default: every case not tagged ``hard`` or ``variant``)
    engines : engine names (default: every registered engine whose engine imports)
    integrators : integrator names (default: every integrator of each engine)
    dts, rtols : step sizes (s) for fixed-step and tolerances for adaptive integrators
    params : dict of case parameter overrides (applied to every selected case that has them); a
        list of values sweeps the parameter (one case variant per value; several swept
        parameters form their product), a tuple is one vector value
    options : dict of engine options, applied to every run whose integrator accepts them (a
        ValueError when no selected one accepts one of them); the other runs, and every run when
        none is given, take each engine's ``variants`` for each case
    force : bool — allow runs of more than ``MAX_STEPS_PER_RUN`` steps

    Returns
    -------
    specs : list of RunSpec — every combination the engines' ``check`` accepts, those an engine refuses included
        (``split`` leaves them out: ``dalembert run`` runs none of them)
    skipped : list of str — engines not installed (only when ``engines`` was not given)
    """
    from dalembert.adapters import adapter_names, get_adapter
    from dalembert.case import in_default_matrix, load_cases
    from dalembert.harness.truths import built_case

    registry = load_cases()
    names = list(cases or [])
    for n in names:
        registry[n]  # "did you mean" for unknown names
    if tags:
        known_tags = {t for _, f in registry.items() for t in f.tags}
        for t in tags:
            if t not in known_tags:
                raise ValueError(f"--tag: unknown tag {t!r}{suggest(t, known_tags)}")
        names += [n for n, f in registry.items() if set(tags) & set(f.tags) and n not in names]
    if not names:  # the default matrix: every case but the hard ones and the variants (select those with --tag)
        names = [n for n, f in registry.items() if in_default_matrix(f)]
    skipped = []
    if engines:
        adapters = {e: get_adapter(e) for e in engines}
        for e, a in adapters.items():
            a.version()  # ImportError: the engine is not installed
    else:
        adapters = {}
        for e in adapter_names():
            a = get_adapter(e)
            try:
                a.version()
                adapters[e] = a
            except ImportError as err:
                skipped.append(f"{e} ({err})")
    for i in integrators or []:
        if not any(i in a.integrators for a in adapters.values()):
            offered = {n for a in adapters.values() for n in a.integrators}
            raise ValueError(f"--integrator: no selected engine offers {i!r}{suggest(i, offered)}")
    given_dts = bool(dts)
    dts = tuple(dts or DEFAULT_DTS)
    rtols = tuple(rtols or DEFAULT_RTOLS)
    params = dict(params or {})
    specs = []
    variants = []  # (factory, parameters of one case variant)
    for name in names:
        factory = registry[name]
        mine = {k: v if isinstance(v, list) else [v] for k, v in params.items() if k in factory.params}
        variants += [(factory, dict(zip(mine, values))) for values in itertools.product(*mine.values())]
    for factory, case_params in variants:
        case, version = built_case(factory.name, case_params)
        case_dts = dts if given_dts else _dividing(dts, case)
        for e, adapter in adapters.items():
            for integ, ispec in adapter.integrators.items():
                if integrators and integ not in integrators:
                    continue
                if ispec.fixed_step:
                    knobs = [dict(dt=dt) for dt in case_dts]
                else:
                    knobs = [dict(rtol=r, atol=r * ATOL_PER_RTOL) for r in rtols]
                # given options apply where the integrator takes them; else the engine's own variants
                mine = {k: v for k, v in (options or {}).items() if k in ispec.options}
                option_sets = [mine] if mine else adapter.variants(case.scene)
                specs += [spec(case, e, Settings(integ, options=opts, **k), case_params, force, version)
                          for opts in option_sets for k in knobs]
    for key in options or {}:
        if not any(key in ispec.options for a in adapters.values() for name, ispec in a.integrators.items()
                   if not integrators or name in integrators):
            offered = {o for a in adapters.values() for ispec in a.integrators.values() for o in ispec.options}
            raise ValueError(f"--option {key}: no selected engine's integrator takes it{suggest(key, offered)}")
    return specs, skipped


def split(specs):
    """The runs of ``specs`` their engines can run, and those an engine refuses before building a model
    (``Adapter.unsupported_before_build``: effects, options, the scene's parts; the same reason a worker's
    ``unsupported`` would store).

    Returns
    -------
    runnable : list of RunSpec — in the order given; a refusal only the built model shows is among them (a worker
        stores it ``unsupported``)
    refused : list of (RunSpec, str) — each refused spec with its engine's reason (``refusal.group`` lists them once
        per engine, case variant and reason)
    """
    from dalembert.adapters import get_adapter
    from dalembert.harness.truths import built_case

    runnable, refused = [], []
    for s in specs:
        case, _ = built_case(s.case, s.params)  # (built once per process: the expansion built it)
        reason = get_adapter(s.engine, s.adapter or None).unsupported_before_build(case.scene, s.settings)
        if reason:
            refused.append((s, reason))
        else:
            runnable.append(s)
    return runnable, refused
