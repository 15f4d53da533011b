"""Newton and Warp, imported and initialized once per process, quietly; Newton's version.

Warp's native code writes to file descriptor 2 when it initializes (on a machine without a GPU: that no CUDA
driver was found), past ``sys.stderr``: ``engine`` keeps that text for the audit instead of printing it, and
points Warp's kernel cache at dalembert's cache directory (unless ``WARP_CACHE_PATH`` says otherwise), so the
kernels Newton compiles on first use are compiled once per machine, not once per run.
"""

from __future__ import annotations

import functools
import os
import tempfile

__all__ = ["DEVICE", "engine", "version"]

DEVICE = "cpu"  # Warp's CPU backend: the adapter runs where no accelerator is


@functools.cache
def engine():
    """``(warp, newton, init message)``: Warp initialized once per process on its kernel cache, its log quiet;
    the message is what Warp's native code printed at init, kept for the audit."""
    import warp as wp

    from dalembert.cache import cache_dir

    wp.config.log_level = wp.LOG_ERROR  # no "Module ... load ... (compiled)" line per kernel
    wp.config.quiet = True
    if not os.environ.get("WARP_CACHE_PATH"):
        wp.config.kernel_cache_dir = cache_dir("warp")
    with tempfile.TemporaryFile(mode="w+") as err:  # native code writes to fd 2, past sys.stderr
        saved = os.dup(2)
        os.dup2(err.fileno(), 2)
        try:
            wp.init()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        err.seek(0)
        message = err.read().strip()
    import newton

    return wp, newton, message


@functools.cache  # (installed packages do not change under a process)
def version():
    """Newton's distribution version; ImportError naming the extra when it or Warp is missing. Neither is
    imported here (the harness asks before forking its workers)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version
    from importlib.util import find_spec

    for module in ("warp", "newton"):
        if find_spec(module) is None:
            raise ImportError(f"No module named {module!r} (install dalembert[newton])")
    try:
        return dist_version("newton")
    except PackageNotFoundError as e:
        raise ImportError("newton is importable but its distribution is not installed "
                          "(install dalembert[newton])") from e
