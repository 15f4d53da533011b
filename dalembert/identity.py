"""What makes two runs the same run, and two runs of a case comparable: ``run_identity``, ``run_key``,
``check_version``.

A run is identified by its case, the case parameters given, its engine and its ``Settings``
(``run_identity``): ``compare`` pairs the runs of two stores by it. A run's file key in its store
(``run_key``) is that identity within one version of the case: the case version (a content hash of
the case built with its parameters) stands for the parameters there, so the keys of every store
written before still name the same runs (a ``--resume`` finds them by key).
"""

from __future__ import annotations

import hashlib
import json
from typing import NamedTuple

__all__ = ["RunIdentity", "run_identity", "run_key", "check_version"]

# Hex digits of the content hash in a run's file key: 48 bits, no collision among the
# thousands of runs of a store.
KEY_DIGEST_CHARS = 12


class RunIdentity(NamedTuple):
    """What identifies a run across stores.

    Attributes
    ----------
    case : str
    params : str — the case parameters given, as sorted JSON (vectors as lists)
    engine, integrator : str
    dt : float or None — fixed step, s; rtol, atol : float or None — adaptive tolerances
    options : tuple of (str, value) — engine options, sorted by name
    """

    case: str
    params: str
    engine: str
    integrator: str
    dt: float | None
    rtol: float | None
    atol: float | None
    options: tuple


def run_identity(case, params, engine, settings):
    """The identity of running ``case`` (name) with ``params`` (mapping, or (key, value) pairs) on
    ``engine`` with ``settings`` (``dalembert.settings.Settings``)."""
    return RunIdentity(case, json.dumps(dict(params), sort_keys=True, default=list), engine, settings.integrator,
                       settings.dt, settings.rtol, settings.atol, tuple(sorted(settings.options.items())))


def run_key(identity, case_version):
    """A run's deterministic, readable file key: ``<case>__<engine>__<integrator>__<content hash>``.

    ``identity``: its ``RunIdentity``; ``case_version``: the version of the case it runs. The hash
    covers the case version in place of the parameters (see the module docstring), so it is the
    hash every store has been written with.
    """
    i = identity
    payload = json.dumps([i.case, case_version, i.engine, i.integrator, i.dt, i.rtol, i.atol,
                          [list(pair) for pair in i.options]], default=repr)
    digest = hashlib.sha256(payload.encode()).hexdigest()[:KEY_DIGEST_CHARS]
    return f"{i.case}__{i.engine}__{i.integrator}__{digest}"


def check_version(case_name, expected, actual, what, now="now"):
    """Why runs of case ``case_name`` at version ``expected`` cannot go with its version ``actual``,
    or None when they are one version: the one guard against mixing two versions of a case.

    Parameters
    ----------
    case_name : str
    expected : str — the version that ``what`` holds (a matrix's manifest, a store's runs)
    actual : str — the version found ``now`` (the code now, another store)
    what : str — who holds ``expected``, e.g. ``"the matrix was made for"``
    now : str — where ``actual`` was found

    Returns
    -------
    str or None — e.g. ``case 'pendulum' is version 0123456789ab now, the matrix was made for version
    ba9876543210``
    """
    if actual == expected:
        return None
    return f"case {case_name!r} is version {actual} {now}, {what} version {expected}"
