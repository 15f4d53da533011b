"""A worker's start in an engine environment's interpreter, importing the code of the process that starts it.

An engine environment (``dalembert.environments``) holds an engine at a version and the libraries the worker
side needs, not dalembert itself: its workers import this dalembert's code from where the starting process
imports it (``sources``), so that the two sides of the pipe always run one checkout's code (a pickled record's
classes read the same on both) and an environment outlives the checkout that made it. This file runs as a
script, by its path, from the environment's interpreter (``command``):

    ENV/bin/python .../dalembert/harness/boot.py SOURCES ACTION [ARGS...]

``SOURCES``: ``{package: directory}`` as JSON; ``ACTION``: ``serve`` (a pool's long-lived worker,
``dalembert.harness.worker.serve``, its settings in ARGS) or ``run`` (one run on stdin,
``dalembert.harness.worker.main``: a Dask task). Run as a script it imports nothing of dalembert before
``SourceFinder`` is in place, and nothing beside the standard library at all.
"""

import json
import os
import sys
from importlib.util import find_spec, spec_from_file_location

__all__ = ["PACKAGES", "SourceFinder", "sources", "command"]

# dalembert's packages whose directories are their own (pyproject.toml's ``package-dir``: ``dalembert.reference``
# is the checkout's ``reference/``, not ``dalembert/reference/``); every other module is found under one of them.
PACKAGES = ("dalembert", "dalembert.reference", "dalembert.adapters", "dalembert.cases", "dalembert.reports")
ACTIONS = ("serve", "run")


def sources():
    """Where this process imports each of ``PACKAGES`` from: ``{package: directory}`` (absolute paths)."""
    return {name: os.path.abspath(find_spec(name).submodule_search_locations[0]) for name in PACKAGES}


class SourceFinder:
    """A meta path finder that imports each of ``sources``' packages (``{package: directory}``) from its
    directory, ahead of any other finder (an environment's own, stale, install of dalembert included)."""

    def __init__(self, sources):
        self.sources = dict(sources)

    def find_spec(self, fullname, path=None, target=None):
        directory = self.sources.get(fullname)
        if directory is None:
            return None  # a subpackage or module: found by the default machinery in its package's __path__
        return spec_from_file_location(fullname, os.path.join(directory, "__init__.py"),
                                       submodule_search_locations=[directory])


def command(python, action):
    """The command line that starts a worker for ``action`` (``ACTIONS``) in interpreter ``python`` (an engine
    environment's ``bin/python``) on this process's code (list of str; the caller appends ``serve``'s settings)."""
    if action not in ACTIONS:
        raise ValueError(f"boot.command action: {action!r} is none of {', '.join(ACTIONS)} — use one of them")
    return [python, os.path.abspath(__file__), json.dumps(sources()), action]


def _main():
    # a script's directory leads sys.path: this one's (dalembert/harness) holds modules named as packages
    # (``dask``) that would shadow them
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path[:] = [p for p in sys.path if p not in ("", ".") and os.path.abspath(p) != here]
    sys.meta_path.insert(0, SourceFinder(json.loads(sys.argv[1])))
    action, sys.argv[1:] = sys.argv[2], sys.argv[3:]
    # the built-in cases, which the entry point group loads where dalembert is installed (not in an environment)
    import dalembert.cases  # noqa: F401
    from dalembert.harness import worker

    worker.serve() if action == "serve" else worker.main()


if __name__ == "__main__":
    _main()
