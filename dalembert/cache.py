"""Where dalembert keeps what it builds once and reuses: compiled code, never results.

``cache_dir(*parts)``: ``$DALEMBERT_CACHE``, else ``$XDG_CACHE_HOME/dalembert``, else
``~/.cache/dalembert``, joined with ``parts`` and created. Entries are keyed by everything
that makes them (source, compiler, versions), so a stale entry is never used: deleting the
directory costs only the time to build again. Results live in stores, not here.
"""

from __future__ import annotations

import os

__all__ = ["cache_dir"]


def cache_dir(*parts):
    """The cache directory (created), or its subdirectory ``parts``; str."""
    root = os.environ.get("DALEMBERT_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "dalembert")
    path = os.path.join(root, *parts)
    os.makedirs(path, exist_ok=True)
    return path
