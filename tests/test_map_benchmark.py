"""benchmarks/map.py's command line: what it refuses before any map runs, and the store's size it reports."""

import pytest
from benchmark_modules import benchmark


@pytest.fixture()
def bench():
    with benchmark("map") as module:
        yield module


@pytest.mark.parametrize("argv,message", [
    (["--probes", "10", "--trajectories", "some"], "--trajectories: 'some' is not a choice — use one of all, drawn, none"),
    (["--trajectories", "none"], "--trajectories: says what the --probes map's store keeps — give --probes N"),
    (["--probes", "0"], "--probes: 0 probes — give at least 1"),
    (["--jobs", "2"], "--jobs: runs the --probes map locally — give --probes N and at least 1 job"),
])
def test_bad_arguments_are_refused_before_any_map_runs(bench, argv, message, capsys, monkeypatch):
    monkeypatch.setattr(bench, "probe_map", lambda *a, **k: pytest.fail("a map ran"))
    monkeypatch.setattr(bench, "_cluster_map", lambda *a, **k: pytest.fail("a map ran"))
    with pytest.raises(SystemExit) as stop:
        bench.main(argv)
    assert stop.value.code == 2 and message in capsys.readouterr().err


def test_the_store_s_size_is_every_file_s_bytes_below_it(bench, tmp_path):
    (tmp_path / "a").write_bytes(b"x" * 1000)
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "b").write_bytes(b"y" * 234)
    assert bench._disk_bytes(str(tmp_path)) == 1234
