"""Newton and Warp, imported and initialized once per process, quietly (``adapters.warp_runtime``: Warp's
init message kept for the audit, its kernels compiled into dalembert's cache once per machine); Newton's version.
"""

from __future__ import annotations

import functools

__all__ = ["DEVICE", "engine", "version"]

DEVICE = "cpu"  # Warp's CPU backend, the default (option ``device``: ``warp_runtime.DEVICES``)


@functools.cache
def engine():
    """``(warp, newton, init message)``: Warp initialized once per process on its kernel cache, its log quiet
    (``adapters.warp_runtime.init``); the message is what Warp's native code printed at init, kept for the audit."""
    from dalembert.adapters.warp_runtime import init

    wp, message = init()
    import newton

    return wp, newton, message


@functools.cache  # (installed packages do not change under a process)
def version():
    """Newton's distribution version; ImportError naming the extra when it or Warp is missing. Neither is
    imported here (the harness asks before forking its workers)."""
    from dalembert.adapters.warp_runtime import distribution_version

    return distribution_version(("warp", "newton"), "newton", "newton")
