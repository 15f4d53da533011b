"""The case registry: ``CASES``, filled by ``@case`` with ``CaseFactory``s, the entry points that load
case packages (``load_cases``), and ``make_case``; the cases' modules, handed to a worker in an engine
environment (``case_modules``, ``load_modules``).

A case is made by a factory function decorated ``@case(tags=..., units=..., positive=..., counts=...)``;
its keyword parameters (all with defaults) give variants for free. Each parameter's domain is declared
there once and checked whenever the case is made, before the factory runs (``dalembert.params``).
``load_cases()`` loads every package registered in the entry-point group ``dalembert.cases``: the
built-in ``dalembert.cases`` and any third party's. ``dalembert.case`` re-exports every name.

A worker in an engine environment (``dalembert.harness.boot``) has none of those packages installed: it is
told, by the process that starts it, the module that registered each case there (``case_modules``) and
imports the one a run asks for when it asks (``load_modules``), in place of the entry points.
"""

from __future__ import annotations

import importlib
import inspect
import sys
from dataclasses import dataclass
from typing import Callable

from dalembert.params import domain_problems
from dalembert.registry import Registry, suggest
from dalembert.scene import SceneError

__all__ = ["CASES", "OUT_OF_DEFAULT", "in_default_matrix", "CaseFactory", "case", "load_cases", "make_case",
           "case_modules", "load_modules", "OWN_PREFIX", "MAIN"]

# The top-level package of dalembert's own cases: a worker imports them itself, through ``dalembert.cases``.
OWN_PREFIX = "dalembert."
# The name of the module a script runs as: no other process can import it by that name.
MAIN = "__main__"


class _Cases(Registry):
    """The case registry; in a worker told where the cases live (``load_modules``), a case not yet registered is
    imported from its module when asked for, and one whose module cannot be imported there says why."""

    def __init__(self):
        super().__init__("case")
        self.modules = {}  # name -> the module that registers it (``load_modules``; empty: the entry points')

    def __getitem__(self, name):
        if name not in self._items and name in self.modules:
            _import_for(name, self.modules.pop(name))
        return super().__getitem__(name)


CASES = _Cases()
# The module that registered each case (``@case``), outside dalembert's own: what another interpreter imports
# to know the same case (``case_modules``).
_REGISTERED_IN = {}
# Tags that keep a case out of the default matrix (``dalembert run`` with no selection, ``dalembert
# validate``): ``hard`` (long, fast, chaotic: run them with ``--tag hard``) and ``variant`` (presets
# and variants of a canonical case, e.g. a published benchmark's set-up: run them by name or with
# ``--tag variant``) and ``contact`` (the contact cases: most engines do not map contact yet, so the default
# matrix would grow by unsupported runs: run them with ``--tag contact``).
OUT_OF_DEFAULT = ("hard", "variant", "contact")


def in_default_matrix(factory):
    """Whether the case family ``factory`` (a ``CaseFactory``) runs in the default matrix."""
    return not set(OUT_OF_DEFAULT) & set(factory.tags)


@dataclass(frozen=True)
class CaseFactory:
    """A registered case family: the factory, its tags, parameter units, and its parameters' domains
    (``dalembert.params``): those that must be positive (every component of a vector one) and those
    that count things (whole numbers >= 1). Calling it checks the parameters, then makes the case."""

    name: str
    func: Callable
    tags: tuple
    units: dict
    positive: tuple = ()
    counts: tuple = ()

    @property
    def params(self):
        """Keyword parameters and their defaults, as a dict."""
        return {p.name: p.default for p in inspect.signature(self.func).parameters.values()}

    @property
    def summary(self):
        """First paragraph of the factory's docstring, on one line."""
        doc = inspect.getdoc(self.func) or ""
        return " ".join(doc.split("\n\n")[0].split())

    def __call__(self, **params):
        known = self.params
        unknown = sorted(set(params) - set(known))
        if unknown:
            raise SceneError(f"case {self.name!r}", [
                f"parameter {k!r}: unknown{suggest(k, known)}" for k in unknown])
        merged = {**known, **params}
        problems = domain_problems(self.name, known, params, self.positive, self.counts, self.units)
        if problems:
            raise SceneError(f"case {self.name!r}", problems)
        made = self.func(**params)
        # a Case (dalembert.case), told which family made it; known by its method, so that this module
        # need not import dalembert.case, which re-exports it
        in_family = getattr(made, "in_family", None)
        if not callable(in_family):
            raise SceneError(f"case {self.name!r}", [f"factory: returned {type(made).__name__}, not a Case"])
        return in_family(self.name, self.tags, merged, self.units)


def case(tags=(), units=None, positive=(), counts=()):
    """Register a case factory under its function name.

    Every parameter must have a default (a case runs without arguments), and one of
    them is ``t_final`` (s): the contract tests and ``--param t_final=...`` shorten a
    case through it. Each parameter's domain is declared here, once, and checked every time
    the case is made, before the factory runs (``dalembert.params.domain_problems``):
    ``positive`` names the parameters that must be positive (lengths, masses, radii, inertias,
    sample intervals: a zero-length rod would run "ok" with every error exactly 0), ``counts``
    those that are whole numbers >= 1 (links, bodies); every numeric parameter must be finite
    and within ``params.MAX_MAGNITUDE``, and ``t_final`` positive. Raises ``SceneError`` naming
    the case and the parameter ("case.param: what is wrong — the fix"); a declaration the
    defaults themselves break is refused at registration.
    """

    def register(func):
        sig = inspect.signature(func)
        problems = [f"parameter {p.name!r}: has no default — every parameter needs one (a case runs without "
                    "arguments)" for p in sig.parameters.values() if p.default is inspect.Parameter.empty]
        if "t_final" not in sig.parameters:
            problems.append("t_final: the factory has no t_final parameter — add t_final=<horizon, s> and pass it to "
                            "Case (the contract tests and --param t_final=... shorten a case through it)")
        for label, names in (("positive", positive), ("counts", counts)):
            problems += [f"{label}: {k!r} is not a parameter of it" for k in sorted(set(names) - set(sig.parameters))]
        problems += [f"positive, counts: {k!r} is in both — a count is a whole number >= 1, declare it in counts"
                     for k in sorted(set(positive) & set(counts))]
        if problems:
            raise SceneError(f"case {func.__name__!r}", problems)
        defaults = {p.name: p.default for p in sig.parameters.values()}
        problems = [f"default: {p}" for p in domain_problems(func.__name__, defaults, defaults, positive, counts,
                                                             units)]
        if problems:
            raise SceneError(f"case {func.__name__!r}", problems)
        CASES.register(func.__name__, CaseFactory(func.__name__, func, tuple(tags), dict(units or {}),
                                                  tuple(positive), tuple(counts)))
        _REGISTERED_IN[func.__name__] = _importing_module(func)
        return func

    return register


_LOADED = False


def load_cases():
    """Load every case package registered in the entry-point group ``dalembert.cases``
    (the built-in ``dalembert.cases`` is one of them) and return the registry."""
    global _LOADED
    if _LOADED:
        return CASES
    from importlib.metadata import entry_points

    for ep in entry_points(group="dalembert.cases"):
        try:
            ep.load()
        except Exception as e:
            raise ImportError(f"cases entry point {ep.name!r} ({ep.value}) failed to load: "
                              f"{type(e).__name__}: {e} — fix or uninstall the package that declares it") from e
    _LOADED = True
    return CASES


def _importing_module(func):
    """The module whose import registers ``func`` now: the innermost module body on the stack (the decorator may
    be applied by a helper of another module, the function defined in a third)."""
    frame = sys._getframe(2)
    while frame is not None and frame.f_code.co_name != "<module>":
        frame = frame.f_back
    return frame.f_globals.get("__name__", func.__module__) if frame is not None else func.__module__


def case_modules():
    """The module that registered each loaded case outside dalembert's own (``{case: module}``; ``MAIN`` for a
    case a script defines): what a worker in another interpreter imports to know it (``load_modules``)."""
    load_cases()
    return {name: module for name, module in sorted(_REGISTERED_IN.items())
            if name in CASES and not (module + ".").startswith(OWN_PREFIX)}


def load_modules(modules):
    """Know the cases of ``modules`` (``{case: module}``, another process's ``case_modules``) in place of this
    interpreter's entry points: a worker in an engine environment, where the packages that declare them are not
    installed. Each module is imported when its case is first asked for (``CASES[name]``), so that a module
    this interpreter cannot import fails the runs of its own cases only, naming itself and the fix."""
    global _LOADED
    CASES.modules.update({name: module for name, module in modules.items() if name not in CASES})
    _LOADED = True  # (the environment's entry points, if any, are not the starting process's)


def _import_for(name, module):
    """Import ``module`` to register case ``name``; ImportError naming both and the fix when it cannot be."""
    where = f"case {name!r}: its module {module!r}"
    if module == MAIN:
        raise ImportError(f"{where} is the script that started the run, which a worker in an engine environment "
                          "cannot import — move the case into a module of its own (imported by the script) or a "
                          "package registered in the entry-point group dalembert.cases")
    try:
        importlib.import_module(module)
    except Exception as e:
        raise ImportError(f"{where} cannot be imported in this worker's interpreter ({sys.prefix}): "
                          f"{type(e).__name__}: {e} — install what it imports into that environment "
                          f"({sys.executable} -m pip install NAME; one uv made: uv pip install --python "
                          f"{sys.executable} NAME), or run the case on an engine without a version") from e
    if name not in CASES:
        raise ImportError(f"{where} was imported in this worker but registered no case {name!r} — register it "
                          "with @case when the module is imported")


def make_case(name, **params):
    """Build the registered case ``name`` with keyword ``params`` overriding defaults."""
    return load_cases()[name](**params)
