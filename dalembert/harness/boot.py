"""A worker's start in an engine environment's interpreter, importing the code of the process that starts it.

An engine environment (``dalembert.environments``) holds an engine at a version and the libraries the worker
side needs, not dalembert itself: its workers import this dalembert's code from where the starting process
imports it (``sources``), so that the two sides of the pipe always run one checkout's code (a pickled record's
classes read the same on both) and an environment outlives the checkout that made it. This file runs as a
script, by its path, from the environment's interpreter (``command``):

    ENV/bin/python .../dalembert/harness/boot.py CODE ACTION [ARGS...]

``CODE`` (JSON, ``code``): ``packages``, dalembert's ``{package: directory}`` (``sources``); ``cases``, the module
that registered each of the starting process's cases outside dalembert's own (``{case: module}``: its entry
points' case packages, and modules that registered cases when imported: ``case_registry.case_modules``), and
``modules``, where the starting process imports each of those modules' top-level package or module
(``{name: [directories]}`` for a package, ``{name: file}`` for a module): a third party's cases run in an
environment's worker as in a forked one, their own modules imported from where the starting process imports
them, what they import in turn from the environment. ``ACTION``: ``serve`` (a pool's long-lived worker,
``dalembert.harness.worker.serve``, its settings in ARGS), ``run`` (one run on stdin,
``dalembert.harness.worker.main``: a Dask task) or ``batches`` (a group of runs on stdin,
``dalembert.harness.batches.main``: a Dask task of a chunk or a batch). Run as a script it imports nothing of
dalembert before ``SourceFinder`` is in place, and nothing beside the standard library at all.
"""

import json
import os
import sys
from importlib.machinery import ModuleSpec
from importlib.util import find_spec, spec_from_file_location

__all__ = ["PACKAGES", "SourceFinder", "sources", "case_sources", "code", "command"]

# dalembert's packages whose directories are their own (pyproject.toml's ``package-dir``: ``dalembert.reference``
# is the checkout's ``reference/``, not ``dalembert/reference/``); every other module is found under one of them.
PACKAGES = ("dalembert", "dalembert.reference", "dalembert.adapters", "dalembert.cases", "dalembert.reports")
ACTIONS = ("serve", "run", "batches")


def sources():
    """Where this process imports each of ``PACKAGES`` from: ``{package: directory}`` (absolute paths)."""
    return {name: os.path.abspath(find_spec(name).submodule_search_locations[0]) for name in PACKAGES}


def case_sources():
    """The third-party cases this process knows and where it imports their modules from: ``(cases, modules)``,
    ``{case: module}`` (``case_registry.case_modules``) and ``{top-level name: [directories] or file}`` of
    those modules (a namespace package's several directories; ``__main__``, a script, has none)."""
    from dalembert.case_registry import MAIN, case_modules

    cases = case_modules()
    modules = {}
    for top in sorted({m.partition(".")[0] for m in cases.values()} - {MAIN}):
        spec = getattr(sys.modules.get(top), "__spec__", None) or _find(top)
        if spec is None:
            continue  # nowhere to import it from: its cases' runs say so in the worker
        if spec.submodule_search_locations is not None:
            modules[top] = [os.path.abspath(d) for d in spec.submodule_search_locations]
        elif spec.origin and os.path.isfile(spec.origin):
            modules[top] = os.path.abspath(spec.origin)
    return cases, modules


def _find(name):
    """``find_spec(name)``, None where it cannot be found."""
    try:
        return find_spec(name)
    except (ImportError, ValueError):
        return None


def code():
    """What a worker in another interpreter imports, as ``CODE`` (module docstring): a dict for JSON."""
    cases, modules = case_sources()
    return {"packages": sources(), "cases": cases, "modules": modules}


class SourceFinder:
    """A meta path finder that imports each of ``sources``' packages and modules from where it names, ahead of
    any other finder (an environment's own, stale, install of dalembert included): ``{name: directory}`` (a
    package: dalembert's), ``{name: [directories]}`` (a package, or a namespace package's portions) or
    ``{name: file}`` (a module)."""

    def __init__(self, sources):
        self.sources = dict(sources)

    def find_spec(self, fullname, path=None, target=None):
        where = self.sources.get(fullname)
        if where is None:
            return None  # a subpackage or module: found by the default machinery in its package's __path__
        if isinstance(where, str) and not os.path.isdir(where):
            return spec_from_file_location(fullname, where)  # a module
        directories = [where] if isinstance(where, str) else list(where)
        init = os.path.join(directories[0], "__init__.py")
        if len(directories) == 1 and os.path.isfile(init):
            return spec_from_file_location(fullname, init, submodule_search_locations=directories)
        spec = ModuleSpec(fullname, None, is_package=True)  # a namespace package
        spec.submodule_search_locations = directories
        return spec


def command(python, action):
    """The command line that starts a worker for ``action`` (``ACTIONS``) in interpreter ``python`` (an engine
    environment's ``bin/python``) on this process's code (list of str; the caller appends ``serve``'s settings)."""
    if action not in ACTIONS:
        raise ValueError(f"boot.command action: {action!r} is none of {', '.join(ACTIONS)} — use one of them")
    return [python, os.path.abspath(__file__), json.dumps(code()), action]


def _install(given):
    """Import, in this interpreter, the code ``given`` names (``code()`` of the starting process): dalembert's
    packages and the case modules from where that process imports them, its built-in cases, and its others
    known by module (each imported when a run asks for it: ``case_registry.load_modules``)."""
    # a script's directory leads sys.path: this one's (dalembert/harness) holds modules named as packages
    # (``dask``) that would shadow them
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path[:] = [p for p in sys.path if p not in ("", ".") and os.path.abspath(p) != here]
    # dalembert's packages win over the case modules' (a case package may not shadow dalembert)
    sys.meta_path.insert(0, SourceFinder({**given["modules"], **given["packages"]}))
    # the built-in cases, which the entry point group loads where dalembert is installed (not in an environment)
    import dalembert.cases  # noqa: F401
    from dalembert.case_registry import load_modules

    load_modules(given["cases"])


def _main():
    _install(json.loads(sys.argv[1]))
    action, sys.argv[1:] = sys.argv[2], sys.argv[3:]
    if action == "batches":
        from dalembert.harness import batches

        return batches.main()
    from dalembert.harness import worker

    worker.serve() if action == "serve" else worker.main()


if __name__ == "__main__":
    _main()
