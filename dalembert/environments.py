"""Engine environments: an engine at a version of its own, in a virtual environment under the cache.

An engine named with a requirement (``mujoco==3.6.0``, PEP 440: any specifier the package index
understands) runs in an environment made for it by ``dalembert env create mujoco==3.6.0``: a
virtual environment at ``cache_dir("environments", ...)`` holding the libraries of dalembert's worker side,
``WORKER_LIBRARIES`` at this environment's versions (the records and trajectories cross between the
two interpreters as pickles), and the engine's distribution at the asked version with
its own dependencies. It holds no dalembert: its workers import the code of the process that starts them,
from where that process imports it (``dalembert.harness.boot``), so that both sides always run one
checkout's code and an environment outlives the checkout (or installed wheel) that made it. It is made
with ``uv`` when ``uv`` is on PATH, else with ``venv`` and pip, from
this interpreter (the same Python version: a pickle's classes and numpy's arrays must read the same).

Only ``create`` reaches the network. A run of a versioned engine (``dalembert run --engine
mujoco==3.6.0``) starts its workers from the environment's interpreter (``dalembert.harness.pool``)
and refuses, before anything runs, an environment that is missing (naming the command that makes
it) or an engine version the adapter does not support (``Adapter.supported_versions``).

The engine name a record carries is the requirement as ``packaging`` writes it (``mujoco==3.6.0``),
so that one store holds several versions of one engine; the record's ``engine_version`` is what the
environment's interpreter imported.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from datetime import datetime, timezone

from dalembert.cache import cache_dir

__all__ = ["DISTRIBUTIONS", "EngineSpec", "Environment", "parse_engine", "is_versioned", "engine_of", "environment",
           "require", "serving", "create", "environments", "remove", "installer", "WORKER_LIBRARIES", "ENGINE_LIBRARIES",
           "PICKLED_LIBRARIES"]

# The distribution on the package index of each built-in adapter's engine (``importlib.metadata``'s
# names of the installed wheels: ``pin`` is Pinocchio's, ``mujoco-mjx`` MJX's, ``dartpy`` DART's).
DISTRIBUTIONS = {"mujoco": "mujoco", "pinocchio": "pin", "exudyn": "exudyn", "drake": "drake", "mjx": "mujoco-mjx",
                 "pybullet": "pybullet", "dart": "dartpy", "newton": "newton"}
# What the worker side imports besides the engine, installed at this environment's versions: numpy and
# scipy (arrays and the truths' integrators; a pickled array must read the same), threadpoolctl (each
# worker's thread pools, ``dalembert.harness.threads``), packaging (an engine's name read as a requirement).
WORKER_LIBRARIES = ("numpy", "scipy", "threadpoolctl", "packaging")
# What crosses the pipe between a worker and its parent as pickles besides dalembert's own classes (the
# trajectories' arrays): an environment whose version of one differs from this process's is stale (``stale``).
PICKLED_LIBRARIES = ("numpy",)
# What an engine's adapter needs beside the engine's own dependencies (pyproject's), at this environment's versions:
# Pinocchio's compiled stepper builds against Eigen's headers from ``cmeel-eigen`` (without them its runs take the
# Python loop, and say so in their audit).
ENGINE_LIBRARIES = {"pinocchio": ("cmeel-eigen",)}
# The file in an environment that says what it holds (written last: an environment without it is unfinished).
INFO = "environment.json"
# A requirement's first operator character: a name without one is a plain engine name.
_OPERATORS = re.compile(r"[=<>!~\[@;\s]")
# How much of a failed install's output an error quotes (its end says why).
TAIL_CHARS = 2000


def is_versioned(name):
    """Whether engine ``name`` carries a requirement (``mujoco==3.6.0``), by its text alone (cheap)."""
    return bool(_OPERATORS.search(name))


def engine_of(name):
    """The adapter's engine name of engine ``name``: ``mujoco`` for ``mujoco==3.6.0`` and for ``mujoco``."""
    return parse_engine(name).engine if is_versioned(name) else name


@dataclass(frozen=True)
class EngineSpec:
    """An engine at a version: ``name`` as records carry it (``mujoco==3.6.0``), the adapter's ``engine``
    name (``mujoco``), its ``distribution`` on the index (``mujoco``) and the ``specifier`` (``==3.6.0``)."""

    name: str
    engine: str
    distribution: str
    specifier: str

    @property
    def requirement(self):
        """What pip installs: the distribution with the specifier (``pin==2.6.0`` for ``pinocchio==2.6.0``)."""
        return self.distribution + self.specifier

    def install(self, extras=()):
        """What an environment installs: ``requirement`` with ``extras`` (the ones its adapter declares,
        ``Adapter.environment_extras``: ``newton[sim]==1.8.0``, whose ``sim`` brings the MuJoCo that Newton's MuJoCo
        solver pins)."""
        return self.distribution + (f"[{','.join(extras)}]" if extras else "") + self.specifier

    @property
    def directory(self):
        """The environment's directory name: readable, and unique to ``name`` (a hash of it)."""
        slug = re.sub(r"[^A-Za-z0-9.]+", "_", self.name).strip("_")
        return f"{slug}-{hashlib.sha256(self.name.encode()).hexdigest()[:8]}"


def parse_engine(text, flag="--engine"):
    """The ``EngineSpec`` of ``text`` (``mujoco==3.6.0``); ValueError naming ``flag`` and the fix for a text
    that is not a requirement, an unknown engine, an engine with no distribution of its own (the reference),
    or extras, a URL or a marker (an environment is one engine at one version)."""
    from packaging.requirements import InvalidRequirement, Requirement

    from dalembert.registry import suggest

    try:
        req = Requirement(text)
    except InvalidRequirement as e:
        raise ValueError(f"{flag} {text}: not a requirement ({str(e).splitlines()[0]}) — write ENGINE==VERSION, e.g. "
                         "mujoco==3.6.0") from None
    if req.extras or req.url or req.marker:
        raise ValueError(f"{flag} {text}: extras, URLs and markers are not an engine version — write ENGINE==VERSION "
                         "(or another version specifier), e.g. mujoco==3.6.0")
    if req.name not in DISTRIBUTIONS:
        raise ValueError(f"{flag} {text}: {req.name!r} is no engine with a distribution of its own on the package "
                         f"index to install at a version (versions are for {', '.join(sorted(DISTRIBUTIONS))})"
                         f"{suggest(req.name, DISTRIBUTIONS)}; an engine without one runs by its plain name — drop "
                         "the version")
    if not str(req.specifier):
        raise ValueError(f"{flag} {text}: no version — write {req.name}==VERSION, or {req.name} for this "
                         "environment's")
    specifier = ",".join(sorted(str(s) for s in req.specifier))
    return EngineSpec(req.name + specifier, req.name, DISTRIBUTIONS[req.name], specifier)


@dataclass(frozen=True)
class Environment:
    """The environment of one ``EngineSpec``: ``path`` (its directory) and what ``INFO`` says of it."""

    spec: EngineSpec
    path: str

    @property
    def python(self):
        """The environment's interpreter (str)."""
        return os.path.join(self.path, "bin", "python")

    @property
    def exists(self):
        """Whether it was made to the end (its ``INFO`` written last)."""
        return os.path.isfile(os.path.join(self.path, INFO))

    def info(self):
        """What the environment holds: ``requirement``, ``engine_version``, ``python``, ``installer``, ``created``
        (dict; one made before its workers imported the starting process's code also names the ``checkout`` it
        installed, which they no longer import); FileNotFoundError when it was not made."""
        with open(os.path.join(self.path, INFO)) as f:
            return json.load(f)

    @property
    def engine_version(self):
        """The engine version installed in it (str)."""
        return self.info()["engine_version"]

    def version(self):
        """The engine version a run records outside the environment: ``engine_version``; ImportError naming the
        command that makes the environment when it was not made (as for an engine not installed)."""
        if not self.exists:
            raise ImportError(f"no environment for {self.spec.name} — make it with: dalembert env create "
                              f"{self.spec.name}")
        return self.engine_version

    def stale(self):
        """Why this made environment's workers cannot serve this process: its Python or a ``PICKLED_LIBRARIES``
        version differs from this process's (``["numpy 2.3.0 there, 2.4.6 here"]``; empty when it can)."""
        import glob
        from importlib import metadata

        out = []
        there, here = self.info().get("python", ""), sys.version.split()[0]
        if there.rpartition(".")[0] != here.rpartition(".")[0]:  # (a patch release reads the same pickles)
            out.append(f"Python {there} there, {here} here")
        sites = glob.glob(os.path.join(self.path, "lib", "python*", "site-packages"))
        for lib in PICKLED_LIBRARIES:
            found = next(iter(metadata.distributions(name=lib, path=sites)), None)
            there = found.version if found is not None else "none"
            try:
                here = metadata.version(lib)
            except metadata.PackageNotFoundError:
                here = "none"
            if there != here:
                out.append(f"{lib} {there} there, {here} here")
        return out

    @property
    def active(self):
        """Whether this process runs in it: its interpreter's, or a pool's worker started for it (``serving``)."""
        return os.path.realpath(self.path) in _SERVING | {os.path.realpath(sys.prefix)}


# The environments this process is a pool's worker of (``serving``).
_SERVING = set()


def serving(path):
    """Say that this process is a pool's worker started for the environment at ``path``: its versioned engine
    runs here (``dalembert.harness.worker.serve``, started with the environment's interpreter)."""
    _SERVING.add(os.path.realpath(path))


def environment(name):
    """The ``Environment`` of engine ``name`` (``mujoco==3.6.0``), made or not."""
    spec = parse_engine(name)
    return Environment(spec, os.path.join(cache_dir("environments"), spec.directory))


def require(name, flag="--engine", problem=None):
    """The made ``Environment`` of ``name``; ValueError naming ``flag`` and the command that makes it otherwise
    (checked before anything runs: ``run`` never installs), or when ``problem(version)`` (the adapter's
    ``version_problem``) says why its engine version cannot run."""
    env = environment(name)
    if not env.exists:
        raise ValueError(f"{flag} {name}: no environment for it — make it (this needs the package index) with: "
                         f"dalembert env create {env.spec.name}")
    why = problem(env.engine_version) if problem else None
    if why:
        raise ValueError(f"{flag} {name}: {why} — remove it (dalembert env remove {env.spec.name}) and make "
                         "one at a supported version")
    stale = env.stale()
    if stale:
        raise ValueError(f"{flag} {name}: its environment is stale ({'; '.join(stale)}: its workers' arrays must "
                         f"read as this process's) — remake it: dalembert env create --force {env.spec.name}")
    return env


def installer():
    """``"uv"`` when ``uv`` is on PATH, else ``"pip"`` (``venv`` and pip)."""
    return "uv" if shutil.which("uv") else "pip"


def _pinned(libraries=WORKER_LIBRARIES):
    """``libraries`` at this environment's versions (``numpy==2.1.3``, ...); one not installed is left to pip."""
    from importlib import metadata

    out = []
    for lib in libraries:
        try:
            out.append(f"{lib}=={metadata.version(lib)}")
        except metadata.PackageNotFoundError:
            out.append(lib)
    return out


def _call(command, what, log):
    """Run ``command`` (a list); RuntimeError naming ``what`` with the end of its output when it fails."""
    log(" ".join(command))
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode:
        tail = (done.stdout + done.stderr)[-TAIL_CHARS:]
        raise RuntimeError(f"env create: {what} failed (exit code {done.returncode}):\n{tail}")
    return done.stdout


def create(name, log=lambda line: None, tool=None, problem=None, force=False, extras=()):
    """Make the environment of engine ``name`` (``mujoco==3.6.0``; reaches the package index) and return it.

    ``log``: told each command; ``tool``: ``"uv"`` or ``"pip"`` (default: ``installer()``); ``problem``: why
    an installed engine version cannot run (the adapter's ``version_problem``), or None; ``force``: make it
    again when it exists (a stale one), replacing it once the new one is made; ``extras``: the distribution's extras
    to install with it (the adapter's ``environment_extras``). ValueError when it exists
    already (without ``force``), or ``problem`` names one (nothing is then left behind); RuntimeError with the
    installer's output when an install fails (nor then, and a forced environment's old one stays).
    """
    env = environment(name)
    if env.exists and not force:
        raise ValueError(f"env create {name}: already made, at {env.path} (engine {env.engine_version}) — use it, or "
                         f"make it again: dalembert env create --force {env.spec.name}")
    tool = tool or installer()
    partial = env.path + ".partial"
    shutil.rmtree(partial, ignore_errors=True)
    python = os.path.join(partial, "bin", "python")
    try:
        if tool == "uv":
            _call(["uv", "venv", "--quiet", "--python", sys.executable, partial], "uv venv", log)
            pip = ["uv", "pip", "install", "--quiet", "--python", python]
        else:
            _call([sys.executable, "-m", "venv", partial], "venv", log)
            pip = [python, "-m", "pip", "install", "--quiet", "--disable-pip-version-check"]
        pinned = _pinned() + _pinned(ENGINE_LIBRARIES.get(env.spec.engine, ()))
        requirement = env.spec.install(extras)
        _call(pip + pinned + [requirement], f"installing {requirement} beside {' '.join(pinned)} "
              "(this environment's versions: the worker's arrays must read as the parent's; an engine release that "
              "needs others cannot run beside this dalembert)", log)
        version = _call([python, "-c", "import importlib.metadata as m, sys; "
                         f"print(m.version({env.spec.distribution!r}))"], "reading the engine's version", log).strip()
        why = problem(version) if problem else None
        if why:
            raise ValueError(f"env create {name}: {why} — ask for a supported version")
        info = {"engine": env.spec.name, "requirement": requirement, "engine_version": version,
                "python": sys.version.split()[0], "installer": tool,
                "created": datetime.now(timezone.utc).isoformat(timespec="seconds")}
        with open(os.path.join(partial, INFO), "w") as f:
            json.dump(info, f, indent=1)
        if force:
            shutil.rmtree(env.path, ignore_errors=True)
        os.replace(partial, env.path)  # whole or not at all: a run never finds half an environment
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    return env


def _version_order(info):
    """Sorts environments by engine, then engine version (PEP 440: 3.10.0 after 3.9.0; one ``packaging`` cannot
    read after the others, by text)."""
    from packaging.version import InvalidVersion, Version

    engine = _engine_name(info["engine"])
    try:
        return (engine, 0, Version(info["engine_version"]), info["engine"])
    except InvalidVersion:
        return (engine, 1, info["engine_version"], info["engine"])


def _engine_name(name):
    """The engine name of a made environment's ``name``: ``engine_of``'s, or its text before the version for an
    engine this dalembert does not know at a version (an environment another checkout or release made)."""
    try:
        return engine_of(name)
    except ValueError:
        return _OPERATORS.split(name, maxsplit=1)[0]


def environments():
    """Every made environment, ``[(engine name, info dict, path)]`` sorted by engine, then engine version."""
    root = cache_dir("environments")
    out = []
    for entry in sorted(os.listdir(root)):
        try:
            with open(os.path.join(root, entry, INFO)) as f:
                info = json.load(f)
        except (OSError, ValueError):
            continue  # an unfinished one (``.partial``) or another file
        out.append((info["engine"], info, os.path.join(root, entry)))
    return sorted(out, key=lambda e: _version_order(e[1]))


def remove(name):
    """Remove the environment of engine ``name``; ValueError naming the made ones when there is none."""
    made = environments()
    try:
        env = environment(name)
    except ValueError:  # an engine this dalembert cannot run at a version, made by another: removed by its listed name
        path = next((p for listed, _, p in made if listed == name), None)
        if path is None:
            raise
        shutil.rmtree(path)
        return Environment(EngineSpec(name, _engine_name(name), "", ""), path)
    if not env.exists:
        raise ValueError(f"env remove {name}: no environment for it (made: {', '.join(e[0] for e in made) or 'none'}) "
                         "— see dalembert env list")
    shutil.rmtree(env.path)
    return env
