"""Which installed distribution provides which top-level module, and its version: read once per environment.

A run records the versions of the libraries loaded where it ran (``harness.execute._libraries``) and the
distribution of its engine's adapter (``adapters.registry.adapter_distribution``). Both ask
``importlib.metadata.packages_distributions()``, which reads every installed distribution's metadata and, for one
without ``top_level.txt``, its whole ``RECORD``: ~0.2 s of CPU, paid by every fresh worker process (a pool's,
a forkserver's child, a Dask task's, an engine environment's). ``installed()`` answers from a small JSON file
under ``dalembert.cache.cache_dir("distributions")`` instead, computed by the first process of an environment.

The answer (``Distributions``) is exactly what the uncached calls give: ``packages`` is
``packages_distributions()``, ``version(name)`` is ``metadata.version(name)`` (``PackageNotFoundError`` where it
raises), ``files(name)`` the real paths of ``metadata.distribution(name).files``. The file is keyed by the
interpreter (``sys.executable``, ``sys.version``), the ``sys.path`` entries and each entry's ``st_mtime_ns``:
the distributions importlib finds are the ``*.dist-info``/``*.egg-info`` folders directly in those entries, and
installing, removing or upgrading one adds, removes or renames such a folder, which changes its entry's mtime.
What the key does not see: a file edited inside a dist-info folder without reinstalling (its ``METADATA`` or
``top_level.txt`` rewritten in place), two changes within one tick of a file system with coarse timestamps, and
distributions that a custom ``sys.meta_path`` finder provides. Deleting the cache folder recomputes it.

A cache file that is missing, corrupt, unreadable, of another key or unwritable never fails a run: the answer is
computed and the run goes on.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys

__all__ = ["Distributions", "compute", "installed"]

# The layout of the cache file; a file of another format is recomputed.
FORMAT = 1
# At most this many cache files (one per interpreter and ``sys.path``) are kept: a test's temporary ``sys.path``
# entry makes a new one, and the oldest beyond this are removed when one is written.
MAX_FILES = 64


class Distributions:
    """The installed distributions of one interpreter and ``sys.path``.

    Parameters
    ----------
    packages : dict
        ``{top-level module or folder: [distribution, ...]}``: ``importlib.metadata.packages_distributions()``.
    versions : dict
        ``{distribution: version or None}`` for every distribution named in ``packages`` (None: ``metadata.version``
        raises ``PackageNotFoundError`` for that name).
    files : dict
        ``{distribution: frozenset of real paths}``, the files installed by each distribution that shares a
        top-level name with another (where ``_libraries`` tells them apart); others are read when asked.
    """

    __slots__ = ("packages", "versions", "_files")

    def __init__(self, packages, versions, files):
        self.packages, self.versions, self._files = packages, versions, dict(files)

    def version(self, name):
        """``importlib.metadata.version(name)``; raises ``PackageNotFoundError`` as it does."""
        from importlib import metadata

        if name not in self.versions:
            return metadata.version(name)
        if self.versions[name] is None:
            raise metadata.PackageNotFoundError(name)
        return self.versions[name]

    def files(self, name):
        """The real paths of the files distribution ``name`` installed (a frozenset; read once if not cached)."""
        if name not in self._files:
            self._files[name] = _files(name)
        return self._files[name]

    def as_json(self):
        """The answer as plain JSON types (what the cache file holds)."""
        return {"packages": self.packages, "versions": self.versions,
                "files": {name: sorted(paths) for name, paths in self._files.items()}}

    def __eq__(self, other):
        return isinstance(other, Distributions) and self.as_json() == other.as_json()

    __hash__ = None


def _files(name):
    from importlib import metadata

    dist = metadata.distribution(name)
    return frozenset(os.path.realpath(dist.locate_file(p)) for p in dist.files or ())


def compute():
    """The answer read from the installed metadata now (no cache): ``Distributions``."""
    from importlib import metadata

    packages = metadata.packages_distributions()
    versions = {}
    for name in sorted({d for names in packages.values() for d in names}):
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:  # (a name packages_distributions read but no metadata answers to)
            versions[name] = None
    shared = sorted({d for names in packages.values() if len(names) > 1 for d in names})
    files = {}
    for name in shared:
        try:
            files[name] = _files(name)
        except metadata.PackageNotFoundError:
            continue
    return Distributions(dict(packages), versions, files)


def _key():
    """What decides the answer: the interpreter, the ``sys.path`` entries and each existing entry's mtime."""
    entries = []
    for entry in sys.path:
        path = os.path.abspath(entry or ".")  # ("": the working directory, as importlib reads it)
        try:
            mtime = os.stat(path).st_mtime_ns
        except OSError:  # an entry that does not exist (python311.zip) holds nothing; it may appear later
            mtime = None
        entries.append([path, mtime])
    return {"format": FORMAT, "executable": sys.executable, "version": sys.version, "path": entries}


def _file(key):
    """The cache file of ``key``'s interpreter and ``sys.path`` (its mtimes are checked inside)."""
    name = json.dumps([key["format"], key["executable"], key["version"], [p for p, _ in key["path"]]])
    from dalembert.cache import cache_dir

    return os.path.join(cache_dir("distributions"), hashlib.sha256(name.encode()).hexdigest()[:24] + ".json")


def _read(path, key):
    """The answer stored at ``path`` for ``key``, or None (missing, corrupt, unreadable or another key)."""
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
        if data.get("key") != key:
            return None
        return Distributions(data["packages"], data["versions"],
                             {name: frozenset(paths) for name, paths in data["files"].items()})
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def _write(path, key, answer):
    """Store ``answer`` at ``path`` (atomically) and keep at most ``MAX_FILES`` in its folder; never raises OSError."""
    from dalembert.atomic import atomic_write

    try:
        atomic_write(path, json.dumps({"key": key, **answer.as_json()}))
        folder = os.path.dirname(path)
        names = [os.path.join(folder, n) for n in os.listdir(folder) if n.endswith(".json")]
        if len(names) > MAX_FILES:
            for old in sorted(names, key=_mtime)[:len(names) - MAX_FILES]:
                os.unlink(old)
    except OSError:  # an unwritable cache (or a file another process removed first): the answer stands
        pass


def _mtime(path):
    try:
        return os.stat(path).st_mtime_ns
    except OSError:
        return 0


def installed():
    """The installed distributions of this interpreter and ``sys.path`` (``Distributions``): from this process's
    memo or the cache file when their key is current, else computed (and stored)."""
    global _MEMO
    key = _key()
    if _MEMO[0] == key:
        return _MEMO[1]
    try:
        path = _file(key)
    except OSError:  # the cache folder cannot be made
        path = None
    answer = _read(path, key) if path else None
    if answer is None:
        answer = compute()
        if path:
            _write(path, key, answer)
    _MEMO = (key, answer)
    return answer


# (key, answer) of this process's last ``installed()``: a forked worker inherits it and only checks the key.
_MEMO = (None, None)
