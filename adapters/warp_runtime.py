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

from dalembert.adapters.base import Option

__all__ = ["init", "distribution_version", "DEVICES", "DEVICE_OPTION", "device_problem", "device"]

# The devices option ``device`` takes: Warp's CPU backend (the default: every stored number is from it), its
# current CUDA device, or CUDA device N (up to 8 per machine, the most a node of the usual GPU servers holds).
DEVICES = ("cpu", "cuda", *(f"cuda:{n}" for n in range(8)))
DEVICE_OPTION = Option(DEVICES, "cpu", "where Warp steps: its CPU backend, or a CUDA device (cuda: the current "
                       "one); refused where Warp finds none")


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


def device_problem(name):
    """Why Warp cannot step on device ``name`` (one of ``DEVICES``) in this process, in the project's words, or
    None. ``cpu`` is always there and asks nothing; a CUDA device initializes Warp (``init``) to find out."""
    if name == "cpu":
        return None
    wp, _ = init()
    count = wp.get_cuda_device_count() if wp.is_cuda_available() else 0
    if count == 0:
        return (f"options.device: no CUDA device here (Warp found none) — run with device=cpu, or on a machine "
                f"with a GPU")
    if name != "cuda" and int(name.split(":")[1]) >= count:
        return (f"options.device: {name} is not here (Warp found {count} CUDA device{'s' * (count > 1)}: cuda:0"
                f"{f' to cuda:{count - 1}' if count > 1 else ''}) — run with one of those, or device=cpu")
    return None


def device(name):
    """Warp's name of device ``name`` (``cuda`` becomes the current CUDA device, ``cuda:0``), as the record
    stores where the engine stepped; ``device_problem`` first."""
    if name == "cpu":
        return "cpu"
    wp, _ = init()
    return str(wp.get_device(name))


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
