"""Engines by name: the built-in adapters, programmatic registrations and entry points.

Built-in adapters are listed in ``BUILTIN`` as ``"module:Class"`` and imported
only when asked for; third-party ones register through the entry-point group
``dalembert.adapters`` or ``register_adapter``.

A plugin is loaded (its module imported, its class read) when engines are listed,
so that one plugin that cannot be imported is named in a ``PluginWarning`` and
left out, and every other engine still lists and runs. A plugin whose entry point
reuses a built-in engine's name is refused the same way, naming its distribution:
the name stays the built-in's. ``adapter_distribution`` says which installed
distribution provides an engine's adapter, and its version (a run records it).
"""

from __future__ import annotations

import importlib
import sys
import warnings

from dalembert.registry import Registry, UnknownNameError, suggest

__all__ = ["BUILTIN", "GROUP", "PluginWarning", "adapter_distribution", "adapter_names", "adapter_path",
           "get_adapter", "plugin_problems", "register_adapter"]

BUILTIN = {
    "reference": "dalembert.adapters.reference:ReferenceAdapter",
    "mujoco": "dalembert.adapters.mujoco:MujocoAdapter",
    "pinocchio": "dalembert.adapters.pinocchio:PinocchioAdapter",
    "exudyn": "dalembert.adapters.exudyn:ExudynAdapter",
    "drake": "dalembert.adapters.drake:DrakeAdapter",
    "mjx": "dalembert.adapters.mjx:MjxAdapter",
    "pybullet": "dalembert.adapters.pybullet:PybulletAdapter",
    "dart": "dalembert.adapters.dart:DartAdapter",
    "simbody": "dalembert.adapters.simbody:SimbodyAdapter",
    "mujoco_warp": "dalembert.adapters.mujoco_warp:MujocoWarpAdapter",
    "newton": "dalembert.adapters.newton:NewtonAdapter",
}
# The entry-point group third-party adapters register in (a package's ``[project.entry-points."dalembert.adapters"]``).
GROUP = "dalembert.adapters"
# The distribution of the built-in adapters (this package).
OWN_DISTRIBUTION = "dalembert"

_REGISTRY = Registry("engine")


class PluginWarning(UserWarning):
    """A plugin engine left out: it cannot be imported, or its name is a built-in engine's."""


def _distribution_label(ep):
    """``name version`` of the distribution that declares entry point ``ep`` ("an unknown distribution" without)."""
    dist = getattr(ep, "dist", None)
    return f"{dist.name} {dist.version}" if dist is not None else "an unknown distribution"


def _entry_points():
    """The group's entry points by name, the refused ones (a built-in's name) left out."""
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group=GROUP) if ep.name not in BUILTIN}


def plugin_problems():
    """Every installed plugin left out, ``{name: why — the fix}``. Loads each plugin (imports its module:
    adapters import their engine lazily, so this is cheap) and names its distribution."""
    from importlib.metadata import entry_points

    out = {}
    for ep in entry_points(group=GROUP):
        where = f"plugin engine {ep.name!r} ({ep.value}, from {_distribution_label(ep)})"
        if ep.name in BUILTIN:
            out[ep.name] = (f"{where}: refused — {ep.name!r} is a built-in engine's name; rename the entry point "
                            f"in that package's {GROUP!r} entry points")
        elif ep.name not in _REGISTRY:
            try:
                ep.load()
            except Exception as e:  # whatever a broken plugin raises on import is its problem, named here
                out[ep.name] = (f"{where}: left out, it cannot be imported ({type(e).__name__}: {e}) — fix or "
                                "uninstall that package")
    return out


def register_adapter(name, cls):
    """Register an adapter class under ``name`` programmatically (plugins, tests).

    The class must be importable by module and name: worker processes that do
    not share this process's memory (forkserver, Dask) import it from there.
    """
    BUILTIN.pop(name, None)
    _REGISTRY.register(name, cls)
    return cls


def adapter_path(name):
    """``"module:Class"`` of the adapter registered as ``name`` (how another process imports it); a versioned
    name's (``mujoco==3.6.0``) is its engine's."""
    if name not in _REGISTRY and name not in BUILTIN and _versioned(name):
        from dalembert.environments import parse_engine

        name = parse_engine(name).engine
    if name in _REGISTRY:
        cls = _REGISTRY[name]
        return f"{cls.__module__}:{cls.__qualname__}"
    if name in BUILTIN:
        return BUILTIN[name]
    eps = _entry_points()
    if name in eps:
        return eps[name].value
    raise UnknownNameError(f"unknown engine {name!r}{suggest(name, adapter_names())}")


def _in_environment(name, path):
    """The adapter of versioned engine ``name`` (``mujoco==3.6.0``): its engine's, whose ``version()`` outside the
    engine's environment is the environment's (``Environment.version``: ImportError naming ``dalembert env
    create`` when it was not made) and inside it, in the environment's worker, the engine's own."""
    from dalembert.environments import environment

    env = environment(name)
    adapter = get_adapter(env.spec.engine, path)
    if not env.active:
        adapter.version = env.version  # this instance only: this process's own engine keeps its version

        def elsewhere(*args, **kwargs):  # never a run of this process's engine recorded under another version
            raise RuntimeError(f"{name} runs in its environment's workers only ({env.path}), not in {sys.prefix}")
        adapter.prepare = adapter.run = elsewhere
    return adapter


def _versioned(name):
    from dalembert.environments import is_versioned

    return is_versioned(name)


def adapter_names():
    """Every engine that can be used by name (built-in, programmatic and the entry points that load), sorted.

    A plugin that cannot be imported, or that reuses a built-in's name, is left out with a ``PluginWarning``
    naming it and its distribution (``plugin_problems``)."""
    problems = plugin_problems()
    for problem in problems.values():
        warnings.warn(problem, PluginWarning, stacklevel=2)
    return sorted(set(BUILTIN) | (set(_entry_points()) - set(problems)) | set(_REGISTRY))


def adapter_distribution(name):
    """``(distribution, version)`` of the installed package that provides engine ``name``'s adapter.

    ``("dalembert", its version)`` for a built-in; for a plugin, the distribution that declares its entry
    point; for an adapter registered programmatically, the distribution that installs its top-level module;
    ``("", "")`` when none does (a class defined in a script or a test). The installed distributions are read
    once per environment (``dalembert.distributions``)."""
    from dalembert.distributions import installed

    if name in BUILTIN:
        return OWN_DISTRIBUTION, _own_version()
    eps = _entry_points()
    if name in eps and (name not in _REGISTRY or adapter_path(name) == eps[name].value):
        dist = getattr(eps[name], "dist", None)
        if dist is not None:
            return dist.name, dist.version
    if name in _REGISTRY:
        top = _REGISTRY[name].__module__.split(".")[0]
        installs = installed()
        for dist in installs.packages.get(top, ()):
            return dist, installs.version(dist)
    return "", ""


def _own_version():
    from importlib import metadata

    from dalembert.distributions import installed

    try:
        return installed().version(OWN_DISTRIBUTION)
    except metadata.PackageNotFoundError:  # run from a checkout that was never installed
        return sys.modules["dalembert"].__version__


def get_adapter(name, path=None):
    """An instance of the adapter registered as ``name`` (imported on first use).

    ``path`` (``"module:Class"``) lets a worker process import an adapter that
    was registered programmatically in its parent. A plugin that cannot be imported raises ``ImportError``
    naming it and its distribution. A versioned name (``mujoco==3.6.0``) is its engine's adapter, in an engine
    environment (``dalembert.environments.adapter_for``).
    """
    if name not in _REGISTRY and name not in BUILTIN and _versioned(name):
        return _in_environment(name, path)
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
            try:
                loaded = eps[name].load()
            except Exception as e:
                raise ImportError(f"plugin engine {name!r} ({eps[name].value}, from {_distribution_label(eps[name])}) "
                                  f"cannot be imported ({type(e).__name__}: {e}) — fix or uninstall that "
                                  "package") from e
            _REGISTRY.register(name, loaded)
        else:
            raise UnknownNameError(f"unknown engine {name!r}{suggest(name, adapter_names())}")
    return _REGISTRY[name]()
