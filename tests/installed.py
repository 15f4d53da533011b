"""Whether an optional engine is installed, found without importing it.

``pytest.importorskip`` at a module's top imports the engine while pytest collects, in every pytest-xdist
worker, whether or not that worker runs one of the module's tests: ``mujoco.mjx`` (with JAX), ``mujoco_warp``
and ``newton`` (with Warp) cost seconds each to import, tens of seconds on 2 loaded cores. A module marked with
:func:`needs` is skipped when the engine is missing, and imports it only when a test of it runs.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util

import pytest

__all__ = ["found", "needs"]


def found(name):
    """Whether the module ``name`` (dotted, e.g. ``"mujoco.mjx"``) can be imported, by its spec alone.

    A parent package's spec gives where its submodules are; no package is imported (``importlib.util.find_spec``
    would import ``mujoco`` to find ``mujoco.mjx``).
    """
    parts = name.split(".")
    spec = importlib.util.find_spec(parts[0])
    for i in range(1, len(parts)):
        if spec is None or not spec.submodule_search_locations:
            return False
        spec = importlib.machinery.PathFinder.find_spec(".".join(parts[:i + 1]), spec.submodule_search_locations)
    return spec is not None


def needs(*names, reason=None):
    """A mark that skips a test (or, as ``pytestmark``, a module) unless every module of ``names`` is installed.

    ``names``: the engine's module and the packages it needs that a wheel may ship without (``mujoco`` ships
    ``mujoco.mjx`` without JAX, which ``pip install dalembert[mjx]`` adds).
    """
    missing = [n for n in names if not found(n)]
    return pytest.mark.skipif(bool(missing), reason=reason or f"{', '.join(missing)} is not installed")
