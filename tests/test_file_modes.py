"""Stored files take the process umask, as ``open()`` would give them, so a report can be
served or shared as written (``mkstemp`` alone makes every file 0600)."""

import os
import stat

import pytest

from dalembert.store import atomic_write


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_atomic_write_uses_the_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        atomic_write(tmp_path / "a.txt", "text")
        atomic_write(tmp_path / "b.bin", b"bytes")
    finally:
        os.umask(old)
    for name in ("a.txt", "b.bin"):
        assert stat.S_IMODE(os.stat(tmp_path / name).st_mode) == 0o666 & ~umask
