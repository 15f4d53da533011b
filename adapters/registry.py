"""Engines by name: the built-in adapters, programmatic registrations and entry points.

Built-in adapters are listed in ``BUILTIN`` as ``"module:Class"`` and imported
only when asked for; third-party ones register through the entry-point group
``dalembert.adapters`` or ``register_adapter``.
"""

from __future__ import annotations

import importlib

from dalembert.registry import Registry, UnknownNameError, suggest

__all__ = ["BUILTIN", "adapter_names", "adapter_path", "get_adapter", "register_adapter"]

BUILTIN = {
    "reference": "dalembert.adapters.reference:ReferenceAdapter",
    "mujoco": "dalembert.adapters.mujoco:MujocoAdapter",
    "pinocchio": "dalembert.adapters.pinocchio:PinocchioAdapter",
    "exudyn": "dalembert.adapters.exudyn:ExudynAdapter",
    "drake": "dalembert.adapters.drake:DrakeAdapter",
    "mjx": "dalembert.adapters.mjx:MjxAdapter",
    "dart": "dalembert.adapters.dart:DartAdapter",
}

_REGISTRY = Registry("engine")


def _entry_points():
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group="dalembert.adapters")}


def register_adapter(name, cls):
    """Register an adapter class under ``name`` programmatically (plugins, tests).

    The class must be importable by module and name: worker processes that do
    not share this process's memory (forkserver, Dask) import it from there.
    """
    BUILTIN.pop(name, None)
    _REGISTRY.register(name, cls)
    return cls


def adapter_path(name):
    """``"module:Class"`` of the adapter registered as ``name`` (how another process imports it)."""
    if name in _REGISTRY:
        cls = _REGISTRY[name]
        return f"{cls.__module__}:{cls.__qualname__}"
    if name in BUILTIN:
        return BUILTIN[name]
    eps = _entry_points()
    if name in eps:
        return eps[name].value
    raise UnknownNameError(f"unknown engine {name!r}{suggest(name, adapter_names())}")


def adapter_names():
    """Every registered engine name (built-in, programmatic and entry points), sorted."""
    return sorted(set(BUILTIN) | set(_entry_points()) | set(_REGISTRY))


def get_adapter(name, path=None):
    """An instance of the adapter registered as ``name`` (imported on first use).

    ``path`` (``"module:Class"``) lets a worker process import an adapter that
    was registered programmatically in its parent.
    """
    if name not in _REGISTRY and path and name not in BUILTIN:
        module, cls = path.split(":")
        obj = getattr(importlib.import_module(module), cls)
        if name not in _REGISTRY:  # importing the module may have registered it already
            _REGISTRY.register(name, obj)
    if name not in _REGISTRY:
        if name in BUILTIN:
            module, cls = BUILTIN[name].split(":")
            _REGISTRY.register(name, getattr(importlib.import_module(module), cls))
        elif name in (eps := _entry_points()):
            _REGISTRY.register(name, eps[name].load())
        else:
            raise UnknownNameError(f"unknown engine {name!r}{suggest(name, adapter_names())}")
    return _REGISTRY[name]()
