"""Where and with what a matrix ran: the harness's commit, the numerical libraries' versions, the machine, the time.

The manifest of every store records them (``dalembert.harness.session``).
"""

from __future__ import annotations

import os
import platform
import socket
import subprocess
import sys
from datetime import datetime, timezone

import numpy as np

__all__ = ["harness_commit", "library_versions", "machine_info", "now"]


def harness_commit():
    """The git commit of the harness source (with ``-dirty`` if modified), or 'unknown'."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True,
                                timeout=10).stdout.strip()
        # --no-optional-locks: reading must not take .git/index.lock in the user's checkout
        dirty = subprocess.run(["git", "--no-optional-locks", "status", "--porcelain", "--untracked-files=no"], cwd=here,
                               capture_output=True, text=True, timeout=10).stdout.strip()
        return (commit + ("-dirty" if dirty else "")) or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def library_versions():
    """The numerical libraries every engine's numbers pass through (``{"numpy": ..., "scipy": ...}``): the
    reference and every read-back compute with them, so a store records them beside the engines' versions."""
    import scipy

    return {"numpy": np.__version__, "scipy": scipy.__version__}


def machine_info():
    """CPU model, cores, OS, Python, host."""
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"cpu": cpu or "unknown", "cores": os.cpu_count(), "os": platform.platform(),
            "python": sys.version.split()[0], "host": socket.gethostname()}


def now():
    return datetime.now(timezone.utc).isoformat(timespec="seconds")
