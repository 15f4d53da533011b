"""The Pinocchio adapter's compiled loop (``adapters/pinocchio/native.py``): a compile that failed is remembered.

The compiler is replaced by a command that fails at once (or records that it ran), and the cache is this test's
own: nothing here compiles ``stepper.cpp`` or touches the user's cache.
"""

import os
import sys

import pytest

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter

pytest.importorskip("pinocchio")  # CI installs it: this never skips there

from dalembert.adapters.pinocchio import native  # noqa: E402

ERROR = "stepper.cpp:1: error: no member named 'jacobian' in namespace 'pinocchio'"
# What Pinocchio 4.0.0's headers make g++ write: a deprecation warning per use (measured: the last 1500 characters
# of its output, all the reason quoted before, were such warnings alone).
WARNINGS = "aligned-vector.hxx:24:11: warning: 'aligned_vector' is deprecated [-Wdeprecated-declarations]\n" * 50


@pytest.fixture
def compiler(tmp_path, monkeypatch):
    """A fresh cache and library state, and a compiler that fails with ``ERROR`` among ``WARNINGS``; ``calls`` counts
    its runs."""
    monkeypatch.setenv("DALEMBERT_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(native, "_cached", {})
    calls = []

    def command(prefix, out):
        calls.append(out)
        said = WARNINGS + ERROR + "\n" + WARNINGS
        return [sys.executable, "-c", f"import sys; sys.stderr.write({said!r}); sys.exit(1)"]

    monkeypatch.setattr(native, "_command", command)
    return calls


def test_a_failed_compile_is_remembered_and_later_workers_fall_back_at_once(compiler, monkeypatch):
    """The first worker compiles, fails and leaves a marker keyed as the library (source, flags, Pinocchio version)
    with the error; a later worker (a fresh process: no in-memory state) does not compile again, and its run takes
    the Python loop, its audit saying why and naming the marker to delete."""
    with pytest.raises(RuntimeError, match=r"building stepper.cpp failed \(exit status 1\): .*no member named") as e:
        native.library()
    assert "warning" not in str(e.value)  # the error line, not the warnings around it
    assert len(compiler) == 1
    (marker,) = [f for f in os.listdir(native.cache_dir()) if f.endswith(native.FAILED)]
    assert marker.startswith("pinocchio_stepper-")

    monkeypatch.setattr(native, "_cached", {})  # a later worker
    with pytest.raises(RuntimeError, match="remembered in .*delete it to try again.*no member named 'jacobian'"):
        native.library()
    assert len(compiler) == 1  # not compiled again

    monkeypatch.setattr(native, "_cached", {})
    adapter = get_adapter("pinocchio")
    case = make_case("pivoted_rod", t_final=0.1)
    outcome = adapter.run(adapter.prepare(case.scene, case.times, Settings("rk4", dt=1e-2)))
    assert outcome.info["loop"].startswith("Python (the compiled loop is unavailable: stepper.cpp did not compile "
                                           "against Pinocchio"), outcome.info
    assert ERROR in outcome.info["loop"] and len(compiler) == 1


def test_a_remembered_failure_is_one_pinocchio_versions(compiler, monkeypatch):
    """Another Pinocchio version (another key) compiles again; deleting the marker retries the same one."""
    with pytest.raises(RuntimeError, match="building"):
        native.library()
    prefix, version = native._paths()
    monkeypatch.setattr(native, "_paths", lambda: (prefix, version + ".post1"))
    monkeypatch.setattr(native, "_cached", {})
    with pytest.raises(RuntimeError, match="building"):
        native.library()
    assert len(compiler) == 2
    markers = [f for f in os.listdir(native.cache_dir()) if f.endswith(native.FAILED)]
    assert len(markers) == 2
    for f in markers:
        os.remove(os.path.join(native.cache_dir(), f))
    monkeypatch.setattr(native, "_cached", {})
    with pytest.raises(RuntimeError, match="building"):
        native.library()
    assert len(compiler) == 3
