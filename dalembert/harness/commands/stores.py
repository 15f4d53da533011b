"""A results directory opened for a command that reads it."""

from __future__ import annotations

__all__ = ["open_store"]


def open_store(path, schemas=None):
    """The store at ``path`` (``dalembert.store.Store``) if its schema is one of ``schemas`` (default:
    this dalembert's); ValueError naming the directory otherwise."""
    from dalembert.record import SCHEMA_VERSION
    from dalembert.store import Store

    return Store.open(path, schemas or (SCHEMA_VERSION,))
