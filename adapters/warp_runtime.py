"""Warp, initialized once per process and quietly, for the engines built on it (MuJoCo Warp, Newton); and the
version of an optional engine's distribution, asked without importing it.

Warp's native code writes to file descriptor 2 when it initializes (on a machine without a GPU: that no CUDA
driver was found), past ``sys.stderr``: ``init`` keeps that text for the audit instead of printing it, and
points Warp's kernel cache at dalembert's cache directory (unless ``WARP_CACHE_PATH`` says otherwise), so the
kernels an engine compiles on first use are compiled once per machine, not once per run.
"""

from __future__ import annotations

import functools
import os
import tempfile

__all__ = ["init", "distribution_version"]


@functools.cache
def init():
    """``(warp, init message)``: Warp initialized once per process on dalembert's kernel cache, its log quiet;
    the message is what Warp's native code printed on fd 2 at init, kept for the audit."""
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
    return wp, message


def distribution_version(modules, distribution, extra):
    """The installed version of ``distribution``, without importing it (the harness asks before it forks its
    workers); ImportError naming ``dalembert[extra]`` when one of ``modules`` is missing."""
    from importlib.metadata import PackageNotFoundError, version
    from importlib.util import find_spec

    for module in modules:
        if find_spec(module) is None:
            raise ImportError(f"No module named {module!r} (install dalembert[{extra}])")
    try:
        return version(distribution)
    except PackageNotFoundError as e:
        raise ImportError(f"{modules[-1]} is importable but its distribution is not installed "
                          f"(install dalembert[{extra}])") from e
