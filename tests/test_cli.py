"""The command line: listing, truth CSV, validation table, and fast failures."""

import numpy as np
import pytest

from dalembert import make_case
from dalembert.harness.cli import main
from dalembert.trajectory import CSV_COLUMNS, read_csv


def test_cases_lists_everything(capsys):
    assert main(["cases", "--verbose"]) == 0
    out = capsys.readouterr().out
    for name in ("pivoted_rod", "free_top", "free_top_intermediate", "particle_box"):
        assert name in out
    assert "omega0" in out and "(rad/s)" in out


def test_truth_csv_is_full_precision(tmp_path, capsys):
    path = tmp_path / "box.csv"
    assert main(["truth", "particle_box", "--param", "t_final=1", "--param", "omega0=0,1,2", "--csv", str(path)]) == 0
    header = path.read_text().splitlines()[0]
    assert tuple(header.split(",")) == CSV_COLUMNS
    back = read_csv(path)
    exact = make_case("particle_box", t_final=1.0, omega0=(0.0, 1.0, 2.0))
    tr = exact.exact(exact.times)
    assert np.array_equal(back.bodies["box"].quaternion, tr.bodies["box"].quaternion)
    assert np.array_equal(back.t, exact.times)


@pytest.mark.parametrize("argv,words", [
    (["truth", "free_tp", "--csv", "x.csv"], "did you mean 'free_top'"),
    (["truth", "free_top", "--param", "omega0=1,2", "--csv", "x.csv"], "omega0"),
    (["truth", "free_top", "--param", "t_final=abc", "--csv", "x.csv"], "t_final"),
    (["validate", "--case", "pivoted_rd"], "did you mean 'pivoted_rod'"),
    (["validate", "--jobs", "0"], "--jobs"),
])
def test_bad_command_lines_fail_fast(argv, words, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert words in capsys.readouterr().err
    assert not any(tmp_path.iterdir())  # nothing written


def test_unwritable_output(capsys):
    assert main(["truth", "free_top", "--csv", "/proc/nope/x.csv"]) == 2
    assert "cannot write" in capsys.readouterr().err


@pytest.mark.long
def test_validate_writes_the_table(tmp_path, capsys):
    assert main(["validate", "--case", "pivoted_rod", "--jobs", "2", "--out", str(tmp_path)]) == 0
    md = (tmp_path / "reference-validation.md").read_text()
    assert "## pivoted_rod" in md and "rk4 dt=0.001" in md
    csv = (tmp_path / "reference-validation.csv").read_text()
    assert "within_tolerance" in csv
