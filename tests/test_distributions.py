"""The installed distributions read once per environment (dalembert.distributions): the cached answer is the
uncached one, a distribution installed or removed is seen on the next read, and a cache that is corrupt or cannot
be written never fails a run."""

import json
import os
import sys
from importlib import metadata

import pytest

from dalembert import atomic, cache as cache_module, distributions  # noqa: F401 (imported before ``small_path``)
from dalembert.harness import execute


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache of this test's own, and no answer remembered by this process."""
    monkeypatch.setenv("DALEMBERT_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(distributions, "_MEMO", (None, None))
    return tmp_path / "cache" / "distributions"


@pytest.fixture
def small_path(tmp_path, monkeypatch):
    """``sys.path`` without its site-packages, and an empty folder ``site`` first: the cache's behaviour (keys,
    corrupt and unwritable files, its bound) over a handful of distributions instead of the whole environment's
    (computing that is ~1 s of CPU each time, and these tests compute it a dozen times). The real environment's
    answer is the first two tests'."""
    site = tmp_path / "site"
    site.mkdir()
    # (a list of its own, put back whole after the test: never ``monkeypatch.syspath_prepend`` with it, whose undo
    # writes its saved copy into the list then in place, after this one is back)
    monkeypatch.setattr(sys, "path", [str(site)] + [p for p in sys.path if "-packages" not in p])
    return site


def _install(site, name, version, top, files=()):
    """A distribution ``name`` installed in folder ``site``: its dist-info (METADATA, top_level.txt, RECORD) and
    ``files`` (paths under ``site``)."""
    info = site / f"{name.replace('-', '_')}-{version}.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n")
    (info / "top_level.txt").write_text(f"{top}\n")
    for path in files:
        (site / path).parent.mkdir(parents=True, exist_ok=True)
        (site / path).write_text("")
    (info / "RECORD").write_text("".join(f"{p},,\n" for p in (*files, f"{info.name}/METADATA")))
    return info


def _forget(monkeypatch):
    """Make the next ``installed()`` read the cache file, as a fresh worker process does."""
    monkeypatch.setattr(distributions, "_MEMO", (None, None))


def _no_compute(monkeypatch):
    def refuse():
        raise AssertionError("computed although the cache file is current")
    monkeypatch.setattr(distributions, "compute", refuse)


def test_the_cached_answer_is_importlib_metadatas(cache, tmp_path, monkeypatch):
    site = tmp_path / "site"  # (two distributions in one folder, as mujoco's and mujoco-mjx's: their files kept)
    _install(site, "fake-one", "1.0", "fake_shared", ["fake_shared/__init__.py", "fake_shared/one.py"])
    _install(site, "fake-two", "2.0", "fake_shared", ["fake_shared/two.py"])
    monkeypatch.syspath_prepend(str(site))
    written = distributions.installed()
    assert len(os.listdir(cache)) == 1
    _forget(monkeypatch)
    _no_compute(monkeypatch)
    read = distributions.installed()
    assert read is not written and read == written
    assert read.packages == metadata.packages_distributions()
    names = {d for names in read.packages.values() for d in names}
    assert names and set(read.versions) == names
    for name in names:
        assert read.version(name) == metadata.version(name)
    shared = {d for names in read.packages.values() if len(names) > 1 for d in names}
    assert {"fake-one", "fake-two"} <= shared
    assert read.files("fake-two") == {os.path.realpath(site / p) for p in ("fake_shared/two.py",
                                                                        "fake_two-2.0.dist-info/METADATA")}
    for name in shared:
        dist = metadata.distribution(name)
        assert read.files(name) == {os.path.realpath(dist.locate_file(p)) for p in dist.files or ()}


def test_a_runs_libraries_are_those_the_uncached_metadata_gives(cache, monkeypatch):
    pytest.importorskip("mujoco")  # (one folder, several distributions: told apart by the files loaded)
    import numpy  # noqa: F401

    distributions.installed()  # (written)
    _forget(monkeypatch)
    monkeypatch.setattr(execute, "_LAST", (None, None))
    _no_compute(monkeypatch)
    cached = execute._libraries()
    monkeypatch.undo()  # (the real compute, and every read uncached)
    monkeypatch.setattr(distributions, "installed", distributions.compute)
    monkeypatch.setattr(execute, "_LAST", (None, None))
    assert cached == execute._libraries()
    assert cached["mujoco"] == metadata.version("mujoco")  # (its folder's other distributions: only if loaded)
    assert ("mujoco-mjx" in cached) == any(name.startswith("mujoco.mjx") for name in sys.modules)


def test_a_distribution_installed_is_seen_on_the_next_read_and_removed_is_gone(cache, small_path, monkeypatch):
    site = small_path
    assert "fake_top" not in distributions.installed().packages
    info = _install(site, "fake-dist", "1.2.3", "fake_top")
    answer = distributions.installed()
    assert answer.packages["fake_top"] == ["fake-dist"] and answer.version("fake-dist") == "1.2.3"
    _forget(monkeypatch)
    assert distributions.installed() == answer  # (and the cache file holds it)
    for path in info.iterdir():
        path.unlink()
    info.rmdir()
    answer = distributions.installed()
    assert "fake_top" not in answer.packages and "fake-dist" not in answer.versions
    with pytest.raises(metadata.PackageNotFoundError):
        answer.version("fake-dist")


@pytest.mark.parametrize("text", ["{not json", "[1, 2]", '{"key": null}', ""])
def test_a_corrupt_cache_file_is_computed_again_and_rewritten(cache, small_path, monkeypatch, text):
    _install(small_path, "fake-dist", "1.0", "fake_top")
    expected = distributions.installed()
    assert expected.packages == {"fake_top": ["fake-dist"]}
    (path,) = cache.iterdir()
    if text == '{"key": null}':  # (the right key, then a field missing)
        text = json.dumps({"key": json.loads(path.read_text())["key"], "packages": {}})
    path.write_text(text)
    _forget(monkeypatch)
    assert distributions.installed() == expected
    assert json.loads(path.read_text())["packages"] == expected.packages


def test_a_cache_that_cannot_be_written_still_answers(small_path, tmp_path, monkeypatch):
    _install(small_path, "fake-dist", "1.0", "fake_top")
    expected = distributions.compute()
    blocker = tmp_path / "a file"
    blocker.write_text("")
    monkeypatch.setenv("DALEMBERT_CACHE", str(blocker / "cache"))  # (its folder cannot be made)
    monkeypatch.setattr(distributions, "_MEMO", (None, None))
    assert distributions.installed() == expected

    def refuse(path, data):
        raise PermissionError(13, "Permission denied", path)
    monkeypatch.setattr("dalembert.atomic.atomic_write", refuse)
    monkeypatch.setenv("DALEMBERT_CACHE", str(tmp_path / "cache"))  # (its folder is made, the file not written)
    monkeypatch.setattr(distributions, "_MEMO", (None, None))
    assert distributions.installed() == expected
    assert os.listdir(tmp_path / "cache" / "distributions") == []


def test_the_cache_keeps_a_bounded_number_of_files(cache, small_path, tmp_path, monkeypatch):
    monkeypatch.setattr(distributions, "MAX_FILES", 2)
    for i in range(4):
        folder = tmp_path / f"entry{i}"
        folder.mkdir()
        sys.path.insert(0, str(folder))  # (another sys.path: another file; ``small_path``'s list, dropped after)
        distributions.installed()
    assert len(os.listdir(cache)) == 2
